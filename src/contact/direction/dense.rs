//! The Newton matrix factored densely (docs/method.md §4.4, §9.7): Q + H on free rows, H the laws'
//! exact Hessian where that is positive definite, else convexified, with a shift that grows
//! until Cholesky succeeds.

use super::super::outcome::ContactOutcome;
use super::super::problem::ContactProblem;
use super::super::settings::TUNING;
use super::system::{Direction, DirectionSolver, NewtonSystem};
use crate::linalg::dense::DenseCholesky;

/// A direction by a fresh factorisation of the Newton matrix on every free row: what serves
/// every system (the last solver asked).
pub struct Dense;

impl DirectionSolver for Dense {
    fn direction(
        &mut self,
        problem: &ContactProblem,
        system: &NewtonSystem,
        outcome: &mut ContactOutcome,
    ) -> Option<Direction> {
        outcome.factorisations += 1;
        let all: Vec<usize> = (0..system.free.len()).collect();
        let factored = factor_rows(problem, system, &all, (outcome, true));
        Some(Direction {
            x: factored.factor.solve(&system.rhs()),
        })
    }
}

/// The Newton matrix on some of the free rows, factored, with the diagonal and pair couplings
/// it was formed with.
#[derive(Debug)]
pub struct FactoredRows {
    pub factor: DenseCholesky,
    /// The contact rows it holds, in its order.
    pub rows: Vec<usize>,
    /// Per row: the laws' diagonal (with the proximal shift and any convexifying shift) and the
    /// pair coupling (0 where the row has none in the factor).
    pub diagonal: Vec<f64>,
    pub coupling: Vec<f64>,
}

/// The Newton matrix Q + H on the free rows `factored` (indices into `system.free`) factored: H
/// the laws' exact Hessian with the proximal shift, else (where that is not positive definite,
/// or not `exact_first`) the convexified one, shifted as docs/method.md §4.4 says until Cholesky
/// succeeds (counted in `outcome.convexified`).
pub fn factor_rows(
    problem: &ContactProblem,
    system: &NewtonSystem,
    factored: &[usize],
    (outcome, exact_first): (&mut ContactOutcome, bool),
) -> FactoredRows {
    let (free, hessian, proximal) = (system.free, system.hessian, system.proximal);
    let rows: Vec<usize> = factored.iter().map(|&i| free[i]).collect();
    let n = rows.len();
    let mut place = vec![None; free.len()];
    for (a, &i) in factored.iter().enumerate() {
        place[i] = Some(a);
    }
    let on_rows = |v: &[f64]| -> Vec<f64> { factored.iter().map(|&i| v[i]).collect() };
    let partner: Vec<Option<usize>> = (factored.iter())
        .map(|&i| hessian.partner[i].and_then(|j| place[j]))
        .collect();
    // the matrix's lower triangle column by column, column j from Q's row rows[j] (Q is
    // symmetric)
    let build = |diag: &[f64], coupling: &[f64]| {
        DenseCholesky::from_lower(n, |matrix| {
            for (j, column) in matrix.chunks_exact_mut(n).enumerate() {
                let p = rows[j];
                for (i, v) in column.iter_mut().enumerate().skip(j) {
                    *v = problem.operator.q(p, rows[i]);
                }
                column[j] += diag[j];
                if let Some(k) = partner[j].filter(|&k| k > j) {
                    column[k] += coupling[k];
                }
            }
        })
    };
    let exact: Vec<f64> = factored.iter().map(|&i| hessian.diagonal[i] + proximal[i]).collect();
    let coupling = on_rows(&hessian.coupling);
    let (factor, diagonal, coupling) = match exact_first.then(|| build(&exact, &coupling)).flatten() {
        Some(llt) => (llt, exact, coupling),
        None => {
            outcome.convexified += 1;
            let mut shift = 0.0;
            loop {
                let diagonal: Vec<f64> = (factored.iter())
                    .map(|&i| hessian.convex_diagonal[i] + proximal[i] + shift)
                    .collect();
                let coupling = on_rows(&hessian.convex_coupling);
                if let Some(llt) = build(&diagonal, &coupling) {
                    break (llt, diagonal, coupling);
                }
                shift = if shift == 0.0 {
                    TUNING.convex_shift * problem.c(rows[0])
                } else {
                    shift * TUNING.convex_growth
                };
            }
        }
    };
    FactoredRows {
        factor,
        rows,
        diagonal,
        coupling,
    }
}
