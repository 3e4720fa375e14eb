//! The direction by a product by W (docs/method.md §4.6, §9.7): where no row is held and no law
//! curves any row (a surface that starts a step apart, under a law without curvature off
//! contact), the Newton system is Q Δ = G on every row, and Δ = W G: a product by W where W is
//! formed, two triangular solves where it is not, in place of a factorisation of Q.

use super::super::outcome::ContactOutcome;
use super::super::problem::ContactProblem;
use super::super::settings::TUNING;
use super::system::{Direction, DirectionSolver, NewtonSystem};
use crate::linalg::dense::matvec_row_major;

/// Δ = W G where every row is free and uncurved; it counts as one factorisation.
pub struct WProduct;

impl DirectionSolver for WProduct {
    fn direction(
        &mut self,
        problem: &ContactProblem,
        system: &NewtonSystem,
        outcome: &mut ContactOutcome,
    ) -> Option<Direction> {
        let m = problem.m();
        if problem.singular || system.free.len() != m {
            return None;
        }
        let mut x = vec![0.0; m];
        match problem.operator.w() {
            Some(w) => {
                if !uncurved(system, w, m) {
                    return None;
                }
                matvec_row_major(w, m, system.gradient, &mut x);
            }
            None => {
                if system.hessian.is_curved() || !problem.operator.apply_w(system.gradient, &mut x) {
                    return None;
                }
            }
        }
        outcome.factorisations += 1;
        outcome.in_w += 1;
        Some(Direction { x })
    }
}

/// Whether no law curves a row: every curvature h (a pair: both of its block's) non-negative and
/// below [`TUNING`]`.negligible_curvature` of its direction's least stiffness 1/(eᵀWe).
fn uncurved(system: &NewtonSystem, w: &[f64], m: usize) -> bool {
    let (free, hessian) = (system.free, system.hessian);
    let negligible = |h: f64, e: &[(usize, f64)]| {
        let compliance: f64 = e
            .iter()
            .flat_map(|&(p, a)| e.iter().map(move |&(q, b)| a * b * w[p * m + q]))
            .sum();
        h >= 0.0 && h * compliance <= TUNING.negligible_curvature
    };
    (0..free.len()).all(|i| match hessian.partner[i] {
        None => negligible(hessian.diagonal[i], &[(free[i], 1.0)]),
        Some(j) if i < j => {
            let (a, b, n) = hessian.pair[i];
            let rows = [free[i], free[j]];
            negligible(a, &[(rows[0], n[0]), (rows[1], n[1])]) && negligible(b, &[(rows[0], -n[1]), (rows[1], n[0])])
        }
        Some(_) => true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::hessian::LawHessian;
    use crate::contact::nodal::NodalLaws;
    use crate::contact::DenseNormalStiffness;

    /// With every row free and none curved, the direction is W G on every row (to round-off);
    /// a held row, or a curved one, leaves it to the next solver.
    #[test]
    fn an_uncurved_free_surface_is_moved_by_w_g() {
        let m = 48;
        let x = |p: usize| (p as f64 / m as f64).sqrt();
        let w: Vec<f64> = (0..m * m)
            .map(|k| {
                let (p, q) = (k / m, k % m);
                (-(x(p) - x(q)).abs() / 0.2).exp() + if p == q { 0.02 } else { 0.0 }
            })
            .collect();
        let op = DenseNormalStiffness::from_w(w.clone(), m).unwrap();
        let laws = NodalLaws::default();
        let problem = ContactProblem::new(&op, &laws);
        let g: Vec<f64> = (0..m).map(|i| (0.21 * i as f64).cos()).collect();
        let zeros = vec![0.0; m];
        let all: Vec<usize> = (0..m).collect();
        let direction = |free: &[usize], h: &[f64]| {
            let hessian = LawHessian::diagonal(h);
            let system = NewtonSystem {
                free,
                hessian: &hessian,
                proximal: &zeros[..free.len()],
                gradient: &g,
                forcing: 1e-13,
            };
            WProduct.direction(&problem, &system, &mut ContactOutcome::default())
        };
        let got = direction(&all, &zeros).unwrap();
        for (p, v) in got.x.iter().enumerate() {
            let wg: f64 = (0..m).map(|q| w[p * m + q] * g[q]).sum();
            assert!((v - wg).abs() <= 1e-12 * wg.abs().max(1.0), "{v} against {wg}");
        }
        assert!(direction(&all[1..], &zeros[1..]).is_none(), "a held row");
        let mut curved = zeros.clone();
        curved[7] = 1.0;
        assert!(direction(&all, &curved).is_none(), "a curved row");
    }
}
