//! The command line: `harness render | scene | trials | sweep | scan | compare-runs | compare-maps`.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Parser, Subcommand, ValueEnum};

use ftmap::Task;

use crate::campaign::{self, Summary};
use crate::eye::Eye;
use crate::fmu_driver::{Fmu, Settings, default_fmu_path};
use crate::scene::{self, SceneSpec};
use crate::sensor::Noise;
use crate::sim::Sim;
use crate::trial::{Strategy, TrialConfig, TrialResult};
use crate::vision::Detector;
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
    /// Render the vision camera's image (experiment D) with the expected CAD edges (blue)
    /// and the detected lines (red) drawn over it; prints each edge's detection.
    Render {
        /// Task name or task.toml path (a task whose scene has a camera).
        #[arg(long, default_value = "bearing_housing")]
        task: String,
        /// Output PNG.
        #[arg(long, default_value = "out/d.png")]
        out: PathBuf,
        /// True offset of part B, "x,y" in mm.
        #[arg(long, default_value = "2,-3", allow_hyphen_values = true)]
        object_mm: String,
        /// Task frame (part A), "x,y" in mm; it hangs at the approach height.
        #[arg(long, default_value = "0,0", allow_hyphen_values = true)]
        tcp_mm: String,
        /// Gaussian image noise (grey levels) added before detection.
        #[arg(long, default_value_t = 0.0)]
        noise: f64,
        /// Seed of the noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Line detector.
        #[arg(long, value_enum, default_value_t = Detector::Gradient)]
        detector: Detector,
        /// Only time the detection (both detectors) on this many noisy copies of the image.
        #[arg(long)]
        bench: Option<usize>,
    },
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
    /// Two campaigns side by side (their trials.csv): contacts, contact measurements, y
    /// spread, trial by trial when they ran the same offsets; writes a plot.
    CompareRuns {
        /// First campaign's output folder.
        a: PathBuf,
        /// Second campaign's output folder.
        b: PathBuf,
        /// Bar plot of the contacts per trial.
        #[arg(long, default_value = "out/compare_runs.png")]
        plot: PathBuf,
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

/// The FMU's `vision_method`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum VisionMethodArg {
    /// Relative feature distances (section III-B-1).
    Relative,
    /// Camera recalibration on the passive part (section III-B-2).
    Recalibration,
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
    /// FT-Map for the FMU (default: the FMU's embedded map for peg_in_hole, else the task's
    /// map computed from its CAD meshes and cached in target/maps/).
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Fuse the camera with the F/T sensor (experiment D): an image before the first contact
    /// and at every contact, its edge features handed to the FMU.
    #[arg(long)]
    pub vision: bool,
    /// How the FMU evaluates particles by vision.
    #[arg(long, value_enum, default_value_t = VisionMethodArg::Recalibration)]
    pub vision_method: VisionMethodArg,
    /// FMU parameter `sigma_vision` (px).
    #[arg(long)]
    pub sigma_vision: Option<f64>,
    /// Gaussian image noise (grey levels) added to each rendered image.
    #[arg(long, default_value_t = 2.0)]
    pub image_noise: f64,
    /// Line detector for the camera's edges.
    #[arg(long, value_enum, default_value_t = Detector::Gradient)]
    pub detector: Detector,
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
    use ftmap::task::cad::Geometry;
    Ok(match *task.geometry()? {
        Geometry::RoundPeg {
            peg_radius,
            hole_radius,
            ..
        } => hole_radius - peg_radius,
        Geometry::OctagonPeg {
            peg_across_flats,
            hole_across_flats,
            ..
        } => (hole_across_flats - peg_across_flats) / 2.0,
        Geometry::GearOnShaft {
            bore_radius,
            shaft_radius,
            ..
        } => bore_radius - shaft_radius,
        Geometry::BearingHousing {
            bore_radius,
            seat_radius,
            ..
        } => bore_radius - seat_radius,
    })
}

fn config(run: &RunArgs, task: &Task) -> anyhow::Result<TrialConfig> {
    let map = match &run.map {
        Some(m) => Some(std::path::absolute(m).with_context(|| format!("map {}", m.display()))?),
        None if task.name == "peg_in_hole" => None,
        None => {
            let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/maps");
            let t0 = std::time::Instant::now();
            let (path, computed) = ftmap::generate::cached(task, &dir)
                .with_context(|| format!("the FT-Map of task {}", task.name))?;
            let how = if computed {
                format!(
                    "computed from the CAD meshes in {:.1} s",
                    t0.elapsed().as_secs_f64()
                )
            } else {
                "cached".into()
            };
            println!("map {} ({how})", path.display());
            Some(path)
        }
    };
    if let Some(m) = &map
        && !m.is_file()
    {
        bail!(
            "map {} not found: `ftmap generate --task {} --out {}`",
            m.display(),
            task.name,
            m.display()
        );
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
        noise: if run.sensor_noise == Switch::On {
            Noise::TYPICAL
        } else {
            Noise::NONE
        },
        spiral_step,
        spiral_radius,
        settings: Settings {
            map,
            particles: run.particles,
            iterations: run.iterations,
            sigma_torque: run.sigma_torque,
            sigma_vision: run.sigma_vision,
            vision_method: Some(match run.vision_method {
                VisionMethodArg::Relative => 0,
                VisionMethodArg::Recalibration => 1,
            }),
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

/// The camera, when `--vision` asks for it: its vision model is written to `<out>/vision.json`
/// and handed to the FMU.
fn open_eye(run: &RunArgs, task: &Task, cfg: &mut TrialConfig) -> anyhow::Result<Option<Eye>> {
    if !run.vision {
        return Ok(None);
    }
    if run.strategy != Strategy::Pf {
        bail!("--vision needs --strategy pf (the spiral search uses no estimator)");
    }
    let eye = Eye::open(task, run.image_noise, run.detector)?;
    std::fs::create_dir_all(&run.out).with_context(|| format!("creating {}", run.out.display()))?;
    let path =
        std::path::absolute(run.out.join("vision.json")).context("the vision model's path")?;
    eye.model().save(&path)?;
    println!(
        "vision model {} (camera as MuJoCo places it)",
        path.display()
    );
    cfg.settings.vision = Some(path);
    Ok(Some(eye))
}

fn finish(
    run: &RunArgs,
    task: &Task,
    results: &[TrialResult],
    wall: f64,
) -> anyhow::Result<Summary> {
    std::fs::create_dir_all(&run.out).with_context(|| format!("creating {}", run.out.display()))?;
    campaign::write_trials_csv(&run.out.join("trials.csv"), results)?;
    let summary = campaign::summarize(
        &task.name,
        run.strategy,
        run.sensor_noise == Switch::On,
        run.vision,
        results,
        wall,
    );
    campaign::write_summary(&run.out.join("summary.json"), &summary)?;
    println!("{}", summary.table());
    Ok(summary)
}

/// Runs the command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    crate::runtime::check_mujoco()?;
    match cli.command {
        Command::Scene { task, check } => scene_cmd(task.as_deref(), check),
        Command::Render {
            task,
            out,
            object_mm,
            tcp_mm,
            noise,
            seed,
            detector,
            bench,
        } => {
            let view = RenderView {
                object: parse_mm(&object_mm)?,
                tcp: parse_mm(&tcp_mm)?,
                noise,
                seed,
            };
            render_cmd(&task, &out, &view, detector, bench)
        }
        Command::Trials {
            run,
            trials,
            range_mm,
        } => {
            let (task, mut sim) = open_task(&run.task)?;
            let mut cfg = config(&run, &task)?;
            let mut eye = open_eye(&run, &task, &mut cfg)?;
            let fmu = load_fmu(&run)?;
            let size = range_mm.map_or(task.omega.size_trans, |r| r * 1e-3);
            let offsets = campaign::random_offsets(trials, size, run.seed);
            let (results, wall) = campaign::timed(|| {
                campaign::run_campaign(
                    &mut sim,
                    fmu.as_ref(),
                    eye.as_mut(),
                    &cfg,
                    &offsets,
                    run.seed,
                )
            });
            let results = results?;
            finish(&run, &task, &results, wall)?;
            if run.strategy == Strategy::Pf {
                // The first trial that needed a second contact measurement (else the first).
                let pick = results
                    .iter()
                    .position(|r| r.measurements() >= 2)
                    .unwrap_or(0);
                if let Some(r) = results.get(pick) {
                    let path = run.out.join("estimates.png");
                    plot::estimates(&path, r, task.omega.size_trans)?;
                    println!(
                        "plot {} (trial {pick}: estimate and 1/2-sigma ellipse after its first three measurements; the FMU exposes no particles)",
                        path.display()
                    );
                }
            }
            Ok(())
        }
        Command::Sweep {
            run,
            grid,
            range_mm,
        } => {
            let (task, mut sim) = open_task(&run.task)?;
            let mut cfg = config(&run, &task)?;
            let mut eye = open_eye(&run, &task, &mut cfg)?;
            let fmu = load_fmu(&run)?;
            let size = range_mm.map_or(task.omega.size_trans, |r| r * 1e-3);
            let offsets = campaign::grid_offsets(grid, size);
            let (results, wall) = campaign::timed(|| {
                campaign::run_campaign(
                    &mut sim,
                    fmu.as_ref(),
                    eye.as_mut(),
                    &cfg,
                    &offsets,
                    run.seed,
                )
            });
            let results = results?;
            finish(&run, &task, &results, wall)?;
            let path = run.out.join("sweep.png");
            let cell = if grid > 1 {
                2.0 * size / (grid - 1) as f64
            } else {
                2.0 * size
            };
            plot::sweep(&path, &results, size, cell)?;
            println!("plot {}", path.display());
            Ok(())
        }
        Command::Scan {
            task,
            out,
            step,
            size,
        } => {
            let (task, mut sim) = open_task(&task)?;
            let size = size.map_or(task.omega.size_trans, |s| s * 1e-3);
            let map = scan::scan(&mut sim, &task, step * 1e-3, size)?;
            if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir)
                    .with_context(|| format!("creating {}", dir.display()))?;
            }
            ftmap::map::format::save(&map, &out)?;
            println!(
                "measured map {} ({} cells, {:.1} s simulated)",
                out.display(),
                map.grid().cells(),
                sim.simulated()
            );
            Ok(())
        }
        Command::CompareMaps { a, b, plot: png } => compare_cmd(&a, &b, &png),
        Command::CompareRuns { a, b, plot: png } => {
            let (ra, rb) = (
                campaign::read_trials_csv(&a.join("trials.csv"))?,
                campaign::read_trials_csv(&b.join("trials.csv"))?,
            );
            let name = |p: &Path| {
                p.file_name().map_or_else(
                    || p.display().to_string(),
                    |n| n.to_string_lossy().into_owned(),
                )
            };
            let names = [name(&a), name(&b)];
            print!(
                "{}",
                campaign::comparison_table([&names[0], &names[1]], [&ra, &rb])
            );
            plot::contacts_per_trial(&png, [&names[0], &names[1]], [&ra, &rb])?;
            println!("plot {}", png.display());
            Ok(())
        }
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
            Sim::load(&path, spec)
                .with_context(|| format!("loading the new scene {}", path.display()))?;
            println!("wrote {}", path.display());
        }
    }
    if !stale.is_empty() {
        bail!(
            "scenes not current (run `harness scene`): {}",
            stale.join(", ")
        );
    }
    Ok(())
}

fn parse_mm(s: &str) -> anyhow::Result<[f64; 2]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("\"{s}\": want x,y in mm"))?;
    match v.as_slice() {
        [x, y] => Ok([x * 1e-3, y * 1e-3]),
        _ => bail!("\"{s}\": want x,y in mm"),
    }
}

/// What `render` shows: part B's offset and part A's position (m), image noise and its seed.
struct RenderView {
    object: [f64; 2],
    tcp: [f64; 2],
    noise: f64,
    seed: u64,
}

fn render_cmd(
    task: &str,
    out: &Path,
    rv: &RenderView,
    detector: Detector,
    bench: Option<usize>,
) -> anyhow::Result<()> {
    let RenderView {
        object,
        tcp,
        noise,
        seed,
    } = *rv;
    use crate::camera::{CameraScene, RgbImage};
    use crate::vision::{self, Features};
    let task = Task::find(task)?;
    let spec = SceneSpec::of_task(&task)?;
    let no_features = || {
        format!(
            "task {} has no vision features and no camera (only bearing_housing has)",
            task.name
        )
    };
    let designed = spec
        .camera
        .as_ref()
        .with_context(no_features)?
        .camera
        .clone();
    vision::task_model(&task, designed)?;
    let mut view = CameraScene::load(&scene::scene_path(&task), spec)?;
    let model = vision::task_model(&task, view.camera())?;
    let tcp = [tcp[0], tcp[1], view.approach_height()];
    let object3 = [object[0], object[1], 0.0];
    view.place(object, tcp);
    let t0 = std::time::Instant::now();
    let image = view.render()?;
    let render_ms = t0.elapsed().as_secs_f64() * 1e3;
    let cam = view.camera();
    let mut gray = image.to_gray();
    if noise > 0.0 {
        vision::add_noise(&mut gray, noise, seed);
    }
    if let Some(n) = bench {
        let t = std::time::Instant::now();
        view.render()?;
        let frame_ms = t.elapsed().as_secs_f64() * 1e3;
        let copies: Vec<Vec<f32>> = (0..n.max(1) as u64)
            .map(|k| {
                let mut g = image.to_gray();
                vision::add_noise(&mut g, noise.max(5.0), seed + k);
                g
            })
            .collect();
        for d in [Detector::Gradient, Detector::Hough] {
            let t = std::time::Instant::now();
            let mut found = 0;
            for g in &copies {
                found +=
                    vision::detect_edges(g, &cam, &model, tcp, object3, task.omega.size_trans, d)
                        .iter()
                        .filter(|e| e.found.is_ok())
                        .count();
            }
            let ms = t.elapsed().as_secs_f64() * 1e3 / copies.len() as f64;
            println!(
                "{d:?} detector (Sobel + 4 edges) on {} noisy {}x{} images: {ms:.2} ms per image, {:.0} images/s ({found} of {} edges found)",
                copies.len(),
                cam.width,
                cam.height,
                1e3 / ms,
                4 * copies.len()
            );
        }
        println!(
            "rendering: first frame (GL context) {render_ms:.0} ms, next frame {frame_ms:.0} ms"
        );
        return Ok(());
    }
    let results = vision::detect_edges(
        &gray,
        &cam,
        &model,
        tcp,
        object3,
        task.omega.size_trans,
        detector,
    );
    let mut img = if noise > 0.0 {
        RgbImage::from_gray(cam.width, cam.height, &gray)
    } else {
        image
    };
    println!(
        "camera: {}x{} px, fovy {} deg, f = {:.1} px, at {:?} m; render {render_ms:.1} ms",
        cam.width,
        cam.height,
        cam.fovy,
        cam.focal(),
        cam.pos
    );
    println!(
        "{:<14} {:>9} {:>9} {:>9} {:>9} {:>6}  detected",
        "edge", "angle", "offset", "d_angle", "d_offset", "band"
    );
    for r in &results {
        img.line(r.expected.p0, r.expected.p1, [60, 120, 255]);
        match &r.found {
            Ok(l) => {
                img.line(l.p0, l.p1, [255, 40, 40]);
                img.cross(l.p0, [255, 220, 0]);
                img.cross(l.p1, [255, 220, 0]);
                println!(
                    "{:<14} {:>9.3} {:>9.2} {:>9.3} {:>9.3} {:>6.0}  {} points, rms {:.2} px",
                    r.name,
                    l.angle,
                    l.offset,
                    l.angle - r.truth.angle,
                    l.offset - r.truth.offset,
                    r.band,
                    l.points,
                    l.rms
                );
            }
            Err(e) => println!("{:<14} {e}", r.name),
        }
    }
    let v = cam.reference_row();
    match (Features::of(&results, &cam), model.distances(tcp, object3)) {
        (Some(f), Some(truth)) => {
            for (k, side) in ["left", "right"].iter().enumerate() {
                println!(
                    "vision.{side}_distance = {:.2} px (truth {:.2}; active to passive edge along u at row {v:.1}), vision.passive_{side} = {:.2} px",
                    f.distances[k], truth[k], f.passive[k]
                );
            }
        }
        _ => println!("vision.valid = false (not all four edges found)"),
    }
    img.save_png(out)?;
    println!(
        "image {} (blue: expected CAD edges, red: detected lines, yellow: endpoints)",
        out.display()
    );
    Ok(())
}

fn compare_cmd(a: &Path, b: &Path, png: &Path) -> anyhow::Result<()> {
    let (ma, mb) = (ftmap::map::format::load(a)?, ftmap::map::format::load(b)?);
    let agreement = compare::compare(&ma, &mb)?;
    println!(
        "A = {} ({:?}), B = {} ({:?})",
        a.display(),
        ma.meta().model,
        b.display(),
        mb.meta().model
    );
    print!("{}", agreement.table());
    plot::agreement(
        png,
        &["tx [N m]", "ty [N m]"],
        &agreement.pairs[3..5],
        ["A", "B"],
    )?;
    println!("plot {}", png.display());
    Ok(())
}
