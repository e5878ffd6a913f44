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

/// The slide covers the estimate's spread along its major axis this many times each way.
pub const SLIDE_SIGMAS: f64 = 2.0;
/// Share of the fit's clearance within which a motion counts on part A going in: a slide
/// drops in where it passes within 0.9 clearances of the hole (`harness/tests/slide.rs`).
pub const CAPTURE: f64 = 0.9;

/// The estimate's spread as a 2-D Gaussian: its standard deviations along the major and
/// minor axes and the major axis's direction (`object.x_std`, `object.y_std`,
/// `object.xy_corr`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// Standard deviation along the major axis (m).
    pub major: f64,
    /// Standard deviation along the minor axis (m).
    pub minor: f64,
    /// Unit direction of the major axis.
    pub axis: [f64; 2],
}

impl Spread {
    /// The principal axes of the estimate's covariance.
    pub fn of(e: &Estimate) -> Self {
        let [sx, sy] = e.std;
        let (a, b, c) = (sx * sx, e.corr * sx * sy, sy * sy);
        let mid = 0.5 * (a + c);
        let half = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        let theta = 0.5 * (2.0 * b).atan2(a - c);
        Self {
            major: (mid + half).max(0.0).sqrt(),
            minor: (mid - half).max(0.0).sqrt(),
            axis: [theta.cos(), theta.sin()],
        }
    }

    /// The chance that part B lies within `r` of the estimate (a contact motion there goes
    /// in): the Gaussian's mass over the disc, by quadrature over the direction.
    pub fn within(&self, r: f64) -> f64 {
        const STEPS: usize = 64;
        let (a, b) = (self.major.max(1e-12), self.minor.max(1e-12));
        let sum: f64 = (0..STEPS)
            .map(|k| {
                let t = std::f64::consts::TAU * (k as f64 + 0.5) / STEPS as f64;
                let q = (t.cos() / a).powi(2) + (t.sin() / b).powi(2);
                (1.0 - (-0.5 * r * r * q).exp()) / q
            })
            .sum();
        (sum / STEPS as f64 / (a * b)).min(1.0)
    }

    /// The chance that a slide along the major axis across `SLIDE_SIGMAS` of it each way
    /// passes within `r` of part B.
    pub fn swept(&self, r: f64) -> f64 {
        let inside = |x: f64, s: f64| {
            if s > 0.0 {
                libm::erf(x / (s * 2f64.sqrt()))
            } else {
                1.0
            }
        };
        inside(r, self.minor) * inside(SLIDE_SIGMAS * self.major + r, self.major)
    }
}

/// The motion after a measurement that gave `estimate`, the TCP at `tcp`: a contact at the
/// estimate (Algorithm 1), or, with `slide` (the fit's clearance), a slide under force
/// along the major axis of the estimate's spread, across [`SLIDE_SIGMAS`] of it each way,
/// where the spread reaches beyond the capture and a slide is likelier to find the hole
/// than a contact at the estimate (a slide through it covers the disc a contact would: with
/// a spread within the capture a contact is enough). A contact near
/// the hole tells the direction of part B well and its distance poorly (the rim torque's
/// lever hardly changes with the offset), and a camera sees one axis better than the other:
/// the posterior is then a segment that contact motions would halve one by one, and that
/// a slide crosses in one motion, dropping in where it finds the hole. The slide starts at
/// the end nearer the TCP.
pub fn next_motion(tcp: [f64; 2], estimate: &Estimate, slide: Option<f64>) -> Motion {
    let e = estimate.object;
    let Some(clearance) = slide else {
        return Motion::Contact(e);
    };
    let spread = Spread::of(estimate);
    let reach = CAPTURE * clearance;
    if spread.major <= reach || spread.swept(reach) <= spread.within(reach) {
        return Motion::Contact(e);
    }
    let toward = (e[0] - tcp[0]) * spread.axis[0] + (e[1] - tcp[1]) * spread.axis[1];
    let u = spread.axis.map(|a| if toward < 0.0 { -a } else { a });
    let half = SLIDE_SIGMAS * spread.major;
    Motion::Slide(
        [e[0] - half * u[0], e[1] - half * u[1]],
        [e[0] + half * u[0], e[1] + half * u[1]],
    )
}

/// A trial's true offsets: what the estimator is to find.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Truth {
    /// The object offset (m): the TCP position at which the parts align (with a grip
    /// offset, part B sits that much farther off, under part A).
    pub object: [f64; 2],
    /// How far off-centre the hand holds part A (m; the paper's r1).
    pub grip: [f64; 2],
}

impl Truth {
    /// Each of `objects` with the grip held as nominal.
    pub fn objects(objects: &[[f64; 2]]) -> Vec<Self> {
        objects
            .iter()
            .map(|&object| Self {
                object,
                grip: [0.0; 2],
            })
            .collect()
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
    /// True grip offset (m).
    pub grip: [f64; 2],
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

/// Runs one trial against the true offsets `truth` with seed `seed` (noise and FMU seed);
/// `eye` adds the camera.
///
/// # Errors
/// When the FMU or rendering fails.
pub fn run_trial(
    sim: &mut dyn World,
    fmu: Option<&Fmu>,
    mut eye: Option<&mut Eye>,
    cfg: &TrialConfig,
    truth: Truth,
    seed: u64,
) -> Result<TrialResult> {
    let start = Instant::now();
    let sim_start = sim.simulated();
    let offset = truth.object;
    sim.set_grip(truth.grip);
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
                motion = next_motion([c.tcp[0], c.tcp[1]], &est, cfg.slide);
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
        grip: truth.grip,
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
    use crate::sensor::gaussian;

    #[test]
    fn the_spread_has_the_covariance_s_principal_axes() {
        // 0.3 mm along 30 degrees, 0.02 mm across: back from x/y spreads and correlation.
        let (a, b, t) = (3e-4f64, 2e-5f64, 30f64.to_radians());
        let (sx2, sy2) = (
            (a * t.cos()).powi(2) + (b * t.sin()).powi(2),
            (a * t.sin()).powi(2) + (b * t.cos()).powi(2),
        );
        let cxy = (a * a - b * b) * t.sin() * t.cos();
        let e = Estimate {
            std: [sx2.sqrt(), sy2.sqrt()],
            corr: cxy / (sx2 * sy2).sqrt(),
            ..Estimate::default()
        };
        let s = Spread::of(&e);
        assert!(
            (s.major - a).abs() < 1e-12 && (s.minor - b).abs() < 1e-12,
            "{s:?}"
        );
        assert!((s.axis[1].atan2(s.axis[0]) - t).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn the_chances_of_going_in_are_the_gaussian_s() {
        // A round Gaussian: the disc of radius r holds 1 - exp(-r^2 / 2 s^2).
        let round = Spread {
            major: 1e-4,
            minor: 1e-4,
            axis: [1.0, 0.0],
        };
        for r in [2e-5, 1e-4, 3e-4] {
            let want = 1.0 - (-0.5 * (r / 1e-4f64).powi(2)).exp();
            assert!((round.within(r) - want).abs() < 1e-6, "{r}");
        }
        // An elongated one against a Monte Carlo count of the same Gaussian.
        let long = Spread {
            major: 3e-4,
            minor: 3e-5,
            axis: [1.0, 0.0],
        };
        let (mut rng, r) = (StdRng::seed_from_u64(3), 5e-5);
        let n = 200_000;
        let hits = (0..n)
            .filter(|_| {
                let (x, y) = (3e-4 * gaussian(&mut rng), 3e-5 * gaussian(&mut rng));
                x.hypot(y) <= r
            })
            .count();
        assert!((long.within(r) - hits as f64 / n as f64).abs() < 0.005);
        // A slide along it passes within r where |minor error| <= r and the major error is
        // within the slide's reach: erf(r / (sqrt 2 minor)) erf((2 major + r) / (sqrt 2 major)).
        let want = 0.904_419 * 0.969_740;
        assert!((long.swept(r) - want).abs() < 1e-6, "{}", long.swept(r));
    }

    #[test]
    fn the_next_motion_slides_where_a_slide_is_likelier_to_find_the_hole() {
        let c = 5e-5;
        let tcp = [0.001, 0.002];
        // Spread 0.1 mm along x, 0.01 mm across: a slide along x through the estimate from
        // the end nearer the TCP, 0.2 mm each way.
        let along_x = Estimate {
            object: [0.0014, 0.002],
            std: [1e-4, 1e-5],
            ..Estimate::default()
        };
        match next_motion(tcp, &along_x, Some(c)) {
            Motion::Slide(a, b) => {
                assert!((a[0] - 0.0012).abs() < 1e-12 && (b[0] - 0.0016).abs() < 1e-12);
                assert!((a[1] - 0.002).abs() < 1e-12 && (b[1] - 0.002).abs() < 1e-12);
            }
            m => panic!("{m:?}"),
        }
        // The same along the diagonal (correlated x and y): the slide follows it, starting
        // nearer the TCP.
        let s = 1e-4 / 2f64.sqrt();
        let diagonal = Estimate {
            object: [0.0, 0.0],
            std: [s, s],
            corr: 0.98,
            ..Estimate::default()
        };
        match next_motion([0.001, 0.001], &diagonal, Some(c)) {
            Motion::Slide(a, b) => {
                assert!(a[0] > 0.0 && (a[0] - a[1]).abs() < 2e-6, "{a:?}");
                assert!((b[0] + a[0]).abs() < 1e-12 && (b[1] + a[1]).abs() < 1e-12);
            }
            m => panic!("{m:?}"),
        }
        // A spread within the capture: a contact at the estimate; and a contact without
        // slides, whatever the spread.
        for (std, slide) in [([2e-5, 3e-5], Some(c)), ([1e-4, 1e-5], None)] {
            let e = Estimate {
                object: [0.0003, 0.0],
                std,
                ..Estimate::default()
            };
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
