//! The closed loop of Algorithm 1 through FtFusion.fmu (built by `cargo xtask fmu`).

use ftmap::Task;
use harness::boundary::chamfer_yield;
use harness::campaign::{random_offsets, run_campaign};
use harness::fmu_driver::{Fmu, Settings, default_fmu_path};
use harness::sensor::Noise;
use harness::sim::{Sim, open_task};
use harness::trial::{Strategy, TrialConfig, Truth};

mod common;

/// Runs 5 trials of `task` (seed 7, F/T noise on) through the FMU with `map` (None: the
/// embedded one) and checks that each inserts the part within `most` contacts, the last
/// approach point within the fit's clearance (and what the robot yields on a chamfer) of
/// the truth.
fn five_trials_succeed_within(
    task: &Task,
    sim: &mut Sim,
    map: Option<std::path::PathBuf>,
    most: usize,
) {
    let fmu = Fmu::load(&default_fmu_path()).unwrap_or_else(|e| panic!("{e}"));
    let cfg = TrialConfig {
        strategy: Strategy::Pf,
        max_contacts: most,
        max_sim_time: 5.0,
        noise: Noise::TYPICAL,
        spiral_step: 0.0,
        spiral_radius: 0.0,
        slide: None,
        symmetry: None,
        twist: None,
        settings: Settings {
            map,
            ..Settings::default()
        },
    };
    let offsets = random_offsets(5, task.omega.size_trans, 7);
    let results = run_campaign(sim, Some(&fmu), None, &cfg, &Truth::objects(&offsets), 7)
        .expect("the campaign runs");
    let clearance = task.geometry().expect("a [geometry]").clearance()
        + chamfer_yield(task).expect("a [geometry]");
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

/// The map of `task` computed from its CAD meshes, cached like a campaign's.
fn computed_map(task: &Task) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/maps");
    ftmap::generate::cached(task, &dir)
        .expect("the map computed from CAD")
        .0
}

#[test]
fn a_5_trial_peg_in_hole_campaign_through_the_fmu_succeeds_within_10_contacts() {
    let (task, mut sim) = open_task("peg_in_hole").expect("the task and its scene");
    five_trials_succeed_within(&task, &mut sim, None, 10);
}

#[test]
fn a_5_trial_tight_fit_campaign_succeeds_within_15_contacts() {
    // 0.02 mm radial clearance.
    let (task, mut sim) = open_task("tight_peg").expect("the task and its scene");
    let map = computed_map(&task);
    five_trials_succeed_within(&task, &mut sim, Some(map), 15);
}

#[test]
fn a_5_trial_campaign_with_chamfers_succeeds_within_5_contacts() {
    // peg_in_hole with a 0.5 + 0.5 mm chamfer pair: its map, scene and the FMU's use of the
    // contact height on the chamfer (100 trials: 2.89 contacts mean, max 3).
    let (task, mut sim) = common::chamfered("peg_in_hole", 0.5e-3, 0.5e-3);
    let map = computed_map(&task);
    five_trials_succeed_within(&task, &mut sim, Some(map), 5);
}

#[test]
fn a_5_trial_octagon_campaign_succeeds_within_10_contacts() {
    // The paper's task A: 0.05 mm across flats (100 trials: 2.87-3.01 contacts mean, max 5).
    let (task, mut sim) = open_task("octagon").expect("the task and its scene");
    let map = computed_map(&task);
    five_trials_succeed_within(&task, &mut sim, Some(map), 10);
}

#[test]
fn a_5_trial_gear_campaign_succeeds_within_10_contacts() {
    // A bore onto a toothed shaft (100 trials: 2.46-2.51 contacts mean, max 5).
    let (task, mut sim) = open_task("gear").expect("the task and its scene");
    let map = computed_map(&task);
    five_trials_succeed_within(&task, &mut sim, Some(map), 10);
}
