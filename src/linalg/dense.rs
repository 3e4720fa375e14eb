//! Small dense linear algebra for the contact solve (docs/method.md §4, §9.2): the Cholesky factor
//! of a symmetric positive definite matrix given entry by entry, and the row-major product by Q.
//! faer does the work; the rest of hvi sees slices.

use faer::linalg::solvers::{DenseSolveCore, Llt, Solve};
use faer::{Mat, MatMut};

/// The dense Cholesky factor L Lᵀ of a symmetric positive definite n × n matrix.
#[derive(Debug)]
pub struct DenseCholesky {
    n: usize,
    llt: Llt<f64>,
}

impl DenseCholesky {
    /// Factors the matrix with entries `a(i, j)` (its lower triangle is read); None if it is not
    /// (numerically) positive definite.
    pub fn new(n: usize, a: impl Fn(usize, usize) -> f64) -> Option<Self> {
        let llt = Mat::<f64>::from_fn(n, n, a).llt(faer::Side::Lower).ok()?;
        Some(DenseCholesky { n, llt })
    }

    /// The order n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// A⁻¹ b.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let rhs = Mat::<f64>::from_fn(self.n, 1, |i, _| b[i]);
        let x = self.llt.solve(&rhs);
        (0..self.n).map(|i| x[(i, 0)]).collect()
    }

    /// x ← A⁻¹ x.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        self.llt
            .solve_in_place(MatMut::from_column_major_slice_mut(x, self.n, 1));
    }

    /// ½(A⁻¹ + A⁻ᵀ), row-major: the inverse, symmetrised against round-off (one n × n copy
    /// beside faer's).
    pub fn symmetric_inverse(&self) -> Vec<f64> {
        let inv = self.llt.inverse();
        let n = self.n;
        (0..n * n)
            .map(|k| 0.5 * (inv[(k / n, k % n)] + inv[(k % n, k / n)]))
            .collect()
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
