//! Whether the estimator's reported spread tells the truth: for every contact measurement,
//! the error of the estimate against the true offset in units of the reported spread
//! (`object.x_std`, `object.y_std`), the fraction of measurements whose true offset lies
//! within the 1- and 2-sigma regions, and the normalised estimation error squared (NEES).
//!
//! The FMU reports a spread per DOF and the correlation of the two (`object.xy_corr`): the
//! region is the ellipse of that covariance C. For a calibrated 2-D Gaussian estimate, the
//! true offset lies within the 1-sigma ellipse in 1 - e^(-1/2) = 39.3 % of measurements and
//! within the 2-sigma ellipse in 1 - e^(-2) = 86.5 %; per DOF within 1 and 2 sigma in 68.3 %
//! and 95.4 %; and the NEES, e^T C^-1 e for the error e, has mean 2 (the DOF count) and
//! median 2 ln 2 = 1.386 (a chi-square of 2 DOFs). The mean is a few measurements' where a
//! set locks off the truth with a narrow spread (a NEES of thousands); the median is the
//! typical measurement's.

use serde::Serialize;

use crate::fmu_driver::Estimate;
use crate::trial::{TrialResult, rotation_error};

/// Spreads below this (m) count as this: a collapsed spread gives a huge, not an infinite,
/// NEES.
pub const MIN_STD: f64 = 1e-9;
/// Correlations count at most this in magnitude: a degenerate ellipse (a line) gives a huge,
/// not an infinite, NEES across it.
pub const MAX_CORR: f64 = 0.999;

/// Names of the DOFs an [`Estimate`] holds, in its order.
pub const DOFS: [&str; 2] = ["object.x", "object.y"];

/// One contact measurement: the estimate after it and the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Trial index in the campaign.
    pub trial: usize,
    /// 1 for the trial's first contact measurement, 2 for the second, ...
    pub measurement: usize,
    /// Whether an image went with the wrench.
    pub image: bool,
    /// The true offset (m).
    pub truth: [f64; 2],
    /// The true grip offset (m).
    pub grip_truth: [f64; 2],
    /// The true rotation of part B (rotation vector, rad).
    pub rot_truth: [f64; 3],
    /// The estimate's rotation error, R_estimate^T R_true as a rotation vector (rad), yaw
    /// modulo the fit's symmetry.
    pub rot_error: [f64; 3],
    /// The FMU's outputs after the measurement.
    pub estimate: Estimate,
}

impl Sample {
    /// Measurement `measurement` of trial `trial` (result `r`) that gave `estimate`.
    fn of(
        trial: usize,
        measurement: usize,
        image: bool,
        r: &TrialResult,
        estimate: Estimate,
    ) -> Self {
        Self {
            trial,
            measurement,
            image,
            truth: r.offset,
            grip_truth: r.grip,
            rot_truth: r.rot,
            rot_error: rotation_error(estimate.rot, r.rot, r.symmetry),
            estimate,
        }
    }

    /// Error of the estimate in units of the reported spread, per DOF.
    pub fn z(&self) -> [f64; 2] {
        std::array::from_fn(|k| {
            (self.estimate.object[k] - self.truth[k]) / self.estimate.std[k].max(MIN_STD)
        })
    }

    /// Error of the rotation estimate in units of its reported spread, per axis (0 where
    /// the rotation is certain: no spread and no error).
    pub fn rot_z(&self) -> [f64; 3] {
        std::array::from_fn(|k| {
            let e = self.rot_error[k];
            if e == 0.0 {
                0.0
            } else {
                e / self.estimate.rot_std[k].max(MIN_STD)
            }
        })
    }

    /// Error of the grip estimate in units of its reported spread, per DOF.
    pub fn grip_z(&self) -> [f64; 2] {
        std::array::from_fn(|k| {
            (self.estimate.grip[k] - self.grip_truth[k]) / self.estimate.grip_std[k].max(MIN_STD)
        })
    }

    /// The normalised estimation error squared, e^T Sigma^-1 e with the reported covariance.
    pub fn nees(&self) -> f64 {
        let [x, y] = self.z();
        let r = self.estimate.corr.clamp(-MAX_CORR, MAX_CORR);
        (x * x - 2.0 * r * x * y + y * y) / (1.0 - r * r)
    }
}

/// Every contact measurement of a campaign, in trial order.
pub fn samples(results: &[TrialResult]) -> Vec<Sample> {
    results
        .iter()
        .enumerate()
        .flat_map(|(trial, r)| {
            r.steps
                .iter()
                .flat_map(|s| {
                    [
                        s.started.map(|e| (false, e)),
                        s.estimate.map(|e| (s.image, e)),
                    ]
                })
                .flatten()
                .enumerate()
                .map(move |(k, (image, estimate))| Sample::of(trial, k + 1, image, r, estimate))
        })
        .collect()
}

/// The estimate after each trial's first image (taken before any contact, with a camera)
/// against the truth, as measurement 0.
pub fn first_images(results: &[TrialResult]) -> Vec<Sample> {
    results
        .iter()
        .enumerate()
        .filter_map(|(trial, r)| {
            r.first_look
                .map(|estimate| Sample::of(trial, 0, true, r, estimate))
        })
        .collect()
}

/// The calibration of one DOF's spread.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DofCalibration {
    /// The DOF (`object.x`, ...).
    pub dof: &'static str,
    /// Fraction of measurements with |error| <= 1 sigma (ideal 0.683).
    pub within_1sigma: f64,
    /// Fraction with |error| <= 2 sigma (ideal 0.954).
    pub within_2sigma: f64,
}

/// The calibration of a campaign's reported spreads (`summary.json`'s `calibration`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Calibration {
    /// Contact measurements counted.
    pub measurements: usize,
    /// Fraction of measurements whose true offset lies within the 1-sigma ellipse (ideal 0.393).
    pub within_1sigma: f64,
    /// Fraction within the 2-sigma ellipse (ideal 0.865).
    pub within_2sigma: f64,
    /// Per DOF.
    pub per_dof: Vec<DofCalibration>,
    /// Mean NEES (ideal: the DOF count).
    pub nees_mean: f64,
    /// The ideal mean NEES: the number of DOFs.
    pub nees_ideal: f64,
    /// Median NEES (ideal [`NEES_MEDIAN_IDEAL`]; the mean of the middle two of an even
    /// count).
    pub nees_median: f64,
}

/// The median of a chi-square of 2 DOFs, 2 ln 2: a calibrated estimate's median NEES.
pub const NEES_MEDIAN_IDEAL: f64 = 2.0 * std::f64::consts::LN_2;

impl Calibration {
    /// The calibration of `samples`; fractions, mean and median are NaN when there are none.
    pub fn of(samples: &[Sample]) -> Self {
        let n = samples.len() as f64;
        let fraction = |inside: &dyn Fn(&Sample) -> bool| {
            samples.iter().filter(|s| inside(s)).count() as f64 / n
        };
        let per_dof = DOFS
            .iter()
            .enumerate()
            .map(|(k, &dof)| DofCalibration {
                dof,
                within_1sigma: fraction(&|s| s.z()[k].abs() <= 1.0),
                within_2sigma: fraction(&|s| s.z()[k].abs() <= 2.0),
            })
            .collect();
        let nees: Vec<f64> = samples.iter().map(Sample::nees).collect();
        let within = |bound: f64| nees.iter().filter(|&&v| v <= bound).count() as f64 / n;
        Self {
            measurements: samples.len(),
            within_1sigma: within(1.0),
            within_2sigma: within(4.0),
            per_dof,
            nees_mean: nees.iter().sum::<f64>() / n,
            nees_ideal: DOFS.len() as f64,
            nees_median: median(nees),
        }
    }

    /// One line for the summary table.
    pub fn line(&self) -> String {
        let pct = |f: f64| format!("{:.1} %", 100.0 * f);
        format!(
            "{} / {} (ideal 39.3 / 86.5 %), NEES mean {:.2} (ideal {}), median {:.2} (ideal {:.2}) over {} measurements",
            pct(self.within_1sigma),
            pct(self.within_2sigma),
            self.nees_mean,
            self.nees_ideal,
            self.nees_median,
            NEES_MEDIAN_IDEAL,
            self.measurements
        )
    }
}

/// The median of `values`, the mean of the middle two of an even count (NaN for none).
pub(crate) fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    match values.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => values[n / 2],
        n => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(error: [f64; 2], std: [f64; 2]) -> Sample {
        Sample {
            trial: 0,
            measurement: 1,
            image: false,
            truth: [1e-3, -2e-3],
            grip_truth: [0.0; 2],
            rot_truth: [0.0; 3],
            rot_error: [0.0; 3],
            estimate: Estimate {
                object: [1e-3 + error[0], -2e-3 + error[1]],
                std,
                ..Estimate::default()
            },
        }
    }

    #[test]
    fn a_gaussian_estimate_with_its_true_spread_is_calibrated() {
        // Errors drawn from the reported spread itself: a deterministic low-discrepancy
        // sample of the 2-D normal (Box-Muller on a Halton sequence).
        let halton = |mut i: u32, b: u32| {
            let (mut f, mut r) = (1.0, 0.0);
            while i > 0 {
                f /= f64::from(b);
                r += f * f64::from(i % b);
                i /= b;
            }
            r
        };
        let std = [2e-5, 5e-5];
        let samples: Vec<Sample> = (1..20_000)
            .map(|i| {
                let (u, v) = (halton(i, 2), halton(i, 3));
                let r = (-2.0 * u.ln()).sqrt();
                let t = std::f64::consts::TAU * v;
                sample([std[0] * r * t.cos(), std[1] * r * t.sin()], std)
            })
            .collect();
        let c = Calibration::of(&samples);
        let near = |got: f64, want: f64| (got - want).abs() < 0.01;
        assert!(near(c.within_1sigma, 1.0 - (-0.5f64).exp()), "{c:?}");
        assert!(near(c.within_2sigma, 1.0 - (-2.0f64).exp()), "{c:?}");
        for d in &c.per_dof {
            assert!(
                near(d.within_1sigma, 0.6827) && near(d.within_2sigma, 0.9545),
                "{d:?}"
            );
        }
        assert!((c.nees_mean - 2.0).abs() < 0.05, "{c:?}");
        assert!((c.nees_median - NEES_MEDIAN_IDEAL).abs() < 0.02, "{c:?}");
    }

    #[test]
    fn the_ellipse_follows_the_correlation() {
        // Spread 1 mm along the diagonal x = y, 0.1 mm across it: std 0.71 mm on each axis,
        // correlation 0.98. An error of 0.5 mm along the diagonal is within 1 sigma; the
        // same error across it is 5 sigma, though each axis alone sees 0.35 sigma.
        let (a, b) = (1e-3f64, 1e-4f64);
        let std = ((a * a + b * b) / 2.0).sqrt();
        let corr = (a * a - b * b) / (a * a + b * b);
        let at = |e: [f64; 2]| {
            let mut s = sample(e, [std, std]);
            s.estimate.corr = corr;
            s
        };
        let h = 0.5e-3 / 2f64.sqrt();
        assert!((at([h, h]).nees() - 0.25).abs() < 1e-9);
        assert!((at([h, -h]).nees() - 25.0).abs() < 1e-9);
    }

    #[test]
    fn an_overconfident_spread_is_seen() {
        // The true error 3 sigma off in x: outside both ellipses, NEES 9.
        let c = Calibration::of(&[sample([3e-5, 0.0], [1e-5, 1e-5])]);
        assert_eq!((c.within_1sigma, c.within_2sigma), (0.0, 0.0));
        assert!((c.nees_mean - 9.0).abs() < 1e-9, "{c:?}");
        assert_eq!(c.per_dof[1].within_1sigma, 1.0);
        // A collapsed spread counts as MIN_STD, not as zero.
        let collapsed = Calibration::of(&[sample([1e-6, 0.0], [0.0, 0.0])]);
        assert!(collapsed.nees_mean.is_finite() && collapsed.nees_mean > 1e5);
        // One locked measurement moves the mean, not the median.
        let mut typical: Vec<Sample> = (0..9).map(|_| sample([1e-5, 0.0], [1e-5, 1e-5])).collect();
        typical.push(sample([1e-2, 0.0], [1e-5, 1e-5]));
        let c = Calibration::of(&typical);
        assert!(
            c.nees_mean > 1e5 && (c.nees_median - 1.0).abs() < 1e-9,
            "{c:?}"
        );
    }
}
