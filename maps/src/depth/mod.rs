//! Orthographic depth images along the approach vector (the paper's z-buffer method) and
//! the backend trait that renders them and reduces their shifted differences to contacts.

use nalgebra::{Isometry3, Point3, Vector3};

use crate::error::Result;
use crate::mesh::{Mesh, NO_NEIGHBOUR};

pub mod cpu;
#[cfg(feature = "gpu")]
pub mod gpu;
pub(crate) mod region;

/// Height value of a pixel where A has no surface (never in contact).
pub const EMPTY_A: f32 = f32::INFINITY;
/// Height value of a pixel where B has no surface (nothing to rest on).
pub const EMPTY_B: f32 = f32::NEG_INFINITY;

/// An orthonormal frame whose w axis points against the approach vector: images are
/// taken in (u, v), heights along w.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Image x axis.
    pub u: Vector3<f64>,
    /// Image y axis.
    pub v: Vector3<f64>,
    /// Height axis, -a.
    pub w: Vector3<f64>,
}

impl View {
    /// The view for approach vector `a` (any length > 0): w = -a, u chosen from x (or y
    /// when a is near x), v = w x u.
    pub fn along(a: Vector3<f64>) -> Self {
        let w = -a.normalize();
        let seed = if w.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = (seed - w * seed.dot(&w)).normalize();
        let v = w.cross(&u);
        Self { u, v, w }
    }

    /// (u, v, w) coordinates of a point.
    pub fn project(&self, p: &Point3<f64>) -> [f64; 3] {
        [
            p.coords.dot(&self.u),
            p.coords.dot(&self.v),
            p.coords.dot(&self.w),
        ]
    }

    /// The point with view coordinates (u, v, w).
    pub fn unproject(&self, c: [f64; 3]) -> Point3<f64> {
        Point3::from(self.u * c[0] + self.v * c[1] + self.w * c[2])
    }
}

/// Which surface a depth image keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Surface {
    /// The highest point along w (part B seen against the approach).
    Top,
    /// The lowest point along w (part A seen along the approach).
    Bottom,
}

/// A rectangle of the global pixel lattice: pixel (i, j) has its centre at
/// (i * pixel, j * pixel) in view coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelWindow {
    /// Lattice column of the first image column.
    pub i0: i64,
    /// Lattice row of the first image row.
    pub j0: i64,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

impl PixelWindow {
    /// The smallest window holding every pixel centre inside the (u, v) box, grown by `margin` pixels.
    pub fn covering(umin: f64, umax: f64, vmin: f64, vmax: f64, pixel: f64, margin: i64) -> Self {
        let i0 = (umin / pixel).ceil() as i64 - margin;
        let i1 = (umax / pixel).floor() as i64 + margin;
        let j0 = (vmin / pixel).ceil() as i64 - margin;
        let j1 = (vmax / pixel).floor() as i64 + margin;
        Self {
            i0,
            j0,
            width: (i1 - i0 + 1).max(0) as usize,
            height: (j1 - j0 + 1).max(0) as usize,
        }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// True when the window has no pixel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The smallest window holding both.
    pub fn union(&self, other: &Self) -> Self {
        let i0 = self.i0.min(other.i0);
        let j0 = self.j0.min(other.j0);
        let i1 = (self.i0 + self.width as i64).max(other.i0 + other.width as i64);
        let j1 = (self.j0 + self.height as i64).max(other.j0 + other.height as i64);
        Self {
            i0,
            j0,
            width: (i1 - i0) as usize,
            height: (j1 - j0) as usize,
        }
    }
}

/// What to render: a mesh at a pose, seen in a view, over a window.
#[derive(Debug, Clone, Copy)]
pub struct RenderJob<'a> {
    /// The mesh in its own frame.
    pub mesh: &'a Mesh,
    /// Pose of the mesh's frame in the task frame.
    pub pose: Isometry3<f64>,
    /// The view frame (in task-frame coordinates).
    pub view: View,
    /// Which surface to keep.
    pub surface: Surface,
    /// The pixel window.
    pub window: PixelWindow,
    /// Pixel size (m).
    pub pixel: f64,
}

impl RenderJob<'_> {
    /// The corners of triangle `t` in window pixel coordinates, with their heights (m).
    pub fn corners(&self, t: usize) -> [[f64; 3]; 3] {
        self.mesh.triangle(t).map(|q| {
            let c = self.view.project(&(self.pose * q));
            [
                c[0] / self.pixel - self.window.i0 as f64,
                c[1] / self.pixel - self.window.j0 as f64,
                c[2],
            ]
        })
    }
}

/// How near (pixels) outside a triangle's edge a pixel centre still counts as on it: far
/// above either backend's rounding (f64 on the CPU; f32 relative to a lattice point by the
/// triangle on the GPU, about 1e-7 of its size), far below any feature a mesh resolves (0.1
/// µm at a 0.1 mm pixel).
pub const ON_EDGE_PX: f64 = 1e-3;

/// How far (m) the height of a pixel centre counted on a triangle's edge from outside may
/// stray from the edge's, by the triangle's slope: on steep triangles (a wall seen nearly
/// edge-on) the tolerance shrinks below [`ON_EDGE_PX`] to keep it.
pub const ON_EDGE_HEIGHT: f64 = 1e-8;

/// The coverage rule both backends share, for the triangle `p` in window pixel coordinates
/// (either winding) and heights (m), within its box ([`pixel_box`]): per edge `k` (from
/// corner `k + 1` to corner `k + 2`), the least value of its edge function
/// `(p[k+2] - p[k+1]) x (q - p[k+1])`, signed positive inside, at which the pixel centre `q`
/// is covered: inside the triangle, on its edges, or within [`ON_EDGE_PX`] of them (less
/// on a steep triangle: [`ON_EDGE_HEIGHT`]). A centre on an edge is then covered by both
/// backends alike, whatever their rounding (the box, [`pixel_box`], is computed once in
/// f64 for both), and counts as on the edge ([`outline_coverage`]).
pub fn edge_thresholds(p: &[[f64; 3]; 3]) -> [f64; 3] {
    let area = edge_function(p[0], p[1], p[2]);
    let d = |k: usize, c: usize| p[k][c] - p[0][c];
    // The height's gradient per pixel, along u and along v.
    let slope = ((d(1, 2) * d(2, 1) - d(2, 2) * d(1, 1)) / area)
        .hypot((d(1, 0) * d(2, 2) - d(2, 0) * d(1, 2)) / area);
    let near = ON_EDGE_PX.min(ON_EDGE_HEIGHT / slope);
    std::array::from_fn(|k| {
        let (a, b) = (p[(k + 1) % 3], p[(k + 2) % 3]);
        -near * (b[0] - a[0]).hypot(b[1] - a[1])
    })
}

/// The pixel centres (first and last column, first and last row) within the bounding box
/// of the triangle `p` (window pixel coordinates) grown by [`ON_EDGE_PX`], clipped to a
/// window `width` x `height`; `None` where none is. Grown, so that a centre on an edge
/// along the rows or columns is covered up to rounding, as one on a slanted edge is.
pub fn pixel_box(p: &[[f64; 3]; 3], width: usize, height: usize) -> Option<[i64; 4]> {
    let range = |c: usize, size: usize| {
        let lo = p.iter().map(|q| q[c]).fold(f64::INFINITY, f64::min);
        let hi = p.iter().map(|q| q[c]).fold(f64::NEG_INFINITY, f64::max);
        (
            (lo - ON_EDGE_PX).ceil().max(0.0) as i64,
            ((hi + ON_EDGE_PX).floor() as i64).min(size as i64 - 1),
        )
    };
    let ((x0, x1), (y0, y1)) = (range(0, width), range(1, height));
    (x0 <= x1 && y0 <= y1).then_some([x0, x1, y0, y1])
}

/// Writes into `img` ([`DepthImage::coverage`]), per pixel whose centre lies on the outline
/// of the surface it sees (on an edge of the
/// triangle seen there, within the coverage rule's distance, whose neighbour across it is
/// not seen from the same side: a wall edge-on, or a face turned away), the share of the
/// pixel that surface covers: 1/2 on an edge; at a corner, the angle of the triangles seen
/// about it between its two outline edges, over a turn. Sorted by pixel index. Every other
/// pixel with a surface counts whole. So a strip whose edges lie on pixel centres (round
/// dimensions on a lattice of round pixels), which the coverage rule samples a pixel
/// wider, counts as wide as it is. Open and non-manifold edges, and those beside a sliver
/// that closes a T-junction, are not outlines.
pub fn outline_coverage(job: &RenderJob<'_>, img: &mut DepthImage) {
    let (width, height) = (job.window.width as i64, job.window.height as i64);
    let fan = Fan::of(job);
    // The pixels whose centre lies on an outline edge of the triangle seen there.
    let mut on = std::collections::BTreeMap::new();
    for (t, p) in fan.corners.iter().enumerate() {
        if !fan.seen(t) {
            continue;
        }
        for k in (0..3).filter(|&k| fan.outline(t, k)) {
            let (a, b) = (p[(k + 1) % 3], p[(k + 2) % 3]);
            // The centres within a thousandth of a pixel of the edge's line: at most one per
            // step along its longer axis.
            let along = usize::from((b[1] - a[1]).abs() > (b[0] - a[0]).abs());
            let (lo, hi) = (a[along].min(b[along]), a[along].max(b[along]));
            let slope = (b[1 - along] - a[1 - along]) / (b[along] - a[along]);
            for x in (lo - ON_EDGE_PX).ceil() as i64..=(hi + ON_EDGE_PX).floor() as i64 {
                let y = (a[1 - along] + (x as f64 - a[along]) * slope).round() as i64;
                let (i, j) = if along == 0 { (x, y) } else { (y, x) };
                if i < 0 || j < 0 || i >= width || j >= height {
                    continue;
                }
                let idx = (j * width + i) as usize;
                if img.tri[idx] as usize == t && fan.on_edge(t, k, [i as f64, j as f64, 0.0]) {
                    on.insert(idx as u32, t);
                }
            }
        }
    }
    img.coverage = on
        .into_iter()
        .map(|(idx, t)| {
            let q = [
                (idx as i64 % width) as f64,
                (idx as i64 / width) as f64,
                0.0,
            ];
            let edges: Vec<usize> = (0..3).filter(|&k| fan.on_edge(t, k, q)).collect();
            let share = match edges[..] {
                // On two edges: at the corner they share, the one neither of them faces.
                [k1, k2] => fan.angle(t, 3 - k1 - k2) / std::f64::consts::TAU,
                _ => 0.5,
            };
            (idx, share as f32)
        })
        .collect();
    let list = &img.coverage;
    img.coverage_rows = (0..=height as usize)
        .map(|r| list.partition_point(|&(i, _)| (i as usize) < r * width as usize) as u32)
        .collect();
}

/// A mesh's triangles as a render job sees them, for [`outline_coverage`].
struct Fan<'a> {
    mesh: &'a Mesh,
    /// Each triangle's corners in window pixels, with their heights.
    corners: Vec<[[f64; 3]; 3]>,
}

impl<'a> Fan<'a> {
    fn of(job: &RenderJob<'a>) -> Self {
        Self {
            mesh: job.mesh,
            corners: (0..job.mesh.faces.len()).map(|t| job.corners(t)).collect(),
        }
    }

    /// Twice triangle `t`'s signed area in the image.
    fn area(&self, t: usize) -> f64 {
        let p = &self.corners[t];
        edge_function(p[0], p[1], p[2])
    }

    /// Whether triangle `t` is rendered (not edge-on).
    fn seen(&self, t: usize) -> bool {
        self.area(t).abs() >= EDGE_ON
    }

    /// The triangle across edge `k` of `t` when it continues `t`'s surface as seen (same
    /// side up; a sliver closing a T-junction continues it, and is continued); `Some(None)`
    /// at an outline, `None` at an open or non-manifold edge.
    fn next(&self, t: usize, k: usize) -> Option<Option<usize>> {
        let n = self.mesh.across[t][k];
        if n == NO_NEIGHBOUR {
            return None;
        }
        let n = n as usize;
        let continues = self.mesh.is_sliver(n)
            || (self.seen(n)
                && (self.mesh.is_sliver(t) || self.area(n).signum() == self.area(t).signum()));
        Some(continues.then_some(n))
    }

    /// Whether edge `k` of triangle `t` is an outline of the surface seen.
    fn outline(&self, t: usize, k: usize) -> bool {
        self.next(t, k) == Some(None)
    }

    /// Whether the pixel centre `q` lies on edge `k` of triangle `t` within the coverage
    /// rule's distance ([`edge_thresholds`]), either side.
    fn on_edge(&self, t: usize, k: usize, q: [f64; 3]) -> bool {
        let p = &self.corners[t];
        edge_function(p[(k + 1) % 3], p[(k + 2) % 3], q).abs() <= -edge_thresholds(p)[k]
    }

    /// The image angle at corner `m` of triangle `t` and of the triangles seen about that
    /// corner across `t`'s edges that are not outlines, out to the outline each way (a
    /// turn where they close round it). A sliver closing a T-junction at its middle corner
    /// adds a half turn: the side of the long triangle across it, which lacks that corner.
    fn angle(&self, t: usize, m: usize) -> f64 {
        let vertex = self.mesh.faces[t][m];
        let at = |t: usize| {
            let p = &self.corners[t];
            let m = self.mesh.faces[t].iter().position(|&v| v == vertex)?;
            let d = |k: usize| [p[k][0] - p[m][0], p[k][1] - p[m][1]];
            let (u, v) = (d((m + 1) % 3), d((m + 2) % 3));
            Some((
                m,
                (u[0] * v[1] - u[1] * v[0])
                    .abs()
                    .atan2(u[0] * v[0] + u[1] * v[1]),
            ))
        };
        let mut total = at(t).map_or(0.0, |(_, a)| a);
        // Each way round: out through the edge from the corner to the next one, then the
        // one to the previous one.
        for first in [(m + 2) % 3, (m + 1) % 3] {
            let (mut tri, mut edge) = (t, first);
            for _ in 0..self.corners.len() {
                let Some(Some(n)) = self.next(tri, edge) else {
                    break;
                };
                if n == t {
                    return std::f64::consts::TAU;
                }
                let Some((mn, a)) = at(n) else { break };
                total += a;
                // Of n's two edges at the corner, the one it did not come in by.
                let [e1, e2] = [(mn + 1) % 3, (mn + 2) % 3];
                let came = self.mesh.across[n][e1] as usize == tri;
                (tri, edge) = (n, if came { e2 } else { e1 });
            }
        }
        total.min(std::f64::consts::TAU)
    }
}

/// Twice the projected area (square pixels) under which a triangle is edge-on: invisible
/// along the view.
pub const EDGE_ON: f64 = 1e-9;

/// Twice the signed area of (a, b, c) in the image plane (u, v).
pub fn edge_function(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// A rendered depth image: a height along w and the triangle that made it, per pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthImage {
    /// Where it lies on the lattice.
    pub window: PixelWindow,
    /// Pixel size (m).
    pub pixel: f64,
    /// Heights along w (m), row-major; [`EMPTY_A`] / [`EMPTY_B`] where no surface.
    pub height: Vec<f32>,
    /// Index of the triangle seen at each pixel; `u32::MAX` where none.
    pub tri: Vec<u32>,
    /// The pixels on the outline of the surface seen and the share of each it covers
    /// ([`outline_coverage`]), by index.
    pub coverage: Vec<(u32, f32)>,
    /// Per image row and one more, where its pixels start in `coverage`.
    pub coverage_rows: Vec<u32>,
}

impl DepthImage {
    /// An image with no surface anywhere.
    pub fn empty(window: PixelWindow, pixel: f64, surface: Surface) -> Self {
        let fill = match surface {
            Surface::Top => EMPTY_B,
            Surface::Bottom => EMPTY_A,
        };
        Self {
            window,
            pixel,
            height: vec![fill; window.len()],
            tri: vec![u32::MAX; window.len()],
            coverage: Vec::new(),
            coverage_rows: vec![0; window.height + 1],
        }
    }

    /// The part of the image within `window`, which it must hold, read in place: the same
    /// pixels a render over `window` gives (a pixel's value depends on its lattice position
    /// alone).
    ///
    /// # Panics
    /// When the image does not hold `window`.
    pub fn patch(&self, window: PixelWindow) -> Patch<'_> {
        let (di, dj) = (window.i0 - self.window.i0, window.j0 - self.window.j0);
        assert!(
            di >= 0
                && dj >= 0
                && di as usize + window.width <= self.window.width
                && dj as usize + window.height <= self.window.height,
            "patch {window:?} outside {:?}",
            self.window
        );
        Patch {
            image: self,
            window,
            start: dj as usize * self.window.width + di as usize,
        }
    }

    /// The whole image as a [`Patch`].
    pub fn whole(&self) -> Patch<'_> {
        self.patch(self.window)
    }

    /// Number of pixels with a surface.
    pub fn covered(&self) -> usize {
        self.height.iter().filter(|h| h.is_finite()).count()
    }
}

/// A window of a [`DepthImage`], read in place ([`DepthImage::patch`]).
#[derive(Debug, Clone, Copy)]
pub struct Patch<'a> {
    image: &'a DepthImage,
    /// Where it lies on the lattice.
    window: PixelWindow,
    /// Index in the image of the window's first pixel.
    start: usize,
}

impl<'a> Patch<'a> {
    /// Where it lies on the lattice.
    pub fn window(&self) -> PixelWindow {
        self.window
    }

    /// The image's row that is row `r` of the window.
    pub fn image_row(&self, r: usize) -> usize {
        self.start / self.image.window.width + r
    }

    /// The image's column that is column 0 of the window.
    pub fn image_col(&self) -> usize {
        self.start % self.image.window.width
    }

    /// Heights of row `r` of the window.
    pub fn heights(&self, r: usize) -> &'a [f32] {
        let k = self.start + r * self.image.window.width;
        &self.image.height[k..k + self.window.width]
    }

    /// Triangles seen along row `r` of the window.
    pub fn tris(&self, r: usize) -> &'a [u32] {
        let k = self.start + r * self.image.window.width;
        &self.image.tri[k..k + self.window.width]
    }

    /// The outline's pixels ([`DepthImage::coverage`]) of the window's rows `rows`, with
    /// those of the image's columns beside the window on them.
    fn outline_rows(&self, rows: std::ops::Range<usize>) -> &'a [(u32, f32)] {
        let first = self.start / self.image.window.width;
        let at = |r: usize| self.image.coverage_rows[first + r] as usize;
        &self.image.coverage[at(rows.start)..at(rows.end)]
    }

    /// The window's row and column of the image's pixel `k`, where it lies in the window.
    fn place(&self, k: u32) -> Option<[usize; 2]> {
        let k = (k as usize).checked_sub(self.start)?;
        let (r, c) = (k / self.image.window.width, k % self.image.window.width);
        (r < self.window.height && c < self.window.width).then_some([r, c])
    }

    /// Calls `f` with the row, column and covered share of each outline pixel of the window
    /// that lies in the span of one of `rows` (row, first and last column, of a window
    /// whose row and column 0 lie at `off` in this one), in that window's rows and columns:
    /// through the outline's list where it is shorter than `rows`, row by row otherwise.
    fn outline_under(
        &self,
        rows: &[(u32, u32, u32)],
        off: [i64; 2],
        mut f: impl FnMut(usize, usize, f32),
    ) {
        let (height, width) = (self.window.height, self.window.width);
        let all = self.outline_rows(0..height);
        let back = |[r, c]: [usize; 2]| {
            let (r, c) = (r as i64 - off[0], c as i64 - off[1]);
            (r >= 0 && c >= 0).then_some([r as usize, c as usize])
        };
        if all.len() <= rows.len() {
            for &(k, share) in all {
                let Some([r, c]) = self.place(k).and_then(back) else {
                    continue;
                };
                let k = rows.partition_point(|&(row, _, _)| (row as usize) < r);
                if rows.get(k).is_some_and(|&(row, first, last)| {
                    row as usize == r && (first as usize..=last as usize).contains(&c)
                }) {
                    f(r, c, share);
                }
            }
            return;
        }
        for &(row, first, last) in rows {
            let pr = i64::from(row) + off[0];
            let (c0, c1) = (i64::from(first) + off[1], i64::from(last) + off[1]);
            if pr < 0 || pr as usize >= height || c1 < 0 || c0 >= width as i64 {
                continue;
            }
            let span = c0.max(0) as usize..=(c1 as usize).min(width - 1);
            let pr = pr as usize;
            for &(k, share) in self.outline_rows(pr..pr + 1) {
                if let Some([_, c]) = self.place(k).filter(|[_, c]| span.contains(c)) {
                    f(row as usize, (c as i64 - off[1]) as usize, share);
                }
            }
        }
    }

    /// The share of the pixel in row `r`, column `c` of the window that its surface covers.
    pub fn coverage(&self, r: usize, c: usize) -> f32 {
        let k = (self.start + r * self.image.window.width + c) as u32;
        let row = self.outline_rows(r..r + 1);
        row.binary_search_by_key(&k, |&(i, _)| i)
            .map_or(1.0, |i| row[i].1)
    }
}

/// Counts each contact pixel of `c` (A's patch `a` on B's patch `b` at shift `s`, contact
/// `tolerance` as the reduction used, B's triangle normals `b_normals`) on the parts'
/// outlines by the share of it both cover (A's times B's, [`outline_coverage`]) instead of
/// whole: its sums lose the rest, [`ContactSummary::deficit`] gains it.
pub fn weigh_outline(
    c: &mut ContactSummary,
    a: Patch<'_>,
    b: Patch<'_>,
    b_normals: &[[f32; 3]],
    s: Shift,
    tolerance: f32,
) {
    if c.rows.is_empty() || (a.image.coverage.is_empty() && b.image.coverage.is_empty()) {
        return;
    }
    let thr = c.gap + tolerance;
    let (aw, bw) = (a.window(), b.window());
    // A's row r, column col is B's row r + off[0], column col + off[1].
    let off = [aw.j0 - s.dv - bw.j0, aw.i0 - s.du - bw.i0];
    debug_assert!(c.rows.is_sorted_by_key(|&(r, _, _)| r));
    let mut lost = ContactSummary::none(c.gap);
    let mut weigh = |r: usize, col: usize, share: f32, of_a: bool| {
        let (br, bc) = (r as i64 + off[0], col as i64 + off[1]);
        if br < 0 || bc < 0 || br as usize >= bw.height || bc as usize >= bw.width {
            return;
        }
        let (br, bc) = (br as usize, bc as usize);
        let both = if of_a {
            share * b.coverage(br, bc)
        } else if a.coverage(r, col) < 1.0 {
            return;
        } else {
            share
        };
        let ha = a.heights(r)[col];
        if ha - b.heights(br)[bc] > thr {
            return;
        }
        let d = f64::from(1.0 - both);
        let normal = b_normals
            .get(b.tris(br)[bc] as usize)
            .copied()
            .unwrap_or_default();
        lost.deficit += d;
        lost.sum_col += d * col as f64;
        lost.sum_row += d * r as f64;
        lost.sum_height += d * f64::from(ha);
        for (acc, n) in lost.sum_normal.iter_mut().zip(normal) {
            *acc += d * f64::from(n);
        }
    };
    // A's outline pixels in its contact rows' spans, then B's there that are not A's.
    a.outline_under(&c.rows, [0, 0], |r, col, share| weigh(r, col, share, true));
    b.outline_under(&c.rows, off, |r, col, share| weigh(r, col, share, false));
    c.deficit += lost.deficit;
    c.sum_col -= lost.sum_col;
    c.sum_row -= lost.sum_row;
    c.sum_height -= lost.sum_height;
    for (acc, n) in c.sum_normal.iter_mut().zip(lost.sum_normal) {
        *acc -= n;
    }
}

/// A translation of B across the view, in whole pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shift {
    /// Columns B moves by (+u).
    pub du: i64,
    /// Rows B moves by (+v).
    pub dv: i64,
}

/// The reduced contact set of one configuration: what the wrench models need, never the
/// contact pixels themselves.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSummary {
    /// Minimal gap hA - hB over the image (m); +inf when A and B never meet.
    pub gap: f32,
    /// Contact pixels (gap within tolerance of the minimum).
    pub count: u32,
    /// Sum of contact pixels' lattice columns relative to A's window (i - i0).
    pub sum_col: f64,
    /// Sum of contact pixels' lattice rows relative to A's window (j - j0).
    pub sum_row: f64,
    /// Sum of A's heights at the contact pixels (m).
    pub sum_height: f64,
    /// Sum of B's unit normals at the contact pixels, in view coordinates (u, v, w).
    pub sum_normal: [f64; 3],
    /// Per image row of A with a contact: (row, first contact column, last contact column).
    pub rows: Vec<(u32, u32, u32)>,
    /// The share of the contact pixels that the parts' outlines leave uncovered
    /// ([`weigh_outline`]), in pixels; the sums above are of the covered shares.
    pub deficit: f64,
}

impl ContactSummary {
    /// No contact pixel, with the minimal gap `gap`.
    pub fn none(gap: f32) -> Self {
        Self {
            gap,
            count: 0,
            sum_col: 0.0,
            sum_row: 0.0,
            sum_height: 0.0,
            sum_normal: [0.0; 3],
            rows: Vec::new(),
            deficit: 0.0,
        }
    }

    /// The contact's area in pixels: its pixels, each counted by the share of it the parts
    /// cover.
    pub fn area(&self) -> f64 {
        f64::from(self.count) - self.deficit
    }

    /// The region's mean width in pixels: twice its pixel count over the perimeter of its
    /// rows' spans, counted in pixel steps (a w x l rectangle along the rows or columns:
    /// w l / (w + l); a disc of radius r: about 0.8 r). Only each row's first and last
    /// pixel are known, so pieces side by side in the same rows count as one of their
    /// rows' extent.
    pub fn mean_width(&self) -> f64 {
        let span = |&(_, first, last): &(u32, u32, u32)| f64::from(last - first + 1);
        let between: f64 = self
            .rows
            .iter()
            .zip(self.rows.iter().skip(1))
            .map(|(p, q)| {
                // The edge between two rows' spans: what one has and the other lacks.
                let shared = if q.0 == p.0 + 1 {
                    (f64::from(p.2.min(q.2)) - f64::from(p.1.max(q.1)) + 1.0).max(0.0)
                } else {
                    0.0
                };
                span(p) + span(q) - 2.0 * shared
            })
            .sum();
        let ends = self.rows.first().map_or(0.0, span) + self.rows.last().map_or(0.0, span);
        let perimeter = between + ends + 2.0 * self.rows.len() as f64;
        if perimeter > 0.0 {
            2.0 * f64::from(self.count) / perimeter
        } else {
            0.0
        }
    }

    /// The region's pixels on an edge across its rows, as a share of its pixel count: those
    /// of rows at most three pixels long, and those not between the spans of the rows just
    /// above and below. A strip up to three pixels wide across the rows, or two along them,
    /// has all of its pixels there (sampled by a pixel more or less at its edges: the
    /// inclusive edge rule puts a strip 2 pixels wide whose edges lie on pixel centres at
    /// 3), a square 10 pixels across a fifth of them, a disc of radius r about 4 / (pi r).
    /// Only each row's first and last pixel are known, so pieces side by side in the same
    /// rows count as one span.
    pub fn edge_share(&self) -> f64 {
        let rows = &self.rows;
        let edge: u64 = (rows.iter().enumerate())
            .map(|(k, &(row, first, last))| {
                let len = u64::from(last - first + 1);
                // The span of the row `k` + `d` of the list where it is the next row.
                let beside = |d: isize| {
                    let &(r, f, l) = rows.get(k.checked_add_signed(d)?)?;
                    (r.abs_diff(row) == 1).then_some((f, l))
                };
                match (beside(-1), beside(1)) {
                    (Some((f0, l0)), Some((f1, l1))) if len > 3 => {
                        let (f, l) = (first.max(f0).max(f1), last.min(l0).min(l1));
                        len - if l >= f { u64::from(l - f + 1) } else { 0 }
                    }
                    _ => len,
                }
            })
            .sum();
        edge as f64 / f64::from(self.count.max(1))
    }
}

/// Renders depth images and reduces shifted image pairs to contact summaries.
pub trait DepthBackend: Sync {
    /// Short name for reports (`cpu`, `gpu:<adapter>`).
    fn name(&self) -> String;

    /// Renders one depth image.
    fn render(&self, job: &RenderJob<'_>) -> Result<DepthImage>;

    /// For each shift of B against A, the contact summary; `b_normals` are B's triangle
    /// normals in view coordinates, `tolerance` the contact tolerance (m). B's window must
    /// hold A's window under every shift.
    fn contacts(
        &self,
        a: &DepthImage,
        b: &DepthImage,
        b_normals: &[[f32; 3]],
        shifts: &[Shift],
        tolerance: f32,
    ) -> Result<Vec<ContactSummary>>;
}

#[cfg(test)]
mod tests {
    use super::ContactSummary;

    /// The summary of the pixels for which `inside(row, col)` holds in a 200 x 200 image.
    fn region(inside: impl Fn(u32, u32) -> bool) -> ContactSummary {
        let mut c = ContactSummary::none(0.0);
        for row in 0..200 {
            let cols: Vec<u32> = (0..200).filter(|&col| inside(row, col)).collect();
            if let (Some(&first), Some(&last)) = (cols.first(), cols.last()) {
                c.count += cols.len() as u32;
                c.rows.push((row, first, last));
            }
        }
        c
    }

    #[test]
    fn the_mean_width_of_rectangles_and_a_disc_is_their_width() {
        // A w x l rectangle: twice w l over its perimeter 2 (w + l).
        let rectangle = |w: f64, l: f64| w * l / (w + l);
        let across = region(|row, col| (50..150).contains(&col) && (20..23).contains(&row));
        let along = region(|row, col| (50..150).contains(&row) && (20..23).contains(&col));
        for strip in [across, along] {
            assert!((strip.mean_width() - rectangle(3.0, 100.0)).abs() < 1e-9);
        }
        // A strip broken in two along its length: as wide as each piece.
        let broken = region(|row, col| {
            (20..22).contains(&col) && [50..90, 110..150].iter().any(|r| r.contains(&row))
        });
        assert!((broken.mean_width() - rectangle(2.0, 40.0)).abs() < 1e-9);
        // A disc: its staircase outline is as long as its bounding square's.
        let r = 40.0;
        let disc = region(|row, col| (f64::from(row) - 100.0).hypot(f64::from(col) - 100.0) < r);
        let expected = std::f64::consts::FRAC_PI_4 * r;
        assert!((disc.mean_width() - expected).abs() < 0.05 * expected);
        assert_eq!(region(|_, _| false).mean_width(), 0.0);
    }

    #[test]
    fn the_edge_share_counts_the_pixels_of_strips_and_of_a_region_s_top_and_bottom_rows() {
        // A square: its top and bottom rows.
        let square = region(|row, col| (50..60).contains(&row) && (50..60).contains(&col));
        assert!((square.edge_share() - 0.2).abs() < 1e-12);
        // Strips three pixels wide across the rows and two along them: all of their pixels.
        let across = region(|row, col| (20..120).contains(&row) && (30..33).contains(&col));
        let along = region(|row, col| (30..32).contains(&row) && (20..120).contains(&col));
        for strip in [across, along] {
            assert!((strip.edge_share() - 1.0).abs() < 1e-12);
        }
        // An L: a strip one row tall (100 pixels, all on the edge) under one 6 pixels wide
        // and 40 rows tall (its top row on the edge).
        let l = region(|row, col| {
            (row == 100 && (50..150).contains(&col))
                || ((60..100).contains(&row) && (50..56).contains(&col))
        });
        assert_eq!(l.count, 340);
        assert!((l.edge_share() - 106.0 / 340.0).abs() < 1e-12);
        // A disc of radius 20: about 4 / (pi r).
        let disc = region(|row, col| (f64::from(row) - 100.0).hypot(f64::from(col) - 100.0) < 20.0);
        let expected = 4.0 / (std::f64::consts::PI * 20.0);
        assert!((disc.edge_share() - expected).abs() < 0.1 * expected);
        assert_eq!(region(|_, _| false).edge_share(), 0.0);
    }
}
