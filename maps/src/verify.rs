//! A computed map checked against the exact geometry, with parry's queries between the two
//! meshes instead of the z-buffer: at sampled cells, part A swept along the approach until
//! it touches part B (a shape cast) gives the exact contact height, and rays along the
//! approach at that height, off the map's pixel lattice, give the contact region and its
//! centroid. The map's depth channel must agree with the first within the contact
//! tolerance; the lever point of a centroid map's wrench with the second within a pixel,
//! the region taken where the map's own contact height puts it.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::query::{
    self, ClosestPoints, ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher, Ray,
    RayCast,
};
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{RngCore, SeedableRng};
use rayon::prelude::*;
use std::collections::BTreeMap;

use crate::depth::View;
use crate::error::{MapError, Result};
use crate::exact::{Pair, span};
use crate::generate::{pose_values, rotation};
use crate::map::{FtMap, NCH};
use crate::mesh::Mesh;
use crate::task::Task;
use crate::task::omega::MAX_AXES;
use crate::wrench::WrenchModel;

/// Share of the sampled cells that must agree for a map to pass (the 99.9 %).
pub const REQUIRED_SHARE: f64 = 0.999;
/// Rays per cell at most for the contact region; a part wider than that at one ray per
/// pixel is sampled more coarsely (the centroid of a region of many rays is far finer than
/// their pitch).
const MAX_RAYS: f64 = 40_000.0;
/// Rays of a finer search at most; past them it starts again twice as coarse.
const MAX_FINE_RAYS: f64 = 200_000.0;
/// The first scan's centroid is taken as it is when its sampling error (estimated from its
/// rays on the region's edge) is below this share of the pixel the map is held to.
const SAMPLING_SHARE: f64 = 0.05;
/// Rays in a row that a finer search looks past the region's last touching ray: the tips
/// of a crescent thinner than its pitch touch only now and then along it.
const REACH: u32 = 3;
/// How much finer the second search of the contact region is than the first, at least.
const REFINE: f64 = 2.0;
/// The rays' lattice is turned about the approach by this angle (rad) against the map's
/// pixels: its tangent the golden ratio's conjugate, the slope farthest from every ratio of
/// small integers, so that no edge at a round angle (0, 30, 45, 60, 90 degrees) runs along
/// its rows and each edge cuts the lattice at every phase (a lattice in phase with a
/// straight edge puts its whole length up to half a pitch off at once).
const LATTICE_TURN: f64 = 0.553_574_358_897_045_3;
/// Finer lattices a search of the contact region tries at most.
const SEARCHES: usize = 4;
/// Clearance between the parts before the sweep, and past each mesh's bounds for rays (m).
const MARGIN: f64 = 1e-3;
/// Lattice steps within which a first ray in contact stands for a place where the exact
/// geometry puts the parts within the first scan's slack: farther, the first rays passed
/// it by.
const PASSED: f64 = 2.0;

/// How a verification samples the map.
#[derive(Debug, Clone, Copy)]
pub struct VerifyOptions {
    /// Cells to check (all of them when the map has fewer).
    pub samples: usize,
    /// Seed of the cell sample and of the phases of the rays' lattices.
    pub seed: u64,
}

/// One checked cell.
#[derive(Debug, Clone, PartialEq)]
pub struct CellCheck {
    /// Flat cell index.
    pub cell: usize,
    /// The cell's coordinates (SI, one per grid axis).
    pub coords: Vec<f64>,
    /// Map depth minus the exact contact height (m).
    pub depth_error: f64,
    /// How far the map's depth may miss beyond the contact tolerance where the parts are
    /// tilted against each other (m): a pixel times the tilt's tangent, since the z-buffer
    /// samples the face that rests on an edge up to a pixel from that edge.
    pub sampling: f64,
    /// The gap (m) within which the exact contact region is taken: the contact tolerance
    /// plus how far below the exact contact height the map's depth lies, where that depth
    /// is within bounds (the map's lowest gap is that much above the exact one, and its
    /// contact pixels are those within the tolerance of it); the tolerance elsewhere.
    pub threshold: f64,
    /// Distance across the approach from the map's lever point to the exact contact
    /// region's centroid (m; where no ray along the approach meets the region, the point
    /// where parry puts the parts closest): infinite where neither finds the contact;
    /// `None` where the map's model does not put the lever at the centroid.
    pub centroid_error: Option<f64>,
    /// The exact contact region's centroid across the approach (m; part A's view of
    /// [`View::along`] its approach; the region within `threshold` of touching), or the
    /// closest points' where no ray meets it.
    pub centroid: Option<[f64; 2]>,
    /// Where the map's wrench puts the lever across the approach (m, the frame of
    /// `centroid`): its line of action at the exact region's mean height; `None` where
    /// there is no centroid to compare with.
    pub lever: Option<[f64; 2]>,
    /// Where the lever misses by more than a pixel on tilted parts: how far the exact
    /// centroid moves (m) when the threshold moves by half the pixel's climb across the
    /// tilt (`sampling` / 2), the most the map's pixel centres can shift the region's edge
    /// in gap. Larger than a pixel: the region is in pieces or a tip, whose centroid the
    /// threshold does not fix to a pixel.
    pub spread: Option<f64>,
}

/// The checked cells and the bounds they are held to.
#[derive(Debug, Clone)]
pub struct Verification {
    /// Every checked cell, in cell order.
    pub checks: Vec<CellCheck>,
    /// Contact tolerance of the depth check (m).
    pub tolerance: f64,
    /// Pixel of the centroid check (m).
    pub pixel: f64,
}

impl Verification {
    /// Share of the cells whose depth is within the contact tolerance (plus its sampling
    /// allowance on tilted parts).
    pub fn depth_share(&self) -> f64 {
        let within = self
            .checks
            .iter()
            .filter(|c| c.depth_error.abs() <= self.tolerance + c.sampling);
        within.count() as f64 / self.checks.len().max(1) as f64
    }

    /// The cells whose lever point misses the exact centroid by more than a pixel, and how
    /// many of them have a centroid that the threshold does not fix to a pixel
    /// ([`CellCheck::spread`]).
    pub fn centroid_misses(&self) -> (usize, usize) {
        let misses = self
            .checks
            .iter()
            .filter(|c| c.centroid_error.is_some_and(|e| e > self.pixel));
        let unsettled = misses
            .clone()
            .filter(|c| c.spread.is_some_and(|s| s > self.pixel));
        (misses.count(), unsettled.count())
    }

    /// Share of the cells with a centroid check whose lever point is within a pixel of the
    /// exact centroid (`None`: no centroid checked).
    pub fn centroid_share(&self) -> Option<f64> {
        let errors = self.checks.iter().filter_map(|c| c.centroid_error);
        let checked = errors.clone().count();
        (checked > 0).then(|| errors.filter(|&e| e <= self.pixel).count() as f64 / checked as f64)
    }

    /// Whether both shares reach [`REQUIRED_SHARE`].
    pub fn passes(&self) -> bool {
        self.depth_share() >= REQUIRED_SHARE
            && self.centroid_share().is_none_or(|s| s >= REQUIRED_SHARE)
    }

    /// Quantiles `qs` (0..=1) of |depth error| (m).
    pub fn depth_quantiles(&self, qs: &[f64]) -> Vec<f64> {
        quantiles(self.checks.iter().map(|c| c.depth_error.abs()), qs)
    }

    /// Quantiles `qs` (0..=1) of the centroid error (m), over the cells with one.
    pub fn centroid_quantiles(&self, qs: &[f64]) -> Vec<f64> {
        quantiles(self.checks.iter().filter_map(|c| c.centroid_error), qs)
    }

    /// The `n` cells farthest out of bounds (depth error over the tolerance plus centroid
    /// error over the pixel, each in its own bound's units), worst first.
    pub fn worst(&self, n: usize) -> Vec<&CellCheck> {
        let excess = |c: &CellCheck| {
            (c.depth_error.abs() / (self.tolerance + c.sampling))
                .max(c.centroid_error.unwrap_or(0.0) / self.pixel)
        };
        let mut all: Vec<&CellCheck> = self.checks.iter().collect();
        all.sort_by(|a, b| excess(b).total_cmp(&excess(a)));
        all.truncate(n);
        all
    }
}

fn quantiles(values: impl Iterator<Item = f64>, qs: &[f64]) -> Vec<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    qs.iter()
        .map(|q| {
            if v.is_empty() {
                return f64::NAN;
            }
            v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)]
        })
        .collect()
}

/// Checks `opts.samples` cells of `map` against the exact geometry of `task`'s meshes (A,
/// B): refuses a map that was not computed from CAD, or from other meshes than these.
pub fn verify(
    map: &FtMap,
    task: &Task,
    meshes: [&Mesh; 2],
    opts: VerifyOptions,
) -> Result<Verification> {
    verify_cells(
        map,
        task,
        meshes,
        &sample(map.grid().cells(), opts),
        opts.seed,
    )
}

/// Checks the cells `cells` of `map` against the exact geometry of `meshes` (A, B), the
/// ray lattices' phases drawn from `seed`; refuses as [`verify`] does.
pub fn verify_cells(
    map: &FtMap,
    task: &Task,
    meshes: [&Mesh; 2],
    cells: &[usize],
    seed: u64,
) -> Result<Verification> {
    verify_cells_with(map, task, meshes, cells, seed, &|_| {})
}

/// Checks the cells `cells` of `map` as [`verify_cells`] does; `progress` is called with
/// the number of cells checked since its last call.
pub fn verify_cells_with(
    map: &FtMap,
    task: &Task,
    [mesh_a, mesh_b]: [&Mesh; 2],
    cells: &[usize],
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Verification> {
    let meta = map.meta();
    if !meta.model.is_computed() {
        return Err(MapError::Geometry(format!(
            "a {:?} map is not computed from CAD: there is no geometry to verify it against",
            meta.model
        )));
    }
    for (role, mesh) in [("A", mesh_a), ("B", mesh_b)] {
        let source = meta.sources.iter().find(|s| s.role == role);
        if let Some(s) = source.filter(|s| s.sha256 != mesh.sha256) {
            return Err(MapError::Mesh {
                path: mesh.path.clone(),
                reason: format!(
                    "not the mesh the map was computed from (part {role}: the map names {} with SHA-256 {}, this file has {})",
                    s.file, s.sha256, mesh.sha256
                ),
            });
        }
    }
    let parts = Parts::new(task, mesh_a, mesh_b, meta.model == WrenchModel::Centroid)?;
    let checks = cells
        .par_iter()
        .map(|&cell| {
            let check = parts.check(map, cell, seed);
            progress(1);
            check
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Verification {
        checks,
        tolerance: task.depth.tolerance,
        pixel: task.depth.pixel,
    })
}

/// `opts.samples` distinct cells of `n` (all of them when there are fewer), ascending: the
/// cells [`verify`] checks.
pub fn sample(n: usize, opts: VerifyOptions) -> Vec<usize> {
    if opts.samples >= n {
        return (0..n).collect();
    }
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(opts.seed);
    let mut all: Vec<usize> = (0..n).collect();
    for i in 0..opts.samples {
        let j = i + (rng.next_u64() % (n - i) as u64) as usize;
        all.swap(i, j);
    }
    all.truncate(opts.samples);
    all.sort_unstable();
    all
}

/// The two meshes as parry shapes, and what every cell's check shares.
struct Parts<'a> {
    task: &'a Task,
    pair: Pair,
    /// Whether the map's lever point is the contact centroid (the centroid model).
    centroid: bool,
}

impl<'a> Parts<'a> {
    fn new(task: &'a Task, mesh_a: &Mesh, mesh_b: &Mesh, centroid: bool) -> Result<Self> {
        Ok(Self {
            task,
            pair: Pair::new(mesh_a, mesh_b)?,
            centroid,
        })
    }

    /// The exact contact of `cell` against the map's values there; its ray lattices'
    /// phases drawn from `seed` and the cell.
    fn check(&self, map: &FtMap, cell: usize, seed: u64) -> Result<CellCheck> {
        let grid = map.grid();
        let mut idx = [0usize; MAX_AXES];
        grid.unflat(cell, &mut idx[..grid.ndim()]);
        let v = pose_values(grid, &idx[..grid.ndim()]);
        let (r1, r2) = (rotation(&v[3..6]), rotation(&v[9..12]));
        let t_grip = Vector3::new(v[0], v[1], v[2]);
        let t_obj = Vector3::new(v[6], v[7], v[8]);
        // Part A in its own frame, part B at the cell's pose in it, as the map computes them.
        let view = View::along(r1.inverse() * Vector3::from(self.task.contact.approach));
        let b_pose = Isometry3::from_parts(
            Translation3::from(t_obj),
            UnitQuaternion::from_rotation_matrix(&r2),
        );
        let a_range = span(&self.pair.a, &Isometry3::identity(), &view.w);
        let b_range = span(&self.pair.b, &b_pose, &view.w);
        let coords = grid.coords(cell);
        let missed = |what: &str| {
            MapError::Geometry(format!(
                "at cell {coords:?} of the map, {what} by the exact geometry"
            ))
        };
        let rise = self
            .touch(&view.w, &b_pose, a_range, b_range)
            .ok_or_else(|| missed("part A swept along the approach misses part B"))?;
        // Part B's face turned against part A's (both across the approach at rest).
        let approach = Vector3::from(self.task.contact.approach);
        let tilt = (r2 * approach).angle(&approach);
        let values = map.cell(cell);
        let depth_error = f64::from(values[NCH - 1]) - (t_obj.dot(&view.w) + rise);
        let sampling = map.meta().pixel * tilt.tan();
        // The map's contact region is the pixels within the tolerance of its own lowest gap,
        // which lies as far above the exact one as its depth lies below the exact contact
        // height: where that depth is within bounds, its pixels sample the exact region at
        // the tolerance plus that much (the depth's error is held to its own bound above).
        let tolerance = self.task.depth.tolerance;
        let threshold = if depth_error.abs() <= tolerance + sampling {
            tolerance + (-depth_error).max(0.0)
        } else {
            tolerance
        };
        // A contact that no ray along the approach meets (an edge on a wall) is a point,
        // where parry's closest points put it. A face tilted against another is searched
        // for where it rests on its rim.
        let phase = Xoshiro256PlusPlus::seed_from_u64(seed ^ (cell as u64).rotate_left(32));
        let region_within = |threshold: f64| {
            let (bounds, ranges) = ([rise, threshold], [a_range, b_range]);
            self.region(&view, &b_pose, bounds, tilt.tan(), phase.clone(), ranges)
        };
        let region = self.centroid.then(|| region_within(threshold)).flatten();
        let lever = region.map(|(_, height)| {
            let force = r1.inverse() * Vector3::new(values[0], values[1], values[2]).cast::<f64>();
            let torque = r1.inverse() * Vector3::new(values[3], values[4], values[5]).cast::<f64>();
            let sensor = r1.inverse() * (Vector3::from(self.task.contact.sensor_origin) - t_grip);
            // The wrench's line of action, at the contact's height along w.
            let nearest = sensor + force.cross(&torque) / force.norm_squared();
            let along = (height - nearest.dot(&view.w)) / force.dot(&view.w);
            let [u, v, _] = view.project(&Point3::from(nearest + force * along));
            [u, v]
        });
        let centroid_error = self.centroid.then(|| match (region, lever) {
            (Some(([u, v], _)), Some([lu, lv])) => (lu - u).hypot(lv - v),
            _ => f64::INFINITY,
        });
        // Where the lever misses, how far the exact centroid moves as the threshold moves by
        // half a pixel's climb across the tilt (how far the map's pixel centres may put the
        // region's edge, in gap).
        let climb = 0.5 * sampling;
        let spread = (centroid_error.is_some_and(|e| e > self.task.depth.pixel) && climb > 0.0)
            .then(|| {
                let [u, v] = region?.0;
                let moved = [threshold - climb, threshold + climb].map(|t| {
                    region_within(t.max(0.0)).map_or(0.0, |([x, y], _)| (x - u).hypot(y - v))
                });
                Some(moved[0].max(moved[1]))
            })
            .flatten();
        Ok(CellCheck {
            cell,
            coords,
            depth_error,
            sampling,
            threshold,
            centroid_error,
            centroid: region.map(|(c, _)| c),
            lever,
            spread,
        })
    }

    /// How far A must rise along `w` from its own frame to just touch B at `b_pose`:
    /// lowered along -w onto B from clear of it ([`Pair::travel`]).
    fn touch(
        &self,
        w: &Vector3<f64>,
        b_pose: &Isometry3<f64>,
        a_range: [f64; 2],
        b_range: [f64; 2],
    ) -> Option<f64> {
        let lift = (b_range[1] - a_range[0]).max(0.0) + MARGIN;
        let reach = lift + (a_range[1] - b_range[0]).max(0.0) + MARGIN;
        let from = Isometry3::translation(lift * w.x, lift * w.y, lift * w.z);
        Some(lift - self.pair.travel(&from, &(-w), b_pose, reach)?)
    }

    /// Centroid (u, v) and mean height along w of the contact region of A risen by `rise`
    /// along w against B at `b_pose`: the rays along w where the gap is within `tolerance`
    /// of touching, first at about the pixel over all of A; where their centroid
    /// is not fine enough (few rays, or many on the region's edge: a crescent, a strip a
    /// few rays wide), again finer over the region itself, grown ray by ray from them, from
    /// every first ray within a slack of touching, from the closest points and from every
    /// place where parry's contact manifolds put the parts within that slack with no
    /// touching first ray near ([`Seeds`]; `slope`, the tangent of B's tilt against A): a
    /// thin crescent's centroid moves with its sampling, its tips may be thinner than the
    /// first rays' pitch, and a face tilted against another may rest on its rim at two
    /// places micrometres apart in height, slivers narrower than the pitch that the first
    /// rays may touch at one place or none.
    fn region(
        &self,
        view: &View,
        b_pose: &Isometry3<f64>,
        [rise, tolerance]: [f64; 2],
        slope: f64,
        mut phase: Xoshiro256PlusPlus,
        ranges: [[f64; 2]; 2],
    ) -> Option<([f64; 2], f64)> {
        let a_box = [view.u, view.v].map(|axis| span(&self.pair.a, &Isometry3::identity(), &axis));
        let (lo, hi) = (a_box.map(|r| r[0]), a_box.map(|r| r[1]));
        let rays = Rays {
            parts: self,
            view,
            b_pose,
            rise,
            tolerance,
            ranges,
            bounds: [lo, hi],
        };
        let pitch = self
            .task
            .depth
            .pixel
            .max(((hi[0] - lo[0]) * (hi[1] - lo[1]) / MAX_RAYS).sqrt());
        let lattice = Lattice::new(pitch, &mut phase);
        // A pitch of the tilt's slope more than the tolerance widens a sliver to about a
        // pitch: every place where the parts rest has a first ray within it.
        let slack = tolerance + pitch * slope;
        let near = rays.scan(&lattice, slack);
        let touching: BTreeMap<[i64; 2], f64> = (near.iter())
            .filter(|(_, (_, gap))| *gap <= tolerance)
            .map(|(&k, &(h, _))| (k, h))
            .collect();
        // Where the parts come within the slack with no touching first ray near, the first
        // rays may have passed a piece of the region by (a lens tip far from the rest).
        let reach = PASSED * pitch;
        let passed: Vec<[f64; 2]> = (rays.manifold_points(slack).into_iter())
            .filter(|&p| {
                let [i, j] = lattice.nearest(p);
                let r = PASSED as i64;
                !(i - r..=i + r)
                    .flat_map(|i| (j - r..=j + r).map(move |j| [i, j]))
                    .any(|k| {
                        let [u, v] = lattice.at(k);
                        touching.contains_key(&k) && (u - p[0]).hypot(v - p[1]) <= reach
                    })
            })
            .collect();
        let coarse = (!touching.is_empty()).then(|| Scan::of(&touching, &lattice));
        let error = match &coarse {
            Some(c) if passed.is_empty() => c.sampling_error(),
            _ => pitch,
        };
        if let Some(c) = coarse
            .as_ref()
            .filter(|_| error < SAMPLING_SHARE * self.task.depth.pixel)
        {
            return Some(c.mean());
        }
        let closest = touching.is_empty().then(|| rays.closest()).flatten();
        let seeds = Seeds {
            // The closest points where no first ray touches: a rim's sliver.
            inside: (touching.keys().map(|&k| lattice.at(k)))
                .chain(closest.map(|(p, _)| p))
                .collect(),
            near: (near.iter())
                .filter(|(_, (_, gap))| *gap > tolerance)
                .map(|(&k, _)| lattice.at(k))
                .chain(passed)
                .collect(),
            radius: pitch,
        };
        let found = rays.refine(seeds, pitch, error, &mut phase);
        // No ray of a finer lattice near the first ones touches: nothing finer to say; and
        // where no ray touches at all, the parts touch at a point no ray along the approach
        // meets within the tolerance (an edge on a wall): the closest points stand for it.
        (found.or(coarse).map(|s| s.mean())).or(closest)
    }
}

/// Rays along w through A risen by `rise` and B at `b_pose`.
struct Rays<'a> {
    parts: &'a Parts<'a>,
    view: &'a View,
    b_pose: &'a Isometry3<f64>,
    rise: f64,
    /// How far above touching a ray's gap may be for the ray to be in contact (m).
    tolerance: f64,
    /// A's and B's extent along w.
    ranges: [[f64; 2]; 2],
    /// A's (u, v) box: no ray outside it meets A.
    bounds: [[f64; 2]; 2],
}

/// A lattice of rays in (u, v), turned by [`LATTICE_TURN`] and shifted by a random phase.
struct Lattice {
    pitch: f64,
    /// Sine and cosine of the turn.
    turn: (f64, f64),
    /// Shift of the lattice in pitches.
    phase: [f64; 2],
}

impl Lattice {
    /// A lattice of `pitch` at a phase drawn from `rng`.
    fn new(pitch: f64, rng: &mut Xoshiro256PlusPlus) -> Self {
        Self {
            pitch,
            turn: LATTICE_TURN.sin_cos(),
            phase: [0, 1].map(|_| (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64),
        }
    }

    /// The (u, v) of the lattice point (i, j).
    fn at(&self, [i, j]: [i64; 2]) -> [f64; 2] {
        let (sin, cos) = self.turn;
        let [a, b] = [(i, 0), (j, 1)].map(|(k, d)| (k as f64 + self.phase[d]) * self.pitch);
        [cos * a - sin * b, sin * a + cos * b]
    }

    /// The lattice point nearest (u, v).
    fn nearest(&self, [u, v]: [f64; 2]) -> [i64; 2] {
        let (sin, cos) = self.turn;
        let (a, b) = (cos * u + sin * v, -sin * u + cos * v);
        [(a, 0), (b, 1)].map(|(x, k)| (x / self.pitch - self.phase[k]).round() as i64)
    }
}

/// The rays one search found in contact.
struct Scan {
    /// Each contact ray's (u, v) and A's height along w there.
    hits: Vec<([f64; 2], f64)>,
    /// Contact rays with a neighbour on the lattice that is not one.
    edge: usize,
    /// The lattice's pitch (m).
    pitch: f64,
}

impl Scan {
    /// Contact rays found.
    fn rays(&self) -> usize {
        self.hits.len()
    }

    /// An estimate of the error of the rays' centroid (m): each ray on the region's edge in
    /// or out by chance (a variance p (1 - p) of 1/6 on average over where the edge cuts
    /// its cell), at up to the region's extent from the centroid, and at least a pitch (a
    /// region of one ray, or a row of them, may reach a pitch beyond its rays).
    fn sampling_error(&self) -> f64 {
        let ([u, v], _) = self.mean();
        let extent = self
            .hits
            .iter()
            .map(|([x, y], _)| (x - u).hypot(y - v))
            .fold(self.pitch, f64::max);
        (self.edge as f64 / 6.0).sqrt() * extent / self.rays() as f64
    }

    /// Mean (u, v) and mean height of the contact rays.
    fn mean(&self) -> ([f64; 2], f64) {
        let n = self.hits.len() as f64;
        let sum = self
            .hits
            .iter()
            .fold([0.0; 3], |s, ([u, v], h)| [s[0] + u, s[1] + v, s[2] + h]);
        ([sum[0] / n, sum[1] / n], sum[2] / n)
    }
}

/// Where a finer search of the contact region starts.
struct Seeds {
    /// Points in the region.
    inside: Vec<[f64; 2]>,
    /// Points near it: the region may lie anywhere within `radius` of them.
    near: Vec<[f64; 2]>,
    /// How far from a point near the region the search starts (m).
    radius: f64,
}

impl Seeds {
    /// The contact rays of a search.
    fn inside(scan: &Scan) -> Self {
        Self {
            inside: scan.hits.iter().map(|&(p, _)| p).collect(),
            near: Vec::new(),
            radius: 0.0,
        }
    }
}

/// The four lattice neighbours of (i, j).
fn neighbours([i, j]: [i64; 2]) -> [[i64; 2]; 4] {
    [[i - 1, j], [i + 1, j], [i, j - 1], [i, j + 1]]
}

impl Rays<'_> {
    /// A's height along w at (u, v) and the gap there, when the ray there meets both parts
    /// with a gap within `slack`.
    fn gap_at(&self, [u, v]: [f64; 2], slack: f64) -> Option<(f64, f64)> {
        let [lo, hi] = self.bounds;
        if u < lo[0] || u > hi[0] || v < lo[1] || v > hi[1] {
            return None;
        }
        let [a_range, b_range] = self.ranges;
        let w = self.view.w;
        // A's leading surface from below, B's facing one from above.
        let below = self.view.unproject([u, v, a_range[0] - MARGIN]);
        let ta = self.parts.pair.a.cast_ray(
            &Isometry3::identity(),
            &Ray::new(below, w),
            a_range[1] - a_range[0] + 2.0 * MARGIN,
            false,
        )?;
        let above = self.view.unproject([u, v, b_range[1] + MARGIN]);
        let tb = self.parts.pair.b.cast_ray(
            self.b_pose,
            &Ray::new(above, -w),
            b_range[1] - b_range[0] + 2.0 * MARGIN,
            false,
        )?;
        let h_a = a_range[0] - MARGIN + ta + self.rise;
        let h_b = b_range[1] + MARGIN - tb;
        (h_a - h_b <= slack).then_some((h_a, h_a - h_b))
    }

    /// The rays of `lattice` over A's box with a gap within `slack`: A's height and the
    /// gap at each.
    fn scan(&self, lattice: &Lattice, slack: f64) -> BTreeMap<[i64; 2], (f64, f64)> {
        let [lo, hi] = self.bounds;
        let corners = [lo, [hi[0], lo[1]], [lo[0], hi[1]], hi].map(|c| lattice.nearest(c));
        let range = |k: usize| {
            let (min, max) = corners
                .iter()
                .fold((i64::MAX, i64::MIN), |(l, h), c| (l.min(c[k]), h.max(c[k])));
            min - 1..=max + 1
        };
        let mut hit = BTreeMap::new();
        for i in range(0) {
            for j in range(1) {
                if let Some(found) = self.gap_at(lattice.at([i, j]), slack) {
                    hit.insert([i, j], found);
                }
            }
        }
        hit
    }

    /// The contact rays of `lattice` reached from `seeds` (those nearest its points inside
    /// the region, and those within its radius of its points near it) through rays no more
    /// than [`REACH`] apart (none when none touches); `None` when more than
    /// [`MAX_FINE_RAYS`] rays would be cast.
    fn flood(&self, lattice: &Lattice, seeds: &Seeds) -> Option<Scan> {
        // Each ray cast: A's height where it touches, and the fewest misses in a row on a
        // path that reached it from a touching one (a ray about a point near the region
        // starts at the most: a miss there leads nowhere).
        let mut seen: BTreeMap<[i64; 2], (Option<f64>, u32)> = BTreeMap::new();
        let steps = (seeds.radius / lattice.pitch).floor() as i64;
        let about = |p: &[f64; 2]| {
            let [i, j] = lattice.nearest(*p);
            (-steps..=steps).flat_map(move |di| (-steps..=steps).map(move |dj| [i + di, j + dj]))
        };
        let mut todo: Vec<([i64; 2], u32)> = (seeds.inside.iter())
            .map(|p| (lattice.nearest(*p), 0))
            .chain(seeds.near.iter().flat_map(about).map(|k| (k, REACH)))
            .collect();
        while let Some((k, misses)) = todo.pop() {
            let touch = match seen.get(&k) {
                Some(&(_, fewest)) if fewest <= misses => continue,
                Some(&(touch, _)) => touch,
                None if seen.len() as f64 >= MAX_FINE_RAYS => return None,
                None => self.gap_at(lattice.at(k), self.tolerance).map(|(h, _)| h),
            };
            let misses = if touch.is_some() { 0 } else { misses + 1 };
            seen.insert(k, (touch, misses));
            if misses <= REACH {
                todo.extend(neighbours(k).map(|n| (n, misses)));
            }
        }
        let hit = seen
            .into_iter()
            .filter_map(|(k, (touch, _))| Some((k, touch?)))
            .collect();
        Some(Scan::of(&hit, lattice))
    }

    /// Where the exact geometry puts the parts closest (A risen a tolerance more): a point
    /// of the contact region, though no ray of a lattice may meet it within the tolerance
    /// (a rim's sliver, an edge on a wall), and A's height along w there.
    fn closest(&self) -> Option<([f64; 2], f64)> {
        let pair = &self.parts.pair;
        let tolerance = self.tolerance;
        let lifted = Isometry3::from(Translation3::from(self.view.w * (self.rise + tolerance)));
        match query::closest_points(&lifted, &pair.a, self.b_pose, &pair.b, 2.0 * tolerance) {
            Ok(ClosestPoints::WithinMargin(on_a, _)) => {
                let [u, v, h] = self.view.project(&on_a);
                Some(([u, v], h - tolerance))
            }
            _ => None,
        }
    }

    /// Where parry's contact manifolds between the two meshes put them within `slack`
    /// (m) of each other, with B's surface below A's within the slack along the approach:
    /// each such point of A as (u, v).
    fn manifold_points(&self, slack: f64) -> Vec<[f64; 2]> {
        let pair = &self.parts.pair;
        let w = self.view.w;
        let a_pose = Isometry3::from(Translation3::from(w * self.rise));
        let mut manifolds: Vec<ContactManifold<(), ()>> = Vec::new();
        let found = DefaultQueryDispatcher.contact_manifolds(
            &a_pose.inv_mul(self.b_pose),
            &pair.a,
            &pair.b,
            slack,
            &mut manifolds,
            &mut None,
        );
        if found.is_err() {
            return Vec::new();
        }
        let mut out = Vec::new();
        for m in &manifolds {
            let sub = m.subshape_pos1.unwrap_or_else(Isometry3::identity);
            for c in m.points.iter().filter(|c| c.dist <= slack) {
                let p = a_pose * (sub * c.local_p1);
                let down = Ray::new(p + w * slack, -w);
                if pair.b.intersects_ray(self.b_pose, &down, 2.0 * slack) {
                    let [u, v, _] = self.view.project(&p);
                    out.push([u, v]);
                }
            }
        }
        out
    }

    /// The contact region grown from `seeds` (found on a lattice of `pitch`, their
    /// centroid good to about `error`) on finer lattices until its centroid is good to half
    /// the [`SAMPLING_SHARE`] of a pixel, for at most [`SEARCHES`] lattices: each fine
    /// enough for that were the error to go as pitch^1.5 (the rays on the edge, pitch^-1,
    /// over the rays, pitch^-2; a sliver's, every ray on its edge, falls slower) and at
    /// least [`REFINE`] times finer than the last; the first twice as coarse while it
    /// would cast more than [`MAX_FINE_RAYS`], a later one not at all. `None` when no
    /// finer lattice's ray touches.
    fn refine(
        &self,
        seeds: Seeds,
        pitch: f64,
        mut error: f64,
        phase: &mut Xoshiro256PlusPlus,
    ) -> Option<Scan> {
        let target = 0.5 * SAMPLING_SHARE * self.parts.task.depth.pixel;
        let (mut best, mut fine): (Option<Scan>, f64) = (None, pitch);
        let mut from = seeds;
        for _ in 0..SEARCHES {
            let mut next = fine * (target / error).powf(2.0 / 3.0).min(1.0 / REFINE);
            let found = loop {
                match self.flood(&Lattice::new(next, phase), &from) {
                    Some(found) => break found,
                    None if best.is_none() => next *= 2.0,
                    None => return best,
                }
            };
            if found.hits.is_empty() {
                break;
            }
            error = found.sampling_error();
            fine = next;
            from = Seeds::inside(&found);
            best = Some(found);
            if error < target {
                break;
            }
        }
        best
    }
}

impl Scan {
    /// The scan of the contact rays `hit` (lattice point: A's height) of `lattice`.
    fn of(hit: &BTreeMap<[i64; 2], f64>, lattice: &Lattice) -> Scan {
        Scan {
            pitch: lattice.pitch,
            hits: hit.iter().map(|(&k, &h)| (lattice.at(k), h)).collect(),
            edge: hit
                .keys()
                .filter(|&&k| neighbours(k).iter().any(|n| !hit.contains_key(n)))
                .count(),
        }
    }
}
