//! The packaged `target/fmu/FtFusion.fmu` driven through the `fmi` crate's FMI 2.0
//! importer: instantiate, set parameters, step with contact inputs read from the FMU's own
//! map, read outputs, and get / set / serialize states; two instances at once.

#[path = "../../tests/prerequisite.rs"]
mod prerequisite;

use std::io::Read;
use std::path::{Path, PathBuf};

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use fmi::traits::FmiStatus;
use model_description::by_name;

fn fmu() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/fmu/FtFusion.fmu");
    if p.is_file() {
        Some(p)
    } else {
        prerequisite::missing(
            &format!("{} is missing", p.display()),
            "run `cargo xtask fmu` first",
        );
        None
    }
}

fn vr(name: &str) -> u32 {
    by_name(name).expect("variable in the table").vr
}

/// The map in the FMU's resources, read with the map library.
fn resource_map(fmu: &Path) -> ftmap::FtMap {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(fmu).expect("open FMU")).expect("zip");
    let mut bytes = Vec::new();
    zip.by_name("resources/peg_in_hole.ftmap")
        .expect("map entry")
        .read_to_end(&mut bytes)
        .expect("read");
    ftmap::map::format::from_bytes(&bytes, Path::new("peg_in_hole.ftmap")).expect("valid map")
}

fn start(import: &Fmi2Import, name: &str, seed: i32) -> InstanceCS {
    let mut inst = import
        .instantiate_cs(name, false, true)
        .expect("instantiate");
    inst.set_integer(&[vr("particles"), vr("seed")], &[3000, seed])
        .expect("parameters");
    inst.setup_experiment(None, 0.0, None).expect("setup");
    inst.enter_initialization_mode().expect("enter init");
    inst.exit_initialization_mode().expect("exit init");
    inst
}

/// One contact: wrench and contact height at `truth`, rising then falling `contact`.
fn contact(inst: &mut InstanceCS, map: &ftmap::FtMap, truth: [f64; 2], t: f64) {
    let c = map.nearest(&truth).expect("2 coords");
    let names = [
        "wrench.fx",
        "wrench.fy",
        "wrench.fz",
        "wrench.tx",
        "wrench.ty",
        "wrench.tz",
        "tcp.z",
    ];
    let vrs: Vec<u32> = names.iter().map(|n| vr(n)).collect();
    let vals: Vec<f64> = c.iter().map(|&x| f64::from(x)).collect();
    inst.set_real(&vrs, &vals).expect("inputs");
    inst.set_boolean(&[vr("contact")], &[1]).expect("contact");
    inst.do_step(t, 0.1, true).expect("step");
    inst.set_boolean(&[vr("contact")], &[0]).expect("contact");
    inst.do_step(t + 0.1, 0.1, true).expect("step");
}

fn outputs(inst: &mut InstanceCS) -> Vec<f64> {
    let names = ["object.x", "object.y", "object.x_std", "confidence", "ess"];
    let vrs: Vec<u32> = names.iter().map(|n| vr(n)).collect();
    let mut out = vec![0.0; names.len()];
    inst.get_real(&vrs, &mut out).expect("outputs");
    out
}

#[test]
fn the_packaged_fmu_estimates_the_offset_and_replays_saved_states() {
    let Some(path) = fmu() else { return };
    let import: Fmi2Import = fmi::import::from_path(&path).expect("import FtFusion.fmu");
    let map = resource_map(&path);
    let (truth_a, truth_b) = ([2.0e-3, -1.5e-3], [-3.0e-3, 0.8e-3]);
    let mut a = start(&import, "a", 1);
    let mut b = start(&import, "b", 2);
    for k in 0..4 {
        contact(&mut a, &map, truth_a, k as f64);
        contact(&mut b, &map, truth_b, k as f64);
    }
    let (oa, ob) = (outputs(&mut a), outputs(&mut b));
    assert!(
        (oa[0] - truth_a[0]).hypot(oa[1] - truth_a[1]) < 2e-4,
        "instance a: {oa:?}"
    );
    assert!(
        (ob[0] - truth_b[0]).hypot(ob[1] - truth_b[1]) < 2e-4,
        "instance b: {ob:?}"
    );
    let mut n = [0];
    a.get_integer(&[vr("measurements")], &mut n)
        .expect("measurements");
    assert_eq!(n, [4]);

    let state = a.get_fmu_state().expect("get state");
    let bytes = a.serialize_fmu_state(&state).expect("serialize");
    contact(&mut a, &map, truth_a, 10.0);
    let after = outputs(&mut a);
    a.set_fmu_state(&state).ok().expect("set state");
    contact(&mut a, &map, truth_a, 10.0);
    assert_eq!(
        outputs(&mut a),
        after,
        "a restored state replays bit for bit"
    );
    let restored = a.deserialize_fmu_state(&bytes).expect("deserialize");
    a.set_fmu_state(&restored)
        .ok()
        .expect("set deserialized state");
    contact(&mut a, &map, truth_a, 10.0);
    assert_eq!(outputs(&mut a), after);
    assert!(
        a.deserialize_fmu_state(b"FTFSTATE garbage").is_err(),
        "foreign bytes are refused"
    );
    Common::terminate(&mut a).expect("terminate");
    Common::terminate(&mut b).expect("terminate");
}
