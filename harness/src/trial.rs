//! One assembly trial: the closed loop of the paper's Algorithm 1 (contact, measure, move
//! to the estimate, contact again; with slides, a slide under force across the estimate's
//! spread where that spread is a short segment: [`next_motion`]) or the blind spiral search
//! it is compared with. With a camera (experiment D), an image is taken before the first
//! contact motion (handed to the FMU alone) and at every contact (handed with the wrench).
//!
//! Success: a motion inserts the part (it brings the task frame less than
//! [`SUCCESS_HEIGHT`](crate::sim::SUCCESS_HEIGHT) above the goal). Every motion, contact or
//! slide, counts as one contact motion, the successful one included; a trial ends as a
//! failure after `max_contacts` motions or `max_sim_time` of simulated time.

use std::time::Instant;

use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::error::Result;
use crate::eye::Eye;
use crate::fmu_driver::{Estimate, Fmu, Settings, Swept};
use crate::sensor::{Noise, map_wrench};
use crate::world::{World, foot, lean};

/// How the next approach point is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
    /// Slides under force: [`next_motion`]; `None`, contact motions only.
    pub slide: Option<Slide>,
    /// n-fold symmetry of the fit about the approach (z): a yaw error counts modulo
    /// 2 pi / n.
    pub symmetry: Option<u32>,
    /// Twists under force about z where the yaw is uncertain: [`next_motion`]; `None`,
    /// none.
    pub twist: Option<Twist>,
}

/// What decides a slide under force and where it presses after it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slide {
    /// The fit's radial clearance (m).
    pub clearance: f64,
    /// Where a slide that found no hole presses for its measurement.
    pub press: SlidePress,
}

/// Where a slide under force that found no hole presses again for a static wrench (after
/// sliding, friction holds part A sideways: [`World::slide_motion`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SlidePress {
    /// At the estimate the slide crossed (its midpoint): near part B's likeliest place,
    /// where the contact's wrench says most about the offset.
    #[default]
    Estimate,
    /// Where the slide stopped, the far end of the spread.
    End,
}

/// What decides a twist under force: the fit's tolerances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Twist {
    /// The fit's radial clearance (m).
    pub clearance: f64,
    /// The fit's yaw play at zero offset (rad).
    pub play: f64,
    /// The yaw's period where the fit is symmetric about z (rad).
    pub period: Option<f64>,
}

/// The next motion of Algorithm 1 (the paper moves to the estimate and presses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// A contact motion at this point (m).
    Contact([f64; 2]),
    /// A slide under force between the first two points (m), then, where it found no hole,
    /// a press at the third.
    Slide([f64; 2], [f64; 2], [f64; 2]),
    /// A twist under force at this point (m) from one yaw to another (rad).
    Twist([f64; 2], f64, f64),
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
/// estimate (Algorithm 1), or, with `slide`, a slide under force
/// along the major axis of the estimate's spread, across [`SLIDE_SIGMAS`] of it each way,
/// where the spread reaches beyond the capture and a slide is likelier to find the hole
/// than a contact at the estimate (a slide through it covers the disc a contact would: with
/// a spread within the capture a contact is enough). A contact near
/// the hole tells the direction of part B well and its distance poorly (the rim torque's
/// lever hardly changes with the offset), and a camera sees one axis better than the other:
/// the posterior is then a segment that contact motions would halve one by one, and that
/// a slide crosses in one motion, dropping in where it finds the hole. The slide starts at
/// the end nearer the TCP; where it finds no hole, part A presses again where
/// [`SlidePress`] says (by default at the estimate: Algorithm 1's contact, after the sweep).
///
/// With `twist`, where the spread across x, y lies within the capture and the yaw's spread
/// beyond half the fit's play: a twist at the estimate through the whole period where the
/// fit is symmetric about z (else across [`SLIDE_SIGMAS`] of the yaw's spread each way). A
/// press where x, y are right but the yaw is not stays out, and near the centre the corners
/// rest on the rim alike at every yaw: there the yaw is weakly observable. A twist passes
/// every yaw of its range and drops in at the right one.
pub fn next_motion(
    tcp: [f64; 2],
    estimate: &Estimate,
    slide: Option<Slide>,
    twist: Option<Twist>,
) -> Motion {
    let e = estimate.object;
    if let Some(t) = twist {
        let (yaw, std) = (estimate.rot[2], estimate.rot_std[2]);
        if Spread::of(estimate).major <= CAPTURE * t.clearance && std > 0.5 * t.play {
            let half = t.period.map_or(SLIDE_SIGMAS * std, |p| 0.5 * p);
            return Motion::Twist(e, yaw - half, yaw + half);
        }
    }
    let Some(slide) = slide else {
        return Motion::Contact(e);
    };
    let spread = Spread::of(estimate);
    let reach = CAPTURE * slide.clearance;
    if spread.major <= reach || spread.swept(reach) <= spread.within(reach) {
        return Motion::Contact(e);
    }
    let toward = (e[0] - tcp[0]) * spread.axis[0] + (e[1] - tcp[1]) * spread.axis[1];
    let u = spread.axis.map(|a| if toward < 0.0 { -a } else { a });
    let half = SLIDE_SIGMAS * spread.major;
    let end = [e[0] + half * u[0], e[1] + half * u[1]];
    Motion::Slide(
        [e[0] - half * u[0], e[1] - half * u[1]],
        end,
        match slide.press {
            SlidePress::Estimate => e,
            SlidePress::End => end,
        },
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
    /// Part B's rotation relative to the nominal goal (rotation vector, rad): the TCP
    /// rotation at which the parts align.
    pub rot: [f64; 3],
}

impl Truth {
    /// Each of `objects` with the grip held as nominal and part B unturned.
    pub fn objects(objects: &[[f64; 2]]) -> Vec<Self> {
        objects
            .iter()
            .map(|&object| Self {
                object,
                ..Self::default()
            })
            .collect()
    }
}

/// One contact motion of a trial.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Step {
    /// Commanded and settled task frame position (m).
    pub tcp: [f64; 3],
    /// The task frame's rotation (rotation vector, rad).
    pub rot: [f64; 3],
    /// Wrench handed to the estimator (map convention, with noise).
    pub wrench: [f64; 6],
    /// The FMU's estimate after this contact (pf only).
    pub estimate: Option<Estimate>,
    /// The FMU's estimate after the press a slide started from, read at rest before it slid
    /// (pf only): a contact measurement of its own within the same motion.
    #[serde(default)]
    pub started: Option<Estimate>,
    /// An image's features went with the wrench.
    pub image: bool,
    /// The motion was a slide under force.
    pub slide: bool,
    /// The motion was a twist under force.
    pub twist: bool,
}

impl Step {
    /// Where the tool's axis met the goal's height at this contact (x, y, m): the TCP's
    /// own x, y for a level tool; what part B's offset is compared with.
    pub fn foot(&self) -> [f64; 2] {
        foot(
            self.tcp,
            &nalgebra::Rotation3::new(nalgebra::Vector3::from(self.rot)),
        )
    }
}

/// What a trial ended with.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrialResult {
    /// True object offset (m).
    pub offset: [f64; 2],
    /// True grip offset (m).
    pub grip: [f64; 2],
    /// True rotation of part B (rotation vector, rad).
    pub rot: [f64; 3],
    /// The fit's n-fold symmetry about z, modulo whose period yaw errors count.
    pub symmetry: Option<u32>,
    /// Contact motions made.
    pub contacts: usize,
    /// Whether the part reached the goal depth.
    pub success: bool,
    /// Distance of the last approach point (where the tool's axis met the goal's height) from
    /// the true offset (m).
    pub final_error: f64,
    /// The last approach's rotation error: the rotation vector of R_tcp^T R_object (rad),
    /// its z component modulo the symmetry's period.
    pub final_rot_error: [f64; 3],
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
    /// Contact measurements handed to the FMU (contact motions that did not insert the
    /// part, and the presses that slides started from).
    pub fn measurements(&self) -> usize {
        self.steps
            .iter()
            .map(|s| usize::from(s.estimate.is_some()) + usize::from(s.started.is_some()))
            .sum()
    }

    /// The result without its wall-clock times: what a repeated run (on other workers or
    /// machines) reproduces exactly.
    pub fn untimed(&self) -> Self {
        Self {
            wall: 0.0,
            sim_wall: 0.0,
            ..self.clone()
        }
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

/// The rotation from a TCP turned by `tcp` to part B turned by `object` (rotation vectors,
/// rad): the rotation vector of R_tcp^T R_object, its z component brought within half the
/// period of an n-fold `symmetry` about z.
pub fn rotation_error(tcp: [f64; 3], object: [f64; 3], symmetry: Option<u32>) -> [f64; 3] {
    use nalgebra::{Rotation3, Vector3};
    let r = Rotation3::from_scaled_axis(Vector3::from(tcp)).inverse()
        * Rotation3::from_scaled_axis(Vector3::from(object));
    let mut e: [f64; 3] = r.scaled_axis().into();
    if let Some(n) = symmetry {
        let period = std::f64::consts::TAU / f64::from(n);
        e[2] -= period * (e[2] / period).round();
    }
    e
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
    let offset = truth.object;
    sim.set_grip(truth.grip);
    sim.set_object(offset);
    sim.set_object_rotation(truth.rot)?;
    sim.set_tcp_rotation([0.0; 3])?;
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
    // Summed per trial, not read off the world's running total: a trial's figure does not
    // depend on what the world simulated before it (on another worker, say).
    let mut sim_time = 0.0;
    let (mut first_look, mut images_missed) = (None, 0);
    if let (Some(e), Some(eye)) = (estimator.as_mut(), eye.as_deref_mut()) {
        let tcp = [0.0, 0.0, eye.look_height()];
        match eye.look(offset, tcp, seed)? {
            Some(f) => {
                let est = e.look(tcp, &f)?;
                motion = next_motion([tcp[0], tcp[1]], &est, cfg.slide, cfg.twist);
                first_look = Some(est);
            }
            None => images_missed += 1,
        }
    }
    while steps.len() < cfg.max_contacts && sim_time < cfg.max_sim_time {
        if cfg.strategy == Strategy::Spiral {
            match spiral_pts.get(steps.len()) {
                Some(p) => motion = Motion::Contact(*p),
                None => break,
            }
        }
        let t0 = Instant::now();
        let (slide, twist) = (
            matches!(motion, Motion::Slide(..)),
            matches!(motion, Motion::Twist(..)),
        );
        let (c, start, stopped) = match motion {
            Motion::Contact(p) => (sim.contact_motion(p), None, p),
            Motion::Slide(from, to, press) => {
                let slid = sim.slide_motion(from, to, press);
                (slid.end, slid.start, slid.stopped)
            }
            Motion::Twist(p, from, to) => (sim.twist_motion(p, from, to)?, None, p),
        };
        sim_wall += t0.elapsed().as_secs_f64();
        sim_time += c.time;
        let wrench = cfg.noise.apply(map_wrench(c.raw), &mut rng);
        if c.inserted {
            steps.push(Step {
                tcp: c.tcp,
                rot: c.rot,
                wrench,
                estimate: None,
                started: None,
                image: false,
                slide,
                twist,
            });
            success = true;
            break;
        }
        // The press a slide started from, at rest: a static contact like any other.
        let started = match (estimator.as_mut(), start) {
            (Some(e), Some(s)) => {
                let w = cfg.noise.apply(map_wrench(s.raw), &mut rng);
                Some(e.measure(w, s.tcp, s.rot, None, None)?)
            }
            _ => None,
        };
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
                // Where the TCP itself stood when the sweep began (at the end's height and
                // tilt): the motions are commanded where the tool's axis meets the goal's
                // height, which a tilted TCP stands beside.
                let lean = lean(&nalgebra::Rotation3::new(nalgebra::Vector3::from(c.rot)));
                let tcp_at = |p: [f64; 2]| [p[0] + lean[0] * c.tcp[2], p[1] + lean[1] * c.tcp[2]];
                let at = |p: [f64; 2], rz: f64| {
                    let [x, y] = tcp_at(p);
                    [x, y, rz]
                };
                let swept = match motion {
                    // A slide pressed again elsewhere rules out the line up to where it
                    // stopped: its far end, or short of it where part A dropped and jammed.
                    Motion::Slide(from, to, press) => Some(Swept {
                        start: at(from, c.rot[2]),
                        end: (press != to).then(|| at(stopped, c.rot[2])),
                    }),
                    Motion::Twist(p, from, _) => Some(Swept {
                        start: at(p, from),
                        end: None,
                    }),
                    Motion::Contact(_) => None,
                };
                let est = e.measure(wrench, c.tcp, c.rot, swept, image.as_ref())?;
                motion = next_motion([c.tcp[0], c.tcp[1]], &est, cfg.slide, cfg.twist);
                sim.set_tcp_rotation(est.rot)?;
                Some(est)
            }
            None => None,
        };
        steps.push(Step {
            tcp: c.tcp,
            rot: c.rot,
            wrench,
            estimate,
            started,
            image: image.is_some(),
            slide,
            twist,
        });
    }
    let last = steps.last().map_or([0.0; 2], Step::foot);
    let last_rot = steps.last().map_or([0.0; 3], |s| s.rot);
    Ok(TrialResult {
        offset,
        grip: truth.grip,
        rot: truth.rot,
        symmetry: cfg.symmetry,
        contacts: steps.len(),
        success,
        final_error: (last[0] - offset[0]).hypot(last[1] - offset[1]),
        final_rot_error: rotation_error(last_rot, truth.rot, cfg.symmetry),
        wall: start.elapsed().as_secs_f64(),
        sim_time,
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
    fn a_tilted_step_s_foot_lies_down_its_axis() {
        // A TCP at height h tilted by t about y (its axis leaning towards +x going up) met
        // the goal's height h tan t towards -x; about x, towards +y; level, under itself.
        let (h, t) = (0.01f64, 0.03f64);
        let step = |rot| Step {
            tcp: [1e-3, -2e-3, h],
            rot,
            wrench: [0.0; 6],
            estimate: None,
            started: None,
            image: false,
            slide: false,
            twist: false,
        };
        assert_eq!(step([0.0, 0.0, 0.4]).foot(), [1e-3, -2e-3]);
        let near = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-12;
        assert!(near(
            step([0.0, t, 0.0]).foot(),
            [1e-3 - h * t.tan(), -2e-3]
        ));
        assert!(near(
            step([t, 0.0, 0.0]).foot(),
            [1e-3, -2e-3 + h * t.tan()]
        ));
    }

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
        let slide = |press| {
            Some(Slide {
                clearance: c,
                press,
            })
        };
        match next_motion(tcp, &along_x, slide(SlidePress::Estimate), None) {
            Motion::Slide(a, b, p) => {
                assert!((a[0] - 0.0012).abs() < 1e-12 && (b[0] - 0.0016).abs() < 1e-12);
                assert!((a[1] - 0.002).abs() < 1e-12 && (b[1] - 0.002).abs() < 1e-12);
                assert_eq!(p, along_x.object, "it presses again at the estimate");
            }
            m => panic!("{m:?}"),
        }
        match next_motion(tcp, &along_x, slide(SlidePress::End), None) {
            Motion::Slide(_, b, p) => assert_eq!(p, b, "it presses again where it stopped"),
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
        match next_motion([0.001, 0.001], &diagonal, slide(SlidePress::Estimate), None) {
            Motion::Slide(a, b, _) => {
                assert!(a[0] > 0.0 && (a[0] - a[1]).abs() < 2e-6, "{a:?}");
                assert!((b[0] + a[0]).abs() < 1e-12 && (b[1] + a[1]).abs() < 1e-12);
            }
            m => panic!("{m:?}"),
        }
        // A spread within the capture: a contact at the estimate; and a contact without
        // slides, whatever the spread.
        for (std, slide) in [
            ([2e-5, 3e-5], slide(SlidePress::Estimate)),
            ([1e-4, 1e-5], None),
        ] {
            let e = Estimate {
                object: [0.0003, 0.0],
                std,
                ..Estimate::default()
            };
            assert_eq!(next_motion(tcp, &e, slide, None), Motion::Contact(e.object));
        }
    }

    #[test]
    fn the_next_motion_twists_through_the_period_once_x_and_y_are_within_the_capture() {
        let c = 2.5e-5;
        let period = std::f64::consts::TAU / 8.0;
        let twist = Twist {
            clearance: c,
            play: 0.5f64.to_radians(),
            period: Some(period),
        };
        let slide = Some(Slide {
            clearance: c,
            press: SlidePress::default(),
        });
        let at = |std: [f64; 2], yaw_std: f64| Estimate {
            object: [0.001, -0.002],
            std,
            rot: [0.0, 0.0, 0.1],
            rot_std: [0.0, 0.0, yaw_std],
            ..Estimate::default()
        };
        // x, y within the capture, the yaw uncertain: a twist through one whole period
        // about the estimated yaw, at the estimate.
        match next_motion([0.0; 2], &at([5e-6, 8e-6], 0.05), slide, Some(twist)) {
            Motion::Twist(p, from, to) => {
                assert_eq!(p, [0.001, -0.002]);
                assert!((from - (0.1 - period / 2.0)).abs() < 1e-12, "{from}");
                assert!((to - (0.1 + period / 2.0)).abs() < 1e-12, "{to}");
            }
            m => panic!("{m:?}"),
        }
        // The yaw known within the play, or x, y not yet within the capture: no twist.
        let known = at([5e-6, 8e-6], 0.001);
        assert_eq!(
            next_motion([0.0; 2], &known, slide, Some(twist)),
            Motion::Contact(known.object)
        );
        let wide = at([1e-4, 1e-4], 0.05);
        assert!(!matches!(
            next_motion([0.0; 2], &wide, slide, Some(twist)),
            Motion::Twist(..)
        ));
        // Without symmetry: SLIDE_SIGMAS of the yaw's spread each way.
        let open = Twist {
            period: None,
            ..twist
        };
        match next_motion([0.0; 2], &at([5e-6, 8e-6], 0.05), slide, Some(open)) {
            Motion::Twist(_, from, to) => {
                assert!((to - from - 2.0 * SLIDE_SIGMAS * 0.05).abs() < 1e-12);
            }
            m => panic!("{m:?}"),
        }
    }

    #[test]
    fn rotation_errors_compose_and_count_modulo_the_symmetry() {
        // A TCP at 20 degrees over a part at -24 degrees: -44 degrees, 1 modulo 45.
        let deg = f64::to_radians;
        let e = rotation_error([0.0, 0.0, deg(20.0)], [0.0, 0.0, deg(-24.0)], Some(8));
        assert!((e[2] - deg(1.0)).abs() < 1e-12, "{e:?}");
        let plain = rotation_error([0.0, 0.0, deg(20.0)], [0.0, 0.0, deg(-24.0)], None);
        assert!((plain[2] - deg(-44.0)).abs() < 1e-12, "{plain:?}");
        // Tilts compose as rotations: R_tcp^T R_object for two tilts about x and y.
        let (a, b) = (deg(2.0), deg(-1.5));
        let e = rotation_error([a, 0.0, 0.0], [0.0, b, 0.0], None);
        let want = nalgebra::Rotation3::from_scaled_axis(nalgebra::Vector3::new(-a, 0.0, 0.0))
            * nalgebra::Rotation3::from_scaled_axis(nalgebra::Vector3::new(0.0, b, 0.0));
        let w = want.scaled_axis();
        assert!((0..3).all(|k| (e[k] - w[k]).abs() < 1e-12), "{e:?} {w:?}");
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
