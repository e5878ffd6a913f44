//! The command line: `harness scene | trials | sweep | scan | compare-maps`.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};

use ftmap::Task;

use crate::campaign::{self, Summary};
use crate::fmu_driver::{Fmu, Settings, default_fmu_path};
use crate::scene::{self, SceneSpec};
use crate::sensor::Noise;
use crate::sim::Sim;
use crate::trial::{Strategy, TrialConfig, TrialResult};
use crate::{compare, plot, scan};

/// MuJoCo validation harness of ftfusion: scenes, closed-loop trials through FtFusion.fmu,
/// measured maps.
#[derive(Debug, Parser)]
#[command(name = "harness", version)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Write (or check) models_mjcf/<task>/scene.xml from the task's task.toml.
    Scene {
        /// Task name or task.toml path; all tasks with a [geometry] table when omitted.
        #[arg(long)]
        task: Option<String>,
        /// Only check that the committed scenes are current (exit 1 if not).
        #[arg(long)]
        check: bool,
    },
    /// Trial campaign on random true offsets: trials.csv, summary.json, plots.
    Trials {
        /// Common settings.
        #[command(flatten)]
        run: RunArgs,
        /// Number of trials.
        #[arg(long, default_value_t = 20)]
        trials: usize,
        /// Half width of the square of true offsets (mm); default: Omega's size_trans.
        #[arg(long)]
        range_mm: Option<f64>,
    },
    /// Trials on a grid of true offsets; plots contacts per offset (the paper's Fig. 10).
    Sweep {
        /// Common settings.
        #[command(flatten)]
        run: RunArgs,
        /// Grid points per axis.
        #[arg(long, default_value_t = 11)]
        grid: usize,
        /// Half width of the grid (mm); default: Omega's size_trans.
        #[arg(long)]
        range_mm: Option<f64>,
    },
    /// Measure an FT-Map by contact motions in MuJoCo (model `Measured`).
    Scan {
        /// Task name or task.toml path.
        #[arg(long)]
        task: String,
        /// Output map file.
        #[arg(long)]
        out: PathBuf,
        /// Grid step (mm).
        #[arg(long, default_value_t = 0.1)]
        step: f64,
        /// Half width of the scanned square (mm); default: Omega's size_trans.
        #[arg(long)]
        size: Option<f64>,
    },
    /// Per-channel agreement of two maps over the cells of the first; writes a plot.
    CompareMaps {
        /// First map (its cells are compared).
        a: PathBuf,
        /// Second map (interpolated at A's cells).
        b: PathBuf,
        /// Scatter plot of tx and ty.
        #[arg(long, default_value = "out/compare_maps.png")]
        plot: PathBuf,
    },
}

/// On or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Switch {
    /// On.
    On,
    /// Off.
    Off,
}

/// Settings shared by `trials` and `sweep`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Task name or task.toml path.
    #[arg(long)]
    pub task: String,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of the offsets, the sensor noise and the FMU.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// FT-Map for the FMU (default: the FMU's embedded peg_in_hole map).
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// How the next contact point is chosen.
    #[arg(long, value_enum, default_value_t = Strategy::Pf)]
    pub strategy: Strategy,
    /// Gaussian F/T sensor noise (0.05 N, 2 mN m).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub sensor_noise: Switch,
    /// The FMU.
    #[arg(long, env = "FTFUSION_FMU")]
    pub fmu: Option<PathBuf>,
    /// Most contact motions per trial (default: 30 for pf; enough to cover Omega for spiral).
    #[arg(long)]
    pub max_contacts: Option<usize>,
    /// Most simulated time per trial (s; default: 0.3 s per allowed contact).
    #[arg(long)]
    pub max_sim_time: Option<f64>,
    /// FMU parameter `particles`.
    #[arg(long)]
    pub particles: Option<i32>,
    /// FMU parameter `iterations`.
    #[arg(long)]
    pub iterations: Option<i32>,
    /// FMU parameter `sigma_torque` (N m).
    #[arg(long)]
    pub sigma_torque: Option<f64>,
}

/// The task, its scene and a simulation of it.
pub fn open_task(name: &str) -> anyhow::Result<(Task, Sim)> {
    let task = Task::find(name)?;
    let spec = SceneSpec::of_task(&task)?;
    let path = scene::scene_path(&task);
    let sim = Sim::load(&path, spec)?;
    Ok((task, sim))
}

/// Radial clearance of a task's parts (m): the spiral's pitch stays below twice it.
fn clearance(task: &Task) -> anyhow::Result<f64> {
    use ftmap::cad::Geometry;
    Ok(match ftmap::cad::geometry_of(&task.path)? {
        Geometry::RoundPeg { peg_radius, hole_radius, .. } => hole_radius - peg_radius,
        Geometry::OctagonPeg { peg_across_flats, hole_across_flats, .. } => (hole_across_flats - peg_across_flats) / 2.0,
        Geometry::GearOnShaft { bore_radius, shaft_radius, .. } => bore_radius - shaft_radius,
        Geometry::BearingHousing { bore_radius, seat_radius, .. } => bore_radius - seat_radius,
    })
}

fn config(run: &RunArgs, task: &Task) -> anyhow::Result<TrialConfig> {
    let map = match &run.map {
        Some(m) => Some(std::path::absolute(m).with_context(|| format!("map {}", m.display()))?),
        None if task.name == "peg_in_hole" => None,
        None => bail!(
            "task {} needs --map (the FMU embeds the peg_in_hole map only): `ftmap generate --task {} --out out/{}.ftmap`",
            task.name,
            task.name,
            task.name
        ),
    };
    if let Some(m) = &map
        && !m.is_file()
    {
        bail!("map {} not found: `ftmap generate --task {} --out {}`", m.display(), task.name, m.display());
    }
    let size = task.omega.size_trans;
    let spiral_step = 1.6 * clearance(task)?;
    let spiral_radius = size * 2f64.sqrt();
    let spiral_points = crate::trial::spiral(spiral_step, spiral_radius).len();
    let max_contacts = run.max_contacts.unwrap_or(match run.strategy {
        Strategy::Pf => 30,
        Strategy::Spiral => spiral_points,
    });
    Ok(TrialConfig {
        strategy: run.strategy,
        max_contacts,
        max_sim_time: run.max_sim_time.unwrap_or(0.3 * max_contacts as f64),
        noise: if run.sensor_noise == Switch::On { Noise::TYPICAL } else { Noise::NONE },
        spiral_step,
        spiral_radius,
        settings: Settings {
            map,
            particles: run.particles,
            iterations: run.iterations,
            sigma_torque: run.sigma_torque,
            ..Settings::default()
        },
    })
}

fn load_fmu(run: &RunArgs) -> anyhow::Result<Option<Fmu>> {
    match run.strategy {
        Strategy::Pf => {
            let path = run.fmu.clone().unwrap_or_else(default_fmu_path);
            Ok(Some(Fmu::load(&path)?))
        }
        Strategy::Spiral => Ok(None),
    }
}

fn finish(run: &RunArgs, task: &Task, results: &[TrialResult], wall: f64) -> anyhow::Result<Summary> {
    std::fs::create_dir_all(&run.out).with_context(|| format!("creating {}", run.out.display()))?;
    campaign::write_trials_csv(&run.out.join("trials.csv"), results)?;
    let summary = campaign::summarize(&task.name, run.strategy, run.sensor_noise == Switch::On, results, wall);
    campaign::write_summary(&run.out.join("summary.json"), &summary)?;
    println!("{}", summary.table());
    Ok(summary)
}

/// Runs the command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    crate::runtime::check_mujoco()?;
    match cli.command {
        Command::Scene { task, check } => scene_cmd(task.as_deref(), check),
        Command::Trials { run, trials, range_mm } => {
            let (task, mut sim) = open_task(&run.task)?;
            let cfg = config(&run, &task)?;
            let fmu = load_fmu(&run)?;
            let size = range_mm.map_or(task.omega.size_trans, |r| r * 1e-3);
            let offsets = campaign::random_offsets(trials, size, run.seed);
            let (results, wall) = campaign::timed(|| campaign::run_campaign(&mut sim, fmu.as_ref(), &cfg, &offsets, run.seed));
            let results = results?;
            finish(&run, &task, &results, wall)?;
            if run.strategy == Strategy::Pf {
                let pick = results.iter().position(|r| r.contacts >= 3).unwrap_or(0);
                if let Some(r) = results.get(pick) {
                    let path = run.out.join("estimates.png");
                    plot::estimates(&path, r, task.omega.size_trans)?;
                    println!("plot {} (trial {pick}: estimate and 1/2-sigma ellipse after contacts 1-3; the FMU exposes no particles)", path.display());
                }
            }
            Ok(())
        }
        Command::Sweep { run, grid, range_mm } => {
            let (task, mut sim) = open_task(&run.task)?;
            let cfg = config(&run, &task)?;
            let fmu = load_fmu(&run)?;
            let size = range_mm.map_or(task.omega.size_trans, |r| r * 1e-3);
            let offsets = campaign::grid_offsets(grid, size);
            let (results, wall) = campaign::timed(|| campaign::run_campaign(&mut sim, fmu.as_ref(), &cfg, &offsets, run.seed));
            let results = results?;
            finish(&run, &task, &results, wall)?;
            let path = run.out.join("sweep.png");
            let cell = if grid > 1 { 2.0 * size / (grid - 1) as f64 } else { 2.0 * size };
            plot::sweep(&path, &results, size, cell)?;
            println!("plot {}", path.display());
            Ok(())
        }
        Command::Scan { task, out, step, size } => {
            let (task, mut sim) = open_task(&task)?;
            let size = size.map_or(task.omega.size_trans, |s| s * 1e-3);
            let map = scan::scan(&mut sim, &task, step * 1e-3, size)?;
            if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            }
            ftmap::format::save(&map, &out)?;
            println!("measured map {} ({} cells, {:.1} s simulated)", out.display(), map.grid().cells(), sim.simulated());
            Ok(())
        }
        Command::CompareMaps { a, b, plot: png } => compare_cmd(&a, &b, &png),
    }
}

fn scene_cmd(task: Option<&str>, check: bool) -> anyhow::Result<()> {
    let tasks = match task {
        Some(t) => vec![Task::find(t)?],
        None => scene::tasks_with_scenes()?,
    };
    let mut stale = Vec::new();
    for t in &tasks {
        if check {
            if !scene::scene_is_current(t)? {
                stale.push(scene::scene_path(t).display().to_string());
            }
        } else {
            let path = scene::write_scene(t)?;
            let spec = SceneSpec::of_task(t)?;
            Sim::load(&path, spec).with_context(|| format!("loading the new scene {}", path.display()))?;
            println!("wrote {}", path.display());
        }
    }
    if !stale.is_empty() {
        bail!("scenes not current (run `harness scene`): {}", stale.join(", "));
    }
    Ok(())
}

fn compare_cmd(a: &Path, b: &Path, png: &Path) -> anyhow::Result<()> {
    let (ma, mb) = (ftmap::format::load(a)?, ftmap::format::load(b)?);
    let agreement = compare::compare(&ma, &mb)?;
    println!("A = {} ({:?}), B = {} ({:?})", a.display(), ma.meta().model, b.display(), mb.meta().model);
    print!("{}", agreement.table());
    plot::agreement(png, &["tx [N m]", "ty [N m]"], &agreement.pairs[3..5], ["A", "B"])?;
    println!("plot {}", png.display());
    Ok(())
}
