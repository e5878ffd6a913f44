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
//! A contact that went in says the converse: part B is within the clearance of the TCP.
//! The term then rules out every particle outside that disc, and replaces the depth
//! channel there too, whose interpolated step would otherwise rule out all but the
//! inserted cell's centre.
//!
//! It applies to maps over `object.x`, `object.y`, with grip translations besides (a grip
//! offset moves part A in the hand, and the object coordinates are the TCP position that
//! aligns the parts whatever it is) and object rotations whose play the map shows (cells
//! through its centre inserted along them). With a rotation error part A goes in within
//! less than the clearance, so the term rules out only the particles inside the diamond
//! |offset| / clearance + sum |rotation error| / play < 1, a region the fit's insertion
//! set holds when that set is convex (to first order the octagon's is: the room its
//! corners leave shrinks linearly with the yaw). Grip rotations, and object rotations
//! without play, leave no such region: no term then.

use ftmap::{Axis, Pose};

use super::lookup::MapAxis;

/// Log-likelihood of a particle that the contact rules out (a likelihood of e^-30: out,
/// but finite, so that a set that has only such particles is re-spread, not lost).
pub const RULED_OUT: f32 = -30.0;

/// A slide's or twist's start this close to its end (a share of the clearance or of the
/// yaw's step) is its end.
pub const UNMOVED: f64 = 0.01;

/// The negative contact on one map.
#[derive(Debug, Clone, PartialEq)]
pub struct NegativeContact {
    /// The fit's radial clearance (m).
    pub clearance: f64,
    x: MapAxis,
    y: MapAxis,
    /// The particles' axis indices of `x` and `y`.
    axes: [usize; 2],
    /// The object rotation axes.
    rotations: Vec<Rotation>,
}

/// An object rotation axis as the term reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Rotation {
    /// The particles' axis index.
    k: usize,
    axis: MapAxis,
    /// Its zero rotation (grid units).
    zero: f32,
    /// The fit's play about it (grid units).
    play: f32,
}

impl NegativeContact {
    /// The term for a map with `axes` (with each axis's rotational `play`, grid units),
    /// when they are `object.x`, `object.y`, grip translations and object rotations with
    /// play, and the clearance is positive.
    pub fn new(axes: &[MapAxis], play: &[f32], clearance: f64) -> Option<Self> {
        let find = |axis| {
            axes.iter()
                .position(|a| a.dof.pose == Pose::Object && a.dof.axis == axis)
        };
        let rotations: Vec<Rotation> = axes
            .iter()
            .zip(play)
            .enumerate()
            .filter(|(_, (a, _))| a.dof.pose == Pose::Object && a.dof.is_rotation())
            .map(|(k, (&axis, &play))| Rotation {
                k,
                axis,
                zero: axis.coord(0.0),
                play,
            })
            .collect();
        let others_allowed = axes.iter().zip(play).all(|(a, &p)| match a.dof.pose {
            Pose::Object => matches!(a.dof.axis, Axis::X | Axis::Y) || p > 0.0,
            Pose::Grip => !a.dof.axis.is_rotation(),
        });
        match (find(Axis::X), find(Axis::Y)) {
            (Some(i), Some(j)) if others_allowed && clearance > 0.0 => Some(Self {
                clearance,
                x: axes[i],
                y: axes[j],
                axes: [i, j],
                rotations,
            }),
            _ => None,
        }
    }

    /// Adds [`RULED_OUT`] to the log-likelihood of every particle (grid coordinates in
    /// `pos`, axis-major, its map coordinates relative to the TCP in `rel`) whose object
    /// offset lies within the clearance of any of `motions`, less what its rotation errors
    /// use of the play. A motion `[from, to]` (the TCP's x, y in m and rz in rad) started
    /// at `from` and ended at `to`: where only x, y differ, a slide, whose swept line
    /// counts; where only rz differs, a twist about z, whose swept yaws count; where both
    /// differ, only its end. Differences below [`UNMOVED`] of the clearance (x, y) or of
    /// the yaw's grid step (rz, and any rz on a map without yaw) count as none: a robot's
    /// own jitter.
    pub fn add_log_likelihood(
        &self,
        pos: &[f32],
        rel: &[f32],
        motions: &[[[f64; 3]; 2]],
        ll: &mut [f32],
    ) {
        let swept: Vec<Swept> = motions
            .iter()
            .map(|&[from, to]| self.swept(from, to))
            .collect();
        let n = ll.len();
        for (i, l) in ll.iter_mut().enumerate() {
            // Without a branch on the particle (which way it goes is a coin's toss there):
            // every motion is tested.
            let within = swept
                .iter()
                .fold(false, |w, s| w | self.within(s, pos, rel, n, i));
            *l += if within { RULED_OUT } else { 0.0 };
        }
    }

    /// Adds [`RULED_OUT`] to the log-likelihood of every particle that a contact motion
    /// which went in at `at` (the TCP's x, y in m and rz in rad) rules out: those whose
    /// object offset does not lie within the clearance of `at`, less what their rotation
    /// errors use of the play.
    pub fn add_went_in_log_likelihood(
        &self,
        pos: &[f32],
        rel: &[f32],
        at: [f64; 3],
        ll: &mut [f32],
    ) {
        let s = self.swept(at, at);
        let n = ll.len();
        for (i, l) in ll.iter_mut().enumerate() {
            *l += if self.within(&s, pos, rel, n, i) {
                0.0
            } else {
                RULED_OUT
            };
        }
    }

    /// The motion from `from` to `to` as [`Self::add_log_likelihood`] reads it, in the
    /// particles' terms.
    fn swept(&self, from: [f64; 3], to: [f64; 3]) -> Swept {
        let slid = (from[0] - to[0]).hypot(from[1] - to[1]) > UNMOVED * self.clearance;
        let twisted = self.rotations.iter().any(|r| {
            r.axis.dof.axis == Axis::Rz && (from[2] - to[2]).abs() > UNMOVED * r.axis.step
        });
        let from = match (slid, twisted) {
            (true, false) => [from[0], from[1], to[2]],
            (false, true) => [to[0], to[1], from[2]],
            _ => to,
        };
        // In clearances, relative to `to`.
        let scale = [
            (self.x.step / self.clearance) as f32,
            (self.y.step / self.clearance) as f32,
        ];
        let end = [self.x.coord(to[0]), self.y.coord(to[1])];
        let line = [
            (self.x.coord(from[0]) - end[0]) * scale[0],
            (self.y.coord(from[1]) - end[1]) * scale[1],
        ];
        Swept {
            scale,
            end,
            line,
            len2: line[0] * line[0] + line[1] * line[1],
            twist: self
                .rotations
                .iter()
                .find(|r| r.axis.dof.axis == Axis::Rz)
                .map_or(0.0, |r| ((from[2] - to[2]) / r.axis.step) as f32),
        }
    }

    /// Whether particle `i` of `n` lies within the clearance of motion `s`, less what its
    /// rotation errors use of the play (a yaw error counted from the nearest yaw the twist
    /// passed).
    #[inline(always)]
    fn within(&self, s: &Swept, pos: &[f32], rel: &[f32], n: usize, i: usize) -> bool {
        let left = 1.0
            - self
                .rotations
                .iter()
                .map(|r| {
                    let e = r.axis.difference(rel[r.k * n + i] - r.zero);
                    let swept = if r.axis.dof.axis == Axis::Rz {
                        s.twist
                    } else {
                        0.0
                    };
                    beyond(&r.axis, e, swept) / r.play
                })
                .sum::<f32>();
        let [u, v] = self.axes.map(|k| pos[k * n + i]);
        let (dx, dy) = ((u - s.end[0]) * s.scale[0], (v - s.end[1]) * s.scale[1]);
        let [ax, ay] = s.line;
        // The nearest point of the segment, as a share of the way from the end to the start.
        let t = if s.len2 > 0.0 {
            ((dx * ax + dy * ay) / s.len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (ex, ey) = (dx - t * ax, dy - t * ay);
        (left > 0.0) & (ex * ex + ey * ey < left * left)
    }
}

/// A motion in the particles' terms: where it ended (grid units) and the line back to its
/// start, in clearances.
struct Swept {
    /// Grid units per clearance, along x and y.
    scale: [f32; 2],
    /// The end's grid coordinates.
    end: [f32; 2],
    /// From the end to the start, in clearances.
    line: [f32; 2],
    /// The line's squared length.
    len2: f32,
    /// The yaws swept, from the end to the start (grid units of `object.rz`; 0 without
    /// that axis).
    twist: f32,
}

/// How far the rotation error `e` (grid units) lies outside the interval between 0 and
/// `swept` on axis `a`, the shortest way round on a periodic axis (0 inside it).
fn beyond(a: &MapAxis, e: f32, swept: f32) -> f32 {
    let (lo, hi) = (swept.min(0.0), swept.max(0.0));
    let outside = |x: f32| (lo - x).max(x - hi).max(0.0);
    match a.period {
        Some(p) if hi - lo >= p => 0.0,
        Some(p) => [-p, 0.0, p]
            .iter()
            .map(|k| outside(e + k))
            .fold(f32::INFINITY, f32::min),
        None => outside(e),
    }
}
