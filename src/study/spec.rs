//! Study files: a convergence study as data (`hvi study STUDY.toml`). A study names a scene,
//! the meshes (the paper's rectangle generated for each n = 1/h, or one `.msh` file per n),
//! a reference (n and its time levels), refinement paths in h and in k, and optionally published
//! errors to print beside ours. It writes `study.md`, `study.csv`, `error_vs_h.svg`,
//! `error_vs_k.svg`, `work_precision.svg` and `gamma3.svg` (u_ν on Γ₃ of the reference at the
//! compared times). A k path's levels are uniform step counts, steps per decade or tolerances of
//! automatic steps (docs/method.md §20); [`StudySpec::time_levels`] checks them.

use super::level::{decade_times, LevelKind, TimeLevel};
use super::report::Published;
use super::runner::Keep;
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
    /// The first step of steps per decade (required with them), and of automatic steps (their
    /// own default when absent).
    pub first_step: Option<f64>,
    /// h-refinement paths: fixed N, list of n.
    #[serde(default)]
    pub h_paths: Vec<HPath>,
    /// k-refinement paths: fixed n, a list of N, of steps per decade or of tolerances.
    #[serde(default)]
    pub k_paths: Vec<KPath>,
    /// Times compared for the max-over-time error: multiples of this (default 1/16 of T; uniform
    /// steps only).
    pub compare_every: Option<f64>,
    /// Times compared for the max-over-time error, made levels of the reference and of every run
    /// whose steps are not uniform (default with such runs: one a decade, and T).
    pub compare_at: Option<Vec<f64>>,
}

fn default_cells() -> String {
    "square".into()
}

fn default_shape() -> String {
    "quad".into()
}

/// n = 1/h and one way of stepping: N uniform steps, s steps per decade or a tolerance.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSize {
    pub n: usize,
    pub steps: Option<usize>,
    pub steps_per_decade: Option<f64>,
    pub tolerance: Option<f64>,
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

/// A k-refinement path: fixed n, and exactly one of the lists of levels, coarse to fine.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KPath {
    pub n: usize,
    pub steps: Option<Vec<usize>>,
    pub steps_per_decade: Option<Vec<f64>>,
    pub tolerance: Option<Vec<f64>>,
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

/// The time levels of a study, checked ([`StudySpec::time_levels`]).
#[derive(Clone, Debug)]
pub struct TimeLevels {
    pub reference: TimeLevel,
    /// The levels of each `[[k_paths]]` entry, coarse to fine.
    pub k_paths: Vec<Vec<TimeLevel>>,
    /// The steps every run keeps for the max-over-time error: multiples of `compare_every` when
    /// every level is uniform (and no `compare_at`), else the compared times.
    pub keep: Keep,
}

/// `{name}: `key` = value: fix`, as a scene's messages read.
fn invalid(name: &str, key: &str, value: impl std::fmt::Display, fix: &str) -> String {
    format!("{name}: `{key}` = {value}: {fix}")
}

/// `[a, b, c]` with each value as written.
fn list<T: std::fmt::Display>(values: &[T]) -> String {
    format!(
        "[{}]",
        values.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ")
    )
}

const WAYS: &str = "steps = [4, 8, 16] (uniform steps), steps_per_decade = [5, 10, 20] (steps growing with time from \
                    the study's first_step) or tolerance = [1e-2, 1e-3, 1e-4] (automatic steps)";

/// One level's value checked: `key` names it (e.g. `k_paths[1].steps_per_decade[0]`).
fn level(name: &str, key: &str, kind: LevelKind, value: f64) -> Result<TimeLevel, String> {
    match kind {
        LevelKind::Steps if value >= 1.0 => Ok(TimeLevel::Steps(value as usize)),
        LevelKind::Steps => Err(invalid(name, key, value, "a run needs at least one step")),
        // as the scene's time.steps_per_decade and time.tolerance (src/scene/time.rs)
        LevelKind::PerDecade if value.is_finite() && value >= 0.1 => Ok(TimeLevel::PerDecade(value)),
        LevelKind::PerDecade => Err(invalid(
            name,
            key,
            value,
            "give a positive, finite number of steps per decade, at least 0.1 (e.g. 10: each step 26 % longer than \
             the last)",
        )),
        LevelKind::Tolerance if value.is_finite() && value > 0.0 && value < 1.0 => Ok(TimeLevel::Tolerance(value)),
        LevelKind::Tolerance => Err(invalid(
            name,
            key,
            value,
            "give the local error allowed per step, relative to the largest displacement: a number in (0, 1), e.g. \
             1e-3",
        )),
    }
}

/// The one way of stepping of `at` (`reference` or `k_paths[i]`) among the given lists.
fn one_way(
    name: &str,
    at: &str,
    given: [(LevelKind, Option<Vec<f64>>); 3],
    example: &str,
) -> Result<(LevelKind, Vec<f64>), String> {
    let mut present: Vec<(LevelKind, Vec<f64>)> = given.into_iter().filter_map(|(k, v)| Some((k, v?))).collect();
    match present.len() {
        0 => Err(invalid(
            name,
            at,
            "(no steps, steps_per_decade or tolerance)",
            &format!("give exactly one way of stepping: {example}"),
        )),
        1 => Ok(present.remove(0)),
        _ => Err(invalid(
            name,
            &format!("{at}.{}", present[1].0.key()),
            format!("(with {at}.{})", present[0].0.key()),
            &format!(
                "give one way of stepping, not {}: {example}; to compare two ways, give each its own entry",
                present.iter().map(|(k, _)| k.key()).collect::<Vec<_>>().join(" and ")
            ),
        )),
    }
}

impl StudySpec {
    /// The reference's and the k paths' time levels and the compared times, checked against the
    /// scene's final time T (docs/method.md §6, §20): each level one way of stepping with values
    /// in range, `first_step` given (and shorter than T) for steps per decade, the compared times
    /// in (0, T]. `automatic_first` is the automatic steps' own first step (the lower end of the
    /// default compared times when a tolerance path gives no `first_step`).
    pub fn time_levels(&self, name: &str, final_time: f64, automatic_first: f64) -> Result<TimeLevels, String> {
        let t = final_time;
        let floats = |v: &Option<Vec<usize>>| v.as_ref().map(|v| v.iter().map(|&n| n as f64).collect());
        let r = &self.reference;
        let (kind, values) = one_way(
            name,
            "reference",
            [
                (LevelKind::Steps, r.steps.map(|n| vec![n as f64])),
                (LevelKind::PerDecade, r.steps_per_decade.map(|s| vec![s])),
                (LevelKind::Tolerance, r.tolerance.map(|e| vec![e])),
            ],
            "reference = { n = 64, steps = 64 }, { n = 64, steps_per_decade = 80 } or { n = 64, tolerance = 1e-6 }",
        )?;
        let reference = level(name, &format!("reference.{}", kind.key()), kind, values[0])?;
        let mut k_paths = Vec::with_capacity(self.k_paths.len());
        for (i, p) in self.k_paths.iter().enumerate() {
            let at = format!("k_paths[{i}]");
            let (kind, values) = one_way(
                name,
                &at,
                [
                    (LevelKind::Steps, floats(&p.steps)),
                    (LevelKind::PerDecade, p.steps_per_decade.clone()),
                    (LevelKind::Tolerance, p.tolerance.clone()),
                ],
                WAYS,
            )?;
            if values.is_empty() {
                return Err(invalid(
                    name,
                    &format!("{at}.{}", kind.key()),
                    "[]",
                    "give at least one level, coarse to fine",
                ));
            }
            let levels = values
                .iter()
                .enumerate()
                .map(|(j, &v)| level(name, &format!("{at}.{}[{j}]", kind.key()), kind, v))
                .collect::<Result<Vec<_>, _>>()?;
            k_paths.push(levels);
        }
        // who needs the first step: steps per decade always, automatic steps when given
        let all = || {
            std::iter::once((String::from("reference"), vec![reference])).chain(
                k_paths
                    .iter()
                    .enumerate()
                    .map(|(i, l)| (format!("k_paths[{i}]"), l.clone())),
            )
        };
        let per_decade = all().find(|(_, l)| l.iter().any(|x| x.kind() == LevelKind::PerDecade));
        let non_uniform = all().find(|(_, l)| l.iter().any(|x| !x.is_uniform()));
        if let Some(first) = self.first_step {
            if !(first.is_finite() && first > 0.0) {
                return Err(invalid(name, "first_step", first, "give a positive, finite first step"));
            }
            if first >= t {
                return Err(invalid(
                    name,
                    "first_step",
                    first,
                    &format!("the first step must be shorter than the scene's time.final_time = {t}"),
                ));
            }
            if non_uniform.is_none() {
                return Err(invalid(
                    name,
                    "first_step",
                    first,
                    "first_step is the first step of steps_per_decade and tolerance levels, and this study has none \
                     (its levels are uniform steps = N): remove it",
                ));
            }
        } else if let Some((who, levels)) = &per_decade {
            let values: Vec<f64> = levels
                .iter()
                .filter_map(|l| match l {
                    TimeLevel::PerDecade(s) => Some(*s),
                    _ => None,
                })
                .collect();
            let shown = if who == "reference" {
                values[0].to_string()
            } else {
                list(&values)
            };
            return Err(invalid(
                name,
                &format!("{who}.steps_per_decade"),
                shown,
                &format!(
                    "steps per decade grow from the study's first step: add `first_step = …` at the top of the study \
                     file, shorter than T = {t} and than the fastest relaxation time (e.g. first_step = 1e{})",
                    (t * 1e-6).log10().round() as i32
                ),
            ));
        }
        let keep = match (&self.compare_every, &self.compare_at, &non_uniform) {
            (Some(_), Some(_), _) => {
                return Err(invalid(
                    name,
                    "compare_every",
                    self.compare_every.expect("given"),
                    "give the compared times once: compare_every (multiples, uniform steps) or compare_at (a list)",
                ))
            }
            (Some(every), None, Some((who, _))) => {
                return Err(invalid(
                    name,
                    "compare_every",
                    every,
                    &format!(
                        "{} does not step uniformly, so multiples of a step are not its levels: give the compared \
                         times as compare_at = [t₁, t₂, …] (made levels of every such run), or leave both out to \
                         compare one time a decade and T",
                        if who == "reference" { "the reference" } else { who }
                    ),
                ))
            }
            (every, None, None) => Keep::MultiplesOf(every.unwrap_or(t / 16.0)),
            (None, Some(at), _) => {
                let mut times = Vec::with_capacity(at.len() + 1);
                for (i, &s) in at.iter().enumerate() {
                    if !(s.is_finite() && s > 0.0 && s <= t * (1.0 + 1e-12)) {
                        return Err(invalid(
                            name,
                            &format!("compare_at[{i}]"),
                            s,
                            &format!("a compared time lies in (0, T = {t}]"),
                        ));
                    }
                    times.push(s.min(t));
                }
                times.push(t);
                times.sort_by(f64::total_cmp);
                times.dedup();
                Keep::Times(times)
            }
            (None, None, Some(_)) => Keep::Times(decade_times(self.first_step.unwrap_or(automatic_first), t)),
        };
        Ok(TimeLevels {
            reference,
            k_paths,
            keep,
        })
    }
}
