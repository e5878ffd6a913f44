//! The command line's grammar (clap): `harness render | scene | trials | sweep | scan |
//! compare-runs | compare-maps`, and the library options each command's arguments fill.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use harness::campaign::{CampaignOptions, CentreMap, Offsets, VisionMethod};
use harness::trial::{SlidePress, Strategy};
use harness::vision::Detector;
use harness::world::WorldKind;

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
        #[arg(long, default_value_t = 0.0, value_parser = non_negative)]
        noise: f64,
        /// Seed of the noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Line detector.
        #[arg(long, value_enum, default_value_t = DetectorArg::Gradient)]
        detector: DetectorArg,
        /// Only time the detection (both detectors) on this many noisy copies of the image.
        #[arg(long, value_parser = count)]
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
        #[arg(long, default_value_t = 20, value_parser = count)]
        trials: usize,
        /// Half width of the square of true offsets (mm); default: Omega's size_trans.
        #[arg(long, value_parser = positive)]
        range_mm: Option<f64>,
    },
    /// The campaign benchmark: the same random trials on one worker, then on `--jobs`
    /// (default: one per core); prints trials per second of each, the speed-up, whether the
    /// results agree, and the real-time factor. Writes the two reports under `--out`.
    Bench {
        /// Common settings.
        #[command(flatten)]
        run: RunArgs,
        /// Number of trials.
        #[arg(long, default_value_t = 20, value_parser = count)]
        trials: usize,
    },
    /// Trials on a grid of true offsets; plots contacts per offset (the paper's Fig. 10).
    Sweep {
        /// Common settings.
        #[command(flatten)]
        run: RunArgs,
        /// Grid points per axis.
        #[arg(long, default_value_t = 11, value_parser = count)]
        grid: usize,
        /// Half width of the grid (mm); default: Omega's size_trans.
        #[arg(long, value_parser = positive)]
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
        #[arg(long, default_value_t = 0.1, value_parser = positive)]
        step: f64,
        /// Half width of the scanned square (mm); default: Omega's size_trans.
        #[arg(long, value_parser = positive)]
        size: Option<f64>,
        /// Yaw step of part B (degrees) where Omega holds object.rz; default: Omega's
        /// delta_rot.
        #[arg(long, value_parser = positive)]
        yaw_step: Option<f64>,
        /// Half width of the scanned yaws (degrees; 0: part B unturned); default: Omega's
        /// size_rot.
        #[arg(long, value_parser = non_negative)]
        yaw_size: Option<f64>,
    },
    /// Where each scene accepts part A (a centred contact motion, part B moved off by
    /// bisection) against the geometry's insertion limit.
    Boundary {
        /// Task name or task.toml path; default: every task with a scene.
        #[arg(long)]
        task: Option<String>,
        /// Directions over a half turn.
        #[arg(long, default_value_t = 8, value_parser = count)]
        directions: usize,
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
    /// Joins the shards of one campaign (`trials --shard I/N`) into the report that one run
    /// of the whole campaign writes.
    Merge {
        /// The shards: `shard.json` files or the folders holding them.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// Output folder of the report.
        #[arg(long)]
        out: PathBuf,
    },
    /// Campaigns in one Markdown table (their summary.json): task, DOFs, success, contacts
    /// per trial, the last approach's error per DOF.
    Table {
        /// Campaign output folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
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

/// Which line detector finds the edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DetectorArg {
    /// Gradient maxima per row or column, fitted and extended (the paper's Fig. 5).
    Gradient,
    /// The bounded Hough transform restricted to the expected area, then the same refinement.
    Hough,
}

/// How the next approach point is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StrategyArg {
    /// Move to the FMU's estimate after each contact (Algorithm 1).
    Pf,
    /// An Archimedean spiral of contact motions about the nominal goal.
    Spiral,
}

/// Where a slide that found no hole presses again.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SlidePressArg {
    /// At the estimate it crossed (its midpoint): the contact Algorithm 1 makes, after the
    /// sweep.
    Estimate,
    /// Where it stopped, the far end of the spread.
    End,
}

impl From<SlidePressArg> for SlidePress {
    fn from(s: SlidePressArg) -> Self {
        match s {
            SlidePressArg::Estimate => Self::Estimate,
            SlidePressArg::End => Self::End,
        }
    }
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
    /// The map's centre map for the FMU, a finer map of the cells around the goal (default:
    /// computed from the CAD meshes and cached with a computed map whose grid is too coarse
    /// for the fit; none with --map).
    #[arg(long, conflicts_with = "no_centre_map")]
    pub centre_map: Option<PathBuf>,
    /// No centre map, even where the grid is too coarse for the fit.
    #[arg(long)]
    pub no_centre_map: bool,
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
    #[arg(long, default_value_t = 2.0, value_parser = non_negative)]
    pub image_noise: f64,
    /// Line detector for the camera's edges.
    #[arg(long, value_enum, default_value_t = DetectorArg::Gradient)]
    pub detector: DetectorArg,
    /// How the next contact point is chosen.
    #[arg(long, value_enum, default_value_t = StrategyArg::Pf)]
    pub strategy: StrategyArg,
    /// Gaussian F/T sensor noise (0.05 N, 2 mN m).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub sensor_noise: Switch,
    /// Slides under force across the estimate's spread along the line of the last contact
    /// (pf only).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub slide: Switch,
    /// Where a slide that found no hole presses again for its measurement.
    #[arg(long, value_enum, default_value_t = SlidePressArg::Estimate)]
    pub slide_press: SlidePressArg,
    /// Twists under force about z across the yaw's spread once x, y are within the
    /// capture, where the task's yaw is uncertain (pf only).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub twist: Switch,
    /// The FMU.
    #[arg(long, env = "FTFUSION_FMU")]
    pub fmu: Option<PathBuf>,
    /// Most contact motions per trial (default: 30 for pf; enough to cover Omega for spiral).
    #[arg(long, value_parser = count)]
    pub max_contacts: Option<usize>,
    /// Most simulated time per trial (s; default: none, only --max-contacts ends a trial).
    #[arg(long, value_parser = positive)]
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
    /// FMU parameter `sigma_force` (N).
    #[arg(long)]
    pub sigma_force: Option<f64>,
    /// FMU parameter `sigma_depth` (m).
    #[arg(long)]
    pub sigma_depth: Option<f64>,
    /// FMU parameter `mismatch` (share of the measured force's and torque's magnitudes).
    #[arg(long)]
    pub mismatch: Option<f64>,
    /// FMU parameter `mismatch_angle` (rad: how far the map may miss their directions).
    #[arg(long)]
    pub mismatch_angle: Option<f64>,
    /// FMU parameter `mismatch_position` (m: how far the contact may sit from where the
    /// map has it).
    #[arg(long)]
    pub mismatch_position: Option<f64>,
    /// FMU parameter `mismatch_interpolation` (share of the map lookup's own interpolation
    /// error that counts as mismatch; 0: none).
    #[arg(long)]
    pub mismatch_interpolation: Option<f64>,
    /// FMU parameter `mismatch_lever` (m: how far the contact's pressure centre may lie from
    /// the map's; times the force's magnitude, a miss on every torque component).
    #[arg(long)]
    pub mismatch_lever: Option<f64>,
    /// FMU parameter `mismatch_reach` (grid steps: how near an earlier contact a contact
    /// shares the map's miss with it; 0: every contact's mismatch afresh).
    #[arg(long)]
    pub mismatch_reach: Option<f64>,
    /// FMU parameter `tilt_floor` (rad: the relative tilt below which a flat face's wrench
    /// is read along the tilt's direction; 0: the map's tilt step's diagonal; negative: off).
    #[arg(long, allow_negative_numbers = true)]
    pub tilt_floor: Option<f64>,
    /// Measure the scene's misses against the map before the trials (96 presses, cached) and
    /// hand them to the FMU as `mismatch` and `mismatch_angle` where those are not given.
    #[arg(long)]
    pub measure_mismatch: bool,
    /// FMU parameter `lost` (prior probability per measurement that the particles lost the
    /// truth; 0: never redraw).
    #[arg(long)]
    pub lost: Option<f64>,
    /// Where the contact motions happen: the task's MuJoCo scene, or a world that is the
    /// FT-Map itself (the map's wrench at the true offset, part A going in where the
    /// geometry says).
    #[arg(long, value_enum, default_value_t = WorldArg::Mujoco)]
    pub world: WorldArg,
    /// The map that answers the contacts in the map world (default: the FMU's map), e.g. a
    /// measured map (`harness scan`) against the computed one the FMU reads.
    #[arg(long, requires = "world")]
    pub world_map: Option<PathBuf>,
    /// Trials run at once, each worker with its own world, camera and FMU instance; the
    /// results are those of a serial run, in trial order (default: one per core).
    #[arg(long, value_parser = count)]
    pub jobs: Option<usize>,
    /// Run only shard I of N of the trials (`I/N`: trial i where i mod N = I) and write
    /// `shard.json` instead of the report; join the shards with `merge`.
    #[arg(long, value_parser = ftmap::process::parse_shard)]
    pub shard: Option<[usize; 2]>,
}

/// Where a campaign's contact motions happen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WorldArg {
    /// The task's MuJoCo scene.
    Mujoco,
    /// The FT-Map itself.
    Map,
}

impl From<DetectorArg> for Detector {
    fn from(d: DetectorArg) -> Self {
        match d {
            DetectorArg::Gradient => Self::Gradient,
            DetectorArg::Hough => Self::Hough,
        }
    }
}

impl From<StrategyArg> for Strategy {
    fn from(s: StrategyArg) -> Self {
        match s {
            StrategyArg::Pf => Self::Pf,
            StrategyArg::Spiral => Self::Spiral,
        }
    }
}

impl From<VisionMethodArg> for VisionMethod {
    fn from(m: VisionMethodArg) -> Self {
        match m {
            VisionMethodArg::Relative => Self::Relative,
            VisionMethodArg::Recalibration => Self::Recalibration,
        }
    }
}

/// A count given on the command line: a whole number >= 1.
fn count(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}

/// A size given on the command line: a finite number > 0.
fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(v) => Err(format!("{v} must be a finite number > 0")),
        Err(e) => Err(e.to_string()),
    }
}

/// An amount given on the command line: a finite number >= 0.
fn non_negative(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        Ok(v) => Err(format!("{v} must be a finite number >= 0")),
        Err(e) => Err(e.to_string()),
    }
}

/// A length in mm on the command line, in m.
pub fn mm(v: f64) -> f64 {
    v * 1e-3
}

impl RunArgs {
    /// The campaign's options, with its true offsets.
    pub fn options(self, offsets: Offsets) -> CampaignOptions {
        CampaignOptions {
            task: self.task,
            out: self.out,
            seed: self.seed,
            offsets,
            map: self.map,
            centre_map: match (self.centre_map, self.no_centre_map) {
                (Some(file), _) => CentreMap::File(file),
                (None, true) => CentreMap::None,
                (None, false) => CentreMap::Auto,
            },
            vision: self.vision,
            vision_method: self.vision_method.into(),
            sigma_vision: self.sigma_vision,
            image_noise: self.image_noise,
            detector: self.detector.into(),
            strategy: self.strategy.into(),
            sensor_noise: self.sensor_noise == Switch::On,
            slide: self.slide == Switch::On,
            slide_press: self.slide_press.into(),
            twist: self.twist == Switch::On,
            fmu: self.fmu,
            max_contacts: self.max_contacts,
            max_sim_time: self.max_sim_time,
            particles: self.particles,
            iterations: self.iterations,
            sigma_torque: self.sigma_torque,
            sigma_force: self.sigma_force,
            sigma_depth: self.sigma_depth,
            mismatch: self.mismatch,
            mismatch_angle: self.mismatch_angle,
            mismatch_position: self.mismatch_position,
            mismatch_interpolation: self.mismatch_interpolation,
            mismatch_lever: self.mismatch_lever,
            mismatch_reach: self.mismatch_reach,
            tilt_floor: self.tilt_floor,
            measure_mismatch: self.measure_mismatch,
            lost: self.lost,
            world: match self.world {
                WorldArg::Mujoco => WorldKind::Mujoco,
                WorldArg::Map => WorldKind::Map(self.world_map),
            },
            jobs: self.jobs,
            shard: self.shard,
        }
    }
}
