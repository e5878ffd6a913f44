//! `ftmap task new` from the peg_in_hole STLs written in millimetres, as a CAD system
//! exports them: the settings it derives are the hand-written task's, and so is its map,
//! cell for cell; parts not in the assembly's coordinates and units read wrongly are refused.

use std::path::{Path, PathBuf};

use ftmap::depth::cpu::CpuBackend;
use ftmap::generate::{GenerateOptions, generate};
use ftmap::task::Units;
use ftmap::task::cad;
use ftmap::task::create::{NewTask, create};
use ftmap::{NCH, Task};

/// The task's two STLs scaled to millimetres, in `dir`: (part A, part B).
fn millimetre_stls(task: &Task, dir: &Path) -> [PathBuf; 2] {
    [&task.part_a.mesh, &task.part_b.mesh].map(|p| {
        let mesh = ftmap::mesh::Mesh::load(p).expect("mesh");
        let triangles: Vec<[[f32; 3]; 3]> = (0..mesh.faces.len())
            .map(|i| {
                mesh.triangle(i)
                    .map(|v| v.coords.map(|c| (c * 1e3) as f32).into())
            })
            .collect();
        let out = dir.join(p.file_name().expect("name"));
        std::fs::write(&out, cad::stl_bytes(&triangles)).expect("write");
        out
    })
}

fn spec(part_a: PathBuf, part_b: PathBuf, units: Units, out: PathBuf) -> NewTask {
    NewTask {
        part_a,
        part_b,
        units,
        out,
        approach: [0.0, 0.0, -1.0],
        force: 50.0,
        friction: 0.3,
        size: None,
    }
}

#[test]
fn a_task_from_millimetre_stls_is_the_hand_written_one() {
    let dir = std::env::temp_dir().join(format!("ftmap-task-new-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let mut hand = Task::find("peg_in_hole").expect("task");
    let [a, b] = millimetre_stls(&hand, &dir);
    let (mut made, _) = create(&spec(a, b, Units::Mm, dir.join("mypeg"))).expect("task new");
    assert_eq!(made.part_a.units, Units::Mm);
    assert_eq!(made.contact.sensor_origin, hand.contact.sensor_origin);
    assert_eq!(made.contact.approach, hand.contact.approach);
    let pairs = [
        (made.omega.size_trans, hand.omega.size_trans),
        (made.omega.delta_trans, hand.omega.delta_trans),
        (made.depth.pixel, hand.depth.pixel),
        (made.depth.tolerance, hand.depth.tolerance),
    ];
    for (m, h) in pairs {
        assert!((m - h).abs() < 1e-12, "{m} vs {h}");
    }
    // A smaller Omega on both, to keep the test short: the hole and the rim around it.
    for t in [&mut made, &mut hand] {
        t.omega.size_trans = 0.0012;
    }
    let opts = GenerateOptions::default();
    let maps = [&made, &hand].map(|t| generate(t, &CpuBackend, &opts, &|_| ()).expect("map"));
    let tolerance = hand.depth.tolerance as f32;
    for cell in 0..maps[1].grid().cells() {
        let (m, h) = (maps[0].cell(cell), maps[1].cell(cell));
        assert!(
            (m[NCH - 1] - h[NCH - 1]).abs() <= tolerance,
            "cell {cell}: {m:?} vs {h:?}"
        );
        for k in 0..NCH - 1 {
            assert!(
                (m[k] - h[k]).abs() <= 1e-3 * 50.0,
                "cell {cell} channel {k}: {m:?} vs {h:?}"
            );
        }
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn parts_out_of_place_or_in_the_wrong_units_are_refused() {
    let dir = std::env::temp_dir().join(format!("ftmap-task-refused-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let peg = Task::find("peg_in_hole").expect("task");
    let [a, b] = millimetre_stls(&peg, &dir);
    let e = create(&spec(a.clone(), b, Units::M, dir.join("t1")))
        .expect_err("millimetres read as metres")
        .to_string();
    assert!(
        e.contains("millimetres read as metres") && e.contains("peg.stl"),
        "{e}"
    );
    // The peg against itself: the parts overlap at the goal.
    let e = create(&spec(a.clone(), a, Units::Mm, dir.join("t2")))
        .expect_err("overlap")
        .to_string();
    assert!(
        e.contains("overlap") && e.contains("assembly's coordinates"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).ok();
}
