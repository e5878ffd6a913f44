//! Every scene accepts part A where its CAD does: a centred part with part B moved off by
//! bisection stops going in within 10 micrometres of the geometry's insertion limit, in
//! eight directions (for the octagon, along its flat normals and between them).

mod common;

use ftmap::task::cad::Geometry;
use harness::boundary::{boundaries, boundary, chamfer_yield, directions};
use harness::scene::tasks_with_scenes;
use harness::sim::Sim;

/// The largest |MuJoCo - geometry| allowed (m): the README's figure.
const TOLERANCE: f64 = 10e-6;

#[test]
fn every_scene_stops_insertion_where_the_geometry_does() {
    let tasks = tasks_with_scenes().unwrap();
    assert_eq!(tasks.len(), 7);
    // A scene per thread: the bisections are independent.
    std::thread::scope(|s| {
        for task in &tasks {
            s.spawn(move || {
                let mut sim = Sim::of_task(task).unwrap();
                let found = boundaries(&mut sim, task, &directions(8)).unwrap();
                assert!(found.worst() <= TOLERANCE, "{found}");
                // The geometry's limit itself depends on the direction for the octagons only.
                let limits: Vec<f64> = found.directions.iter().map(|b| b.geometric).collect();
                let spread = limits.iter().fold(0.0f64, |m, &l| m.max(l))
                    - limits.iter().fold(1.0f64, |m, &l| m.min(l));
                let octagon = matches!(task.geometry(), Ok(Geometry::OctagonPeg { .. }));
                assert_eq!(spread > 1e-6, octagon, "{found}");
            });
        }
    });
}

/// 45-degree chamfers widen the capture by how far the robot's stiff x/y servos yield to the
/// chamfer's lateral push, F (1 - mu) / (1 + mu) / k (a part pressed down a 45-degree slope
/// against friction), not by the chamfers' width: 27 µm at 50 N, mu 0.3 and 1 MN/m, for a
/// 0.2 or a 0.5 mm chamfer pair alike. Along a flat normal of the octagon too.
#[test]
fn chamfers_widen_the_capture_by_what_the_servos_yield_to_their_slope() {
    for (name, peg, hole) in [
        ("peg_in_hole", 0.1e-3, 0.1e-3),
        ("peg_in_hole", 0.25e-3, 0.25e-3),
        ("octagon", 0.2e-3, 0.2e-3),
    ] {
        let (task, mut sim) = common::chamfered(name, peg, hole);
        let yield_ = chamfer_yield(&task).unwrap();
        assert!((yield_ - 26.9e-6).abs() < 0.1e-6, "{yield_}");
        let b = boundary(&mut sim, &task, 0.0).unwrap();
        assert!(b.chamfer_reach > b.geometric + yield_, "{name}: {b:?}");
        assert!(
            (b.excess() - yield_).abs() < 3e-6,
            "{name} with {peg} + {hole} m chamfers: goes in {:.1} µm beyond the fit, the servos' yield is {:.1} µm",
            b.excess() * 1e6,
            yield_ * 1e6
        );
    }
}
