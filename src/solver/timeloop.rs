//! The time loop (METHOD.md §3–4). Per step n:
//!
//! ```text
//!   F_n            ← loads(t_n)                      (once, if no load depends on t)
//!   rhs            ← F_n − K_B h_n                   (history, only with a memory kernel)
//!   y              ← L⁻¹ P rhs                       (forward sweep, cached factor)
//!   λ              ← contact.solve(d = Gᵀ y)         (only with contact; d = C K⁻¹ rhs)
//!   y              ← y − G λ                         (only with contact)
//!   u_n            ← Pᵀ L⁻ᵀ y = K⁻¹ (rhs − Cᵀ λ)     (backward sweep)
//!   history.push(u_n); write the frame if it is an output step
//! ```
//!
//! with K = Pᵀ L Lᵀ P = K_A + (k/2) b(0) K_B factored once and G = L⁻¹ P Cᵀ formed once
//! (METHOD.md §4, "the fast path"): a step costs one solve, contact or not.
//! Step 0 has no history and uses K_A alone;
//! when its solution is not trivially zero and K ≠ K_A, K_A gets a factor of its own.

use super::error::SolveError;
use super::setup::{ContactSetup, Simulation};
use super::stats::{timed, RunStats};
use crate::contact::active_set::{ActiveSetSolver, ContactOutcome, ContactState};
use crate::contact::CondensedOperator;
use crate::fem::assembly::assemble_stiffness;
use crate::fem::{NodeBlockMatrix, SymmetricMatrix};
use crate::history::History;
use crate::linalg::{Analysis, Counters, Factor, Forward};
use crate::material::IDENTITY_TENSOR;
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
        symbolic: &Analysis,
        matrix: &SymmetricMatrix,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Self, SolveError> {
        let factor = timed(&mut stats.phases.factorisation, || {
            Factor::new(symbolic, matrix, counters)
        })
        .map_err(|e| SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail: e.to_string(),
        })?;
        timed(&mut stats.phases.factorisation, || probe_singularity(&factor, matrix)).map_err(|detail| {
            SolveError::Singular {
                mesh: sim.mesh.path.display().to_string(),
                detail,
            }
        })?;
        let condensed = match &sim.contact {
            Some(c) if !c.nodes.is_empty() => Some(
                timed(&mut stats.phases.condensation, || {
                    CondensedOperator::new(&c.nodes, &factor, counters)
                })
                .map_err(SolveError::Setup)?,
            ),
            _ => None,
        };
        Ok(StepOperator { factor, condensed })
    }

    /// Solves one step with one forward and one backward sweep over the factor:
    /// y = L⁻¹ P rhs, d = C K⁻¹ rhs = Gᵀ y, contact → λ, y ← y − G λ, u_n = Pᵀ L⁻ᵀ y.
    /// `y` is a work vector, `u` receives u_n.
    #[allow(clippy::too_many_arguments)]
    fn solve(
        &self,
        sim: &Simulation,
        step: usize,
        rhs: &[f64],
        y: &mut Forward,
        u: &mut [f64],
        state: Option<&mut ContactState>,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Option<ContactOutcome>, SolveError> {
        timed(&mut stats.phases.forward_sweep, || self.factor.forward_into(rhs, y));
        let outcome = match (&sim.contact, &self.condensed, state) {
            (Some(setup), Some(op), Some(state)) => {
                let outcome = timed(&mut stats.phases.contact, || {
                    contact_solve(sim, setup, op, step, y, state)
                })?;
                stats.contact_solves += 1;
                timed(&mut stats.phases.backward_sweep, || op.subtract_forces(&state.force, y));
                Some(outcome)
            }
            _ => None,
        };
        timed(&mut stats.phases.backward_sweep, || {
            self.factor.backward_from(y, u, counters)
        });
        Ok(outcome)
    }
}

/// A Cholesky factorisation of a singular matrix can succeed on round-off pivots (a body held
/// at a single point can still rotate about it). One probe solve, K⁻¹(K v) against v for a fixed
/// pseudo-random v, tells: an error far above round-off means the matrix is (nearly) singular.
/// The probe is not counted among the run's solves.
fn probe_singularity(factor: &Factor, matrix: &SymmetricMatrix) -> Result<(), String> {
    let n = matrix.n();
    let v: Vec<f64> = (0..n)
        .map(|i| ((i as f64 + 1.0) * 0.618_033_988_749_895).fract() - 0.5)
        .collect();
    let mut x = vec![0.0; n];
    matrix.matvec(&v, &mut x);
    factor.solve_in_place(&mut x, &Counters::default());
    let scale = v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let error = x.iter().zip(&v).fold(0.0f64, |a, (p, q)| a.max((p - q).abs())) / scale;
    if error.is_finite() && error <= 1e-6 {
        Ok(())
    } else {
        Err(format!(
            "the stiffness matrix is singular or nearly so (a probe solve is off by {error:.1e} relative): the body is not held against rigid motions; clamp a part of the boundary (groups.clamped) that stops translations and rotations"
        ))
    }
}

fn contact_solve(
    sim: &Simulation,
    setup: &ContactSetup,
    op: &CondensedOperator,
    step: usize,
    forward: &Forward,
    state: &mut ContactState,
) -> Result<ContactOutcome, SolveError> {
    let mut d = vec![0.0; setup.nodes.len()];
    op.normal_displacements(forward, &mut d);
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

/// K_B as the time loop multiplies it: in node blocks (a third of the memory traffic) when
/// its pattern allows, else as assembled.
enum MemoryStiffness {
    NodeBlocks(NodeBlockMatrix),
    Full(SymmetricMatrix),
}

impl MemoryStiffness {
    fn matvec(&self, x: &[f64], y: &mut [f64]) {
        match self {
            MemoryStiffness::NodeBlocks(m) => m.matvec(x, y),
            MemoryStiffness::Full(m) => m.matvec(x, y),
        }
    }
}

/// The state of a run between steps: the assembled matrices, the cached factor, the history
/// and the contact warm start. [`Stepper::prepare`] does the one-off work, [`Stepper::advance`]
/// one time step (METHOD.md §3–4).
pub struct Stepper<'s> {
    sim: &'s Simulation,
    pub counters: Counters,
    pub stats: RunStats,
    k_a: SymmetricMatrix,
    /// K_B for the memory load K_B h_n of every step.
    k_b: Option<MemoryStiffness>,
    symbolic: Analysis,
    main: StepOperator,
    /// (k/2) b(0), the memory term's share of K.
    memory_diagonal: Option<f64>,
    history: Option<History>,
    contact: Option<ContactState>,
    time_dependent_loads: bool,
    /// No memory and constant loads: every step equals step 0.
    single_solve: bool,
    load: Vec<f64>,
    /// Work vectors of a step: its right-hand side and its forward sweep.
    rhs: Vec<f64>,
    work: Forward,
    memory_load: Vec<f64>,
    memory_rhs: Vec<f64>,
    displacement: Vec<f64>,
    memory_displacement: Option<Vec<f64>>,
    outcome: Option<ContactOutcome>,
    next: usize,
}

impl<'s> Stepper<'s> {
    /// Assembles K_A (and K_B with memory), factorises K = K_A + (k/2) b(0) K_B once, and
    /// condenses the contact normals.
    pub fn prepare(sim: &'s Simulation) -> Result<Self, SolveError> {
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
        let memory_diagonal = sim.kernel.as_ref().map(|b| 0.5 * k * b.value(0.0));
        let symbolic = timed(&mut stats.phases.factorisation, || Factor::analyse(&k_a))
            .map_err(|e| SolveError::Setup(e.to_string()))?;
        let main = match (&k_b, memory_diagonal) {
            (Some(kb), Some(c)) => {
                let k_step = timed(&mut stats.phases.assembly, || k_a.plus_scaled(c, kb));
                StepOperator::new(sim, &symbolic, &k_step, &counters, &mut stats)?
            }
            _ => StepOperator::new(sim, &symbolic, &k_a, &counters, &mut stats)?,
        };
        if let (Some(op), Some(c)) = (&main.condensed, &sim.contact) {
            if let Some(law) = &c.law {
                stats.smallness = Some(law.relaxed_monotonicity() * op.trace_constant(&c.nodes.weights));
            }
        }
        let k_b = k_b.map(|kb| match NodeBlockMatrix::new(&kb) {
            Some(blocks) => MemoryStiffness::NodeBlocks(blocks),
            None => MemoryStiffness::Full(kb),
        });
        let history = sim.kernel.as_ref().map(|b| History::new(b, n_dof, k));
        let contact = sim.contact.as_ref().map(|c| ContactState::new(c.nodes.len()));
        let time_dependent_loads = sim.loads.is_time_dependent();
        Ok(Stepper {
            sim,
            counters,
            stats,
            k_a,
            k_b,
            symbolic,
            main,
            memory_diagonal,
            single_solve: history.is_none() && !time_dependent_loads,
            history,
            contact,
            time_dependent_loads,
            load: vec![0.0; n_dof],
            rhs: vec![0.0; n_dof],
            work: Forward::zeros(n_dof),
            memory_load: vec![0.0; n_dof],
            memory_rhs: vec![0.0; n_dof],
            displacement: vec![0.0; n_dof],
            memory_displacement: None,
            outcome: None,
            next: 0,
        })
    }

    /// The index of the step [`Stepper::advance`] will solve next.
    pub fn next_step(&self) -> usize {
        self.next
    }

    /// Solves the next step: loads, memory load, forward sweep, contact, backward sweep, history update.
    pub fn advance(&mut self) -> Result<StepView<'_>, SolveError> {
        let n = self.next;
        let sim = self.sim;
        let t = sim.time.time(n);
        if n == 0 || self.time_dependent_loads {
            let load = &mut self.load;
            timed(&mut self.stats.phases.loads, || sim.loads.assemble(t, &sim.dofs, load)).map_err(|detail| {
                SolveError::NonFiniteLoad {
                    step: n,
                    time: t,
                    detail,
                }
            })?;
        }
        if self.single_solve && n > 0 {
            // Nothing changes: the state of step 0 stands for every step.
            if let Some(o) = self.outcome {
                self.stats.newton_iterations.push(0);
                self.stats.contact.push(ContactOutcome { iterations: 0, ..o });
            }
        } else {
            let mut rhs = std::mem::take(&mut self.rhs);
            rhs.copy_from_slice(&self.load);
            self.subtract_memory_load(n, &mut rhs);
            let outcome = if n == 0 && self.history.is_some() {
                self.step_zero(&rhs)?
            } else {
                self.main.solve(
                    sim,
                    n,
                    &rhs,
                    &mut self.work,
                    &mut self.displacement,
                    self.contact.as_mut(),
                    &self.counters,
                    &mut self.stats,
                )?
            };
            self.rhs = rhs;
            if self.displacement.iter().any(|v| !v.is_finite()) {
                return Err(SolveError::NonFinite { step: n, time: t });
            }
            self.outcome = outcome;
            if let Some(o) = outcome {
                self.stats.newton_iterations.push(o.iterations);
                self.stats.max_contact_residual = self.stats.max_contact_residual.max(o.residual);
                self.stats.contact.push(o);
            }
        }
        self.update_history(n);
        self.next += 1;
        Ok(StepView {
            step: n,
            time: t,
            displacement: &self.displacement,
            memory_displacement: self.memory_displacement.as_deref(),
            contact: self.contact.as_ref(),
            outcome: self.outcome,
        })
    }

    /// Step 0 with a memory kernel: K_A u_0 + Cᵀλ = F_0 (no history term). When u_0 = 0 solves
    /// it exactly (no load, and the contact law exerts no force at 0) nothing is factorised.
    fn step_zero(&mut self, rhs: &[f64]) -> Result<Option<ContactOutcome>, SolveError> {
        let sim = self.sim;
        let law_at_zero = sim
            .contact
            .as_ref()
            .and_then(|c| c.law.as_ref())
            .map_or(0.0, |l| l.derivative(0.0));
        let bound_ok = sim
            .contact
            .as_ref()
            .and_then(|c| c.bound.as_ref())
            .is_none_or(|g| g.iter().all(|v| *v >= 0.0));
        if rhs.iter().all(|v| *v == 0.0) && law_at_zero == 0.0 && bound_ok {
            let outcome = self.contact.as_mut().map(|s| {
                let m = s.force.len();
                *s = ContactState::new(m);
                ContactOutcome::default()
            });
            self.displacement.fill(0.0);
            return Ok(outcome);
        }
        let op = StepOperator::new(sim, &self.symbolic, &self.k_a, &self.counters, &mut self.stats)?;
        let mut y = Forward::zeros(rhs.len());
        op.solve(
            sim,
            0,
            rhs,
            &mut y,
            &mut self.displacement,
            self.contact.as_mut(),
            &self.counters,
            &mut self.stats,
        )
    }

    /// rhs ← rhs − K_B h_n (METHOD.md §3); h_0 = 0.
    fn subtract_memory_load(&mut self, n: usize, rhs: &mut [f64]) {
        let (Some(history), Some(k_b)) = (&self.history, &self.k_b) else {
            return;
        };
        let (h, kb_h) = (&mut self.memory_load, &mut self.memory_rhs);
        timed(&mut self.stats.phases.history, || {
            history.memory_load(h);
            if n > 0 {
                k_b.matvec(h, kb_h);
                rhs.iter_mut().zip(kb_h.iter()).for_each(|(r, v)| *r -= v);
            }
        });
    }

    /// Records u_n in the history and keeps m_n = h_n + (k/2) b(0) u_n for the stresses.
    fn update_history(&mut self, n: usize) {
        let (Some(history), Some(c)) = (&mut self.history, self.memory_diagonal) else {
            return;
        };
        let (h, u) = (&self.memory_load, &self.displacement);
        let memory_displacement = &mut self.memory_displacement;
        let wanted = self.sim.is_output_step(n);
        timed(&mut self.stats.phases.history, || {
            // only output steps show the memory stress
            *memory_displacement = wanted.then(|| {
                h.iter()
                    .zip(u)
                    .map(|(hv, uv)| if n == 0 { c * uv } else { hv + c * uv })
                    .collect()
            });
            history.push(u);
        });
    }

    /// Closes the statistics of the run.
    pub fn finish(mut self) -> RunStats {
        self.stats.history_algorithm = self.history.as_ref().map(|h| h.algorithm().to_string());
        self.stats.history_bytes = self.history.as_ref().map_or(0, |h| h.bytes_held());
        self.stats.factorisations = self.counters.factorisations();
        self.stats.solves = self.counters.solves();
        self.stats.sparse_forward_sweeps = self.counters.sparse_forward_sweeps();
        self.stats
    }
}

/// Runs the whole time series, handing every step to `sink`. `stop` is polled once per step.
pub fn run(sim: &Simulation, sink: &mut dyn FrameSink, stop: Option<&AtomicBool>) -> Result<RunStats, SolveError> {
    let started = Instant::now();
    let mut stepper = Stepper::prepare(sim)?;
    let mut output_seconds = 0.0;
    let mut frames = 0;
    let mut last_written = None;
    for n in 0..=sim.time.steps {
        if stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return Err(SolveError::Interrupted { last_written });
        }
        let view = stepper.advance()?;
        sink.step_done(sim, &view);
        if sim.is_output_step(n) {
            timed(&mut output_seconds, || sink.write_frame(sim, &view))?;
            frames += 1;
            last_written = Some(n);
        }
    }
    let mut stats = stepper.finish();
    stats.phases.output += output_seconds;
    stats.frames_written = frames;
    stats.phases.total = started.elapsed().as_secs_f64();
    Ok(stats)
}
