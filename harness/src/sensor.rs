//! The F/T sensor in the FT-Map's convention, and a model of a real sensor's noise.
//!
//! The map's wrench (docs/method.md, "Sign conventions") is the one the environment exerts
//! on part A, in the nominal task frame's axes, torque about the sensor origin. MuJoCo's
//! `force` and `torque` sensors at site `ft` (on `part_a`, at the sensor origin, axes
//! parallel to the task frame) report the wrench that the parent body (the carriage) exerts
//! on part A, in the site frame, torque about the site. With gravity off and the contact
//! settled, part A is in equilibrium: carriage wrench + environment wrench = 0, so the map's
//! wrench is the negated reading (a peg pressed on a plate reads fz = -50 N raw, +50 N
//! converted).

use rand::Rng;

/// The wrench the environment exerts on part A (fx, fy, fz, tx, ty, tz), from MuJoCo's raw
/// force and torque readings at site `ft`.
pub fn map_wrench(raw: [f64; 6]) -> [f64; 6] {
    raw.map(|v| -v)
}

/// Gaussian noise of a 6-axis F/T sensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Standard deviation of each force component (N).
    pub force: f64,
    /// Standard deviation of each torque component (N m).
    pub torque: f64,
}

impl Noise {
    /// Typical noise of a 6-axis F/T sensor: 0.05 N and 2 mN m.
    pub const TYPICAL: Self = Self {
        force: 0.05,
        torque: 0.002,
    };
    /// No noise.
    pub const NONE: Self = Self {
        force: 0.0,
        torque: 0.0,
    };

    /// `w` plus independent Gaussian noise per component.
    pub fn apply(&self, w: [f64; 6], rng: &mut impl Rng) -> [f64; 6] {
        let mut out = w;
        for (k, v) in out.iter_mut().enumerate() {
            let sigma = if k < 3 { self.force } else { self.torque };
            if sigma > 0.0 {
                *v += sigma * gaussian(rng);
            }
        }
        out
    }
}

/// A standard normal sample (Box-Muller).
pub fn gaussian(rng: &mut impl Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn noise_has_the_asked_spread() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let n = 20_000;
        let (mut sf, mut st) = (0.0, 0.0);
        for _ in 0..n {
            let w = Noise::TYPICAL.apply([0.0; 6], &mut rng);
            sf += w[0] * w[0];
            st += w[5] * w[5];
        }
        let (sf, st) = ((sf / n as f64).sqrt(), (st / n as f64).sqrt());
        assert!((sf - 0.05).abs() < 0.002, "{sf}");
        assert!((st - 0.002).abs() < 0.0001, "{st}");
    }
}
