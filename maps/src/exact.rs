//! Exact queries between the two parts' meshes with parry, independent of the z-buffer: how
//! far part A travels along a direction until it touches part B (a shape cast, good to some
//! 30 micrometres, refined by exact mesh-to-mesh distances until they vanish).

use nalgebra::{Isometry3, Translation3, Vector3};
use parry3d_f64::query::{self, ShapeCastOptions};
use parry3d_f64::shape::TriMesh;

use crate::error::{MapError, Result};
use crate::mesh::Mesh;

/// How far the shape cast may stop short of or past the contact (m): the advance by exact
/// distances starts this far before where it stopped.
const CAST_SLACK: f64 = 1e-4;
/// Distance at which the advance counts as touching (m).
const CONVERGED: f64 = 1e-9;
/// Advances at most: a contact at 80 degrees to the travel closes its gap by 17 % a step.
const ADVANCES: usize = 200;

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
    /// Swept with parry's shape cast, then advanced by the exact distance between the meshes
    /// until it vanishes: a distance never exceeds the gap along the travel, so no step
    /// passes the contact.
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
        let at = |t: f64| Translation3::from(dir * t) * from;
        let distance = |t: f64| query::distance(&at(t), &self.a, b_pose, &self.b).ok();
        // Clear of B first: where the cast stopped past the contact, back off further.
        let mut back_off = CAST_SLACK;
        let mut t = (hit.time_of_impact - back_off).max(0.0);
        let mut d = distance(t)?;
        while d == 0.0 && t > 0.0 {
            back_off *= 2.0;
            t = (hit.time_of_impact - back_off).max(0.0);
            d = distance(t)?;
        }
        for _ in 0..ADVANCES {
            if d < CONVERGED {
                break;
            }
            t += d;
            d = distance(t)?;
        }
        Some(t)
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
