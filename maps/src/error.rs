//! The error type of the `ftmap` crate: one structured variant per way a task, mesh, map
//! file or computation can fail.

use std::path::PathBuf;

/// Everything that can go wrong while reading tasks and meshes, computing maps or reading
/// map files.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MapError {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The path names something other than a regular file (a FIFO, a device, a folder).
    #[error("{}: not a regular file but {kind}: refused before reading", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What it is.
        kind: &'static str,
    },
    /// The file is larger than what it may hold.
    #[error("{}: {size} bytes, more than {what} may have ({max} bytes)", path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its size (bytes).
        size: u64,
        /// The limit (bytes).
        max: u64,
        /// What the file was read as.
        what: &'static str,
    },
    /// A map value that is NaN (in a whole map) or beyond any physical magnitude.
    #[error("{}: corrupt data: cell {cell}, channel {channel} = {value}: not a finite value within ±{max}", path.display())]
    BadData {
        /// The file.
        path: PathBuf,
        /// The cell.
        cell: usize,
        /// The channel's name.
        channel: &'static str,
        /// The value read.
        value: f32,
        /// The largest magnitude allowed.
        max: f64,
    },
    /// The file does not start with the FT-Map magic bytes.
    #[error("{}: not an FT-Map file (starts with {found:02x?}, an FT-Map starts with {expected:02x?})", path.display())]
    NotAMap {
        /// The file.
        path: PathBuf,
        /// The first bytes found.
        found: Vec<u8>,
        /// The magic bytes expected.
        expected: Vec<u8>,
    },
    /// The file is an FT-Map of a format version this build cannot read.
    #[error("{}: FT-Map format version {found} is not supported (this build reads version {supported})", path.display())]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// The version in the file.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// The file ends before its declared content does.
    #[error("{}: truncated: {what} needs {expected} bytes but the file has {got}", path.display())]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Which part was cut off.
        what: &'static str,
        /// Bytes the file should have.
        expected: u64,
        /// Bytes it has.
        got: u64,
    },
    /// The stored checksum does not match the content.
    #[error("{}: corrupted: checksum stored {stored:08x}, computed {computed:08x}", path.display())]
    Checksum {
        /// The file.
        path: PathBuf,
        /// The CRC-32 in the file.
        stored: u32,
        /// The CRC-32 of the content.
        computed: u32,
    },
    /// The header is unreadable or disagrees with the data.
    #[error("{}: bad header: {reason}", path.display())]
    BadHeader {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A task description is missing, unreadable or inconsistent.
    #[error("task {}: {reason}", path.display())]
    Task {
        /// The task file or name.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A mesh file is missing or unreadable.
    #[error("mesh {}: {reason}", path.display())]
    Mesh {
        /// The mesh file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A name that is not one of the twelve DOFs.
    #[error("unknown DOF `{0}` (expected grip.x .. grip.rz or object.x .. object.rz)")]
    UnknownDof(String),
    /// A tolerance-space grid that cannot be built.
    #[error("invalid grid: {0}")]
    Grid(String),
    /// A coordinate list that does not fit the map's grid.
    #[error("coordinates: expected {expected} values (one per grid axis), got {got}")]
    Coordinates {
        /// Axes of the grid.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// The GPU backend could not start or failed.
    #[error("GPU backend: {0}")]
    Gpu(String),
    /// A rendering that does not fit the configuration (e.g. no overlap of the parts).
    #[error("geometry: {0}")]
    Geometry(String),
    /// A vision model file that is missing, unreadable or invalid.
    #[error("vision model {}: {reason}", path.display())]
    Vision {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

impl MapError {
    /// The conversion of an I/O error on `path` into [`MapError::Io`], for `map_err`.
    pub fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.to_owned();
        move |source| Self::Io { path, source }
    }
}

/// Result with [`MapError`].
pub type Result<T, E = MapError> = std::result::Result<T, E>;
