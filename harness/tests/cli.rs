//! What a user sees from the `harness` binary: scene check, clear errors.

#[path = "../../tests/prerequisite.rs"]
mod prerequisite;

use std::process::Command;

fn harness() -> Command {
    Command::new(env!("CARGO_BIN_EXE_harness"))
}

#[test]
fn the_committed_scenes_are_current() {
    let out = harness().args(["scene", "--check"]).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn an_fmu_refusal_says_what_the_fmu_logged() {
    // A map file that is no FT-Map: the FMU refuses it at initialisation and logs why; the
    // harness's error carries that message, not only the FMI status.
    let dir = std::env::temp_dir().join(format!("harness-badmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let map = dir.join("garbage.ftmap");
    std::fs::write(&map, b"this is not a map").unwrap();
    let out = harness()
        .args(["trials", "--task", "peg_in_hole", "--trials", "1", "--map"])
        .arg(&map)
        .arg("--out")
        .arg(dir.join("run"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("fmi2ExitInitializationMode")
            && err.contains("garbage.ftmap")
            && err.contains("not an FT-Map file"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn counts_and_sizes_out_of_range_are_refused_by_flag() {
    for (args, flag) in [
        (
            &["trials", "--task", "peg_in_hole", "--trials", "0"][..],
            "--trials",
        ),
        (&["sweep", "--task", "peg_in_hole", "--grid", "0"], "--grid"),
        (
            &["scan", "--task", "peg_in_hole", "--out", "x", "--step=-0.1"],
            "--step",
        ),
        (&["boundary", "--directions", "0"], "--directions"),
        (
            &["trials", "--task", "peg_in_hole", "--max-sim-time", "nan"],
            "--max-sim-time",
        ),
    ] {
        let out = harness().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} ran");
        assert!(err.contains(&format!("for '{flag}")), "{args:?}: {err}");
    }
}

#[test]
fn a_missing_fmu_names_cargo_xtask_fmu() {
    let dir = std::env::temp_dir().join(format!("harness-nofmu-{}", std::process::id()));
    let out = harness()
        .args([
            "trials",
            "--task",
            "peg_in_hole",
            "--trials",
            "1",
            "--fmu",
            "/nonexistent/FtFusion.fmu",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("/nonexistent/FtFusion.fmu") && err.contains("cargo xtask fmu"),
        "{err}"
    );
}

#[test]
fn another_mujoco_library_names_the_setup_script() {
    // Debian's MuJoCo 2.2.2 preloaded in front of 3.17.0: the version check must refuse it.
    let debian = "/usr/lib/x86_64-linux-gnu/libmujoco.so.2.2.2";
    if !std::path::Path::new(debian).is_file() {
        prerequisite::missing(
            &format!("{debian} not installed"),
            "scripts/setup.sh installs libmujoco-dev",
        );
        return;
    }
    let out = harness()
        .args(["scene", "--check"])
        .env("LD_PRELOAD", debian)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("bash scripts/setup.sh") && err.contains("222"),
        "{err}"
    );
}

#[test]
fn a_missing_mujoco_library_names_the_setup_script() {
    let out = harness()
        .args(["scene", "--check"])
        .env("FTFUSION_MUJOCO_DIR", "/nonexistent")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("/nonexistent/libmujoco.so.3.17.0") && err.contains("bash scripts/setup.sh"),
        "{err}"
    );
}

#[test]
fn the_launcher_finds_the_library_in_another_folder() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../.deps/mujoco");
    let out = harness()
        .args(["scene", "--check"])
        .env("FTFUSION_MUJOCO_DIR", &dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn vision_on_a_task_without_a_camera_or_with_the_spiral_is_refused_by_name() {
    let dir = std::env::temp_dir().join(format!("harness-novision-{}", std::process::id()));
    let out = harness()
        .args([
            "trials",
            "--task",
            "peg_in_hole",
            "--trials",
            "1",
            "--vision",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success()
            && err.contains("peg_in_hole has no camera")
            && err.contains("[camera]"),
        "{err}"
    );
    let out = harness()
        .args([
            "trials",
            "--task",
            "bearing_housing",
            "--trials",
            "1",
            "--vision",
            "--strategy",
            "spiral",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--vision needs --strategy pf"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compare_runs_tabulates_two_campaigns_and_names_a_bad_file() {
    let dir = std::env::temp_dir().join(format!("harness-compare-{}", std::process::id()));
    let head = "trial,offset_x_m,offset_y_m,contacts,measurements,success,final_error_m,y_std_first_contact_m,images_missed,wall_s,sim_time_s\n";
    let runs = [
        ("a", [(1, "0.000002"), (2, "0.000004"), (3, "")]),
        ("b", [(3, "0.00006"), (2, "0.00008"), (6, "")]),
    ];
    for (name, rows) in runs {
        std::fs::create_dir_all(dir.join(name)).unwrap();
        let body: String = rows
            .iter()
            .enumerate()
            .map(|(i, (c, y))| {
                format!(
                    "{i},0.00{i},-0.001,{c},{},true,0.00003,{y},0,0.1,0.3\n",
                    c - 1
                )
            })
            .collect();
        std::fs::write(dir.join(name).join("trials.csv"), format!("{head}{body}")).unwrap();
    }
    let out = harness()
        .arg("compare-runs")
        .arg(dir.join("a"))
        .arg(dir.join("b"))
        .arg("--plot")
        .arg(dir.join("c.png"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for want in [
        "2.00 / 2 / 3 / 3",
        "3.67 / 3 / 6 / 6",
        "1.00 / 1 / 2 / 2",
        "0.0030 mm",
        "0.0700 mm",
        "a needed fewer contacts in 2, as many in 1, more in 0 trials",
    ] {
        assert!(text.contains(want), "no {want:?} in:\n{text}");
    }
    assert!(dir.join("c.png").is_file());
    std::fs::write(
        dir.join("b").join("trials.csv"),
        format!("{head}0,0.0,0.0,three,2,true,0,,0,0,0\n"),
    )
    .unwrap();
    let out = harness()
        .arg("compare-runs")
        .arg(dir.join("a"))
        .arg(dir.join("b"))
        .arg("--plot")
        .arg(dir.join("c.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("b/trials.csv"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
