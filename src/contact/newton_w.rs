//! The contact solve's Newton system written with W instead of Q (docs/method.md §4.6).
//!
//! The projected Newton step of docs/method.md §4.4 solves (Q_ℐℐ + H) Δ = g on the free rows ℐ,
//! the rows 𝒜 = the rest held at their bound, and H ≥ 0 the laws' curvature: diagonal, with
//! 2 × 2 blocks on 3D friction's pairs. Write H = Σ_k h_k e_k e_kᵀ over its directions of
//! positive curvature (a row, or an eigenvector of a pair's block) and B = [e_1 … e_K | I_𝒜],
//! the directions beside the held rows (m × (K + |𝒜|)). With Q = W⁻¹,
//!
//! ```text
//!     (BᵀWB + diag(1/h_1, …, 1/h_K, 0, …, 0)) y = BᵀW ĝ,     Δ = (W (ĝ − B y))_ℐ,
//! ```
//!
//! ĝ the right-hand side spread over ℐ (0 on 𝒜). The matrix is symmetric positive definite
//! (W is, B has full column rank), its entries are W's own (a pair's direction combines two
//! rows), and it has K + |𝒜| rows instead of |ℐ|: the free rows without curvature (a separated
//! normal row, the tangential rows of a node without a friction bound) drop out, as they do
//! from the dual problem in the contact forces. Nothing computed is kept between directions,
//! only the storage of the factorisation (`FactorBuffer`).
//!
//! Derivation: with z = W⁻¹ x, x = Δ on ℐ and 0 on 𝒜, Q_ℐℐ Δ = z_ℐ, so the system is
//! z_ℐ + H Δ = g, i.e. z_ℐ = g − Σ_k e_k η_k with η_k = h_k e_kᵀΔ; W z = x reads
//! e_kᵀ(W z) = η_k / h_k and (W z)_𝒜 = 0, and with y = (η, −z_𝒜) that is the system above.

use crate::linalg::dense::{matvec_row_major, FactorBuffer};

/// A direction of positive curvature h of the laws' Hessian: rows (the second usize::MAX for a
/// single row) and the unit vector's components on them. A pair with both directions curved
/// is two single rows coupled by its 2 × 2 block of H⁻¹.
#[derive(Clone, Copy, Debug)]
pub struct Curvature {
    pub rows: [usize; 2],
    pub along: [f64; 2],
    /// (H⁻¹) on the direction (0 for a row held at its bound).
    pub inverse: f64,
    /// The index of the direction coupled to this one by H⁻¹ (usize::MAX: none) and (H⁻¹)
    /// between them.
    pub partner: usize,
    pub coupling: f64,
}

impl Curvature {
    /// Row p, 1/h on it.
    pub fn row(p: usize, inverse: f64) -> Self {
        Curvature {
            inverse,
            ..Curvature::held(p)
        }
    }

    /// A pair's direction e on rows p, q, 1/h along it.
    pub fn pair(rows: [usize; 2], along: [f64; 2], inverse: f64) -> Self {
        Curvature {
            rows,
            along,
            inverse,
            partner: usize::MAX,
            coupling: 0.0,
        }
    }

    /// eᵀWe: the compliance along the direction.
    pub fn compliance(&self, w: &[f64], m: usize) -> f64 {
        self.entries()
            .flat_map(|(p, a)| self.entries().map(move |(q, b)| a * b * w[p * m + q]))
            .sum()
    }

    /// A held row: infinite curvature.
    fn held(p: usize) -> Self {
        Curvature {
            rows: [p, usize::MAX],
            along: [1.0, 0.0],
            inverse: 0.0,
            partner: usize::MAX,
            coupling: 0.0,
        }
    }

    /// (row, component) pairs.
    fn entries(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.rows
            .iter()
            .zip(self.along)
            .filter(|(&p, _)| p != usize::MAX)
            .map(|(&p, e)| (p, e))
    }
}

/// Whether the system in W is cheaper than a dense factorisation of the |ℐ| rows of Q_ℐℐ + H:
/// at most half its flops (a factorisation of K + |𝒜| rows and two products by W).
pub fn pays(m: usize, free: usize, directions: usize) -> bool {
    let n = (directions + m - free) as f64;
    let primal = (free as f64).powi(3) / 3.0;
    n.powi(3) / 3.0 + 4.0 * (m * m) as f64 <= 0.5 * primal
}

/// Δ on ℐ with (Q_ℐℐ + H) Δ = g, for W (row-major m × m, Q = W⁻¹ exactly) and H given by its
/// directions of positive curvature; None if the system is not numerically positive definite
/// (the caller solves in Q).
pub fn direction(
    (w, m): (&[f64], usize),
    free: &[usize],
    curvature: &[Curvature],
    g: &[f64],
    buffer: &mut FactorBuffer,
) -> Option<Vec<f64>> {
    let mut spread = vec![0.0; m];
    let mut is_free = vec![false; m];
    for (&p, v) in free.iter().zip(g) {
        spread[p] = *v;
        is_free[p] = true;
    }
    let columns: Vec<Curvature> = curvature
        .iter()
        .copied()
        .chain((0..m).filter(|&p| !is_free[p]).map(Curvature::held))
        .collect();
    let mut wg = vec![0.0; m];
    matvec_row_major(w, m, &spread, &mut wg);
    let n = columns.len();
    // BᵀWB + the inverse curvatures, lower triangle, column by column: column l reads the rows
    // of W of its direction (a single row's second is its first with weight 0: no branch)
    let first: Vec<usize> = columns.iter().map(|c| c.rows[0]).collect();
    let second: Vec<usize> = columns
        .iter()
        .map(|c| if c.rows[1] == usize::MAX { c.rows[0] } else { c.rows[1] })
        .collect();
    let weights: Vec<[f64; 2]> = columns
        .iter()
        .map(|c| if c.rows[1] == usize::MAX { [1.0, 0.0] } else { c.along })
        .collect();
    let fill = |matrix: &mut [f64]| {
        for (l, column) in matrix.chunks_exact_mut(n.max(1)).enumerate() {
            for (row, a) in [(first[l], weights[l][0]), (second[l], weights[l][1])] {
                if a == 0.0 {
                    continue;
                }
                let row = &w[row * m..(row + 1) * m];
                for k in l..n {
                    column[k] += a * (weights[k][0] * row[first[k]] + weights[k][1] * row[second[k]]);
                }
            }
            column[l] += columns[l].inverse;
            if columns[l].partner != usize::MAX && columns[l].partner > l {
                column[columns[l].partner] += columns[l].coupling;
            }
        }
    };
    let factor = buffer.factor(n, fill)?;
    let mut y: Vec<f64> = columns
        .iter()
        .map(|c| c.entries().map(|(p, a)| a * wg[p]).sum())
        .collect();
    factor.solve_in_place(&mut y);
    buffer.recycle(factor);
    for (c, v) in columns.iter().zip(&y) {
        for (p, a) in c.entries() {
            spread[p] -= a * v;
        }
    }
    matvec_row_major(w, m, &spread, &mut wg);
    Some(free.iter().map(|&p| wg[p]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::dense::DenseCholesky;

    /// The direction in W against the dense solve of (Q_ℐℐ + H) Δ = g, Q = W⁻¹: W a smooth
    /// kernel on m rows, a quarter of them held (𝒜), H with single rows, pairs by their two
    /// eigendirections, by one, and by their two rows coupled by H⁻¹, and rows without
    /// curvature. To 1e-10 of Δ; and with no curvature and nothing held, Δ = W g.
    #[test]
    fn the_direction_in_w_solves_the_newton_system_in_q() {
        let m = 48;
        let x = |p: usize| (p as f64 / m as f64).sqrt();
        let w: Vec<f64> = (0..m * m)
            .map(|k| {
                let (p, q) = (k / m, k % m);
                (-(x(p) - x(q)).abs() / 0.2).exp() + if p == q { 0.02 } else { 0.0 }
            })
            .collect();
        let q = DenseCholesky::new(m, |i, j| w[i * m + j]).unwrap().symmetric_inverse();
        let free: Vec<usize> = (0..m).filter(|p| p % 4 != 1).collect();
        let nf = free.len();
        // H on ℐ: free rows 0..6 single, 6 and 7 a pair with both directions, 8 and 9 a pair
        // with one, the rest 0
        let mut h = vec![0.0; nf * nf];
        let mut curvature = Vec::new();
        for i in 0..6 {
            h[i * nf + i] = 0.5 + i as f64;
            curvature.push(Curvature::row(free[i], 1.0 / h[i * nf + i]));
        }
        let mut pair = |i: usize, (a, b): (f64, f64), n: [f64; 2]| {
            let t = [-n[1], n[0]];
            for (c, e) in [(a, n), (b, t)] {
                for (r, s) in [(i, i), (i, i + 1), (i + 1, i), (i + 1, i + 1)] {
                    h[r * nf + s] += c * e[r - i] * e[s - i];
                }
                if c > 0.0 {
                    curvature.push(Curvature::pair([free[i], free[i + 1]], e, 1.0 / c));
                }
            }
        };
        pair(6, (3.0, 0.2), [0.6, 0.8]);
        pair(8, (0.0, 1.5), [0.8, -0.6]);
        // a pair with both directions as its two rows coupled by H⁻¹: rows 10, 11
        let (a, b, n) = (2.0, 0.7, [0.28f64, 0.96]);
        let (ia, ib) = (1.0 / a, 1.0 / b);
        for (r, s) in [(10, 10), (10, 11), (11, 10), (11, 11)] {
            let (x, y) = (n[r - 10], n[s - 10]);
            h[r * nf + s] = b * f64::from(u8::from(r == s)) + (a - b) * x * y;
        }
        let k = curvature.len();
        let c = (ia - ib) * n[0] * n[1];
        curvature.push(Curvature {
            partner: k + 1,
            coupling: c,
            ..Curvature::row(free[10], ib + (ia - ib) * n[0] * n[0])
        });
        curvature.push(Curvature {
            partner: k,
            coupling: c,
            ..Curvature::row(free[11], ib + (ia - ib) * n[1] * n[1])
        });
        let dense = DenseCholesky::new(nf, |i, j| q[free[i] * m + free[j]] + h[i * nf + j]).unwrap();
        let rhs: Vec<f64> = (0..nf).map(|i| (0.37 * i as f64).sin()).collect();
        let expected = dense.solve(&rhs);
        let got = direction((&w, m), &free, &curvature, &rhs, &mut FactorBuffer::default()).unwrap();
        let scale = expected.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        for (e, g) in expected.iter().zip(&got) {
            assert!((e - g).abs() <= 1e-10 * scale, "{e} against {g}");
        }
        let all: Vec<usize> = (0..m).collect();
        let g: Vec<f64> = (0..m).map(|i| (0.21 * i as f64).cos()).collect();
        let got = direction((&w, m), &all, &[], &g, &mut FactorBuffer::default()).unwrap();
        for (p, v) in got.iter().enumerate() {
            let wg: f64 = (0..m).map(|q| w[p * m + q] * g[q]).sum();
            assert!((v - wg).abs() <= 1e-12 * wg.abs().max(1.0), "{v} against {wg}");
        }
    }
}
