//! Coulomb's first round where every bound force is 0 (no normal force yet, docs/method.md
//! §17.2): no tangential row holds a force, so the round is the frictionless problem of the
//! normal rows, whose stiffness is the Schur complement S = (W_νν)⁻¹ of Q on them and whose free
//! forces are S d_ν, d = W q. Solved there (m rows, where the full round factors m + m_τ), the
//! tangential rows follow as r_τ = d_τ − W_τν λ_ν; the state is then the full round's solution.

use super::super::condensed::{DenseNormalStiffness, NormalStiffness};
use super::super::newton::ActiveSetSolver;
use super::super::nodal::NodalLaws;
use super::super::outcome::{ContactFailure, ContactOutcome};
use super::super::problem::ContactProblem;
use super::super::state::{ContactState, SolverCache};
use crate::linalg::dense::matvec_row_major;

/// The unloaded round on the normal rows `0..m` of `operator` (their laws `laws`, origins,
/// bounds and bilateral rows as given); None (the full round runs) where W is not at hand or
/// not positive definite on the normal rows.
pub fn solve(
    solver: &ActiveSetSolver,
    (operator, laws, m): (&dyn NormalStiffness, &NodalLaws, usize),
    (offset, bound, fixed): (&[f64], Option<&[f64]>, Option<&[bool]>),
    q: &[f64],
    state: &mut ContactState,
) -> Result<Option<ContactOutcome>, ContactFailure> {
    let all = operator.m();
    let Some(w) = operator.w() else {
        return Ok(None);
    };
    let normal_block: Vec<f64> = (0..m).flat_map(|p| w[p * all..p * all + m].iter().copied()).collect();
    let Ok(reduced) = DenseNormalStiffness::from_w(normal_block, m) else {
        return Ok(None);
    };
    let mut d = vec![0.0; all];
    matvec_row_major(w, all, q, &mut d);
    let mut free_forces = vec![0.0; m];
    reduced.apply_q(&d[..m], &mut free_forces);
    let mut rows = ContactState::new(m);
    rows.normal_displacement
        .copy_from_slice(&state.normal_displacement[..m]);
    let problem = ContactProblem {
        offset: Some(&offset[..m]),
        bound: bound.map(|g| &g[..m]),
        fixed,
        ..ContactProblem::new(&reduced, laws)
    };
    let outcome = solver.solve_forces(&problem, &free_forces, &mut rows, &mut SolverCache::default())?;
    // λ_τ = 0 and r = d − W λ
    let mut lambda = vec![0.0; all];
    lambda[..m].copy_from_slice(&rows.force);
    let mut moved = vec![0.0; all];
    matvec_row_major(w, all, &lambda, &mut moved);
    state.normal_displacement[..m].copy_from_slice(&rows.normal_displacement);
    for p in m..all {
        state.normal_displacement[p] = d[p] - moved[p];
    }
    state.force.copy_from_slice(&lambda);
    Ok(Some(outcome))
}
