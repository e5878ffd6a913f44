//! How part A fits into part B: how far off centre part B may sit, direction by direction,
//! with part A still going in (the insertion limit; its smallest value is the fit's radial
//! clearance), and how far below part B's top part A sinks on the chamfers at the fit's
//! edge. A parametric task answers from its dimensions ([`Geometry`]); a task made of
//! meshes alone from parry's exact queries between them ([`MeshFit`]).

use std::f64::consts::TAU;
use std::fmt::Debug;

use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use parry3d_f64::query;
use rayon::prelude::*;

use crate::depth::View;
use crate::error::{MapError, Result};
use crate::exact::{Pair, span};
use crate::task::Task;
use crate::task::cad::Geometry;

/// The fit of a task's two parts, in the goal frame's plane across the approach.
pub trait Fit: Debug + Send + Sync {
    /// How far part B may sit off centre along `theta` (rad, from the view's u axis: x
    /// for an approach along -z) with part A still going in (m).
    fn insertion_limit(&self, theta: f64) -> f64;

    /// How far below part B's top part A's tip rests on the chamfers at the fit's edge (m).
    fn chamfers(&self) -> f64;

    /// The smallest insertion limit over all directions, the fit's radial clearance (m).
    fn clearance(&self) -> f64;

    /// Whether part A goes in with part B at `offset` (m) off the TCP: within the
    /// insertion limit of its direction.
    fn inserts(&self, offset: [f64; 2]) -> bool {
        offset[0].hypot(offset[1]) <= self.insertion_limit(offset[1].atan2(offset[0]))
    }

    /// Whether part A goes in with part B at `offset` (m) off the TCP and turned by `yaw`
    /// (rad) about the approach; `None` where the fit is known at zero yaw only.
    fn inserts_turned(&self, offset: [f64; 2], yaw: f64) -> Option<bool> {
        (yaw == 0.0).then(|| self.inserts(offset))
    }

    /// How far part B may sit off centre along `theta` with part A's tip still landing on a
    /// chamfer or in the hole (m): the insertion limit widened by the 45-degree chamfers.
    fn chamfer_reach(&self, theta: f64) -> f64 {
        self.insertion_limit(theta) * (1.0 + self.chamfers() / self.clearance())
    }
}

impl Fit for Geometry {
    fn insertion_limit(&self, theta: f64) -> f64 {
        Geometry::insertion_limit(self, theta)
    }

    fn chamfers(&self) -> f64 {
        Geometry::chamfers(self)
    }

    fn clearance(&self) -> f64 {
        Geometry::clearance(self)
    }

    fn inserts_turned(&self, offset: [f64; 2], yaw: f64) -> Option<bool> {
        Some(Geometry::inserts_turned(self, offset, yaw))
    }
}

/// Directions over a full turn at which a mesh fit's insertion limit is measured; it is
/// interpolated linearly between them.
pub const DIRECTIONS: usize = 72;
/// Part A is lifted this far off its seat at the goal before it is moved across (m).
const LIFT: f64 = 1e-5;
/// The chamfers' depth is read this far beyond the insertion limit (m).
const BEYOND: f64 = 1e-6;
/// ... against part A's height this far beyond it at most (m), resting on part B's top.
const FAR: f64 = 0.002;
/// Directions at which the chamfers' depth is read.
const CHAMFER_DIRECTIONS: usize = 8;

/// The fit of two meshes, measured with parry's exact queries.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshFit {
    /// Insertion limit at each of [`DIRECTIONS`] directions, the first along u (m).
    limits: Vec<f64>,
    /// Depth of the chamfers (m).
    chamfers: f64,
}

impl MeshFit {
    /// The fit of `task`'s parts given as `pair`: part A at the goal (both frames
    /// coincide), lifted off its seat, moved across the approach until it touches part B,
    /// in each direction; the chamfers' depth from part A lowered onto part B just beyond the
    /// insertion limit and farther out.
    ///
    /// # Errors
    /// When part A does not sit at the goal clear of part B (the meshes are not in the
    /// assembly's coordinates) or can move out of the fit sideways without touching it.
    pub fn measure(task: &Task, pair: &Pair) -> Result<Self> {
        let view = View::along(Vector3::from(task.contact.approach));
        let across = |theta: f64| view.u * theta.cos() + view.v * theta.sin();
        let seated = Isometry3::from(Translation3::from(view.w * LIFT));
        let reach = 2.0 * task.omega.size_trans.max(FAR);
        let err = |reason: String| MapError::Task {
            path: task.path.clone(),
            reason,
        };
        // Directions are independent: measured on every core.
        let limits = (0..DIRECTIONS)
            .into_par_iter()
            .map(|k| {
                let theta = TAU * k as f64 / DIRECTIONS as f64;
                // B off along theta is A off along -theta.
                pair.travel(&seated, &-across(theta), &Isometry3::identity(), reach)
                    .ok_or_else(|| {
                        err(format!(
                            "part A at the goal, lifted {} µm, moves {:.1} mm across the approach at {:.0}° without touching part B: the meshes must be in the assembly's coordinates (part A's frame on part B's at the goal) and part A must sit in a fit",
                            LIFT * 1e6,
                            reach * 1e3,
                            theta.to_degrees()
                        ))
                    })
            })
            .collect::<Result<Vec<f64>>>()?;
        let height = |offset: Vector3<f64>| -> Result<f64> {
            let b_pose = Isometry3::from(Translation3::from(offset));
            let (a_range, b_range) = (
                span(&pair.a, &Isometry3::identity(), &view.w),
                span(&pair.b, &b_pose, &view.w),
            );
            let lift = (b_range[1] - a_range[0]).max(0.0) + FAR;
            let from = Isometry3::from(Translation3::from(view.w * lift));
            let reach = lift + (a_range[1] - b_range[0]).max(0.0) + FAR;
            pair.travel(&from, &-view.w, &b_pose, reach)
                .map(|t| lift - t)
                .ok_or_else(|| {
                    err("part A lowered along the approach beside the fit misses part B".into())
                })
        };
        let steps = (0..CHAMFER_DIRECTIONS)
            .into_par_iter()
            .map(|k| {
                let theta = TAU * k as f64 / CHAMFER_DIRECTIONS as f64;
                let limit = interpolate(&limits, theta);
                let far = height(across(theta) * (limit + FAR.min(task.omega.size_trans)))?;
                let edge = height(across(theta) * (limit + BEYOND))?;
                Ok(far - edge)
            })
            .collect::<Result<Vec<f64>>>()?;
        let mut chamfers = steps.into_iter().fold(0.0, f64::max);
        // A step this small is the edge's own rounding, not a chamfer.
        if chamfers < task.depth.tolerance {
            chamfers = 0.0;
        }
        Ok(Self { limits, chamfers })
    }

    /// The largest insertion limit over the smallest: 1 for a round fit, more where flats
    /// face each other across it (a square's sqrt 2, a hexagon's 1.155, an octagon's 1.082).
    pub fn anisotropy(&self) -> f64 {
        self.limits.iter().copied().fold(0.0, f64::max) / self.clearance()
    }
}

/// The largest turn (rad) within which a fit's rotational play is looked for: a part that
/// turns this far without touching (a round peg about its axis) has no play to state.
const MAX_PLAY: f64 = 0.2;
/// Halvings of a bisection's bracket: [`MAX_PLAY`] / 2^40, far below a nanoradian.
const PLAY_HALVINGS: usize = 40;

/// The fit's rotational play about `axis` (goal frame) at zero offset, by parry's exact
/// intersection tests between the meshes of `pair`: how far part A, seated at the goal and
/// turned about its frame's origin (the tip's centre), turns either way before it touches
/// part B (the smaller way), its lowest point held [`LIFT`] above where it sat, so that a
/// tilted tip's edge does not dig into a blind hole's floor. A position-controlled part goes
/// in where its offset over the clearance and its rotation over this play sum to less than
/// one (to first order; a round peg tilted in its bore: the clearance over the depth).
/// `None` where part A touches unturned or turns [`MAX_PLAY`] both ways freely.
pub fn rotational_play(pair: &Pair, approach: Vector3<f64>, axis: Vector3<f64>) -> Option<f64> {
    let w = View::along(approach).w;
    let axis = Unit::new_normalize(axis);
    let lowest = |r: &UnitQuaternion<f64>| {
        pair.a
            .vertices()
            .iter()
            .map(|p| (r * p).coords.dot(&w))
            .fold(f64::INFINITY, f64::min)
    };
    let seat = lowest(&UnitQuaternion::identity());
    let free = |angle: f64| {
        let r = UnitQuaternion::from_axis_angle(&axis, angle);
        let pose = Isometry3::from_parts(Translation3::from(w * (seat - lowest(&r) + LIFT)), r);
        query::intersection_test(&pose, &pair.a, &Isometry3::identity(), &pair.b)
            .is_ok_and(|hit| !hit)
    };
    if !free(0.0) {
        return None;
    }
    let one_way = |sign: f64| {
        if free(sign * MAX_PLAY) {
            return None;
        }
        Some(largest(|angle| free(sign * angle), MAX_PLAY))
    };
    one_way(1.0)
        .into_iter()
        .chain(one_way(-1.0))
        .reduce(f64::min)
}

/// The largest `x` in [0, `hi`] where `inside` holds, by bisection ([`PLAY_HALVINGS`]
/// halvings): it holds at 0 and not at `hi`, and once it fails it fails beyond.
pub fn largest(inside: impl Fn(f64) -> bool, hi: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, hi);
    for _ in 0..PLAY_HALVINGS {
        let mid = 0.5 * (lo + hi);
        if inside(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// `values` at [`DIRECTIONS`] even directions interpolated linearly at `theta`.
fn interpolate(values: &[f64], theta: f64) -> f64 {
    let n = values.len();
    let x = theta.rem_euclid(TAU) / TAU * n as f64;
    let (k, t) = (x.floor() as usize % n, x.fract());
    values[k] * (1.0 - t) + values[(k + 1) % n] * t
}

impl Fit for MeshFit {
    fn insertion_limit(&self, theta: f64) -> f64 {
        interpolate(&self.limits, theta)
    }

    fn chamfers(&self) -> f64 {
        self.chamfers
    }

    fn clearance(&self) -> f64 {
        self.limits.iter().copied().fold(f64::INFINITY, f64::min)
    }
}
