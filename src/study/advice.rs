//! What `hvi study --target` says (docs/method.md §6.1): the cheapest run that reaches the target,
//! why nothing cheaper does, and the command to run it.

use super::format::fraction;
use super::target::{self, Candidate, CostModel, CostSample, ErrorModel, ErrorSample};
use super::{Keep, RunOptions, Study};
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::study::spec::{StudySpec, TimeLevels};
use std::fmt::Write as _;
use std::path::Path;

/// What to plan after the study (`hvi study --target E [--verify]`).
#[derive(Clone, Debug, Default)]
pub struct Targets {
    /// Target H¹ errors at T (each > 0).
    pub errors: Vec<f64>,
    /// Run each recommendation and compare it with its prediction.
    pub verify: bool,
}

/// What the planner needs to know about the study besides its runs.
pub(super) struct TargetContext<'a> {
    pub(super) spec: &'a StudySpec,
    pub(super) dir: &'a Path,
    pub(super) extra: &'a [String],
    pub(super) final_time: f64,
    pub(super) keep: &'a Keep,
    pub(super) reference: (usize, usize),
    /// The n of the study's mesh files.
    pub(super) mesh_files: std::collections::BTreeSet<usize>,
    /// Generated meshes: 2h × h cells (n × n in the plane) instead of square ones.
    pub(super) wide: bool,
    /// Generated meshes are the 3D slab (n divisible by 4), not the rectangle.
    pub(super) solid: bool,
}

/// `--target` plans uniform steps only (docs/method.md §6.1): its error model is C_k k^q in the
/// uniform step k = T/N and its cost model a cost per step, neither of which describes steps per
/// decade or automatic steps. The study's first level that is not uniform is named in the refusal.
pub(super) fn uniform_only(name: &str, levels: &TimeLevels) -> Result<(), String> {
    let mut all = std::iter::once((String::from("the reference"), vec![levels.reference])).chain(
        levels
            .k_paths
            .iter()
            .enumerate()
            .map(|(i, l)| (format!("k_paths[{i}]"), l.clone())),
    );
    match all.find_map(|(who, l)| Some((who, l.into_iter().find(|x| !x.is_uniform())?))) {
        None => Ok(()),
        Some((who, level)) => Err(format!(
            "{name}: --target: {who} steps by {} ({}), but the planner models uniform steps only: its error model \
             e ≈ C_h h^p + C_k k^q and its cost per step are in k = T/N (docs/method.md §6.1), and say nothing of \
             steps per decade or automatic steps. Plan on a study whose reference and k paths give `steps`, or run \
             this one without --target",
            level.kind().key(),
            level.label()
        )),
    }
}

/// n = 1/h of a run (h is set to 1/n by the study).
pub(super) fn n_of(h: f64) -> usize {
    (1.0 / h).round() as usize
}

/// The `hvi solve` command of a planned run.
pub(super) fn solve_command(c: &TargetContext, n: usize, steps: usize) -> String {
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
pub(super) fn why_no_cheaper(
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
pub(super) fn target_sections<const D: usize>(
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
        // the cheapest run of the tables that reaches the target (measured): by its work,
        // unknowns × steps, which the machine's noise does not reorder (wall times of runs a few
        // tens of per cent apart swap places from one minute to the next); wall time breaks ties
        let cheapest = study
            .runs
            .iter()
            .filter(|r| r.errors.at_final.h1_seminorm <= e_target)
            .min_by(|a, b| {
                let work = |r: &&super::runner::EvaluatedRun| r.summary.unknowns as f64 * r.summary.steps as f64;
                work(a)
                    .total_cmp(&work(b))
                    .then(a.summary.wall.total_cmp(&b.summary.wall))
            });
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
        if n == n_ref {
            let _ = writeln!(
                md,
                "* **This h is the reference's own: against this reference its spatial error is 0 by construction, \
                 so the target cannot be verified against it** (what is measured is the temporal error alone). \
                 To verify, run the study with a finer reference (reference.n above {n_ref})."
            );
        }
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
