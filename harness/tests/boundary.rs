//! Every scene accepts part A where its CAD does: a centred part with part B moved off by
//! bisection stops going in within 10 micrometres of the geometry's insertion limit, in
//! eight directions (for the octagon, along its flat normals and between them).

use harness::boundary::{boundaries, directions};
use harness::scene::tasks_with_scenes;
use harness::sim::Sim;

/// The largest |MuJoCo - geometry| allowed (m): the README's figure.
const TOLERANCE: f64 = 10e-6;

#[test]
fn every_scene_stops_insertion_where_the_geometry_does() {
    let tasks = tasks_with_scenes().unwrap();
    assert_eq!(tasks.len(), 5);
    for task in &tasks {
        let mut sim = Sim::of_task(task).unwrap();
        let found = boundaries(&mut sim, task, &directions(8)).unwrap();
        assert!(found.worst() <= TOLERANCE, "{found}");
        // The geometry's limit itself depends on the direction for the octagon only.
        let limits: Vec<f64> = found.directions.iter().map(|b| b.geometric).collect();
        let spread = limits.iter().fold(0.0f64, |m, &l| m.max(l))
            - limits.iter().fold(1.0f64, |m, &l| m.min(l));
        assert_eq!(spread > 1e-6, task.name == "octagon", "{found}");
    }
}
