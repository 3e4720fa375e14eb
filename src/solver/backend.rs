//! The linear-algebra backend seam of the time loop (docs/method.md §9, §13): everything the loop
//! asks of the linear algebra, so that the loop has one path whichever backend runs it. The
//! cached faer factor ([`super::faer::FaerBackend`]) is one implementation, PETSc over MPI
//! (`src/petsc/backend.rs`) another.

use super::error::SolveError;
use super::operator::StepOperator;
use super::reactions::Reactions;
use super::setup::Simulation;
use super::stats::RunStats;
use crate::contact::{ContactOutcome, ContactState};
use crate::linalg::Counters;

/// Which unmodified stiffness matrix (no identity rows) a [`Backend::product`] applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stiffness {
    /// K_A, the elastic stiffness.
    Elastic,
    /// K_j, the stiffness of memory channel j's tensor (B₀ = I for the paper; docs/method.md §3,
    /// §15.1).
    Memory(usize),
}

/// A linear-algebra backend of the time loop: it builds the operator (solver, condensation,
/// lifting) of each distinct step matrix, multiplies by the unmodified stiffness matrices, and
/// may run the contact solve on one process only and share its forces with the others. The time
/// loop, the history, the loads and the contact law stay the same.
///
/// A backend may hold only a share of the unknowns on this process
/// ([`Backend::held_unknowns`]): the time loop then keeps every step vector (loads, history,
/// displacement) over that share, and makes the decisions that must be the same everywhere (a
/// non-finite solution, a zero step, a stop) through [`Backend::sum`] (docs/method.md §13.2).
pub trait Backend<const D: usize>: Sync {
    /// The operator of the step matrix K = K_A + Σ_j c_j K_j with identity rows at the
    /// prescribed unknowns, c = `memory` (one number per memory channel; empty: K_A alone).
    /// Called once for the run's K first, then for K_A when step 0 needs a factor of its own.
    fn operator(
        &mut self,
        sim: &Simulation<D>,
        memory: &[f64],
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<StepOperator, SolveError>;
    /// How the reactions of [`Simulation::dirichlet`]'s groups are computed (called once,
    /// after the first [`Backend::operator`], when the scene asks for reactions).
    fn reactions(&mut self, sim: &Simulation<D>) -> Reactions;
    /// The unknowns (hvi's numbers D·p + c) this process holds, in the order of every vector
    /// the time loop passes to the backend and shows its sink; None when it holds all of them
    /// in hvi's order.
    fn held_unknowns(&self) -> Option<&[usize]> {
        None
    }
    /// y = K x over the held unknowns for an unmodified K_A or K_j (collective). A failure fills
    /// y with NaN, which the collective checks then see on every process.
    fn product(&self, sim: &Simulation<D>, matrix: Stiffness, x: &[f64], y: &mut [f64]);
    /// Replaces `values` by their sum over all processes (collective; NaN stays NaN). One
    /// process: nothing to do.
    fn sum(&self, _values: &mut [f64]) {}
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
    /// True on every process if `local` is true on any (collective).
    fn any(&self, local: bool) -> bool {
        let mut v = [f64::from(u8::from(local))];
        self.sum(&mut v);
        v[0] != 0.0
    }
    /// The number of held unknowns.
    fn held_len(&self, sim: &Simulation<D>) -> usize {
        self.held_unknowns().map_or(sim.dofs.n(), <[usize]>::len)
    }
}

/// A backend lent to a run: its owner keeps it after the run (PETSc reads its failure).
impl<const D: usize, B: Backend<D> + ?Sized> Backend<D> for &mut B {
    fn operator(
        &mut self,
        sim: &Simulation<D>,
        memory: &[f64],
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<StepOperator, SolveError> {
        (**self).operator(sim, memory, counters, stats)
    }
    fn reactions(&mut self, sim: &Simulation<D>) -> Reactions {
        (**self).reactions(sim)
    }
    fn held_unknowns(&self) -> Option<&[usize]> {
        (**self).held_unknowns()
    }
    fn product(&self, sim: &Simulation<D>, matrix: Stiffness, x: &[f64], y: &mut [f64]) {
        (**self).product(sim, matrix, x, y)
    }
    fn sum(&self, values: &mut [f64]) {
        (**self).sum(values)
    }
    fn solves_contact(&self) -> bool {
        (**self).solves_contact()
    }
    fn share_contact(
        &self,
        state: &mut ContactState,
        local: Result<ContactOutcome, SolveError>,
    ) -> Result<ContactOutcome, SolveError> {
        (**self).share_contact(state, local)
    }
}
