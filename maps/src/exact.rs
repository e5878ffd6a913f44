//! Exact queries between the two parts' meshes with parry, independent of the z-buffer: how
//! far part A travels along a direction until it touches part B (a shape cast, good to some
//! 30 micrometres, refined by bisection with exact intersection tests).

use nalgebra::{Isometry3, Translation3, Vector3};
use parry3d_f64::query::{self, ShapeCastOptions};
use parry3d_f64::shape::TriMesh;

use crate::error::{MapError, Result};
use crate::mesh::Mesh;

/// How far the shape cast may stop short of or past the contact (m): the bracket about
/// where it stopped starts this far either side, and doubles until it holds the contact.
const CAST_SLACK: f64 = 1e-4;
/// Width of the bracket at which the travel counts as found (m).
const CONVERGED: f64 = 1e-9;

/// Parts A and B as parry triangle meshes.
pub struct Pair {
    /// Part A in its own frame (the task frame).
    pub a: TriMesh,
    /// Part B in its own frame (the goal frame).
    pub b: TriMesh,
}

impl Pair {
    /// The parry shapes of two checked meshes.
    pub fn new(mesh_a: &Mesh, mesh_b: &Mesh) -> Result<Self> {
        let shape = |m: &Mesh| {
            TriMesh::new(m.vertices.clone(), m.faces.clone()).map_err(|e| MapError::Mesh {
                path: m.path.clone(),
                reason: format!("parry cannot build a triangle mesh of it: {e}"),
            })
        };
        Ok(Self {
            a: shape(mesh_a)?,
            b: shape(mesh_b)?,
        })
    }

    /// How far A at `from` travels along the unit vector `dir` until it touches B at
    /// `b_pose` (m), within `reach`; `None` when it does not. A must be clear of B at `from`.
    /// Swept with parry's shape cast, then bracketed about where the cast stopped between a
    /// pose clear of B and one touching it, and the bracket halved by parry's intersection
    /// tests until it is [`CONVERGED`] wide: an intersection test stops at the first pair of
    /// triangles that touch, where an exact distance between parts in a fit weighs every
    /// pair of the walls that face each other.
    pub fn travel(
        &self,
        from: &Isometry3<f64>,
        dir: &Vector3<f64>,
        b_pose: &Isometry3<f64>,
        reach: f64,
    ) -> Option<f64> {
        let hit = query::cast_shapes(
            from,
            dir,
            &self.a,
            b_pose,
            &Vector3::zeros(),
            &self.b,
            ShapeCastOptions::with_max_time_of_impact(reach),
        )
        .ok()??;
        let toi = hit.time_of_impact;
        let touching = |t: f64| {
            query::intersection_test(
                &(Translation3::from(dir * t) * from),
                &self.a,
                b_pose,
                &self.b,
            )
            .ok()
        };
        // Clear of B below the bracket: where the cast stopped past the contact, back off further.
        let mut slack = CAST_SLACK;
        let mut lo = (toi - slack).max(0.0);
        while touching(lo)? {
            if lo == 0.0 {
                return None;
            }
            slack *= 2.0;
            lo = (toi - slack).max(0.0);
        }
        // Touching above it: where the cast stopped short of the contact, look further.
        let mut slack = CAST_SLACK;
        let mut hi = toi + slack;
        while !touching(hi)? {
            if hi >= reach {
                return None;
            }
            slack *= 2.0;
            hi = (toi + slack).min(reach);
        }
        while hi - lo > CONVERGED {
            let mid = 0.5 * (lo + hi);
            if touching(mid)? {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(lo)
    }
}

/// Lowest and highest coordinate along `w` of `shape` at `pose` (its bounding box's).
pub fn span(shape: &TriMesh, pose: &Isometry3<f64>, w: &Vector3<f64>) -> [f64; 2] {
    let local = shape.local_aabb();
    local
        .vertices()
        .iter()
        .map(|c| (pose * c).coords.dot(w))
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], x| {
            [lo.min(x), hi.max(x)]
        })
}
