//! Fast Gaussian jitter: standard-normal quantiles in a small table, indexed by random
//! bits, five draws per 64-bit random number. The jitter only needs a bell-shaped
//! spread, and the table (4096 quantiles, tails cut at |z| = 3.7) is exact to the
//! quantile it samples.

use std::sync::OnceLock;

use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::Rng;

/// Bits of randomness per draw.
const BITS: u32 = 12;
/// Entries of the quantile table.
const SIZE: usize = 1 << BITS;

/// The standard-normal quantiles at (i + 0.5) / SIZE.
fn table() -> &'static [f32; SIZE] {
    static TABLE: OnceLock<[f32; SIZE]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| inverse_normal_cdf((i as f64 + 0.5) / SIZE as f64) as f32)
    })
}

/// Adds `scale` times a standard-normal draw to every value and brings it back into its
/// axis with `fold` (a mirror at its bounds, or a wrap on a periodic axis).
pub fn jitter(
    rng: &mut Xoshiro256PlusPlus,
    values: &mut [f32],
    scale: f32,
    fold: impl Fn(f32) -> f32,
) {
    let t = table();
    let mut chunks = values.chunks_mut(5);
    for chunk in &mut chunks {
        let mut bits = rng.next_u64();
        for v in chunk {
            let z = t[(bits as usize) & (SIZE - 1)];
            bits >>= BITS;
            *v = fold(*v + scale * z);
        }
    }
}

/// The standard normal quantile function (Acklam's rational approximation, relative
/// error below 1.2e-9).
pub fn inverse_normal_cdf(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.38357751867269e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    const LOW: f64 = 0.02425;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_xoshiro::rand_core::SeedableRng;

    #[test]
    fn quantiles_match_known_values() {
        // Standard normal quantiles from tables.
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959963984540054),
            (0.8413447460685429, 1.0),
            (0.001, -3.090232306167813),
            (0.01, -2.326347874040841),
        ] {
            assert!(
                (inverse_normal_cdf(p) - z).abs() < 1e-8,
                "p {p}: {} vs {z}",
                inverse_normal_cdf(p)
            );
        }
    }

    #[test]
    fn jitter_has_zero_mean_and_the_requested_spread() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let n = 200_000;
        let mut v = vec![50.0f32; n];
        jitter(&mut rng, &mut v, 0.5, |x| x.clamp(0.0, 100.0));
        let mean = v.iter().map(|&x| f64::from(x)).sum::<f64>() / n as f64;
        let var = v
            .iter()
            .map(|&x| (f64::from(x) - mean).powi(2))
            .sum::<f64>()
            / n as f64;
        assert!((mean - 50.0).abs() < 0.01, "mean {mean}");
        assert!((var.sqrt() - 0.5).abs() < 0.01, "std {}", var.sqrt());
        let mut c = vec![0.1f32; 1000];
        jitter(&mut rng, &mut c, 5.0, |x| x.clamp(0.0, 0.2));
        assert!(
            c.iter().all(|&x| (0.0..=0.2).contains(&x)),
            "clamped into [0, top]"
        );
        let mut w = vec![0.1f32; 1000];
        jitter(&mut rng, &mut w, 5.0, |x| x.rem_euclid(1.0));
        assert!(
            w.iter().all(|&x| (0.0..1.0).contains(&x)),
            "wrapped into [0, 1)"
        );
        assert!(w.iter().any(|&x| x > 0.5), "wrapped, not clamped");
    }
}
