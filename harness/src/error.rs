//! The error type of the harness: one structured variant per way a library, scene, FMU,
//! map or trial can fail.

use std::path::PathBuf;

/// Everything the harness can refuse or fail at.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum HarnessError {
    /// The MuJoCo library found at run time is not the one mujoco-rs binds.
    #[error(
        "MuJoCo {got} found, the harness needs {expected} (mujoco-rs 7.0.0): run `bash scripts/setup.sh` \
         (it installs libmujoco.so.3.17.0 into .deps/mujoco/)"
    )]
    MujocoVersion {
        /// The version the harness is built for (3017000 for 3.17.0).
        expected: i32,
        /// The version of the loaded library.
        got: i32,
    },
    /// MuJoCo refused a scene.
    #[error("scene {}: {reason}", path.display())]
    Scene {
        /// The scene file (or the task it was generated for).
        path: PathBuf,
        /// MuJoCo's or the generator's message.
        reason: String,
    },
    /// A named element the harness needs is missing from a scene.
    #[error("scene has no {kind} named `{name}` (regenerate it: `harness scene --task <task>`)")]
    SceneElement {
        /// Element kind (body, joint, actuator, sensor, site).
        kind: &'static str,
        /// Its expected name.
        name: &'static str,
    },
    /// The FMU file is missing.
    #[error("FMU {} not found: build it with `cargo xtask fmu`", path.display())]
    FmuMissing {
        /// Where it was looked for.
        path: PathBuf,
    },
    /// The FMU could not be loaded, instantiated or driven.
    #[error("FMU {what}: {reason}")]
    Fmu {
        /// The call or variable concerned.
        what: String,
        /// The importer's message.
        reason: String,
    },
    /// A task, map or file problem reported by the map library.
    #[error(transparent)]
    Map(#[from] ftmap::MapError),
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// An argument outside what the harness supports.
    #[error("{what}: {reason}")]
    Invalid {
        /// The argument.
        what: &'static str,
        /// Why it is refused.
        reason: String,
    },
    /// A plot could not be drawn.
    #[error("plot {}: {reason}", path.display())]
    Plot {
        /// The image file.
        path: PathBuf,
        /// The plotting library's message.
        reason: String,
    },
}

/// Result with [`HarnessError`].
pub type Result<T> = std::result::Result<T, HarnessError>;

impl HarnessError {
    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}
