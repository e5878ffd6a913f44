//! The CPU depth backend, the reference: a scan-converting orthographic z-buffer
//! rasterizer and the shifted-difference contact reduction, parallel with rayon.

use rayon::prelude::*;
use wide::f32x8;

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
                [
                    c[0] / job.pixel - job.window.i0 as f64,
                    c[1] / job.pixel - job.window.j0 as f64,
                    c[2],
                ]
            });
            let area = edge(p[0], p[1], p[2]);
            if area.abs() < 1e-9 {
                continue; // edge-on: invisible along the view
            }
            let xmin = p
                .iter()
                .map(|q| q[0])
                .fold(f64::INFINITY, f64::min)
                .ceil()
                .max(0.0) as i64;
            let xmax = (p
                .iter()
                .map(|q| q[0])
                .fold(f64::NEG_INFINITY, f64::max)
                .floor() as i64)
                .min(w - 1);
            let ymin = p
                .iter()
                .map(|q| q[1])
                .fold(f64::INFINITY, f64::min)
                .ceil()
                .max(0.0) as i64;
            let ymax = (p
                .iter()
                .map(|q| q[1])
                .fold(f64::NEG_INFINITY, f64::max)
                .floor() as i64)
                .min(h - 1);
            let eps = -1e-9 * area.abs();
            for y in ymin..=ymax {
                // Only the pixels about where the row crosses the triangle: a sliver's box
                // (a top face fanned from a hole to its corners) is mostly outside it. A
                // pixel of margin each side; the test below decides as before.
                let Some([xl, xr]) = row_crossing(&p, y as f64) else {
                    continue;
                };
                let x0 = xmin.max(xl.floor() as i64 - 1);
                let x1 = xmax.min(xr.ceil() as i64 + 1);
                for x in x0..=x1 {
                    let q = [x as f64, y as f64, 0.0];
                    let (b0, b1, b2) = (
                        edge(p[1], p[2], q) / area,
                        edge(p[2], p[0], q) / area,
                        edge(p[0], p[1], q) / area,
                    );
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
        let rows = Rows {
            spans: RowSpans::of(a),
            flat: flat_rows(a),
            solid: solid_rows(a),
            normals: Normals::of(b, b_normals),
        };
        // A single shift (a thin region again at the finer pixel) reads each of B's pixels
        // under A once: tables over all of B would cost more than they save.
        let ranges = RowRanges::of(b, if shifts.len() > 1 { &rows.solid } else { &[] });
        Ok(shifts
            .par_iter()
            .map_init(Vec::new, |scratch, &s| {
                summarize(a, b, &rows, &ranges, s, tolerance, scratch)
            })
            .collect())
    }
}

/// Where the line at height `y` crosses the triangle `p` in the image plane: the least and
/// greatest x of its edges' points at that height (`None` where it misses them all).
fn row_crossing(p: &[[f64; 3]; 3], y: f64) -> Option<[f64; 2]> {
    let mut range: Option<[f64; 2]> = None;
    let mut take = |x: f64| {
        range = Some(match range {
            Some([l, r]) => [l.min(x), r.max(x)],
            None => [x, x],
        });
    };
    for k in 0..3 {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        if a[1] == b[1] {
            if a[1] == y {
                take(a[0]);
                take(b[0]);
            }
        } else if (a[1] - y) * (b[1] - y) <= 0.0 {
            take(a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]));
        }
    }
    range
}

/// Twice the signed area of (a, b, c) in the image plane.
fn edge(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Lane width of the vector loops.
const LANES: usize = 8;

/// Per row of A's image, the first and last column with a surface (widened to whole lanes).
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
                    // Widen to whole lanes of 8 where the row allows (the extra pixels are
                    // empty, so they never touch): the lane loops then need no remainder.
                    let c0 = first - first % LANES;
                    let c1 = (c0 + (last - c0 + 1).div_ceil(LANES) * LANES).min(w) - 1;
                    Some((c0, c1))
                })
                .collect(),
        )
    }
}

/// The row of A (r) overlapping B under a shift: A columns c0..=c1 and the B slice start.
#[derive(Clone, Copy)]
struct RowPair {
    r: usize,
    c0: usize,
    c1: usize,
    brow_start: usize,
}

fn row_pairs<'s>(
    a: &'s DepthImage,
    b: &'s DepthImage,
    spans: &'s RowSpans,
    s: Shift,
) -> impl Iterator<Item = RowPair> + 's {
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
        Some(RowPair {
            r,
            c0,
            c1: c1 as usize,
            brow_start: (br as usize) * b.window.width + (c0 as i64 + off_col) as usize,
        })
    })
}

/// Eight lanes of `s` starting at `k`.
fn lanes(s: &[f32], k: usize) -> f32x8 {
    f32x8::from(<[f32; 8]>::try_from(&s[k..k + 8]).expect("8 values"))
}

/// Minimum of `a[k] - b[k]`, eight lanes at a time.
fn min_diff(a: &[f32], b: &[f32]) -> f32 {
    let full = a.len() - a.len() % 8;
    let mut acc = f32x8::splat(f32::INFINITY);
    for k in (0..full).step_by(8) {
        acc = acc.fast_min(lanes(a, k) - lanes(b, k));
    }
    let mut m = acc.to_array().into_iter().fold(f32::INFINITY, f32::min);
    for k in full..a.len() {
        m = m.min(a[k] - b[k]);
    }
    m
}

/// Sums over the contact pixels of one row.
struct RowSums {
    count: f32,
    sum_col: f32,
    sum_height: f32,
    normal: [f32; 3],
    first: f32,
    last: f32,
}

/// Contacts of one row: pixels k with `a[k] - b[k] <= thr`; columns counted from `col0`.
/// Masks are applied bitwise, so empty pixels (infinite heights) never make a NaN.
/// Without `SUMS` the height and normal sums are left 0 (the caller knows them: flat A
/// row, one B normal).
fn row_sums<const SUMS: bool>(
    a: &[f32],
    b: &[f32],
    n: [&[f32]; 3],
    thr: f32,
    col0: f32,
) -> RowSums {
    let full = a.len() - a.len() % 8;
    let (thr8, one, zero) = (f32x8::splat(thr), f32x8::splat(1.0), f32x8::ZERO);
    let (mut cnt, mut sc, mut sh) = (zero, zero, zero);
    let mut sn = [zero; 3];
    let (mut first, mut last) = (f32x8::splat(f32::INFINITY), f32x8::splat(f32::NEG_INFINITY));
    let mut col = f32x8::from([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]) + f32x8::splat(col0);
    for k in (0..full).step_by(8) {
        let av = lanes(a, k);
        let hit = (av - lanes(b, k)).simd_le(thr8);
        cnt += hit & one;
        sc += hit & col;
        if SUMS {
            sh += hit & av;
            for (acc, nn) in sn.iter_mut().zip(&n) {
                *acc += hit & lanes(nn, k);
            }
        }
        first = hit.bitselect(first.fast_min(col), first);
        last = hit.bitselect(last.fast_max(col), last);
        col += f32x8::splat(8.0);
    }
    let mut out = RowSums {
        count: cnt.reduce_add(),
        sum_col: sc.reduce_add(),
        sum_height: sh.reduce_add(),
        normal: sn.map(|v| v.reduce_add()),
        first: first.to_array().into_iter().fold(f32::INFINITY, f32::min),
        last: last
            .to_array()
            .into_iter()
            .fold(f32::NEG_INFINITY, f32::max),
    };
    for k in full..a.len() {
        if a[k] - b[k] <= thr {
            let col = col0 + k as f32;
            out.count += 1.0;
            out.sum_col += col;
            if SUMS {
                out.sum_height += a[k];
                for (o, nn) in out.normal.iter_mut().zip(&n) {
                    *o += nn[k];
                }
            }
            out.first = out.first.min(col);
            out.last = out.last.max(col);
        }
    }
    out
}

/// B's contact normal per pixel, one image per component (zero where B has no surface),
/// and per row the normal shared by all its pixels, if they share one.
struct Normals {
    comp: [Vec<f32>; 3],
    row_uniform: Vec<Option<[f32; 3]>>,
}

impl Normals {
    fn of(b: &DepthImage, bn: &[[f32; 3]]) -> Self {
        let comp = |c: usize| {
            b.tri
                .iter()
                .map(|&t| bn.get(t as usize).map_or(0.0, |n| n[c]))
                .collect()
        };
        let w = b.window.width;
        let row_uniform = (0..b.window.height)
            .map(|r| {
                let mut seen = b.tri[r * w..(r + 1) * w]
                    .iter()
                    .filter_map(|&t| bn.get(t as usize));
                let first = *seen.next().unwrap_or(&[0.0; 3]);
                seen.all(|n| *n == first).then_some(first)
            })
            .collect();
        Self {
            comp: [comp(0), comp(1), comp(2)],
            row_uniform,
        }
    }
}

/// Per row of A's image, its height when all its pixels with a surface share one.
fn flat_rows(a: &DepthImage) -> Vec<Option<f32>> {
    a.height
        .chunks_exact(a.window.width)
        .map(|row| {
            let mut h = row.iter().copied().filter(|h| h.is_finite());
            let first = h.next().unwrap_or(0.0);
            h.all(|x| x == first).then_some(first)
        })
        .collect()
}

/// A row of A whose surface is one unbroken run at one height.
#[derive(Clone, Copy)]
struct Solid {
    height: f32,
    first: usize,
    len: usize,
}

/// Per row of A's image, its run when it is [`Solid`].
fn solid_rows(a: &DepthImage) -> Vec<Option<Solid>> {
    a.height
        .chunks_exact(a.window.width)
        .map(|row| {
            let first = row.iter().position(|h| h.is_finite())?;
            let last = row.iter().rposition(|h| h.is_finite())?;
            let run = &row[first..=last];
            run.iter().all(|&h| h == run[0]).then_some(Solid {
                height: run[0],
                first,
                len: run.len(),
            })
        })
        .collect()
}

/// The greatest and least height of B's rows over windows of any length, in two lookups
/// (sparse tables: per power of two 2^k, the maximum and minimum of every window of that
/// length; a window is covered by its two overlapping power-of-two windows). A solid row
/// of A under a shift has its minimal gap at the run's height minus the window's maximum
/// (exact in floats: h - b decreases monotonically in b), and every pixel of the run in
/// contact where the run's height minus the window's minimum is within the threshold.
struct RowRanges<'b> {
    /// B's width.
    width: usize,
    /// B's heights: the level of windows of one pixel.
    heights: &'b [f32],
    /// Level k >= 1 at k - 1: per row, at column c, the maximum and the minimum of columns
    /// c..c + 2^k.
    levels: Vec<[Vec<f32>; 2]>,
}

impl<'b> RowRanges<'b> {
    /// The tables of `b` up to the longest run of `solid`.
    fn of(b: &'b DepthImage, solid: &[Option<Solid>]) -> Self {
        let width = b.window.width;
        let longest = solid.iter().flatten().map(|s| s.len).max().unwrap_or(0);
        let mut ranges = Self {
            width,
            heights: &b.height,
            levels: Vec::new(),
        };
        let mut span = 1;
        while 2 * span <= longest.min(width) {
            let [hi, lo] = ranges.level(ranges.levels.len());
            let next = |prev: &[f32], pick: fn(f32, f32) -> f32| -> Vec<f32> {
                let mut out = Vec::with_capacity(prev.len());
                for row in prev.chunks_exact(width) {
                    let (head, tail) = row.split_at(width - span);
                    out.extend(head.iter().zip(&row[span..]).map(|(&x, &y)| pick(x, y)));
                    out.extend_from_slice(tail);
                }
                out
            };
            let level = [next(hi, f32::max), next(lo, f32::min)];
            ranges.levels.push(level);
            span *= 2;
        }
        ranges
    }

    /// Level `k`'s maxima and minima.
    fn level(&self, k: usize) -> [&[f32]; 2] {
        match k.checked_sub(1) {
            None => [self.heights, self.heights],
            Some(i) => [&self.levels[i][0], &self.levels[i][1]],
        }
    }

    /// The maximum and minimum of B's row `r` over columns `c..c + len` (`len` >= 1 within
    /// the tables' lengths, the window inside the row).
    fn window(&self, r: usize, c: usize, len: usize) -> [f32; 2] {
        let k = len.ilog2() as usize;
        let [hi, lo] = self.level(k);
        let (i, j) = (r * self.width + c, r * self.width + c + len - (1 << k));
        [hi[i].max(hi[j]), lo[i].min(lo[j])]
    }

    /// The maximum and minimum of B's row `br` under solid run `s` starting at B column
    /// `bcol`, where the run lies wholly within the row and the tables reach its length.
    fn under(&self, s: Solid, br: usize, bcol: i64) -> Option<[f32; 2]> {
        let c = usize::try_from(bcol).ok()?;
        (c + s.len <= self.width && s.len.ilog2() as usize <= self.levels.len())
            .then(|| self.window(br, c, s.len))
    }
}

/// What the contact reduction precomputes once per image pair.
struct Rows {
    spans: RowSpans,
    flat: Vec<Option<f32>>,
    solid: Vec<Option<Solid>>,
    normals: Normals,
}

/// A row of A against B under one shift.
#[derive(Clone, Copy)]
struct RowGap {
    pair: RowPair,
    /// The row's least gap.
    min: f32,
    /// For a solid row whose run lies within B's row, the greatest gap over the run: every
    /// pixel of the run touches where that is within the threshold.
    max: Option<f32>,
}

/// The contact summary of one shift; `ranges` serve its solid rows, `scratch` holds the
/// rows' gaps.
fn summarize(
    a: &DepthImage,
    b: &DepthImage,
    rows: &Rows,
    ranges: &RowRanges<'_>,
    s: Shift,
    tol: f32,
    scratch: &mut Vec<RowGap>,
) -> ContactSummary {
    let (w, bw, spans, bn) = (
        a.window.width,
        b.window.width,
        &rows.spans,
        &rows.normals.comp,
    );
    let off_col = a.window.i0 - s.du - b.window.i0;
    let mut gap = f32::INFINITY;
    let gaps = scratch;
    gaps.clear();
    for pair in row_pairs(a, b, spans, s) {
        let n = pair.c1 - pair.c0 + 1;
        let solid = rows.solid[pair.r];
        let window = solid.and_then(|sd| {
            let [hi, lo] = ranges.under(sd, pair.brow_start / bw, sd.first as i64 + off_col)?;
            Some([sd.height - hi, sd.height - lo])
        });
        let (min, max) = match window {
            Some([min, max]) => (min, Some(max)),
            None => (
                min_diff(
                    &a.height[pair.r * w + pair.c0..][..n],
                    &b.height[pair.brow_start..][..n],
                ),
                None,
            ),
        };
        gap = gap.min(min);
        gaps.push(RowGap { pair, min, max });
    }
    let mut out = ContactSummary::none(gap);
    if !gap.is_finite() {
        return out;
    }
    let thr = gap + tol;
    for &RowGap { pair: p, min, max } in gaps.iter() {
        if min > thr {
            continue;
        }
        let n = p.c1 - p.c0 + 1;
        let bs = p.brow_start;
        let (av, bv) = (&a.height[p.r * w + p.c0..][..n], &b.height[bs..bs + n]);
        let nv = [&bn[0][bs..bs + n], &bn[1][bs..bs + n], &bn[2][bs..bs + n]];
        let uniform = (rows.flat[p.r], rows.normals.row_uniform[bs / bw]);
        let r = match (uniform, rows.solid[p.r]) {
            ((Some(h), Some(normal)), Some(sd)) if max.is_some_and(|m| m <= thr) => {
                // The whole run touches: its sums in closed form (whole numbers, exact in
                // f32 as the lanes' sums are).
                let (first, count) = (sd.first as f32, sd.len as f32);
                let last = first + count - 1.0;
                RowSums {
                    count,
                    sum_col: (0.5 * f64::from(count) * f64::from(first + last)) as f32,
                    sum_height: count * h,
                    normal: normal.map(|c| c * count),
                    first,
                    last,
                }
            }
            ((Some(h), Some(normal)), _) => {
                let mut r = row_sums::<false>(av, bv, nv, thr, p.c0 as f32);
                r.sum_height = r.count * h;
                r.normal = normal.map(|c| c * r.count);
                r
            }
            _ => row_sums::<true>(av, bv, nv, thr, p.c0 as f32),
        };
        if r.count == 0.0 {
            continue;
        }
        out.count += r.count as u32;
        out.sum_col += f64::from(r.sum_col);
        out.sum_row += f64::from(r.count) * p.r as f64;
        out.sum_height += f64::from(r.sum_height);
        for (acc, v) in out.sum_normal.iter_mut().zip(r.normal) {
            *acc += f64::from(v);
        }
        out.rows.push((p.r as u32, r.first as u32, r.last as u32));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::depth::PixelWindow;

    #[test]
    fn a_row_crossing_holds_every_point_of_the_triangle_on_that_row() {
        // Slivers, vertices on the row, horizontal edges: every point on row y that is inside
        // (all three edge functions of one sign) lies within the crossing.
        let triangles = [
            [[0.0, 0.0, 0.0], [100.0, 3.0, 0.0], [0.5, 80.0, 0.0]],
            [[2.0, 5.0, 0.0], [90.0, 5.0, 0.0], [40.0, 5.7, 0.0]],
            [[10.0, 10.0, 0.0], [10.0, 30.0, 0.0], [10.3, 20.0, 0.0]],
            [[0.25, 0.0, 0.0], [7.75, 0.0, 0.0], [4.0, 6.0, 0.0]],
        ];
        for p in &triangles {
            let area = edge(p[0], p[1], p[2]);
            let (lo, hi) = (
                p.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min),
                p.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max),
            );
            for k in 0..=200 {
                let y = lo + (hi - lo) * f64::from(k) / 200.0;
                let [l, r] = row_crossing(p, y).expect("a row within the triangle's height");
                for i in 0..=2000 {
                    let q = [-1.0 + 102.0 * f64::from(i) / 2000.0, y, 0.0];
                    let e = [
                        edge(p[1], p[2], q),
                        edge(p[2], p[0], q),
                        edge(p[0], p[1], q),
                    ];
                    if e.iter().all(|v| v * area.signum() >= 0.0) {
                        assert!(
                            l - 1e-9 <= q[0] && q[0] <= r + 1e-9,
                            "{p:?} y {y}: {q:?} outside [{l}, {r}]"
                        );
                    }
                }
            }
            assert_eq!(row_crossing(p, hi + 0.5), None);
        }
    }

    #[test]
    fn a_shift_reduced_alone_equals_the_same_shift_among_many() {
        // A: a flat disc (solid rows, the sparse tables' case); B: a bumpy slope with a hole
        // and two triangles' normals. One shift alone reads B's rows directly, many through
        // the tables: the summaries must agree exactly.
        let (w, r) = (24usize, 6i64);
        let window = |i0: i64, width: usize| PixelWindow {
            i0,
            j0: i0,
            width,
            height: width,
        };
        let mut a = DepthImage::empty(window(0, w), 1.0, Surface::Bottom);
        for (k, (h, t)) in a.height.iter_mut().zip(&mut a.tri).enumerate() {
            let (x, y) = ((k % w) as f64 - 11.5, (k / w) as f64 - 11.5);
            if x.hypot(y) < 10.0 {
                (*h, *t) = (0.0, 0);
            }
        }
        let bw = w + 2 * r as usize;
        let mut b = DepthImage::empty(window(-r, bw), 1.0, Surface::Top);
        for (k, (h, t)) in b.height.iter_mut().zip(&mut b.tri).enumerate() {
            let (x, y) = ((k % bw) as f64 - 17.5, (k / bw) as f64 - 17.5);
            if x.hypot(y) > 6.0 {
                // A slope with bumps; rows above the middle share one triangle's normal.
                *h = (-1e-3 * (0.3 * x + 0.2 * y) - 1e-4 * ((k * 7919) % 5) as f64) as f32;
                *t = u32::from(y > 0.0 || x > 0.0);
            }
        }
        let normals = [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]];
        let shifts: Vec<Shift> = (-r..=r)
            .flat_map(|dv| (-r..=r).map(move |du| Shift { du, dv }))
            .collect();
        let many = CpuBackend
            .contacts(&a, &b, &normals, &shifts, 2e-3)
            .expect("many shifts");
        let disc = a.height.iter().filter(|h| h.is_finite()).count() as u32;
        assert!(
            many.iter().any(|c| c.count > 0 && c.count < disc),
            "some shift touches in part"
        );
        for (s, want) in shifts.iter().zip(&many) {
            let alone = CpuBackend
                .contacts(&a, &b, &normals, &[*s], 2e-3)
                .expect("one shift");
            assert_eq!(&alone[0], want, "shift {s:?}");
        }
    }

    #[test]
    fn row_ranges_equal_the_direct_maximum_and_minimum_of_every_window() {
        let (width, height) = (37, 3);
        let heights: Vec<f32> = (0..width * height)
            .map(|i| ((i * 7919) % 23) as f32 - if i % 5 == 0 { f32::INFINITY } else { 0.0 })
            .collect();
        let mut b = DepthImage::empty(
            PixelWindow {
                i0: 0,
                j0: 0,
                width,
                height,
            },
            1.0,
            Surface::Top,
        );
        b.height = heights.clone();
        let solid = [Some(Solid {
            height: 0.0,
            first: 0,
            len: width,
        })];
        let ranges = RowRanges::of(&b, &solid);
        for r in 0..height {
            let row = &heights[r * width..(r + 1) * width];
            for len in 1..=width {
                for c in 0..=width - len {
                    let w = &row[c..c + len];
                    let direct = [
                        w.iter().copied().fold(f32::NEG_INFINITY, f32::max),
                        w.iter().copied().fold(f32::INFINITY, f32::min),
                    ];
                    assert_eq!(
                        ranges.window(r, c, len),
                        direct,
                        "row {r}, {c}..{}",
                        c + len
                    );
                }
            }
        }
        let run = |len| Solid {
            height: 0.0,
            first: 0,
            len,
        };
        assert_eq!(ranges.under(run(10), 0, 28), None, "past the row's end");
        assert_eq!(ranges.under(run(10), 0, -1), None, "before its start");
        assert!(ranges.under(run(10), 0, 27).is_some());
    }
}
