//! The unmodified columns of a step matrix at chosen prescribed unknowns (docs/method.md §7.2,
//! §7.7): what lifts prescribed values, and what the rigid parameters' reactions are made of.
//! Apart from the operator so that the operator and the rigid parameters both read it.

use crate::fem::SymmetricMatrix;

/// The columns of the prescribed unknowns of an unmodified matrix (all rows): what the
/// prescribed part of the system contributes (docs/method.md §7).
pub(super) struct PrescribedColumns {
    /// (prescribed unknown j, its column entries (i, K_ij)).
    pub(super) columns: Vec<(usize, Vec<(usize, f64)>)>,
}

impl PrescribedColumns {
    pub(super) fn new<const D: usize>(matrix: &SymmetricMatrix, dofs: &crate::fem::DofMap<D>) -> Self {
        Self::of(matrix, (0..matrix.n()).filter(|&j| dofs.is_prescribed(j)))
    }

    /// The columns of `unknowns`, in their order.
    pub(super) fn of(matrix: &SymmetricMatrix, unknowns: impl Iterator<Item = usize>) -> Self {
        let columns = unknowns.map(|j| (j, matrix.column(j).collect())).collect();
        PrescribedColumns { columns }
    }

    /// Every column times `ratio` (the step matrix rescaled, docs/method.md §20.3).
    pub(super) fn scale(&mut self, ratio: f64) {
        for (_, col) in &mut self.columns {
            col.iter_mut().for_each(|(_, v)| *v *= ratio);
        }
    }

    /// The number of columns.
    pub(super) fn len(&self) -> usize {
        self.columns.len()
    }

    /// rhs_i −= Σ_j K_ij over the columns `range` at the free rows i: the lifting of the value 1
    /// at those unknowns.
    pub(super) fn lift_unit<const D: usize>(
        &self,
        range: std::ops::Range<usize>,
        dofs: &crate::fem::DofMap<D>,
        rhs: &mut [f64],
    ) {
        for (_, col) in &self.columns[range] {
            for &(i, v) in col {
                if !dofs.is_prescribed(i) {
                    rhs[i] -= v;
                }
            }
        }
    }

    /// rhs_i −= Σ_j K_ij g_j at the free rows i.
    pub(super) fn lift<const D: usize>(&self, g: &[f64], dofs: &crate::fem::DofMap<D>, rhs: &mut [f64]) {
        for (j, col) in &self.columns {
            if g[*j] != 0.0 {
                for &(i, v) in col {
                    if !dofs.is_prescribed(i) {
                        rhs[i] -= v * g[*j];
                    }
                }
            }
        }
    }

    /// (K x)_j at each prescribed j, added into `out` (indexed like the columns).
    pub(super) fn add_product(&self, x: &[f64], out: &mut [f64]) {
        for ((_, col), o) in self.columns.iter().zip(out.iter_mut()) {
            *o += col.iter().map(|&(i, v)| v * x[i]).sum::<f64>();
        }
    }
}
