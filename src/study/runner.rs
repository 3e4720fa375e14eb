//! Runs of a convergence study and their errors against a reference (docs/method.md §6).
//!
//! [`run`] solves one scene on one mesh and keeps what a study needs: the nodal displacement
//! at T and at the chosen output times, the per-phase times, the Newton count and the peak
//! memory. [`Study`] holds a reference (a finer run, or an exact field) and evaluates each run
//! against it as it is added: the H¹-seminorm and L² errors at T, the largest H¹ error over the
//! output times both share, and then the observed orders along each refinement path.
//! [`run_plan`] runs a [`StudyPlan`], whose k paths may step uniformly, by steps per decade or
//! to a tolerance ([`TimeLevel`], docs/method.md §20).

use super::interpolate::{boundary_sagitta, Extension, Locator};
use super::level::TimeLevel;
use super::seminorm_errors;
use crate::fem::norms::{errors, FieldErrors};
use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::solver::{timeloop, FrameSink, PhaseTimes, Simulation, SolveError, StepView};
use std::time::Instant;

/// Which steps' displacements a run keeps (besides the last one, always kept).
#[derive(Clone, Debug, PartialEq)]
pub enum Keep {
    /// The scene's output steps (`output.every`, and the last).
    Output,
    /// Every step.
    All,
    /// Only the last step.
    Final,
    /// The steps at these times (matched to 1e-9 of each time: a run over decades has its
    /// compared times as exact levels, some far below 1e-9 T).
    Times(Vec<f64>),
    /// The steps whose time is an integer multiple of this (e.g. 1/16).
    MultiplesOf(f64),
}

impl Keep {
    fn wants<const D: usize>(&self, sim: &Simulation<D>, view: &StepView) -> bool {
        let t = view.time;
        let tol = 1e-9 * sim.time.final_time().abs().max(1.0);
        match self {
            Keep::Output => view.output,
            Keep::All => true,
            Keep::Final => t == sim.time.final_time(),
            Keep::Times(ts) => ts.iter().any(|s| (s - t).abs() <= 1e-9 * s.abs()),
            Keep::MultiplesOf(dt) => {
                let q = t / dt;
                (q - q.round()).abs() * dt.abs() <= tol
            }
        }
    }
}

/// How to run and label one run of a study.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub label: String,
    /// The mesh size to report (default: the longest cell edge).
    pub h: Option<f64>,
    pub keep: Keep,
}

impl RunOptions {
    /// Keeps the output steps and measures h from the mesh.
    pub fn new(label: impl Into<String>) -> Self {
        RunOptions {
            label: label.into(),
            h: None,
            keep: Keep::Output,
        }
    }
}

/// One solved run, with what a study compares and reports.
pub struct RunRecord<const D: usize> {
    pub label: String,
    /// Mesh size (the longest cell edge unless set by [`RunOptions::h`]).
    pub h: f64,
    /// Time step T / N (the largest step); in a study's run of a level that is not uniform, the
    /// level's parameter ([`TimeLevel::parameter`]).
    pub k: f64,
    /// The time level a study gave the run (None outside a [`StudyPlan`]).
    pub level: Option<TimeLevel>,
    pub steps: usize,
    pub final_time: f64,
    pub nodes: usize,
    pub unknowns: usize,
    /// Nodal displacement at T (zero on Γ₁).
    pub final_displacement: Vec<[f64; D]>,
    /// Nodal displacements at the kept times (see [`Keep`]), in time order.
    pub displacement_at: Vec<(f64, Vec<[f64; D]>)>,
    pub phases: PhaseTimes,
    /// Wall time of setup and time loop, seconds.
    pub wall: f64,
    /// Newton (active-set) iterations summed over the steps.
    pub newton_total: usize,
    /// Peak resident memory of the process during the run (VmHWM, reset before the run where
    /// the kernel allows; it includes whatever the process already held).
    pub peak_rss_bytes: Option<u64>,
    pub mesh: Mesh<D>,
}

impl<const D: usize> RunRecord<D> {
    /// The run without its fields and mesh (what reports need).
    pub fn summary(&self) -> RunSummary {
        RunSummary {
            label: self.label.clone(),
            h: self.h,
            k: self.k,
            level: self.level,
            steps: self.steps,
            nodes: self.nodes,
            unknowns: self.unknowns,
            phases: self.phases.clone(),
            wall: self.wall,
            newton_total: self.newton_total,
            peak_rss_bytes: self.peak_rss_bytes,
        }
    }
}

/// A run's sizes, times and counters (no fields).
#[derive(Clone, Debug)]
pub struct RunSummary {
    pub label: String,
    pub h: f64,
    /// The time parameter of the orders: T/N, or a non-uniform level's parameter.
    pub k: f64,
    /// The time level a study gave the run (None outside a [`StudyPlan`]).
    pub level: Option<TimeLevel>,
    pub steps: usize,
    pub nodes: usize,
    pub unknowns: usize,
    pub phases: PhaseTimes,
    pub wall: f64,
    pub newton_total: usize,
    pub peak_rss_bytes: Option<u64>,
}

impl RunSummary {
    /// The run's time level as a table writes it: k as a fraction (`1/32`) for uniform steps,
    /// else the level (`10/decade`, `tol 1e-3`).
    pub fn k_text(&self) -> String {
        match self.level {
            Some(level) if !level.is_uniform() => level.label(),
            _ => super::format::fraction(self.k),
        }
    }

    /// True unless a study gave the run a level that is not uniform.
    pub fn is_uniform(&self) -> bool {
        self.level.is_none_or(|l| l.is_uniform())
    }

    /// Seconds of the time steps proper (loads, history, solves, contact, recovery).
    pub fn steps_seconds(&self) -> f64 {
        let p = &self.phases;
        p.loads + p.history + p.forward_sweep + p.contact + p.backward_sweep
    }
}

struct KeepSink<'a, const D: usize> {
    keep: &'a Keep,
    kept: Vec<(f64, Vec<[f64; D]>)>,
    last: Option<Vec<[f64; D]>>,
}

impl<const D: usize> FrameSink<D> for KeepSink<'_, D> {
    fn step_done(&mut self, sim: &Simulation<D>, view: &StepView) {
        let last = view.time == sim.time.final_time();
        let wanted = self.keep.wants(sim, view);
        if wanted || last {
            let nodal = sim.dofs.to_nodal(view.displacement);
            if last {
                self.last = Some(nodal.clone());
            }
            if wanted {
                self.kept.push((view.time, nodal));
            }
        }
    }

    fn write_frame(&mut self, _sim: &Simulation<D>, _view: &StepView) -> Result<(), SolveError> {
        Ok(())
    }
}

/// Solves `scene` on `mesh`, keeping the output steps.
pub fn run<const D: usize>(mesh: Mesh<D>, scene: &Scene, label: impl Into<String>) -> Result<RunRecord<D>, SolveError> {
    run_with(mesh, scene, &RunOptions::new(label))
}

/// Solves `scene` on `mesh` with the given options.
pub fn run_with<const D: usize>(
    mesh: Mesh<D>,
    scene: &Scene,
    options: &RunOptions,
) -> Result<RunRecord<D>, SolveError> {
    reset_peak_rss();
    let started = Instant::now();
    let h = options.h.unwrap_or_else(|| mesh.longest_edge());
    if scene.material.plane == Some(crate::scene::Plane::Axisymmetric) {
        // its error norms would need the measure 2πr (docs/method.md §8.6)
        return Err(SolveError::Setup(format!(
            "{}: `hvi study` measures its errors over the mesh's plane, not over the body of revolution \
             (material.plane = \"axisymmetric\"): run the levels with `hvi solve` and compare their outputs",
            scene.origin
        )));
    }
    let sim = Simulation::new(scene, mesh)?;
    let mut sink = KeepSink {
        keep: &options.keep,
        kept: Vec::new(),
        last: None,
    };
    let stats = timeloop::run(&sim, &mut sink, None)?;
    let wall = started.elapsed().as_secs_f64();
    let final_displacement = sink
        .last
        .take()
        .ok_or_else(|| SolveError::Setup("the run produced no step".into()))?;
    Ok(RunRecord {
        label: options.label.clone(),
        h,
        k: stats.largest_step,
        level: None,
        steps: stats.steps,
        final_time: sim.time.final_time(),
        nodes: sim.mesh.points.len(),
        unknowns: sim.dofs.n_free(),
        final_displacement,
        displacement_at: sink.kept,
        phases: stats.phases.clone(),
        wall,
        newton_total: stats.newton_iterations.iter().sum(),
        peak_rss_bytes: peak_rss_bytes(),
        mesh: sim.mesh,
    })
}

/// VmHWM of this process from /proc/self/status, in bytes (None where there is no procfs).
pub fn peak_rss_bytes() -> Option<u64> {
    crate::solver::stats::peak_memory_bytes()
}

/// Resets VmHWM to the current RSS (Linux ≥ 4.0; silently nothing elsewhere).
pub fn reset_peak_rss() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// An exact displacement field: (t, x) ↦ (u, ∇u), (∇u)_ij = ∂u_i/∂x_j.
pub type ExactField<const D: usize> = Box<dyn Fn(f64, [f64; D]) -> ([f64; D], [[f64; D]; D])>;

/// What the runs of a study are compared with.
pub enum Reference<const D: usize> {
    /// A (finer) run: coarse fields are carried to its mesh by nodal interpolation.
    Run(Box<RunRecord<D>>),
    /// A known solution: errors are integrated on each run's own mesh.
    Exact(ExactField<D>),
}

/// Which parameter a refinement path refines.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refinement {
    /// Mesh size h (time step fixed).
    H,
    /// Time step k (mesh fixed).
    K,
}

/// Errors of one run against the reference.
#[derive(Clone, Copy, Debug, Default)]
pub struct RunErrors {
    /// At T.
    pub at_final: FieldErrors,
    /// max over the output times shared with the reference of the H¹-seminorm error.
    pub h1_max_over_time: f64,
    /// The time where that maximum is attained.
    pub h1_max_time: f64,
    /// How many times were compared for the maximum.
    pub times_compared: usize,
    /// Reference nodes outside the run's mesh, evaluated by extension (non-nested meshes of a
    /// curved domain); None when every one was inside.
    pub extension: Option<Extension>,
}

/// A run once evaluated: its summary and errors.
#[derive(Clone, Debug)]
pub struct EvaluatedRun {
    pub summary: RunSummary,
    pub errors: RunErrors,
}

/// An ordered list of runs (coarse to fine) refining one parameter.
#[derive(Clone, Debug)]
pub struct RefinementPath {
    pub name: String,
    pub refine: Refinement,
    /// Indices into [`Study::runs`].
    pub runs: Vec<usize>,
}

/// One line of a study's tables: a run on a path, with the observed orders from the
/// previous run of the path.
#[derive(Clone, Debug)]
pub struct Row {
    pub path: String,
    pub refine: Refinement,
    /// Index into [`Study::runs`].
    pub run: usize,
    pub summary: RunSummary,
    pub errors: RunErrors,
    /// log(e_{i−1}/e_i) / log(p_{i−1}/p_i) of the H¹-seminorm error at T (p = h or k).
    pub order: Option<f64>,
    /// The same for the L² error at T.
    pub l2_order: Option<f64>,
    /// The same for the max-over-time H¹ error.
    pub max_order: Option<f64>,
}

/// A convergence study: a reference and the runs evaluated against it.
///
/// Runs are evaluated when added and their fields dropped, so a study holds only the
/// reference's fields.
pub struct Study<const D: usize> {
    pub reference: Reference<D>,
    pub runs: Vec<EvaluatedRun>,
    pub paths: Vec<RefinementPath>,
}

impl<const D: usize> Study<D> {
    /// A study against a reference run (keep the times to compare: see [`Keep`]).
    pub fn against_run(reference: RunRecord<D>) -> Self {
        Study {
            reference: Reference::Run(Box::new(reference)),
            runs: Vec::new(),
            paths: Vec::new(),
        }
    }

    /// A study against an exact solution.
    pub fn against_exact(exact: ExactField<D>) -> Self {
        Study {
            reference: Reference::Exact(exact),
            runs: Vec::new(),
            paths: Vec::new(),
        }
    }

    /// The reference run, if the reference is a run.
    pub fn reference_run(&self) -> Option<&RunRecord<D>> {
        match &self.reference {
            Reference::Run(r) => Some(r),
            Reference::Exact(_) => None,
        }
    }

    /// Evaluates `run` against the reference and stores its summary and errors; returns its
    /// index for [`Study::add_path`].
    pub fn add_run(&mut self, run: &RunRecord<D>) -> Result<usize, String> {
        let errors = self.evaluate(run)?;
        self.runs.push(EvaluatedRun {
            summary: run.summary(),
            errors,
        });
        Ok(self.runs.len() - 1)
    }

    /// Declares a refinement path through runs already added (coarse to fine).
    pub fn add_path(&mut self, name: impl Into<String>, refine: Refinement, runs: Vec<usize>) -> Result<(), String> {
        if let Some(&bad) = runs.iter().find(|&&r| r >= self.runs.len()) {
            return Err(format!(
                "path refers to run {bad}, but the study has {} runs",
                self.runs.len()
            ));
        }
        self.paths.push(RefinementPath {
            name: name.into(),
            refine,
            runs,
        });
        Ok(())
    }

    /// The errors of `run` against the reference (nothing stored).
    pub fn evaluate(&self, run: &RunRecord<D>) -> Result<RunErrors, String> {
        match &self.reference {
            Reference::Exact(exact) => {
                let on_mesh = |t: f64, u: &[[f64; D]]| errors(&run.mesh.cells, &run.mesh.points, u, |x| exact(t, x));
                let at_final = on_mesh(run.final_time, &run.final_displacement);
                let tol = time_tolerance(run.final_time);
                let others = run
                    .displacement_at
                    .iter()
                    .filter(|(t, _)| (t - run.final_time).abs() > tol)
                    .map(|(t, u)| (*t, on_mesh(*t, u).h1_seminorm));
                Ok(with_max_over_time(at_final, run.final_time, others))
            }
            Reference::Run(reference) => {
                let tol = time_tolerance(reference.final_time);
                if (run.final_time - reference.final_time).abs() > tol {
                    return Err(format!(
                        "run {} ends at T = {} but the reference {} at T = {}",
                        run.label, run.final_time, reference.label, reference.final_time
                    ));
                }
                // non-nested meshes of a curved domain: reference nodes up to the coarse boundary's
                // sagitta outside the run's mesh are evaluated by extension (docs/method.md §6.2)
                let (transfer, extension) = Locator::new(&run.mesh)
                    .transfer_extending(&reference.mesh.points, boundary_sagitta(&run.mesh))
                    .map_err(|e| format!("carrying run {} to the reference mesh: {e}", run.label))?;
                let at =
                    |u_ref: &[[f64; D]], u: &[[f64; D]]| seminorm_errors(&reference.mesh, u_ref, &transfer.apply(u));
                let at_final = at(&reference.final_displacement, &run.final_displacement);
                let others = run
                    .displacement_at
                    .iter()
                    .filter(|(t, _)| (t - run.final_time).abs() > tol)
                    .filter_map(|(t, u)| {
                        // the nearest of the reference's kept times (times a decade apart from 1e-6
                        // on may all lie within the tolerance of 1e-9 T)
                        let (_, u_ref) = reference
                            .displacement_at
                            .iter()
                            .filter(|(s, _)| (s - t).abs() <= tol)
                            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))?;
                        Some((*t, at(u_ref, u).h1_seminorm))
                    });
                let mut errors = with_max_over_time(at_final, run.final_time, others);
                errors.extension = (extension.points > 0).then_some(extension);
                Ok(errors)
            }
        }
    }

    /// The rows of every path, with observed orders between neighbours.
    pub fn rows(&self) -> Vec<Row> {
        let mut rows = Vec::new();
        for path in &self.paths {
            let mut prev: Option<&EvaluatedRun> = None;
            for &r in &path.runs {
                let run = &self.runs[r];
                let param = |e: &EvaluatedRun| match path.refine {
                    Refinement::H => e.summary.h,
                    Refinement::K => e.summary.k,
                };
                let order = |f: fn(&RunErrors) -> f64| {
                    prev.map(|p| observed_order(param(p), f(&p.errors), param(run), f(&run.errors)))
                };
                rows.push(Row {
                    path: path.name.clone(),
                    refine: path.refine,
                    run: r,
                    summary: run.summary.clone(),
                    errors: run.errors,
                    order: order(|e| e.at_final.h1_seminorm),
                    l2_order: order(|e| e.at_final.l2),
                    max_order: order(|e| e.h1_max_over_time),
                });
                prev = Some(run);
            }
        }
        rows
    }

    /// Least-squares order of the H¹ error at T along a path (None for < 2 runs).
    pub fn fitted_order(&self, path: &RefinementPath) -> Option<f64> {
        (path.runs.len() >= 2).then(|| {
            let (p, e): (Vec<f64>, Vec<f64>) = path
                .runs
                .iter()
                .map(|&r| {
                    let run = &self.runs[r];
                    let p = if path.refine == Refinement::H {
                        run.summary.h
                    } else {
                        run.summary.k
                    };
                    (p, run.errors.at_final.h1_seminorm)
                })
                .unzip();
            crate::fem::norms::fitted_order(&p, &e)
        })
    }
}

/// log(e₀/e₁) / log(p₀/p₁).
pub fn observed_order(p0: f64, e0: f64, p1: f64, e1: f64) -> f64 {
    (e0 / e1).ln() / (p0 / p1).ln()
}

fn time_tolerance(final_time: f64) -> f64 {
    1e-9 * final_time.abs().max(1.0)
}

/// A study on uniformly refined meshes: a mesh is named by n (h = 1/n), a time grid by its
/// level: N uniform steps (k = T/N), s steps per decade or a tolerance (docs/method.md §20).
#[derive(Clone, Debug)]
pub struct StudyPlan {
    /// (n, level) of the reference run.
    pub reference: (usize, TimeLevel),
    /// h-refinement paths: (N, [n coarse to fine]), uniform steps.
    pub h_paths: Vec<(usize, Vec<usize>)>,
    /// k-refinement paths: (n, [level coarse to fine]), the levels of one path of one kind.
    pub k_paths: Vec<(usize, Vec<TimeLevel>)>,
    /// Which steps every run keeps (the reference too): the max over time compares the kept
    /// times both have. With [`Keep::Times`] those times are made levels of the reference and of
    /// every run whose level is not uniform (its scene's `output.times`); a uniform run keeps those
    /// on its own grid.
    pub keep: Keep,
}

/// Runs a [`StudyPlan`]: the reference first, then every distinct (n, level) once, in the order
/// the paths name them, each evaluated and dropped (only the reference's fields are held).
/// `make_mesh(n)` builds the mesh of h = 1/n, `make_scene(level)` the scene stepping by `level`;
/// `progress` sees each run (with its errors, None for the reference) as it finishes. A run of a
/// level that is not uniform reports the level's parameter as its `k` (docs/method.md §6).
pub fn run_plan<const D: usize>(
    plan: &StudyPlan,
    make_mesh: &dyn Fn(usize) -> Mesh<D>,
    make_scene: &dyn Fn(&TimeLevel) -> Scene,
    progress: &mut dyn FnMut(&RunRecord<D>, Option<&RunErrors>),
) -> Result<Study<D>, String> {
    let one = |n: usize, level: &TimeLevel, label: String, reference: bool| -> Result<RunRecord<D>, String> {
        let options = RunOptions {
            label: label.clone(),
            h: Some(1.0 / n as f64),
            keep: plan.keep.clone(),
        };
        let mut scene = make_scene(level);
        // the compared times are levels of every run that would not meet them otherwise
        // (docs/method.md §20.1: output times are levels)
        if let Keep::Times(times) = &plan.keep {
            if reference || !level.is_uniform() {
                let outputs = &mut scene.output.times;
                outputs.extend(times.iter().copied());
                outputs.sort_by(f64::total_cmp);
                outputs.dedup();
            }
        }
        let mut record = run_with(make_mesh(n), &scene, &options).map_err(|e| format!("run {label}: {e}"))?;
        if !level.is_uniform() {
            record.k = level.parameter(record.final_time);
        }
        record.level = Some(*level);
        Ok(record)
    };
    let label = |n: usize, level: &TimeLevel| format!("h=1/{n} {}", level.label());
    let (rn, rl) = plan.reference;
    let reference = one(rn, &rl, format!("reference {}", label(rn, &rl)), true)?;
    progress(&reference, None);
    let mut study = Study::against_run(reference);
    let mut done: Vec<((usize, TimeLevel), usize)> = Vec::new();
    let mut index = |study: &mut Study<D>,
                     n: usize,
                     level: TimeLevel,
                     progress: &mut dyn FnMut(&RunRecord<D>, Option<&RunErrors>)|
     -> Result<usize, String> {
        if let Some(&(_, i)) = done.iter().find(|(key, _)| *key == (n, level)) {
            return Ok(i);
        }
        let record = one(n, &level, label(n, &level), false)?;
        let i = study.add_run(&record)?;
        progress(&record, Some(&study.runs[i].errors));
        done.push(((n, level), i));
        Ok(i)
    };
    for (steps, ns) in plan.h_paths.iter().filter(|(_, ns)| !ns.is_empty()) {
        let runs = ns
            .iter()
            .map(|&n| index(&mut study, n, TimeLevel::Steps(*steps), progress))
            .collect::<Result<Vec<_>, _>>()?;
        let k = study.runs[runs[0]].summary.k;
        study.add_path(format!("h (k={})", super::format::fraction(k)), Refinement::H, runs)?;
    }
    for (n, levels) in plan.k_paths.iter().filter(|(_, s)| !s.is_empty()) {
        let runs = levels
            .iter()
            .map(|&l| index(&mut study, *n, l, progress))
            .collect::<Result<Vec<_>, _>>()?;
        study.add_path(k_path_name(*n, &levels[0]), Refinement::K, runs)?;
    }
    Ok(study)
}

/// The name of a k path at h = 1/n by the kind of its levels: `k (h=1/64)` for uniform steps,
/// `k per decade (h=1/64)`, `k by tolerance (h=1/64)`.
fn k_path_name(n: usize, level: &TimeLevel) -> String {
    match level {
        TimeLevel::Steps(_) => format!("k (h=1/{n})"),
        TimeLevel::PerDecade(_) => format!("k per decade (h=1/{n})"),
        TimeLevel::Tolerance(_) => format!("k by tolerance (h=1/{n})"),
    }
}

/// The errors at T plus the largest H¹ error over the other compared times `(t, error)`.
fn with_max_over_time(at_final: FieldErrors, final_time: f64, others: impl Iterator<Item = (f64, f64)>) -> RunErrors {
    let mut max = (at_final.h1_seminorm, final_time);
    let mut count = 1;
    for (t, e) in others {
        count += 1;
        if e > max.0 {
            max = (e, t);
        }
    }
    RunErrors {
        at_final,
        h1_max_over_time: max.0,
        h1_max_time: max.1,
        times_compared: count,
        extension: None,
    }
}
