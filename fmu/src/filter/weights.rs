//! Eq. 3 in log space for a batch of predicted cells at once: how a predicted cell is
//! weighed against a measurement ([`Weights`]), written without branches over the batch so
//! that it runs in vector lanes, with a logarithm that does too ([`ln`]).

use ftmap::NCH;

/// Channels per padded cell: fx fy fz tx ty tz depth, contact (1) or inserted (0).
pub const LANES: usize = 8;
/// Mismatch terms per cell: the squared slopes of the force and of the torque, then the
/// variances of their multilinear interpolation error (both from the lookup's map); each the
/// mean over the vector's x and y components, across the tool's axis.
pub(super) const TERMS: usize = 4;
/// The first of the interpolation-error terms.
pub(super) const INTERPOLATION: usize = 2;
/// The lane that flags a contact cell.
pub(super) const CONTACT: usize = LANES - 1;

/// Predictions weighed together ([`Weights::log_likelihoods`]).
pub(super) const BATCH: usize = 8;

/// Predicted cells with their mismatch terms, channel by channel: `lanes[l][j]` is channel
/// `l` of prediction `j`.
#[derive(Debug, Clone, Default)]
pub(super) struct Batch {
    pub(super) lanes: [[f32; BATCH]; LANES],
    pub(super) terms: [[f32; BATCH]; TERMS],
}

impl Batch {
    /// Puts the channels `lanes` and terms `terms` of a prediction in place `j`.
    #[inline(always)]
    pub(super) fn set(&mut self, j: usize, lanes: &[f32; LANES], terms: &[f32; TERMS]) {
        for (l, v) in lanes.iter().enumerate() {
            self.lanes[l][j] = *v;
        }
        for (l, v) in terms.iter().enumerate() {
            self.terms[l][j] = *v;
        }
    }
}

/// How a predicted cell is weighed against a measurement (Eq. 3 in log space): each
/// channel's residual squared times its inverse variance, plus, for the force and torque
/// vectors, `along` times the square of the residual's component along `axis` (the measured
/// vector's direction), so that the map may miss a vector's magnitude by more (or less)
/// than its direction. Where the map may miss the contact's position (`position`), the x
/// and y components of the force and the torque (across the tool's axis, where a contact
/// displaced across it moves them) get that much more variance per unit of their squared
/// slope at the particle, and the likelihood its normalisation (a particle on a steep slope
/// explains a wide range of measurements, each less well). The multilinear lookup's own
/// error, large where the field bends within a cell (round the hole, where the rim torque
/// turns), adds its variance to the same components (`interpolation`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Weights {
    /// Measured channels, padded.
    pub meas: [f32; LANES],
    /// Inverse variances of the channels (0: unused).
    pub inv_var: [f32; LANES],
    /// Unit direction of the measured force and torque (zero: none).
    pub axis: [[f32; 3]; 2],
    /// Extra inverse variance along each `axis`.
    pub along: [f32; 2],
    /// Variance added to the force's and torque's x and y components per unit of their
    /// squared slope (m^2: the square of the position the map may miss, in each axis across
    /// the approach), for the force and the torque.
    pub position: [f32; 2],
    /// Share of the lookup's interpolation-error variance (the terms from `INTERPOLATION` on)
    /// that counts, for the force and the torque: the `mismatch_interpolation` parameter for the
    /// multilinear lookup, 0 for the nearest cell (whose error, that share of the cell's
    /// width, is in `position`).
    pub interpolation: [f32; 2],
    /// Degrees of freedom of a Student-t likelihood over the channels used; 0: Gaussian.
    pub tail: f32,
    /// Relative tilt (rad) below which the force and torque are read where the tilt's
    /// direction meets this radius (the lookup's tilts); 0: where the particle lies.
    pub tilt_floor: f32,
    /// The channels used (inverse variance above 0), counted once by [`Weights::student`].
    pub(crate) channels: f32,
}

impl Weights {
    /// Weights of `meas` with inverse variances `inv_var` alone (no direction term).
    pub fn diagonal(meas: [f32; LANES], inv_var: [f32; LANES]) -> Self {
        Self {
            meas,
            inv_var,
            ..Self::default()
        }
    }

    /// These weights with a Student-t likelihood of `tail` degrees of freedom (0: Gaussian)
    /// over the channels `inv_var` uses.
    pub fn student(self, tail: f32) -> Self {
        Self {
            tail,
            channels: self.inv_var.iter().filter(|v| **v > 0.0).count() as f32,
            ..self
        }
    }

    /// Writes into `out` the log-likelihood of the first `out.len()` predictions of `batch`,
    /// whose force and torque have the mismatch terms of the batch ([`TERMS`]; constants
    /// of the measurement dropped: 0 for a perfect prediction without them). The contact
    /// lane's inverse variance is 0. Without branches over the batch: each prediction's
    /// covariance is chosen by a select, so that the loop runs in vector lanes.
    pub(super) fn log_likelihoods(&self, batch: &Batch, out: &mut [f32]) {
        let (p, t) = (&batch.lanes, &batch.terms);
        let mut ll = [0.0f32; BATCH];
        for (j, o) in ll.iter_mut().enumerate() {
            let mut chi2 = 0.0f32;
            // How much larger the determinant of the covariance is than without the terms.
            let mut ratio = 1.0f32;
            for g in 0..2 {
                let r: [f32; 3] = std::array::from_fn(|k| self.meas[3 * g + k] - p[3 * g + k][j]);
                let a = &self.axis[g];
                let across = self.inv_var[3 * g];
                let extra =
                    self.position[g] * t[g][j] + self.interpolation[g] * t[INTERPOLATION + g][j];
                // Covariance D + c a a^T, D diagonal: the variance across plus `extra` on
                // x and y, c the variance along less that across; its inverse by
                // Sherman-Morrison.
                let va = 1.0 / across;
                let c = 1.0 / (across + self.along[g]) - va;
                let inv = 1.0 / (va + extra);
                let q = inv * (r[0] * r[0] + r[1] * r[1]) + across * r[2] * r[2];
                let ad = inv * (a[0] * r[0] + a[1] * r[1]) + across * a[2] * r[2];
                let aa = inv * (a[0] * a[0] + a[1] * a[1]) + across * a[2] * a[2];
                let den = 1.0 + c * aa;
                let base = 1.0 + c * across * (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
                let grown = 1.0 + extra * across;
                // Without the terms: each channel's own inverse variance.
                let along = r[0] * a[0] + r[1] * a[1] + r[2] * a[2];
                let mut diagonal = chi2;
                for (k, v) in r.iter().enumerate() {
                    diagonal += self.inv_var[3 * g + k] * v * v;
                }
                diagonal += self.along[g] * along * along;
                let widened = extra > 0.0 && across > 0.0;
                chi2 = if widened {
                    chi2 + (q - c * ad * ad / den)
                } else {
                    diagonal
                };
                ratio *= if widened {
                    grown * grown * den / base
                } else {
                    1.0
                };
            }
            // The depth and the contact lane (whose inverse variance is 0).
            let rest = NCH - 1..LANES;
            for ((m, p), v) in self.meas[rest.clone()]
                .iter()
                .zip(&p[rest.clone()])
                .zip(&self.inv_var[rest])
            {
                let d = m - p[j];
                chi2 += v * d * d;
            }
            let fit = if self.tail > 0.0 {
                // Multivariate Student-t in the Gaussian's chi^2 over the d channels used:
                // log (1 + chi^2 / nu) ^ (-(nu + d) / 2).
                -0.5 * (self.tail + self.channels) * ln(1.0 + chi2 / self.tail)
            } else {
                -0.5 * chi2
            };
            *o = if ratio > 1.0 {
                fit - 0.5 * ln(ratio)
            } else {
                fit
            };
        }
        let n = out.len().min(BATCH);
        out[..n].copy_from_slice(&ll[..n]);
    }
}

/// The natural logarithm of a normal positive `x` (+inf and NaN pass through), without a
/// branch or a call: Cephes' `logf` (x = m 2^e with m in [sqrt(1/2), sqrt(2)), a degree-9
/// polynomial in m - 1), within a few units in the last place of `f32::ln`.
#[inline(always)]
pub(super) fn ln(x: f32) -> f32 {
    const P: [f32; 9] = [
        7.037_683_6e-2,
        -1.151_461e-1,
        1.167_699_9e-1,
        -1.242_014_1e-1,
        1.424_932_3e-1,
        -1.666_805_8e-1,
        2.000_071_4e-1,
        -2.499_999_4e-1,
        3.333_333e-1,
    ];
    let bits = x.to_bits();
    // x = m 2^e, m in [1/2, 1).
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f00_0000);
    let e = ((bits >> 23) & 0xff) as i32 - 126;
    let low = m < std::f32::consts::FRAC_1_SQRT_2;
    let (f, e) = if low {
        (m + m - 1.0, (e - 1) as f32)
    } else {
        (m - 1.0, e as f32)
    };
    let z = f * f;
    let y = P.iter().fold(0.0, |acc, c| acc * f + c) * f * z - 2.121_944_4e-4 * e - 0.5 * z;
    let r = f + y + 0.693_359_4 * e;
    if x < f32::INFINITY { r } else { x }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix3, Vector3};

    use super::*;

    /// The log-likelihood of one prediction.
    fn one(w: &Weights, pred: &[f32; LANES], terms: &[f32; TERMS]) -> f32 {
        let mut batch = Batch::default();
        batch.set(3, pred, terms);
        let mut out = [0.0; BATCH];
        w.log_likelihoods(&batch, &mut out);
        out[3]
    }

    /// The terms' log-likelihood in f64 with each group's covariance written out: across
    /// `va`, along the measured vector `vb`, plus `position` times the slope and
    /// `interpolation` times the interpolation error on x and y; less the log determinant
    /// of the covariance without them.
    fn written_out(w: &Weights, pred: &[f32; LANES], terms: &[f32; TERMS]) -> f64 {
        let mut ll = 0.0;
        for g in 0..2 {
            let a = Vector3::from_iterator(w.axis[g].iter().map(|v| f64::from(*v)));
            let va = 1.0 / f64::from(w.inv_var[3 * g]);
            let vb = 1.0 / (f64::from(w.inv_var[3 * g]) + f64::from(w.along[g]));
            let base = Matrix3::identity() * va + a * a.transpose() * (vb - va);
            let e = f64::from(w.position[g]) * f64::from(terms[g])
                + f64::from(w.interpolation[g]) * f64::from(terms[INTERPOLATION + g]);
            let slope = Matrix3::from_diagonal(&Vector3::new(e, e, 0.0));
            let cov = base + slope;
            let r = Vector3::from_iterator(
                (0..3).map(|k| f64::from(w.meas[3 * g + k]) - f64::from(pred[3 * g + k])),
            );
            let chi2 = (r.transpose() * cov.try_inverse().expect("invertible") * r)[0];
            ll += -0.5 * chi2 - 0.5 * (cov.determinant() / base.determinant()).ln();
        }
        ll
    }

    #[test]
    fn mismatch_terms_widen_the_likelihood_as_the_covariance_written_out_does() {
        let meas = [0.3, -0.2, 20.0, 0.12, 0.05, 0.001, 0.0, 0.0];
        let pred = [0.25, -0.1, 19.0, 0.10, 0.07, 0.0, 0.0, 1.0];
        let unit = |v: &[f32]| {
            let n = v.iter().map(|x| x * x).sum::<f32>().sqrt();
            [v[0] / n, v[1] / n, v[2] / n]
        };
        // Along the measured force it may miss more than across, along the torque less.
        let (va, vb) = ([1e-2f32, 1e-5], [3e-2f32, 0.5e-5]);
        let mut inv_var = [0.0f32; LANES];
        inv_var[..3].fill(1.0 / va[0]);
        inv_var[3..6].fill(1.0 / va[1]);
        let w = Weights {
            meas,
            inv_var,
            axis: [unit(&meas[..3]), unit(&meas[3..6])],
            along: [1.0 / vb[0] - 1.0 / va[0], 1.0 / vb[1] - 1.0 / va[1]],
            position: [2.5e-11, 4e-11],
            interpolation: [0.7, 0.5],
            ..Weights::default()
        };
        for terms in [
            [1e9, 4e6, 0.0, 0.0],
            [0.0, 6e6, 0.0, 0.0],
            [4e8, 0.0, 0.0, 0.0],
            [0.0, 0.0, 2e-3, 4e-5],
            [1e9, 4e6, 0.0, 2e-4],
            [0.0; TERMS],
        ] {
            let got = f64::from(one(&w, &pred, &terms));
            let want = written_out(&w, &pred, &terms);
            assert!(
                (got - want).abs() < 1e-4 * (1.0 + want.abs()),
                "terms {terms:?}: {got} against {want}"
            );
        }
        // Steeper, the same residual costs less, and a perfect prediction more.
        let steep = [0.0, 6e6, 0.0, 0.0];
        assert!(one(&w, &pred, &steep) > one(&w, &pred, &[0.0; TERMS]));
        assert!(one(&w, &meas, &steep) < one(&w, &meas, &[0.0; TERMS]));
    }

    #[test]
    fn the_logarithm_matches_f64s_over_every_binade() {
        let mut worst = 0.0f64;
        for k in -126..128 {
            for m in 0..997 {
                let x = (1.0 + m as f32 / 997.0) * 2f32.powi(k);
                let want = f64::from(x).ln();
                worst = worst.max((f64::from(ln(x)) - want).abs() / want.abs().max(1.0));
            }
        }
        assert!(worst < 4.0 * f64::from(f32::EPSILON), "worst error {worst}");
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert!(ln(f32::NAN).is_nan());
    }

    #[test]
    fn a_batch_weighs_each_prediction_as_it_weighs_it_alone() {
        let meas = [0.3, -0.2, 20.0, 0.12, 0.05, 0.001, 0.004, 0.0];
        let mut inv_var = [0.0f32; LANES];
        inv_var[..3].copy_from_slice(&[100.0, 120.0, 80.0]);
        inv_var[3..6].fill(1e5);
        inv_var[6] = 1e6;
        let w = Weights {
            meas,
            inv_var,
            axis: [[0.0, 0.0, 1.0], [0.6, 0.8, 0.0]],
            along: [50.0, 2e4],
            position: [2.5e-11, 4e-11],
            interpolation: [0.7, 0.5],
            ..Weights::diagonal(meas, inv_var)
        }
        .student(4.0);
        let mut batch = Batch::default();
        let preds: Vec<([f32; LANES], [f32; TERMS])> = (0..BATCH)
            .map(|j| {
                let s = j as f32;
                let mut pred = meas;
                pred[0] += 0.05 * s;
                pred[4] -= 0.01 * s;
                pred[6] += 1e-4 * s;
                pred[CONTACT] = 1.0;
                // Every other prediction without terms: the diagonal covariance.
                let terms = if j % 2 == 0 {
                    [0.0; TERMS]
                } else {
                    [1e9 * s, 4e6, 2e-3, 0.0]
                };
                (pred, terms)
            })
            .collect();
        for (j, (pred, terms)) in preds.iter().enumerate() {
            batch.set(j, pred, terms);
        }
        let mut out = [0.0; BATCH];
        w.log_likelihoods(&batch, &mut out);
        for (j, (pred, terms)) in preds.iter().enumerate() {
            assert_eq!(out[j], one(&w, pred, terms), "prediction {j}");
        }
        assert!(out.iter().all(|l| l.is_finite()) && out[0] > out[BATCH - 2]);
        // Fewer places than the batch: only those written.
        let mut short = [7.0; 3];
        w.log_likelihoods(&batch, &mut short);
        assert_eq!(short, [out[0], out[1], out[2]]);
    }
}
