//! A task from two meshes (`ftmap task new`): the meshes copied into the task's folder and
//! a `task.toml` beside them whose settings come from the geometry: the sensor above part
//! A, Omega as wide as part A or part B's top, the pixel from the fit's clearance measured with parry.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Translation3, Vector3};
use parry3d_f64::query;

use crate::depth::View;
use crate::error::{MapError, Result};
use crate::exact::{Pair, span};
use crate::map::resolution::SLACK;
use crate::mesh::Mesh;
use crate::task::fit::{Fit, MeshFit};
use crate::task::{Task, Units};

/// The sensor sits this far above part A's highest point (m).
const SENSOR_ABOVE: f64 = 0.02;
/// Omega's translational bound is part A's half-width, or the radius of part B's highest
/// level where that is less, rounded up to this (m).
const SIZE_ROUNDING: f64 = 0.0005;
/// Omega's translational step unless the pixel is wider (m).
const STEP: f64 = 0.0001;
/// A fit whose insertion limit varies with direction by more than this (largest over
/// smallest) has flats facing each other across it: a meshed circle's facets vary it by a
/// fraction of a percent.
const FLATS: f64 = 1.02;
/// The contact tolerance at most (m); half a pixel when that is less.
const TOLERANCE: f64 = 0.00002;
/// Part A is checked clear of part B this far above its seat at the goal (m).
const SEAT_LIFT: f64 = 1e-5;

/// What `ftmap task new` is given.
#[derive(Debug, Clone)]
pub struct NewTask {
    /// Part A's STL (gripped, its frame the task frame).
    pub part_a: PathBuf,
    /// Part B's STL (fixed, its frame the goal frame; at the goal both frames coincide).
    pub part_b: PathBuf,
    /// The STLs' length unit.
    pub units: Units,
    /// The task's folder (created); its name is the task's name.
    pub out: PathBuf,
    /// Approach vector (default -z).
    pub approach: [f64; 3],
    /// Imposed force (N).
    pub force: f64,
    /// Friction coefficient.
    pub friction: f64,
    /// Omega's translational bound (m); default from part A's width.
    pub size: Option<f64>,
}

/// The largest of 1, 2, 5 times a power of ten at or below `x` (within the resolution
/// check's slack: a meshed circle's facets shave the clearance by a fraction of a percent).
fn nice_below(x: f64) -> f64 {
    let decade = 10f64.powf((x * (1.0 + SLACK)).log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|&v| v <= x * (1.0 + SLACK))
        .unwrap_or(decade)
}

/// The pixel for a fit of radial `clearance` (m) whose insertion limit varies with direction
/// by `anisotropy` (its largest over its smallest): the largest of 1, 2, 5 times a power of
/// ten at or below the grid's step and the fit's diametral gap (see `map::resolution`), or
/// half its radial clearance where flats face each other across the fit (`anisotropy` above
/// [`FLATS`]). Along a flat, part A rests on a straight strip as thin as the offset less the
/// clearance, and a strip thinner than a pixel reads a whole pixel wide or none: on a square
/// peg 0.06 mm into its hole at a 0.1 mm pixel the map's torque missed MuJoCo's by up to
/// 18 degrees near the hole and the spread held the truth 63 % of the time within 2 sigma;
/// at 0.02 mm, 74 % (docs/RESULTS.md).
fn pixel_for(clearance: f64, anisotropy: f64) -> f64 {
    let across = if anisotropy > FLATS {
        0.5 * clearance
    } else {
        2.0 * clearance
    };
    nice_below(across.min(STEP))
}

/// Writes the task folder of `spec`; the loaded task and its fit.
///
/// # Errors
/// When a mesh is refused ([`Mesh::load_scaled`]), the parts overlap at the goal or part A
/// does not sit in a fit of part B there, or the folder cannot be written.
pub fn create(spec: &NewTask) -> Result<(Task, MeshFit)> {
    let scale = spec.units.metres();
    let (mesh_a, mesh_b) = (
        Mesh::load_scaled(&spec.part_a, scale)?,
        Mesh::load_scaled(&spec.part_b, scale)?,
    );
    let name = spec
        .out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .filter(|n| !n.is_empty())
        .ok_or_else(|| MapError::Geometry(format!("{}: not a folder name", spec.out.display())))?;
    let a = Vector3::from(spec.approach);
    if !(a.norm() > 1e-9 && a.iter().all(|c| c.is_finite())) {
        return Err(MapError::Geometry(format!(
            "approach {:?} is not a direction",
            spec.approach
        )));
    }
    let view = View::along(a);
    let pair = Pair::new(&mesh_a, &mesh_b)?;
    let seated = Isometry3::from(Translation3::from(view.w * SEAT_LIFT));
    if query::intersection_test(&seated, &pair.a, &Isometry3::identity(), &pair.b).unwrap_or(false)
    {
        return Err(MapError::Geometry(format!(
            "{} and {} overlap with part A {} µm above the goal: export both parts in the assembly's coordinates (part A where it sits when assembled), or part A's frame on part B's",
            spec.part_a.display(),
            spec.part_b.display(),
            SEAT_LIFT * 1e6
        )));
    }
    let half_width = [view.u, view.v]
        .map(|axis| {
            let [lo, hi] = span(&pair.a, &Isometry3::identity(), &axis);
            lo.abs().max(hi.abs())
        })
        .into_iter()
        .fold(0.0, f64::max);
    // Where part B's highest level lies (the hole's rim, the shaft's or seat's top): part
    // A over it touches the feature that the fit is about.
    let coords = |v: &nalgebra::Point3<f64>| view.project(v);
    let highest = mesh_b
        .vertices
        .iter()
        .map(|v| coords(v)[2])
        .fold(f64::NEG_INFINITY, f64::max);
    let top_width = mesh_b
        .vertices
        .iter()
        .map(coords)
        .filter(|c| highest - c[2] <= 1e-9)
        .map(|c| c[0].hypot(c[1]))
        .fold(0.0, f64::max);
    let size = spec
        .size
        .unwrap_or((half_width.min(top_width) / SIZE_ROUNDING - 1e-9).ceil() * SIZE_ROUNDING);
    let top_a = span(&pair.a, &Isometry3::identity(), &view.w)[1];
    // To the micrometre: the meshes' single precision is no part of the design.
    let sensor = (view.w * (top_a + SENSOR_ABOVE)).map(|c| (c * 1e6).round() / 1e6 + 0.0);
    std::fs::create_dir_all(&spec.out).map_err(MapError::io(&spec.out))?;
    let file = |p: &Path, fallback: &str| {
        p.file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_else(|| fallback.into())
    };
    let (mut file_a, mut file_b) = (
        file(&spec.part_a, "part_a.stl"),
        file(&spec.part_b, "part_b.stl"),
    );
    if file_a == file_b {
        (file_a, file_b) = (format!("part_a_{file_a}"), format!("part_b_{file_b}"));
    }
    for (from, to) in [(&spec.part_a, &file_a), (&spec.part_b, &file_b)] {
        let to = spec.out.join(to);
        if std::fs::canonicalize(from).ok() != std::fs::canonicalize(&to).ok() {
            std::fs::copy(from, &to).map_err(MapError::io(&to))?;
        }
    }
    // A first draft with a provisional pixel, to measure the fit the pixel follows.
    let draft = |pixel: f64| {
        let step = STEP.max(pixel);
        text(&Draft {
            name: &name,
            files: [&file_a, &file_b],
            units: spec.units,
            approach: a.normalize(),
            force: spec.force,
            friction: spec.friction,
            sensor: [sensor.x, sensor.y, sensor.z],
            // A whole number of steps, to the nanometre (no 0.011000000000000001).
            size: ((size / step).round().max(1.0) * step * 1e9).round() / 1e9,
            step,
            pixel,
            tolerance: TOLERANCE.min(pixel / 2.0),
        })
    };
    let path = spec.out.join("task.toml");
    let write = |text: String| std::fs::write(&path, text).map_err(MapError::io(&path));
    write(draft(STEP))?;
    let fit = MeshFit::measure(&Task::load(&path)?, &pair)?;
    let clearance = fit.clearance();
    if clearance <= 0.0 {
        return Err(MapError::Geometry(format!(
            "part A does not fit part B: no clearance at the goal ({:.2} µm)",
            clearance * 1e6
        )));
    }
    write(draft(pixel_for(clearance, fit.anisotropy())))?;
    Ok((Task::load(&path)?, fit))
}

/// The values of a task file.
struct Draft<'a> {
    name: &'a str,
    files: [&'a str; 2],
    units: Units,
    approach: Vector3<f64>,
    force: f64,
    friction: f64,
    sensor: [f64; 3],
    size: f64,
    step: f64,
    pixel: f64,
    tolerance: f64,
}

/// The task file's text, every value commented.
fn text(d: &Draft) -> String {
    let mm = |v: f64| {
        format!("{:.4}", v * 1e3)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_owned()
    };
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# Written by `ftmap task new` from two meshes. SI units (m, rad, N); edit freely."
    );
    let _ = writeln!(t, "name = \"{}\"", d.name);
    let _ = writeln!(t, "description = \"{} into {}\"", d.files[0], d.files[1]);
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "# Active part A, gripped: its frame is the task frame (the TCP)."
    );
    let _ = writeln!(
        t,
        "[part_a]\nmesh = \"{}\"\nunits = \"{}\"",
        d.files[0],
        d.units.name()
    );
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "# Passive part B, fixed: its frame is the goal frame; assembled, both frames coincide."
    );
    let _ = writeln!(
        t,
        "[part_b]\nmesh = \"{}\"\nunits = \"{}\"",
        d.files[1],
        d.units.name()
    );
    let _ = writeln!(t);
    let _ = writeln!(t, "[contact]");
    let _ = writeln!(
        t,
        "approach = [{:?}, {:?}, {:?}] # the direction part A moves in to assemble (task frame)",
        d.approach.x, d.approach.y, d.approach.z
    );
    let _ = writeln!(
        t,
        "force = {:?} # N, pressed along the approach at each contact",
        d.force
    );
    let _ = writeln!(t, "friction = {:?} # between the parts", d.friction);
    let _ = writeln!(
        t,
        "sensor_origin = [{:?}, {:?}, {:?}] # the F/T sensor, {} mm above part A's highest point",
        d.sensor[0],
        d.sensor[1],
        d.sensor[2],
        mm(SENSOR_ABOVE)
    );
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "# The tolerance space: where part B may lie relative to the TCP."
    );
    let _ = writeln!(t, "[omega]\ngrip = []\nobject = [\"x\", \"y\"]");
    let _ = writeln!(
        t,
        "size_trans = {:?} # ± {} mm: part A's half-width, or part B's top's where less",
        d.size,
        mm(d.size)
    );
    let _ = writeln!(
        t,
        "delta_trans = {:?} # {} mm grid step",
        d.step,
        mm(d.step)
    );
    let _ = writeln!(t);
    let _ = writeln!(t, "[depth]");
    let _ = writeln!(
        t,
        "pixel = {:?} # {} mm: resolves the fit's diametral gap (twice the clearance measured on the meshes), or half the clearance where flats face each other across the fit",
        d.pixel,
        mm(d.pixel)
    );
    let _ = writeln!(
        t,
        "tolerance = {:?} # {} mm: pixels this close to touching are in contact",
        d.tolerance,
        mm(d.tolerance)
    );
    let _ = writeln!(t);
    let _ = writeln!(
        t,
        "# [scene]\n# bed_pitch = 0.001 # m: a coarser sphere bed under part A in the harness's scene steps faster and presses less evenly; `harness bench` prints both"
    );
    t
}

#[cfg(test)]
mod tests {
    use super::{nice_below, pixel_for};

    #[test]
    fn flats_across_the_fit_halve_the_clearance_the_pixel_follows() {
        // (radial clearance, anisotropy, pixel): a round peg (its mesh's facets 0.3 %), a
        // square, a hexagon, an octagon; a coarse grid caps the pixel.
        for (c, k, want) in [
            (0.05e-3, 1.003, 0.1e-3),
            (0.06e-3, 2f64.sqrt(), 0.02e-3),
            (0.04e-3, 1.155, 0.02e-3),
            (0.05e-3, 1.082, 0.02e-3),
            (0.5e-3, 1.0, 0.1e-3),
        ] {
            let got = pixel_for(c, k);
            assert!(
                (got - want).abs() < 1e-12,
                "clearance {c}, {k}: pixel {got}, want {want}"
            );
        }
    }

    #[test]
    fn nice_values_are_one_two_five_times_a_power_of_ten() {
        for (x, want) in [(1e-4, 1e-4), (0.99e-4, 5e-5), (4e-5, 2e-5), (1.9e-5, 1e-5)] {
            assert!((nice_below(x) - want).abs() < 1e-12 * want.max(1.0), "{x}");
        }
    }
}
