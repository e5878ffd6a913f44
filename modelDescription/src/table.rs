//! The variable table: every FMU variable once, with the attributes the XML writer emits
//! and the FMU checks against (value reference, type, causality, range).
//!
//! Value references: parameters 1xx, inputs 2xx, outputs 3xx. Vision parameters and
//! feature inputs take the ranges [`VISION_PARAMETER_VRS`] and [`VISION_INPUT_VRS`].
//!
//! The variables that belong together (the wrench, the TCP pose, the vision features, the
//! estimate and its spread) are named once here as groups, in the order the filter and the
//! harness use them, as the Reference FMUs' `config.h` enumerates its value references; the
//! table is written from the groups, and the FMU and its drivers take the names from them.

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
    /// Exact name (`wrench.fx`, `object.x_std`, ...), as docs/fmu.md lists it.
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

/// The measured wrench inputs: fx, fy, fz (N), tx, ty, tz (N.m) about the sensor origin.
pub const WRENCH: [&str; 6] = [
    "wrench.fx",
    "wrench.fy",
    "wrench.fz",
    "wrench.tx",
    "wrench.ty",
    "wrench.tz",
];
/// The TCP pose inputs: x, y, z (m), rx, ry, rz (rad) of the task frame relative to the
/// nominal goal frame.
pub const TCP: [&str; 6] = ["tcp.x", "tcp.y", "tcp.z", "tcp.rx", "tcp.ry", "tcp.rz"];
/// The input flag whose rising edge takes the wrench as a contact measurement.
pub const CONTACT: &str = "contact";
/// The contact ended a slide under force from `SLIDE_START`.
pub const SLIDE: &str = "slide";
/// Where a slide under force started (m, task frame relative to the nominal goal).
pub const SLIDE_START: [&str; 3] = ["slide_start.x", "slide_start.y", "slide_start.rz"];
/// The input flag saying `SLIDE_END` holds where the slide ended, the contact pressed after it.
pub const SLIDE_END_VALID: &str = "slide_end.valid";
/// Where a slide under force ended, when the contact was pressed elsewhere after it (m, rad).
pub const SLIDE_END: [&str; 3] = ["slide_end.x", "slide_end.y", "slide_end.rz"];
/// The vision feature inputs (px): the left and right distances from the active part's
/// edge to the passive part's, then the passive part's left and right columns.
pub const VISION_FEATURES: [&str; 4] = [
    "vision.left_distance",
    "vision.right_distance",
    "vision.passive_left",
    "vision.passive_right",
];
/// The input flag saying the vision inputs hold a detection.
pub const VISION_VALID: &str = "vision.valid";
/// The estimated grip offset outputs, x .. rz.
pub const GRIP: [&str; 6] = [
    "grip.x", "grip.y", "grip.z", "grip.rx", "grip.ry", "grip.rz",
];
/// The estimated object pose outputs, x .. rz: commanding `tcp := object` mates the parts.
pub const OBJECT: [&str; 6] = [
    "object.x",
    "object.y",
    "object.z",
    "object.rx",
    "object.ry",
    "object.rz",
];
/// The spread outputs of the grip offset, in the order of [`GRIP`].
pub const GRIP_STD: [&str; 6] = [
    "grip.x_std",
    "grip.y_std",
    "grip.z_std",
    "grip.rx_std",
    "grip.ry_std",
    "grip.rz_std",
];
/// The spread outputs of the object pose, in the order of [`OBJECT`].
pub const OBJECT_STD: [&str; 6] = [
    "object.x_std",
    "object.y_std",
    "object.z_std",
    "object.rx_std",
    "object.ry_std",
    "object.rz_std",
];
/// The correlation of the object's x and y spreads.
pub const OBJECT_XY_CORR: &str = "object.xy_corr";

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

/// A Boolean input that is false until the importer raises it (a discrete event).
const fn flag(name: &'static str, vr: u32, description: &'static str) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Input,
        variability: Variability::Discrete,
        initial: Initial::Exact,
        ty: Boolean,
        start: Start::Boolean(false),
        unit: "",
        min: None,
        max: None,
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
        Start::Integer(0),
        "",
        [Some(0.0), Some(1_000_000.0)],
        "Number of particles, at least 10; 0: automatic, 4000 for up to two uncertain DOFs and four times as many per DOF beyond (16000 for three, 64000 for four)",
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
        "Filter iterations (weight, resample, jitter) per contact measurement; each weighs with \
         the likelihood to the power 1 / iterations, so that a measurement counts once",
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
        Start::Real(0.003),
        "N.m",
        [Some(1e-9), Some(1e6)],
        "Standard deviation of a measured torque component",
    ),
    param(
        "sigma_depth",
        106,
        Real,
        Start::Real(0.00002),
        "m",
        [Some(0.0), Some(1.0)],
        "Standard deviation of the contact height tcp.z against the map's depth; 0: depth unused, else at least 1e-9",
    ),
    param(
        "jitter",
        107,
        Real,
        Start::Real(0.15),
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
    param(
        "tail",
        111,
        Real,
        Start::Real(4.0),
        "",
        [Some(0.0), Some(1e6)],
        "Degrees of freedom of the Student-t likelihood of the wrench residual (heavy tails: \
         a contact the map does not explain cannot wipe out the right hypothesis); 0: Gaussian",
    ),
    param(
        "clearance",
        112,
        Real,
        Start::Real(0.0),
        "m",
        [Some(-1.0), Some(1.0)],
        "Radial clearance of the fit: a contact that did not go in rules out part B within it \
         of the TCP (maps over object.x, object.y, grip translations and object rotations \
         with play; it replaces the depth channel there); \
         0: the map's (ftmap writes it from the task's geometry), none if the map has none; \
         negative: off",
    ),
    param(
        "mismatch",
        113,
        Real,
        Start::Real(-1.0),
        "",
        [Some(-1.0), Some(1.0)],
        "Share of the measured force's and torque's magnitudes that the map may miss (contact \
         physics it does not model): along the measured vector, added to sigma_force and \
         sigma_torque in quadrature; negative: the map's (0.01; 0.02 on a map of the \
         object's tilts about x or y, whose edge contacts friction decides)",
    ),
    param(
        "mismatch_angle",
        114,
        Real,
        Start::Real(-1.0),
        "rad",
        [Some(-1.0), Some(1.0)],
        "Angle by which the map may miss the direction of the measured force and torque: across \
         the measured vector, that angle times its magnitude is added to sigma_force and \
         sigma_torque in quadrature; negative: the map's (0.01; 0.02 on a map of the object's \
         tilts about x or y)",
    ),
    param(
        "trace",
        115,
        VarType::String,
        Start::String(""),
        "",
        [None, None],
        "File to which every measurement appends the particles (pose in each uncertain DOF, \
         weight) and the estimate, CSV (docs/fmu.md, Trace files); created if missing; empty: \
         none",
    ),
    param(
        "lost",
        116,
        Real,
        Start::Real(1e-9),
        "",
        [Some(0.0), Some(0.5)],
        "Prior probability that the particles have lost the truth (locked on a wrong \
         hypothesis): where the measurements since they last explained one better than a \
         uniform draw over Omega does make that more likely than not, half the particles are \
         redrawn uniformly over Omega; 0: never",
    ),
    param(
        "centre_map",
        117,
        VarType::String,
        Start::String(""),
        "",
        [None, None],
        "Centre map of `map` (a finer map of the cells around the goal, `ftmap generate \
         --centre`): a name in the FMU's resources folder or an absolute path; empty: none",
    ),
    param(
        "mismatch_position",
        118,
        Real,
        Start::Real(5e-6),
        "m",
        [Some(0.0), Some(0.001)],
        "How far the contact may sit from where the map has it (standard deviation in each \
         axis across the approach; on an object rotation, over the lever at which the fit's \
         play takes up its clearance): the variance of the force's and torque's x and y \
         components grows by its square times their squared slope at the particle (steep near \
         the hole, flat far from it), with the likelihood's normalisation; 0: none",
    ),
    param(
        "mismatch_interpolation",
        119,
        Real,
        Start::Real(1.0),
        "",
        [Some(0.0), Some(100.0)],
        "Share of the multilinear lookup's own error that counts as model mismatch: the \
         variance of the force's and torque's x and y components grows by it times the mean \
         square of the interpolation error that the map's second differences imply at the \
         particle (large within a few cells of the hole, where the rim torque turns), with \
         the likelihood's normalisation; 1: as the map implies it, 0: none (e.g. a world that \
         is the interpolated map itself). The nearest-cell lookup counts that share of its \
         cell's width (a step h: h^2 / 12) in the position term instead",
    ),
    param(
        "tilt_floor",
        120,
        Real,
        Start::Real(0.0),
        "rad",
        [Some(-1.0), Some(1.0)],
        "On a map of the object's tilts about x and y: the relative tilt below which the \
         force and torque are read where the tilt's direction meets this radius (a flat face \
         tilted by any angle rests on its lowest edge, so its wrench follows the tilt's \
         direction, not its size; depth and insertion are read where the particle lies); \
         0: the diagonal of the map's tilt step; negative: off",
    ),
    param(
        "mismatch_reach",
        121,
        Real,
        Start::Real(1.0),
        "",
        [Some(0.0), Some(100.0)],
        "How near a contact must lie to earlier ones, in grid steps of each map axis the TCP \
         moves, for the map to miss them alike: the mismatch terms (`mismatch`, \
         `mismatch_angle`, `mismatch_position`, `mismatch_interpolation`, \
         `mismatch_lever`) then count once over the contacts at that place while the \
         sensor noise counts at each, so a press repeated where the map misses does not \
         say the miss again; 0: every contact's mismatch is drawn afresh",
    ),
    param(
        "mismatch_lever",
        122,
        Real,
        Start::Real(-1.0),
        "m",
        [Some(-1.0), Some(0.01)],
        "How far the contact's pressure centre may lie from where the map has it (standard \
         deviation across the force): that distance times the measured force's magnitude (up \
         to the map's largest) is added to the miss of each torque component in quadrature, \
         near the hole and far from it alike (a miss that does not grow with the torque); 0: \
         none; negative: the map's (5e-5 m; 0 on a map of the object's tilts about x or y, \
         whose edge point has no face to wander over)",
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
        Start::Real(0.2),
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
        WRENCH[0],
        200,
        "N",
        "Measured force x in the sensor (= nominal task) frame",
    ),
    input(WRENCH[1], 201, "N", "Measured force y in the sensor frame"),
    input(WRENCH[2], 202, "N", "Measured force z in the sensor frame"),
    input(
        WRENCH[3],
        203,
        "N.m",
        "Measured torque x about the sensor origin",
    ),
    input(
        WRENCH[4],
        204,
        "N.m",
        "Measured torque y about the sensor origin",
    ),
    input(
        WRENCH[5],
        205,
        "N.m",
        "Measured torque z about the sensor origin",
    ),
    input(
        TCP[0],
        206,
        "m",
        "Task frame relative to the nominal goal frame: x",
    ),
    input(
        TCP[1],
        207,
        "m",
        "Task frame relative to the nominal goal frame: y",
    ),
    input(
        TCP[2],
        208,
        "m",
        "Task frame relative to the nominal goal frame: z (at contact: the contact height)",
    ),
    input(
        TCP[3],
        209,
        "rad",
        "Task frame relative to the nominal goal frame: rotation-vector x",
    ),
    input(
        TCP[4],
        210,
        "rad",
        "Task frame relative to the nominal goal frame: rotation-vector y",
    ),
    input(
        TCP[5],
        211,
        "rad",
        "Task frame relative to the nominal goal frame: rotation-vector z",
    ),
    flag(
        CONTACT,
        212,
        "The wrench is a settled contact; a measurement is taken on its rising edge",
    ),
    flag(
        SLIDE,
        213,
        "The contact ended a slide under force from slide_start.x, slide_start.y \
         (a twist: from slide_start.rz) that did not go in: the line swept rules out \
         part B within the clearance of it, as a contact does of its point",
    ),
    input(
        SLIDE_START[0],
        214,
        "m",
        "Where the slide started: x in the frame of tcp.x",
    ),
    input(
        SLIDE_START[1],
        215,
        "m",
        "Where the slide started: y in the frame of tcp.y",
    ),
    input(
        SLIDE_START[2],
        216,
        "rad",
        "Where a twist under force (the TCP turned about z while pressing) started: \
         rz in the frame of tcp.rz",
    ),
    flag(
        SLIDE_END_VALID,
        217,
        "With slide: the slide ended at slide_end.x, slide_end.y, slide_end.rz, and the \
         contact (tcp.*) was pressed after it, lifted off the line's end (at the estimate, \
         say): the line swept runs from slide_start to slide_end, and the press rules out \
         part B within the clearance of its own point. False: the slide ended at the contact",
    ),
    input(
        SLIDE_END[0],
        218,
        "m",
        "Where the slide ended: x in the frame of tcp.x (with slide_end.valid)",
    ),
    input(
        SLIDE_END[1],
        219,
        "m",
        "Where the slide ended: y in the frame of tcp.y (with slide_end.valid)",
    ),
    input(
        SLIDE_END[2],
        220,
        "rad",
        "Where a twist under force ended: rz in the frame of tcp.rz (with slide_end.valid)",
    ),
    // ---- Vision feature inputs (reserved: VISION_INPUT_VRS, 250..299) -------------------
    input(
        VISION_FEATURES[0],
        250,
        "px",
        "Detected distance along u, at the image's centre row, from the active part's left \
         edge to the passive part's left edge",
    ),
    input(
        VISION_FEATURES[1],
        251,
        "px",
        "Detected distance along u from the active part's right edge to the passive part's right edge",
    ),
    input(
        VISION_FEATURES[2],
        252,
        "px",
        "Detected column (u) of the passive part's left edge at the centre row (vision_method 1)",
    ),
    input(
        VISION_FEATURES[3],
        253,
        "px",
        "Detected column (u) of the passive part's right edge at the centre row (vision_method 1)",
    ),
    flag(
        VISION_VALID,
        254,
        "The vision inputs hold a detection: used by the next contact measurement, \
         or alone on its rising edge while contact is false",
    ),
    // ---- Outputs (3xx) ------------------------------------------------------------------
    output(
        OBJECT[0],
        300,
        Real,
        "m",
        "Estimated mating-part frame relative to the nominal goal: x",
    ),
    output(
        OBJECT[1],
        301,
        Real,
        "m",
        "Estimated mating-part frame relative to the nominal goal: y",
    ),
    output(
        OBJECT[2],
        302,
        Real,
        "m",
        "Estimated mating-part frame relative to the nominal goal: z",
    ),
    output(
        OBJECT[3],
        303,
        Real,
        "rad",
        "Estimated mating-part frame relative to the nominal goal: rx",
    ),
    output(
        OBJECT[4],
        304,
        Real,
        "rad",
        "Estimated mating-part frame relative to the nominal goal: ry",
    ),
    output(
        OBJECT[5],
        305,
        Real,
        "rad",
        "Estimated mating-part frame relative to the nominal goal: rz",
    ),
    output(GRIP[0], 306, Real, "m", "Estimated grip offset: x"),
    output(GRIP[1], 307, Real, "m", "Estimated grip offset: y"),
    output(GRIP[2], 308, Real, "m", "Estimated grip offset: z"),
    output(GRIP[3], 309, Real, "rad", "Estimated grip offset: rx"),
    output(GRIP[4], 310, Real, "rad", "Estimated grip offset: ry"),
    output(GRIP[5], 311, Real, "rad", "Estimated grip offset: rz"),
    output(
        OBJECT_STD[0],
        312,
        Real,
        "m",
        "Spread of the particles about the estimate (weighted RMS distance, every cluster counted: its expected error): object.x",
    ),
    output(
        OBJECT_STD[1],
        313,
        Real,
        "m",
        "Spread of the particles about the estimate: object.y",
    ),
    output(
        OBJECT_STD[2],
        314,
        Real,
        "m",
        "Spread of the particles about the estimate: object.z",
    ),
    output(
        OBJECT_STD[3],
        315,
        Real,
        "rad",
        "Spread of the particles about the estimate: object.rx",
    ),
    output(
        OBJECT_STD[4],
        316,
        Real,
        "rad",
        "Spread of the particles about the estimate: object.ry",
    ),
    output(
        OBJECT_STD[5],
        317,
        Real,
        "rad",
        "Spread of the particles about the estimate: object.rz",
    ),
    output(
        GRIP_STD[0],
        318,
        Real,
        "m",
        "Spread of the particles about the estimate: grip.x",
    ),
    output(
        GRIP_STD[1],
        319,
        Real,
        "m",
        "Spread of the particles about the estimate: grip.y",
    ),
    output(
        GRIP_STD[2],
        320,
        Real,
        "m",
        "Spread of the particles about the estimate: grip.z",
    ),
    output(
        GRIP_STD[3],
        321,
        Real,
        "rad",
        "Spread of the particles about the estimate: grip.rx",
    ),
    output(
        GRIP_STD[4],
        322,
        Real,
        "rad",
        "Spread of the particles about the estimate: grip.ry",
    ),
    output(
        GRIP_STD[5],
        323,
        Real,
        "rad",
        "Spread of the particles about the estimate: grip.rz",
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
    output(
        OBJECT_XY_CORR,
        329,
        Real,
        "",
        "Correlation of object.x and object.y over the particles about the estimate \
         (-1..1): with object.x_std and object.y_std, the spread along any direction; 0 unless \
         both are uncertain",
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
    fn every_group_names_table_variables_of_its_kind() {
        let kind = |name: &str| {
            let v = by_name(name).unwrap_or_else(|| panic!("{name} is not in the table"));
            (v.causality, v.ty)
        };
        let real_in = (Causality::Input, VarType::Real);
        let bool_in = (Causality::Input, VarType::Boolean);
        let real_out = (Causality::Output, VarType::Real);
        for name in WRENCH.iter().chain(&TCP).chain(&VISION_FEATURES) {
            assert_eq!(kind(name), real_in, "{name}");
        }
        for name in [CONTACT, VISION_VALID] {
            assert_eq!(kind(name), bool_in, "{name}");
        }
        for name in GRIP
            .iter()
            .chain(&OBJECT)
            .chain(&GRIP_STD)
            .chain(&OBJECT_STD)
            .chain(&[OBJECT_XY_CORR])
        {
            assert_eq!(kind(name), real_out, "{name}");
        }
        // Spreads follow their estimates, value references in the same order.
        for (est, std) in GRIP
            .iter()
            .chain(&OBJECT)
            .zip(GRIP_STD.iter().chain(&OBJECT_STD))
        {
            assert_eq!(format!("{est}_std"), *std);
        }
        let vrs = |names: &[&str]| {
            names
                .iter()
                .map(|n| by_name(n).map(|v| v.vr))
                .collect::<Vec<_>>()
        };
        for group in [&WRENCH[..], &TCP, &OBJECT, &OBJECT_STD] {
            let v = vrs(group);
            assert!(
                v.windows(2).all(|w| w[1] == w[0].map(|x| x + 1)),
                "{group:?}: {v:?}"
            );
        }
    }

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
