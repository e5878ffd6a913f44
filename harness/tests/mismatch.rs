//! The scene's model mismatch a campaign measures and hands the FMU where asked
//! (`--measure-mismatch`, harness::mismatch): zero where the world is the map, left alone
//! where the user sets it, recorded by where it came from, and a reported spread that tells
//! the truth in MuJoCo with it.

use std::sync::Arc;

use ftmap::map::format;
use harness::calibration::{Calibration, samples};
use harness::campaign::{Campaign, CampaignOptions, Offsets, SetupNote, random_offsets};
use harness::mismatch::{Given, Misses, Source, measure};
use harness::trial::Truth;
use harness::world::MapWorld;

mod common;

/// A campaign of `trials` on `task` with `seed`, force only, every FMU parameter as the
/// harness chooses, `mismatch`, `mismatch_angle` as given and `measure` the scene's misses
/// or not.
fn options(
    task: &str,
    trials: usize,
    seed: u64,
    mismatch: Option<[f64; 2]>,
    measure: bool,
) -> CampaignOptions {
    let out = std::env::temp_dir().join(format!("ftfusion-mismatch-{task}-{seed}"));
    serde_json::from_value(serde_json::json!({
        "task": task, "out": out, "seed": seed,
        "offsets": Offsets::Random { trials, half_width: None },
        "map": null, "vision": false, "vision_method": "Recalibration",
        "sigma_vision": null, "image_noise": 2.0, "detector": "Gradient",
        "strategy": "pf", "sensor_noise": true, "slide": true, "twist": true, "fmu": null,
        "max_contacts": null, "max_sim_time": null, "particles": null, "iterations": null,
        "sigma_torque": null, "sigma_force": null, "sigma_depth": null,
        "mismatch": mismatch.map(|m| m[0]), "mismatch_angle": mismatch.map(|m| m[1]),
        "measure_mismatch": measure,
        "lost": null, "world": "mujoco", "jobs": null, "shard": null,
    }))
    .expect("options")
}

/// Opens a campaign, returning it with the notes it made.
fn open(options: CampaignOptions) -> (Campaign, Vec<SetupNote>) {
    let mut notes = Vec::new();
    let campaign = Campaign::open(options, &mut |n| notes.push(n)).expect("the campaign opens");
    (campaign, notes)
}

fn measured(notes: &[SetupNote]) -> Option<Misses> {
    notes.iter().find_map(|n| match n {
        SetupNote::Mismatch { misses, .. } => Some(*misses),
        _ => None,
    })
}

#[test]
fn a_world_that_is_the_map_misses_nothing() {
    let (task, _) = common::scene("octagon");
    let (map, _) = format::load_any(&common::cached_map(&task)).expect("the octagon's map");
    let fit: Arc<dyn ftmap::task::fit::Fit> = task.fit().expect("a fit");
    let world = || MapWorld::new(map.clone(), fit.clone()).expect("a map world");
    let truths = Truth::objects(&random_offsets(24, task.omega.size_trans, 5));
    let near = Truth::objects(&random_offsets(24, 2e-4, 6));
    let misses = measure(&mut world(), &mut world(), &truths, &near).expect("presses");
    assert!(misses.pooled().presses >= 30, "{misses}");
    assert_eq!(
        (misses.pooled().along, misses.pooled().across),
        (0.0, 0.0),
        "{misses}"
    );
}

#[test]
fn the_report_names_where_the_fmu_s_mismatch_came_from() {
    // Given by the user: not measured over, recorded as given.
    let (mut campaign, notes) = open(options("peg_in_hole", 1, 1, Some([0.05, 0.04]), true));
    assert_eq!(measured(&notes), None, "{notes:?}");
    let outcome = campaign.run().expect("the trial runs");
    let given = |along, across| Given { along, across };
    assert_eq!(
        outcome.mismatch,
        Some(given(Source::Given(0.05), Source::Given(0.04)))
    );
    // Not asked for: the FMU's defaults, nothing measured.
    let (mut campaign, notes) = open(options("peg_in_hole", 1, 1, None, false));
    assert_eq!(measured(&notes), None, "{notes:?}");
    let outcome = campaign.run().expect("the trial runs");
    assert_eq!(
        outcome.mismatch,
        Some(given(Source::Default, Source::Default))
    );
    // One given, the other measured.
    let mut half = options("peg_in_hole", 1, 1, None, true);
    half.mismatch_angle = Some(0.04);
    let (mut campaign, notes) = open(half);
    let pooled = measured(&notes).expect("measured").pooled();
    let outcome = campaign.run().expect("the trial runs");
    assert_eq!(
        outcome.mismatch,
        Some(given(Source::Measured(pooled.along), Source::Given(0.04)))
    );
}

#[test]
fn with_the_measured_mismatch_the_bearing_s_spread_tells_the_truth_in_mujoco() {
    // Issue 10's calibration: the truth within 2 sigma in >= 80 % of the contact
    // measurements and the NEES within a factor 2 of its ideal, 2. With the FMU's defaults,
    // made for the map that misses most, bearing_housing's spread is too wide (NEES 0.84
    // over 100 trials of seed 31; 2.33 with the measured mismatch).
    let (mut campaign, notes) = open(options("bearing_housing", 30, 43, None, true));
    let misses = measured(&notes).unwrap_or_else(|| panic!("no mismatch measured: {notes:?}"));
    let pooled = misses.pooled();
    assert!(
        pooled.presses >= 80 && pooled.along < 0.1 && pooled.across < 0.05,
        "{misses}"
    );
    let outcome = campaign.run().expect("the trials run");
    assert!(outcome.results.iter().all(|r| r.success));
    let c = Calibration::of(&samples(&outcome.results));
    assert!(
        c.within_2sigma >= 0.8 && (1.0..=4.0).contains(&c.nees_mean),
        "within 2 sigma {}, NEES {} ({misses})",
        c.within_2sigma,
        c.nees_mean
    );
}

#[test]
fn on_a_tilted_hole_the_map_world_reads_part_b_s_tilt_as_the_scene_does() {
    // Presses with the TCP upright on part B tilted within Omega's ±2 degrees, over Omega
    // and near the goal, as `--measure-mismatch` makes them: the map world reads the map at
    // part B's tilt, the scene rests on its rim. A tilt read about the wrong axis or with
    // the wrong sign would miss by the torque's whole size and by up to pi; the scene's
    // own misses are a few percent and hundredths of a radian.
    let (task, mut sim) = common::tilted_with_band(Some(2e-6));
    let (map, _) = format::load_any(&common::cached_map(&task)).expect("the tilted map");
    let mut world = MapWorld::new(map, task.fit().expect("a fit")).expect("a map world");
    let tilted = |objects: Vec<[f64; 2]>, seed: u64| -> Vec<Truth> {
        let tilts = random_offsets(objects.len(), task.omega.size_rot, seed);
        objects
            .into_iter()
            .zip(tilts)
            .map(|(object, t)| Truth {
                object,
                rot: [t[0], t[1], 0.0],
                ..Truth::default()
            })
            .collect()
    };
    let omega = tilted(random_offsets(32, task.omega.size_trans, 7), 8);
    let near = tilted(random_offsets(24, 2e-4, 9), 10);
    let misses = measure(&mut sim, &mut world, &omega, &near).expect("presses");
    assert!(
        misses.omega.presses >= 24 && misses.near.presses >= 16,
        "{misses}"
    );
    let pooled = misses.pooled();
    assert!(
        pooled.along > 0.0 && pooled.along < 0.15 && pooled.across < 0.15,
        "{misses}"
    );
}
