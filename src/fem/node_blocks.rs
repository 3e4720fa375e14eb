//! A symmetric matrix stored as the upper triangle of its D × D node blocks, for a product
//! that moves a third of the bytes of the full compressed-column form.
//!
//! The memory term multiplies K_B by a vector every time step (docs/method.md §3, rhs = F − K_B h),
//! and that product is bound by memory traffic: full storage reads 16 bytes per entry (value
//! and row index), this form 9 per stored entry (four values share one 4-byte index) over
//! about half the entries. It also leaves more of the cache to the factor's sweeps.

use crate::linalg::sparse::SymmetricMatrix;

/// The upper-triangular D × D blocks of a symmetric matrix whose pattern is made of node
/// blocks (unknowns D·k + c of node k), in block-row order.
#[derive(Clone, Debug)]
pub struct NodeBlockMatrix<const D: usize> {
    n_nodes: usize,
    /// Block row k has blocks `row_ptr[k]..row_ptr[k + 1]`.
    row_ptr: Vec<usize>,
    /// Block column of each block (≥ its row).
    col: Vec<u32>,
    /// Each block row-major: a[r][c] = entry (D·k + r, D·q + c).
    values: Vec<[[f64; D]; D]>,
}

impl<const D: usize> NodeBlockMatrix<D> {
    /// The node blocks of `matrix`, or None if its pattern is not made of D × D node blocks or
    /// has more nodes than a u32 indexes.
    pub fn new(matrix: &SymmetricMatrix) -> Option<Self> {
        let pattern = &matrix.pattern;
        if pattern.block != D {
            return None;
        }
        let graph = pattern.node_graph();
        let n_nodes = graph.len();
        if n_nodes > u32::MAX as usize {
            return None;
        }
        let sym = pattern.symbolic();
        let (col_ptr, v) = (sym.col_ptr(), &matrix.values);
        let mut out = NodeBlockMatrix {
            n_nodes,
            row_ptr: Vec::with_capacity(n_nodes + 1),
            col: Vec::new(),
            values: Vec::new(),
        };
        out.row_ptr.push(0);
        // Column D·k + c holds the rows of block column k; by symmetry block (k, q) for q ≥ k has
        // entry (r, c) = a(D·k + r, D·q + c) = a(D·q + c, D·k + r), stored in column D·k + r at
        // position D·p + c.
        for k in 0..n_nodes {
            for (p, &q) in graph.coupled(k).iter().enumerate() {
                if q < k {
                    continue;
                }
                let mut block = [[0.0; D]; D];
                for (r, row) in block.iter_mut().enumerate() {
                    let base = col_ptr[D * k + r] + D * p;
                    row.copy_from_slice(&v[base..base + D]);
                }
                out.values.push(block);
                out.col.push(q as u32);
            }
            out.row_ptr.push(out.col.len());
        }
        Some(out)
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        D * self.n_nodes
    }

    /// y = A x.
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for k in 0..self.n_nodes {
            let xk: [f64; D] = std::array::from_fn(|c| x[D * k + c]);
            let mut yk = [0.0; D];
            for p in self.row_ptr[k]..self.row_ptr[k + 1] {
                let q = self.col[p] as usize;
                let a = &self.values[p];
                let xq: [f64; D] = std::array::from_fn(|c| x[D * q + c]);
                for r in 0..D {
                    for c in 0..D {
                        yk[r] += a[r][c] * xq[c];
                    }
                }
                if q != k {
                    // the mirrored block (q, k) is the transpose
                    for c in 0..D {
                        let mut s = 0.0;
                        for r in 0..D {
                            s += a[r][c] * xk[r];
                        }
                        y[D * q + c] += s;
                    }
                }
            }
            for r in 0..D {
                y[D * k + r] += yk[r];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::assembly::rectangle_stiffness;
    use crate::linalg::sparse::test_matrices::relative_difference;
    use crate::material::{Elasticity, PlaneModel, IDENTITY_TENSOR};
    use crate::mesh::structured::CellShape;

    /// The block product equals the full product on P1 and Q1 stiffness matrices.
    #[test]
    fn node_block_product_equals_the_full_product() {
        let e = Elasticity {
            youngs_modulus: 2.0,
            poisson_ratio: 0.3,
            plane: Some(PlaneModel::Stress),
        };
        for shape in [CellShape::Quad, CellShape::Tri] {
            for k in rectangle_stiffness(9, 5, shape, &[e.tensor(), IDENTITY_TENSOR]) {
                let blocks = NodeBlockMatrix::<2>::new(&k).expect("node blocks");
                let x: Vec<f64> = (0..k.n()).map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0).collect();
                let (mut full, mut ours) = (vec![0.0; k.n()], vec![0.0; k.n()]);
                k.matvec(&x, &mut full);
                blocks.matvec(&x, &mut ours);
                let diff = relative_difference(&ours, &full);
                assert!(diff <= 1e-14, "{diff:e}");
            }
        }
    }
}
