//! Systematic resampling (Algorithm 1, steps 17-23, with one random offset for all draws).

/// Fills `pick` with the indices of the particles drawn from normalised weights `w`:
/// draw i of m takes the particle whose cumulative weight first reaches (u0 + i) / m.
pub fn systematic(w: &[f32], u0: f64, pick: &mut [u32]) {
    let n = w.len();
    let step = 1.0 / pick.len() as f64;
    let mut target = u0 * step;
    let mut j = 0usize;
    let mut cum = f64::from(w[0]);
    for p in pick.iter_mut() {
        while cum < target && j < n - 1 {
            j += 1;
            cum += f64::from(w[j]);
        }
        *p = j as u32;
        target += step;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_follow_the_weights() {
        let w = [0.5f32, 0.25, 0.0, 0.25];
        let mut pick = [0u32; 8];
        systematic(&w, 0.5, &mut pick);
        assert_eq!(pick, [0, 0, 0, 0, 1, 1, 3, 3]);
        systematic(&w, 0.999, &mut pick);
        assert_eq!(pick.iter().filter(|&&p| p == 2).count(), 0);
    }
}
