//! The FT-Map itself: a wrench and a contact depth per cell of Omega, with what it was
//! made from, cell lookup and multilinear interpolation.

use serde::{Deserialize, Serialize};

use crate::error::{MapError, Result};
use crate::task::omega::Grid;
use crate::wrench::WrenchModel;

pub mod blend;
pub mod centre;
pub mod format;
pub mod parity;
pub mod resolution;

/// Channels stored per cell, in order.
pub const CHANNELS: [&str; 7] = ["fx", "fy", "fz", "tx", "ty", "tz", "depth"];
/// SI unit of each channel.
pub const UNITS: [&str; 7] = ["N", "N", "N", "N.m", "N.m", "N.m", "m"];
/// Number of channels per cell.
pub const NCH: usize = CHANNELS.len();

/// Index of a channel by name (`fx` .. `depth`).
pub fn channel_index(name: &str) -> Result<usize> {
    CHANNELS.iter().position(|c| *c == name).ok_or_else(|| {
        MapError::Grid(format!(
            "unknown channel `{name}` (one of {})",
            CHANNELS.join(", ")
        ))
    })
}

/// A source mesh of a map and its SHA-256.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SourceMesh {
    /// `A` (active, gripped) or `B` (passive, fixed).
    pub role: String,
    /// File name as given in the task.
    pub file: String,
    /// Hex SHA-256 of the file's bytes.
    pub sha256: String,
}

/// What a map was computed from and under which conventions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapMeta {
    /// Task name.
    pub task: String,
    /// Wrench model used.
    pub model: WrenchModel,
    /// Approach vector a in the nominal task frame (unit).
    pub approach: [f64; 3],
    /// Imposed force along a (N).
    pub force: f64,
    /// Friction coefficient.
    pub friction: f64,
    /// Sensor origin in the nominal task frame (m); torques are about it.
    pub sensor_origin: [f64; 3],
    /// Pixel size of the depth maps (m); 0 for measured maps.
    pub pixel: f64,
    /// Source meshes and their hashes.
    pub sources: Vec<SourceMesh>,
    /// Program and version that wrote the map.
    pub generator: String,
    /// Radial clearance of the fit by the geometry (m): part A goes in wherever part B is
    /// less than this off the TCP (at zero rotation error); absent when unknown.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clearance: Option<f64>,
    /// n-fold symmetry of the fit about the approach axis: `object.rz` wraps with period
    /// 2 pi / n; absent when the parts have none that Omega uses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub symmetry: Option<u32>,
    /// The fit's rotational play about x, y and z at zero offset by the geometry (rad,
    /// [`crate::task::fit::rotational_play`]) on the object rotations the grid samples, 0 on
    /// the others and where the part turns freely; absent when none was measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub play: Option<[f64; 3]>,
}

/// A Force Torque Map: `NCH` values per cell of a grid, cell-major.
#[derive(Debug, Clone, PartialEq)]
pub struct FtMap {
    grid: Grid,
    meta: MapMeta,
    data: Vec<f32>,
}

impl FtMap {
    /// A map of zeros over `grid`.
    pub fn zeros(grid: Grid, meta: MapMeta) -> Self {
        let data = vec![0.0; grid.cells() * NCH];
        Self { grid, meta, data }
    }

    /// A map from existing cell-major data; errors when its length does not fit the grid.
    pub fn from_data(grid: Grid, meta: MapMeta, data: Vec<f32>) -> Result<Self> {
        let want = grid.cells() * NCH;
        if data.len() != want {
            return Err(MapError::Grid(format!(
                "data has {} values, grid needs {want}",
                data.len()
            )));
        }
        Ok(Self { grid, meta, data })
    }

    /// The grid over Omega.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// What the map was made from.
    pub fn meta(&self) -> &MapMeta {
        &self.meta
    }

    /// All values, `NCH` per cell.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// All values, mutable.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// The channels of cell `cell`.
    pub fn cell(&self, cell: usize) -> &[f32; NCH] {
        self.data[cell * NCH..(cell + 1) * NCH]
            .try_into()
            .expect("NCH values per cell")
    }

    /// The channels of cell `cell`, mutable.
    pub fn cell_mut(&mut self, cell: usize) -> &mut [f32; NCH] {
        (&mut self.data[cell * NCH..(cell + 1) * NCH])
            .try_into()
            .expect("NCH values per cell")
    }

    /// The channels of the cell nearest to `coords` (one coordinate per grid axis), O(1).
    pub fn nearest(&self, coords: &[f64]) -> Result<&[f32; NCH]> {
        Ok(self.cell(self.grid.nearest(coords)?))
    }

    /// Multilinear interpolation of all channels at `coords` (clamped into the grid).
    pub fn interpolate(&self, coords: &[f64]) -> Result<[f64; NCH]> {
        Ok(self.interpolate_over(coords, |_| true)?.0)
    }

    /// The lowest and highest contact depth over the cells, when the depth channel holds
    /// values (not all zero).
    pub fn depth_range(&self) -> Option<[f32; 2]> {
        let depths = || self.data.iter().skip(NCH - 1).step_by(NCH);
        depths().any(|&d| d != 0.0).then(|| {
            depths().fold([f32::INFINITY, f32::NEG_INFINITY], |r, &d| {
                [r[0].min(d), r[1].max(d)]
            })
        })
    }

    /// The depth that tells a contact from an insertion: the middle of the depth channel's
    /// range (between resting on part B and inserted); `None` on a map without depths.
    pub fn contact_depth(&self) -> Option<f32> {
        self.depth_range().map(|[lo, hi]| 0.5 * (lo + hi))
    }

    /// The fit's rotational play along axis `k`: the geometry's, where the header holds it
    /// ([`MapMeta::play`]); else a whole number of grid steps below the true one: one step
    /// short of how far from zero the cells through the map's centre (every other axis at
    /// its sample nearest zero) stay inserted both ways, since the depth maps' pixel may
    /// round the fit open by up to a step (octagon_yaw: inserted to ±1° on its 0.05 mm
    /// pixel, ±0.70° by the geometry; play 0.5°), which on a grid whose step is about the
    /// play (the tilted hole's 0.25° against 0.29°) leaves none. 0 where `k` is no object
    /// rotation, the map has no depths or its centre is not inserted.
    pub fn rotational_play(&self, k: usize) -> f64 {
        let Some(a) = self.grid.axes().get(k) else {
            return 0.0;
        };
        if !(a.dof.pose == crate::Pose::Object && a.dof.is_rotation()) {
            return 0.0;
        }
        if let Some(play) = self.meta.play
            && let Some(&p) = play.get(a.dof.axis.index() - 3)
            && p > 0.0
        {
            return p;
        }
        let Some(middle) = self.contact_depth() else {
            return 0.0;
        };
        let mut idx = [0usize; crate::task::omega::MAX_AXES];
        for (j, b) in self.grid.axes().iter().enumerate() {
            idx[j] = b.nearest(0.0);
        }
        let centre = idx[k];
        let mut inserted = |i: usize| {
            idx[k] = i;
            self.cell(self.grid.flat(&idx[..self.grid.ndim()]))[NCH - 1] < middle
        };
        if !inserted(centre) {
            return 0.0;
        }
        let up = (centre + 1..a.count).take_while(|&i| inserted(i)).count();
        let down = (0..centre).rev().take_while(|&i| inserted(i)).count();
        up.min(down).saturating_sub(1) as f64 * a.step
    }

    /// The channels of a contact at `coords`: multilinear over the surrounding cells where
    /// part A rests on part B (depth at or above `contact_depth`, from
    /// [`FtMap::contact_depth`], which reads every cell: find it once), leaving out the
    /// cells where it went in (their wrench says nothing about a contact); plain
    /// [`FtMap::interpolate`] where every corner went in or the map has no depths.
    pub fn interpolate_contact(
        &self,
        coords: &[f64],
        contact_depth: Option<f32>,
    ) -> Result<[f64; NCH]> {
        let Some(middle) = contact_depth else {
            return self.interpolate(coords);
        };
        match self.interpolate_over(coords, |c| c[NCH - 1] >= middle)? {
            (contact, total) if total > 0.0 => Ok(contact),
            _ => self.interpolate(coords),
        }
    }

    /// The share of the multilinear weight at `coords` on cells where part A went in (depth
    /// below `contact_depth`, [`FtMap::contact_depth`]): above a half, the map says part A
    /// goes in there; 0 on a map without depths.
    pub fn inserted_share(&self, coords: &[f64], contact_depth: Option<f32>) -> Result<f64> {
        let Some(middle) = contact_depth else {
            return Ok(0.0);
        };
        Ok(self.interpolate_over(coords, |c| c[NCH - 1] < middle)?.1)
    }

    /// Multilinear interpolation at `coords` over the corners `keep` accepts, renormalised
    /// over them, and the sum of their weights (zeros and 0 when it accepts none).
    fn interpolate_over(
        &self,
        coords: &[f64],
        keep: impl Fn(&[f32; NCH]) -> bool,
    ) -> Result<([f64; NCH], f64)> {
        self.grid.check_len(coords)?;
        let mut out = [0.0; NCH];
        let mut total = 0.0;
        self.grid.for_each_corner(coords, |cell, w| {
            let c = self.cell(cell);
            if keep(c) {
                total += w;
                for (o, v) in out.iter_mut().zip(c) {
                    *o += w * f64::from(*v);
                }
            }
        });
        if total > 0.0 {
            out.iter_mut().for_each(|o| *o /= total);
        }
        Ok((out, total))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::task::dof::{Axis, Dof, Pose};
    use crate::task::omega::GridAxis;

    /// A small map whose channels are known functions of the coordinates.
    pub(crate) fn sample_map() -> FtMap {
        let x = GridAxis {
            dof: Dof::new(Pose::Object, Axis::X),
            min: -2e-3,
            step: 1e-3,
            count: 5,
            omega: None,
        };
        let y = GridAxis {
            dof: Dof::new(Pose::Object, Axis::Y),
            min: -1e-3,
            step: 1e-3,
            count: 3,
            omega: None,
        };
        let grid = Grid::new(vec![x, y]).unwrap();
        let meta = MapMeta {
            task: "sample".into(),
            model: WrenchModel::Centroid,
            approach: [0.0, 0.0, -1.0],
            force: 50.0,
            friction: 0.3,
            sensor_origin: [0.0, 0.0, 0.05],
            pixel: 1e-4,
            sources: vec![SourceMesh {
                role: "A".into(),
                file: "a.stl".into(),
                sha256: "00".into(),
            }],
            generator: "test".into(),
            clearance: None,
            symmetry: None,
            play: None,
        };
        let mut map = FtMap::zeros(grid, meta);
        for cell in 0..map.grid().cells() {
            let c = map.grid().coords(cell);
            let v = map.cell_mut(cell);
            v[3] = (1000.0 * c[1]) as f32;
            v[4] = (-1000.0 * c[0]) as f32;
            v[2] = 50.0;
            v[6] = (c[0] * c[0]) as f32;
        }
        map
    }

    #[test]
    fn interpolation_is_exact_on_cells_and_linear_between() {
        let map = sample_map();
        let at = map.interpolate(&[1e-3, -1e-3]).unwrap();
        assert!((at[3] - (-1.0)).abs() < 1e-6 && (at[4] - (-1.0)).abs() < 1e-6);
        let mid = map.interpolate(&[0.5e-3, 0.25e-3]).unwrap();
        assert!((mid[3] - 0.25).abs() < 1e-6, "{mid:?}");
        assert!((mid[4] + 0.5).abs() < 1e-6, "{mid:?}");
        // x^2 between samples 0 and 1e-3 interpolates linearly: 0.5e-6 at 0.5e-3.
        assert!((mid[6] - 0.5e-6).abs() < 1e-12);
        assert!(map.interpolate(&[0.0]).is_err());
        let [lo, hi] = map.depth_range().unwrap();
        assert!(lo == 0.0 && (hi - 4e-6).abs() < 1e-12, "{lo} {hi}");
        assert_eq!(map.nearest(&[0.4e-3, 0.6e-3]).unwrap()[3], 1.0);
    }

    #[test]
    fn a_contact_leaves_out_the_cells_where_part_a_went_in() {
        // Depth x^2 over x in [-2, 2] mm: the middle of its range is 2e-6, so only the
        // columns x = ±2 mm are contacts.
        let map = sample_map();
        let depth = map.contact_depth();
        let c = map.interpolate_contact(&[1.5e-3, 0.0], depth).unwrap();
        assert!(
            (c[4] + 2.0).abs() < 1e-6,
            "the x = 2 mm column alone: {c:?}"
        );
        let plain = map.interpolate(&[1.5e-3, 0.0]).unwrap();
        assert!((plain[4] + 1.5).abs() < 1e-6, "{plain:?}");
        // Every corner went in: plain interpolation.
        let inside = map.interpolate_contact(&[0.5e-3, 0.0], depth).unwrap();
        assert_eq!(inside, map.interpolate(&[0.5e-3, 0.0]).unwrap());
    }
}
