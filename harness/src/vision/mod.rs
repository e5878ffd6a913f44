//! The camera pipeline of experiment D (the paper's section III): from a grey image and the
//! vision model's expected edges to the relative features the FMU compares per particle.
//!
//! Dependencies point down only: [`features`] uses the two detectors, [`gradient`] (the
//! paper's Fig. 5) and [`hough`] (the bounded Hough transform of section III-A), which use
//! only the image primitives of [`image`].
//!
//! - [`image`], the primitives: the Sobel gradient, [`Line`](image::Line), the robust line
//!   fit, image noise, [`VisionError`](image::VisionError);
//! - [`gradient`], [`detect_line`](gradient::detect_line): gradient maxima per row or column;
//! - [`hough`], [`detect_line_hough`](hough::detect_line_hough): the bounded Hough transform;
//! - [`features`], the expected edges, the [`Detector`], [`detect_edges`](features::detect_edges)
//!   and the [`Features`] handed to the FMU.

pub mod features;
pub mod gradient;
pub mod hough;
pub mod image;

pub use features::{Detector, Features};
