//! A symmetric sparse matrix in compressed-column form whose pattern is built once from the
//! elements (the node lists of a mesh's cells); an element's local matrix goes into the value
//! array through [`Pattern::cell_positions`].
//! Every matrix of a run (K_A, K_B, K = K_A + c·K_B) shares the pattern, so re-assembly and
//! linear combinations are plain loops over values.
//!
//! The pattern is built on nodes and expanded to D × D node blocks (unknowns D·k + c of node
//! k, docs/method.md §7): the block size is part of the pattern, so the ordering and the
//! node-block product know it without guessing.

use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use std::sync::Arc;

/// The pattern: full symmetric storage (both triangles), rows sorted in each column.
#[derive(Debug)]
pub struct Pattern {
    pub n: usize,
    /// Unknowns per node (the dimension D).
    pub block: usize,
    symbolic: SymbolicSparseColMat<usize>,
    /// Node k couples with `nodes.coupled(k)`.
    nodes: NodeGraph,
}

impl Pattern {
    /// Builds the pattern of the element couplings of `cells` on `n_nodes` nodes with `block`
    /// unknowns each: column D·k + c holds the rows D·q … D·q + D − 1 of every node q coupled
    /// with k, in order.
    pub fn new<E: AsRef<[usize]>>(cells: &[E], n_nodes: usize, block: usize) -> Self {
        let d = block;
        let n = d * n_nodes;
        // Node adjacency (including the node itself), sorted.
        let mut adjacency: Vec<Vec<usize>> = vec![Vec::new(); n_nodes];
        for cell in cells {
            for &a in cell.as_ref() {
                adjacency[a].extend_from_slice(cell.as_ref());
            }
        }
        for list in &mut adjacency {
            list.sort_unstable();
            list.dedup();
        }
        let mut graph = NodeGraph {
            ptr: Vec::with_capacity(n_nodes + 1),
            nodes: Vec::with_capacity(adjacency.iter().map(Vec::len).sum()),
        };
        graph.ptr.push(0);
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(adjacency.iter().map(|l| d * d * l.len()).sum());
        for list in &adjacency {
            graph.nodes.extend_from_slice(list);
            graph.ptr.push(graph.nodes.len());
            for _component in 0..d {
                row_idx.extend(list.iter().flat_map(|&q| (0..d).map(move |c| d * q + c)));
                col_ptr.push(row_idx.len());
            }
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Pattern {
            n,
            block,
            symbolic,
            nodes: graph,
        }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    /// The positions in the value array of the local matrix of a cell on `nodes`, row-major
    /// over its D·n local unknowns: local entry (i, j) = (node b comp c', node a comp c) sits at
    /// `col_ptr[D·a + c] + D·(position of b among a's couplings) + c'`. Computed per cell (a
    /// binary search per node pair) rather than stored: a stored map is D²·n² positions per
    /// cell, 147 MB of fresh pages for 32 000 hexahedra (docs/method.md §9.6).
    pub fn cell_positions(&self, nodes: &[usize], out: &mut [usize]) {
        let d = self.block;
        let nl = d * nodes.len();
        let col_ptr = self.symbolic.col_ptr();
        for (ja, &a) in nodes.iter().enumerate() {
            let coupled = self.nodes.coupled(a);
            for (ib, &b) in nodes.iter().enumerate() {
                let k = coupled.binary_search(&b).expect("pattern holds every element coupling");
                for c in 0..d {
                    for c2 in 0..d {
                        out[(d * ib + c2) * nl + d * ja + c] = col_ptr[d * a + c] + d * k + c2;
                    }
                }
            }
        }
    }

    /// faer's view of the pattern.
    pub fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        self.symbolic.as_ref()
    }

    /// The node graph the pattern was expanded from.
    pub fn node_graph(&self) -> &NodeGraph {
        &self.nodes
    }
}

/// The node graph of a pattern made of D × D node blocks. Entry p of
/// [`NodeGraph::coupled`]`(k)` is node q, whose rows D·q … D·q + D − 1 sit at positions
/// `col_ptr[D·k + c] + D·p` (+ c') of column D·k + c.
#[derive(Clone, Debug)]
pub struct NodeGraph {
    /// Node k couples with `nodes[ptr[k]..ptr[k + 1]]` (ascending, itself included).
    pub ptr: Vec<usize>,
    pub nodes: Vec<usize>,
}

impl NodeGraph {
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

/// Which unknowns are prescribed (Dirichlet data): their rows and columns become the
/// identity's in [`SymmetricMatrix::with_identity_rows`].
pub trait Prescribed {
    /// True if unknown `i` is prescribed.
    fn is_prescribed(&self, i: usize) -> bool;
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

    /// The entries of column j: (row, value).
    pub fn column(&self, j: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let sym = self.pattern.symbolic();
        let range = sym.col_ptr()[j]..sym.col_ptr()[j + 1];
        sym.row_idx()[range.clone()]
            .iter()
            .copied()
            .zip(self.values[range].iter().copied())
    }

    /// The matrix with the rows and columns of the prescribed unknowns replaced by those of the
    /// identity (docs/method.md §7): symmetric positive definite when the free block is. A node
    /// whose every component is prescribed is decoupled from the others in the pattern of the
    /// result (its couplings would be explicit zeros, and would cost fill in the factor); a
    /// partly prescribed node keeps its D × D blocks, with explicit zeros.
    pub fn with_identity_rows(&self, dofs: &impl Prescribed) -> SymmetricMatrix {
        let d = self.pattern.block;
        let old = self.pattern.node_graph();
        let n_nodes = old.len();
        let isolated: Vec<bool> = (0..n_nodes)
            .map(|k| (0..d).all(|c| dofs.is_prescribed(d * k + c)))
            .collect();
        let mut graph = NodeGraph {
            ptr: Vec::with_capacity(n_nodes + 1),
            nodes: Vec::with_capacity(old.nodes.len()),
        };
        graph.ptr.push(0);
        // position in the old adjacency of each kept coupling
        let mut kept: Vec<usize> = Vec::with_capacity(old.nodes.len());
        for k in 0..n_nodes {
            for (p, &q) in old.coupled(k).iter().enumerate() {
                if q == k || !(isolated[k] || isolated[q]) {
                    graph.nodes.push(q);
                    kept.push(p);
                }
            }
            graph.ptr.push(graph.nodes.len());
        }
        let sym = self.pattern.symbolic();
        let old_ptr = sym.col_ptr();
        let n = self.n();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(d * d * graph.nodes.len());
        let mut values = Vec::with_capacity(d * d * graph.nodes.len());
        for k in 0..n_nodes {
            for c in 0..d {
                let j = d * k + c;
                for e in graph.ptr[k]..graph.ptr[k + 1] {
                    let (q, p) = (graph.nodes[e], kept[e]);
                    for c2 in 0..d {
                        let i = d * q + c2;
                        row_idx.push(i);
                        values.push(if dofs.is_prescribed(i) || dofs.is_prescribed(j) {
                            if i == j {
                                1.0
                            } else {
                                0.0
                            }
                        } else {
                            self.values[old_ptr[j] + d * p + c2]
                        });
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let pattern = Pattern {
            n,
            block: d,
            symbolic: SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx),
            nodes: graph,
        };
        SymmetricMatrix {
            pattern: Arc::new(pattern),
            values,
        }
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

/// Test matrices for the linear algebra's own tests, without the finite-element layer above it:
/// the pattern of a P1 or Q1 mesh of a rectangle with two unknowns per node, and values that
/// share a stiffness matrix's structure (a Laplacian with rigid modes in every element,
/// condition number ~ h⁻², components coupled in every block), clamped on the left side.
#[cfg(test)]
pub(crate) mod test_matrices {
    use super::{Pattern, Prescribed, SymmetricMatrix};
    use std::sync::Arc;

    /// The clamped unknowns: both components of the nodes on x = 0.
    struct LeftSide {
        nx: usize,
    }

    impl Prescribed for LeftSide {
        fn is_prescribed(&self, i: usize) -> bool {
            (i / 2).is_multiple_of(self.nx + 1)
        }
    }

    /// K = L ⊗ A on an `nx × ny` grid of unit squares (split into two triangles each unless
    /// `quads`), A = [[2, ½], [½, 1]], with identity rows on the left side.
    pub(crate) fn grid_stiffness(nx: usize, ny: usize, quads: bool) -> SymmetricMatrix {
        let node = |i: usize, j: usize| j * (nx + 1) + i;
        let mut cells: Vec<Vec<usize>> = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1));
                if quads {
                    cells.push(vec![a, b, c, d]);
                } else {
                    cells.push(vec![a, b, c]);
                    cells.push(vec![a, c, d]);
                }
            }
        }
        // the Laplacian's element matrices on a unit square and on its two halves
        const Q1: [[f64; 4]; 4] = [
            [4.0, -1.0, -2.0, -1.0],
            [-1.0, 4.0, -1.0, -2.0],
            [-2.0, -1.0, 4.0, -1.0],
            [-1.0, -2.0, -1.0, 4.0],
        ];
        const P1_LOWER: [[f64; 3]; 3] = [[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]];
        const P1_UPPER: [[f64; 3]; 3] = [[1.0, 0.0, -1.0], [0.0, 1.0, -1.0], [-1.0, -1.0, 2.0]];
        const A: [[f64; 2]; 2] = [[2.0, 0.5], [0.5, 1.0]];
        let pattern = Arc::new(Pattern::new(&cells, (nx + 1) * (ny + 1), 2));
        let mut k = SymmetricMatrix::zeros(pattern.clone());
        for (e, cell) in cells.iter().enumerate() {
            let laplacian = |a: usize, b: usize| match (quads, e % 2) {
                (true, _) => Q1[a][b] / 6.0,
                (false, 0) => P1_LOWER[a][b] / 2.0,
                (false, _) => P1_UPPER[a][b] / 2.0,
            };
            let n = 2 * cell.len();
            let mut positions = vec![0; n * n];
            pattern.cell_positions(cell, &mut positions);
            for (p, &at) in positions.iter().enumerate() {
                let (r, c) = (p / n, p % n);
                k.values[at] += laplacian(r / 2, c / 2) * A[r % 2][c % 2];
            }
        }
        k.with_identity_rows(&LeftSide { nx })
    }

    /// max |a − b| / max |b|.
    pub(crate) fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
    }
}
