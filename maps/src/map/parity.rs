//! How far two maps of one grid disagree, in the method's terms: the cells whose contact
//! differs, and elsewhere how far apart the two wrenches' lines of action run (the lever
//! the filter reads), against the map's pixel.

use nalgebra::Vector3;

use crate::error::{MapError, Result};
use crate::map::{FtMap, NCH};

/// Share of the larger force (or of 1 N) by which two cells' forces may differ and still
/// be the same contact.
const FORCE_AGREES: f64 = 1e-3;

/// What [`compare`] finds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Parity {
    /// Cells compared.
    pub cells: usize,
    /// Cells whose contact differs: one map touches where the other does not, or a force
    /// component differs by more than [`FORCE_AGREES`] of the larger force (or of 1 N).
    pub contact_differs: usize,
    /// Of the cells with the same contact, those whose lines of action run more than a
    /// pixel apart.
    pub lever_over_pixel: usize,
    /// The largest distance (m) between the lines of action of a cell with the same
    /// contact in both maps.
    pub max_lever: f64,
    /// The largest difference of the depth channel (m).
    pub max_depth: f64,
    /// The first [`EXAMPLES`] cells (flat indices) whose contact differs.
    pub differing: Vec<usize>,
}

/// How many differing cells [`Parity::differing`] names.
pub const EXAMPLES: usize = 5;

/// Compares `b` against `a` cell by cell; both must share one grid.
pub fn compare(a: &FtMap, b: &FtMap) -> Result<Parity> {
    if a.grid() != b.grid() {
        return Err(MapError::Grid(
            "the two maps do not share one grid: they cannot be compared cell by cell".into(),
        ));
    }
    let pixel = a.meta().pixel;
    let mut p = Parity::default();
    for (cell, (x, y)) in a
        .data()
        .chunks_exact(NCH)
        .zip(b.data().chunks_exact(NCH))
        .enumerate()
    {
        p.cells += 1;
        p.max_depth = p.max_depth.max(f64::from((x[6] - y[6]).abs()));
        let vec = |c: &[f32], k: usize| Vector3::new(c[k], c[k + 1], c[k + 2]).cast::<f64>();
        let (fa, fb) = (vec(x, 0), vec(y, 0));
        let agree = FORCE_AGREES * fa.norm().max(fb.norm()).max(1.0);
        if (fa.norm() > 0.0) != (fb.norm() > 0.0) || (fa - fb).amax() > agree {
            p.contact_differs += 1;
            if p.differing.len() < EXAMPLES {
                p.differing.push(cell);
            }
            continue;
        }
        if fa.norm() == 0.0 {
            continue;
        }
        // Lines of action r x f = t with one force: F x (t_a - t_b) / |F|^2 apart.
        let lever = fa.cross(&(vec(x, 3) - vec(y, 3))).norm() / fa.norm_squared();
        p.max_lever = p.max_lever.max(lever);
        p.lever_over_pixel += usize::from(lever > pixel);
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::tests::sample_map;

    /// The small test map with every cell's wrench that of 50 N along -z applied `r` (m)
    /// along x from the sensor.
    fn pressed_at(r: f64) -> FtMap {
        let mut map = sample_map();
        let (f, lever) = (Vector3::new(0.0, 0.0, -50.0), Vector3::new(r, 0.0, -0.02));
        let t = lever.cross(&f);
        for c in map.data_mut().chunks_exact_mut(NCH) {
            c[..6].copy_from_slice(&[f.x, f.y, f.z, t.x, t.y, t.z].map(|v| v as f32));
        }
        map
    }

    #[test]
    fn a_lever_moved_by_more_than_a_pixel_and_a_lost_contact_are_counted() {
        let pixel = sample_map().meta().pixel;
        let a = pressed_at(0.003);
        // Every cell's lever 1.5 pixels farther out: the lines of action that far apart.
        let p = compare(&a, &pressed_at(0.003 + 1.5 * pixel)).unwrap();
        assert_eq!((p.contact_differs, p.lever_over_pixel), (0, p.cells));
        assert!((p.max_lever - 1.5 * pixel).abs() < 1e-2 * pixel, "{p:?}");
        // Half a pixel: within it; and a cell without contact in one of them differs.
        let mut c = pressed_at(0.003 + 0.5 * pixel);
        c.data_mut()[..6].fill(0.0);
        let p = compare(&a, &c).unwrap();
        assert_eq!((p.contact_differs, p.lever_over_pixel), (1, 0));
        assert_eq!(p.differing, vec![0]);
        assert!((p.max_lever - 0.5 * pixel).abs() < 1e-2 * pixel, "{p:?}");
        assert_eq!(compare(&a, &a).unwrap().max_lever, 0.0);
    }
}
