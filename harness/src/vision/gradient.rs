//! The gradient line detector (the paper's Fig. 5, section III-A): line edge detection from
//! an expected image pose.
//!
//! From the expected endpoints of a CAD edge projected with the calibrated camera: the
//! endpoints are moved toward each other; along the line's major axis (image columns for a
//! rather horizontal line, rows for a steep one) the maximal gradient across the line is
//! taken between them, within a search band (sub-pixel by a parabola through the peak);
//! a least-squares line fit (with outliers beyond 1.5 px dropped and the fit repeated);
//! the point set is extended along the line in both directions until the gradient falls
//! below a threshold; a final fit gives the line and its endpoints. When the gradient along
//! the expected line is too weak, or too few points agree on a line, the result is
//! [`VisionError::FeatureNotFound`], never a guess.

use super::image::{EdgePoints, Gradient, Line, LineParams, VisionError};

/// Detects the line edge expected between `expected[0]` and `expected[1]` (pixel coordinates).
///
/// # Errors
/// [`VisionError::FeatureNotFound`] when the gradient near the expected line is too weak or
/// its maxima do not line up.
pub fn detect_line(
    grad: &Gradient,
    expected: [[f64; 2]; 2],
    p: &LineParams,
) -> Result<Line, VisionError> {
    let [e0, e1] = expected;
    let steep = (e1[1] - e0[1]).abs() > (e1[0] - e0[0]).abs();
    // (s, t): s the major axis (rows when steep), t across.
    let st = |q: [f64; 2]| if steep { [q[1], q[0]] } else { q };
    let (mut a0, mut a1) = (st(e0), st(e1));
    if a0[0] > a1[0] {
        std::mem::swap(&mut a0, &mut a1);
    }
    let len = a1[0] - a0[0];
    if len < 4.0 {
        return Err(VisionError::FeatureNotFound(
            "expected line shorter than 4 px".into(),
        ));
    }
    let slope0 = (a1[1] - a0[1]) / len;
    // Unit normal of the expected line in image coordinates.
    let (du, dv) = (e1[0] - e0[0], e1[1] - e0[1]);
    let norm = du.hypot(dv);
    let n = [(-dv / norm) as f32, (du / norm) as f32];
    // Step 1: move the endpoints toward each other; step 2: maxima per row/column.
    let (s0, s1) = (
        (a0[0] + p.shrink * len).ceil() as i64,
        (a1[0] - p.shrink * len).floor() as i64,
    );
    let searched = (s1 - s0 + 1).max(1) as f64;
    let mut points = Vec::new();
    let mut gradients = Vec::new();
    for s in s0..=s1 {
        let te = a0[1] + slope0 * (s as f64 - a0[0]);
        if let Some((t, g)) = grad.peak(steep, n, s, te - p.band, te + p.band)
            && g >= p.min_gradient
        {
            points.push([s as f64, t]);
            gradients.push(g);
        }
    }
    if (points.len() as f64) < p.min_support * searched {
        return Err(VisionError::FeatureNotFound(format!(
            "{} of {} {} have a gradient above {}",
            points.len(),
            searched,
            if steep { "rows" } else { "columns" },
            p.min_gradient
        )));
    }
    // Steps 3 and 4: fit, extend along the line while the gradient holds, fit again.
    EdgePoints {
        steep,
        normal: n,
        points,
        gradients,
        searched,
    }
    .fit(grad, p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::image::add_noise;
    use crate::vision::image::tests::step;

    #[test]
    fn synthetic_edges_are_found_to_a_fraction_of_a_pixel() {
        for (angle, p, seed) in [
            (80.0, [300.3, 240.0], 1),
            (-86.5, [200.7, 200.0], 2),
            (7.0, [320.0, 250.4], 3),
            (-30.0, [320.0, 240.2], 4),
        ] {
            let mut g = step(angle, p, |_| true);
            add_noise(&mut g, 5.0, seed);
            let grad = Gradient::sobel(640, 480, &g);
            let truth = Line::through(
                p,
                [
                    p[0] + 100.0 * f64::to_radians(angle).cos(),
                    p[1] + 100.0 * f64::to_radians(angle).sin(),
                ],
                640,
                480,
            );
            // Expected: 4 px off across the line and 1 degree off.
            let (s, c) = (angle + 1.0).to_radians().sin_cos();
            let q = [p[0] - 4.0 * s, p[1] + 4.0 * c];
            let e = [
                [q[0] - 120.0 * c, q[1] - 120.0 * s],
                [q[0] + 120.0 * c, q[1] + 120.0 * s],
            ];
            let l = detect_line(&grad, e, &LineParams::default()).expect("edge found");
            let mut da = l.angle - truth.angle;
            if da > 90.0 {
                da -= 180.0;
            } else if da < -90.0 {
                da += 180.0;
            }
            assert!(da.abs() < 0.2, "angle {angle}: error {da}");
            assert!(
                (l.distance(p, 640, 480)).abs() < 0.5,
                "angle {angle}: {l:?}"
            );
            // The extension reaches beyond the shrunken expected span.
            assert!(
                (l.p1[0] - l.p0[0]).hypot(l.p1[1] - l.p0[1]) > 0.6 * 240.0,
                "{l:?}"
            );
        }
    }

    #[test]
    fn flat_noise_is_feature_not_found() {
        let mut g = vec![100.0f32; 640 * 480];
        add_noise(&mut g, 5.0, 9);
        let grad = Gradient::sobel(640, 480, &g);
        let r = detect_line(
            &grad,
            [[300.0, 100.0], [310.0, 380.0]],
            &LineParams {
                band: 40.0,
                ..LineParams::default()
            },
        );
        assert!(matches!(r, Err(VisionError::FeatureNotFound(_))), "{r:?}");
    }
}
