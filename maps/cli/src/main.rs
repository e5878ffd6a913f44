#![doc = include_str!("../README.md")]

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::builder::BoolishValueParser;
use clap::{ArgAction, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use ftmap::depth::DepthBackend;
use ftmap::generate::{GenerateOptions, generate, generate_with, merge, shard_configs};
use ftmap::map::resolution::too_coarse;
use ftmap::map::{format, parity};
use ftmap::{CHANNELS, FtMap, Task, UNITS, WrenchModel};

mod plot;

#[derive(Parser)]
#[command(
    name = "ftmap",
    version,
    about = "Force Torque Maps from CAD meshes by the z-buffer method"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

/// Which depth backend computes the map.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackendKind {
    /// Rasterizer and contact reduction on the CPU (rayon), the reference.
    Cpu,
    /// wgpu render and compute pipelines (Vulkan; Mesa lavapipe without a GPU).
    Gpu,
}

/// The wrench models a map can be computed with (`measured` maps come from `harness scan`).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ModelArg {
    /// The paper's: force from contact normals and friction (Eq. 2), torque from the
    /// convex-hull lever rule.
    Paper,
    /// Pressure spread evenly over the contact area: torque about the contact centroid.
    Centroid,
}

impl From<ModelArg> for WrenchModel {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Paper => Self::Paper,
            ModelArg::Centroid => Self::Centroid,
        }
    }
}

#[derive(Subcommand)]
enum Cmd {
    /// Computes the FT-Map of a task.
    Generate {
        /// Task name (a folder of models_mjcf/) or path of a task.toml.
        #[arg(long)]
        task: String,
        #[arg(long, value_enum, default_value = "cpu")]
        backend: BackendKind,
        #[arg(long, value_enum, default_value = "centroid")]
        model: ModelArg,
        /// Output map file.
        #[arg(long)]
        out: PathBuf,
        /// Compute only shard I of N (`I/N`, rotation cells split round-robin); join with `merge`.
        #[arg(long, value_parser = ftmap::process::parse_shard)]
        shard: Option<[usize; 2]>,
        /// Also compute the map's centre map into this file, where Omega's step is too coarse
        /// for the fit beside a rotation: a finer map of the cells around the goal, for the
        /// FMU's `centre_map`.
        #[arg(long, conflicts_with = "shard")]
        centre: Option<PathBuf>,
        /// Fail when the GPU backend finds only a CPU adapter (e.g. lavapipe).
        #[arg(long, env = "FTMAP_REQUIRE_GPU", action = ArgAction::SetTrue, value_parser = BoolishValueParser::new())]
        require_gpu: bool,
    },
    /// Prints a map file's header: task, model, grid, channels and their ranges.
    Info { file: PathBuf },
    /// Writes a map as CSV: the grid coordinates named after their DOFs, then fx..tz, depth (SI).
    ExportCsv {
        file: PathBuf,
        #[arg(long)]
        out: PathBuf,
    },
    /// Draws one channel over two axes as a PNG heat map.
    Plot {
        file: PathBuf,
        /// fx, fy, fz, tx, ty, tz or depth.
        #[arg(long)]
        channel: String,
        /// Values of the other axes, in mm and degrees, e.g. `rx=0,ry=0.5` (default 0).
        #[arg(long, value_parser = parse_at, value_delimiter = ',')]
        at: Vec<(String, f64)>,
        /// The two axes to draw, e.g. `object.x,object.y` (default: the first two).
        #[arg(long)]
        axes: Option<String>,
        #[arg(long)]
        out: PathBuf,
    },
    /// Times the computation of a task's map on each backend and prints configs/s.
    Bench {
        #[arg(long)]
        task: String,
        /// Backends to time (default: both; the GPU one is skipped with a message when no adapter exists).
        #[arg(long, value_enum)]
        backend: Vec<BackendKind>,
        #[arg(long, value_enum, default_value = "centroid")]
        model: ModelArg,
        /// Fail when the GPU backend finds only a CPU adapter.
        #[arg(long, env = "FTMAP_REQUIRE_GPU", action = ArgAction::SetTrue, value_parser = BoolishValueParser::new())]
        require_gpu: bool,
    },
    /// Corrects a computed map by a sparse measured one (`harness scan --step`): the residual
    /// measured - computed at the measured cells, interpolated over the computed grid.
    Blend {
        /// The map computed from CAD.
        computed: PathBuf,
        /// The measured map (same DOFs, any step).
        measured: PathBuf,
        /// Output map file.
        #[arg(long)]
        out: PathBuf,
    },
    /// Joins the shard files of one computation into the whole map.
    Merge {
        shards: Vec<PathBuf>,
        #[arg(long)]
        out: PathBuf,
    },
    /// Writes a task's vision model (its [camera] and the silhouette features of its
    /// [geometry]) as a *.vision.json file for the FMU's `vision` parameter.
    Vision {
        /// Task name or path of a task.toml.
        #[arg(long)]
        task: String,
        /// Output file.
        #[arg(long)]
        out: PathBuf,
    },
    /// Checks a computed map against the exact geometry of its meshes (parry's shape cast and
    /// ray queries) at sampled cells: depth within the contact tolerance (plus a pixel of
    /// a tilted face's slope), contact centroid within a pixel; exits 1 when fewer than
    /// 99.9 % of the cells agree.
    Verify {
        file: PathBuf,
        /// Task name or path of the task.toml the map was computed from (default: a
        /// task.toml beside the map, else the committed task the map names).
        #[arg(long)]
        task: Option<String>,
        /// Cells to check (all when the map has fewer).
        #[arg(long, default_value_t = 2000)]
        samples: usize,
        /// Seed of the cell sample and of the rays' offset from the pixel lattice.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// How many of the cells farthest out of bounds to list.
        #[arg(long, default_value_t = 5)]
        worst: usize,
        /// Check these cells (flat indices, as `--worst` lists them) instead of a sample,
        /// and print each one's exact contact and the map's lever point.
        #[arg(long = "cell", value_name = "CELL")]
        cells: Vec<usize>,
    },
    /// Makes tasks from a user's meshes.
    Task {
        #[command(subcommand)]
        cmd: TaskCmd,
    },
    /// Writes (or with --check, verifies) the STL meshes of tasks from their [geometry] tables.
    Cad {
        /// Task name or `all`.
        #[arg(long, default_value = "all")]
        task: String,
        #[arg(long)]
        check: bool,
    },
}

#[derive(Subcommand)]
enum TaskCmd {
    /// Writes a task folder from two STL files in the assembly's coordinates (part A where it
    /// sits when assembled): the meshes, checked and copied, and a commented task.toml whose
    /// settings come from the geometry (sensor above part A, Omega as wide as part A or part B's top, the
    /// pixel from the fit's clearance measured on the meshes).
    New {
        /// STL of part A, the gripped part; its frame is the task frame (the TCP).
        #[arg(long)]
        part_a: PathBuf,
        /// STL of part B, the fixed part; its frame is the goal frame.
        #[arg(long)]
        part_b: PathBuf,
        /// The STL files' length unit.
        #[arg(long, value_enum)]
        units: UnitsArg,
        /// The task folder to write; its name is the task's.
        #[arg(long)]
        out: PathBuf,
        /// Approach vector `x,y,z` (task frame).
        #[arg(long, value_delimiter = ',', num_args = 3, default_values_t = [0.0, 0.0, -1.0], allow_hyphen_values = true)]
        approach: Vec<f64>,
        /// Force pressed along the approach at each contact (N).
        #[arg(long, default_value_t = 50.0)]
        force: f64,
        /// Friction coefficient between the parts.
        #[arg(long, default_value_t = 0.3)]
        friction: f64,
        /// Omega's translational bound (m; default: part A's half-width, or part B's top's radius where less, rounded up to 0.5 mm).
        #[arg(long)]
        omega: Option<f64>,
    },
}

/// A mesh file's length unit.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum UnitsArg {
    M,
    Mm,
    In,
}

fn parse_at(s: &str) -> Result<(String, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}`: expected AXIS=VALUE, e.g. rx=0"))?;
    Ok((
        k.trim().to_owned(),
        v.trim().parse::<f64>().map_err(|e| format!("`{s}`: {e}"))?,
    ))
}

fn main() -> Result<()> {
    ftmap::process::die_quietly_on_broken_pipe();
    match Cli::parse().cmd {
        Cmd::Generate {
            task,
            backend,
            model,
            out,
            shard,
            centre,
            require_gpu,
        } => cmd_generate(
            &task,
            backend,
            &GenerateOptions {
                model: model.into(),
                shard,
            },
            &out,
            centre.as_deref(),
            require_gpu,
        ),
        Cmd::Info { file } => cmd_info(&file),
        Cmd::ExportCsv { file, out } => cmd_export_csv(&file, &out),
        Cmd::Plot {
            file,
            channel,
            at,
            axes,
            out,
        } => cmd_plot(&file, &channel, &at, axes.as_deref(), &out),
        Cmd::Bench {
            task,
            backend,
            model,
            require_gpu,
        } => cmd_bench(&task, &backend, model.into(), require_gpu),
        Cmd::Blend {
            computed,
            measured,
            out,
        } => cmd_blend(&computed, &measured, &out),
        Cmd::Merge { shards, out } => cmd_merge(&shards, &out),
        Cmd::Vision { task, out } => cmd_vision(&task, &out),
        Cmd::Cad { task, check } => cmd_cad(&task, check),
        Cmd::Task {
            cmd:
                TaskCmd::New {
                    part_a,
                    part_b,
                    units,
                    out,
                    approach,
                    force,
                    friction,
                    omega,
                },
        } => cmd_task_new(&ftmap::task::create::NewTask {
            part_a,
            part_b,
            units: match units {
                UnitsArg::M => ftmap::task::Units::M,
                UnitsArg::Mm => ftmap::task::Units::Mm,
                UnitsArg::In => ftmap::task::Units::In,
            },
            out,
            approach: [approach[0], approach[1], approach[2]],
            force,
            friction,
            size: omega,
        }),
        Cmd::Verify {
            file,
            task,
            samples,
            seed,
            worst,
            cells,
        } => cmd_verify(&file, task.as_deref(), samples, seed, worst, &cells),
    }
}

fn cmd_task_new(spec: &ftmap::task::create::NewTask) -> Result<()> {
    use ftmap::task::fit::Fit;
    let (task, fit) = ftmap::task::create::create(spec)?;
    for part in [&task.part_a, &task.part_b] {
        load_part(part)?;
    }
    println!(
        "{}: clearance {:.4} mm, chamfers {:.3} mm; Omega ± {:.3} mm at {:.3} mm, pixel {:.3} mm -> {}",
        task.name,
        fit.clearance() * 1e3,
        fit.chamfers() * 1e3,
        task.omega.size_trans * 1e3,
        task.omega.delta_trans * 1e3,
        task.depth.pixel * 1e3,
        task.path.display()
    );
    Ok(())
}

/// A task's part, its mesh's warnings printed.
fn load_part(part: &ftmap::task::Part) -> Result<ftmap::mesh::Mesh> {
    let mesh = part.load()?;
    for w in &mesh.warnings {
        eprintln!("warning: mesh {}: {w}", part.mesh.display());
    }
    Ok(mesh)
}

/// A progress bar on stderr (drawn only on a terminal) over `total` `units`.
fn progress_bar(total: u64, units: &str) -> Result<ProgressBar> {
    let template = format!(
        "{{spinner}} {{msg}} [{{bar:40}}] {{human_pos}}/{{human_len}} {units}, {{per_sec}}, eta {{eta}}"
    );
    let style = ProgressStyle::with_template(&template).context("progress template")?;
    Ok(ProgressBar::new(total).with_style(style.progress_chars("=> ")))
}

fn cmd_verify(
    file: &Path,
    task: Option<&str>,
    samples: usize,
    seed: u64,
    worst: usize,
    cells: &[usize],
) -> Result<()> {
    let map = format::load(file)?;
    let beside = file.with_file_name("task.toml");
    let task = match task {
        Some(t) => Task::find(t)?,
        None if beside.is_file() => Task::load(&beside)?,
        None => Task::find(&map.meta().task)?,
    };
    let (mesh_a, mesh_b) = (load_part(&task.part_a)?, load_part(&task.part_b)?);
    let start = Instant::now();
    if let Some(&c) = cells.iter().find(|&&c| c >= map.grid().cells()) {
        bail!(
            "cell {c} is not in the map: it has {} cells",
            map.grid().cells()
        );
    }
    let meshes = [&mesh_a, &mesh_b];
    let checked = match cells.is_empty() {
        true => ftmap::verify::sample(
            map.grid().cells(),
            ftmap::verify::VerifyOptions { samples, seed },
        ),
        false => cells.to_vec(),
    };
    let bar = progress_bar(checked.len() as u64, "cells")?;
    bar.set_message("verify");
    let v = ftmap::verify::verify_cells_with(&map, &task, meshes, &checked, seed, &|n| bar.inc(n))?;
    bar.finish_and_clear();
    let qs = [0.5, 0.99, 0.999, 1.0];
    let um = |xs: Vec<f64>| {
        xs.iter()
            .map(|x| format!("{:.2}", x * 1e6))
            .collect::<Vec<_>>()
            .join(" / ")
    };
    println!(
        "verified {} cells of {} against task {} in {:.1} s",
        v.checks.len(),
        file.display(),
        task.name,
        start.elapsed().as_secs_f64()
    );
    println!(
        "depth     |error| median / p99 / p99.9 / max {} um; within the contact tolerance ({:.1} um, plus a pixel of a tilted face's slope) {:.2} %",
        um(v.depth_quantiles(&qs)),
        v.tolerance * 1e6,
        100.0 * v.depth_share()
    );
    match v.centroid_share() {
        Some(s) => println!(
            "centroid  error median / p99 / p99.9 / max {} um; within a pixel ({:.1} um) {:.2} %",
            um(v.centroid_quantiles(&qs)),
            v.pixel * 1e6,
            100.0 * s
        ),
        None => println!(
            "centroid  not checked: a {:?} map's lever point is not the contact centroid",
            map.meta().model
        ),
    }
    let (misses, unsettled) = v.centroid_misses();
    if misses > 0 {
        println!(
            "misses    {misses} cells over a pixel; {unsettled} of them ill-conditioned: their exact centroid moves more than a pixel when the threshold moves by half a pixel's climb across the tilt (a region in pieces, a tip)"
        );
    }
    let spread = |c: &ftmap::verify::CellCheck| {
        c.spread.map_or(String::new(), |s| {
            format!(
                "; the centroid moves {:.2} um within half a pixel's climb",
                s * 1e6
            )
        })
    };
    let coords = |c: &ftmap::verify::CellCheck| describe_cell(&map, &c.coords);
    let mm = |p: Option<[f64; 2]>| {
        p.map_or("-".into(), |[u, v]| {
            format!("({:+.4}, {:+.4}) mm", u * 1e3, v * 1e3)
        })
    };
    // Chosen cells are each read out; a sample only by its worst.
    let chosen = if cells.is_empty() {
        &[][..]
    } else {
        &v.checks[..]
    };
    for c in chosen {
        println!(
            "cell      {} ({}): depth error {:.2} um (allowed {:.2}); region within {:.2} um of touching: centroid {}, the map's lever {}{}",
            c.cell,
            coords(c),
            c.depth_error * 1e6,
            (v.tolerance + c.sampling) * 1e6,
            c.threshold * 1e6,
            mm(c.centroid),
            mm(c.lever),
            spread(c)
        );
    }
    for c in v.worst(worst) {
        println!(
            "worst     cell {} ({}): depth error {:.2} um, centroid error {}{}",
            c.cell,
            coords(c),
            c.depth_error * 1e6,
            match c.centroid_error {
                None => "-".into(),
                Some(e) if e.is_infinite() =>
                    "none: neither the rays along the approach nor the closest points find the contact".into(),
                Some(e) => format!("{:.2} um", e * 1e6),
            },
            spread(c)
        );
    }
    if !v.passes() {
        bail!(
            "{}: fewer than {:.1} % of the sampled cells agree with the exact geometry",
            file.display(),
            100.0 * ftmap::verify::REQUIRED_SHARE
        );
    }
    println!("passed");
    Ok(())
}

fn cmd_vision(task: &str, out: &Path) -> Result<()> {
    let task = Task::find(task)?;
    let Some(model) = ftmap::vision::VisionModel::of_task(&task)? else {
        bail!(
            "task {} has no vision model: it needs a [camera] table and a [geometry] with silhouette features (bearing_housing has both)",
            task.name
        );
    };
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    model.save(out)?;
    let c = &model.camera;
    println!(
        "wrote {} (camera {}x{} px, fovy {} deg, at {:?} m)",
        out.display(),
        c.width,
        c.height,
        c.fovy,
        c.pos
    );
    Ok(())
}

#[cfg_attr(not(feature = "gpu"), allow(unused_variables))]
fn make_backend(kind: BackendKind, require_gpu: bool) -> Result<Box<dyn DepthBackend>> {
    Ok(match kind {
        BackendKind::Cpu => Box::new(ftmap::depth::cpu::CpuBackend),
        #[cfg(not(feature = "gpu"))]
        BackendKind::Gpu => {
            bail!("this build of ftmap has no GPU backend (built without the `gpu` feature)")
        }
        #[cfg(feature = "gpu")]
        BackendKind::Gpu => {
            use ftmap::depth::gpu::GpuBackend;
            let gpu = if require_gpu {
                GpuBackend::new_require_gpu()
            } else {
                GpuBackend::new()
            }
            .context("starting the GPU backend")?;
            eprintln!("GPU adapter: {}", gpu.name());
            Box::new(gpu)
        }
    })
}

fn cmd_generate(
    task: &str,
    kind: BackendKind,
    opts: &GenerateOptions,
    out: &Path,
    centre: Option<&Path>,
    require_gpu: bool,
) -> Result<()> {
    let task = Task::find(task)?;
    let backend = make_backend(kind, require_gpu)?;
    let grid = task.grid()?;
    let clearance = match task.fit() {
        Ok(fit) => Some(fit.clearance()),
        Err(e) => {
            eprintln!(
                "warning: {}: no clearance to check the grid against: {e}",
                task.name
            );
            None
        }
    };
    for coarse in too_coarse(&grid, task.depth.pixel, clearance) {
        eprintln!("warning: {}: {coarse}", task.name);
    }
    let (mesh_a, mesh_b) = (load_part(&task.part_a)?, load_part(&task.part_b)?);
    let compute = |t: &Task, out: &Path| -> Result<()> {
        let total = shard_configs(&t.grid()?, opts.shard);
        let bar = progress_bar(total as u64, "configs")?;
        bar.set_message(format!("{} ({})", t.name, backend.name()));
        let start = Instant::now();
        let map = generate_with(t, &mesh_a, &mesh_b, backend.as_ref(), opts, &|n| bar.inc(n))?;
        let secs = start.elapsed().as_secs_f64();
        bar.finish_and_clear();
        format::write_bytes(&format::encode(&map, opts.shard), out)?;
        println!(
            "{}: {} configs in {:.2} s = {:.0} configs/s ({}, {:?} model) -> {}",
            t.name,
            total,
            secs,
            total as f64 / secs,
            backend.name(),
            opts.model,
            out.display()
        );
        Ok(())
    };
    compute(&task, out)?;
    if let Some(file) = centre {
        match ftmap::map::centre::centre_task(&task, &grid, clearance)? {
            Some(c) => compute(&c, file)?,
            None => println!(
                "{}: no centre map: the grid resolves the fit (or its clearance is unknown)",
                task.name
            ),
        }
    }
    Ok(())
}

fn cmd_info(file: &Path) -> Result<()> {
    let (map, shard) = format::load_any(file)?;
    let m = map.meta();
    let g = map.grid();
    println!(
        "file       {} ({} bytes)",
        file.display(),
        std::fs::metadata(file)?.len()
    );
    if let Some([i, n]) = shard {
        println!("shard      {i} of {n} (other cells are NaN; join with `ftmap merge`)");
    }
    println!("task       {}", m.task);
    println!("model      {:?}", m.model);
    println!("generator  {}", m.generator);
    println!(
        "approach   {:?}  force {} N  friction {}",
        m.approach, m.force, m.friction
    );
    println!(
        "sensor     {:?} m (task frame)  pixel {} mm",
        m.sensor_origin,
        m.pixel * 1e3
    );
    match m.clearance {
        Some(c) => println!("clearance  {:.4} mm (radial, from the geometry)", c * 1e3),
        None => println!("clearance  unknown (no negative contact unless the FMU is given one)"),
    }
    for coarse in too_coarse(g, m.pixel, m.clearance) {
        println!("warning    {coarse}");
    }
    if let Some(play) = m.play {
        let about = ["rx", "ry", "rz"]
            .iter()
            .zip(play)
            .filter(|(_, p)| *p > 0.0)
            .map(|(a, p)| format!("{a} ±{:.4}°", p.to_degrees()))
            .collect::<Vec<_>>()
            .join(", ");
        println!("play       {about} (at zero offset, from the geometry)");
    }
    for s in &m.sources {
        println!("mesh {}     {} sha256 {}", s.role, s.file, s.sha256);
    }
    println!("grid       {} axes, {} cells", g.ndim(), g.cells());
    for a in g.axes() {
        let omega = a.omega.map_or(String::new(), |h| {
            format!(", Omega {}", a.dof.display(h).replace('+', "±"))
        });
        println!(
            "  {:<10} {} .. {} step {} ({} samples{omega})",
            a.dof.to_string(),
            a.dof.display(a.min),
            a.dof.display(a.max()),
            a.dof.display(a.step).trim_start_matches('+'),
            a.count
        );
    }
    println!(
        "channels   {:<6} {:>12} {:>12} {:>12}",
        "", "min", "mean", "max"
    );
    for (c, (name, unit)) in CHANNELS.iter().zip(UNITS).enumerate() {
        let vals = map
            .data()
            .iter()
            .skip(c)
            .step_by(ftmap::NCH)
            .copied()
            .filter(|v| v.is_finite());
        let (mut lo, mut hi, mut sum, mut n) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
        for v in vals {
            let v = f64::from(v);
            (lo, hi, sum, n) = (lo.min(v), hi.max(v), sum + v, n + 1);
        }
        println!(
            "  {name:<6} {unit:<4} {lo:>12.5} {:>12.5} {hi:>12.5}",
            sum / n.max(1) as f64
        );
    }
    Ok(())
}

fn cmd_export_csv(file: &Path, out: &Path) -> Result<()> {
    let map = format::load(file)?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let mut w =
        csv::Writer::from_path(out).with_context(|| format!("creating {}", out.display()))?;
    let g = map.grid();
    let header: Vec<String> = g
        .axes()
        .iter()
        .map(|a| a.dof.to_string())
        .chain(CHANNELS.iter().map(|c| c.to_string()))
        .collect();
    w.write_record(&header)?;
    let mut row: Vec<String> = Vec::with_capacity(header.len());
    for cell in 0..g.cells() {
        row.clear();
        row.extend(g.coords(cell).iter().map(|v| format!("{v:.9}")));
        row.extend(map.cell(cell).iter().map(|v| v.to_string()));
        w.write_record(&row)?;
    }
    w.flush()?;
    println!("{} rows -> {}", g.cells(), out.display());
    Ok(())
}

fn cmd_plot(
    file: &Path,
    channel: &str,
    at: &[(String, f64)],
    axes: Option<&str>,
    out: &Path,
) -> Result<()> {
    let map = format::load(file)?;
    let g = map.grid();
    let find = |name: &str| {
        g.axes()
            .iter()
            .position(|a| a.dof.to_string() == name || a.dof.axis.name() == name)
            .with_context(|| format!("the map has no axis `{name}`"))
    };
    let axes = match axes {
        None => None,
        Some(s) => {
            let (x, y) = s
                .split_once(',')
                .context("--axes expects two names, e.g. object.x,object.y")?;
            Some([find(x.trim())?, find(y.trim())?])
        }
    };
    // --at is given in mm and degrees: convert to SI.
    let at_si = at
        .iter()
        .map(|(name, v)| Ok((name.clone(), v / g.axes()[find(name)?].dof.display_unit().0)))
        .collect::<Result<Vec<_>>>()?;
    plot::heat_map(&map, channel, axes, &at_si, out)?;
    println!("{} -> {}", channel, out.display());
    Ok(())
}

fn cmd_bench(
    task: &str,
    kinds: &[BackendKind],
    model: WrenchModel,
    require_gpu: bool,
) -> Result<()> {
    let task = Task::find(task)?;
    let cells = task.grid()?.cells();
    let kinds = if kinds.is_empty() {
        vec![BackendKind::Cpu, BackendKind::Gpu]
    } else {
        kinds.to_vec()
    };
    println!("task {}: {} configs, {:?} model", task.name, cells, model);
    let mut reference: Option<FtMap> = None;
    for kind in kinds {
        let backend = match make_backend(kind, require_gpu) {
            Ok(b) => b,
            Err(e) if kind == BackendKind::Gpu && !require_gpu => {
                println!("gpu: skipped: {e:#}");
                continue;
            }
            Err(e) => return Err(e),
        };
        let opts = GenerateOptions { model, shard: None };
        // Warm up on one rotation cell (GPU pipelines, page faults), then time the whole map.
        let warm = GenerateOptions {
            model,
            shard: Some([0, cells]),
        };
        generate(&task, backend.as_ref(), &warm, &|_| ())?;
        let start = Instant::now();
        let map = generate(&task, backend.as_ref(), &opts, &|_| ())?;
        let secs = start.elapsed().as_secs_f64();
        println!(
            "{:<40} {:>10.3} s {:>14.0} configs/s",
            backend.name(),
            secs,
            cells as f64 / secs
        );
        match &reference {
            None => reference = Some(map),
            Some(r) => {
                let p = parity::compare(r, &map)?;
                println!(
                    "{:<40} against the first backend: contact differs in {} of {} cells; lines of action over a pixel ({:.1} um) apart in {} (max {:.2} um); depth max {:.3} um apart",
                    "",
                    p.contact_differs,
                    p.cells,
                    1e6 * r.meta().pixel,
                    p.lever_over_pixel,
                    1e6 * p.max_lever,
                    1e6 * p.max_depth,
                );
                for &cell in &p.differing {
                    let at = r.grid().coords(cell);
                    let forces = [r, &map].map(|m| {
                        let c = m.cell(cell);
                        format!("({:.3}, {:.3}, {:.3}) N", c[0], c[1], c[2])
                    });
                    println!(
                        "{:<40} differs at {}: force {} against {}",
                        "",
                        describe_cell(r, &at),
                        forces[0],
                        forces[1]
                    );
                }
            }
        }
    }
    Ok(())
}

/// A cell's coordinates `at` as its axes' names and values in mm and degrees.
fn describe_cell(map: &FtMap, at: &[f64]) -> String {
    let axes = map.grid().axes().iter().zip(at);
    let named: Vec<String> = axes
        .map(|(a, x)| format!("{}={}", a.dof, a.dof.display(*x)))
        .collect();
    named.join(" ")
}

fn cmd_merge(shards: &[PathBuf], out: &Path) -> Result<()> {
    let parts = shards
        .iter()
        .map(|p| match format::load_any(p)? {
            (m, Some(s)) => Ok((m, s)),
            (_, None) => bail!("{} is a whole map, not a shard", p.display()),
        })
        .collect::<Result<Vec<_>>>()?;
    let map = merge(parts)?;
    format::save(&map, out)?;
    println!("{} shards -> {}", shards.len(), out.display());
    Ok(())
}

fn cmd_blend(computed: &Path, measured: &Path, out: &Path) -> Result<()> {
    let (c, m) = (format::load(computed)?, format::load(measured)?);
    let blended = ftmap::map::blend::blend(&c, &m)?;
    format::save(&blended, out)?;
    println!(
        "{} corrected by {} ({} measured cells) -> {}",
        computed.display(),
        measured.display(),
        m.grid().cells(),
        out.display()
    );
    Ok(())
}

fn cmd_cad(task: &str, check: bool) -> Result<()> {
    let tasks = if task == "all" {
        Task::all_with_geometry()?
    } else {
        vec![Task::find(task)?]
    };
    let mut stale_total = 0;
    for task in tasks {
        if check {
            let stale = task.stale_meshes()?;
            for f in &stale {
                println!("{}: {f} is stale", task.name);
            }
            stale_total += stale.len();
        } else {
            for f in task.write_meshes()? {
                println!("wrote {}", f.display());
            }
        }
    }
    if stale_total > 0 {
        bail!("{stale_total} mesh file(s) differ from their task's [geometry]: run `ftmap cad`");
    }
    Ok(())
}
