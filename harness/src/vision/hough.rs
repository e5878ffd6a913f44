//! The paper's fast line edge detector (section III-A): a Hough transform bounded to the
//! expected area of a line edge, with a sub-pixel least-squares refinement.
//!
//! The Hough space (theta the normal's direction, rho the distance along it, measured from
//! the expected line's midpoint) spans only theta within the largest angle deviation of the
//! expected normal and rho within the search band of the expected line; its resolution
//! follows the expected geometry (a theta step moves the line by at most `resolution` px
//! within the expected length, a rho step is at most `resolution` px). Pixels within the band
//! between the shrunk expected endpoints vote with their gradient component along the expected
//! normal (those above the least gradient), split linearly between the two nearest rho bins.
//! The accumulator's peak (smoothed over 1 px in rho, so that it reads as the mean gradient
//! along its line) gives a provisional line; the sub-pixel gradient maxima per row or column
//! within 1.5 px of it are fitted by least squares (outliers beyond 1.5 px dropped), extended
//! along the line while the gradient holds, and fitted again. Too weak a peak, or too few
//! supporting points, is [`VisionError::FeatureNotFound`], never a guess.

use super::image::{EdgePoints, Gradient, Line, LineParams, NEAR, VisionError};

/// Tuning of [`detect_line_hough`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoughParams {
    /// The search near the expected line (band: the rho range; shrink, least gradient,
    /// extension and support as for the gradient detector).
    pub line: LineParams,
    /// Largest deviation of the line's direction from the expected one (degrees): the theta range.
    pub max_angle: f64,
    /// Hough resolution (px): the largest line displacement per rho step, and per theta step within the expected length.
    pub resolution: f64,
    /// Least mean gradient (grey levels per px) along the accumulator's peak line.
    pub min_peak: f32,
}

impl Default for HoughParams {
    fn default() -> Self {
        Self {
            line: LineParams::default(),
            max_angle: 3.0,
            resolution: 0.5,
            min_peak: 4.0,
        }
    }
}

/// Detects the line edge expected between `expected[0]` and `expected[1]` (pixel coordinates)
/// by the bounded Hough transform.
///
/// # Errors
/// [`VisionError::FeatureNotFound`] when the expected line is too short, the parameters leave
/// no Hough space, the accumulator's peak is too weak, or too few edge points support it.
pub fn detect_line_hough(
    grad: &Gradient,
    expected: [[f64; 2]; 2],
    p: &HoughParams,
) -> Result<Line, VisionError> {
    let not_found = |why: String| Err(VisionError::FeatureNotFound(why));
    let [e0, e1] = expected;
    let (du, dv) = (e1[0] - e0[0], e1[1] - e0[1]);
    let len = du.hypot(dv);
    if !len.is_finite() || len < 4.0 {
        return not_found(format!(
            "expected line of {len} px, not a finite length of 4 px or more"
        ));
    }
    // Below 45 degrees the peak line stays within 90 degrees of the expected major axis.
    if !(p.line.band > 0.0
        && p.max_angle >= 0.0
        && p.max_angle < 45.0
        && p.resolution >= 0.05
        && p.line.shrink >= 0.0
        && p.line.shrink < 0.5)
    {
        return not_found(format!(
            "no Hough space for band {}, max angle {}, resolution {}, shrink {}",
            p.line.band, p.max_angle, p.resolution, p.line.shrink
        ));
    }
    let (w, h) = (grad.width, grad.height);
    // Frame of the expected line: midpoint m, direction d, normal n0 (as in `detect_line`).
    let m = [0.5 * (e0[0] + e1[0]), 0.5 * (e0[1] + e1[1])];
    let d = [du / len, dv / len];
    let n0 = [-d[1], d[0]];
    // No line farther from m than `reach` crosses the image, nor is more than `diag` of one
    // in it: they bound the accumulator's size.
    let diag = (w as f64).hypot(h as f64);
    let reach = diag + (m[0] - 0.5 * w as f64).hypot(m[1] - 0.5 * h as f64);
    let band = p.line.band.min(reach);
    // Hough space: theta steps moving the expected segment's ends by at most `resolution`.
    let half_len = 0.5 * len;
    let max_angle = p.max_angle.to_radians();
    let half_theta = (max_angle * 0.5 * len.min(diag) / p.resolution).ceil() as usize;
    let dtheta = if half_theta == 0 {
        0.0
    } else {
        max_angle / half_theta as f64
    };
    let n_rho = (2.0 * band / p.resolution).ceil() as usize + 1;
    let drho = 2.0 * band / (n_rho - 1) as f64;
    let phi0 = n0[1].atan2(n0[0]);
    let normals: Vec<[f64; 2]> = (0..=2 * half_theta)
        .map(|k| {
            let (s, c) = (phi0 + (k as f64 - half_theta as f64) * dtheta).sin_cos();
            [c, s]
        })
        .collect();
    // Voting region: within the band (widened by the largest rotation) between the shrunk ends.
    let half_vote = half_len * (1.0 - 2.0 * p.line.shrink);
    if half_vote < 1.0 {
        return not_found(format!(
            "voting span of {:.1} px after shrinking by {}",
            2.0 * half_vote,
            p.line.shrink
        ));
    }
    let across = band + half_vote * max_angle.sin() + 1.0;
    let ys =
        [-1.0, 1.0].map(|a| [-1.0, 1.0].map(|b| m[1] + a * half_vote * d[1] + b * across * n0[1]));
    let (y0, y1) = ys
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, r), y| {
            (l.min(*y), r.max(*y))
        });
    let (y0, y1) = (
        y0.floor().max(1.0) as i64,
        y1.ceil().min(h as f64 - 2.0) as i64,
    );
    // Columns where |a rx + b ry| <= c at row offset ry.
    let slab = |a: f64, b: f64, c: f64, ry: f64| {
        if a.abs() < 1e-12 {
            if (b * ry).abs() <= c {
                (f64::NEG_INFINITY, f64::INFINITY)
            } else {
                (f64::INFINITY, f64::NEG_INFINITY)
            }
        } else {
            let (l, r) = ((-c - b * ry) / a, (c - b * ry) / a);
            if a > 0.0 { (l, r) } else { (r, l) }
        }
    };
    let nf = [n0[0] as f32, n0[1] as f32];
    // Voters (position relative to m, gradient), then the votes theta by theta.
    let mut voters = Vec::new();
    for y in y0..=y1 {
        let ry = y as f64 - m[1];
        let ((l0, r0), (l1, r1)) = (
            slab(d[0], d[1], half_vote, ry),
            slab(n0[0], n0[1], across, ry),
        );
        let (x0, x1) = (
            (m[0] + l0.max(l1)).ceil().max(1.0),
            (m[0] + r0.min(r1)).floor().min(w as f64 - 2.0),
        );
        for x in x0 as i64..=x1 as i64 {
            let g = grad.along(x, y, nf);
            if g >= p.line.min_gradient {
                voters.push([x as f64 - m[0], ry, f64::from(g)]);
            }
        }
    }
    let mut acc = vec![0.0f64; normals.len() * n_rho];
    let last = (n_rho - 1) as f64;
    for (row, n) in acc.chunks_exact_mut(n_rho).zip(&normals) {
        // Fractional rho bin: f = (r . n + band) / drho.
        let (cx, cy, c0) = (n[0] / drho, n[1] / drho, band / drho);
        for &[rx, ry, g] in &voters {
            let f = rx * cx + ry * cy + c0;
            if (0.0..last).contains(&f) {
                let i = f as usize;
                let t = f - i as f64;
                row[i] += g * (1.0 - t);
                row[i + 1] += g * t;
            }
        }
    }
    // Peak of the accumulator smoothed by [1/2, 1, 1/2] in rho: per unit length, the gradient
    // summed over 1 px across the line, i.e. the mean gradient along it.
    let (mut best, mut bk, mut bi) = (0.0f64, 0usize, 0usize);
    for (k, row) in acc.chunks_exact(n_rho).enumerate() {
        for i in 0..n_rho {
            let v = row[i]
                + 0.5
                    * (if i > 0 { row[i - 1] } else { 0.0 }
                        + row.get(i + 1).copied().unwrap_or(0.0));
            if v > best {
                (best, bk, bi) = (v, k, i);
            }
        }
    }
    let mean = best / (2.0 * half_vote);
    if mean < f64::from(p.min_peak) {
        return not_found(format!(
            "Hough peak's mean gradient {mean:.2} below {} (band {band} px, max angle {} deg)",
            p.min_peak, p.max_angle
        ));
    }
    let n = normals[bk];
    let rho = bi as f64 * drho - band;
    // Refinement in (s, t): s the major axis of the expected line (rows when steep), t across.
    let steep = dv.abs() > du.abs();
    let st = |q: [f64; 2]| if steep { [q[1], q[0]] } else { q };
    // The peak line t = a s + b: through m + rho n, along (n.y, -n.x).
    let (q, dir) = (
        st([m[0] + rho * n[0], m[1] + rho * n[1]]),
        st([n[1], -n[0]]),
    );
    let a = dir[1] / dir[0];
    let b = q[1] - a * q[0];
    let nf = [n[0] as f32, n[1] as f32];
    let (mut a0, mut a1) = (st(e0), st(e1));
    if a0[0] > a1[0] {
        std::mem::swap(&mut a0, &mut a1);
    }
    let span = a1[0] - a0[0];
    let (s0, s1) = (
        (a0[0] + p.line.shrink * span).ceil(),
        (a1[0] - p.line.shrink * span).floor(),
    );
    let searched = (s1 - s0 + 1.0).max(1.0);
    let smax = if steep { h } else { w };
    let mut pts = Vec::new();
    let mut grads = Vec::new();
    // Positions outside the image hold no points (but count as searched).
    for s in s0.max(1.0) as i64..=s1.min(smax as f64 - 2.0) as i64 {
        let t = a * s as f64 + b;
        if let Some((t, g)) = grad.peak(steep, nf, s, t - NEAR, t + NEAR)
            && g >= p.line.min_gradient
        {
            pts.push([s as f64, t]);
            grads.push(g);
        }
    }
    let axis = if steep { "rows" } else { "columns" };
    if (pts.len() as f64) < p.line.min_support * searched {
        return not_found(format!(
            "{} of {searched} {axis} have a gradient above {} within {NEAR} px of the Hough peak line",
            pts.len(),
            p.line.min_gradient
        ));
    }
    // Fit, extend along the fitted line while the gradient holds, fit again.
    EdgePoints {
        steep,
        normal: nf,
        points: pts,
        gradients: grads,
        searched,
    }
    .fit(grad, &p.line)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::image::add_noise;
    use crate::vision::image::tests::step;

    const W: usize = 640;
    const H: usize = 480;

    /// Expected endpoints 240 px apart, `off` px across the true line through `p` and `tilt`
    /// degrees off its direction.
    fn expected(angle: f64, p: [f64; 2], off: f64, tilt: f64) -> [[f64; 2]; 2] {
        let (s, c) = (angle + tilt).to_radians().sin_cos();
        let q = [p[0] - off * s, p[1] + off * c];
        [
            [q[0] - 120.0 * c, q[1] - 120.0 * s],
            [q[0] + 120.0 * c, q[1] + 120.0 * s],
        ]
    }

    #[test]
    fn synthetic_edges_are_found_to_a_fraction_of_a_pixel() {
        for (angle, p, seed) in [
            (80.0, [300.3, 240.0], 1),
            (-86.5, [200.7, 200.0], 2),
            (7.0, [320.0, 250.4], 3),
            (-30.0, [320.0, 240.2], 4),
            (90.0, [410.6, 260.0], 5),
            (0.0, [330.0, 120.3], 6),
        ] {
            let mut g = step(angle, p, |_| true);
            add_noise(&mut g, 5.0, seed);
            let grad = Gradient::sobel(W, H, &g);
            // Ground truth independent of the detectors: the generator's line.
            let truth = Line::through(
                p,
                [
                    p[0] + 100.0 * f64::to_radians(angle).cos(),
                    p[1] + 100.0 * f64::to_radians(angle).sin(),
                ],
                W,
                H,
            );
            for (off, tilt) in [(4.0, 1.0), (-4.0, -1.0)] {
                let l = detect_line_hough(
                    &grad,
                    expected(angle, p, off, tilt),
                    &HoughParams::default(),
                )
                .unwrap_or_else(|e| panic!("angle {angle}: {e}"));
                let mut da = l.angle - truth.angle;
                if da > 90.0 {
                    da -= 180.0;
                } else if da < -90.0 {
                    da += 180.0;
                }
                let dist = [l.p0, l.p1].map(|q| truth.distance(q, W, H).abs());
                println!(
                    "angle {angle} expected {off} px {tilt} deg off: d_angle {da:.4} deg, endpoint distances {dist:?} px, {} points, rms {:.3}",
                    l.points, l.rms
                );
                assert!(da.abs() < 0.2, "angle {angle}: error {da} deg ({l:?})");
                assert!(l.distance(p, W, H).abs() < 0.5, "angle {angle}: {l:?}");
                assert!(
                    dist.iter().all(|e| *e < 0.5),
                    "angle {angle}: endpoints {dist:?} px off the true line"
                );
                // The extension reaches beyond the shrunken expected span.
                assert!(
                    (l.p1[0] - l.p0[0]).hypot(l.p1[1] - l.p0[1]) > 0.6 * 240.0,
                    "{l:?}"
                );
            }
        }
    }

    #[test]
    fn flat_noise_is_feature_not_found() {
        let mut g = vec![100.0f32; W * H];
        add_noise(&mut g, 5.0, 9);
        let grad = Gradient::sobel(W, H, &g);
        let r = detect_line_hough(
            &grad,
            [[300.0, 100.0], [310.0, 380.0]],
            &HoughParams {
                line: LineParams {
                    band: 40.0,
                    ..LineParams::default()
                },
                ..HoughParams::default()
            },
        );
        assert!(
            matches!(&r, Err(VisionError::FeatureNotFound(why)) if why.contains("peak")),
            "{r:?}"
        );
    }

    #[test]
    fn an_edge_along_too_little_of_the_expected_span_is_feature_not_found() {
        // A strong edge over 50 px of the 144 px voting span: the peak is clear, its support is not.
        let (angle, p) = (12.0, [320.0, 240.0]);
        let mut g = step(angle, p, |a| (-25.0..25.0).contains(&a));
        add_noise(&mut g, 5.0, 10);
        let grad = Gradient::sobel(W, H, &g);
        let r = detect_line_hough(&grad, expected(angle, p, 3.0, 0.5), &HoughParams::default());
        assert!(
            matches!(&r, Err(VisionError::FeatureNotFound(why)) if why.contains("have a gradient")),
            "{r:?}"
        );
        // The same edge along the whole span is found.
        let mut g = step(angle, p, |_| true);
        add_noise(&mut g, 5.0, 10);
        let grad = Gradient::sobel(W, H, &g);
        let l = detect_line_hough(&grad, expected(angle, p, 3.0, 0.5), &HoughParams::default())
            .expect("edge found");
        assert!(l.distance(p, W, H).abs() < 0.5, "{l:?}");
    }

    #[test]
    fn the_stronger_of_two_edges_in_the_band_wins_and_bad_input_is_refused() {
        // Two parallel steps 8 px apart (40 | 90 | 190): the stronger (90 -> 190) is found.
        let (angle, p) = (-60.0, [330.0, 230.0]);
        let (s, c) = f64::to_radians(angle).sin_cos();
        let strong = [p[0] - 8.0 * s, p[1] + 8.0 * c];
        let g: Vec<f32> = step(angle, p, |_| true)
            .iter()
            .zip(step(angle, strong, |_| true))
            .map(|(a, b)| 40.0 + (a - 40.0) / 3.0 + (b - 40.0) * 2.0 / 3.0)
            .collect();
        let grad = Gradient::sobel(W, H, &g);
        let l = detect_line_hough(&grad, expected(angle, p, 4.0, 0.0), &HoughParams::default())
            .expect("edge found");
        assert!(l.distance(strong, W, H).abs() < 0.5, "{l:?}");
        for (e, params) in [
            ([[10.0, 10.0], [12.0, 11.0]], HoughParams::default()),
            ([[f64::NAN, 10.0], [200.0, 11.0]], HoughParams::default()),
            (
                [[10.0, 10.0], [200.0, 11.0]],
                HoughParams {
                    line: LineParams {
                        band: 0.0,
                        ..LineParams::default()
                    },
                    ..HoughParams::default()
                },
            ),
            (
                [[10.0, 10.0], [200.0, 11.0]],
                HoughParams {
                    line: LineParams {
                        shrink: 0.5,
                        ..LineParams::default()
                    },
                    ..HoughParams::default()
                },
            ),
            (
                [[10.0, 10.0], [200.0, 11.0]],
                HoughParams {
                    resolution: f64::NAN,
                    ..HoughParams::default()
                },
            ),
            (
                [[10.0, 10.0], [200.0, 11.0]],
                HoughParams {
                    max_angle: 45.0,
                    ..HoughParams::default()
                },
            ),
            (
                [[f64::INFINITY, 10.0], [200.0, 11.0]],
                HoughParams::default(),
            ),
            // Far beyond the image (a projection near the camera plane): refused quickly, no huge Hough space.
            (
                [[-1e12, 40.0], [1e12, 45.0]],
                HoughParams {
                    line: LineParams {
                        band: 1e9,
                        ..LineParams::default()
                    },
                    ..HoughParams::default()
                },
            ),
        ] {
            let r = detect_line_hough(&grad, e, &params);
            assert!(
                matches!(r, Err(VisionError::FeatureNotFound(_))),
                "{e:?} {params:?}: {r:?}"
            );
        }
    }
}
