#![doc = include_str!("../README.md")]
//!
//! The FMU dispatches its get/set calls through [`VARIABLES`]; the packager writes
//! [`xml()`]; the FMU, its tests and the harness's FMI driver take the names of the
//! variables that belong together from the groups ([`WRENCH`], [`TCP`], [`CONTACT`],
//! [`SLIDE`], [`SLIDE_START`], [`SLIDE_END_VALID`], [`SLIDE_END`], [`VISION_FEATURES`],
//! [`VISION_VALID`], [`OBJECT`], [`GRIP`] and their spreads); both read the [`trace`] file
//! format.

mod table;
pub mod trace;
mod xml;

pub use table::{
    CONTACT, Causality, GRIP, GRIP_STD, Initial, OBJECT, OBJECT_STD, OBJECT_XY_CORR, SLIDE,
    SLIDE_END, SLIDE_END_VALID, SLIDE_START, Start, TCP, VARIABLES, VISION_FEATURES,
    VISION_INPUT_VRS, VISION_PARAMETER_VRS, VISION_VALID, VarType, Variability, Variable, WRENCH,
    by_name, by_vr,
};
pub use xml::{guid, xml};

/// The FMU's model name and `modelIdentifier` (the shared library's file stem).
pub const MODEL_IDENTIFIER: &str = "FtFusion";

/// The FMI version the FMU implements.
pub const FMI_VERSION: &str = "2.0";

/// Units used by the variables: (name, exponents of kg, m, s, rad); `px` (image pixels)
/// is dimensionless.
pub const UNITS: [(&str, [i32; 4]); 5] = [
    ("m", [0, 1, 0, 0]),
    ("rad", [0, 0, 0, 1]),
    ("N", [1, 1, -2, 0]),
    ("N.m", [1, 2, -2, 0]),
    ("px", [0, 0, 0, 0]),
];

/// Log categories the FMU knows, with what each reports.
pub const LOG_CATEGORIES: [(&str, &str); 4] = [
    (
        "logStatusWarning",
        "Skipped measurements, degenerate particle sets",
    ),
    (
        "logStatusError",
        "Refused calls, bad parameters, unreadable maps",
    ),
    (
        "logFilter",
        "One line per measurement: estimate, confidence, ESS, clusters",
    ),
    ("logCalls", "Every FMI call"),
];
