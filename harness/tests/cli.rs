//! What a user sees from the `harness` binary: scene check, clear errors.

use std::process::Command;

fn harness() -> Command {
    Command::new(env!("CARGO_BIN_EXE_harness"))
}

#[test]
fn the_committed_scenes_are_current() {
    let out = harness().args(["scene", "--check"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn a_missing_fmu_names_cargo_xtask_fmu() {
    let dir = std::env::temp_dir().join(format!("harness-nofmu-{}", std::process::id()));
    let out = harness()
        .args(["trials", "--task", "peg_in_hole", "--trials", "1", "--fmu", "/nonexistent/FtFusion.fmu", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("/nonexistent/FtFusion.fmu") && err.contains("cargo xtask fmu"), "{err}");
}

#[test]
fn another_mujoco_library_names_the_setup_script() {
    // Debian's MuJoCo 2.2.2 preloaded in front of 3.17.0: the version check must refuse it.
    let debian = "/usr/lib/x86_64-linux-gnu/libmujoco.so.2.2.2";
    if !std::path::Path::new(debian).is_file() {
        eprintln!("skipped: {debian} not installed (scripts/setup.sh installs libmujoco-dev)");
        return;
    }
    let out = harness().args(["scene", "--check"]).env("LD_PRELOAD", debian).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("bash scripts/setup.sh") && err.contains("222"), "{err}");
}

#[test]
fn a_missing_mujoco_library_names_the_setup_script() {
    let out = harness().args(["scene", "--check"]).env("FTFUSION_MUJOCO_DIR", "/nonexistent").output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("/nonexistent/libmujoco.so.3.17.0") && err.contains("bash scripts/setup.sh"), "{err}");
}

#[test]
fn the_launcher_finds_the_library_in_another_folder() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../.deps/mujoco");
    let out = harness().args(["scene", "--check"]).env("FTFUSION_MUJOCO_DIR", &dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn vision_on_a_task_without_a_camera_or_with_the_spiral_is_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("harness-novision-{}", std::process::id()));
    let out = harness().args(["trials", "--task", "peg_in_hole", "--trials", "1", "--vision", "--out"]).arg(&dir).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("peg_in_hole has no camera") && err.contains("[camera]"), "{err}");
    let out = harness().args(["trials", "--task", "bearing_housing", "--trials", "1", "--vision", "--strategy", "spiral", "--out"]).arg(&dir).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--vision needs --strategy pf"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
