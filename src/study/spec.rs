//! Study files: a convergence study as data (`hvi study STUDY.toml`). A study names a scene,
//! the meshes (the paper's rectangle generated for each n = 1/h, or one `.msh` file per n),
//! a reference (n, N), refinement paths in h and in k, and optionally published errors to
//! print beside ours. It writes `study.md`, `study.csv`, `error_vs_h.svg`, `error_vs_k.svg`,
//! `work_precision.svg` and `gamma3.svg` (u_ν on Γ₃ of the reference at the compared times).

use super::report::{self, Published};
use super::{plot, run_plan, Keep, Refinement, RunErrors, RunRecord, StudyPlan};
use crate::mesh::structured::{rectangle, CellShape};
use crate::mesh::Mesh;
use crate::scene::Scene;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
fn published(errors: &[f64], params: &[f64]) -> Vec<Published> {
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

/// What a study wrote: its Markdown report and the files (names in the output directory).
#[derive(Clone, Debug)]
pub struct StudyOutput {
    pub report: String,
    /// study.md, study.csv, then the plots that had something to draw.
    pub files: Vec<String>,
}

/// Runs a study file, writing its tables and the plots it can draw to `out` (a study with only
/// an h path has no error-against-k plot, and the reverse).
pub fn run_file(path: &Path, out: &Path, extra_overrides: &[String]) -> Result<StudyOutput, String> {
    let spec = read(path)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    run_spec(&spec, dir, out, extra_overrides, &path.display().to_string())
}

/// Runs a study spec (paths relative to `dir`).
pub fn run_spec(spec: &StudySpec, dir: &Path, out: &Path, extra: &[String], name: &str) -> Result<StudyOutput, String> {
    let started = Instant::now();
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}; choose another --out", out.display()))?;
    let scene_path = spec.scene.as_ref().map(|p| dir.join(p));
    let mut overrides = spec.set.clone();
    overrides.extend_from_slice(extra);
    let base = Scene::load(scene_path.as_deref(), &overrides).map_err(|e| e.to_string())?;
    let make_scene = |steps: usize| {
        let mut s = base.clone();
        s.time.steps = steps;
        s
    };
    let shape = match spec.shape.as_str() {
        "quad" => CellShape::Quad,
        "tri" => CellShape::Tri,
        other => return Err(format!("{name}: shape = \"{other}\": use \"quad\" or \"tri\"")),
    };
    let wide = match spec.cells.as_str() {
        "square" => false,
        "wide" => true,
        other => {
            return Err(format!(
                "{name}: cells = \"{other}\": use \"square\" (h × h) or \"wide\" (2h × h)"
            ))
        }
    };
    let mut files = BTreeMap::new();
    for (n, file) in &spec.mesh_files {
        let n: usize = n
            .parse()
            .map_err(|_| format!("{name}: mesh_files key `{n}` is not an integer n = 1/h"))?;
        files.insert(
            n,
            crate::mesh::read_mesh::<2>(&dir.join(file)).map_err(|e| e.to_string())?,
        );
    }
    let make_mesh = |n: usize| -> Mesh {
        match files.get(&n) {
            Some(m) => m.clone(),
            None if wide => rectangle(2.0, 1.0, n, n, shape),
            None => rectangle(2.0, 1.0, 2 * n, n, shape),
        }
    };
    let t = base.time.final_time;
    let plan = StudyPlan {
        reference: (spec.reference.n, spec.reference.steps),
        h_paths: spec.h_paths.iter().map(|p| (p.steps, p.n.clone())).collect(),
        k_paths: spec.k_paths.iter().map(|p| (p.n, p.steps.clone())).collect(),
        keep: Keep::MultiplesOf(spec.compare_every.unwrap_or(t / 16.0)),
    };
    let mut progress = |r: &RunRecord, e: Option<&RunErrors>| {
        let errs = e.map_or(String::from("(reference)"), |e| {
            format!(
                "H¹ error {:.4e}, L² {:.4e}, max_t H¹ {:.4e}",
                e.at_final.h1_seminorm, e.at_final.l2, e.h1_max_over_time
            )
        });
        eprintln!(
            "  {:<28} {:>8} unknowns {:>5} steps {:>8.2} s {:>6} Newton  {errs}",
            r.label, r.unknowns, r.steps, r.wall, r.newton_total
        );
    };
    let study = run_plan(&plan, &make_mesh, &make_scene, &mut progress)?;
    let rows = study.rows();
    let mut written: Vec<String> = Vec::new();

    let mut md = String::new();
    let _ = writeln!(md, "# Convergence study `{name}`\n");
    let _ = writeln!(
        md,
        "Reference h = 1/{}, k = T/{}; errors at T: the H¹ seminorm |u_ref − u_hk|₁ and the L² norm, coarse solutions \
         carried to the reference mesh by nodal interpolation (exact for nested meshes). Meshes: {}. Wall time of \
         the study {:.1} s.\n",
        plan.reference.0,
        plan.reference.1,
        if files.is_empty() {
            format!("the paper's rectangle, {} {} cells", spec.cells, spec.shape)
        } else {
            "mesh files".into()
        },
        started.elapsed().as_secs_f64()
    );
    let h_rows = report::rows_of(&rows, Refinement::H);
    let k_rows = report::rows_of(&rows, Refinement::K);
    for (i, p) in spec.h_paths.iter().enumerate() {
        let these: Vec<_> = h_rows
            .iter()
            .filter(|r| r.path == study.paths[i].name)
            .copied()
            .collect();
        let title = format!("h refined at k = T/{}", p.steps);
        if p.published.is_empty() {
            let _ = writeln!(md, "## {title}\n");
        } else {
            let hs: Vec<f64> = p.n.iter().map(|n| 1.0 / *n as f64).collect();
            let _ = writeln!(
                md,
                "## {title}\n\n{}",
                report::comparison_markdown(&these, &published(&p.published, &hs))
            );
        }
    }
    for (j, p) in spec.k_paths.iter().enumerate() {
        let these: Vec<_> = k_rows
            .iter()
            .filter(|r| r.path == study.paths[spec.h_paths.len() + j].name)
            .copied()
            .collect();
        let title = format!("k refined at h = 1/{}", p.n);
        if p.published.is_empty() {
            let _ = writeln!(md, "## {title}\n");
        } else {
            let ks: Vec<f64> = p.steps.iter().map(|s| t / *s as f64).collect();
            let _ = writeln!(
                md,
                "## {title}\n\n{}",
                report::comparison_markdown(&these, &published(&p.published, &ks))
            );
        }
    }
    let fitted: Vec<String> = study
        .paths
        .iter()
        .map(|p| format!("{}: {:.3}", p.name, study.fitted_order(p).unwrap_or(f64::NAN)))
        .collect();
    let _ = writeln!(
        md,
        "Least-squares orders of the H¹ error at T: {}.\n",
        fitted.join(", ")
    );
    let _ = writeln!(
        md,
        "## All runs (wall time per phase in seconds)\n\n{}",
        report::markdown(&rows)
    );
    if let Some(reference) = study.reference_run() {
        let _ = writeln!(
            md,
            "Reference run: {} unknowns, {:.1} s wall, {} Newton iterations, peak RSS {}.\n",
            reference.unknowns,
            reference.wall,
            reference.newton_total,
            reference
                .peak_rss_bytes
                .map_or("unknown".into(), |b| format!("{:.0} MB", b as f64 / 1048576.0))
        );
        // u_ν on Γ₃ of the reference at the compared times
        if let Ok(gamma3) = reference.mesh.boundary(&base.groups.contact) {
            let series: Vec<(f64, Vec<(f64, f64)>)> = reference
                .displacement_at
                .iter()
                .filter(|(s, _)| *s > 0.0)
                .step_by(2)
                .map(|(s, u)| {
                    let pts = gamma3
                        .nodes
                        .iter()
                        .zip(&gamma3.normals)
                        .map(|(&p, nu)| (reference.mesh.points[p][0], u[p][0] * nu[0] + u[p][1] * nu[1]))
                        .collect();
                    (*s, pts)
                })
                .collect();
            plot::plot_gamma3(&out.join("gamma3.svg"), &series)?;
            written.push("gamma3.svg".to_string());
        }
    }
    for (file, drawn) in [
        (
            "error_vs_h.svg",
            plot::plot_error_vs_h(&out.join("error_vs_h.svg"), &rows)?,
        ),
        (
            "error_vs_k.svg",
            plot::plot_error_vs_k(&out.join("error_vs_k.svg"), &rows)?,
        ),
        (
            "work_precision.svg",
            plot::plot_work_precision(&out.join("work_precision.svg"), &rows)?,
        ),
    ] {
        if drawn {
            written.push(file.to_string());
        }
    }
    let write = |file: &str, text: &str| {
        crate::output::write_atomic(&out.join(file), text.as_bytes()).map_err(|e| e.to_string())
    };
    write("study.csv", &report::csv(&rows))?;
    write("study.md", &md)?;
    written.splice(0..0, ["study.md".to_string(), "study.csv".to_string()]);
    Ok(StudyOutput {
        report: md,
        files: written,
    })
}
