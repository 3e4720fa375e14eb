//! Study files: a convergence study as data (`hvi study STUDY.toml`). A study names a scene,
//! the meshes (the paper's rectangle generated for each n = 1/h, or one `.msh` file per n),
//! a reference (n, N), refinement paths in h and in k, and optionally published errors to
//! print beside ours. It writes `study.md`, `study.csv`, `error_vs_h.svg`, `error_vs_k.svg`,
//! `work_precision.svg` and `gamma3.svg` (u_ν on Γ₃ of the reference at the compared times).

use super::format::fraction;
use super::report::{self, Published};
use super::target::{self, Candidate, CostModel, CostSample, ErrorModel, ErrorSample};
use super::{plot, run_plan, Keep, Refinement, RunErrors, RunOptions, RunRecord, Study, StudyPlan};
use crate::mesh::structured::{block, rectangle, CellShape, SolidShape};
use crate::mesh::{AnyMesh, Mesh};
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
    run_file_with(path, out, extra_overrides, &Targets::default())
}

/// What to plan after the study (`hvi study --target E [--verify]`).
#[derive(Clone, Debug, Default)]
pub struct Targets {
    /// Target H¹ errors at T (each > 0).
    pub errors: Vec<f64>,
    /// Run each recommendation and compare it with its prediction.
    pub verify: bool,
}

/// Runs a study spec (paths relative to `dir`).
pub fn run_spec(spec: &StudySpec, dir: &Path, out: &Path, extra: &[String], name: &str) -> Result<StudyOutput, String> {
    run_spec_with(spec, dir, out, extra, name, &Targets::default())
}

/// Runs a study file and plans a run for each target (see [`run_spec_with`]).
pub fn run_file_with(
    path: &Path,
    out: &Path,
    extra_overrides: &[String],
    targets: &Targets,
) -> Result<StudyOutput, String> {
    let spec = read(path)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    run_spec_with(&spec, dir, out, extra_overrides, &path.display().to_string(), targets)
}

/// Runs a study spec and, for each target error, fits the error and cost models to its runs
/// and recommends the cheapest (h, k) predicted to meet it (docs/method.md §6.1), verified by
/// running it when asked; the plans are a section of the report (study.md).
pub fn run_spec_with(
    spec: &StudySpec,
    dir: &Path,
    out: &Path,
    extra: &[String],
    name: &str,
    targets: &Targets,
) -> Result<StudyOutput, String> {
    if let Some(bad) = targets.errors.iter().find(|e| !(e.is_finite() && **e > 0.0)) {
        return Err(format!(
            "--target {bad}: the target error must be a positive number, e.g. --target 1e-3"
        ));
    }
    if targets.verify && targets.errors.is_empty() {
        return Err("--verify checks the run planned for a --target: give --target E as well".into());
    }
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
    // Generated meshes: the paper's rectangle (quad, tri) or its slab (0,2)×(0,1)×(0,0.25) with
    // cubic cells (hex, tet); mesh files decide the dimension when given.
    let simplex = match spec.shape.as_str() {
        "quad" | "hex" => false,
        "tri" | "tet" => true,
        other => {
            return Err(format!(
                "{name}: shape = \"{other}\": use \"quad\" or \"tri\" (the rectangle), \"hex\" or \"tet\" (the slab)"
            ))
        }
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
    let (mut two, mut three) = (BTreeMap::new(), BTreeMap::new());
    for (n, file) in &spec.mesh_files {
        let n: usize = n
            .parse()
            .map_err(|_| format!("{name}: mesh_files key `{n}` is not an integer n = 1/h"))?;
        match crate::mesh::read_msh(&dir.join(file)).map_err(|e| e.to_string())? {
            AnyMesh::Two(m) => {
                two.insert(n, m);
            }
            AnyMesh::Three(m) => {
                three.insert(n, m);
            }
        }
    }
    if !two.is_empty() && !three.is_empty() {
        return Err(format!(
            "{name}: mesh_files mixes 2D meshes (n = {}) and 3D meshes (n = {}): a study runs in one dimension",
            two.keys().map(|n| n.to_string()).collect::<Vec<_>>().join(", "),
            three.keys().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")
        ));
    }
    let solid = !three.is_empty() || (two.is_empty() && matches!(spec.shape.as_str(), "hex" | "tet"));
    let t = base.time.final_time;
    let plan = StudyPlan {
        reference: (spec.reference.n, spec.reference.steps),
        h_paths: spec.h_paths.iter().map(|p| (p.steps, p.n.clone())).collect(),
        k_paths: spec.k_paths.iter().map(|p| (p.n, p.steps.clone())).collect(),
        keep: Keep::MultiplesOf(spec.compare_every.unwrap_or(t / 16.0)),
    };
    let setup = Setup {
        spec,
        dir,
        out,
        extra,
        name,
        targets,
        base: &base,
        make_scene: &make_scene,
        plan,
        started,
        wide,
    };
    if solid {
        // cubic cells h = 1/n through the depth 0.25: n/4 layers
        let needed = std::iter::once(spec.reference.n)
            .chain(spec.h_paths.iter().flat_map(|p| p.n.iter().copied()))
            .chain(spec.k_paths.iter().map(|p| p.n));
        for n in needed {
            if !three.contains_key(&n) && n % 4 != 0 {
                return Err(format!(
                    "{name}: n = {n}: a generated slab (0,2)×(0,1)×(0,0.25) with cubic cells of size 1/n needs n \
                     divisible by 4 (n/4 layers); use such n or give a mesh file for it in mesh_files"
                ));
            }
        }
        let kind = if simplex { SolidShape::Tet } else { SolidShape::Hex };
        let make_mesh = |n: usize| -> Mesh<3> {
            match three.get(&n) {
                Some(m) => m.clone(),
                None => {
                    let h = 1.0 / n as f64;
                    let nx = if wide { n } else { 2 * n };
                    block(
                        [2.0, 1.0, (n / 4) as f64 * h],
                        [nx, if wide { n / 2 } else { n }, n / 4],
                        kind,
                    )
                }
            }
        };
        run_in(&setup, &three, &make_mesh)
    } else {
        let shape = if simplex { CellShape::Tri } else { CellShape::Quad };
        let make_mesh = |n: usize| -> Mesh<2> {
            match two.get(&n) {
                Some(m) => m.clone(),
                None if wide => rectangle(2.0, 1.0, n, n, shape),
                None => rectangle(2.0, 1.0, 2 * n, n, shape),
            }
        };
        run_in(&setup, &two, &make_mesh)
    }
}

/// What a study's runs in either dimension share (read and checked by [`run_spec_with`]).
struct Setup<'a> {
    spec: &'a StudySpec,
    dir: &'a Path,
    out: &'a Path,
    extra: &'a [String],
    name: &'a str,
    targets: &'a Targets,
    base: &'a Scene,
    make_scene: &'a dyn Fn(usize) -> Scene,
    plan: StudyPlan,
    started: Instant,
    wide: bool,
}

/// Runs the study in dimension D (the meshes `make_mesh` builds), writes its tables, plots and
/// plans.
fn run_in<const D: usize>(
    setup: &Setup,
    files: &BTreeMap<usize, Mesh<D>>,
    make_mesh: &dyn Fn(usize) -> Mesh<D>,
) -> Result<StudyOutput, String> {
    let Setup {
        spec,
        dir,
        out,
        extra,
        name,
        targets,
        base,
        make_scene,
        ref plan,
        started,
        ..
    } = *setup;
    let t = base.time.final_time;
    let mut progress = |r: &RunRecord<D>, e: Option<&RunErrors>| {
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
    let study = run_plan(plan, make_mesh, make_scene, &mut progress)?;
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
            format!(
                "the paper's {}, {} {} cells",
                if D == 2 { "rectangle" } else { "slab" },
                spec.cells,
                spec.shape
            )
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
        // u_ν on Γ₃ of the reference at the compared times, against arc length (2D: a 3D Γ₃
        // is a surface, drawn by `hvi plot` of a run)
        let plane = (&reference.mesh as &dyn std::any::Any).downcast_ref::<Mesh<2>>();
        if let Some((mesh, gamma3)) = plane.and_then(|m| Some((m, m.boundary(&base.groups.contact).ok()?))) {
            let (arc, order, _) = crate::plot::arc_length(mesh, &gamma3.nodes);
            let series: Vec<(f64, Vec<(f64, f64)>)> = reference
                .displacement_at
                .iter()
                .filter(|(s, _)| *s > 0.0)
                .step_by(2)
                .map(|(s, u)| {
                    let pts = order
                        .iter()
                        .map(|&k| {
                            let (p, nu) = (gamma3.nodes[k], gamma3.normals[k]);
                            (arc[k], u[p][0] * nu[0] + u[p][1] * nu[1])
                        })
                        .collect();
                    (*s, pts)
                })
                .collect();
            let title = format!(
                "u_ν along Γ₃ ({}) of the reference run, h = 1/{}, k = T/{}",
                base.groups.contact, plan.reference.0, plan.reference.1
            );
            plot::plot_gamma3(&out.join("gamma3.svg"), &title, &series)?;
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
    if !targets.errors.is_empty() {
        let context = TargetContext {
            spec,
            dir,
            extra,
            final_time: t,
            keep: &plan.keep,
            reference: plan.reference,
            mesh_files: files.keys().copied().collect(),
            wide: setup.wide,
            solid: D == 3,
        };
        let section = target_sections(&study, &context, targets, make_mesh, make_scene)?;
        md.push_str(&section);
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

/// What the planner needs to know about the study besides its runs.
struct TargetContext<'a> {
    spec: &'a StudySpec,
    dir: &'a Path,
    extra: &'a [String],
    final_time: f64,
    keep: &'a Keep,
    reference: (usize, usize),
    /// The n of the study's mesh files.
    mesh_files: std::collections::BTreeSet<usize>,
    /// Generated meshes: 2h × h cells (n × n in the plane) instead of square ones.
    wide: bool,
    /// Generated meshes are the 3D slab (n divisible by 4), not the rectangle.
    solid: bool,
}

/// n = 1/h of a run (h is set to 1/n by the study).
fn n_of(h: f64) -> usize {
    (1.0 / h).round() as usize
}

/// The `hvi solve` command of a planned run.
fn solve_command(c: &TargetContext, n: usize, steps: usize) -> String {
    let mesh = match c
        .spec
        .mesh_files
        .iter()
        .find(|(key, _)| key.parse::<usize>().ok() == Some(n))
    {
        Some((_, file)) => c.dir.join(file).display().to_string(),
        None if c.solid => {
            let (nx, ny) = if c.wide { (n, n / 2) } else { (2 * n, n) };
            let shape = if c.spec.shape == "tet" || c.spec.shape == "tri" {
                ":tet"
            } else {
                ""
            };
            format!("box:{nx}x{ny}x{}{shape}", n / 4)
        }
        None => {
            let (nx, ny) = if c.wide { (n, n) } else { (2 * n, n) };
            let shape = if c.spec.shape == "tri" { ":tri" } else { "" };
            format!("rect:{nx}x{ny}{shape}")
        }
    };
    let mut command = format!("hvi solve {mesh}");
    if let Some(scene) = &c.spec.scene {
        let _ = write!(command, " --scene {}", c.dir.join(scene).display());
    }
    for s in c.spec.set.iter().chain(c.extra) {
        let _ = write!(command, " --set {s}");
    }
    let _ = write!(command, " --set time.steps={steps}");
    command
}

/// Why no candidate is cheaper than `chosen` (docs/method.md §6.1): the nearest coarser mesh
/// among the candidates (its spatial error alone, and its best prediction with the shortest
/// step), and on the chosen mesh the next longer step.
fn why_no_cheaper(
    error: &ErrorModel,
    cost: &CostModel,
    candidates: &[Candidate],
    chosen: Candidate,
    target: f64,
) -> String {
    let fmt_n = |x: f64| format!("{x:.3e}");
    let mut why = Vec::new();
    let coarser = candidates.iter().filter(|c| c.n < chosen.n).map(|c| c.n).max();
    match coarser {
        Some(m) => {
            let h = 1.0 / m as f64;
            let k_min = candidates.iter().map(|c| c.k).fold(f64::INFINITY, f64::min);
            let spatial = error.spatial(h);
            let meeting = candidates
                .iter()
                .filter(|c| c.n == m && error.predict(c.h, c.k) <= target)
                .map(|c| (cost.predict(c.unknowns, c.steps as f64), c))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            why.push(match meeting {
                _ if spatial > target => format!(
                    "The nearest coarser mesh the model describes, h = 1/{m}, has a spatial error of {} alone, more \
                     than the target whatever the step.",
                    fmt_n(spatial)
                ),
                None => format!(
                    "The nearest coarser mesh the model describes, h = 1/{m}, is predicted at {} even with the \
                     shortest step k = {} (spatial {}).",
                    fmt_n(error.predict(h, k_min)),
                    fraction(k_min),
                    fmt_n(spatial)
                ),
                Some((wall, c)) => format!(
                    "The nearest coarser mesh the model describes, h = 1/{m}, meets the target only with k ≤ {}, \
                     predicted to take {wall:.2} s.",
                    fraction(c.k)
                ),
            });
        }
        None => why.push(format!(
            "No candidate mesh is coarser than h = 1/{} (the candidates are the meshes nested in the reference's, \
             or the study's mesh files).",
            chosen.n
        )),
    }
    if let Some(longer) = candidates
        .iter()
        .filter(|c| c.n == chosen.n && c.steps < chosen.steps)
        .max_by_key(|c| c.steps)
    {
        why.push(format!(
            "On h = 1/{}, the next longer step k = {} is predicted at {}, above the target.",
            chosen.n,
            fraction(longer.k),
            fmt_n(error.predict(longer.h, longer.k))
        ));
    }
    why.push(
        "Meshes the model cannot describe are left out on purpose: non-nested ones, whose transfer to the reference \
         mesh measures less than their error (docs/method.md §6.1, which also measures cells of other aspect ratios \
         on the paper's example)."
            .into(),
    );
    why.join(" ")
}

/// The Markdown sections of the targets: models, recommendation, and the check when asked.
fn target_sections<const D: usize>(
    study: &Study<D>,
    c: &TargetContext,
    targets: &Targets,
    make_mesh: &dyn Fn(usize) -> Mesh<D>,
    make_scene: &dyn Fn(usize) -> Scene,
) -> Result<String, String> {
    let (n_ref, steps_ref) = c.reference;
    let (h_ref, k_ref) = (1.0 / n_ref as f64, c.final_time / steps_ref as f64);
    let samples: Vec<ErrorSample> = study
        .runs
        .iter()
        .map(|r| ErrorSample {
            h: r.summary.h,
            k: r.summary.k,
            error: r.errors.at_final.h1_seminorm,
        })
        .collect();
    let error = ErrorModel::fit(&samples, h_ref, k_ref).map_err(|e| format!("--target: {e}"))?;
    let mut sizes: Vec<(usize, usize, &super::RunSummary)> = study
        .runs
        .iter()
        .map(|r| (n_of(r.summary.h), r.summary.steps, &r.summary))
        .collect();
    let reference_summary = study.reference_run().map(|r| r.summary());
    if let Some(r) = &reference_summary {
        sizes.push((n_ref, steps_ref, r));
    }
    let cost_samples: Vec<CostSample> = sizes
        .iter()
        .map(|(_, _, s)| CostSample {
            unknowns: s.unknowns as f64,
            steps: s.steps as f64,
            setup_seconds: s.wall - s.steps_seconds(),
            steps_seconds: s.steps_seconds(),
        })
        .collect();
    let cost = CostModel::fit(&cost_samples).map_err(|e| format!("--target: {e}"))?;
    let unknowns_points: Vec<(f64, f64)> = sizes.iter().map(|(n, _, s)| (*n as f64, s.unknowns as f64)).collect();
    let (c_n, beta) =
        target::power_fit(&unknowns_points).ok_or("--target: the runs have a single mesh size: add an h path")?;
    // the candidates: h between the coarsest run's and the reference's (meshes hvi builds: any n
    // for the generated rectangle, the study's own sizes with mesh files), k likewise
    let n_min = sizes.iter().map(|s| s.0).min().unwrap_or(n_ref);
    let steps_min = sizes.iter().map(|s| s.1).min().unwrap_or(steps_ref);
    // Generated rectangles: only those nested in the reference's (n divides n_ref). The error
    // of a run is measured by carrying it to the reference mesh, exact only for nested meshes;
    // on the paper's example a non-nested mesh measures about half the error of its nested
    // neighbours (h = 1/37 against h_r = 1/64: 1.6e-3, the nested trend 2.9e-3), so a model
    // fitted to nested runs would not predict what --verify measures.
    let ns: Vec<usize> = if c.mesh_files.is_empty() {
        (n_min..=n_ref)
            .filter(|n| n_ref % n == 0 && (!c.solid || n % 4 == 0))
            .collect()
    } else {
        let mut v: Vec<usize> = sizes.iter().map(|s| s.0).chain(c.mesh_files.iter().copied()).collect();
        v.sort_unstable();
        v.dedup();
        v.retain(|n| (n_min..=n_ref).contains(n));
        v
    };
    let known_unknowns = |n: usize| {
        sizes
            .iter()
            .find(|s| s.0 == n)
            .map_or(c_n * (n as f64).powf(beta), |s| s.2.unknowns as f64)
    };
    let candidates: Vec<Candidate> = ns
        .iter()
        .flat_map(|&n| {
            (steps_min..=steps_ref).map(move |steps| Candidate {
                n,
                steps,
                h: 1.0 / n as f64,
                k: c.final_time / steps as f64,
                unknowns: 0.0,
            })
        })
        .map(|mut cand| {
            cand.unknowns = known_unknowns(cand.n);
            cand
        })
        .collect();

    let mut md = String::new();
    let fmt_n = |x: f64| format!("{x:.3e}");
    let _ = writeln!(
        md,
        "## Planning for a target error\n\n\
         Error model (docs/method.md §6.1), fitted jointly to the {} runs by \
         least squares on relative residuals (rms {:.1} %): against the reference (h_r = {}, k_r = {}) \
         e ≈ C_h·√(h^(2p) − h_r^(2p)) + C_k·(k^q − k_r^q), i.e. e ≈ C_h h^p + C_k k^q against the exact solution, \
         with **C_h = {}, p = {:.3}; C_k = {}, q = {:.3}**.\n\n\
         Cost model, fitted to the {} runs and the reference: wall ≈ {}·N^{:.3} s (setup) + {}·N^{:.3}·steps s \
         (time steps), N the unknowns, N ≈ {:.3}·n^{:.3} for h = 1/n.\n\n\
         Candidates: h = 1/n for n = {} (meshes {}), k = T/N for N = {steps_min} … {steps_ref}.\n",
        error.samples,
        100.0 * error.rms_relative_residual,
        fraction(h_ref),
        fraction(k_ref),
        fmt_n(error.c_h),
        error.p,
        fmt_n(error.c_k),
        error.q,
        study.runs.len(),
        fmt_n(cost.c_setup),
        cost.b,
        fmt_n(cost.c_step),
        cost.a,
        c_n,
        beta,
        ns.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", "),
        if c.mesh_files.is_empty() {
            "nested in the reference's, on which the measured error is the one the model describes"
        } else {
            "of the study"
        }
    );
    for &e_target in &targets.errors {
        let _ = writeln!(md, "### Target: H¹ error at T ≤ {e_target:.3e}\n");
        // the cheapest run of the tables that reaches the target (measured)
        let cheapest = study
            .runs
            .iter()
            .filter(|r| r.errors.at_final.h1_seminorm <= e_target)
            .min_by(|a, b| a.summary.wall.total_cmp(&b.summary.wall));
        let Some(p) = target::plan(&error, &cost, candidates.iter().copied(), e_target) else {
            let _ = writeln!(
                md,
                "No run between h = 1/{n_min} … 1/{n_ref} and k = T/{steps_min} … T/{steps_ref} is predicted to \
                reach it.\n"
            );
            continue;
        };
        let (n, steps) = (p.run.n, p.run.steps);
        let _ = writeln!(
            md,
            "* Recommended: **h = 1/{n}, k = {}** ({} unknowns, {steps} steps): predicted error **{}** \
            (spatial {} + temporal {}), predicted wall **{:.2} s**.",
            fraction(p.run.k),
            p.run.unknowns.round(),
            fmt_n(p.error),
            fmt_n(p.spatial),
            fmt_n(p.temporal),
            p.wall
        );
        let exact = error.against_exact(p.run.h, p.run.k);
        let _ = writeln!(
            md,
            "* Against the exact solution the model predicts {} (the reference's own error is {}).",
            fmt_n(exact),
            fmt_n(error.against_exact(h_ref, k_ref))
        );
        let _ = writeln!(md, "* Run it: `{}`", solve_command(c, n, steps));
        match cheapest {
            Some(r) => {
                let _ = writeln!(
                    md,
                    "* Cheapest run of the tables that reaches the target: {} (error {}, wall {:.2} s).",
                    r.summary.label,
                    fmt_n(r.errors.at_final.h1_seminorm),
                    r.summary.wall
                );
            }
            None => {
                let _ = writeln!(md, "* No run of the tables reaches the target.");
            }
        }
        if let Some(r) = cheapest.filter(|r| (n_of(r.summary.h), r.summary.steps) == (n, steps)) {
            let _ = writeln!(
                md,
                "* **The recommendation is the cheapest run of the tables itself ({}): no run the model describes is \
                 predicted cheaper and within the target.** {}",
                r.summary.label,
                why_no_cheaper(&error, &cost, &candidates, p.run, e_target)
            );
        }
        if targets.verify {
            let options = RunOptions {
                label: format!("planned h=1/{n} N={steps}"),
                h: Some(1.0 / n as f64),
                keep: c.keep.clone(),
            };
            let record = super::run_with(make_mesh(n), &make_scene(steps), &options)
                .map_err(|e| format!("--verify: run h = 1/{n}, {steps} steps: {e}"))?;
            let measured = study.evaluate(&record)?;
            let e = measured.at_final.h1_seminorm;
            let verdict = if e <= e_target {
                "meets the target".to_string()
            } else if e <= 1.5 * e_target {
                format!("within 1.5·E = {}", fmt_n(1.5 * e_target))
            } else {
                format!("MISSES the target (more than 1.5·E = {})", fmt_n(1.5 * e_target))
            };
            let _ = writeln!(
                md,
                "* Verified: measured error **{}** against predicted {} (measured/predicted {:.2}; {verdict}); \
                measured wall **{:.2} s** against predicted {:.2} s ({:.2}); {} unknowns.",
                fmt_n(e),
                fmt_n(p.error),
                e / p.error,
                record.wall,
                p.wall,
                record.wall / p.wall,
                record.unknowns
            );
            if let Some(r) = cheapest {
                if (n_of(r.summary.h), r.summary.steps) == (n, steps) {
                    let _ = writeln!(
                        md,
                        "* Cost: {:.2} s against {:.2} s for the run of the tables, which is the same h and k: no \
                         saving, the times differ only by the machine's noise.",
                        record.wall, r.summary.wall
                    );
                } else {
                    let _ = writeln!(
                        md,
                        "* Cost against the cheapest run of the tables that reaches the target: {:.2} s against \
                         {:.2} s ({:.2}×{}).",
                        record.wall,
                        r.summary.wall,
                        r.summary.wall / record.wall,
                        if record.wall < r.summary.wall {
                            " cheaper"
                        } else {
                            ": NOT cheaper"
                        }
                    );
                }
            }
        }
        md.push('\n');
    }
    Ok(md)
}
