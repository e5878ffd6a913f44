//! The CPU depth backend, the reference: a scan-converting orthographic z-buffer
//! rasterizer and the shifted-difference contact reduction, parallel with rayon.

use rayon::prelude::*;
use wide::f32x8;

use crate::depth::edge_function as edge;
use crate::depth::{
    ContactSummary, DepthBackend, DepthImage, EDGE_ON, Patch, RenderJob, Shift, Surface,
    edge_thresholds, outline_coverage, pixel_box,
};
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
        let w = job.window.width as i64;
        for t in 0..job.mesh.faces.len() {
            let p = job.corners(t);
            let area = edge(p[0], p[1], p[2]);
            if area.abs() < EDGE_ON {
                continue; // edge-on: invisible along the view
            }
            let Some([xmin, xmax, ymin, ymax]) = pixel_box(&p, job.window.width, job.window.height)
            else {
                continue;
            };
            let least = edge_thresholds(&p);
            for y in ymin..=ymax {
                // Only the pixels about where the row crosses the triangle: a sliver's box
                // (a top face fanned from a hole to its corners) is mostly outside it. A
                // pixel of margin each side; the coverage rule decides.
                let [xl, xr] = row_crossing(&p, y as f64);
                let x0 = xmin.max(xl.floor() as i64 - 1);
                let x1 = xmax.min(xr.ceil() as i64 + 1);
                for x in x0..=x1 {
                    let q = [x as f64, y as f64, 0.0];
                    let e = [
                        edge(p[1], p[2], q),
                        edge(p[2], p[0], q),
                        edge(p[0], p[1], q),
                    ];
                    if (0..3).any(|k| e[k] * area.signum() < least[k]) {
                        continue;
                    }
                    let [b0, b1, b2] = e.map(|v| v / area);
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
        outline_coverage(job, &mut img);
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
        // A single shift reads each of B's pixels under A once: tables and runs over all of
        // B would cost more than they save.
        if let [s] = shifts {
            let whole = WholeRows::of(a, b, b_normals);
            return Ok(vec![contact_in_place(
                a.whole(),
                b.whole(),
                &whole,
                b_normals,
                *s,
                tolerance,
                &mut InPlace::default(),
            )]);
        }
        let rows = Rows {
            spans: RowSpans::of(a),
            whole: WholeRows::of(a, b, b_normals),
            solid: solid_rows(a),
            b_normals,
            runs: Runs::of(b),
        };
        let ranges = RowRanges::of(b, &rows.solid);
        // Each strip fills its own slots of the output.
        let mut out = vec![ContactSummary::none(f32::INFINITY); shifts.len()];
        let mut rest = out.as_mut_slice();
        let mut parts = Vec::new();
        for strip in strips(shifts) {
            let (slots, tail) = rest.split_at_mut(strip.range.len());
            parts.push((strip, slots));
            rest = tail;
        }
        parts.into_par_iter().for_each_init(
            StripGaps::default,
            |gaps, (Strip { range, step }, slots)| {
                let strip = &shifts[range];
                gaps.fill(a, b, &rows, &ranges, strip, step);
                let n = strip.len();
                for (j, (slot, &s)) in slots.iter_mut().zip(strip).enumerate() {
                    *slot = summarize(a, b, &rows, s, tolerance, gaps, n - 1 - j);
                }
            },
        );
        Ok(out)
    }
}

/// Where the line at height `y` crosses the triangle `p` in the image plane: the least and
/// greatest x of its edges' points at that height, or at the triangle's nearest one where
/// `y` lies outside it (just outside, within the pixel box: a row of centres the coverage
/// rule takes in along an edge along the rows, [`pixel_box`]).
fn row_crossing(p: &[[f64; 3]; 3], y: f64) -> [f64; 2] {
    let lo = p.iter().map(|q| q[1]).fold(f64::INFINITY, f64::min);
    let hi = p.iter().map(|q| q[1]).fold(f64::NEG_INFINITY, f64::max);
    let y = y.clamp(lo, hi);
    let mut range = [f64::INFINITY, f64::NEG_INFINITY];
    for k in 0..3 {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        let x = if a[1] == b[1] {
            if a[1] != y {
                continue;
            }
            range = [range[0].min(a[0]), range[1].max(a[0])];
            b[0]
        } else if (a[1] - y) * (b[1] - y) <= 0.0 {
            a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
        } else {
            continue;
        };
        range = [range[0].min(x), range[1].max(x)];
    }
    range
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
                .map(|r| lane_span(&a.height[r * w..(r + 1) * w]))
                .collect(),
        )
    }
}

/// A row's first and last column with a surface, widened to whole lanes of 8 where the row
/// allows (the extra pixels are empty, so they never touch): the lane loops then need no
/// remainder.
fn lane_span(row: &[f32]) -> Option<(usize, usize)> {
    let first = row.iter().position(|h| h.is_finite())?;
    let last = row.iter().rposition(|h| h.is_finite())?;
    let c0 = first - first % LANES;
    let c1 = (c0 + (last - c0 + 1).div_ceil(LANES) * LANES).min(row.len()) - 1;
    Some((c0, c1))
}

/// The row of A (r) overlapping B under a shift: A columns c0..=c1 and the B slice start.
#[derive(Clone, Copy)]
struct RowPair {
    r: usize,
    c0: usize,
    c1: usize,
    brow_start: usize,
}

/// A row's span `c0..=c1` clipped to B's columns (A column + `off_col` is B's column; B
/// `bw` wide): outside B there is nothing to touch.
fn clip(span: Option<(usize, usize)>, off_col: i64, bw: usize) -> Option<(usize, usize)> {
    let (c0, c1) = span?;
    let c0 = c0.max((-off_col).max(0) as usize);
    let c1 = (c1 as i64).min(bw as i64 - 1 - off_col);
    (c1 >= c0 as i64).then_some((c0, c1 as usize))
}

/// Row `r` of A against B under shift `s`, where it overlaps B.
fn row_pair(
    a: &DepthImage,
    b: &DepthImage,
    spans: &RowSpans,
    s: Shift,
    r: usize,
) -> Option<RowPair> {
    let off_col = a.window.i0 - s.du - b.window.i0;
    let br = r as i64 + a.window.j0 - s.dv - b.window.j0;
    if br < 0 || br >= b.window.height as i64 {
        return None;
    }
    let (c0, c1) = clip(spans.0[r], off_col, b.window.width)?;
    Some(RowPair {
        r,
        c0,
        c1,
        brow_start: (br as usize) * b.window.width + (c0 as i64 + off_col) as usize,
    })
}

/// Eight lanes of `s` starting at `k`.
fn lanes(s: &[f32], k: usize) -> f32x8 {
    f32x8::from(<[f32; 8]>::try_from(&s[k..k + 8]).expect("8 values"))
}

/// Minimum of `a[k] - b[k]`, eight lanes at a time.
#[inline(always)]
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

/// B's normal (u, v, w) at a pixel that sees triangle `t` of B's `normals` (zero where it
/// sees none).
fn normal_of(normals: &[[f32; 3]], t: u32) -> [f32; 3] {
    normals.get(t as usize).copied().unwrap_or_default()
}

/// Contacts of one row: pixels k with `a[k] - b[k] <= thr`; columns counted from `col0`.
/// Masks are applied bitwise, so empty pixels (infinite heights) never make a NaN. With
/// `normal` (B's normal at pixel k), the height and normal sums too, over the lanes between
/// the first and the last contact alone (the others add zeros: the same sums); without,
/// they are left 0 (the caller knows them: flat A row, one B normal).
#[inline(always)]
fn row_sums(
    a: &[f32],
    b: &[f32],
    normal: Option<&dyn Fn(usize) -> [f32; 3]>,
    thr: f32,
    col0: f32,
) -> RowSums {
    let full = a.len() - a.len() % 8;
    let (thr8, one, zero) = (f32x8::splat(thr), f32x8::splat(1.0), f32x8::ZERO);
    let hit = |k: usize| (lanes(a, k) - lanes(b, k)).simd_le(thr8);
    let (mut cnt, mut sc) = (zero, zero);
    let (mut first, mut last) = (f32x8::splat(f32::INFINITY), f32x8::splat(f32::NEG_INFINITY));
    let mut col = f32x8::from([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]) + f32x8::splat(col0);
    for k in (0..full).step_by(8) {
        let hit = hit(k);
        cnt += hit & one;
        sc += hit & col;
        first = hit.bitselect(first.fast_min(col), first);
        last = hit.bitselect(last.fast_max(col), last);
        col += f32x8::splat(8.0);
    }
    let mut out = RowSums {
        count: cnt.reduce_add(),
        sum_col: sc.reduce_add(),
        sum_height: 0.0,
        normal: [0.0; 3],
        first: first.to_array().into_iter().fold(f32::INFINITY, f32::min),
        last: last
            .to_array()
            .into_iter()
            .fold(f32::NEG_INFINITY, f32::max),
    };
    if let Some(normal) = normal.filter(|_| out.first.is_finite()) {
        let (k0, k1) = ((out.first - col0) as usize, (out.last - col0) as usize);
        let (mut sh, mut sn) = (zero, [zero; 3]);
        for k in (k0 - k0 % 8..=k1).step_by(8) {
            let (hit, av) = (hit(k), lanes(a, k));
            sh += hit & av;
            let n: [[f32; 3]; 8] = std::array::from_fn(|j| normal(k + j));
            for (c, acc) in sn.iter_mut().enumerate() {
                *acc += hit & f32x8::from(n.map(|v| v[c]));
            }
        }
        out.sum_height = sh.reduce_add();
        out.normal = sn.map(|v| v.reduce_add());
    }
    for k in full..a.len() {
        if a[k] - b[k] <= thr {
            let col = col0 + k as f32;
            out.count += 1.0;
            out.sum_col += col;
            if let Some(normal) = normal {
                out.sum_height += a[k];
                for (o, n) in out.normal.iter_mut().zip(normal(k)) {
                    *o += n;
                }
            }
            out.first = out.first.min(col);
            out.last = out.last.max(col);
        }
    }
    out
}

/// B's rows with at most one run of equal height per this many pixels are summed run by
/// run under a flat, unbroken row of A ([`run_sums`]); busier rows (a tilted face, a
/// chamfer) pixel by pixel.
const PIXELS_PER_RUN: usize = 16;

/// B's rows as runs of equal height: a face across the approach, a hole's floor.
struct Runs {
    /// Per pixel of B, the column of B (exclusive) where its run ends.
    end: Vec<u32>,
    /// Per row of B, whether its runs are few ([`PIXELS_PER_RUN`]).
    few: Vec<bool>,
}

impl Runs {
    /// The runs of `b`'s rows.
    fn of(b: &DepthImage) -> Self {
        let w = b.window.width;
        let mut end = vec![0; b.height.len()];
        let few = (b.height.chunks_exact(w).zip(end.chunks_exact_mut(w)))
            .map(|(row, ends)| {
                let (mut runs, mut e) = (1, w);
                for c in (0..w).rev() {
                    if c + 1 < w && row[c] != row[c + 1] {
                        (runs, e) = (runs + 1, c + 1);
                    }
                    ends[c] = e as u32;
                }
                runs * PIXELS_PER_RUN <= w
            })
            .collect();
        Self { end, few }
    }
}

/// Contacts of a solid row of A at height `h` over B's pixels `b` (`ends`: their runs' ends
/// as B columns, `b[0]` at B column `bcol`): pixels k with `h - b[k] <= thr`, a run at a
/// time; columns counted from `col0`. Without the height and normal sums, as
/// [`row_sums`]`::<false>`, and the same sums (whole numbers, exact in f32).
fn run_sums(h: f32, b: &[f32], ends: &[u32], bcol: usize, thr: f32, col0: usize) -> RowSums {
    let (mut count, mut sum_col) = (0usize, 0usize);
    let (mut first, mut last) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut k = 0;
    while k < b.len() {
        let e = (ends[k] as usize - bcol).min(b.len());
        if h - b[k] <= thr {
            let (c0, c1) = (col0 + k, col0 + e - 1);
            count += e - k;
            sum_col += (c0 + c1) * (e - k) / 2;
            first = first.min(c0 as f32);
            last = c1 as f32;
        }
        k = e;
    }
    RowSums {
        count: count as f32,
        sum_col: sum_col as f32,
        sum_height: 0.0,
        normal: [0.0; 3],
        first,
        last,
    }
}

/// Per row of A's image, its height when all its pixels with a surface share one.
fn flat_rows(a: &DepthImage) -> Vec<Option<f32>> {
    a.height
        .chunks_exact(a.window.width)
        .map(flat_row)
        .collect()
}

/// A row's height when all its pixels with a surface share one.
fn flat_row(row: &[f32]) -> Option<f32> {
    let mut h = row.iter().copied().filter(|h| h.is_finite());
    let first = h.next().unwrap_or(0.0);
    h.all(|x| x == first).then_some(first)
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
/// The tables are stored column by column: shifts along v read a window's maxima for
/// consecutive rows of B from consecutive memory ([`StripGaps`]).
struct RowRanges {
    /// B's width.
    width: usize,
    /// B's height (rows).
    height: usize,
    /// Level k: at `c * height + r`, the maximum and the minimum of row r's columns
    /// c..c + 2^k (level 0: B's heights). Empty when no solid row of A needs them.
    levels: Vec<[Vec<f32>; 2]>,
}

impl RowRanges {
    /// The tables of `b` up to the longest run of `solid`.
    fn of(b: &DepthImage, solid: &[Option<Solid>]) -> Self {
        let (width, height) = (b.window.width, b.window.height);
        let longest = solid.iter().flatten().map(|s| s.len).max().unwrap_or(0);
        let mut ranges = Self {
            width,
            height,
            levels: Vec::new(),
        };
        if longest == 0 {
            return ranges;
        }
        let columns: Vec<f32> = (0..width)
            .flat_map(|c| (0..height).map(move |r| b.height[r * width + c]))
            .collect();
        ranges.levels.push([columns.clone(), columns]);
        let mut span = 1;
        while 2 * span <= longest.min(width) {
            let [hi, lo] = &ranges.levels[ranges.levels.len() - 1];
            let next = |prev: &[f32], pick: fn(f32, f32) -> f32| -> Vec<f32> {
                let column = |c: usize| &prev[c * height..(c + 1) * height];
                let mut out = Vec::with_capacity(prev.len());
                for c in 0..width {
                    if c + span < width {
                        out.extend(
                            column(c)
                                .iter()
                                .zip(column(c + span))
                                .map(|(&x, &y)| pick(x, y)),
                        );
                    } else {
                        out.extend_from_slice(column(c));
                    }
                }
                out
            };
            let level = [next(hi, f32::max), next(lo, f32::min)];
            ranges.levels.push(level);
            span *= 2;
        }
        ranges
    }

    /// Whether the tables hold windows of `len` columns starting at B column `bcol`, and
    /// if so that column.
    fn column(&self, len: usize, bcol: i64) -> Option<usize> {
        let c = usize::try_from(bcol).ok()?;
        (c + len <= self.width && (len.ilog2() as usize) < self.levels.len()).then_some(c)
    }

    /// The maxima and the minima of B's rows `rows` over columns `c..c + len`: per table,
    /// the columns of the two power-of-two windows that cover it (maximum or minimum of
    /// the pair, row by row).
    fn columns(&self, rows: std::ops::Range<usize>, c: usize, len: usize) -> [[&[f32]; 2]; 2] {
        let k = len.ilog2() as usize;
        let (h, d) = (self.height, len - (1 << k));
        let [hi, lo] = self.levels[k].each_ref().map(Vec::as_slice);
        let at = |c: usize| c * h + rows.start..c * h + rows.end;
        [[&hi[at(c)], &hi[at(c + d)]], [&lo[at(c)], &lo[at(c + d)]]]
    }
}

/// What the contact reduction precomputes once per image pair.
struct Rows<'b> {
    spans: RowSpans,
    /// A's flat rows and B's rows of one normal.
    whole: WholeRows,
    solid: Vec<Option<Solid>>,
    /// B's triangle normals.
    b_normals: &'b [[f32; 3]],
    /// B's runs.
    runs: Runs,
}

/// Longest run of shifts that one pass over A's rows serves.
const STRIP: usize = 64;

/// A run of shifts with one du and dv rising by one step (the grid's interval in pixels).
struct Strip {
    /// Where it lies in the list of shifts.
    range: std::ops::Range<usize>,
    /// The step between its shifts' dv (1 for a single shift).
    step: i64,
}

/// The list of shifts as strips, at most [`STRIP`] long, in list order.
fn strips(shifts: &[Shift]) -> Vec<Strip> {
    let mut out = Vec::new();
    let (mut start, mut step) = (0, 1);
    for k in 1..=shifts.len() {
        let rise = k < shifts.len() && shifts[k].du == shifts[k - 1].du;
        let rise = rise.then(|| shifts[k].dv - shifts[k - 1].dv);
        match rise {
            Some(d) if d > 0 && k - start == 1 => step = d,
            Some(d) if d == step && k - start < STRIP => {}
            _ => {
                out.push(Strip {
                    range: start..k,
                    step,
                });
                (start, step) = (k, 1);
            }
        }
    }
    out
}

/// The first pass of the reduction over a [`Strip`]: per row of A and shift, the row's
/// least gap to B (+inf where the row misses B), and per shift the least of them. Shift j
/// of n is numbered t = n - 1 - j, so that a row's shifts run over B's rows upwards; a
/// shift's rows lie together, so that the second pass reads them in order.
#[derive(Default)]
struct StripGaps {
    /// A's height (rows).
    height: usize,
    /// At `t * height + r`: row r's least gap under shift t.
    rows: Vec<f32>,
    /// At `t * height + r`, for a solid row whose run lies within B's row: its greatest
    /// gap (every pixel of the run touches where that is within the threshold); +inf for
    /// other rows.
    whole: Vec<f32>,
    /// Per shift t, the least gap of all rows.
    least: Vec<f32>,
}

impl StripGaps {
    /// The gaps of the strip `strip` (consecutive dv, one du).
    fn fill(
        &mut self,
        a: &DepthImage,
        b: &DepthImage,
        rows: &Rows<'_>,
        ranges: &RowRanges,
        strip: &[Shift],
        step: i64,
    ) {
        let (n, h) = (strip.len(), a.window.height);
        let (w, bw, bh) = (a.window.width, b.window.width, b.window.height as i64);
        self.height = h;
        self.rows.clear();
        self.rows.resize(h * n, f32::INFINITY);
        self.whole.clear();
        self.whole.resize(h * n, f32::INFINITY);
        let (du, top) = (strip[0].du, strip[n - 1].dv);
        let off_col = a.window.i0 - du - b.window.i0;
        for (r, span) in rows.spans.0.iter().enumerate() {
            let Some((c0, c1)) = clip(*span, off_col, bw) else {
                continue;
            };
            // B's row under shift t: `low + t step`, within B for t in t0..t1.
            let low = r as i64 + a.window.j0 - top - b.window.j0;
            let first_in = |edge: i64| (edge - low + step - 1).div_euclid(step);
            let (t0, t1) = (first_in(0).max(0), first_in(bh).min(n as i64));
            if t1 <= t0 {
                continue;
            }
            let (t0, t1) = (t0 as usize, t1 as usize);
            let brow = |t: usize| (low + t as i64 * step) as usize;
            let (brows, every) = (brow(t0)..brow(t1 - 1) + 1, step as usize);
            // Row r under shifts t0..t1.
            let out = self.rows[t0 * h + r..].iter_mut().step_by(h);
            let fast = rows.solid[r]
                .and_then(|sd| Some((sd, ranges.column(sd.len, sd.first as i64 + off_col)?)));
            if let Some((sd, c)) = fast {
                let [[x, y], [p, q]] = ranges.columns(brows, c, sd.len);
                let (x, y) = (x.iter().step_by(every), y.iter().step_by(every));
                for ((o, &x), &y) in out.zip(x).zip(y) {
                    *o = sd.height - x.max(y);
                }
                let whole = self.whole[t0 * h + r..].iter_mut().step_by(h);
                let (p, q) = (p.iter().step_by(every), q.iter().step_by(every));
                for ((o, &p), &q) in whole.zip(p).zip(q) {
                    *o = sd.height - p.min(q);
                }
            } else {
                let len = c1 - c0 + 1;
                let arow = &a.height[r * w + c0..][..len];
                let bcol = (c0 as i64 + off_col) as usize;
                for (o, br) in out.zip(brows.step_by(every)) {
                    *o = min_diff(arow, &b.height[br * bw + bcol..][..len]);
                }
            }
        }
        self.least.clear();
        let least = |g: &[f32]| g.iter().copied().fold(f32::INFINITY, f32::min);
        self.least.extend(self.rows.chunks_exact(h).map(least));
    }
}

/// The contact summary of shift `s`, the strip's shift `t` in `gaps` (its first pass).
fn summarize(
    a: &DepthImage,
    b: &DepthImage,
    rows: &Rows<'_>,
    s: Shift,
    tol: f32,
    gaps: &StripGaps,
    t: usize,
) -> ContactSummary {
    let (w, bw) = (a.window.width, b.window.width);
    let gap = gaps.least[t];
    let mut out = ContactSummary::none(gap);
    if !gap.is_finite() {
        return out;
    }
    let thr = gap + tol;
    let shift_rows = t * gaps.height..(t + 1) * gaps.height;
    let whole = &gaps.whole[shift_rows.clone()];
    let touching = gaps.rows[shift_rows.clone()].iter().filter(|&&g| g <= thr);
    out.rows.reserve_exact(touching.count());
    for (r, &row_gap) in gaps.rows[shift_rows].iter().enumerate() {
        // Rows that miss B have an infinite gap.
        if row_gap > thr {
            continue;
        }
        let Some(p) = row_pair(a, b, &rows.spans, s, r) else {
            continue;
        };
        let n = p.c1 - p.c0 + 1;
        let bs = p.brow_start;
        let (av, bv) = (&a.height[p.r * w + p.c0..][..n], &b.height[bs..bs + n]);
        let normal = |k: usize| normal_of(rows.b_normals, b.tri[bs + k]);
        let brow = bs / bw;
        let uniform = (
            rows.whole.flat[p.r],
            (rows.whole.normals).uniform(rows.b_normals, brow, 0..=bw - 1),
        );
        let r = match (uniform, rows.solid[p.r]) {
            ((Some(h), Some(normal)), Some(sd)) if whole[r] <= thr => {
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
            ((Some(h), Some(normal)), solid) => {
                let runs = rows.runs.few[brow].then_some(&rows.runs);
                let mut r = match (solid, runs) {
                    // The run's pixels within B's row.
                    (Some(sd), Some(runs)) => {
                        let lo = sd.first.max(p.c0);
                        let hi = (sd.first + sd.len).min(p.c1 + 1).max(lo);
                        let at = bs + lo - p.c0..bs + hi - p.c0;
                        let bcol = at.start - brow * bw;
                        let ends = &runs.end[at.clone()];
                        run_sums(h, &b.height[at], ends, bcol, thr, lo)
                    }
                    _ => row_sums(av, bv, None, thr, p.c0 as f32),
                };
                r.sum_height = r.count * h;
                r.normal = normal.map(|c| c * r.count);
                r
            }
            _ => row_sums(av, bv, Some(&normal), thr, p.c0 as f32),
        };
        add_row(&mut out, p.r, &r);
    }
    out
}

/// Adds the sums of A's row `r` to a contact summary (nothing for a row without contact).
fn add_row(out: &mut ContactSummary, r: usize, sums: &RowSums) {
    if sums.count == 0.0 {
        return;
    }
    out.count += sums.count as u32;
    out.sum_col += f64::from(sums.sum_col);
    out.sum_row += f64::from(sums.count) * r as f64;
    out.sum_height += f64::from(sums.sum_height);
    for (acc, v) in out.sum_normal.iter_mut().zip(sums.normal) {
        *acc += f64::from(v);
    }
    out.rows
        .push((r as u32, sums.first as u32, sums.last as u32));
}

/// What holds of whole rows of two images, A's and B's, and so of their rows in any window
/// ([`contact_in_place`]): a row of A flat as a whole is flat, at its height, wherever A has
/// a surface in it; B's pixels in runs of one normal.
pub(crate) struct WholeRows {
    /// Per row of A, its height when all its pixels with a surface share one.
    flat: Vec<Option<f32>>,
    /// B's runs of one normal.
    normals: NormalRuns,
}

impl WholeRows {
    /// The rows of `a` and of `b` (normals `b_normals`).
    pub(crate) fn of(a: &DepthImage, b: &DepthImage, b_normals: &[[f32; 3]]) -> Self {
        Self {
            flat: flat_rows(a),
            normals: NormalRuns::of(b, b_normals),
        }
    }
}

/// B's pixels in runs that share one normal, read from each pixel rightwards: whether the
/// pixels with a surface among any columns of a row share one normal, without a pass over
/// them ([`NormalRuns::uniform`]).
struct NormalRuns {
    width: usize,
    /// Per pixel, the first column at or after it (in its row) whose surface's normal
    /// differs from that of the first pixel with a surface there (the width: none).
    until: Vec<u32>,
    /// Per pixel, the column and the triangle of the first pixel at or after it with a
    /// surface (the width and `u32::MAX`: none).
    first: Vec<[u32; 2]>,
}

impl NormalRuns {
    /// The runs of `b`'s rows (triangle normals `bn`). Neighbouring pixels of one triangle
    /// share its normal; others where the normals compare equal.
    fn of(b: &DepthImage, bn: &[[f32; 3]]) -> Self {
        let w = b.window.width;
        let (mut until, mut first) = (vec![0; b.tri.len()], vec![[0; 2]; b.tri.len()]);
        for (r, tris) in b.tri.chunks_exact(w).enumerate() {
            // The nearest pixel with a surface to the right: its column and triangle.
            let (mut next, mut end): (Option<(usize, u32)>, usize) = (None, w);
            for (c, &t) in tris.iter().enumerate().rev() {
                if let Some(n) = bn.get(t as usize) {
                    let same = next.is_some_and(|(k, tk)| {
                        (tk == t && k == c + 1) || bn.get(tk as usize) == Some(n)
                    });
                    if !same {
                        end = next.map_or(w, |(k, _)| k);
                    }
                    next = Some((c, t));
                }
                until[r * w + c] = end as u32;
                first[r * w + c] = next.map_or([w as u32, u32::MAX], |(k, t)| [k as u32, t]);
            }
        }
        Self {
            width: w,
            until,
            first,
        }
    }

    /// The normal every pixel with a surface shares among columns `cols` of row `r` (normals
    /// `bn`), if they share one ([0, 0, 0] where none has a surface).
    fn uniform(
        &self,
        bn: &[[f32; 3]],
        r: usize,
        cols: std::ops::RangeInclusive<usize>,
    ) -> Option<[f32; 3]> {
        let k = r * self.width + cols.start();
        let [col, t] = self.first[k];
        let seen = (col as usize <= *cols.end()).then_some(t);
        (self.until[k] as usize > *cols.end()).then(|| {
            seen.and_then(|t| bn.get(t as usize))
                .copied()
                .unwrap_or_default()
        })
    }
}

/// What [`contact_in_place`] reuses from one call to the next (one per thread): millions
/// of small regions a map, each of which would otherwise allocate and grow its own.
#[derive(Default)]
pub(crate) struct InPlace {
    /// Each row of A over B: its row, B's row under it and its least gap.
    rows: Vec<(usize, usize, f32)>,
}

/// The contact summary of `a` against `b` (normals `b_normals`) under the one shift `s`,
/// read in place: exactly what [`CpuBackend::contacts`] gives for it, from each row's least
/// gap and then the rows in contact alone (`whole`: what holds of the images' whole rows).
/// A thin contact region computed again at a finer pixel is one such window of the finer
/// images.
pub(crate) fn contact_in_place(
    a: Patch<'_>,
    b: Patch<'_>,
    whole: &WholeRows,
    b_normals: &[[f32; 3]],
    s: Shift,
    tolerance: f32,
    scratch: &mut InPlace,
) -> ContactSummary {
    let (aw, bw) = (a.window(), b.window());
    // A's column c is B's column c + off_col, its row r B's row r + off_row.
    let off_col = aw.i0 - s.du - bw.i0;
    let off_row = aw.j0 - s.dv - bw.j0;
    let bcols = |(c0, c1): (usize, usize)| {
        (c0 as i64 + off_col) as usize..(c1 as i64 + off_col) as usize + 1
    };
    // A's columns over B: outside them nothing touches, and an empty pixel of A never does,
    // so a row's least gap over them is its least over its span.
    let over = (aw.width > 0)
        .then(|| clip(Some((0, aw.width - 1)), off_col, bw.width))
        .flatten();
    // Each row of A over B: its row of B and its least gap.
    let rows = &mut scratch.rows;
    rows.clear();
    if let Some(cols) = over {
        // A's rows over B's.
        let within = |r: i64| r.clamp(0, aw.height as i64) as usize;
        for r in within(-off_row)..within(bw.height as i64 - off_row) {
            let br = (r as i64 + off_row) as usize;
            let gap = min_diff(&a.heights(r)[cols.0..=cols.1], &b.heights(br)[bcols(cols)]);
            rows.push((r, br, gap));
        }
    }
    let gap = rows.iter().fold(f32::INFINITY, |m, &(_, _, g)| m.min(g));
    let mut out = ContactSummary::none(gap);
    if !gap.is_finite() {
        return out;
    }
    let thr = gap + tolerance;
    let touching = || rows.iter().filter(|&&(_, _, g)| g <= thr);
    out.rows.reserve_exact(touching().count());
    for &(r, br, _) in touching() {
        let arow = a.heights(r);
        let Some((c0, c1)) = clip(lane_span(arow), off_col, bw.width) else {
            continue;
        };
        let (av, bv) = (&arow[c0..=c1], &b.heights(br)[bcols((c0, c1))]);
        let tris = b.tris(br);
        // A row in contact has a surface in both images.
        let flat = whole.flat[a.image_row(r)].or_else(|| flat_row(arow));
        let (row, col) = (b.image_row(br), b.image_col());
        let runs = &whole.normals;
        // The whole row's normal first, then the window's: where both share one, the first
        // pixel's of the row, as the coarse reduction takes it.
        let uniform = (runs.uniform(b_normals, row, 0..=runs.width - 1))
            .or_else(|| runs.uniform(b_normals, row, col..=col + bw.width - 1));
        let sums = match (flat, uniform) {
            (Some(h), Some(normal)) => {
                let mut sums = row_sums(av, bv, None, thr, c0 as f32);
                sums.sum_height = sums.count * h;
                sums.normal = normal.map(|c| c * sums.count);
                sums
            }
            _ => {
                let seen = &tris[bcols((c0, c1))];
                row_sums(
                    av,
                    bv,
                    Some(&|k| normal_of(b_normals, seen[k])),
                    thr,
                    c0 as f32,
                )
            }
        };
        add_row(&mut out, r, &sums);
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
                let [l, r] = row_crossing(p, y);
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
            // Beyond the triangle's rows: its nearest row's crossing.
            assert_eq!(row_crossing(p, hi + 0.5), row_crossing(p, hi));
        }
    }

    #[test]
    fn shifts_reduced_in_strips_equal_each_shift_reduced_alone() {
        // A: a flat disc (solid rows, the sparse tables' case); B: a bumpy slope with a hole
        // and two triangles' normals. One shift alone reads B's rows directly; many read
        // the tables, in strips of dv rising by a step (one shift per strip where the list
        // runs along u, up to `STRIP` where it runs along v, and split beyond): the
        // summaries must agree exactly.
        let (w, r, reach) = (24usize, 6i64, 40i64);
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
        let bw = w + 2 * reach as usize;
        let middle = 0.5 * (bw - 1) as f64;
        let mut b = DepthImage::empty(window(-reach, bw), 1.0, Surface::Top);
        for (k, (h, t)) in b.height.iter_mut().zip(&mut b.tri).enumerate() {
            let (x, y) = ((k % bw) as f64 - middle, (k / bw) as f64 - middle);
            if x.hypot(y) > 6.0 {
                // A slope with bumps; rows above the middle share one triangle's normal.
                *h = (-1e-3 * (0.05 * x + 0.2 * y) - 1e-4 * ((k * 7919) % 5) as f64) as f32;
                *t = u32::from(y > 0.0 || x > 0.0);
            }
        }
        let normals = [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]];
        let along_u = (-r..=r).flat_map(|dv| (-r..=r).map(move |du| Shift { du, dv }));
        let along_v = [-reach, -r, 0, 3, reach]
            .into_iter()
            .flat_map(|du| (-reach..=reach).map(move |dv| Shift { du, dv }));
        // A grid twice and three times the pixel: strips whose dv rises by 2 and 3.
        let coarser = [(1, 2), (-2, 3)].into_iter().flat_map(|(du, step)| {
            (-reach..=reach)
                .step_by(step)
                .map(move |dv| Shift { du, dv })
        });
        let shifts: Vec<Shift> = along_u.chain(along_v).chain(coarser).collect();
        let strips: Vec<(usize, i64)> = strips(&shifts)
            .iter()
            .map(|s| (s.range.len(), s.step))
            .collect();
        for strip in [(1, 1), (STRIP, 1), (17, 1), (41, 2), (27, 3)] {
            assert!(strips.contains(&strip), "{strip:?} among {strips:?}");
        }
        let many = CpuBackend
            .contacts(&a, &b, &normals, &shifts, 2e-3)
            .expect("many shifts");
        let disc = a.height.iter().filter(|h| h.is_finite()).count() as u32;
        assert!(
            many.iter().any(|c| c.count > 0 && c.count < disc),
            "some shift touches in part"
        );
        // Whole rows in contact (their sums in closed form): a row's first and last contact
        // at its run's ends.
        let run = |row: usize| {
            let h = &a.height[row * w..(row + 1) * w];
            (
                h.iter().position(|h| h.is_finite()),
                h.iter().rposition(|h| h.is_finite()),
            )
        };
        assert!(
            many.iter()
                .flat_map(|c| &c.rows)
                .any(|&(row, first, last)| {
                    run(row as usize) == (Some(first as usize), Some(last as usize))
                }),
            "some row touches all along"
        );
        for (s, want) in shifts.iter().zip(&many) {
            let alone = CpuBackend
                .contacts(&a, &b, &normals, &[*s], 2e-3)
                .expect("one shift");
            assert_eq!(&alone[0], want, "shift {s:?}");
        }
    }

    #[test]
    fn a_window_read_in_place_equals_images_made_over_that_window_alone() {
        // Heights and triangles as functions of the lattice position (as a render gives
        // them): A a tilted-or-flat bottom with a notch, B a slope whose rows see one, two or
        // three triangles. Windows of the large images read in place must reduce exactly as
        // images made over those windows alone do by the many shifts' tables, though a
        // row's facts (flat, one normal) differ between the large image's row and the
        // window's.
        let a_at = |i: i64, j: i64| -> Option<f32> {
            let (x, y) = (i as f32, j as f32);
            match (j.rem_euclid(3), x.hypot(y) < 14.0, i == 4 && j > 0) {
                (_, false, _) | (_, _, true) => None,
                (0, true, _) => Some(1e-6 * x),
                _ => Some(0.0),
            }
        };
        let b_at = |i: i64, j: i64| -> Option<(f32, u32)> {
            let (x, y) = (i as f32, j as f32);
            let tri = match j.rem_euclid(4) {
                0 => 0,
                1 => u32::from(i > 7),
                2 => u32::from(i > -9) + u32::from(i > 11),
                _ => 1,
            };
            let h = -2e-6 * x - 1e-6 * y - 3e-6 * ((i * j).rem_euclid(3)) as f32;
            (x.hypot(y) > 3.0).then_some((h, tri))
        };
        let image = |window: PixelWindow, surface: Surface| {
            let mut img = DepthImage::empty(window, 1.0, surface);
            for r in 0..window.height {
                for c in 0..window.width {
                    let (i, j) = (window.i0 + c as i64, window.j0 + r as i64);
                    let k = r * window.width + c;
                    let value = match surface {
                        Surface::Bottom => a_at(i, j).map(|h| (h, 0)),
                        Surface::Top => b_at(i, j),
                    };
                    if let Some((h, t)) = value {
                        (img.height[k], img.tri[k]) = (h, t);
                    }
                }
            }
            img
        };
        let window = |i0: i64, j0: i64, width: usize, height: usize| PixelWindow {
            i0,
            j0,
            width,
            height,
        };
        let (big_a, big_b) = (
            image(window(-20, -20, 48, 40), Surface::Bottom),
            image(window(-40, -40, 90, 80), Surface::Top),
        );
        let normals = [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8]];
        let whole = WholeRows::of(&big_a, &big_b, &normals);
        let mut touched = 0;
        for (a_win, s) in [
            (window(-20, -20, 48, 40), Shift { du: 0, dv: 0 }),
            (window(-10, -6, 16, 12), Shift { du: 3, dv: -2 }),
            (window(0, 2, 24, 9), Shift { du: -7, dv: 5 }),
            (window(-15, -15, 8, 30), Shift { du: 12, dv: 11 }),
        ] {
            // B's window: under A's at the shift, and wider.
            let b_win = window(
                a_win.i0 - s.du - 3,
                a_win.j0 - s.dv - 2,
                a_win.width + 5,
                a_win.height + 4,
            );
            let in_place = contact_in_place(
                big_a.patch(a_win),
                big_b.patch(b_win),
                &whole,
                &normals,
                s,
                1e-4,
                &mut InPlace::default(),
            );
            // Through the tables of many shifts: the reduction that does not read in place.
            let next = Shift { du: s.du + 1, ..s };
            let alone = CpuBackend
                .contacts(
                    &image(a_win, Surface::Bottom),
                    &image(b_win, Surface::Top),
                    &normals,
                    &[s, next],
                    1e-4,
                )
                .expect("two shifts");
            assert_eq!(in_place, alone[0], "window {a_win:?}, shift {s:?}");
            touched += usize::from(in_place.count > 0);
        }
        assert!(touched >= 3, "the windows touch: {touched}");
    }

    /// Numbers below `m` drawn from a linear congruential generator seeded with `seed`.
    fn draws(mut seed: u64) -> impl FnMut(usize) -> usize {
        move |m| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 33) as usize % m
        }
    }

    /// An empty image of B's kind, `width` x `height` pixels at the origin.
    fn top_image(width: usize, height: usize) -> DepthImage {
        let window = PixelWindow {
            i0: 0,
            j0: 0,
            width,
            height,
        };
        DepthImage::empty(window, 1.0, Surface::Top)
    }

    /// The normal shared by every pixel of a row of B that sees the triangles `tris`
    /// (normals `bn`), if they share one ([0, 0, 0] where the row sees none), pixel by
    /// pixel.
    fn uniform_normal(tris: &[u32], bn: &[[f32; 3]]) -> Option<[f32; 3]> {
        let (mut first, mut last) = (None, u32::MAX);
        // A triangle seen again at once has its normal compared already.
        for &t in tris {
            if t == last {
                continue;
            }
            last = t;
            match (bn.get(t as usize), first) {
                (Some(n), None) => first = Some(*n),
                (Some(n), Some(f)) if *n != f => return None,
                _ => {}
            }
        }
        Some(first.unwrap_or([0.0; 3]))
    }

    #[test]
    fn runs_of_one_normal_agree_with_every_windows_pixels() {
        // Triangle normals: two equal, one signed zero apart, one NaN (a degenerate
        // triangle), one other; triangle 9 is none (no surface).
        let up = [0.0, 0.0, 1.0];
        let bn = [
            up,
            up,
            [-0.0, 0.0, 1.0],
            [f32::NAN, 0.0, 1.0],
            [0.6, 0.0, 0.8],
        ];
        let (width, height) = (40, 60);
        let mut b = top_image(width, height);
        let mut next = draws(777);
        for (r, row) in b.tri.chunks_exact_mut(width).enumerate() {
            // Runs of one triangle, each 1 to 6 pixels; rows after the first few draw from
            // fewer triangles, so that some are uniform over long stretches.
            let choices: &[u32] = match r % 4 {
                0 => &[0, 1, 2, 3, 4, 9],
                1 => &[0, 1, 9],
                2 => &[3, 9],
                _ => &[0, 1, 2],
            };
            let mut c = 0;
            while c < width {
                let (len, t) = (1 + next(6), choices[next(choices.len())]);
                row[c..(c + len).min(width)].fill(t);
                c += len;
            }
        }
        let runs = NormalRuns::of(&b, &bn);
        let bits = |n: Option<[f32; 3]>| n.map(|v| v.map(f32::to_bits));
        let (mut uniform, mut mixed, mut windows) = (0, 0, 0);
        for r in 0..height {
            let tris = &b.tri[r * width..(r + 1) * width];
            for c0 in 0..width {
                for c1 in c0..width {
                    let want = uniform_normal(&tris[c0..=c1], &bn);
                    let got = runs.uniform(&bn, r, c0..=c1);
                    assert_eq!(bits(got), bits(want), "row {r} columns {c0}..={c1}");
                    uniform += usize::from(want.is_some() && c1 > c0 + 4);
                    mixed += usize::from(want.is_none());
                    windows += 1;
                }
            }
        }
        // Both kinds, long uniform stretches among them.
        assert!(
            uniform > windows / 20 && mixed > windows / 20,
            "{uniform} long uniform and {mixed} mixed windows of {windows}"
        );
    }

    #[test]
    fn a_row_summed_run_by_run_equals_the_row_summed_pixel_by_pixel() {
        // B's rows: runs of heights drawn from a few levels (one of them empty), each run 1
        // to 40 pixels; row 3 changes height at every pixel. A flat row of A over every
        // window of every row at thresholds between the levels.
        let (width, height) = (120, 4);
        let levels = [f32::NEG_INFINITY, 0.0, 1e-3, 2.5e-3, 4e-3];
        let mut b = top_image(width, height);
        let mut next = draws(12345);
        for row in b.height.chunks_exact_mut(width).take(3) {
            let mut c = 0;
            while c < width {
                let (len, level) = (1 + next(40), levels[next(levels.len())]);
                row[c..(c + len).min(width)].fill(level);
                c += len;
            }
        }
        for (c, h) in b.height[3 * width..].iter_mut().enumerate() {
            *h = 1e-4 * c as f32;
        }
        let runs = Runs::of(&b);
        assert_eq!(runs.few, [true, true, true, false]);
        let h = 5e-3;
        let (mut partial, mut windows) = (0, 0);
        for r in 0..height {
            for thr in [1e-3, 2e-3, 3.5e-3, 6e-3] {
                for start in (0..width).step_by(7) {
                    for len in [1, 5, 8, 23, 64, width - start] {
                        if start + len > width {
                            continue;
                        }
                        let at = r * width + start..r * width + start + len;
                        let (bv, ends) = (&b.height[at.clone()], &runs.end[at]);
                        let by_runs = run_sums(h, bv, ends, start, thr, start + 3);
                        let av = vec![h; len];
                        let by_pixels = row_sums(&av, bv, None, thr, (start + 3) as f32);
                        let sums = |s: &RowSums| (s.count, s.sum_col, s.first, s.last);
                        assert_eq!(
                            sums(&by_runs),
                            sums(&by_pixels),
                            "row {r} {start}+{len} at {thr}"
                        );
                        windows += 1;
                        partial += usize::from(by_runs.count > 0.0 && by_runs.count < len as f32);
                    }
                }
            }
        }
        assert!(
            partial > windows / 8,
            "{partial} of {windows} windows touch in part"
        );
    }

    #[test]
    fn row_ranges_equal_the_direct_maximum_and_minimum_of_every_window() {
        let (width, height) = (37, 3);
        let heights: Vec<f32> = (0..width * height)
            .map(|i| ((i * 7919) % 23) as f32 - if i % 5 == 0 { f32::INFINITY } else { 0.0 })
            .collect();
        let mut b = top_image(width, height);
        b.height = heights.clone();
        let solid = [Some(Solid {
            height: 0.0,
            first: 0,
            len: width,
        })];
        let ranges = RowRanges::of(&b, &solid);
        for len in 1..=width {
            for c in 0..=width - len {
                // Every row at once, as a strip of shifts reads them.
                let [[x, y], [p, q]] = ranges.columns(0..height, c, len);
                for r in 0..height {
                    let w = &heights[r * width + c..r * width + c + len];
                    let direct = [
                        w.iter().copied().fold(f32::NEG_INFINITY, f32::max),
                        w.iter().copied().fold(f32::INFINITY, f32::min),
                    ];
                    assert_eq!(
                        [x[r].max(y[r]), p[r].min(q[r])],
                        direct,
                        "row {r}, {c}..{}",
                        c + len
                    );
                }
            }
        }
        assert_eq!(ranges.column(10, 28), None, "past the row's end");
        assert_eq!(ranges.column(10, -1), None, "before its start");
        assert_eq!(ranges.column(10, 27), Some(27));
        assert_eq!(
            RowRanges::of(&b, &[None]).column(1, 0),
            None,
            "no tables without a solid row"
        );
    }
}
