//! Mesh validation on real STL files: every committed part passes; a hole in the surface,
//! a flipped triangle, a degenerate triangle and millimetres read as metres are each
//! reported by name, with the file and the triangles; parry's half-edge topology of the
//! same meshes (a second method) agrees on what is closed and what is flipped.

use std::path::{Path, PathBuf};

use ftmap::Task;
use ftmap::mesh::Mesh;
use ftmap::task::cad::{self, Role};

/// The triangles of the peg_in_hole task's peg, as generated from its geometry.
fn peg() -> Vec<[[f32; 3]; 3]> {
    let task = Task::find("peg_in_hole").expect("task");
    cad::meshes(task.geometry().expect("geometry"))
        .into_iter()
        .find(|m| m.role == Role::A)
        .expect("part A")
        .triangles
}

fn write(dir: &Path, name: &str, triangles: &[[[f32; 3]; 3]]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, cad::stl_bytes(triangles)).expect("write");
    path
}

#[test]
fn every_committed_part_is_sound() {
    for name in Task::names() {
        let task = Task::find(&name).expect("task");
        for part in [&task.part_a, &task.part_b] {
            let mesh = part.load().unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(mesh.warnings.is_empty(), "{name}: {:?}", mesh.warnings);
        }
    }
}

#[test]
fn each_defect_is_reported_by_name_with_its_file_and_triangles() {
    let dir = std::env::temp_dir().join(format!("ftmap-mesh-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let sound = peg();
    let refused = |path: &Path, scale: f64| {
        Mesh::load_scaled(path, scale)
            .expect_err("refused")
            .to_string()
    };

    let mut holed = sound.clone();
    holed.remove(7);
    let e = refused(&write(&dir, "holed.stl", &holed), 1.0);
    assert!(e.contains("holed.stl") && e.contains("3 open edges"), "{e}");

    let mut flipped = sound.clone();
    flipped[7].swap(1, 2);
    let e = refused(&write(&dir, "flipped.stl", &flipped), 1.0);
    assert!(
        e.contains("flipped.stl") && e.contains("flipped triangles"),
        "{e}"
    );

    // A triangle with a repeated corner covers nothing: a warning, the mesh is kept.
    let mut degenerate = sound.clone();
    degenerate.push([sound[0][0], sound[0][0], sound[0][1]]);
    let path = write(&dir, "degenerate.stl", &degenerate);
    let mesh = Mesh::load(&path).expect("kept");
    let warnings: Vec<String> = mesh.warnings.iter().map(ToString::to_string).collect();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let want = format!(
        "1 degenerate triangles (no area) (triangles {})",
        sound.len()
    );
    assert!(warnings[0].starts_with(&want), "{warnings:?}");

    // The peg written in millimetres and read as metres: 40 m long.
    let mm: Vec<[[f32; 3]; 3]> = sound
        .iter()
        .map(|t| t.map(|v| v.map(|c| c * 1000.0)))
        .collect();
    let path = write(&dir, "peg_mm.stl", &mm);
    let e = refused(&path, 1.0);
    assert!(
        e.contains("peg_mm.stl") && e.contains("millimetres read as metres"),
        "{e}"
    );
    let scaled = Mesh::load_scaled(&path, 0.001).expect("read in millimetres");
    let metres = Mesh::load(&write(&dir, "peg.stl", &sound)).expect("peg");
    let worst = scaled
        .vertices
        .iter()
        .zip(&metres.vertices)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "mm mesh scaled differs by {worst} m");
    std::fs::remove_dir_all(dir).ok();
}

/// Open half-edges of parry's half-edge topology of `mesh`, or parry's refusal.
fn parry_open_edges(mesh: &Mesh) -> Result<usize, String> {
    use parry3d_f64::shape::{TriMesh, TriMeshFlags};
    // `with_flags` drops a topology error: set the flag afterwards to see it.
    let mut shape =
        TriMesh::new(mesh.vertices.clone(), mesh.faces.clone()).map_err(|e| e.to_string())?;
    shape
        .set_flags(TriMeshFlags::HALF_EDGE_TOPOLOGY)
        .map_err(|e| e.to_string())?;
    let topology = shape.topology().ok_or("no topology")?;
    Ok(topology
        .half_edges
        .iter()
        .filter(|h| h.twin == u32::MAX)
        .count())
}

#[test]
fn parry_s_half_edge_topology_agrees_with_the_check() {
    let sound = peg();
    let mesh = |triangles: &[[[f32; 3]; 3]]| {
        let v: Vec<nalgebra::Point3<f64>> = triangles
            .iter()
            .flatten()
            .map(|c| nalgebra::Point3::from(c.map(f64::from)))
            .collect();
        // Corners merged as the loader does, by their bits.
        let mut index = std::collections::HashMap::new();
        let mut vertices = Vec::new();
        let faces: Vec<[u32; 3]> = v
            .chunks(3)
            .map(|t| {
                [0, 1, 2].map(|k| {
                    let key = t[k].coords.map(f64::to_bits);
                    *index.entry(key).or_insert_with(|| {
                        vertices.push(t[k]);
                        vertices.len() as u32 - 1
                    })
                })
            })
            .collect();
        Mesh::from_parts(vertices, faces)
    };
    // Sound: parry builds a closed topology; the check finds nothing.
    let m = mesh(&sound);
    assert_eq!(parry_open_edges(&m), Ok(0));
    assert!(
        ftmap::mesh::check::check(&m.vertices, &m.faces)
            .0
            .is_empty()
    );
    // A hole: parry's open half-edges are the check's open edges.
    let mut holed = sound.clone();
    holed.remove(7);
    let m = mesh(&holed);
    let (defects, _) = ftmap::mesh::check::check(&m.vertices, &m.faces);
    assert_eq!(parry_open_edges(&m), Ok(defects[0].count));
    // A flipped triangle: parry refuses the orientation, the check names it.
    let mut flipped = sound;
    flipped[7].swap(1, 2);
    let m = mesh(&flipped);
    let e = parry_open_edges(&m).expect_err("parry refuses");
    assert!(e.contains("orientation"), "{e}");
    let (defects, _) = ftmap::mesh::check::check(&m.vertices, &m.faces);
    assert_eq!(defects[0].kind, ftmap::mesh::check::DefectKind::Flipped);
}
