//! The closed loop of Algorithm 1 through FtFusion.fmu (built by `cargo xtask fmu`).

use ftmap::Task;
use harness::campaign::{random_offsets, run_campaign};
use harness::fmu_driver::{Fmu, Settings, default_fmu_path};
use harness::sensor::Noise;
use harness::sim::open_task;
use harness::trial::{Strategy, TrialConfig};

/// Runs 5 trials of `task` (seed 7, F/T noise on) through the FMU with `map` (None: the
/// embedded one) and checks that each inserts the part within `most` contacts, the last
/// approach point within the fit's clearance of the truth.
fn five_trials_succeed_within(task: &str, map: Option<std::path::PathBuf>, most: usize) {
    let fmu = Fmu::load(&default_fmu_path()).unwrap_or_else(|e| panic!("{e}"));
    let (task, mut sim) = open_task(task).expect("the task and its scene");
    let cfg = TrialConfig {
        strategy: Strategy::Pf,
        max_contacts: most,
        max_sim_time: 5.0,
        noise: Noise::TYPICAL,
        spiral_step: 0.0,
        spiral_radius: 0.0,
        slide: None,
        settings: Settings {
            map,
            ..Settings::default()
        },
    };
    let offsets = random_offsets(5, task.omega.size_trans, 7);
    let results =
        run_campaign(&mut sim, Some(&fmu), None, &cfg, &offsets, 7).expect("the campaign runs");
    let clearance = task.geometry().expect("a [geometry]").clearance();
    for r in &results {
        assert!(
            r.success && r.contacts <= most,
            "{}, offset {:?}: {} contacts, success {}",
            task.name,
            r.offset,
            r.contacts,
            r.success
        );
        assert!(r.final_error < clearance + 1e-5, "{r:?}");
    }
}

#[test]
fn a_5_trial_peg_in_hole_campaign_through_the_fmu_succeeds_within_10_contacts() {
    five_trials_succeed_within("peg_in_hole", None, 10);
}

#[test]
fn a_5_trial_tight_fit_campaign_succeeds_within_15_contacts() {
    // 0.02 mm radial clearance; the map computed from the CAD meshes (cached like a campaign's).
    let task = Task::find("tight_peg").unwrap();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/maps");
    let (map, _) = ftmap::generate::cached(&task, &dir).unwrap();
    five_trials_succeed_within("tight_peg", Some(map), 15);
}
