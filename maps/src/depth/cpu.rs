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
        // Shifts of one row offset share B's rows: batch them so that the sliding maxima of
        // B's rows are computed once per batch.
        let mut order: Vec<usize> = (0..shifts.len()).collect();
        order.sort_by_key(|&k| (shifts[k].dv, shifts[k].du));
        let batches: Vec<&[usize]> = order
            .chunk_by(|&x, &y| shifts[x].dv == shifts[y].dv)
            .flat_map(|g| g.chunks(BATCH))
            .collect();
        let mut done: Vec<(usize, ContactSummary)> = batches
            .par_iter()
            .flat_map_iter(|batch| {
                let maxima = RowMaxima::new(a, b, &rows.solid, shifts[batch[0]].dv);
                let mut scratch = Vec::new();
                batch
                    .iter()
                    .map(|&k| {
                        (
                            k,
                            summarize(a, b, &rows, &maxima, shifts[k], tolerance, &mut scratch),
                        )
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        done.sort_unstable_by_key(|(k, _)| *k);
        Ok(done.into_iter().map(|(_, summary)| summary).collect())
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

/// Shifts per batch that share the sliding maxima of B's rows.
const BATCH: usize = 128;

/// For one row offset of B against A: per solid row of A, the maximum of B's row over
/// every window of the run's length (indexed by the window's first B column). Then the
/// minimal gap of that row under a shift is the run's height minus one lookup; floats
/// keep it exact, since h - b decreases monotonically in b.
struct RowMaxima {
    /// All rows' maxima, one after the other.
    values: Vec<f32>,
    /// Per A row, the range of `values` holding its maxima (empty when not solid).
    ranges: Vec<std::ops::Range<usize>>,
}

impl RowMaxima {
    fn new(a: &DepthImage, b: &DepthImage, solid: &[Option<Solid>], dv: i64) -> Self {
        let bw = b.window.width;
        let off_row = a.window.j0 - dv - b.window.j0;
        let mut values = Vec::with_capacity(solid.len() * bw);
        let mut prefix = Vec::with_capacity(bw);
        let ranges = solid
            .iter()
            .enumerate()
            .map(|(r, s)| {
                let start = values.len();
                let row = s.and_then(|s| {
                    let br = usize::try_from(r as i64 + off_row)
                        .ok()
                        .filter(|&br| br < b.window.height)?;
                    Some((s.len, &b.height[br * bw..(br + 1) * bw]))
                });
                if let Some((len, row)) = row {
                    sliding_max(row, len, &mut prefix, &mut values);
                }
                start..values.len()
            })
            .collect();
        Self { values, ranges }
    }

    /// The minimal gap of solid row `r` whose run starts at B column `bcol`, if known.
    fn row_min(&self, solid: Option<Solid>, r: usize, bcol: i64) -> Option<f32> {
        let s = solid?;
        let at = usize::try_from(bcol).ok()?;
        self.values[self.ranges[r].clone()]
            .get(at)
            .map(|m| s.height - m)
    }
}

/// Appends to `out`, for every window `x[i..i + len]` inside `x`, its maximum (van Herk /
/// Gil-Werman: running maxima forwards and backwards within blocks of `len`); `prefix`
/// is scratch space.
fn sliding_max(x: &[f32], len: usize, prefix: &mut Vec<f32>, out: &mut Vec<f32>) {
    let n = x.len();
    if len == 0 || len > n {
        return;
    }
    prefix.clear();
    prefix.extend_from_slice(x);
    let base = out.len();
    out.extend_from_slice(x);
    let suffix = &mut out[base..];
    for start in (0..n).step_by(len) {
        let end = (start + len).min(n);
        for i in start + 1..end {
            prefix[i] = prefix[i].max(prefix[i - 1]);
        }
        for i in (start..end - 1).rev() {
            suffix[i] = suffix[i].max(suffix[i + 1]);
        }
    }
    for i in 0..=n - len {
        suffix[i] = suffix[i].max(prefix[i + len - 1]);
    }
    out.truncate(base + n - len + 1);
}

/// What the contact reduction precomputes once per image pair.
struct Rows {
    spans: RowSpans,
    flat: Vec<Option<f32>>,
    solid: Vec<Option<Solid>>,
    normals: Normals,
}

/// The contact summary of one shift; `maxima` serve its solid rows, `scratch` holds the
/// row minima.
fn summarize(
    a: &DepthImage,
    b: &DepthImage,
    rows: &Rows,
    maxima: &RowMaxima,
    s: Shift,
    tol: f32,
    scratch: &mut Vec<(RowPair, f32)>,
) -> ContactSummary {
    let (w, spans, bn) = (a.window.width, &rows.spans, &rows.normals.comp);
    let off_col = a.window.i0 - s.du - b.window.i0;
    let mut gap = f32::INFINITY;
    let row_min = scratch;
    row_min.clear();
    for p in row_pairs(a, b, spans, s) {
        let n = p.c1 - p.c0 + 1;
        let solid = rows.solid[p.r];
        let m = match maxima.row_min(solid, p.r, solid.map_or(-1, |sd| sd.first as i64 + off_col)) {
            Some(m) => m,
            None => min_diff(
                &a.height[p.r * w + p.c0..][..n],
                &b.height[p.brow_start..][..n],
            ),
        };
        gap = gap.min(m);
        row_min.push((p, m));
    }
    let mut out = ContactSummary::none(gap);
    if !gap.is_finite() {
        return out;
    }
    let thr = gap + tol;
    for &(p, m) in row_min.iter() {
        if m > thr {
            continue;
        }
        let n = p.c1 - p.c0 + 1;
        let bs = p.brow_start;
        let (av, bv) = (&a.height[p.r * w + p.c0..][..n], &b.height[bs..bs + n]);
        let nv = [&bn[0][bs..bs + n], &bn[1][bs..bs + n], &bn[2][bs..bs + n]];
        let uniform = (
            rows.flat[p.r],
            rows.normals.row_uniform[bs / b.window.width],
        );
        let r = match uniform {
            (Some(h), Some(normal)) => {
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
    fn sliding_max_equals_the_direct_maximum_of_every_window() {
        let x: Vec<f32> = (0..37)
            .map(|i| ((i * 7919) % 23) as f32 - if i % 5 == 0 { f32::INFINITY } else { 0.0 })
            .collect();
        let mut prefix = Vec::new();
        for len in 1..=x.len() {
            let mut fast = vec![-1.0];
            sliding_max(&x, len, &mut prefix, &mut fast);
            assert_eq!(fast.remove(0), -1.0, "appends after what is there");
            assert_eq!(fast.len(), x.len() - len + 1);
            for (i, m) in fast.iter().enumerate() {
                let direct = x[i..i + len]
                    .iter()
                    .copied()
                    .fold(f32::NEG_INFINITY, f32::max);
                assert_eq!(*m, direct, "window {i}..{} ", i + len);
            }
        }
        let mut none = Vec::new();
        sliding_max(&x, 0, &mut prefix, &mut none);
        sliding_max(&x, 38, &mut prefix, &mut none);
        assert!(none.is_empty());
    }
}
