//! A campaign's records: the table of trials (`trials.csv`, written and read back), the
//! summary (`summary.json` and a readable table) and the statistics behind them.

use std::path::Path;

use ftmap::{Axis, Pose, Task};
use serde::{Deserialize, Serialize};

use crate::calibration::{self, Calibration, Sample};
use crate::error::{HarnessError, Result};
use crate::mismatch::Given;
use crate::trial::{Step, Strategy, TrialResult};
use crate::world::WorldKind;

/// Statistics of a count per trial.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ContactStats {
    /// Mean.
    pub mean: f64,
    /// Median.
    pub median: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Maximum.
    pub max: f64,
}

/// The summary of a campaign (`summary.json`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Summary {
    /// Task name.
    pub task: String,
    /// The task's uncertain DOFs (`object.x`, ...).
    pub dofs: Vec<String>,
    /// Where the contact motions happened.
    pub world: WorldKind,
    /// Strategy.
    pub strategy: Strategy,
    /// Trials run.
    pub trials: usize,
    /// Fraction of trials that reached the goal depth.
    pub success_rate: f64,
    /// Contact motions per trial (all trials), the inserting one included.
    pub contacts: ContactStats,
    /// Contact measurements per trial: contact motions that did not insert the part.
    pub measurements: ContactStats,
    /// Simulated time per trial (s): the contact motions' own, without the free-space moves
    /// between them.
    pub sim_time: ContactStats,
    /// Mean `object.y_std` after the first contact measurement (m).
    pub y_std_first_contact: f64,
    /// Whether the reported spreads are calibrated, over every contact measurement; `None`
    /// without the estimator.
    pub calibration: Option<Calibration>,
    /// The same over the estimates after each trial's first image, before any contact
    /// (with a camera; `None` without).
    pub first_image_calibration: Option<Calibration>,
    /// Whether a camera took part (experiment D).
    pub vision: bool,
    /// Images in which not all four edges were found (all trials).
    pub images_missed: usize,
    /// Mean distance of the last approach point from the true offset (m).
    pub final_error_mean: f64,
    /// Largest such distance (m).
    pub final_error_max: f64,
    /// The last approach's error per uncertain DOF (the last grip estimate's on the grip).
    pub final_errors: Vec<DofError>,
    /// Trials per wall-clock second.
    pub trials_per_second: f64,
    /// Workers that ran the trials at once.
    pub jobs: usize,
    /// Simulated time over wall-clock time spent in MuJoCo.
    pub realtime_factor: f64,
    /// Simulated time over the whole wall-clock time of the trials (FMU included).
    pub realtime_factor_overall: f64,
    /// Whether the sensor noise was on.
    pub sensor_noise: bool,
    /// Slides under force made, of all contact motions.
    pub slides: usize,
    /// Trials whose part went in on a slide.
    pub inserted_by_slide: usize,
    /// Twists under force made, of all contact motions.
    pub twists: usize,
    /// Trials whose part went in on a twist.
    pub inserted_by_twist: usize,
    /// The grip estimate, where the campaign's grip offsets were uncertain.
    pub grip: Option<GripSummary>,
    /// The rotation estimate, where part B's rotations were uncertain.
    pub rotation: Option<RotationSummary>,
    /// The FMU's `mismatch` and `mismatch_angle` and where they came from (`None` without
    /// the FMU).
    pub mismatch: Option<Given>,
}

/// How well a campaign found the grip offsets.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct GripSummary {
    /// Mean distance of the trials' last grip estimate from the true grip offset (m).
    pub error_mean: f64,
    /// Largest such distance (m).
    pub error_max: f64,
    /// Share of contact measurements whose true grip.x, grip.y lies within 2 reported sigma.
    pub within_2sigma: [f64; 2],
}

impl GripSummary {
    /// The summary of `results` and their `samples`; `None` where no trial's grip was off.
    fn of(results: &[TrialResult], samples: &[Sample]) -> Option<Self> {
        if results.iter().all(|r| r.grip == [0.0; 2]) {
            return None;
        }
        let errors: Vec<f64> = results
            .iter()
            .filter_map(|r| {
                let e = r.steps.iter().rev().find_map(|s| s.estimate)?;
                Some((e.grip[0] - r.grip[0]).hypot(e.grip[1] - r.grip[1]))
            })
            .collect();
        let n = samples.len().max(1) as f64;
        Some(Self {
            error_mean: errors.iter().sum::<f64>() / errors.len().max(1) as f64,
            error_max: errors.iter().copied().fold(0.0, f64::max),
            within_2sigma: std::array::from_fn(|k| {
                samples
                    .iter()
                    .filter(|s| s.grip_z()[k].abs() <= 2.0)
                    .count() as f64
                    / n
            }),
        })
    }
}

/// How well a campaign's reported rotation spreads held the truth, per rotation axis
/// part B was turned about.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RotationSummary {
    /// `object.rx` .. `object.rz`, those turned.
    pub dofs: Vec<String>,
    /// Share of contact measurements whose true rotation lies within 2 reported sigma,
    /// per DOF.
    pub within_2sigma: Vec<f64>,
}

impl RotationSummary {
    /// The summary of `results` and their `samples`; `None` where no part B was turned.
    fn of(results: &[TrialResult], samples: &[Sample]) -> Option<Self> {
        let turned: Vec<usize> = (0..3)
            .filter(|&k| results.iter().any(|r| r.rot[k] != 0.0))
            .collect();
        if turned.is_empty() {
            return None;
        }
        let m = samples.len().max(1) as f64;
        Some(Self {
            dofs: turned
                .iter()
                .map(|&k| format!("object.{}", ["rx", "ry", "rz"][k]))
                .collect(),
            within_2sigma: turned
                .iter()
                .map(|&k| samples.iter().filter(|s| s.rot_z()[k].abs() <= 2.0).count() as f64 / m)
                .collect(),
        })
    }
}

/// A value (m or rad) of the DOF named `dof` as a person reads it: degrees on a rotation,
/// mm otherwise, with its unit.
pub fn shown(dof: &str, v: f64) -> (f64, &'static str) {
    if dof.parse::<ftmap::Dof>().is_ok_and(|d| d.is_rotation()) {
        (v.to_degrees(), "deg")
    } else {
        (v * 1e3, "mm")
    }
}

/// The last approach's error on one uncertain DOF, over a campaign's trials.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct DofError {
    /// The DOF (`object.x`, `object.rz`, ...).
    pub dof: String,
    /// Mean |error| (m or rad).
    pub mean: f64,
    /// Largest |error| (m or rad).
    pub max: f64,
}

/// The last approach's error per uncertain DOF of `task` over `results`: where the tool's
/// axis met the goal's height ([`Step::foot`]) against the true offset on object x, y;
/// [`TrialResult::final_rot_error`] on object rotations; the last grip estimate against
/// the true grip on grip x, y.
fn final_errors(task: &Task, results: &[TrialResult]) -> Vec<DofError> {
    let dofs = task.dofs().unwrap_or_default();
    let error = |d: &ftmap::Dof, r: &TrialResult| -> Option<f64> {
        let k = d.axis.index();
        match (d.pose, d.axis) {
            (Pose::Object, Axis::X | Axis::Y) => Some(
                r.steps
                    .last()
                    .map_or(r.offset[k], |s| s.foot()[k] - r.offset[k]),
            ),
            (Pose::Object, Axis::Rx | Axis::Ry | Axis::Rz) => Some(r.final_rot_error[k - 3]),
            (Pose::Grip, Axis::X | Axis::Y) => Some(
                r.steps
                    .iter()
                    .rev()
                    .find_map(|s| s.estimate)
                    .map_or(r.grip[k], |e| e.grip[k] - r.grip[k]),
            ),
            _ => None,
        }
    };
    dofs.iter()
        .filter_map(|d| {
            let errors: Vec<f64> = results
                .iter()
                .map(|r| error(d, r).map(f64::abs))
                .collect::<Option<_>>()?;
            Some(DofError {
                dof: d.to_string(),
                mean: errors.iter().sum::<f64>() / errors.len().max(1) as f64,
                max: errors.iter().copied().fold(0.0, f64::max),
            })
        })
        .collect()
}

impl DofError {
    /// `object.x 0.0120 / 0.0300 mm` (degrees on a rotation).
    pub fn text(&self) -> String {
        let ((mean, unit), (max, _)) = (shown(&self.dof, self.mean), shown(&self.dof, self.max));
        let digits = if unit == "deg" { 3 } else { 4 };
        format!("{} {mean:.digits$} / {max:.digits$} {unit}", self.dof)
    }
}

impl ContactStats {
    /// Mean, median, p95 and maximum of `values`.
    pub fn of(mut values: Vec<f64>) -> Self {
        values.sort_by(f64::total_cmp);
        Self {
            mean: values.iter().sum::<f64>() / values.len().max(1) as f64,
            median: percentile(&values, 0.5),
            p95: percentile(&values, 0.95),
            max: values.last().copied().unwrap_or(f64::NAN),
        }
    }
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

/// The contact motions of `results` that `kind` picks (slides, twists).
fn made(results: &[TrialResult], kind: impl Fn(&Step) -> bool) -> usize {
    results
        .iter()
        .map(|r| r.steps.iter().filter(|s| kind(s)).count())
        .sum()
}

/// The trials of `results` whose part went in on a motion that `kind` picks.
fn inserted_by(results: &[TrialResult], kind: impl Fn(&Step) -> bool) -> usize {
    results
        .iter()
        .filter(|r| r.success && r.steps.last().is_some_and(&kind))
        .count()
}

/// How long a campaign's trials took, on how many workers.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pace {
    /// Wall-clock time of the whole campaign (s).
    pub wall: f64,
    /// Workers that ran the trials at once.
    pub jobs: usize,
}

/// Summarises trial results.
pub fn summarize(
    task: &Task,
    world: &WorldKind,
    strategy: Strategy,
    sensor_noise: bool,
    vision: bool,
    results: &[TrialResult],
    pace: Pace,
) -> Summary {
    let n = results.len().max(1) as f64;
    let first: Vec<f64> = results.iter().filter_map(first_contact_y_std).collect();
    let sim: f64 = results.iter().map(|r| r.sim_time).sum();
    let sim_wall: f64 = results.iter().map(|r| r.sim_wall).sum();
    let trial_wall: f64 = results.iter().map(|r| r.wall).sum();
    let samples = calibration::samples(results);
    Summary {
        task: task.name.clone(),
        dofs: task
            .dofs()
            .unwrap_or_default()
            .iter()
            .map(ToString::to_string)
            .collect(),
        world: world.clone(),
        strategy,
        trials: results.len(),
        success_rate: results.iter().filter(|r| r.success).count() as f64 / n,
        contacts: ContactStats::of(results.iter().map(|r| r.contacts as f64).collect()),
        measurements: ContactStats::of(results.iter().map(|r| r.measurements() as f64).collect()),
        sim_time: ContactStats::of(results.iter().map(|r| r.sim_time).collect()),
        y_std_first_contact: first.iter().sum::<f64>() / first.len().max(1) as f64,
        calibration: Some(&samples)
            .filter(|s| !s.is_empty())
            .map(|s| Calibration::of(s)),
        first_image_calibration: Some(calibration::first_images(results))
            .filter(|s| !s.is_empty())
            .map(|s| Calibration::of(&s)),
        vision,
        images_missed: results.iter().map(|r| r.images_missed).sum(),
        final_error_mean: results.iter().map(|r| r.final_error).sum::<f64>() / n,
        final_error_max: results.iter().map(|r| r.final_error).fold(0.0, f64::max),
        final_errors: final_errors(task, results),
        trials_per_second: results.len() as f64 / pace.wall.max(1e-9),
        jobs: pace.jobs,
        realtime_factor: sim / sim_wall.max(1e-9),
        realtime_factor_overall: sim / trial_wall.max(1e-9),
        sensor_noise,
        slides: made(results, |s| s.slide),
        inserted_by_slide: inserted_by(results, |s| s.slide),
        twists: made(results, |s| s.twist),
        inserted_by_twist: inserted_by(results, |s| s.twist),
        grip: GripSummary::of(results, &samples),
        rotation: RotationSummary::of(results, &samples),
        mismatch: None,
    }
}

impl Summary {
    /// The summary of a campaign whose FMU ran with `mismatch`.
    pub fn with_mismatch(self, mismatch: Option<Given>) -> Self {
        Self { mismatch, ..self }
    }

    /// "`made` of N contact motions, `inserted` of them inserted the part".
    fn motions(&self, made: usize, inserted: usize) -> String {
        format!(
            "{made} of {} contact motions, {inserted} of them inserted the part",
            (self.contacts.mean * self.trials as f64).round() as usize
        )
    }

    /// A readable table of the summary.
    pub fn table(&self) -> String {
        let mm = |m: f64| format!("{:.3} mm", m * 1e3);
        let rows = [
            ("task", self.task.clone()),
            (
                "world",
                match &self.world {
                    WorldKind::Mujoco => "MuJoCo".to_owned(),
                    WorldKind::Map(Some(file)) => format!("the map {}", file.display()),
                    WorldKind::Map(None) => "the FMU's map".to_owned(),
                },
            ),
            ("strategy", format!("{:?}", self.strategy).to_lowercase()),
            (
                "sensor noise",
                if self.sensor_noise { "on" } else { "off" }.to_owned(),
            ),
            (
                "slides under force",
                self.motions(self.slides, self.inserted_by_slide),
            ),
            (
                "twists under force",
                self.motions(self.twists, self.inserted_by_twist),
            ),
            (
                "camera",
                if self.vision {
                    format!("on ({} images missed an edge)", self.images_missed)
                } else {
                    "off".to_owned()
                },
            ),
            ("trials", self.trials.to_string()),
            (
                "success rate",
                format!("{:.1} %", 100.0 * self.success_rate),
            ),
            (
                "contacts mean / median / p95 / max",
                format!(
                    "{:.2} / {} / {} / {}",
                    self.contacts.mean, self.contacts.median, self.contacts.p95, self.contacts.max
                ),
            ),
            (
                "contact measurements mean / median / p95 / max",
                format!(
                    "{:.2} / {} / {} / {}",
                    self.measurements.mean,
                    self.measurements.median,
                    self.measurements.p95,
                    self.measurements.max
                ),
            ),
            (
                "simulated time per trial mean / median / p95 / max",
                format!(
                    "{:.2} / {:.2} / {:.2} / {:.2} s",
                    self.sim_time.mean, self.sim_time.median, self.sim_time.p95, self.sim_time.max
                ),
            ),
            (
                "object.y_std after the first contact",
                mm(self.y_std_first_contact),
            ),
            (
                "the FMU's model mismatch",
                self.mismatch
                    .map_or("n/a (no estimator)".to_owned(), |m| m.to_string()),
            ),
            (
                "true offset within 1 / 2 sigma",
                self.calibration
                    .as_ref()
                    .map_or("n/a (no estimator)".to_owned(), Calibration::line),
            ),
            (
                "first image: true offset within 1 / 2 sigma",
                self.first_image_calibration
                    .as_ref()
                    .map_or("n/a (no camera)".to_owned(), Calibration::line),
            ),
            (
                "final error mean / max",
                format!(
                    "{} / {}",
                    mm(self.final_error_mean),
                    mm(self.final_error_max)
                ),
            ),
            (
                "grip: final error mean / max, within 2 sigma x / y",
                self.grip
                    .as_ref()
                    .map_or("n/a (grip certain)".to_owned(), |g| {
                        format!(
                            "{} / {}, {:.1} / {:.1} %",
                            mm(g.error_mean),
                            mm(g.error_max),
                            100.0 * g.within_2sigma[0],
                            100.0 * g.within_2sigma[1]
                        )
                    }),
            ),
            (
                "final |error| per DOF, mean / max",
                self.final_errors
                    .iter()
                    .map(DofError::text)
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
            (
                "rotation: true within 2 sigma",
                self.rotation
                    .as_ref()
                    .map_or("n/a (rotations certain)".to_owned(), |r| {
                        r.dofs
                            .iter()
                            .zip(&r.within_2sigma)
                            .map(|(d, x)| format!("{d} {:.1} %", 100.0 * x))
                            .collect::<Vec<_>>()
                            .join(", ")
                    }),
            ),
            (
                "trials per second",
                format!("{:.2} ({} workers)", self.trials_per_second, self.jobs),
            ),
            (
                "real-time factor (MuJoCo / whole loop)",
                match self.world {
                    WorldKind::Mujoco => format!(
                        "{:.1} x / {:.1} x",
                        self.realtime_factor, self.realtime_factor_overall
                    ),
                    WorldKind::Map(_) => "n/a (nothing simulated)".to_owned(),
                },
            ),
        ];
        let w = rows.iter().map(|r| r.0.len()).max().unwrap_or(0);
        rows.iter()
            .map(|(k, v)| format!("  {k:<w$}  {v}\n"))
            .collect()
    }
}

/// Writes `trials.csv`: one row per trial.
///
/// # Errors
/// When the file cannot be written.
pub fn write_trials_csv(path: &Path, results: &[TrialResult]) -> Result<()> {
    let io = |source| HarnessError::Csv {
        path: path.to_owned(),
        source,
    };
    let mut w = csv::Writer::from_path(path).map_err(io)?;
    w.write_record([
        "trial",
        "offset_x_m",
        "offset_y_m",
        "contacts",
        "measurements",
        "success",
        "final_error_m",
        "y_std_first_contact_m",
        "images_missed",
        "wall_s",
        "sim_time_s",
        "grip_x_m",
        "grip_y_m",
        "rot_x_rad",
        "rot_y_rad",
        "rot_z_rad",
        "final_rot_error_x_rad",
        "final_rot_error_y_rad",
        "final_rot_error_z_rad",
    ])
    .map_err(io)?;
    for (i, r) in results.iter().enumerate() {
        // True offsets exactly (shortest round-trip text), so that a script repeats a trial
        // bit for bit: near the fit's boundary a nanometre can decide an insertion.
        w.write_record([
            i.to_string(),
            r.offset[0].to_string(),
            r.offset[1].to_string(),
            r.contacts.to_string(),
            r.measurements().to_string(),
            r.success.to_string(),
            format!("{:.9}", r.final_error),
            first_contact_y_std(r).map_or(String::new(), |v| format!("{v:.9}")),
            r.images_missed.to_string(),
            format!("{:.4}", r.wall),
            format!("{:.4}", r.sim_time),
            r.grip[0].to_string(),
            r.grip[1].to_string(),
            r.rot[0].to_string(),
            r.rot[1].to_string(),
            r.rot[2].to_string(),
            format!("{:.9}", r.final_rot_error[0]),
            format!("{:.9}", r.final_rot_error[1]),
            format!("{:.9}", r.final_rot_error[2]),
        ])
        .map_err(io)?;
    }
    w.flush().map_err(|e| HarnessError::io(path, e))
}

/// Writes `measurements.csv`: one row per contact measurement, with the estimate, its
/// reported spread and the true offset (what the calibration is computed from).
///
/// # Errors
/// When the file cannot be written.
pub fn write_measurements_csv(path: &Path, samples: &[Sample]) -> Result<()> {
    let io = |source| HarnessError::Csv {
        path: path.to_owned(),
        source,
    };
    let mut w = csv::Writer::from_path(path).map_err(io)?;
    w.write_record([
        "trial",
        "measurement",
        "image",
        "true_x_m",
        "true_y_m",
        "object_x_m",
        "object_y_m",
        "object_x_std_m",
        "object_y_std_m",
        "object_xy_corr",
        "confidence",
        "clusters",
        "converged",
        "nees",
        "true_grip_x_m",
        "true_grip_y_m",
        "grip_x_m",
        "grip_y_m",
        "grip_x_std_m",
        "grip_y_std_m",
        "true_rot_x_rad",
        "true_rot_y_rad",
        "true_rot_z_rad",
        "object_rx_rad",
        "object_ry_rad",
        "object_rz_rad",
        "object_rx_std_rad",
        "object_ry_std_rad",
        "object_rz_std_rad",
    ])
    .map_err(io)?;
    for s in samples {
        let e = &s.estimate;
        let m = |v: f64| format!("{v:.9}");
        let sd = |v: f64| format!("{v:.12}");
        w.write_record([
            s.trial.to_string(),
            s.measurement.to_string(),
            s.image.to_string(),
            s.truth[0].to_string(),
            s.truth[1].to_string(),
            m(e.object[0]),
            m(e.object[1]),
            sd(e.std[0]),
            sd(e.std[1]),
            format!("{:.6}", e.corr),
            format!("{:.4}", e.confidence),
            e.clusters.to_string(),
            e.converged.to_string(),
            format!("{:.6}", s.nees()),
            s.grip_truth[0].to_string(),
            s.grip_truth[1].to_string(),
            m(e.grip[0]),
            m(e.grip[1]),
            sd(e.grip_std[0]),
            sd(e.grip_std[1]),
            s.rot_truth[0].to_string(),
            s.rot_truth[1].to_string(),
            s.rot_truth[2].to_string(),
            m(e.rot[0]),
            m(e.rot[1]),
            m(e.rot[2]),
            sd(e.rot_std[0]),
            sd(e.rot_std[1]),
            sd(e.rot_std[2]),
        ])
        .map_err(io)?;
    }
    w.flush().map_err(|e| HarnessError::io(path, e))
}

/// One row of a `trials.csv`, read back (the columns a comparison needs).
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct TrialRow {
    /// True offset x (m).
    pub offset_x_m: f64,
    /// True offset y (m).
    pub offset_y_m: f64,
    /// Contact motions.
    pub contacts: usize,
    /// Contact measurements.
    pub measurements: usize,
    /// Whether the part went in.
    pub success: bool,
    /// `object.y_std` after the first contact measurement (m), if there was one.
    pub y_std_first_contact_m: Option<f64>,
}

/// Reads a campaign's `trials.csv`.
///
/// # Errors
/// When the file cannot be read or a row lacks a column or holds a malformed value.
pub fn read_trials_csv(path: &Path) -> Result<Vec<TrialRow>> {
    let bad = |source| HarnessError::Csv {
        path: path.to_owned(),
        source,
    };
    let mut r = csv::Reader::from_path(path).map_err(bad)?;
    r.deserialize()
        .collect::<std::result::Result<Vec<TrialRow>, _>>()
        .map_err(bad)
}

/// `object.y_std` after a trial's first contact measurement.
fn first_contact_y_std(r: &TrialResult) -> Option<f64> {
    r.steps.iter().find_map(|s| s.estimate).map(|e| e.std[1])
}

/// Writes `summary.json`.
///
/// # Errors
/// When the file cannot be written.
pub fn write_summary(path: &Path, s: &Summary) -> Result<()> {
    let text = serde_json::to_string_pretty(s).map_err(|source| HarnessError::Json {
        path: path.to_owned(),
        source,
    })?;
    std::fs::write(path, text + "\n").map_err(|e| HarnessError::io(path, e))
}
