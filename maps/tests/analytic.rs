//! FT-Maps against cases computed independently inside the tests: a flat peg on a plate,
//! the pressure centroid of a peg resting on a hole's rim (integrated numerically here),
//! the lever of a peg tilted on a plate under the paper's model, the insertion depth, and
//! the symmetries of the peg and octagon maps.

use std::f64::consts::PI;

use ftmap::depth::cpu::CpuBackend;
use ftmap::generate::{GenerateOptions, generate, generate_with};
use ftmap::mesh::Mesh;
use ftmap::{FtMap, Task, WrenchModel};
use nalgebra::Point3;

/// A closed prism over a convex polygon (counter-clockwise), from z0 to z1.
fn prism(polygon: &[(f64, f64)], z0: f64, z1: f64) -> Mesh {
    let n = polygon.len() as u32;
    let mut v: Vec<Point3<f64>> = polygon
        .iter()
        .map(|&(x, y)| Point3::new(x, y, z0))
        .collect();
    v.extend(polygon.iter().map(|&(x, y)| Point3::new(x, y, z1)));
    let (bc, tc) = (2 * n, 2 * n + 1);
    v.push(Point3::new(0.0, 0.0, z0));
    v.push(Point3::new(0.0, 0.0, z1));
    let mut f = Vec::new();
    for i in 0..n {
        let j = (i + 1) % n;
        f.push([bc, j, i]);
        f.push([tc, n + i, n + j]);
        f.push([i, j, n + j]);
        f.push([i, n + j, n + i]);
    }
    Mesh::from_parts(v, f)
}

fn disk_polygon(r: f64, n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|k| 2.0 * PI * k as f64 / n as f64)
        .map(|a| (r * a.cos(), r * a.sin()))
        .collect()
}

fn square(half: f64) -> Vec<(f64, f64)> {
    vec![(-half, -half), (half, -half), (half, half), (-half, half)]
}

/// The peg task with a small Omega: x, y in ±size at `step` (m).
fn peg_task(size: f64, step: f64) -> Task {
    let mut t = Task::find("peg_in_hole").expect("peg_in_hole task");
    t.omega.size_trans = size;
    t.omega.delta_trans = step;
    t
}

fn cell_at(map: &FtMap, x: f64, y: f64) -> [f32; 7] {
    *map.nearest(&[x, y]).expect("2-D map")
}

const F: f64 = 50.0;

#[test]
fn flat_peg_fully_on_a_plate_feels_pure_normal_force_under_both_models() {
    let task = peg_task(3e-3, 1e-3);
    let peg = prism(&disk_polygon(4.95e-3, 128), 0.0, 0.04);
    let plate = prism(&square(0.02), -0.01, 0.0);
    for model in [WrenchModel::Centroid, WrenchModel::Paper] {
        let map = generate_with(
            &task,
            &peg,
            &plate,
            &CpuBackend,
            &GenerateOptions { model, shard: None },
            &|_| (),
        )
        .unwrap();
        for cell in 0..map.grid().cells() {
            let c = map.cell(cell);
            assert!(
                c[0].abs() < 1e-6 && c[1].abs() < 1e-6,
                "{model:?} cell {cell}: {c:?}"
            );
            assert!(
                (f64::from(c[2]) - F).abs() < 1e-4,
                "{model:?} cell {cell}: {c:?}"
            );
            for t in &c[3..6] {
                assert!(t.abs() < 1e-6, "{model:?} cell {cell}: torque {c:?}");
            }
            assert!(
                c[6].abs() < 1e-7,
                "depth on a plate at the goal height is 0: {c:?}"
            );
        }
    }
}

/// Centroid of the part of the peg's disk (radius rp, at the origin) outside the hole's
/// disk (radius rh, centred at `o`), by midpoint integration on a fine grid.
fn crescent_centroid(rp: f64, rh: f64, o: (f64, f64)) -> (f64, f64) {
    let n = 2000;
    let h = 2.0 * rp / n as f64;
    let (mut sx, mut sy, mut a) = (0.0, 0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (-rp + (i as f64 + 0.5) * h, -rp + (j as f64 + 0.5) * h);
            if x * x + y * y <= rp * rp && (x - o.0).powi(2) + (y - o.1).powi(2) > rh * rh {
                sx += x;
                sy += y;
                a += 1.0;
            }
        }
    }
    (sx / a, sy / a)
}

#[test]
fn peg_on_the_rim_torque_follows_the_crescent_centroid() {
    let task = peg_task(3e-3, 1e-3);
    let map = generate(&task, &CpuBackend, &GenerateOptions::default(), &|_| ()).unwrap();
    let sensor_z = task.contact.sensor_origin[2];
    for (x, y) in [
        (1e-3, 0.0),
        (2e-3, 0.0),
        (3e-3, 0.0),
        (0.0, -2e-3),
        (2e-3, 2e-3),
        (-3e-3, 1e-3),
    ] {
        let c = cell_at(&map, x, y);
        let (cx, cy) = crescent_centroid(4.95e-3, 5.0e-3, (x, y));
        // Force (0, 0, F) at the centroid (cx, cy, h): torque about the sensor origin.
        let expected = (cy * F, -cx * F);
        let got = (f64::from(c[3]), f64::from(c[4]));
        let err = ((got.0 - expected.0).powi(2) + (got.1 - expected.1).powi(2)).sqrt();
        let mag = (expected.0.powi(2) + expected.1.powi(2)).sqrt();
        assert!(
            err < 0.02 * mag,
            "offset ({x}, {y}): torque {got:?}, crescent centroid gives {expected:?}"
        );
        // Perpendicular to the offset, along z x offset.
        let dot = got.0 * x + got.1 * y;
        let cross_z = -y * got.0 + x * got.1;
        assert!(
            dot.abs() < 0.02 * mag * (x * x + y * y).sqrt(),
            "torque not perpendicular to the offset"
        );
        assert!(cross_z > 0.0, "torque should point along z x offset");
        assert!(c[5].abs() < 1e-6, "no torque about the approach axis");
        assert!(
            (f64::from(c[6]) - 0.01).abs() < 1e-6,
            "resting on the rim 10 mm above the goal: {c:?}"
        );
        let _ = sensor_z;
    }
}

#[test]
fn centred_peg_inserts_to_depth_zero_and_feels_no_torque() {
    let map = generate(
        &peg_task(1e-3, 1e-4),
        &CpuBackend,
        &GenerateOptions::default(),
        &|_| (),
    )
    .unwrap();
    let c = cell_at(&map, 0.0, 0.0);
    assert!(
        c[6].abs() < 1e-7,
        "centred peg reaches the hole bottom: depth {}",
        c[6]
    );
    assert!(c[3].abs() < 1e-6 && c[4].abs() < 1e-6, "{c:?}");
    // One clearance step off (0.1 mm > 0.05 mm radial clearance): it rests on the rim.
    assert!((f64::from(cell_at(&map, 1e-4, 0.0)[6]) - 0.01).abs() < 1e-6);
}

#[test]
fn tilted_peg_on_a_plate_under_the_paper_model_levers_on_the_lowest_rim_point() {
    let mut task = peg_task(0.0, 1e-4);
    task.omega.object = vec!["rx".into(), "ry".into()];
    task.omega.size_rot = 2f64.to_radians();
    task.omega.delta_rot = 1f64.to_radians();
    task.depth.tolerance = 1e-6;
    let r = 4.95e-3;
    let peg = prism(&disk_polygon(r, 256), 0.0, 0.04);
    let plate = prism(&square(0.02), -0.01, 0.0);
    let opts = GenerateOptions {
        model: WrenchModel::Paper,
        shard: None,
    };
    let map = generate_with(&task, &peg, &plate, &CpuBackend, &opts, &|_| ()).unwrap();
    for cell in 0..map.grid().cells() {
        let coords = map.grid().coords(cell);
        let c = map.cell(cell);
        let t =
            (f64::from(c[3]).powi(2) + f64::from(c[4]).powi(2) + f64::from(c[5]).powi(2)).sqrt();
        if coords == [0.0, 0.0] {
            assert!(t < 1e-6, "flat: no torque, got {c:?}");
            continue;
        }
        // The plate tilted by (rx, ry) touches the disk first at the rim point where the
        // plate is highest; the projected lever is the peg radius (to a pixel).
        assert!(
            (t / F - r).abs() < 0.02 * r,
            "tilt {coords:?}: lever {} mm, expected {} mm",
            t / F * 1e3,
            r * 1e3
        );
        // The torque turns the peg about the axis perpendicular to the contact direction.
        let n = nalgebra::Rotation3::new(nalgebra::Vector3::new(coords[0], coords[1], 0.0))
            * nalgebra::Vector3::z();
        let contact_dir = nalgebra::Vector3::new(-n.x, -n.y, 0.0).normalize();
        let expected = contact_dir.cross(&nalgebra::Vector3::z());
        let got = nalgebra::Vector3::new(f64::from(c[3]), f64::from(c[4]), f64::from(c[5])) / t;
        assert!(
            got.dot(&expected) > 0.99,
            "tilt {coords:?}: torque direction {got:?}, expected {expected:?}"
        );
    }
}

#[test]
fn peg_map_has_the_mirror_symmetries_of_a_round_peg() {
    let map = generate(
        &peg_task(5e-3, 2e-4),
        &CpuBackend,
        &GenerateOptions::default(),
        &|_| (),
    )
    .unwrap();
    let axis = map.grid().axes()[0];
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    for i in 0..axis.count {
        for j in 0..axis.count {
            let (x, y) = (axis.value(i), axis.value(j));
            let c = cell_at(&map, x, y);
            let my = cell_at(&map, x, -y);
            let mx = cell_at(&map, -x, y);
            worst = worst
                .max(f64::from(c[3] + my[3]).abs())
                .max(f64::from(c[4] + mx[4]).abs());
            scale = scale.max(f64::from(c[3]).abs());
        }
    }
    assert!(scale > 0.05, "the map has torques ({scale} N.m)");
    assert!(
        worst < 1e-3 * scale,
        "tx(x,y) = -tx(x,-y), ty(x,y) = -ty(-x,y): worst {worst} of {scale}"
    );
}

#[test]
fn octagon_map_has_the_eightfold_symmetry_of_its_parts() {
    let mut task = Task::find("octagon").expect("octagon task");
    task.omega.size_trans = 3e-3;
    task.omega.delta_trans = 5e-4;
    let map = generate(&task, &CpuBackend, &GenerateOptions::default(), &|_| ()).unwrap();
    // Quarter turns and mirrors map the grid onto itself: exact, up to pixels.
    let axis = map.grid().axes()[0];
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    for i in 0..axis.count {
        for j in 0..axis.count {
            let (x, y) = (axis.value(i), axis.value(j));
            let c = cell_at(&map, x, y);
            let q = cell_at(&map, -y, x); // rotated by 90 degrees: torque rotates too
            worst = worst
                .max(f64::from(q[3] + c[4]).abs())
                .max(f64::from(q[4] - c[3]).abs());
            let d = cell_at(&map, y, x); // mirrored about the diagonal: (tx, ty) -> (-ty, -tx)
            worst = worst
                .max(f64::from(d[3] + c[4]).abs())
                .max(f64::from(d[4] + c[3]).abs());
            scale = scale.max(f64::from(c[3]).abs());
        }
    }
    assert!(scale > 0.05, "the map has torques ({scale} N.m)");
    assert!(
        worst < 0.02 * scale,
        "quarter-turn and diagonal symmetry: worst {worst} of {scale}"
    );
    // Eighth turns: |torque| at 2 mm along x equals |torque| at 2 mm along the diagonal.
    let mag = |t: [f64; 7]| (t[3] * t[3] + t[4] * t[4]).sqrt();
    let s = 2e-3 / 2f64.sqrt();
    let (a, b) = (
        mag(map.interpolate(&[2e-3, 0.0]).unwrap()),
        mag(map.interpolate(&[s, s]).unwrap()),
    );
    assert!((a - b).abs() < 0.05 * a, "|t| at 0 deg {a}, at 45 deg {b}");
}

#[test]
fn paper_model_gives_no_rim_torque_once_the_crescent_hull_holds_the_axis() {
    // The crescent (peg disk outside the hole) spans more than half the peg's circle, so
    // its convex hull contains the peg axis, exactly when the offset exceeds
    // sqrt(R_hole^2 - r_peg^2) = 0.705 mm. The crescent's tips thin out below a pixel, so
    // the pixel hull loses them: test clear of the critical offset by 0.5 mm above and
    // 0.2 mm below.
    let critical = (5.0e-3f64.powi(2) - 4.95e-3f64.powi(2)).sqrt();
    let opts = GenerateOptions {
        model: WrenchModel::Paper,
        shard: None,
    };
    let map = generate(&peg_task(3e-3, 1e-4), &CpuBackend, &opts, &|_| ()).unwrap();
    let axis = map.grid().axes()[0];
    for i in 0..axis.count {
        for j in 0..axis.count {
            let (x, y) = (axis.value(i), axis.value(j));
            let d = (x * x + y * y).sqrt();
            let c = cell_at(&map, x, y);
            let t = f64::from(c[3]).hypot(f64::from(c[4]));
            if d > critical + 5e-4 {
                assert!(t < 1e-6, "offset {d}: hull holds the axis, torque {t}");
            } else if d > 1.5e-4 && d < critical - 2e-4 {
                // Lever = distance from the axis to the chord between the crescent's tips,
                // (R^2 - r^2 - d^2) / 2d; the pixel hull's trimmed tips only lengthen it.
                let chord = (5.0e-3f64.powi(2) - 4.95e-3f64.powi(2) - d * d) / (2.0 * d);
                assert!(
                    t / F > chord - 5e-5,
                    "offset {d}: lever {} mm, chord at {} mm",
                    t / F * 1e3,
                    chord * 1e3
                );
                // Along z x offset, within the pixel hull's ragged edge (cos > 0.9).
                let along = (-y * f64::from(c[3]) + x * f64::from(c[4])) / (t * d);
                assert!(
                    along > 0.9,
                    "offset ({x}, {y}): torque {:?} not along z x offset",
                    &c[3..5]
                );
            }
        }
    }
}
