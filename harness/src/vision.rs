//! Line edge detection from an expected image pose (the paper's Fig. 5, section III-A), the
//! expected image edges of a task's vision model (experiment D), and the relative features
//! that the FMU compares per particle.
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

use ftmap::vision::{Camera, VisionModel};

/// Why a feature was not detected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VisionError {
    /// No line with enough gradient near the expected pose (e.g. the part is not in view).
    #[error("feature not found: {0}")]
    FeatureNotFound(String),
}

/// Gradient image (Sobel), components in grey levels per pixel (the 3x3 kernels / 8).
#[derive(Debug, Clone)]
pub struct Gradient {
    /// Width (px).
    pub width: usize,
    /// Height (px).
    pub height: usize,
    /// d/du.
    pub gx: Vec<f32>,
    /// d/dv.
    pub gy: Vec<f32>,
}

impl Gradient {
    /// Sobel gradient of a grey image (border pixels get 0).
    pub fn sobel(width: usize, height: usize, g: &[f32]) -> Self {
        let mut gx = vec![0.0f32; width * height];
        let mut gy = vec![0.0f32; width * height];
        for y in 1..height.saturating_sub(1) {
            let (a, b, c) = (
                &g[(y - 1) * width..y * width],
                &g[y * width..(y + 1) * width],
                &g[(y + 1) * width..(y + 2) * width],
            );
            let (ox, oy) = (
                &mut gx[y * width..(y + 1) * width],
                &mut gy[y * width..(y + 1) * width],
            );
            for x in 1..width - 1 {
                ox[x] = ((a[x + 1] + 2.0 * b[x + 1] + c[x + 1])
                    - (a[x - 1] + 2.0 * b[x - 1] + c[x - 1]))
                    * 0.125;
                oy[x] = ((c[x - 1] + 2.0 * c[x] + c[x + 1]) - (a[x - 1] + 2.0 * a[x] + a[x + 1]))
                    * 0.125;
            }
        }
        Self {
            width,
            height,
            gx,
            gy,
        }
    }

    /// Gradient component along the unit normal `n` at an integer pixel (0 outside).
    pub(crate) fn along(&self, x: i64, y: i64, n: [f32; 2]) -> f32 {
        if x < 1 || y < 1 || x >= self.width as i64 - 1 || y >= self.height as i64 - 1 {
            return 0.0;
        }
        let i = y as usize * self.width + x as usize;
        (self.gx[i] * n[0] + self.gy[i] * n[1]).abs()
    }
}

/// Tuning of [`detect_line`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineParams {
    /// Fraction of the expected length by which each endpoint moves toward the other.
    pub shrink: f64,
    /// Half width of the search band across the expected line (px).
    pub band: f64,
    /// Least gradient (grey levels per px) of an edge point.
    pub min_gradient: f32,
    /// Extension stops where the gradient falls below this fraction of the median edge gradient.
    pub stop_ratio: f32,
    /// Least fraction of the searched rows/columns that must hold agreeing edge points.
    pub min_support: f64,
}

impl Default for LineParams {
    fn default() -> Self {
        Self {
            shrink: 0.2,
            band: 12.0,
            min_gradient: 8.0,
            stop_ratio: 0.35,
            min_support: 0.5,
        }
    }
}

/// A detected line: t = slope * s + intercept in the (major, minor) axes of the search.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// Direction angle in the image (degrees, in (-90, 90]: 0 along +u, 90 along +v).
    pub angle: f64,
    /// Signed distance of the line from the image centre (px), along the normal
    /// (-sin angle, cos angle).
    pub offset: f64,
    /// First endpoint (pixel coordinates).
    pub p0: [f64; 2],
    /// Second endpoint.
    pub p1: [f64; 2],
    /// Edge points the final fit used.
    pub points: usize,
    /// RMS distance of those points from the line (px).
    pub rms: f64,
}

impl Line {
    /// The line through two pixel positions, its offset relative to the centre of a
    /// `width` x `height` image.
    pub fn through(p0: [f64; 2], p1: [f64; 2], width: usize, height: usize) -> Self {
        let mut angle = (p1[1] - p0[1]).atan2(p1[0] - p0[0]).to_degrees();
        if angle <= -90.0 {
            angle += 180.0;
        } else if angle > 90.0 {
            angle -= 180.0;
        }
        let (s, c) = angle.to_radians().sin_cos();
        let (cx, cy) = (0.5 * (width as f64 - 1.0), 0.5 * (height as f64 - 1.0));
        let offset = -s * (p0[0] - cx) + c * (p0[1] - cy);
        Self {
            angle,
            offset,
            p0,
            p1,
            points: 0,
            rms: 0.0,
        }
    }

    /// Signed distance of a pixel position from the line, along its normal.
    pub fn distance(&self, p: [f64; 2], width: usize, height: usize) -> f64 {
        let (s, c) = self.angle.to_radians().sin_cos();
        let (cx, cy) = (0.5 * (width as f64 - 1.0), 0.5 * (height as f64 - 1.0));
        -s * (p[0] - cx) + c * (p[1] - cy) - self.offset
    }
}

/// Least-squares t = a s + b over points (s, t); `None` when degenerate.
fn fit(p: &[[f64; 2]]) -> Option<(f64, f64)> {
    let n = p.len() as f64;
    if p.len() < 2 {
        return None;
    }
    let (ms, mt) = (
        p.iter().map(|q| q[0]).sum::<f64>() / n,
        p.iter().map(|q| q[1]).sum::<f64>() / n,
    );
    let sss: f64 = p.iter().map(|q| (q[0] - ms).powi(2)).sum();
    if sss <= 0.0 {
        return None;
    }
    let sst: f64 = p.iter().map(|q| (q[0] - ms) * (q[1] - mt)).sum();
    let a = sst / sss;
    Some((a, mt - a * ms))
}

/// Fit, drop points farther than `tol` from the line, refit (twice).
pub(crate) fn robust_fit(p: &mut Vec<[f64; 2]>, tol: f64) -> Option<(f64, f64)> {
    let mut ab = fit(p)?;
    for _ in 0..2 {
        p.retain(|q| (q[1] - ab.0 * q[0] - ab.1).abs() <= tol);
        ab = fit(p)?;
    }
    Some(ab)
}

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
    let xy = |s: f64, t: f64| if steep { [t, s] } else { [s, t] };
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
    let (smax, tmax) = if steep {
        (grad.height, grad.width)
    } else {
        (grad.width, grad.height)
    };
    let at = |s: i64, t: i64| {
        if steep {
            grad.along(t, s, n)
        } else {
            grad.along(s, t, n)
        }
    };
    // Sub-pixel peak across the line at major coordinate s, searching t in [lo, hi].
    let peak = |s: i64, lo: f64, hi: f64| -> Option<(f64, f32)> {
        let (lo, hi) = (
            lo.ceil().max(1.0) as i64,
            hi.floor().min(tmax as f64 - 2.0) as i64,
        );
        if s < 1 || s >= smax as i64 - 1 || lo > hi {
            return None;
        }
        let (mut best, mut bt) = (0.0f32, lo);
        for t in lo..=hi {
            let g = at(s, t);
            if g > best {
                (best, bt) = (g, t);
            }
        }
        let (gm, gp) = (at(s, bt - 1), at(s, bt + 1));
        let den = gm - 2.0 * best + gp;
        let dt = if den < 0.0 {
            (0.5 * (gm - gp) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        Some((bt as f64 + f64::from(dt), best))
    };
    // Step 1: move the endpoints toward each other; step 2: maxima per row/column.
    let (s0, s1) = (
        (a0[0] + p.shrink * len).ceil() as i64,
        (a1[0] - p.shrink * len).floor() as i64,
    );
    let searched = (s1 - s0 + 1).max(1) as f64;
    let mut pts = Vec::new();
    let mut grads = Vec::new();
    for s in s0..=s1 {
        let te = a0[1] + slope0 * (s as f64 - a0[0]);
        if let Some((t, g)) = peak(s, te - p.band, te + p.band)
            && g >= p.min_gradient
        {
            pts.push([s as f64, t]);
            grads.push(g);
        }
    }
    let not_found = |why: String| Err(VisionError::FeatureNotFound(why));
    if (pts.len() as f64) < p.min_support * searched {
        return not_found(format!(
            "{} of {} {} have a gradient above {}",
            pts.len(),
            searched,
            if steep { "rows" } else { "columns" },
            p.min_gradient
        ));
    }
    let Some((mut a, mut b)) = robust_fit(&mut pts, 1.5) else {
        return not_found("degenerate edge points".into());
    };
    if (pts.len() as f64) < p.min_support * searched {
        return not_found(format!(
            "only {} of {} edge points lie on one line",
            pts.len(),
            searched
        ));
    }
    // Step 3: extend along the provisional line while the gradient holds.
    grads.sort_by(f32::total_cmp);
    let stop = (grads[grads.len() / 2] * p.stop_ratio).max(p.min_gradient);
    let (first, last) = (pts[0][0] as i64, pts[pts.len() - 1][0] as i64);
    for dir in [-1i64, 1] {
        let mut s = if dir < 0 { first - 1 } else { last + 1 };
        while let Some((t, g)) = peak(s, a * s as f64 + b - 1.5, a * s as f64 + b + 1.5) {
            if g < stop {
                break;
            }
            pts.push([s as f64, t]);
            s += dir;
        }
    }
    // Step 4: final fit on the extended set.
    let Some(ab) = robust_fit(&mut pts, 1.5) else {
        return not_found("degenerate edge points".into());
    };
    (a, b) = ab;
    let (sl, sr) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, r), q| {
            (l.min(q[0]), r.max(q[0]))
        });
    let rms = (pts
        .iter()
        .map(|q| (q[1] - a * q[0] - b).powi(2))
        .sum::<f64>()
        / pts.len() as f64)
        .sqrt();
    let mut line = Line::through(
        xy(sl, a * sl + b),
        xy(sr, a * sr + b),
        grad.width,
        grad.height,
    );
    line.points = pts.len();
    line.rms = rms;
    Ok(line)
}

/// A named expected edge: its 3-D endpoints.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeModel {
    /// Name: `active.left`, `active.right`, `passive.left`, `passive.right`.
    pub name: String,
    /// Endpoints in the world frame (m).
    pub ends: [[f64; 3]; 2],
}

impl EdgeModel {
    /// Projected endpoints; `None` when one lies behind the camera.
    pub fn project(&self, cam: &Camera) -> Option<[[f64; 2]; 2]> {
        Some([cam.project(self.ends[0])?, cam.project(self.ends[1])?])
    }

    /// The projected (ground truth or expected) line.
    pub fn line(&self, cam: &Camera) -> Option<Line> {
        let [a, b] = self.project(cam)?;
        Some(Line::through(a, b, cam.width, cam.height))
    }
}

/// The silhouette edges of a vision model's parts seen by `cam`: the active part with the
/// task frame at `tcp`, the passive part with the goal frame at `object` (m).
pub fn model_edges(
    model: &VisionModel,
    cam: &Camera,
    tcp: [f64; 3],
    object: [f64; 3],
) -> Vec<EdgeModel> {
    let mut out = Vec::new();
    for (part, prism, at) in [
        ("active", &model.active, tcp),
        ("passive", &model.passive, object),
    ] {
        if let Some(s) = prism.silhouette(cam, at) {
            out.push(EdgeModel {
                name: format!("{part}.left"),
                ends: s.left,
            });
            out.push(EdgeModel {
                name: format!("{part}.right"),
                ends: s.right,
            });
        }
    }
    out
}

/// The vision model of a task (its `[camera]` and the features of its `[geometry]`) seen by
/// `camera` (MuJoCo's, as rendered) instead of the designed one.
///
/// # Errors
/// When the task has no camera, or parts without vision features.
pub fn task_model(task: &ftmap::Task, camera: Camera) -> crate::error::Result<VisionModel> {
    let model = VisionModel::of_task(task)?.ok_or_else(|| crate::error::HarnessError::Invalid {
        what: "vision",
        reason: format!(
            "task {} has no camera (a [camera] table in its task.toml; bearing_housing has one)",
            task.name
        ),
    })?;
    Ok(VisionModel { camera, ..model })
}

/// One edge: where the model expects it, where it truly is, what was found.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeResult {
    /// Edge name.
    pub name: String,
    /// Expected image line (passive part at its nominal pose, active part at the TCP).
    pub expected: Line,
    /// Ground truth: the edge projected at the true pose.
    pub truth: Line,
    /// Search band used (px).
    pub band: f64,
    /// The detection.
    pub found: Result<Line, VisionError>,
}

/// Column (u) of a line at image row `v`.
pub fn u_at(l: &Line, v: f64) -> f64 {
    let dv = l.p1[1] - l.p0[1];
    if dv.abs() < 1e-12 {
        l.p0[0]
    } else {
        l.p0[0] + (v - l.p0[1]) * (l.p1[0] - l.p0[0]) / dv
    }
}

/// Horizontal image distance (px) from line `a` to line `b` at image row `v`.
pub fn u_distance(a: &Line, b: &Line, v: f64) -> f64 {
    u_at(b, v) - u_at(a, v)
}

/// The relative features of one image (the FMU's `vision.*` inputs), at the camera's
/// reference row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Features {
    /// Distance from the active part's edge to the passive part's edge: left, right (px).
    pub distances: [f64; 2],
    /// Columns of the passive part's left and right edges (px).
    pub passive: [f64; 2],
}

impl Features {
    /// From the detections; `None` unless all four edges were found.
    pub fn of(results: &[EdgeResult], cam: &Camera) -> Option<Self> {
        let v = cam.reference_row();
        let found = |name: &str| results.iter().find(|r| r.name == name)?.found.as_ref().ok();
        let side = |s: &str| {
            Some((
                found(&format!("active.{s}"))?,
                found(&format!("passive.{s}"))?,
            ))
        };
        let ((al, pl), (ar, pr)) = (side("left")?, side("right")?);
        Some(Self {
            distances: [u_distance(al, pl, v), u_distance(ar, pr, v)],
            passive: [u_at(pl, v), u_at(pr, v)],
        })
    }
}

/// Which line detector finds the edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Detector {
    /// Gradient maxima per row or column, fitted and extended (the paper's Fig. 5).
    #[default]
    Gradient,
    /// The bounded Hough transform restricted to the expected area, then the same refinement.
    Hough,
}

impl Detector {
    /// Detects the line expected between `ends` within `band` px.
    ///
    /// # Errors
    /// [`VisionError::FeatureNotFound`] as the detector decides.
    pub fn detect(
        self,
        grad: &Gradient,
        ends: [[f64; 2]; 2],
        band: f64,
    ) -> Result<Line, VisionError> {
        match self {
            Self::Gradient => detect_line(
                grad,
                ends,
                &LineParams {
                    band,
                    ..LineParams::default()
                },
            ),
            Self::Hough => crate::hough::detect_line_hough(
                grad,
                ends,
                &crate::hough::HoughParams {
                    band,
                    ..crate::hough::HoughParams::default()
                },
            ),
        }
    }
}

/// Detects a vision model's four edges in a grey image. The active part's pose (`tcp`) is
/// known to the robot; the passive part is expected at the nominal goal and may lie anywhere
/// within `size_trans` (m) in x and y, so its search band covers that; `object` is the true
/// pose, used only for the ground truth lines.
pub fn detect_edges(
    gray: &[f32],
    cam: &Camera,
    model: &VisionModel,
    tcp: [f64; 3],
    object: [f64; 3],
    size_trans: f64,
    detector: Detector,
) -> Vec<EdgeResult> {
    let grad = Gradient::sobel(cam.width, cam.height, gray);
    detect_edges_in(&grad, cam, model, tcp, object, size_trans, detector)
}

/// As [`detect_edges`], on a gradient image.
pub fn detect_edges_in(
    grad: &Gradient,
    cam: &Camera,
    model: &VisionModel,
    tcp: [f64; 3],
    object: [f64; 3],
    size_trans: f64,
    detector: Detector,
) -> Vec<EdgeResult> {
    let expected = model_edges(model, cam, tcp, [0.0; 3]);
    let truth = model_edges(model, cam, tcp, object);
    let s = size_trans;
    let shifted: Vec<Vec<EdgeModel>> = [[s, s, 0.0], [s, -s, 0.0], [-s, s, 0.0], [-s, -s, 0.0]]
        .iter()
        .map(|o| model_edges(model, cam, tcp, *o))
        .collect();
    expected
        .iter()
        .zip(&truth)
        .filter_map(|(e, t)| {
            let ends = e.project(cam)?;
            let (el, tl) = (e.line(cam)?, t.line(cam)?);
            let band = if e.name.starts_with("passive") {
                let far = shifted
                    .iter()
                    .filter_map(|v| v.iter().find(|m| m.name == e.name)?.line(cam))
                    .map(|l| {
                        ends.iter()
                            .map(|p| l.distance(*p, cam.width, cam.height).abs())
                            .fold(0.0, f64::max)
                    })
                    .fold(0.0, f64::max);
                far + 6.0
            } else {
                LineParams::default().band
            };
            Some(EdgeResult {
                name: e.name.clone(),
                expected: el,
                truth: tl,
                band,
                found: detector.detect(grad, ends, band),
            })
        })
        .collect()
}

/// Adds Gaussian noise of `sigma` grey levels (seeded), clamped to 0..255.
pub fn add_noise(gray: &mut [f32], sigma: f64, seed: u64) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    for g in gray.iter_mut() {
        let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
        let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
        *g = (f64::from(*g) + sigma * z).clamp(0.0, 255.0) as f32;
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A 640x480 image of a straight step edge (grey 40 | 190) through `p` at `angle` degrees,
    /// anti-aliased by 4x4 supersampling; only where `keep` holds for the position along the
    /// edge (px from `p`), elsewhere grey 40.
    pub(crate) fn step(angle: f64, p: [f64; 2], keep: impl Fn(f64) -> bool) -> Vec<f32> {
        let (s, c) = angle.to_radians().sin_cos();
        let (w, h) = (640, 480);
        let mut g = vec![0.0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut cov = 0.0;
                for k in 0..16 {
                    let (sx, sy) = (
                        x as f64 - 0.375 + 0.25 * f64::from(k % 4),
                        y as f64 - 0.375 + 0.25 * f64::from(k / 4),
                    );
                    if -s * (sx - p[0]) + c * (sy - p[1]) > 0.0
                        && keep(c * (sx - p[0]) + s * (sy - p[1]))
                    {
                        cov += 1.0 / 16.0;
                    }
                }
                g[y * w + x] = (40.0 + 150.0 * cov) as f32;
            }
        }
        g
    }

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
