//! The Newton direction of an iteration (docs/method.md §4.4, §9.2, §9.7): the solvers of the
//! Newton system and, in [`newton_direction`], the one place where one is chosen.

pub mod dense;
pub mod kept;
pub mod system;
mod update;
pub mod w_product;

pub use system::{Direction, DirectionSolver, NewtonSystem};

use super::outcome::ContactOutcome;
use super::problem::ContactProblem;
use super::settings::ContactSettings;
use super::state::SolverCache;

/// The direction of `system` from the first solver that serves it, in this order:
/// 1. Δ = W G ([`w_product::WProduct`]), where every row is free and none is curved;
/// 2. CG with the kept factor ([`kept::Kept`]), above `dense_limit` free rows (refactored where
///    it no longer serves);
/// 3. a dense factorisation ([`dense::Dense`]), which serves every system.
pub fn newton_direction(
    problem: &ContactProblem,
    system: &NewtonSystem,
    settings: &ContactSettings,
    cache: &mut SolverCache,
    outcome: &mut ContactOutcome,
) -> Direction {
    if system.free.is_empty() {
        return Direction { x: Vec::new() };
    }
    let (mut product, mut dense) = (w_product::WProduct, dense::Dense);
    let mut kept = kept::Kept {
        factor: &mut cache.kept,
        settings,
    };
    let mut solvers: Vec<&mut dyn DirectionSolver> = Vec::with_capacity(3);
    if settings.strategies.w_product {
        solvers.push(&mut product);
    }
    solvers.push(&mut kept);
    solvers.push(&mut dense);
    solvers
        .into_iter()
        .find_map(|solver| solver.direction(problem, system, outcome))
        .expect("a dense factorisation serves every Newton system")
}
