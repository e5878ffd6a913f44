//! Where the simulated work cell accepts part A: a contact motion at the nominal goal with
//! part B moved off along a direction, the offset bisected until insertion stops, against
//! the geometry's insertion limit. A scene is honest when the two agree: campaign figures
//! measured in a hole more forgiving than the CAD flatter the estimator.

use std::f64::consts::PI;
use std::fmt;

use ftmap::Task;

use crate::error::{HarnessError, Result};
use crate::scene::SERVO_KP;
use crate::sim::Sim;
use crate::world::World;

/// The bisection stops when the bracket is this narrow (m).
pub const RESOLUTION: f64 = 1.0e-6;
/// The outer end of the bracket, in insertion limits beyond the chamfers' reach: part A
/// must not go in that far off.
const OUTER: f64 = 3.0;

/// The insertion boundary along one direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boundary {
    /// Direction of part B's offset (rad, goal frame).
    pub theta: f64,
    /// The geometry's insertion limit (m).
    pub geometric: f64,
    /// How far off part A's tip still lands on a chamfer (m; the insertion limit without).
    pub chamfer_reach: f64,
    /// The largest offset at which part A went in (m, to [`RESOLUTION`]).
    pub measured: f64,
}

impl Boundary {
    /// Measured minus geometric (m): positive where the scene is more forgiving.
    pub fn excess(&self) -> f64 {
        self.measured - self.geometric
    }
}

/// Boundaries of one task along several directions.
#[derive(Debug, Clone, PartialEq)]
pub struct Boundaries {
    /// Task name.
    pub task: String,
    /// One per direction.
    pub directions: Vec<Boundary>,
}

impl Boundaries {
    /// The largest |measured - geometric| over the directions (m).
    pub fn worst(&self) -> f64 {
        self.directions
            .iter()
            .map(|b| b.excess().abs())
            .fold(0.0, f64::max)
    }
}

impl fmt::Display for Boundaries {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "insertion boundary of {} (mm)", self.task)?;
        writeln!(
            f,
            "direction  geometry  chamfers' reach  MuJoCo  difference"
        )?;
        for b in &self.directions {
            writeln!(
                f,
                "{:>8.1}°  {:>8.4}  {:>15.4}  {:>6.4}  {:>+10.4}",
                b.theta.to_degrees(),
                b.geometric * 1e3,
                b.chamfer_reach * 1e3,
                b.measured * 1e3,
                b.excess() * 1e3
            )?;
        }
        writeln!(f, "worst difference {:.4} mm", self.worst() * 1e3)
    }
}

/// How far the x/y servos give way while part A slides down a 45-degree chamfer pressed with
/// the task's force against friction mu: F (1 - mu) / (1 + mu) over their stiffness (m); 0
/// without chamfers. Part A goes in this much farther off than the fit allows.
///
/// # Errors
/// When the task's fit cannot be had ([`Task::fit`]).
pub fn chamfer_yield(task: &Task) -> Result<f64> {
    if task.fit()?.chamfers() == 0.0 {
        return Ok(0.0);
    }
    let (f, mu) = (task.contact.force, task.contact.friction);
    Ok(f * (1.0 - mu) / (1.0 + mu) / SERVO_KP)
}

/// `n` directions evenly over a half turn (the parts are point-symmetric), the first along +x.
pub fn directions(n: usize) -> Vec<f64> {
    (0..n).map(|k| PI * k as f64 / n as f64).collect()
}

/// Whether part A goes in at the nominal goal with part B at `offset` (m).
fn inserts(sim: &mut Sim, offset: [f64; 2]) -> bool {
    sim.set_object(offset);
    sim.contact_motion([0.0, 0.0]).inserted
}

/// The insertion boundary along `theta`: bisects part B's offset between 0 (part A must go
/// in) and the chamfers' reach plus three insertion limits (it must not).
///
/// # Errors
/// When part A does not go in centred, or goes in at the bracket's outer end.
pub fn boundary(sim: &mut Sim, task: &Task, theta: f64) -> Result<Boundary> {
    let fit = task.fit()?;
    let (geometric, chamfer_reach) = (fit.insertion_limit(theta), fit.chamfer_reach(theta));
    let along = |d: f64| [d * theta.cos(), d * theta.sin()];
    let invalid = |reason: String| HarnessError::Invalid {
        what: "insertion boundary",
        reason: format!("task {}: {reason}", task.name),
    };
    if !inserts(sim, [0.0, 0.0]) {
        return Err(invalid("part A does not go in with part B centred".into()));
    }
    let (mut lo, mut hi) = (0.0, chamfer_reach + OUTER * geometric);
    if inserts(sim, along(hi)) {
        return Err(invalid(format!(
            "part A goes in {:.4} mm off along {:.1}°, {OUTER} insertion limits beyond the chamfers",
            hi * 1e3,
            theta.to_degrees()
        )));
    }
    while hi - lo > RESOLUTION {
        let mid = 0.5 * (lo + hi);
        if inserts(sim, along(mid)) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Boundary {
        theta,
        geometric,
        chamfer_reach,
        measured: lo,
    })
}

/// The insertion boundaries of `task` along `thetas`.
///
/// # Errors
/// As [`boundary`].
pub fn boundaries(sim: &mut Sim, task: &Task, thetas: &[f64]) -> Result<Boundaries> {
    Ok(Boundaries {
        task: task.name.clone(),
        directions: thetas
            .iter()
            .map(|&t| boundary(sim, task, t))
            .collect::<Result<_>>()?,
    })
}
