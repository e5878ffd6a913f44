#![doc = include_str!("../README.md")]

pub mod error;
pub mod filter;
pub mod fmi2;
pub mod instance;
pub mod params;
pub mod shared;
pub mod trace;

pub use error::{FusionError, Result};
pub use filter::{Config, Estimate, Filter, Interpolation, Measurement, Report};
pub use instance::{Instance, Mode, Status};
pub use params::Params;
