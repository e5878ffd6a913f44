//! Whether a map resolves its fit: the z-buffer's pixel and Omega's translation step
//! against the fit's diametral gap (twice the radial clearance).
//!
//! A pixel wider than the gap can hide it: the rendered hole may not take the part at all.
//! A translation step wider than the gap leaves the configurations where the part goes in
//! (a disc of the clearance's radius) between the grid's nodes, so that the map's depth
//! channel cannot say where the hole is to better than a step. On maps over `object.x`,
//! `object.y` alone the FMU's negative contact states that disc exactly, whatever the step
//! (measured: a 0.01 mm fit on a 0.1 mm grid, docs/RESULTS.md), so the step counts as
//! coarse only on maps with other DOFs.

use std::fmt;

use crate::task::dof::{Axis, Dof, Pose};
use crate::task::omega::Grid;

/// Share by which a pixel or step may exceed the gap before it counts as coarse: a meshed
/// circle's facets shave the clearance by a fraction of a percent, and a pixel equal to the
/// nominal gap resolves it.
pub(crate) const SLACK: f64 = 0.01;

/// A resolution of a map that is too coarse for the fit's clearance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Coarse {
    /// The depth maps' pixel (m) is wider than the diametral gap (m).
    Pixel {
        /// Pixel size (m).
        pixel: f64,
        /// Twice the radial clearance (m).
        gap: f64,
    },
    /// A translation axis's step (m) is wider than the diametral gap (m), on a map where the
    /// negative contact does not apply.
    Step {
        /// The axis's DOF.
        dof: Dof,
        /// Grid step (m).
        step: f64,
        /// Twice the radial clearance (m).
        gap: f64,
    },
}

/// What of `grid` and `pixel` (m; 0 for measured maps) is too coarse for a fit of radial
/// `clearance` (m); nothing when the clearance is unknown.
pub fn too_coarse(grid: &Grid, pixel: f64, clearance: Option<f64>) -> Vec<Coarse> {
    let Some(gap) = clearance.filter(|c| *c > 0.0).map(|c| 2.0 * c) else {
        return Vec::new();
    };
    let coarse = |v: f64| v > gap * (1.0 + SLACK);
    let mut found = Vec::new();
    if coarse(pixel) {
        found.push(Coarse::Pixel { pixel, gap });
    }
    // The FMU's negative contact states the fit exactly on maps over object.x, object.y
    // (grip translations besides, which only move the sensor's lever: any step is exact).
    let planar = grid.axes().iter().all(|a| {
        a.count == 1
            || (a.dof.pose == Pose::Object && matches!(a.dof.axis, Axis::X | Axis::Y))
            || (a.dof.pose == Pose::Grip && !a.dof.axis.is_rotation())
    });
    if !planar {
        found.extend(
            grid.axes()
                .iter()
                .filter(|a| a.count > 1 && a.dof.pose == Pose::Object)
                .filter(|a| !a.dof.axis.is_rotation() && coarse(a.step))
                .map(|a| Coarse::Step {
                    dof: a.dof,
                    step: a.step,
                    gap,
                }),
        );
    }
    found
}

impl fmt::Display for Coarse {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mm = 1e3;
        match *self {
            Self::Pixel { pixel, gap } => write!(
                f,
                "the pixel {:.4} mm is wider than the fit's diametral gap {:.4} mm: the depth \
                 maps may hide the hole; set [depth] pixel <= {:.4} mm",
                pixel * mm,
                gap * mm,
                gap * mm
            ),
            Self::Step { dof, step, gap } => write!(
                f,
                "{dof}'s step {:.4} mm is wider than the fit's diametral gap {:.4} mm: the \
                 cells where the part goes in fall between the grid's nodes (the FMU's negative \
                 contact states them exactly on maps over object.x, object.y and grip \
                 translations; with object rotations, only the part within the rotational \
                 play the map shows); set the step <= {:.4} mm, or give the FMU a centre map \
                 (`ftmap generate --centre`, FMU parameter centre_map)",
                step * mm,
                gap * mm,
                gap * mm
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::task::omega::GridAxis;

    fn grid(axes: &[(Pose, Axis, f64)]) -> Grid {
        let axes = axes
            .iter()
            .map(|&(pose, axis, step)| {
                GridAxis::symmetric(Dof::new(pose, axis), 10.0 * step, step).unwrap()
            })
            .collect();
        Grid::new(axes).unwrap()
    }

    #[test]
    fn the_pixel_and_the_step_are_held_against_the_diametral_gap() {
        let (x, y, rz) = (
            (Pose::Object, Axis::X, 1e-4),
            (Pose::Object, Axis::Y, 1e-4),
            (Pose::Object, Axis::Rz, 0.01),
        );
        // 0.05 mm radial clearance: a 0.1 mm gap; a 0.1 mm pixel and step resolve it.
        assert!(too_coarse(&grid(&[x, y, rz]), 1e-4, Some(5e-5)).is_empty());
        // A 0.02 mm fit: the pixel is too wide; the planar step is covered by the negative
        // contact, the step beside a rotation is not.
        assert_eq!(
            too_coarse(&grid(&[x, y]), 1e-4, Some(2e-5)),
            vec![Coarse::Pixel {
                pixel: 1e-4,
                gap: 4e-5
            }]
        );
        let found = too_coarse(&grid(&[x, y, rz]), 2e-5, Some(2e-5));
        let dofs: Vec<String> = found
            .iter()
            .map(|c| match c {
                Coarse::Step { dof, .. } => dof.to_string(),
                Coarse::Pixel { .. } => "pixel".into(),
            })
            .collect();
        assert_eq!(dofs, ["object.x", "object.y"]);
        // A grip translation only moves the sensor's lever: the negative contact still states
        // the fit, at any grip step; a grip rotation does not, and the object's steps count.
        let grip = (Pose::Grip, Axis::X, 1e-3);
        assert!(too_coarse(&grid(&[grip, x, y]), 2e-5, Some(2e-5)).is_empty());
        let tilt = (Pose::Grip, Axis::Rx, 0.01);
        assert_eq!(too_coarse(&grid(&[tilt, x, y]), 2e-5, Some(2e-5)).len(), 2);
        // No clearance known (a user's meshes without [geometry]): nothing to say.
        assert!(too_coarse(&grid(&[x, y, rz]), 1.0, None).is_empty());
    }
}
