//! Image primitives shared by the line detectors: the Sobel gradient image, the [`Line`]
//! type, the sub-pixel gradient peak across a line, the robust least-squares line fit with
//! its extension along the line, Gaussian image noise, and [`VisionError`].
//!
//! A line search works in (s, t) axes: s the major axis of the expected line (image columns
//! for a rather horizontal line, rows for a steep one), t across it.

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

    /// Sub-pixel maximum of the gradient along `n` at major coordinate `s`, t in [lo, hi]
    /// (a parabola through the peak), with its gradient; `None` outside the image.
    pub(crate) fn peak(
        &self,
        steep: bool,
        n: [f32; 2],
        s: i64,
        lo: f64,
        hi: f64,
    ) -> Option<(f64, f32)> {
        let (smax, tmax) = if steep {
            (self.height, self.width)
        } else {
            (self.width, self.height)
        };
        let at = |t: i64| {
            if steep {
                self.along(t, s, n)
            } else {
                self.along(s, t, n)
            }
        };
        let (lo, hi) = (
            lo.ceil().max(1.0) as i64,
            hi.floor().min(tmax as f64 - 2.0) as i64,
        );
        if s < 1 || s >= smax as i64 - 1 || lo > hi {
            return None;
        }
        let (mut best, mut bt) = (0.0f32, lo);
        for t in lo..=hi {
            let g = at(t);
            if g > best {
                (best, bt) = (g, t);
            }
        }
        let (gm, gp) = (at(bt - 1), at(bt + 1));
        let den = gm - 2.0 * best + gp;
        let dt = if den < 0.0 {
            (0.5 * (gm - gp) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        Some((bt as f64 + f64::from(dt), best))
    }
}

/// A detected line: its direction, its offset from the image centre and its endpoints.
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
fn robust_fit(p: &mut Vec<[f64; 2]>, tol: f64) -> Option<(f64, f64)> {
    let mut ab = fit(p)?;
    for _ in 0..2 {
        p.retain(|q| (q[1] - ab.0 * q[0] - ab.1).abs() <= tol);
        ab = fit(p)?;
    }
    Some(ab)
}

/// Tolerance (px) across a line for its edge points: the outlier distance of the fits and
/// the half width of the search while extending.
pub(crate) const NEAR: f64 = 1.5;

/// Edge points found across an expected line, ready for [`EdgePoints::fit`].
#[derive(Debug, Clone)]
pub(crate) struct EdgePoints {
    /// Whether s runs along image rows (a steep line) rather than columns.
    pub steep: bool,
    /// Unit normal (image axes) along which the gradient is read.
    pub normal: [f32; 2],
    /// Positions (s, t), in increasing s.
    pub points: Vec<[f64; 2]>,
    /// Their gradients.
    pub gradients: Vec<f32>,
    /// Rows or columns searched.
    pub searched: f64,
}

/// The search for a line edge near its expected place, shared by both detectors (the
/// gradient detector and the bounded Hough transform).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineParams {
    /// Fraction of the expected length by which each endpoint moves toward the other.
    pub shrink: f64,
    /// Half width of the search band across the expected line (px): for Hough, the rho range.
    pub band: f64,
    /// Least gradient (grey levels per px) of an edge point (and of a Hough vote).
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

impl EdgePoints {
    /// The line through the edge points: a least-squares fit with outliers beyond [`NEAR`]
    /// dropped, the point set extended along it in both directions while the gradient holds,
    /// and a final fit giving the line and its endpoints.
    ///
    /// # Errors
    /// [`VisionError::FeatureNotFound`] when the points are degenerate or too few lie on one
    /// line.
    pub fn fit(mut self, grad: &Gradient, p: &LineParams) -> Result<Line, VisionError> {
        let not_found = |why: String| Err(VisionError::FeatureNotFound(why));
        let pts = &mut self.points;
        let Some((a, b)) = robust_fit(pts, NEAR) else {
            return not_found("degenerate edge points".into());
        };
        if (pts.len() as f64) < p.min_support * self.searched {
            return not_found(format!(
                "only {} of {} edge points lie on one line",
                pts.len(),
                self.searched
            ));
        }
        // Extend along the provisional line while the gradient holds.
        self.gradients.sort_by(f32::total_cmp);
        let stop = (self.gradients[self.gradients.len() / 2] * p.stop_ratio).max(p.min_gradient);
        let (first, last) = (pts[0][0] as i64, pts[pts.len() - 1][0] as i64);
        for dir in [-1i64, 1] {
            let mut s = if dir < 0 { first - 1 } else { last + 1 };
            while let Some((t, g)) = grad.peak(
                self.steep,
                self.normal,
                s,
                a * s as f64 + b - NEAR,
                a * s as f64 + b + NEAR,
            ) {
                if g < stop {
                    break;
                }
                pts.push([s as f64, t]);
                s += dir;
            }
        }
        // The final fit on the extended set.
        let Some((a, b)) = robust_fit(pts, NEAR) else {
            return not_found("degenerate edge points".into());
        };
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
        let xy = |s: f64, t: f64| if self.steep { [t, s] } else { [s, t] };
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
}
