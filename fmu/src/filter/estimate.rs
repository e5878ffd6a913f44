//! The estimate of a weighted particle set: particles binned into the map's cells,
//! clusters as connected groups of occupied cells, the weighted mode of the dominant
//! cluster (refined by the weighted mean around it), its spread about that estimate, and
//! the confidence.

use ftmap::{Axis, Pose};

use super::{Config, Lookup};

/// Share of the total weight a cluster must hold to be counted.
const CLUSTER_SHARE: f64 = 0.05;

/// What the filter reports after a measurement.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Estimate {
    /// Estimated pose value per map axis (m or rad).
    pub pose: Vec<f64>,
    /// Weighted root-mean-square distance of every particle from the estimate per map axis:
    /// the estimate's expected error, the other clusters included (about the dominant
    /// cluster's spread when it holds the weight).
    pub std: Vec<f64>,
    /// Correlation of the `object.x` and `object.y` axes over the particles about the
    /// estimate (0 unless the map has both).
    pub xy_corr: f64,
    /// Weight within the confidence radius of the estimate (0..1).
    pub confidence: f64,
    /// confidence > threshold.
    pub converged: bool,
    /// Effective sample size.
    pub ess: f64,
    /// Clusters holding at least 5 % of the weight (at least 1).
    pub clusters: u32,
}

/// Union-find root of `i` with path halving.
fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

impl Estimate {
    /// Computes the estimate of particles `pos` (grid units, axis-major) with normalised
    /// log weights `lw`.
    pub fn compute(lookup: &Lookup, cfg: &Config, pos: &[f32], lw: &[f32]) -> Self {
        let n = lw.len();
        let axes = lookup.axes();
        let d = axes.len();
        let w: Vec<f64> = lw.iter().map(|&l| f64::from(l).exp()).collect();
        // Samples per turn of a periodic axis (its last sample is its first), else all.
        let samples = |a: &super::MapAxis| a.period.map_or(a.count, |p| p as usize);
        let cell_of = |i: usize| -> usize {
            axes.iter()
                .enumerate()
                .map(|(k, a)| {
                    ((a.fold(pos[k * n + i]) + 0.5) as usize % samples(a).max(1)) * a.stride
                })
                .sum()
        };
        let mut order: Vec<(usize, u32)> = (0..n).map(|i| (cell_of(i), i as u32)).collect();
        order.sort_unstable();
        // Occupied cells: (cell, weight, first, end) over `order`.
        let mut cells: Vec<(usize, f64, usize, usize)> = Vec::new();
        for (j, &(cell, i)) in order.iter().enumerate() {
            match cells.last_mut() {
                Some(last) if last.0 == cell => {
                    last.1 += w[i as usize];
                    last.3 = j + 1;
                }
                _ => cells.push((cell, w[i as usize], j, j + 1)),
            }
        }
        let mut parent: Vec<usize> = (0..cells.len()).collect();
        for (c, &(key, ..)) in cells.iter().enumerate() {
            for a in axes {
                let i = (key / a.stride) % a.count;
                // The next sample along the axis, round the turn on a periodic one.
                let next = match a.period {
                    Some(_) if samples(a) > 1 => Some((i + 1) % samples(a)),
                    _ => (i + 1 < a.count).then_some(i + 1),
                };
                if let Some(j) = next
                    && let Ok(nb) =
                        cells.binary_search_by_key(&(key - i * a.stride + j * a.stride), |x| x.0)
                {
                    let (ra, rb) = (root(&mut parent, c), root(&mut parent, nb));
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        let mut comp_weight = vec![0.0f64; cells.len()];
        for (c, cell) in cells.iter().enumerate() {
            let r = root(&mut parent, c);
            comp_weight[r] += cell.1;
        }
        let total: f64 = comp_weight.iter().sum();
        let clusters = comp_weight
            .iter()
            .filter(|&&x| x >= CLUSTER_SHARE * total && x > 0.0)
            .count()
            .max(1) as u32;
        let dominant = (0..cells.len()).fold(0, |best, c| {
            if comp_weight[c] > comp_weight[best] {
                c
            } else {
                best
            }
        });
        let members: Vec<usize> = (0..cells.len())
            .filter(|&c| root(&mut parent, c) == dominant)
            .collect();
        let mode =
            members.iter().copied().fold(
                members[0],
                |b, c| if cells[c].1 > cells[b].1 { c } else { b },
            );
        let index = |cell: usize, a: &super::MapAxis| ((cell / a.stride) % a.count) as f32;
        // Grid coordinates' difference `u - v`, the shortest way round on a periodic axis.
        let diff = |k: usize, u: f32, v: f32| f64::from(axes[k].difference(u - v));

        // Weighted mean of the particles within one cell of the mode (about the mode, so
        // that a periodic axis's mean does not straddle the turn).
        let at_mode: Vec<f32> = axes.iter().map(|a| index(cells[mode].0, a)).collect();
        let mut near = vec![0.0f64; d];
        let mut near_w = 0.0;
        for &c in &members {
            let close = axes
                .iter()
                .enumerate()
                .all(|(k, a)| diff(k, index(cells[c].0, a), at_mode[k]).abs() <= 1.0);
            if !close {
                continue;
            }
            for &(_, i) in &order[cells[c].2..cells[c].3] {
                let i = i as usize;
                for k in 0..d {
                    near[k] += w[i] * diff(k, pos[k * n + i], at_mode[k]);
                }
                near_w += w[i];
            }
        }
        let est: Vec<f64> = near
            .iter()
            .zip(axes)
            .zip(&at_mode)
            .map(|((s, a), &m)| {
                let offset = if near_w > 0.0 { s / near_w } else { 0.0 };
                f64::from(a.fold((f64::from(m) + offset) as f32))
            })
            .collect();
        // Every particle's mean squared distance from the estimate (the other clusters are
        // where the truth may be too), and the x-y cross term.
        let object = |axis| {
            axes.iter()
                .position(|a| a.dof.pose == Pose::Object && a.dof.axis == axis)
        };
        let xy = object(Axis::X).zip(object(Axis::Y));
        let mut var = vec![0.0f64; d];
        let (mut cov_xy, mut cluster_w) = (0.0, 0.0);
        for cell in &cells {
            for &(_, i) in &order[cell.2..cell.3] {
                let i = i as usize;
                let e = |k: usize| diff(k, pos[k * n + i], est[k] as f32);
                for (k, v) in var.iter_mut().enumerate() {
                    *v += w[i] * e(k) * e(k);
                }
                if let Some((kx, ky)) = xy {
                    cov_xy += w[i] * e(kx) * e(ky);
                }
                cluster_w += w[i];
            }
        }
        let xy_corr = xy.map_or(0.0, |(kx, ky)| {
            let norm = (var[kx] * var[ky]).sqrt();
            if norm > 0.0 {
                (cov_xy / norm).clamp(-1.0, 1.0)
            } else {
                0.0
            }
        });

        // Confidence: weight within the radius, in grid intervals of the finest translation.
        let ref_step = axes
            .iter()
            .filter(|a| !a.dof.is_rotation())
            .map(|a| a.step)
            .reduce(f64::min)
            .unwrap_or_else(|| axes.iter().map(|a| a.step).fold(f64::INFINITY, f64::min));
        let r = cfg.confidence_radius / ref_step;
        let r2 = r * r;
        // Translations in that interval's units, rotations in their own grid intervals.
        let scale: Vec<f64> = axes
            .iter()
            .map(|a| {
                if a.dof.is_rotation() {
                    1.0
                } else {
                    a.step / ref_step
                }
            })
            .collect();
        let mut confidence = 0.0;
        for i in 0..n {
            let dist2: f64 = (0..d)
                .map(|k| {
                    let e = diff(k, pos[k * n + i], est[k] as f32) * scale[k];
                    e * e
                })
                .sum();
            if dist2 <= r2 {
                confidence += w[i];
            }
        }
        let confidence = (confidence / total).clamp(0.0, 1.0);
        let sum_w2: f64 = w.iter().map(|x| x * x).sum();
        Self {
            pose: axes
                .iter()
                .zip(&est)
                .map(|(a, &u)| a.min + u * a.step)
                .collect(),
            std: axes
                .iter()
                .zip(&var)
                .map(|(a, &v)| (v / cluster_w.max(f64::MIN_POSITIVE)).sqrt() * a.step)
                .collect(),
            xy_corr,
            confidence,
            converged: confidence > cfg.threshold,
            ess: if sum_w2 > 0.0 {
                total * total / sum_w2
            } else {
                0.0
            },
            clusters,
        }
    }
}
