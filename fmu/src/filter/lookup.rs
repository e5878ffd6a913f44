//! The FT-Map as the filter reads it: cells padded to eight `f32` channels, axes in grid
//! units, and the log-likelihood of Eq. 3 for a whole particle set in one pass (nearest
//! cell or multilinear, specialised per number of axes).
//!
//! A wrench is measured where part A rests on part B, never where it went in: the wrench of
//! an inserted cell (the depth channel at the inserted end of its range) says nothing about
//! a contact. Its wrench channels are masked (the eighth lane holds 1 for a contact cell, 0
//! for an inserted one) and an interpolation renormalises the wrench over the contact
//! corners: a particle 0.06 mm off the hole's centre on a 0.1 mm grid reads the rim's
//! torque, not a blend with the inserted centre's zero torque. The depth channel is not
//! masked.

use std::path::Path;

use ftmap::{Axis, Dof, FtMap, NCH, Pose};

use crate::error::{FusionError, Result};

/// Channels per padded cell: fx fy fz tx ty tz depth, contact (1) or inserted (0).
pub const LANES: usize = 8;
/// The lane that flags a contact cell.
const CONTACT: usize = LANES - 1;

/// One axis of the map in the filter's terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapAxis {
    /// The DOF the axis samples.
    pub dof: Dof,
    /// Value of sample 0 (m or rad).
    pub min: f64,
    /// Grid interval (m or rad).
    pub step: f64,
    /// Number of samples.
    pub count: usize,
    /// Flat-index distance between neighbours along the axis.
    pub stride: usize,
    /// Component 0..6 of the TCP pose that moves this axis's map coordinate, if any.
    pub tcp: Option<usize>,
    /// Period in grid units where the axis wraps around (`object.rz` of a map with an
    /// n-fold symmetry about the approach: 2 pi / n, the whole axis).
    pub period: Option<f32>,
}

impl MapAxis {
    /// Largest grid coordinate (count - 1).
    pub fn top(&self) -> f32 {
        (self.count - 1) as f32
    }

    /// SI value of grid coordinate `u`.
    pub fn value(&self, u: f32) -> f64 {
        self.min + f64::from(u) * self.step
    }

    /// Grid coordinate of SI value `x` (not clamped).
    pub fn coord(&self, x: f64) -> f32 {
        ((x - self.min) / self.step) as f32
    }

    /// Grid coordinate `u` brought into the axis: wrapped into [0, period) on a periodic
    /// axis, clamped into [0, top] on another.
    #[inline(always)]
    pub fn fold(&self, u: f32) -> f32 {
        match self.period {
            Some(p) => {
                let w = u.rem_euclid(p);
                // rem_euclid may round up to p itself for a tiny negative u.
                if w >= p { 0.0 } else { w }
            }
            None => u.clamp(0.0, self.top()),
        }
    }

    /// The difference `d` of two grid coordinates, the shortest way round on a periodic axis.
    #[inline(always)]
    pub fn difference(&self, d: f32) -> f32 {
        match self.period {
            Some(p) => d - p * (d / p).round(),
            None => d,
        }
    }
}

/// The map prepared for lookups.
#[derive(Debug, Clone)]
pub struct Lookup {
    /// The map's task (its metadata).
    task: String,
    axes: Vec<MapAxis>,
    cells: Vec<[f32; LANES]>,
    /// Lowest and highest value of the depth channel, when it holds values.
    depth_range: Option<[f32; 2]>,
    approach: [f64; 3],
    clearance: Option<f64>,
    /// Largest force and torque magnitudes over the map's cells.
    largest: [f64; 2],
    /// Per axis, the fit's rotational play at zero offset (grid units; 0 but on object
    /// rotations).
    play: Vec<f32>,
}

/// How a predicted cell is weighed against a measurement (Eq. 3, -1/2 chi^2): each
/// channel's residual squared times its inverse variance, plus, for the force and torque
/// vectors, `along` times the square of the residual's component along `axis` (the measured
/// vector's direction), so that the map may miss a vector's magnitude by more (or less)
/// than its direction.
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

    /// -1/2 chi^2 of the predicted channels `pred` (the contact lane's inverse variance is 0).
    #[inline(always)]
    fn log_likelihood(&self, pred: &[f32; LANES]) -> f32 {
        let mut d = [0.0f32; LANES];
        let mut s = 0.0;
        for l in 0..LANES {
            d[l] = self.meas[l] - pred[l];
            s += self.inv_var[l] * d[l] * d[l];
        }
        for g in 0..2 {
            let a = &self.axis[g];
            let p = d[3 * g] * a[0] + d[3 * g + 1] * a[1] + d[3 * g + 2] * a[2];
            s += self.along[g] * p * p;
        }
        -0.5 * s
    }
}

/// Which lookup the likelihood uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    /// The cell nearest to the particle (the paper's lookup).
    Nearest,
    /// Multilinear between the 2^d surrounding cells.
    Multilinear,
}

impl Lookup {
    /// Prepares `map`; `path` names the file in errors (NaN cells, empty grid).
    pub fn new(map: &FtMap, path: &Path) -> Result<Self> {
        let grid = map.grid();
        let bad = |reason: String| FusionError::Map {
            path: path.to_owned(),
            reason,
        };
        if grid.ndim() == 0 {
            return Err(bad("the map has no uncertain DOF".into()));
        }
        let symmetry = map.meta().symmetry;
        let axes: Vec<MapAxis> = grid
            .axes()
            .iter()
            .enumerate()
            .map(|(k, a)| MapAxis {
                dof: a.dof,
                min: a.min,
                step: a.step,
                count: a.count,
                stride: grid.stride(k),
                // Object DOFs move with the TCP (particle pose - TCP pose); z is the approach
                // axis, whose TCP value is the measured contact height, not a displacement.
                tcp: (a.dof.pose == Pose::Object && a.dof.axis != Axis::Z)
                    .then_some(a.dof.axis.index()),
                period: (a.dof == Dof::new(Pose::Object, Axis::Rz) && symmetry.is_some())
                    .then(|| (a.count - 1) as f32),
            })
            .collect();
        if let Some(n) = symmetry
            && let Some(a) = axes.iter().find(|a| a.period.is_some())
        {
            let period = std::f64::consts::TAU / f64::from(n);
            if ((a.count - 1) as f64 * a.step - period).abs() > 1e-6 * period {
                return Err(bad(format!(
                    "object.rz spans {} rad, not the period 2 pi / {n} of the symmetry the metadata states",
                    (a.count - 1) as f64 * a.step
                )));
            }
        }
        let mut cells = Vec::with_capacity(grid.cells());
        let mut largest = [0.0f64; 2];
        for i in 0..grid.cells() {
            let c = map.cell(i);
            if let Some(ch) = c.iter().position(|v| !v.is_finite()) {
                return Err(bad(format!(
                    "cell {i} has a non-finite value in channel {}",
                    ftmap::CHANNELS[ch]
                )));
            }
            for (l, v) in largest.iter_mut().zip([&c[..3], &c[3..6]]) {
                *l = l.max(f64::from(v.iter().map(|x| x * x).sum::<f32>().sqrt()));
            }
            let mut padded = [0.0; LANES];
            padded[..NCH].copy_from_slice(c);
            padded[CONTACT] = 1.0;
            cells.push(padded);
        }
        let mut lookup = Self {
            task: map.meta().task.clone(),
            axes,
            cells,
            depth_range: map.depth_range(),
            approach: map.meta().approach,
            clearance: map.meta().clearance,
            largest,
            play: Vec::new(),
        };
        for i in 0..lookup.cells.len() {
            if lookup.inserted(f64::from(lookup.cells[i][NCH - 1])) {
                let cell = &mut lookup.cells[i];
                cell[..NCH - 1].fill(0.0);
                cell[CONTACT] = 0.0;
            }
        }
        lookup.play = lookup
            .axes
            .iter()
            .enumerate()
            .map(|(k, a)| (map.rotational_play(k) / a.step) as f32)
            .collect();
        Ok(lookup)
    }

    /// The fit's rotational play of each axis (grid units, [`FtMap::rotational_play`]).
    pub fn play(&self) -> &[f32] {
        &self.play
    }

    /// The task the map was made for.
    pub fn task(&self) -> &str {
        &self.task
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.cells.len()
    }

    /// The axes in map order.
    pub fn axes(&self) -> &[MapAxis] {
        &self.axes
    }

    /// The axes' DOF names (`object.x`, ...), in map order.
    pub fn dof_names(&self) -> Vec<String> {
        self.axes.iter().map(|a| a.dof.to_string()).collect()
    }

    /// Number of axes.
    pub fn ndim(&self) -> usize {
        self.axes.len()
    }

    /// The largest force (N) and torque (N.m) magnitudes over the map's cells.
    pub fn largest(&self) -> [f64; 2] {
        self.largest
    }

    /// The fit's radial clearance, when the map's metadata has it (m).
    pub fn clearance(&self) -> Option<f64> {
        self.clearance
    }

    /// True when the depth channel holds values (not all zero).
    pub fn has_depth(&self) -> bool {
        self.depth_range.is_some()
    }

    /// Whether a contact at `height` (m) went in: below the middle of the depth channel's
    /// range (between resting on part B and inserted); never on a map without depth.
    pub fn inserted(&self, height: f64) -> bool {
        self.depth_range
            .is_some_and(|[lo, hi]| height < 0.5 * f64::from(lo + hi))
    }

    /// Whether a contact at `height` (m) rests more than `slack` below the highest contact
    /// the map holds (part B's top face): on a chamfer or another slope.
    pub fn below_top(&self, height: f64, slack: f64) -> bool {
        self.depth_range
            .is_some_and(|[_, hi]| height < f64::from(hi) - slack)
    }

    /// Height of a TCP position against the approach vector (the contact height at a contact).
    pub fn height(&self, tcp: &[f64; 6]) -> f64 {
        -(self.approach[0] * tcp[0] + self.approach[1] * tcp[1] + self.approach[2] * tcp[2])
    }

    /// Writes each particle's map coordinates (grid units, axis-major like `pos`, folded
    /// into the axes) for the TCP pose `tcp` into `out`: the object's pose relative to the
    /// TCP's, T_tcp^-1 T_object (grip DOFs and `object.z`, the approach, as they are).
    /// Without a TCP rotation that is the particle's object pose minus the TCP's; with one,
    /// the poses are composed exactly, the TCP at its contact height.
    pub fn relative(&self, pos: &[f32], tcp: &[f64; 6], out: &mut [f32]) {
        let n = pos.len() / self.ndim().max(1);
        if tcp[3..].iter().all(|r| *r == 0.0) {
            for (k, a) in self.axes.iter().enumerate() {
                let shift = a.tcp.map_or(0.0, |c| (tcp[c] / a.step) as f32);
                for (o, &u) in out[k * n..(k + 1) * n]
                    .iter_mut()
                    .zip(&pos[k * n..(k + 1) * n])
                {
                    *o = a.fold(u - shift);
                }
            }
            return;
        }
        use nalgebra::{Rotation3, Vector3};
        let r_tcp = Rotation3::new(Vector3::new(tcp[3], tcp[4], tcp[5])).inverse();
        // The TCP's z is the contact height: along a tilted tool axis it moves the TCP's x,
        // y too, which the map's x, y (across the tool's axis) do not see; the relative z
        // (along it) is what the depth channel reads.
        let t_tcp = Vector3::new(tcp[0], tcp[1], tcp[2]);
        for i in 0..n {
            let mut pose = [0.0f64; 6];
            for (k, a) in self.axes.iter().enumerate() {
                if a.dof.pose == Pose::Object {
                    pose[a.dof.axis.index()] = a.value(pos[k * n + i]);
                }
            }
            let t = r_tcp * (Vector3::new(pose[0], pose[1], pose[2]) - t_tcp);
            let r = (r_tcp * Rotation3::new(Vector3::new(pose[3], pose[4], pose[5]))).scaled_axis();
            for (k, a) in self.axes.iter().enumerate() {
                out[k * n + i] = if a.dof.pose == Pose::Object && a.dof.axis != Axis::Z {
                    let c = a.dof.axis.index();
                    let v = if c < 3 { t[c] } else { r[c - 3] };
                    // A rotation read on its periodic axis: the nearest turn of the period.
                    a.fold(a.coord(v))
                } else {
                    pos[k * n + i]
                };
            }
        }
    }

    /// The padded channels at grid coordinates `u` (one per axis), multilinear, clamped.
    pub fn at(&self, u: &[f32]) -> [f32; LANES] {
        let mut out = [0.0; LANES];
        let n = u.len().min(self.ndim());
        let mut base = 0;
        let mut frac = [0.0f32; ftmap::task::omega::MAX_AXES];
        for (k, a) in self.axes.iter().enumerate().take(n) {
            let t = u[k].clamp(0.0, a.top());
            let i = (t as usize).min(a.count.saturating_sub(2));
            base += i * a.stride;
            frac[k] = if a.count > 1 { t - i as f32 } else { 0.0 };
        }
        for corner in 0..1usize << n {
            let mut w = 1.0f32;
            let mut idx = base;
            for (k, a) in self.axes.iter().enumerate().take(n) {
                if corner >> k & 1 == 1 {
                    w *= frac[k];
                    idx += if a.count > 1 { a.stride } else { 0 };
                } else {
                    w *= 1.0 - frac[k];
                }
            }
            if w != 0.0 {
                for (o, v) in out.iter_mut().zip(&self.cells[idx]) {
                    *o += w * v;
                }
            }
        }
        over_contacts(&mut out);
        out
    }

    /// Writes -1/2 of the weighted squared residual (Eq. 3 in log space, constants
    /// dropped) of every particle into `out`. `rel` holds the particles' map coordinates
    /// axis-major (`rel[k * n + i]`, [`Lookup::relative`]), `w` the measurement and its
    /// weights.
    pub fn log_likelihood(&self, interp: Interpolation, rel: &[f32], w: &Weights, out: &mut [f32]) {
        macro_rules! dispatch {
            ($($d:literal)*) => {
                match (self.ndim(), interp) {
                    $(
                        ($d, Interpolation::Nearest) => self.ll_nearest::<$d>(rel, w, out),
                        ($d, Interpolation::Multilinear) => self.ll_linear::<$d>(rel, w, out),
                    )*
                    _ => self.ll_any(interp, rel, w, out),
                }
            };
        }
        dispatch!(1 2 3 4 5 6)
    }

    /// Clamped grid parameters of `D` axes: (top, last lower index, stride, stride to the upper neighbour).
    fn axis_params<const D: usize>(&self) -> ([f32; D], [usize; D], [usize; D], [usize; D]) {
        let mut top = [0.0; D];
        let mut lo_max = [0; D];
        let mut stride = [0; D];
        let mut up = [0; D];
        for (k, a) in self.axes.iter().enumerate().take(D) {
            top[k] = a.top();
            lo_max[k] = a.count.saturating_sub(2);
            stride[k] = a.stride;
            up[k] = if a.count > 1 { a.stride } else { 0 };
        }
        (top, lo_max, stride, up)
    }

    fn ll_nearest<const D: usize>(&self, rel: &[f32], w: &Weights, out: &mut [f32]) {
        let n = out.len();
        let (top, _, stride, _) = self.axis_params::<D>();
        for (i, o) in out.iter_mut().enumerate() {
            let mut idx = 0;
            for k in 0..D {
                let t = rel[k * n + i].clamp(0.0, top[k]);
                idx += (t + 0.5) as usize * stride[k];
            }
            *o = w.log_likelihood(&self.cells[idx]);
        }
    }

    fn ll_linear<const D: usize>(&self, rel: &[f32], w: &Weights, out: &mut [f32]) {
        let n = out.len();
        let (top, lo_max, stride, up) = self.axis_params::<D>();
        for (i, o) in out.iter_mut().enumerate() {
            let mut base = 0;
            let mut frac = [0.0f32; D];
            for k in 0..D {
                let t = rel[k * n + i].clamp(0.0, top[k]);
                let lo = (t as usize).min(lo_max[k]);
                base += lo * stride[k];
                frac[k] = t - lo as f32;
            }
            // Corner weights and indices by tensor expansion: 2 + 4 + .. + 2^D products.
            let mut wts = [0.0f32; 1 << 6];
            let mut idx = [0usize; 1 << 6];
            wts[0] = 1.0;
            idx[0] = base;
            let mut len = 1;
            for k in 0..D {
                for j in 0..len {
                    wts[j + len] = wts[j] * frac[k];
                    idx[j + len] = idx[j] + up[k];
                    wts[j] *= 1.0 - frac[k];
                }
                len *= 2;
            }
            let mut acc = [0.0f32; LANES];
            for (wt, &c) in wts.iter().zip(&idx).take(1 << D) {
                let cell = &self.cells[c];
                for l in 0..LANES {
                    acc[l] += wt * cell[l];
                }
            }
            over_contacts(&mut acc);
            *o = w.log_likelihood(&acc);
        }
    }

    fn ll_any(&self, interp: Interpolation, rel: &[f32], w: &Weights, out: &mut [f32]) {
        let n = out.len();
        let mut u = vec![0.0f32; self.ndim()];
        for (i, o) in out.iter_mut().enumerate() {
            for (k, a) in self.axes.iter().enumerate() {
                let t = rel[k * n + i].clamp(0.0, a.top());
                u[k] = match interp {
                    Interpolation::Nearest => t.round(),
                    Interpolation::Multilinear => t,
                };
            }
            *o = w.log_likelihood(&self.at(&u));
        }
    }
}

/// Renormalises an interpolated wrench over the contact corners (their weight is the
/// contact lane); with none, the masked zeros stay.
#[inline(always)]
fn over_contacts(acc: &mut [f32; LANES]) {
    let w = acc[CONTACT];
    if w > 0.0 && w < 1.0 {
        let s = 1.0 / w;
        for v in &mut acc[..NCH - 1] {
            *v *= s;
        }
    }
}
