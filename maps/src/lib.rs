//! Force Torque Maps (FT-Maps) from CAD meshes, after section II of "Multi Sensor Fusion
//! in Robot Assembly Using Particle Filters": the tolerance space Omega, tasks, meshes,
//! z-buffer depth backends (CPU and wgpu), contacts, wrench models, the map type with its
//! O(1) lookup and its file format.

pub mod cad;
pub mod cpu;
pub mod depth;
pub mod dof;
pub mod error;
pub mod format;
pub mod generate;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod grid;
pub mod map;
pub mod mesh;
pub mod plot;
pub mod task;
pub mod vision;
pub mod wrench;

pub use dof::{Axis, Dof, Pose};
pub use error::{MapError, Result};
pub use grid::{Grid, GridAxis};
pub use map::{CHANNELS, FtMap, MapMeta, NCH, SourceMesh, UNITS, WrenchModel};
pub use task::Task;
