//! The `trace` parameter's file: after every measurement the instance appends the
//! particles (pose in every uncertain DOF, weight) and the estimate, in the format of
//! [`model_description::trace`], which also reads it back.

use std::fs::OpenOptions;
use std::path::{Path, PathBuf};

use model_description::trace;

use crate::error::{FusionError, Result};
use crate::filter::Filter;

/// An instance's trace file.
#[derive(Debug, Clone)]
pub struct Trace {
    path: PathBuf,
    /// Whether this instance wrote its header yet (each writes one before its first rows).
    header_written: bool,
}

impl Trace {
    /// The trace at `path`, created if missing; refused when it cannot be opened for
    /// appending.
    ///
    /// # Errors
    /// [`FusionError::Trace`] naming the file and why.
    pub fn open(path: &Path) -> Result<Self> {
        OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| FusionError::Trace {
                path: path.to_owned(),
                reason: e.to_string(),
            })?;
        Ok(Self {
            path: path.to_owned(),
            header_written: false,
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends `filter`'s particles and estimate after its measurement number
    /// `measurement`.
    ///
    /// # Errors
    /// When the file cannot be opened or written.
    pub fn append(&mut self, measurement: u32, filter: &Filter) -> std::io::Result<()> {
        let file = OpenOptions::new().append(true).open(&self.path)?;
        let out = std::io::BufWriter::new(file);
        let d = filter.lookup().ndim();
        let header = (!self.header_written).then(|| trace::header(&filter.lookup().dof_names()));
        let poses = (0..filter.config().particles).map(|i| {
            (
                (0..d).map(|k| filter.particle(i, k)).collect(),
                filter.weight(i),
            )
        });
        let e = filter.estimate();
        trace::append(
            out,
            header.as_deref(),
            measurement,
            poses,
            (&e.pose, e.confidence),
        )?;
        self.header_written = true;
        Ok(())
    }
}
