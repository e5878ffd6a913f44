//! ftfusion's MuJoCo validation harness: task scenes generated from `task.toml`, contact
//! motions in MuJoCo 3.17.0 (mujoco-rs), the F/T sensor in the FT-Map's convention, and
//! the closed loop of the paper's Algorithm 1 through `FtFusion.fmu` (the `fmi` importer),
//! with trial campaigns, measured maps and plots.

pub mod camera;
pub mod campaign;
pub mod cli;
pub mod compare;
pub mod error;
pub mod eye;
pub mod fmu_driver;
pub mod hough;
pub mod plot;
pub mod runtime;
pub mod scan;
pub mod scene;
pub mod sensor;
pub mod sim;
pub mod trial;
pub mod vision;

pub use error::{HarnessError, Result};
