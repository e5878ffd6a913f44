//! Developer tasks of the ftfusion workspace, run as `cargo xtask <task>`:
//! - `fmu`: builds `target/fmu/FtFusion.fmu` (release cdylib linked against glibc 2.17 with
//!   `cargo zigbuild`, modelDescription.xml, the default `peg_in_hole` map in resources/,
//!   documentation/index.html);
//! - `bench-filter`: the filter benchmark (Rust) next to the same update in NumPy;
//! - `fuzz --time S`: each target of `fmu/tests/fuzz.rs` for S seconds on fresh seeds.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use model_description::{Causality, Start, VARIABLES};

/// The task whose map the FMU carries by default.
const DEFAULT_TASK: &str = "peg_in_hole";

/// The FMU's Rust target, the host's (no other rustup target needed) ...
const TRIPLE: &str = "x86_64-unknown-linux-gnu";
/// ... linked by zig against the symbol versions of this glibc, the newest the binary may
/// need (manylinux2014: RHEL/CentOS 7, Rocky 8 and Ubuntu 20.04 load it). `cargo zigbuild`
/// takes it as a suffix of the target: `x86_64-unknown-linux-gnu.2.17`.
const GLIBC: &str = "2.17";

/// The pinned cargo-zigbuild that `scripts/setup.sh` installs.
const ZIGBUILD: &str = "cargo-zigbuild 0.24.1";

/// The shared library's exports as a linker-script VERSION command: the `fmi2*` functions
/// and nothing else. zig keeps only the last `--version-script` it is given, which is
/// `fmu/exports.map` (hiding `fmi-sys`'s `callback_log`), not rustc's export list, so
/// without this every Rust symbol would be exported; a VERSION command in a `-T` script
/// is merged with that version script.
const EXPORTS: &str = "VERSION {\n  {\n    global:\n      fmi2*;\n    local:\n      *;\n  };\n}\n";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("fmu") => fmu(),
        Some("bench-filter") => bench(&args[1..]),
        Some("fuzz") => fuzz(&args[1..]),
        _ => {
            eprintln!(
                "usage: cargo xtask fmu | cargo xtask bench-filter [--particles N] [--iterations K] | cargo xtask fuzz [--time SECONDS]"
            );
            bail!("unknown or missing task")
        }
    }
}

/// Runs each fuzz target (`fmu/tests/fuzz.rs`) for `--time` seconds (default 600) on fresh
/// seeds, one after the other; fails naming the target and seed of a broken case.
fn fuzz(args: &[String]) -> Result<()> {
    let seconds: u64 = match args {
        [] => 600,
        [flag, s] if flag == "--time" => s
            .parse()
            .ok()
            .filter(|&s| s > 0)
            .with_context(|| format!("--time {s}: a whole number of seconds > 0"))?,
        _ => bail!("usage: cargo xtask fuzz [--time SECONDS]"),
    };
    println!("xtask fuzz: each target for {seconds} s");
    run(cargo()
        .args([
            "test",
            "--release",
            "-p",
            "ftfusion",
            "--test",
            "fuzz",
            "--",
        ])
        .args(["--nocapture", "--test-threads", "1"])
        .env("FUZZ_SECONDS", seconds.to_string()))
}

/// The workspace root (the parent of this crate's folder).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap_or(Path::new("."))
        .to_owned()
}

/// Runs a command in the workspace root, failing on a non-zero exit.
fn run(cmd: &mut Command) -> Result<()> {
    let status = cmd
        .current_dir(root())
        .status()
        .with_context(|| format!("starting {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed: {status}");
    }
    Ok(())
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// Builds the FMU archive.
fn fmu() -> Result<()> {
    let root = root();
    let target = root.join("target");
    let so = build_library(&target)?;
    // The line tables of the release profile are for developers: strip them from the FMU.
    let stripped = target.join("fmu/FtFusion.so");
    std::fs::create_dir_all(target.join("fmu"))?;
    std::fs::copy(&so, &stripped).with_context(|| format!("copying {}", so.display()))?;
    if Command::new("strip")
        .arg("--strip-debug")
        .arg(&stripped)
        .status()
        .map(|s| !s.success())
        .unwrap_or(true)
    {
        println!(
            "xtask fmu: `strip` unavailable or failed: the binary keeps its debug line tables"
        );
    }
    let binary =
        std::fs::read(&stripped).with_context(|| format!("reading {}", stripped.display()))?;
    let map = default_map(&target.join("maps"))?;
    let map_bytes = std::fs::read(&map).with_context(|| format!("reading {}", map.display()))?;

    let out = target.join("fmu/FtFusion.fmu");
    std::fs::create_dir_all(out.parent().unwrap_or(&target))?;
    let partial = out.with_extension("fmu.partial");
    let file = std::fs::File::create(&partial)
        .with_context(|| format!("creating {}", partial.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    let (xml, doc) = (model_description::xml(), documentation());
    let entries: [(&str, &[u8]); 4] = [
        ("modelDescription.xml", xml.as_bytes()),
        ("binaries/linux64/FtFusion.so", &binary),
        ("resources/peg_in_hole.ftmap", &map_bytes),
        ("documentation/index.html", doc.as_bytes()),
    ];
    for (name, bytes) in entries {
        zip.start_file(name, opts)
            .with_context(|| format!("adding {name}"))?;
        zip.write_all(bytes)
            .with_context(|| format!("writing {name}"))?;
    }
    zip.finish().context("finishing the archive")?;
    std::fs::rename(&partial, &out)?;
    println!(
        "xtask fmu: wrote {} (GUID {})",
        out.display(),
        model_description::guid()
    );
    Ok(())
}

/// Builds the FMU's shared library for [`TRIPLE`] and [`GLIBC`] with `cargo zigbuild`
/// (`cargo rustc` with zig as the linker, so that the export script reaches only the
/// cdylib's link) and returns its path. No fallback to the host's linker: that binary would
/// need the build machine's glibc.
fn build_library(target: &Path) -> Result<PathBuf> {
    let version = Command::new("cargo-zigbuild").arg("--version").output();
    match version {
        Ok(out) if out.status.success() => {
            let found = String::from_utf8_lossy(&out.stdout).trim().to_owned();
            if found != ZIGBUILD {
                println!("xtask fmu: found {found}, scripts/setup.sh installs {ZIGBUILD}");
            }
        }
        _ => bail!(
            "cargo-zigbuild is not installed: run `bash scripts/setup.sh` (it installs \
             {ZIGBUILD} and zig from the PyPI package ziglang, which link the FMU against \
             glibc 2.17 so that it loads on older distributions)"
        ),
    }
    let exports = target.join("fmu/fmi2-exports.ld");
    std::fs::create_dir_all(target.join("fmu"))?;
    if std::fs::read_to_string(&exports).ok().as_deref() != Some(EXPORTS) {
        std::fs::write(&exports, EXPORTS)
            .with_context(|| format!("writing {}", exports.display()))?;
    }
    let zig_target = format!("{TRIPLE}.{GLIBC}");
    println!("xtask fmu: building the FtFusion shared library (release, {zig_target})");
    let mut cmd = Command::new("cargo-zigbuild");
    cmd.args([
        "rustc",
        "--release",
        "-p",
        "ftfusion",
        "--lib",
        "--crate-type",
        "cdylib",
    ])
    .args(["--target", &zig_target, "--"])
    .arg(format!("-Clink-arg=-Wl,-T,{}", exports.display()));
    run(&mut cmd).context(
        "cargo zigbuild failed (if it cannot find zig, run `bash scripts/setup.sh`: it \
         installs the PyPI package ziglang)",
    )?;
    Ok(target.join(TRIPLE).join("release/libftfusion.so"))
}

/// The default task's map, computed with the CPU backend and cached in `cache` under the
/// hash of the task file and its meshes.
fn default_map(cache: &Path) -> Result<PathBuf> {
    let task =
        ftmap::Task::find(DEFAULT_TASK).with_context(|| format!("loading task {DEFAULT_TASK}"))?;
    let t0 = std::time::Instant::now();
    let (path, computed) = ftmap::generate::cached(&task, cache)
        .with_context(|| format!("computing the {DEFAULT_TASK} map"))?;
    let how = if computed {
        format!(
            "computed in {:.1} s (CPU backend)",
            t0.elapsed().as_secs_f64()
        )
    } else {
        "cached".to_owned()
    };
    println!("xtask fmu: map {} ({how})", path.display());
    Ok(path)
}

/// Escapes text for HTML.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// documentation/index.html: what the FMU does, its variables (from the table), usage and
/// an example.
fn documentation() -> String {
    let mut rows = String::new();
    for v in VARIABLES {
        let start = match v.start {
            Start::None => String::new(),
            Start::Real(x) => format!("{x}"),
            Start::Integer(x) => format!("{x}"),
            Start::Boolean(x) => format!("{x}"),
            Start::String(x) => x.to_owned(),
        };
        let range = match (v.min, v.max) {
            (None, None) => String::new(),
            (a, b) => format!(
                "[{}, {}]",
                a.map_or("-inf".into(), |x| format!("{x}")),
                b.map_or("inf".into(), |x| format!("{x}"))
            ),
        };
        rows.push_str(&format!(
            "<tr><td><code>{}</code></td><td>{}</td><td>{:?}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            v.name,
            v.vr,
            v.causality,
            v.ty,
            esc(&start),
            v.unit,
            range,
            esc(v.description)
        ));
    }
    let params: Vec<&str> = VARIABLES
        .iter()
        .filter(|v| v.causality == Causality::Parameter)
        .map(|v| v.name)
        .collect();
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>FtFusion.fmu</title>
<style>body{{font-family:sans-serif;max-width:70em;margin:auto}}td,th{{border:1px solid #ccc;padding:2px 6px}}table{{border-collapse:collapse}}</style>
</head><body>
<h1>FtFusion.fmu</h1>
<p>An FMI 2.0 Co-Simulation FMU (GUID <code>{guid}</code>) holding a condensation particle filter that
estimates the unknown relative pose between a gripped part and its mating part from contact wrenches and a
Force Torque Map (FT-Map), after "Multi Sensor Fusion in Robot Assembly Using Particle Filters", section IV.</p>
<h2>How it works</h2>
<ul>
<li>At <code>fmi2ExitInitializationMode</code> the FMU loads the FT-Map named by <code>map</code> (a file in the
FMU's <code>resources/</code> folder or an absolute path; default: <code>peg_in_hole.ftmap</code>, computed from the
CAD meshes of the peg-in-hole task) and spreads <code>particles</code> uniformly over the map's uncertain DOFs.</li>
<li>Each time the Boolean input <code>contact</code> rises, the <code>fmi2DoStep</code> that sees it takes one
measurement: the wrench inputs (sensor frame, torque about the sensor origin) and the TCP pose (task frame
relative to the nominal goal). It runs <code>iterations</code> filter iterations (weight by Eq. 3 with
<code>sigma_force</code>, <code>sigma_torque</code>, <code>sigma_depth</code>; normalise; systematic resampling
when the effective sample size falls to N/2; jitter of <code>jitter</code> grid intervals).</li>
<li>A particle's map coordinate for an <code>object.*</code> DOF is its object pose minus the TCP pose
(<code>object.z</code> excepted: <code>tcp.z</code> at the contact is the measured contact height, compared with
the map's depth channel when <code>sigma_depth</code> &gt; 0); <code>grip.*</code> DOFs do not move with the TCP.
So commanding <code>tcp := object</code> aligns the parts.</li>
<li>Outputs: the estimate (weighted mode of the dominant particle cluster), its spread (<code>*_std</code>),
<code>confidence</code> (weight within <code>confidence_radius</code>), <code>converged</code>
(confidence &gt; <code>threshold</code>), <code>ess</code>, <code>measurements</code>, <code>clusters</code>.
DOFs the map does not have stay 0.</li>
<li>NaN or infinite inputs: the measurement is skipped with fmi2Warning. Parameters out of range, a missing or
corrupt map: fmi2Error at initialization naming the problem. Calls in the wrong state: fmi2Error, the
instance stays usable. FMU states can be saved, restored and serialized; a restored run replays bit for bit.</li>
</ul>
<h2>Parameters</h2><p>{params}</p>
<h2>Variables</h2>
<table><tr><th>name</th><th>value reference</th><th>causality</th><th>type</th><th>start</th><th>unit</th><th>range</th><th>description</th></tr>
{rows}</table>
<h2>Example (Python, FMPy)</h2>
<pre>
import numpy as np
from fmpy import simulate_fmu

# one contact at t = 1 s: the peg rests on the rim, the torque says where the hole is
rows = [(0.0, 0, 0, 0, 0, 0, 0, 0.0, False),
        (1.0, 0, 0, 50, 0.12, -0.08, 0, 0.01, True),
        (2.0, 0, 0, 50, 0.12, -0.08, 0, 0.01, False)]
dtype = [('time', float), ('wrench.fx', float), ('wrench.fy', float), ('wrench.fz', float),
         ('wrench.tx', float), ('wrench.ty', float), ('wrench.tz', float), ('tcp.z', float), ('contact', bool)]
result = simulate_fmu('FtFusion.fmu', stop_time=3.0, step_size=0.1, input=np.array(rows, dtype=dtype),
                      start_values={{'particles': 4000, 'seed': 1}},
                      output=['object.x', 'object.y', 'confidence', 'converged'])
print(result[-1])
</pre>
<p>Loop of Algorithm 1 in a system simulation: move into contact, set the wrench and the TCP pose, raise
<code>contact</code>, step, read <code>object.x</code>/<code>object.y</code>, command the TCP there, lower
<code>contact</code>, repeat until <code>converged</code>.</p>
</body></html>
"#,
        guid = model_description::guid(),
        params = params
            .iter()
            .map(|p| format!("<code>{p}</code>"))
            .collect::<Vec<_>>()
            .join(", "),
    )
}

/// The filter benchmark: Rust (release) and NumPy on the same sizes, and the ratio.
fn bench(args: &[String]) -> Result<()> {
    let bench = ["bench", "-p", "ftfusion", "--bench", "filter"];
    run(cargo().args(bench).arg("--no-run"))?;
    let out = cargo()
        .args(bench)
        .arg("--")
        .args(args)
        .current_dir(root())
        .output()
        .context("running the ftfusion filter benchmark")?;
    print!("{}", String::from_utf8_lossy(&out.stdout));
    if !out.status.success() {
        bail!(
            "the ftfusion filter benchmark failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let rust = figure(
        &String::from_utf8_lossy(&out.stdout),
        "multilinear_updates_per_s",
    )?;
    let py = Command::new("python3")
        .arg(root().join("tests/bench_numpy.py"))
        .args(args)
        .current_dir(root())
        .output()
        .context("running python3 tests/bench_numpy.py")?;
    print!("{}", String::from_utf8_lossy(&py.stdout));
    if !py.status.success() {
        bail!(
            "tests/bench_numpy.py failed: {}",
            String::from_utf8_lossy(&py.stderr)
        );
    }
    let numpy = figure(&String::from_utf8_lossy(&py.stdout), "numpy_updates_per_s")?;
    println!(
        "speedup_rust_over_numpy = {:.1}x (goal >= 10x)",
        rust / numpy
    );
    Ok(())
}

/// The number after `key =` in a benchmark's output.
fn figure(text: &str, key: &str) -> Result<f64> {
    text.lines()
        .find_map(|l| {
            l.strip_prefix(key)?
                .trim_start()
                .strip_prefix('=')?
                .split_whitespace()
                .next()?
                .parse()
                .ok()
        })
        .with_context(|| format!("no `{key} = ` line in the benchmark output"))
}
