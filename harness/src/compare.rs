//! Agreement of two FT-Maps over the cells of the first: per channel the sign agreement,
//! the correlation and the RMS difference, and the mean angle between torque directions.

use ftmap::{CHANNELS, FtMap, NCH};

use crate::error::Result;

/// Torques below this magnitude (N m) carry no sign: cells where either map is below it
/// are left out of the sign and direction figures.
pub const TORQUE_FLOOR: f64 = 0.005;

/// Agreement of one channel.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelAgreement {
    /// Channel name.
    pub name: &'static str,
    /// Cells compared.
    pub cells: usize,
    /// Fraction of the cells (with both values above the floor) whose signs agree.
    pub sign_agreement: f64,
    /// Pearson correlation.
    pub correlation: f64,
    /// RMS of the difference.
    pub rms: f64,
}

/// The agreement of two maps.
#[derive(Debug, Clone, PartialEq)]
pub struct Agreement {
    /// One entry per channel.
    pub channels: Vec<ChannelAgreement>,
    /// Mean angle between the (tx, ty) vectors where both exceed the floor (rad).
    pub torque_angle_mean: f64,
    /// Largest such angle (rad).
    pub torque_angle_max: f64,
    /// (a, b) pairs per channel, for plots.
    pub pairs: Vec<Vec<(f64, f64)>>,
}

/// Compares `b` with `a` at every cell of `a` that lies inside `b`'s grid.
///
/// # Errors
/// When the maps' grids have different DOFs.
pub fn compare(a: &FtMap, b: &FtMap) -> Result<Agreement> {
    let mut pairs: Vec<Vec<(f64, f64)>> = vec![Vec::new(); NCH];
    let (mut angle_sum, mut angle_max, mut angles) = (0.0, 0.0f64, 0usize);
    for cell in 0..a.grid().cells() {
        let c = a.grid().coords(cell);
        if !b.grid().contains(&c) {
            continue;
        }
        let vb = b.interpolate(&c)?;
        let va = a.cell(cell);
        for k in 0..NCH {
            let (x, y) = (f64::from(va[k]), vb[k]);
            if x.is_finite() && y.is_finite() {
                pairs[k].push((x, y));
            }
        }
        let (ta, tb) = ([f64::from(va[3]), f64::from(va[4])], [vb[3], vb[4]]);
        let (na, nb) = (ta[0].hypot(ta[1]), tb[0].hypot(tb[1]));
        if na > TORQUE_FLOOR && nb > TORQUE_FLOOR {
            let cos = ((ta[0] * tb[0] + ta[1] * tb[1]) / (na * nb)).clamp(-1.0, 1.0);
            let ang = cos.acos();
            angle_sum += ang;
            angle_max = angle_max.max(ang);
            angles += 1;
        }
    }
    let channels = pairs
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let floor = if (3..6).contains(&k) {
                TORQUE_FLOOR
            } else {
                1e-6
            };
            let signed: Vec<_> = p
                .iter()
                .filter(|(x, y)| x.abs() > floor && y.abs() > floor)
                .collect();
            let agree = signed
                .iter()
                .filter(|(x, y)| x.signum() == y.signum())
                .count();
            ChannelAgreement {
                name: CHANNELS[k],
                cells: p.len(),
                sign_agreement: if signed.is_empty() {
                    f64::NAN
                } else {
                    agree as f64 / signed.len() as f64
                },
                correlation: correlation(p),
                rms: (p.iter().map(|(x, y)| (x - y).powi(2)).sum::<f64>() / p.len().max(1) as f64)
                    .sqrt(),
            }
        })
        .collect();
    let mean = if angles == 0 {
        f64::NAN
    } else {
        angle_sum / angles as f64
    };
    Ok(Agreement {
        channels,
        torque_angle_mean: mean,
        torque_angle_max: angle_max,
        pairs,
    })
}

fn correlation(p: &[(f64, f64)]) -> f64 {
    let n = p.len() as f64;
    if p.len() < 2 {
        return f64::NAN;
    }
    let (mx, my) = (
        p.iter().map(|q| q.0).sum::<f64>() / n,
        p.iter().map(|q| q.1).sum::<f64>() / n,
    );
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in p {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    if sxx <= 0.0 || syy <= 0.0 {
        f64::NAN
    } else {
        sxy / (sxx * syy).sqrt()
    }
}

impl Agreement {
    /// A readable table.
    pub fn table(&self) -> String {
        let mut s = format!(
            "  {:<7} {:>7} {:>14} {:>12} {:>12}\n",
            "channel", "cells", "sign agreement", "correlation", "RMS diff"
        );
        // NaN: a channel without signs (all zero in a map) or without spread: say so.
        let or_na = |v: f64, text: String| if v.is_nan() { "n/a".to_owned() } else { text };
        for c in &self.channels {
            s += &format!(
                "  {:<7} {:>7} {:>14} {:>12} {:>12.4}\n",
                c.name,
                c.cells,
                or_na(
                    c.sign_agreement,
                    format!("{:.1}%", 100.0 * c.sign_agreement)
                ),
                or_na(c.correlation, format!("{:.3}", c.correlation)),
                c.rms
            );
        }
        s += &format!(
            "  torque direction (tx, ty) angle: mean {:.1} deg, max {:.1} deg\n",
            self.torque_angle_mean.to_degrees(),
            self.torque_angle_max.to_degrees()
        );
        s
    }
}
