//! Model information for vision (the paper's section III): a calibrated pinhole camera and
//! the CAD features of both parts that it sees, as the filter evaluates them per particle by
//! 3d-to-2d projection (section III-B), and the file that carries them (`*.vision.json`).
//!
//! Features are the silhouette edges of vertical prisms (a part's outline in its xy plane,
//! extruded between two heights): a circle's two tangent generators or a convex polygon's two
//! outermost vertical edges, as seen from the camera. Their relative pose is compared in the
//! image: the distance along u, at the image's centre row, from the active part's edge to the
//! passive part's edge on the same side (left and right; experiment D).
//!
//! The camera itself lives in [`camera`].

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{MapError, Result};
use crate::task::Task;
use crate::task::cad::Geometry;

pub mod camera;

pub use camera::Camera;

/// `kind` of a vision model file.
pub const VISION_KIND: &str = "ftfusion-vision";
/// Version of the vision model file this build reads and writes.
pub const VISION_VERSION: u32 = 1;

/// A part's outline in its xy plane.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outline {
    /// A circle about the part's z axis (m).
    Circle {
        /// Radius (m).
        radius: f64,
    },
    /// A convex polygon (m), corners in order.
    Polygon {
        /// Corners (x, y).
        corners: Vec<[f64; 2]>,
    },
}

/// A vertical prism: an outline extruded between two heights of its part's frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Prism {
    /// The outline.
    pub outline: Outline,
    /// Lowest and highest z (m).
    pub z: [f64; 2],
}

/// The two silhouette edges of a prism seen by a camera: 3-D endpoints (bottom, top).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Silhouette {
    /// The edge on the image's left.
    pub left: [[f64; 3]; 2],
    /// The edge on the image's right.
    pub right: [[f64; 3]; 2],
}

impl Prism {
    /// The silhouette edges with the part's frame at `offset` (m, world frame, no rotation);
    /// `None` when the camera stands inside the outline or sees a point from behind.
    pub fn silhouette(&self, cam: &Camera, offset: [f64; 3]) -> Option<Silhouette> {
        let c = [cam.pos[0] - offset[0], cam.pos[1] - offset[1]];
        let pair = match &self.outline {
            Outline::Circle { radius: r } => {
                let dd = c[0] * c[0] + c[1] * c[1];
                if dd <= r * r {
                    return None;
                }
                let (k, h) = (r * r / dd, r * (dd - r * r).sqrt() / dd);
                [
                    [k * c[0] - h * c[1], k * c[1] + h * c[0]],
                    [k * c[0] + h * c[1], k * c[1] - h * c[0]],
                ]
            }
            Outline::Polygon { corners } => {
                // The outermost corners by their bearing from the camera, relative to the
                // bearing of the outline's first corner (a convex outline spans < 180 degrees).
                let first = corners.first()?;
                let base = (first[1] - c[1]).atan2(first[0] - c[0]);
                let bearing = |q: &[f64; 2]| {
                    let a = (q[1] - c[1]).atan2(q[0] - c[0]) - base;
                    (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI
                };
                let lo = corners
                    .iter()
                    .min_by(|a, b| bearing(a).total_cmp(&bearing(b)))?;
                let hi = corners
                    .iter()
                    .max_by(|a, b| bearing(a).total_cmp(&bearing(b)))?;
                [*lo, *hi]
            }
        };
        let edge = |q: [f64; 2]| {
            let p = [q[0] + offset[0], q[1] + offset[1]];
            [
                [p[0], p[1], self.z[0] + offset[2]],
                [p[0], p[1], self.z[1] + offset[2]],
            ]
        };
        let (a, b) = (edge(pair[0]), edge(pair[1]));
        let mid = |e: [[f64; 3]; 2]| {
            cam.project([e[0][0], e[0][1], 0.5 * (e[0][2] + e[1][2])])
                .map(|p| p[0])
        };
        let (ua, ub) = (mid(a)?, mid(b)?);
        Some(if ua <= ub {
            Silhouette { left: a, right: b }
        } else {
            Silhouette { left: b, right: a }
        })
    }

    /// Columns (u, px) of the left and right silhouette edges at the camera's reference row.
    pub fn columns(&self, cam: &Camera, offset: [f64; 3]) -> Option<[f64; 2]> {
        let s = self.silhouette(cam, offset)?;
        let v = cam.reference_row();
        Some([cam.u_at_row(s.left, v)?, cam.u_at_row(s.right, v)?])
    }

    fn check(&self, which: &str) -> std::result::Result<(), String> {
        let finite = |x: &f64| x.is_finite();
        if !(self.z.iter().all(finite) && self.z[0] < self.z[1]) {
            return Err(format!("{which}: z {:?} must be finite and rising", self.z));
        }
        match &self.outline {
            Outline::Circle { radius } if !(radius.is_finite() && *radius > 0.0) => {
                Err(format!("{which}: circle radius {radius} must be positive"))
            }
            Outline::Polygon { corners }
                if corners.len() < 3 || !corners.iter().flatten().all(finite) =>
            {
                Err(format!(
                    "{which}: a polygon needs at least 3 finite corners, got {}",
                    corners.len()
                ))
            }
            _ => Ok(()),
        }
    }
}

/// The vision model of a task: the calibrated camera and the features of both parts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VisionModel {
    /// The camera.
    pub camera: Camera,
    /// Active part A (gripped), in the task frame.
    pub active: Prism,
    /// Passive part B (fixed), in the goal frame.
    pub passive: Prism,
    /// The task whose parts these are (a map of another task does not fit them); absent in
    /// files that do not say.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<String>,
}

/// The largest vision model file this build reads (bytes).
pub const MAX_FILE: u64 = 1 << 20;

/// The file layout: kind and version, then the model.
#[derive(Serialize, Deserialize)]
struct VisionFile {
    kind: String,
    version: u32,
    #[serde(flatten)]
    model: VisionModel,
}

impl VisionModel {
    /// The features of a task's parametric geometry seen by `camera`; `None` for tasks
    /// without vertical silhouette edges to compare (only the bearing housing has them).
    pub fn of_geometry(geometry: &Geometry, camera: Camera) -> Option<Self> {
        match *geometry {
            Geometry::BearingHousing {
                housing,
                seat_radius,
                seat_height,
                ..
            } => {
                let (hx, hy) = (housing[0] / 2.0, housing[1] / 2.0);
                Some(Self {
                    camera,
                    active: Prism {
                        outline: Outline::Polygon {
                            corners: vec![[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]],
                        },
                        z: [0.0, housing[2]],
                    },
                    passive: Prism {
                        outline: Outline::Circle {
                            radius: seat_radius,
                        },
                        z: [0.0, seat_height],
                    },
                    task: None,
                })
            }
            _ => None,
        }
    }

    /// A task's vision model: its `[camera]` and the features of its `[geometry]`; `None`
    /// when the task has no camera.
    ///
    /// # Errors
    /// [`MapError::Task`] when the task has a camera but no `[geometry]` whose parts show
    /// silhouette edges to compare.
    pub fn of_task(task: &Task) -> Result<Option<Self>> {
        let Some(setup) = &task.camera else {
            return Ok(None);
        };
        Self::of_geometry(task.geometry()?, Camera::from(setup))
            .map(|m| {
                Some(Self {
                    task: Some(task.name.clone()),
                    ..m
                })
            })
            .ok_or_else(|| MapError::Task {
                path: task.path.clone(),
                reason: "[camera]: the parts of its [geometry] have no silhouette edges to \
                         compare (vision features exist for kind \"bearing_housing\")"
                    .into(),
            })
    }

    /// The relative features: u-distance (px) from the active part's edge (task frame at
    /// `tcp`) to the passive part's edge (goal frame at `object`), left and right.
    pub fn distances(&self, tcp: [f64; 3], object: [f64; 3]) -> Option<[f64; 2]> {
        let (a, b) = (
            self.active.columns(&self.camera, tcp)?,
            self.passive.columns(&self.camera, object)?,
        );
        Some([b[0] - a[0], b[1] - a[1]])
    }

    /// Reads a vision model file.
    ///
    /// # Errors
    /// [`MapError::Vision`] naming the file and what is wrong with it.
    pub fn load(path: &Path) -> Result<Self> {
        let bad = |reason: String| MapError::Vision {
            path: path.to_owned(),
            reason,
        };
        let bytes = crate::file::read_regular(path, MAX_FILE, "a vision model file")?;
        let text = String::from_utf8(bytes).map_err(|e| bad(format!("not UTF-8 text: {e}")))?;
        let file: VisionFile =
            serde_json::from_str(&text).map_err(|e| bad(format!("not a vision model: {e}")))?;
        if file.kind != VISION_KIND {
            return Err(bad(format!(
                "kind \"{}\", expected \"{VISION_KIND}\"",
                file.kind
            )));
        }
        if file.version != VISION_VERSION {
            return Err(bad(format!(
                "version {}, this build reads {VISION_VERSION}",
                file.version
            )));
        }
        let m = file.model;
        m.camera
            .check()
            .and_then(|()| m.active.check("active"))
            .and_then(|()| m.passive.check("passive"))
            .map_err(bad)?;
        Ok(m)
    }

    /// Writes the model as a vision model file (JSON).
    ///
    /// # Errors
    /// [`MapError::Io`] when the file cannot be written.
    pub fn save(&self, path: &Path) -> Result<()> {
        let file = VisionFile {
            kind: VISION_KIND.into(),
            version: VISION_VERSION,
            model: self.clone(),
        };
        let text = serde_json::to_string_pretty(&file).map_err(|e| MapError::Vision {
            path: path.to_owned(),
            reason: e.to_string(),
        })?;
        std::fs::write(path, text).map_err(MapError::io(path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::camera::tests::level_camera;

    /// The bearing housing task's geometry.
    fn bearing() -> Geometry {
        Task::find("bearing_housing")
            .expect("task")
            .geometry
            .expect("its [geometry]")
    }

    #[test]
    fn circle_silhouette_columns_are_the_tangent_rays() {
        let cam = level_camera();
        let prism = Prism {
            outline: Outline::Circle { radius: 0.01 },
            z: [0.0, 0.02],
        };
        let [l, r] = prism.columns(&cam, [0.0, 0.003, 0.0]).expect("in view");
        // Level camera: a vertical line projects to a constant column. The tangent rays from
        // the camera to the circle make angles asin(r/d) with the ray to the centre.
        let d = 0.2f64.hypot(0.003);
        let centre = (0.003f64 / 0.2).atan();
        let half = (0.01 / d).asin();
        let f = cam.focal();
        let (cx, _) = cam.principal_point();
        // Image right is world -y: a larger world y bearing is further left.
        let (want_l, want_r) = (
            cx - f * (centre + half).tan(),
            cx - f * (centre - half).tan(),
        );
        assert!(
            (l - want_l).abs() < 1e-9 && (r - want_r).abs() < 1e-9,
            "{l} {r} vs {want_l} {want_r}"
        );
    }

    #[test]
    fn polygon_silhouette_takes_the_outermost_corners() {
        let cam = level_camera();
        let box_ = Prism {
            outline: Outline::Polygon {
                corners: vec![[0.02, 0.02], [-0.02, 0.02], [-0.02, -0.02], [0.02, -0.02]],
            },
            z: [0.0, 0.016],
        };
        let [l, r] = box_.columns(&cam, [0.0; 3]).expect("in view");
        // From straight in front, the outermost corners are the near ones (x = -0.02).
        let f = cam.focal();
        let (cx, _) = cam.principal_point();
        let want = f * 0.02 / 0.18;
        assert!(
            (l - (cx - want)).abs() < 1e-9 && (r - (cx + want)).abs() < 1e-9,
            "{l} {r}"
        );
    }

    #[test]
    fn distances_move_with_y_and_hardly_with_x() {
        let g = bearing();
        let m = VisionModel::of_geometry(&g, level_camera()).expect("bearing housing has features");
        let d0 = m.distances([0.0; 3], [0.0; 3]).expect("in view");
        let dy = m.distances([0.0; 3], [0.0, 0.001, 0.0]).expect("in view");
        let dx = m.distances([0.0; 3], [0.001, 0.0, 0.0]).expect("in view");
        // 1 mm of y at about 200 mm: f * 0.001 / 0.2 px, both edges the same way.
        let px = level_camera().focal() * 0.001 / 0.2;
        for k in 0..2 {
            assert!(
                ((d0[k] - dy[k]).abs() - px).abs() < 0.1 * px,
                "y: {d0:?} {dy:?}"
            );
            assert!((d0[k] - dx[k]).abs() < 0.1 * px, "x: {d0:?} {dx:?}");
        }
    }

    #[test]
    fn files_round_trip_and_bad_ones_are_named() {
        let dir = std::env::temp_dir().join(format!("ftmap-vision-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let g = bearing();
        let m = VisionModel::of_geometry(&g, level_camera()).expect("features");
        let path = dir.join("m.vision.json");
        m.save(&path).expect("written");
        assert_eq!(VisionModel::load(&path).expect("read back"), m);
        let text = std::fs::read_to_string(&path).expect("text");
        for (bad, needle) in [
            (text.replace("\"fovy\": 12.0", "\"fovy\": 0.0"), "fovy"),
            (text.replacen("-1.0", "1.0", 1), "reflection"),
            (text.replace("ftfusion-vision", "ftmap"), "kind"),
            (
                text.replace("\"version\": 1", "\"version\": 9"),
                "version 9",
            ),
            (
                text.replace("\"radius\": 0.01095", "\"radius\": -1.0"),
                "radius",
            ),
            (text[..text.len() / 2].to_owned(), "not a vision model"),
        ] {
            std::fs::write(&path, bad).expect("write");
            let e = VisionModel::load(&path).expect_err(needle).to_string();
            assert!(e.contains(needle) && e.contains("m.vision.json"), "{e}");
        }
        let e = VisionModel::load(&dir.join("missing.json"))
            .expect_err("missing")
            .to_string();
        assert!(e.contains("missing.json"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_task_s_model_comes_from_its_camera_and_geometry() {
        let task = Task::find("bearing_housing").expect("task");
        let m = VisionModel::of_task(&task)
            .expect("valid")
            .expect("a camera");
        assert_eq!(
            m.camera,
            Camera::from(task.camera.as_ref().expect("camera"))
        );
        assert_eq!(m.passive.outline, Outline::Circle { radius: 0.01095 });
        let peg = Task::find("peg_in_hole").expect("task");
        assert_eq!(VisionModel::of_task(&peg).expect("no camera is fine"), None);
        // A camera over parts without features is an error, not a silent "no vision".
        let with_camera = Task {
            camera: task.camera.clone(),
            ..peg
        };
        let e = VisionModel::of_task(&with_camera)
            .expect_err("no features")
            .to_string();
        assert!(e.contains("[camera]") && e.contains("task.toml"), "{e}");
    }
}
