//! A symmetric sparse matrix in compressed-column form whose pattern is built once from the
//! mesh, with a precomputed scatter map from each cell's local matrix into the value array.
//! Every matrix of a run (K_A, K_B, K = K_A + c·K_B) shares the pattern, so re-assembly and
//! linear combinations are plain loops over values.

use super::dofs::DofMap;
use crate::mesh::Cell;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use std::sync::Arc;

/// The pattern: full symmetric storage (both triangles), rows sorted in each column.
#[derive(Debug)]
pub struct Pattern {
    pub n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    /// For cell e and local pair (i, j) of its 2·n_local element dofs: the position of that
    /// entry in the value array, or `usize::MAX` if either dof is constrained.
    scatter: Vec<usize>,
    scatter_offset: Vec<usize>,
}

impl Pattern {
    /// Builds the pattern of the element dof couplings.
    pub fn new(cells: &[Cell], dofs: &DofMap) -> Self {
        let n = dofs.n_free();
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut local = Vec::with_capacity(8);
        for cell in cells {
            element_dofs(cell, dofs, &mut local);
            for &j in local.iter().filter(|d| **d != usize::MAX) {
                for &i in local.iter().filter(|d| **d != usize::MAX) {
                    cols[j].push(i);
                }
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        for c in cols.iter_mut() {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let mut scatter = Vec::new();
        let mut scatter_offset = Vec::with_capacity(cells.len() + 1);
        scatter_offset.push(0);
        for cell in cells {
            element_dofs(cell, dofs, &mut local);
            for &j in &local {
                for &i in &local {
                    let pos = if i == usize::MAX || j == usize::MAX {
                        usize::MAX
                    } else {
                        let col = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                        col_ptr[j] + col.binary_search(&i).expect("pattern holds every element coupling")
                    };
                    scatter.push(pos);
                }
            }
            scatter_offset.push(scatter.len());
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Pattern {
            n,
            symbolic,
            scatter,
            scatter_offset,
        }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// The scatter positions of cell `e` (row-major over its local dofs).
    pub fn cell_scatter(&self, e: usize) -> &[usize] {
        &self.scatter[self.scatter_offset[e]..self.scatter_offset[e + 1]]
    }

    /// faer's view of the pattern.
    pub fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        self.symbolic.as_ref()
    }
}

/// The free-dof indices of a cell's local dofs, ordered (node a, component c) → 2a + c;
/// constrained ones are `usize::MAX`.
pub fn element_dofs(cell: &Cell, dofs: &DofMap, out: &mut Vec<usize>) {
    out.clear();
    for &p in cell.nodes() {
        out.push(dofs.raw(p, 0));
        out.push(dofs.raw(p, 1));
    }
}

/// A symmetric matrix on a shared [`Pattern`].
#[derive(Clone, Debug)]
pub struct SymmetricMatrix {
    pub pattern: Arc<Pattern>,
    pub values: Vec<f64>,
}

impl SymmetricMatrix {
    /// The zero matrix on `pattern`.
    pub fn zeros(pattern: Arc<Pattern>) -> Self {
        let nnz = pattern.nnz();
        SymmetricMatrix {
            pattern,
            values: vec![0.0; nnz],
        }
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.pattern.n
    }

    /// `self + c·other` on the same pattern.
    pub fn plus_scaled(&self, c: f64, other: &SymmetricMatrix) -> SymmetricMatrix {
        assert!(
            Arc::ptr_eq(&self.pattern, &other.pattern),
            "matrices must share a pattern"
        );
        let values = self.values.iter().zip(&other.values).map(|(a, b)| a + c * b).collect();
        SymmetricMatrix {
            pattern: self.pattern.clone(),
            values,
        }
    }

    /// y = A x (full symmetric storage, so column j is row j).
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        let sym = self.pattern.symbolic();
        let (cp, ri) = (sym.col_ptr(), sym.row_idx());
        y.par_chunks_mut(4096).enumerate().for_each(|(chunk, ys)| {
            for (k, yj) in ys.iter_mut().enumerate() {
                let j = chunk * 4096 + k;
                let mut s = 0.0;
                for q in cp[j]..cp[j + 1] {
                    s += self.values[q] * x[ri[q]];
                }
                *yj = s;
            }
        });
    }

    /// faer's view of the matrix.
    pub fn as_faer(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(self.pattern.symbolic(), &self.values)
    }

    /// Diagonal entries.
    pub fn diagonal(&self) -> Vec<f64> {
        let sym = self.pattern.symbolic();
        (0..self.n())
            .map(|j| {
                let rows = &sym.row_idx()[sym.col_ptr()[j]..sym.col_ptr()[j + 1]];
                rows.binary_search(&j)
                    .map_or(0.0, |k| self.values[sym.col_ptr()[j] + k])
            })
            .collect()
    }
}
