//! Parity of the wgpu depth backend with the CPU reference: depth images of a peg, a
//! blind-hole block and a box (straight and tilted, top and bottom surfaces), and the
//! contact summaries of the peg over the block for 10,201 shifts. Without a Vulkan
//! adapter it is skipped with a message, and fails under `CI=true`.
#![cfg(feature = "gpu")]

#[path = "../../tests/prerequisite.rs"]
mod prerequisite;

use std::f64::consts::TAU;
use std::time::Instant;

use ftmap::Task;
use ftmap::depth::cpu::CpuBackend;
use ftmap::depth::gpu::GpuBackend;
use ftmap::depth::{
    DepthBackend, DepthImage, ON_EDGE_HEIGHT, PixelWindow, RenderJob, Shift, Surface, View,
};
use ftmap::generate::{GenerateOptions, generate};
use ftmap::map::parity;
use ftmap::mesh::Mesh;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

const PIXEL: f64 = 1e-4;
const SEGMENTS: usize = 128;

/// Adds the ring of `SEGMENTS` vertices of radius `r` at height `z`; returns its first index.
fn ring(v: &mut Vec<Point3<f64>>, r: f64, z: f64) -> u32 {
    let first = v.len() as u32;
    v.extend((0..SEGMENTS).map(|k| {
        let a = TAU * k as f64 / SEGMENTS as f64;
        Point3::new(r * a.cos(), r * a.sin(), z)
    }));
    first
}

/// Quads between rings `lo` and `hi` (counter-clockwise seen from +radial when `outward`).
fn wall(f: &mut Vec<[u32; 3]>, lo: u32, hi: u32, outward: bool) {
    let n = SEGMENTS as u32;
    for k in 0..n {
        let k1 = (k + 1) % n;
        let (a, b, c, d) = (lo + k, lo + k1, hi + k1, hi + k);
        if outward {
            f.extend([[a, b, c], [a, c, d]]);
        } else {
            f.extend([[a, c, b], [a, d, c]]);
        }
    }
}

/// A fan closing ring `first` around `centre`, facing +z when `up`.
fn disc(f: &mut Vec<[u32; 3]>, centre: u32, first: u32, up: bool) {
    let n = SEGMENTS as u32;
    for k in 0..n {
        let (a, b) = (first + k, first + (k + 1) % n);
        f.push(if up { [centre, a, b] } else { [centre, b, a] });
    }
}

/// A cylinder of radius `r` from z = 0 to z = `h` (a peg with a flat bottom at z = 0).
fn peg(r: f64, h: f64) -> Mesh {
    let (mut v, mut f) = (vec![Point3::origin(), Point3::new(0.0, 0.0, h)], Vec::new());
    let (lo, hi) = (ring(&mut v, r, 0.0), ring(&mut v, r, h));
    disc(&mut f, 0, lo, false);
    disc(&mut f, 1, hi, true);
    wall(&mut f, lo, hi, true);
    Mesh::from_parts(v, f)
}

/// A round block of radius `outer` from z = -`depth` to 0 with a blind hole of radius
/// `hole` and depth `depth` / 2 in its top.
fn block(outer: f64, hole: f64, depth: f64) -> Mesh {
    let floor = -depth / 2.0;
    let (mut v, mut f) = (
        vec![Point3::new(0.0, 0.0, -depth), Point3::new(0.0, 0.0, floor)],
        Vec::new(),
    );
    let (out_lo, out_hi) = (ring(&mut v, outer, -depth), ring(&mut v, outer, 0.0));
    let (in_lo, in_hi) = (ring(&mut v, hole, floor), ring(&mut v, hole, 0.0));
    wall(&mut f, out_lo, out_hi, true);
    wall(&mut f, in_lo, in_hi, false);
    disc(&mut f, 0, out_lo, false);
    disc(&mut f, 1, in_lo, true);
    // The top annulus between the hole and the outer rim, facing +z.
    let n = SEGMENTS as u32;
    for k in 0..n {
        let k1 = (k + 1) % n;
        f.extend([
            [in_hi + k, out_hi + k, out_hi + k1],
            [in_hi + k, out_hi + k1, in_hi + k1],
        ]);
    }
    Mesh::from_parts(v, f)
}

/// An axis-aligned box with half sides `hx`, `hy` from z = 0 to `h`.
fn cuboid(hx: f64, hy: f64, h: f64) -> Mesh {
    let v = (0..8)
        .map(|k| {
            Point3::new(
                if k & 1 == 0 { -hx } else { hx },
                if k & 2 == 0 { -hy } else { hy },
                if k & 4 == 0 { 0.0 } else { h },
            )
        })
        .collect();
    let f = vec![
        [0, 2, 1],
        [1, 2, 3], // bottom
        [4, 5, 6],
        [5, 7, 6], // top
        [0, 1, 5],
        [0, 5, 4], // -y
        [2, 6, 7],
        [2, 7, 3], // +y
        [0, 4, 6],
        [0, 6, 2], // -x
        [1, 3, 7],
        [1, 7, 5], // +x
    ];
    Mesh::from_parts(v, f)
}

fn tilted(x: f64, y: f64, z: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(0.05, -0.03, 0.2),
    )
}

fn window_of(mesh: &Mesh, pose: &Isometry3<f64>, view: &View, margin: i64) -> PixelWindow {
    let p: Vec<[f64; 3]> = mesh
        .vertices
        .iter()
        .map(|q| view.project(&(pose * q)))
        .collect();
    let bound = |c: usize, f: fn(f64, f64) -> f64, init: f64| p.iter().map(|q| q[c]).fold(init, f);
    PixelWindow::covering(
        bound(0, f64::min, f64::INFINITY),
        bound(0, f64::max, f64::NEG_INFINITY),
        bound(1, f64::min, f64::INFINITY),
        bound(1, f64::max, f64::NEG_INFINITY),
        PIXEL,
        margin,
    )
}

fn job<'a>(mesh: &'a Mesh, pose: Isometry3<f64>, surface: Surface, margin: i64) -> RenderJob<'a> {
    let view = View::along(-Vector3::z());
    RenderJob {
        mesh,
        pose,
        view,
        surface,
        window: window_of(mesh, &pose, &view, margin),
        pixel: PIXEL,
    }
}

fn gpu() -> Option<GpuBackend> {
    match GpuBackend::new() {
        Ok(g) => {
            eprintln!("GPU parity on {}", g.name());
            Some(g)
        }
        // Only a missing adapter is a missing prerequisite: a shader or pipeline the
        // adapter refuses is a fault of the backend.
        Err(e) if e.to_string().contains("no Vulkan adapter") => {
            prerequisite::missing(
                &format!("no Vulkan adapter for GPU parity: {e}"),
                "scripts/setup.sh installs Mesa's lavapipe",
            );
            None
        }
        Err(e) => panic!("the GPU backend fails to start: {e}"),
    }
}

/// Compares two renderings; returns (covered pixels, coverage or triangle mismatches, max height error).
fn compare(job: &RenderJob<'_>, cpu: &DepthImage, gpu: &DepthImage) -> (usize, usize, f32) {
    assert_eq!(
        (cpu.window, cpu.height.len(), cpu.tri.len()),
        (gpu.window, gpu.height.len(), gpu.tri.len())
    );
    let normal = |t: u32| job.pose * job.mesh.normal(t as usize);
    let (mut mismatched, mut max_err) = (0, 0.0f32);
    let width = cpu.window.width;
    let mut mismatch = |k: usize| {
        if mismatched < 5 {
            eprintln!(
                "  mismatch at column {} row {}: CPU height {:e} triangle {}, GPU {:e} triangle {}",
                k % width,
                k / width,
                cpu.height[k],
                cpu.tri[k],
                gpu.height[k],
                gpu.tri[k]
            );
        }
        mismatched += 1;
    };
    for k in 0..cpu.height.len() {
        let (hc, hg) = (cpu.height[k], gpu.height[k]);
        match (hc.is_finite(), hg.is_finite()) {
            (true, true) => {
                max_err = max_err.max((hc - hg).abs());
                // On an edge shared by two triangles either may win: fine when they face
                // alike, or where the two planes meet there, each at the pixel's height up
                // to the coverage rule's rounding (a ridge, each backend rounding the
                // steeper face's tolerance its own way).
                if cpu.tri[k] != gpu.tri[k]
                    && normal(cpu.tri[k]).dot(&normal(gpu.tri[k])) < 1.0 - 1e-9
                    && f64::from((hc - hg).abs()) > 2.0 * ON_EDGE_HEIGHT
                {
                    mismatch(k);
                }
            }
            (false, false) => assert_eq!((hc, gpu.tri[k]), (hg, u32::MAX), "empty pixels agree"),
            _ => mismatch(k),
        }
    }
    (cpu.covered(), mismatched, max_err)
}

#[test]
fn depth_images_match_the_cpu() {
    let Some(gpu) = gpu() else { return };
    let (peg, block, off_box) = (
        peg(4.95e-3, 20e-3),
        block(9.95e-3, 5.0e-3, 10e-3),
        cuboid(7.45e-3, 6.35e-3, 5e-3),
    );
    let lattice_box = cuboid(5e-3, 3e-3, 5e-3);
    let still = Isometry3::translation(3.3e-5, -1.7e-5, 0.0);
    let cases = [
        ("peg bottom", &peg, still, Surface::Bottom),
        ("peg top", &peg, still, Surface::Top),
        (
            "peg tilted bottom",
            &peg,
            tilted(1e-3, 2e-3, 1e-3),
            Surface::Bottom,
        ),
        ("block top", &block, still, Surface::Top),
        (
            "block tilted top",
            &block,
            tilted(-2e-3, 1e-3, 0.0),
            Surface::Top,
        ),
        (
            "block bottom",
            &block,
            Isometry3::identity(),
            Surface::Bottom,
        ),
        (
            "box top off the lattice",
            &off_box,
            Isometry3::identity(),
            Surface::Top,
        ),
        (
            "box bottom on the lattice",
            &lattice_box,
            Isometry3::identity(),
            Surface::Bottom,
        ),
        (
            "box tilted bottom",
            &off_box,
            tilted(0.0, 0.0, 0.0),
            Surface::Bottom,
        ),
    ];
    for (name, mesh, pose, surface) in cases {
        let job = job(mesh, pose, surface, 3);
        let c = CpuBackend.render(&job).expect("CPU render");
        let g = gpu.render(&job).expect("GPU render");
        let (covered, mismatched, err) = compare(&job, &c, &g);
        eprintln!(
            "{name}: {}x{} px, {covered} covered, {mismatched} coverage/triangle mismatches, max height error {err:.2e} m",
            job.window.width, job.window.height
        );
        assert!(covered > 1000, "{name}: the mesh is in the window");
        assert!(err <= 1e-6, "{name}: height error {err} m");
        // One coverage rule, tolerant of both backends' rounding: not a pixel apart.
        assert_eq!(
            mismatched, 0,
            "{name}: {mismatched} of {covered} pixels differ"
        );
    }
}

#[test]
fn large_windows_render_in_tiles() {
    let Some(gpu) = gpu() else { return };
    // 0.01 mm pixels: a 5000 x 5000 px window, more than one 4096 px tile per side.
    let mesh = cuboid(2.4995e-2, 2.4995e-2, 1e-3);
    let view = View::along(-Vector3::z());
    let pose = tilted(0.0, 0.0, 0.0);
    let pixel = 1e-5;
    let window = PixelWindow {
        i0: -2500,
        j0: -2500,
        width: 5000,
        height: 5000,
    };
    let job = RenderJob {
        mesh: &mesh,
        pose,
        view,
        surface: Surface::Top,
        window,
        pixel,
    };
    let (c, g) = (
        CpuBackend.render(&job).expect("CPU render"),
        gpu.render(&job).expect("GPU render"),
    );
    let (covered, mismatched, err) = compare(&job, &c, &g);
    eprintln!(
        "tiled box: {covered} covered, {mismatched} mismatches, max height error {err:.2e} m"
    );
    assert!(covered > 1_000_000 && err <= 1e-6 && mismatched == 0);
}

#[test]
fn contacts_match_the_cpu() {
    let Some(gpu) = gpu() else { return };
    let (peg, block) = (peg(4.95e-3, 20e-3), block(9.95e-3, 5.0e-3, 10e-3));
    let cpu = CpuBackend;
    // A: the tilted peg just above the block, seen along the approach; B: the block.
    let a_job = job(&peg, tilted(2e-5, -3e-5, 0.4e-3), Surface::Bottom, 0);
    let a = cpu.render(&a_job).expect("render A");
    let r = 50;
    let mut b_job = job(&block, Isometry3::identity(), Surface::Top, 0);
    b_job.window = PixelWindow {
        i0: a.window.i0 - r,
        j0: a.window.j0 - r,
        width: a.window.width + 2 * r as usize,
        height: a.window.height + 2 * r as usize,
    };
    let b = cpu.render(&b_job).expect("render B");
    let normals: Vec<[f32; 3]> = (0..block.faces.len())
        .map(|t| {
            let n = block.normal(t);
            [
                n.dot(&b_job.view.u) as f32,
                n.dot(&b_job.view.v) as f32,
                n.dot(&b_job.view.w) as f32,
            ]
        })
        .collect();
    let shifts: Vec<Shift> = (-r..=r)
        .flat_map(|dv| (-r..=r).map(move |du| Shift { du, dv }))
        .collect();
    let tol = 2e-5;
    let start = Instant::now();
    let want = cpu
        .contacts(&a, &b, &normals, &shifts, tol)
        .expect("CPU contacts");
    let cpu_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let got = gpu
        .contacts(&a, &b, &normals, &shifts, tol)
        .expect("GPU contacts");
    let gpu_s = start.elapsed().as_secs_f64();
    eprintln!(
        "contacts: A {}x{} px, B {}x{} px, {} shifts: CPU {:.0} configs/s, {} {:.0} configs/s",
        a.window.width,
        a.window.height,
        b.window.width,
        b.window.height,
        shifts.len(),
        shifts.len() as f64 / cpu_s,
        gpu.name(),
        shifts.len() as f64 / gpu_s
    );
    assert_eq!(want.len(), got.len());
    let close = |x: f64, y: f64, scale: f64| (x - y).abs() <= 1e-4 * x.abs().max(scale);
    let (mut touching, mut no_overlap) = (0, 0);
    for (s, (w, g)) in shifts.iter().zip(want.iter().zip(&got)) {
        let ctx = format!("shift {s:?}: CPU {w:?}\nGPU {g:?}");
        assert!(
            w.gap == g.gap || (w.gap - g.gap).abs() <= 1e-6,
            "gap, {ctx}"
        );
        assert_eq!(w.count, g.count, "count, {ctx}");
        let n = f64::from(w.count);
        assert!(
            close(w.sum_col, g.sum_col, n) && close(w.sum_row, g.sum_row, n),
            "centroid sums, {ctx}"
        );
        assert!(
            close(w.sum_height, g.sum_height, n * 1e-3),
            "height sum, {ctx}"
        );
        for k in 0..3 {
            assert!(
                close(w.sum_normal[k], g.sum_normal[k], n),
                "normal sum {k}, {ctx}"
            );
        }
        assert_eq!(w.rows, g.rows, "rows, {ctx}");
        if w.gap.is_finite() {
            touching += 1;
        } else {
            no_overlap += 1;
        }
    }
    eprintln!("contacts: {touching} shifts with overlap, {no_overlap} without: all fields agree");
    assert!(touching > 1000, "the peg meets the block");
    // Nothing under A: no contact anywhere.
    let nothing = DepthImage::empty(b.window, PIXEL, Surface::Top);
    let got = gpu
        .contacts(&a, &nothing, &normals, &shifts[..10], tol)
        .expect("GPU contacts");
    assert!(
        got.iter()
            .all(|c| c.gap == f32::INFINITY && c.count == 0 && c.rows.is_empty()),
        "{got:?}"
    );
}

#[test]
fn a_tilted_map_matches_the_cpu_cell_for_cell() {
    let Some(gpu) = gpu() else { return };
    // peg_in_hole_4dof's meshes on a coarse grid: x, y in steps of 0.8 mm, tilts of 0.5
    // degrees about x and y; the tilted peg inside the hole rests where one of the hole's
    // walls, nearly edge-on, meets the pixel lattice (a cell the backends once put 5 mm
    // apart).
    let meshes = concat!(env!("CARGO_MANIFEST_DIR"), "/../models_mjcf/peg_in_hole");
    let dir = std::env::temp_dir().join(format!("ftmap-parity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary folder");
    let toml = format!(
        r#"name = "tilted_parity"
[part_a]
mesh = "{meshes}/peg.stl"
[part_b]
mesh = "{meshes}/block.stl"
[contact]
approach = [0.0, 0.0, -1.0]
force = 50.0
friction = 0.3
sensor_origin = [0.0, 0.0, 0.06]
[omega]
object = ["x", "y", "rx", "ry"]
size_trans = 0.0008
delta_trans = 0.0008
size_rot = 0.008726646259971648
delta_rot = 0.008726646259971648
[depth]
pixel = 0.0001
tolerance = 0.000002
"#
    );
    let path = dir.join("task.toml");
    std::fs::write(&path, toml).expect("task file");
    let task = Task::load(&path).expect("task");
    let opts = GenerateOptions::default();
    let cpu = generate(&task, &CpuBackend, &opts, &|_| ()).expect("CPU map");
    let gpu = generate(&task, &gpu, &opts, &|_| ()).expect("GPU map");
    let p = parity::compare(&cpu, &gpu).expect("one grid");
    eprintln!("tilted map: {p:?}");
    assert!(p.cells >= 225, "{p:?}");
    assert_eq!((p.contact_differs, p.lever_over_pixel), (0, 0), "{p:?}");
    assert!(p.max_lever < 1e-6 && p.max_depth < 1e-8, "{p:?}");
    std::fs::remove_dir_all(&dir).ok();
}
