//! Scenes for parts given by their meshes alone (a task without `[geometry]`).
//!
//! Part B: an exact convex decomposition of the surface it shows along the approach. Its
//! up-facing triangles are grouped by plane, each group split into convex polygons
//! (Hertel-Mehlhorn, parry2d), and each polygon extruded down into a prism whose top is the
//! polygon itself: the prisms tile part B as seen from above, the vertical steps between
//! them its walls. That is exact where part B is a height field along the approach (every
//! line along it crosses part B's upper surface once) near the fit; an overhang or undercut
//! part A could reach is not, and then no scene is written. Either way the pieces are
//! checked against the mesh with parry's point queries within [`BOUND`].
//!
//! Part A: its contact face is the region of its lowest flat faces looking along the
//! approach (the bed of small spheres of [`crate::scene`] covers it); its other faces that
//! look along the approach (chamfers, steps) become convex wedges.

use std::collections::{BTreeMap, HashMap};

use nalgebra::{Isometry3, Point2, Point3};
use parry3d_f64::bounding_volume::BoundingVolume;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::{ConvexPolyhedron, SharedShape};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use ftmap::Task;
use ftmap::mesh::Mesh;

use crate::error::{HarnessError, Result};
use crate::scene::{Face, Outline, Piece, SPHERE_RADIUS, area};

/// How far part B's pieces may stray from its mesh where part A can touch it (m).
pub const BOUND: f64 = 1e-5;
/// A triangle whose normal's component along the approach is below this is a wall.
const WALL: f64 = 1e-4;
/// A flat face's normal is within this of the approach (1 - cos).
const FLAT: f64 = 1e-9;
/// Vertices this close along the approach are at one level (m).
const LEVEL: f64 = 1e-9;
/// Part A's tip face must lie this close to its frame's origin along the approach (m).
const TIP_AT_ORIGIN: f64 = 1e-6;
/// Lattice pitch of the sphere bed at least (m); wider on faces that would need more than
/// [`BED_CELLS`] cells.
const PITCH: f64 = 0.0005;
/// Lattice cells of the bed at most.
const BED_CELLS: f64 = 1500.0;
/// Height of part A's wedges above the faces they stand on (m).
const WEDGE_RISE: f64 = 0.001;
/// Corners of a piece's top at most.
const MAX_CORNERS: usize = 32;
/// Surface samples of part B checked against the pieces.
const SAMPLES: usize = 20_000;

/// A convex hull's vertices (m).
type Hull = Vec<[f64; 3]>;

/// Part A's contact face and wedges, part B's pieces and top, from the task's meshes.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshScene {
    /// Part A's contact face (the bed's region).
    pub face: Face,
    /// Part A's other faces looking along the approach, as convex hulls (task frame).
    pub wedges: Vec<Hull>,
    /// Part B's convex pieces.
    pub pieces: Vec<Piece>,
    /// Height of part B's top above part A's tip where they can touch (m).
    pub top: f64,
    /// The largest distance found between part B's mesh and its pieces where part A can
    /// touch it (m).
    pub deviation: f64,
}

/// The scene parts of `task` from its meshes.
///
/// # Errors
/// When the approach is not along -z, part A's tip is not at its frame's origin or has no
/// flat face, or part B's pieces stray more than [`BOUND`] from its mesh where part A can
/// touch it (an overhang or undercut).
pub fn mesh_scene(task: &Task) -> Result<MeshScene> {
    let invalid = |reason: String| HarnessError::Invalid {
        what: "scene from meshes",
        reason: format!("task {}: {reason}", task.name),
    };
    if task.contact.approach[2] > -1.0 + FLAT {
        return Err(invalid(format!(
            "the scene's robot moves along z: the approach must be -z, not {:?}",
            task.contact.approach
        )));
    }
    let (a, b) = (task.part_a.load()?, task.part_b.load()?);
    let omega_reach = task.omega.size_trans * 2f64.sqrt();
    // Only the part of A's face that can reach B's highest level carries spheres (plus a
    // millimetre, as the parametric scenes).
    let highest = b
        .vertices
        .iter()
        .map(|v| v.z)
        .fold(f64::NEG_INFINITY, f64::max);
    let top_radius = b
        .vertices
        .iter()
        .filter(|v| highest - v.z <= LEVEL)
        .map(|v| v.x.hypot(v.y))
        .fold(0.0, f64::max);
    let (face, wedges) = contact_face(&a, top_radius + omega_reach + 0.001).map_err(invalid)?;
    let region = face.reach + omega_reach;
    let top = (0..b.faces.len())
        .filter(|&i| b.normal(i).z > WALL && axis_distance(&b.triangle(i)) <= region)
        .flat_map(|i| b.triangle(i).map(|v| v.z))
        .fold(f64::NEG_INFINITY, f64::max);
    let polygons = up_facing_polygons(&b);
    let pieces = prisms(
        &polygons,
        b.vertices.iter().map(|v| v.z).fold(f64::INFINITY, f64::min),
    );
    let deviation = deviation(&b, &pieces, region);
    if deviation > BOUND {
        return Err(invalid(format!(
            "part B's convex pieces stray {:.1} µm from its mesh within {:.1} mm of the axis, more than the {:.0} µm bound: part B is not a height field along the approach there (an overhang or undercut part A could reach), which the exact decomposition needs; no scene is written rather than one whose clearance is wrong",
            deviation * 1e6,
            region * 1e3,
            BOUND * 1e6
        )));
    }
    Ok(MeshScene {
        face,
        wedges,
        pieces,
        top,
        deviation,
    })
}

/// How far a triangle comes to the axis across it (m): 0 where it spans the axis.
fn axis_distance(t: &[Point3<f64>; 3]) -> f64 {
    let flat = t.map(|v| [v.x, v.y]);
    let sides = (0..3).map(|k| {
        let (a, b) = (flat[k], flat[(k + 1) % 3]);
        a[0] * b[1] - a[1] * b[0]
    });
    if sides.clone().all(|s| s >= 0.0) || sides.clone().all(|s| s <= 0.0) {
        return 0.0;
    }
    (0..3)
        .map(|k| {
            let (a, b) = (flat[k], flat[(k + 1) % 3]);
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            let t = (-(a[0] * ex + a[1] * ey) / (ex * ex + ey * ey)).clamp(0.0, 1.0);
            (a[0] + t * ex).hypot(a[1] + t * ey)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The farthest distance of a polygon from the axis (m).
fn radius(v: &[[f64; 2]]) -> f64 {
    v.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max)
}

/// Part A's contact face (its lowest flat faces looking along the approach, at z = 0) and
/// wedges over its other faces looking along it. Spheres farther than `reach` from the axis are left out.
fn contact_face(a: &Mesh, reach: f64) -> std::result::Result<(Face, Vec<Hull>), String> {
    let tip = a.vertices.iter().map(|v| v.z).fold(f64::INFINITY, f64::min);
    if tip.abs() > TIP_AT_ORIGIN {
        return Err(format!(
            "part A's lowest point lies at z = {:.4} mm in its frame: the task frame's origin must be on part A's tip (move both meshes by the same offset)",
            tip * 1e3
        ));
    }
    let (mut flat, mut wedges) = (Vec::new(), Vec::new());
    for (i, f) in a.faces.iter().enumerate() {
        let n = a.normal(i);
        let corners = a.triangle(i);
        if n.z < -(1.0 - FLAT) && corners.iter().all(|v| (v.z - tip).abs() <= LEVEL) {
            flat.push(*f);
        } else if n.z < -WALL {
            // Level with the bed's sphere centres where it meets the face, as the
            // parametric chamfers are, so that a flat surface touches the bed alone.
            let z = |v: &Point3<f64>| {
                if v.z - tip <= LEVEL {
                    tip + SPHERE_RADIUS
                } else {
                    v.z
                }
            };
            wedges.push(
                corners
                    .iter()
                    .map(|v| [v.x, v.y, z(v)])
                    .chain(corners.iter().map(|v| [v.x, v.y, v.z + WEDGE_RISE]))
                    .collect(),
            );
        }
    }
    let mut loops = boundary_loops(&a.vertices, &flat);
    if loops.is_empty() {
        return Err("part A has no flat face looking along the approach at its tip".into());
    }
    loops.sort_by(|p, q| area(q).abs().total_cmp(&area(p).abs()));
    let outer = loops.remove(0);
    if loops.len() > 1 {
        return Err(format!(
            "part A's tip face has {} holes: a scene's contact face may have one bore",
            loops.len()
        ));
    }
    let face_area = area(&outer).abs() - loops.first().map_or(0.0, |l| area(l).abs());
    let face = Face {
        reach: radius(&outer).min(reach),
        outer: Outline::Loop(outer),
        chamfer: 0.0,
        inner: loops.pop().map(Outline::Loop),
        pitch: PITCH.max((face_area / BED_CELLS / (3f64.sqrt() / 2.0)).sqrt()),
        turned: false,
    };
    Ok((face, wedges))
}

/// The closed boundary loops of the triangles `faces` in the xy plane, each
/// counter-clockwise, each from its lowest vertex index: the same mesh gives the same
/// loops, point for point, and with them the same bed.
fn boundary_loops(vertices: &[Point3<f64>], faces: &[[u32; 3]]) -> Vec<Vec<[f64; 2]>> {
    let mut count: HashMap<(u32, u32), usize> = HashMap::new();
    for f in faces {
        for k in 0..3 {
            let (p, q) = (f[k], f[(k + 1) % 3]);
            *count.entry((p.min(q), p.max(q))).or_default() += 1;
        }
    }
    let mut next: BTreeMap<u32, u32> = BTreeMap::new();
    for f in faces {
        for k in 0..3 {
            let (p, q) = (f[k], f[(k + 1) % 3]);
            if count[&(p.min(q), p.max(q))] == 1 {
                next.insert(p, q);
            }
        }
    }
    let mut loops = Vec::new();
    while let Some((&start, _)) = next.first_key_value() {
        let mut ring = vec![start];
        let mut at = next.remove(&start);
        while let Some(v) = at.filter(|&v| v != start) {
            ring.push(v);
            at = next.remove(&v);
        }
        let mut points: Vec<[f64; 2]> = ring
            .iter()
            .map(|&i| [vertices[i as usize].x, vertices[i as usize].y])
            .collect();
        if points.len() >= 3 {
            if area(&points) < 0.0 {
                points.reverse();
            }
            loops.push(points);
        }
    }
    loops
}

/// Part B's up-facing triangles, grouped by plane and split into convex polygons (3-D
/// vertices, counter-clockwise seen from above).
fn up_facing_polygons(b: &Mesh) -> Vec<Vec<Point3<f64>>> {
    let mut planes: HashMap<[i64; 4], Vec<[u32; 3]>> = HashMap::new();
    for (i, f) in b.faces.iter().enumerate() {
        let n = b.normal(i);
        if n.z > WALL {
            let d = n.dot(&b.vertices[f[0] as usize].coords);
            let key = [n.x, n.y, n.z, d].map(|c| (c * 1e9).round() as i64);
            planes.entry(key).or_default().push(*f);
        }
    }
    let flat: Vec<Point2<f64>> = b.vertices.iter().map(|v| Point2::new(v.x, v.y)).collect();
    let mut keys: Vec<&[i64; 4]> = planes.keys().collect();
    keys.sort();
    keys.into_iter()
        .flat_map(|k| parry2d_f64::transformation::hertel_mehlhorn_idx(&flat, &planes[k]))
        .flat_map(|poly| {
            // Fans of at most MAX_CORNERS corners from the first: convex hulls of many nearly
            // coplanar side faces are where hull algorithms lose precision.
            let step = MAX_CORNERS - 2;
            (1..poly.len() - 1)
                .step_by(step)
                .map(|k| {
                    std::iter::once(poly[0])
                        .chain(poly[k..(k + step + 1).min(poly.len())].iter().copied())
                        .map(|i| b.vertices[i as usize])
                        .collect()
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Each polygon extruded down below `floor` (m): a prism mirrored about its mid-plane, its
/// half height the power of two that reaches `floor` from the highest polygon, so that a
/// flat top is at exactly `+half` in the piece's frame and lands on its height in MuJoCo
/// (see `scene::tile_half_height`).
fn prisms(polygons: &[Vec<Point3<f64>>], floor: f64) -> Vec<Piece> {
    let highest = polygons
        .iter()
        .flatten()
        .map(|v| v.z)
        .fold(f64::NEG_INFINITY, f64::max);
    let half = 2f64.powi(((highest - floor) / 2.0).log2().ceil() as i32);
    polygons
        .iter()
        .map(|poly| {
            let n = poly.len() as f64;
            let (cx, cy) = (
                poly.iter().map(|v| v.x).sum::<f64>() / n,
                poly.iter().map(|v| v.y).sum::<f64>() / n,
            );
            let z_ref = poly.iter().map(|v| v.z).fold(f64::NEG_INFINITY, f64::max);
            let zc = z_ref - half;
            let dz = |z: f64| if z == z_ref { half } else { z - zc };
            let vertices = [1.0, -1.0]
                .into_iter()
                .flat_map(|s| poly.iter().map(move |v| [v.x - cx, v.y - cy, s * dz(v.z)]))
                .collect();
            Piece::Hull {
                center: [cx, cy, zc],
                vertices,
            }
        })
        .collect()
}

/// How deep `x` lies inside `hull` (m; negative outside): its least distance to a face's
/// plane. Exact, where parry's projection from inside a polyhedron may give up.
fn depth(hull: &ConvexPolyhedron, x: &Point3<f64>) -> f64 {
    let (points, adjacent) = (hull.points(), hull.vertices_adj_to_face());
    hull.faces()
        .iter()
        .map(|f| {
            let on = points[adjacent[f.first_vertex_or_edge as usize] as usize];
            f.normal.dot(&(on - x))
        })
        .fold(f64::INFINITY, f64::min)
}

/// The largest distance between part B's mesh and `pieces` within `region` of the axis
/// (m): the mesh's surface (but its bottom) sampled and projected on the pieces (a point
/// inside a piece or outside them all strays), and each piece's top corners against the
/// mesh.
fn deviation(b: &Mesh, pieces: &[Piece], region: f64) -> f64 {
    let shapes: Vec<(Isometry3<f64>, SharedShape)> = pieces
        .iter()
        .filter_map(|p| match p {
            Piece::Hull { center, vertices } => {
                let points: Vec<Point3<f64>> = vertices.iter().map(|&v| Point3::from(v)).collect();
                ConvexPolyhedron::from_convex_hull(&points).map(|hull| {
                    (
                        Isometry3::translation(center[0], center[1], center[2]),
                        SharedShape::new(hull),
                    )
                })
            }
            _ => None,
        })
        .collect();
    let bottom = b.vertices.iter().map(|v| v.z).fold(f64::INFINITY, f64::min);
    let within = |p: &Point3<f64>| p.x.hypot(p.y) <= region;
    let faces: Vec<usize> = (0..b.faces.len())
        .filter(|&i| {
            let t = b.triangle(i);
            axis_distance(&t) <= region && !t.iter().all(|v| (v.z - bottom).abs() <= LEVEL)
        })
        .collect();
    let areas: Vec<f64> = faces
        .iter()
        .map(|&i| {
            let [p, q, r] = b.triangle(i);
            (q - p).cross(&(r - p)).norm() / 2.0
        })
        .collect();
    let total: f64 = areas.iter().sum();
    let mut rng = StdRng::seed_from_u64(0x5ce9e);
    let mut worst: f64 = 0.0;
    let identity = Isometry3::identity();
    for _ in 0..SAMPLES {
        let mut pick = rng.random::<f64>() * total;
        let k = areas
            .iter()
            .position(|&a| {
                pick -= a;
                pick <= 0.0
            })
            .unwrap_or(areas.len() - 1);
        let [p, q, r] = b.triangle(faces[k]);
        let (mut s, mut t) = (rng.random::<f64>(), rng.random::<f64>());
        if s + t > 1.0 {
            (s, t) = (1.0 - s, 1.0 - t);
        }
        let x = p + (q - p) * s + (r - p) * t;
        if !within(&x) {
            continue;
        }
        // Each nearby piece's signed depth from its faces' planes (exact where the nearest
        // point is inside a face, as on the mesh's surface; GJK's tolerance on pieces tens
        // of millimetres long is micrometres): inside one, by the least depth of those
        // holding it; outside them all, by the least distance.
        let depths: Vec<f64> = shapes
            .iter()
            .filter(|(pose, shape)| {
                shape
                    .compute_aabb(pose)
                    .loosened(1e-3)
                    .contains_local_point(&x)
            })
            .filter_map(|(pose, shape)| {
                Some(depth(shape.as_convex_polyhedron()?, &(pose.inverse() * x)))
            })
            .collect();
        let inside = depths
            .iter()
            .copied()
            .filter(|&d| d >= 0.0)
            .fold(f64::INFINITY, f64::min);
        let outside = depths.iter().map(|&d| -d).fold(f64::INFINITY, f64::min);
        worst = worst.max(if inside.is_finite() { inside } else { outside });
    }
    let mesh = parry3d_f64::shape::TriMesh::new(b.vertices.clone(), b.faces.clone());
    if let Ok(mesh) = mesh {
        for (pose, shape) in &shapes {
            if let Some(hull) = shape.as_convex_polyhedron() {
                let top = hull
                    .points()
                    .iter()
                    .map(|v| v.z)
                    .fold(f64::NEG_INFINITY, f64::max);
                for v in hull.points().iter().filter(|v| v.z >= top - 1e-12) {
                    let w = pose * v;
                    if within(&w) {
                        worst = worst.max(mesh.distance_to_point(&identity, &w, false));
                    }
                }
            }
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_face_gives_the_same_loops_every_time() {
        // A 24-gon fan about its centre (vertex 0): one boundary loop of 24 points. A loop
        // started at whichever vertex a hash map gave first came out rotated from call to
        // call (a new map, a new hasher seed), and with it the order of the bed's spheres.
        let n = 24;
        let vertices: Vec<Point3<f64>> = std::iter::once(Point3::origin())
            .chain((0..n).map(|k| {
                let t = std::f64::consts::TAU * f64::from(k) / f64::from(n);
                Point3::new(t.cos(), t.sin(), 0.0)
            }))
            .collect();
        let faces: Vec<[u32; 3]> = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
        let first = boundary_loops(&vertices, &faces);
        assert_eq!(first.len(), 1);
        assert_eq!(first[0].len(), n as usize);
        assert!(area(&first[0]) > 0.0, "counter-clockwise");
        for _ in 0..16 {
            assert_eq!(boundary_loops(&vertices, &faces), first);
        }
    }
}
