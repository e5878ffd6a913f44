//! The scene's model mismatch: how far the torque a scene settles on misses the FT-Map's
//! at the same pose, measured by contact motions at true offsets drawn as a campaign draws
//! them (where first contacts land) and near the goal (where later contacts land), and
//! handed to the FMU as its `mismatch` (along the measured torque, a share of its size) and
//! `mismatch_angle` (across it, rad): the spread the filter reports is then as wide as the
//! scene's misses, not as a default's (docs/fmu.md, "Parameters").
//!
//! The scales are robust (from the median), so a few presses the map does not explain at
//! all (a part half in, on the hole's edge) do not widen them: the FMU's Student-t tail is
//! there for those. The two sets are scaled apart and their variances averaged: a contact
//! lands in one or the other, and a median over both together would be the smaller set's
//! (octagon_yaw's misses near the goal are 14 times those over Omega).

use std::fmt;

use crate::calibration::median;
use crate::error::Result;
use crate::sensor::Noise;
use crate::trial::Truth;
use crate::world::World;

/// Torques smaller than this (N m) have no direction to compare: five times the typical
/// sensor's noise.
const MIN_TORQUE: f64 = 5.0 * Noise::TYPICAL.torque;

/// Median of chi^2 with one degree of freedom: sqrt(median(x^2) / this) is the standard
/// deviation of a zero-mean Gaussian x.
const MEDIAN_CHI2_1: f64 = 0.454_936_423;
/// sqrt(2 ln 2): the median of a Rayleigh distribution in units of its scale, the angle of
/// a vector whose two components across are Gaussian with that standard deviation.
const MEDIAN_RAYLEIGH: f64 = 1.177_410_023;

/// The robust scales of a set of presses' misses.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Scales {
    /// Standard deviation of the share of the measured torque's size the map misses.
    pub along: f64,
    /// Standard deviation of each component across the measured torque, in units of its
    /// size (rad).
    pub across: f64,
    /// Presses that rested with a torque on both sides (the others are not counted).
    pub presses: usize,
}

impl Scales {
    /// The scales of the misses `(along, angle)` of single presses.
    pub fn of(misses: &[(f64, f64)]) -> Self {
        // No presses: no miss.
        let median = |v: Vec<f64>| if v.is_empty() { 0.0 } else { median(v) };
        Self {
            along: (median(misses.iter().map(|m| m.0 * m.0).collect()) / MEDIAN_CHI2_1).sqrt(),
            across: median(misses.iter().map(|m| m.1).collect()) / MEDIAN_RAYLEIGH,
            presses: misses.len(),
        }
    }
}

/// What a scene misses of its map, over Omega and near the goal.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Misses {
    /// At true offsets drawn over the campaign's Omega.
    pub omega: Scales,
    /// At true offsets near the goal.
    pub near: Scales,
}

impl Misses {
    /// What the FMU is given: the root of the mean of the two sets' variances (the set
    /// with no counted press left out), and the presses of both.
    pub fn pooled(&self) -> Scales {
        let sets: Vec<&Scales> = [&self.omega, &self.near]
            .into_iter()
            .filter(|s| s.presses > 0)
            .collect();
        let rms = |f: fn(&Scales) -> f64| {
            (sets.iter().map(|s| f(s).powi(2)).sum::<f64>() / sets.len().max(1) as f64).sqrt()
        };
        Scales {
            along: rms(|s| s.along),
            across: rms(|s| s.across),
            presses: self.omega.presses + self.near.presses,
        }
    }
}

impl fmt::Display for Misses {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = |s: &Scales| {
            format!(
                "{:.1} %, {:.3} rad ({} presses)",
                100.0 * s.along,
                s.across,
                s.presses
            )
        };
        write!(
            f,
            "along / across the torque {}: over Omega {}, near the goal {}",
            s(&self.pooled()),
            s(&self.omega),
            s(&self.near)
        )
    }
}

/// A value of `mismatch` or `mismatch_angle` a campaign's FMU ran with, by where it came
/// from.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// The FMU's default.
    Default,
    /// Set by the user.
    Given(f64),
    /// The scene's misses, measured by the campaign ([`Misses::pooled`]).
    Measured(f64),
}

impl Source {
    /// The value, as `shown` writes it, and its source.
    fn text(self, shown: impl Fn(f64) -> String) -> String {
        match self {
            Self::Default => "the FMU's default".to_owned(),
            Self::Given(v) => format!("{} (given)", shown(v)),
            Self::Measured(v) => format!("{} (measured)", shown(v)),
        }
    }
}

/// The `mismatch` and `mismatch_angle` a campaign's FMU ran with (`summary.json`'s
/// `mismatch`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Given {
    /// `mismatch`: a share of the measured magnitudes.
    pub along: Source,
    /// `mismatch_angle` (rad).
    pub across: Source,
}

impl fmt::Display for Given {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "mismatch {}, mismatch_angle {}",
            self.along.text(|v| format!("{:.1} %", 100.0 * v)),
            self.across.text(|v| format!("{v:.3} rad"))
        )
    }
}

/// The miss of one press: the share of the measured torque `measured`'s size that the
/// map's `map` misses, and the angle between them (rad); `None` where either torque is too
/// small to have a direction.
fn miss(measured: [f64; 3], map: [f64; 3]) -> Option<(f64, f64)> {
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let (a, b) = (norm(measured), norm(map));
    if a < MIN_TORQUE || b < MIN_TORQUE {
        return None;
    }
    let cos = measured.iter().zip(&map).map(|(x, y)| x * y).sum::<f64>() / (a * b);
    Some((1.0 - b / a, cos.clamp(-1.0, 1.0).acos()))
}

/// The misses of `scene` against `map` (two worlds of one task) at the true offsets
/// `omega` and `near`: one contact motion at the nominal goal each, in both worlds; a press
/// that goes in, or rests without a torque, in either is not counted.
///
/// # Errors
/// When either world cannot take a truth's rotation.
pub fn measure(
    scene: &mut dyn World,
    map: &mut dyn World,
    omega: &[Truth],
    near: &[Truth],
) -> Result<Misses> {
    let mut presses = |truths: &[Truth]| -> Result<Vec<(f64, f64)>> {
        let mut out = Vec::new();
        for t in truths {
            let torque = |w: &mut dyn World| -> Result<Option<[f64; 3]>> {
                w.set_grip(t.grip);
                w.set_object(t.object);
                w.set_object_rotation(t.rot)?;
                w.set_tcp_rotation([0.0; 3])?;
                let c = w.contact_motion([0.0, 0.0]);
                Ok((!c.inserted).then(|| [c.raw[3], c.raw[4], c.raw[5]]))
            };
            if let (Some(a), Some(b)) = (torque(scene)?, torque(map)?)
                && let Some(m) = miss(a, b)
            {
                out.push(m);
            }
        }
        Ok(out)
    };
    Ok(Misses {
        omega: Scales::of(&presses(omega)?),
        near: Scales::of(&presses(near)?),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scales_of_gaussian_misses_are_their_standard_deviations() {
        // Misses drawn with a known spread: along N(0, 0.04); across, two components
        // N(0, 0.02) each, whose angle is Rayleigh.
        use rand::{SeedableRng, rngs::StdRng};
        let mut rng = StdRng::seed_from_u64(3);
        let g = |rng: &mut StdRng| crate::sensor::gaussian(rng);
        let misses: Vec<(f64, f64)> = (0..20_000)
            .map(|_| {
                let along = 0.04 * g(&mut rng);
                let across = (0.02 * g(&mut rng)).hypot(0.02 * g(&mut rng));
                (along, across)
            })
            .collect();
        let s = Scales::of(&misses);
        assert!((s.along / 0.04 - 1.0).abs() < 0.03, "along {}", s.along);
        assert!((s.across / 0.02 - 1.0).abs() < 0.03, "across {}", s.across);
        assert_eq!(s.presses, 20_000);
    }

    #[test]
    fn the_pooled_scale_averages_the_sets_variances() {
        let set = |along, across, presses| Scales {
            along,
            across,
            presses,
        };
        let m = Misses {
            omega: set(0.01, 0.004, 40),
            near: set(0.07, 0.032, 40),
        };
        let p = m.pooled();
        assert!((p.along - 0.0025f64.sqrt()).abs() < 1e-12, "{p:?}");
        assert!((p.across - 0.00052f64.sqrt()).abs() < 1e-12, "{p:?}");
        assert_eq!(p.presses, 80);
        // A set with no counted press does not pull the other down.
        let alone = Misses {
            near: set(0.0, 0.0, 0),
            ..m
        };
        assert_eq!(alone.pooled(), set(0.01, 0.004, 40));
    }

    #[test]
    fn a_miss_reads_the_size_and_the_angle() {
        let (along, angle) = miss([0.0, 0.2, 0.0], [0.0, 0.18, 0.018]).expect("torques");
        assert!((along - (1.0 - 0.18f64.hypot(0.018) / 0.2)).abs() < 1e-12);
        assert!((angle - 0.1f64.atan()).abs() < 1e-12);
        assert_eq!(miss([0.0, 0.2, 0.0], [0.0, 0.001, 0.0]), None);
    }
}
