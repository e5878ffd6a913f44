//! Feature assembly (experiment D): the expected image edges of a task's vision model, the
//! choice of line detector, the four edges detected in an image with their search bands,
//! and the relative features that the FMU compares per particle.

use ftmap::vision::{Camera, VisionModel};

use super::gradient::detect_line;
use super::hough::{HoughParams, detect_line_hough};
use super::image::{Gradient, Line, LineParams, VisionError};
use crate::error::{HarnessError, Result};

/// A named expected edge: its 3-D endpoints.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeModel {
    /// Name: `active.left`, `active.right`, `passive.left`, `passive.right`.
    pub name: String,
    /// Endpoints in the world frame (m).
    pub ends: [[f64; 3]; 2],
}

impl EdgeModel {
    /// Projected endpoints; `None` when one lies behind the camera.
    pub fn project(&self, cam: &Camera) -> Option<[[f64; 2]; 2]> {
        Some([cam.project(self.ends[0])?, cam.project(self.ends[1])?])
    }

    /// The projected (ground truth or expected) line.
    pub fn line(&self, cam: &Camera) -> Option<Line> {
        let [a, b] = self.project(cam)?;
        Some(Line::through(a, b, cam.width, cam.height))
    }
}

/// The silhouette edges of a vision model's parts seen by `cam`: the active part with the
/// task frame at `tcp`, the passive part with the goal frame at `object` (m).
pub fn model_edges(
    model: &VisionModel,
    cam: &Camera,
    tcp: [f64; 3],
    object: [f64; 3],
) -> Vec<EdgeModel> {
    let mut out = Vec::new();
    for (part, prism, at) in [
        ("active", &model.active, tcp),
        ("passive", &model.passive, object),
    ] {
        if let Some(s) = prism.silhouette(cam, at) {
            out.push(EdgeModel {
                name: format!("{part}.left"),
                ends: s.left,
            });
            out.push(EdgeModel {
                name: format!("{part}.right"),
                ends: s.right,
            });
        }
    }
    out
}

/// The vision model of a task (its `[camera]` and the features of its `[geometry]`) seen by
/// `camera` (MuJoCo's, as rendered) instead of the designed one.
///
/// # Errors
/// When the task has no camera, or parts without vision features.
pub fn task_model(task: &ftmap::Task, camera: Camera) -> Result<VisionModel> {
    let model = VisionModel::of_task(task)?.ok_or_else(|| HarnessError::NoCamera {
        task: task.name.clone(),
    })?;
    Ok(VisionModel { camera, ..model })
}

/// One edge: where the model expects it, where it truly is, what was found.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeResult {
    /// Edge name.
    pub name: String,
    /// Expected image line (passive part at its nominal pose, active part at the TCP).
    pub expected: Line,
    /// Ground truth: the edge projected at the true pose.
    pub truth: Line,
    /// Search band used (px).
    pub band: f64,
    /// The detection.
    pub found: std::result::Result<Line, VisionError>,
}

/// Column (u) of a line at image row `v`.
pub fn u_at(l: &Line, v: f64) -> f64 {
    let dv = l.p1[1] - l.p0[1];
    if dv.abs() < 1e-12 {
        l.p0[0]
    } else {
        l.p0[0] + (v - l.p0[1]) * (l.p1[0] - l.p0[0]) / dv
    }
}

/// Horizontal image distance (px) from line `a` to line `b` at image row `v`.
pub fn u_distance(a: &Line, b: &Line, v: f64) -> f64 {
    u_at(b, v) - u_at(a, v)
}

/// The relative features of one image (the FMU's `vision.*` inputs), at the camera's
/// reference row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Features {
    /// Distance from the active part's edge to the passive part's edge: left, right (px).
    pub distances: [f64; 2],
    /// Columns of the passive part's left and right edges (px).
    pub passive: [f64; 2],
}

impl Features {
    /// From the detections; `None` unless all four edges were found.
    pub fn of(results: &[EdgeResult], cam: &Camera) -> Option<Self> {
        let v = cam.reference_row();
        let found = |name: &str| results.iter().find(|r| r.name == name)?.found.as_ref().ok();
        let side = |s: &str| {
            Some((
                found(&format!("active.{s}"))?,
                found(&format!("passive.{s}"))?,
            ))
        };
        let ((al, pl), (ar, pr)) = (side("left")?, side("right")?);
        Some(Self {
            distances: [u_distance(al, pl, v), u_distance(ar, pr, v)],
            passive: [u_at(pl, v), u_at(pr, v)],
        })
    }
}

/// Which line detector finds the edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Detector {
    /// Gradient maxima per row or column, fitted and extended (the paper's Fig. 5).
    #[default]
    Gradient,
    /// The bounded Hough transform restricted to the expected area, then the same refinement.
    Hough,
}

impl Detector {
    /// Detects the line expected between `ends` within `band` px.
    ///
    /// # Errors
    /// [`VisionError::FeatureNotFound`] as the detector decides.
    pub fn detect(
        self,
        grad: &Gradient,
        ends: [[f64; 2]; 2],
        band: f64,
    ) -> std::result::Result<Line, VisionError> {
        match self {
            Self::Gradient => detect_line(
                grad,
                ends,
                &LineParams {
                    band,
                    ..LineParams::default()
                },
            ),
            Self::Hough => detect_line_hough(
                grad,
                ends,
                &HoughParams {
                    line: LineParams {
                        band,
                        ..LineParams::default()
                    },
                    ..HoughParams::default()
                },
            ),
        }
    }
}

/// Detects a vision model's four edges in a grey image. The active part's pose (`tcp`) is
/// known to the robot; the passive part is expected at the nominal goal and may lie anywhere
/// within `size_trans` (m) in x and y, so its search band covers that; `object` is the true
/// pose, used only for the ground truth lines.
pub fn detect_edges(
    gray: &[f32],
    cam: &Camera,
    model: &VisionModel,
    tcp: [f64; 3],
    object: [f64; 3],
    size_trans: f64,
    detector: Detector,
) -> Vec<EdgeResult> {
    let grad = Gradient::sobel(cam.width, cam.height, gray);
    detect_edges_in(&grad, cam, model, tcp, object, size_trans, detector)
}

/// As [`detect_edges`], on a gradient image.
pub fn detect_edges_in(
    grad: &Gradient,
    cam: &Camera,
    model: &VisionModel,
    tcp: [f64; 3],
    object: [f64; 3],
    size_trans: f64,
    detector: Detector,
) -> Vec<EdgeResult> {
    let expected = model_edges(model, cam, tcp, [0.0; 3]);
    let truth = model_edges(model, cam, tcp, object);
    let s = size_trans;
    let shifted: Vec<Vec<EdgeModel>> = [[s, s, 0.0], [s, -s, 0.0], [-s, s, 0.0], [-s, -s, 0.0]]
        .iter()
        .map(|o| model_edges(model, cam, tcp, *o))
        .collect();
    expected
        .iter()
        .zip(&truth)
        .filter_map(|(e, t)| {
            let ends = e.project(cam)?;
            let (el, tl) = (e.line(cam)?, t.line(cam)?);
            let band = if e.name.starts_with("passive") {
                let far = shifted
                    .iter()
                    .filter_map(|v| v.iter().find(|m| m.name == e.name)?.line(cam))
                    .map(|l| {
                        ends.iter()
                            .map(|p| l.distance(*p, cam.width, cam.height).abs())
                            .fold(0.0, f64::max)
                    })
                    .fold(0.0, f64::max);
                far + 6.0
            } else {
                LineParams::default().band
            };
            Some(EdgeResult {
                name: e.name.clone(),
                expected: el,
                truth: tl,
                band,
                found: detector.detect(grad, ends, band),
            })
        })
        .collect()
}
