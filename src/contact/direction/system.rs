//! The Newton system of one iteration (docs/method.md §4.4) as a value, and the trait of the
//! solvers that give its direction.

use super::super::hessian::LawHessian;
use super::super::outcome::ContactOutcome;
use super::super::problem::ContactProblem;

/// (Q_ℐℐ + H + diag(proximal)) x = G_ℐ on the free rows ℐ: H the laws' Hessian there (diagonal,
/// and 2 × 2 blocks on pairs), G the gradient.
pub struct NewtonSystem<'a> {
    /// ℐ, ascending.
    pub free: &'a [usize],
    /// H on ℐ (with its convexified copy).
    pub hessian: &'a LawHessian,
    /// The proximal shift per free row (0 unless Q is singular, docs/method.md §7.7).
    pub proximal: &'a [f64],
    /// G over all rows.
    pub gradient: &'a [f64],
    /// The relative residual an iterative solver must reach (inexact Newton, docs/method.md §9.2).
    pub forcing: f64,
}

impl NewtonSystem<'_> {
    /// The exact diagonal of the laws' part: H_ii + the proximal shift.
    pub fn exact_diagonal(&self) -> Vec<f64> {
        (self.hessian.diagonal.iter().zip(self.proximal))
            .map(|(e, p)| e + p)
            .collect()
    }

    /// G on ℐ (the right-hand side).
    pub fn rhs(&self) -> Vec<f64> {
        self.free.iter().map(|&p| self.gradient[p]).collect()
    }
}

/// A Newton direction: x on the free rows.
pub struct Direction {
    pub x: Vec<f64>,
}

/// A way to solve the Newton system. `direction` gives None where the solver does not serve this
/// system (the next one is asked; the order is `super::newton_direction`'s).
pub trait DirectionSolver {
    fn direction(
        &mut self,
        problem: &ContactProblem,
        system: &NewtonSystem,
        outcome: &mut ContactOutcome,
    ) -> Option<Direction>;
}
