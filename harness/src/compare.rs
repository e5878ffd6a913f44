//! Comparisons: the agreement of two FT-Maps over the cells of the first (per channel the
//! sign agreement, the correlation and the RMS difference, overall and per region of
//! contact physics: centre, rim, outside; and the mean angle between torque directions),
//! and two campaigns' trials side by side.

use std::fmt;
use std::path::{Path, PathBuf};

use ftmap::{CHANNELS, FtMap, NCH, WrenchModel};

use crate::error::Result;
use crate::plot;
use crate::report::{ContactStats, TrialRow, read_trials_csv};

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

/// Where on the map a cell lies, by the contact the reference map (the computed one of the
/// two, else A) has there: regions of different contact physics.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// The part goes in: the contact depth is below half the deepest of the compared cells.
    Centre = 0,
    /// The part rests on an edge: torque magnitude above [`TORQUE_FLOOR`].
    Rim = 1,
    /// The part rests flat on a surface: no torque.
    Outside = 2,
}

impl Region {
    /// Every region, in table order.
    pub const ALL: [Self; 3] = [Self::Centre, Self::Rim, Self::Outside];

    /// The region's name in tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::Centre => "centre",
            Self::Rim => "rim",
            Self::Outside => "outside",
        }
    }

    /// The region of a cell whose reference values are `v`; `deepest` is the largest
    /// contact depth of the compared cells (m).
    fn of(v: &[f64; NCH], deepest: f64) -> Self {
        if v[6] < 0.5 * deepest {
            Self::Centre
        } else if v[3].hypot(v[4]) > TORQUE_FLOOR {
            Self::Rim
        } else {
            Self::Outside
        }
    }
}

/// The agreement of the two maps within one region.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionAgreement {
    /// The region.
    pub region: Region,
    /// One entry per channel.
    pub channels: Vec<ChannelAgreement>,
}

/// Where one compared cell lies and how far the maps' torques differ there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellDifference {
    /// The cell's coordinates on the first two grid axes (SI).
    pub at: [f64; 2],
    /// Its region.
    pub region: Region,
    /// |(tx, ty) of B - (tx, ty) of A| (N m).
    pub torque: f64,
}

/// The agreement of two maps.
#[derive(Debug, Clone, PartialEq)]
pub struct Agreement {
    /// One entry per channel, over every compared cell.
    pub channels: Vec<ChannelAgreement>,
    /// The same per region.
    pub regions: Vec<RegionAgreement>,
    /// Mean angle between the (tx, ty) vectors where both exceed the floor (rad).
    pub torque_angle_mean: f64,
    /// Root mean square of that angle (rad): the direction part of the maps' mismatch, the
    /// FMU's `mismatch_angle` for a world like A with a map like B.
    pub torque_angle_rms: f64,
    /// Largest such angle (rad).
    pub torque_angle_max: f64,
    /// Mean of |(tx, ty) of B| / |(tx, ty) of A| - 1 over the same cells.
    pub torque_ratio_mean: f64,
    /// Root mean square of that ratio minus 1: the magnitude part of the maps' mismatch,
    /// the FMU's `mismatch`.
    pub torque_ratio_rms: f64,
    /// (a, b) pairs per channel, for plots.
    pub pairs: Vec<Vec<(f64, f64)>>,
    /// Every compared cell, for the plot of where the maps disagree.
    pub cells: Vec<CellDifference>,
    /// Names of the grid's first two axes, along which `cells` lie.
    pub axes: [String; 2],
}

/// Compares `b` with `a` at every cell of `a` that lies inside `b`'s grid; regions are
/// judged by `b` when only `a` is a measured map, else by `a`.
///
/// # Errors
/// When the maps' grids have different DOFs.
pub fn compare(a: &FtMap, b: &FtMap) -> Result<Agreement> {
    let mut compared: Vec<([f64; 2], [f64; NCH], [f64; NCH])> = Vec::new();
    let b_contact = b.contact_depth();
    for cell in 0..a.grid().cells() {
        let c = a.grid().coords(cell);
        if !b.grid().contains(&c) {
            continue;
        }
        let at = [
            c.first().copied().unwrap_or(0.0),
            c.get(1).copied().unwrap_or(0.0),
        ];
        compared.push((
            at,
            a.cell(cell).map(f64::from),
            b.interpolate_contact(&c, b_contact)?,
        ));
    }
    let b_is_reference =
        a.meta().model == WrenchModel::Measured && b.meta().model != WrenchModel::Measured;
    let reference = |va: &[f64; NCH], vb: &[f64; NCH]| if b_is_reference { *vb } else { *va };
    let deepest = compared
        .iter()
        .map(|(_, va, vb)| reference(va, vb)[6])
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max);
    let mut pairs: Vec<Vec<(f64, f64)>> = vec![Vec::new(); NCH];
    let mut by_region: Vec<Vec<Vec<(f64, f64)>>> = vec![vec![Vec::new(); NCH]; Region::ALL.len()];
    let mut cells = Vec::with_capacity(compared.len());
    let (mut angle_max, mut angles, mut ratios) = (0.0f64, Vec::new(), Vec::new());
    for (at, va, vb) in &compared {
        let region = Region::of(&reference(va, vb), deepest);
        let r = region as usize;
        for k in 0..NCH {
            let (x, y) = (va[k], vb[k]);
            if x.is_finite() && y.is_finite() {
                pairs[k].push((x, y));
                by_region[r][k].push((x, y));
            }
        }
        let (ta, tb) = ([va[3], va[4]], [vb[3], vb[4]]);
        cells.push(CellDifference {
            at: *at,
            region,
            torque: (tb[0] - ta[0]).hypot(tb[1] - ta[1]),
        });
        let (na, nb) = (ta[0].hypot(ta[1]), tb[0].hypot(tb[1]));
        if na > TORQUE_FLOOR && nb > TORQUE_FLOOR {
            let cos = ((ta[0] * tb[0] + ta[1] * tb[1]) / (na * nb)).clamp(-1.0, 1.0);
            let ang = cos.acos();
            angle_max = angle_max.max(ang);
            angles.push(ang);
            ratios.push(nb / na - 1.0);
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let rms = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt() / (v.len() as f64).sqrt();
    Ok(Agreement {
        channels: channel_agreements(&pairs),
        regions: Region::ALL
            .iter()
            .zip(&by_region)
            .map(|(&region, p)| RegionAgreement {
                region,
                channels: channel_agreements(p),
            })
            .collect(),
        torque_angle_mean: mean(&angles),
        torque_angle_rms: rms(&angles),
        torque_angle_max: angle_max,
        torque_ratio_mean: mean(&ratios),
        torque_ratio_rms: rms(&ratios),
        pairs,
        cells,
        axes: std::array::from_fn(|k| {
            a.grid()
                .axes()
                .get(k)
                .map_or_else(|| "-".to_owned(), |x| x.dof.to_string())
        }),
    })
}

/// Sign agreement, correlation and RMS difference of each channel's (a, b) pairs.
fn channel_agreements(pairs: &[Vec<(f64, f64)>]) -> Vec<ChannelAgreement> {
    pairs
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
        .collect()
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
    /// A readable table: every channel over all compared cells, then the force and torque
    /// channels across a per region.
    pub fn table(&self) -> String {
        let mut s = format!(
            "  {:<8} {:<7} {:>7} {:>14} {:>12} {:>12}\n",
            "region", "channel", "cells", "sign agreement", "correlation", "RMS diff"
        );
        // NaN: a channel without signs (all zero in a map) or without spread: say so.
        let or_na = |v: f64, text: String| if v.is_nan() { "n/a".to_owned() } else { text };
        let row = |region: &str, c: &ChannelAgreement| {
            format!(
                "  {:<8} {:<7} {:>7} {:>14} {:>12} {:>12.4}\n",
                region,
                c.name,
                c.cells,
                or_na(
                    c.sign_agreement,
                    format!("{:.1}%", 100.0 * c.sign_agreement)
                ),
                or_na(c.correlation, format!("{:.3}", c.correlation)),
                c.rms
            )
        };
        for c in &self.channels {
            s += &row("all", c);
        }
        for r in &self.regions {
            for c in r
                .channels
                .iter()
                .filter(|c| ["fx", "fy", "tx", "ty"].contains(&c.name))
            {
                s += &row(r.region.name(), c);
            }
        }
        s += &format!(
            "  torque direction (tx, ty) angle: mean {:.1} deg, RMS {:.1} deg ({:.3} rad), max {:.1} deg\n",
            self.torque_angle_mean.to_degrees(),
            self.torque_angle_rms.to_degrees(),
            self.torque_angle_rms,
            self.torque_angle_max.to_degrees()
        );
        s += &format!(
            "  torque magnitude |B| / |A| - 1: mean {:+.1} %, RMS {:.1} %\n",
            100.0 * self.torque_ratio_mean,
            100.0 * self.torque_ratio_rms
        );
        s
    }
}

/// Two map files compared: their paths, wrench models and agreement.
#[derive(Debug, Clone, PartialEq)]
pub struct MapComparison {
    /// The files: A (whose cells are compared) and B (interpolated at A's cells).
    pub files: [PathBuf; 2],
    /// Their wrench models.
    pub models: [WrenchModel; 2],
    /// B's agreement with A.
    pub agreement: Agreement,
}

impl MapComparison {
    /// Loads two map files and compares B with A at A's cells.
    ///
    /// # Errors
    /// When a file cannot be loaded or the maps' grids have different DOFs.
    pub fn of_files(a: &Path, b: &Path) -> Result<Self> {
        let (ma, mb) = (ftmap::map::format::load(a)?, ftmap::map::format::load(b)?);
        Ok(Self {
            files: [a.to_owned(), b.to_owned()],
            models: [ma.meta().model, mb.meta().model],
            agreement: compare(&ma, &mb)?,
        })
    }

    /// Scatter plot of tx and ty, B against A, and where on the map their torques differ.
    ///
    /// # Errors
    /// When the image cannot be written.
    pub fn plot(&self, png: &Path) -> Result<()> {
        let differences: Vec<([f64; 2], f64)> = self
            .agreement
            .cells
            .iter()
            .map(|c| (c.at, c.torque))
            .collect();
        plot::agreement(
            png,
            &["tx [N m]", "ty [N m]"],
            &self.agreement.pairs[3..5],
            ["A", "B"],
            (
                &differences,
                [&self.agreement.axes[0], &self.agreement.axes[1]],
            ),
        )
    }
}

impl fmt::Display for MapComparison {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "A = {} ({:?}), B = {} ({:?})",
            self.files[0].display(),
            self.models[0],
            self.files[1].display(),
            self.models[1]
        )?;
        f.write_str(&self.agreement.table())
    }
}

/// Two campaigns side by side: their folders' names and their `trials.csv` rows.
#[derive(Debug, Clone, PartialEq)]
pub struct RunsComparison {
    /// The campaigns' names (their output folders' names).
    pub names: [String; 2],
    /// Their trials.
    pub runs: [Vec<TrialRow>; 2],
}

impl RunsComparison {
    /// Reads the `trials.csv` of two campaigns' output folders.
    ///
    /// # Errors
    /// When a file cannot be read or holds a malformed row.
    pub fn read(a: &Path, b: &Path) -> Result<Self> {
        let name = |p: &Path| {
            p.file_name().map_or_else(
                || p.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            )
        };
        Ok(Self {
            runs: [
                read_trials_csv(&a.join("trials.csv"))?,
                read_trials_csv(&b.join("trials.csv"))?,
            ],
            names: [name(a), name(b)],
        })
    }

    /// Bar plot of the contacts per trial.
    ///
    /// # Errors
    /// When the image cannot be written.
    pub fn plot(&self, png: &Path) -> Result<()> {
        plot::contacts_per_trial(
            png,
            [&self.names[0], &self.names[1]],
            [&self.runs[0], &self.runs[1]],
        )
    }
}

impl fmt::Display for RunsComparison {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&comparison_table(
            [&self.names[0], &self.names[1]],
            [&self.runs[0], &self.runs[1]],
        ))
    }
}

/// Two campaigns side by side (contacts, contact measurements, y spread), and, when they ran
/// the same true offsets, in how many trials the first needed fewer, as many or more contacts.
fn comparison_table(names: [&str; 2], runs: [&[TrialRow]; 2]) -> String {
    let stats =
        |r: &[TrialRow], f: fn(&TrialRow) -> f64| ContactStats::of(r.iter().map(f).collect());
    let row = |label: &str, f: &dyn Fn(&[TrialRow]) -> String| {
        format!("  {label:<44} {:>22} {:>22}\n", f(runs[0]), f(runs[1]))
    };
    let quartet = |c: ContactStats| format!("{:.2} / {} / {} / {}", c.mean, c.median, c.p95, c.max);
    let mut out = format!("  {:<44} {:>22} {:>22}\n", "", names[0], names[1]);
    out += &row("trials", &|r| r.len().to_string());
    out += &row("success rate", &|r| {
        format!(
            "{:.1} %",
            100.0 * r.iter().filter(|t| t.success).count() as f64 / r.len().max(1) as f64
        )
    });
    out += &row("contacts mean / median / p95 / max", &|r| {
        quartet(stats(r, |t| t.contacts as f64))
    });
    out += &row("contact measurements mean / median / p95 / max", &|r| {
        quartet(stats(r, |t| t.measurements as f64))
    });
    out += &row("object.y_std after the first contact (mean)", &|r| {
        let v: Vec<f64> = r.iter().filter_map(|t| t.y_std_first_contact_m).collect();
        if v.is_empty() {
            "-".into()
        } else {
            format!("{:.4} mm", 1e3 * v.iter().sum::<f64>() / v.len() as f64)
        }
    });
    let paired = runs[0].len() == runs[1].len()
        && runs[0].iter().zip(runs[1]).all(|(a, b)| {
            (a.offset_x_m - b.offset_x_m).abs() < 1e-9 && (a.offset_y_m - b.offset_y_m).abs() < 1e-9
        });
    if paired {
        let count = |f: fn(usize, usize) -> bool| {
            runs[0]
                .iter()
                .zip(runs[1])
                .filter(|(a, b)| f(a.contacts, b.contacts))
                .count()
        };
        out += &format!(
            "  same true offsets: {} needed fewer contacts in {}, as many in {}, more in {} trials\n",
            names[0],
            count(|a, b| a < b),
            count(|a, b| a == b),
            count(|a, b| a > b)
        );
    } else {
        out += "  the campaigns ran different true offsets: no trial-by-trial comparison\n";
    }
    out
}
