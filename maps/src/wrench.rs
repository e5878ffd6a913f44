//! Wrench models: from a reduced contact set to the wrench the F/T sensor reads, the
//! force by the paper's Eq. 2 (contact normals, friction) and the torque either by the
//! paper's convex-hull lever rule or by the pressure centroid.

use nalgebra::{Point3, Vector2, Vector3};

use serde::{Deserialize, Serialize};

use crate::depth::{ContactSummary, View};

/// How the wrench of a contact configuration was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WrenchModel {
    /// The paper's: force from contact normals and friction (Eq. 2), torque 0 when the
    /// sensor axis meets the contact hull, else PK x F.
    Paper,
    /// Pressure spread evenly over the contact area: torque = (centroid - sensor) x F.
    Centroid,
    /// Scanned by contact motions in a (simulated) work cell.
    Measured,
    /// Computed from CAD and corrected by a sparse measured map ([`crate::map::blend`]).
    Blended,
}

impl WrenchModel {
    /// Whether the wrench is computed from CAD by this model (paper, centroid), rather than
    /// measured or blended.
    pub fn is_computed(self) -> bool {
        matches!(self, Self::Paper | Self::Centroid)
    }
}

/// Everything about a configuration the wrench models need besides its contacts.
#[derive(Debug, Clone, Copy)]
pub struct WrenchSetup {
    /// The view of the contact computation (task-frame coordinates).
    pub view: View,
    /// Lattice column and row of A's image origin.
    pub origin: (i64, i64),
    /// Pixel size (m).
    pub pixel: f64,
    /// Imposed force along the approach (N).
    pub force: f64,
    /// Friction coefficient.
    pub friction: f64,
}

/// The sensed wrench of a contact: force (N) and torque about the sensor origin (N.m),
/// in task-frame coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wrench {
    /// Force on part A.
    pub force: Vector3<f64>,
    /// Torque on part A about the sensor origin.
    pub torque: Vector3<f64>,
}

impl WrenchSetup {
    /// The wrench on A for contacts `c` under `model`, torque about `sensor` (task frame).
    /// `None` when there is no contact. (`Measured` maps are not computed; it reads as `Centroid`.)
    pub fn wrench(
        &self,
        c: &ContactSummary,
        model: WrenchModel,
        sensor: &Point3<f64>,
    ) -> Option<Wrench> {
        if c.count == 0 {
            return None;
        }
        let force = self.force_on_a(c);
        let n = c.area();
        let mean_h = c.sum_height / n;
        let lever_point = match model {
            WrenchModel::Paper => {
                let hull = convex_hull(self.row_extremes(c));
                let p = Vector2::new(
                    sensor.coords.dot(&self.view.u),
                    sensor.coords.dot(&self.view.v),
                );
                match closest_outside(&hull, p, self.pixel * 1e-3) {
                    None => {
                        return Some(Wrench {
                            force,
                            torque: Vector3::zeros(),
                        });
                    }
                    Some(k) => self.view.unproject([k.x, k.y, mean_h]),
                }
            }
            // Only the computed models reach here (`generate` refuses the others).
            WrenchModel::Centroid | WrenchModel::Measured | WrenchModel::Blended => {
                let (u, v) = self.lattice_to_view(c.sum_col / n, c.sum_row / n);
                self.view.unproject([u, v, mean_h])
            }
        };
        Some(Wrench {
            force,
            torque: (lever_point - sensor).cross(&force),
        })
    }

    /// View (u, v) of a point given in A-image columns and rows.
    fn lattice_to_view(&self, col: f64, row: f64) -> (f64, f64) {
        (
            (self.origin.0 as f64 + col) * self.pixel,
            (self.origin.1 as f64 + row) * self.pixel,
        )
    }

    /// The first and last contact pixel of every contact row, in view (u, v).
    fn row_extremes(&self, c: &ContactSummary) -> Vec<Vector2<f64>> {
        c.rows
            .iter()
            .flat_map(|&(r, first, last)| [(first, r), (last, r)])
            .map(|(col, row)| {
                let (u, v) = self.lattice_to_view(f64::from(col), f64::from(row));
                Vector2::new(u, v)
            })
            .collect()
    }

    /// Eq. 2: the reaction on A along B's mean contact normal, turned towards -a by at most
    /// the friction angle, scaled so its component against the approach is the imposed force.
    fn force_on_a(&self, c: &ContactSummary) -> Vector3<f64> {
        let w = Vector3::z();
        let n = Vector3::from(c.sum_normal)
            .try_normalize(1e-12)
            .filter(|n| n.z > 1e-6)
            .unwrap_or(w);
        let phi = self.friction.atan();
        let dir = if n.z.clamp(-1.0, 1.0).acos() <= phi {
            w
        } else {
            let t = (w - n * n.z).normalize();
            n * phi.cos() + t * phi.sin()
        };
        let f = dir * (self.force / dir.z);
        self.view.u * f.x + self.view.v * f.y + self.view.w * f.z
    }
}

/// Convex hull (counter-clockwise, no repeated points) by Andrew's monotone chain.
pub fn convex_hull(mut pts: Vec<Vector2<f64>>) -> Vec<Vector2<f64>> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>| (a - o).perp(&(b - o));
    let mut hull: Vec<Vector2<f64>> = Vec::with_capacity(2 * pts.len());
    for pass in [pts.clone(), pts.iter().rev().copied().collect()] {
        let start = hull.len();
        for p in pass {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// The point K of the hull nearest to `p` when `p` lies outside it (farther than `eps`),
/// else `None` (the paper's "P inside the convex hull").
pub fn closest_outside(hull: &[Vector2<f64>], p: Vector2<f64>, eps: f64) -> Option<Vector2<f64>> {
    let closest_on = |a: Vector2<f64>, b: Vector2<f64>| {
        let ab = b - a;
        let t = if ab.norm_squared() > 0.0 {
            ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        a + ab * t
    };
    let k = match hull.len() {
        0 => return None,
        1 => hull[0],
        n => {
            let inside =
                n >= 3 && (0..n).all(|i| (hull[(i + 1) % n] - hull[i]).perp(&(p - hull[i])) >= 0.0);
            if inside {
                return None;
            }
            (0..n)
                .map(|i| closest_on(hull[i], hull[(i + 1) % n]))
                .min_by(|a, b| (a - p).norm_squared().total_cmp(&(b - p).norm_squared()))
                .unwrap_or(hull[0])
        }
    };
    ((k - p).norm() > eps).then_some(k)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_inner_points() {
        let pts = [
            (0., 0.),
            (2., 0.),
            (2., 2.),
            (0., 2.),
            (1., 1.),
            (1., 0.),
            (0.5, 1.5),
        ]
        .map(|(x, y)| Vector2::new(x, y))
        .to_vec();
        let hull = convex_hull(pts);
        assert_eq!(hull.len(), 4);
        let area: f64 = (0..4)
            .map(|i| hull[i].perp(&hull[(i + 1) % 4]))
            .sum::<f64>()
            / 2.0;
        assert!((area - 4.0).abs() < 1e-12, "counter-clockwise area {area}");
        assert_eq!(closest_outside(&hull, Vector2::new(1.0, 1.0), 1e-9), None);
        assert_eq!(
            closest_outside(&hull, Vector2::new(3.0, 1.0), 1e-9),
            Some(Vector2::new(2.0, 1.0))
        );
        assert_eq!(
            closest_outside(&hull, Vector2::new(-1.0, -1.0), 1e-9),
            Some(Vector2::new(0.0, 0.0))
        );
    }

    #[test]
    fn friction_cone_keeps_shallow_normals_vertical_and_tilts_steep_ones() {
        let setup = WrenchSetup {
            view: View::along(-Vector3::z()),
            origin: (0, 0),
            pixel: 1e-4,
            force: 50.0,
            friction: 0.3,
        };
        let contact = |n: [f64; 3]| ContactSummary {
            gap: 0.0,
            count: 1,
            sum_col: 0.0,
            sum_row: 0.0,
            sum_height: 0.0,
            sum_normal: n,
            rows: vec![(0, 0, 0)],
            deficit: 0.0,
        };
        // 10 degrees < atan(0.3) = 16.7 degrees: friction holds, force straight up.
        let s = 10f64.to_radians();
        let f = setup.force_on_a(&contact([s.sin(), 0.0, s.cos()]));
        assert!((f - Vector3::new(0.0, 0.0, 50.0)).norm() < 1e-9, "{f}");
        // 45 degrees: force on the cone's edge, 45 - 16.7 degrees from vertical, fz = 50.
        let s = 45f64.to_radians();
        let f = setup.force_on_a(&contact([s.sin(), 0.0, s.cos()]));
        let tilt = f.x.atan2(f.z).to_degrees();
        assert!(
            (tilt - (45.0 - 0.3f64.atan().to_degrees())).abs() < 1e-9,
            "{tilt}"
        );
        assert!((f.z - 50.0).abs() < 1e-9);
    }
}
