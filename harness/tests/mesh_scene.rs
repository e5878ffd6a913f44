//! Scenes for parts given by their meshes alone: a task made by `ftmap task new` from the
//! peg_in_hole STLs gets a scene whose clearance is the parametric scene's within the bound,
//! and a 5-trial campaign in it succeeds in every trial; a part B with a cavity under its
//! top (no height field along the approach) gets no scene, and the error says why; meshes in
//! ASCII STL and millimetres get a scene that MuJoCo loads.

use std::path::{Path, PathBuf};

use ftmap::Task;
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
use nalgebra::{Isometry3, Point3, Vector3};
use parry3d_f64::shape::{ConvexPolyhedron, Cuboid, SharedShape};

/// A scratch folder for this test process.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mesh-scene-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch folder");
    dir
}

/// A task made by `ftmap task new` from the peg_in_hole STLs alone.
fn mypeg() -> Task {
    let peg = Task::find("peg_in_hole").expect("task");
    create(&NewTask {
        part_a: peg.part_a.mesh.clone(),
        part_b: peg.part_b.mesh.clone(),
        units: Units::M,
        out: scratch("task").join("mypeg"),
        approach: [0.0, 0.0, -1.0],
        force: 50.0,
        friction: 0.3,
        size: None,
    })
    .expect("task new")
    .0
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
    let corner = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    // Each face's corners counter-clockwise seen from outside.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .map(|t| {
            let t = if outward { t } else { [t[0], t[2], t[1]] };
            t.map(corner)
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
    let (task, _) = create(&NewTask {
        part_a: a,
        part_b: b,
        units: Units::Mm,
        out: dir.join("ascii_peg"),
        approach: [0.0, 0.0, -1.0],
        force: 50.0,
        friction: 0.3,
        size: None,
    })
    .expect("task new");
    let spec = SceneSpec::of_task(&task).expect("a scene from the meshes");
    let pieces = SceneSpec::of_task(&mypeg()).expect("scene").pieces.len();
    assert_eq!(
        spec.pieces.len(),
        pieces,
        "as many pieces as from the metres"
    );
    let path = regenerate_scene(&task).expect("the scene loads in MuJoCo");
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
