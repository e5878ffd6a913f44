//! The CPU depth backend, the reference: a scan-converting orthographic z-buffer
//! rasterizer and the shifted-difference contact reduction, parallel with rayon.

use rayon::prelude::*;

use crate::depth::{ContactSummary, DepthBackend, DepthImage, RenderJob, Shift, Surface};
use crate::error::Result;

/// The CPU backend.
#[derive(Debug, Clone, Copy, Default)]
pub struct CpuBackend;

impl DepthBackend for CpuBackend {
    fn name(&self) -> String {
        format!("cpu ({} threads)", rayon::current_num_threads())
    }

    fn render(&self, job: &RenderJob<'_>) -> Result<DepthImage> {
        let mut img = DepthImage::empty(job.window, job.pixel, job.surface);
        let (w, h) = (job.window.width as i64, job.window.height as i64);
        for t in 0..job.mesh.faces.len() {
            let p = job.mesh.triangle(t).map(|q| {
                let c = job.view.project(&(job.pose * q));
                [c[0] / job.pixel - job.window.i0 as f64, c[1] / job.pixel - job.window.j0 as f64, c[2]]
            });
            let area = edge(p[0], p[1], p[2]);
            if area.abs() < 1e-9 {
                continue; // edge-on: invisible along the view
            }
            let xmin = p.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min).ceil().max(0.0) as i64;
            let xmax = (p.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max).floor() as i64).min(w - 1);
            let ymin = p.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min).ceil().max(0.0) as i64;
            let ymax = (p.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max).floor() as i64).min(h - 1);
            let eps = -1e-9 * area.abs();
            for y in ymin..=ymax {
                for x in xmin..=xmax {
                    let q = [x as f64, y as f64, 0.0];
                    let (b0, b1, b2) = (edge(p[1], p[2], q) / area, edge(p[2], p[0], q) / area, edge(p[0], p[1], q) / area);
                    if b0 * area.abs() < eps || b1 * area.abs() < eps || b2 * area.abs() < eps {
                        continue;
                    }
                    let z = (b0 * p[0][2] + b1 * p[1][2] + b2 * p[2][2]) as f32;
                    let k = (y * w + x) as usize;
                    let closer = match job.surface {
                        Surface::Top => z > img.height[k],
                        Surface::Bottom => z < img.height[k],
                    };
                    if closer {
                        img.height[k] = z;
                        img.tri[k] = t as u32;
                    }
                }
            }
        }
        Ok(img)
    }

    fn contacts(
        &self,
        a: &DepthImage,
        b: &DepthImage,
        b_normals: &[[f32; 3]],
        shifts: &[Shift],
        tolerance: f32,
    ) -> Result<Vec<ContactSummary>> {
        let spans = RowSpans::of(a);
        Ok(shifts.par_iter().map(|s| summarize(a, b, b_normals, &spans, *s, tolerance)).collect())
    }
}

/// Twice the signed area of (a, b, c) in the image plane.
fn edge(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Per row of A's image, the first and last column with a surface.
struct RowSpans(Vec<Option<(usize, usize)>>);

impl RowSpans {
    fn of(a: &DepthImage) -> Self {
        let w = a.window.width;
        Self(
            (0..a.window.height)
                .map(|r| {
                    let row = &a.height[r * w..(r + 1) * w];
                    let first = row.iter().position(|h| h.is_finite())?;
                    let last = row.iter().rposition(|h| h.is_finite())?;
                    Some((first, last))
                })
                .collect(),
        )
    }
}

/// The row of A (r) overlapping B under a shift: A columns c0..=c1 and the B slice start.
struct RowPair {
    r: usize,
    c0: usize,
    c1: usize,
    brow_start: usize,
}

fn row_pairs<'s>(a: &'s DepthImage, b: &'s DepthImage, spans: &'s RowSpans, s: Shift) -> impl Iterator<Item = RowPair> + 's {
    let off_col = a.window.i0 - s.du - b.window.i0;
    let off_row = a.window.j0 - s.dv - b.window.j0;
    spans.0.iter().enumerate().filter_map(move |(r, span)| {
        let (c0, c1) = (*span)?;
        let br = r as i64 + off_row;
        if br < 0 || br >= b.window.height as i64 {
            return None;
        }
        // Clip to B's columns: outside B there is nothing to touch.
        let c0 = c0.max((-off_col).max(0) as usize);
        let c1 = (c1 as i64).min(b.window.width as i64 - 1 - off_col);
        if c1 < c0 as i64 {
            return None;
        }
        Some(RowPair { r, c0, c1: c1 as usize, brow_start: (br as usize) * b.window.width + (c0 as i64 + off_col) as usize })
    })
}

/// Minimum of `a[k] - b[k]`, written so that it vectorizes.
fn min_diff(a: &[f32], b: &[f32]) -> f32 {
    const L: usize = 8;
    let mut acc = [f32::INFINITY; L];
    let (ac, bc) = (a.chunks_exact(L), b.chunks_exact(L));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for k in 0..L {
            let d = x[k] - y[k];
            acc[k] = if d < acc[k] { d } else { acc[k] };
        }
    }
    let mut m = acc.iter().copied().fold(f32::INFINITY, f32::min);
    for (x, y) in ar.iter().zip(br) {
        m = m.min(x - y);
    }
    m
}

fn summarize(a: &DepthImage, b: &DepthImage, bn: &[[f32; 3]], spans: &RowSpans, s: Shift, tol: f32) -> ContactSummary {
    let w = a.window.width;
    let mut gap = f32::INFINITY;
    let mut row_min = Vec::with_capacity(spans.0.len());
    for p in row_pairs(a, b, spans, s) {
        let n = p.c1 - p.c0 + 1;
        let m = min_diff(&a.height[p.r * w + p.c0..][..n], &b.height[p.brow_start..][..n]);
        gap = gap.min(m);
        row_min.push((p, m));
    }
    let mut out = ContactSummary {
        gap,
        count: 0,
        sum_col: 0.0,
        sum_row: 0.0,
        sum_height: 0.0,
        sum_normal: [0.0; 3],
        rows: Vec::new(),
    };
    if !gap.is_finite() {
        return out;
    }
    let thr = gap + tol;
    for (p, m) in row_min {
        if m > thr {
            continue;
        }
        let (mut first, mut last) = (u32::MAX, 0u32);
        for k in 0..=(p.c1 - p.c0) {
            let (ha, bk) = (a.height[p.r * w + p.c0 + k], p.brow_start + k);
            let hb = b.height[bk];
            if ha - hb > thr {
                continue;
            }
            let c = (p.c0 + k) as u32;
            first = first.min(c);
            last = last.max(c);
            out.count += 1;
            out.sum_col += f64::from(c);
            out.sum_row += p.r as f64;
            out.sum_height += f64::from(ha);
            if let Some(n) = bn.get(b.tri[bk] as usize) {
                for (acc, v) in out.sum_normal.iter_mut().zip(n) {
                    *acc += f64::from(*v);
                }
            }
        }
        if first <= last {
            out.rows.push((p.r as u32, first, last));
        }
    }
    out
}
