//! The vision term of Eq. 3 (section III-B): each particle's features projected with the
//! calibrated camera (3d to 2d) and compared with the detected ones, by relative feature
//! distances (III-B-1) or with a camera recalibrated on the passive part (III-B-2).

use ftmap::vision::{Camera, VisionModel};
use ftmap::{Axis, Pose};
use nalgebra::{Matrix2, Vector2};

use super::lookup::Lookup;

/// Log-likelihood of a particle whose features the camera cannot see (e.g. the camera would
/// stand inside the outline): far below any Gaussian term, yet finite.
const UNSEEN: f32 = -1.0e30;

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

/// Step (m) of the finite differences taken of columns against a camera displacement.
const STEP: f64 = 1e-6;

/// Jacobian of `f` at `t` by forward differences: row r, column c is d f_r / d t_c.
fn jacobian(f: impl Fn([f64; 2]) -> Option<[f64; 2]>, t: [f64; 2]) -> Option<Matrix2<f64>> {
    let m = f(t)?;
    let (mx, my) = (f([t[0] + STEP, t[1]])?, f([t[0], t[1] + STEP])?);
    Some(Matrix2::from_fn(|r, c| ([mx, my][c][r] - m[r]) / STEP))
}

/// Inverse of `j`; `None` when it is (nearly) singular.
fn inverse(j: Matrix2<f64>) -> Option<Matrix2<f64>> {
    (j.determinant().abs() >= 1e-9)
        .then(|| j.try_inverse())
        .flatten()
}

/// A displacement of the camera (across its view, in the world's x and y; m).
type Displacement = [f64; 2];

/// The displacement of the camera of `model` that makes the passive part's silhouette edges at
/// its nominal pose fall on the detected columns `passive` (left, right; px): Gauss-Newton
/// on both columns. `None` when the columns cannot be fitted (the edges out of view, or no
/// displacement within ±50 mm fits).
pub fn recalibration(model: &VisionModel, passive: [f64; 2]) -> Option<Displacement> {
    let columns = |t: Displacement| {
        model
            .passive
            .columns(&model.camera.translated([t[0], t[1], 0.0]), [0.0; 3])
    };
    let mut t = [0.0f64; 2];
    for _ in 0..12 {
        let c = columns(t)?;
        let m = [c[0] - passive[0], c[1] - passive[1]];
        if m[0].abs().max(m[1].abs()) < 1e-4 {
            return Some(t);
        }
        let step = inverse(jacobian(columns, t)?)? * Vector2::from(m);
        t[0] -= step[0];
        t[1] -= step[1];
        if t[0].abs().max(t[1].abs()) > 0.05 {
            return None;
        }
    }
    None
}

/// One image's detections: the FMU's `vision.*` inputs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VisionMeasurement {
    /// u-distance (px) from the active part's edge to the passive part's edge: left, right.
    pub distances: [f64; 2],
    /// Columns (px) of the passive part's left and right edges (recalibration only).
    pub passive: [f64; 2],
}

/// The vision model bound to a map's axes: which particle coordinates move which part.
#[derive(Debug, Clone)]
pub struct VisionSense {
    model: VisionModel,
    method: VisionMethod,
    /// Variance of a feature (px^2).
    var: f64,
    /// Map axis of object x, y, z and grip x, y, z, where the map has one.
    object: [Option<usize>; 3],
    grip: [Option<usize>; 3],
}

/// A measurement made ready for the particles: the camera and what is compared.
#[derive(Debug, Clone)]
pub struct Prepared {
    camera: Camera,
    /// Relative: the measured distances; recalibration: the active part's detected columns.
    target: [f64; 2],
    /// Columns of the active part when no grip axis moves it (relative method).
    active: Option<[f64; 2]>,
    tcp: [f64; 3],
    /// Inverse covariance (px^-2) of the two residuals, target minus prediction.
    information: Matrix2<f64>,
}

impl VisionSense {
    /// Binds `model` to the axes of `lookup`; `sigma` is the standard deviation of a feature (px).
    pub fn new(model: VisionModel, method: VisionMethod, sigma: f64, lookup: &Lookup) -> Self {
        let find = |pose: Pose, axis: Axis| {
            lookup
                .axes()
                .iter()
                .position(|a| a.dof.pose == pose && a.dof.axis == axis)
        };
        let xyz = |pose| [Axis::X, Axis::Y, Axis::Z].map(|a| find(pose, a));
        Self {
            model,
            method,
            var: sigma * sigma,
            object: xyz(Pose::Object),
            grip: xyz(Pose::Grip),
        }
    }

    /// Prepares one image's detections for a TCP pose; `None` when recalibration finds no
    /// camera displacement that fits the passive part's detected edges.
    pub fn prepare(&self, m: &VisionMeasurement, tcp: &[f64; 6]) -> Option<Prepared> {
        let tcp = [tcp[0], tcp[1], tcp[2]];
        let model = &self.model;
        let isotropic = Matrix2::identity() / self.var;
        match self.method {
            VisionMethod::Relative => {
                let active = if self.grip.iter().all(Option::is_none) {
                    model.active.columns(&model.camera, tcp)
                } else {
                    None
                };
                Some(Prepared {
                    camera: model.camera.clone(),
                    target: m.distances,
                    active,
                    tcp,
                    information: isotropic,
                })
            }
            VisionMethod::Recalibration => {
                let t = recalibration(model, m.passive)?;
                Some(Prepared {
                    camera: model.camera.translated([t[0], t[1], 0.0]),
                    target: [m.passive[0] - m.distances[0], m.passive[1] - m.distances[1]],
                    active: None,
                    tcp,
                    information: self.recalibrated_information(t, tcp).unwrap_or(isotropic),
                })
            }
        }
    }

    /// Inverse covariance of the active columns' residuals with the camera recalibrated by
    /// `t`, at the TCP: `sigma^2 (I + A A^T)`, `A` = d(active columns)/d(displacement) times
    /// d(displacement)/d(passive columns), linearised. The displacement is fitted to two
    /// noisy columns, so the active columns it predicts carry their noise too; the passive
    /// part's scale is all that fixes the camera along its optical axis and changes by a
    /// fraction of a pixel per millimetre: taking the displaced camera as exact made the
    /// spread along that axis 2-3 times too narrow. `None` where the columns leave the view.
    fn recalibrated_information(&self, t: Displacement, tcp: [f64; 3]) -> Option<Matrix2<f64>> {
        let model = &self.model;
        let displaced = |d: Displacement| model.camera.translated([t[0] + d[0], t[1] + d[1], 0.0]);
        let passive = jacobian(|d| model.passive.columns(&displaced(d), [0.0; 3]), [0.0; 2])?;
        let active = jacobian(|d| model.active.columns(&displaced(d), tcp), [0.0; 2])?;
        let a = active * inverse(passive)?;
        inverse((Matrix2::identity() + a * a.transpose()) * self.var)
    }

    /// Adds each particle's vision log-likelihood to `ll`; `value(k, i)` is particle `i`'s
    /// pose on map axis `k` (m).
    pub fn add_log_likelihood(
        &self,
        p: &Prepared,
        n: usize,
        value: impl Fn(usize, usize) -> f64,
        ll: &mut [f32],
    ) {
        let model = &self.model;
        let at = |axes: &[Option<usize>; 3], i: usize| axes.map(|k| k.map_or(0.0, |k| value(k, i)));
        for (i, l) in ll.iter_mut().enumerate().take(n) {
            let (object, grip) = (at(&self.object, i), at(&self.grip, i));
            let active_at = std::array::from_fn::<f64, 3, _>(|k| p.tcp[k] + grip[k]);
            let predicted = match self.method {
                VisionMethod::Relative => {
                    let a = p
                        .active
                        .or_else(|| model.active.columns(&p.camera, active_at));
                    a.zip(model.passive.columns(&p.camera, object))
                        .map(|(a, b)| [b[0] - a[0], b[1] - a[1]])
                }
                VisionMethod::Recalibration => model
                    .active
                    .columns(&p.camera, std::array::from_fn(|k| active_at[k] - object[k])),
            };
            *l += match predicted {
                Some(q) => {
                    let r = Vector2::new(p.target[0] - q[0], p.target[1] - q[1]);
                    (-0.5 * r.dot(&(p.information * r))) as f32
                }
                None => UNSEEN,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recalibration_moves_the_camera_so_the_passive_part_fits_at_its_nominal_pose() {
        let m = ftfusion_testkit::bearing_vision();
        // Part B truly off by `object`: its detected columns; the displaced camera puts the
        // nominal part there, and part A at tcp - object then lands where A truly is.
        for object in [
            [0.0, 0.002, 0.0],
            [-0.003, 0.0045, 0.0],
            [0.004, -0.001, 0.0],
        ] {
            let seen = m.passive.columns(&m.camera, object).expect("in view");
            let t = recalibration(&m, seen).expect("a displacement fits");
            let cam = m.camera.translated([t[0], t[1], 0.0]);
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
        assert_eq!(recalibration(&m, [0.0, 600.0]), None);
    }
}
