//! One step of the time loop (docs/method.md §3–4, §7, §9, §20), written once for both dimensions.
//! Per step n of size k_n:
//!
//! ```text
//!   F_n            ← loads(t_n)                      (once, if no load depends on t)
//!   h_n, β_n       ← history.begin(t_n, k_n)          (only with memory: one or two channels)
//!   K              ← operators(β_n)                   (factorised once per distinct β, §20.3)
//!   rhs            ← F_n − Σ_j K_j h_n^j
//!   rhs            ← lift(rhs, g(t_n))               (prescribed components: rhs_f −= K_fp g, rhs_p = g)
//!   d              ← C K⁻¹ rhs                       (condensation: start the step's solve)
//!   λ              ← contact.solve(d)                (only with contact)
//!   u_n            ← K⁻¹ (rhs − Cᵀ λ)                (condensation: complete the solve)
//!   history.push(u_n); reactions and the frame if it is an output step
//! ```
//!
//! with K = K_A + Σ_j β_j K_j (identity rows at prescribed components). Every piece of linear
//! algebra comes from a [`Backend`]: the cached faer factor ([`FaerBackend`], the default) or
//! PETSc over MPI; the loop has one path for both. Step 0 has no history (β = 0: K_A alone); when
//! its solution is not trivially zero it is solved with K_A's operator. The drivers that take the
//! steps are src/solver/timeloop.rs (a fixed grid) and src/solver/automatic.rs.

use super::backend::{Backend, Stiffness};
use super::error::SolveError;
use super::faer::FaerBackend;
use super::operators::Operators;
use super::reactions::{Reactions, StepState};
use super::setup::Simulation;
use super::stats::{timed, Reaction, RunStats};
use super::step::{lift, StepSolve};
use crate::contact::{ContactOutcome, ContactState, SolverCache};
use crate::history::History;
use crate::linalg::Counters;
use crate::time::Schedule;
use std::sync::atomic::{AtomicBool, Ordering};

/// One step to take: its index n, its time t_n and size k_n (0 for step 0), and whether it is
/// written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    pub index: usize,
    pub time: f64,
    pub size: f64,
    pub output: bool,
}

/// What the driver shows a sink after a step. The vectors are over the unknowns this process
/// holds: all of them (D per node) in a serial run, a [`Backend`]'s share
/// ([`Backend::held_unknowns`]) otherwise.
pub struct StepView<'a> {
    pub step: usize,
    pub time: f64,
    /// Whether the step is written (an output step).
    pub output: bool,
    /// u_n.
    pub displacement: &'a [f64],
    /// m_n^j = h_n^j + β_j u_n of each memory channel j, one after the other (one vector of the
    /// step's length each); σ_n = Aε(u_n) + Σ_j T_j ε(m_n^j) (None without memory).
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

/// The state of a run between steps: the operators of its step matrices, the history and the
/// contact warm start. [`Stepper::prepare`] does the one-off work, [`Stepper::advance`] one time
/// step (docs/method.md §3–4).
pub struct Stepper<'s, const D: usize> {
    pub(super) sim: &'s Simulation<D>,
    pub counters: Counters,
    pub stats: RunStats,
    /// The linear algebra: operators, products by K_A and K_j, collective decisions.
    pub(super) backend: Box<dyn Backend<D> + 's>,
    /// The operators of the step matrices (docs/method.md §20.3).
    pub(super) operators: Operators,
    /// β_j of the step being solved: the memory's share of K.
    pub(super) beta: Vec<f64>,
    pub(super) history: Option<History>,
    pub(super) contact: Option<ContactState>,
    /// The contact solver's caches, beside its state (docs/method.md §9.2).
    pub(super) contact_cache: SolverCache,
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
    pub(super) memory_load: Vec<f64>,
    memory_rhs: Vec<f64>,
    pub(super) displacement: Vec<f64>,
    /// a: the motion of each rigid parameter in the last step (docs/method.md §7.7).
    pub(super) motion: Vec<f64>,
    pub(super) memory_displacement: Option<Vec<f64>>,
    pub(super) outcome: Option<ContactOutcome>,
    /// The sizes of the steps taken, by their bits (for the summary).
    sizes: Vec<u64>,
    /// The index of the next step.
    next: usize,
}

impl<'s, const D: usize> Stepper<'s, D> {
    /// Assembles K_A (and the K_j with memory), factorises the first step's matrix
    /// K = K_A + Σ_j β_j K_j with the faer backend, and condenses the contact normals.
    pub fn prepare(sim: &'s Simulation<D>) -> Result<Self, SolveError> {
        Self::prepare_with(sim, Box::new(FaerBackend::default()))
    }

    /// [`Stepper::prepare`] with the step matrices solved by `backend`.
    pub fn prepare_with(sim: &'s Simulation<D>, mut backend: Box<dyn Backend<D> + 's>) -> Result<Self, SolveError> {
        crate::linalg::set_parallelism(sim.threads);
        let counters = Counters::default();
        let first = first_step(sim);
        let mut stats = RunStats {
            nodes: sim.mesh.points.len(),
            cells: sim.mesh.cells.len(),
            unknowns: sim.dofs.n_free(),
            contact_nodes: sim.contact.as_ref().map_or(0, |c| c.nodes.len()),
            contact_bound: sim.contact.as_ref().is_some_and(|c| c.bound.is_some()),
            steps: sim.time.steps().unwrap_or(0),
            time_step: first,
            final_time: sim.time.final_time(),
            effects: super::plan::Plan::new(sim).effect_names(),
            ..Default::default()
        };
        let coefficients = |k: f64| -> Vec<f64> {
            sim.materials
                .memory()
                .map_or(Vec::new(), |m| m.step_coefficients(k, sim.rules))
        };
        // the β of a fixed grid's runs of one step size (step 0's K_A first), for keeping the
        // operators used again
        let future = sim.time.grid().map(|g| {
            std::iter::once((0, coefficients(0.0)))
                .chain(g.size_runs().into_iter().map(|(n, k)| (n, coefficients(k))))
                .collect::<Vec<_>>()
        });
        let mut operators = Operators::new(sim, future);
        let beta = coefficients(first);
        // the first step's operator now: its factor, its condensation and the smallness number
        let main = operators.get(&beta, 1, &mut *backend, sim, &counters, &mut stats)?;
        if let (Some(op), Some(c)) = (&main.condensed, &sim.contact) {
            if !c.laws.is_empty() {
                // (the tangential rows of friction, after the normal ones, have no normal law)
                let mut weights = c.laws.monotonicity_weights(c.nodes.len());
                weights.resize(c.condensed_rows().len(), 0.0);
                stats.smallness = Some(op.trace_constant(&weights));
            }
        }
        let reactions = (!sim.dirichlet.reaction_groups.is_empty()).then(|| backend.reactions(sim));
        // The vectors of a step: over all unknowns, or the share a backend holds here.
        let n_dof = backend.held_len(sim);
        let history = sim.materials.memory().map(|m| History::new(m, n_dof, sim.rules));
        let n_channels = beta.len();
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
            operators,
            beta,
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
            sizes: Vec::new(),
            next: 0,
        })
    }

    /// The next level of a fixed grid (None past its end, or with automatic steps).
    pub fn next_step(&self) -> Option<Step> {
        let grid = self.sim.time.grid()?;
        (self.next <= grid.steps()).then(|| Step {
            index: self.next,
            time: grid.time(self.next),
            size: grid.step_size(self.next),
            output: self.sim.is_output_step(self.next),
        })
    }

    /// Solves the next level of a fixed grid ([`Self::advance`]); an error past its end or with
    /// automatic steps.
    pub fn advance_next(&mut self) -> Result<StepView<'_>, SolveError> {
        let step = self
            .next_step()
            .ok_or_else(|| SolveError::Setup("no level of a fixed grid left to solve".into()))?;
        self.advance(step)
    }

    /// Solves `step` (docs/method.md §3–4): the loads and prescribed values at t_n, the step's
    /// solve (history load, lifting, free solve, contact, recovery), the history update, and on
    /// an output step the reactions and contact forces.
    pub fn advance(&mut self, step: Step) -> Result<StepView<'_>, SolveError> {
        self.solve(step)?;
        self.commit(step)
    }

    /// The step's solve, leaving the history at the step begun (so that automatic steps can
    /// estimate its error and take it back).
    pub(super) fn solve(&mut self, step: Step) -> Result<(), SolveError> {
        let (n, t) = (step.index, step.time);
        self.update_data(n, t)?;
        if let Some(h) = &mut self.history {
            h.begin(t, step.size);
        }
        if let Some(m) = self.sim.materials.memory() {
            self.beta = m.step_coefficients(step.size, self.sim.rules);
        }
        if self.single_solve && n > 0 {
            // Nothing changes: the state of step 0 stands for every step.
            if let Some(o) = self.outcome {
                self.stats.newton_iterations.push(0);
                self.stats.contact.push(ContactOutcome { iterations: 0, ..o });
            }
            Ok(())
        } else {
            self.solve_step(step)
        }
    }

    /// Records the step solved in the history and, on an output step, its reactions and contact
    /// forces.
    pub(super) fn commit(&mut self, step: Step) -> Result<StepView<'_>, SolveError> {
        let (n, t) = (step.index, step.time);
        self.next = n + 1;
        self.update_history(n, step.output);
        if step.size > 0.0 {
            let bits = step.size.to_bits();
            if !self.sizes.contains(&bits) {
                self.sizes.push(bits);
            }
            let s = &mut self.stats;
            s.smallest_step = if s.largest_step == 0.0 {
                step.size
            } else {
                s.smallest_step.min(step.size)
            };
            s.largest_step = s.largest_step.max(step.size);
        }
        if step.output {
            self.record_reactions(n, t)?;
            self.record_contact_forces(n, t)?;
        }
        let with_forces = step.output && self.contact.is_some();
        Ok(StepView {
            step: n,
            time: t,
            output: step.output,
            displacement: &self.displacement,
            memory_displacement: self.memory_displacement.as_deref(),
            contact: self.contact.as_ref(),
            outcome: self.outcome,
            reactions: (self.reactions.is_some() && step.output).then_some(&self.reaction_values[..]),
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
                step: Some(n),
                time: t,
                detail,
            })?;
        }
        if let Some(g) = &mut self.prescribed {
            if n == 0 || sim.dirichlet.is_time_dependent() {
                sim.dirichlet.values(t, g).map_err(|detail| SolveError::NonFiniteLoad {
                    step: Some(n),
                    time: t,
                    detail,
                })?;
            }
        }
        Ok(())
    }

    /// rhs = F_n − Σ_j K_j h_n^j, lifted; d = C K⁻¹ rhs; λ from the contact law; u_n recovered.
    fn solve_step(&mut self, step: Step) -> Result<(), SolveError> {
        let (n, t) = (step.index, step.time);
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
        let outcome = if n == 0 && self.history.is_some() && self.zero_solves_step_zero(&rhs) {
            // u_0 = 0 solves step 0 exactly: nothing to factorise (docs/method.md §3)
            let outcome = self.contact.as_mut().map(|s| {
                *s = ContactState::new(s.force.len());
                ContactOutcome::default()
            });
            self.contact_cache = SolverCache::default();
            self.displacement.fill(0.0);
            outcome
        } else {
            let operator =
                self.operators
                    .get(&self.beta, n, &mut *self.backend, sim, &self.counters, &mut self.stats)?;
            lift(operator, sim, self.prescribed.as_deref(), &mut rhs, &*self.backend);
            let solve = StepSolve {
                step: n,
                time: t,
                rhs: &rhs,
                offset: self.prescribed.as_deref(),
                rigid_loads: &rigid_loads,
                motion: &mut self.motion,
                u: &mut self.displacement,
                state: self.contact.as_mut().map(|s| (s, &mut self.contact_cache)),
            };
            super::step::solve(operator, sim, &*self.backend, solve, &self.counters, &mut self.stats)?
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

    /// True if u_0 = 0 solves step 0 (its lifted right-hand side `rhs` before lifting) exactly.
    fn zero_solves_step_zero(&self, rhs: &[f64]) -> bool {
        let prescribed_zero = self.prescribed.as_ref().is_none_or(|g| g.iter().all(|v| *v == 0.0));
        let rhs_zero = !self.backend.any(rhs.iter().any(|v| *v != 0.0));
        zero_solves_step_zero(self.sim, rhs_zero, prescribed_zero)
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
            step: Some(n),
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

    /// Records u_n in the history and keeps m_n^j = h_n^j + β_j u_n of every channel for the
    /// stresses of an output step (m_0 = 0: the memory integral is empty at t = 0).
    fn update_history(&mut self, n: usize, output: bool) {
        let Some(history) = &mut self.history else {
            return;
        };
        let (loads, u) = (&self.memory_load, &self.displacement);
        let beta = &self.beta;
        let memory_displacement = &mut self.memory_displacement;
        timed(&mut self.stats.phases.history, || {
            // only output steps show the memory stress
            *memory_displacement = output.then(|| {
                loads
                    .chunks_exact(u.len())
                    .zip(beta)
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
        self.stats.step_matrices = self.operators.built;
        self.stats.distinct_steps = self.sizes.len();
        self.stats.solves = self.counters.solves();
        self.stats.sparse_forward_sweeps = self.counters.sparse_forward_sweeps();
        self.stats
    }
}

/// The size of the first step after step 0 (whose β the first operator is built for).
fn first_step<const D: usize>(sim: &Simulation<D>) -> f64 {
    match &sim.time {
        Schedule::Fixed(g) => g.step_size(1),
        Schedule::Automatic(a) => crate::time::Controller::new(a.clone()).propose().size,
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

/// What the drivers share: the frames written so far and their time.
pub(super) struct Written {
    pub frames: usize,
    pub last: Option<usize>,
    pub seconds: f64,
}

impl Written {
    /// Hands a step to the sink, and writes it when it is an output step.
    pub(super) fn step<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        sink: &mut dyn FrameSink<D>,
        view: &StepView,
    ) -> Result<(), SolveError> {
        sink.step_done(sim, view);
        if view.output {
            timed(&mut self.seconds, || sink.write_frame(sim, view))?;
            self.frames += 1;
            self.last = Some(view.step);
        }
        Ok(())
    }

    /// Whether the run is to stop (a stop on any process stops every process at the same step).
    pub(super) fn stopped<const D: usize>(&self, backend: &dyn Backend<D>, stop: Option<&AtomicBool>) -> bool {
        stop.is_some() && backend.any(stop.is_some_and(|s| s.load(Ordering::Relaxed)))
    }
}
