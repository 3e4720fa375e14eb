//! The active set of an iteration (docs/method.md §4.3, §4.4): the rows the Newton step holds at
//! their bound, by the primal–dual active-set rule 𝒜 = {p : r_p − G_p/c_p ≥ g_p}, c_p = Q_pp;
//! bilateral rows are always held.

use super::problem::ContactProblem;

/// Per row, whether it is held at its bound in this iteration, at r with the gradient `grad`.
pub fn held_rows(problem: &ContactProblem, r: &[f64], grad: &[f64]) -> Vec<bool> {
    (0..problem.m())
        .map(|p| {
            let g = problem.g(p);
            problem.is_fixed(p) || g.is_finite() && r[p] - grad[p] / problem.c(p) >= g
        })
        .collect()
}

/// The free rows ℐ: those not held.
pub fn free_rows(held: &[bool]) -> Vec<usize> {
    (0..held.len()).filter(|&p| !held[p]).collect()
}
