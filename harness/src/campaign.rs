//! Trial campaigns: the options a campaign runs with, setting it up (the task and its
//! simulation, the FT-Map handed to the FMU, the trial limits, the camera, the FMU), random
//! true offsets (or a grid of them), one trial each with a progress bar, and its report
//! (`trials.csv`, `summary.json`, a plot).

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

use ftmap::map::format;
use ftmap::map::resolution::{Coarse, too_coarse};
use ftmap::task::fit::Fit;
use ftmap::task::omega::GridAxis;
use ftmap::{Axis, FtMap, Pose, Task};

use crate::calibration;
use crate::error::{HarnessError, Result, create_dir};
use crate::eye::Eye;
use crate::fmu_driver::{Estimator, Fmu, Settings, default_fmu_path};
use crate::mismatch::{self, Given, Misses, Source};
use crate::plot;
use crate::report::{self, Pace, Summary};
use crate::scene::scene_path;
use crate::sensor::Noise;
use crate::sim::Sim;
use crate::trial::{
    Slide, SlidePress, Strategy, TrialConfig, TrialResult, Truth, Twist, run_trial, spiral,
};
use crate::vision::Detector;
use crate::world::{MapWorld, World, WorldKind};
use model_description::trace;

/// How the FMU evaluates particles by vision (its `vision_method` parameter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum VisionMethod {
    /// Relative feature distances (section III-B-1).
    Relative,
    /// Camera recalibration on the passive part (section III-B-2).
    #[default]
    Recalibration,
}

impl VisionMethod {
    /// The value of the FMU's `vision_method` parameter.
    pub fn parameter(self) -> i32 {
        match self {
            Self::Relative => 0,
            Self::Recalibration => 1,
        }
    }
}

/// The true offsets of a campaign's trials.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Offsets {
    /// `trials` offsets uniform in the square ±`half_width` (m; default Omega's size_trans).
    Random {
        /// Number of trials.
        trials: usize,
        /// Half width of the square (m).
        half_width: Option<f64>,
    },
    /// A `points` x `points` grid over the square ±`half_width` (the paper's Fig. 10).
    Grid {
        /// Grid points per axis.
        points: usize,
        /// Half width of the grid (m; default Omega's size_trans).
        half_width: Option<f64>,
    },
}

/// What a campaign runs with (the `trials` and `sweep` commands' settings, SI units).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CampaignOptions {
    /// Task name or task.toml path.
    pub task: String,
    /// Output folder.
    pub out: PathBuf,
    /// Seed of the offsets, the sensor noise and the FMU.
    pub seed: u64,
    /// The true offsets.
    pub offsets: Offsets,
    /// FT-Map for the FMU (default: the FMU's embedded map for peg_in_hole, else the task's
    /// map computed from its CAD meshes and cached in target/maps/).
    pub map: Option<PathBuf>,
    /// The centre map for the FMU ([`ftmap::map::centre`]).
    #[serde(default)]
    pub centre_map: CentreMap,
    /// Fuse the camera with the F/T sensor (experiment D).
    pub vision: bool,
    /// How the FMU evaluates particles by vision.
    pub vision_method: VisionMethod,
    /// FMU parameter `sigma_vision` (px).
    pub sigma_vision: Option<f64>,
    /// Gaussian image noise (grey levels) added to each rendered image.
    pub image_noise: f64,
    /// Line detector for the camera's edges.
    pub detector: Detector,
    /// How the next contact point is chosen.
    pub strategy: Strategy,
    /// Gaussian F/T sensor noise ([`Noise::TYPICAL`]) on or off.
    pub sensor_noise: bool,
    /// Slides under force across the estimate's spread ([`crate::trial::next_motion`]).
    pub slide: bool,
    /// Where a slide that found no hole presses for its measurement.
    #[serde(default)]
    pub slide_press: SlidePress,
    /// Twists under force about z where the yaw is uncertain ([`crate::trial::next_motion`]).
    pub twist: bool,
    /// The FMU (default: [`default_fmu_path`]).
    pub fmu: Option<PathBuf>,
    /// Most contact motions per trial (default: 30 for pf; enough to cover Omega for spiral).
    pub max_contacts: Option<usize>,
    /// Most simulated time per trial (s; default: none, the trial ends after `max_contacts`
    /// motions, each of them bounded by [`crate::sim::MAX_TIME`]).
    pub max_sim_time: Option<f64>,
    /// FMU parameter `particles`.
    pub particles: Option<i32>,
    /// FMU parameter `iterations`.
    pub iterations: Option<i32>,
    /// FMU parameter `sigma_torque` (N m).
    pub sigma_torque: Option<f64>,
    /// FMU parameter `sigma_force` (N).
    pub sigma_force: Option<f64>,
    /// FMU parameter `sigma_depth` (m).
    pub sigma_depth: Option<f64>,
    /// FMU parameter `mismatch` (share of the measured force's and torque's magnitudes).
    pub mismatch: Option<f64>,
    /// FMU parameter `mismatch_angle` (rad).
    pub mismatch_angle: Option<f64>,
    /// FMU parameter `mismatch_position` (m).
    #[serde(default)]
    pub mismatch_position: Option<f64>,
    /// FMU parameter `mismatch_interpolation` (share of the lookup's interpolation error).
    #[serde(default)]
    pub mismatch_interpolation: Option<f64>,
    /// FMU parameter `mismatch_lever` (m: how far the contact's pressure centre may lie from
    /// the map's).
    #[serde(default)]
    pub mismatch_lever: Option<f64>,
    /// FMU parameter `mismatch_reach` (grid steps; 0: every contact's mismatch afresh).
    #[serde(default)]
    pub mismatch_reach: Option<f64>,
    /// FMU parameter `tilt_floor` (rad; negative: off).
    #[serde(default)]
    pub tilt_floor: Option<f64>,
    /// Measure the scene's misses against the map before the trials and hand them to the
    /// FMU as `mismatch` and `mismatch_angle` where those are not given ([`mismatch`]).
    #[serde(default)]
    pub measure_mismatch: bool,
    /// FMU parameter `lost`.
    pub lost: Option<f64>,
    /// Where the contact motions happen.
    pub world: WorldKind,
    /// Trials run at once, each worker with its own world, camera and FMU instance
    /// (default: one per core).
    pub jobs: Option<usize>,
    /// Run only shard I of N of the trials (trial i where i mod N = I), for `merge`.
    pub shard: Option<[usize; 2]>,
}

/// Which centre map the FMU reads besides the map.
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CentreMap {
    /// Computed from the CAD meshes and cached with a map computed from them, where its
    /// grid is too coarse for the fit ([`ftmap::map::centre::centre_task`]); none with a
    /// given map.
    #[default]
    Auto,
    /// None.
    None,
    /// This file.
    File(PathBuf),
}

/// What setting a campaign up did that its user should hear of, in order.
#[derive(Debug, Clone, PartialEq)]
pub enum SetupNote {
    /// The task's FT-Map from the cache (`computed: None`) or computed from its CAD meshes
    /// in `computed` seconds.
    Map {
        /// The map file.
        path: PathBuf,
        /// Seconds the computation took, when the map was not cached.
        computed: Option<f64>,
    },
    /// The map's centre map from the cache (`computed: None`) or computed from the CAD
    /// meshes in `computed` seconds.
    Centre {
        /// The centre map file.
        path: PathBuf,
        /// Seconds the computation took, when the map was not cached.
        computed: Option<f64>,
    },
    /// The camera's vision model, written for the FMU.
    VisionModel(PathBuf),
    /// The map is too coarse for the fit's clearance.
    Coarse(Coarse),
    /// The scene's misses against the map, from the cache (`seconds: None`) or measured in
    /// `seconds`, handed to the FMU as its `mismatch` and `mismatch_angle` where the user did
    /// not set them ([`mismatch`]).
    Mismatch {
        /// What the presses measured.
        misses: Misses,
        /// Seconds the presses took, when they were not cached.
        seconds: Option<f64>,
    },
    /// The scene's misses could not be measured: the FMU's defaults stand.
    MismatchUnmeasured(String),
}

impl fmt::Display for SetupNote {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Map {
                path,
                computed: Some(s),
            } => write!(
                f,
                "map {} (computed from the CAD meshes in {s:.1} s)",
                path.display()
            ),
            Self::Map {
                path,
                computed: None,
            } => write!(f, "map {} (cached)", path.display()),
            Self::Centre { path, computed } => write!(
                f,
                "centre map {} ({})",
                path.display(),
                computed.map_or("cached".into(), |s| format!(
                    "computed from the CAD meshes in {s:.1} s"
                ))
            ),
            Self::VisionModel(path) => write!(
                f,
                "vision model {} (camera as MuJoCo places it)",
                path.display()
            ),
            Self::Coarse(coarse) => write!(f, "warning: {coarse}"),
            Self::Mismatch { misses, seconds } => write!(
                f,
                "model mismatch of the scene against the map ({}): {misses}",
                seconds.map_or("cached".into(), |s| format!("measured in {s:.1} s"))
            ),
            Self::MismatchUnmeasured(why) => write!(
                f,
                "model mismatch not measured ({why}): the FMU's defaults stand"
            ),
        }
    }
}

/// The trials a campaign ran, and how long they took on how many workers.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// One result per true offset.
    pub results: Vec<TrialResult>,
    /// How long they took, on how many workers.
    pub pace: Pace,
    /// The `mismatch` and `mismatch_angle` the FMU ran with (`None` without the FMU).
    pub mismatch: Option<Given>,
}

/// A plot a campaign wrote.
#[derive(Debug, Clone, PartialEq)]
pub enum CampaignPlot {
    /// `estimates.png`: one trial's estimate and spread after its first measurements; and
    /// `particles.png`: the first trial's particles, from the FMU's trace.
    Estimates {
        /// The image file.
        path: PathBuf,
        /// The trial shown.
        trial: usize,
        /// The particles' image file, where the first trial made a measurement.
        particles: Option<PathBuf>,
    },
    /// `sweep.png`: contacts per true offset.
    Sweep {
        /// The image file.
        path: PathBuf,
    },
}

impl fmt::Display for CampaignPlot {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Estimates {
                path,
                trial,
                particles,
            } => {
                write!(
                    f,
                    "plot {} (trial {trial}: estimate and 1/2-sigma ellipse after its first three measurements)",
                    path.display()
                )?;
                match particles {
                    Some(p) => write!(
                        f,
                        "\nplot {} (trial 0: the FMU's particles after its first three measurements, from trace.csv)",
                        p.display()
                    ),
                    None => Ok(()),
                }
            }
            Self::Sweep { path } => write!(f, "plot {}", path.display()),
        }
    }
}

/// A campaign apart from where it runs: its task and options. It draws the trials' true
/// offsets and writes the report, of the campaign that ran or of its merged shards.
pub struct Plan {
    task: Task,
    options: CampaignOptions,
}

impl Plan {
    /// The plan of `options`.
    ///
    /// # Errors
    /// When the task cannot be read.
    pub fn new(options: CampaignOptions) -> Result<Self> {
        Ok(Self {
            task: Task::find(&options.task)?,
            options,
        })
    }

    /// The task.
    pub fn task(&self) -> &Task {
        &self.task
    }

    /// The options.
    pub fn options(&self) -> &CampaignOptions {
        &self.options
    }

    /// `<out>/trace.csv` (absolute), where the FMU traces a random campaign's first trial.
    ///
    /// # Errors
    /// When the output folder has no absolute path.
    pub fn trace_file(&self) -> Result<Option<PathBuf>> {
        match (self.options.strategy, &self.options.offsets) {
            (Strategy::Pf, Offsets::Random { .. }) => Ok(Some(
                std::path::absolute(self.options.out.join("trace.csv"))
                    .map_err(|e| HarnessError::io(&self.options.out, e))?,
            )),
            _ => Ok(None),
        }
    }

    /// Half width of the square of true offsets (m).
    fn half_width(&self) -> f64 {
        let (Offsets::Random { half_width, .. } | Offsets::Grid { half_width, .. }) =
            self.options.offsets;
        half_width.unwrap_or(self.task.omega.size_trans)
    }

    /// Trials of the whole campaign (its shards' together).
    pub fn trials(&self) -> usize {
        match self.options.offsets {
            Offsets::Random { trials, .. } => trials,
            Offsets::Grid { points, .. } => points * points,
        }
    }

    /// The true offsets of the trials (m): object offsets as asked, grip offsets uniform
    /// over the task's grip bounds where its grip is uncertain (from a stream of their own,
    /// so that the object offsets of a seed are those of a task without).
    pub fn truths(&self) -> Vec<Truth> {
        let size = self.half_width();
        let objects = match self.options.offsets {
            Offsets::Random { trials, .. } => random_offsets(trials, size, self.options.seed),
            Offsets::Grid { points, .. } => grid_offsets(points, size),
        };
        truths_at(&self.task, objects, None, self.options.seed)
    }

    /// Writes `<out>/trials.csv`, `measurements.csv`, `first_images.csv` (with a camera: the
    /// estimate after each trial's first image, as measurement 0) and `summary.json`; returns
    /// the summary.
    ///
    /// # Errors
    /// When the folder or a file cannot be written.
    pub fn write_report(&self, outcome: &Outcome) -> Result<Summary> {
        let out = &self.options.out;
        create_dir(out)?;
        report::write_trials_csv(&out.join("trials.csv"), &outcome.results)?;
        report::write_measurements_csv(
            &out.join("measurements.csv"),
            &calibration::samples(&outcome.results),
        )?;
        let first = calibration::first_images(&outcome.results);
        if !first.is_empty() {
            report::write_measurements_csv(&out.join("first_images.csv"), &first)?;
        }
        let summary = report::summarize(
            &self.task,
            &self.options.world,
            self.options.strategy,
            self.options.sensor_noise,
            self.options.vision,
            &outcome.results,
            outcome.pace,
        )
        .with_mismatch(outcome.mismatch);
        report::write_summary(&out.join("summary.json"), &summary)?;
        Ok(summary)
    }

    /// Draws the campaign's plot: for random offsets with the estimator, `estimates.png` of
    /// the first trial that needed a second contact measurement (else the first trial); for
    /// a grid, `sweep.png`. `None` when there is nothing to draw.
    ///
    /// # Errors
    /// When the image cannot be written.
    pub fn plot(&self, outcome: &Outcome) -> Result<Option<CampaignPlot>> {
        let results = &outcome.results;
        match self.options.offsets {
            Offsets::Random { .. } if self.options.strategy == Strategy::Pf => {
                let trial = results
                    .iter()
                    .position(|r| r.measurements() >= 2)
                    .unwrap_or(0);
                let Some(r) = results.get(trial) else {
                    return Ok(None);
                };
                let path = self.options.out.join("estimates.png");
                plot::estimates(&path, r, self.task.omega.size_trans)?;
                let particles = self.plot_particles(results)?;
                Ok(Some(CampaignPlot::Estimates {
                    path,
                    trial,
                    particles,
                }))
            }
            Offsets::Random { .. } => Ok(None),
            Offsets::Grid { points, .. } => {
                let size = self.half_width();
                let cell = if points > 1 {
                    2.0 * size / (points - 1) as f64
                } else {
                    2.0 * size
                };
                let path = self.options.out.join("sweep.png");
                plot::sweep(&path, results, size, cell)?;
                Ok(Some(CampaignPlot::Sweep { path }))
            }
        }
    }

    /// `particles.png` of the first trial from its trace (`trace.csv`), where it made a
    /// measurement.
    ///
    /// # Errors
    /// When the trace cannot be read or the image written.
    fn plot_particles(&self, results: &[TrialResult]) -> Result<Option<PathBuf>> {
        let (Some(file), Some(first)) = (self.trace_file()?, results.first()) else {
            return Ok(None);
        };
        if first.measurements() == 0 {
            return Ok(None);
        }
        let text = std::fs::File::open(&file).map_err(|e| HarnessError::io(&file, e))?;
        let measurements = trace::read(text).map_err(|e| HarnessError::Invalid {
            what: "trace",
            reason: format!("{}: {e}", file.display()),
        })?;
        let Some(m) = measurements.first() else {
            return Ok(None);
        };
        let truth: Vec<f64> = m
            .dofs
            .iter()
            .map(|d| match d.as_str() {
                "object.x" => first.offset[0],
                "object.y" => first.offset[1],
                "object.rx" => first.rot[0],
                "object.ry" => first.rot[1],
                "object.rz" => first.rot[2],
                "grip.x" => first.grip[0],
                "grip.y" => first.grip[1],
                _ => 0.0,
            })
            .collect();
        let path = self.options.out.join("particles.png");
        plot::particles(&path, &measurements, &truth)?;
        Ok(Some(path))
    }
}

/// A campaign set up and ready to run: the task, its simulation, the trial limits and
/// settings, the camera and the FMU.
pub struct Campaign {
    plan: Plan,
    /// What each further worker opens its own world from.
    source: WorldSource,
    /// The first worker's rig, opened with the campaign (so that it fails early).
    rig: Rig,
    config: TrialConfig,
    fmu: Option<Fmu>,
}

/// A worker's work cell: the world its trials run in and, with the camera, its eye.
pub struct Rig {
    /// Where the contact motions happen.
    pub world: Box<dyn World>,
    /// The camera, in experiment D.
    pub eye: Option<Eye>,
}

/// What a campaign's worlds are opened from.
enum WorldSource {
    /// The task's MuJoCo scene.
    Mujoco,
    /// An FT-Map as the world, for parts that fit as `fit` says.
    Map(Box<FtMap>, Arc<dyn Fit>),
}

impl WorldSource {
    /// A new world of this source for `task`.
    fn open(&self, task: &Task) -> Result<Box<dyn World>> {
        Ok(match self {
            Self::Mujoco => Box::new(Sim::of_task(task)?),
            Self::Map(map, fit) => Box::new(MapWorld::new(FtMap::clone(map), fit.clone())?),
        })
    }
}

impl Campaign {
    /// Sets a campaign up: opens the task and its scene, resolves the FT-Map, builds the
    /// trial limits, opens the camera (writing `<out>/vision.json`) and loads the FMU,
    /// telling `note` what a user should hear of as it goes.
    ///
    /// # Errors
    /// When the task, its scene, map, camera or the FMU cannot be had, or the camera is asked
    /// for with the spiral search.
    pub fn open(options: CampaignOptions, note: &mut dyn FnMut(SetupNote)) -> Result<Self> {
        let plan = Plan::new(options)?;
        let (task, options) = (&plan.task, &plan.options);
        check_dofs(task, options.vision)?;
        let (map, centre) = resolve_map(options, task, note)?;
        let fit = task.fit()?;
        let source = match &options.world {
            WorldKind::Mujoco => WorldSource::Mujoco,
            WorldKind::Map(file) => {
                let file = match file.as_ref().or(map.as_ref()) {
                    Some(f) => f.clone(),
                    None => cached_map(task, note)?,
                };
                let (world_map, _) = format::load_any(&file)?;
                WorldSource::Map(Box::new(world_map), fit.clone())
            }
        };
        let mut world = source.open(task)?;
        let mut config = trial_config(&plan, fit.as_ref(), map, centre)?;
        if options.measure_mismatch && options.strategy == Strategy::Pf {
            match source {
                WorldSource::Mujoco => {
                    measure_mismatch(
                        &plan,
                        world.as_mut(),
                        fit.clone(),
                        &mut config.settings,
                        note,
                    )?;
                }
                WorldSource::Map(..) => note(SetupNote::MismatchUnmeasured(
                    "the world is the map: it misses nothing".into(),
                )),
            }
        }
        let eye = open_eye(options, task, &mut config, note)?;
        let fmu = match options.strategy {
            Strategy::Pf => {
                let path = options.fmu.clone().unwrap_or_else(default_fmu_path);
                Some(Fmu::load(&path)?)
            }
            Strategy::Spiral => None,
        };
        Ok(Self {
            plan,
            source,
            rig: Rig { world, eye },
            config,
            fmu,
        })
    }

    /// What the campaign is: its task and options.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Runs the campaign's trials (those of its shard, when it is one) on its workers, with
    /// a progress bar.
    ///
    /// # Errors
    /// When a worker's world or camera cannot be opened, or the FMU or rendering fails.
    pub fn run(&mut self) -> Result<Outcome> {
        let truths = self.plan.truths();
        let (task, options) = (&self.plan.task, &self.plan.options);
        // The FMU appends to its trace: start it afresh.
        if let Some(file) = &self.config.settings.trace {
            create_dir(&options.out)?;
            match std::fs::remove_file(file) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(HarnessError::io(file, e));
                }
                _ => {}
            }
        }
        let set = TrialSet {
            truths: &truths,
            seed: options.seed,
            shard: options.shard.unwrap_or([0, 1]),
        };
        let jobs = options
            .jobs
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from))
            .clamp(1, set.indices().len().max(1));
        let source = &self.source;
        let open = || -> Result<Rig> {
            let eye = match options.vision {
                true => Some(Eye::open(task, options.image_noise, options.detector)?),
                false => None,
            };
            Ok(Rig {
                world: source.open(task)?,
                eye,
            })
        };
        let (results, wall) = timed(|| {
            run_parallel(
                &mut self.rig,
                jobs,
                &open,
                self.fmu.as_ref(),
                &self.config,
                set,
            )
        });
        Ok(Outcome {
            results: results?,
            pace: Pace { wall, jobs },
            mismatch: self.fmu.is_some().then(|| self.mismatch_given()),
        })
    }

    /// The `mismatch` and `mismatch_angle` the FMU runs with, by where they came from.
    fn mismatch_given(&self) -> Given {
        let source = |user: Option<f64>, used: Option<f64>| match (user, used) {
            (Some(v), _) => Source::Given(v),
            (None, Some(v)) => Source::Measured(v),
            (None, None) => Source::Default,
        };
        let (options, settings) = (&self.plan.options, &self.config.settings);
        Given {
            along: source(options.mismatch, settings.mismatch),
            across: source(options.mismatch_angle, settings.mismatch_angle),
        }
    }
}

/// The FT-Map file for the FMU: the given one, none for peg_in_hole (the FMU's embedded
/// map), else the task's map computed from its CAD meshes and cached in target/maps/; and
/// its centre map, where one is given or computed ([`CentreMap`]).
fn resolve_map(
    options: &CampaignOptions,
    task: &Task,
    note: &mut dyn FnMut(SetupNote),
) -> Result<(Option<PathBuf>, Option<PathBuf>)> {
    let absolute = |m: &Path| std::path::absolute(m).map_err(|e| HarnessError::io(m, e));
    let map = match &options.map {
        Some(m) => Some(absolute(m)?),
        None if task.name == "peg_in_hole" => None,
        None => Some(cached_map(task, note)?),
    };
    let centre = match &options.centre_map {
        CentreMap::File(c) => Some(absolute(c)?),
        _ => None,
    };
    if let Some(m) = map.iter().chain(&centre).find(|m| !m.is_file()) {
        return Err(HarnessError::MapMissing {
            path: m.clone(),
            task: task.name.clone(),
        });
    }
    // What the FMU will read: the map's own grid and pixel (a file the FMU cannot read is
    // its to report), or the task's for the embedded map.
    let loaded = map
        .as_deref()
        .and_then(|m| format::load_any(m).ok())
        .map(|(m, _)| m);
    let centre = match (&options.centre_map, &loaded) {
        (CentreMap::Auto, Some(m)) if options.map.is_none() => cached_centre(task, m, note)?,
        _ => centre,
    };
    let coarse = match &loaded {
        Some(m) => too_coarse(m.grid(), m.meta().pixel, m.meta().clearance),
        None if map.is_some() => Vec::new(),
        None => too_coarse(
            &task.grid().map_err(|source| HarnessError::TaskMap {
                task: task.name.clone(),
                source,
            })?,
            task.depth.pixel,
            task.geometry.as_ref().map(|g| g.clearance()),
        ),
    };
    // A centre map resolves the fit where the grid's step does not.
    coarse
        .into_iter()
        .filter(|c| centre.is_none() || !matches!(c, Coarse::Step { .. }))
        .for_each(|c| note(SetupNote::Coarse(c)));
    Ok((map, centre))
}

/// The centre map of `task`, whose map computed from CAD is `map`, from the cache in
/// target/maps/ when it is there; `None` where the map's grid resolves the fit.
fn cached_centre(
    task: &Task,
    map: &ftmap::FtMap,
    note: &mut dyn FnMut(SetupNote),
) -> Result<Option<PathBuf>> {
    let t0 = Instant::now();
    let found = ftmap::generate::cached_centre(task, map, &maps_dir()).map_err(|source| {
        HarnessError::TaskMap {
            task: task.name.clone(),
            source,
        }
    })?;
    Ok(found.map(|(path, computed)| {
        note(SetupNote::Centre {
            path: path.clone(),
            computed: computed.then(|| t0.elapsed().as_secs_f64()),
        });
        path
    }))
}

/// Where computed maps are cached: target/maps/.
fn maps_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/maps")
}

/// The task's FT-Map computed from its CAD meshes, from the cache in target/maps/ when it
/// is there.
fn cached_map(task: &Task, note: &mut dyn FnMut(SetupNote)) -> Result<PathBuf> {
    let t0 = Instant::now();
    let (path, computed) =
        ftmap::generate::cached(task, &maps_dir()).map_err(|source| HarnessError::TaskMap {
            task: task.name.clone(),
            source,
        })?;
    note(SetupNote::Map {
        path: path.clone(),
        computed: computed.then(|| t0.elapsed().as_secs_f64()),
    });
    Ok(path)
}

/// The twist of a task whose yaw is uncertain, from its map (the fit's yaw play there) and
/// geometry; `None` for another task, or where the map shows no play or is the FMU's own.
fn twist_setup(task: &Task, fit: &dyn Fit, map: Option<&Path>) -> Result<Option<Twist>> {
    let Some(file) = map else {
        return Ok(None);
    };
    let grid = task.grid()?;
    let Some(k) = grid.axis_of(ftmap::Dof::new(Pose::Object, Axis::Rz)) else {
        return Ok(None);
    };
    let (m, _) = format::load_any(file)?;
    let play = m.rotational_play(k);
    Ok((play > 0.0).then(|| Twist {
        clearance: fit.clearance(),
        play,
        period: task
            .omega
            .symmetry
            .map(|n| std::f64::consts::TAU / f64::from(n)),
    }))
}

/// Presses per set of true offsets the scene's misses are measured at ([`mismatch`]).
const MISMATCH_PRESSES: usize = 48;
/// Seed of the true offsets the misses are measured at, the same for every campaign (its
/// shards and workers alike).
const MISMATCH_SEED: u64 = 0x6d69_7373;
/// Revision of the measured misses' file: a cached file of another is measured again.
const MISMATCH_REVISION: u32 = 3;
/// Half width of the square near the goal whose true offsets stand for the later contacts,
/// in the map's grid steps (a first contact leaves the estimate about a step off); part B's
/// rotations there lie within as many of their own steps of zero, as the TCP's do of part
/// B's once it follows the estimate.
const NEAR_STEPS: f64 = 2.0;

/// Measures the scene's misses against the map the FMU reads ([`mismatch::measure`], cached
/// in target/maps/ under the files they depend on) and sets from them those of the FMU's
/// `mismatch` and `mismatch_angle` that the user left unset; where the map world cannot
/// read the map (tilts) or no press rested with a torque, says so and leaves the FMU's
/// defaults.
///
/// # Errors
/// When the map cannot be had or loaded, or the scene cannot take a true offset.
fn measure_mismatch(
    plan: &Plan,
    scene: &mut dyn World,
    fit: Arc<dyn Fit>,
    settings: &mut Settings,
    note: &mut dyn FnMut(SetupNote),
) -> Result<()> {
    if settings.mismatch.is_some() && settings.mismatch_angle.is_some() {
        return Ok(());
    }
    let file = match &settings.map {
        Some(m) => m.clone(),
        None => cached_map(&plan.task, note)?,
    };
    let cache = mismatch_cache(plan, &file)?;
    let cached = std::fs::read_to_string(&cache)
        .ok()
        .and_then(|text| serde_json::from_str::<Misses>(&text).ok());
    let (misses, seconds) = match cached {
        Some(misses) => (misses, None),
        None => {
            let t0 = Instant::now();
            let (map, _) = format::load_any(&file)?;
            let step = map
                .grid()
                .axis_of(ftmap::Dof::new(Pose::Object, Axis::X))
                .map(|k| map.grid().axes()[k].step);
            let (mut world, step) = match (MapWorld::new(map, fit), step) {
                (Ok(w), Some(step)) => (w, step),
                (Err(e), _) => {
                    note(SetupNote::MismatchUnmeasured(e.to_string()));
                    return Ok(());
                }
                (_, None) => {
                    note(SetupNote::MismatchUnmeasured(
                        "the map has no object.x".into(),
                    ));
                    return Ok(());
                }
            };
            let draw = |half_width: f64, near: Option<f64>, seed: u64| {
                let objects = random_offsets(MISMATCH_PRESSES, half_width, seed);
                truths_at(&plan.task, objects, near, seed)
            };
            let omega = draw(plan.half_width(), None, MISMATCH_SEED);
            let near = draw(NEAR_STEPS * step, Some(NEAR_STEPS), MISMATCH_SEED ^ 1);
            let misses = mismatch::measure(scene, &mut world, &omega, &near)?;
            create_dir(&maps_dir())?;
            let text =
                serde_json::to_string_pretty(&misses).map_err(|source| HarnessError::Json {
                    path: cache.clone(),
                    source,
                })?;
            std::fs::write(&cache, text).map_err(|e| HarnessError::io(&cache, e))?;
            (misses, Some(t0.elapsed().as_secs_f64()))
        }
    };
    let pooled = misses.pooled();
    if pooled.presses == 0 {
        note(SetupNote::MismatchUnmeasured(
            "no press rested with a torque".into(),
        ));
        return Ok(());
    }
    settings.mismatch.get_or_insert(pooled.along);
    settings.mismatch_angle.get_or_insert(pooled.across);
    note(SetupNote::Mismatch { misses, seconds });
    Ok(())
}

/// The cache file of a campaign's measured misses against the map file `map`: named by the
/// hash of what they depend on (the task, its meshes and scene, the map, the presses' half
/// width and the harness's version).
fn mismatch_cache(plan: &Plan, map: &Path) -> Result<PathBuf> {
    let task = &plan.task;
    let hash = ftmap::file::cache_hash(
        &[
            &task.path,
            &task.part_a.mesh,
            &task.part_b.mesh,
            &scene_path(task),
            map,
        ],
        &[
            env!("CARGO_PKG_VERSION").as_bytes(),
            &plan.half_width().to_le_bytes(),
            &MISMATCH_PRESSES.to_le_bytes(),
            &MISMATCH_SEED.to_le_bytes(),
            &NEAR_STEPS.to_le_bytes(),
            &MISMATCH_REVISION.to_le_bytes(),
        ],
    )?;
    Ok(maps_dir().join(format!("{}-{hash}.mismatch.json", task.name)))
}

/// The trial limits and FMU settings of a campaign, with the FT-Map file `map`.
fn trial_config(
    plan: &Plan,
    fit: &dyn Fit,
    map: Option<PathBuf>,
    centre_map: Option<PathBuf>,
) -> Result<TrialConfig> {
    let (task, options) = (&plan.task, &plan.options);
    let size = task.omega.size_trans;
    // The spiral's pitch stays below twice the radial clearance.
    let spiral_step = 1.6 * fit.clearance();
    let spiral_radius = size * 2f64.sqrt();
    let spiral_points = spiral(spiral_step, spiral_radius).len();
    let max_contacts = options.max_contacts.unwrap_or(match options.strategy {
        Strategy::Pf => 30,
        Strategy::Spiral => spiral_points,
    });
    Ok(TrialConfig {
        strategy: options.strategy,
        max_contacts,
        max_sim_time: options.max_sim_time.unwrap_or(f64::INFINITY),
        slide: options.slide.then(|| Slide {
            clearance: fit.clearance(),
            press: options.slide_press,
        }),
        symmetry: task.omega.symmetry,
        twist: if options.twist {
            twist_setup(task, fit, map.as_deref())?
        } else {
            None
        },
        noise: if options.sensor_noise {
            Noise::TYPICAL
        } else {
            Noise::NONE
        },
        spiral_step,
        spiral_radius,
        settings: Settings {
            map,
            centre_map,
            particles: options.particles,
            iterations: options.iterations,
            sigma_torque: options.sigma_torque,
            sigma_force: options.sigma_force,
            sigma_depth: options.sigma_depth,
            mismatch: options.mismatch,
            mismatch_angle: options.mismatch_angle,
            mismatch_position: options.mismatch_position,
            mismatch_interpolation: options.mismatch_interpolation,
            mismatch_lever: options.mismatch_lever,
            mismatch_reach: options.mismatch_reach,
            tilt_floor: options.tilt_floor,
            lost: options.lost,
            sigma_vision: options.sigma_vision,
            vision_method: Some(options.vision_method.parameter()),
            trace: plan.trace_file()?,
            ..Settings::default()
        },
    })
}

/// The camera, when the options ask for it: its vision model is written to
/// `<out>/vision.json` and handed to the FMU through `config`.
fn open_eye(
    options: &CampaignOptions,
    task: &Task,
    config: &mut TrialConfig,
    note: &mut dyn FnMut(SetupNote),
) -> Result<Option<Eye>> {
    if !options.vision {
        return Ok(None);
    }
    if options.strategy != Strategy::Pf {
        return Err(HarnessError::VisionNeedsEstimator);
    }
    let eye = Eye::open(task, options.image_noise, options.detector)?;
    create_dir(&options.out)?;
    let file = options.out.join("vision.json");
    let path = std::path::absolute(&file).map_err(|e| HarnessError::io(file, e))?;
    eye.model().save(&path)?;
    note(SetupNote::VisionModel(path.clone()));
    config.settings.vision = Some(path);
    Ok(Some(eye))
}

/// Refuses a task whose uncertain DOFs the work cell cannot set: its robot moves x and y
/// (z presses), part B moves in x and y, and the hand holds part A off-centre in x and y.
fn check_dofs(task: &Task, vision: bool) -> Result<()> {
    let dofs = task.dofs()?;
    // Object rotations turn part B and the robot's wrist; grip rotations are not modelled.
    let supported = |d: &ftmap::Dof| {
        matches!(d.axis, Axis::X | Axis::Y) || (d.pose == Pose::Object && d.axis.is_rotation())
    };
    let has = |pose, axis| dofs.iter().any(|d| d.pose == pose && d.axis == axis);
    let unsupported: Vec<String> = dofs
        .iter()
        .filter(|d| !supported(d))
        .map(|d| d.to_string())
        .collect();
    let reason = if !unsupported.is_empty() {
        format!(
            "the work cell sets object and grip offsets in x and y and object rotations only; task {} also has {}",
            task.name,
            unsupported.join(", ")
        )
    } else if !(has(Pose::Object, Axis::X) && has(Pose::Object, Axis::Y)) {
        format!(
            "task {} must have object.x and object.y uncertain",
            task.name
        )
    } else if vision && dofs.iter().any(|d| d.pose == Pose::Grip || d.is_rotation()) {
        format!(
            "the camera's model places part A on the TCP, unturned: task {} has an uncertain grip or rotation",
            task.name
        )
    } else if has(Pose::Grip, Axis::X) && dofs.iter().any(|d| d.is_rotation()) {
        format!(
            "the work cell does not turn a part held off-centre: task {} has an uncertain grip and rotation",
            task.name
        )
    } else {
        return Ok(());
    };
    Err(HarnessError::Invalid {
        what: "campaign",
        reason,
    })
}

/// Mixed into a campaign's seed for its grip offsets.
const GRIP_STREAM: u64 = 0x6772_6970;
/// Mixed into a campaign's seed for its object rotations.
const ROTATION_STREAM: u64 = 0x726f_7461;

/// `n` rotation vectors (rad) from `seed`: on each of the grid's object rotation axes
/// uniform over the axis's span (one whole period where it wraps), or over the part of it
/// within `within` of the axis's steps of zero where given; zero on the other axes.
pub fn random_rotations(
    n: usize,
    axes: &[GridAxis],
    within: Option<f64>,
    seed: u64,
) -> Vec<[f64; 3]> {
    let mut rng = StdRng::seed_from_u64(seed);
    let spans: Vec<(usize, f64, f64)> = axes
        .iter()
        .filter(|a| a.dof.pose == Pose::Object && a.dof.is_rotation())
        .map(|a| {
            let reach = within.map_or(f64::INFINITY, |steps| steps * a.step);
            (
                a.dof.axis.index() - 3,
                a.min.max(-reach),
                a.max().min(reach),
            )
        })
        .collect();
    (0..n)
        .map(|_| {
            let mut r = [0.0; 3];
            for &(k, lo, hi) in &spans {
                r[k] = rng.random_range(lo..=hi);
            }
            r
        })
        .collect()
}

/// Each of the object offsets `objects` with a grip offset and a rotation of part B drawn
/// from `seed` over what the task's grid leaves uncertain (none where it is certain), the
/// rotations within `near` of their steps of zero where given ([`random_rotations`]).
fn truths_at(task: &Task, objects: Vec<[f64; 2]>, near: Option<f64>, seed: u64) -> Vec<Truth> {
    let axes = task.grid().map(|g| g.axes().to_vec()).unwrap_or_default();
    // The grid's own grip bound (the task's `size_grip`, its default resolved there).
    let grip_bound = axes
        .iter()
        .find(|a| a.dof.pose == Pose::Grip)
        .map(|a| a.max());
    let grips = match grip_bound {
        Some(bound) => random_offsets(objects.len(), bound, seed ^ GRIP_STREAM),
        None => vec![[0.0; 2]; objects.len()],
    };
    let rotations = random_rotations(objects.len(), &axes, near, seed ^ ROTATION_STREAM);
    objects
        .into_iter()
        .zip(grips)
        .zip(rotations)
        .map(|((object, grip), rot)| Truth { object, grip, rot })
        .collect()
}

/// True offsets uniform in the square ±`size` (m), from `seed`.
pub fn random_offsets(n: usize, size: f64, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            [
                rng.random_range(-size..=size),
                rng.random_range(-size..=size),
            ]
        })
        .collect()
}

/// True offsets on a `k` x `k` grid over the square ±`size` (m).
pub fn grid_offsets(k: usize, size: f64) -> Vec<[f64; 2]> {
    let at = |i: usize| {
        if k < 2 {
            0.0
        } else {
            -size + 2.0 * size * i as f64 / (k - 1) as f64
        }
    };
    (0..k)
        .flat_map(|j| (0..k).map(move |i| [at(i), at(j)]))
        .collect()
}

/// The trials a run takes of a campaign: trial i, with true offsets `truths[i]` and seed
/// `seed + i`, for each i of shard I of N (i mod N = I; shard 0 of 1 is every trial).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialSet<'a> {
    /// The true offsets of the whole campaign's trials.
    pub truths: &'a [Truth],
    /// The campaign's seed.
    pub seed: u64,
    /// Shard I of N.
    pub shard: [usize; 2],
}

impl<'a> TrialSet<'a> {
    /// Every trial of `truths`.
    pub fn all(truths: &'a [Truth], seed: u64) -> Self {
        Self {
            truths,
            seed,
            shard: [0, 1],
        }
    }

    /// The indices of the trials taken, ascending.
    pub fn indices(&self) -> Vec<usize> {
        shard_indices(self.shard, self.truths.len()).collect()
    }
}

/// The trial indices of shard I of N of `trials` trials: i mod N = I, ascending.
pub fn shard_indices([i, n]: [usize; 2], trials: usize) -> impl Iterator<Item = usize> {
    (i..trials).step_by(n.max(1))
}

/// Runs one trial per set of true offsets, in order, on one world; trial i uses seed
/// `seed + i`; `eye` adds the camera.
///
/// # Errors
/// When the FMU or rendering fails.
pub fn run_campaign(
    sim: &mut dyn World,
    fmu: Option<&Fmu>,
    eye: Option<&mut Eye>,
    cfg: &TrialConfig,
    truths: &[Truth],
    seed: u64,
) -> Result<Vec<TrialResult>> {
    let _held = hold_maps(fmu, cfg)?;
    let queue = Queue::new(TrialSet::all(truths, seed), cfg.strategy);
    let done = queue.work(sim, fmu, eye, cfg);
    queue.finish(vec![done])
}

/// An estimator instance held for a whole run, which no trial uses: the FMU shares a map
/// file between the instances that hold it and frees it with the last one, so without it
/// each trial, instantiated after the one before was freed, read its map again (the
/// 4-DOF map: 327 MB, about 0.4 s a trial). `None` where the trials use no FMU.
///
/// # Errors
/// When the FMU refuses to instantiate or initialise.
fn hold_maps(fmu: Option<&Fmu>, cfg: &TrialConfig) -> Result<Option<Estimator>> {
    match (cfg.strategy, fmu) {
        (Strategy::Pf, Some(f)) => f
            .estimator(&Settings {
                trace: None,
                ..cfg.settings.clone()
            })
            .map(Some),
        _ => Ok(None),
    }
}

/// Runs the trials of `set` on `jobs` workers: this thread with `rig`, and `jobs - 1`
/// threads each with a rig of its own from `open` (a camera's rendering context belongs to
/// the thread that made it). Each worker takes the next trial not yet taken; a trial resets
/// its world, so results are those of [`run_campaign`], in trial order.
///
/// # Errors
/// When a worker's rig cannot be opened, or the FMU or rendering fails: the error of the
/// lowest trial index, after the workers stopped taking trials.
pub fn run_parallel(
    rig: &mut Rig,
    jobs: usize,
    open: &(dyn Fn() -> Result<Rig> + Sync),
    fmu: Option<&Fmu>,
    cfg: &TrialConfig,
    set: TrialSet,
) -> Result<Vec<TrialResult>> {
    let _held = hold_maps(fmu, cfg)?;
    let queue = Queue::new(set, cfg.strategy);
    let done = std::thread::scope(|s| {
        let workers: Vec<_> = (1..jobs)
            .map(|_| {
                let queue = &queue;
                s.spawn(move || match open() {
                    Ok(mut r) => queue.work(r.world.as_mut(), fmu, r.eye.as_mut(), cfg),
                    Err(e) => {
                        queue.stop();
                        vec![(0, Err(e))]
                    }
                })
            })
            .collect();
        let mut done = vec![queue.work(rig.world.as_mut(), fmu, rig.eye.as_mut(), cfg)];
        for w in workers {
            done.push(w.join().unwrap_or_else(|_| {
                vec![(
                    0,
                    Err(HarnessError::Invalid {
                        what: "campaign",
                        reason: "a worker thread panicked".into(),
                    }),
                )]
            }));
        }
        done
    });
    queue.finish(done)
}

/// The trials of a run handed out to its workers, and their progress bar.
struct Queue<'a> {
    set: TrialSet<'a>,
    indices: Vec<usize>,
    /// The position in `indices` of the next trial to take.
    next: AtomicUsize,
    stopped: AtomicBool,
    ok: AtomicUsize,
    bar: ProgressBar,
}

/// Trial results by trial index, as a worker ran them.
type Done = Vec<(usize, Result<TrialResult>)>;

impl<'a> Queue<'a> {
    /// The queue of the trials of `set`, with its progress bar.
    fn new(set: TrialSet<'a>, strategy: Strategy) -> Self {
        let indices = set.indices();
        let bar = ProgressBar::new(indices.len() as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "{prefix} [{bar:30}] {pos}/{len} trials {msg} ({elapsed}, eta {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.set_prefix(format!("{strategy:?}").to_lowercase());
        Self {
            set,
            indices,
            next: AtomicUsize::new(0),
            stopped: AtomicBool::new(false),
            ok: AtomicUsize::new(0),
            bar,
        }
    }

    /// No worker takes another trial.
    fn stop(&self) {
        self.stopped.store(true, Ordering::Relaxed);
    }

    /// Takes trials until none is left or a trial failed: trial 0 with `cfg`'s trace, the
    /// others without.
    fn work(
        &self,
        world: &mut dyn World,
        fmu: Option<&Fmu>,
        mut eye: Option<&mut Eye>,
        cfg: &TrialConfig,
    ) -> Done {
        let untraced = TrialConfig {
            settings: Settings {
                trace: None,
                ..cfg.settings.clone()
            },
            ..cfg.clone()
        };
        let mut done = Vec::new();
        while !self.stopped.load(Ordering::Relaxed) {
            let k = self.next.fetch_add(1, Ordering::Relaxed);
            let Some(&i) = self.indices.get(k) else { break };
            let c = if i == 0 { cfg } else { &untraced };
            let truth = self.set.truths[i];
            let r = run_trial(
                world,
                fmu,
                eye.as_deref_mut(),
                c,
                truth,
                self.set.seed + i as u64,
            );
            match &r {
                Ok(r) => {
                    let ok = self.ok.fetch_add(usize::from(r.success), Ordering::Relaxed);
                    self.bar
                        .set_message(format!("{} ok", ok + usize::from(r.success)));
                    self.bar.inc(1);
                }
                Err(_) => self.stop(),
            }
            done.push((i, r));
        }
        done
    }

    /// The workers' results in trial order, or the error of the lowest trial index.
    fn finish(self, done: Vec<Done>) -> Result<Vec<TrialResult>> {
        let mut all: Done = done.into_iter().flatten().collect();
        all.sort_by_key(|(i, _)| *i);
        let results: Result<Vec<TrialResult>> = all.into_iter().map(|(_, r)| r).collect();
        match &results {
            Ok(r) if r.len() == self.indices.len() => self.bar.finish(),
            _ => self.bar.abandon(),
        }
        results
    }
}

/// Times a closure (s).
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let out = f();
    (out, t.elapsed().as_secs_f64())
}
