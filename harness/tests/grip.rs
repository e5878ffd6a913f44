//! A grip offset (task peg_grip, the paper's r1): the lever it adds in MuJoCo against the
//! map computed from CAD and against g x F, and a campaign through the FMU.

mod common;

use harness::campaign::random_offsets;
use harness::fmu_driver::{Fmu, Settings, default_fmu_path};
use harness::sensor::{Noise, map_wrench};
use harness::trial::{Slide, SlidePress, Strategy, TrialConfig, Truth};
use harness::world::World;

/// The peg_grip map computed from its CAD meshes, cached like a campaign's.
fn grip_map(task: &ftmap::Task) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/maps");
    ftmap::generate::cached(task, &dir)
        .expect("the map computed from CAD")
        .0
}

#[test]
fn a_peg_held_2_mm_off_centre_reads_the_lever_the_map_predicts() {
    let (task, mut sim) = common::scene("peg_grip");
    let (map, _) = ftmap::map::format::load_any(&grip_map(&task)).expect("the map loads");
    // (grip, object offset): rim contacts on three sides, the grip 2 mm off each way.
    for (grip, off) in [
        ([0.002, 0.0], [0.002, 0.001]),
        ([0.0, -0.002], [-0.001, 0.003]),
        ([-0.0015, 0.0014], [0.0, -0.0025]),
    ] {
        let mut torque = |g: [f64; 2]| {
            sim.set_grip(g);
            sim.set_object(off);
            let c = sim.contact_motion([0.0, 0.0]);
            assert!(c.settled && !c.inserted, "{g:?} {off:?}: {c:?}");
            map_wrench(c.raw)
        };
        let (held, centred) = (torque(grip), torque([0.0, 0.0]));
        let cell = |g: [f64; 2]| map.interpolate(&[g[0], g[1], off[0], off[1]]).unwrap();
        let (m_held, m_centred) = (cell(grip), cell([0.0, 0.0]));
        // The torque across the approach that the grip adds.
        let lever = |a: &[f64], b: &[f64]| [a[3] - b[3], a[4] - b[4]];
        let (measured, predicted) = (lever(&held, &centred), lever(&m_held, &m_centred));
        // The map's lever is g x F for the force it holds: (gy fz, -gx fz) across the approach.
        let fz = m_held[2];
        let cross = [grip[1] * fz, -grip[0] * fz];
        let size = predicted[0].hypot(predicted[1]);
        assert!(
            (predicted[0] - cross[0]).hypot(predicted[1] - cross[1]) < 0.02 * size,
            "grip {grip:?}: the map's lever {predicted:?}, g x F {cross:?}"
        );
        assert!(
            (measured[0] - predicted[0]).hypot(measured[1] - predicted[1]) < 0.1 * size,
            "grip {grip:?}, offset {off:?}: MuJoCo's lever {measured:?}, the map's {predicted:?}"
        );
    }
}

#[test]
fn five_trials_with_an_unknown_grip_go_in_through_the_fmu() {
    let task = ftmap::Task::find("peg_grip").expect("task peg_grip");
    let fmu = Fmu::load(&default_fmu_path()).unwrap_or_else(|e| panic!("{e}"));
    let most = 30;
    let cfg = TrialConfig {
        strategy: Strategy::Pf,
        max_contacts: most,
        // Slides across an early, wide spread take seconds of simulated time.
        max_sim_time: 40.0,
        noise: Noise::TYPICAL,
        spiral_step: 0.0,
        spiral_radius: 0.0,
        slide: Some(Slide {
            clearance: task.geometry().expect("a [geometry]").clearance(),
            press: SlidePress::Estimate,
        }),
        symmetry: None,
        twist: None,
        settings: Settings {
            map: Some(grip_map(&task)),
            ..Settings::default()
        },
    };
    let objects = random_offsets(5, task.omega.size_trans, 22);
    let grips = random_offsets(5, task.omega.size_grip.expect("a grip bound"), 23);
    let truths: Vec<Truth> = objects
        .into_iter()
        .zip(grips)
        .map(|(object, grip)| Truth {
            object,
            grip,
            ..Truth::default()
        })
        .collect();
    let open = || Box::new(common::scene("peg_grip").1) as Box<dyn World>;
    let results = common::run_on_two(&open, &fmu, &cfg, &truths, 22);
    // Every trial goes in. One of these five (offset -4.8, -4.6 mm, grip -1.86, -1.16 mm)
    // did not within 30 before the FMU's relocation: after three contacts the filter held a
    // grip at the edge of its bound (-1.97, -1.95 mm) with a 0.03 mm spread, explained the
    // rim torques by an object estimate 0.5 mm off, and crept 0.08 mm a contact towards
    // the truth.
    let failed: Vec<String> = results
        .iter()
        .filter(|r| !(r.success && r.contacts <= most))
        .map(|r| {
            format!(
                "offset {:?}, grip {:?}: {} contacts, success {}",
                r.offset, r.grip, r.contacts, r.success
            )
        })
        .collect();
    assert!(failed.is_empty(), "{failed:#?}");
}
