//! The error type of the harness: one structured variant per way a library, scene, FMU,
//! map, camera, campaign or report can fail; wrapped errors stay reachable as sources.

use std::path::{Path, PathBuf};

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
    /// A scene file that MuJoCo loaded is not one the harness can drive.
    #[error("scene {}: {reason}", path.display())]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// MuJoCo refused a scene.
    #[error("scene {}: {source}", path.display())]
    SceneLoad {
        /// The scene file (`<string>` for MJCF text).
        path: PathBuf,
        /// MuJoCo's error.
        source: mujoco_rs::error::MjModelError,
    },
    /// A task's scene file has not been generated.
    #[error("scene {}: no such file (generate it: `harness scene --task {task}`)", path.display())]
    SceneMissing {
        /// Where the scene was looked for.
        path: PathBuf,
        /// The task it belongs to.
        task: String,
    },
    /// A scene just generated from its task does not load.
    #[error("loading the new scene {}", path.display())]
    NewScene {
        /// The scene file written.
        path: PathBuf,
        /// Why it does not load.
        source: Box<HarnessError>,
    },
    /// Committed scene files differ from what their tasks generate.
    #[error(
        "scenes not what their task.toml generates (write each again: `harness scene --task <its task>`): {}",
        joined(paths)
    )]
    ScenesStale {
        /// The stale scene files.
        paths: Vec<PathBuf>,
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
    #[error("FMU {what}{}", log.iter().map(|m| format!(": {m}")).collect::<String>())]
    Fmu {
        /// The call or variable concerned.
        what: String,
        /// What the FMU logged (warnings and errors) on the way, oldest first.
        log: Vec<String>,
        /// The importer's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A task, map or file problem reported by the map library.
    #[error(transparent)]
    Map(#[from] ftmap::MapError),
    /// A task's FT-Map could not be computed or read from the cache.
    #[error("the FT-Map of task {task}")]
    TaskMap {
        /// The task.
        task: String,
        /// The map library's error.
        source: ftmap::MapError,
    },
    /// The FT-Map file handed to the FMU does not exist.
    #[error("map {} not found: `ftmap generate --task {task} --out {}`", path.display(), path.display())]
    MapMissing {
        /// The map file.
        path: PathBuf,
        /// The task it should be computed for.
        task: String,
    },
    /// A map cannot serve as the world of a campaign.
    #[error("the map world: {0}")]
    MapWorld(String),
    /// The task has no camera (no `[camera]` table) but the camera was asked for.
    #[error(
        "vision: task {task} has no camera (a [camera] table in its task.toml; bearing_housing has one)"
    )]
    NoCamera {
        /// The task.
        task: String,
    },
    /// `render` asked for a task without a camera.
    #[error("task {task} has no vision features and no camera (only bearing_housing has)")]
    RenderNeedsCamera {
        /// The task.
        task: String,
    },
    /// The camera was asked for with a strategy that has no estimator to hand images to.
    #[error("--vision needs --strategy pf (the spiral search uses no estimator)")]
    VisionNeedsEstimator,
    /// Offscreen rendering failed (no OpenGL context, or the renderer refused).
    #[error("offscreen rendering: {source}")]
    Render {
        /// The renderer's error.
        source: mujoco_rs::renderer::RendererError,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A folder could not be created.
    #[error("creating {}", path.display())]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A CSV file could not be written, read or parsed.
    #[error("{}: {source}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// The CSV library's error.
        source: csv::Error,
    },
    /// A JSON file could not be written.
    #[error("{}: {source}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The JSON library's error.
        source: serde_json::Error,
    },
    /// An argument outside what the harness supports.
    #[error("{what}: {reason}")]
    Invalid {
        /// The argument.
        what: &'static str,
        /// Why it is refused.
        reason: String,
    },
    /// A plot or image could not be drawn or written.
    #[error("plot {}: {source}", path.display())]
    Plot {
        /// The image file.
        path: PathBuf,
        /// The plotting or PNG library's error.
        source: Box<dyn std::error::Error + Send + Sync>,
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

    /// A plotting or PNG error on the image `path`.
    pub fn plot(path: &Path, source: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        Self::Plot {
            path: path.to_owned(),
            source: source.into(),
        }
    }
}

/// Creates a folder and its parents.
///
/// # Errors
/// [`HarnessError::CreateDir`] when it cannot be created.
pub(crate) fn create_dir(path: &Path) -> Result<()> {
    std::fs::create_dir_all(path).map_err(|source| HarnessError::CreateDir {
        path: path.to_owned(),
        source,
    })
}

/// Creates the folder a file is to be written in (nothing for a bare file name).
///
/// # Errors
/// [`HarnessError::CreateDir`] when it cannot be created.
pub(crate) fn create_parent(file: &Path) -> Result<()> {
    match file.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => create_dir(dir),
        None => Ok(()),
    }
}

/// Paths joined by ", " for a message.
fn joined(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}
