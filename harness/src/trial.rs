//! One assembly trial: the closed loop of the paper's Algorithm 1 (contact, measure, move
//! to the estimate, contact again; with slides, a slide under force across the estimate's
//! spread where that spread is a short segment: [`next_motion`]) or the blind spiral search
//! it is compared with. With a camera (experiment D), an image is taken before the first
//! contact motion (handed to the FMU alone) and at every contact (handed with the wrench).
//!
//! Success: a motion inserts the part (it settles with the task frame less than
//! [`SUCCESS_HEIGHT`](crate::sim::SUCCESS_HEIGHT) above the goal). Every motion, contact or
//! slide, counts as one contact motion, the successful one included; a trial ends as a
//! failure after `max_contacts` motions or `max_sim_time` of simulated time.

use std::time::Instant;

use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::error::Result;
use crate::eye::Eye;
use crate::fmu_driver::{Estimate, Fmu, Settings};
use crate::sensor::{Noise, map_wrench};
use crate::world::World;

/// How the next approach point is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Strategy {
    /// Move to the FMU's estimate after each contact (Algorithm 1).
    Pf,
    /// An Archimedean spiral of contact motions about the nominal goal.
    Spiral,
}

/// Limits and settings of a trial.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialConfig {
    /// Strategy.
    pub strategy: Strategy,
    /// Most contact motions before the trial fails.
    pub max_contacts: usize,
    /// Most simulated time before the trial fails (s).
    pub max_sim_time: f64,
    /// Sensor noise.
    pub noise: Noise,
    /// Spiral pitch and spacing of its contact points (m).
    pub spiral_step: f64,
    /// The spiral ends at this radius (m): it then covers Omega.
    pub spiral_radius: f64,
    /// FMU settings (the seed is set per trial).
    pub settings: Settings,
    /// Slides under force with the fit's radial clearance (m): [`next_motion`]; `None`,
    /// contact motions only.
    pub slide: Option<f64>,
}

/// The next motion of Algorithm 1 (the paper moves to the estimate and presses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// A contact motion at this point (m).
    Contact([f64; 2]),
    /// A slide under force between these points (m).
    Slide([f64; 2], [f64; 2]),
}

/// The slide covers the estimate's spread along its line this many times each way.
pub const SLIDE_SIGMAS: f64 = 2.0;
/// Error of the direction a contact's torque gives (rad): `harness compare-maps` measures
/// 1.3° mean, 5° max between the map's and MuJoCo's torque directions.
pub const DIRECTION_ERROR: f64 = 0.035;

/// The motion after a contact at `tcp` that gave `estimate`: a contact at the estimate; or,
/// with `slide` (the fit's clearance), a slide under force across the estimate where its
/// spread is a segment wider than the clearance. A contact near the hole tells the
/// direction of part B well and its distance poorly (the rim torque's lever hardly changes
/// with the offset), so the posterior is a segment along the line from `tcp` to the
/// estimate: used when that line is close enough that its direction's error moves it by at
/// most half the clearance. A camera sees one axis better than the other, so the posterior
/// is a segment along the axis it sees least: used when the spread across that axis is
/// within half the clearance. Contact motions would halve such a segment one by one; a
/// slide crosses it in one motion and drops in where it finds the hole.
pub fn next_motion(tcp: [f64; 2], estimate: &Estimate, slide: Option<f64>) -> Motion {
    let e = estimate.object;
    let Some(clearance) = slide else {
        return Motion::Contact(e);
    };
    let along = |u: [f64; 2]| (u[0] * estimate.std[0]).hypot(u[1] * estimate.std[1]);
    let (dx, dy) = (e[0] - tcp[0], e[1] - tcp[1]);
    let dist = dx.hypot(dy);
    let line = (dist > 0.0 && dist * DIRECTION_ERROR <= 0.5 * clearance)
        .then(|| [dx / dist, dy / dist])
        .filter(|&u| along(u) > clearance);
    let wide = usize::from(estimate.std[1] > estimate.std[0]);
    let mut axis = [0.0; 2];
    axis[wide] = 1.0;
    let segment = line.or_else(|| {
        (estimate.std[wide] > clearance && estimate.std[1 - wide] <= 0.5 * clearance)
            .then_some(axis)
    });
    match segment {
        Some(u) => {
            let half = SLIDE_SIGMAS * along(u);
            Motion::Slide(
                [e[0] - half * u[0], e[1] - half * u[1]],
                [e[0] + half * u[0], e[1] + half * u[1]],
            )
        }
        None => Motion::Contact(e),
    }
}

/// One contact motion of a trial.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Commanded and settled task frame position (m).
    pub tcp: [f64; 3],
    /// Wrench handed to the estimator (map convention, with noise).
    pub wrench: [f64; 6],
    /// The FMU's estimate after this contact (pf only).
    pub estimate: Option<Estimate>,
    /// An image's features went with the wrench.
    pub image: bool,
    /// The motion was a slide under force.
    pub slide: bool,
}

/// What a trial ended with.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialResult {
    /// True object offset (m).
    pub offset: [f64; 2],
    /// Contact motions made.
    pub contacts: usize,
    /// Whether the part reached the goal depth.
    pub success: bool,
    /// Distance of the last approach point from the true offset (m).
    pub final_error: f64,
    /// Wall-clock time of the trial (s).
    pub wall: f64,
    /// Simulated time of the trial (s).
    pub sim_time: f64,
    /// Wall-clock time spent in MuJoCo (s).
    pub sim_wall: f64,
    /// Every contact motion.
    pub steps: Vec<Step>,
    /// The estimate after the image taken before the first contact (with a camera).
    pub first_look: Option<Estimate>,
    /// Images in which not all four edges were found.
    pub images_missed: usize,
}

impl TrialResult {
    /// Contact measurements handed to the FMU (contact motions that did not insert the part).
    pub fn measurements(&self) -> usize {
        self.steps.iter().filter(|s| s.estimate.is_some()).count()
    }
}

/// Points of an Archimedean spiral r = pitch * theta / 2 pi about the origin, spaced about
/// `step` along the curve, the first at the origin, out to radius `radius`.
pub fn spiral(step: f64, radius: f64) -> Vec<[f64; 2]> {
    let b = step / std::f64::consts::TAU;
    let mut pts = vec![[0.0, 0.0]];
    let mut theta: f64 = std::f64::consts::TAU; // first turn at r = step
    while b * theta <= radius + step {
        let r = b * theta;
        pts.push([r * theta.cos(), r * theta.sin()]);
        theta += step / (r * r + b * b).sqrt();
    }
    pts
}

/// Runs one trial against the true `offset` with seed `seed` (noise and FMU seed); `eye`
/// adds the camera.
///
/// # Errors
/// When the FMU or rendering fails.
pub fn run_trial(
    sim: &mut dyn World,
    fmu: Option<&Fmu>,
    mut eye: Option<&mut Eye>,
    cfg: &TrialConfig,
    offset: [f64; 2],
    seed: u64,
) -> Result<TrialResult> {
    let start = Instant::now();
    let sim_start = sim.simulated();
    sim.set_object(offset);
    let mut rng = StdRng::seed_from_u64(seed);
    let mut estimator = match (cfg.strategy, fmu) {
        (Strategy::Pf, Some(f)) => {
            let settings = Settings {
                seed: Some((seed % i32::MAX as u64) as i32),
                ..cfg.settings.clone()
            };
            Some(f.estimator(&settings)?)
        }
        _ => None,
    };
    let spiral_pts = match cfg.strategy {
        Strategy::Spiral => spiral(cfg.spiral_step, cfg.spiral_radius),
        Strategy::Pf => Vec::new(),
    };
    let mut motion = Motion::Contact([0.0, 0.0]);
    let mut steps = Vec::new();
    let mut success = false;
    let mut sim_wall = 0.0;
    let (mut first_look, mut images_missed) = (None, 0);
    if let (Some(e), Some(eye)) = (estimator.as_mut(), eye.as_deref_mut()) {
        let tcp = [0.0, 0.0, eye.look_height()];
        match eye.look(offset, tcp, seed)? {
            Some(f) => {
                let est = e.look(tcp, &f)?;
                motion = next_motion([tcp[0], tcp[1]], &est, cfg.slide);
                first_look = Some(est);
            }
            None => images_missed += 1,
        }
    }
    while steps.len() < cfg.max_contacts && sim.simulated() - sim_start < cfg.max_sim_time {
        if cfg.strategy == Strategy::Spiral {
            match spiral_pts.get(steps.len()) {
                Some(p) => motion = Motion::Contact(*p),
                None => break,
            }
        }
        let t0 = Instant::now();
        let slide = matches!(motion, Motion::Slide(..));
        let c = match motion {
            Motion::Contact(p) => sim.contact_motion(p),
            Motion::Slide(from, to) => sim.slide_motion(from, to),
        };
        sim_wall += t0.elapsed().as_secs_f64();
        let wrench = cfg.noise.apply(map_wrench(c.raw), &mut rng);
        if c.inserted {
            steps.push(Step {
                tcp: c.tcp,
                wrench,
                estimate: None,
                image: false,
                slide,
            });
            success = true;
            break;
        }
        let image = match (&estimator, eye.as_deref_mut()) {
            (Some(_), Some(eye)) => {
                let f = eye.look(offset, c.tcp, seed.wrapping_add(steps.len() as u64 + 1))?;
                images_missed += usize::from(f.is_none());
                f
            }
            _ => None,
        };
        let estimate = match estimator.as_mut() {
            Some(e) => {
                let slide_start = match motion {
                    Motion::Slide(from, _) => Some(from),
                    Motion::Contact(_) => None,
                };
                let est = e.measure(wrench, c.tcp, slide_start, image.as_ref())?;
                // After a slide that found no hole the next motion is a contact: slides in a
                // row, each ruling out its line, run into long tails (docs/RESULTS.md).
                let slide = cfg.slide.filter(|_| matches!(motion, Motion::Contact(_)));
                motion = next_motion([c.tcp[0], c.tcp[1]], &est, slide);
                Some(est)
            }
            None => None,
        };
        steps.push(Step {
            tcp: c.tcp,
            wrench,
            estimate,
            image: image.is_some(),
            slide,
        });
    }
    let last = steps.last().map_or([0.0; 2], |s| [s.tcp[0], s.tcp[1]]);
    Ok(TrialResult {
        offset,
        contacts: steps.len(),
        success,
        final_error: (last[0] - offset[0]).hypot(last[1] - offset[1]),
        wall: start.elapsed().as_secs_f64(),
        sim_time: sim.simulated() - sim_start,
        sim_wall,
        steps,
        first_look,
        images_missed,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn estimate(object: [f64; 2], std: [f64; 2]) -> Estimate {
        Estimate {
            object,
            std,
            ..Estimate::default()
        }
    }

    #[test]
    fn the_next_motion_slides_across_a_segment_along_the_line_or_an_axis() {
        let c = 5e-5;
        let tcp = [0.001, 0.002];
        // 0.2 mm away along +x, spread 0.1 mm along x: a slide from 0.2 mm before the
        // estimate to 0.2 mm beyond, on the line through the TCP.
        let e = estimate([0.0012, 0.002], [1e-4, 1e-5]);
        match next_motion(tcp, &e, Some(c)) {
            Motion::Slide(a, b) => {
                assert!((a[0] - 0.001).abs() < 1e-12 && (b[0] - 0.0014).abs() < 1e-12);
                assert!((a[1] - 0.002).abs() < 1e-12 && (b[1] - 0.002).abs() < 1e-12);
            }
            m => panic!("{m:?}"),
        }
        // The line too long for its direction's error, but the spread a segment along y (a
        // camera's view): a slide along y across the estimate.
        let e = estimate([0.003, 0.002], [1e-5, 1e-4]);
        match next_motion(tcp, &e, Some(c)) {
            Motion::Slide(a, b) => {
                assert!((a[0] - 0.003).abs() < 1e-12 && (b[0] - 0.003).abs() < 1e-12);
                assert!((a[1] - 0.0018).abs() < 1e-12 && (b[1] - 0.0022).abs() < 1e-12);
            }
            m => panic!("{m:?}"),
        }
        // Spread within the clearance, slides off, or the line too long for its direction's
        // error and the spread across the wide axis over half the clearance: a contact at
        // the estimate.
        for (e, slide) in [
            (estimate([0.0012, 0.002], [4e-5, 1e-5]), Some(c)),
            (e, None),
            (estimate([0.003, 0.002], [1e-4, 3e-5]), Some(c)),
        ] {
            assert_eq!(next_motion(tcp, &e, slide), Motion::Contact(e.object));
        }
    }

    #[test]
    fn the_spiral_covers_its_disc_with_the_asked_spacing() {
        let pts = spiral(0.0001, 0.002);
        assert_eq!(pts[0], [0.0, 0.0]);
        for w in pts.windows(2).skip(1) {
            let d = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
            assert!(d < 0.00011 && d > 0.00009, "{d}");
        }
        // every point of the disc lies within a pitch of some spiral point
        for k in 0..200 {
            let (r, t) = (0.002 * (k as f64 / 200.0).sqrt(), k as f64 * 2.4);
            let q = [r * t.cos(), r * t.sin()];
            let near = pts
                .iter()
                .map(|p| (p[0] - q[0]).hypot(p[1] - q[1]))
                .fold(f64::INFINITY, f64::min);
            assert!(near < 0.0001, "{q:?} {near}");
        }
    }
}
