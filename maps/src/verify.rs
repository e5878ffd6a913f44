//! A computed map checked against the exact geometry, with parry's queries between the two
//! meshes instead of the z-buffer: at sampled cells, part A swept along the approach until
//! it touches part B (a shape cast) gives the exact contact height, and rays along the
//! approach at that height, off the map's pixel lattice, give the contact region and its
//! centroid. The map's depth channel must agree with the first within the contact
//! tolerance; the lever point of a centroid map's wrench with the second within a pixel.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use parry3d_f64::query::{Ray, RayCast};
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{RngCore, SeedableRng};
use rayon::prelude::*;

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
/// A region with more than this share of its rays on its edge has a part a few rays wide:
/// it is scanned finer too.
const EDGE_SHARE: f64 = 0.2;
/// Rays of a finer scan at most: a crescent 8 mm long and 50 micrometres wide holds a few
/// hundred of them at 25 micrometres.
const MAX_FINE_RAYS: f64 = 200_000.0;
/// Contact rays of the first scan from which its centroid is taken as it is: the
/// sampling's error of a region's centroid shrinks with the rays inside it.
const FINE_ENOUGH: usize = 1000;
/// How much finer the second scan of the contact region is than the first.
const REFINE: f64 = 8.0;
/// Clearance between the parts before the sweep, and past each mesh's bounds for rays (m).
const MARGIN: f64 = 1e-3;

/// How a verification samples the map.
#[derive(Debug, Clone, Copy)]
pub struct VerifyOptions {
    /// Cells to check (all of them when the map has fewer).
    pub samples: usize,
    /// Seed of the cell sample and of the rays' offset from the pixel lattice.
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
    /// Distance across the approach from the map's lever point to the exact contact
    /// region's centroid (m): infinite where no ray along the approach sees the contact;
    /// `None` where the map's model does not put the lever at the centroid.
    pub centroid_error: Option<f64>,
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
    /// Share of the cells whose depth is within the contact tolerance.
    pub fn depth_share(&self) -> f64 {
        let within = self
            .checks
            .iter()
            .filter(|c| c.depth_error.abs() <= self.tolerance);
        within.count() as f64 / self.checks.len().max(1) as f64
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
            (c.depth_error.abs() / self.tolerance).max(c.centroid_error.unwrap_or(0.0) / self.pixel)
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
/// rays off the pixel lattice by an offset drawn from `seed`; refuses as [`verify`] does.
pub fn verify_cells(
    map: &FtMap,
    task: &Task,
    [mesh_a, mesh_b]: [&Mesh; 2],
    cells: &[usize],
    seed: u64,
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
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5eed_0ff5);
    // Off the pixel lattice by a random share of a pixel in each direction (never zero).
    let offset = [0, 1].map(|_| 0.1 + 0.8 * (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64);
    let checks = cells
        .par_iter()
        .map(|&cell| parts.check(map, cell, offset))
        .collect::<Result<Vec<_>>>()?;
    Ok(Verification {
        checks,
        tolerance: task.depth.tolerance,
        pixel: task.depth.pixel,
    })
}

/// `opts.samples` distinct cells of `n` (all of them when there are fewer), ascending.
fn sample(n: usize, opts: VerifyOptions) -> Vec<usize> {
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

    /// The exact contact of `cell` against the map's values there; rays `offset` pixels off
    /// the lattice.
    fn check(&self, map: &FtMap, cell: usize, offset: [f64; 2]) -> Result<CellCheck> {
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
        let values = map.cell(cell);
        let depth_error = f64::from(values[NCH - 1]) - (t_obj.dot(&view.w) + rise);
        // A contact that no ray along the approach sees (an edge on a wall) is one the
        // z-buffer cannot see either: the map's lever point is nowhere near it.
        let centroid_error = self.centroid.then(|| {
            let Some((centroid, height)) =
                self.region(&view, &b_pose, rise, offset, [a_range, b_range])
            else {
                return f64::INFINITY;
            };
            let force = r1.inverse() * Vector3::new(values[0], values[1], values[2]).cast::<f64>();
            let torque = r1.inverse() * Vector3::new(values[3], values[4], values[5]).cast::<f64>();
            let sensor = r1.inverse() * (Vector3::from(self.task.contact.sensor_origin) - t_grip);
            // The wrench's line of action, at the contact's height along w.
            let nearest = sensor + force.cross(&torque) / force.norm_squared();
            let along = (height - nearest.dot(&view.w)) / force.dot(&view.w);
            let lever = view.project(&Point3::from(nearest + force * along));
            (lever[0] - centroid[0]).hypot(lever[1] - centroid[1])
        });
        Ok(CellCheck {
            cell,
            coords,
            depth_error,
            centroid_error,
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
    /// along w against B at `b_pose`: the rays along w where the gap is within the contact
    /// tolerance of touching, first at about the pixel over all of A, then [`REFINE`] times
    /// finer over the region they found (a thin crescent's centroid moves with its
    /// sampling).
    fn region(
        &self,
        view: &View,
        b_pose: &Isometry3<f64>,
        rise: f64,
        offset: [f64; 2],
        ranges: [[f64; 2]; 2],
    ) -> Option<([f64; 2], f64)> {
        let a_box = [view.u, view.v].map(|axis| span(&self.pair.a, &Isometry3::identity(), &axis));
        let (lo, hi) = (a_box.map(|r| r[0]), a_box.map(|r| r[1]));
        let rays = Rays {
            parts: self,
            view,
            b_pose,
            rise,
            ranges,
        };
        let coarse = rays.scan([lo, hi], self.task.depth.pixel, offset, MAX_RAYS)?;
        if coarse.rays >= FINE_ENOUGH && (coarse.edge as f64) < EDGE_SHARE * coarse.rays as f64 {
            return Some((coarse.centroid, coarse.height));
        }
        // Few rays, or many on the region's edge (a strip a few rays wide somewhere): the
        // coarse rays miss a crescent's thin tips and a strip's width, so a finer scan, its
        // box growing on every side its region reaches, up to A's own box.
        let [found_lo, found_hi] = coarse.bounds;
        let mut scan_box = [
            [0, 1].map(|k| (found_lo[k] - coarse.pitch).max(lo[k])),
            [0, 1].map(|k| (found_hi[k] + coarse.pitch).min(hi[k])),
        ];
        loop {
            let fine = rays.scan(scan_box, coarse.pitch / REFINE, offset, MAX_FINE_RAYS)?;
            let mut grown = false;
            for k in 0..2 {
                let reach = 0.5 * (scan_box[1][k] - scan_box[0][k]);
                if fine.bounds[0][k] - scan_box[0][k] < 2.0 * fine.pitch && scan_box[0][k] > lo[k] {
                    scan_box[0][k] = (scan_box[0][k] - reach).max(lo[k]);
                    grown = true;
                }
                if scan_box[1][k] - fine.bounds[1][k] < 2.0 * fine.pitch && scan_box[1][k] < hi[k] {
                    scan_box[1][k] = (scan_box[1][k] + reach).min(hi[k]);
                    grown = true;
                }
            }
            if !grown {
                return Some((fine.centroid, fine.height));
            }
        }
    }
}

/// Rays along w through A risen by `rise` and B at `b_pose`.
struct Rays<'a> {
    parts: &'a Parts<'a>,
    view: &'a View,
    b_pose: &'a Isometry3<f64>,
    rise: f64,
    /// A's and B's extent along w.
    ranges: [[f64; 2]; 2],
}

/// What one scan of rays found in contact.
struct Scan {
    /// Rays in contact.
    rays: usize,
    /// The rays' pitch (m).
    pitch: f64,
    /// Mean (u, v) of the contact rays.
    centroid: [f64; 2],
    /// Mean height of A along w at them.
    height: f64,
    /// Lowest and highest (u, v) among them.
    bounds: [[f64; 2]; 2],
    /// Contact rays with a neighbour on the lattice that is not one.
    edge: usize,
}

impl Rays<'_> {
    /// The contact rays on a lattice of `pitch` (at least, so that no more than `max_rays`
    /// are cast) over the (u, v) box `[lo, hi]`, `offset` pitches off the lattice through
    /// the origin; `None` when no ray is in contact.
    fn scan(
        &self,
        [lo, hi]: [[f64; 2]; 2],
        pitch: f64,
        offset: [f64; 2],
        max_rays: f64,
    ) -> Option<Scan> {
        let pitch = pitch.max(((hi[0] - lo[0]) * (hi[1] - lo[1]) / max_rays).sqrt());
        let start = [0, 1].map(|k| ((lo[k] / pitch).floor() + offset[k]) * pitch);
        let steps = [0, 1].map(|k| ((hi[k] - start[k]) / pitch).ceil().max(0.0) as usize + 1);
        let [a_range, b_range] = self.ranges;
        let tolerance = self.parts.task.depth.tolerance;
        let w = self.view.w;
        let (mut n, mut sum) = (0usize, [0.0f64; 3]);
        let mut bounds = [[f64::INFINITY; 2], [f64::NEG_INFINITY; 2]];
        let mut hit = vec![false; steps[0] * steps[1]];
        for i in 0..steps[0] {
            for j in 0..steps[1] {
                let (u, v) = (start[0] + i as f64 * pitch, start[1] + j as f64 * pitch);
                // A's leading surface from below, B's facing one from above.
                let below = self.view.unproject([u, v, a_range[0] - MARGIN]);
                let Some(ta) = self.parts.pair.a.cast_ray(
                    &Isometry3::identity(),
                    &Ray::new(below, w),
                    a_range[1] - a_range[0] + 2.0 * MARGIN,
                    false,
                ) else {
                    continue;
                };
                let above = self.view.unproject([u, v, b_range[1] + MARGIN]);
                let Some(tb) = self.parts.pair.b.cast_ray(
                    self.b_pose,
                    &Ray::new(above, -w),
                    b_range[1] - b_range[0] + 2.0 * MARGIN,
                    false,
                ) else {
                    continue;
                };
                let h_a = a_range[0] - MARGIN + ta + self.rise;
                let h_b = b_range[1] + MARGIN - tb;
                if h_a - h_b <= tolerance {
                    hit[i * steps[1] + j] = true;
                    n += 1;
                    sum[0] += u;
                    sum[1] += v;
                    sum[2] += h_a;
                    bounds = [
                        [bounds[0][0].min(u), bounds[0][1].min(v)],
                        [bounds[1][0].max(u), bounds[1][1].max(v)],
                    ];
                }
            }
        }
        let at = |i: usize, j: usize| i < steps[0] && j < steps[1] && hit[i * steps[1] + j];
        let edge = (0..steps[0])
            .flat_map(|i| (0..steps[1]).map(move |j| (i, j)))
            .filter(|&(i, j)| at(i, j))
            .filter(|&(i, j)| {
                i == 0 || j == 0 || !at(i - 1, j) || !at(i + 1, j) || !at(i, j - 1) || !at(i, j + 1)
            })
            .count();
        (n > 0).then(|| Scan {
            rays: n,
            edge,
            pitch,
            centroid: [sum[0] / n as f64, sum[1] / n as f64],
            height: sum[2] / n as f64,
            bounds,
        })
    }
}
