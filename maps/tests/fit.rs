//! The fit measured on the meshes alone with parry (a task without `[geometry]`) against
//! the one its dimensions give: the insertion limit in every direction, the clearance and
//! the chamfers' depth.

use std::f64::consts::TAU;

use ftmap::Task;
use ftmap::exact::Pair;
use ftmap::task::cad::{self, Geometry, Role};
use ftmap::task::fit::{Fit, MeshFit};

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
