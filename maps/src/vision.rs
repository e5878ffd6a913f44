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
//! Pixel coordinates: `u` to the right, `v` down, the centre of pixel (column i, row j) at
//! (i, j). The camera looks along its -z axis, x to the image's right, y up (MuJoCo's camera).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::cad::Geometry;
use crate::error::{MapError, Result};
use crate::task::Task;

/// `kind` of a vision model file.
pub const VISION_KIND: &str = "ftfusion-vision";
/// Version of the vision model file this build reads and writes.
pub const VISION_VERSION: u32 = 1;

/// A pinhole camera without distortion, as MuJoCo renders it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Image width (px).
    pub width: usize,
    /// Image height (px).
    pub height: usize,
    /// Vertical field of view (degrees).
    pub fovy: f64,
    /// Optical centre in the world (= nominal goal) frame (m).
    pub pos: [f64; 3],
    /// Orientation, row-major: column k is camera axis k in the world frame (x right, y up,
    /// looking along -z), as MuJoCo's `cam_xmat`.
    pub xmat: [f64; 9],
}

impl Camera {
    /// A camera of `size` px (width, height) and vertical field of view `fovy` (degrees)
    /// `distance` in front of the goal along -x, looking along +x, tilted down by `pitch`
    /// (rad) so that its optical axis meets the goal's x = 0 plane at height `aim_z` (m):
    /// experiment D's set-up.
    pub fn looking_along_x(
        distance: f64,
        aim_z: f64,
        pitch: f64,
        fovy: f64,
        size: [usize; 2],
    ) -> Self {
        let (s, c) = pitch.sin_cos();
        // Columns: x = image right = -y world; y = image up; z = against the view direction.
        let (x, y, z) = ([0.0, -1.0, 0.0], [s, 0.0, c], [-c, 0.0, s]);
        Self {
            width: size[0],
            height: size[1],
            fovy,
            pos: [-distance, 0.0, aim_z + distance * pitch.tan()],
            xmat: [x[0], y[0], z[0], x[1], y[1], z[1], x[2], y[2], z[2]],
        }
    }

    /// The camera's x axis (image right) and y axis (image up) in the world frame, as
    /// MJCF's `xyaxes`.
    pub fn xyaxes(&self) -> [f64; 6] {
        let r = &self.xmat;
        [r[0], r[3], r[6], r[1], r[4], r[7]]
    }

    /// Focal length (px): half the image height over tan(fovy / 2).
    pub fn focal(&self) -> f64 {
        0.5 * self.height as f64 / (0.5 * self.fovy.to_radians()).tan()
    }

    /// A world point in the camera frame (x right, y up, -z the viewing direction).
    pub fn to_camera(&self, p: [f64; 3]) -> [f64; 3] {
        let d = [p[0] - self.pos[0], p[1] - self.pos[1], p[2] - self.pos[2]];
        let r = &self.xmat;
        std::array::from_fn(|k| r[k] * d[0] + r[3 + k] * d[1] + r[6 + k] * d[2])
    }

    /// Pixel coordinates of a world point; `None` behind the camera.
    pub fn project(&self, p: [f64; 3]) -> Option<[f64; 2]> {
        let c = self.to_camera(p);
        if c[2] >= 0.0 {
            return None;
        }
        let f = self.focal();
        let (cx, cy) = self.principal_point();
        Some([cx + f * c[0] / -c[2], cy - f * c[1] / -c[2]])
    }

    /// The image centre (px), where the optical axis meets the image.
    pub fn principal_point(&self) -> (f64, f64) {
        (
            0.5 * (self.width as f64 - 1.0),
            0.5 * (self.height as f64 - 1.0),
        )
    }

    /// The image row at which relative features are compared: the centre row.
    pub fn reference_row(&self) -> f64 {
        self.principal_point().1
    }

    /// Column (u) of the image line through the projections of two world points, at row
    /// `v`; `None` when a point is behind the camera or the line runs along the row.
    pub fn u_at_row(&self, ends: [[f64; 3]; 2], v: f64) -> Option<f64> {
        let (a, b) = (self.project(ends[0])?, self.project(ends[1])?);
        let dv = b[1] - a[1];
        (dv.abs() > 1e-9).then(|| a[0] + (v - a[1]) * (b[0] - a[0]) / dv)
    }

    /// The camera moved by `t` (m, world frame): the "deliberate minor displacement" of
    /// section III-B-2. Moved by -o, it sees a part at its nominal pose where the unmoved
    /// camera sees it displaced by o.
    pub fn translated(&self, t: [f64; 3]) -> Self {
        Self {
            pos: std::array::from_fn(|k| self.pos[k] + t[k]),
            ..self.clone()
        }
    }

    /// Errors unless the camera is usable: a positive size, fovy in (0, 180) degrees,
    /// finite position and a rotation matrix.
    fn check(&self) -> std::result::Result<(), String> {
        if self.width < 2 || self.height < 2 {
            return Err(format!(
                "camera size {}x{} px: need at least 2x2",
                self.width, self.height
            ));
        }
        if !(self.fovy > 0.0 && self.fovy < 180.0) {
            return Err(format!("camera fovy {} degrees: need (0, 180)", self.fovy));
        }
        if !self.pos.iter().chain(&self.xmat).all(|x| x.is_finite()) {
            return Err("camera pos/xmat hold a non-finite value".into());
        }
        let r = &self.xmat;
        let col = |k: usize| [r[k], r[3 + k], r[6 + k]];
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                if (dot(col(i), col(j)) - want).abs() > 1e-6 {
                    return Err(format!(
                        "camera xmat is not a rotation (columns {i}, {j}: dot {})",
                        dot(col(i), col(j))
                    ));
                }
            }
        }
        let (x, y, z) = (col(0), col(1), col(2));
        let cross = [
            x[1] * y[2] - x[2] * y[1],
            x[2] * y[0] - x[0] * y[2],
            x[0] * y[1] - x[1] * y[0],
        ];
        if dot(cross, z) < 0.0 {
            return Err("camera xmat is a reflection, not a rotation (x cross y is -z)".into());
        }
        Ok(())
    }
}

/// A task's `[camera]` table: a calibrated camera set up as in experiment D
/// ([`Camera::looking_along_x`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSetup {
    /// Distance in front of the goal along -x (m).
    distance: f64,
    /// Height at which the optical axis meets the goal's x = 0 plane (m).
    aim_z: f64,
    /// Downward tilt (degrees).
    pitch_deg: f64,
    /// Vertical field of view (degrees).
    fovy: f64,
    /// Image width and height (px).
    size: [usize; 2],
}

/// The camera of a task's `[camera]` table; `None` when the task has none.
///
/// # Errors
/// [`MapError::Task`] when the table is malformed or describes no usable camera.
pub fn task_camera(task: &Task) -> Result<Option<Camera>> {
    #[derive(Deserialize)]
    struct WithCamera {
        camera: Option<CameraSetup>,
    }
    let err = |reason: String| MapError::Task {
        path: task.path.clone(),
        reason: format!("[camera]: {reason}"),
    };
    let text = std::fs::read_to_string(&task.path).map_err(|e| err(e.to_string()))?;
    let file: WithCamera = toml::from_str(&text).map_err(|e| err(e.to_string()))?;
    let Some(setup) = file.camera else {
        return Ok(None);
    };
    if !(setup.distance > 0.0 && setup.aim_z.is_finite() && setup.pitch_deg.abs() < 90.0) {
        return Err(err(format!(
            "distance {} must be > 0, aim_z finite, |pitch_deg| {} < 90",
            setup.distance, setup.pitch_deg
        )));
    }
    let camera = Camera::looking_along_x(
        setup.distance,
        setup.aim_z,
        setup.pitch_deg.to_radians(),
        setup.fovy,
        setup.size,
    );
    camera.check().map_err(err)?;
    Ok(Some(camera))
}

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

/// The comparison of section III-B that the filter makes per particle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VisionMethod {
    /// III-B-1: the measured distances (active to passive edge, left and right) against the
    /// particle's distances, both parts projected with the calibrated camera.
    Relative,
    /// III-B-2: the camera is displaced once per image so that the passive part's detected
    /// edges fit its nominal pose; the active part's detected edges are compared with its
    /// edges at the particle's relative pose, projected with the displaced camera.
    Recalibration,
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
}

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
                })
            }
            _ => None,
        }
    }

    /// A task's vision model: its `[camera]` and the features of its `[geometry]`; `None`
    /// when it lacks either.
    ///
    /// # Errors
    /// When the task's `[camera]` or `[geometry]` table is malformed.
    pub fn of_task(task: &Task) -> Result<Option<Self>> {
        let Some(camera) = task_camera(task)? else {
            return Ok(None);
        };
        Ok(Self::of_geometry(
            &crate::cad::geometry_of(&task.path)?,
            camera,
        ))
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

    /// The camera displaced (translated across its view, in the world's x and y) so that
    /// the passive part's silhouette edges at its nominal pose fall on the detected columns
    /// `passive` (left, right; px): Gauss-Newton on both columns. `None` when the columns
    /// cannot be fitted (the edges out of view, or no displacement within ±50 mm fits).
    pub fn recalibrated(&self, passive: [f64; 2]) -> Option<Camera> {
        let miss = |t: [f64; 2]| {
            let c = self
                .passive
                .columns(&self.camera.translated([t[0], t[1], 0.0]), [0.0; 3])?;
            Some([c[0] - passive[0], c[1] - passive[1]])
        };
        let (mut t, h) = ([0.0f64; 2], 1e-6);
        for _ in 0..12 {
            let m = miss(t)?;
            if m[0].abs().max(m[1].abs()) < 1e-4 {
                return Some(self.camera.translated([t[0], t[1], 0.0]));
            }
            let (mx, my) = (miss([t[0] + h, t[1]])?, miss([t[0], t[1] + h])?);
            // Jacobian columns: d(miss)/dtx, d(miss)/dty.
            let j = [
                [(mx[0] - m[0]) / h, (my[0] - m[0]) / h],
                [(mx[1] - m[1]) / h, (my[1] - m[1]) / h],
            ];
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if det.abs() < 1e-9 {
                return None;
            }
            t[0] -= (j[1][1] * m[0] - j[0][1] * m[1]) / det;
            t[1] -= (j[0][0] * m[1] - j[1][0] * m[0]) / det;
            if t[0].abs().max(t[1].abs()) > 0.05 {
                return None;
            }
        }
        None
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
        let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
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
        std::fs::write(path, text).map_err(|source| MapError::Io {
            path: path.to_owned(),
            source,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bearing housing task's geometry.
    fn bearing() -> Geometry {
        crate::cad::geometry_of(&Task::find("bearing_housing").expect("task").path)
            .expect("its [geometry]")
    }

    /// A camera 200 mm in front of the goal along -x, looking along +x, level (no tilt).
    fn level_camera() -> Camera {
        // x axis (image right) = -y world, y axis (up) = +z world, -z (view) = +x world.
        Camera {
            width: 640,
            height: 480,
            fovy: 12.0,
            pos: [-0.2, 0.0, 0.01],
            xmat: [0.0, 0.0, -1.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
        }
    }

    #[test]
    fn a_tilted_camera_sees_its_aim_point_at_the_image_centre() {
        let cam = Camera::looking_along_x(0.2, 0.014, 8f64.to_radians(), 12.0, [640, 480]);
        assert_eq!(cam.check(), Ok(()));
        let p = cam.project([0.0, 0.0, 0.014]).expect("in front");
        let (cx, cy) = cam.principal_point();
        assert!(
            (p[0] - cx).abs() < 1e-9 && (p[1] - cy).abs() < 1e-9,
            "{p:?}"
        );
        // A point 1 mm higher on the aim plane lies higher in the image (smaller v), and a
        // point at +y world lies to the image's left.
        assert!(cam.project([0.0, 0.0, 0.015]).expect("in front")[1] < cy);
        assert!(cam.project([0.0, 0.001, 0.014]).expect("in front")[0] < cx);
        assert_eq!(
            Camera::looking_along_x(0.2, 0.01, 0.0, 12.0, [640, 480]).xyaxes(),
            [0.0, -1.0, 0.0, 0.0, 0.0, 1.0]
        );
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
    fn recalibration_moves_the_camera_so_the_passive_part_fits_at_its_nominal_pose() {
        let g = bearing();
        let m = VisionModel::of_geometry(
            &g,
            Camera::looking_along_x(0.2, 0.014, 8f64.to_radians(), 12.0, [640, 480]),
        )
        .expect("features");
        // Part B truly off by `object`: its detected columns; the displaced camera puts the
        // nominal part there, and part A at tcp - object then lands where A truly is.
        for object in [
            [0.0, 0.002, 0.0],
            [-0.003, 0.0045, 0.0],
            [0.004, -0.001, 0.0],
        ] {
            let seen = m.passive.columns(&m.camera, object).expect("in view");
            let cam = m.recalibrated(seen).expect("a displacement fits");
            let nominal = m.passive.columns(&cam, [0.0; 3]).expect("in view");
            assert!(
                (nominal[0] - seen[0]).abs() < 1e-3 && (nominal[1] - seen[1]).abs() < 1e-3,
                "{nominal:?} {seen:?}"
            );
            let truth = m
                .active
                .columns(&m.camera, [0.0, 0.0, 0.012])
                .expect("A at the TCP");
            let relative = m
                .active
                .columns(&cam, [-object[0], -object[1], 0.012])
                .expect("A relative to B");
            for k in 0..2 {
                assert!(
                    (truth[k] - relative[k]).abs() < 0.01,
                    "{object:?}: {truth:?} {relative:?}"
                );
            }
        }
        // Columns no displacement can produce (the part wider than it can look) are refused.
        assert_eq!(m.recalibrated([0.0, 600.0]), None);
    }

    #[test]
    fn the_bearing_housing_task_has_experiment_ds_camera_and_others_none() {
        let task = Task::find("bearing_housing").expect("task");
        let cam = task_camera(&task)
            .expect("valid [camera]")
            .expect("a camera");
        assert_eq!((cam.width, cam.height, cam.fovy), (640, 480, 12.0));
        // 200 mm in front, looking along +x: the optical axis meets x = 0 at the aim height.
        let axis = [-cam.xmat[2], -cam.xmat[5], -cam.xmat[8]];
        let t = -cam.pos[0] / axis[0];
        assert!(
            (cam.pos[0] + 0.2).abs() < 1e-12 && (cam.pos[2] + t * axis[2] - 0.014).abs() < 1e-12,
            "{cam:?}"
        );
        assert_eq!(
            task_camera(&Task::find("peg_in_hole").expect("task")).expect("no table is fine"),
            None
        );
        let dir = std::env::temp_dir().join(format!("ftmap-camera-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let text = std::fs::read_to_string(&task.path).expect("task file");
        for (bad, needle) in [
            (text.replace("fovy = 12.0", "fovy = 200.0"), "fovy"),
            (text.replace("size = [640, 480]", "size = [640]"), "size"),
        ] {
            let path = dir.join("task.toml");
            std::fs::write(&path, bad).expect("write");
            let e = task_camera(&Task {
                path,
                ..task.clone()
            })
            .expect_err(needle)
            .to_string();
            assert!(
                e.contains("[camera]") && e.contains(needle) && e.contains("task.toml"),
                "{e}"
            );
        }
        std::fs::remove_dir_all(&dir).ok();
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
}
