//! Sparse linear algebra with one cached Cholesky factor (docs/method.md §3–4, §9).
//!
//! * [`Factor`]: K = Pᵀ L Lᵀ P, symbolic analysis (AMD ordering, supernodal) once, numeric
//!   factorisation once per distinct matrix, and the two halves of a solve apart: the forward
//!   sweep y = L⁻¹ P r ([`Factor::forward`]) and the backward sweep x = Pᵀ L⁻ᵀ y
//!   ([`Factor::backward`]). A vector between the two sweeps has its own type, [`Forward`].
//! * [`ForwardColumns`]: G = L⁻¹ P Cᵀ for a sparse C with few rows (the contact normals),
//!   computed by sparse forward sweeps that touch only the supernodes on each column's path to
//!   the root of the elimination tree. With it, C K⁻¹ r = Gᵀ (L⁻¹ P r) and
//!   K⁻¹ (r − Cᵀ λ) = Pᵀ L⁻ᵀ (L⁻¹ P r − G λ): a contact step costs one forward and one backward
//!   sweep, the cost of a single solve, and W = C K⁻¹ Cᵀ = Gᵀ G.
//! * [`TrailingBlock`]: L_cc, the factor's block of the unknowns ordered last, with the Schur
//!   complement L_cc L_ccᵀ and its inverse as dense products (docs/method.md §9.4).
//!
//! ```
//! use hvi::fem::{assembly::assemble_stiffness, DofMap};
//! use hvi::linalg::{Counters, Factor};
//! use hvi::material::{Elasticity, PlaneModel};
//! use hvi::mesh::structured::{rectangle, CellShape};
//! use hvi::mesh::GroupSelector;
//!
//! let mesh = rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
//! let clamped = mesh.group_nodes(&GroupSelector::Name("Gamma1".into())).unwrap();
//! let dofs = DofMap::<2>::new(mesh.points.len(), &clamped);
//! let elasticity = Elasticity { youngs_modulus: 1.0, poisson_ratio: 0.3, plane: Some(PlaneModel::Stress) };
//! let [k] = assemble_stiffness(&mesh.cells, &mesh.points, &dofs, &[elasticity.tensor()]);
//! let k = k.with_identity_rows(&dofs);
//! let counters = Counters::default();
//! let factor = Factor::new(&Factor::analyse(&k).unwrap(), &k, &counters).unwrap();
//! // K⁻¹ (K 1) = 1
//! let ones = vec![1.0; k.n()];
//! let mut r = vec![0.0; k.n()];
//! k.matvec(&ones, &mut r);
//! let mut x = vec![0.0; k.n()];
//! factor.backward(factor.forward(&r), &mut x, &counters);
//! assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-10));
//! ```

pub mod dense;
mod factor;
mod forward_columns;
mod numeric;
mod schedule;
pub mod sparse;
mod supernodes;
mod trailing;

pub use factor::{decoupled_unknowns, set_parallelism, Analysis, Counters, Factor, FactorError, Forward, NodeOrdering};
pub use forward_columns::{forward_columns_entries, ForwardColumns, BLOCKED_FROM_COLUMNS};
pub use trailing::TrailingBlock;

/// METIS keeps its random state in process globals (GKlib's `random.c`), and a call seeds it and
/// draws from it: two calls at once race, and their orderings differ from run to run (a test
/// thread's nnz(L) moved by 0.4 % on CI). Every METIS call holds this lock.
pub(crate) fn metis_lock() -> std::sync::MutexGuard<'static, ()> {
    static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    METIS.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Solves with a fixed matrix K (docs/method.md §9): the seam a second linear-algebra backend
/// plugs into. The cached faer [`Factor`] is one implementation.
pub trait LinearSolver: Send + Sync {
    /// Order of K.
    fn n(&self) -> usize;
    /// x = K⁻¹ rhs (one counted solve).
    fn solve(&self, rhs: &[f64], x: &mut [f64], counters: &Counters);
    /// B ← K⁻¹ B for `k` right-hand sides stored column-major in `b` (n × k).
    fn solve_many(&self, b: &mut [f64], k: usize, counters: &Counters) {
        let n = self.n();
        let mut x = vec![0.0; n];
        for c in 0..k {
            let col = &mut b[c * n..(c + 1) * n];
            self.solve(col, &mut x, counters);
            col.copy_from_slice(&x);
        }
    }
}

impl LinearSolver for Factor {
    fn n(&self) -> usize {
        Factor::n(self)
    }

    fn solve(&self, rhs: &[f64], x: &mut [f64], counters: &Counters) {
        x.copy_from_slice(rhs);
        self.solve_in_place(x, counters);
    }
}
