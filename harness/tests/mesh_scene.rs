//! Scenes for parts given by their meshes alone: a task made by `ftmap task new` from the
//! peg_in_hole STLs gets a scene whose clearance is the parametric scene's within the bound,
//! and a 5-trial campaign in it succeeds in every trial; a part B with a cavity under its
//! top (no height field along the approach) gets no scene, and the error says why; meshes in
//! ASCII STL and millimetres get a scene that MuJoCo loads; a square peg reads the torque of
//! the strips it rests on, the thinnest included.

use std::path::{Path, PathBuf};

use ftmap::Task;
use ftmap::mesh::Mesh;
use ftmap::task::Units;
use ftmap::task::cad;
use ftmap::task::create::{NewTask, create};
use harness::campaign::{random_offsets, run_campaign};
use harness::decompose::{BOUND, mesh_scene};
use harness::fmu_driver::{Fmu, Settings, default_fmu_path};
use harness::scene::{Piece, SPHERE_RADIUS, SceneSpec, Visual};
use harness::sensor::Noise;
use harness::sim::{Sim, regenerate_scene};
use harness::trial::{Strategy, TrialConfig, Truth};
use harness::world::World;
use nalgebra::{Isometry3, Point3, Vector3};
use parry3d_f64::shape::{ConvexPolyhedron, Cuboid, SharedShape};

/// A scratch folder for this test process.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mesh-scene-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    dir
}

/// The task `ftmap task new` makes in `out` from the meshes `part_a` and `part_b` in
/// `units`, with its default approach, force, friction and Omega.
fn task_new(part_a: PathBuf, part_b: PathBuf, units: Units, out: PathBuf) -> Task {
    create(&NewTask {
        part_a,
        part_b,
        units,
        out,
        approach: [0.0, 0.0, -1.0],
        force: 50.0,
        friction: 0.3,
        size: None,
    })
    .expect("task new")
    .0
}

/// A task made by `ftmap task new` from the peg_in_hole STLs alone.
fn mypeg() -> Task {
    let peg = Task::find("peg_in_hole").expect("task");
    task_new(
        peg.part_a.mesh.clone(),
        peg.part_b.mesh.clone(),
        Units::M,
        scratch("task").join("mypeg"),
    )
}

/// A scene's pieces as parry shapes (boxes and hulls: what the peg scenes use).
fn shapes(spec: &SceneSpec) -> Vec<(Isometry3<f64>, SharedShape)> {
    spec.pieces
        .iter()
        .map(|p| match p {
            Piece::Box { center, half } => (
                Isometry3::translation(center[0], center[1], center[2]),
                SharedShape::new(Cuboid::new(Vector3::from(*half))),
            ),
            Piece::Hull { center, vertices } => {
                let points: Vec<Point3<f64>> = vertices.iter().map(|&v| v.into()).collect();
                (
                    Isometry3::translation(center[0], center[1], center[2]),
                    SharedShape::new(ConvexPolyhedron::from_convex_hull(&points).expect("hull")),
                )
            }
            Piece::Cylinder { .. } => panic!("no cylinders in a peg scene"),
        })
        .collect()
}

/// The scene's radial clearance: the hole's radius halfway down (the nearest piece to the
/// axis) less the bed's (its outermost sphere's reach).
fn clearance(spec: &SceneSpec) -> f64 {
    let mid = Point3::new(0.0, 0.0, spec.top / 2.0);
    let hole = shapes(spec)
        .iter()
        .map(|(pose, shape)| shape.distance_to_point(pose, &mid, true))
        .fold(f64::INFINITY, f64::min);
    let bed = spec
        .face
        .bed()
        .iter()
        .map(|s| s.at[0].hypot(s.at[1]) + SPHERE_RADIUS)
        .fold(0.0, f64::max);
    hole - bed
}

#[test]
fn a_scene_from_the_meshes_alone_keeps_the_clearance_and_its_campaign_succeeds() {
    let task = mypeg();
    let spec = SceneSpec::of_task(&task).expect("a scene from the meshes");
    let parametric = SceneSpec::of_task(&Task::find("peg_in_hole").expect("task")).expect("scene");
    let (c, want) = (clearance(&spec), clearance(&parametric));
    assert!(
        (c - want).abs() <= BOUND,
        "clearance {:.2} µm from the meshes, {:.2} µm parametric",
        c * 1e6,
        want * 1e6
    );
    assert!(
        spec.deviation.is_some_and(|d| d <= BOUND),
        "{:?}",
        spec.deviation
    );
    assert!(
        (spec.top - parametric.top).abs() < 1e-9,
        "{} vs {}",
        spec.top,
        parametric.top
    );

    regenerate_scene(&task).expect("the scene loads in MuJoCo");
    let mut sim = Sim::of_task(&task).expect("the scene");
    let fmu = Fmu::load(&default_fmu_path()).unwrap_or_else(|e| panic!("{e}"));
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/maps");
    let (map, _) = ftmap::generate::cached(&task, &dir).expect("the map");
    let cfg = TrialConfig {
        strategy: Strategy::Pf,
        max_contacts: 10,
        max_sim_time: 5.0,
        noise: Noise::TYPICAL,
        spiral_step: 0.0,
        spiral_radius: 0.0,
        slide: None,
        symmetry: None,
        twist: None,
        settings: Settings {
            map: Some(map),
            ..Settings::default()
        },
    };
    let offsets = random_offsets(5, task.omega.size_trans, 7);
    let results = run_campaign(
        &mut sim,
        Some(&fmu),
        None,
        &cfg,
        &Truth::objects(&offsets),
        7,
    )
    .expect("the campaign runs");
    for r in &results {
        assert!(
            r.success,
            "offset {:?}: {} contacts, failed",
            r.offset, r.contacts
        );
    }
}

/// A closed box from `lo` to `hi`, its triangles facing out (or in, for a cavity).
fn cuboid(lo: [f32; 3], hi: [f32; 3], outward: bool) -> Vec<[[f32; 3]; 3]> {
    let mesh = Mesh::cuboid(lo.map(f64::from), hi.map(f64::from));
    (0..mesh.faces.len())
        .map(|t| {
            let [p, q, r] = mesh.triangle(t).map(|p| [p.x, p.y, p.z].map(|c| c as f32));
            if outward { [p, q, r] } else { [p, r, q] }
        })
        .collect()
}

#[test]
fn a_part_b_with_a_cavity_under_its_top_gets_no_scene_and_is_told_why() {
    let dir = scratch("cavity");
    let mut triangles = cuboid([-0.02, -0.02, -0.01], [0.02, 0.02, 0.01], true);
    triangles.extend(cuboid([-0.003, -0.003, 0.0], [0.003, 0.003, 0.005], false));
    let path = dir.join("hollow.stl");
    std::fs::write(&path, cad::stl_bytes(&triangles)).expect("write");
    let mut task = Task::find("peg_in_hole").expect("task");
    task.geometry = None;
    task.part_b.mesh = path;
    let e = mesh_scene(&task).expect_err("no scene").to_string();
    assert!(e.contains("not a height field") && e.contains("µm"), "{e}");
    std::fs::remove_dir_all(dir).ok();
}

/// `path`'s triangles written as ASCII STL, coordinates times `scale`.
fn ascii_stl(path: &Path, scale: f64, out: &Path) {
    let mesh = ftmap::mesh::Mesh::load(path).expect("mesh");
    let mut text = String::from("solid part\n");
    for i in 0..mesh.faces.len() {
        text.push_str(" facet normal 0 0 0\n  outer loop\n");
        for p in mesh.triangle(i) {
            let v = p.coords * scale;
            text.push_str(&format!("   vertex {} {} {}\n", v.x, v.y, v.z));
        }
        text.push_str("  endloop\n endfacet\n");
    }
    text.push_str("endsolid part\n");
    std::fs::write(out, text).expect("write");
}

#[test]
fn meshes_in_ascii_stl_and_millimetres_get_a_scene_that_mujoco_loads() {
    // MuJoCo reads binary STL only: the scene shows a binary copy in metres, and its
    // collision geometry is made as from the binary files in metres.
    let dir = scratch("ascii");
    let peg = Task::find("peg_in_hole").expect("task");
    let (a, b) = (dir.join("peg_mm.stl"), dir.join("block_mm.stl"));
    ascii_stl(&peg.part_a.mesh, 1000.0, &a);
    ascii_stl(&peg.part_b.mesh, 1000.0, &b);
    let task = task_new(a, b, Units::Mm, dir.join("ascii_peg"));
    let spec = SceneSpec::of_task(&task).expect("a scene from the meshes");
    let pieces = SceneSpec::of_task(&mypeg()).expect("scene").pieces.len();
    assert_eq!(
        spec.pieces.len(),
        pieces,
        "as many pieces as from the metres"
    );
    let path = regenerate_scene(&task).expect("the scene loads in MuJoCo");
    for part in [&task.part_a, &task.part_b] {
        let text = std::fs::read(&part.mesh).expect("the task's mesh");
        assert!(
            text.starts_with(b"solid part"),
            "{:?} kept as given",
            part.mesh
        );
    }
    for (visual, original) in spec.visual.iter().zip([&peg.part_a.mesh, &peg.part_b.mesh]) {
        let Visual::Converted { file, .. } = visual else {
            panic!("{visual:?}: an ASCII file is shown as a binary copy");
        };
        let copy = ftmap::mesh::Mesh::load(&path.with_file_name(file)).expect("the copy");
        let original = ftmap::mesh::Mesh::load(original).expect("mesh");
        assert_eq!(copy.faces.len(), original.faces.len());
        let far = (copy.vertices.iter().zip(&original.vertices))
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        assert!(
            far < 1e-9,
            "the copy is {far} m off the metres it stands for"
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

/// A square prism from `lo` to `hi` in x, y (a square `half` wide each way) with a blind
/// square hole `hole` wide each way from `bottom` up to its top `top`, from `base`: closed,
/// facing out. The top is the annulus between the square and the hole, cut into four
/// trapezoids.
fn square_block(half: f32, hole: f32, base: f32, bottom: f32, top: f32) -> Vec<[[f32; 3]; 3]> {
    let square = |r: f32, z: f32| [[r, -r, z], [r, r, z], [-r, r, z], [-r, -r, z]];
    let quad = |a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]| [[a, b, c], [a, c, d]];
    let (outer_top, inner_top) = (square(half, top), square(hole, top));
    let (outer_base, inner_bottom) = (square(half, base), square(hole, bottom));
    let mut t = Vec::new();
    for i in 0..4 {
        let j = (i + 1) % 4;
        t.extend(quad(inner_top[i], outer_top[i], outer_top[j], inner_top[j]));
        t.extend(quad(
            outer_base[i],
            outer_base[j],
            outer_top[j],
            outer_top[i],
        ));
        t.extend(quad(
            inner_bottom[i],
            inner_top[i],
            inner_top[j],
            inner_bottom[j],
        ));
    }
    t.extend(quad(
        outer_base[0],
        outer_base[3],
        outer_base[2],
        outer_base[1],
    ));
    t.extend(quad(
        inner_bottom[0],
        inner_bottom[1],
        inner_bottom[2],
        inner_bottom[3],
    ));
    t
}

#[test]
fn a_square_peg_across_a_flat_reads_the_share_of_its_thinnest_strip() {
    // An 8 mm square peg in a hole 0.06 mm wider each side, part B about 0.1 mm off across a
    // flat and 0.4-1.2 mm along it, on each side: the peg rests on a wide strip and on one
    // 0.03-0.05 mm wide at right angles, which carries a tenth of the load under uniform
    // pressure (the map's centroid model). The thin strip's spheres carry nothing for the
    // first tens of milliseconds after the press stops: read when the torque had held still
    // over 10 ms (`sim::TORQUE_WINDOW` before), MuJoCo missed the polygons' torque by up to
    // 17-21 %; over 30 ms, by 6-8 % at most.
    let dir = scratch("square");
    let (peg, block) = (dir.join("square_peg.stl"), dir.join("square_block.stl"));
    std::fs::write(
        &peg,
        cad::stl_bytes(&cuboid([-0.004, -0.004, 0.0], [0.004, 0.004, 0.03], true)),
    )
    .expect("write");
    std::fs::write(
        &block,
        cad::stl_bytes(&square_block(0.015, 0.00406, -0.01, 0.0, 0.008)),
    )
    .expect("write");
    let task = task_new(peg, block, Units::M, dir.join("square"));
    regenerate_scene(&task).expect("the scene loads in MuJoCo");
    let mut sim = Sim::of_task(&task).expect("the scene");
    let (a, h) = (0.004, 0.00406);
    for (across, along) in [(0.1, 0.4), (0.1, 0.8), (0.09, 0.6), (0.11, 1.2)] {
        for offset in [
            [across, along],
            [-along, across],
            [-across, -along],
            [along, -across],
        ] {
            let offset = offset.map(|v| v * 1e-3);
            sim.set_object(offset);
            let c = sim.contact_motion([0.0, 0.0]);
            assert!(c.settled && !c.inserted, "{offset:?}: {c:?}");
            let w = harness::sensor::map_wrench(c.raw);
            // The face less the hole: on the side of each axis part B is off to, the strip
            // between the face's edge and the hole's, each over the other's width.
            let (x0, y0) = (offset[0].abs() - h, offset[1].abs() - h);
            let strips = [
                ((x0 + a) * 2.0 * a, [(x0 - a) / 2.0, 0.0]),
                ((y0 + a) * (a - x0), [(x0 + a) / 2.0, (y0 - a) / 2.0]),
            ];
            let area: f64 = strips.iter().map(|s| s.0).sum();
            let centroid = [0, 1].map(|k| {
                offset[k].signum() * strips.iter().map(|s| s.0 * s.1[k]).sum::<f64>() / area
            });
            let exact = [
                centroid[1] * task.contact.force,
                -centroid[0] * task.contact.force,
            ];
            let size = exact[0].hypot(exact[1]);
            assert!(
                (w[3] - exact[0]).hypot(w[4] - exact[1]) < 0.1 * size,
                "part B at {offset:?}: MuJoCo {w:?}, polygons {exact:?}"
            );
        }
    }
    std::fs::remove_dir_all(dir).ok();
}
