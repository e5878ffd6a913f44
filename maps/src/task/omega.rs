//! The discrete tolerance space Omega (paper, Definition 2.1.1) as a regular grid over a
//! subset of the twelve DOFs: axes, cell indices and coordinates, multilinear weights.

use serde::{Deserialize, Serialize};

use crate::error::{MapError, Result};
use crate::task::dof::Dof;

/// Largest number of axes a grid can have (every DOF of both poses).
pub const MAX_AXES: usize = 12;

/// One uncertain DOF sampled at `count` values `min + i * step`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GridAxis {
    /// The DOF this axis samples.
    pub dof: Dof,
    /// Value of the first sample (m or rad).
    pub min: f64,
    /// Interval between samples (m or rad), > 0.
    pub step: f64,
    /// Number of samples, >= 1.
    pub count: usize,
    /// Half-width of Omega on an axis that samples farther, [-omega, omega] (m or rad): the
    /// object's x and y, which the filter reads at the part's pose relative to a TCP
    /// anywhere in Omega ([`crate::task::Omega::reach`]); absent where the axis is Omega.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub omega: Option<f64>,
}

impl GridAxis {
    /// A symmetric axis from -size to +size at `step` (count rounded to the nearest whole).
    pub fn symmetric(dof: Dof, size: f64, step: f64) -> Result<Self> {
        if !(size >= 0.0 && size.is_finite() && step > 0.0 && step.is_finite()) {
            return Err(MapError::Grid(format!(
                "{dof}: size {size} and step {step} must be finite, size >= 0, step > 0"
            )));
        }
        let half = (size / step).round() as usize;
        Ok(Self {
            dof,
            min: -(half as f64) * step,
            step,
            count: 2 * half + 1,
            omega: None,
        })
    }

    /// A symmetric axis over Omega's +-`size` at `step`, sampled out to `reach` times `size`
    /// (at least 1; [`GridAxis::omega`] set where it samples farther).
    pub fn reaching(dof: Dof, size: f64, reach: f64, step: f64) -> Result<Self> {
        let farther = reach > 1.0 && size > 0.0;
        Self::symmetric(dof, size * reach, step).map(|a| Self {
            omega: farther.then_some(size),
            ..a
        })
    }

    /// Omega's bounds on this axis (m or rad): [-omega, omega] on an axis that samples
    /// farther, else the axis's own.
    pub fn omega_bounds(&self) -> [f64; 2] {
        self.omega.map_or([self.min, self.max()], |h| [-h, h])
    }

    /// Value of sample `i`.
    pub fn value(&self, i: usize) -> f64 {
        self.min + i as f64 * self.step
    }

    /// Value of the last sample.
    pub fn max(&self) -> f64 {
        self.value(self.count - 1)
    }

    /// Index of the sample nearest to `x`, clamped into the axis.
    pub fn nearest(&self, x: f64) -> usize {
        let t = ((x - self.min) / self.step).round();
        t.clamp(0.0, (self.count - 1) as f64) as usize
    }

    /// Lower sample index and fraction towards the next one, clamped into the axis.
    pub fn bracket(&self, x: f64) -> (usize, f64) {
        if self.count == 1 {
            return (0, 0.0);
        }
        let t = ((x - self.min) / self.step).clamp(0.0, (self.count - 1) as f64);
        let i = (t as usize).min(self.count - 2);
        (i, t - i as f64)
    }

    /// True when `x` lies within [min, max].
    pub fn contains(&self, x: f64) -> bool {
        x >= self.min && x <= self.max()
    }
}

/// A regular grid over some DOFs; cells are numbered row-major, the last axis fastest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GridRepr", into = "GridRepr")]
pub struct Grid {
    axes: Vec<GridAxis>,
    strides: Vec<usize>,
    cells: usize,
}

#[derive(Serialize, Deserialize)]
struct GridRepr {
    axes: Vec<GridAxis>,
}

impl TryFrom<GridRepr> for Grid {
    type Error = MapError;
    fn try_from(r: GridRepr) -> Result<Self> {
        Grid::new(r.axes)
    }
}

impl From<Grid> for GridRepr {
    fn from(g: Grid) -> Self {
        GridRepr { axes: g.axes }
    }
}

impl Grid {
    /// Builds a grid; refuses repeated DOFs, empty axes, non-positive steps and an Omega
    /// outside its axis.
    pub fn new(axes: Vec<GridAxis>) -> Result<Self> {
        if axes.len() > MAX_AXES {
            return Err(MapError::Grid(format!(
                "{} axes, at most {MAX_AXES}",
                axes.len()
            )));
        }
        for (i, a) in axes.iter().enumerate() {
            if a.count == 0 || !(a.step > 0.0 && a.step.is_finite()) || !a.min.is_finite() {
                return Err(MapError::Grid(format!(
                    "axis {}: count {} must be >= 1, step {} > 0 and finite, min {} finite",
                    a.dof, a.count, a.step, a.min
                )));
            }
            if let Some(h) = a.omega
                && !(h > 0.0 && h.is_finite() && a.contains(-h) && a.contains(h))
            {
                return Err(MapError::Grid(format!(
                    "axis {}: Omega's half-width {h} must be > 0 and within the axis [{}, {}]",
                    a.dof,
                    a.min,
                    a.max()
                )));
            }
            if axes[..i].iter().any(|b| b.dof == a.dof) {
                return Err(MapError::Grid(format!("DOF {} appears twice", a.dof)));
            }
        }
        let mut strides = vec![1; axes.len()];
        let mut cells: usize = 1;
        for (k, a) in axes.iter().enumerate().rev() {
            strides[k] = cells;
            cells = cells
                .checked_mul(a.count)
                .ok_or_else(|| MapError::Grid("cell count overflows".into()))?;
        }
        Ok(Self {
            axes,
            strides,
            cells,
        })
    }

    /// The axes in storage order.
    pub fn axes(&self) -> &[GridAxis] {
        &self.axes
    }

    /// Number of axes.
    pub fn ndim(&self) -> usize {
        self.axes.len()
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.cells
    }

    /// Distance in the flat index between neighbours along axis `k`.
    pub fn stride(&self, k: usize) -> usize {
        self.strides[k]
    }

    /// Position of `dof` among the axes, if the grid has it.
    pub fn axis_of(&self, dof: Dof) -> Option<usize> {
        self.axes.iter().position(|a| a.dof == dof)
    }

    /// Flat index of the cell with per-axis sample indices `idx`.
    pub fn flat(&self, idx: &[usize]) -> usize {
        idx.iter().zip(&self.strides).map(|(i, s)| i * s).sum()
    }

    /// Per-axis sample indices of flat cell `cell`, written into `out`.
    pub fn unflat(&self, mut cell: usize, out: &mut [usize]) {
        for (k, s) in self.strides.iter().enumerate() {
            out[k] = cell / s;
            cell %= s;
        }
    }

    /// Coordinates (one per axis) of flat cell `cell`.
    pub fn coords(&self, cell: usize) -> Vec<f64> {
        let mut idx = [0usize; MAX_AXES];
        self.unflat(cell, &mut idx);
        self.axes.iter().zip(idx).map(|(a, i)| a.value(i)).collect()
    }

    /// Flat index of the cell nearest to `coords` (clamped into the grid).
    pub fn nearest(&self, coords: &[f64]) -> Result<usize> {
        self.check_len(coords)?;
        Ok(self
            .axes
            .iter()
            .zip(coords)
            .zip(&self.strides)
            .map(|((a, &x), s)| a.nearest(x) * s)
            .sum())
    }

    /// True when every coordinate lies within its axis.
    pub fn contains(&self, coords: &[f64]) -> bool {
        coords.len() == self.ndim() && self.axes.iter().zip(coords).all(|(a, &x)| a.contains(x))
    }

    /// Errors unless `coords` has one value per axis.
    pub fn check_len(&self, coords: &[f64]) -> Result<()> {
        if coords.len() == self.ndim() {
            Ok(())
        } else {
            Err(MapError::Coordinates {
                expected: self.ndim(),
                got: coords.len(),
            })
        }
    }

    /// Calls `f(flat_index, weight)` for the 2^ndim corners of the cell around `coords`
    /// with multilinear weights summing to 1 (coordinates clamped into the grid).
    pub fn for_each_corner(&self, coords: &[f64], mut f: impl FnMut(usize, f64)) {
        let n = self.ndim().min(coords.len());
        let mut base = 0usize;
        let mut frac = [0.0f64; MAX_AXES];
        for k in 0..n {
            let (i, t) = self.axes[k].bracket(coords[k]);
            base += i * self.strides[k];
            frac[k] = t;
        }
        for corner in 0..(1usize << n) {
            let mut w = 1.0;
            let mut idx = base;
            for (k, &t) in frac.iter().enumerate().take(n) {
                if corner >> k & 1 == 1 {
                    if t == 0.0 {
                        w = 0.0;
                        break;
                    }
                    w *= t;
                    idx += self.strides[k];
                } else {
                    w *= 1.0 - t;
                }
            }
            if w != 0.0 {
                f(idx, w);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::task::dof::{Axis, Pose};

    fn dof(a: Axis) -> Dof {
        Dof::new(Pose::Object, a)
    }

    #[test]
    fn paper_grids_have_the_expected_cell_counts() {
        let x = GridAxis::symmetric(dof(Axis::X), 5e-3, 1e-4).unwrap();
        let rx =
            GridAxis::symmetric(dof(Axis::Rx), 2f64.to_radians(), 0.5f64.to_radians()).unwrap();
        assert_eq!(x.count, 101);
        assert_eq!(rx.count, 9);
        let g = Grid::new(vec![
            x,
            GridAxis {
                dof: dof(Axis::Y),
                ..x
            },
            rx,
            GridAxis {
                dof: dof(Axis::Ry),
                ..rx
            },
        ])
        .unwrap();
        assert_eq!(g.cells(), 826_281);
    }

    #[test]
    fn flat_and_unflat_are_inverse_and_last_axis_is_fastest() {
        let a = GridAxis {
            dof: dof(Axis::X),
            min: -1.0,
            step: 0.5,
            count: 5,
            omega: None,
        };
        let b = GridAxis {
            dof: dof(Axis::Y),
            min: 0.0,
            step: 1.0,
            count: 3,
            omega: None,
        };
        let g = Grid::new(vec![a, b]).unwrap();
        assert_eq!(g.flat(&[0, 1]), 1);
        assert_eq!(g.flat(&[1, 0]), 3);
        let mut idx = [0; 2];
        for cell in 0..g.cells() {
            g.unflat(cell, &mut idx);
            assert_eq!(g.flat(&idx), cell);
        }
        assert_eq!(g.coords(7), vec![0.0, 1.0]);
        assert_eq!(g.nearest(&[0.2, 1.6]).unwrap(), g.flat(&[2, 2]));
    }

    #[test]
    fn corner_weights_sum_to_one_and_reproduce_linear_functions() {
        let a = GridAxis {
            dof: dof(Axis::X),
            min: -1.0,
            step: 0.5,
            count: 5,
            omega: None,
        };
        let b = GridAxis {
            dof: dof(Axis::Y),
            min: 0.0,
            step: 1.0,
            count: 3,
            omega: None,
        };
        let c = GridAxis {
            dof: dof(Axis::Rz),
            min: 0.0,
            step: 0.1,
            count: 4,
            omega: None,
        };
        let g = Grid::new(vec![a, b, c]).unwrap();
        let lin = |p: &[f64]| 2.0 * p[0] - 3.0 * p[1] + 5.0 * p[2] + 1.0;
        for p in [
            [0.3, 1.2, 0.17],
            [-1.0, 0.0, 0.0],
            [1.0, 2.0, 0.3],
            [0.49, 1.99, 0.05],
        ] {
            let (mut sum_w, mut val) = (0.0, 0.0);
            g.for_each_corner(&p, |i, w| {
                sum_w += w;
                val += w * lin(&g.coords(i));
            });
            assert!((sum_w - 1.0).abs() < 1e-12);
            assert!((val - lin(&p)).abs() < 1e-9, "{p:?}: {val} vs {}", lin(&p));
        }
    }

    #[test]
    fn bad_grids_are_refused() {
        let a = GridAxis {
            dof: dof(Axis::X),
            min: 0.0,
            step: 0.5,
            count: 5,
            omega: None,
        };
        assert!(Grid::new(vec![a, a]).is_err());
        assert!(Grid::new(vec![GridAxis { count: 0, ..a }]).is_err());
        assert!(Grid::new(vec![GridAxis { step: 0.0, ..a }]).is_err());
        assert!(GridAxis::symmetric(dof(Axis::X), 1.0, f64::NAN).is_err());
        for h in [0.0, -1.0, 2.5, f64::NAN] {
            let e = Grid::new(vec![GridAxis {
                omega: Some(h),
                ..a
            }])
            .expect_err("bad Omega");
            assert!(e.to_string().contains("Omega's half-width"), "{h}: {e}");
        }
    }

    #[test]
    fn omega_is_the_axis_unless_it_samples_farther() {
        let a = GridAxis::symmetric(dof(Axis::X), 1.0, 0.5).unwrap();
        assert_eq!(a.omega_bounds(), [-1.0, 1.0]);
        let wide = GridAxis::reaching(dof(Axis::X), 1.0, 2.0, 0.5).unwrap();
        assert_eq!(wide.omega_bounds(), [-1.0, 1.0]);
        assert_eq!(Grid::new(vec![wide]).unwrap().axes()[0].omega, Some(1.0));
    }
}
