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
//! solve goes through the [`LinearSolver`] and [`Condensation`] seams; the default condensation
//! is the faer factor's split sweeps (docs/method.md §4.5): a step costs one solve, contact or
//! not. Step 0 has no history and uses K_A alone; when its solution is not trivially zero and
//! K ≠ K_A, K_A gets a factor of its own.

use super::error::SolveError;
use super::setup::{ContactSetup, Simulation};
use super::stats::{timed, Reaction, RunStats};
use crate::contact::active_set::{ActiveSetSolver, ContactOutcome, ContactState};
use crate::contact::{Condensation, SplitSweeps, StoredResponses};
use crate::fem::assembly::assemble_stiffness;
use crate::fem::{NodeBlockMatrix, SymmetricMatrix};
use crate::history::History;
use crate::linalg::{Analysis, Counters, Factor, LinearSolver};
use crate::material::Isotropic;
use crate::scene::CondensationKind;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
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

/// The columns of the prescribed unknowns of an unmodified matrix (all rows): what the
/// prescribed part of the system contributes (docs/method.md §7).
struct PrescribedColumns {
    /// (prescribed unknown j, its column entries (i, K_ij)).
    columns: Vec<(usize, Vec<(usize, f64)>)>,
}

impl PrescribedColumns {
    fn new<const D: usize>(matrix: &SymmetricMatrix, dofs: &crate::fem::DofMap<D>) -> Self {
        let columns = (0..matrix.n())
            .filter(|&j| dofs.is_prescribed(j))
            .map(|j| (j, matrix.column(j).collect()))
            .collect();
        PrescribedColumns { columns }
    }

    /// rhs_i −= Σ_j K_ij g_j at the free rows i.
    fn lift<const D: usize>(&self, g: &[f64], dofs: &crate::fem::DofMap<D>, rhs: &mut [f64]) {
        for (j, col) in &self.columns {
            if g[*j] != 0.0 {
                for &(i, v) in col {
                    if !dofs.is_prescribed(i) {
                        rhs[i] -= v * g[*j];
                    }
                }
            }
        }
    }

    /// (K x)_j at each prescribed j, added into `out` (indexed like the columns).
    fn add_product(&self, x: &[f64], out: &mut [f64]) {
        for ((_, col), o) in self.columns.iter().zip(out.iter_mut()) {
            *o += col.iter().map(|&(i, v)| v * x[i]).sum::<f64>();
        }
    }
}

/// Which unmodified stiffness matrix (no identity rows) a [`Backend::product`] applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stiffness {
    /// K_A, the elastic stiffness.
    Elastic,
    /// K_B, the stiffness of the memory's one channel tensor (B₀ = I for the paper; docs/method.md
    /// §3, §15.1). A backend runs memory of one channel only ([`Stepper::prepare_with`]).
    Memory,
}

/// A linear-algebra backend other than the cached faer factor (docs/method.md §13): it builds
/// the solver and the condensation of each distinct step matrix, and may run the contact solve
/// on one process only and share its forces with the others. The time loop, the history, the
/// loads and the contact law stay the same.
///
/// A backend may hold only a share of the unknowns on this process ([`Backend::unknowns`]):
/// the time loop then keeps every step vector (loads, history, displacement) over that share,
/// multiplies by K_A and K_B through [`Backend::product`], and makes the decisions that must be
/// the same everywhere (a non-finite solution, a zero step) through [`Backend::sum`]
/// (docs/method.md §13.2).
pub trait Backend<const D: usize>: Sync {
    /// A solver (and, with contact nodes, a condensation) for the step matrix
    /// K = K_A + c K_B with identity rows at the prescribed unknowns, c = `memory` (None: K_A).
    #[allow(clippy::type_complexity)]
    fn operator(
        &self,
        sim: &Simulation<D>,
        memory: Option<f64>,
        counters: &Counters,
    ) -> Result<(Arc<dyn LinearSolver>, Option<Box<dyn Condensation>>), SolveError>;
    /// True if this process runs the active-set solve of a step (the others receive its result).
    fn solves_contact(&self) -> bool {
        true
    }
    /// Gives every process the result of the process that solved the contact problem: on that
    /// one, `local` is its result and `state` its state; on the others both are overwritten.
    fn share_contact(
        &self,
        _state: &mut ContactState,
        local: Result<ContactOutcome, SolveError>,
    ) -> Result<ContactOutcome, SolveError> {
        local
    }
    /// The unknowns (hvi's numbers D·p + c) this process holds, in the order of every vector
    /// the time loop passes to the backend's solvers and products and shows its sink.
    fn unknowns(&self) -> &[usize];
    /// y = K x over this process's unknowns for the unmodified K_A or K_B (collective). A
    /// failure fills y with NaN, which the collective checks then see on every process.
    fn product(&self, sim: &Simulation<D>, matrix: Stiffness, x: &[f64], y: &mut [f64]);
    /// Replaces `values` by their sum over all processes (collective; NaN stays NaN).
    fn sum(&self, values: &mut [f64]);
}

/// True on every process if `local` is true on any (collective with a backend).
fn any<const D: usize>(backend: Option<&dyn Backend<D>>, local: bool) -> bool {
    match backend {
        None => local,
        Some(b) => {
            let mut v = [f64::from(u8::from(local))];
            b.sum(&mut v);
            v[0] != 0.0
        }
    }
}

/// How a step operator lifts non-zero prescribed values (docs/method.md §7.2).
enum Lifting {
    /// The unmodified columns of the prescribed unknowns (serial).
    Columns(PrescribedColumns),
    /// rhs −= (K_A + c K_B) g at the free unknowns through [`Backend::product`] (c = `memory`).
    Products { memory: Option<f64> },
}

/// A factor of a step matrix and, with contact, its condensation.
struct StepOperator {
    solver: Arc<dyn LinearSolver>,
    condensed: Option<Box<dyn Condensation>>,
    /// How non-zero prescribed values are lifted (None when they are all zero).
    lifting: Option<Lifting>,
}

/// The matrix a factor is built from (identity rows at the prescribed unknowns, docs/method.md
/// §7) and, when some prescribed value is non-zero, the unmodified columns that lift them.
fn system_matrix<const D: usize>(sim: &Simulation<D>, matrix: &SymmetricMatrix) -> (SymmetricMatrix, Option<Lifting>) {
    let lifting = sim
        .dirichlet
        .is_nonzero()
        .then(|| Lifting::Columns(PrescribedColumns::new(matrix, &sim.dofs)));
    (matrix.with_identity_rows(&sim.dofs), lifting)
}

impl StepOperator {
    /// Factors `matrix` (from [`system_matrix`]) and condenses the contact normals.
    fn new<const D: usize>(
        sim: &Simulation<D>,
        symbolic: &Analysis,
        (matrix, lifting): (SymmetricMatrix, Option<Lifting>),
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Self, SolveError> {
        // The probe's product K v is taken before the factorisation, which consumes the matrix:
        // K is not held next to its factor (docs/method.md §9.3).
        let probe = timed(&mut stats.phases.factorisation, || Probe::new(&matrix));
        let factor = timed(&mut stats.phases.factorisation, || {
            Factor::new_consuming(symbolic, matrix, counters)
        })
        .map_err(|e| SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail: e.to_string(),
        })?;
        timed(&mut stats.phases.factorisation, || probe.verdict(&factor)).map_err(|detail| SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail,
        })?;
        let factor = Arc::new(factor);
        let condensed: Option<Box<dyn Condensation>> = match &sim.contact {
            Some(c) if !c.nodes.is_empty() => Some(
                timed(
                    &mut stats.phases.condensation,
                    || -> Result<Box<dyn Condensation>, String> {
                        Ok(match sim.condensation {
                            CondensationKind::SplitSweeps => {
                                Box::new(SplitSweeps::new(&c.nodes, factor.clone(), counters)?)
                            }
                            kind @ (CondensationKind::StoredResponses | CondensationKind::RecoverySolve) => {
                                let solver: Arc<dyn LinearSolver> = factor.clone();
                                let keep = kind == CondensationKind::StoredResponses;
                                Box::new(StoredResponses::new(&c.nodes, solver, keep, counters)?)
                            }
                        })
                    },
                )
                .map_err(SolveError::Setup)?,
            ),
            _ => None,
        };
        if let Some(c) = &condensed {
            stats.condensation = Some(c.name().to_string());
        }
        Ok(StepOperator {
            solver: factor,
            condensed,
            lifting,
        })
    }

    /// The operator of a [`Backend`] for K = K_A + c K_B (c = `memory`), lifting through the
    /// backend's products.
    fn with_backend<const D: usize>(
        sim: &Simulation<D>,
        backend: &dyn Backend<D>,
        memory: Option<f64>,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Self, SolveError> {
        let lifting = sim.dirichlet.is_nonzero().then_some(Lifting::Products { memory });
        let (solver, condensed) = timed(&mut stats.phases.factorisation, || {
            backend.operator(sim, memory, counters)
        })?;
        if let Some(c) = &condensed {
            stats.condensation = Some(c.name().to_string());
        }
        Ok(StepOperator {
            solver,
            condensed,
            lifting,
        })
    }

    /// Solves one step: d = C K⁻¹ rhs, contact → λ, u_n = K⁻¹ (rhs − Cᵀ λ). `offset` is the
    /// prescribed part of u_ν (None when it is zero); `u` receives u_n.
    #[allow(clippy::too_many_arguments)]
    fn solve<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        step: usize,
        rhs: &[f64],
        offset: Option<&[f64]>,
        u: &mut [f64],
        state: Option<&mut ContactState>,
        backend: Option<&dyn Backend<D>>,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Option<ContactOutcome>, SolveError> {
        match (&sim.contact, self.condensed.as_mut(), state) {
            (Some(setup), Some(op), Some(state)) => {
                let mut d = vec![0.0; setup.nodes.len()];
                timed(&mut stats.phases.forward_sweep, || {
                    op.free_normal(rhs, &mut d, counters)
                });
                if let Some(g) = offset {
                    setup.nodes.prescribed_offset(g, &mut d);
                }
                let outcome = timed(&mut stats.phases.contact, || match backend {
                    None => contact_solve(sim, setup, op.as_ref(), step, &d, state),
                    Some(b) => {
                        let local = if b.solves_contact() {
                            contact_solve(sim, setup, op.as_ref(), step, &d, state)
                        } else {
                            Ok(ContactOutcome::default())
                        };
                        b.share_contact(state, local)
                    }
                })?;
                stats.contact_solves += 1;
                timed(&mut stats.phases.backward_sweep, || {
                    op.recover(&state.force, u, counters)
                });
                Ok(Some(outcome))
            }
            _ => {
                timed(&mut stats.phases.backward_sweep, || self.solver.solve(rhs, u, counters));
                Ok(None)
            }
        }
    }
}

/// A Cholesky factorisation of a singular matrix can succeed on round-off pivots (a body held
/// at a single point can still rotate about it). One probe solve, K⁻¹(K v) against v for a fixed
/// pseudo-random v, tells: an error far above round-off means the matrix is (nearly) singular.
/// The probe is not counted among the run's solves.
struct Probe {
    v: Vec<f64>,
    /// K v.
    product: Vec<f64>,
}

impl Probe {
    /// The probe vector v and K v.
    fn new(matrix: &SymmetricMatrix) -> Self {
        let n = matrix.n();
        let v: Vec<f64> = (0..n)
            .map(|i| ((i as f64 + 1.0) * 0.618_033_988_749_895).fract() - 0.5)
            .collect();
        let mut product = vec![0.0; n];
        matrix.matvec(&v, &mut product);
        Probe { v, product }
    }

    /// K⁻¹(K v) against v with the factor of K.
    fn verdict(mut self, factor: &Factor) -> Result<(), String> {
        factor.solve_in_place(&mut self.product, &Counters::default());
        let scale = self.v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let error = self
            .product
            .iter()
            .zip(&self.v)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()))
            / scale;
        singularity_verdict(error)
    }
}

/// The verdict of a probe solve whose relative error is `error` (any backend's probe).
pub fn singularity_verdict(error: f64) -> Result<(), String> {
    if error.is_finite() && error <= 1e-6 {
        Ok(())
    } else {
        Err(format!(
            "the stiffness matrix is singular or nearly so (a probe solve is off by {error:.1e} relative): the body is not held against rigid motions; clamp a part of the boundary (groups.clamped) that stops translations and rotations"
        ))
    }
}

fn contact_solve<const D: usize>(
    sim: &Simulation<D>,
    setup: &ContactSetup<D>,
    op: &dyn Condensation,
    step: usize,
    d: &[f64],
    state: &mut ContactState,
) -> Result<ContactOutcome, SolveError> {
    // a moving obstacle moves the laws' origins and the bounds (docs/method.md §14.2)
    let t = sim.time.time(step);
    let moved = setup
        .gaps_at(t)
        .map_err(|detail| SolveError::NonFiniteLoad { step, time: t, detail })?;
    let (offset, bound) = match &moved {
        Some((o, g)) => (Some(&o[..]), Some(&g[..])),
        None => (setup.gap.as_deref(), setup.bound.as_deref()),
    };
    let solver = ActiveSetSolver {
        operator: op.stiffness(),
        laws: &setup.laws,
        offset,
        bound,
        settings: setup.settings,
    };
    solver.solve(d, state).map_err(|f| SolveError::ContactFailed {
        step,
        time: sim.time.time(step),
        iterations: f.outcome.iterations,
        residual: f.outcome.residual,
        tolerance: setup.settings.tolerance,
        reason: f.reason,
    })
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

/// The reaction forces at the prescribed components (docs/method.md §7):
/// R = K_A u_n + K_B m_n − F_n + Cᵀ λ at each prescribed unknown.
struct Reactions {
    /// K_A's and K_B's unmodified columns of the prescribed unknowns (serial; with a backend,
    /// its products).
    k_a: Option<PrescribedColumns>,
    /// One per memory channel (serial).
    k_b: Vec<PrescribedColumns>,
    /// Per reaction group: positions of its unknowns in the prescribed columns (serial), or in
    /// this process's vectors (only the unknowns it holds, with a backend).
    groups: Vec<Vec<usize>>,
    totals: Vec<f64>,
}

impl Reactions {
    fn new<const D: usize>(sim: &Simulation<D>, k_a: &SymmetricMatrix, k_b: &[SymmetricMatrix]) -> Self {
        let k_a = PrescribedColumns::new(k_a, &sim.dofs);
        let position: std::collections::HashMap<usize, usize> =
            k_a.columns.iter().enumerate().map(|(k, (j, _))| (*j, k)).collect();
        let groups = sim
            .dirichlet
            .reaction_groups
            .iter()
            .map(|g| g.unknowns.iter().map(|d| position[d]).collect())
            .collect();
        Reactions {
            k_b: k_b.iter().map(|m| PrescribedColumns::new(m, &sim.dofs)).collect(),
            groups,
            totals: vec![0.0; sim.dirichlet.reaction_groups.len()],
            k_a: Some(k_a),
        }
    }

    /// The reactions of the unknowns a backend holds (`unknowns`, its order).
    fn held<const D: usize>(sim: &Simulation<D>, unknowns: &[usize]) -> Self {
        let position: std::collections::HashMap<usize, usize> =
            unknowns.iter().enumerate().map(|(k, &d)| (d, k)).collect();
        let groups = sim
            .dirichlet
            .reaction_groups
            .iter()
            .map(|g| g.unknowns.iter().filter_map(|d| position.get(d).copied()).collect())
            .collect();
        Reactions {
            k_a: None,
            k_b: Vec::new(),
            groups,
            totals: vec![0.0; sim.dirichlet.reaction_groups.len()],
        }
    }

    /// [`Reactions::compute`] with a backend: R over the unknowns this process holds, the
    /// group totals summed over all processes (collective).
    fn compute_held<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        backend: &dyn Backend<D>,
        u: &[f64],
        memory: Option<&[f64]>,
        load: &[f64],
        contact: Option<&ContactState>,
    ) -> &[f64] {
        let unknowns = backend.unknowns();
        let mut r = vec![0.0; u.len()];
        backend.product(sim, Stiffness::Elastic, u, &mut r);
        if let Some(m) = memory {
            let mut y = vec![0.0; u.len()];
            backend.product(sim, Stiffness::Memory, m, &mut y);
            r.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
        }
        // Cᵀλ at the prescribed unknowns: the prescribed parts of the contact rows.
        let mut force: std::collections::HashMap<usize, f64> = std::collections::HashMap::new();
        if let (Some(c), Some(state)) = (&sim.contact, contact) {
            for (l, fixed) in state.force.iter().zip(c.nodes.prescribed_rows()) {
                for &(d, coefficient) in fixed {
                    *force.entry(d).or_insert(0.0) += l * coefficient;
                }
            }
        }
        for (total, members) in self.totals.iter_mut().zip(&self.groups) {
            *total = members
                .iter()
                .map(|&k| r[k] + force.get(&unknowns[k]).copied().unwrap_or(0.0) - load[k])
                .sum();
        }
        backend.sum(&mut self.totals);
        &self.totals
    }

    #[allow(clippy::too_many_arguments)]
    fn compute<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        u: &[f64],
        memory: Option<&[f64]>,
        load: &[f64],
        contact: Option<&ContactState>,
    ) -> &[f64] {
        let Some(k_a) = &self.k_a else {
            return &self.totals;
        };
        let mut r = vec![0.0; k_a.columns.len()];
        k_a.add_product(u, &mut r);
        if let Some(m) = memory {
            for (kb, m) in self.k_b.iter().zip(m.chunks_exact(u.len())) {
                kb.add_product(m, &mut r);
            }
        }
        let mut force = vec![0.0; u.len()];
        if let (Some(c), Some(state)) = (&sim.contact, contact) {
            c.nodes.add_forces(&state.force, &mut force);
        }
        for (rk, (j, _)) in r.iter_mut().zip(&k_a.columns) {
            *rk += force[*j] - load[*j];
        }
        for (total, members) in self.totals.iter_mut().zip(&self.groups) {
            *total = members.iter().map(|&k| r[k]).sum();
        }
        &self.totals
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

/// The prescribed components in a right-hand side (docs/method.md §7): rhs_f −= K_fp g at the
/// free rows, rhs_p = g_p at the prescribed ones (zero without non-zero values). `g` is over
/// all unknowns, `rhs` over this process's ([`Backend::unknowns`] with a backend).
fn lift<const D: usize>(
    op: &StepOperator,
    sim: &Simulation<D>,
    g: Option<&[f64]>,
    rhs: &mut [f64],
    backend: Option<&dyn Backend<D>>,
) {
    match (g, &op.lifting, backend) {
        (Some(g), Some(Lifting::Columns(columns)), _) => columns.lift(g, &sim.dofs, rhs),
        (Some(g), Some(Lifting::Products { memory }), Some(b)) => {
            // K g with g zero at the free unknowns is Σ_j K_ij g_j over the prescribed j.
            let held: Vec<f64> = b.unknowns().iter().map(|&d| g[d]).collect();
            let mut kg = vec![0.0; held.len()];
            b.product(sim, Stiffness::Elastic, &held, &mut kg);
            if let Some(c) = memory {
                let mut y = vec![0.0; held.len()];
                b.product(sim, Stiffness::Memory, &held, &mut y);
                kg.iter_mut().zip(&y).for_each(|(a, v)| *a += c * v);
            }
            for ((r, &d), v) in rhs.iter_mut().zip(b.unknowns()).zip(&kg) {
                if !sim.dofs.is_prescribed(d) {
                    *r -= v;
                }
            }
        }
        _ => {}
    }
    for (k, r) in rhs.iter_mut().enumerate() {
        let d = backend.map_or(k, |b| b.unknowns()[k]);
        if sim.dofs.is_prescribed(d) {
            *r = g.map_or(0.0, |g| g[d]);
        }
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
