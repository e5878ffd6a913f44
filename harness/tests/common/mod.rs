//! Helpers shared by the harness's integration tests.

#![allow(dead_code)]

use std::sync::OnceLock;

use ftmap::generate::{GenerateOptions, generate};
use ftmap::vision::VisionModel;
use ftmap::{FtMap, Task};
use harness::camera::CameraScene;
use harness::campaign::{Rig, TrialSet, run_parallel};
use harness::fmu_driver::Fmu;
use harness::scene::{SceneSpec, scene_path};
use harness::sim::Sim;
use harness::trial::{TrialConfig, TrialResult, Truth};
use harness::vision::features::task_model;
use harness::world::World;

/// The trials of `truths` on two workers, each with a world from `open`: the results of
/// `run_campaign` (same seeds, trial order), in half the time on two cores.
pub fn run_on_two(
    open: &(dyn Fn() -> Box<dyn World> + Sync),
    fmu: &Fmu,
    cfg: &TrialConfig,
    truths: &[Truth],
    seed: u64,
) -> Vec<TrialResult> {
    let rig = || Rig {
        world: open(),
        eye: None,
    };
    let set = TrialSet::all(truths, seed);
    run_parallel(&mut rig(), 2, &|| Ok(rig()), Some(fmu), cfg, set).expect("the campaign runs")
}

/// The peg_in_hole task and a simulation of its committed scene.
pub fn peg() -> (Task, Sim) {
    scene("peg_in_hole")
}

/// A committed task and a simulation of its committed scene.
pub fn scene(name: &str) -> (Task, Sim) {
    let task = Task::find(name).expect("a committed task");
    let spec = SceneSpec::of_task(&task).expect("its scene description");
    let sim = Sim::load(&scene_path(&task), spec).expect("its committed scene");
    (task, sim)
}

/// A committed peg task (`peg_in_hole`, `octagon`) with 45-degree chamfers of legs `peg`
/// and `hole` (m), written to a scratch folder with its meshes and scene, and a simulation
/// of that scene.
pub fn chamfered(name: &str, peg: f64, hole: f64) -> (Task, Sim) {
    let committed = Task::find(name).expect("a committed task");
    let text = std::fs::read_to_string(&committed.path).expect("its task file");
    let last_table = text.lines().rfind(|l| l.starts_with('['));
    assert_eq!(
        last_table,
        Some("[geometry]"),
        "{name}: chamfers go at the end"
    );
    let dir = std::env::temp_dir().join(format!(
        "chamfered-{name}-{}-{peg}-{hole}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let path = dir.join("task.toml");
    let text = text.replace(
        &format!("name = \"{name}\""),
        &format!("name = \"{name}_chamfered\""),
    );
    std::fs::write(
        &path,
        format!("{text}\npeg_chamfer = {peg}\nhole_chamfer = {hole}\n"),
    )
    .expect("the chamfered task file");
    let task = Task::load(&path).expect("the chamfered task");
    task.write_meshes().expect("its meshes");
    harness::sim::regenerate_scene(&task).expect("its scene");
    let sim = Sim::of_task(&task).expect("its scene loads");
    (task, sim)
}

/// peg_in_hole with the hole's tilts uncertain too (object rx, ry within ±2 degrees at
/// 0.5), written to a scratch folder with its meshes and scene (a wrist with rx, ry
/// hinges), and a simulation of that scene.
pub fn tilted() -> (Task, Sim) {
    tilted_with_band(None)
}

/// [`tilted`] with the contact band `tolerance` (m) of peg_in_hole_4dof where given, the
/// committed peg's (20 µm) where not.
pub fn tilted_with_band(tolerance: Option<f64>) -> (Task, Sim) {
    let committed = Task::find("peg_in_hole").expect("a committed task");
    let text = std::fs::read_to_string(&committed.path).expect("its task file");
    // A folder per call: tests run in parallel, and one rewriting the task file another
    // reads made it read an empty file.
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("tilted-{}-{call}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    let path = dir.join("task.toml");
    let tilted = text
        .replace("name = \"peg_in_hole\"", "name = \"peg_in_hole_tilted\"")
        .replace(
            "object = [\"x\", \"y\"]",
            "object = [\"x\", \"y\", \"rx\", \"ry\"]",
        )
        .replace("size_rot = 0.0", "size_rot = 0.03490658503988659")
        .replace(
            "tolerance = 0.00002 ",
            &tolerance.map_or("tolerance = 0.00002 ".into(), |t| {
                format!("tolerance = {t} ")
            }),
        );
    assert!(
        tilted.contains("\"rx\"")
            && tilted.contains("0.0349")
            && tolerance.is_none_or(|t| tilted.contains(&format!("tolerance = {t} "))),
        "the edits took"
    );
    std::fs::write(&path, tilted).expect("the tilted task file");
    let task = Task::load(&path).expect("the tilted task");
    task.write_meshes().expect("its meshes");
    harness::sim::regenerate_scene(&task).expect("its scene");
    let sim = Sim::of_task(&task).expect("its scene loads");
    (task, sim)
}

/// The peg_in_hole map computed from the CAD meshes (centroid model, CPU backend).
pub fn computed_peg_map() -> &'static FtMap {
    static MAP: OnceLock<FtMap> = OnceLock::new();
    MAP.get_or_init(|| {
        let task = Task::find("peg_in_hole").expect("task peg_in_hole");
        generate(
            &task,
            &ftmap::depth::cpu::CpuBackend,
            &GenerateOptions::default(),
            &|_| {},
        )
        .expect("its computed map")
    })
}

/// A task's map computed from its CAD meshes, cached like a campaign's (target/maps/).
pub fn cached_map(task: &Task) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/maps");
    ftmap::generate::cached(task, &dir)
        .expect("the map computed from CAD")
        .0
}

/// The peg's and the hole's widths across flats (m) of an octagon task.
pub fn octagon_flats(task: &Task) -> [f64; 2] {
    match *task.geometry().expect("a [geometry]") {
        ftmap::task::cad::Geometry::OctagonPeg {
            peg_across_flats,
            hole_across_flats,
            ..
        } => [peg_across_flats, hole_across_flats],
        _ => panic!("{} is not an octagon", task.name),
    }
}

/// `n` random true offsets and rotations over `task`'s Omega (seed `seed`).
pub fn turned_truths(task: &Task, n: usize, seed: u64) -> Vec<harness::trial::Truth> {
    let grid = task.grid().expect("its grid");
    harness::campaign::random_offsets(n, task.omega.size_trans, seed)
        .into_iter()
        .zip(harness::campaign::random_rotations(
            n,
            grid.axes(),
            None,
            seed,
        ))
        .map(|(object, rot)| harness::trial::Truth {
            object,
            rot,
            ..harness::trial::Truth::default()
        })
        .collect()
}

/// The bearing_housing task, its committed scene loaded for the camera, and its vision model
/// with MuJoCo's camera.
pub fn bearing() -> (Task, CameraScene, VisionModel) {
    let task = Task::find("bearing_housing").expect("task bearing_housing");
    let spec = SceneSpec::of_task(&task).expect("its scene description");
    let view = CameraScene::load(&scene_path(&task), spec)
        .expect("its committed scene with camera `vision`");
    let model = task_model(&task, view.camera()).expect("bearing housing features");
    (task, view, model)
}
