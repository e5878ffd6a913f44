//! The exact contact region of tilted parts, pixel by pixel: within each pixel's square,
//! the surfaces of A and of B seen about it, as planes within their outlines, clipped
//! against each other and then against the contact tolerance. A region thinner than a
//! pixel (the band a tolerance draws across a tilt, the tip of the lens where two rims
//! cross) then counts by its area wherever the pixel centres fall, and its least gap is
//! the least over the surfaces' overlap, at a corner or a crossing of their outlines, not
//! that at the nearest pixel centre.

use rayon::prelude::*;

use crate::depth::{
    ContactSummary, DepthImage, EDGE_ON, Fan, RenderJob, Shift, Surface, edge_function,
};

/// How far (m) two triangles' heights may differ over a pixel for them to count as one
/// plane there: far below any contact tolerance, far above rounding.
const COPLANAR: f64 = 1e-10;
/// The slope (tangent) past which a triangle counts as a wall seen edge-on, whatever its
/// area in the image by rounding (a wall at 89.99 degrees: 5,700).
const STEEP: f64 = 1e5;
/// How far (pixels) a pixel centre may lie on the wrong side of an outline line and still
/// agree with it (a centre on an outline counts as covered, [`super::ON_EDGE_PX`]).
const LINE_SLACK: f64 = 2e-3;

/// One image with what [`exact_contact`] reads of it beside its pixels: its mesh's
/// triangles as planes, each pixel's footprint, and the pixels on its rim.
pub(crate) struct Planes<'a> {
    img: &'a DepthImage,
    facets: Facets,
    prints: Footprints,
    /// The pixels (row, column) whose footprint is not one plain face: on an outline or a
    /// crease.
    rim: Vec<(u32, u32)>,
    /// Per pixel, whether it is in `rim`.
    on_rim: Vec<bool>,
}

impl<'a> Planes<'a> {
    /// The planes of `img`, the image `job` renders.
    pub(crate) fn of(job: &RenderJob<'_>, img: &'a DepthImage) -> Self {
        let facets = Facets::of(job);
        let prints = Footprints::of(img, &facets);
        let on_rim: Vec<bool> = (prints.cells.iter())
            .map(|f| f.as_ref().is_some_and(|f| !f.plain()))
            .collect();
        let width = prints.width;
        let rim = (on_rim.iter().enumerate())
            .filter(|(_, on)| **on)
            .map(|(k, _)| ((k / width) as u32, (k % width) as u32))
            .collect();
        Self {
            img,
            facets,
            prints,
            rim,
            on_rim,
        }
    }

    /// Whether pixel (x, y) is on the rim (false outside the image).
    fn on_rim(&self, x: i64, y: i64) -> bool {
        let (w, h) = (self.prints.width as i64, self.prints.height as i64);
        (0..w).contains(&x) && (0..h).contains(&y) && self.on_rim[(y * w + x) as usize]
    }
}

/// A mesh's triangles as one image sees them.
struct Facets {
    /// Per triangle, its three edges as lines in the image ([`Line`]), each >= 0 on the
    /// triangle's side; `None` where the triangle is edge-on or turned away from the view.
    edges: Vec<Option<[Line; 3]>>,
    /// Per triangle, its height plane: h = p[0] + p[1] x + p[2] y (m; x, y in pixels).
    plane: Vec<[f64; 3]>,
    /// The edges on the outline of the surface seen ([`Fan::outline`]), each from its
    /// first point to its second with its triangle (the second item) on the left.
    outline: Vec<([[f64; 2]; 2], u32)>,
}

impl Facets {
    /// The triangles of `job`'s mesh in its image.
    fn of(job: &RenderJob<'_>) -> Self {
        let fan = Fan::of(job);
        let mut out = Self {
            edges: Vec::with_capacity(fan.corners.len()),
            plane: Vec::with_capacity(fan.corners.len()),
            outline: Vec::new(),
        };
        for (t, p) in fan.corners.iter().enumerate() {
            let area = edge_function(p[0], p[1], p[2]);
            if area.abs() < EDGE_ON {
                out.edges.push(None);
                out.plane.push([0.0; 3]);
                continue;
            }
            let d = |k: usize, c: usize| p[k][c] - p[0][c];
            let hx = (d(1, 2) * d(2, 1) - d(2, 2) * d(1, 1)) / area;
            let hy = (d(1, 0) * d(2, 2) - d(2, 0) * d(1, 2)) / area;
            out.plane
                .push([p[0][2] - hx * p[0][0] - hy * p[0][1], hx, hy]);
            let facing = match job.surface {
                Surface::Top => area > 0.0,
                Surface::Bottom => area < 0.0,
            };
            if !facing || hx.hypot(hy) / job.pixel > STEEP {
                // Turned away (hidden behind the part's near side), or a wall seen edge-on
                // but for rounding: its edges are the faces' beside it.
                out.edges.push(None);
                continue;
            }
            let q = p.map(|q| [q[0], q[1]]);
            // Counter-clockwise in the image.
            let c = if area > 0.0 { q } else { [q[0], q[2], q[1]] };
            out.edges
                .push(Some([0, 1, 2].map(|e| Line::left_of(c[e], c[(e + 1) % 3]))));
            out.outline
                .extend((0..3).filter(|&k| fan.outline(t, k)).map(|k| {
                    let (a, b) = (q[(k + 1) % 3], q[(k + 2) % 3]);
                    (if area > 0.0 { [a, b] } else { [b, a] }, t as u32)
                }));
        }
        out
    }
}

/// Most lines that bound one part of a pixel's footprint (a triangle's three).
const MAX_LINES: usize = 3;

/// One plane of a surface over the part of a pixel's square where each of its lines holds,
/// in coordinates about the pixel's centre.
#[derive(Debug, Clone, Copy)]
struct Part {
    /// h = plane[0] + plane[1] dx + plane[2] dy (m; dx, dy in pixels).
    plane: [f64; 3],
    /// Affine functions of (dx, dy), each >= 0 over the part.
    lines: [[f64; 3]; MAX_LINES],
    /// How many of `lines` hold.
    n: u8,
    /// One triangle of the plane.
    tri: u32,
}

/// A part with no plane and no lines, to fill arrays.
const EMPTY_PART: Part = Part {
    plane: [0.0; 3],
    lines: [[0.0; 3]; MAX_LINES],
    n: 0,
    tri: u32::MAX,
};

/// The parts of pixel (x, y) of one image (`planes`): its footprint's, or where that is
/// [`Footprint::Mixed`], each triangle seen about it within its three edges (written into
/// `buf`); `None` where it sees no surface.
fn parts_at<'b>(
    planes: &'b Planes<'_>,
    x: i64,
    y: i64,
    buf: &'b mut [Part; 9],
) -> Option<&'b [Part]> {
    let (img, facets) = (planes.img, &planes.facets);
    match planes.prints.at(x, y)? {
        Footprint::Parts { parts, n } => Some(&parts[..usize::from(*n)]),
        Footprint::Mixed => {
            let mut tris = [0; 9];
            let n = about(img, x, y, &mut tris);
            let (xf, yf) = (x as f64, y as f64);
            let mut k = 0;
            for &t in &tris[..n] {
                let Some(edges) = &facets.edges[t as usize] else {
                    continue;
                };
                let p = facets.plane[t as usize];
                let mut part = Part {
                    plane: [p[0] + p[1] * xf + p[2] * yf, p[1], p[2]],
                    tri: t,
                    ..EMPTY_PART
                };
                for (line, edge) in part.lines.iter_mut().zip(edges) {
                    *line = edge.about(xf, yf);
                }
                part.n = 3;
                buf[k] = part;
                k += 1;
            }
            Some(&buf[..k])
        }
    }
}

/// A line of the image as an affine function of its columns and rows, in pixels:
/// `c[0] + c[1] x + c[2] y`, >= 0 on one side.
#[derive(Debug, Clone, Copy)]
struct Line([f64; 3]);

impl Line {
    /// The side left of the line a -> b (image pixels).
    fn left_of(a: [f64; 2], b: [f64; 2]) -> Self {
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        let len = ex.hypot(ey);
        Self([(ey * a[0] - ex * a[1]) / len, -ey / len, ex / len])
    }

    /// This line as an affine function of (dx, dy) about the pixel centre (x, y).
    fn about(&self, x: f64, y: f64) -> [f64; 3] {
        let [c, nx, ny] = self.0;
        [c + nx * x + ny * y, nx, ny]
    }
}

impl Part {
    /// This part where `line` holds too; `None` when it has [`MAX_LINES`] already.
    fn with(mut self, line: [f64; 3]) -> Option<Self> {
        let n = usize::from(self.n);
        (n < MAX_LINES).then(|| {
            self.lines[n] = line;
            self.n += 1;
            self
        })
    }
}

/// What one image's surface is over one pixel's square.
#[derive(Debug, Clone, Copy)]
// Held by value, one per pixel of an image; the small variant is the rare one.
#[allow(clippy::large_enum_variant)]
enum Footprint {
    /// One or two convex parts, each of one plane (`parts[..n]`): a face, a face within its
    /// outline (a rim: where two lines both hold, or where either does when the outline
    /// turns away from the surface, as a hole's does), or two faces on either side of the
    /// crease where their planes meet.
    Parts { parts: [Part; 2], n: u8 },
    /// Anything else: each triangle seen about the pixel is a part ([`parts_at`]).
    Mixed,
}

impl Footprint {
    /// Whether this is one face over the whole square, with no outline or crease in it.
    fn plain(&self) -> bool {
        matches!(self, Footprint::Parts { parts, n: 1 } if parts[0].n == 0)
    }
}

/// One image's [`Footprint`] at each of its pixels; `None` where it sees no surface.
struct Footprints {
    width: usize,
    height: usize,
    cells: Vec<Option<Footprint>>,
}

impl Footprints {
    /// The footprints of image `img` of the triangles `facets`.
    fn of(img: &DepthImage, facets: &Facets) -> Self {
        let (width, height) = (img.window.width, img.window.height);
        let edges = EdgesAt::of(facets, width, height);
        let cells = (0..width * height)
            .into_par_iter()
            .with_min_len(1024)
            .map(|k| footprint(img, facets, &edges, (k % width) as i64, (k / width) as i64))
            .collect();
        Self {
            width,
            height,
            cells,
        }
    }

    fn at(&self, x: i64, y: i64) -> Option<&Footprint> {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return None;
        }
        self.cells[y as usize * self.width + x as usize].as_ref()
    }
}

/// The outline edges through each pixel's square of an image.
struct EdgesAt {
    width: usize,
    /// Per pixel and one more, where its edges start in `list`.
    starts: Vec<u32>,
    /// Indices into [`Facets::outline`], pixel by pixel.
    list: Vec<u32>,
}

impl EdgesAt {
    fn of(facets: &Facets, width: usize, height: usize) -> Self {
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (e, &([a, b], _)) in facets.outline.iter().enumerate() {
            let lo = |c: usize| (a[c].min(b[c]) - 0.5).ceil().max(0.0) as i64;
            let hi = |c: usize, n: usize| ((a[c].max(b[c]) + 0.5).floor() as i64).min(n as i64 - 1);
            for y in lo(1)..=hi(1, height) {
                for x in lo(0)..=hi(0, width) {
                    if crosses_square(a, b, x as f64, y as f64) {
                        pairs.push(((y as usize * width + x as usize) as u32, e as u32));
                    }
                }
            }
        }
        pairs.sort_unstable();
        let starts = (0..=width * height)
            .map(|k| pairs.partition_point(|&(p, _)| (p as usize) < k) as u32)
            .collect();
        Self {
            width,
            starts,
            list: pairs.into_iter().map(|(_, e)| e).collect(),
        }
    }

    fn at(&self, x: i64, y: i64) -> &[u32] {
        let k = y as usize * self.width + x as usize;
        &self.list[self.starts[k] as usize..self.starts[k + 1] as usize]
    }
}

/// The distinct triangles seen at the 3 x 3 pixel centres about pixel (x, y) of `img`.
fn about(img: &DepthImage, x: i64, y: i64, out: &mut [u32; 9]) -> usize {
    let (w, h) = (img.window.width as i64, img.window.height as i64);
    let mut n = 0;
    for yy in (y - 1).max(0)..=(y + 1).min(h - 1) {
        for xx in (x - 1).max(0)..=(x + 1).min(w - 1) {
            let t = img.tri[(yy * w + xx) as usize];
            if t != u32::MAX && !out[..n].contains(&t) {
                out[n] = t;
                n += 1;
            }
        }
    }
    n
}

/// The footprint of pixel (x, y) of `img` (triangles `facets`, outline edges `edges`):
/// the plane seen at its centre within the outline edges through its square (both of two
/// that meet turning towards the surface, either of two that meet turning away); beyond
/// them the plane seen beyond them about the pixel, if any; where no outline crosses the
/// square but two planes are seen about it, each where it is the lower (a ridge seen from
/// above) or the higher of the two, split where they meet when that crosses the square.
fn footprint(
    img: &DepthImage,
    facets: &Facets,
    edges: &EdgesAt,
    x: i64,
    y: i64,
) -> Option<Footprint> {
    let (xf, yf) = (x as f64, y as f64);
    let part = |t: u32| {
        let p = facets.plane[t as usize];
        Part {
            plane: [p[0] + p[1] * xf + p[2] * yf, p[1], p[2]],
            tri: t,
            ..EMPTY_PART
        }
    };
    let one = |p: Part| Footprint::Parts {
        parts: [p, p],
        n: 1,
    };
    // Two parts, each with one line more (never past MAX_LINES here: at most two before).
    let two = |p: Option<Part>, q: Option<Part>| {
        p.zip(q)
            .map_or(Footprint::Mixed, |(p, q)| Footprint::Parts {
                parts: [p, q],
                n: 2,
            })
    };
    let through = edges.at(x, y);
    let w = img.window.width;
    let centre = img.tri[y as usize * w + x as usize];
    let mut tris = [0; 9];
    let n = about(img, x, y, &mut tris);
    if n == 0 && through.is_empty() {
        return None;
    }
    // Whether two triangles lie in one plane over the square.
    let height = |t: u32, dx: f64, dy: f64| {
        let p = facets.plane[t as usize];
        p[0] + p[1] * (xf + dx) + p[2] * (yf + dy)
    };
    let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)];
    let same = |t: u32, u: u32| {
        corners
            .iter()
            .all(|&(dx, dy)| (height(t, dx, dy) - height(u, dx, dy)).abs() <= COPLANAR)
    };
    // The planes seen about the pixel other than the centre's (or than the first one's).
    let first = if centre != u32::MAX { centre } else { tris[0] };
    let mut other = None;
    for &t in &tris[..n] {
        if !same(t, first) {
            match other {
                None => other = Some(t),
                Some(o) if same(t, o) => {}
                Some(_) => return Some(Footprint::Mixed),
            }
        }
    }
    if through.is_empty() {
        let Some(o) = other else {
            return (centre != u32::MAX).then(|| one(part(centre)));
        };
        if centre == u32::MAX {
            return Some(Footprint::Mixed);
        }
        // Two planes and no outline: a crease, if they meet within the square.
        let (p, q) = (part(centre), part(o));
        let d = [
            q.plane[0] - p.plane[0],
            q.plane[1] - p.plane[1],
            q.plane[2] - p.plane[2],
        ];
        let reach = 0.5 * (d[1].abs() + d[2].abs());
        if d[0].abs() > reach {
            // They do not meet over the square: the centre's holds all of it.
            return Some(one(p));
        }
        // The centre's plane is where it lies on the side it is seen on.
        let sign = if d[0] >= 0.0 { 1.0 } else { -1.0 };
        return Some(two(
            p.with(d.map(|c| c * sign)),
            q.with(d.map(|c| -c * sign)),
        ));
    }
    // Outline edges through the square: all of one plane's triangles.
    let owner = facets.outline[through[0] as usize].1;
    let mut near = part(owner);
    let mut segments = [[[0.0; 2]; 2]; 2];
    for (k, &e) in through.iter().enumerate() {
        let ([a, b], t) = facets.outline[e as usize];
        if k == 2 || !same(t, owner) {
            return Some(Footprint::Mixed);
        }
        segments[k] = [a, b];
        let Some(within) = near.with(Line::left_of(a, b).about(xf, yf)) else {
            return Some(Footprint::Mixed);
        };
        near = within;
    }
    // Two edges that meet turning away from the surface (a hole's rim): either holds.
    let mut parts = [near, near];
    let mut count = 1;
    if near.n == 2 {
        let [[a1, b1], [a2, b2]] = segments;
        let turn = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
            (q[0] - p[0]) * (r[1] - q[1]) - (q[1] - p[1]) * (r[0] - q[0])
        };
        let away = if b1 == a2 {
            turn(a1, b1, b2) < 0.0
        } else if b2 == a1 {
            turn(a2, b2, b1) < 0.0
        } else {
            false
        };
        if away {
            let l = near.lines;
            parts[0] = Part { n: 1, ..near };
            parts[1] = Part {
                lines: [l[1], l[0].map(|c| -c), [0.0; 3]],
                ..near
            };
            count = 2;
        }
    }
    // Beyond the outline: the other plane seen about the pixel, where it is not.
    let beyond = other
        .filter(|_| same(first, owner))
        .or_else(|| (!same(first, owner)).then_some(first));
    let inside = |p: &Part, dx: f64, dy: f64| {
        p.lines[..usize::from(p.n)]
            .iter()
            .all(|l| l[0] + l[1] * dx + l[2] * dy >= -LINE_SLACK)
    };
    // The centre, unless it lies on a line, is in the near parts exactly where its plane
    // is the owner's.
    let in_near = parts[..count].iter().any(|p| inside(p, 0.0, 0.0));
    let centre_near = centre != u32::MAX && same(centre, owner);
    if in_near != centre_near
        && parts[..count].iter().all(|p| {
            p.lines[..usize::from(p.n)]
                .iter()
                .all(|l| l[0].abs() > LINE_SLACK)
        })
    {
        return Some(Footprint::Mixed);
    }
    match (beyond, count) {
        (None, 1) => Some(one(near)),
        (None, _) => Some(two(Some(parts[0]), Some(parts[1]))),
        (Some(f), 1) if near.n == 1 => {
            Some(two(Some(near), part(f).with(near.lines[0].map(|c| -c))))
        }
        _ => Some(Footprint::Mixed),
    }
}

/// Whether the segment a -> b passes through the square of the pixel centred at (x, y)
/// (Liang-Barsky).
fn crosses_square(a: [f64; 2], b: [f64; 2], x: f64, y: f64) -> bool {
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (p, q0, c) in [(a[0], b[0], x), (a[1], b[1], y)] {
        let d = q0 - p;
        let (lo, hi) = (c - 0.5, c + 0.5);
        if d.abs() < 1e-300 {
            if p < lo || p > hi {
                return false;
            }
            continue;
        }
        let (mut s0, mut s1) = ((lo - p) / d, (hi - p) / d);
        if s0 > s1 {
            std::mem::swap(&mut s0, &mut s1);
        }
        t0 = t0.max(s0);
        t1 = t1.min(s1);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// Most corners a pixel's square clipped by two triangles (or six lines) and a line can
/// have.
const MAX_CORNERS: usize = 11;

/// A convex polygon, counter-clockwise.
#[derive(Clone, Copy)]
struct Polygon {
    n: usize,
    p: [[f64; 2]; MAX_CORNERS],
}

impl Polygon {
    /// No corners yet (a buffer to clip into).
    const EMPTY: Self = Self {
        n: 0,
        p: [[0.0; 2]; MAX_CORNERS],
    };

    /// Makes this a pixel's square about its centre (writing its four corners alone: the
    /// polygons are buffers reused piece after piece).
    fn set_square(&mut self) {
        self.p[..4].copy_from_slice(&[[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]);
        self.n = 4;
    }

    /// Makes this the polygon of these corners (at most [`MAX_CORNERS`]).
    fn set(&mut self, corners: &[[f64; 2]]) {
        self.p[..corners.len()].copy_from_slice(corners);
        self.n = corners.len();
    }

    /// The part where the affine function `f` (f[0] + f[1] x + f[2] y) is >= 0, written to
    /// `out`; `false` (and `out` left as it was) where that is the whole polygon.
    fn clip(&self, f: [f64; 3], out: &mut Self) -> bool {
        let at = |q: [f64; 2]| f[0] + f[1] * q[0] + f[2] * q[1];
        let mut v = [0.0; MAX_CORNERS];
        let mut inside = 0;
        for (value, &q) in v.iter_mut().zip(&self.p[..self.n]) {
            *value = at(q);
            inside += usize::from(*value >= 0.0);
        }
        // Most lines leave a pixel's square whole or cut nothing of it.
        if inside == self.n {
            return false;
        }
        let mut m = 0;
        if inside > 0 {
            for k in 0..self.n {
                let j = (k + 1) % self.n;
                let (q0, q1, f0, f1) = (self.p[k], self.p[j], v[k], v[j]);
                if f0 >= 0.0 && m < MAX_CORNERS {
                    out.p[m] = q0;
                    m += 1;
                }
                if (f0 >= 0.0) != (f1 >= 0.0) && m < MAX_CORNERS {
                    let t = f0 / (f0 - f1);
                    out.p[m] = [q0[0] + t * (q1[0] - q0[0]), q0[1] + t * (q1[1] - q0[1])];
                    m += 1;
                }
            }
        }
        out.n = m;
        true
    }

    fn corners(&self) -> &[[f64; 2]] {
        &self.p[..self.n]
    }

    /// Area and centroid.
    fn moments(&self) -> (f64, [f64; 2]) {
        let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
        let o = self.p[0];
        for k in 1..self.n.saturating_sub(1) {
            let (p, q) = (self.p[k], self.p[k + 1]);
            let cross = (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
            a += cross;
            cx += cross * (o[0] + p[0] + q[0]);
            cy += cross * (o[1] + p[1] + q[1]);
        }
        if a <= 0.0 {
            return (0.0, [0.0; 2]);
        }
        (a / 2.0, [cx / (3.0 * a), cy / (3.0 * a)])
    }
}

/// A's and B's images with their planes, and B's normals.
pub(crate) struct Overlay<'a> {
    /// A's image and its planes.
    pub a: &'a Planes<'a>,
    /// B's.
    pub b: &'a Planes<'a>,
    /// B's triangle normals in view coordinates.
    pub b_normals: &'a [[f32; 3]],
}

/// One piece of a pixel's square where A lies over B: the gap over it and A's height
/// (affine about the pixel's centre), B's triangle, and where its polygon's corners lie in
/// [`Kept::corners`].
struct Piece {
    gap: [f64; 3],
    height: [f64; 3],
    b_tri: u32,
    corners: std::ops::Range<usize>,
}

impl Overlay<'_> {
    /// Keeps each piece of A's image pixel (x, y) over B's pixel (x, y) + `off` whose least
    /// gap may be at most `below` (m) in `kept` (pairs of planes whose gap over the whole
    /// square stays above it are passed over); returns the least gap over them (+inf where
    /// there are none).
    fn pieces(
        &self,
        [x, y]: [i64; 2],
        off: [i64; 2],
        below: f64,
        [buf_a, buf_b]: &mut [[Part; 9]; 2],
        kept: &mut Kept,
    ) -> f64 {
        let (bx, by) = (x + off[0], y + off[1]);
        let mut least = f64::INFINITY;
        let Some(pa) = parts_at(self.a, x, y, buf_a) else {
            return least;
        };
        let Some(pb) = parts_at(self.b, bx, by, buf_b) else {
            return least;
        };
        for a in pa {
            for b in pb {
                let gap = [
                    a.plane[0] - b.plane[0],
                    a.plane[1] - b.plane[1],
                    a.plane[2] - b.plane[2],
                ];
                if gap[0] - 0.5 * (gap[1].abs() + gap[2].abs()) > below {
                    continue;
                }
                let [mut polygon, mut spare] = kept.polygons.each_mut();
                polygon.set_square();
                for l in a.lines[..usize::from(a.n)]
                    .iter()
                    .chain(&b.lines[..usize::from(b.n)])
                {
                    if polygon.n < 3 {
                        break;
                    }
                    if polygon.clip(*l, spare) {
                        std::mem::swap(&mut polygon, &mut spare);
                    }
                }
                if polygon.n >= 3 {
                    for q in polygon.corners() {
                        least = least.min(gap[0] + gap[1] * q[0] + gap[2] * q[1]);
                    }
                    let start = kept.corners.len();
                    kept.corners.extend_from_slice(polygon.corners());
                    kept.pieces.push(Piece {
                        gap,
                        height: a.plane,
                        b_tri: b.tri,
                        corners: start..kept.corners.len(),
                    });
                }
            }
        }
        least
    }
}

/// The pieces of the pixels a flood reached whose least gap may be within the tolerance,
/// and the polygons they are clipped in.
struct Kept {
    /// The pieces, pixel after pixel.
    pieces: Vec<Piece>,
    /// Their polygons' corners.
    corners: Vec<[f64; 2]>,
    /// Buffers to clip a piece's polygon in.
    polygons: [Polygon; 2],
}

impl Default for Kept {
    fn default() -> Self {
        Self {
            pieces: Vec::new(),
            corners: Vec::new(),
            polygons: [Polygon::EMPTY; 2],
        }
    }
}

/// What [`exact_contact`] reuses from one call to the next (one per thread).
#[derive(Default)]
pub(crate) struct Flood {
    /// Per pixel of A's image, the call that last reached it.
    seen: Vec<u32>,
    /// This call's mark in `seen`.
    call: u32,
    /// The pixels reached (row, column), with the least gap over their square (m) and
    /// where their pieces lie in `kept`.
    reached: Vec<(u32, u32, f64, std::ops::Range<usize>)>,
    /// The pieces of the pixels reached.
    kept: Kept,
    /// The reached pixels within the tolerance, as their index in the image above their
    /// index in `reached`, in order.
    order: Vec<u64>,
    /// Pixels still to look at.
    stack: Vec<(u32, u32)>,
}

/// The contact of B at `shift` under A in `o`, computed exactly within each pixel: grown
/// from the pixels of `seed` (the contact found at the pixel centres, whose least gap the
/// exact one is at most) and from every pixel where A's rim lies over B's (where two rims
/// cross, the parts may touch at a cap thinner than a pixel that no pixel centre sees) to
/// every pixel of A's image joined to them by pixels whose least
/// gap is within `tolerance` (m) of the least; `None` where it finds no overlap. Its pixels
/// are those with a share of the region, and the region's area is their count less
/// [`ContactSummary::deficit`].
pub(crate) fn exact_contact(
    o: &Overlay<'_>,
    shift: Shift,
    seed: &ContactSummary,
    tolerance: f32,
    scratch: &mut Flood,
) -> Option<ContactSummary> {
    let (aw, bw) = (o.a.img.window, o.b.img.window);
    let off = [aw.i0 - shift.du - bw.i0, aw.j0 - shift.dv - bw.j0];
    let (w, h) = (aw.width, aw.height);
    let tol = f64::from(tolerance);
    scratch.call = scratch.call.wrapping_add(1);
    if scratch.call == 0 || scratch.seen.len() != w * h {
        scratch.seen.clear();
        scratch.seen.resize(w * h, 0);
        scratch.call = 1;
    }
    let call = scratch.call;
    scratch.reached.clear();
    scratch.kept.pieces.clear();
    scratch.kept.corners.clear();
    scratch.stack.clear();
    for &(r, first, last) in &seed.rows {
        for c in first..=last {
            scratch.seen[r as usize * w + c as usize] = call;
            scratch.stack.push((r, c));
        }
    }
    for &(r, c) in &o.a.rim {
        let k = r as usize * w + c as usize;
        let over = o.b.on_rim(i64::from(c) + off[0], i64::from(r) + off[1]);
        if over && scratch.seen[k] != call {
            scratch.seen[k] = call;
            scratch.stack.push((r, c));
        }
    }
    let mut least = f64::from(seed.gap);
    let mut bufs = [[EMPTY_PART; 9]; 2];
    while let Some((r, c)) = scratch.stack.pop() {
        // The least gap over the pixel, and its pieces kept for the region below: the
        // threshold only falls as the least gap does, so they are all it will need.
        let start = scratch.kept.pieces.len();
        let at = [i64::from(c), i64::from(r)];
        let g = o.pieces(at, off, least + tol, &mut bufs, &mut scratch.kept);
        scratch
            .reached
            .push((r, c, g, start..scratch.kept.pieces.len()));
        least = least.min(g);
        if g > least + tol {
            continue;
        }
        for (dr, dc) in [
            (-1, -1),
            (-1, 0),
            (-1, 1),
            (0, -1),
            (0, 1),
            (1, -1),
            (1, 0),
            (1, 1),
        ] {
            let (rr, cc) = (i64::from(r) + dr, i64::from(c) + dc);
            if rr < 0 || cc < 0 || rr as usize >= h || cc as usize >= w {
                continue;
            }
            let k = rr as usize * w + cc as usize;
            if scratch.seen[k] != call {
                scratch.seen[k] = call;
                scratch.stack.push((rr as u32, cc as u32));
            }
        }
    }
    if !least.is_finite() {
        return None;
    }
    let thr = least + tol;
    let mut out = ContactSummary::none(least as f32);
    let mut area = 0.0;
    scratch.order.clear();
    scratch.order.extend(
        (scratch.reached.iter().enumerate())
            .filter(|(_, (_, _, g, _))| *g <= thr)
            .map(|(k, (r, c, _, _))| ((u64::from(*r) * w as u64 + u64::from(*c)) << 32) | k as u64),
    );
    scratch.order.sort_unstable();
    for &key in &scratch.order {
        let (r, c, _, pieces) = &scratch.reached[(key & u64::from(u32::MAX)) as usize];
        let (r, c) = (*r, *c);
        let mut share = 0.0;
        let kept = &mut scratch.kept;
        for p in &kept.pieces[pieces.clone()] {
            let [piece, within] = &mut kept.polygons;
            piece.set(&kept.corners[p.corners.clone()]);
            let cut = piece.clip([thr - p.gap[0], -p.gap[1], -p.gap[2]], within);
            let (a, [dx, dy]) = if cut { within } else { piece }.moments();
            if a <= 0.0 {
                continue;
            }
            share += a;
            out.sum_col += a * (f64::from(c) + dx);
            out.sum_row += a * (f64::from(r) + dy);
            out.sum_height += a * (p.height[0] + p.height[1] * dx + p.height[2] * dy);
            let n = o
                .b_normals
                .get(p.b_tri as usize)
                .copied()
                .unwrap_or_default();
            for (acc, n) in out.sum_normal.iter_mut().zip(n) {
                *acc += a * f64::from(n);
            }
        }
        if share <= 0.0 {
            continue;
        }
        area += share;
        out.count += 1;
        match out.rows.last_mut() {
            Some(row) if row.0 == r => row.2 = c,
            _ => out.rows.push((r, c, c)),
        }
    }
    if out.count == 0 {
        return None;
    }
    out.deficit = f64::from(out.count) - area;
    Some(out)
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

    use super::*;
    use crate::depth::cpu::CpuBackend;
    use crate::depth::{DepthBackend, PixelWindow, View};
    use crate::mesh::Mesh;

    #[test]
    fn a_flat_face_on_a_tilted_one_rests_on_the_band_the_closed_form_gives() {
        // Part A's flat bottom, a rectangle whose edges lie off the pixel lattice, over part
        // B's top tilted by 2 degrees about x: the gap grows as tan(2 deg) v from A's far
        // edge, so the region within the tolerance is the band tolerance / tan(2 deg) =
        // 57 um deep along it, thinner than the 100 um pixel: no pixel centre row need lie
        // in it, and the pixels' count puts it a whole pixel deep or none.
        let (pixel, tolerance) = (1e-4, 2e-6_f32);
        let (x0, x1, y0, y1) = (-1.03e-3, 1.27e-3, -0.71e-3, 1.137e-3);
        let a = Mesh::cuboid([x0, y0, 0.0], [x1, y1, 1e-3]);
        let b = Mesh::cuboid([-3e-3, -3e-3, -2e-3], [3e-3, 3e-3, 0.0]);
        for (theta, drop) in [(2f64.to_radians(), 0.0), (1.3f64.to_radians(), 3e-7)] {
            let view = View::along(-Vector3::z());
            let a_pose = Isometry3::identity();
            let b_pose = Isometry3::from_parts(
                Translation3::new(0.0, 0.0, -drop),
                UnitQuaternion::from_axis_angle(&Vector3::x_axis(), theta),
            );
            let win = PixelWindow::covering(-2e-3, 2e-3, -2e-3, 2e-3, pixel, 1);
            let job = |mesh, pose, surface| RenderJob {
                mesh,
                pose,
                view,
                surface,
                window: win,
                pixel,
            };
            let jobs = [
                job(&a, a_pose, Surface::Bottom),
                job(&b, b_pose, Surface::Top),
            ];
            let [ai, bi] = jobs.map(|j| CpuBackend.render(&j).expect("renders"));
            let normals: Vec<[f32; 3]> = (0..b.faces.len())
                .map(|t| {
                    let n = b_pose.rotation * b.normal(t);
                    [n.x as f32, n.y as f32, n.z as f32]
                })
                .collect();
            let shift = Shift { du: 0, dv: 0 };
            let seed = CpuBackend
                .contacts(&ai, &bi, &normals, &[shift], tolerance)
                .expect("reduces")
                .remove(0);
            let planes = [Planes::of(&jobs[0], &ai), Planes::of(&jobs[1], &bi)];
            let overlay = Overlay {
                a: &planes[0],
                b: &planes[1],
                b_normals: &normals,
            };
            let c = exact_contact(&overlay, shift, &seed, tolerance, &mut Flood::default())
                .expect("a contact");
            // B's top (lowered by `drop`) at A's far edge, the highest point under A.
            let t = theta.tan();
            let lowest = drop - y1 * t;
            let depth = f64::from(tolerance) / t;
            let area = (x1 - x0) * depth;
            let got_area = c.area() * pixel * pixel;
            let centroid = [
                (win.i0 as f64 + c.sum_col / c.area()) * pixel,
                (win.j0 as f64 + c.sum_row / c.area()) * pixel,
            ];
            assert!(
                (f64::from(c.gap) - lowest).abs() < 1e-9,
                "gap {} against {lowest}",
                c.gap
            );
            assert!(
                (got_area / area - 1.0).abs() < 1e-6,
                "area {got_area} against {area}"
            );
            let want = [(x0 + x1) / 2.0, y1 - depth / 2.0];
            let miss = (centroid[0] - want[0]).hypot(centroid[1] - want[1]);
            assert!(miss < 1e-9, "centroid {centroid:?} against {want:?}");
            // A's heights over the band, B's normal there.
            assert!((c.sum_height / c.area()).abs() < 1e-12);
            let n = Vector3::from(c.sum_normal).normalize();
            let up = b_pose.rotation * Vector3::z();
            assert!((n - up).norm() < 1e-6, "normal {n:?} against {up:?}");
            // The pixel centres alone put the band on their row.
            let row = (win.j0 as f64 + seed.sum_row / seed.area()) * pixel;
            assert!(
                (row - want[1]).abs() > 5e-6,
                "the lattice happens to hold the band: {row} against {}",
                want[1]
            );
        }
    }
}
