//! The `render` command's work: a task's vision camera placed and rendered, the vision
//! model's four edges detected in the image, the image annotated with the expected CAD edges
//! and the detected lines; and the detectors timed on noisy copies of the image.

use std::fmt;
use std::path::Path;
use std::time::Instant;

use ftmap::Task;
use ftmap::vision::{Camera, VisionModel};

use crate::camera::{CameraScene, RgbImage};
use crate::error::{HarnessError, Result};
use crate::scene::{SceneSpec, scene_path};
use crate::vision::features::{Detector, EdgeResult, Features, detect_edges, task_model};
use crate::vision::image::add_noise;

/// What `render` shows (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Task name or task.toml path (a task whose scene has a camera).
    pub task: String,
    /// True offset of part B, x and y (m).
    pub object: [f64; 2],
    /// Task frame (part A), x and y (m); it hangs at the approach height.
    pub tcp: [f64; 2],
    /// Gaussian image noise (grey levels) added before detection.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// Line detector.
    pub detector: Detector,
}

/// A task's camera view with both parts placed, rendered once.
pub struct View {
    options: RenderOptions,
    size_trans: f64,
    scene: CameraScene,
    model: VisionModel,
    tcp: [f64; 3],
    object: [f64; 3],
    image: RgbImage,
    render_ms: f64,
}

impl View {
    /// Loads the task's scene for its camera, places part B and part A (at the approach
    /// height) and renders the first frame.
    ///
    /// # Errors
    /// When the task has no camera or vision features, its scene does not load, or no
    /// OpenGL context can be made.
    pub fn open(options: RenderOptions) -> Result<Self> {
        let task = Task::find(&options.task)?;
        let spec = SceneSpec::of_task(&task)?;
        let designed = spec
            .camera
            .as_ref()
            .ok_or_else(|| HarnessError::RenderNeedsCamera {
                task: task.name.clone(),
            })?
            .camera
            .clone();
        // The designed camera must see the parts' features too.
        task_model(&task, designed)?;
        let mut scene = CameraScene::load(&scene_path(&task), spec)?;
        let model = task_model(&task, scene.camera())?;
        let tcp = [options.tcp[0], options.tcp[1], scene.look_height()];
        let object = [options.object[0], options.object[1], 0.0];
        scene.place(options.object, tcp);
        let t0 = Instant::now();
        let image = scene.render()?;
        let render_ms = t0.elapsed().as_secs_f64() * 1e3;
        Ok(Self {
            options,
            size_trans: task.omega.size_trans,
            scene,
            model,
            tcp,
            object,
            image,
            render_ms,
        })
    }

    /// Adds the image noise, detects the four edges and draws the expected CAD edges (blue),
    /// the detected lines (red) and their endpoints (yellow) over the image.
    pub fn detect(&self) -> Detected {
        let (noise, seed) = (self.options.noise, self.options.seed);
        let camera = self.scene.camera();
        let mut gray = self.image.to_gray();
        if noise > 0.0 {
            add_noise(&mut gray, noise, seed);
        }
        let edges = detect_edges(
            &gray,
            &camera,
            &self.model,
            self.tcp,
            self.object,
            self.size_trans,
            self.options.detector,
        );
        let mut image = if noise > 0.0 {
            RgbImage::from_gray(camera.width, camera.height, &gray)
        } else {
            self.image.clone()
        };
        for r in &edges {
            image.line(r.expected.p0, r.expected.p1, [60, 120, 255]);
            if let Ok(l) = &r.found {
                image.line(l.p0, l.p1, [255, 40, 40]);
                image.cross(l.p0, [255, 220, 0]);
                image.cross(l.p1, [255, 220, 0]);
            }
        }
        Detected {
            features: Features::of(&edges, &camera),
            truth: self.model.distances(self.tcp, self.object),
            camera,
            render_ms: self.render_ms,
            edges,
            image,
        }
    }

    /// Times a second frame, then both detectors on `copies` (at least one) copies of the
    /// image with Gaussian noise of at least 5 grey levels (seeds `seed`, `seed + 1`, ...).
    ///
    /// # Errors
    /// When rendering fails.
    pub fn bench(&mut self, copies: usize) -> Result<Bench> {
        let t = Instant::now();
        self.scene.render()?;
        let next_frame_ms = t.elapsed().as_secs_f64() * 1e3;
        let camera = self.scene.camera();
        let (noise, seed) = (self.options.noise, self.options.seed);
        let images: Vec<Vec<f32>> = (0..copies.max(1) as u64)
            .map(|k| {
                let mut g = self.image.to_gray();
                add_noise(&mut g, noise.max(5.0), seed + k);
                g
            })
            .collect();
        let detectors = [Detector::Gradient, Detector::Hough].map(|detector| {
            let t = Instant::now();
            let mut found = 0;
            for g in &images {
                found += detect_edges(
                    g,
                    &camera,
                    &self.model,
                    self.tcp,
                    self.object,
                    self.size_trans,
                    detector,
                )
                .iter()
                .filter(|e| e.found.is_ok())
                .count();
            }
            DetectorTiming {
                detector,
                ms: t.elapsed().as_secs_f64() * 1e3 / images.len() as f64,
                found,
            }
        });
        Ok(Bench {
            images: images.len(),
            width: camera.width,
            height: camera.height,
            detectors,
            first_frame_ms: self.render_ms,
            next_frame_ms,
        })
    }
}

/// The edges detected in a rendered image, the features they give and the annotated image.
#[derive(Debug, Clone, PartialEq)]
pub struct Detected {
    /// The camera as MuJoCo placed it.
    pub camera: Camera,
    /// Time of the first frame (ms, the GL context included).
    pub render_ms: f64,
    /// The four edges: expected, true and detected.
    pub edges: Vec<EdgeResult>,
    /// The features handed to the FMU; `None` unless all four edges were found.
    pub features: Option<Features>,
    /// The distances the vision model computes at the true pose (px).
    pub truth: Option<[f64; 2]>,
    /// The image with the expected and detected edges drawn over it.
    pub image: RgbImage,
}

impl Detected {
    /// Writes the annotated image as PNG.
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.image.save_png(path)
    }
}

impl fmt::Display for Detected {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let cam = &self.camera;
        writeln!(
            f,
            "camera: {}x{} px, fovy {} deg, f = {:.1} px, at {:?} m; render {:.1} ms",
            cam.width,
            cam.height,
            cam.fovy,
            cam.focal(),
            cam.pos,
            self.render_ms
        )?;
        writeln!(
            f,
            "{:<14} {:>9} {:>9} {:>9} {:>9} {:>6}  detected",
            "edge", "angle", "offset", "d_angle", "d_offset", "band"
        )?;
        for r in &self.edges {
            match &r.found {
                Ok(l) => writeln!(
                    f,
                    "{:<14} {:>9.3} {:>9.2} {:>9.3} {:>9.3} {:>6.0}  {} points, rms {:.2} px",
                    r.name,
                    l.angle,
                    l.offset,
                    l.angle - r.truth.angle,
                    l.offset - r.truth.offset,
                    r.band,
                    l.points,
                    l.rms
                )?,
                Err(e) => writeln!(f, "{:<14} {e}", r.name)?,
            }
        }
        let v = cam.reference_row();
        match (&self.features, &self.truth) {
            (Some(feat), Some(truth)) => {
                for (k, side) in ["left", "right"].iter().enumerate() {
                    writeln!(
                        f,
                        "vision.{side}_distance = {:.2} px (truth {:.2}; active to passive edge along u at row {v:.1}), vision.passive_{side} = {:.2} px",
                        feat.distances[k], truth[k], feat.passive[k]
                    )?;
                }
                Ok(())
            }
            _ => writeln!(f, "vision.valid = false (not all four edges found)"),
        }
    }
}

/// One detector's speed on the noisy copies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorTiming {
    /// The detector.
    pub detector: Detector,
    /// Time per image (ms), the Sobel gradient and all four edges included.
    pub ms: f64,
    /// Edges found over all copies.
    pub found: usize,
}

/// The detectors' speed and the rendering times.
#[derive(Debug, Clone, PartialEq)]
pub struct Bench {
    /// Noisy copies of the image.
    pub images: usize,
    /// Image width (px).
    pub width: usize,
    /// Image height (px).
    pub height: usize,
    /// Both detectors.
    pub detectors: [DetectorTiming; 2],
    /// First frame (ms, the GL context included).
    pub first_frame_ms: f64,
    /// The next frame (ms).
    pub next_frame_ms: f64,
}

impl fmt::Display for Bench {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for d in &self.detectors {
            writeln!(
                f,
                "{:?} detector (Sobel + 4 edges) on {} noisy {}x{} images: {:.2} ms per image, {:.0} images/s ({} of {} edges found)",
                d.detector,
                self.images,
                self.width,
                self.height,
                d.ms,
                1e3 / d.ms,
                d.found,
                4 * self.images
            )?;
        }
        writeln!(
            f,
            "rendering: first frame (GL context) {:.0} ms, next frame {:.0} ms",
            self.first_frame_ms, self.next_frame_ms
        )
    }
}
