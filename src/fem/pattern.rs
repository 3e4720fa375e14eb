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
    /// Builds the pattern of the element dof couplings. Both components of a node are free or
    /// both clamped, and free nodes are numbered in order (unknowns 2k, 2k + 1 for free node
    /// k), so the pattern is built on nodes and expanded to 2 × 2 blocks: column 2k + c holds
    /// the rows 2q, 2q + 1 of every free node q coupled with k, in order.
    pub fn new(cells: &[Cell], dofs: &DofMap) -> Self {
        let n = dofs.n_free();
        let free_node = |p: usize| {
            let d = dofs.raw(p, 0);
            (d != usize::MAX).then_some(d / 2)
        };
        // Node adjacency (including the node itself), sorted.
        let mut adjacency: Vec<Vec<usize>> = vec![Vec::new(); n / 2];
        let mut local: Vec<Option<usize>> = Vec::with_capacity(4);
        for cell in cells {
            local.clear();
            local.extend(cell.nodes().iter().map(|&p| free_node(p)));
            for a in local.iter().flatten() {
                adjacency[*a].extend(local.iter().flatten());
            }
        }
        for list in &mut adjacency {
            list.sort_unstable();
            list.dedup();
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(adjacency.iter().map(|l| 4 * l.len()).sum());
        for list in &adjacency {
            for _component in 0..2 {
                row_idx.extend(list.iter().flat_map(|&q| [2 * q, 2 * q + 1]));
                col_ptr.push(row_idx.len());
            }
        }
        // Scatter: local entry (i, j) = (node b comp c', node a comp c) sits at
        // col_ptr[2·a + c] + 2·(position of b in adjacency[a]) + c'.
        let mut scatter = Vec::with_capacity(cells.iter().map(|c| 4 * c.nodes().len().pow(2)).sum());
        let mut scatter_offset = Vec::with_capacity(cells.len() + 1);
        scatter_offset.push(0);
        for cell in cells {
            local.clear();
            local.extend(cell.nodes().iter().map(|&p| free_node(p)));
            let nl = 2 * local.len();
            let start = scatter.len();
            scatter.resize(start + nl * nl, usize::MAX);
            let block = &mut scatter[start..];
            for (ja, a) in local.iter().enumerate() {
                let Some(a) = *a else { continue };
                for (ib, b) in local.iter().enumerate() {
                    let Some(b) = *b else { continue };
                    let k = adjacency[a]
                        .binary_search(&b)
                        .expect("pattern holds every element coupling");
                    for c in 0..2 {
                        for c2 in 0..2 {
                            // row-major over local dofs: (i, j) at i·nl + j
                            block[(2 * ib + c2) * nl + 2 * ja + c] = col_ptr[2 * a + c] + 2 * k + c2;
                        }
                    }
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

/// The node graph of a pattern made of 2 × 2 node blocks — unknowns 2k, 2k + 1 of node k
/// with one shared column pattern of row pairs (2q, 2q + 1), as [`Pattern::new`] builds it.
/// Entry p of [`NodeGraph::coupled`]`(k)` is node q, whose rows 2q, 2q + 1 sit at positions
/// `col_ptr[2k] + 2p` (+1) of column 2k and `col_ptr[2k + 1] + 2p` (+1) of column 2k + 1.
#[derive(Clone, Debug)]
pub struct NodeGraph {
    /// Node k couples with `nodes[ptr[k]..ptr[k + 1]]` (ascending, itself included).
    pub ptr: Vec<usize>,
    pub nodes: Vec<usize>,
}

impl NodeGraph {
    /// The node graph of `pattern`, or None if it is not made of 2 × 2 node blocks (odd
    /// order, the two unknowns of a node with different patterns, or rows not in pairs).
    pub fn of(pattern: SymbolicSparseColMatRef<'_, usize>) -> Option<Self> {
        let n = pattern.nrows();
        if n % 2 != 0 {
            return None;
        }
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let mut graph = NodeGraph {
            ptr: Vec::with_capacity(n / 2 + 1),
            nodes: Vec::with_capacity(row_idx.len() / 4),
        };
        graph.ptr.push(0);
        for k in 0..n / 2 {
            let first = &row_idx[col_ptr[2 * k]..col_ptr[2 * k + 1]];
            if first != &row_idx[col_ptr[2 * k + 1]..col_ptr[2 * k + 2]] || first.len() % 2 != 0 {
                return None;
            }
            for pair in first.chunks_exact(2) {
                if pair[0] % 2 != 0 || pair[1] != pair[0] + 1 {
                    return None;
                }
                graph.nodes.push(pair[0] / 2);
            }
            graph.ptr.push(graph.nodes.len());
        }
        Some(graph)
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.ptr.len() - 1
    }

    /// True if there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The nodes node k couples with, ascending.
    pub fn coupled(&self, k: usize) -> &[usize] {
        &self.nodes[self.ptr[k]..self.ptr[k + 1]]
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
