//! The camera as a trial's second sensor (experiment D): renders the scene as the trial left
//! it, detects the vision model's edges where the model expects them, and hands back the
//! relative features that the FMU compares per particle.

use ftmap::Task;
use ftmap::vision::VisionModel;

use crate::camera::CameraScene;
use crate::error::{HarnessError, Result};
use crate::scene::{SceneSpec, scene_path};
use crate::vision::features::{Detector, Features, detect_edges, task_model};
use crate::vision::image::add_noise;

/// The task's camera with its vision model.
pub struct Eye {
    scene: CameraScene,
    model: VisionModel,
    size_trans: f64,
    noise: f64,
    detector: Detector,
}

impl Eye {
    /// The camera of `task`'s scene, its vision model calibrated from MuJoCo's camera,
    /// Gaussian image noise of `noise` grey levels, and the line detector.
    ///
    /// # Errors
    /// When the task's scene has no camera or the task no vision features.
    pub fn open(task: &Task, noise: f64, detector: Detector) -> Result<Self> {
        let spec = SceneSpec::of_task(task)?;
        if spec.camera.is_none() {
            return Err(HarnessError::NoCamera {
                task: task.name.clone(),
            });
        }
        let scene = CameraScene::load(&scene_path(task), spec)?;
        let model = task_model(task, scene.camera())?;
        Ok(Self {
            scene,
            model,
            size_trans: task.omega.size_trans,
            noise,
            detector,
        })
    }

    /// The vision model (the camera as MuJoCo places it, the parts' features).
    pub fn model(&self) -> &VisionModel {
        &self.model
    }

    /// The task frame's height where the first image is taken, before any contact (m).
    pub fn look_height(&self) -> f64 {
        self.scene.look_height()
    }

    /// Renders part B at `object` and the task frame at `tcp` (m), adds the image noise
    /// (seeded by `seed`) and detects the edges: the features, or `None` unless all four
    /// edges were found.
    ///
    /// # Errors
    /// When rendering fails.
    pub fn look(&mut self, object: [f64; 2], tcp: [f64; 3], seed: u64) -> Result<Option<Features>> {
        self.scene.place(object, tcp);
        let image = self.scene.render()?;
        let cam = self.scene.camera();
        let mut gray = image.to_gray();
        if self.noise > 0.0 {
            add_noise(&mut gray, self.noise, seed);
        }
        let edges = detect_edges(
            &gray,
            &cam,
            &self.model,
            tcp,
            [object[0], object[1], 0.0],
            self.size_trans,
            self.detector,
        );
        Ok(Features::of(&edges, &cam))
    }
}
