//! The variable table: every FMU variable once, with the attributes the XML writer emits
//! and the FMU checks against (value reference, type, causality, range).
//!
//! Value references: parameters 1xx, inputs 2xx, outputs 3xx. Vision parameters and
//! feature inputs take the ranges [`VISION_PARAMETER_VRS`] and [`VISION_INPUT_VRS`].

use std::ops::Range;

/// FMI 2.0 causality of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set before initialization, fixed afterwards.
    Parameter,
    /// Set by the importer before each step.
    Input,
    /// Computed by the FMU.
    Output,
}

/// FMI 2.0 variability of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variability {
    /// Constant after initialization.
    Fixed,
    /// Changes only at communication points.
    Discrete,
    /// May change continuously.
    Continuous,
}

/// FMI 2.0 `initial` attribute.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Initial {
    /// The start value is the value.
    Exact,
    /// Computed during initialization.
    Calculated,
}

/// Type of a variable's value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VarType {
    /// fmi2Real (f64).
    Real,
    /// fmi2Integer (i32).
    Integer,
    /// fmi2Boolean.
    Boolean,
    /// fmi2String.
    String,
}

/// Start value of a variable (none for calculated outputs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// No start attribute.
    None,
    /// A Real start value.
    Real(f64),
    /// An Integer start value.
    Integer(i32),
    /// A Boolean start value.
    Boolean(bool),
    /// A String start value.
    String(&'static str),
}

/// One FMU variable with all its attributes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variable {
    /// Exact name as in DESIGN.md (`wrench.fx`, `object.x_std`, ...).
    pub name: &'static str,
    /// Value reference, unique over all types.
    pub vr: u32,
    /// Parameter, input or output.
    pub causality: Causality,
    /// Fixed, discrete or continuous.
    pub variability: Variability,
    /// Exact (parameters, inputs) or calculated (outputs).
    pub initial: Initial,
    /// Value type.
    pub ty: VarType,
    /// Start value.
    pub start: Start,
    /// Unit name (one of [`crate::UNITS`]) or "" for none.
    pub unit: &'static str,
    /// Smallest allowed value (Real/Integer), inclusive.
    pub min: Option<f64>,
    /// Largest allowed value (Real/Integer), inclusive.
    pub max: Option<f64>,
    /// One line for the user.
    pub description: &'static str,
}

/// Value references of the vision parameters (`vision`, `sigma_vision`, ...).
pub const VISION_PARAMETER_VRS: Range<u32> = 150..200;
/// Value references of the vision feature inputs (`vision.*`).
pub const VISION_INPUT_VRS: Range<u32> = 250..300;

const fn param(
    name: &'static str,
    vr: u32,
    ty: VarType,
    start: Start,
    unit: &'static str,
    [min, max]: [Option<f64>; 2],
    description: &'static str,
) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Parameter,
        variability: Variability::Fixed,
        initial: Initial::Exact,
        ty,
        start,
        unit,
        min,
        max,
        description,
    }
}

const fn input(
    name: &'static str,
    vr: u32,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Input,
        variability: Variability::Continuous,
        initial: Initial::Exact,
        ty: VarType::Real,
        start: Start::Real(0.0),
        unit,
        min: None,
        max: None,
        description,
    }
}

const fn output(
    name: &'static str,
    vr: u32,
    ty: VarType,
    unit: &'static str,
    description: &'static str,
) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Output,
        variability: Variability::Discrete,
        initial: Initial::Calculated,
        ty,
        start: Start::None,
        unit,
        min: None,
        max: None,
        description,
    }
}

use VarType::{Boolean, Integer, Real};

/// Every variable of the FMU, in the order of `ModelVariables` (index = position + 1).
pub const VARIABLES: &[Variable] = &[
    // ---- Parameters (1xx) --------------------------------------------------------------
    param(
        "map",
        100,
        VarType::String,
        Start::String("peg_in_hole.ftmap"),
        "",
        [None, None],
        "FT-Map file: a name in the FMU's resources folder or an absolute path",
    ),
    param(
        "particles",
        101,
        Integer,
        Start::Integer(4000),
        "",
        [Some(10.0), Some(1_000_000.0)],
        "Number of particles",
    ),
    param(
        "seed",
        102,
        Integer,
        Start::Integer(1),
        "",
        [None, None],
        "Seed of the random numbers: equal seeds and inputs give equal outputs",
    ),
    param(
        "iterations",
        103,
        Integer,
        Start::Integer(20),
        "",
        [Some(1.0), Some(1000.0)],
        "Filter iterations (weight, resample, jitter) per contact measurement",
    ),
    param(
        "sigma_force",
        104,
        Real,
        Start::Real(1.0),
        "N",
        [Some(1e-6), Some(1e6)],
        "Standard deviation of a measured force component",
    ),
    param(
        "sigma_torque",
        105,
        Real,
        Start::Real(0.01),
        "N.m",
        [Some(1e-9), Some(1e6)],
        "Standard deviation of a measured torque component",
    ),
    param(
        "sigma_depth",
        106,
        Real,
        Start::Real(0.0005),
        "m",
        [Some(0.0), Some(1.0)],
        "Standard deviation of the contact height tcp.z against the map's depth; 0: depth unused",
    ),
    param(
        "jitter",
        107,
        Real,
        Start::Real(0.2),
        "",
        [Some(0.0), Some(10.0)],
        "Jitter after each iteration, standard deviation in grid intervals of each DOF",
    ),
    param(
        "confidence_radius",
        108,
        Real,
        Start::Real(0.0001),
        "m",
        [Some(1e-9), Some(1.0)],
        "Radius around the estimate within which particle weight counts as confidence \
         (rotations: the same number of grid intervals)",
    ),
    param(
        "threshold",
        109,
        Real,
        Start::Real(0.9),
        "",
        [Some(0.0), Some(1.0)],
        "Confidence above which `converged` is true",
    ),
    param(
        "interpolation",
        110,
        Integer,
        Start::Integer(1),
        "",
        [Some(0.0), Some(1.0)],
        "Map lookup: 0 nearest cell, 1 multilinear",
    ),
    // ---- Vision parameters (reserved: VISION_PARAMETER_VRS, 150..199) -------------------
    param(
        "vision",
        150,
        VarType::String,
        Start::String(""),
        "",
        [None, None],
        "Vision model file (*.vision.json: camera and CAD features): a name in the FMU's \
         resources folder or an absolute path; empty: no vision",
    ),
    param(
        "sigma_vision",
        151,
        Real,
        Start::Real(0.5),
        "px",
        [Some(1e-6), Some(1e6)],
        "Standard deviation of a measured feature distance or edge column",
    ),
    param(
        "vision_method",
        152,
        Integer,
        Start::Integer(1),
        "",
        [Some(0.0), Some(1.0)],
        "Particle evaluation by vision: 0 relative feature distances (III-B-1), \
         1 camera recalibration on the passive part (III-B-2)",
    ),
    // ---- Inputs (2xx) -------------------------------------------------------------------
    input(
        "wrench.fx",
        200,
        "N",
        "Measured force x in the sensor (= nominal task) frame",
    ),
    input(
        "wrench.fy",
        201,
        "N",
        "Measured force y in the sensor frame",
    ),
    input(
        "wrench.fz",
        202,
        "N",
        "Measured force z in the sensor frame",
    ),
    input(
        "wrench.tx",
        203,
        "N.m",
        "Measured torque x about the sensor origin",
    ),
    input(
        "wrench.ty",
        204,
        "N.m",
        "Measured torque y about the sensor origin",
    ),
    input(
        "wrench.tz",
        205,
        "N.m",
        "Measured torque z about the sensor origin",
    ),
    input(
        "tcp.x",
        206,
        "m",
        "Task frame relative to the nominal goal frame: x",
    ),
    input(
        "tcp.y",
        207,
        "m",
        "Task frame relative to the nominal goal frame: y",
    ),
    input(
        "tcp.z",
        208,
        "m",
        "Task frame relative to the nominal goal frame: z (at contact: the contact height)",
    ),
    input(
        "tcp.rx",
        209,
        "rad",
        "Task frame relative to the nominal goal frame: rotation-vector x",
    ),
    input(
        "tcp.ry",
        210,
        "rad",
        "Task frame relative to the nominal goal frame: rotation-vector y",
    ),
    input(
        "tcp.rz",
        211,
        "rad",
        "Task frame relative to the nominal goal frame: rotation-vector z",
    ),
    Variable {
        name: "contact",
        vr: 212,
        causality: Causality::Input,
        variability: Variability::Discrete,
        initial: Initial::Exact,
        ty: Boolean,
        start: Start::Boolean(false),
        unit: "",
        min: None,
        max: None,
        description: "The wrench is a settled contact; a measurement is taken on its rising edge",
    },
    // ---- Vision feature inputs (reserved: VISION_INPUT_VRS, 250..299) -------------------
    input(
        "vision.left_distance",
        250,
        "px",
        "Detected distance along u, at the image's centre row, from the active part's left \
         edge to the passive part's left edge",
    ),
    input(
        "vision.right_distance",
        251,
        "px",
        "Detected distance along u from the active part's right edge to the passive part's right edge",
    ),
    input(
        "vision.passive_left",
        252,
        "px",
        "Detected column (u) of the passive part's left edge at the centre row (vision_method 1)",
    ),
    input(
        "vision.passive_right",
        253,
        "px",
        "Detected column (u) of the passive part's right edge at the centre row (vision_method 1)",
    ),
    Variable {
        name: "vision.valid",
        vr: 254,
        causality: Causality::Input,
        variability: Variability::Discrete,
        initial: Initial::Exact,
        ty: Boolean,
        start: Start::Boolean(false),
        unit: "",
        min: None,
        max: None,
        description: "The vision inputs hold a detection: used by the next contact measurement, \
                      or alone on its rising edge while contact is false",
    },
    // ---- Outputs (3xx) ------------------------------------------------------------------
    output(
        "object.x",
        300,
        Real,
        "m",
        "Estimated mating-part frame relative to the nominal goal: x",
    ),
    output(
        "object.y",
        301,
        Real,
        "m",
        "Estimated mating-part frame relative to the nominal goal: y",
    ),
    output(
        "object.z",
        302,
        Real,
        "m",
        "Estimated mating-part frame relative to the nominal goal: z",
    ),
    output(
        "object.rx",
        303,
        Real,
        "rad",
        "Estimated mating-part frame relative to the nominal goal: rx",
    ),
    output(
        "object.ry",
        304,
        Real,
        "rad",
        "Estimated mating-part frame relative to the nominal goal: ry",
    ),
    output(
        "object.rz",
        305,
        Real,
        "rad",
        "Estimated mating-part frame relative to the nominal goal: rz",
    ),
    output("grip.x", 306, Real, "m", "Estimated grip offset: x"),
    output("grip.y", 307, Real, "m", "Estimated grip offset: y"),
    output("grip.z", 308, Real, "m", "Estimated grip offset: z"),
    output("grip.rx", 309, Real, "rad", "Estimated grip offset: rx"),
    output("grip.ry", 310, Real, "rad", "Estimated grip offset: ry"),
    output("grip.rz", 311, Real, "rad", "Estimated grip offset: rz"),
    output(
        "object.x_std",
        312,
        Real,
        "m",
        "Spread (weighted standard deviation) of the dominant cluster: object.x",
    ),
    output(
        "object.y_std",
        313,
        Real,
        "m",
        "Spread of the dominant cluster: object.y",
    ),
    output(
        "object.z_std",
        314,
        Real,
        "m",
        "Spread of the dominant cluster: object.z",
    ),
    output(
        "object.rx_std",
        315,
        Real,
        "rad",
        "Spread of the dominant cluster: object.rx",
    ),
    output(
        "object.ry_std",
        316,
        Real,
        "rad",
        "Spread of the dominant cluster: object.ry",
    ),
    output(
        "object.rz_std",
        317,
        Real,
        "rad",
        "Spread of the dominant cluster: object.rz",
    ),
    output(
        "grip.x_std",
        318,
        Real,
        "m",
        "Spread of the dominant cluster: grip.x",
    ),
    output(
        "grip.y_std",
        319,
        Real,
        "m",
        "Spread of the dominant cluster: grip.y",
    ),
    output(
        "grip.z_std",
        320,
        Real,
        "m",
        "Spread of the dominant cluster: grip.z",
    ),
    output(
        "grip.rx_std",
        321,
        Real,
        "rad",
        "Spread of the dominant cluster: grip.rx",
    ),
    output(
        "grip.ry_std",
        322,
        Real,
        "rad",
        "Spread of the dominant cluster: grip.ry",
    ),
    output(
        "grip.rz_std",
        323,
        Real,
        "rad",
        "Spread of the dominant cluster: grip.rz",
    ),
    output(
        "confidence",
        324,
        Real,
        "",
        "Particle weight within confidence_radius of the estimate (0..1)",
    ),
    output("converged", 325, Boolean, "", "confidence > threshold"),
    output(
        "ess",
        326,
        Real,
        "",
        "Effective sample size of the particle weights",
    ),
    output(
        "measurements",
        327,
        Integer,
        "",
        "Measurements used so far: contacts, and images taken alone",
    ),
    output(
        "clusters",
        328,
        Integer,
        "",
        "Particle clusters holding at least 5 % of the weight",
    ),
];

/// The variable with value reference `vr`.
pub fn by_vr(vr: u32) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.vr == vr)
}

/// The variable called `name`.
pub fn by_name(name: &str) -> Option<&'static Variable> {
    VARIABLES.iter().find(|v| v.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_references_and_names_are_unique_and_grouped() {
        for (i, v) in VARIABLES.iter().enumerate() {
            assert!(
                VARIABLES[..i]
                    .iter()
                    .all(|w| w.vr != v.vr && w.name != v.name),
                "{} repeated",
                v.name
            );
            let group = match v.causality {
                Causality::Parameter => 100..200,
                Causality::Input => 200..300,
                Causality::Output => 300..400,
            };
            assert!(group.contains(&v.vr), "{} vr {}", v.name, v.vr);
            let vision = v.name.starts_with("vision") || v.name == "sigma_vision";
            let reserved = VISION_PARAMETER_VRS.contains(&v.vr) || VISION_INPUT_VRS.contains(&v.vr);
            assert_eq!(
                vision, reserved,
                "{} vr {}: vision variables and only they take the vision ranges",
                v.name, v.vr
            );
        }
    }

    #[test]
    fn every_dof_has_an_estimate_and_a_spread_output() {
        for pose in ["object", "grip"] {
            for axis in ["x", "y", "z", "rx", "ry", "rz"] {
                let est = by_name(&format!("{pose}.{axis}")).expect("estimate output");
                let std = by_name(&format!("{pose}.{axis}_std")).expect("spread output");
                assert_eq!(est.unit, std.unit);
                assert_eq!(est.unit, if axis.starts_with('r') { "rad" } else { "m" });
            }
        }
    }
}
