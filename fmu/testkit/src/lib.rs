//! Fixtures of the `ftfusion` crate's tests and benchmark, kept out of the FMU's library:
//! an analytic FT-Map (the field of a flat peg resting on the rim of its hole: torque
//! direction z x offset, lever shrinking with the offset) over object translations and,
//! optionally, object tilts, with no CAD meshes needed; and experiment D's vision model.

use ftmap::{Axis, Dof, FtMap, Grid, GridAxis, MapMeta, Pose, WrenchModel};

/// Imposed force (N).
pub const FORCE: f64 = 50.0;
/// Radial clearance inside which the peg drops into the hole (m).
pub const CLEARANCE: f64 = 5e-5;
/// Depth of the hole: the contact height on the rim (m).
pub const HOLE_DEPTH: f64 = 0.01;

/// The wrench and depth of the analytic field at object pose (x, y, rx, ry).
pub fn field(x: f64, y: f64, rx: f64, ry: f64) -> [f32; 7] {
    let r = x.hypot(y);
    let (mut tx, mut ty, mut depth) = (0.0, 0.0, 0.0);
    if r > CLEARANCE {
        // Lever of the contact-crescent centroid: 3.9 mm near the centre, shorter further out.
        let lever = 0.0039 - 0.45 * r;
        tx = FORCE * lever * y / r;
        ty = -FORCE * lever * x / r;
        depth = HOLE_DEPTH;
    }
    // A tilted hole pushes the peg sideways.
    let (fx, fy) = (FORCE * ry, -FORCE * rx);
    [fx, fy, FORCE, tx, ty, 0.0, depth].map(|v| v as f32)
}

/// The metadata of a synthetic map of task `task`: centroid model, approach -z, [`FORCE`],
/// no friction, the sensor at the origin, the fit's [`CLEARANCE`], no symmetry.
pub fn synthetic_meta(task: &str) -> MapMeta {
    MapMeta {
        task: task.into(),
        model: WrenchModel::Centroid,
        approach: [0.0, 0.0, -1.0],
        force: FORCE,
        friction: 0.0,
        sensor_origin: [0.0, 0.0, 0.0],
        pixel: 0.0,
        sources: Vec::new(),
        generator: "ftfusion::synthetic".into(),
        clearance: Some(CLEARANCE),
        symmetry: None,
    }
}

/// The field sampled on object.x, object.y in +-`size` at `step` (m), and when `rot` is
/// `Some((size, step))` also on object.rx, object.ry (rad).
pub fn peg_map(size: f64, step: f64, rot: Option<(f64, f64)>) -> ftmap::Result<FtMap> {
    let dof = |a| Dof::new(Pose::Object, a);
    let mut axes = vec![
        GridAxis::symmetric(dof(Axis::X), size, step)?,
        GridAxis::symmetric(dof(Axis::Y), size, step)?,
    ];
    if let Some((s, d)) = rot {
        axes.push(GridAxis::symmetric(dof(Axis::Rx), s, d)?);
        axes.push(GridAxis::symmetric(dof(Axis::Ry), s, d)?);
    }
    let grid = Grid::new(axes)?;
    let mut map = FtMap::zeros(grid, synthetic_meta("synthetic_peg"));
    for cell in 0..map.grid().cells() {
        let c = map.grid().coords(cell);
        let (rx, ry) = if c.len() == 4 {
            (c[2], c[3])
        } else {
            (0.0, 0.0)
        };
        *map.cell_mut(cell) = field(c[0], c[1], rx, ry);
    }
    Ok(map)
}

/// Experiment D's vision model, from the bearing_housing task's `[camera]` and `[geometry]`.
pub fn bearing_vision() -> ftmap::vision::VisionModel {
    let task = ftmap::Task::find("bearing_housing").expect("task bearing_housing");
    ftmap::vision::VisionModel::of_task(&task)
        .expect("valid tables")
        .expect("a camera and features")
}
