//! Fixtures of the `ftfusion` crate's tests and benchmark, kept out of the FMU's library:
//! an analytic FT-Map (the field of a flat peg resting on the rim of its hole: torque
//! direction z x offset, lever shrinking with the offset) over object translations and,
//! optionally, object tilts, with no CAD meshes needed; experiment D's vision model; and
//! the exact rim torque of an octagonal peg on its hole, from the polygons.

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
        play: None,
    }
}

/// The field sampled on object.x, object.y in +-`size` at `step` (m), and when `rot` is
/// `Some((size, step))` also on object.rx, object.ry (rad).
pub fn peg_map(size: f64, step: f64, rot: Option<(f64, f64)>) -> ftmap::Result<FtMap> {
    peg_map_reaching(size, 1.0, step, rot)
}

/// As [`peg_map`] over an Omega of +-`size` whose object.x, object.y the map samples out to
/// `reach` times `size` (a task's `[omega] reach`).
pub fn peg_map_reaching(
    size: f64,
    reach: f64,
    step: f64,
    rot: Option<(f64, f64)>,
) -> ftmap::Result<FtMap> {
    let dof = |a| Dof::new(Pose::Object, a);
    let mut axes = vec![
        GridAxis::reaching(dof(Axis::X), size, reach, step)?,
        GridAxis::reaching(dof(Axis::Y), size, reach, step)?,
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

/// The torque (tx, ty; N.m, the map's convention) of an octagonal peg's flat face (across
/// flats `peg`, m) pressed with `force` (N) onto the top of an octagonal hole (across flats
/// `hole`) whose centre sits at `offset` (m) from the peg's and which is turned by `yaw`
/// (rad), under uniform pressure: the force at the centroid of the face less the hole, by
/// intersecting the two convex polygons (parry). Zero where the face lies within the hole.
pub fn octagon_rim_torque(peg: f64, hole: f64, offset: [f64; 2], yaw: f64, force: f64) -> [f64; 2] {
    use nalgebra::Point2;
    let octagon = |across: f64, turn: f64, centre: [f64; 2]| -> Vec<Point2<f64>> {
        let r = across / 2.0 / (std::f64::consts::PI / 8.0).cos();
        (0..8)
            .map(|k| {
                let a = std::f64::consts::PI / 8.0 * f64::from(2 * k + 1) + turn;
                Point2::new(centre[0] + r * a.cos(), centre[1] + r * a.sin())
            })
            .collect()
    };
    let face = octagon(peg, 0.0, [0.0; 2]);
    let mut inside = Vec::new();
    parry2d_f64::transformation::convex_polygons_intersection_points(
        &face,
        &octagon(hole, yaw, offset),
        &mut inside,
    );
    let ([a_face, x_face, y_face], [a_in, x_in, y_in]) = (moments(&face), moments(&inside));
    let area = a_face - a_in;
    if area <= 1e-18 {
        return [0.0; 2];
    }
    let centroid = [(x_face - x_in) / area, (y_face - y_in) / area];
    [centroid[1] * force, -centroid[0] * force]
}

/// Area and first moments (x, y) of a polygon (shoelace; none for fewer than 3 points).
fn moments(p: &[nalgebra::Point2<f64>]) -> [f64; 3] {
    let mut m = [0.0; 3];
    if p.len() < 3 {
        return m;
    }
    for (i, a) in p.iter().enumerate() {
        let b = p[(i + 1) % p.len()];
        let c = a.x * b.y - b.x * a.y;
        m[0] += c / 2.0;
        m[1] += (a.x + b.x) * c / 6.0;
        m[2] += (a.y + b.y) * c / 6.0;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rim_torque_of_a_strip_along_a_flat_is_the_flat_s_lever() {
        // The hole 0.03 mm off along +x, 0.005 mm beyond the flats' clearance: the face
        // rests on a strip along its flat at x = -5 mm, as long as the flat and its corners'
        // sliver (centroid within the strip's width of the flat): ty = F (5 mm - w / 2).
        let [tx, ty] = octagon_rim_torque(0.01, 0.01005, [3e-5, 0.0], 0.0, FORCE);
        assert!(tx.abs() < 1e-9, "{tx}");
        assert!(
            (ty - FORCE * (5e-3 - 2.5e-6)).abs() < 1e-4 * FORCE * 5e-3,
            "{ty}"
        );
        // Within the clearance the face lies in the hole; turned the other way, mirrored.
        assert_eq!(
            octagon_rim_torque(0.01, 0.01005, [2e-5, 0.0], 0.0, FORCE),
            [0.0; 2]
        );
        let a = octagon_rim_torque(0.01, 0.01005, [3e-5, 0.0], 0.035, FORCE);
        let b = octagon_rim_torque(0.01, 0.01005, [3e-5, 0.0], -0.035, FORCE);
        assert!(
            (a[0] + b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9,
            "{a:?} {b:?}"
        );
    }
}
