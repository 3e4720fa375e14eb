//! The condensation read off the factor's trailing block (docs/method.md §9.4).
//!
//! With the contact rows' unknowns ordered last, L = [L₁₁ 0; L_c1 L_cc] and C = [0 T]: the rows
//! of C touch only the trailing unknowns. Where T is square — each node has as many rows as
//! unknowns with a non-zero coefficient, as on a face normal to an axis (one row, one unknown)
//! or with friction (D rows, D unknowns: an orthonormal frame) — then
//!
//! * Q = W⁻¹ = T⁻ᵀ (L_cc L_ccᵀ) T⁻¹, a dense triangular product of k³/3 multiply–adds and no
//!   inverse;
//! * W = T (L_cc⁻ᵀ L_cc⁻¹) Tᵀ, formed only with friction (Coulomb's unloaded round, §17.2);
//! * per step d = T L_cc⁻ᵀ y_c and y_c ← y_c − L_cc⁻¹ Tᵀ λ, two dense triangular solves of order
//!   k around the step's one solve,
//!
//! where [`super::SplitSweeps`] with sparse columns forms G = L⁻¹PCᵀ by m sparse sweeps, W = GᵀG
//! and Q = W⁻¹. This module sees the rows of C as (node, row) lists; [`super::SplitSweeps`] holds
//! either kind of columns.

use crate::linalg::dense::symmetrise_row_major;
use crate::linalg::{Factor, Forward, TrailingBlock};
use std::collections::BTreeMap;

/// The rows of one node and the unknowns they use: T's diagonal block there (square).
#[derive(Debug)]
struct NodeBlock {
    rows: Vec<usize>,
    /// Original unknowns, then (in [`TrailingColumns::new`]) their positions in the trailing block.
    unknowns: Vec<usize>,
    /// T_b, r × r row-major: entry (row a, unknown i).
    t: Vec<f64>,
    /// T_b⁻¹, r × r row-major: entry (unknown i, row a).
    inverse: Vec<f64>,
}

/// T's blocks by node (`nodes[p]`: the node of row p, `rows[p]`: its (unknown, coefficient)
/// pairs), when every node's rows use exactly as many unknowns (non-zero coefficients) as there
/// are rows and the block is well conditioned (None otherwise).
fn node_blocks(nodes: &[usize], rows: &[Vec<(usize, f64)>]) -> Option<Vec<NodeBlock>> {
    let mut by_node: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (p, &node) in nodes.iter().enumerate() {
        by_node.entry(node).or_default().push(p);
    }
    let mut blocks = Vec::with_capacity(by_node.len());
    for (_, block_rows) in by_node {
        let mut unknowns: Vec<usize> = block_rows
            .iter()
            .flat_map(|&p| rows[p].iter().filter(|(_, c)| *c != 0.0).map(|&(i, _)| i))
            .collect();
        unknowns.sort_unstable();
        unknowns.dedup();
        let r = block_rows.len();
        if unknowns.len() != r {
            return None;
        }
        let mut t = vec![0.0; r * r];
        for (a, &p) in block_rows.iter().enumerate() {
            for &(i, c) in &rows[p] {
                if let Ok(col) = unknowns.binary_search(&i) {
                    t[a * r + col] += c;
                }
            }
        }
        let matrix = nalgebra::DMatrix::from_row_slice(r, r, &t);
        let inverse = matrix.clone().try_inverse()?;
        // a block this ill-conditioned (two rows nearly alike) is left to the G path, which
        // reports a singular W
        if matrix.norm() * inverse.norm() > 1e8 {
            return None;
        }
        let inverse = (0..r * r).map(|k| inverse[(k / r, k % r)]).collect();
        blocks.push(NodeBlock {
            rows: block_rows,
            unknowns,
            t,
            inverse,
        });
    }
    Some(blocks)
}

/// Whether T is square by node (see [`node_blocks`]): then the trailing-block path applies, and
/// ordering the rows' unknowns last pays at any m (docs/method.md §9.4).
pub(super) fn applies(nodes: &[usize], rows: &[Vec<(usize, f64)>]) -> bool {
    node_blocks(nodes, rows).is_some()
}

/// Bᵀ M B with B block-diagonal by node (`b(block, i, a)`: entry (unknown i, row a) of the
/// node's block), M symmetric k × k over the trailing positions, into an m × m row-major matrix
/// over the rows (m = k), in M's storage. Two passes of O(k² r): X = M B by columns, then Bᵀ X.
fn congruence(mut s: Vec<f64>, blocks: &[NodeBlock], b: impl Fn(&NodeBlock, usize, usize) -> f64) -> Vec<f64> {
    let k = blocks.iter().map(|b| b.rows.len()).sum::<usize>();
    // Xᵗ: row p (contiguous) is column p of X = M B, a combination of rows of M (M symmetric)
    let mut xt = vec![0.0; k * k];
    for blk in blocks {
        for (a, &p) in blk.rows.iter().enumerate() {
            let out = &mut xt[p * k..(p + 1) * k];
            for (i, &u) in blk.unknowns.iter().enumerate() {
                let c = b(blk, i, a);
                if c != 0.0 {
                    for (o, v) in out.iter_mut().zip(&s[u * k..(u + 1) * k]) {
                        *o += c * v;
                    }
                }
            }
        }
    }
    // (Bᵀ X)ᵗ = Xᵀ B: row p of the result from row p of Xᵗ, into M's storage (every entry is
    // written: the blocks' rows are all k rows)
    for p in 0..k {
        let row = &xt[p * k..(p + 1) * k];
        let out = &mut s[p * k..(p + 1) * k];
        for blk in blocks {
            for (a, &q) in blk.rows.iter().enumerate() {
                out[q] = blk
                    .unknowns
                    .iter()
                    .enumerate()
                    .map(|(i, &u)| b(blk, i, a) * row[u])
                    .sum();
            }
        }
    }
    symmetrise_row_major(&mut s, k);
    s
}

/// G's place in the split sweeps when Q is read off the trailing block (docs/method.md §9.4):
/// L_cc and T's rows over its positions.
pub(super) struct TrailingColumns {
    block: TrailingBlock,
    /// Row p of T: (trailing position, coefficient).
    rows: Vec<Vec<(usize, f64)>>,
    /// A vector over the trailing block.
    work: Vec<f64>,
}

/// What [`TrailingColumns::new`] forms: the columns, Q and W (empty unless asked for).
pub(super) type Formed = (TrailingColumns, Vec<f64>, Vec<f64>);

impl TrailingColumns {
    /// Q (and W when `with_w`) from the factor's trailing block, both m × m row-major. None when
    /// the path does not apply: nothing was ordered last, the rows use other unknowns than
    /// those, or T is not square by node.
    pub(super) fn new(nodes: &[usize], rows: &[Vec<(usize, f64)>], factor: &Factor, with_w: bool) -> Option<Formed> {
        let mut blocks = node_blocks(nodes, rows)?;
        let block = factor.trailing_block()?;
        let k = block.len();
        if k != rows.len() {
            return None;
        }
        for b in &mut blocks {
            for u in &mut b.unknowns {
                *u = block.position(factor, *u).filter(|&q| q < k)?;
            }
        }
        let rows: Vec<Vec<(usize, f64)>> = rows
            .iter()
            .map(|row| {
                row.iter()
                    .filter(|(_, c)| *c != 0.0)
                    .map(|&(i, c)| block.position(factor, i).map(|q| (q, c)))
                    .collect::<Option<Vec<_>>>()
            })
            .collect::<Option<_>>()?;
        let q = congruence(block.schur_complement(), &blocks, |b, i, a| {
            b.inverse[i * b.rows.len() + a]
        });
        // W = T S⁻¹ Tᵀ: B_b = T_bᵀ, entry (unknown i, row a) = T_b(a, i)
        let w = match with_w {
            true => congruence(block.schur_inverse(), &blocks, |b, i, a| b.t[a * b.rows.len() + i]),
            false => Vec::new(),
        };
        let columns = TrailingColumns {
            work: vec![0.0; k],
            block,
            rows,
        };
        Some((columns, q, w))
    }

    /// out = T z (z over the trailing positions, out over the rows).
    fn apply_t(&self, z: &[f64], out: &mut [f64]) {
        for (o, row) in out.iter_mut().zip(&self.rows) {
            *o = row.iter().map(|&(q, c)| c * z[q]).sum();
        }
    }

    /// z = Tᵀ x (x over the rows, z over the trailing positions).
    fn apply_t_transpose(&self, x: &[f64], z: &mut [f64]) {
        z.fill(0.0);
        for (&l, row) in x.iter().zip(&self.rows) {
            for &(q, c) in row {
                z[q] += c * l;
            }
        }
    }

    /// d = T L_cc⁻ᵀ y_c for a forward-swept y.
    pub(super) fn free_normal(&mut self, y: &Forward, d: &mut [f64]) {
        let mut z = std::mem::take(&mut self.work);
        z.copy_from_slice(self.block.part(y));
        self.block.solve_upper(&mut z);
        self.apply_t(&z, d);
        self.work = z;
    }

    /// y_c ← y_c − L_cc⁻¹ Tᵀ λ.
    pub(super) fn subtract(&mut self, lambda: &[f64], y: &mut Forward) {
        let mut z = std::mem::take(&mut self.work);
        self.apply_t_transpose(lambda, &mut z);
        self.block.solve_lower(&mut z);
        for (yc, zc) in self.block.part_mut(y).iter_mut().zip(&z) {
            *yc -= zc;
        }
        self.work = z;
    }

    /// y = W x = T L_cc⁻ᵀ L_cc⁻¹ Tᵀ x by two triangular solves.
    pub(super) fn apply_w(&self, x: &[f64], y: &mut [f64]) {
        let mut z = vec![0.0; self.block.len()];
        self.apply_t_transpose(x, &mut z);
        self.block.solve_lower(&mut z);
        self.block.solve_upper(&mut z);
        self.apply_t(&z, y);
    }
}
