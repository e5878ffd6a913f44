//! Vision (experiment D): the camera model against MuJoCo's rendering, and line detection
//! on rendered images against the ground truth projected from the scene's geometry.

mod common;

use std::sync::Mutex;

use ftmap::Task;
use ftmap::vision::VisionModel;
use harness::camera::CameraScene;
use harness::scene::{SceneSpec, scene_path};
use harness::vision::features::{Detector, Features, detect_edges, model_edges};
use harness::vision::image::{Gradient, VisionError, add_noise};

/// One offscreen GL context at a time.
static GL: Mutex<()> = Mutex::new(());

/// Detection errors (degrees, px) of all four edges, each asserted found.
fn errors(
    task: &Task,
    view: &mut CameraScene,
    model: &VisionModel,
    object: [f64; 2],
    tcp_xy: [f64; 2],
    noise: Option<u64>,
) -> Vec<(String, f64, f64)> {
    let tcp = [tcp_xy[0], tcp_xy[1], view.look_height()];
    view.place(object, tcp);
    let image = view.render().expect("offscreen rendering (Mesa EGL)");
    let cam = view.camera();
    let mut gray = image.to_gray();
    if let Some(seed) = noise {
        add_noise(&mut gray, 5.0, seed);
    }
    let results = detect_edges(
        &gray,
        &cam,
        model,
        tcp,
        [object[0], object[1], 0.0],
        task.omega.size_trans,
        Detector::Gradient,
    );
    assert_eq!(results.len(), 4, "four edges expected");
    results
        .into_iter()
        .map(|r| {
            let l = r
                .found
                .unwrap_or_else(|e| panic!("{} at object {object:?}: {e}", r.name));
            (r.name, l.angle - r.truth.angle, l.offset - r.truth.offset)
        })
        .collect()
}

#[test]
fn detected_edges_match_the_projected_geometry() {
    let _gl = GL.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let (task, mut view, model) = common::bearing();
    let cases = [
        ([0.0, 0.0], [0.0, 0.0]),
        ([0.002, -0.003], [0.0, 0.0]),
        ([-0.004, 0.0045], [0.0, 0.0]),
        ([0.001, 0.002], [0.0005, -0.001]),
    ];
    for (k, (object, tcp)) in cases.iter().enumerate() {
        for noise in [None, Some(k as u64 + 1)] {
            for (name, da, doff) in errors(&task, &mut view, &model, *object, *tcp, noise) {
                println!(
                    "object {object:?} tcp {tcp:?} noise {noise:?} {name}: d_angle {da:.4} deg, d_offset {doff:.3} px"
                );
                assert!(
                    da.abs() < 0.2,
                    "{name} at {object:?} (noise {noise:?}): angle error {da} deg"
                );
                assert!(
                    doff.abs() < 0.5,
                    "{name} at {object:?} (noise {noise:?}): offset error {doff} px"
                );
            }
        }
    }
}

#[test]
fn camera_model_projects_like_mujoco_renders() {
    let _gl = GL.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let task = Task::find("bearing_housing").expect("task");
    let path = scene_path(&task);
    let dir = path
        .parent()
        .expect("scene folder")
        .canonicalize()
        .expect("absolute folder");
    let points = [
        [0.0, 0.026, 0.02],
        [0.0, -0.026, 0.02],
        [0.01, 0.025, 0.025],
        [0.01, -0.025, 0.012],
    ];
    let spheres: String = points
        .iter()
        .map(|p| format!("<geom type=\"sphere\" size=\"0.0004\" pos=\"{} {} {}\" material=\"marker\" contype=\"0\" conaffinity=\"0\"/>", p[0], p[1], p[2]))
        .collect();
    let xml = std::fs::read_to_string(&path)
        .expect("scene")
        .replace("meshdir=\".\"", &format!("meshdir=\"{}\"", dir.display()))
        .replace(
            "<asset>",
            "<asset><material name=\"marker\" rgba=\"1 1 1 1\" emission=\"1\"/>",
        )
        .replace("<worldbody>", &format!("<worldbody>{spheres}"));
    let spec = SceneSpec::of_task(&task).expect("spec");
    let mut view = CameraScene::from_xml_string(&xml, spec).expect("scene with markers");
    view.place([0.0, 0.0], [0.0, 0.0, view.look_height()]);
    let image = view.render().expect("offscreen rendering (Mesa EGL)");
    let cam = view.camera();
    let gray = image.to_gray();
    for p in points {
        let uv = cam.project(p).expect("in front of the camera");
        let (mut sw, mut su, mut sv) = (0.0, 0.0, 0.0);
        for v in (uv[1].round() as i64 - 12)..=(uv[1].round() as i64 + 12) {
            for u in (uv[0].round() as i64 - 12)..=(uv[0].round() as i64 + 12) {
                assert!(
                    u >= 0 && v >= 0 && (u as usize) < cam.width && (v as usize) < cam.height,
                    "marker {p:?} near the border"
                );
                let g = f64::from(gray[v as usize * cam.width + u as usize]);
                if g > 8.0 {
                    (sw, su, sv) = (sw + g, su + g * u as f64, sv + g * v as f64);
                }
            }
        }
        assert!(
            sw > 255.0 * 20.0,
            "marker {p:?} not rendered near its projection {uv:?}"
        );
        let (cu, cv) = (su / sw, sv / sw);
        println!(
            "marker {p:?}: projected ({:.3}, {:.3}), rendered centroid ({cu:.3}, {cv:.3})",
            uv[0], uv[1]
        );
        assert!(
            (cu - uv[0]).hypot(cv - uv[1]) < 0.5,
            "marker {p:?}: projected {uv:?}, rendered centroid ({cu}, {cv})"
        );
    }
}

#[test]
fn no_part_in_view_gives_feature_not_found() {
    let _gl = GL.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let (task, mut view, model) = common::bearing();
    let tcp = [0.0, 0.0, view.look_height()];
    view.place([0.0, 0.0], tcp);
    let expected = model_edges(&model, &view.camera(), tcp, [0.0; 3]);
    // Both parts moved 1 m aside: nothing in the camera's view.
    view.place([0.0, 1.0], [0.0, 1.0, tcp[2]]);
    let image = view.render().expect("offscreen rendering (Mesa EGL)");
    let cam = view.camera();
    let mut gray = image.to_gray();
    add_noise(&mut gray, 5.0, 3);
    let grad = Gradient::sobel(cam.width, cam.height, &gray);
    assert_eq!(expected.len(), 4, "four edges expected");
    for e in &expected {
        let ends = e.project(&cam).expect("projected");
        for d in [Detector::Gradient, Detector::Hough] {
            match d.detect(&grad, ends, 60.0) {
                Err(VisionError::FeatureNotFound(why)) => {
                    println!("{} ({d:?}): feature not found: {why}", e.name)
                }
                Ok(l) => panic!("{} ({d:?}): found a line in an empty view: {l:?}", e.name),
            }
        }
    }
    let results = detect_edges(
        &gray,
        &cam,
        &model,
        tcp,
        [0.0; 3],
        task.omega.size_trans,
        Detector::Gradient,
    );
    assert!(results.iter().all(|r| r.found.is_err()), "{results:?}");
    assert_eq!(Features::of(&results, &cam), None);
}

#[test]
fn camera_model_is_mujocos_camera() {
    let (_, mut view, _) = common::bearing();
    view.place([0.0, 0.0], [0.0, 0.0, view.look_height()]);
    let cam = view.camera();
    let spec = view.spec().camera.clone().expect("scene camera").camera;
    assert_eq!((cam.width, cam.height), (640, 480));
    assert!((cam.fovy - spec.fovy).abs() < 1e-12);
    assert!((cam.focal() - 240.0 / 6f64.to_radians().tan()).abs() < 1e-9);
    let xyaxes = spec.xyaxes();
    for k in 0..3 {
        assert!(
            (cam.pos[k] - spec.pos[k]).abs() < 1e-12,
            "pos {:?} vs {:?}",
            cam.pos,
            spec.pos
        );
        // Columns 0 and 1 of cam_xmat are the MJCF xyaxes (unit vectors here).
        assert!((cam.xmat[3 * k] - xyaxes[k]).abs() < 1e-9, "{:?}", cam.xmat);
        assert!(
            (cam.xmat[3 * k + 1] - xyaxes[3 + k]).abs() < 1e-9,
            "{:?}",
            cam.xmat
        );
    }
    // The designed camera (what the scene generator wrote) and MuJoCo's project every
    // point of the work cell alike: within 1e-6 px.
    for p in [
        [0.0, 0.0, 0.0],
        [0.01, 0.02, 0.016],
        [-0.02, -0.02, 0.03],
        [0.005, -0.011, 0.012],
    ] {
        let (a, b) = (
            cam.project(p).expect("in front"),
            spec.project(p).expect("in front"),
        );
        assert!(
            (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-6,
            "{p:?}: MuJoCo {a:?}, designed {b:?}"
        );
    }
    // The optical axis (-z) projects to the image centre, camera x to the right, y up.
    let z = [cam.xmat[2], cam.xmat[5], cam.xmat[8]];
    let at = |d: [f64; 3]| {
        cam.project([cam.pos[0] + d[0], cam.pos[1] + d[1], cam.pos[2] + d[2]])
            .expect("in front")
    };
    let c = at([-0.2 * z[0], -0.2 * z[1], -0.2 * z[2]]);
    assert!(
        (c[0] - 319.5).abs() < 1e-9 && (c[1] - 239.5).abs() < 1e-9,
        "{c:?}"
    );
    let r = at([
        -0.2 * z[0] + 0.01 * cam.xmat[0],
        -0.2 * z[1] + 0.01 * cam.xmat[3],
        -0.2 * z[2] + 0.01 * cam.xmat[6],
    ]);
    assert!(
        (r[0] - 319.5 - cam.focal() * 0.05).abs() < 1e-9 && (r[1] - 239.5).abs() < 1e-9,
        "{r:?}"
    );
    assert!(
        cam.project([cam.pos[0] + z[0], cam.pos[1] + z[1], cam.pos[2] + z[2]])
            .is_none(),
        "behind the camera"
    );
}

#[test]
fn harness_render_writes_the_image_and_the_edge_distances() {
    let _gl = GL.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let out = std::env::temp_dir().join(format!("harness-render-{}/d.png", std::process::id()));
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "render",
            "--task",
            "bearing_housing",
            "--object-mm",
            "1.5,-2",
            "--noise",
            "5",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("harness runs");
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for want in [
        "active.left",
        "active.right",
        "passive.left",
        "passive.right",
        "vision.left_distance",
        "vision.right_distance",
        "vision.passive_left",
    ] {
        assert!(text.contains(want), "no {want} in:\n{text}");
    }
    assert!(!text.contains("not found"), "{text}");
    let decoder = mujoco_rs::renderer::png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&out).expect("image written"),
    ));
    let info = decoder.read_info().expect("a PNG");
    assert_eq!((info.info().width, info.info().height), (640, 480));
    let _ = std::fs::remove_dir_all(out.parent().expect("folder"));
    // A task without a camera is refused with a clear message.
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["render", "--task", "peg_in_hole", "--out"])
        .arg(&out)
        .output()
        .expect("harness runs");
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && err.contains("no vision features"),
        "{err}"
    );
}

#[test]
fn measured_features_match_the_particle_side_model() {
    let _gl = GL.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let (task, mut view, model) = common::bearing();
    // At the approach height and resting on the seat's top (a contact), parts in several places.
    for (object, tcp) in [
        ([0.0, 0.0], [0.0, 0.0, 0.0]),
        ([0.003, 0.004], [0.0, 0.0, 0.0]),
        ([-0.002, -0.0045], [0.001, -0.0005, 0.0]),
        ([0.0045, -0.002], [0.0, 0.0, 0.012]),
    ] {
        let tcp = [
            tcp[0],
            tcp[1],
            if tcp[2] > 0.0 {
                tcp[2]
            } else {
                view.look_height()
            },
        ];
        view.place(object, tcp);
        let image = view.render().expect("offscreen rendering (Mesa EGL)");
        let cam = view.camera();
        let mut gray = image.to_gray();
        add_noise(&mut gray, 5.0, 11);
        let object = [object[0], object[1], 0.0];
        let r = detect_edges(
            &gray,
            &cam,
            &model,
            tcp,
            object,
            task.omega.size_trans,
            Detector::Gradient,
        );
        let f =
            Features::of(&r, &cam).unwrap_or_else(|| panic!("all four edges at {object:?}: {r:?}"));
        // What the FMU computes for a particle at the true pose.
        let d = model.distances(tcp, object).expect("in view");
        let p = model.passive.columns(&cam, object).expect("in view");
        for k in 0..2 {
            println!(
                "object {object:?} tcp {tcp:?} side {k}: distance {:.3} px (model {:.3}), passive column {:.3} px (model {:.3})",
                f.distances[k], d[k], f.passive[k], p[k]
            );
            assert!(
                (f.distances[k] - d[k]).abs() < 0.5,
                "{object:?} side {k}: {f:?} vs {d:?}"
            );
            assert!(
                (f.passive[k] - p[k]).abs() < 0.5,
                "{object:?} side {k}: {f:?} vs {p:?}"
            );
        }
    }
}
