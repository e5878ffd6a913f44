//! The committed STL meshes of every task with a `[geometry]` table are byte for byte what
//! the generator makes of it now, and the task files name them.

use std::path::{Path, PathBuf};

use ftmap::Task;
use ftmap::mesh::Mesh;
use ftmap::task::cad::{self, Role};

const REGENERATE: &str = "cargo run --release -p ftmap-cli -- cad (or target/release/ftmap cad)";

fn models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../models_mjcf")
}

#[test]
fn committed_meshes_are_current() {
    let tasks = Task::all_with_geometry().expect("models_mjcf is readable");
    let names: Vec<&str> = tasks.iter().map(|t| t.name.as_str()).collect();
    for task in ["bearing_housing", "gear", "octagon", "peg_in_hole"] {
        assert!(
            names.contains(&task),
            "task {task} has no [geometry] table (found {names:?})"
        );
    }
    let mut stale = Vec::new();
    for task in &tasks {
        let dir = task.path.parent().expect("a task file lies in a folder");
        let geometry = task.geometry.as_ref().expect("a [geometry] table");
        for mesh in cad::meshes(geometry) {
            let path = dir.join(mesh.file);
            let want = cad::stl_bytes(&mesh.triangles);
            match std::fs::read(&path) {
                Ok(got) if got == want => {}
                Ok(got) => stale.push(format!(
                    "{} is stale ({} bytes, generated {})",
                    path.display(),
                    got.len(),
                    want.len()
                )),
                Err(e) => stale.push(format!("{} is missing: {e}", path.display())),
            }
        }
    }
    assert!(
        stale.is_empty(),
        "{}\nregenerate with `{REGENERATE}` and commit the files",
        stale.join("\n")
    );
}

#[test]
fn task_files_name_the_generated_meshes() {
    for task in Task::all_with_geometry().expect("models_mjcf is readable") {
        let dir = task.path.parent().expect("a task file lies in a folder");
        let geometry = task.geometry.as_ref().expect("a [geometry] table");
        for mesh in cad::meshes(geometry) {
            let named = match mesh.role {
                Role::A => &task.part_a.mesh,
                Role::B => &task.part_b.mesh,
            };
            assert_eq!(
                named,
                &dir.join(mesh.file),
                "task {}: part {:?}",
                task.name,
                mesh.role
            );
        }
    }
}

#[test]
fn every_task_loads_with_readable_meshes() {
    let mut names: Vec<String> = std::fs::read_dir(models())
        .expect("models_mjcf is readable")
        .flatten()
        .filter(|e| e.path().join("task.toml").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.len() >= 5, "tasks found: {names:?}");
    for name in names {
        let task =
            Task::load(&models().join(&name).join("task.toml")).expect("the task file loads");
        assert_eq!(task.name, name, "the task's name is its folder's");
        for part in [&task.part_a, &task.part_b] {
            let mesh = Mesh::load(&part.mesh).unwrap_or_else(|e| panic!("task {name}: {e}"));
            assert!(
                mesh.faces.len() > 10,
                "task {name}: {}",
                mesh.path.display()
            );
        }
    }
}
