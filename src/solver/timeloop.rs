//! The time loop (METHOD.md §3–4). Per step n:
//!
//! ```text
//!   F_n            ← loads(t_n)                      (once, if no load depends on t)
//!   rhs            ← F_n − K_B h_n                   (history, only with a memory kernel)
//!   u_free         ← K⁻¹ rhs                         (free solve, cached factor)
//!   λ              ← contact.solve(d = C u_free)     (only with contact)
//!   u_n            ← K⁻¹ (rhs − Cᵀ λ)                (recover)
//!   history.push(u_n); write the frame if it is an output step
//! ```
//!
//! with K = K_A + (k/2) b(0) K_B factored once. Step 0 has no history and uses K_A alone;
//! when its solution is not trivially zero and K ≠ K_A, K_A gets a factor of its own.

use super::error::SolveError;
use super::setup::{ContactSetup, Simulation};
use super::stats::{timed, RunStats};
use crate::contact::active_set::{ActiveSetSolver, ContactOutcome, ContactState};
use crate::contact::CondensedOperator;
use crate::fem::assembly::assemble_stiffness;
use crate::fem::SymmetricMatrix;
use crate::history::History;
use crate::linalg::{Counters, Factor};
use crate::material::IDENTITY_TENSOR;
use faer::sparse::linalg::solvers::SymbolicLlt;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// What the driver shows a sink after a step: all vectors over the free unknowns.
pub struct StepView<'a> {
    pub step: usize,
    pub time: f64,
    /// u_n.
    pub displacement: &'a [f64],
    /// m_n = h_n + (k/2) b(0) u_n, whose strain is the memory stress (None without memory).
    pub memory_displacement: Option<&'a [f64]>,
    pub contact: Option<&'a ContactState>,
    pub outcome: Option<ContactOutcome>,
}

/// Receives the steps of a run (the output layer implements this; tests collect in memory).
pub trait FrameSink {
    /// Called after every step (for progress reporting).
    fn step_done(&mut self, _sim: &Simulation, _view: &StepView) {}
    /// Called for every output step.
    fn write_frame(&mut self, sim: &Simulation, view: &StepView) -> Result<(), SolveError>;
}

/// A factor of a step matrix and, with contact, its condensed operator.
struct StepOperator {
    factor: Factor,
    condensed: Option<CondensedOperator>,
}

impl StepOperator {
    fn new(
        sim: &Simulation,
        symbolic: &SymbolicLlt<usize>,
        matrix: &SymmetricMatrix,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Self, SolveError> {
        let factor = timed(&mut stats.phases.factorisation, || Factor::new(symbolic, matrix, counters)).map_err(|e| {
            SolveError::Singular { mesh: sim.mesh.path.display().to_string(), detail: e.to_string() }
        })?;
        let condensed = match &sim.contact {
            Some(c) if !c.nodes.is_empty() => Some(
                timed(&mut stats.phases.condensation, || CondensedOperator::new(&c.nodes, &factor, counters))
                    .map_err(SolveError::Setup)?,
            ),
            _ => None,
        };
        Ok(StepOperator { factor, condensed })
    }

    /// Solves one step: free solve, contact, recover. `rhs` is consumed into u_n.
    fn solve(
        &self,
        sim: &Simulation,
        step: usize,
        rhs: &mut Vec<f64>,
        state: Option<&mut ContactState>,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<(Vec<f64>, Option<ContactOutcome>), SolveError> {
        let mut u = rhs.clone();
        timed(&mut stats.phases.free_solve, || self.factor.solve_in_place(&mut u, counters));
        let (Some(setup), Some(op), Some(state)) = (&sim.contact, &self.condensed, state) else {
            return Ok((u, None));
        };
        let outcome = timed(&mut stats.phases.contact, || contact_solve(sim, setup, op, step, &u, state))?;
        stats.contact_solves += 1;
        timed(&mut stats.phases.recover, || {
            setup.nodes.subtract_transpose(&state.force, rhs);
            self.factor.solve_in_place(rhs, counters);
        });
        Ok((std::mem::take(rhs), Some(outcome)))
    }
}

fn contact_solve(
    sim: &Simulation,
    setup: &ContactSetup,
    op: &CondensedOperator,
    step: usize,
    u_free: &[f64],
    state: &mut ContactState,
) -> Result<ContactOutcome, SolveError> {
    let mut d = vec![0.0; setup.nodes.len()];
    setup.nodes.normal_displacements(u_free, &mut d);
    let solver = ActiveSetSolver {
        operator: op,
        weights: &setup.nodes.weights,
        law: setup.law.as_ref(),
        bound: setup.bound.as_deref(),
        settings: setup.settings,
    };
    solver.solve(&d, state).map_err(|f| SolveError::ContactFailed {
        step,
        time: sim.time.time(step),
        iterations: f.outcome.iterations,
        residual: f.outcome.residual,
        tolerance: setup.settings.tolerance,
        reason: f.reason,
    })
}

/// Runs the whole time series, handing every step to `sink`. `stop` is polled once per step.
pub fn run(sim: &Simulation, sink: &mut dyn FrameSink, stop: Option<&AtomicBool>) -> Result<RunStats, SolveError> {
    let started = Instant::now();
    crate::linalg::set_parallelism(sim.threads);
    let counters = Counters::default();
    let mut stats = RunStats {
        nodes: sim.mesh.points.len(),
        cells: sim.mesh.cells.len(),
        unknowns: sim.dofs.n_free(),
        contact_nodes: sim.contact.as_ref().map_or(0, |c| c.nodes.len()),
        steps: sim.time.steps,
        time_step: sim.time.step(),
        final_time: sim.time.final_time,
        effects: super::plan::Plan::new(sim).effect_names(),
        ..Default::default()
    };
    let k = sim.time.step();
    let n_dof = sim.dofs.n_free();
    let (points, cells) = (&sim.mesh.points, &sim.mesh.cells);

    // Assembly: K_A, and K_B only with a memory kernel.
    let d_a = sim.elasticity.voigt();
    let (k_a, k_b) = timed(&mut stats.phases.assembly, || match &sim.kernel {
        Some(_) => {
            let [a, b] = assemble_stiffness(cells, points, &sim.dofs, &[d_a, IDENTITY_TENSOR]);
            (a, Some(b))
        }
        None => {
            let [a] = assemble_stiffness(cells, points, &sim.dofs, &[d_a]);
            (a, None)
        }
    });
    stats.matrix_nonzeros = k_a.values.len();
    // K = K_A + (k/2) b(0) K_B.
    let memory_diagonal = sim.kernel.as_ref().map(|b| 0.5 * k * b.value(0.0));
    let k_step = match (&k_b, memory_diagonal) {
        (Some(kb), Some(c)) => timed(&mut stats.phases.assembly, || k_a.plus_scaled(c, kb)),
        _ => k_a.clone(),
    };
    let symbolic = timed(&mut stats.phases.factorisation, || Factor::analyse(&k_step))
        .map_err(|e| SolveError::Setup(e.to_string()))?;
    let main = StepOperator::new(sim, &symbolic, &k_step, &counters, &mut stats)?;
    drop(k_step);

    let mut history = sim.kernel.as_ref().map(|b| History::new(b, n_dof, k));
    let mut state = sim.contact.as_ref().map(|c| ContactState::new(c.nodes.len()));
    if let (Some(state), Some(c)) = (&mut state, &sim.contact) {
        if let Some(g) = &c.bound {
            // start at no contact, inside the bound
            state.normal_displacement.iter_mut().zip(g).for_each(|(r, g)| *r = r.min(*g));
        }
    }
    let time_dependent = sim.loads.is_time_dependent();
    let single_solve = history.is_none() && !time_dependent;

    let mut f = vec![0.0; n_dof];
    let mut h = vec![0.0; n_dof];
    let mut kb_h = vec![0.0; n_dof];
    let mut memory_disp: Option<Vec<f64>> = None;
    let mut u: Vec<f64> = Vec::new();
    let mut outcome: Option<ContactOutcome> = None;
    for n in 0..=sim.time.steps {
        if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Err(SolveError::Interrupted { last_written: n.saturating_sub(1) });
        }
        let t = sim.time.time(n);
        if n == 0 || time_dependent {
            timed(&mut stats.phases.loads, || sim.loads.assemble(t, &sim.dofs, &mut f));
        }
        if !(single_solve && n > 0) {
            let mut rhs = f.clone();
            if let (Some(hist), Some(kb)) = (&history, &k_b) {
                timed(&mut stats.phases.history, || {
                    hist.memory_load(&mut h);
                    if n > 0 {
                        kb.matvec(&h, &mut kb_h);
                        rhs.iter_mut().zip(&kb_h).for_each(|(r, v)| *r -= v);
                    }
                });
            }
            let (un, out) = if n == 0 && history.is_some() {
                step_zero(sim, &symbolic, &k_a, &mut rhs, state.as_mut(), &counters, &mut stats)?
            } else {
                main.solve(sim, n, &mut rhs, state.as_mut(), &counters, &mut stats)?
            };
            if un.iter().any(|v| !v.is_finite()) {
                return Err(SolveError::NonFinite { step: n, time: t });
            }
            u = un;
            outcome = out;
            if let Some(o) = outcome {
                stats.newton_iterations.push(o.iterations);
                stats.max_contact_residual = stats.max_contact_residual.max(o.residual);
                stats.contact.push(o);
            }
        } else if let Some(o) = outcome {
            stats.newton_iterations.push(0);
            stats.contact.push(ContactOutcome { iterations: 0, ..o });
        }
        if let (Some(hist), Some(c)) = (&mut history, memory_diagonal) {
            timed(&mut stats.phases.history, || {
                // m_n = h_n + (k/2) b(0) u_n (h_0 = 0)
                let m: Vec<f64> = h.iter().zip(&u).map(|(hv, uv)| if n == 0 { c * uv } else { hv + c * uv }).collect();
                memory_disp = Some(m);
                hist.push(&u);
            });
        }
        let view = StepView {
            step: n,
            time: t,
            displacement: &u,
            memory_displacement: memory_disp.as_deref(),
            contact: state.as_ref(),
            outcome,
        };
        sink.step_done(sim, &view);
        if sim.is_output_step(n) {
            timed(&mut stats.phases.output, || sink.write_frame(sim, &view))?;
            stats.frames_written += 1;
        }
    }
    stats.history_algorithm = history.as_ref().map(|h| h.algorithm().to_string());
    stats.history_bytes = history.as_ref().map_or(0, |h| h.bytes_held());
    stats.factorisations = counters.factorisations();
    stats.solves = counters.solves();
    stats.phases.total = started.elapsed().as_secs_f64();
    Ok(stats)
}

/// Step 0 with a memory kernel: K_A u_0 + Cᵀλ = F_0 (no history term). When u_0 = 0 solves it
/// exactly (no load, and the contact law exerts no force at 0) nothing is factorised.
fn step_zero(
    sim: &Simulation,
    symbolic: &SymbolicLlt<usize>,
    k_a: &SymmetricMatrix,
    rhs: &mut Vec<f64>,
    state: Option<&mut ContactState>,
    counters: &Counters,
    stats: &mut RunStats,
) -> Result<(Vec<f64>, Option<ContactOutcome>), SolveError> {
    let law_at_zero = sim.contact.as_ref().and_then(|c| c.law.as_ref()).map_or(0.0, |l| l.derivative(0.0));
    let bound_ok = sim.contact.as_ref().and_then(|c| c.bound.as_ref()).is_none_or(|g| g.iter().all(|v| *v >= 0.0));
    if rhs.iter().all(|v| *v == 0.0) && law_at_zero == 0.0 && bound_ok {
        let outcome = state.map(|s| {
            let m = s.force.len();
            *s = ContactState::new(m);
            ContactOutcome::default()
        });
        return Ok((vec![0.0; rhs.len()], outcome));
    }
    let op = StepOperator::new(sim, symbolic, k_a, counters, stats)?;
    op.solve(sim, 0, rhs, state, counters, stats)
}
