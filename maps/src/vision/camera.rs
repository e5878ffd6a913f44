//! The calibrated pinhole camera of section III, in MuJoCo's conventions.
//!
//! Pixel coordinates: `u` to the right, `v` down, the centre of pixel (column i, row j) at
//! (i, j). The camera looks along its -z axis, x to the image's right, y up (MuJoCo's camera).

use serde::{Deserialize, Serialize};

use crate::task::CameraSetup;

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
    pub(crate) fn check(&self) -> std::result::Result<(), String> {
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

impl From<&CameraSetup> for Camera {
    /// The camera a task's `[camera]` table describes.
    fn from(setup: &CameraSetup) -> Self {
        Self::looking_along_x(
            setup.distance,
            setup.aim_z,
            setup.pitch_deg.to_radians(),
            setup.fovy,
            setup.size,
        )
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::Task;

    /// A camera 200 mm in front of the goal along -x, looking along +x, level (no tilt).
    pub(crate) fn level_camera() -> Camera {
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
    fn the_bearing_housing_tasks_camera_aims_where_its_table_says() {
        let task = Task::find("bearing_housing").expect("task");
        let cam = Camera::from(task.camera.as_ref().expect("a camera"));
        assert_eq!(cam.check(), Ok(()));
        assert_eq!((cam.width, cam.height, cam.fovy), (640, 480, 12.0));
        // 200 mm in front, looking along +x: the optical axis meets x = 0 at the aim height.
        let axis = [-cam.xmat[2], -cam.xmat[5], -cam.xmat[8]];
        let t = -cam.pos[0] / axis[0];
        assert!(
            (cam.pos[0] + 0.2).abs() < 1e-12 && (cam.pos[2] + t * axis[2] - 0.014).abs() < 1e-12,
            "{cam:?}"
        );
    }
}
