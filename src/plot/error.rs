//! What stops `hvi plot`: each error names the run directory or the file, and what to do.

use crate::output::OutputError;
use std::path::PathBuf;

/// Why a run's pictures could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The run directory, or a file in it, is not what `hvi solve` writes (or cannot be drawn).
    #[error("{}: {detail}", dir.display())]
    Run { dir: PathBuf, detail: String },
    /// An obstacle of the run's `scene.toml` cannot be drawn (the message names the key).
    #[error("{0}")]
    Scene(String),
    /// A file could not be read or written.
    #[error(transparent)]
    Output(#[from] OutputError),
}
