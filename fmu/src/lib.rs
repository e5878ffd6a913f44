//! FtFusion: the condensation particle filter of "Multi Sensor Fusion in Robot Assembly
//! Using Particle Filters" (section IV, Algorithm 1, Eq. 3) over an FT-Map, and the FMI 2.0
//! Co-Simulation export layer that makes it `FtFusion.fmu`.
//!
//! Layers, outermost first: [`fmi2`] (the 34 exported C functions, all `unsafe` FFI of the
//! crate), [`instance`] (the FMU instance: state machine, variable store, state
//! snapshots), [`params`] (parameters checked against the variable table), [`filter`]
//! (the estimator, no FMI types).

pub mod error;
pub mod filter;
pub mod fmi2;
pub mod instance;
pub mod params;

pub use error::{FusionError, Result};
pub use filter::{Config, Estimate, Filter, Interpolation, Measurement, Report};
pub use instance::{Instance, Mode, Status};
pub use params::Params;
