//! Triangle meshes read from STL files (binary or ASCII), with their SHA-256 and
//! per-triangle normals.

use std::path::{Path, PathBuf};

use nalgebra::{Point3, Vector3};
use sha2::{Digest, Sha256};

use crate::error::{MapError, Result};

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
}

impl Mesh {
    /// Reads an STL file; refuses missing, unreadable, empty or non-finite meshes.
    pub fn load(path: &Path) -> Result<Self> {
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
        let vertices: Vec<Point3<f64>> = stl
            .vertices
            .iter()
            .map(|v| Point3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2])))
            .collect();
        if vertices
            .iter()
            .any(|v| !v.coords.iter().all(|c| c.is_finite()))
        {
            return Err(err("a vertex has a NaN or infinite coordinate".into()));
        }
        let faces = stl
            .faces
            .iter()
            .map(|f| f.vertices.map(|i| i as u32))
            .collect();
        let sha256 = Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        Ok(Self {
            path: path.to_owned(),
            sha256,
            vertices,
            faces,
        })
    }

    /// A mesh from vertices and faces (for tests and generated geometry).
    pub fn from_parts(vertices: Vec<Point3<f64>>, faces: Vec<[u32; 3]>) -> Self {
        Self {
            path: PathBuf::from("<memory>"),
            sha256: String::new(),
            vertices,
            faces,
        }
    }

    /// The three corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Point3<f64>; 3] {
        self.faces[i].map(|v| self.vertices[v as usize])
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
}
