//! Model mismatch: what the map may miss of a measured wrench (physics it does not
//! model), its defaults by the kind of contact a map holds, and how a miss repeated at one
//! place counts.

use ftmap::{Axis, Pose};

use super::lookup::Lookup;
use super::{Config, magnitude};

/// The `mismatch`, `mismatch_angle` and `mismatch_lever` a map's contacts call for where
/// the user leaves them to the map (a negative value).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapMismatch {
    /// Share of the force's and torque's magnitudes along them (`mismatch`).
    pub share: f64,
    /// Angle across them (rad, `mismatch_angle`).
    pub angle: f64,
    /// The pressure centre's miss (m, `mismatch_lever`).
    pub lever: f64,
}

impl MapMismatch {
    /// On a map whose faces meet level: a face pressed on a face, whose pressure centre
    /// wanders over the face with the contact's compliance (the lever term); with 1 % along
    /// and 0.01 rad across, every level task's campaign kept the truth within 2 sigma in
    /// 83.7-95.3 % of its contacts.
    pub const LEVEL: Self = Self {
        share: 0.01,
        angle: 0.01,
        lever: 5e-5,
    };

    /// On a map of the object's tilts about x or y: a tilted face rests on an edge point,
    /// and where two points lie equally low (the horns of a crescent) friction picks one,
    /// so the torque flips from press to press at one place (the tilted hole: +-0.2 N.m
    /// about x), which a frictionless map cannot say. Wider shares, no lever term (the edge
    /// point has no face to wander over): on the tilted hole they kept every trial of four
    /// seeds, where the level ones lost one of three.
    pub const TILTED: Self = Self {
        share: 0.02,
        angle: 0.02,
        lever: 0.0,
    };

    /// The defaults for `lookup`'s map: [`Self::TILTED`] where it samples the object's
    /// tilts about x or y, else [`Self::LEVEL`].
    pub fn of(lookup: &Lookup) -> Self {
        let tilts = lookup
            .axes()
            .iter()
            .any(|a| a.dof.pose == Pose::Object && matches!(a.dof.axis, Axis::Rx | Axis::Ry));
        if tilts { Self::TILTED } else { Self::LEVEL }
    }

    /// `cfg` with each of its three values that is negative replaced by this default.
    pub fn fill(self, cfg: Config) -> Config {
        let or = |v: f64, default: f64| if v < 0.0 { default } else { v };
        Config {
            mismatch: or(cfg.mismatch, self.share),
            mismatch_angle: or(cfg.mismatch_angle, self.angle),
            mismatch_lever: or(cfg.mismatch_lever, self.lever),
            ..cfg
        }
    }
}

/// How far the map may miss a measured force or torque vector: inverse variances across
/// and along its direction.
pub(super) struct Mismatch {
    /// 1 / (sigma^2 + (mismatch_angle |v|)^2): each component, across the measured vector.
    pub across: f32,
    /// The measured vector's direction (zero for a vector too small to have one).
    pub axis: [f32; 3],
    /// 1 / (sigma^2 + (mismatch |v|)^2) - `across`: what the component along `axis` weighs
    /// more (or less) than one across it.
    pub along: f32,
    /// The factor on the mismatch's variances at this contact ([`repeated`]): 1 at a place
    /// pressed for the first time.
    pub repeat: f32,
}

impl Mismatch {
    /// The mismatch of a measured vector `v` whose sensor noise is `sigma`, the vector's
    /// magnitude counted up to the map's `largest` (a wrench beyond anything the map holds
    /// is not excused by its own size), with a miss `fixed` on every component beside its
    /// shares (the torque's from the pressure centre's lever), at the `looks`-th contact at
    /// its place ([`Filter::looks`]).
    pub fn of(c: &Config, sigma: f64, v: &[f64], largest: f64, fixed: f64, looks: f64) -> Self {
        let size = magnitude(v);
        let counted = size.min(largest);
        let missed = |share: f64| (share * counted).powi(2) + fixed * fixed;
        let repeat = repeated(looks, missed(c.mismatch_angle) / (sigma * sigma));
        let inverse = |share: f64| 1.0 / (sigma * sigma + repeat * missed(share));
        let across = inverse(c.mismatch_angle);
        if size <= sigma {
            // No direction to speak of: the smaller of the two weights on every component.
            let w = across.min(inverse(c.mismatch)) as f32;
            return Self {
                across: w,
                axis: [0.0; 3],
                along: 0.0,
                repeat: repeat as f32,
            };
        }
        Self {
            across: across as f32,
            axis: std::array::from_fn(|k| (v[k] / size) as f32),
            along: (inverse(c.mismatch) - across) as f32,
            repeat: repeat as f32,
        }
    }
}

/// The factor on a mismatch variance m at the `k`-th contact at one place (k >= 1, a soft
/// count; `ratio` = m / e, e the sensor noise's variance). The map misses alike at every
/// contact there while the noise is drawn afresh, so k contacts with one residual r weigh
/// r^2 / (m + e / k) together. With variances e + g_j m, g_j = (2 j - 1) + j (j - 1) m / e,
/// contact j weighs 1 / (e + g_j m) = (e / m) (1 / (e + (j - 1) m) - 1 / (e + j m)), and
/// these add up to exactly that. 1 at the first contact; about 2 k - 1 where the noise
/// outweighs the miss; about k^2 m / e where the miss outweighs the noise.
pub(super) fn repeated(k: f64, ratio: f64) -> f64 {
    let k = k.max(1.0);
    (2.0 * k - 1.0) + k * (k - 1.0) * ratio
}
