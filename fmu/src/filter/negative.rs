//! The negative contact: a contact motion that did not insert part A says that part B is
//! not within the fit's clearance of the TCP. The map's depth channel says the same, but
//! only at the grid step: a 0.05 mm disc of inserted configurations around one cell of a
//! 0.1 mm grid is, after interpolation, a dip a whole cell wide that also rules out the
//! offsets between the clearance and the step, where the true one often lies once the
//! filter is close. This term rules out exactly the disc of particles within the clearance
//! of the TCP, and on the maps it applies to it replaces the depth channel.
//!
//! A slide under force that did not go in says the same of every point it passed: the
//! term then rules out the particles within the clearance of the swept line.
//!
//! It applies to maps over `object.x`, `object.y`, with grip translations besides (a grip
//! offset moves part A in the hand, and the object coordinates are the TCP position that
//! aligns the parts whatever it is): with a rotation error part A may not go in even
//! within the clearance.

use ftmap::{Axis, Pose};

use super::lookup::MapAxis;

/// Log-likelihood of a particle that the contact rules out (a likelihood of e^-30: out,
/// but finite, so that a set that has only such particles is re-spread, not lost).
pub const RULED_OUT: f32 = -30.0;

/// The negative contact on one map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NegativeContact {
    /// The fit's radial clearance (m).
    pub clearance: f64,
    x: MapAxis,
    y: MapAxis,
    /// The particles' axis indices of `x` and `y`.
    axes: [usize; 2],
}

impl NegativeContact {
    /// The term for a map with `axes`, when they are `object.x`, `object.y` and grip
    /// translations, and the clearance is positive.
    pub fn new(axes: &[MapAxis], clearance: f64) -> Option<Self> {
        let find = |axis| {
            axes.iter()
                .position(|a| a.dof.pose == Pose::Object && a.dof.axis == axis)
        };
        let others_are_grip_translations = axes.iter().all(|a| {
            (a.dof.pose == Pose::Object && matches!(a.dof.axis, Axis::X | Axis::Y))
                || (a.dof.pose == Pose::Grip && !a.dof.axis.is_rotation())
        });
        match (find(Axis::X), find(Axis::Y)) {
            (Some(i), Some(j)) if others_are_grip_translations && clearance > 0.0 => Some(Self {
                clearance,
                x: axes[i],
                y: axes[j],
                axes: [i, j],
            }),
            _ => None,
        }
    }

    /// Adds [`RULED_OUT`] to the log-likelihood of every particle (grid coordinates in
    /// `pos`, axis-major over `n` particles) whose object offset lies within the clearance
    /// of the segment from `from` to `to` (the TCP's x, y in m; a point where they are
    /// equal, a slide's swept line where not).
    pub fn add_log_likelihood(
        &self,
        pos: &[f32],
        n: usize,
        from: [f64; 2],
        to: [f64; 2],
        ll: &mut [f32],
    ) {
        // In clearances, relative to `to`.
        let (sx, sy) = (
            (self.x.step / self.clearance) as f32,
            (self.y.step / self.clearance) as f32,
        );
        let (cx, cy) = (self.x.coord(to[0]), self.y.coord(to[1]));
        let (ax, ay) = (
            (self.x.coord(from[0]) - cx) * sx,
            (self.y.coord(from[1]) - cy) * sy,
        );
        let len2 = ax * ax + ay * ay;
        let [i, j] = self.axes;
        let (us, vs) = (&pos[i * n..(i + 1) * n], &pos[j * n..(j + 1) * n]);
        for ((l, &u), &v) in ll.iter_mut().zip(us).zip(vs) {
            let (dx, dy) = ((u - cx) * sx, (v - cy) * sy);
            // The nearest point of the segment, as a share of the way from `to` to `from`.
            let t = if len2 > 0.0 {
                ((dx * ax + dy * ay) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (ex, ey) = (dx - t * ax, dy - t * ay);
            if ex * ex + ey * ey < 1.0 {
                *l += RULED_OUT;
            }
        }
    }
}
