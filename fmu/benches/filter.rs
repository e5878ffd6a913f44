//! Benchmark of the filter on the paper's 4-DOF peg map size (object.x, object.y in
//! +-5 mm at 0.1 mm, object.rx, object.ry in +-2 deg at 0.5 deg: 826,281 cells, analytic
//! field): particle updates per second for both lookups, and the time of one doStep
//! without a new measurement through the FMU instance layer. Prints `key = value` lines.
//! Options: `--particles N` (10000), `--iterations K` (20), `--measurements M` (5).

use std::path::Path;
use std::time::Instant;

use ftfusion::filter::{Config, Filter, Interpolation, Measurement};
use ftfusion::instance::{Instance, Status};
use ftfusion::params::Value;
use ftfusion_testkit::{field, peg_map};
use model_description::{VarType, by_name};

fn arg(args: &[String], name: &str, default: usize) -> usize {
    args.windows(2)
        .find(|w| w[0] == name)
        .and_then(|w| w[1].parse().ok())
        .unwrap_or(default)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let particles = arg(&args, "--particles", 10_000);
    let iterations = arg(&args, "--iterations", 20);
    let measurements = arg(&args, "--measurements", 5);
    let deg = 1f64.to_radians();
    let map = peg_map(5e-3, 1e-4, Some((2.0 * deg, 0.5 * deg)))?;
    println!("map_cells = {}", map.grid().cells());
    println!("particles = {particles}");
    println!("iterations = {iterations}");
    let truth = [1.7e-3, -2.3e-3, 0.6 * deg, -1.1 * deg];
    let w = field(truth[0], truth[1], truth[2], truth[3]);
    let m = Measurement {
        wrench: [w[0], w[1], w[2], w[3], w[4], w[5]].map(f64::from),
        tcp: [0.0, 0.0, f64::from(w[6]), 0.0, 0.0, 0.0],
        ..Measurement::default()
    };
    for (name, interpolation) in [
        ("multilinear", Interpolation::Multilinear),
        ("nearest", Interpolation::Nearest),
    ] {
        let cfg = Config {
            particles,
            iterations,
            interpolation,
            sigma_force: 0.2,
            ..Config::default()
        };
        let mut f = Filter::new(&map, Path::new("synthetic"), cfg)?;
        let t0 = Instant::now();
        for _ in 0..measurements {
            f.measure(&m)?;
        }
        let dt = t0.elapsed().as_secs_f64();
        let updates = (particles * iterations * measurements) as f64;
        println!("{name}_updates_per_s = {:.3e}", updates / dt);
        println!(
            "{name}_ms_per_measurement = {:.2}",
            1e3 * dt / measurements as f64
        );
        let e = f.estimate();
        println!(
            "{name}_error = {:.3} mm {:.3} mm {:.3} deg {:.3} deg (confidence {:.2})",
            (e.pose[0] - truth[0]) * 1e3,
            (e.pose[1] - truth[1]) * 1e3,
            (e.pose[2] - truth[2]) / deg,
            (e.pose[3] - truth[3]) / deg,
            e.confidence
        );
    }

    // One doStep without a new measurement, through the FMU instance layer.
    let dir = std::env::temp_dir().join(format!("ftfusion-bench-{}", std::process::id()));
    let path = dir.join("peg4.ftmap");
    ftmap::map::format::save(&map, &path)?;
    let mut inst = Instance::new("bench", None, Box::new(|_, _, _| {}), false);
    let vr = |n: &str| by_name(n).map(|v| v.vr).unwrap_or(0);
    inst.set(
        VarType::String,
        &[vr("map")],
        vec![Value::String(path.display().to_string())],
    )?;
    inst.set(
        VarType::Integer,
        &[vr("particles")],
        vec![Value::Integer(particles as i32)],
    )?;
    inst.enter_initialization_mode()?;
    inst.exit_initialization_mode()?;
    let steps = 1_000_000;
    let t0 = Instant::now();
    for k in 0..steps {
        let s = inst.do_step(k as f64 * 1e-3, 1e-3)?;
        if s != Status::Ok {
            anyhow::bail!("doStep returned {s:?}");
        }
    }
    let dt = t0.elapsed().as_secs_f64();
    println!("do_step_us = {:.4}", 1e6 * dt / steps as f64);
    std::fs::remove_dir_all(dir).ok();
    Ok(())
}
