//! Blended maps, the paper's two routes combined: a map computed from CAD, corrected where a
//! sparse measured map (a few hundred contact motions, `harness scan --step`) says the world
//! differs. The residual measured - computed is taken at the measured cells and spread over
//! the computed grid by multilinear interpolation, so the blended map equals the measured
//! one at its cells and keeps the computed map's detail between them.

use crate::error::{MapError, Result};
use crate::map::{FtMap, MapMeta, NCH};
use crate::wrench::WrenchModel;

/// The computed map `computed` corrected by the measured map `measured` over the same DOFs.
///
/// # Errors
/// [`MapError::Grid`] when the two maps do not have the same DOFs in the same order, when
/// `computed` is not a computed map or `measured` not a measured one, or when a map holds a
/// non-finite value where the residual is taken.
pub fn blend(computed: &FtMap, measured: &FtMap) -> Result<FtMap> {
    let bad = |reason: String| Err(MapError::Grid(reason));
    let dofs = |m: &FtMap| m.grid().axes().iter().map(|a| a.dof).collect::<Vec<_>>();
    if dofs(computed) != dofs(measured) {
        return bad(format!(
            "blend: the computed map's DOFs {:?} differ from the measured map's {:?}",
            dofs(computed),
            dofs(measured)
        ));
    }
    if !computed.meta().model.is_computed() || measured.meta().model != WrenchModel::Measured {
        return bad(format!(
            "blend: needs a computed map and a measured one, got models {:?} and {:?}",
            computed.meta().model,
            measured.meta().model
        ));
    }
    // The residual on the measured grid.
    let mut residual = FtMap::zeros(measured.grid().clone(), measured.meta().clone());
    for cell in 0..measured.grid().cells() {
        let at = measured.grid().coords(cell);
        let c = computed.interpolate(&at)?;
        let m = measured.cell(cell);
        for k in 0..NCH {
            let r = f64::from(m[k]) - c[k];
            if !r.is_finite() {
                return bad(format!(
                    "blend: channel {k} is not finite at the measured cell {at:?}"
                ));
            }
            residual.cell_mut(cell)[k] = r as f32;
        }
    }
    let meta = MapMeta {
        model: WrenchModel::Blended,
        sources: computed
            .meta()
            .sources
            .iter()
            .chain(&measured.meta().sources)
            .cloned()
            .collect(),
        generator: format!(
            "{} corrected by a {}-cell measured map",
            computed.meta().generator,
            measured.grid().cells()
        ),
        ..computed.meta().clone()
    };
    let mut out = FtMap::zeros(computed.grid().clone(), meta);
    for cell in 0..computed.grid().cells() {
        let r = residual.interpolate(&computed.grid().coords(cell))?;
        let c = computed.cell(cell);
        for k in 0..NCH {
            out.cell_mut(cell)[k] = (f64::from(c[k]) + r[k]) as f32;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::tests::sample_map;
    use crate::task::dof::{Axis, Dof, Pose};
    use crate::task::omega::{Grid, GridAxis};

    const STEP: f64 = 5e-4;

    /// A computed map over object x, y in ±4 mm at 0.5 mm with smooth, non-linear channels.
    fn computed_map() -> FtMap {
        let axis = |a| GridAxis::symmetric(Dof::new(Pose::Object, a), 4e-3, STEP).expect("axis");
        let grid = Grid::new(vec![axis(Axis::X), axis(Axis::Y)]).expect("grid");
        let mut map = FtMap::zeros(grid, sample_map().meta().clone());
        for cell in 0..map.grid().cells() {
            let c = map.grid().coords(cell);
            let (x, y) = (c[0] * 1e3, c[1] * 1e3);
            *map.cell_mut(cell) = [
                0.1 * x,
                -0.2 * y,
                50.0,
                (0.7 * y).sin(),
                x.cos(),
                0.0,
                x * x,
            ]
            .map(|v| v as f32);
        }
        map
    }

    /// `map` resampled on a grid of `step` (m), as a measured map: a sparse scan of a world
    /// whose wrench is `world(coords, computed values)`.
    fn scan_of(map: &FtMap, step: f64, world: impl Fn(&[f64], [f64; NCH]) -> [f64; NCH]) -> FtMap {
        let axes = map
            .grid()
            .axes()
            .iter()
            .map(|a| GridAxis::symmetric(a.dof, a.max(), step).expect("axis"))
            .collect();
        let grid = Grid::new(axes).expect("grid");
        let meta = MapMeta {
            model: WrenchModel::Measured,
            ..map.meta().clone()
        };
        let mut out = FtMap::zeros(grid.clone(), meta);
        for cell in 0..grid.cells() {
            let at = grid.coords(cell);
            let v = world(&at, map.interpolate(&at).expect("inside"));
            *out.cell_mut(cell) = v.map(|x| x as f32);
        }
        out
    }

    #[test]
    fn a_world_offset_by_a_linear_field_is_recovered_everywhere() {
        let computed = computed_map();
        let step = 4.0 * STEP;
        // The world's tx is the map's plus 0.1 + 2 x (linear: multilinear interpolation of
        // the residual is exact), the other channels as computed.
        let world = |at: &[f64], mut v: [f64; NCH]| {
            v[3] += 0.1 + 2.0 * at[0];
            v
        };
        let measured = scan_of(&computed, step, world);
        let blended = blend(&computed, &measured).expect("same DOFs");
        assert_eq!(blended.meta().model, WrenchModel::Blended);
        for cell in 0..computed.grid().cells() {
            let at = computed.grid().coords(cell);
            let want = world(&at, computed.cell(cell).map(f64::from));
            let got = blended.cell(cell);
            for k in 0..NCH {
                assert!(
                    (f64::from(got[k]) - want[k]).abs() < 1e-5,
                    "cell {at:?} channel {k}: {} vs {}",
                    got[k],
                    want[k]
                );
            }
        }
    }

    #[test]
    fn the_blend_equals_the_scan_at_its_cells_and_the_map_where_they_agree() {
        let computed = computed_map();
        let step = 2.0 * STEP;
        // A local bump the sparse scan sees at one of its cells only.
        let bump = |at: &[f64], mut v: [f64; NCH]| {
            if at.iter().all(|x| x.abs() < 1e-12) {
                v[4] -= 0.5;
            }
            v
        };
        let measured = scan_of(&computed, step, bump);
        let blended = blend(&computed, &measured).expect("same DOFs");
        for cell in 0..measured.grid().cells() {
            let at = measured.grid().coords(cell);
            let (b, m) = (blended.nearest(&at).expect("inside"), measured.cell(cell));
            assert!(b.iter().zip(m).all(|(x, y)| (x - y).abs() < 1e-5), "{at:?}");
        }
        // Further than one scan step from the bump the computed map is kept as it was.
        for cell in 0..computed.grid().cells() {
            let at = computed.grid().coords(cell);
            if at.iter().any(|x| x.abs() >= step) {
                assert_eq!(blended.cell(cell), computed.cell(cell), "{at:?}");
            }
        }
        // Two computed maps, or maps of other DOFs, are refused by name.
        let e = blend(&computed, &computed)
            .expect_err("not measured")
            .to_string();
        assert!(e.contains("measured"), "{e}");
        let x_only = FtMap::zeros(
            Grid::new(vec![computed.grid().axes()[0]]).expect("grid"),
            computed.meta().clone(),
        );
        let e = blend(&x_only, &measured)
            .map(|_| ())
            .expect_err("other DOFs");
        assert!(e.to_string().contains("DOFs"), "{e}");
    }
}
