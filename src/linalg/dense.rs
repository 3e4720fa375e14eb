//! Small dense linear algebra for the contact solve (docs/method.md §4, §9.2, §9.7): the Cholesky
//! factor of a symmetric positive definite matrix, small LU factors, and the row-major product by
//! Q. faer does the work; the rest of hvi sees slices.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::{MatMut, MatRef, Par};

/// From this order on a dense factorisation or inverse runs on the run's threads (below it the
/// threads' start-up costs more than they save).
const PARALLEL_FROM: usize = 512;

fn par(n: usize) -> Par {
    if n >= PARALLEL_FROM {
        Par::rayon(0)
    } else {
        Par::Seq
    }
}

/// The dense Cholesky factor L Lᵀ of a symmetric positive definite n × n matrix, L in the lower
/// triangle of a column-major slice.
#[derive(Debug)]
pub struct DenseCholesky {
    n: usize,
    values: Vec<f64>,
}

impl DenseCholesky {
    /// Factors the matrix with entries `a(i, j)` (its lower triangle is read); None if it is not
    /// (numerically) positive definite.
    pub fn new(n: usize, a: impl Fn(usize, usize) -> f64) -> Option<Self> {
        Self::from_lower(n, |column_major| {
            for (j, column) in column_major.chunks_exact_mut(n.max(1)).enumerate() {
                for (i, v) in column.iter_mut().enumerate().skip(j) {
                    *v = a(i, j);
                }
            }
        })
    }

    /// Factors the symmetric n × n matrix whose lower triangle `fill` writes into a zeroed
    /// column-major slice (column j at j n..(j + 1) n); None if it is not (numerically) positive
    /// definite.
    pub fn from_lower(n: usize, fill: impl FnOnce(&mut [f64])) -> Option<Self> {
        use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
        let mut values = vec![0.0; n * n];
        fill(&mut values);
        let mut scratch = MemBuffer::new(cholesky_in_place_scratch::<f64>(n, par(n), Default::default()));
        cholesky_in_place(
            MatMut::from_column_major_slice_mut(&mut values, n, n),
            Default::default(),
            par(n),
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .is_ok()
        .then_some(DenseCholesky { n, values })
    }

    /// The order n.
    pub fn n(&self) -> usize {
        self.n
    }

    fn l(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.values, self.n, self.n)
    }

    /// A⁻¹ b.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        self.solve_in_place(&mut x);
        x
    }

    /// x ← A⁻¹ x.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        self.solve_block(x, 1, Par::Seq);
    }

    /// X ← A⁻¹ X for the n × k column-major X: k right-hand sides at once, so each sweep reads
    /// L once for all of them (blocked, on the run's threads from order 512).
    pub fn solve_columns_in_place(&self, x: &mut [f64], k: usize) {
        self.solve_block(x, k, par(self.n));
    }

    fn solve_block(&self, x: &mut [f64], k: usize, par: Par) {
        use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
        let mut rhs = MatMut::from_column_major_slice_mut(x, self.n, k);
        solve_lower_triangular_in_place(self.l(), rhs.as_mut(), par);
        solve_upper_triangular_in_place(self.l().transpose(), rhs, par);
    }

    /// A⁻¹, row-major: L⁻ᵀ L⁻¹ by faer's triangular inverse and product, its lower triangle
    /// mirrored (exactly symmetric).
    pub fn symmetric_inverse(&self) -> Vec<f64> {
        use faer::linalg::cholesky::llt::inverse::{inverse, inverse_scratch};
        let n = self.n;
        let mut inv = vec![0.0; n * n];
        let mut scratch = MemBuffer::new(inverse_scratch::<f64>(n, par(n)));
        inverse(
            MatMut::from_column_major_slice_mut(&mut inv, n, n),
            self.l(),
            par(n),
            MemStack::new(&mut scratch),
        );
        // column-major lower triangle = row-major upper triangle: mirror it down
        for p in 0..n {
            for q in 0..p {
                inv[p * n + q] = inv[q * n + p];
            }
        }
        inv
    }
}

/// The LU factors (partial pivoting) of a small general k × k matrix (the capacitance matrix of
/// a low-rank update, docs/method.md §9.2).
pub struct DenseLu(faer::linalg::solvers::PartialPivLu<f64>);

impl DenseLu {
    /// Factors the k × k matrix whose column j is `column(j)` written into a slice of k zeros
    /// (built a column at a time into faer's storage, without a call per entry).
    pub fn from_columns(k: usize, mut column: impl FnMut(usize, &mut [f64])) -> Self {
        let mut a = faer::Mat::<f64>::zeros(k, k);
        for j in 0..k {
            column(
                j,
                a.col_mut(j)
                    .try_as_col_major_mut()
                    .expect("a Mat's columns are contiguous")
                    .as_slice_mut(),
            );
        }
        DenseLu(a.partial_piv_lu())
    }

    /// x ← A⁻¹ x.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        use faer::linalg::solvers::Solve;
        let k = x.len();
        self.0.solve_in_place(MatMut::from_column_major_slice_mut(x, k, 1));
    }
}

/// A ← ½(A + Aᵀ) for a row-major n × n matrix: exact symmetry against the round-off of a
/// product that should be symmetric (W = GᵀG, C Z, Q after an update).
pub fn symmetrise_row_major(a: &mut [f64], n: usize) {
    for p in 0..n {
        for q in 0..p {
            let v = 0.5 * (a[p * n + q] + a[q * n + p]);
            a[p * n + q] = v;
            a[q * n + p] = v;
        }
    }
}

/// Copies the lower triangle of the row-major n × n matrix `a` onto its upper one.
pub fn mirror_lower_row_major(a: &mut [f64], n: usize) {
    for p in 0..n {
        for q in 0..p {
            a[q * n + p] = a[p * n + q];
        }
    }
}

/// y = A x for a row-major n × n matrix `a`: faer's SIMD product, on two threads from n = 512
/// (the contact solve's products by Q were its largest cost at m in the thousands).
pub fn matvec_row_major(a: &[f64], n: usize, x: &[f64], y: &mut [f64]) {
    let a = faer::MatRef::from_row_major_slice(a, n, n);
    let par = if n >= 512 { faer::Par::rayon(0) } else { faer::Par::Seq };
    faer::linalg::matmul::matmul(
        faer::ColMut::from_slice_mut(y),
        faer::Accum::Replace,
        a,
        faer::ColRef::from_slice(x),
        1.0,
        par,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric positive definite test matrix: a smooth kernel plus a diagonal shift.
    fn entry(i: usize, j: usize) -> f64 {
        (-(i as f64 - j as f64).abs() / 7.0).exp() + if i == j { 0.5 } else { 0.0 }
    }

    fn residual(n: usize, x: &[f64], b: &[f64]) -> f64 {
        (0..n)
            .map(|i| ((0..n).map(|j| entry(i, j) * x[j]).sum::<f64>() - b[i]).abs())
            .fold(0.0, f64::max)
    }

    /// The inverse, on one thread and (from 512 on) on the run's threads: A A⁻¹ = I to
    /// round-off, and exactly symmetric.
    #[test]
    fn the_symmetric_inverse_inverts() {
        for n in [50, 600] {
            let inverse = DenseCholesky::new(n, entry).unwrap().symmetric_inverse();
            for p in (0..n).step_by(37) {
                let row = &inverse[p * n..(p + 1) * n];
                let e: Vec<f64> = (0..n).map(|i| if i == p { 1.0 } else { 0.0 }).collect();
                assert!(residual(n, row, &e) < 1e-12, "n = {n}, row {p}");
                for (q, v) in row.iter().enumerate() {
                    assert_eq!(v.to_bits(), inverse[q * n + p].to_bits());
                }
            }
        }
    }
}
