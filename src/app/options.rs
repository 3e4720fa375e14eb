//! The options of `hvi solve`.

use std::path::PathBuf;

/// Options of `hvi solve`.
pub struct SolveOptions {
    pub mesh: PathBuf,
    pub scene: Option<PathBuf>,
    pub out: PathBuf,
    pub overrides: Vec<String>,
    pub progress: bool,
    /// Replace an earlier run in `out` (remove exactly the files its manifest lists) instead
    /// of refusing to write there.
    pub overwrite: bool,
    /// Run on a mesh with severe defects (not conforming, a crack, overlapping cells) instead of
    /// refusing it: the defects become warnings (docs/method.md §16.3).
    pub accept_mesh_defects: bool,
}
