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
//!
//! A centre map ([`ftmap::map::centre`]), where given, answers for the particles within
//! its region: the same lookup on its finer grid.

use std::path::Path;

use ftmap::task::omega::MAX_AXES;
use ftmap::{Axis, Dof, FtMap, NCH, Pose};

use super::weights::{BATCH, Batch, CONTACT, LANES, TERMS, Weights};
use crate::error::{FusionError, Result};

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
    /// Omega's bounds in grid units, where the particles' poses live: the whole axis, or
    /// its middle on an axis that samples relative poses farther
    /// ([`ftmap::GridAxis::omega`]).
    pub omega: [f32; 2],
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

    /// Grid coordinate `u` of a particle moved by its jitter, brought back into Omega:
    /// wrapped on a periodic axis, mirrored at Omega's bounds on another (a clamp would
    /// pile the particles that cross a bound onto it, a point mass that the uniform prior
    /// does not hold and that reads as a narrow spread at the bound).
    #[inline(always)]
    pub fn reflect(&self, u: f32) -> f32 {
        if self.period.is_some() {
            return self.fold(u);
        }
        let [lo, hi] = self.omega;
        let mirrored = if u < lo {
            2.0 * lo - u
        } else if u > hi {
            2.0 * hi - u
        } else {
            u
        };
        // A step longer than Omega itself crosses both bounds: the clamp ends it.
        mirrored.clamp(lo, hi)
    }

    /// Whether grid coordinate `u` lies in Omega.
    pub fn in_omega(&self, u: f32) -> bool {
        (self.omega[0]..=self.omega[1]).contains(&u)
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
    /// The map's axes and cells.
    level: Level,
    /// The centre map, when one is given.
    centre: Option<Centre>,
    /// Lowest and highest value of the depth channel, when it holds values.
    depth_range: Option<[f32; 2]>,
    approach: [f64; 3],
    clearance: Option<f64>,
    /// Largest force and torque magnitudes over the cells (as [`Lookup::compared`] reads).
    largest: [f64; 2],
    /// The sensor's origin in the task frame (m), where the filter compares torques about
    /// the contact face instead ([`about_face`]: on a map that samples the object's tilts).
    face_from: Option<[f64; 3]>,
    /// Per axis, the fit's rotational play at zero offset (grid units; 0 but on object
    /// rotations).
    play: Vec<f32>,
    /// The widest step of the axes that move the contact, in metres of its motion (step
    /// times lever, [`levers`]).
    widest: f64,
    /// The map's two tilts across the approach, when it samples both.
    tilts: Option<Tilts>,
}

/// The object's tilts about x and y (across the approach) on a map that samples both. A flat
/// face tilted against another by any angle rests on the point of it lowest along the
/// tilt's direction (a band of micrometres is crossed within a few thousandths of a degree
/// across a part): the force and torque depend on the tilt's direction, not on its size,
/// and jump to the whole face's only at zero. Between the samples nearest zero tilt a
/// multilinear lookup blends the face's wrench with edges in two or three directions, a
/// wrench that no pose gives (MuJoCo against the map on the tilted hole: a median miss of
/// 27 % of the torque, 6.5 % read along the direction). Below `floor` the force and torque
/// are read where the particle's tilt direction meets that radius, beyond the map's range
/// where that direction leaves it; depth and insertion, which do grow with the tilt's
/// size, where the particle lies.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tilts {
    /// The axes of `object.rx` and `object.ry`.
    axes: [usize; 2],
    /// Their first samples and steps (rad).
    min: [f32; 2],
    step: [f32; 2],
    /// Their last samples (rad).
    max: [f32; 2],
}

impl Tilts {
    /// The tilt axes of `axes`, when both are sampled on each side of zero.
    fn of(axes: &[MapAxis]) -> Option<Self> {
        let find = |axis| {
            axes.iter().position(|a| {
                a.dof == Dof::new(Pose::Object, axis)
                    && a.count > 1
                    && a.min < 0.0
                    && a.value(a.top()) > 0.0
            })
        };
        let axes_k = [find(Axis::Rx)?, find(Axis::Ry)?];
        let a = axes_k.map(|k| axes[k]);
        Some(Self {
            axes: axes_k,
            min: a.map(|a| a.min as f32),
            step: a.map(|a| a.step as f32),
            max: a.map(|a| a.value(a.top()) as f32),
        })
    }

    /// The radius below which a tilt is read along its direction: the diagonal of the
    /// wider step, so that no corner of the cell read is the untilted face's.
    fn floor(&self) -> f64 {
        f64::from(self.step[0].max(self.step[1])) * std::f64::consts::SQRT_2
    }

    /// Writes into `out` the grid coordinates at which to read the force and torque for the
    /// unclamped coordinates `raw` (the tilt scaled along its direction up to `floor` and
    /// down into the map's range, the other axes clamped) and says whether they differ
    /// from where the particle lies.
    #[inline(always)]
    fn wrench_at(
        &self,
        raw: &[f32],
        top: impl Fn(usize) -> f32,
        floor: f32,
        out: &mut [f32],
    ) -> bool {
        let theta: [f32; 2] =
            std::array::from_fn(|j| self.min[j] + raw[self.axes[j]] * self.step[j]);
        let size2 = theta[0] * theta[0] + theta[1] * theta[1];
        if size2 == 0.0 {
            return false;
        }
        // Divisions only where a scale applies: most particles' tilts lie within the range
        // and beyond `floor`.
        let mut scale = if size2 < floor * floor {
            floor / size2.sqrt()
        } else {
            1.0
        };
        for (j, &t) in theta.iter().enumerate() {
            // The bound on the tilt's side of zero, of the same sign as the tilt.
            let bound = if t > 0.0 { self.max[j] } else { self.min[j] };
            if (t * scale).abs() > bound.abs() {
                scale = bound / t;
            }
        }
        // Unscaled, the tilt lies within the range (no bound scaled it down).
        if scale == 1.0 {
            return false;
        }
        for (k, o) in out.iter_mut().enumerate() {
            *o = raw[k].clamp(0.0, top(k));
        }
        for (j, &t) in theta.iter().enumerate() {
            let k = self.axes[j];
            out[k] = ((t * scale - self.min[j]) / self.step[j]).clamp(0.0, top(k));
        }
        true
    }
}

/// One grid of padded cells: the map's, or its centre map's.
#[derive(Debug, Clone)]
struct Level {
    axes: Vec<MapAxis>,
    cells: Vec<[f32; LANES]>,
    /// Per cell, its mismatch terms ([`TERMS`]).
    terms: Vec<[f32; TERMS]>,
}

/// The channels at a point of the map and its mismatch terms there ([`TERMS`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    lanes: [f32; LANES],
    terms: [f32; TERMS],
}

/// The centre map's cells and where its grid lies on the map's.
#[derive(Debug, Clone)]
struct Centre {
    level: Level,
    /// Per axis, the centre's grid coordinate is the map's times `scale` plus `offset`.
    scale: [f32; MAX_AXES],
    offset: [f32; MAX_AXES],
}

/// What the lookups of `D` axes need of a level: per axis the largest coordinate, the last
/// lower corner index, the stride, and the stride to the upper corner (0 on a single sample).
struct Params<const D: usize> {
    top: [f32; D],
    lo_max: [usize; D],
    stride: [usize; D],
    up: [usize; D],
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
        let bad = |reason: String| FusionError::Map {
            path: path.to_owned(),
            reason,
        };
        if map.grid().ndim() == 0 {
            return Err(bad("the map has no uncertain DOF".into()));
        }
        let axes = axes_of(map);
        if let Some(n) = map.meta().symmetry
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
        let depth_range = map.depth_range();
        let tilts = Tilts::of(&axes);
        let face_from = tilts.map(|_| map.meta().sensor_origin);
        let (cells, largest) = padded(map, depth_range, face_from, path)?;
        let levers = levers(map);
        let widest = axes
            .iter()
            .zip(&levers)
            .map(|(a, l)| a.step * l)
            .fold(0.0, f64::max);
        let play = axes
            .iter()
            .enumerate()
            .map(|(k, a)| (map.rotational_play(k) / a.step) as f32)
            .collect();
        Ok(Self {
            task: map.meta().task.clone(),
            tilts,
            level: Level::new(axes, cells, &levers),
            centre: None,
            depth_range,
            approach: map.meta().approach,
            clearance: map.meta().clearance,
            largest,
            face_from,
            play,
            widest,
        })
    }

    /// The mean square (m^2, per axis) of how far the nearest cell's centre lies from a
    /// point in its cell along the map's widest step that moves the contact: `step^2 / 12`,
    /// the position the nearest-cell lookup misses (on a centre map's finer cells, less).
    pub fn nearest_variance(&self) -> f64 {
        self.widest * self.widest / 12.0
    }

    /// Prepares `map` (file `path`) with its centre map `centre` (file `centre_path`),
    /// which answers for the particles within its region.
    ///
    /// # Errors
    /// As [`Lookup::new`], and when `centre` is not a centre map of `map`
    /// ([`FtMap::check_centre`]).
    pub fn with_centre(
        map: &FtMap,
        path: &Path,
        centre: &FtMap,
        centre_path: &Path,
    ) -> Result<Self> {
        let mut lookup = Self::new(map, path)?;
        map.check_centre(centre).map_err(|e| FusionError::Map {
            path: centre_path.to_owned(),
            reason: e.to_string(),
        })?;
        let axes = axes_of(centre);
        // Inserted where the map says so: one contact depth for both.
        let (cells, largest) = padded(centre, lookup.depth_range, lookup.face_from, centre_path)?;
        let mut scale = [1.0f32; MAX_AXES];
        let mut offset = [0.0f32; MAX_AXES];
        for (k, (a, c)) in lookup.level.axes.iter().zip(&axes).enumerate() {
            scale[k] = (a.step / c.step) as f32;
            offset[k] = ((a.min - c.min) / c.step) as f32;
        }
        for (l, c) in lookup.largest.iter_mut().zip(largest) {
            *l = l.max(c);
        }
        lookup.centre = Some(Centre {
            level: Level::new(axes, cells, &levers(map)),
            scale,
            offset,
        });
        Ok(lookup)
    }

    /// The relative tilt (rad) below which a flat face's force and torque are read along
    /// the tilt's direction ([`Tilts`]), on a map that samples both tilts.
    pub fn tilt_floor(&self) -> Option<f64> {
        self.tilts.map(|t| t.floor())
    }

    /// A measured wrench (torque about the sensor's origin) as the filter compares it with
    /// the cells: with its torque about the contact face on a map that samples the object's
    /// tilts ([`about_face`]), else as it is.
    pub fn compared(&self, wrench: [f64; 6]) -> [f64; 6] {
        self.face_from.map_or(wrench, |o| about_face(wrench, o))
    }

    /// The fit's rotational play of each axis (grid units, [`FtMap::rotational_play`]).
    pub fn play(&self) -> &[f32] {
        &self.play
    }

    /// The task the map was made for.
    pub fn task(&self) -> &str {
        &self.task
    }

    /// Number of cells (the centre map's included).
    pub fn cells(&self) -> usize {
        self.level.cells.len() + self.centre.as_ref().map_or(0, |c| c.level.cells.len())
    }

    /// The axes in map order.
    pub fn axes(&self) -> &[MapAxis] {
        &self.level.axes
    }

    /// The axes' DOF names (`object.x`, ...), in map order.
    pub fn dof_names(&self) -> Vec<String> {
        self.axes().iter().map(|a| a.dof.to_string()).collect()
    }

    /// Number of axes.
    pub fn ndim(&self) -> usize {
        self.level.axes.len()
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
        inserted(self.depth_range, height)
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

    /// Where the tool's axis through the TCP at `tcp` meets the goal's height (the plane
    /// across the approach through the nominal goal): x, y (m). A level TCP's own x, y; a
    /// TCP tilted by t at height h stands h tan t beside it (0.35 mm at 2 degrees and
    /// 10 mm), and whether part A goes in is decided there, not under the TCP.
    pub fn axis_foot(&self, tcp: &[f64; 6]) -> [f64; 2] {
        use nalgebra::{Rotation3, Vector3};
        let a = Vector3::from(self.approach);
        let axis = Rotation3::new(Vector3::new(tcp[3], tcp[4], tcp[5])) * a;
        if (axis - a).norm() < 1e-12 {
            return [tcp[0], tcp[1]];
        }
        let p = Vector3::new(tcp[0], tcp[1], tcp[2]);
        let foot = p - axis * (a.dot(&p) / a.dot(&axis));
        [foot.x, foot.y]
    }

    /// Writes each particle's map coordinates (grid units, axis-major like `pos`, folded
    /// into the axes) for the TCP pose `tcp` into `out`: the object's pose relative to the
    /// TCP's, T_tcp^-1 T_object (grip DOFs and `object.z`, the approach, as they are).
    /// Without a TCP rotation that is the particle's object pose minus the TCP's, and
    /// `heights` is left empty: every particle sees the TCP's height. With one, the poses
    /// are composed exactly, the TCP at its contact height, and `heights` receives each
    /// particle's contact height along the tool's axis, which is what the depth channel
    /// holds (a TCP tilted by 2 degrees 2 mm beside the object's origin is 70 µm higher
    /// along its axis than along the world's).
    pub fn relative(&self, pos: &[f32], tcp: &[f64; 6], out: &mut [f32], heights: &mut Vec<f32>) {
        let n = pos.len() / self.ndim().max(1);
        heights.clear();
        if tcp[3..].iter().all(|r| *r == 0.0) {
            for (k, a) in self.level.axes.iter().enumerate() {
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
            for (k, a) in self.level.axes.iter().enumerate() {
                if a.dof.pose == Pose::Object {
                    pose[a.dof.axis.index()] = a.value(pos[k * n + i]);
                }
            }
            let t = r_tcp * (Vector3::new(pose[0], pose[1], pose[2]) - t_tcp);
            let r = (r_tcp * Rotation3::new(Vector3::new(pose[3], pose[4], pose[5]))).scaled_axis();
            heights.push(
                self.approach
                    .iter()
                    .zip(t.iter())
                    .map(|(a, v)| a * v)
                    .sum::<f64>() as f32,
            );
            for (k, a) in self.level.axes.iter().enumerate() {
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

    /// The padded channels at grid coordinates `u` (one per axis), multilinear, clamped;
    /// from the centre map within its region.
    pub fn at(&self, u: &[f32]) -> [f32; LANES] {
        self.sample(u).lanes
    }

    /// [`Lookup::at`] with the squared slopes of the force and torque components there.
    fn sample(&self, u: &[f32]) -> Sample {
        let n = u.len().min(self.ndim());
        let mut t = [0.0f32; MAX_AXES];
        for (k, a) in self.level.axes.iter().enumerate().take(n) {
            t[k] = u[k].clamp(0.0, a.top());
        }
        if let Some(c) = &self.centre {
            let mut f = [0.0f32; MAX_AXES];
            let mut inside = true;
            for (k, a) in c.level.axes.iter().enumerate().take(n) {
                f[k] = t[k] * c.scale[k] + c.offset[k];
                inside &= (0.0..=a.top()).contains(&f[k]);
            }
            if inside {
                return c.level.at(&f[..n]);
            }
        }
        self.level.at(&t[..n])
    }

    /// Writes every particle's log-likelihood ([`Weights`]: Eq. 3 in log space, constants
    /// dropped) into `out`. `rel` holds the particles' map coordinates
    /// axis-major (`rel[k * n + i]`, [`Lookup::relative`]), `heights` their contact heights
    /// along the tool's axis (empty: the measurement's, as with a level TCP), `w` the
    /// measurement and its weights.
    pub fn log_likelihood(
        &self,
        interp: Interpolation,
        rel: &[f32],
        heights: &[f32],
        w: &Weights,
        out: &mut [f32],
    ) {
        macro_rules! dispatch {
            ($($d:literal)*) => {
                match (self.ndim(), interp) {
                    $(
                        ($d, Interpolation::Nearest) => self.ll_nearest::<$d>(rel, heights, w, out),
                        ($d, Interpolation::Multilinear) => self.ll_linear::<$d>(rel, heights, w, out),
                    )*
                    _ => self.ll_any(interp, rel, heights, w, out),
                }
            };
        }
        dispatch!(1 2 3 4 5 6)
    }

    /// The level that answers at the map's clamped coordinates `t`, and the coordinates on
    /// it: the centre map within its region, else the map.
    #[inline(always)]
    fn level_at<'a, const D: usize>(
        &'a self,
        t: [f32; D],
        params: &'a (Params<D>, Option<Params<D>>),
    ) -> (&'a Level, &'a Params<D>, [f32; D]) {
        if let (Some(c), Some(p)) = (&self.centre, &params.1) {
            let mut f = [0.0f32; D];
            let mut inside = true;
            for k in 0..D {
                f[k] = t[k] * c.scale[k] + c.offset[k];
                inside &= f[k] >= 0.0 && f[k] <= p.top[k];
            }
            if inside {
                return (&c.level, p, f);
            }
        }
        (&self.level, &params.0, t)
    }

    /// The lookup parameters of the map and of its centre map.
    fn params<const D: usize>(&self) -> (Params<D>, Option<Params<D>>) {
        (
            self.level.params(),
            self.centre.as_ref().map(|c| c.level.params()),
        )
    }

    fn ll_nearest<const D: usize>(
        &self,
        rel: &[f32],
        heights: &[f32],
        w: &Weights,
        out: &mut [f32],
    ) {
        self.ll_read::<D>(rel, heights, w, out, |level, p, u| {
            let idx: usize = (0..D).map(|k| (u[k] + 0.5) as usize * p.stride[k]).sum();
            Sample {
                lanes: level.cells[idx],
                terms: level.terms[idx],
            }
        });
    }

    fn ll_linear<const D: usize>(
        &self,
        rel: &[f32],
        heights: &[f32],
        w: &Weights,
        out: &mut [f32],
    ) {
        self.ll_read::<D>(rel, heights, w, out, |level, p, u| level.linear(p, u));
    }

    /// Every particle's log-likelihood with the sample `read` takes of a level at its
    /// coordinates; the force and torque read along a tilt's direction ([`Tilts`]).
    #[inline(always)]
    fn ll_read<const D: usize>(
        &self,
        rel: &[f32],
        heights: &[f32],
        w: &Weights,
        out: &mut [f32],
        read: impl Fn(&Level, &Params<D>, [f32; D]) -> Sample,
    ) {
        let params = self.params::<D>();
        let tilts = self.tilts.filter(|_| w.tilt_floor > 0.0);
        let n = out.len();
        let mut along = [0.0f32; D];
        weigh_in_batches(w, heights, out, |i| {
            let raw: [f32; D] = std::array::from_fn(|k| rel[k * n + i]);
            let t = std::array::from_fn(|k| raw[k].clamp(0.0, params.0.top[k]));
            let (level, p, u) = self.level_at(t, &params);
            let at = read(level, p, u);
            if let Some(tl) = &tilts
                && tl.wrench_at(&raw, |k| params.0.top[k], w.tilt_floor, &mut along)
            {
                let (level, p, u) = self.level_at(along, &params);
                return at.with_wrench(read(level, p, u));
            }
            at
        });
    }

    fn ll_any(
        &self,
        interp: Interpolation,
        rel: &[f32],
        heights: &[f32],
        w: &Weights,
        out: &mut [f32],
    ) {
        let n = out.len();
        let d = self.ndim();
        let (mut raw, mut u, mut along) = (vec![0.0f32; d], vec![0.0f32; d], vec![0.0f32; d]);
        let tilts = self.tilts.filter(|_| w.tilt_floor > 0.0);
        let top = |k: usize| self.level.axes[k].top();
        let round = |v: &mut [f32]| {
            if interp == Interpolation::Nearest {
                v.iter_mut().for_each(|x| *x = x.round());
            }
        };
        weigh_in_batches(w, heights, out, |i| {
            for k in 0..d {
                raw[k] = rel[k * n + i];
                u[k] = raw[k].clamp(0.0, top(k));
            }
            round(&mut u);
            let at = self.sample(&u);
            if let Some(tl) = &tilts
                && tl.wrench_at(&raw, top, w.tilt_floor, &mut along)
            {
                round(&mut along);
                return at.with_wrench(self.sample(&along));
            }
            at
        });
    }
}

/// Writes into `out` each particle's log-likelihood under `w` of the sample `sample` reads
/// for it, its contact height along the tool's axis in `heights` (empty: the measured one),
/// weighed [`BATCH`] at a time.
#[inline(always)]
fn weigh_in_batches(
    w: &Weights,
    heights: &[f32],
    out: &mut [f32],
    mut sample: impl FnMut(usize) -> Sample,
) {
    let mut batch = Batch::default();
    for (b, outs) in out.chunks_mut(BATCH).enumerate() {
        for j in 0..outs.len() {
            let i = b * BATCH + j;
            let at = sample(i);
            batch.set(j, &at.at_height(w, heights.get(i)), &at.terms);
        }
        w.log_likelihoods(&batch, outs);
    }
}

impl Sample {
    /// Its channels as compared with `w`'s measurement by a particle whose contact height
    /// along the tool's axis is `height` (none: the measured one): the depth shifted by
    /// the difference, so that its residual is the particle's.
    #[inline(always)]
    fn at_height(&self, w: &Weights, height: Option<&f32>) -> [f32; LANES] {
        let mut lanes = self.lanes;
        if let Some(h) = height {
            lanes[NCH - 1] += w.meas[NCH - 1] - h;
        }
        lanes
    }

    /// This sample with the force, torque and their mismatch terms of `wrench`, read at
    /// another pose ([`Tilts`]); as it is where either went in.
    #[inline(always)]
    fn with_wrench(self, wrench: Sample) -> Sample {
        if self.lanes[CONTACT] == 0.0 || wrench.lanes[CONTACT] == 0.0 {
            return self;
        }
        let mut lanes = self.lanes;
        lanes[..NCH - 1].copy_from_slice(&wrench.lanes[..NCH - 1]);
        Sample {
            lanes,
            terms: wrench.terms,
        }
    }
}

impl Level {
    /// A level of `cells` on `axes`, with their mismatch terms: the slopes ([`slopes`],
    /// `levers` per axis) and the interpolation errors ([`interpolation_errors`]).
    fn new(axes: Vec<MapAxis>, cells: Vec<[f32; LANES]>, levers: &[f64]) -> Self {
        let terms = slopes(&axes, &cells, levers)
            .into_iter()
            .zip(interpolation_errors(&axes, &cells))
            .map(|([f, t], [ef, et])| [f, t, ef, et])
            .collect();
        Self { axes, cells, terms }
    }

    /// The lookup parameters of its first `D` axes.
    fn params<const D: usize>(&self) -> Params<D> {
        let mut p = Params {
            top: [0.0; D],
            lo_max: [0; D],
            stride: [0; D],
            up: [0; D],
        };
        for (k, a) in self.axes.iter().enumerate().take(D) {
            p.top[k] = a.top();
            p.lo_max[k] = a.count.saturating_sub(2);
            p.stride[k] = a.stride;
            p.up[k] = if a.count > 1 { a.stride } else { 0 };
        }
        p
    }

    /// Multilinear channels at coordinates `t` within the grid (`p`: its parameters).
    #[inline(always)]
    fn linear<const D: usize>(&self, p: &Params<D>, t: [f32; D]) -> Sample {
        let mut base = 0;
        let mut frac = [0.0f32; D];
        for k in 0..D {
            let lo = (t[k] as usize).min(p.lo_max[k]);
            base += lo * p.stride[k];
            frac[k] = t[k] - lo as f32;
        }
        // Corner weights and indices by tensor expansion: 2 + 4 + .. + 2^D products.
        let mut wts = [0.0f32; 1 << 6];
        let mut idx = [0usize; 1 << 6];
        wts[0] = 1.0;
        idx[0] = base;
        let mut len = 1;
        for (&f, &up) in frac.iter().zip(&p.up) {
            for j in 0..len {
                wts[j + len] = wts[j] * f;
                idx[j + len] = idx[j] + up;
                wts[j] *= 1.0 - f;
            }
            len *= 2;
        }
        let mut acc = [0.0f32; LANES];
        let mut terms = [0.0f32; TERMS];
        for (wt, &c) in wts.iter().zip(&idx).take(1 << D) {
            let cell = &self.cells[c];
            for l in 0..LANES {
                acc[l] += wt * cell[l];
            }
            for (s, v) in terms.iter_mut().zip(&self.terms[c]) {
                *s += wt * v;
            }
        }
        over_contacts(&mut acc, &mut terms);
        Sample { lanes: acc, terms }
    }

    /// Multilinear channels at coordinates `t` within the grid, any number of axes.
    fn at(&self, t: &[f32]) -> Sample {
        let mut out = [0.0; LANES];
        let mut terms = [0.0f32; TERMS];
        let n = t.len().min(self.axes.len());
        let mut base = 0;
        let mut frac = [0.0f32; MAX_AXES];
        for (k, a) in self.axes.iter().enumerate().take(n) {
            let i = (t[k] as usize).min(a.count.saturating_sub(2));
            base += i * a.stride;
            frac[k] = if a.count > 1 { t[k] - i as f32 } else { 0.0 };
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
                for (s, v) in terms.iter_mut().zip(&self.terms[idx]) {
                    *s += w * v;
                }
            }
        }
        over_contacts(&mut out, &mut terms);
        Sample { lanes: out, terms }
    }
}

/// The axes of `map` in the filter's terms.
fn axes_of(map: &FtMap) -> Vec<MapAxis> {
    let grid = map.grid();
    let symmetry = map.meta().symmetry;
    grid.axes()
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
            omega: a
                .omega_bounds()
                .map(|x| (((x - a.min) / a.step) as f32).clamp(0.0, (a.count - 1) as f32)),
        })
        .collect()
}

/// The cells of `map` padded to [`LANES`], those where part A went in by `depth_range`
/// masked, their torques about the contact face where `face_from` gives the sensor's origin
/// ([`about_face`]), and the largest force and torque magnitudes; `path` names the file of
/// a cell with a non-finite value.
fn padded(
    map: &FtMap,
    depth_range: Option<[f32; 2]>,
    face_from: Option<[f64; 3]>,
    path: &Path,
) -> Result<(Vec<[f32; LANES]>, [f64; 2])> {
    let cells = map.grid().cells();
    let mut out = Vec::with_capacity(cells);
    let mut largest = [0.0f64; 2];
    for i in 0..cells {
        let c = map.cell(i);
        if let Some(ch) = c.iter().position(|v| !v.is_finite()) {
            return Err(FusionError::Map {
                path: path.to_owned(),
                reason: format!(
                    "cell {i} has a non-finite value in channel {}",
                    ftmap::CHANNELS[ch]
                ),
            });
        }
        let mut padded = [0.0; LANES];
        padded[..NCH].copy_from_slice(c);
        if let Some(origin) = face_from {
            let face = about_face(std::array::from_fn(|k| f64::from(c[k])), origin);
            for (p, v) in padded[3..6].iter_mut().zip(&face[3..]) {
                *p = *v as f32;
            }
        }
        padded[CONTACT] = 1.0;
        for (l, v) in largest.iter_mut().zip([&padded[..3], &padded[3..6]]) {
            *l = l.max(f64::from(v.iter().map(|x| x * x).sum::<f32>().sqrt()));
        }
        if inserted(depth_range, f64::from(c[NCH - 1])) {
            padded[..NCH - 1].fill(0.0);
            padded[CONTACT] = 0.0;
        }
        out.push(padded);
    }
    Ok((out, largest))
}

/// The wrench `w` (force, torque about the sensor's origin `origin`, in the task frame) with
/// its torque taken about the task frame's origin instead, on part A's contact face: there
/// a force across the approach at the contact has no moment across the approach, where
/// 60 mm up it has one of 60 mm times that force. A press on a face that slopes against
/// the approach (a map over the object's tilts) loads friction across it, which holds
/// whatever it must within its cone and which the map's contact model leaves out; on a
/// level face the press loads none, and the force across the approach that the map does
/// model (an edge's) tells the torque about the sensor more than its own channels do.
pub fn about_face(w: [f64; 6], origin: [f64; 3]) -> [f64; 6] {
    let [sx, sy, sz] = origin;
    let [fx, fy, fz] = [w[0], w[1], w[2]];
    [
        fx,
        fy,
        fz,
        w[3] + sy * fz - sz * fy,
        w[4] + sz * fx - sx * fz,
        w[5] + sx * fy - sy * fx,
    ]
}

/// Whether a contact at `height` (m) went in on a map whose depth channel spans
/// `depth_range`: below the middle of it; never on a map without depth.
fn inserted(depth_range: Option<[f32; 2]>, height: f64) -> bool {
    depth_range.is_some_and(|[lo, hi]| height < 0.5 * f64::from(lo + hi))
}

/// Renormalises an interpolated wrench and its mismatch terms over the contact corners
/// (their weight is the contact lane); with none, the masked zeros stay.
#[inline(always)]
fn over_contacts(acc: &mut [f32; LANES], terms: &mut [f32; TERMS]) {
    let w = acc[CONTACT];
    if w > 0.0 && w < 1.0 {
        let s = 1.0 / w;
        for v in acc[..NCH - 1].iter_mut().chain(terms.iter_mut()) {
            *v *= s;
        }
    }
}

/// Per axis of `map`, how far (m) the contact moves per unit of the axis: 1 on the object's
/// x and y; on an object rotation with play, the fit's clearance over that play (the lever
/// at which the play takes up the clearance); 0 on the other axes (a contact's position
/// does not move them).
fn levers(map: &FtMap) -> Vec<f64> {
    let clearance = map.meta().clearance.unwrap_or(0.0);
    map.grid()
        .axes()
        .iter()
        .enumerate()
        .map(|(k, a)| match (a.dof.pose, a.dof.axis) {
            (Pose::Object, Axis::X | Axis::Y) => 1.0,
            (Pose::Object, _) if a.dof.is_rotation() => {
                let play = map.rotational_play(k);
                if play > 0.0 { clearance / play } else { 0.0 }
            }
            _ => 0.0,
        })
        .collect()
}

/// Per cell, the squared slopes of its force and torque per metre the contact moves: for
/// each, the mean over its x and y components of the sum over the axes with a lever
/// ([`levers`]) of the squared derivative, SI units; central differences between contact
/// cells (round a periodic axis), one-sided beside an inserted cell or the grid's edge; 0
/// on an inserted cell. How much a wrench changes when the contact sits elsewhere than the
/// map has it.
fn slopes(axes: &[MapAxis], cells: &[[f32; LANES]], levers: &[f64]) -> Vec<[f32; 2]> {
    let moved: Vec<(&MapAxis, f64)> = axes
        .iter()
        .zip(levers.iter().copied())
        .filter(|(a, lever)| *lever > 0.0 && a.count > 1)
        .collect();
    per_contact_cell(cells, |i, out| {
        for &(a, lever) in &moved {
            let (from, to, steps) = match (along(a, cells, i, -1), along(a, cells, i, 1)) {
                (Some(l), Some(h)) => (l, h, 2.0),
                (Some(l), None) => (l, i, 1.0),
                (None, Some(h)) => (i, h, 1.0),
                (None, None) => continue,
            };
            let h = (steps * a.step * lever) as f32;
            add_xy_mean(out, |l| ((cells[to][l] - cells[from][l]) / h).powi(2));
        }
    })
}

/// Per cell, the mean squared error of the multilinear lookup within the cells around it,
/// for the force and the torque (each the mean over its x and y components, in N^2 and
/// (N.m)^2): per axis, a field with the second difference `d` across three samples is
/// missed by `d t (1 - t) / 2` at a fraction `t` of a step, whose mean square over the step
/// is `d^2 / 120`; summed over the axes (the cross terms dropped). Second differences are
/// taken between contact cells, centred (round a periodic axis) or one-sided beside an
/// inserted cell or the grid's edge; 0 where there are not three in a row, and on an
/// inserted cell.
fn interpolation_errors(axes: &[MapAxis], cells: &[[f32; LANES]]) -> Vec<[f32; 2]> {
    per_contact_cell(cells, |i, out| {
        for a in axes.iter().filter(|a| a.count > 2) {
            let triple = [[-1, 0, 1], [0, 1, 2], [-2, -1, 0]]
                .into_iter()
                .find_map(|ks| match ks.map(|k| along(a, cells, i, k)) {
                    [Some(p), Some(q), Some(r)] => Some([p, q, r]),
                    _ => None,
                });
            let Some([p, q, r]) = triple else { continue };
            add_xy_mean(out, |l| {
                (cells[p][l] - 2.0 * cells[q][l] + cells[r][l]).powi(2) / 120.0
            });
        }
    })
}

/// Per cell, the force's and the torque's values that `fill` adds up for a contact cell
/// (index, output); 0 on an inserted cell.
fn per_contact_cell(cells: &[[f32; LANES]], fill: impl Fn(usize, &mut [f32; 2])) -> Vec<[f32; 2]> {
    (0..cells.len())
        .map(|i| {
            let mut out = [0.0f32; 2];
            if cells[i][CONTACT] > 0.0 {
                fill(i, &mut out);
            }
            out
        })
        .collect()
}

/// The contact cell `k` samples from cell `i` along axis `a` (round a periodic axis,
/// whose last sample is its first), if there is one.
fn along(a: &MapAxis, cells: &[[f32; LANES]], i: usize, k: isize) -> Option<usize> {
    let at = (i / a.stride % a.count) as isize;
    let base = i - at as usize * a.stride;
    let last = (a.count - 1) as isize;
    let j = match a.period {
        Some(_) => (at + k).rem_euclid(last),
        None => Some(at + k).filter(|j| (0..=last).contains(j))?,
    };
    let n = base + j as usize * a.stride;
    (cells[n][CONTACT] > 0.0).then_some(n)
}

/// Adds to `out`, for the force (0) and the torque (1), the mean of `value` over the
/// vector's x and y lanes.
fn add_xy_mean(out: &mut [f32; 2], value: impl Fn(usize) -> f32) {
    for (g, o) in out.iter_mut().enumerate() {
        *o += 0.5 * value(3 * g) + 0.5 * value(3 * g + 1);
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use ftfusion_testkit::{FORCE, HOLE_DEPTH, field, peg_map};
    use nalgebra::Vector3;

    use super::*;
    use crate::filter::weights::INTERPOLATION;

    #[test]
    fn the_slopes_are_the_fields_derivatives() {
        let step = 2.5e-4;
        let map = peg_map(5e-3, step, None).expect("map");
        let lookup = Lookup::new(&map, Path::new("synthetic")).expect("lookup");
        let level = &lookup.level;
        for (x, y) in [(2e-3, 1e-3), (-3e-3, 0.5e-3), (0.75e-3, -4e-3)] {
            let i = level.axes[0].coord(x).round() as usize * level.axes[0].stride
                + level.axes[1].coord(y).round() as usize * level.axes[1].stride;
            // tx = F L(r) y / r, ty = -F L(r) x / r, with L(r) = 3.9 mm - 0.45 r.
            let r = f64::hypot(x, y);
            let (l, dl) = (0.0039 - 0.45 * r, -0.45);
            let dtx = [
                FORCE * x * y / (r * r) * (dl - l / r),
                FORCE * (dl * y * y / (r * r) + l * x * x / (r * r * r)),
            ];
            let dty = [
                -FORCE * (dl * x * x / (r * r) + l * y * y / (r * r * r)),
                -FORCE * x * y / (r * r) * (dl - l / r),
            ];
            let want = 0.5 * (dtx[0].powi(2) + dtx[1].powi(2) + dty[0].powi(2) + dty[1].powi(2));
            let got = f64::from(level.terms[i][1]);
            assert!(
                (got - want).abs() < 0.05 * want,
                "({x}, {y}): {got} against {want}"
            );
            // The force does not change with x, y in this field; the hole's cells none.
            assert!(level.terms[i][0] < 1e-6);
        }
        let centre = level.axes[0].coord(0.0).round() as usize * level.axes[0].stride
            + level.axes[1].coord(0.0).round() as usize * level.axes[1].stride;
        assert_eq!(level.terms[centre], [0.0; TERMS]);
        assert!(
            field(0.0, 0.0, 0.0, 0.0)[6] == 0.0,
            "the field's centre is inserted"
        );
    }

    #[test]
    fn the_interpolation_error_terms_match_the_lookups_own_error() {
        // The analytic field read through a 0.1 mm map: in rings round the hole, where the
        // rim torque turns within a cell, the mean square of the lookup's torque error
        // against the field's (x and y components) is what the terms say it is.
        let map = peg_map(5e-3, 1e-4, None).expect("map");
        let lookup = Lookup::new(&map, Path::new("synthetic")).expect("lookup");
        let [ax, ay] = [lookup.level.axes[0], lookup.level.axes[1]];
        for (inner, outer) in [(1.5e-4, 3e-4), (3e-4, 6e-4), (6e-4, 1.5e-3)] {
            let (mut actual, mut said, mut n) = (0.0f64, 0.0f64, 0.0);
            for i in 0..200 {
                for j in 0..24 {
                    let r = inner + (outer - inner) * (f64::from(i) + 0.5) / 200.0;
                    let phi = std::f64::consts::TAU * (f64::from(j) + 0.37) / 24.0;
                    let (x, y) = (r * phi.cos(), r * phi.sin());
                    let s = lookup.sample(&[ax.coord(x), ay.coord(y)]);
                    let want = field(x, y, 0.0, 0.0);
                    actual += 0.5
                        * (f64::from(s.lanes[3] - want[3]).powi(2)
                            + f64::from(s.lanes[4] - want[4]).powi(2));
                    said += f64::from(s.terms[INTERPOLATION + 1]);
                    n += 1.0;
                }
            }
            let (actual, said) = ((actual / n).sqrt(), (said / n).sqrt());
            eprintln!("ring {inner}-{outer}: error rms {actual:.2e}, terms {said:.2e}");
            assert!(
                said > 0.5 * actual && said < 2.0 * actual,
                "ring {inner}-{outer} m: the lookup misses the torque by {actual:.2e} N.m rms, the terms say {said:.2e}"
            );
        }
    }

    #[test]
    fn jitter_mirrored_at_omega_s_bounds_keeps_a_uniform_set_uniform() {
        use rand_xoshiro::Xoshiro256PlusPlus;
        use rand_xoshiro::rand_core::SeedableRng;
        // Omega the middle half of an axis that samples relative poses twice as far.
        let axis = MapAxis {
            dof: Dof::new(Pose::Object, Axis::X),
            min: -0.004,
            step: 1e-4,
            count: 81,
            stride: 1,
            tcp: Some(0),
            period: None,
            omega: [20.0, 60.0],
        };
        let [lo, hi] = axis.omega;
        let (n, width) = (40_000, hi - lo);
        let mut v: Vec<f32> = (0..n)
            .map(|i| lo + width * (i as f32 + 0.5) / n as f32)
            .collect();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        for _ in 0..200 {
            crate::filter::noise::jitter(&mut rng, &mut v, 0.1 * width, |u| axis.reflect(u));
        }
        // A flat likelihood: the walk's stationary set is the uniform prior over Omega, with
        // no mass piled on a bound (a clamp puts a few per cent on each) and none beyond.
        assert!(v.iter().all(|&u| axis.in_omega(u)), "a particle left Omega");
        let at_bounds = v.iter().filter(|&&u| u == lo || u == hi).count();
        assert!(at_bounds < 10, "{at_bounds} particles on a bound");
        let mut bins = [0usize; 10];
        for &u in &v {
            bins[(((u - lo) / width * 10.0) as usize).min(9)] += 1;
        }
        for (b, &c) in bins.iter().enumerate() {
            let share = c as f64 / n as f64;
            assert!((share - 0.1).abs() < 0.01, "bin {b} holds {share}");
        }
        assert_eq!(axis.reflect(lo - 1.5), lo + 1.5);
        assert_eq!(axis.reflect(hi + 2.0), hi - 2.0);
        assert_eq!(
            axis.reflect(hi + 3.0 * width),
            lo,
            "past both bounds: clamped"
        );
    }

    #[test]
    fn a_force_across_the_approach_at_the_face_leaves_the_face_torque_across_it_as_it_was() {
        // A press of 50 N at a point of part A's face, with and without 3 N of friction
        // across the approach there: about the sensor 60 mm up the friction turns the
        // torque by 0.18 N.m; about the face (the cross product written out) only its z.
        let origin = [0.002, -0.001, 0.06];
        let point = Vector3::new(0.004, 0.0025, 0.0);
        let about = |o: [f64; 3], f: Vector3<f64>| -> [f64; 6] {
            let t = (point - Vector3::from(o)).cross(&f);
            [f.x, f.y, f.z, t.x, t.y, t.z]
        };
        for friction in [Vector3::zeros(), Vector3::new(3.0, -1.5, 0.0)] {
            let f = Vector3::new(0.0, 0.0, FORCE) + friction;
            let face = about_face(about(origin, f), origin);
            let exact = about([0.0; 3], f);
            for k in 0..6 {
                assert!(
                    (face[k] - exact[k]).abs() < 1e-12,
                    "{k}: {face:?} {exact:?}"
                );
            }
            let pressed = about([0.0; 3], Vector3::new(0.0, 0.0, FORCE));
            assert!((face[3] - pressed[3]).abs() < 1e-12 && (face[4] - pressed[4]).abs() < 1e-12);
        }
        let sensor = about(origin, Vector3::new(3.0, -1.5, FORCE));
        let pressed = about(origin, Vector3::new(0.0, 0.0, FORCE));
        assert!((sensor[3] - pressed[3]).hypot(sensor[4] - pressed[4]) > 0.18);
    }

    /// Radius of the flat face of [`tilted_face`] (m).
    const FACE: f64 = 0.005;

    /// A flat face pressed on a plane tilted against it by (rx, ry): it rests on the point
    /// of its rim lowest along the tilt, whose torque follows the tilt's direction and
    /// whose depth (below the plane's height, [`HOLE_DEPTH`]) its size; untilted, on the
    /// whole face (no torque).
    fn tilted_face(rx: f64, ry: f64) -> [f32; NCH] {
        let size = rx.hypot(ry);
        let (px, py) = if size > 0.0 {
            (FACE * rx / size, FACE * ry / size)
        } else {
            (0.0, 0.0)
        };
        [
            0.0,
            0.0,
            FORCE,
            py * FORCE,
            -px * FORCE,
            0.0,
            HOLE_DEPTH - FACE * size,
        ]
        .map(|v| v as f32)
    }

    #[test]
    fn a_small_tilt_reads_the_edge_its_direction_rests_on_and_the_depth_of_its_size() {
        let deg = 1f64.to_radians();
        let dof = |a| Dof::new(Pose::Object, a);
        let grid = ftmap::Grid::new(vec![
            ftmap::GridAxis::symmetric(dof(Axis::X), 1e-4, 1e-4).expect("axis"),
            ftmap::GridAxis::symmetric(dof(Axis::Y), 1e-4, 1e-4).expect("axis"),
            ftmap::GridAxis::symmetric(dof(Axis::Rx), 2.0 * deg, 0.5 * deg).expect("axis"),
            ftmap::GridAxis::symmetric(dof(Axis::Ry), 2.0 * deg, 0.5 * deg).expect("axis"),
        ])
        .expect("grid");
        let mut map = FtMap::zeros(grid, ftfusion_testkit::synthetic_meta("tilted_face"));
        // Part A goes in at x = -0.1 mm (depth 0: the depth channel's range then marks the
        // face's cells as contacts); the tilts are read at x = y = 0.
        for cell in 0..map.grid().cells() {
            let c = map.grid().coords(cell);
            *map.cell_mut(cell) = if c[0] < -5e-5 {
                [0.0; NCH]
            } else {
                tilted_face(c[2], c[3])
            };
        }
        let lookup = Lookup::new(&map, Path::new("tilted_face")).expect("lookup");
        let floor = lookup.tilt_floor().expect("both tilts sampled");
        assert!(
            (floor / (0.5 * deg * std::f64::consts::SQRT_2) - 1.0).abs() < 1e-6,
            "{floor}"
        );
        let axes = lookup.axes().to_vec();
        // Tilts from a tenth of a step to beyond the map's range, in several directions:
        // the torque within 8 % of the edge's (chi^2 < 1 at sigma 8 % of it: the cells read
        // blend edges up to 45 degrees apart, whose chord is 7.6 % short) and the depth
        // within 10 um of the tilt's own (the bilinear cone near its tip; a read at the
        // floor's radius misses it by 31-57 um).
        let (sigma_t, sigma_d) = (0.08 * FACE * FORCE, 1e-5);
        let chi2 = |rx: f64, ry: f64, tilt_floor: f64, depth: bool| {
            let rel: Vec<f32> = [0.0, 0.0, rx, ry]
                .iter()
                .zip(&axes)
                .map(|(v, a)| a.coord(*v))
                .collect();
            let mut meas = [0.0f32; LANES];
            meas[..NCH].copy_from_slice(&tilted_face(rx, ry));
            let t = (1.0 / (sigma_t * sigma_t)) as f32;
            let w = Weights {
                tilt_floor: tilt_floor as f32,
                ..Weights::diagonal(
                    meas,
                    [
                        0.0,
                        0.0,
                        0.0,
                        t,
                        t,
                        0.0,
                        if depth {
                            (1.0 / (sigma_d * sigma_d)) as f32
                        } else {
                            0.0
                        },
                        0.0,
                    ],
                )
            };
            let mut out = [0.0f32; 1];
            lookup.log_likelihood(Interpolation::Multilinear, &rel, &[], &w, &mut out);
            -2.0 * f64::from(out[0])
        };
        for (size, direction) in [
            (0.05, 30.0),
            (0.1, 30.0),
            (0.2, 75.0),
            (0.35, 200.0),
            (0.6, 320.0),
        ] {
            let (s, c) = f64::to_radians(direction).sin_cos();
            let (rx, ry) = (size * deg * c, size * deg * s);
            let read = chi2(rx, ry, floor, true);
            assert!(
                read < 1.0,
                "{size} deg along {direction} deg: chi^2 {read} read along the direction"
            );
            // Within a step of zero the cells around the tilt hold the untilted face's.
            if size < 0.5 {
                let plain = chi2(rx, ry, 0.0, true);
                assert!(
                    plain > 9.0,
                    "{size} deg along {direction} deg: chi^2 {plain} read where it lies"
                );
            }
        }
        // Beyond the map's 2 degrees a tilt is read along its direction at the range's edge,
        // not clamped per axis (which turns it): the torque alone (no depth there).
        let (rx, ry) = (
            3.0 * deg * 10f64.to_radians().cos(),
            3.0 * deg * 10f64.to_radians().sin(),
        );
        let (read, plain) = (chi2(rx, ry, floor, false), chi2(rx, ry, 0.0, false));
        assert!(
            read < 0.1 && plain > 0.5,
            "3 deg along 10 deg: chi^2 {read} along, {plain} clamped"
        );
    }
}
