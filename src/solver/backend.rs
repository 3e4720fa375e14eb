//! The linear-algebra backend seam of the time loop (docs/method.md §13): what a backend other
//! than the cached faer factor provides, and the collective decisions it makes.

use super::error::SolveError;
use super::setup::Simulation;
use crate::contact::active_set::{ContactOutcome, ContactState};
use crate::contact::Condensation;
use crate::linalg::{Counters, LinearSolver};
use std::sync::Arc;

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
pub(super) fn any<const D: usize>(backend: Option<&dyn Backend<D>>, local: bool) -> bool {
    match backend {
        None => local,
        Some(b) => {
            let mut v = [f64::from(u8::from(local))];
            b.sum(&mut v);
            v[0] != 0.0
        }
    }
}
