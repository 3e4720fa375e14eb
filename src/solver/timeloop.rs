//! The time loop (docs/method.md §3–4, §7, §9), written once for both dimensions. Per step n:
//!
//! ```text
//!   F_n            ← loads(t_n)                      (once, if no load depends on t)
//!   rhs            ← F_n − Σ_j K_j h_n^j             (history, only with memory: one or two channels)
//!   rhs            ← lift(rhs, g(t_n))               (prescribed components: rhs_f −= K_fp g, rhs_p = g)
//!   d              ← C K⁻¹ rhs                       (condensation: start the step's solve)
//!   λ              ← contact.solve(d)                (only with contact)
//!   u_n            ← K⁻¹ (rhs − Cᵀ λ)                (condensation: complete the solve)
//!   history.push(u_n); reactions and the frame if it is an output step
//! ```
//!
//! with K = K_A + (k/2) b(0) K_B factored once (identity rows at prescribed components). The
//! solve goes through the [`crate::linalg::LinearSolver`] and [`crate::contact::Condensation`] seams; the default condensation
//! is the faer factor's split sweeps (docs/method.md §4.5): a step costs one solve, contact or
//! not. Step 0 has no history and uses K_A alone; when its solution is not trivially zero and
//! K ≠ K_A, K_A gets a factor of its own.

use super::backend::{any, Backend, Stiffness};
use super::error::SolveError;
use super::reactions::Reactions;
use super::setup::Simulation;
use super::stats::{timed, Reaction, RunStats};
use super::step::{lift, system_matrix, StepOperator};
use crate::contact::active_set::{ContactOutcome, ContactState};
use crate::fem::assembly::assemble_stiffness;
use crate::fem::{NodeBlockMatrix, SymmetricMatrix};
use crate::history::History;
use crate::linalg::{Analysis, Counters, Factor};
use crate::material::Isotropic;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// What the driver shows a sink after a step. The vectors are over the unknowns this process
/// holds: all of them (D per node) in a serial run, a [`Backend`]'s share
/// ([`Backend::unknowns`]) otherwise.
pub struct StepView<'a> {
    pub step: usize,
    pub time: f64,
    /// u_n.
    pub displacement: &'a [f64],
    /// m_n^j = h_n^j + (k/2) b_j(0) u_n of each memory channel j, one after the other (one vector
    /// of the step's length each); σ_n = Aε(u_n) + Σ_j T_j ε(m_n^j) (None without memory).
    pub memory_displacement: Option<&'a [f64]>,
    pub contact: Option<&'a ContactState>,
    pub outcome: Option<ContactOutcome>,
    /// The reaction of each of the simulation's reaction groups (output steps only).
    pub reactions: Option<&'a [f64]>,
    /// The total contact force on the body of each contact group, D components per group
    /// (output steps with contact only; docs/method.md §14.4).
    pub contact_forces: Option<&'a [f64]>,
}

/// Receives the steps of a run (the output layer implements this; tests collect in memory).
pub trait FrameSink<const D: usize> {
    /// Called after every step (for progress reporting).
    fn step_done(&mut self, _sim: &Simulation<D>, _view: &StepView) {}
    /// Called for every output step.
    fn write_frame(&mut self, sim: &Simulation<D>, view: &StepView) -> Result<(), SolveError>;
}

/// K_B as the time loop multiplies it: in node blocks (a third of the memory traffic) when
/// its pattern allows, else as assembled. Unmodified: the memory load includes the history of
/// prescribed displacements (docs/method.md §7).
enum MemoryStiffness<const D: usize> {
    NodeBlocks(NodeBlockMatrix<D>),
    Full(SymmetricMatrix),
}

impl<const D: usize> MemoryStiffness<D> {
    fn matvec(&self, x: &[f64], y: &mut [f64]) {
        match self {
            MemoryStiffness::NodeBlocks(m) => m.matvec(x, y),
            MemoryStiffness::Full(m) => m.matvec(x, y),
        }
    }
}

/// The state of a run between steps: the assembled matrices, the cached factor, the history
/// and the contact warm start. [`Stepper::prepare`] does the one-off work, [`Stepper::advance`]
/// one time step (docs/method.md §3–4).
pub struct Stepper<'s, const D: usize> {
    sim: &'s Simulation<D>,
    pub counters: Counters,
    pub stats: RunStats,
    /// K_A (serial; a backend holds its own).
    k_a: Option<SymmetricMatrix>,
    /// K_B for the memory load K_B h_n of every step (serial; a backend multiplies by its own).
    k_b: Vec<MemoryStiffness<D>>,
    /// The faer factor's symbolic analysis (None with a [`Backend`]).
    symbolic: Option<Analysis>,
    backend: Option<&'s dyn Backend<D>>,
    main: StepOperator,
    /// (k/2) b(0), the memory term's share of K.
    memory_diagonal: Vec<f64>,
    history: Option<History>,
    contact: Option<ContactState>,
    reactions: Option<Reactions>,
    reaction_values: Vec<f64>,
    contact_forces: Vec<f64>,
    time_dependent_loads: bool,
    /// No memory, constant loads and constant prescribed values: every step equals step 0.
    single_solve: bool,
    load: Vec<f64>,
    /// Prescribed values g(t_n) over all unknowns (only when some is non-zero).
    prescribed: Option<Vec<f64>>,
    /// Work vectors of a step.
    rhs: Vec<f64>,
    /// h_n^j of each channel, one after the other.
    memory_load: Vec<f64>,
    memory_rhs: Vec<f64>,
    displacement: Vec<f64>,
    memory_displacement: Option<Vec<f64>>,
    outcome: Option<ContactOutcome>,
    next: usize,
}

impl<'s, const D: usize> Stepper<'s, D> {
    /// Assembles K_A (and K_B with memory), factorises K = K_A + (k/2) b(0) K_B once, and
    /// condenses the contact normals.
    pub fn prepare(sim: &'s Simulation<D>) -> Result<Self, SolveError> {
        Self::prepare_with(sim, None)
    }

    /// [`Stepper::prepare`] with the step matrices solved by `backend` (None: the faer factor).
    pub fn prepare_with(sim: &'s Simulation<D>, backend: Option<&'s dyn Backend<D>>) -> Result<Self, SolveError> {
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
        // The vectors of a step: over all unknowns, or the share a backend holds here.
        let n_dof = backend.map_or(sim.dofs.n(), |b| b.unknowns().len());
        // (k/2) b_j(0) of each memory channel (docs/method.md §15.1)
        let memory_diagonal: Vec<f64> = sim.memory.as_ref().map_or(Vec::new(), |m| {
            (0..m.channels().len())
                .map(|j| 0.5 * k * m.kernel_value(j, 0.0))
                .collect()
        });
        if let Some(b) = backend {
            if memory_diagonal.len() > 1 {
                return Err(SolveError::Setup(
                    "this memory has two channels (tensors that are not proportional, docs/method.md §15.1), and the \
                     PETSc backend runs memory of one channel only: run it without --backend petsc, or give memory \
                     terms whose tensors are proportional (e.g. all \"identity\" or all \"elasticity\", or bulk and \
                     shear relaxing proportionally)"
                        .into(),
                ));
            }
            // The backend assembles and multiplies its own (distributed) matrices.
            let c = memory_diagonal.first().copied();
            let main = StepOperator::with_backend(sim, b, c, &counters, &mut stats)?;
            let reactions = (!sim.dirichlet.reaction_groups.is_empty()).then(|| Reactions::held(sim, b.unknowns()));
            return Ok(Self::with_parts(
                sim,
                counters,
                stats,
                (None, Vec::new(), None),
                backend,
                main,
                memory_diagonal,
                reactions,
                n_dof,
            ));
        }
        let (points, cells) = (&sim.mesh.points, &sim.mesh.cells);
        let a = sim.elasticity.tensor();
        let channels: Vec<Isotropic> = sim
            .memory
            .as_ref()
            .map_or(Vec::new(), |m| m.channels().iter().map(|c| c.tensor).collect());
        let (k_a, k_b) = timed(&mut stats.phases.assembly, || match channels[..] {
            [] => {
                let [a] = assemble_stiffness(cells, points, &sim.dofs, &[a]);
                (a, Vec::new())
            }
            [t] => {
                let [a, b] = assemble_stiffness(cells, points, &sim.dofs, &[a, t]);
                (a, vec![b])
            }
            [t, v] => {
                let [a, b, c] = assemble_stiffness(cells, points, &sim.dofs, &[a, t, v]);
                (a, vec![b, c])
            }
            _ => unreachable!("a memory term has one or two channels"),
        });
        stats.matrix_nonzeros = k_a.values.len();
        // The pattern the factors have: identity rows, fully prescribed nodes decoupled. In 3D the
        // contact normals' unknowns go last (docs/method.md §4.5): G and W then live in the
        // factor's trailing block (measured: box 96x48x12, m = 1248, condensation 12.4 s before).
        let last = sim.unknowns_ordered_last();
        // K = K_A + Σ_j (k/2) b_j(0) K_j (unmodified: before the identity rows)
        let k_step = timed(&mut stats.phases.assembly, || {
            let mut sum: Option<SymmetricMatrix> = None;
            for (kb, c) in k_b.iter().zip(&memory_diagonal) {
                sum = Some(sum.as_ref().unwrap_or(&k_a).plus_scaled(*c, kb));
            }
            sum
        });
        let system = system_matrix(sim, k_step.as_ref().unwrap_or(&k_a));
        drop(k_step);
        // K_B's prescribed columns and its node blocks are taken before the factorisation, and
        // the assembled K_B dropped: it is not held next to the factor (docs/method.md §9.3).
        let reactions = (!sim.dirichlet.reaction_groups.is_empty()).then(|| Reactions::new(sim, &k_a, &k_b));
        let k_b: Vec<MemoryStiffness<D>> = k_b
            .into_iter()
            .map(|kb| match NodeBlockMatrix::new(&kb) {
                Some(blocks) => MemoryStiffness::NodeBlocks(blocks),
                None => MemoryStiffness::Full(kb),
            })
            .collect();
        let symbolic = timed(&mut stats.phases.factorisation, || {
            Factor::analyse_with_last(&system.0, &last)
        })
        .map_err(|e| SolveError::Setup(e.to_string()))?;
        stats.ordering = Some(symbolic.ordering().to_string());
        stats.factor_entries = symbolic.factor_entries();
        let main = StepOperator::new(sim, &symbolic, system, &counters, &mut stats)?;
        Ok(Self::with_parts(
            sim,
            counters,
            stats,
            (Some(k_a), k_b, Some(symbolic)),
            None,
            main,
            memory_diagonal,
            reactions,
            n_dof,
        ))
    }

    /// The Stepper of prepared parts; `n_dof` the length of its vectors.
    #[allow(clippy::too_many_arguments)]
    fn with_parts(
        sim: &'s Simulation<D>,
        counters: Counters,
        mut stats: RunStats,
        (k_a, k_b, symbolic): (Option<SymmetricMatrix>, Vec<MemoryStiffness<D>>, Option<Analysis>),
        backend: Option<&'s dyn Backend<D>>,
        main: StepOperator,
        memory_diagonal: Vec<f64>,
        reactions: Option<Reactions>,
        n_dof: usize,
    ) -> Self {
        if let (Some(op), Some(c)) = (&main.condensed, &sim.contact) {
            if !c.laws.is_empty() {
                let weights = c.laws.monotonicity_weights(c.nodes.len());
                stats.smallness = Some(op.stiffness().trace_constant(&weights));
            }
        }
        let history = sim.memory.as_ref().map(|m| History::new(m, n_dof, sim.time.step()));
        let n_channels = memory_diagonal.len();
        let contact = sim.contact.as_ref().map(|c| ContactState::new(c.nodes.len()));
        let time_dependent_loads = sim.loads.is_time_dependent();
        Stepper {
            sim,
            counters,
            stats,
            k_a,
            k_b,
            symbolic,
            backend,
            main,
            memory_diagonal,
            single_solve: sim.is_static(),
            history,
            contact,
            reaction_values: Vec::new(),
            contact_forces: Vec::new(),
            reactions,
            time_dependent_loads,
            load: vec![0.0; n_dof],
            // g(t_n) over all unknowns on every process (the contact offsets index it so)
            prescribed: sim.dirichlet.is_nonzero().then(|| vec![0.0; sim.dofs.n()]),
            rhs: vec![0.0; n_dof],
            memory_load: vec![0.0; n_channels * n_dof],
            memory_rhs: vec![0.0; n_dof],
            displacement: vec![0.0; n_dof],
            memory_displacement: None,
            outcome: None,
            next: 0,
        }
    }

    /// The index of the step [`Stepper::advance`] will solve next.
    pub fn next_step(&self) -> usize {
        self.next
    }

    /// Solves the next step: loads, memory load, lifting, contact, recovery, history update.
    pub fn advance(&mut self) -> Result<StepView<'_>, SolveError> {
        let n = self.next;
        let sim = self.sim;
        let t = sim.time.time(n);
        if n == 0 || self.time_dependent_loads {
            let (load, backend) = (&mut self.load, self.backend);
            timed(&mut self.stats.phases.loads, || match backend {
                None => sim.loads.assemble(t, &sim.dofs, load),
                Some(b) => {
                    // assembled whole (every process holds the mesh), kept over its share
                    let mut full = vec![0.0; sim.dofs.n()];
                    let assembled = sim.loads.assemble(t, &sim.dofs, &mut full);
                    load.iter_mut().zip(b.unknowns()).for_each(|(l, &d)| *l = full[d]);
                    assembled
                }
            })
            .map_err(|detail| SolveError::NonFiniteLoad {
                step: n,
                time: t,
                detail,
            })?;
        }
        if let Some(g) = &mut self.prescribed {
            if n == 0 || sim.dirichlet.is_time_dependent() {
                sim.dirichlet.values(t, g).map_err(|detail| SolveError::NonFiniteLoad {
                    step: n,
                    time: t,
                    detail,
                })?;
            }
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
                self.step_zero(&mut rhs)?
            } else {
                lift(&self.main, sim, self.prescribed.as_deref(), &mut rhs, self.backend);
                self.main.solve(
                    sim,
                    n,
                    &rhs,
                    self.prescribed.as_deref(),
                    &mut self.displacement,
                    self.contact.as_mut(),
                    self.backend,
                    &self.counters,
                    &mut self.stats,
                )?
            };
            self.rhs = rhs;
            if any(self.backend, self.displacement.iter().any(|v| !v.is_finite())) {
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
        let output = sim.is_output_step(n);
        if let (Some(r), true) = (&mut self.reactions, output) {
            let memory = if n == 0 {
                None
            } else {
                self.memory_displacement.as_deref()
            };
            let values = match self.backend {
                None => r.compute(sim, &self.displacement, memory, &self.load, self.contact.as_ref()),
                Some(b) => r.compute_held(sim, b, &self.displacement, memory, &self.load, self.contact.as_ref()),
            };
            self.reaction_values.clear();
            self.reaction_values.extend_from_slice(values);
            for (g, &force) in sim.dirichlet.reaction_groups.iter().zip(values) {
                self.stats.reactions.push(Reaction {
                    time: t,
                    group: g.group.clone(),
                    component: ["x", "y", "z"][g.component],
                    force,
                });
            }
        }
        let with_forces = output && self.contact.is_some();
        if let (Some(setup), Some(state), true) = (&sim.contact, &self.contact, with_forces) {
            let moved = setup.gaps_at(t).map_err(|detail| SolveError::NonFiniteLoad {
                step: n,
                time: t,
                detail,
            })?;
            let forces = setup.group_forces(state, moved.as_ref().map(|(o, _)| &o[..]));
            self.contact_forces.clear();
            for (group, f) in setup.groups.iter().zip(&forces) {
                self.contact_forces.extend_from_slice(f);
                for (c, &force) in f.iter().enumerate() {
                    self.stats.contact_forces.push(Reaction {
                        time: t,
                        group: group.clone(),
                        component: ["x", "y", "z"][c],
                        force,
                    });
                }
            }
        }
        self.next += 1;
        Ok(StepView {
            step: n,
            time: t,
            displacement: &self.displacement,
            memory_displacement: self.memory_displacement.as_deref(),
            contact: self.contact.as_ref(),
            outcome: self.outcome,
            reactions: (self.reactions.is_some() && output).then_some(&self.reaction_values[..]),
            contact_forces: with_forces.then_some(&self.contact_forces[..]),
        })
    }

    /// Step 0 with a memory kernel: K_A u_0 + Cᵀλ = F_0 (no history term). When u_0 = 0 solves
    /// it exactly (no load, no prescribed value, and the contact law exerts no force at 0)
    /// nothing is factorised.
    fn step_zero(&mut self, rhs: &mut [f64]) -> Result<Option<ContactOutcome>, SolveError> {
        let sim = self.sim;
        let prescribed_zero = self.prescribed.as_ref().is_none_or(|g| g.iter().all(|v| *v == 0.0));
        let rhs_zero = !any(self.backend, rhs.iter().any(|v| *v != 0.0));
        if zero_solves_step_zero(sim, rhs_zero, prescribed_zero) {
            let outcome = self.contact.as_mut().map(|s| {
                let m = s.force.len();
                *s = ContactState::new(m);
                ContactOutcome::default()
            });
            self.displacement.fill(0.0);
            return Ok(outcome);
        }
        let mut op = match (&self.symbolic, &self.k_a, self.backend) {
            (Some(symbolic), Some(k_a), _) => {
                StepOperator::new(sim, symbolic, system_matrix(sim, k_a), &self.counters, &mut self.stats)?
            }
            (_, _, Some(b)) => StepOperator::with_backend(sim, b, None, &self.counters, &mut self.stats)?,
            _ => unreachable!("a Stepper has a symbolic analysis and K_A, or a backend"),
        };
        lift(&op, sim, self.prescribed.as_deref(), rhs, self.backend);
        op.solve(
            sim,
            0,
            rhs,
            self.prescribed.as_deref(),
            &mut self.displacement,
            self.contact.as_mut(),
            self.backend,
            &self.counters,
            &mut self.stats,
        )
    }

    /// rhs ← rhs − Σ_j K_j h_n^j (docs/method.md §3, §15); h_0 = 0.
    fn subtract_memory_load(&mut self, n: usize, rhs: &mut [f64]) {
        let Some(history) = &self.history else {
            return;
        };
        let (sim, k_b, backend) = (self.sim, &self.k_b, self.backend);
        let (loads, kb_h) = (&mut self.memory_load, &mut self.memory_rhs);
        timed(&mut self.stats.phases.history, || {
            for (j, h) in loads.chunks_exact_mut(rhs.len()).enumerate() {
                history.memory_load(j, h);
                if n > 0 {
                    match (k_b.get(j), backend) {
                        (Some(k_b), _) => k_b.matvec(h, kb_h),
                        // one channel only with a backend (prepare_with)
                        (None, Some(b)) => b.product(sim, Stiffness::Memory, h, kb_h),
                        (None, None) => return,
                    }
                    rhs.iter_mut().zip(kb_h.iter()).for_each(|(r, v)| *r -= v);
                }
            }
        });
    }

    /// Records u_n in the history and keeps m_n^j = h_n^j + (k/2) b_j(0) u_n of every channel for
    /// the stresses (m_0 = 0: the trapezoidal sum is empty at n = 0, docs/method.md §3).
    fn update_history(&mut self, n: usize) {
        let Some(history) = &mut self.history else {
            return;
        };
        let (loads, u) = (&self.memory_load, &self.displacement);
        let diagonal = &self.memory_diagonal;
        let memory_displacement = &mut self.memory_displacement;
        let wanted = self.sim.is_output_step(n);
        timed(&mut self.stats.phases.history, || {
            // only output steps show the memory stress
            *memory_displacement = wanted.then(|| {
                loads
                    .chunks_exact(u.len())
                    .zip(diagonal)
                    .flat_map(|(h, &c)| {
                        h.iter()
                            .zip(u)
                            .map(move |(hv, uv)| if n == 0 { 0.0 } else { hv + c * uv })
                    })
                    .collect()
            });
            history.push(u);
        });
    }

    /// Closes the statistics of the run.
    pub fn finish(mut self) -> RunStats {
        self.stats.history_algorithm = self.history.as_ref().map(|h| h.algorithm());
        self.stats.history_bytes = self.history.as_ref().map_or(0, |h| h.bytes_held());
        self.stats.factorisations = self.counters.factorisations();
        self.stats.solves = self.counters.solves();
        self.stats.sparse_forward_sweeps = self.counters.sparse_forward_sweeps();
        self.stats
    }
}

/// True if u_0 = 0 solves step 0 exactly, so that K_A gets no factor of its own: no load
/// (`rhs_zero`), no prescribed value (`prescribed_zero`), no fixed obstacle motion or negative
/// bound, and a contact law that exerts no force at its origin.
pub fn zero_solves_step_zero<const D: usize>(sim: &Simulation<D>, rhs_zero: bool, prescribed_zero: bool) -> bool {
    let law_at_zero = sim.contact.as_ref().map_or(0.0, |c| {
        (0..c.nodes.len())
            .map(|p| c.laws.force(p, -c.gap.as_ref().map_or(0.0, |o| o[p])).abs())
            .fold(0.0, f64::max)
    });
    let bound_ok = sim
        .contact
        .as_ref()
        .is_none_or(|c| c.motion.is_none() && c.bound.as_ref().is_none_or(|g| g.iter().all(|v| *v >= 0.0)));
    rhs_zero && law_at_zero == 0.0 && bound_ok && prescribed_zero
}

/// Runs the whole time series, handing every step to `sink`. `stop` is polled once per step.
pub fn run<const D: usize>(
    sim: &Simulation<D>,
    sink: &mut dyn FrameSink<D>,
    stop: Option<&AtomicBool>,
) -> Result<RunStats, SolveError> {
    run_with(sim, sink, stop, None)
}

/// [`run`] with the step matrices solved by `backend` (None: the faer factor).
pub fn run_with<const D: usize>(
    sim: &Simulation<D>,
    sink: &mut dyn FrameSink<D>,
    stop: Option<&AtomicBool>,
    backend: Option<&dyn Backend<D>>,
) -> Result<RunStats, SolveError> {
    let started = Instant::now();
    let mut stepper = Stepper::prepare_with(sim, backend)?;
    let mut output_seconds = 0.0;
    let mut frames = 0;
    let mut last_written = None;
    for n in 0..=sim.time.steps {
        // (with a backend, a stop on any process stops every process at the same step)
        if stop.is_some() && any(backend, stop.is_some_and(|s| s.load(Ordering::Relaxed))) {
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
