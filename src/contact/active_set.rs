//! The active set of an iteration (docs/method.md §4.3, §4.4): the rows the Newton step holds at
//! their bound. The primal–dual active-set rule 𝒜 = {p : r_p − G_p/c_p ≥ g_p}, c_p = Q_pp, is
//! enlarged by the rows within δ of their bound that the gradient pushes into it, which keeps
//! every direction a descent direction (Bertsekas' projected Newton); bilateral rows are always
//! held.

use super::problem::ContactProblem;
use super::settings::TUNING;

/// Per row, whether it is held at its bound in this iteration, at r with the gradient `grad`.
/// `enlarged`: with the rows within δ of their bound that are pushed into it, δ the largest
/// projected step, at most [`TUNING`]`.near_bound` of the largest bound.
pub fn held_rows(problem: &ContactProblem, r: &[f64], grad: &[f64], enlarged: bool) -> Vec<bool> {
    let m = problem.m();
    let projected_step = (0..m)
        .map(|p| (r[p] - (r[p] - grad[p] / problem.c(p)).min(problem.g(p))).abs())
        .fold(0.0, f64::max);
    let delta = projected_step.min(
        TUNING.near_bound
            * problem.bound.map_or(1.0, |g| {
                g.iter()
                    .filter(|v| v.is_finite())
                    .fold(0.0f64, |a, b| a.max(b.abs()))
                    .max(TUNING.near_bound)
            }),
    );
    (0..m)
        .map(|p| {
            let g = problem.g(p);
            problem.is_fixed(p)
                || g.is_finite()
                    && (r[p] - grad[p] / problem.c(p) >= g || (enlarged && g - r[p] <= delta && grad[p] < 0.0))
        })
        .collect()
}

/// The free rows ℐ: those not held.
pub fn free_rows(held: &[bool]) -> Vec<usize> {
    (0..held.len()).filter(|&p| !held[p]).collect()
}
