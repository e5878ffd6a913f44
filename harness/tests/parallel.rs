//! Campaigns on several workers: each worker's own MuJoCo scene, camera and FMU instance
//! give the results of a serial run, in trial order (each trial resets its world; only the
//! wall-clock times differ), and a worker that cannot open its rig fails the campaign
//! with its reason instead of hanging it.

use std::path::Path;

use ftmap::Task;
use harness::campaign::{Rig, TrialSet, random_offsets, run_campaign, run_parallel};
use harness::error::HarnessError;
use harness::eye::Eye;
use harness::fmu_driver::{Fmu, Settings, default_fmu_path};
use harness::sensor::Noise;
use harness::sim::Sim;
use harness::trial::{Slide, SlidePress, Strategy, TrialConfig, TrialResult, Truth};
use harness::vision::Detector;

/// The trial limits of these campaigns, with the FT-Map `map` and vision model `vision`.
fn config(task: &Task, map: Option<&Path>, vision: Option<&Path>) -> TrialConfig {
    TrialConfig {
        strategy: Strategy::Pf,
        max_contacts: 12,
        max_sim_time: 6.0,
        noise: Noise::TYPICAL,
        spiral_step: 0.0,
        spiral_radius: 0.0,
        slide: Some(Slide {
            clearance: task.fit().expect("fit").clearance(),
            press: SlidePress::Estimate,
        }),
        symmetry: None,
        twist: None,
        settings: Settings {
            map: map.map(Path::to_owned),
            vision: vision.map(Path::to_owned),
            ..Settings::default()
        },
    }
}

/// The rig of `task`: its committed scene and, with `vision`, its camera.
fn rig(task: &Task, vision: bool) -> harness::error::Result<Rig> {
    Ok(Rig {
        world: Box::new(Sim::of_task(task)?),
        eye: match vision {
            true => Some(Eye::open(task, 2.0, Detector::Gradient)?),
            false => None,
        },
    })
}

/// Serial and parallel (`jobs` workers) results of `trials` trials of `task` (seed 5).
fn both(task: &Task, trials: usize, jobs: usize, map: Option<&Path>, vision: bool) {
    let fmu = Fmu::load(&default_fmu_path()).unwrap_or_else(|e| panic!("{e}"));
    let mut serial = rig(task, vision).unwrap_or_else(|e| panic!("{e}"));
    let vision_file = serial.eye.as_ref().map(|e| {
        let path =
            std::env::temp_dir().join(format!("parallel-{}.vision.json", std::process::id()));
        e.model().save(&path).expect("vision model written");
        path
    });
    let cfg = config(task, map, vision_file.as_deref());
    let truths = Truth::objects(&random_offsets(trials, task.omega.size_trans, 5));
    let one = run_campaign(
        serial.world.as_mut(),
        Some(&fmu),
        serial.eye.as_mut(),
        &cfg,
        &truths,
        5,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut first = rig(task, vision).unwrap_or_else(|e| panic!("{e}"));
    let open = || rig(task, vision);
    let many = run_parallel(
        &mut first,
        jobs,
        &open,
        Some(&fmu),
        &cfg,
        TrialSet::all(&truths, 5),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    if let Some(p) = vision_file {
        let _ = std::fs::remove_file(p);
    }
    assert_eq!(many.len(), trials);
    let offsets: Vec<_> = many.iter().map(|r| r.offset).collect();
    let asked: Vec<_> = truths.iter().map(|t| t.object).collect();
    assert_eq!(offsets, asked, "the results in trial order");
    let untimed = |r: &[TrialResult]| r.iter().map(TrialResult::untimed).collect::<Vec<_>>();
    assert_eq!(untimed(&one), untimed(&many));
}

#[test]
fn three_workers_give_the_serial_peg_campaign() {
    let task = Task::find("peg_in_hole").expect("task peg_in_hole");
    both(&task, 7, 3, None, false);
}

#[test]
fn two_workers_with_cameras_give_the_serial_bearing_campaign() {
    let task = Task::find("bearing_housing").expect("task bearing_housing");
    let maps = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/maps");
    let (map, _) = ftmap::generate::cached(&task, &maps).expect("the bearing housing's map");
    both(&task, 4, 2, Some(&map), true);
}

#[test]
fn a_worker_that_cannot_open_its_rig_fails_the_campaign_with_the_reason() {
    let task = Task::find("peg_in_hole").expect("task peg_in_hole");
    let fmu = Fmu::load(&default_fmu_path()).unwrap_or_else(|e| panic!("{e}"));
    let cfg = config(&task, None, None);
    let truths = Truth::objects(&random_offsets(6, task.omega.size_trans, 5));
    let mut first = rig(&task, false).unwrap_or_else(|e| panic!("{e}"));
    let open = || -> harness::error::Result<Rig> {
        Err(HarnessError::Invalid {
            what: "rig",
            reason: "no second scene here".into(),
        })
    };
    let err = run_parallel(
        &mut first,
        2,
        &open,
        Some(&fmu),
        &cfg,
        TrialSet::all(&truths, 5),
    )
    .expect_err("the campaign fails");
    assert!(err.to_string().contains("no second scene here"), "{err}");
}
