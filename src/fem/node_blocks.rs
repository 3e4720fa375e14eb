//! A symmetric matrix stored as the upper triangle of its 2 × 2 node blocks, for a product
//! that moves a third of the bytes of the full compressed-column form.
//!
//! The memory term multiplies K_B by a vector every time step (METHOD.md §3, rhs = F − K_B h),
//! and that product is bound by memory traffic: full storage reads 16 bytes per entry (value
//! and row index), this form 9 per stored entry (four values share one 4-byte index) over
//! about half the entries. It also leaves more of the cache to the factor's sweeps.

use super::pattern::{NodeGraph, SymmetricMatrix};

/// The upper-triangular 2 × 2 blocks of a symmetric matrix whose pattern is made of node
/// blocks (unknowns 2k, 2k + 1 of node k), in block-row order.
#[derive(Clone, Debug)]
pub struct NodeBlockMatrix {
    n_nodes: usize,
    /// Block row k has blocks `row_ptr[k]..row_ptr[k + 1]`.
    row_ptr: Vec<usize>,
    /// Block column of each block (≥ its row).
    col: Vec<u32>,
    /// Each block row-major: [a₀₀, a₀₁, a₁₀, a₁₁].
    values: Vec<[f64; 4]>,
}

impl NodeBlockMatrix {
    /// The node blocks of `matrix`, or None if its pattern is not made of 2 × 2 node blocks
    /// (odd order, or the two unknowns of a node with different patterns).
    pub fn new(matrix: &SymmetricMatrix) -> Option<Self> {
        let sym = matrix.pattern.symbolic();
        let graph = NodeGraph::of(sym)?;
        let n_nodes = graph.len();
        if n_nodes > u32::MAX as usize {
            return None;
        }
        let (col_ptr, v) = (sym.col_ptr(), &matrix.values);
        let mut out = NodeBlockMatrix {
            n_nodes,
            row_ptr: Vec::with_capacity(n_nodes + 1),
            col: Vec::new(),
            values: Vec::new(),
        };
        out.row_ptr.push(0);
        // Columns 2k and 2k + 1 hold the rows of block column k; by symmetry block (k, q) for
        // q ≥ k is the transpose of the stored block (q, k) of column k:
        // [a(2k,2q), a(2k,2q+1); a(2k+1,2q), a(2k+1,2q+1)] = [a(2q,2k), a(2q+1,2k); a(2q,2k+1), a(2q+1,2k+1)].
        for k in 0..n_nodes {
            for (p, &q) in graph.coupled(k).iter().enumerate() {
                if q < k {
                    continue;
                }
                let (a, b) = (col_ptr[2 * k] + 2 * p, col_ptr[2 * k + 1] + 2 * p);
                out.values.push([v[a], v[a + 1], v[b], v[b + 1]]);
                out.col.push(q as u32);
            }
            out.row_ptr.push(out.col.len());
        }
        Some(out)
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        2 * self.n_nodes
    }

    /// y = A x.
    pub fn matvec(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for k in 0..self.n_nodes {
            let (xk0, xk1) = (x[2 * k], x[2 * k + 1]);
            let (mut yk0, mut yk1) = (0.0, 0.0);
            for p in self.row_ptr[k]..self.row_ptr[k + 1] {
                let q = self.col[p] as usize;
                let [a00, a01, a10, a11] = self.values[p];
                let (xq0, xq1) = (x[2 * q], x[2 * q + 1]);
                yk0 += a00 * xq0 + a01 * xq1;
                yk1 += a10 * xq0 + a11 * xq1;
                if q != k {
                    // the mirrored block (q, k) is the transpose
                    y[2 * q] += a00 * xk0 + a10 * xk1;
                    y[2 * q + 1] += a01 * xk0 + a11 * xk1;
                }
            }
            y[2 * k] += yk0;
            y[2 * k + 1] += yk1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::assembly::{rectangle_stiffness, relative_difference};
    use crate::material::{Elasticity, PlaneModel, IDENTITY_TENSOR};
    use crate::mesh::structured::CellShape;

    /// The block product equals the full product on P1 and Q1 stiffness matrices.
    #[test]
    fn node_block_product_equals_the_full_product() {
        let e = Elasticity {
            youngs_modulus: 2.0,
            poisson_ratio: 0.3,
            plane: PlaneModel::Stress,
        };
        for shape in [CellShape::Quad, CellShape::Tri] {
            for k in rectangle_stiffness(9, 5, shape, &[e.voigt(), IDENTITY_TENSOR]) {
                let blocks = NodeBlockMatrix::new(&k).expect("node blocks");
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
