//! The FMU's shared library is the estimator and the map lookup, nothing else: its normal
//! dependency graph holds no command-line, plotting, progress-bar or GPU crate.

use std::process::Command;

/// Crates that belong to the tools, never to `FtFusion.fmu`.
const FORBIDDEN: [&str; 8] = [
    "clap",
    "plotters",
    "font-kit",
    "freetype-sys",
    "indicatif",
    "anyhow",
    "wgpu",
    "mujoco-rs",
];

/// The package names in `cargo tree -p <package> -e normal`.
fn normal_dependencies(package: &str) -> Vec<String> {
    let out = Command::new(env!("CARGO"))
        .args([
            "tree",
            "--offline",
            "-p",
            package,
            "-e",
            "normal",
            "--prefix",
            "none",
        ])
        .args([
            "--manifest-path",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../Cargo.toml"),
        ])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_owned))
        .collect()
}

#[test]
fn the_fmu_links_no_tool_crates() {
    let deps = normal_dependencies("ftfusion");
    assert!(
        deps.iter().any(|d| d == "ftmap") && deps.iter().any(|d| d == "fmi-sys"),
        "the graph was read: {deps:?}"
    );
    let found: Vec<&String> = deps
        .iter()
        .filter(|d| FORBIDDEN.contains(&d.as_str()))
        .collect();
    assert!(
        found.is_empty(),
        "FtFusion.fmu's dependencies include {found:?}"
    );
}

#[test]
fn the_cli_does_link_them() {
    // The check above can fail: the same query on the map tool finds its CLI crates.
    let deps = normal_dependencies("ftmap-cli");
    for d in ["clap", "plotters", "indicatif", "anyhow", "wgpu"] {
        assert!(
            deps.iter().any(|x| x == d),
            "ftmap-cli without {d}: {deps:?}"
        );
    }
}
