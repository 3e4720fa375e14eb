//! The laws' Hessian H on the Newton system's free rows (docs/method.md §4.4, §17.3): a diagonal,
//! and on 3D friction's pairs a 2 × 2 block; with its convexified copy (the laws' negative
//! curvatures dropped), which keeps the Newton direction a descent direction where a
//! non-monotone law makes H indefinite.

use super::problem::ContactProblem;

/// The laws' Hessian on the free rows ℐ, indexed by free row i (row p = ℐ_i).
#[derive(Clone)]
pub struct LawHessian {
    /// H_ii.
    pub diagonal: Vec<f64>,
    /// H between row i and its pair's other row (0 where it has none).
    pub coupling: Vec<f64>,
    /// The same with the laws' negative curvatures dropped.
    pub convex_diagonal: Vec<f64>,
    pub convex_coupling: Vec<f64>,
    /// The free index of row i's pair partner, where it has one and that one is free.
    pub partner: Vec<Option<usize>>,
    /// Per row of a pair: a, b and the pair's unit vector n (the block a nnᵀ + b (I − nnᵀ)).
    pub pair: Vec<(f64, f64, [f64; 2])>,
}

/// A pair's block a nnᵀ + b (I − nnᵀ) seen from its row whose component of n is n[0]: that row's
/// diagonal entry and the coupling to the other row (docs/method.md §17.3).
pub fn pair_block(a: f64, b: f64, n: [f64; 2]) -> (f64, f64) {
    (b + (a - b) * n[0] * n[0], (a - b) * n[0] * n[1])
}

impl LawHessian {
    /// A Hessian of `n` rows with the diagonal `diagonal` and no pairs (all convex where it is
    /// non-negative).
    pub fn diagonal(diagonal: &[f64]) -> Self {
        let n = diagonal.len();
        LawHessian {
            diagonal: diagonal.to_vec(),
            coupling: vec![0.0; n],
            convex_diagonal: diagonal.iter().map(|e| e.max(0.0)).collect(),
            convex_coupling: vec![0.0; n],
            partner: vec![None; n],
            pair: vec![(0.0, 0.0, [1.0, 0.0]); n],
        }
    }

    /// The laws' Hessian on the free rows at r. A pair's block is a n nᵀ + b (I − n nᵀ), n the
    /// unit vector of the pair, a = w j''(ρ) along it and b = w j'(ρ)/ρ across it (the slip
    /// direction's turning stiffness; w j''(0) at ρ = 0, where the smoothed law is isotropic);
    /// convexified, a and b each by max(·, 0) (docs/method.md §17.3).
    pub fn at(problem: &ContactProblem, r: &[f64], free: &[usize]) -> Self {
        let nf = free.len();
        let mut h = LawHessian::diagonal(&vec![0.0; nf]);
        let mut index = Vec::new();
        if problem.pairs.is_some() {
            index = vec![None; problem.m()];
            for (i, &p) in free.iter().enumerate() {
                index[p] = Some(i);
            }
        }
        for (i, &p) in free.iter().enumerate() {
            match problem.partner(p) {
                None => {
                    let e = problem.laws.stiffness(p, r[p] - problem.origin(p));
                    h.diagonal[i] = e;
                    h.convex_diagonal[i] = e.max(0.0);
                }
                Some(q) => {
                    let (x, rho) = problem.pair_at(r, p, q);
                    let a = problem.laws.stiffness(p, rho);
                    let (b, n) = if rho > 0.0 {
                        (problem.laws.force(p, rho) / rho, [x[0] / rho, x[1] / rho])
                    } else {
                        (a, [1.0, 0.0])
                    };
                    h.set_pair_row(i, (a, b, n));
                    h.partner[i] = index[q];
                }
            }
        }
        h
    }

    /// Row i of a pair with the block a nnᵀ + b (I − nnᵀ), seen from its side (n's first
    /// component its own).
    pub fn set_pair_row(&mut self, i: usize, (a, b, n): (f64, f64, [f64; 2])) {
        (self.diagonal[i], self.coupling[i]) = pair_block(a, b, n);
        (self.convex_diagonal[i], self.convex_coupling[i]) = pair_block(a.max(0.0), b.max(0.0), n);
        self.pair[i] = (a, b, n);
    }

    /// Whether any row is curved or paired (the system in W has rows then, docs/method.md §9.7).
    pub fn is_curved(&self) -> bool {
        self.diagonal.iter().any(|&h| h != 0.0) || self.partner.iter().any(Option::is_some)
    }
}
