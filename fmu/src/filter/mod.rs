//! The condensation particle filter (paper, section IV, Algorithm 1): particles over the
//! map's uncertain DOFs, Eq. 3 in log space, systematic resampling, jitter, and the
//! estimate (mode of the dominant cluster, spread, confidence).
//!
//! Particles live in grid units of the map's axes (`(x - min) / step`), axis-major. A
//! particle holds its own pose (object pose relative to the nominal goal, grip offset);
//! its map coordinate for an `object.*` DOF is its pose minus the TCP pose (Algorithm 1,
//! step 13), `grip.*` DOFs are not moved by the TCP. With a vision model, Eq. 3 also holds
//! the image features' residuals (module `vision`).

mod estimate;
mod lookup;
mod mismatch;
mod negative;
mod noise;
mod resample;
mod state;
mod vision;
mod weights;

use std::path::Path;
use std::sync::Arc;

use ftmap::FtMap;
use ftmap::task::omega::MAX_AXES;
use rand_distr::Distribution;
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

pub use estimate::Estimate;
pub use lookup::{Interpolation, Lookup, MapAxis};
pub use mismatch::MapMismatch;
pub use negative::NegativeContact;
pub use state::{Reader, Writer};
pub use vision::{Prepared, VisionMeasurement, VisionMethod, VisionSense};
pub use weights::{LANES, Weights};

use crate::error::{FusionError, Result};
use mismatch::Mismatch;

/// Log-likelihood below which a particle's likelihood counts as underflowed: its linear
/// weight would be below the smallest normal f32 (with the Gaussian likelihood a residual of
/// about 13 sigma; with the Student-t one only an absurd residual).
const UNDERFLOW: f32 = -87.33655;
/// The jitter proposed over one measurement's iterations together moves a particle by at
/// most this share of the particles' spread (standard deviations).
const JITTER_SPREAD: f64 = 0.5;
/// Share of the particles re-spread uniformly when every likelihood underflows, and the
/// most that a relocation redraws.
const RESPREAD_SHARE: f64 = 0.5;
/// One particle in this many is a probe of the relocation test: drawn afresh from the prior
/// to judge whether the prior explains a measurement better than the particle set does.
const PROBE_EVERY: usize = 20;
/// Mixed into the seed for the relocation probes' random stream (the golden ratio's bits).
const PROBE_STREAM: u64 = 0x9E37_79B9_7F4A_7C15;

/// The largest magnitude of a measured value (N, N.m, m, rad, px): beyond it an input is
/// a broken signal, not a measurement (and its square would overflow the likelihood).
pub const MAX_INPUT: f64 = 1.0e6;

/// Particles for a map of `dofs` uncertain DOFs where the user sets none: 4000 for up to
/// two, four times as many per DOF beyond, at most [`MAX_PARTICLES`] (octagon_yaw's x, y and
/// yaw with 8000 kept the truth within 2 sigma in 80 % of contacts, with 16000 in 84-86 %).
pub fn automatic_particles(dofs: usize) -> usize {
    let beyond = dofs.saturating_sub(2).min(8) as u32;
    (4000usize << (2 * beyond)).min(MAX_PARTICLES)
}

/// The most particles a filter holds.
pub const MAX_PARTICLES: usize = 1_000_000;

/// Settings of the filter (the FMU's parameters, checked).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Number of particles; 0: [`automatic_particles`] for the map.
    pub particles: usize,
    /// Seed of the random numbers.
    pub seed: u64,
    /// Filter iterations per measurement.
    pub iterations: usize,
    /// Standard deviation of a force component (N).
    pub sigma_force: f64,
    /// Standard deviation of a torque component (N.m).
    pub sigma_torque: f64,
    /// Standard deviation of the contact height (m); 0: depth unused.
    pub sigma_depth: f64,
    /// Jitter standard deviation in grid intervals.
    pub jitter: f64,
    /// Confidence radius (m; rotations: the same number of grid intervals).
    pub confidence_radius: f64,
    /// Confidence above which the estimate counts as converged.
    pub threshold: f64,
    /// Map lookup.
    pub interpolation: Interpolation,
    /// Degrees of freedom of the Student-t likelihood of the wrench residual; 0: Gaussian.
    pub tail: f64,
    /// Radial clearance of the negative contact (m): 0, the map's; negative, no negative
    /// contact (module `negative`).
    pub clearance: f64,
    /// Share of the measured force's and torque's magnitudes the map may miss: along the
    /// measured vector, added to `sigma_force` and `sigma_torque` in quadrature (model
    /// mismatch); negative: the map's ([`MapMismatch`]).
    pub mismatch: f64,
    /// Angle by which the map may miss the measured force's and torque's directions (rad):
    /// across the measured vector, that angle times its magnitude is added in quadrature;
    /// negative: the map's ([`MapMismatch`]).
    pub mismatch_angle: f64,
    /// How far the contact may sit from where the map has it (m, standard deviation in each
    /// axis across the approach): the variance of the force's and torque's x and y
    /// components grows by its square times their squared slope at the particle (steep near
    /// the hole, flat far from it), with the likelihood's normalisation; 0: none.
    pub mismatch_position: f64,
    /// Share of the lookup's own error added to the variance of the force's and torque's x
    /// and y components (with the likelihood's normalisation); 0: none. Multilinear: the
    /// interpolation error the map's second differences imply; nearest cell: the cell's
    /// width, as a position error in the position term.
    pub mismatch_interpolation: f64,
    /// How far the contact's pressure centre may lie from the map's (m, standard deviation
    /// across the force): that distance times the measured force's magnitude (up to the
    /// map's largest) is added to each torque component's miss in quadrature, near the hole
    /// and far from it alike; 0: none; negative: the map's ([`MapMismatch`]).
    pub mismatch_lever: f64,
    /// How near (in grid steps of each map axis the TCP moves) a contact must lie to an
    /// earlier one for the map to miss both alike: the mismatch terms then count once over
    /// the contacts there, not once per contact ([`Filter::looks`]); 0: every contact's
    /// mismatch is drawn afresh.
    pub mismatch_reach: f64,
    /// Relative tilt (rad) below which a flat face's force and torque are read along the
    /// tilt's direction, where the map samples the object's tilts about x and y: 0, the
    /// diagonal of the map's tilt step; negative, where each particle lies.
    pub tilt_floor: f64,
    /// Prior probability that the particle set has lost the truth (e.g. locked on a wrong
    /// hypothesis by a contact the map did not explain): where the measurements since the
    /// set last explained one better than the prior make that more likely than not, half the
    /// particles are redrawn from the prior; 0: never.
    pub lost: f64,
}

impl Default for Config {
    fn default() -> Self {
        Self {
            particles: 0,
            seed: 1,
            iterations: 20,
            sigma_force: 1.0,
            sigma_torque: 0.003,
            sigma_depth: 0.00002,
            jitter: 0.15,
            confidence_radius: 1e-4,
            threshold: 0.9,
            interpolation: Interpolation::Multilinear,
            tail: 4.0,
            clearance: 0.0,
            mismatch: -1.0,
            mismatch_angle: -1.0,
            mismatch_position: 5e-6,
            mismatch_interpolation: 1.0,
            mismatch_lever: -1.0,
            mismatch_reach: 1.0,
            tilt_floor: 0.0,
            lost: 1e-9,
        }
    }
}

/// One measurement: the wrench in the sensor frame, the TCP pose, and an image's detections.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measurement {
    /// fx fy fz (N), tx ty tz (N.m).
    pub wrench: [f64; 6],
    /// Task frame relative to the nominal goal: x y z (m), rx ry rz (rad).
    pub tcp: [f64; 6],
    /// Detected image features, when an image was taken.
    pub vision: Option<VisionMeasurement>,
    /// No contact: only the image is evaluated (the wrench is ignored).
    pub vision_only: bool,
    /// The contact ended a slide under force that started here (x, y in m, rz in rad, the
    /// frame of `tcp`): the swept line, or for a twist about z the swept yaws, is a
    /// negative contact too.
    pub slide_start: Option<[f64; 3]>,
    /// The slide ended here (the frame of `tcp`) and the contact was pressed at `tcp`
    /// afterwards (none: the slide ended at `tcp`): the line swept runs from `slide_start`
    /// to here, and the press at `tcp` is a negative contact of its own.
    pub slide_end: Option<[f64; 3]>,
}

/// What a measurement update did, beyond the new estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Report {
    /// Iterations in which every likelihood underflowed and particles were re-spread.
    pub respread: u32,
    /// Iterations that resampled (ESS <= N/2).
    pub resampled: u32,
    /// Particles redrawn from the prior because the set explained the measurement far worse
    /// than the prior does (relocation).
    pub relocated: u32,
    /// The image was not used: no vision model, or no camera recalibration fits it.
    pub vision_unused: bool,
}

/// The particle filter over one map.
#[derive(Debug, Clone)]
pub struct Filter {
    lookup: Arc<Lookup>,
    cfg: Config,
    vision: Option<Arc<VisionSense>>,
    negative: Option<NegativeContact>,
    /// Grid coordinates, axis-major: `pos[k * n + i]`.
    pos: Vec<f32>,
    /// Normalised log weights (sum of exp = 1).
    lw: Vec<f32>,
    rng: Xoshiro256PlusPlus,
    measurements: u32,
    /// The TCP poses of the contacts weighed so far ([`Filter::looks`]).
    presses: Vec<[f64; 6]>,
    /// Page's CUSUM of ln(E_prior / E_set) over the measurements since the set last explained
    /// one better than the prior (nats): the evidence that the particles have lost the truth.
    lost_evidence: f64,
    estimate: Estimate,
    scratch: Scratch,
}

/// Buffers reused by every update (no allocation per iteration).
#[derive(Debug, Clone, Default)]
struct Scratch {
    /// Each particle's log-likelihood of the measurement being taken, at its pose.
    ll: Vec<f32>,
    /// The moves' proposals' log-likelihoods (and resampling's spare buffer for `ll`).
    proposed: Vec<f32>,
    w: Vec<f32>,
    pos: Vec<f32>,
    /// The particles' map coordinates relative to the TCP.
    rel: Vec<f32>,
    /// The particles' contact heights along a tilted tool's axis (empty for a level one).
    heights: Vec<f32>,
    pick: Vec<u32>,
    /// The relocation probes' own poses, axis-major, while they stand for the prior.
    kept: Vec<f32>,
}

impl Filter {
    /// A filter over `map` with particles uniform over Omega; `path` names the map in errors.
    pub fn new(map: &FtMap, path: &Path, cfg: Config) -> Result<Self> {
        Ok(Self::with_lookup(Arc::new(Lookup::new(map, path)?), cfg))
    }

    /// A filter over an already prepared map (shared between filters), with the mismatch
    /// values `cfg` leaves to the map filled in ([`MapMismatch::of`]).
    pub fn with_lookup(lookup: Arc<Lookup>, cfg: Config) -> Self {
        let cfg = MapMismatch::of(&lookup).fill(cfg);
        let cfg = Config {
            particles: match cfg.particles {
                0 => automatic_particles(lookup.ndim()),
                n => n,
            },
            ..cfg
        };
        let n = cfg.particles;
        let d = lookup.ndim();
        let clearance = match cfg.clearance {
            c if c > 0.0 => Some(c),
            0.0 => lookup.clearance(),
            _ => None,
        };
        let negative =
            clearance.and_then(|c| NegativeContact::new(lookup.axes(), lookup.play(), c));
        let mut f = Self {
            lookup,
            cfg,
            vision: None,
            negative,
            pos: vec![0.0; n * d],
            lw: vec![-(n as f32).ln(); n],
            rng: Xoshiro256PlusPlus::seed_from_u64(cfg.seed),
            measurements: 0,
            presses: Vec::new(),
            lost_evidence: 0.0,
            estimate: Estimate::default(),
            scratch: Scratch {
                ll: vec![0.0; n],
                proposed: vec![0.0; n],
                w: vec![0.0; n],
                pos: vec![0.0; n * d],
                rel: vec![0.0; n * d],
                heights: Vec::with_capacity(n),
                pick: vec![0; n],
                kept: vec![0.0; n.div_ceil(PROBE_EVERY) * d],
            },
        };
        for i in 0..n {
            f.spread(i);
        }
        f.estimate = Estimate::compute(&f.lookup, &f.cfg, &f.pos, &f.lw);
        f
    }

    /// The filter weighing images too, with `sense` (the vision model on this map's axes).
    pub fn with_vision(mut self, sense: VisionSense) -> Self {
        self.vision = Some(Arc::new(sense));
        self
    }

    /// The vision model, when images are weighed.
    pub fn vision(&self) -> Option<&VisionSense> {
        self.vision.as_deref()
    }

    /// The negative contact, where it applies to this map.
    pub fn negative_contact(&self) -> Option<&NegativeContact> {
        self.negative.as_ref()
    }

    /// The prepared map.
    pub fn lookup(&self) -> &Arc<Lookup> {
        &self.lookup
    }

    /// The settings.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// The current estimate.
    pub fn estimate(&self) -> &Estimate {
        &self.estimate
    }

    /// Measurements used so far.
    pub fn measurements(&self) -> u32 {
        self.measurements
    }

    /// Particle `i`'s pose value on map axis `k` (m or rad).
    pub fn particle(&self, i: usize, k: usize) -> f64 {
        self.lookup.axes()[k].value(self.pos[k * self.cfg.particles + i])
    }

    /// Normalised weight of particle `i`.
    pub fn weight(&self, i: usize) -> f64 {
        f64::from(self.lw[i]).exp()
    }

    /// Moves particle `i` to a uniform random place in Omega.
    fn spread(&mut self, i: usize) {
        Self::spread_with(&mut self.rng, &self.lookup, &mut self.pos, i);
    }

    /// Moves particle `i` of `pos` to a place in Omega drawn uniformly from `rng`.
    fn spread_with(rng: &mut Xoshiro256PlusPlus, lookup: &Lookup, pos: &mut [f32], i: usize) {
        let n = pos.len() / lookup.ndim().max(1);
        for (k, a) in lookup.axes().iter().enumerate() {
            let u: f32 = unit(rng);
            let [lo, hi] = a.omega;
            pos[k * n + i] = lo + u * (hi - lo);
        }
    }

    /// Checks a measurement: every value finite and within ±[`MAX_INPUT`].
    pub fn check(m: &Measurement) -> Result<()> {
        let refuse = |name: &'static str, value: f64| {
            if value.is_finite() {
                FusionError::Absurd {
                    name,
                    value,
                    max: MAX_INPUT,
                }
            } else {
                FusionError::NonFinite { name, value }
            }
        };
        let bad = |v: &f64| v.is_nan() || v.abs() > MAX_INPUT;
        if let Some(v) = &m.vision
            && let Some((&value, name)) = v
                .distances
                .iter()
                .chain(&v.passive)
                .zip(model_description::VISION_FEATURES)
                .find(|(v, _)| bad(v))
        {
            return Err(refuse(name, value));
        }
        match m
            .wrench
            .iter()
            .chain(&m.tcp)
            .chain(m.slide_start.iter().flatten())
            .zip(
                model_description::WRENCH
                    .iter()
                    .chain(&model_description::TCP)
                    .chain(&model_description::SLIDE_START),
            )
            .chain(
                m.slide_end
                    .iter()
                    .flatten()
                    .zip(&model_description::SLIDE_END),
            )
            .find(|(v, _)| bad(v))
        {
            Some((&value, &name)) => Err(refuse(name, value)),
            None => Ok(()),
        }
    }

    /// Takes one measurement: `iterations` rounds of a move (not before the filter's first
    /// weighing), weight (Eq. 3), normalise and resample (when ESS <= N/2), then a new
    /// estimate. A measurement with a non-finite value is refused and changes nothing; an
    /// image alone that cannot be used changes nothing either.
    pub fn measure(&mut self, m: &Measurement) -> Result<Report> {
        Self::check(m)?;
        let vision = match (&self.vision, &m.vision) {
            (Some(sense), Some(v)) => sense.prepare(v, &m.tcp),
            _ => None,
        };
        let mut report = Report {
            vision_unused: m.vision.is_some() && vision.is_none(),
            ..Report::default()
        };
        if m.vision_only && vision.is_none() {
            return Ok(report);
        }
        let evidence = self.evidence(m, vision);
        if self.measurements > 0 && self.cfg.lost > 0.0 {
            report.relocated = self.relocate(&evidence);
        }
        let iterations = self.cfg.iterations;
        for it in 0..iterations {
            // Condensation order: predict (move) before each weighing but the very first, so
            // that the estimate below reads the weighed set (Algorithm 1, step 13), not the
            // set moved for the next iteration. The move's target is the set as weighed so
            // far: none of this measurement's likelihood in its first iteration.
            if it > 0 || self.measurements > 0 {
                self.mutate(&evidence, it as f32 / iterations as f32);
            } else {
                self.evaluate(&evidence);
            }
            let ess = self.weigh(&evidence, &mut report);
            if ess <= self.cfg.particles as f64 / 2.0 {
                self.resample();
                report.resampled += 1;
            }
        }
        self.measurements += 1;
        if evidence.force {
            self.presses.push(m.tcp);
        }
        self.estimate = Estimate::compute(&self.lookup, &self.cfg, &self.pos, &self.lw);
        Ok(report)
    }

    /// What measurement `m` (checked; `vision`, its image prepared) offers the particles:
    /// the channels it weighs and how, and what it says of the fit's clearance.
    fn evidence(&self, m: &Measurement, vision: Option<Prepared>) -> Evidence {
        let c = &self.cfg;
        let height = self.lookup.height(&m.tcp);
        let went_in = self.lookup.inserted(height);
        // A contact says where part B is against the fit's clearance where the map allows
        // it (module `negative`); it replaces the depth channel then, unless it did not go
        // in and part A rests measurably below part B's top (on a chamfer: how far down
        // says how far off), where both count.
        let contact = self.negative.as_ref().filter(|_| !m.vision_only);
        let use_depth = c.sigma_depth > 0.0
            && self.lookup.has_depth()
            && (contact.is_none()
                || (!went_in && self.lookup.below_top(height, 2.0 * c.sigma_depth)));
        let wrench = self.lookup.compared(m.wrench);
        let mut meas = [0.0f32; LANES];
        for (dst, &src) in meas.iter_mut().zip(&wrench) {
            *dst = src as f32;
        }
        meas[6] = height as f32;
        let [force, torque] = self.lookup.largest();
        let looks = self.looks(&m.tcp);
        let lever = c.mismatch_lever * magnitude(&wrench[..3]).min(force);
        let (f, t) = (
            Mismatch::of(c, c.sigma_force, &wrench[..3], force, 0.0, looks),
            Mismatch::of(c, c.sigma_torque, &wrench[3..], torque, lever, looks),
        );
        let vd = if use_depth {
            (1.0 / (c.sigma_depth * c.sigma_depth)) as f32
        } else {
            0.0
        };
        // The lookup's own error: the multilinear one's interpolation error per cell, or the
        // nearest cell's width as a position error.
        let (position, interpolation) = match c.interpolation {
            Interpolation::Multilinear => (c.mismatch_position.powi(2), c.mismatch_interpolation),
            Interpolation::Nearest => (
                c.mismatch_position.powi(2)
                    + c.mismatch_interpolation * self.lookup.nearest_variance(),
                0.0,
            ),
        };
        let weights = Weights {
            meas,
            inv_var: [
                f.across, f.across, f.across, t.across, t.across, t.across, vd, 0.0,
            ],
            axis: [f.axis, t.axis],
            along: [f.along, t.along],
            position: [f.repeat, t.repeat].map(|g| g * position as f32),
            interpolation: [f.repeat, t.repeat].map(|g| g * interpolation as f32),
            tilt_floor: match c.tilt_floor {
                f if f > 0.0 => f as f32,
                0.0 => self.lookup.tilt_floor().unwrap_or(0.0) as f32,
                _ => 0.0,
            },
            ..Weights::default()
        }
        .student(c.tail as f32);
        Evidence {
            // Where the tool's axis met the goal's height, at the end and (at the end's
            // height and tilt) at the start.
            fit: contact.map(|n| {
                let at = |x: f64, y: f64, rz: f64| {
                    let [fx, fy] = self
                        .lookup
                        .axis_foot(&[x, y, m.tcp[2], m.tcp[3], m.tcp[4], rz]);
                    [fx, fy, rz]
                };
                let press = at(m.tcp[0], m.tcp[1], m.tcp[5]);
                let (start, end) = match (m.slide_start, m.slide_end) {
                    (Some(s), Some(e)) => (at(s[0], s[1], s[2]), at(e[0], e[1], e[2])),
                    (Some(s), None) => (at(s[0], s[1], s[2]), press),
                    (None, _) => (press, press),
                };
                Fit {
                    term: n.clone(),
                    start,
                    end,
                    press,
                    went_in,
                }
            }),
            tcp: m.tcp,
            weights,
            force: !m.vision_only,
            vision,
        }
    }

    /// How many contacts, this one at `tcp` counted, share the map's miss here: 1 plus, per
    /// earlier contact, exp(-d^2 / 2), d its distance from `tcp` in `mismatch_reach` grid
    /// steps over the map axes the TCP moves (wrapped on a periodic axis). Two presses
    /// within a grid step read the same cells, so whatever the map misses there it misses
    /// for both ([`repeated`]).
    fn looks(&self, tcp: &[f64; 6]) -> f64 {
        let reach = self.cfg.mismatch_reach;
        if reach <= 0.0 {
            return 1.0;
        }
        let near = |p: &[f64; 6]| {
            let d2: f64 = (self.lookup.axes().iter())
                .filter_map(|a| {
                    let c = a.tcp?;
                    let d = f64::from(a.difference(((tcp[c] - p[c]) / a.step) as f32));
                    Some((d / reach).powi(2))
                })
                .sum();
            (-0.5 * d2).exp()
        };
        1.0 + self.presses.iter().map(near).sum::<f64>()
    }

    /// The log-likelihood of `ev` (Eq. 3: map residuals, image residuals) of each particle
    /// pose of `pos` (axis-major) into `ll`; `rel` and `heights` receive the poses' map
    /// coordinates and contact heights ([`Lookup::relative`]).
    fn log_likelihood(
        &self,
        ev: &Evidence,
        pos: &[f32],
        rel: &mut [f32],
        heights: &mut Vec<f32>,
        ll: &mut [f32],
    ) {
        if ev.force {
            self.lookup.relative(pos, &ev.tcp, rel, heights);
            self.lookup
                .log_likelihood(self.cfg.interpolation, rel, heights, &ev.weights, ll);
            match &ev.fit {
                Some(fit) if fit.went_in => {
                    fit.term.add_went_in_log_likelihood(pos, rel, fit.press, ll);
                }
                Some(fit) => {
                    // A press at the line's end lies on it: the line alone.
                    let motions = [[fit.start, fit.end], [fit.press, fit.press]];
                    let count = if fit.press == fit.end { 1 } else { 2 };
                    fit.term.add_log_likelihood(pos, rel, &motions[..count], ll);
                }
                None => {}
            }
        } else {
            ll.fill(0.0);
        }
        if let (Some(sense), Some(p)) = (&self.vision, &ev.vision) {
            let n = self.cfg.particles;
            let axes = self.lookup.axes();
            sense.add_log_likelihood(p, n, |k, i| axes[k].value(pos[k * n + i]), ll);
        }
    }

    /// Each particle's log-likelihood of `ev` at its pose, into `scratch.ll`.
    fn evaluate(&mut self, ev: &Evidence) {
        let mut ll = std::mem::take(&mut self.scratch.ll);
        let mut rel = std::mem::take(&mut self.scratch.rel);
        let mut heights = std::mem::take(&mut self.scratch.heights);
        self.log_likelihood(ev, &self.pos, &mut rel, &mut heights, &mut ll);
        self.scratch.ll = ll;
        self.scratch.rel = rel;
        self.scratch.heights = heights;
    }

    /// The move (the prediction of the condensation loop) as a Metropolis-Hastings step:
    /// every particle proposes its pose plus the jitter ([`Filter::jitter`], a symmetric
    /// proposal) and takes it with probability min(1, (L(proposal) / L(pose))^`beta`), L
    /// the likelihood of `ev`; `scratch.ll` follows the poses. The target is the set's own
    /// density, flat over a jitter step, times the `beta` share of the measurement weighed
    /// so far: across a narrow ridge of the likelihood a move off it is refused, where a
    /// plain jitter would lose that particle at the next weighing and so thin the ridge's
    /// weight against a broad one's. With `beta` 0 every proposal is taken.
    fn mutate(&mut self, ev: &Evidence, beta: f32) {
        let (n, d) = (self.cfg.particles, self.lookup.ndim());
        let mut proposal = std::mem::take(&mut self.scratch.pos);
        proposal.copy_from_slice(&self.pos);
        self.jitter(&mut proposal);
        let mut proposed = std::mem::take(&mut self.scratch.proposed);
        let mut rel = std::mem::take(&mut self.scratch.rel);
        let mut heights = std::mem::take(&mut self.scratch.heights);
        self.log_likelihood(ev, &proposal, &mut rel, &mut heights, &mut proposed);
        let ll = &mut self.scratch.ll;
        for i in 0..n {
            let gain = beta * (proposed[i] - ll[i]);
            // A NaN gain (no finite likelihood either way) keeps the pose.
            let take = beta == 0.0 || gain >= 0.0 || unit::<f32>(&mut self.rng).ln() < gain;
            if take {
                for k in 0..d {
                    self.pos[k * n + i] = proposal[k * n + i];
                }
                ll[i] = proposed[i];
            }
        }
        self.scratch.pos = proposal;
        self.scratch.proposed = proposed;
        self.scratch.rel = rel;
        self.scratch.heights = heights;
    }

    /// Relocation (sensor resetting, decided by Bayes): the prior for a measurement is
    /// `(1 - lost)` the particle set plus `lost` the prior over Omega. One particle in
    /// [`PROBE_EVERY`] is drawn afresh from the prior; the measurement's mean likelihood
    /// under these probes and under the rest of the set (with its weights) give the Bayes
    /// factor of "lost", accumulated over consecutive measurements (Page's CUSUM). Where
    /// the set is then more likely lost than not, [`RESPREAD_SHARE`] of the particles are
    /// redrawn from the prior with a particle's mean weight, the rest kept as they were;
    /// the probes go back where they were either way. Returns how many were redrawn. One
    /// contact the map does not explain (an outlier) is followed by one the set explains
    /// again, which clears the evidence; a set locked on a wrong hypothesis is not.
    fn relocate(&mut self, ev: &Evidence) -> u32 {
        let (n, d) = (self.cfg.particles, self.lookup.ndim());
        // The probes come from a stream of their own (the seed and the measurement's
        // number), so that a set that is not lost goes on exactly as without them.
        let mut probe_rng = Xoshiro256PlusPlus::seed_from_u64(
            self.cfg.seed ^ PROBE_STREAM.wrapping_mul(u64::from(self.measurements) + 1),
        );
        let offset = (probe_rng.next_u64() % PROBE_EVERY as u64) as usize;
        let probes = (offset..n).step_by(PROBE_EVERY);
        for (j, i) in probes.clone().enumerate() {
            for k in 0..d {
                self.scratch.kept[j * d + k] = self.pos[k * n + i];
            }
            Self::spread_with(&mut probe_rng, &self.lookup, &mut self.pos, i);
        }
        self.evaluate(ev);
        let ll = &self.scratch.ll;
        let is_probe = |i: usize| i >= offset && (i - offset).is_multiple_of(PROBE_EVERY);
        let set = log_sum_exp((0..n).filter(|&i| !is_probe(i)).map(|i| self.lw[i] + ll[i]))
            - log_sum_exp((0..n).filter(|&i| !is_probe(i)).map(|i| self.lw[i]));
        let prior = log_sum_exp(probes.clone().map(|i| ll[i])) - (probes.len() as f64).ln();
        for (j, i) in probes.enumerate() {
            for k in 0..d {
                self.pos[k * n + i] = self.scratch.kept[j * d + k];
            }
        }
        // Page's CUSUM: the evidence accumulates while the prior explains the contacts better
        // than the set and falls back to zero once the set explains one better. The set is
        // more likely lost than not once lost / (1 - lost) times that evidence's Bayes factor
        // passes 1. NaN (no finite likelihood anywhere) is left to the underflow re-spread
        // of the weighing.
        let evidence = self.lost_evidence + prior - set;
        self.lost_evidence = if evidence.is_nan() {
            0.0
        } else {
            evidence.max(0.0)
        };
        if self.lost_evidence <= ((1.0 - self.cfg.lost) / self.cfg.lost).ln() {
            return 0;
        }
        self.lost_evidence = 0.0;
        let redrawn = self.respread(Some(-(n as f32).ln()));
        normalise(&mut self.lw, &mut self.scratch.w);
        redrawn
    }

    /// Moves [`RESPREAD_SHARE`] of the particles (evenly spaced from a random first one) to
    /// uniform random places in Omega, with log weight `weight` where given; returns how
    /// many.
    fn respread(&mut self, weight: Option<f32>) -> u32 {
        let step = (1.0 / RESPREAD_SHARE).round() as usize;
        let first = (self.rng.next_u64() % step as u64) as usize;
        let redrawn = (first..self.cfg.particles).step_by(step);
        let count = redrawn.len() as u32;
        for i in redrawn {
            self.spread(i);
            if let Some(w) = weight {
                self.lw[i] = w;
            }
        }
        count
    }

    /// Multiplies the weights by the likelihood (`scratch.ll`) and normalises
    /// (log-sum-exp); re-spreads a share of the particles when every likelihood underflows.
    /// Returns the ESS and leaves the linear weights in `scratch.w`.
    fn weigh(&mut self, ev: &Evidence, report: &mut Report) -> f64 {
        let best = self
            .scratch
            .ll
            .iter()
            .copied()
            .fold(f32::NEG_INFINITY, f32::max);
        // NaN cannot occur (inputs are checked finite); `best` is -inf only for no particle.
        if best < UNDERFLOW {
            // No particle explains the measurement: start a share of them afresh, forget the
            // old weights, and weigh again.
            report.respread += 1;
            self.respread(None);
            self.evaluate(ev);
            self.lw.fill(0.0);
        }
        // Each of the iterations weighs with the likelihood to the power 1 / iterations
        // (annealing): a measurement counts once, however many iterations move the particles.
        let temper = 1.0 / self.cfg.iterations as f32;
        for (w, l) in self.lw.iter_mut().zip(&self.scratch.ll) {
            *w += l * temper;
        }
        normalise(&mut self.lw, &mut self.scratch.w)
    }

    /// Systematic resampling (the likelihoods in `scratch.ll` follow their particles);
    /// weights become uniform.
    fn resample(&mut self) {
        let n = self.cfg.particles;
        let u0: f64 = unit::<f64>(&mut self.rng);
        resample::systematic(&self.scratch.w, u0, &mut self.scratch.pick);
        let d = self.lookup.ndim();
        for k in 0..d {
            let (src, dst) = (
                &self.pos[k * n..(k + 1) * n],
                &mut self.scratch.pos[k * n..(k + 1) * n],
            );
            for (o, &j) in dst.iter_mut().zip(&self.scratch.pick) {
                *o = src[j as usize];
            }
        }
        std::mem::swap(&mut self.pos, &mut self.scratch.pos);
        for (o, &j) in self.scratch.proposed.iter_mut().zip(&self.scratch.pick) {
            *o = self.scratch.ll[j as usize];
        }
        std::mem::swap(&mut self.scratch.ll, &mut self.scratch.proposed);
        self.lw.fill(-(n as f32).ln());
    }

    /// Gaussian jitter of the particle poses `pos` (axis-major) on every axis, mirrored back
    /// into Omega at its bounds (wrapped on a periodic axis):
    /// `jitter` grid intervals, or less once the particles' spread is small, so that the
    /// jitter proposed over a measurement's iterations together moves a particle by about
    /// [`JITTER_SPREAD`] of the spread: a fixed jitter would blur a posterior narrower than
    /// it (the last tens of micrometres of a fit) and with it what the earlier contacts
    /// said. It never falls below that
    /// share of the fit's clearance on the object's translations (of one grid interval on
    /// other axes, the grip's included, and where the map has no clearance), so that a set
    /// that has collapsed off the truth can still move.
    fn jitter(&mut self, pos: &mut [f32]) {
        let n = self.cfg.particles;
        let s = self.cfg.jitter as f32;
        if s == 0.0 {
            return;
        }
        let per_iteration = (JITTER_SPREAD / (self.cfg.iterations as f64).sqrt()) as f32;
        let spreads = spreads(self.lookup.axes(), &self.pos, &self.lw);
        for (k, a) in self.lookup.axes().iter().enumerate() {
            let top = a.top();
            if top == 0.0 {
                continue;
            }
            let scale_of_fit = match &self.negative {
                Some(nc) if a.tcp.is_some() && !a.dof.is_rotation() => {
                    (nc.clearance / a.step) as f32
                }
                _ => 1.0,
            };
            let values = &mut pos[k * n..(k + 1) * n];
            let scale = s.min(per_iteration * spreads[k].max(scale_of_fit));
            noise::jitter(&mut self.rng, values, scale, |u| a.reflect(u));
        }
    }
}

/// The Euclidean length of `v`.
fn magnitude(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// What one measurement offers the particles, ready for every iteration.
struct Evidence {
    /// What the contact says of the fit's clearance, where the map allows it.
    fit: Option<Fit>,
    /// The TCP pose the map coordinates are relative to.
    tcp: [f64; 6],
    /// The measured channels and how the residual weighs them.
    weights: Weights,
    /// The wrench counts (a contact).
    force: bool,
    /// The image's detections, prepared.
    vision: Option<Prepared>,
}

/// A contact motion against the fit's clearance (module `negative`).
struct Fit {
    /// The term on this map.
    term: NegativeContact,
    /// The slide's start (or the TCP): x, y (m) and rz (rad) where the tool's axis met the
    /// goal's height.
    start: [f64; 3],
    /// The same at the motion's end.
    end: [f64; 3],
    /// The same where the contact was pressed: the end, or a point pressed after a slide.
    press: [f64; 3],
    /// The part went in: it lies within the clearance of `press`, not outside the swept
    /// line.
    went_in: bool,
}

/// Weighted standard deviation on each axis of the particles `pos` (axis-major) under the
/// normalised log weights `lw`, in one pass (one exponential per particle); on a periodic
/// axis the circular one (from the mean resultant length).
fn spreads(axes: &[MapAxis], pos: &[f32], lw: &[f32]) -> [f32; MAX_AXES] {
    let n = lw.len();
    let d = axes.len().min(MAX_AXES);
    let (mut m, mut m2) = ([0.0f64; MAX_AXES], [0.0f64; MAX_AXES]);
    for (i, &l) in lw.iter().enumerate() {
        let w = f64::from(l.exp());
        for (k, a) in axes.iter().enumerate().take(d) {
            let v = f64::from(pos[k * n + i]);
            match a.period {
                // The unit vector of the particle's phase: its mean's length says the spread.
                Some(p) => {
                    let phase = std::f64::consts::TAU * v / f64::from(p);
                    m[k] += w * phase.cos();
                    m2[k] += w * phase.sin();
                }
                None => {
                    m[k] += w * v;
                    m2[k] += w * v * v;
                }
            }
        }
    }
    std::array::from_fn(|k| match axes.get(k).and_then(|a| a.period) {
        Some(p) => {
            let length = m[k].hypot(m2[k]).clamp(1e-12, 1.0);
            ((-2.0 * length.ln()).sqrt() * f64::from(p) / std::f64::consts::TAU) as f32
        }
        None => (m2[k] - m[k] * m[k]).max(0.0).sqrt() as f32,
    })
}

/// A uniform number in [0, 1).
fn unit<T>(rng: &mut Xoshiro256PlusPlus) -> T
where
    rand_distr::StandardUniform: Distribution<T>,
{
    rand_distr::StandardUniform.sample(rng)
}

/// ln sum exp of `values` (f64; -inf for none or all -inf).
fn log_sum_exp(values: impl Iterator<Item = f32> + Clone) -> f64 {
    let max = values.clone().fold(f32::NEG_INFINITY, f32::max);
    if !max.is_finite() {
        return f64::from(max);
    }
    let sum: f64 = values.map(|v| f64::from(v - max).exp()).sum();
    f64::from(max) + sum.ln()
}

/// Shifts log weights so that their exponentials sum to 1 (log-sum-exp), writes the
/// linear weights into `w` and returns the effective sample size (sum w)^2 / sum w^2.
fn normalise(lw: &mut [f32], w: &mut [f32]) -> f64 {
    let max = lw.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    if !max.is_finite() {
        // No weight left (or none finite): uniform weights, the particles as they are.
        lw.fill(0.0);
        w.fill(1.0 / w.len() as f32);
        return w.len() as f64;
    }
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for (o, &l) in w.iter_mut().zip(lw.iter()) {
        let x = (l - max).exp();
        *o = x;
        sum += f64::from(x);
        sum2 += f64::from(x) * f64::from(x);
    }
    let shift = max + sum.ln() as f32;
    let inv = (1.0 / sum) as f32;
    for (l, o) in lw.iter_mut().zip(w.iter_mut()) {
        *l -= shift;
        *o *= inv;
    }
    sum * sum / sum2
}

#[cfg(test)]
mod rotation_tests;
#[cfg(test)]
mod tests;
