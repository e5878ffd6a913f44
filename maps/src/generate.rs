//! The FT-Map computation (paper, section II-B): for every rotation cell of Omega, depth
//! images of A along a and of B against a; every translation of B across a is a
//! whole-pixel shift of B's image, translations along a only move the contact depth, and
//! grip translations only move the sensor origin. The contacts of each configuration are
//! reduced by the backend and turned into a wrench by the chosen model.

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rayon::prelude::*;

use crate::depth::cpu::{CpuBackend, InPlace, WholeRows, contact_in_place};
use crate::depth::region::{Flood, Overlay, Planes, exact_contact};
use crate::depth::{
    ContactSummary, DepthBackend, DepthImage, PixelWindow, RenderJob, Shift, Surface, View,
    weigh_outline,
};
use crate::error::{MapError, Result};
use crate::exact::Pair;
use crate::map::{FtMap, MapMeta, NCH, SourceMesh};
use crate::mesh::Mesh;
use crate::task::Task;
use crate::task::dof::{Axis, Pose};
use crate::task::fit::{Fit, MeshFit, rotational_play};
use crate::task::omega::{Grid, MAX_AXES};
use crate::wrench::WrenchModel;
use crate::wrench::WrenchSetup;

/// Choices of a map computation.
#[derive(Debug, Clone, Copy)]
pub struct GenerateOptions {
    /// The wrench model.
    pub model: WrenchModel,
    /// `Some([i, n])`: compute only rotation cells r with r % n == i (cells of the other
    /// shards stay NaN; `merge` joins the shards).
    pub shard: Option<[usize; 2]>,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        Self {
            model: WrenchModel::Centroid,
            shard: None,
        }
    }
}

/// What kind of work an axis of Omega causes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    /// A rotation: needs new depth images.
    Render,
    /// A translation of the object: a shift of B's image (across a) or of the depth (along a).
    Shift,
    /// A translation of the grip: moves the sensor origin only.
    Sensor,
}

fn role(pose: Pose, axis: Axis) -> Role {
    match (pose, axis.is_rotation()) {
        (_, true) => Role::Render,
        (Pose::Object, false) => Role::Shift,
        (Pose::Grip, false) => Role::Sensor,
    }
}

/// Enumerates the sub-grid of some axes: the per-axis sample indices of its `k`-th cell.
struct SubGrid {
    axes: Vec<usize>,
    counts: Vec<usize>,
    len: usize,
}

impl SubGrid {
    fn new(grid: &Grid, pick: impl Fn(Role) -> bool) -> Self {
        let axes: Vec<usize> = (0..grid.ndim())
            .filter(|&k| pick(role(grid.axes()[k].dof.pose, grid.axes()[k].dof.axis)))
            .collect();
        let counts: Vec<usize> = axes.iter().map(|&k| grid.axes()[k].count).collect();
        let len = counts.iter().product();
        Self { axes, counts, len }
    }

    /// Writes the sample indices of sub-cell `k` into the full index vector `idx`.
    fn fill(&self, mut k: usize, idx: &mut [usize]) {
        for (&axis, &count) in self.axes.iter().zip(&self.counts).rev() {
            idx[axis] = k % count;
            k /= count;
        }
    }
}

/// The twelve pose values (grip x..rz, object x..rz) of a cell.
pub(crate) fn pose_values(grid: &Grid, idx: &[usize]) -> [f64; 12] {
    let mut v = [0.0; 12];
    for (k, a) in grid.axes().iter().enumerate() {
        v[a.dof.index()] = a.value(idx[k]);
    }
    v
}

/// A rotation from three rotation-vector components.
pub(crate) fn rotation(r: &[f64]) -> Rotation3<f64> {
    Rotation3::new(Vector3::new(r[0], r[1], r[2]))
}

/// Computes the FT-Map of `task` with `backend`; `progress` is called with the number of
/// configurations finished since its last call.
pub fn generate(
    task: &Task,
    backend: &dyn DepthBackend,
    opts: &GenerateOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<FtMap> {
    let mesh_a = task.part_a.load()?;
    let mesh_b = task.part_b.load()?;
    generate_with(task, &mesh_a, &mesh_b, backend, opts, progress)
}

/// Revision of what a computed map holds, part of the cache key: raise it when a change
/// to the generator changes the maps (2: the clearance in the metadata; 3: the symmetry;
/// 4: thin contact regions at a finer pixel; 5: thin by mean width too; 6: the object's
/// translations out to `omega.reach`; 7: the fit's rotational play in the metadata; 8:
/// thin regions refined on tilted parts too; 9: thin by the share of edge pixels too; 10:
/// pixel centres within a thousandth of a pixel of a slanted edge covered; 11: pixels on
/// the parts' outlines counted by the share of them covered; 12: the tips of tilted parts'
/// contacts computed exactly; 13: and their regions in pieces; 14: every thin region of
/// tilted parts computed exactly; 15: and grown from where the two parts' rims cross too).
const MAP_REVISION: u32 = 15;

/// The FT-Map of `task` (CPU backend, default options) from the cache folder `dir`, where
/// it is kept under the hash of the task file, its meshes, this crate's version and
/// [`MAP_REVISION`];
/// computed and stored when missing or unreadable (once, when threads ask together).
/// Returns the file and whether it was computed now.
///
/// # Errors
/// When the task's files cannot be read, the map cannot be computed or stored.
pub fn cached(task: &Task, dir: &Path) -> Result<(PathBuf, bool)> {
    cached_as(task, task, "", dir)
}

/// The centre map ([`crate::map::centre`]) of `task`, whose map is `map`, from the cache
/// folder `dir` like [`cached`] (file `<task>-<hash>.centre.ftmap`); `None` where the map's
/// grid resolves the fit.
///
/// # Errors
/// As [`cached`].
pub fn cached_centre(task: &Task, map: &FtMap, dir: &Path) -> Result<Option<(PathBuf, bool)>> {
    match crate::map::centre::centre_task(task, map.grid(), map.meta().clearance)? {
        Some(centre) => cached_as(&centre, task, ".centre", dir).map(Some),
        None => Ok(None),
    }
}

/// The map of `computed` cached under the files of `task` and `suffix` in `dir`.
fn cached_as(computed: &Task, task: &Task, suffix: &str, dir: &Path) -> Result<(PathBuf, bool)> {
    let hash = crate::file::cache_hash(
        &[&task.path, &task.part_a.mesh, &task.part_b.mesh],
        &[&MAP_REVISION.to_le_bytes(), suffix.as_bytes()],
    )?;
    let path = dir.join(format!("{}-{hash}{suffix}.ftmap", task.name));
    // Threads of one process wanting a missing map wait for the first to compute it.
    static COMPUTING: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _computing = COMPUTING
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if path.is_file() && crate::map::format::load(&path).is_ok() {
        return Ok((path, false));
    }
    std::fs::create_dir_all(dir).map_err(MapError::io(dir))?;
    let map = generate(computed, &CpuBackend, &GenerateOptions::default(), &|_| {})?;
    crate::map::format::save(&map, &path)?;
    Ok((path, true))
}

/// Computes the FT-Map of `task` for given meshes of A and B (instead of its mesh files).
pub fn generate_with(
    task: &Task,
    mesh_a: &Mesh,
    mesh_b: &Mesh,
    backend: &dyn DepthBackend,
    opts: &GenerateOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<FtMap> {
    if !opts.model.is_computed() {
        return Err(MapError::Geometry(
            "measured and blended maps come from contact motions (`harness scan`, `ftmap blend`), not from CAD: use --model paper or centroid".into(),
        ));
    }
    let grid = task.grid()?;
    let pair = Pair::new(mesh_a, mesh_b).ok();
    let meta = MapMeta {
        task: task.name.clone(),
        model: opts.model,
        approach: task.contact.approach,
        force: task.contact.force,
        friction: task.contact.friction,
        sensor_origin: task.contact.sensor_origin,
        pixel: task.depth.pixel,
        sources: [
            ("A", mesh_a, &task.part_a.mesh),
            ("B", mesh_b, &task.part_b.mesh),
        ]
        .into_iter()
        .map(|(role, m, p)| SourceMesh {
            role: role.into(),
            file: p
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default(),
            sha256: m.sha256.clone(),
        })
        .collect(),
        generator: format!("ftmap {} ({})", env!("CARGO_PKG_VERSION"), backend.name()),
        clearance: match (&task.geometry, &pair) {
            (Some(g), _) => Some(g.clearance()),
            // A fit that cannot be measured (parts not in a fit) is no reason to refuse a map.
            (None, Some(pair)) => MeshFit::measure(task, pair).ok().map(|f| f.clearance()),
            (None, None) => None,
        },
        symmetry: task.omega.symmetry,
        play: pair
            .as_ref()
            .and_then(|pair| measured_play(task, &grid, pair)),
    };
    let mut map = FtMap::zeros(grid.clone(), meta);
    if let Some([i, n]) = opts.shard {
        if n == 0 || i >= n {
            return Err(MapError::Grid(format!(
                "shard {i}/{n}: need n >= 1 and 0 <= i < n"
            )));
        }
        map.data_mut().fill(f32::NAN);
    }
    let render_axes = SubGrid::new(&grid, |r| r == Role::Render);
    let other_axes = SubGrid::new(&grid, |r| r != Role::Render);
    let [shard_i, shard_n] = opts.shard.unwrap_or([0, 1]);
    let ctx = Context {
        task,
        backend,
        grid: &grid,
        mesh_a,
        mesh_b,
        model: opts.model,
    };
    // Rotation cells on every core, each written into the map as soon as it is done: a
    // cell's renders are serial and its contacts parallel, so that together they keep every
    // core busy, and only the cells in progress are held.
    let rot_cells: Vec<usize> = (0..render_axes.len)
        .filter(|r| r % shard_n == shard_i)
        .collect();
    let done = std::sync::Mutex::new(&mut map);
    rot_cells.par_iter().try_for_each(|&rot_cell| {
        let mut idx = [0usize; MAX_AXES];
        render_axes.fill(rot_cell, &mut idx);
        let values = ctx.rotation_cell(&idx, &other_axes, progress)?;
        // Poisoned only by another cell's panic, which rayon passes on.
        let mut map = done
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        for (cell, values) in values {
            *map.cell_mut(cell) = values;
        }
        Ok(())
    })?;
    Ok(map)
}

/// What every rotation cell of one computation shares.
struct Context<'a> {
    task: &'a Task,
    backend: &'a dyn DepthBackend,
    grid: &'a Grid,
    mesh_a: &'a Mesh,
    mesh_b: &'a Mesh,
    model: WrenchModel,
}

impl Context<'_> {
    /// All cells sharing the rotations in `rot_idx`: (flat cell, channels).
    fn rotation_cell(
        &self,
        rot_idx: &[usize; MAX_AXES],
        others: &SubGrid,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Vec<(usize, [f32; NCH])>> {
        let pixel = self.task.depth.pixel;
        let pose = pose_values(self.grid, rot_idx);
        let r1 = rotation(&pose[3..6]);
        let r2 = rotation(&pose[9..12]);
        let a0 = Vector3::from(self.task.contact.approach);
        let view = View::along(r1.inverse() * a0);

        // Every other cell: its object translation as a shift and depth offset, its grip translation.
        let cells: Vec<([usize; MAX_AXES], Shift, f64, Vector3<f64>)> = (0..others.len)
            .map(|k| {
                let mut idx = *rot_idx;
                others.fill(k, &mut idx);
                let v = pose_values(self.grid, &idx);
                let [tu, tv, tw] = view.project(&Point3::new(v[6], v[7], v[8]));
                let shift = Shift {
                    du: (tu / pixel).round() as i64,
                    dv: (tv / pixel).round() as i64,
                };
                (idx, shift, tw, Vector3::new(v[0], v[1], v[2]))
            })
            .collect();
        let mut shifts: Vec<Shift> = cells.iter().map(|c| c.1).collect();
        shifts.sort_by_key(|s| (s.du, s.dv));
        shifts.dedup();
        let reach_u = shifts.iter().map(|s| s.du.abs()).max().unwrap_or(0);
        let reach_v = shifts.iter().map(|s| s.dv.abs()).max().unwrap_or(0);

        let bounds = |m: &Mesh, iso: &Isometry3<f64>| {
            let mut b = [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ];
            for p in &m.vertices {
                let [u, v, _] = view.project(&(iso * p));
                b = [b[0].min(u), b[1].max(u), b[2].min(v), b[3].max(v)];
            }
            b
        };
        let a_pose = Isometry3::identity();
        let b_pose = Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_rotation_matrix(&r2),
        );
        let [u0, u1, v0, v1] = bounds(self.mesh_a, &a_pose);
        let mut a_win = PixelWindow::covering(u0, u1, v0, v1, pixel, 1);
        a_win.width = a_win.width.next_multiple_of(8); // whole vector lanes per row
        let b_win = PixelWindow {
            i0: a_win.i0 - reach_u,
            j0: a_win.j0 - reach_v,
            width: a_win.width + 2 * reach_u as usize,
            height: a_win.height + 2 * reach_v as usize,
        };
        let job = |mesh, pose, surface, window| RenderJob {
            mesh,
            pose,
            view,
            surface,
            window,
            pixel,
        };
        let a_img = self
            .backend
            .render(&job(self.mesh_a, a_pose, Surface::Bottom, a_win))?;
        let b_img = self
            .backend
            .render(&job(self.mesh_b, b_pose, Surface::Top, b_win))?;
        let b_normals: Vec<[f32; 3]> = (0..self.mesh_b.faces.len())
            .map(|t| {
                let n = r2 * self.mesh_b.normal(t);
                [
                    n.dot(&view.u) as f32,
                    n.dot(&view.v) as f32,
                    n.dot(&view.w) as f32,
                ]
            })
            .collect();
        let tolerance = self.task.depth.tolerance as f32;
        let summaries = self
            .backend
            .contacts(&a_img, &b_img, &b_normals, &shifts, tolerance)?;

        let setup = WrenchSetup {
            view,
            origin: (a_win.i0, a_win.j0),
            pixel,
            force: self.task.contact.force,
            friction: self.task.contact.friction,
        };
        // Thin contact regions again, over their own extent: where the faces stay parallel
        // (the rotations turn the parts about the approach alone), a crescent along a rim at
        // a finer pixel; where they do not, exactly ([`exact_contact`], from the coarse
        // contact's pixels): a band the contact tolerance draws across the tilt (2 um across
        // 2 degrees: 57 um, under the pixel), the tip of the lens where part A's rim crosses
        // the edge of B's hole, caps millimetres apart where the two rims cross at nearly one
        // height. A few coarse or finer pixels sample such a region; their centroid strays
        // from the region's by up to a few pixels, their least gap from its own by up to
        // 17 um at a 2 um tolerance (`ftmap verify`).
        let level = [r1 * a0, r2 * a0].iter().all(|a| (a - a0).norm() < 1e-9);
        let thin = |c: &ContactSummary| {
            c.count > 0
                && (c.count < THIN || c.mean_width() < THIN_WIDTH || c.edge_share() >= THIN_EDGES)
        };
        let exact: Vec<bool> = summaries.iter().map(|c| !level && thin(c)).collect();
        let windows: Vec<Option<[PixelWindow; 2]>> = (shifts.iter().zip(&summaries))
            .map(|(shift, c)| (level && thin(c)).then(|| Fine::windows(c, *shift, &setup, REFINE)))
            .collect();
        let poses = [a_pose, b_pose];
        let fine = Fine::render(self, view, poses, &windows, pixel, REFINE, &b_normals)?;
        // Filled in place (every shift's slot known beforehand): a collection of unknown
        // length would grow by copies, a large part of a map's time. Each thin region of
        // level parts is reduced again at the finer pixel where it finds a contact there;
        // the others' outline pixels are weighed here ([`weigh_outline`]), but for the thin
        // regions of tilted parts, whose coarse contact seeds their exact one below.
        let mut contacts: Vec<(ContactSummary, WrenchSetup)> =
            summaries.into_iter().map(|c| (c, setup)).collect();
        let (a_whole, b_whole) = (a_img.whole(), b_img.whole());
        (contacts
            .par_iter_mut()
            .zip(&exact)
            .zip(&shifts)
            .zip(&windows))
        .filter(|(((_, exact), _), _)| !**exact)
        .for_each_init(InPlace::default, |scratch, (((slot, _), shift), w)| {
            let finer = (fine.as_ref().zip(w.as_ref()))
                .and_then(|(f, w)| f.contact(*shift, w, &setup, &b_normals, scratch));
            match finer {
                Some(finer) => *slot = finer,
                None => {
                    weigh_outline(&mut slot.0, a_whole, b_whole, &b_normals, *shift, tolerance);
                }
            }
        });
        if exact.contains(&true) {
            let planes = [
                Planes::of(&job(self.mesh_a, a_pose, Surface::Bottom, a_win), &a_img),
                Planes::of(&job(self.mesh_b, b_pose, Surface::Top, b_win), &b_img),
            ];
            let overlay = Overlay {
                a: &planes[0],
                b: &planes[1],
                b_normals: &b_normals,
            };
            (contacts.par_iter_mut().zip(&exact).zip(&shifts))
                .filter(|((_, exact), _)| **exact)
                .for_each_init(
                    Flood::default,
                    |flood, (((c, _), _), shift)| match exact_contact(
                        &overlay, *shift, c, tolerance, flood,
                    ) {
                        Some(exact) => *c = exact,
                        None => weigh_outline(c, a_whole, b_whole, &b_normals, *shift, tolerance),
                    },
                );
        }
        let s0 = Point3::from(self.task.contact.sensor_origin);
        let mut out = vec![(0, [0.0; NCH]); cells.len()];
        (out.par_iter_mut().zip(&cells)).try_for_each(|(slot, (idx, shift, tw, t1))| {
            let k = shifts
                .binary_search_by_key(&(shift.du, shift.dv), |s| (s.du, s.dv))
                .expect("every shift is listed");
            let (c, setup) = &contacts[k];
            let sensor = Point3::from(r1.inverse() * (s0 - t1).coords);
            let cell = self.grid.flat(&idx[..self.grid.ndim()]);
            let w = setup.wrench(c, self.model, &sensor).ok_or_else(|| {
                MapError::Geometry(format!(
                    "part A misses part B at cell {:?}: enlarge part B or shrink Omega",
                    self.grid.coords(cell)
                ))
            })?;
            let (f, t) = (r1 * w.force, r1 * w.torque);
            let depth = tw - f64::from(c.gap);
            *slot = (
                cell,
                [f.x, f.y, f.z, t.x, t.y, t.z, depth].map(|x| x as f32),
            );
            Ok(())
        })?;
        progress(out.len() as u64);
        Ok(out)
    }
}

/// A contact region of fewer pixels than this, narrower than [`THIN_WIDTH`], or with
/// [`THIN_EDGES`] of its pixels on its edges, is computed again, [`REFINE`] times finer
/// (exactly where the parts are tilted against each other): a crescent thinner than a
/// pixel (part A resting on the rim just off the hole) is sampled by a few pixels along
/// it, and their centroid strays from the region's by up to a few pixels (`ftmap verify`).
const THIN: u32 = 200;
/// Mean width (pixels, [`ContactSummary::mean_width`]) below which a region is thin
/// however many pixels it has (a crescent along a wide rim).
const THIN_WIDTH: f64 = 2.0;
/// Share of a region's pixels on its edges across the rows ([`ContactSummary::edge_share`])
/// from which it is thin however many pixels it has and however wide it is on average: a
/// strip a few pixels wide along a flat, beside wider strips on other flats (part A resting
/// on two or three sides of a square or octagonal hole), whose edges put a pixel more or
/// less of its width in, is a large share; a square 10 pixels across, a fifth (`ftmap
/// verify` on octagon: 99.4 % of 1000 cells within a pixel without this test, 99.9 % with
/// it).
const THIN_EDGES: f64 = 0.25;
/// How much finer a thin region's pixel is where the faces stay parallel.
const REFINE: i64 = 4;
/// Coarse pixels around a thin region's contact pixels that its finer images cover.
const REFINE_MARGIN: i64 = 2;

/// The finer images of a rotation cell's thin contact regions: A and B rendered once
/// [`REFINE`] times finer over the union of every thin region's windows by the backend,
/// each region then reduced on the CPU over its own part of them (the pixels a render of
/// its windows alone gives).
struct Fine<'a> {
    ctx: &'a Context<'a>,
    /// How much finer than the coarse pixel its pixel is.
    refine: i64,
    a: DepthImage,
    b: DepthImage,
    /// What holds of their whole rows.
    rows: WholeRows,
}

impl<'a> Fine<'a> {
    /// The finer windows of A and B for the contact `c` of B at `shift`: the box of its
    /// contact pixels grown by [`REFINE_MARGIN`] coarse pixels, and B's under it at the
    /// shift.
    fn windows(
        c: &ContactSummary,
        shift: Shift,
        coarse: &WrenchSetup,
        refine: i64,
    ) -> [PixelWindow; 2] {
        let (rows, cols) = c.rows.iter().fold(
            ([u32::MAX, 0], [u32::MAX, 0]),
            |(r, k), &(row, first, last)| {
                (
                    [r[0].min(row), r[1].max(row)],
                    [k[0].min(first), k[1].max(last)],
                )
            },
        );
        let (i0, j0) = coarse.origin;
        let lo = |origin: i64, first: u32| (origin + i64::from(first) - REFINE_MARGIN) * refine;
        let span = |range: [u32; 2]| {
            ((i64::from(range[1] - range[0]) + 2 * REFINE_MARGIN + 1) * refine) as usize
        };
        let a = PixelWindow {
            i0: lo(i0, cols[0]),
            j0: lo(j0, rows[0]),
            width: span(cols).next_multiple_of(8),
            height: span(rows),
        };
        // B's pixels under A's at the shift: the only ones its reduction reads.
        let b = PixelWindow {
            i0: a.i0 - shift.du * refine,
            j0: a.j0 - shift.dv * refine,
            ..a
        };
        [a, b]
    }

    /// A and B (at `poses`; B's normals `b_normals`) rendered `refine` times finer than
    /// `coarse_pixel` over the union of `windows`; `None` where no region is thin.
    fn render(
        ctx: &'a Context<'a>,
        view: View,
        poses: [Isometry3<f64>; 2],
        windows: &[Option<[PixelWindow; 2]>],
        coarse_pixel: f64,
        refine: i64,
        b_normals: &[[f32; 3]],
    ) -> Result<Option<Self>> {
        let Some(union) = windows
            .iter()
            .flatten()
            .copied()
            .reduce(|u, w| [u[0].union(&w[0]), u[1].union(&w[1])])
        else {
            return Ok(None);
        };
        let job = |mesh, pose, surface, window| RenderJob {
            mesh,
            pose,
            view,
            surface,
            window,
            pixel: coarse_pixel / refine as f64,
        };
        let a = ctx
            .backend
            .render(&job(ctx.mesh_a, poses[0], Surface::Bottom, union[0]))?;
        let b = ctx
            .backend
            .render(&job(ctx.mesh_b, poses[1], Surface::Top, union[1]))?;
        Ok(Some(Self {
            ctx,
            refine,
            rows: WholeRows::of(&a, &b, b_normals),
            a,
            b,
        }))
    }

    /// The contact of B at `shift` again at the finer pixel over its `windows` (its outline
    /// pixels weighed, [`weigh_outline`]), with the setup of that finer image, made from
    /// the coarse image's `coarse`; `None` where the finer images find no contact.
    fn contact(
        &self,
        shift: Shift,
        windows: &[PixelWindow; 2],
        coarse: &WrenchSetup,
        b_normals: &[[f32; 3]],
        scratch: &mut InPlace,
    ) -> Option<(ContactSummary, WrenchSetup)> {
        let [a_win, b_win] = *windows;
        let shift = Shift {
            du: shift.du * self.refine,
            dv: shift.dv * self.refine,
        };
        let setup = WrenchSetup {
            origin: (a_win.i0, a_win.j0),
            pixel: coarse.pixel / self.refine as f64,
            ..*coarse
        };
        let tolerance = self.ctx.task.depth.tolerance as f32;
        // On the CPU whatever the backend, in place: each region is one small window of the
        // finer images, for which a GPU dispatch (and on lavapipe its setup) costs far more
        // than the reduction itself.
        let (a, b) = (self.a.patch(a_win), self.b.patch(b_win));
        let mut fine = contact_in_place(a, b, &self.rows, b_normals, shift, tolerance, scratch);
        weigh_outline(&mut fine, a, b, b_normals, shift, tolerance);
        (fine.count > 0).then_some((fine, setup))
    }
}

/// The fit's rotational play ([`rotational_play`]) about each of x, y, z that `grid`
/// samples as an object rotation (0 on the others, and where the part turns freely);
/// `None` where it samples none or none is measured.
fn measured_play(task: &Task, grid: &Grid, pair: &Pair) -> Option<[f64; 3]> {
    let mut play = [0.0; 3];
    for a in grid.axes() {
        if a.count > 1 && a.dof.pose == Pose::Object && a.dof.axis.is_rotation() {
            let k = a.dof.axis.index() - 3;
            play[k] = rotational_play(pair, task.contact.approach.into(), Vector3::ith(k, 1.0))
                .unwrap_or(0.0);
        }
    }
    play.iter().any(|&p| p > 0.0).then_some(play)
}

/// Number of configurations a computation (or shard `[i, n]` of it) computes.
pub fn shard_configs(grid: &Grid, shard: Option<[usize; 2]>) -> usize {
    let rotations = SubGrid::new(grid, |r| r == Role::Render).len;
    let [i, n] = shard.unwrap_or([0, 1]);
    let own = if i < n {
        rotations / n + usize::from(i < rotations % n)
    } else {
        0
    };
    own * (grid.cells() / rotations.max(1))
}

/// Joins shard maps of one computation into the whole map; every shard 0..n exactly once.
pub fn merge(parts: Vec<(FtMap, [usize; 2])>) -> Result<FtMap> {
    let mut parts = parts.into_iter();
    let (mut map, [i0, n]) = parts
        .next()
        .ok_or_else(|| MapError::Grid("merge: no shard given".into()))?;
    let mut seen = vec![false; n];
    seen[i0] = true;
    for (part, [i, m]) in parts {
        if m != n
            || part.grid() != map.grid()
            || part.meta().task != map.meta().task
            || part.meta().model != map.meta().model
        {
            return Err(MapError::Grid(format!(
                "merge: shard {i}/{m} of task {} does not belong with shard {i0}/{n} of task {}",
                part.meta().task,
                map.meta().task
            )));
        }
        if std::mem::replace(&mut seen[i], true) {
            return Err(MapError::Grid(format!("merge: shard {i}/{n} given twice")));
        }
        for (dst, src) in map.data_mut().iter_mut().zip(part.data()) {
            if !src.is_nan() {
                *dst = *src;
            }
        }
    }
    if let Some(missing) = seen.iter().position(|s| !s) {
        return Err(MapError::Grid(format!(
            "merge: shard {missing}/{n} is missing"
        )));
    }
    if map.data().iter().any(|v| v.is_nan()) {
        return Err(MapError::Grid(
            "merge: some cells were computed by no shard".into(),
        ));
    }
    Ok(map)
}
