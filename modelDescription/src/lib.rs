//! The interface of `FtFusion.fmu` (FMI 2.0 Co-Simulation), written once: the variable
//! table (names, value references, causality, variability, start values, units, ranges),
//! the GUID derived from it, and the writer of `modelDescription.xml`. The FMU dispatches
//! its get/set calls through [`VARIABLES`]; the packager writes [`xml()`].

mod table;
mod xml;

pub use table::{
    Causality, Initial, Start, VARIABLES, VISION_INPUT_VRS, VISION_PARAMETER_VRS, VarType,
    Variability, Variable, by_name, by_vr,
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
