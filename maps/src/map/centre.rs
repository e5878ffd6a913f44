//! The centre map: a second, finer map of the few cells around the goal, where part A
//! rests on part B just off the fit and the contact changes within a clearance.
//!
//! Near the goal the rim contact changes faster than a coarse grid follows: with a rotation
//! error the part rests on every side of the hole at once (the octagon turned by 2 degrees
//! rests on its eight corners), and 0.03 mm off centre the torque is 2.3 times what the
//! interpolation between the centre node and the node 0.1 mm away says (measured against
//! the polygons' exact contact centroid: docs/RESULTS.md). On maps over object.x, object.y
//! alone the FMU's negative contact states where the part goes in whatever the step; with
//! object rotations the centre needs its own grid: its translation step is the largest
//! whole fraction of the coarse one within the fit's radial clearance, over
//! [`CENTRE_CELLS`] coarse steps each way, every other axis as the coarse map's.

use crate::error::{MapError, Result};
use crate::map::FtMap;
use crate::map::resolution::{Coarse, too_coarse};
use crate::task::Task;
use crate::task::dof::{Axis, Pose};
use crate::task::omega::Grid;

/// Coarse steps the centre map covers each way from the goal: the cells whose
/// interpolation reaches the goal's node, and one more.
pub const CENTRE_CELLS: f64 = 2.0;

/// Relative slack in comparing two maps' axes and metadata (stored as f64 from the same
/// task values).
const SAME: f64 = 1e-9;

/// The task of `task`'s centre map, for a map of `grid` and a fit of radial `clearance`
/// (m): `None` where the grid resolves the fit ([`too_coarse`] finds no translation step
/// too wide for it).
///
/// # Errors
/// When the centre's grid cannot be made (a task whose grid is invalid).
pub fn centre_task(task: &Task, grid: &Grid, clearance: Option<f64>) -> Result<Option<Task>> {
    let coarse_step = too_coarse(grid, task.depth.pixel, clearance)
        .iter()
        .any(|c| matches!(c, Coarse::Step { .. }));
    let Some(clearance) = clearance.filter(|_| coarse_step) else {
        return Ok(None);
    };
    let coarse = task.omega.delta_trans;
    // A step equal to the clearance up to rounding is within it.
    let parts = (coarse / clearance * (1.0 - 1e-9)).ceil().max(1.0);
    let step = coarse / parts;
    let mut centre = task.clone();
    centre.omega.delta_trans = step;
    centre.omega.size_trans = (CENTRE_CELLS * coarse).min(task.omega.size_trans);
    // The centre is read at the relative poses near the goal alone.
    centre.omega.reach = 1.0;
    // Whole-pixel shifts: the pixel divides the step (the task's pixel where it does).
    let per_step = (step / task.depth.pixel).round();
    if per_step < 1.0 || (step / task.depth.pixel - per_step).abs() > 1e-6 {
        centre.depth.pixel = step;
    }
    centre.grid()?;
    Ok(Some(centre))
}

impl FtMap {
    /// Checks that `centre` is a centre map of this map: the same task, model, meshes and
    /// conventions, the same axes in the same order, its rotation and grip axes this map's,
    /// its object translations no coarser and within this map's range.
    ///
    /// # Errors
    /// [`MapError::Grid`] naming the first thing that differs.
    pub fn check_centre(&self, centre: &FtMap) -> Result<()> {
        let bad = |what: String| {
            Err(MapError::Grid(format!(
                "not a centre map of this map: {what}"
            )))
        };
        let (a, b) = (self.meta(), centre.meta());
        let close = |x: f64, y: f64| (x - y).abs() <= SAME * x.abs().max(y.abs()).max(1e-12);
        let close3 = |x: [f64; 3], y: [f64; 3]| x.iter().zip(&y).all(|(p, q)| close(*p, *q));
        let sha = |m: &crate::map::MapMeta| {
            m.sources
                .iter()
                .map(|s| s.sha256.clone())
                .collect::<Vec<_>>()
        };
        if a.task != b.task {
            return bad(format!("task `{}`, the map's is `{}`", b.task, a.task));
        }
        if a.model != b.model {
            return bad(format!(
                "wrench model {:?}, the map's is {:?}",
                b.model, a.model
            ));
        }
        if sha(a) != sha(b) {
            return bad("computed from other meshes (SHA-256)".into());
        }
        if !close3(a.approach, b.approach)
            || !close3(a.sensor_origin, b.sensor_origin)
            || !close(a.force, b.force)
            || !close(a.friction, b.friction)
            || a.symmetry != b.symmetry
        {
            return bad("approach, sensor origin, force, friction or symmetry differ".into());
        }
        let (ga, gb) = (self.grid().axes(), centre.grid().axes());
        if ga.len() != gb.len() || ga.iter().zip(gb).any(|(p, q)| p.dof != q.dof) {
            return bad("other axes".into());
        }
        for (p, q) in ga.iter().zip(gb) {
            let refined = q.dof.pose == Pose::Object && matches!(q.dof.axis, Axis::X | Axis::Y);
            if !refined {
                if p.count != q.count || !close(p.min, q.min) || !close(p.step, q.step) {
                    return bad(format!("{} is sampled otherwise than on the map", q.dof));
                }
            } else if q.step > p.step * (1.0 + SAME)
                || q.min < p.min - SAME * p.step
                || q.max() > p.max() + SAME * p.step
            {
                return bad(format!(
                    "{} (step {} m over [{}, {}] m) is coarser than the map's or outside it",
                    q.dof,
                    q.step,
                    q.min,
                    q.max()
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_centre_refines_translations_where_the_step_is_too_wide_for_the_fit() {
        let task = Task::find("octagon_yaw").expect("committed task");
        let grid = task.grid().expect("grid");
        let clearance = task.geometry().expect("[geometry]").clearance();
        let centre = centre_task(&task, &grid, Some(clearance))
            .expect("valid")
            .expect("0.1 mm steps beside a yaw do not resolve a 0.025 mm fit");
        // 0.1 mm into whole parts no wider than 0.025 mm: four of 0.025 mm; the task's
        // 0.05 mm pixel does not divide it, so the pixel is the step.
        assert!((centre.omega.delta_trans - 2.5e-5).abs() < 1e-12);
        assert!((centre.depth.pixel - 2.5e-5).abs() < 1e-12);
        assert!((centre.omega.size_trans - 2e-4).abs() < 1e-12);
        let g = centre.grid().expect("its grid");
        assert_eq!(g.axes()[0].count, 17);
        assert_eq!(
            g.axes()[2].count,
            grid.axes()[2].count,
            "the yaw as the map's"
        );
        // A planar map: the negative contact states the fit; no centre.
        let planar = Task::find("octagon").expect("committed task");
        let pg = planar.grid().expect("grid");
        assert!(
            centre_task(&planar, &pg, Some(clearance))
                .expect("valid")
                .is_none()
        );
        // No clearance known: nothing to refine against.
        assert!(centre_task(&task, &grid, None).expect("valid").is_none());
    }
}
