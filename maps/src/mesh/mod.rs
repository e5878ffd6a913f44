//! Triangle meshes read from STL files (binary or ASCII) in metres, millimetres or inches,
//! checked for soundness ([`check`]), with their SHA-256 and per-triangle normals.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use nalgebra::{Point3, Vector3};
use sha2::{Digest, Sha256};

use crate::error::{MapError, Result};

pub mod check;

/// A triangle mesh in its part's own frame (m).
#[derive(Debug, Clone)]
pub struct Mesh {
    /// The file it was read from.
    pub path: PathBuf,
    /// Hex SHA-256 of the file's bytes.
    pub sha256: String,
    /// Vertex positions.
    pub vertices: Vec<Point3<f64>>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub faces: Vec<[u32; 3]>,
    /// Per triangle and edge `k` (corner `k + 1` to corner `k + 2`), the one triangle on
    /// its other side; [`NO_NEIGHBOUR`] on an open or non-manifold edge.
    pub across: Vec<[u32; 3]>,
    /// What [`check`] found wrong with the file that does not refuse it.
    pub warnings: Vec<check::Defect>,
}

impl Mesh {
    /// Reads an STL file in metres; see [`Mesh::load_scaled`].
    pub fn load(path: &Path) -> Result<Self> {
        Self::load_scaled(path, 1.0)
    }

    /// Reads an STL file whose coordinates are in units of `scale` metres (0.001: mm);
    /// refuses missing, unreadable, empty or non-finite meshes and those with a fatal
    /// [`check::Defect`] (naming each), keeps the others' defects as warnings and drops
    /// duplicate triangles. Vertices equal in the file are one vertex (0 and -0 too).
    pub fn load_scaled(path: &Path, scale: f64) -> Result<Self> {
        let err = |reason: String| MapError::Mesh {
            path: path.to_owned(),
            reason,
        };
        let bytes = std::fs::read(path).map_err(MapError::io(path))?;
        let stl = stl_io::read_stl(&mut std::io::Cursor::new(&bytes))
            .map_err(|e| err(format!("not a readable STL file: {e}")))?;
        if stl.faces.is_empty() {
            return Err(err("the mesh has no triangles".into()));
        }
        if stl
            .vertices
            .iter()
            .any(|v| !v.0.iter().all(|c| c.is_finite()))
        {
            return Err(err("a vertex has a NaN or infinite coordinate".into()));
        }
        // stl_io merges vertices by their bits: merge 0 with -0 as well.
        let mut index = HashMap::new();
        let mut vertices = Vec::new();
        let merged: Vec<u32> = stl
            .vertices
            .iter()
            .map(|v| {
                let key = v.0.map(|c| (c + 0.0).to_bits());
                *index.entry(key).or_insert_with(|| {
                    vertices.push(Point3::from(v.0.map(|c| f64::from(c) * scale)));
                    vertices.len() as u32 - 1
                })
            })
            .collect();
        let faces: Vec<[u32; 3]> = stl
            .faces
            .iter()
            .map(|f| f.vertices.map(|i| merged[i]))
            .collect();
        let (defects, faces) = check::check(&vertices, &faces);
        let (fatal, warnings): (Vec<_>, Vec<_>) = defects.into_iter().partition(|d| d.fatal);
        if !fatal.is_empty() {
            let list: Vec<String> = fatal.iter().map(ToString::to_string).collect();
            return Err(err(format!(
                "{} triangles, refused: {}",
                stl.faces.len(),
                list.join("; ")
            )));
        }
        let sha256 = Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        Ok(Self {
            path: path.to_owned(),
            sha256,
            across: across(&faces),
            vertices,
            faces,
            warnings,
        })
    }

    /// A mesh from vertices and faces (for tests and generated geometry).
    pub fn from_parts(vertices: Vec<Point3<f64>>, faces: Vec<[u32; 3]>) -> Self {
        Self {
            path: PathBuf::from("<memory>"),
            sha256: String::new(),
            across: across(&faces),
            vertices,
            faces,
            warnings: Vec::new(),
        }
    }

    /// The closed box from `lo` to `hi` (m), its triangles counter-clockwise seen from
    /// outside (for tests and generated geometry).
    pub fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Self {
        let vertices = (0..8)
            .map(|k| {
                let pick = |c: usize| if k >> c & 1 == 1 { hi[c] } else { lo[c] };
                Point3::new(pick(0), pick(1), pick(2))
            })
            .collect();
        let quads: [[u32; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let faces = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Self::from_parts(vertices, faces)
    }

    /// The three corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Point3<f64>; 3] {
        self.faces[i].map(|v| self.vertices[v as usize])
    }

    /// Whether triangle `i` covers no area ([`check::sliver`]): collinear corners that close
    /// a T-junction.
    pub fn is_sliver(&self, i: usize) -> bool {
        check::sliver(self.triangle(i))
    }

    /// Unit outward normal of triangle `i` from its winding (zero for degenerate ones).
    pub fn normal(&self, i: usize) -> Vector3<f64> {
        let [a, b, c] = self.triangle(i);
        (b - a)
            .cross(&(c - a))
            .try_normalize(0.0)
            .unwrap_or_else(Vector3::zeros)
    }
}

/// [`Mesh::across`]'s value on an edge without exactly one triangle on its other side.
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// Per triangle of `faces` and edge `k` (corner `k + 1` to corner `k + 2`), the one triangle
/// that runs the edge the other way ([`NO_NEIGHBOUR`] where none or several do).
fn across(faces: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let edge = |f: &[u32; 3], k: usize| (f[(k + 1) % 3], f[(k + 2) % 3]);
    let mut runs: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (t, f) in faces.iter().enumerate() {
        for k in 0..3 {
            runs.entry(edge(f, k)).or_default().push(t as u32);
        }
    }
    faces
        .iter()
        .map(|f| {
            std::array::from_fn(|k| {
                let (p, q) = edge(f, k);
                match (runs.get(&(q, p)).map(Vec::as_slice), runs[&(p, q)].len()) {
                    (Some(&[t]), 1) => t,
                    _ => NO_NEIGHBOUR,
                }
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_and_garbage_files_are_named_in_the_error() {
        let e = Mesh::load(Path::new("/nonexistent/peg.stl")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/peg.stl"), "{e}");
        let dir = std::env::temp_dir().join(format!("ftmap-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.stl");
        std::fs::write(&bad, [1u8; 90]).unwrap();
        let e = Mesh::load(&bad).unwrap_err();
        assert!(matches!(e, MapError::Mesh { .. }), "{e}");
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn each_edge_of_a_closed_mesh_has_the_triangle_that_shares_it_across() {
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let faces = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        let m = Mesh::from_parts(v.iter().map(|&c| Point3::from(c)).collect(), faces.clone());
        for (t, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let (p, q) = (f[(k + 1) % 3], f[(k + 2) % 3]);
                let n = m.across[t][k] as usize;
                assert_ne!(n, t);
                let g = faces[n];
                assert!((0..3).any(|j| (g[j], g[(j + 1) % 3]) == (q, p)), "{t} {k}");
            }
        }
        // One triangle alone: every edge open.
        let open = Mesh::from_parts(
            v[..3].iter().map(|&c| Point3::from(c)).collect(),
            vec![[0, 1, 2]],
        );
        assert_eq!(open.across, vec![[NO_NEIGHBOUR; 3]]);
    }
}
