//! Running a study file (docs/method.md §6): the plan's runs, the reference, the tables and the
//! plots, written to the study's directory. The k paths refine uniform steps, steps per decade
//! or the tolerance of automatic steps (docs/method.md §20), each against its own parameter.

use super::level::{LevelKind, TimeLevel};
use super::report::{self};
use super::{plot, run_plan, Keep, Refinement, RunErrors, RunRecord, StudyPlan};
use crate::mesh::structured::{block, rectangle, CellShape, SolidShape};
use crate::mesh::{AnyMesh, Mesh};
use crate::scene::Scene;
use crate::study::advice::target_sections;
use crate::study::advice::uniform_only;
use crate::study::advice::TargetContext;
use crate::study::spec::published;
use crate::study::spec::read;
use crate::study::spec::StudySpec;
use crate::study::Targets;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

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
    let levels = spec.time_levels(name, base.time.final_time, automatic_first_step(&base))?;
    if !targets.errors.is_empty() {
        uniform_only(name, &levels)?;
    }
    // the scene's own way of stepping is replaced by the level's; its final time and quadrature
    // stay (docs/method.md §20)
    let make_scene = |level: &TimeLevel| {
        let mut s = base.clone();
        s.time = level.time_spec(&s.time, spec.first_step);
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
    // with mesh files, every n the study runs needs its file: a generated rectangle or slab
    // beside a user's geometry would compare different bodies
    if !spec.mesh_files.is_empty() {
        let given: Vec<usize> = two.keys().chain(three.keys()).copied().collect();
        let needed = std::iter::once((spec.reference.n, "the reference".to_string()))
            .chain(
                spec.h_paths
                    .iter()
                    .enumerate()
                    .flat_map(|(i, p)| p.n.iter().map(move |&n| (n, format!("h_paths[{i}]")))),
            )
            .chain(
                spec.k_paths
                    .iter()
                    .enumerate()
                    .map(|(i, p)| (p.n, format!("k_paths[{i}]"))),
            );
        for (n, who) in needed {
            if !given.contains(&n) {
                return Err(format!(
                    "{name}: {who} runs n = {n}, but mesh_files has no mesh for it (it has n = {}); with mesh_files \
                     every n needs its file (add `{n} = \"….msh\"` to [mesh_files]), or leave mesh_files out to \
                     run on generated meshes of the paper's body",
                    given.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")
                ));
            }
        }
    }
    let solid = !three.is_empty() || (two.is_empty() && matches!(spec.shape.as_str(), "hex" | "tet"));
    let plan = StudyPlan {
        reference: (spec.reference.n, levels.reference),
        h_paths: spec.h_paths.iter().map(|p| (p.steps, p.n.clone())).collect(),
        k_paths: spec
            .k_paths
            .iter()
            .zip(&levels.k_paths)
            .map(|(p, l)| (p.n, l.clone()))
            .collect(),
        keep: levels.keep.clone(),
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
pub(super) struct Setup<'a> {
    spec: &'a StudySpec,
    dir: &'a Path,
    out: &'a Path,
    extra: &'a [String],
    name: &'a str,
    targets: &'a Targets,
    base: &'a Scene,
    make_scene: &'a dyn Fn(&TimeLevel) -> Scene,
    plan: StudyPlan,
    started: Instant,
    wide: bool,
}

/// Runs the study in dimension D (the meshes `make_mesh` builds), writes its tables, plots and
/// plans.
pub(super) fn run_in<const D: usize>(
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
        "Reference h = 1/{}, {}; errors at T: the H¹ seminorm |u_ref − u_hk|₁ and the L² norm, coarse solutions \
         carried to the reference mesh by nodal interpolation (exact for nested meshes). Meshes: {}. Wall time of \
         the study {:.1} s.\n",
        plan.reference.0,
        level_text(&plan.reference.1, spec.first_step),
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
    if let (Keep::Times(times), false) = (&plan.keep, uniform_study(plan)) {
        let _ = writeln!(
            md,
            "The max-over-time error compares t = {} ({}): levels of the reference and of every run whose steps are \
             not uniform (docs/method.md §20); a run of uniform steps compares those of them on its own grid.\n",
            times.iter().map(|t| format!("{t}")).collect::<Vec<_>>().join(", "),
            if spec.compare_at.is_some() {
                "compare_at"
            } else {
                "one a decade, and T"
            }
        );
    }
    let h_rows = report::rows_of(&rows, Refinement::H);
    let k_rows = report::rows_of(&rows, Refinement::K);
    for (i, p) in spec.h_paths.iter().enumerate() {
        let these: Vec<_> = h_rows
            .iter()
            .filter(|r| r.path == study.paths[i].name)
            .copied()
            .collect();
        let title = format!("h refined at k = T/{}", p.steps);
        let fit = fitted_line(study.fitted_order(&study.paths[i]), "h");
        if p.published.is_empty() {
            let _ = writeln!(md, "## {title}\n\n{}\n{fit}\n", report::path_markdown(&these));
        } else {
            let hs: Vec<f64> = p.n.iter().map(|n| 1.0 / *n as f64).collect();
            let _ = writeln!(
                md,
                "## {title}\n\n{}\n{fit}\n",
                report::comparison_markdown(&these, &published(&p.published, &hs))
            );
        }
    }
    for (j, (p, (_, levels))) in spec.k_paths.iter().zip(&plan.k_paths).enumerate() {
        let these: Vec<_> = k_rows
            .iter()
            .filter(|r| r.path == study.paths[spec.h_paths.len() + j].name)
            .copied()
            .collect();
        let kind = levels[0].kind();
        let title = match kind {
            LevelKind::Steps => format!("k refined at h = 1/{}", p.n),
            LevelKind::PerDecade => format!(
                "Steps per decade refined at h = 1/{} (from k₁ = {})",
                p.n,
                spec.first_step.unwrap_or(f64::NAN)
            ),
            LevelKind::Tolerance => format!("Tolerance refined at h = 1/{}", p.n),
        };
        let order = study.fitted_order(&study.paths[spec.h_paths.len() + j]);
        let fit = match kind {
            LevelKind::Steps => fitted_line(order, "k"),
            _ => format!(
                "The parameter is {}. {}",
                kind.parameter_words(),
                fitted_line(order, kind.symbol())
            ),
        };
        if p.published.is_empty() {
            let _ = writeln!(md, "## {title}\n\n{}\n{fit}\n", report::path_markdown(&these));
        } else {
            let ks: Vec<f64> = levels.iter().map(|l| l.parameter(t)).collect();
            let _ = writeln!(
                md,
                "## {title}\n\n{}\n{fit}\n",
                report::comparison_markdown(&these, &published(&p.published, &ks))
            );
        }
    }
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
                "u_ν along Γ₃ ({}) of the reference run, h = 1/{}, {}",
                base.groups.contact,
                plan.reference.0,
                level_text(&plan.reference.1, spec.first_step)
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
            reference: (
                plan.reference.0,
                plan.reference.1.steps().ok_or("--target plans uniform steps only")?,
            ),
            mesh_files: files.keys().copied().collect(),
            wide: setup.wide,
            solid: D == 3,
        };
        let uniform_scene = |steps: usize| make_scene(&TimeLevel::Steps(steps));
        let section = target_sections(&study, &context, targets, make_mesh, &uniform_scene)?;
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

/// The sentence under a path's table that says which order is which.
fn fitted_line(order: Option<f64>, parameter: &str) -> String {
    match order {
        Some(o) => format!(
            "The `order` columns are observed between neighbouring runs, log(e₁/e₂)/log({parameter}₁/{parameter}₂); \
             fitted over all runs of the path (least squares of log e against log {parameter}) the H¹ error at T has \
             order {o:.3}."
        ),
        None => "(one run: no order)".into(),
    }
}

/// The reference's time levels as the report's first sentence names them: `k = T/64`, `80 steps
/// per decade from k₁ = 0.0001`, `automatic steps to a tolerance of 1e-6`.
fn level_text(level: &TimeLevel, first_step: Option<f64>) -> String {
    match *level {
        TimeLevel::Steps(n) => format!("k = T/{n}"),
        TimeLevel::PerDecade(s) => format!("{s} steps per decade from k₁ = {}", first_step.unwrap_or(f64::NAN)),
        TimeLevel::Tolerance(e) => match first_step {
            Some(k) => format!("automatic steps to a tolerance of {e:e} from k₁ = {k}"),
            None => format!("automatic steps to a tolerance of {e:e}"),
        },
    }
}

/// True when every level of the plan is uniform (the tables are then those of uniform studies).
fn uniform_study(plan: &StudyPlan) -> bool {
    plan.reference.1.is_uniform() && plan.k_paths.iter().all(|(_, l)| l.iter().all(TimeLevel::is_uniform))
}

/// The automatic steps' own first step for `scene` (src/solver/schedule.rs, docs/method.md §20.4):
/// a tenth of the shortest relaxation time of its Prony terms, at most a tenth of T. The lower end
/// of a study's compared times when a tolerance path gives no `first_step`.
fn automatic_first_step(scene: &Scene) -> f64 {
    let t = scene.time.final_time;
    let shortest = scene
        .constants()
        .iter()
        .filter_map(|c| c.model(None).ok()?.1?.shortest_relaxation_time())
        .reduce(f64::min);
    crate::solver::schedule::default_first_step(t, shortest)
}
