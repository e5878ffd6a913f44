//! Helpers shared by the harness's integration tests.

#![allow(dead_code)]

use std::sync::OnceLock;

use ftmap::generate::{GenerateOptions, generate};
use ftmap::vision::VisionModel;
use ftmap::{FtMap, Task};
use harness::camera::CameraScene;
use harness::scene::{SceneSpec, scene_path};
use harness::sim::Sim;
use harness::vision::features::task_model;

/// The peg_in_hole task and a simulation of its committed scene.
pub fn peg() -> (Task, Sim) {
    scene("peg_in_hole")
}

/// A committed task and a simulation of its committed scene.
pub fn scene(name: &str) -> (Task, Sim) {
    let task = Task::find(name).expect("a committed task");
    let spec = SceneSpec::of_task(&task).expect("its scene description");
    let sim = Sim::load(&scene_path(&task), spec).expect("its committed scene");
    (task, sim)
}

/// The peg_in_hole map computed from the CAD meshes (centroid model, CPU backend).
pub fn computed_peg_map() -> &'static FtMap {
    static MAP: OnceLock<FtMap> = OnceLock::new();
    MAP.get_or_init(|| {
        let task = Task::find("peg_in_hole").expect("task peg_in_hole");
        generate(
            &task,
            &ftmap::depth::cpu::CpuBackend,
            &GenerateOptions::default(),
            &|_| {},
        )
        .expect("its computed map")
    })
}

/// The bearing_housing task, its committed scene loaded for the camera, and its vision model
/// with MuJoCo's camera.
pub fn bearing() -> (Task, CameraScene, VisionModel) {
    let task = Task::find("bearing_housing").expect("task bearing_housing");
    let spec = SceneSpec::of_task(&task).expect("its scene description");
    let view = CameraScene::load(&scene_path(&task), spec)
        .expect("its committed scene with camera `vision`");
    let model = task_model(&task, view.camera()).expect("bearing housing features");
    (task, view, model)
}
