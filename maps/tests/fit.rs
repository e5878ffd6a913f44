//! The fit measured on the meshes alone with parry (a task without `[geometry]`) against
//! the one its dimensions give: the insertion limit in every direction, the clearance, the
//! chamfers' depth and the rotational play.

use std::f64::consts::TAU;

use ftmap::Task;
use ftmap::exact::Pair;
use ftmap::task::cad::{self, Geometry, Role};
use ftmap::task::fit::{DIRECTIONS, Fit, MeshFit, largest, rotational_play};
use nalgebra::Vector3;

/// The peg_in_hole task with 0.3 mm chamfers on the peg's tip and 0.5 mm on the hole's
/// mouth, its meshes written to a temporary folder.
fn chamfered() -> Task {
    let mut task = Task::find("peg_in_hole").expect("task");
    let Some(Geometry::RoundPeg {
        peg_chamfer,
        hole_chamfer,
        ..
    }) = &mut task.geometry
    else {
        panic!("peg_in_hole is a round peg");
    };
    (*peg_chamfer, *hole_chamfer) = (0.0003, 0.0005);
    let dir = std::env::temp_dir().join(format!("ftmap-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    for m in cad::meshes(task.geometry().expect("geometry")) {
        let path = dir.join(m.file);
        std::fs::write(&path, cad::stl_bytes(&m.triangles)).expect("write");
        match m.role {
            Role::A => task.part_a.mesh = path,
            Role::B => task.part_b.mesh = path,
        }
    }
    task
}

#[test]
fn the_meshes_alone_give_the_fit_of_the_dimensions() {
    let tasks = [
        "peg_in_hole",
        "tight_peg",
        "octagon",
        "gear",
        "bearing_housing",
    ]
    .map(|name| Task::find(name).expect("task"));
    for task in tasks.into_iter().chain([chamfered()]) {
        let (name, geometry) = (&task.name, task.geometry().expect("geometry"));
        let pair = Pair::new(
            &task.part_a.load().expect("A"),
            &task.part_b.load().expect("B"),
        )
        .expect("pair");
        let measured = MeshFit::measure(&task, &pair).expect("fit");
        let (c, want) = (measured.clearance(), Fit::clearance(geometry));
        assert!((c - want).abs() < 0.5e-6, "{name}: clearance {c} vs {want}");
        // Flats across the fit (the octagon's 8 %) or none (a round fit's facets), at the
        // directions measured.
        let widest = (0..DIRECTIONS)
            .map(|k| Fit::insertion_limit(geometry, TAU * k as f64 / DIRECTIONS as f64))
            .fold(0.0, f64::max);
        assert!(
            (measured.anisotropy() - widest / want).abs() < 0.005,
            "{name}: the limit varies {:.4}x, the dimensions say {:.4}x",
            measured.anisotropy(),
            widest / want
        );
        // Halfway between the measured directions, where the octagon's limit bends most.
        for k in 0..16 {
            let theta = TAU * (k as f64 + 0.37) / 16.0;
            let (l, want) = (
                measured.insertion_limit(theta),
                geometry.insertion_limit(theta),
            );
            assert!(
                (l - want).abs() < 0.01 * want,
                "{name} at {theta}: {l} vs {want}"
            );
        }
        let (ch, want) = (measured.chamfers(), Fit::chamfers(geometry));
        assert!((ch - want).abs() < 2e-6, "{name}: chamfers {ch} vs {want}");
    }
    assert!(Fit::chamfers(chamfered().geometry().expect("geometry")) > 0.0);
}

#[test]
fn the_rotational_play_measured_on_the_meshes_is_the_geometry_s() {
    let pair_of = |task: &Task| {
        Pair::new(
            &task.part_a.load().expect("A"),
            &task.part_b.load().expect("B"),
        )
        .expect("pair")
    };
    // A round peg tilted about its tip's centre in a blind bore touches the mouth's rim:
    // r cos(t) + tan(t) depth = R (its tip's edge held clear of the floor).
    let task = Task::find("peg_in_hole").expect("task");
    let Ok(&Geometry::RoundPeg {
        peg_radius: r,
        hole_radius: big_r,
        hole_depth: depth,
        ..
    }) = task.geometry()
    else {
        panic!("peg_in_hole is a round peg");
    };
    let pair = pair_of(&task);
    let want = largest(|t| r * t.cos() + t.tan() * depth <= big_r, 0.1);
    let approach = task.contact.approach.into();
    for axis in [Vector3::x(), Vector3::y(), Vector3::new(1.0, 1.0, 0.0)] {
        let play = rotational_play(&pair, approach, axis).expect("a tilt play");
        assert!(
            (play - want).abs() < 0.01 * want,
            "tilt about {axis:?}: {play} rad against {want}"
        );
    }
    // About its own axis a round peg turns freely: no play to state.
    assert_eq!(rotational_play(&pair, approach, Vector3::z()), None);
    // The octagon turned about the approach: until a corner meets a flat.
    let task = Task::find("octagon").expect("task");
    let geometry = task.geometry().expect("geometry");
    let want = largest(|yaw| geometry.inserts_turned([0.0, 0.0], yaw), 0.1);
    let play = rotational_play(&pair_of(&task), task.contact.approach.into(), Vector3::z())
        .expect("a yaw play");
    assert!(
        (play - want).abs() < 0.01 * want,
        "octagon's yaw: {play} rad against {want}"
    );
}
