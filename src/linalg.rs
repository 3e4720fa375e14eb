//! The cached sparse Cholesky factor of a symmetric positive definite matrix (METHOD.md §3):
//! symbolic analysis with AMD ordering once, numeric factorisation once per distinct matrix,
//! and counted solves against it.

use crate::fem::SymmetricMatrix;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::{MatMut, Par, Side};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Why a factorisation failed.
#[derive(Debug, thiserror::Error)]
pub enum FactorError {
    #[error("the stiffness matrix is not positive definite (pivot failed in the Cholesky factorisation); usually the body is not held: check that the clamped group has nodes and that they stop rigid motions")]
    NotPositiveDefinite,
    #[error("sparse Cholesky failed: {0}")]
    Other(String),
}

/// How many numeric factorisations and solves a run performed (exposed in `summary.json`
/// and used by tests to check that effects a scene does not name cost nothing).
#[derive(Debug, Default)]
pub struct Counters {
    pub factorisations: AtomicUsize,
    pub solves: AtomicUsize,
}

impl Counters {
    pub fn factorisations(&self) -> usize {
        self.factorisations.load(Ordering::Relaxed)
    }
    pub fn solves(&self) -> usize {
        self.solves.load(Ordering::Relaxed)
    }
}

/// Parallelism for factorisation and solves. On 2 cores `Seq` measured faster (STACK.md).
pub fn set_parallelism(threads: usize) {
    faer::set_global_parallelism(if threads <= 1 { Par::Seq } else { Par::rayon(threads) });
}

/// A cached Cholesky factor K = L Lᵀ (with fill-reducing permutation).
pub struct Factor {
    llt: Llt<usize, f64>,
    n: usize,
}

impl Factor {
    /// Symbolic analysis of the pattern of `matrix` (reusable for every matrix on it).
    pub fn analyse(matrix: &SymmetricMatrix) -> Result<SymbolicLlt<usize>, FactorError> {
        SymbolicLlt::try_new(matrix.pattern.symbolic(), Side::Lower).map_err(|e| FactorError::Other(format!("{e:?}")))
    }

    /// Numeric factorisation of `matrix` with a symbolic analysis of its pattern.
    pub fn new(
        symbolic: &SymbolicLlt<usize>,
        matrix: &SymmetricMatrix,
        counters: &Counters,
    ) -> Result<Self, FactorError> {
        counters.factorisations.fetch_add(1, Ordering::Relaxed);
        let llt = Llt::try_new_with_symbolic(symbolic.clone(), matrix.as_faer(), Side::Lower).map_err(|e| match e {
            faer::sparse::linalg::LltError::Numeric(_) => FactorError::NotPositiveDefinite,
            other => FactorError::Other(format!("{other:?}")),
        })?;
        Ok(Factor { llt, n: matrix.n() })
    }

    /// Order of the factored matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// x ← K⁻¹ x.
    pub fn solve_in_place(&self, x: &mut [f64], counters: &Counters) {
        counters.solves.fetch_add(1, Ordering::Relaxed);
        let n = x.len();
        let mat = MatMut::from_column_major_slice_mut(x, n, 1);
        self.llt.solve_in_place(mat);
    }

    /// X ← K⁻¹ X for a block of right-hand sides (counted as one solve per column).
    pub fn solve_block_in_place(&self, x: MatMut<'_, f64>, counters: &Counters) {
        counters.solves.fetch_add(x.ncols(), Ordering::Relaxed);
        self.llt.solve_in_place(x);
    }
}
