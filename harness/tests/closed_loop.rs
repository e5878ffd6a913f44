//! The closed loop of Algorithm 1 through FtFusion.fmu (built by `cargo xtask fmu`).

mod common;

use harness::campaign::{random_offsets, run_campaign};
use harness::fmu_driver::{Fmu, Settings, default_fmu_path};
use harness::sensor::Noise;
use harness::trial::{Strategy, TrialConfig};

#[test]
fn a_5_trial_peg_in_hole_campaign_through_the_fmu_succeeds_within_10_contacts() {
    let fmu = Fmu::load(&default_fmu_path()).unwrap_or_else(|e| panic!("{e}"));
    let (task, mut sim) = common::peg();
    let cfg = TrialConfig {
        strategy: Strategy::Pf,
        max_contacts: 10,
        max_sim_time: 5.0,
        noise: Noise::TYPICAL,
        spiral_step: 0.0,
        spiral_radius: 0.0,
        settings: Settings::default(),
    };
    let offsets = random_offsets(5, task.omega.size_trans, 7);
    let results = run_campaign(&mut sim, Some(&fmu), None, &cfg, &offsets, 7).unwrap();
    for r in &results {
        assert!(
            r.success && r.contacts <= 10,
            "offset {:?}: {} contacts, success {}",
            r.offset,
            r.contacts,
            r.success
        );
        assert!(r.final_error < 0.0002, "{r:?}");
    }
}
