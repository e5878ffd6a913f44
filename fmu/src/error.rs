//! The error type of the `ftfusion` crate: one structured variant per way a parameter,
//! map, measurement, saved state or FMI call can be refused.

use std::path::PathBuf;

/// Everything the estimator and the FMU instance can refuse.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FusionError {
    /// A parameter outside its allowed range.
    #[error("parameter `{name}` = {value} is out of range: expected {range}")]
    Parameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: String,
        /// The allowed range, e.g. `[10, 1000000]`.
        range: String,
    },
    /// The map cannot be used: not found, or unfit for the filter (no DOF, NaN cells).
    #[error("map {}: {reason}", path.display())]
    Map {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The map file could not be read (the map library's error names the file and why).
    #[error("map file unreadable")]
    MapFile(#[source] ftmap::MapError),
    /// The vision model file is not found.
    #[error("vision model {}: {reason}", path.display())]
    Vision {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The vision model file could not be read (the map library's error names the file
    /// and why).
    #[error("vision model file unreadable")]
    VisionFile(#[source] ftmap::MapError),
    /// The trace file cannot be opened for appending.
    #[error("trace file {}: {reason}", path.display())]
    Trace {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A measurement with NaN or infinite values.
    #[error("input `{name}` is {value}: measurement skipped")]
    NonFinite {
        /// The first non-finite input.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A finite input beyond any physical magnitude.
    #[error("input `{name}` is {value}, beyond ±{max}: not a measurement, skipped")]
    Absurd {
        /// The first such input.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The largest magnitude accepted.
        max: f64,
    },
    /// Saved state bytes that this build cannot restore into this instance.
    #[error("FMU state refused: {0}")]
    State(String),
    /// An FMI function called in a state where FMI 2.0 does not allow it.
    #[error("{call} is not allowed in state {mode}")]
    IllegalCall {
        /// The FMI function.
        call: &'static str,
        /// The instance's state.
        mode: &'static str,
    },
    /// A value reference, type or argument the FMU does not accept.
    #[error("{0}")]
    BadArgument(String),
    /// An FMI function this FMU does not provide.
    #[error("{0} is not supported by FtFusion")]
    Unsupported(&'static str),
}

/// The error and its chain of sources as one line, each cause once: what the FMU logs.
pub fn report(e: &dyn std::error::Error) -> String {
    let mut line = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        // Some errors repeat their source in their own message: say it once.
        if !line.contains(&text) {
            line = format!("{line}: {text}");
        }
        cause = c.source();
    }
    line
}

/// Result with [`FusionError`].
pub type Result<T, E = FusionError> = std::result::Result<T, E>;
