//! The vision term of Eq. 3 (section III-B): each particle's features projected with the
//! calibrated camera (3d to 2d) and compared with the detected ones, by relative feature
//! distances (III-B-1) or with a camera recalibrated on the passive part (III-B-2).

use ftmap::vision::{Camera, VisionModel};
use ftmap::{Axis, Pose};

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

/// The camera of `model` displaced (translated across its view, in the world's x and y) so that
/// the passive part's silhouette edges at its nominal pose fall on the detected columns
/// `passive` (left, right; px): Gauss-Newton on both columns. `None` when the columns
/// cannot be fitted (the edges out of view, or no displacement within ±50 mm fits).
pub fn recalibrated(model: &VisionModel, passive: [f64; 2]) -> Option<Camera> {
    let miss = |t: [f64; 2]| {
        let c = model
            .passive
            .columns(&model.camera.translated([t[0], t[1], 0.0]), [0.0; 3])?;
        Some([c[0] - passive[0], c[1] - passive[1]])
    };
    let (mut t, h) = ([0.0f64; 2], 1e-6);
    for _ in 0..12 {
        let m = miss(t)?;
        if m[0].abs().max(m[1].abs()) < 1e-4 {
            return Some(model.camera.translated([t[0], t[1], 0.0]));
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
    inv_var: f64,
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
            inv_var: 1.0 / (sigma * sigma),
            object: xyz(Pose::Object),
            grip: xyz(Pose::Grip),
        }
    }

    /// Prepares one image's detections for a TCP pose; `None` when recalibration finds no
    /// camera displacement that fits the passive part's detected edges.
    pub fn prepare(&self, m: &VisionMeasurement, tcp: &[f64; 6]) -> Option<Prepared> {
        let tcp = [tcp[0], tcp[1], tcp[2]];
        let model = &self.model;
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
                })
            }
            VisionMethod::Recalibration => {
                let camera = recalibrated(model, m.passive)?;
                let target = [m.passive[0] - m.distances[0], m.passive[1] - m.distances[1]];
                Some(Prepared {
                    camera,
                    target,
                    active: None,
                    tcp,
                })
            }
        }
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
                    (-0.5
                        * self.inv_var
                        * ((p.target[0] - q[0]).powi(2) + (p.target[1] - q[1]).powi(2)))
                        as f32
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
            let cam = recalibrated(&m, seen).expect("a displacement fits");
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
        assert_eq!(recalibrated(&m, [0.0, 600.0]), None);
    }
}
