//! The trailing block of the factor (docs/method.md §9.4). With k unknowns ordered after all
//! others ([`Factor::analyse_with_last`]), L = [L₁₁ 0; L_c1 L_cc] and the Schur complement of K
//! on those unknowns is S = L_cc L_ccᵀ, its inverse (K⁻¹ restricted to them) L_cc⁻ᵀ L_cc⁻¹. The
//! condensation reads both off L_cc by dense kernels (faer's, on every thread of the run's pool:
//! these are large dense products, like the factor's big supernodes) instead of forming
//! G = L⁻¹PCᵀ by sparse sweeps.

use super::factor::{Factor, Forward};
use faer::linalg::matmul::triangular::{matmul, BlockStructure};
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Accum, MatMut, MatRef, Par};

/// L_cc, dense (k × k, column-major, lower triangle; zeros above).
pub struct TrailingBlock {
    k: usize,
    /// The factor's position of the block's first unknown (n − k).
    offset: usize,
    l: Vec<f64>,
}

/// The thread count of the dense products: the run's pool.
fn par() -> Par {
    match rayon::current_num_threads() {
        0 | 1 => Par::Seq,
        t => Par::rayon(t),
    }
}

impl TrailingBlock {
    /// Copies the last k columns of L (k: how many unknowns the analysis ordered last; None when
    /// none was). A column's rows in the factor are its supernode's rows from the column on,
    /// all inside the trailing block.
    fn of(factor: &Factor) -> Option<Self> {
        let (values, supernodes) = (factor.values(), factor.analysis().supernodes());
        let (n, k) = (factor.n(), factor.analysis().ordered_last());
        if k == 0 {
            return None;
        }
        let offset = n - k;
        let mut l = Vec::new();
        crate::alloc::fallible(|| l.try_reserve_exact(k * k)).ok()?;
        l.resize(k * k, 0.0);
        for j in offset..n {
            let s = supernodes.supernode_of[j];
            let (start, width, rows) = (supernodes.start[s], supernodes.width[s], supernodes.rows(s));
            let local = j - start;
            let column = &supernodes.block(values, s)[local * rows..(local + 1) * rows];
            let out = &mut l[(j - offset) * k..(j - offset + 1) * k];
            for (r, &v) in column.iter().enumerate().take(width).skip(local) {
                out[start + r - offset] = v;
            }
            for (&row, &v) in supernodes.pattern(s).iter().zip(&column[width..]) {
                out[row - offset] = v;
            }
        }
        Some(TrailingBlock { k, offset, l })
    }

    /// k, the block's order.
    pub fn len(&self) -> usize {
        self.k
    }

    /// True if the block is empty (never: a block has k ≥ 1).
    pub fn is_empty(&self) -> bool {
        self.k == 0
    }

    /// The block's position of original unknown i (None if it is not in the block).
    pub fn position(&self, factor: &Factor, i: usize) -> Option<usize> {
        factor.position(i).checked_sub(self.offset)
    }

    fn l(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.l, self.k, self.k)
    }

    /// S = L_cc L_ccᵀ, the Schur complement of K on the block's unknowns (k × k, symmetric,
    /// both triangles): k³/3 multiply–adds.
    pub fn schur_complement(&self) -> Vec<f64> {
        self.gram(false)
    }

    /// S⁻¹ = L_cc⁻ᵀ L_cc⁻¹ (k × k, symmetric, both triangles): K⁻¹ restricted to the block's
    /// unknowns. A triangular inverse and a triangular product: 2k³/3 multiply–adds.
    pub fn schur_inverse(&self) -> Vec<f64> {
        self.gram(true)
    }

    fn gram(&self, inverse: bool) -> Vec<f64> {
        let k = self.k;
        let inverted;
        let l = if inverse {
            let mut inv = vec![0.0; k * k];
            faer::linalg::triangular_inverse::invert_lower_triangular(
                MatMut::from_column_major_slice_mut(&mut inv, k, k),
                self.l(),
                par(),
            );
            inverted = inv;
            MatRef::from_column_major_slice(&inverted, k, k)
        } else {
            self.l()
        };
        // L Lᵀ, or with L⁻¹ in place of L: (L⁻¹)ᵀ L⁻¹
        let (lhs, lhs_s, rhs, rhs_s) = if inverse {
            (
                l.transpose(),
                BlockStructure::TriangularUpper,
                l,
                BlockStructure::TriangularLower,
            )
        } else {
            (
                l,
                BlockStructure::TriangularLower,
                l.transpose(),
                BlockStructure::TriangularUpper,
            )
        };
        let mut out = vec![0.0; k * k];
        matmul(
            MatMut::from_column_major_slice_mut(&mut out, k, k),
            BlockStructure::TriangularLower,
            Accum::Replace,
            lhs,
            lhs_s,
            rhs,
            rhs_s,
            1.0,
            par(),
        );
        for j in 0..k {
            for i in j + 1..k {
                out[i * k + j] = out[j * k + i];
            }
        }
        out
    }

    /// The block's part of a forward-swept vector (its last k entries).
    pub fn part<'y>(&self, y: &'y Forward) -> &'y [f64] {
        &y.values[self.offset..]
    }

    /// [`Self::part`], writable.
    pub fn part_mut<'y>(&self, y: &'y mut Forward) -> &'y mut [f64] {
        &mut y.values[self.offset..]
    }

    /// x ← L_cc⁻¹ x.
    pub fn solve_lower(&self, x: &mut [f64]) {
        solve_lower_triangular_in_place(self.l(), MatMut::from_column_major_slice_mut(x, self.k, 1), Par::Seq);
    }

    /// x ← L_cc⁻ᵀ x.
    pub fn solve_upper(&self, x: &mut [f64]) {
        solve_upper_triangular_in_place(
            self.l().transpose(),
            MatMut::from_column_major_slice_mut(x, self.k, 1),
            Par::Seq,
        );
    }
}

impl Factor {
    /// L_cc, the block of the unknowns ordered last (None when none was, or when k² numbers
    /// cannot be allocated).
    pub fn trailing_block(&self) -> Option<TrailingBlock> {
        TrailingBlock::of(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::sparse::test_matrices::grid_stiffness;
    use crate::linalg::Counters;

    #[test]
    fn the_trailing_block_gives_the_schur_complement_and_its_inverse() {
        let k_mat = grid_stiffness(6, 5, true);
        let n = k_mat.n();
        let last = [4, 17, 20, 31, 45, 46, 59];
        let analysis = Factor::analyse_with_last(&k_mat, &last).unwrap();
        let factor = Factor::new(&analysis, &k_mat, &Counters::default()).unwrap();
        let block = factor.trailing_block().unwrap();
        assert_eq!(block.len(), last.len());
        let k = last.len();
        // K⁻¹ restricted to `last`, by whole solves
        let mut inv = vec![0.0; k * k];
        for &j in &last {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            factor.solve_in_place(&mut e, &Counters::default());
            for &i in &last {
                inv[block.position(&factor, i).unwrap() * k + block.position(&factor, j).unwrap()] = e[i];
            }
        }
        let s_inv = block.schur_inverse();
        let s = block.schur_complement();
        for i in 0..k {
            for j in 0..k {
                assert!((s_inv[i * k + j] - inv[i * k + j]).abs() < 1e-13, "S⁻¹ ({i}, {j})");
                // S S⁻¹ = I
                let e: f64 = (0..k).map(|l| s[i * k + l] * inv[l * k + j]).sum();
                assert!(
                    (e - f64::from(u8::from(i == j))).abs() < 1e-12,
                    "S S⁻¹ ({i}, {j}) = {e}"
                );
            }
        }
        // the per-step path: y_c of a forward sweep, x_c = L_cc⁻ᵀ y_c is the solve's block part
        let r: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut y = factor.forward(&r);
        let mut x_c = block.part(&y).to_vec();
        block.solve_upper(&mut x_c);
        let mut x = vec![0.0; n];
        factor.backward_from(&mut y, &mut x, &Counters::default());
        for &i in &last {
            assert!((x_c[block.position(&factor, i).unwrap()] - x[i]).abs() < 1e-13);
        }
        // and L_cc⁻¹ undoes what L_cc does
        let mut z = x_c.clone();
        block.solve_lower(&mut z);
        for j in (0..k).rev() {
            let lz: f64 = (0..=j).map(|i| block.l[i * k + j] * z[i]).sum();
            assert!((lz - x_c[j]).abs() < 1e-13);
        }
    }
}
