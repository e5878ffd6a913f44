//! Tests of the instance layer: the state machine, parameters, maps, measurements through
//! doStep, and saved states.

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::sync::Arc;

use super::*;
use ftfusion_testkit::{field, peg_map};

#[test]
fn the_pose_outputs_are_named_after_the_maps_dofs() {
    for i in 0..12 {
        let dof = ftmap::Dof::from_index(i).expect("12 DOFs");
        let (est, std) = if i < 6 {
            (md::GRIP, md::GRIP_STD)
        } else {
            (md::OBJECT, md::OBJECT_STD)
        };
        assert_eq!(est[i % 6], dof.to_string());
        assert_eq!(std[i % 6], format!("{dof}_std"));
    }
}

/// A resources folder holding the synthetic map as `peg.ftmap` and a corrupt copy, written
/// once per test process (tests run in parallel: none rewrites a file another reads).
fn resources() -> PathBuf {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(write_resources).clone()
}

fn write_resources() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ftfusion-instance-{}", std::process::id()));
    let map = peg_map(5e-3, 2.5e-4, None).expect("map");
    ftmap::map::format::save(&map, &dir.join("peg.ftmap")).expect("write map");
    let mut bytes = ftmap::map::format::to_bytes(&map);
    let at = bytes.len() / 2;
    bytes[at] ^= 0x40;
    std::fs::write(dir.join("corrupt.ftmap"), bytes).expect("write corrupt map");
    // The synthetic map is no task's: a model that does not say its task fits it, one of
    // the bearing housing does not.
    let model = ftfusion_testkit::bearing_vision();
    model
        .save(&dir.join("other_task.vision.json"))
        .expect("write vision model");
    ftmap::vision::VisionModel {
        task: None,
        ..model
    }
    .save(&dir.join("bearing.vision.json"))
    .expect("write vision model");
    std::fs::write(
        dir.join("broken.vision.json"),
        "{\"kind\": \"ftfusion-vision\"",
    )
    .expect("write broken vision model");
    dir
}

type Log = Rc<RefCell<Vec<(Status, String)>>>;

fn instance() -> (Instance, Log) {
    let log: Log = Rc::default();
    let sink = log.clone();
    let logger: Logger = Box::new(move |s, _c, m| sink.borrow_mut().push((s, m.to_owned())));
    (Instance::new("test", Some(resources()), logger, false), log)
}

fn vr(name: &str) -> u32 {
    model_description::by_name(name).expect("variable").vr
}

fn set_string(i: &mut Instance, name: &str, v: &str) -> Result<Status> {
    i.set(VarType::String, &[vr(name)], vec![Value::String(v.into())])
}

fn set_int(i: &mut Instance, name: &str, v: i32) -> Result<Status> {
    i.set(VarType::Integer, &[vr(name)], vec![Value::Integer(v)])
}

fn set_reals(i: &mut Instance, names: &[&str], v: &[f64]) -> Result<Status> {
    let vrs: Vec<u32> = names.iter().map(|n| vr(n)).collect();
    i.set(
        VarType::Real,
        &vrs,
        v.iter().map(|&x| Value::Real(x)).collect(),
    )
}

fn real(i: &Instance, name: &str) -> f64 {
    let mut out = [0.0];
    i.get(VarType::Real, &[vr(name)], &mut out, |v| match v {
        Value::Real(x) => *x,
        _ => f64::NAN,
    })
    .expect("readable");
    out[0]
}

fn initialized() -> (Instance, Log) {
    let (mut i, log) = instance();
    set_string(&mut i, "map", "peg.ftmap").expect("parameter");
    set_int(&mut i, "particles", 2000).expect("parameter");
    i.enter_initialization_mode().expect("allowed");
    i.exit_initialization_mode()
        .expect("valid parameters and map");
    (i, log)
}

/// Feeds the contact at true offset `truth` seen from `tcp`, with a rising contact edge.
fn contact(i: &mut Instance, t: f64, truth: [f64; 2], tcp: [f64; 2]) -> Status {
    let w = field(truth[0] - tcp[0], truth[1] - tcp[1], 0.0, 0.0).map(f64::from);
    let names = [
        "wrench.fx",
        "wrench.fy",
        "wrench.fz",
        "wrench.tx",
        "wrench.ty",
        "wrench.tz",
        "tcp.x",
        "tcp.y",
        "tcp.z",
    ];
    set_reals(
        i,
        &names,
        &[w[0], w[1], w[2], w[3], w[4], w[5], tcp[0], tcp[1], w[6]],
    )
    .expect("inputs");
    i.set(
        VarType::Boolean,
        &[vr("contact")],
        vec![Value::Boolean(true)],
    )
    .expect("input");
    let s = i.do_step(t, 0.1).expect("step");
    i.set(
        VarType::Boolean,
        &[vr("contact")],
        vec![Value::Boolean(false)],
    )
    .expect("input");
    i.do_step(t + 0.1, 0.1).expect("step");
    s
}

#[test]
fn contacts_through_do_step_move_the_outputs_to_the_true_offset() {
    let (mut i, _) = initialized();
    let truth = [2.1e-3, -3.3e-3];
    for k in 0..4 {
        assert_eq!(contact(&mut i, k as f64, truth, [0.0, 0.0]), Status::Ok);
    }
    assert!(
        (real(&i, "object.x") - truth[0]).abs() < 2.5e-4,
        "{}",
        real(&i, "object.x")
    );
    assert!(
        (real(&i, "object.y") - truth[1]).abs() < 2.5e-4,
        "{}",
        real(&i, "object.y")
    );
    assert_eq!(real(&i, "object.z"), 0.0, "DOFs outside the map stay 0");
    assert_eq!(real(&i, "grip.x"), 0.0);
    let mut n = [0];
    i.get(VarType::Integer, &[vr("measurements")], &mut n, |v| {
        if let Value::Integer(x) = v { *x } else { -1 }
    })
    .expect("readable");
    assert_eq!(
        n,
        [4],
        "one measurement per rising edge, none while contact stays high"
    );
}

#[test]
fn calls_in_the_wrong_state_are_refused_and_leave_the_instance_as_it_was() {
    let (mut i, log) = instance();
    let r = i.do_step(0.0, 0.1);
    assert_eq!(i.finish(Call::DoStep, r), Status::Error);
    assert_eq!(i.mode(), Mode::Instantiated);
    assert!(
        log.borrow()
            .last()
            .is_some_and(|(s, m)| *s == Status::Error && m.contains("fmi2DoStep"))
    );
    let r = i.exit_initialization_mode();
    assert!(matches!(r, Err(FusionError::IllegalCall { .. })));
    let (mut i, _) = initialized();
    assert!(matches!(
        set_int(&mut i, "particles", 100),
        Err(FusionError::BadArgument(_))
    ));
    assert!(set_reals(&mut i, &["object.x"], &[1.0]).is_err());
    assert!(i.enter_initialization_mode().is_err());
    assert_eq!(i.mode(), Mode::StepComplete);
    assert_eq!(contact(&mut i, 0.0, [1e-3, 1e-3], [0.0, 0.0]), Status::Ok);
}

#[test]
fn a_parameter_out_of_range_fails_initialization_naming_it_and_its_range() {
    // A sigma_depth between 0 (depth unused) and a nanometre is in the table's range but
    // would overflow the likelihood: refused all the same.
    for (name, value, range) in [
        ("iterations", 0.0, "[1, 1000]"),
        ("sigma_depth", 1e-20, "[1e-9, 1]"),
    ] {
        let (mut i, log) = instance();
        set_string(&mut i, "map", "peg.ftmap").expect("parameter");
        let set = match name {
            "iterations" => set_int(&mut i, name, value as i32),
            _ => set_reals(&mut i, &[name], &[value]),
        };
        set.expect("values are checked at initialization");
        i.enter_initialization_mode().expect("allowed");
        let r = i.exit_initialization_mode();
        assert_eq!(i.finish(Call::ExitInitializationMode, r), Status::Error);
        let msg = log
            .borrow()
            .last()
            .map(|(_, m)| m.clone())
            .unwrap_or_default();
        assert!(
            msg.contains(&format!("`{name}`")) && msg.contains(range),
            "{msg}"
        );
        assert_eq!(i.mode(), Mode::Error);
        i.reset().expect("reset is allowed after an error");
        assert_eq!(i.mode(), Mode::Instantiated);
    }
}

#[test]
fn missing_and_corrupt_maps_fail_initialization_naming_the_file_and_the_problem() {
    for (name, problem) in [
        ("nothere.ftmap", "No such file"),
        ("corrupt.ftmap", "checksum"),
    ] {
        let (mut i, _) = instance();
        set_string(&mut i, "map", name).expect("parameter");
        i.enter_initialization_mode().expect("allowed");
        let e = i.exit_initialization_mode().expect_err("bad map");
        // The map library's error is kept as the source, and the logged line says it all.
        assert!(matches!(e, FusionError::MapFile(_)), "{e}");
        assert!(std::error::Error::source(&e).is_some(), "{e}");
        let line = crate::error::report(&e);
        assert!(line.contains(name) && line.contains(problem), "{line}");
    }
    let (mut i, _) = instance();
    set_string(&mut i, "map", "/does/not/exist.ftmap").expect("parameter");
    i.enter_initialization_mode().expect("allowed");
    let e = i.exit_initialization_mode().expect_err("bad map");
    assert!(crate::error::report(&e).contains("/does/not/exist.ftmap"));
}

#[test]
fn a_nan_input_skips_its_measurement_with_a_warning() {
    let (mut i, log) = initialized();
    contact(&mut i, 0.0, [1e-3, 2e-3], [0.0, 0.0]);
    let before = real(&i, "object.x");
    assert_eq!(
        set_reals(&mut i, &["wrench.tx"], &[f64::NAN]).expect("stored"),
        Status::Warning
    );
    i.set(
        VarType::Boolean,
        &[vr("contact")],
        vec![Value::Boolean(true)],
    )
    .expect("input");
    assert_eq!(i.do_step(1.0, 0.1).expect("step"), Status::Warning);
    assert_eq!(real(&i, "object.x"), before);
    assert!(
        log.borrow()
            .iter()
            .any(|(s, m)| *s == Status::Warning && m.contains("wrench.tx"))
    );
    i.set(
        VarType::Boolean,
        &[vr("contact")],
        vec![Value::Boolean(false)],
    )
    .expect("input");
    i.do_step(1.1, 0.1).expect("the run goes on");
    assert_eq!(contact(&mut i, 2.0, [1e-3, 2e-3], [0.0, 0.0]), Status::Ok);
}

#[test]
fn a_restored_state_replays_the_same_outputs_and_foreign_bytes_are_refused() {
    let (mut i, _) = initialized();
    contact(&mut i, 0.0, [-1e-3, 3e-3], [0.0, 0.0]);
    let saved = i.save_state().expect("allowed");
    contact(&mut i, 1.0, [-1e-3, 3e-3], [1e-3, 1e-3]);
    let first = (
        real(&i, "object.x"),
        real(&i, "object.y"),
        real(&i, "confidence"),
    );
    i.restore_state(&saved).expect("own state");
    contact(&mut i, 1.0, [-1e-3, 3e-3], [1e-3, 1e-3]);
    assert_eq!(
        (
            real(&i, "object.x"),
            real(&i, "object.y"),
            real(&i, "confidence")
        ),
        first
    );

    let mut foreign = saved.clone();
    foreign[0] = b'X';
    assert!(matches!(
        i.restore_state(&foreign),
        Err(FusionError::State(_))
    ));
    assert!(i.restore_state(&saved[..saved.len() - 1]).is_err());
    assert_eq!(
        (
            real(&i, "object.x"),
            real(&i, "object.y"),
            real(&i, "confidence")
        ),
        first
    );
}

fn set_bool(i: &mut Instance, name: &str, v: bool) {
    i.set(VarType::Boolean, &[vr(name)], vec![Value::Boolean(v)])
        .expect("input");
}

#[test]
fn missing_and_broken_vision_models_fail_initialization_naming_the_file() {
    for (name, problem) in [
        ("nothere.vision.json", "No such file"),
        ("broken.vision.json", "not a vision model"),
        (
            "other_task.vision.json",
            "its parts are task `bearing_housing`'s",
        ),
    ] {
        let (mut i, _) = instance();
        set_string(&mut i, "map", "peg.ftmap").expect("parameter");
        set_string(&mut i, "vision", name).expect("parameter");
        i.enter_initialization_mode().expect("allowed");
        let e = i.exit_initialization_mode().expect_err("bad vision model");
        assert!(
            matches!(e, FusionError::VisionFile(_) | FusionError::Vision { .. }),
            "{e}"
        );
        let line = crate::error::report(&e);
        assert!(line.contains(name) && line.contains(problem), "{line}");
    }
}

#[test]
fn an_image_alone_is_measured_on_the_rising_edge_of_vision_valid() {
    let (mut i, log) = instance();
    set_string(&mut i, "map", "peg.ftmap").expect("parameter");
    set_string(&mut i, "vision", "bearing.vision.json").expect("parameter");
    i.enter_initialization_mode().expect("allowed");
    i.exit_initialization_mode()
        .expect("valid parameters, map and vision model");
    let model = ftfusion_testkit::bearing_vision();
    let (truth, tcp) = ([1.0e-3, -2.0e-3, 0.0], [0.0, 0.0, 0.02]);
    let d = model.distances(tcp, truth).expect("in view");
    let p = model
        .passive
        .columns(&model.camera, truth)
        .expect("in view");
    let names = [
        "vision.left_distance",
        "vision.right_distance",
        "vision.passive_left",
        "vision.passive_right",
        "tcp.z",
    ];
    set_reals(&mut i, &names, &[d[0], d[1], p[0], p[1], tcp[2]]).expect("inputs");
    set_bool(&mut i, "vision.valid", true);
    assert_eq!(i.do_step(0.0, 0.1).expect("step"), Status::Ok);
    assert_eq!(i.store.integer(index_of("measurements")), 1);
    assert!(
        (real(&i, "object.y") - truth[1]).abs() < 2.5e-4,
        "{}",
        real(&i, "object.y")
    );
    assert!(real(&i, "object.x_std") > 3.0 * real(&i, "object.y_std"));
    // Held high, no new measurement; a saved state keeps the edge.
    let saved = i.save_state().expect("state");
    assert_eq!(i.do_step(0.1, 0.1).expect("step"), Status::Ok);
    assert_eq!(i.store.integer(index_of("measurements")), 1);
    i.restore_state(&saved).expect("own state");
    i.do_step(0.1, 0.1).expect("step");
    assert_eq!(i.store.integer(index_of("measurements")), 1);
    // A NaN detection with the flag raised again: skipped with a warning naming it.
    set_bool(&mut i, "vision.valid", false);
    i.do_step(0.2, 0.1).expect("step");
    set_reals(&mut i, &["vision.right_distance"], &[f64::NAN])
        .expect("NaN is stored, with a warning");
    set_bool(&mut i, "vision.valid", true);
    assert_eq!(i.do_step(0.3, 0.1).expect("step"), Status::Warning);
    assert_eq!(i.store.integer(index_of("measurements")), 1);
    assert!(
        log.borrow()
            .iter()
            .any(|(s, m)| *s == Status::Warning && m.contains("vision.right_distance")),
        "{:?}",
        log.borrow()
    );
}

#[test]
fn an_image_without_a_vision_model_is_ignored_with_a_warning() {
    let (mut i, log) = initialized();
    set_bool(&mut i, "vision.valid", true);
    assert_eq!(i.do_step(0.0, 0.1).expect("step"), Status::Warning);
    assert_eq!(i.store.integer(index_of("measurements")), 0);
    assert!(
        log.borrow()
            .iter()
            .any(|(_, m)| m.contains("no vision model")),
        "{:?}",
        log.borrow()
    );
    // With a contact the wrench is still used, and the image is reported unused again.
    assert_eq!(
        contact(&mut i, 1.0, [1e-3, 1e-3], [0.0, 0.0]),
        Status::Warning
    );
    assert_eq!(i.store.integer(index_of("measurements")), 1);
}

#[test]
fn a_slide_start_set_with_the_contact_rules_out_the_line_swept() {
    // The same two contacts, the second ending a slide along y at x = 0.2 mm that passed
    // 0.1 mm beside part B (0.3 mm off along +x) or a plain contact there: the inputs
    // `slide` and `slide_start.*` reach the filter and change what it concludes.
    let truth = [3e-4, 0.0];
    let run = |slide: bool| {
        let (mut i, _) = initialized();
        contact(&mut i, 0.0, truth, [0.0, 0.0]);
        set_bool(&mut i, "slide", slide);
        set_reals(&mut i, &["slide_start.x", "slide_start.y"], &[2e-4, -3e-4]).expect("inputs");
        assert_eq!(contact(&mut i, 1.0, truth, [2e-4, 3e-4]), Status::Ok);
        [real(&i, "object.x"), real(&i, "object.y")]
    };
    let (swept, end) = (run(true), run(false));
    assert!(swept.iter().chain(&end).all(|v| v.is_finite()));
    assert_ne!(swept, end, "the line swept changes the estimate");
}

#[test]
fn a_slide_end_set_with_the_contact_reaches_the_filter() {
    // The slide of the test above pressed again at its midpoint: `slide_end.valid` and
    // `slide_end.*` change what the filter concludes; without `slide` they are ignored.
    let truth = [3e-4, 0.0];
    let run = |slide: bool, end: bool| {
        let (mut i, _) = initialized();
        contact(&mut i, 0.0, truth, [0.0, 0.0]);
        set_bool(&mut i, "slide", slide);
        set_bool(&mut i, "slide_end.valid", end);
        set_reals(&mut i, &["slide_start.x", "slide_start.y"], &[2e-4, -3e-4]).expect("inputs");
        set_reals(&mut i, &["slide_end.x", "slide_end.y"], &[2e-4, 3e-4]).expect("inputs");
        assert_eq!(contact(&mut i, 1.0, truth, [2e-4, 0.0]), Status::Ok);
        [real(&i, "object.x"), real(&i, "object.y")]
    };
    let (told, untold) = (run(true, true), run(true, false));
    assert!(told.iter().chain(&untold).all(|v| v.is_finite()));
    assert_ne!(told, untold, "the line to its end changes the estimate");
    assert_eq!(run(false, true), run(false, false), "no slide: no line");
}

#[test]
fn a_state_saved_after_initialization_restores_into_a_fresh_instance() {
    // FMI 2.0 allows fmi2SetFMUstate right after fmi2Instantiate; the reference importer
    // restores a saved run that way and goes on stepping.
    let (mut a, _) = initialized();
    contact(&mut a, 0.0, [-1e-3, 3e-3], [0.0, 0.0]);
    let saved = a.save_state().expect("allowed");
    let (mut b, _) = instance();
    assert_eq!(
        b.restore_state(&saved).expect("a state of this FMU"),
        Status::Ok
    );
    assert_eq!(b.mode(), Mode::StepComplete);
    for i in [&mut a, &mut b] {
        contact(i, 1.0, [-1e-3, 3e-3], [1e-3, 1e-3]);
    }
    for name in ["object.x", "object.y", "object.x_std", "confidence"] {
        assert_eq!(real(&a, name), real(&b, name), "{name}");
    }
    // And a state saved before initialization takes an initialized instance back there.
    let (fresh, _) = instance();
    let before = fresh.save_state().expect("allowed");
    a.restore_state(&before).expect("a state of this FMU");
    assert_eq!(a.mode(), Mode::Instantiated);
    set_string(&mut a, "map", "peg.ftmap").expect("parameter");
    a.enter_initialization_mode().expect("allowed again");
    a.exit_initialization_mode().expect("initializes again");
}

/// The outputs the FMU gives: every Real output.
fn outputs(i: &Instance) -> Vec<(String, f64)> {
    VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Output && v.ty == VarType::Real)
        .map(|v| (v.name.to_string(), real(i, v.name)))
        .collect()
}

#[test]
fn every_parameter_at_either_end_of_its_range_keeps_every_output_finite() {
    let mut ran = 0;
    for v in VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Parameter)
    {
        for end in [v.min, v.max].into_iter().flatten() {
            let (mut i, _) = instance();
            set_string(&mut i, "map", "peg.ftmap").expect("parameter");
            // A million particles at a thousand iterations would take minutes: the ends of
            // `particles` run at one iteration, the other parameters at 200 particles.
            match v.name {
                "particles" => set_int(&mut i, "iterations", 1).expect("parameter"),
                _ => set_int(&mut i, "particles", 200).expect("parameter"),
            };
            let r = match v.ty {
                VarType::Integer => set_int(&mut i, v.name, end as i32),
                _ => set_reals(&mut i, &[v.name], &[end]),
            };
            r.expect("a value in the range");
            i.enter_initialization_mode().expect("allowed");
            i.exit_initialization_mode()
                .unwrap_or_else(|e| panic!("{} = {end}: {e}", v.name));
            // Sound contacts, a contact that went in, and the largest inputs accepted.
            contact(&mut i, 0.0, [1e-3, -2e-3], [0.0, 0.0]);
            contact(&mut i, 1.0, [1e-3, -2e-3], [1e-3, -2e-3]);
            let names = ["wrench.fx", "wrench.ty", "tcp.x", "tcp.z"];
            set_reals(&mut i, &names, &[1e6, -1e6, 1e6, -1e6]).expect("inputs");
            set_bool(&mut i, "contact", true);
            i.do_step(2.0, 0.1).expect("a step");
            set_bool(&mut i, "contact", false);
            i.do_step(2.1, 0.1).expect("a step");
            for (name, x) in outputs(&i) {
                assert!(x.is_finite(), "{} = {end}: output {name} = {x}", v.name);
            }
            let saved = i.save_state().expect("allowed");
            i.restore_state(&saved)
                .unwrap_or_else(|e| panic!("{} = {end}: its own state: {e}", v.name));
            ran += 1;
        }
    }
    assert!(ran >= 25, "{ran} cases");
}

#[test]
fn an_absurd_input_skips_its_measurement_with_a_warning_naming_it() {
    let (mut i, log) = initialized();
    contact(&mut i, 0.0, [1e-3, 2e-3], [0.0, 0.0]);
    let before = outputs(&i);
    set_reals(&mut i, &["tcp.z"], &[2e19]).expect("stored");
    set_bool(&mut i, "contact", true);
    assert_eq!(i.do_step(1.0, 0.1).expect("step"), Status::Warning);
    assert_eq!(outputs(&i), before);
    assert!(
        log.borrow()
            .iter()
            .any(|(s, m)| *s == Status::Warning && m.contains("tcp.z") && m.contains("beyond"))
    );
}

#[test]
fn a_fifo_or_a_device_as_map_or_vision_fails_initialization_without_waiting() {
    let fifo = resources().join(format!("pipe-{:?}", std::thread::current().id()));
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    let fifo = fifo.to_str().expect("a UTF-8 path").to_owned();
    for (map, vision, want) in [
        (fifo.as_str(), "", "a FIFO (named pipe)"),
        ("/dev/zero", "", "a character device"),
        ("peg.ftmap", fifo.as_str(), "a FIFO (named pipe)"),
        ("peg.ftmap", "/dev/zero", "a character device"),
    ] {
        let (mut i, _) = instance();
        set_string(&mut i, "map", map).expect("parameter");
        set_string(&mut i, "vision", vision).expect("parameter");
        i.enter_initialization_mode().expect("allowed");
        let e = i
            .exit_initialization_mode()
            .expect_err("not a regular file");
        let line = crate::error::report(&e);
        assert!(
            line.contains(want) && line.contains("not a regular file"),
            "{line}"
        );
    }
    std::fs::remove_file(&fifo).ok();
}

#[test]
fn two_hundred_instances_on_eight_threads_share_one_map_and_match_a_serial_run() {
    let run = |k: usize| {
        let (mut i, _) = instance();
        set_string(&mut i, "map", "peg.ftmap").expect("parameter");
        set_int(&mut i, "particles", 300).expect("parameter");
        set_int(&mut i, "seed", (k % 7) as i32).expect("parameter");
        i.enter_initialization_mode().expect("allowed");
        i.exit_initialization_mode().expect("initializes");
        contact(&mut i, 0.0, [1e-3, -2e-3], [0.0, 0.0]);
        contact(&mut i, 1.0, [1e-3, -2e-3], [0.5e-3, -1e-3]);
        outputs(&i)
    };
    let serial: Vec<_> = (0..200).map(run).collect();
    let mut parallel: Vec<(usize, Vec<(String, f64)>)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..8)
            .map(|t| s.spawn(move || (t..200).step_by(8).map(|k| (k, run(k))).collect::<Vec<_>>()))
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("a worker ends"))
            .collect()
    });
    parallel.sort_by_key(|(k, _)| *k);
    let parallel: Vec<_> = parallel.into_iter().map(|(_, o)| o).collect();
    assert_eq!(serial, parallel, "bit-identical to the serial run");
    // Instances alive together read one copy of the map.
    let (a, _) = initialized();
    let (b, _) = initialized();
    let lookup = |i: &Instance| i.filter.as_ref().expect("initialized").lookup().clone();
    assert!(Arc::ptr_eq(&lookup(&a), &lookup(&b)));
}

#[test]
fn a_trace_holds_every_measurement_s_particles_and_the_outputs_estimate() {
    let file = std::env::temp_dir().join(format!("ftfusion-trace-{}.csv", std::process::id()));
    std::fs::remove_file(&file).ok();
    let (mut i, _) = instance();
    set_string(&mut i, "map", "peg.ftmap").expect("parameter");
    set_int(&mut i, "particles", 500).expect("parameter");
    set_string(&mut i, "trace", file.to_str().expect("UTF-8")).expect("parameter");
    i.enter_initialization_mode().expect("allowed");
    i.exit_initialization_mode().expect("valid parameters");
    let truth = [2.1e-3, -3.3e-3];
    for k in 0..2 {
        assert_eq!(contact(&mut i, k as f64, truth, [0.0, 0.0]), Status::Ok);
    }
    let text = std::fs::read(&file).expect("the trace was written");
    let back = model_description::trace::read(text.as_slice()).expect("it reads back");
    assert_eq!(back.len(), 2);
    for (k, m) in back.iter().enumerate() {
        assert_eq!(m.measurement, k as u32 + 1);
        assert_eq!(m.dofs, ["object.x", "object.y"]);
        assert_eq!(m.poses.len(), 500);
        let total: f64 = m.weights.iter().sum();
        assert!((total - 1.0).abs() < 1e-3, "weights sum to {total}");
    }
    // The last estimate row is what the outputs say.
    let last = &back[1];
    assert!((last.estimate[0] - real(&i, "object.x")).abs() < 1e-12);
    assert!((last.estimate[1] - real(&i, "object.y")).abs() < 1e-12);
    assert!((last.confidence - real(&i, "confidence")).abs() < 1e-12);
    std::fs::remove_file(&file).ok();
    // A file that cannot be created fails initialization naming it.
    let (mut i, _) = instance();
    set_string(&mut i, "map", "peg.ftmap").expect("parameter");
    set_string(&mut i, "trace", "/does/not/exist/trace.csv").expect("parameter");
    i.enter_initialization_mode().expect("allowed");
    let e = i.exit_initialization_mode().expect_err("no such folder");
    assert!(matches!(e, FusionError::Trace { .. }), "{e}");
    assert!(e.to_string().contains("/does/not/exist/trace.csv"), "{e}");
}
