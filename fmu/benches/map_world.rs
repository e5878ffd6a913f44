//! A world that is the FT-Map itself: the peg-in-hole map computed from CAD answers every
//! contact (plus sensor noise), so no simulator stands between the map and the measurement,
//! and contacts per trial measure the filter alone. A trial starts at the nominal goal with
//! the hole at a random offset in ±4.5 mm; each contact either inserts (the TCP within the
//! radial clearance of the true offset) or is a measurement, after which the TCP moves to
//! the estimate. Compared: the FMU's filter with its default parameters and with its sigmas
//! set to the noise's, and a plain
//! condensation filter written here (Gaussian likelihood with the noise's sigmas, systematic
//! resampling every iteration, jitter, move to the mode). Prints `key = value` lines.
//! Options: `--trials N` (40), `--seed S` (1), `--force-noise N` (0.05), `--torque-noise N.m`
//! (0.002).

use std::path::Path;

use ftfusion::filter::{Config, Filter, Measurement};
use ftmap::FtMap;
use ftmap::depth::cpu::CpuBackend;
use ftmap::generate::{GenerateOptions, generate};
use rand_distr::{Distribution, Normal, StandardUniform};
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::SeedableRng;

/// The peg's radial clearance: the hole takes it within this distance of its axis (m).
const CLEARANCE: f64 = 5e-5;
/// Half width of the square of true offsets (m).
const OFFSETS: f64 = 4.5e-3;
/// Contacts after which a trial counts as failed.
const MAX_CONTACTS: usize = 30;

/// A uniform number in [0, 1).
fn unit(rng: &mut Xoshiro256PlusPlus) -> f64 {
    StandardUniform.sample(rng)
}

fn arg(args: &[String], name: &str, default: f64) -> f64 {
    args.windows(2)
        .find(|w| w[0] == name)
        .and_then(|w| w[1].parse().ok())
        .unwrap_or(default)
}

/// What the world answers at a contact: the map at the object relative to the TCP, with
/// noise on the wrench; the TCP's height is the map's contact depth.
struct World<'a> {
    map: &'a FtMap,
    noise: [f64; 6],
    rng: Xoshiro256PlusPlus,
}

impl World<'_> {
    fn contact(&mut self, truth: [f64; 2], tcp: [f64; 2]) -> anyhow::Result<Measurement> {
        let v = self
            .map
            .interpolate(&[truth[0] - tcp[0], truth[1] - tcp[1]])?;
        let mut wrench = [0.0; 6];
        for (k, w) in wrench.iter_mut().enumerate() {
            *w = v[k] + self.noise[k] * Normal::new(0.0, 1.0)?.sample(&mut self.rng);
        }
        Ok(Measurement {
            wrench,
            tcp: [tcp[0], tcp[1], v[6], 0.0, 0.0, 0.0],
            ..Measurement::default()
        })
    }
}

/// A plain condensation filter over object x, y (m).
struct Plain<'a> {
    map: &'a FtMap,
    particles: Vec<[f64; 2]>,
    sigma: [f64; 6],
    rng: Xoshiro256PlusPlus,
}

impl Plain<'_> {
    const N: usize = 4000;
    const ITERATIONS: usize = 20;
    const JITTER: f64 = 2e-5;

    /// Weighs, resamples and jitters `ITERATIONS` times; returns the mode: the weighted mean
    /// of the particles within 0.1 mm of the heaviest after the last weighing.
    fn measure(&mut self, m: &Measurement) -> anyhow::Result<[f64; 2]> {
        let normal = Normal::new(0.0, Self::JITTER)?;
        let mut w = vec![0.0; Self::N];
        for it in 0..Self::ITERATIONS {
            if it > 0 {
                for p in &mut self.particles {
                    for c in p.iter_mut() {
                        *c = (*c + normal.sample(&mut self.rng)).clamp(-5e-3, 5e-3);
                    }
                }
            }
            let mut ll = Vec::with_capacity(Self::N);
            for p in &self.particles {
                let v = self.map.interpolate(&[p[0] - m.tcp[0], p[1] - m.tcp[1]])?;
                let chi2: f64 = (0..6)
                    .map(|k| ((v[k] - m.wrench[k]) / self.sigma[k]).powi(2))
                    .sum();
                ll.push(-0.5 * chi2);
            }
            let best = ll.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            for (w, l) in w.iter_mut().zip(&ll) {
                *w = (l - best).exp();
            }
            if it + 1 == Self::ITERATIONS {
                break;
            }
            let total: f64 = w.iter().sum();
            let u0 = unit(&mut self.rng);
            let (mut acc, mut j) = (w[0], 0);
            let mut next = Vec::with_capacity(Self::N);
            for i in 0..Self::N {
                let target = (u0 + i as f64) / Self::N as f64 * total;
                while acc < target && j + 1 < Self::N {
                    j += 1;
                    acc += w[j];
                }
                next.push(self.particles[j]);
            }
            self.particles = next;
        }
        let top = (0..Self::N)
            .max_by(|&a, &b| w[a].total_cmp(&w[b]))
            .unwrap_or(0);
        let c = self.particles[top];
        let (mut sum, mut at) = (0.0, [0.0; 2]);
        for (p, &wi) in self.particles.iter().zip(&w) {
            if (p[0] - c[0]).hypot(p[1] - c[1]) < 1e-4 {
                sum += wi;
                at = [at[0] + wi * p[0], at[1] + wi * p[1]];
            }
        }
        Ok([at[0] / sum, at[1] / sum])
    }
}

/// Contacts of one trial (`None` when it did not insert within `MAX_CONTACTS`).
fn trial(
    world: &mut World<'_>,
    truth: [f64; 2],
    mut estimate: impl FnMut(&Measurement) -> anyhow::Result<[f64; 2]>,
) -> anyhow::Result<Option<usize>> {
    let mut tcp = [0.0, 0.0];
    for contact in 1..=MAX_CONTACTS {
        if (tcp[0] - truth[0]).hypot(tcp[1] - truth[1]) <= CLEARANCE {
            return Ok(Some(contact));
        }
        let m = world.contact(truth, tcp)?;
        tcp = estimate(&m)?;
    }
    Ok(None)
}

/// Prints mean, p95 and max of the contacts and the success rate under `name`.
fn report(name: &str, contacts: &[Option<usize>]) {
    let mut done: Vec<usize> = contacts.iter().flatten().copied().collect();
    done.sort_unstable();
    let mean = done.iter().sum::<usize>() as f64 / done.len().max(1) as f64;
    let p95 = done
        .get((done.len() * 95).div_ceil(100).saturating_sub(1))
        .copied()
        .unwrap_or(0);
    println!("{name}_contacts_mean = {mean:.2}");
    println!("{name}_contacts_p95 = {p95}");
    println!(
        "{name}_contacts_max = {}",
        done.last().copied().unwrap_or(0)
    );
    println!(
        "{name}_success = {:.3}",
        done.len() as f64 / contacts.len() as f64
    );
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let trials = arg(&args, "--trials", 40.0) as usize;
    let seed = arg(&args, "--seed", 1.0) as u64;
    let (fnoise, tnoise) = (
        arg(&args, "--force-noise", 0.05),
        arg(&args, "--torque-noise", 0.002),
    );
    let task = ftmap::Task::find("peg_in_hole")?;
    let map = generate(&task, &CpuBackend, &GenerateOptions::default(), &|_| ())?;
    let noise = [fnoise, fnoise, fnoise, tnoise, tnoise, tnoise];
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let truths: Vec<[f64; 2]> = (0..trials)
        .map(|_| {
            let mut u = || (2.0 * unit(&mut rng) - 1.0) * OFFSETS;
            [u(), u()]
        })
        .collect();
    println!("trials = {trials}");
    println!("noise = {fnoise} N, {tnoise} N.m");
    let world = |k: usize| World {
        map: &map,
        noise,
        rng: Xoshiro256PlusPlus::seed_from_u64(seed * 1000 + k as u64),
    };
    let matched = Config {
        sigma_force: fnoise,
        sigma_torque: tnoise,
        mismatch: 0.0,
        ..Config::default()
    };
    for (name, base) in [
        ("fmu_defaults", Config::default()),
        ("fmu_matched", matched),
    ] {
        let mut fmu = Vec::new();
        for (k, &truth) in truths.iter().enumerate() {
            let cfg = Config {
                seed: k as u64 + 1,
                ..base
            };
            let mut f = Filter::new(&map, Path::new("peg_in_hole"), cfg)?;
            fmu.push(trial(&mut world(k), truth, |m| {
                f.measure(m)?;
                let p = &f.estimate().pose;
                Ok([p[0], p[1]])
            })?);
        }
        report(name, &fmu);
    }
    let mut plain = Vec::new();
    for (k, &truth) in truths.iter().enumerate() {
        let mut prng = Xoshiro256PlusPlus::seed_from_u64(k as u64 + 1);
        let particles = (0..Plain::N)
            .map(|_| {
                let mut u = || (2.0 * unit(&mut prng) - 1.0) * 5e-3;
                [u(), u()]
            })
            .collect();
        let mut p = Plain {
            map: &map,
            particles,
            sigma: noise,
            rng: prng,
        };
        plain.push(trial(&mut world(k), truth, |m| p.measure(m))?);
    }
    report("plain", &plain);
    Ok(())
}
