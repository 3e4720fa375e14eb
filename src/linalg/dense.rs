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

/// A dense Cholesky factorisation L Lᵀ in place, in a buffer kept from one factorisation to the
/// next: the contact solve factors a new matrix of about the same order at every Newton
/// iteration, and a fresh allocation each time (n² numbers, tens of MB) cost page faults worth
/// a third of the 3D friction solve's time (docs/method.md §4.6). A cache: a clone starts empty.
#[derive(Debug, Default)]
pub struct FactorBuffer {
    n: usize,
    values: Vec<f64>,
}

impl Clone for FactorBuffer {
    fn clone(&self) -> Self {
        FactorBuffer::default()
    }
}

impl FactorBuffer {
    /// Factors the symmetric n × n matrix whose lower triangle `fill` writes into a zeroed
    /// column-major slice (column j at j n..(j + 1) n); false if it is not (numerically)
    /// positive definite.
    pub fn factor(&mut self, n: usize, fill: impl FnOnce(&mut [f64])) -> bool {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
        self.n = n;
        self.values.clear();
        self.values.resize(n * n, 0.0);
        fill(&mut self.values);
        let par = faer::Par::Seq;
        let mut scratch = MemBuffer::new(cholesky_in_place_scratch::<f64>(n, par, Default::default()));
        let a = MatMut::from_column_major_slice_mut(&mut self.values, n, n);
        cholesky_in_place(
            a,
            Default::default(),
            par,
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .is_ok()
    }

    /// x ← A⁻¹ x for the matrix last factored.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
        let l = faer::MatRef::from_column_major_slice(&self.values, self.n, self.n);
        let mut rhs = MatMut::from_column_major_slice_mut(x, self.n, 1);
        solve_lower_triangular_in_place(l, rhs.as_mut(), faer::Par::Seq);
        solve_upper_triangular_in_place(l.transpose(), rhs, faer::Par::Seq);
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
