#![doc = include_str!("../README.md")]
//!
//! Modules follow the paper's concepts: [`task`] (the task file, the tolerance space Omega
//! and its DOFs, the parametric CAD solids), [`mesh`], [`depth`] (the z-buffer backends),
//! [`wrench`] (wrench models), [`generate`] (the FT-Map computation), [`map`] (the map type,
//! its lookup and file format), [`vision`] (the camera and the parts' features) and
//! [`file`] (reading the files a user names, bounded); [`exact`] answers queries on the exact
//! geometry, with which [`verify`] checks a computed map.

pub mod depth;
pub mod error;
pub mod exact;
pub mod file;
pub mod generate;
pub mod map;
pub mod mesh;
pub mod process;
pub mod task;
pub mod verify;
pub mod vision;
pub mod wrench;

pub use error::{MapError, Result};
pub use map::{CHANNELS, FtMap, MapMeta, NCH, SourceMesh, UNITS};
pub use task::Task;
pub use task::dof::{Axis, Dof, Pose};
pub use task::omega::{Grid, GridAxis};
pub use wrench::WrenchModel;
