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
//! with K = K_A + Σ_j (k/2) b_j(0) K_j factored once (identity rows at prescribed components).
//! Every piece of linear algebra comes from a [`Backend`]: the cached faer factor
//! ([`FaerBackend`], the default) or PETSc over MPI; the loop has one path for both. The default
//! condensation is the faer factor's split sweeps (docs/method.md §4.5): a step costs one solve,
//! contact or not. Step 0 has no history and uses K_A alone; when its solution is not trivially
//! zero and K ≠ K_A, K_A gets an operator of its own.

use super::backend::{Backend, Stiffness};
use super::error::SolveError;
use super::faer::FaerBackend;
use super::operator::StepOperator;
use super::reactions::{Reactions, StepState};
use super::setup::Simulation;
use super::stats::{timed, Reaction, RunStats};
use super::step::{lift, StepSolve};
use crate::contact::{ContactOutcome, ContactState, SolverCache};
use crate::history::History;
use crate::linalg::Counters;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// What the driver shows a sink after a step. The vectors are over the unknowns this process
/// holds: all of them (D per node) in a serial run, a [`Backend`]'s share
/// ([`Backend::held_unknowns`]) otherwise.
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
    /// The displacement of each rigid parameter ([`Simulation::dirichlet`]'s `rigid`: the
    /// force-controlled groups, then the pins; docs/method.md §7.7).
    pub motion: &'a [f64],
}

/// Receives the steps of a run (the output layer implements this; tests collect in memory).
pub trait FrameSink<const D: usize> {
    /// Called after every step (for progress reporting).
    fn step_done(&mut self, _sim: &Simulation<D>, _view: &StepView) {}
    /// Called for every output step.
    fn write_frame(&mut self, sim: &Simulation<D>, view: &StepView) -> Result<(), SolveError>;
}

/// The state of a run between steps: the assembled matrices, the cached factor, the history
/// and the contact warm start. [`Stepper::prepare`] does the one-off work, [`Stepper::advance`]
/// one time step (docs/method.md §3–4).
pub struct Stepper<'s, const D: usize> {
    sim: &'s Simulation<D>,
    pub counters: Counters,
    pub stats: RunStats,
    /// The linear algebra: operators, products by K_A and K_j, collective decisions.
    backend: Box<dyn Backend<D> + 's>,
    /// The operator of the step matrix K.
    main: StepOperator,
    /// (k/2) b(0), the memory term's share of K.
    memory_diagonal: Vec<f64>,
    history: Option<History>,
    contact: Option<ContactState>,
    /// The contact solver's caches, beside its state (docs/method.md §9.2).
    contact_cache: SolverCache,
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
    /// a: the motion of each rigid parameter in the last step (docs/method.md §7.7).
    motion: Vec<f64>,
    memory_displacement: Option<Vec<f64>>,
    outcome: Option<ContactOutcome>,
    next: usize,
}

impl<'s, const D: usize> Stepper<'s, D> {
    /// Assembles K_A (and the K_j with memory), factorises K = K_A + Σ_j (k/2) b_j(0) K_j once
    /// with the faer backend, and condenses the contact normals.
    pub fn prepare(sim: &'s Simulation<D>) -> Result<Self, SolveError> {
        Self::prepare_with(sim, Box::new(FaerBackend::default()))
    }

    /// [`Stepper::prepare`] with the step matrices solved by `backend`.
    pub fn prepare_with(sim: &'s Simulation<D>, mut backend: Box<dyn Backend<D> + 's>) -> Result<Self, SolveError> {
        crate::linalg::set_parallelism(sim.threads);
        let counters = Counters::default();
        let mut stats = RunStats {
            nodes: sim.mesh.points.len(),
            cells: sim.mesh.cells.len(),
            unknowns: sim.dofs.n_free(),
            contact_nodes: sim.contact.as_ref().map_or(0, |c| c.nodes.len()),
            contact_bound: sim.contact.as_ref().is_some_and(|c| c.bound.is_some()),
            steps: sim.time.steps,
            time_step: sim.time.step(),
            final_time: sim.time.final_time,
            effects: super::plan::Plan::new(sim).effect_names(),
            ..Default::default()
        };
        let k = sim.time.step();
        // (k/2) b_j(0) of each memory channel (docs/method.md §15.1)
        let memory_diagonal: Vec<f64> = sim.materials.memory().map_or(Vec::new(), |m| {
            (0..m.channels().len())
                .map(|j| 0.5 * k * m.kernel_value(j, 0.0))
                .collect()
        });
        let main = backend.operator(sim, &memory_diagonal, &counters, &mut stats)?;
        let reactions = (!sim.dirichlet.reaction_groups.is_empty()).then(|| backend.reactions(sim));
        // The vectors of a step: over all unknowns, or the share a backend holds here.
        let n_dof = backend.held_len(sim);
        if let (Some(op), Some(c)) = (&main.condensed, &sim.contact) {
            if !c.laws.is_empty() {
                // (the tangential rows of friction, after the normal ones, have no normal law)
                let mut weights = c.laws.monotonicity_weights(c.nodes.len());
                weights.resize(c.condensed_rows().len(), 0.0);
                stats.smallness = Some(op.trace_constant(&weights));
            }
        }
        let history = sim.materials.memory().map(|m| History::new(m, n_dof, sim.time.step()));
        let n_channels = memory_diagonal.len();
        let contact = sim
            .contact
            .as_ref()
            .map(|c| ContactState::new(c.condensed_rows().len()));
        let time_dependent_loads = sim.loads.is_time_dependent();
        Ok(Stepper {
            sim,
            counters,
            stats,
            backend,
            main,
            memory_diagonal,
            single_solve: sim.is_static(),
            history,
            contact,
            contact_cache: SolverCache::default(),
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
            motion: vec![0.0; sim.dirichlet.rigid.len()],
            memory_displacement: None,
            outcome: None,
            next: 0,
        })
    }

    /// The index of the step [`Stepper::advance`] will solve next.
    pub fn next_step(&self) -> usize {
        self.next
    }

    /// Solves the next step (docs/method.md §3–4): the loads and prescribed values at t_n, the
    /// step's solve (history load, lifting, free solve, contact, recovery), the history update,
    /// and on an output step the reactions and contact forces.
    pub fn advance(&mut self) -> Result<StepView<'_>, SolveError> {
        let n = self.next;
        let t = self.sim.time.time(n);
        self.update_data(n, t)?;
        if self.single_solve && n > 0 {
            // Nothing changes: the state of step 0 stands for every step.
            if let Some(o) = self.outcome {
                self.stats.newton_iterations.push(0);
                self.stats.contact.push(ContactOutcome { iterations: 0, ..o });
            }
        } else {
            self.solve_step(n, t)?;
        }
        self.update_history(n);
        let output = self.sim.is_output_step(n);
        if output {
            self.record_reactions(n, t)?;
            self.record_contact_forces(n, t)?;
        }
        self.next += 1;
        let with_forces = output && self.contact.is_some();
        Ok(StepView {
            step: n,
            time: t,
            displacement: &self.displacement,
            memory_displacement: self.memory_displacement.as_deref(),
            contact: self.contact.as_ref(),
            outcome: self.outcome,
            reactions: (self.reactions.is_some() && output).then_some(&self.reaction_values[..]),
            contact_forces: with_forces.then_some(&self.contact_forces[..]),
            motion: &self.motion,
        })
    }

    /// F_n (once when no load depends on t) and g(t_n) (once when no prescribed value does).
    fn update_data(&mut self, n: usize, t: f64) -> Result<(), SolveError> {
        let sim = self.sim;
        if n == 0 || self.time_dependent_loads {
            let (load, held) = (&mut self.load, self.backend.held_unknowns());
            timed(&mut self.stats.phases.loads, || match held {
                None => sim.loads.assemble(t, &sim.dofs, load),
                Some(held) => {
                    // assembled whole (every process holds the mesh), kept over its share
                    let mut full = vec![0.0; sim.dofs.n()];
                    let assembled = sim.loads.assemble(t, &sim.dofs, &mut full);
                    load.iter_mut().zip(held).for_each(|(l, &d)| *l = full[d]);
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
        Ok(())
    }

    /// rhs = F_n − Σ_j K_j h_n^j, lifted; d = C K⁻¹ rhs; λ from the contact law; u_n recovered.
    fn solve_step(&mut self, n: usize, t: f64) -> Result<(), SolveError> {
        let sim = self.sim;
        let mut rhs = std::mem::take(&mut self.rhs);
        rhs.copy_from_slice(&self.load);
        self.subtract_memory_load(n, &mut rhs);
        // f̃ at the rigid parameters' unknowns, before the lifting replaces it (docs/method.md §7.7)
        let rigid_loads: Vec<f64> = sim
            .dirichlet
            .rigid
            .iter()
            .map(|p| p.unknowns.iter().map(|&d| rhs[d]).sum())
            .collect();
        let outcome = if n == 0 && self.history.is_some() {
            self.step_zero(&mut rhs, &rigid_loads)?
        } else {
            lift(&self.main, sim, self.prescribed.as_deref(), &mut rhs, &*self.backend);
            let step = StepSolve {
                step: n,
                rhs: &rhs,
                offset: self.prescribed.as_deref(),
                rigid_loads: &rigid_loads,
                motion: &mut self.motion,
                u: &mut self.displacement,
                state: self.contact.as_mut().map(|s| (s, &mut self.contact_cache)),
            };
            super::step::solve(
                &mut self.main,
                sim,
                &*self.backend,
                step,
                &self.counters,
                &mut self.stats,
            )?
        };
        self.rhs = rhs;
        if self.backend.any(self.displacement.iter().any(|v| !v.is_finite())) {
            return Err(SolveError::NonFinite {
                step: n,
                time: t,
                what: "displacement".into(),
            });
        }
        self.outcome = outcome;
        if let Some(o) = outcome {
            self.stats.newton_iterations.push(o.iterations);
            self.stats.max_contact_residual = self.stats.max_contact_residual.max(o.residual);
            self.stats.contact.push(o);
        }
        Ok(())
    }

    /// The reactions of the scene's groups at an output step (docs/method.md §7).
    fn record_reactions(&mut self, n: usize, t: f64) -> Result<(), SolveError> {
        let sim = self.sim;
        let Some(r) = &mut self.reactions else {
            return Ok(());
        };
        let memory = if n == 0 {
            None
        } else {
            self.memory_displacement.as_deref()
        };
        let state = StepState {
            u: &self.displacement,
            memory,
            load: &self.load,
            contact: self.contact.as_ref(),
        };
        let values = super::step::reactions(r, sim, &*self.backend, state);
        if let Some(g) = values.iter().position(|v| !v.is_finite()) {
            let g = &sim.dirichlet.reaction_groups[g];
            return Err(SolveError::NonFinite {
                step: n,
                time: t,
                what: format!("reaction on group {} ({})", g.group, ["x", "y", "z"][g.component]),
            });
        }
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
        Ok(())
    }

    /// The total contact force of each contact group at an output step (docs/method.md §14.4).
    fn record_contact_forces(&mut self, n: usize, t: f64) -> Result<(), SolveError> {
        let (Some(setup), Some(state)) = (&self.sim.contact, &self.contact) else {
            return Ok(());
        };
        let moved = setup.gaps_at(t).map_err(|detail| SolveError::NonFiniteLoad {
            step: n,
            time: t,
            detail,
        })?;
        let forces = setup.group_forces(state, moved.as_ref().map(|(o, _)| &o[..]));
        if let Some(g) = forces.iter().position(|f| f.iter().any(|v| !v.is_finite())) {
            return Err(SolveError::NonFinite {
                step: n,
                time: t,
                what: format!("contact force on group {}", setup.force_names()[g]),
            });
        }
        self.contact_forces.clear();
        for (group, f) in setup.force_names().iter().zip(&forces) {
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
        Ok(())
    }

    /// Step 0 with a memory kernel: K_A u_0 + Cᵀλ = F_0 (no history term). When u_0 = 0 solves
    /// it exactly (no load, no prescribed value, and the contact law exerts no force at 0)
    /// nothing is factorised.
    fn step_zero(&mut self, rhs: &mut [f64], rigid_loads: &[f64]) -> Result<Option<ContactOutcome>, SolveError> {
        let sim = self.sim;
        let prescribed_zero = self.prescribed.as_ref().is_none_or(|g| g.iter().all(|v| *v == 0.0));
        let rhs_zero = !self.backend.any(rhs.iter().any(|v| *v != 0.0));
        if zero_solves_step_zero(sim, rhs_zero, prescribed_zero) {
            let outcome = self.contact.as_mut().map(|s| {
                let m = s.force.len();
                *s = ContactState::new(m);
                ContactOutcome::default()
            });
            self.contact_cache = SolverCache::default();
            self.displacement.fill(0.0);
            return Ok(outcome);
        }
        // K_A alone: an operator of its own
        let mut op = self.backend.operator(sim, &[], &self.counters, &mut self.stats)?;
        lift(&op, sim, self.prescribed.as_deref(), rhs, &*self.backend);
        let step = StepSolve {
            step: 0,
            rhs,
            offset: self.prescribed.as_deref(),
            rigid_loads,
            motion: &mut self.motion,
            u: &mut self.displacement,
            state: self.contact.as_mut().map(|s| (s, &mut self.contact_cache)),
        };
        super::step::solve(&mut op, sim, &*self.backend, step, &self.counters, &mut self.stats)
    }

    /// rhs ← rhs − Σ_j K_j h_n^j (docs/method.md §3, §15); h_0 = 0.
    fn subtract_memory_load(&mut self, n: usize, rhs: &mut [f64]) {
        let Some(history) = &self.history else {
            return;
        };
        let (sim, backend) = (self.sim, &self.backend);
        let (loads, kb_h) = (&mut self.memory_load, &mut self.memory_rhs);
        timed(&mut self.stats.phases.history, || {
            for (j, h) in loads.chunks_exact_mut(rhs.len()).enumerate() {
                history.memory_load(j, h);
                if n > 0 {
                    backend.product(sim, Stiffness::Memory(j), h, kb_h);
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
/// (`rhs_zero`), no prescribed value (`prescribed_zero`), no force on a force-controlled group,
/// no fixed obstacle motion or negative bound, and a contact law that exerts no force at its
/// origin.
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
    // a force-controlled group pushed at t = 0 moves the body
    let no_force = sim.dirichlet.rigid.iter().all(|p| p.force_at(0.0) == 0.0);
    rhs_zero && law_at_zero == 0.0 && bound_ok && prescribed_zero && no_force
}

/// Runs the whole time series on the faer backend, handing every step to `sink`. `stop` is
/// polled once per step.
pub fn run<const D: usize>(
    sim: &Simulation<D>,
    sink: &mut dyn FrameSink<D>,
    stop: Option<&AtomicBool>,
) -> Result<RunStats, SolveError> {
    run_with(sim, sink, stop, Box::new(FaerBackend::default()))
}

/// [`run`] with the step matrices solved by `backend` (docs/method.md §3–4): prepare once, then
/// per step advance (history, free solve, contact, recovery) and hand the step to the sink.
pub fn run_with<'s, const D: usize>(
    sim: &'s Simulation<D>,
    sink: &mut dyn FrameSink<D>,
    stop: Option<&AtomicBool>,
    backend: Box<dyn Backend<D> + 's>,
) -> Result<RunStats, SolveError> {
    let started = Instant::now();
    sim.check_data()?;
    let mut stepper = Stepper::prepare_with(sim, backend)?;
    let mut output_seconds = 0.0;
    let mut frames = 0;
    let mut last_written = None;
    for n in 0..=sim.time.steps {
        // (a stop on any process stops every process at the same step)
        if stop.is_some() && stepper.backend.any(stop.is_some_and(|s| s.load(Ordering::Relaxed))) {
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
