#![doc = include_str!("../README.md")]
//! Modules, from the simulated world up:
//!
//! - [`runtime`], the MuJoCo version check, and [`error`], the [`HarnessError`] type;
//! - [`world`], where a trial's contact motions happen (MuJoCo or the FT-Map itself);
//!   [`scene`], MJCF scenes from `task.toml`; [`sim`], the MuJoCo work cell's contact motions;
//!   [`sensor`], the F/T reading in the map's convention and its noise;
//! - [`camera`], the calibrated camera and headless rendering; [`vision`], the camera
//!   pipeline (image primitives, the gradient and Hough line detectors, features);
//!   [`eye`], the camera as a trial's second sensor;
//! - [`fmu_driver`], `FtFusion.fmu` through FMI calls, and [`fmu_log`], what it logged;
//!   [`trial`], one trial (Algorithm 1 or the spiral search); [`campaign`], campaigns set
//!   up and run on every core; [`shard`], a campaign split over machines and merged;
//!   [`report`], `trials.csv`, `measurements.csv` and `summary.json`;
//!   [`table`], many campaigns in one table;
//!   [`calibration`], whether the reported spread tells the truth; [`plot`], the plots;
//! - [`boundary`], where the scene accepts part A against the geometry; [`scan`], measured maps; [`compare`], two maps' agreement and two campaigns side by
//!   side; [`render`], one camera image with its edges, and the detectors' timing.

pub mod boundary;
pub mod calibration;
pub mod camera;
pub mod campaign;
pub mod compare;
pub mod decompose;
pub mod error;
pub mod eye;
pub mod fmu_driver;
pub mod fmu_log;
pub mod mismatch;
pub mod plot;
pub mod render;
pub mod report;
pub mod runtime;
pub mod scan;
pub mod scene;
pub mod sensor;
pub mod shard;
pub mod sim;
pub mod table;
pub mod trial;
pub mod vision;
pub mod world;

pub use error::{HarnessError, Result};
