//! FT-Maps against cases computed independently inside the tests: a flat peg on a plate,
//! the pressure centroid of a peg resting on a hole's rim (integrated numerically here),
//! the lever of a peg tilted on a plate under the paper's model, the insertion depth, and
//! the symmetries of the peg and octagon maps, and pixels on an outline through pixel
//! centres counted by the share of them covered.

use std::f64::consts::PI;

use ftmap::depth::cpu::CpuBackend;
use ftmap::depth::{DepthBackend, PixelWindow, RenderJob, Surface, View};
use ftmap::generate::{GenerateOptions, generate, generate_with};
use ftmap::mesh::Mesh;
use ftmap::{FtMap, Task, WrenchModel};
use nalgebra::{Isometry3, Point3, Vector3};

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

/// Closed boxes in one mesh, each given as (x0, x1, y0, y1), from z0 to z1; each face
/// split along its diagonal from its first corner (the bottom from (x0, y0) to (x1, y1)).
fn boxes(rects: &[[f64; 4]], z0: f64, z1: f64) -> Mesh {
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for &[x0, x1, y0, y1] in rects {
        let o = vertices.len() as u32;
        for z in [z0, z1] {
            vertices.extend(
                [(x0, y0), (x1, y0), (x1, y1), (x0, y1)].map(|(x, y)| Point3::new(x, y, z)),
            );
        }
        let quads = [
            [0, 3, 2, 1],
            [4, 5, 6, 7],
            [0, 1, 5, 4],
            [1, 2, 6, 5],
            [2, 3, 7, 6],
            [3, 0, 4, 7],
        ];
        for [a, b, c, d] in quads.map(|q| q.map(|k| o + k)) {
            faces.extend([[a, b, c], [a, c, d]]);
        }
    }
    Mesh::from_parts(vertices, faces)
}

#[test]
fn a_face_s_outline_on_pixel_centres_counts_half_and_its_corners_a_quarter() {
    // A 20 x 20 pixel face seen from below, its sides on rows and columns of centres
    // (up to rounding: 0.01 m over 1 mm pixels), its diagonal through centres too.
    let pixel = 1e-3;
    let mesh = boxes(&[[-0.01, 0.01, -0.01, 0.01]], 0.0, 0.02);
    let job = RenderJob {
        mesh: &mesh,
        pose: Isometry3::identity(),
        view: View::along(Vector3::new(0.0, 0.0, -1.0)),
        surface: Surface::Bottom,
        window: PixelWindow::covering(-0.01, 0.01, -0.01, 0.01, pixel, 2),
        pixel,
    };
    let img = CpuBackend.render(&job).expect("render");
    // Every centre within the face's square, its sides included, has the face.
    assert_eq!(img.covered(), 21 * 21);
    let width = job.window.width as i64;
    let at = |k: u32| {
        let k = i64::from(k);
        [k % width + job.window.i0, k / width + job.window.j0]
    };
    let mut expected = Vec::new();
    for j in -10..=10i64 {
        for i in -10..=10i64 {
            let on = [i.abs() == 10, j.abs() == 10];
            match on {
                [true, true] => expected.push(([i, j], 0.25)),
                [true, false] | [false, true] => expected.push(([i, j], 0.5)),
                _ => {}
            }
        }
    }
    let found: Vec<([i64; 2], f32)> = img.coverage.iter().map(|&(k, s)| (at(k), s)).collect();
    assert_eq!(found.len(), expected.len(), "{found:?}");
    for ((p, s), (q, e)) in found.iter().zip(&expected) {
        assert_eq!(p, q);
        assert!((s - e).abs() < 1e-6, "{p:?}: {s}, expected {e}");
    }
    // Its area then is the face's, in pixels.
    let covered: f64 = img.coverage.iter().map(|&(_, s)| 1.0 - f64::from(s)).sum();
    assert!((img.covered() as f64 - covered - 400.0).abs() < 1e-4);
}

#[test]
fn strips_whose_edges_lie_on_pixel_centres_weigh_as_much_as_their_area() {
    // A square peg (80 x 80 pixels) over two boxes whose edges lie on pixel centres, as a
    // CAD part's round dimensions do on a lattice of round pixels: it rests on a strip 2
    // pixels wide along one box's edge and a strip 70 x 20 pixels on the other. The
    // coverage rule samples the narrow strip 3 pixels wide; counted so, the lever is 2
    // pixels off.
    let task = peg_task(1e-4, 1e-4);
    let p = task.depth.pixel;
    let h = 40.0 * p;
    let peg = prism(&square(h), 0.0, 0.04);
    let (far, narrow, tall) = (0.02, 2.0 * p, 20.0 * p);
    let plate = boxes(
        &[
            [-far, -h + narrow, -far, far],
            [-h + 10.0 * p, far, -far, -h + tall],
        ],
        -0.01,
        0.0,
    );
    let map = generate_with(
        &task,
        &peg,
        &plate,
        &CpuBackend,
        &GenerateOptions::default(),
        &|_| (),
    )
    .unwrap();
    // The two rectangles of the peg's face over the boxes: area and centroid.
    let rects = [[-h, -h + narrow, -h, h], [-h + 10.0 * p, h, -h, -h + tall]];
    let area: f64 = rects.iter().map(|r| (r[1] - r[0]) * (r[3] - r[2])).sum();
    let centre = |a: usize| {
        rects
            .iter()
            .map(|r| (r[1] - r[0]) * (r[3] - r[2]) * 0.5 * (r[2 * a] + r[2 * a + 1]))
            .sum::<f64>()
            / area
    };
    let c = cell_at(&map, 0.0, 0.0);
    // Force (0, 0, F) at the centroid: torque (cy F, -cx F) about the sensor on the axis.
    let lever = [-f64::from(c[4]) / F, f64::from(c[3]) / F];
    let miss = (lever[0] - centre(0)).hypot(lever[1] - centre(1));
    assert!(
        miss < 0.05 * p,
        "lever {lever:?}, the face's centroid over the boxes ({}, {}): {:.3} pixels off",
        centre(0),
        centre(1),
        miss / p
    );
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
