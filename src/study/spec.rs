//! Study files: a convergence study as data (`hvi study STUDY.toml`). A study names a scene,
//! the meshes (the paper's rectangle generated for each n = 1/h, or one `.msh` file per n),
//! a reference (n, N), refinement paths in h and in k, and optionally published errors to
//! print beside ours. It writes `study.md`, `study.csv`, `error_vs_h.svg`, `error_vs_k.svg`,
//! `work_precision.svg` and `gamma3.svg` (u_ν on Γ₃ of the reference at the compared times).

use super::report::Published;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A study file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudySpec {
    /// The scene (relative to the study file); the embedded default if absent.
    pub scene: Option<PathBuf>,
    /// `--set`-style overrides applied to the scene.
    #[serde(default)]
    pub set: Vec<String>,
    /// Generated rectangles: "square" (h × h cells: 2n × n) or "wide" (2h × h cells: n × n).
    #[serde(default = "default_cells")]
    pub cells: String,
    /// "quad" or "tri" for generated rectangles.
    #[serde(default = "default_shape")]
    pub shape: String,
    /// Mesh files by n (relative to the study file) instead of generated rectangles.
    #[serde(default)]
    pub mesh_files: BTreeMap<String, PathBuf>,
    /// The reference run.
    pub reference: RunSize,
    /// h-refinement paths: fixed N, list of n.
    #[serde(default)]
    pub h_paths: Vec<HPath>,
    /// k-refinement paths: fixed n, list of N.
    #[serde(default)]
    pub k_paths: Vec<KPath>,
    /// Times compared for the max-over-time error: multiples of this (default 1/16 of T).
    pub compare_every: Option<f64>,
}

fn default_cells() -> String {
    "square".into()
}

fn default_shape() -> String {
    "quad".into()
}

/// (n = 1/h, N steps).
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSize {
    pub n: usize,
    pub steps: usize,
}

/// An h-refinement path.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HPath {
    pub steps: usize,
    pub n: Vec<usize>,
    /// Published H¹ errors for these n, printed beside ours.
    #[serde(default)]
    pub published: Vec<f64>,
}

/// A k-refinement path.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KPath {
    pub n: usize,
    pub steps: Vec<usize>,
    #[serde(default)]
    pub published: Vec<f64>,
}

/// Published (error, order) pairs from a list of errors.
pub(super) fn published(errors: &[f64], params: &[f64]) -> Vec<Published> {
    errors
        .iter()
        .enumerate()
        .map(|(i, &e)| Published {
            error: e,
            order: (i > 0).then(|| (errors[i - 1] / e).ln() / (params[i - 1] / params[i]).ln()),
        })
        .collect()
}

/// Reads a study file.
pub fn read(path: &Path) -> Result<StudySpec, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read study file {}: {e}", path.display()))?;
    toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}
