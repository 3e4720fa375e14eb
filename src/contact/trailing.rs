//! The condensation read off the factor's trailing block (docs/method.md §9.4).
//!
//! With the contact rows' unknowns ordered last, L = [L₁₁ 0; L_c1 L_cc] and C = [0 T]: the rows
//! of C touch only the trailing unknowns. Where T is square — each node has as many rows as
//! unknowns with a non-zero coefficient, as on a face normal to an axis (one row, one unknown)
//! or with friction (D rows, D unknowns: an orthonormal frame) — then
//!
//! * Q = W⁻¹ = T⁻ᵀ (L_cc L_ccᵀ) T⁻¹, a dense triangular product of k³/3 multiply–adds and no
//!   inverse;
//! * W = T (L_cc⁻ᵀ L_cc⁻¹) Tᵀ, formed only where the Newton system in W (§4.6) may use it;
//! * per step d = T L_cc⁻ᵀ y_c and y_c ← y_c − L_cc⁻¹ Tᵀ λ, two dense triangular solves of order
//!   k around the step's one solve,
//!
//! where [`super::SplitSweeps`] forms G = L⁻¹PCᵀ by m sparse sweeps, W = GᵀG and Q = W⁻¹.

use super::condensed::{Condensation, ContactNodes, DenseNormalStiffness};
use crate::linalg::dense::{matvec_row_major, symmetrise_row_major};
use crate::linalg::{Counters, Factor, Forward, TrailingBlock};
use std::collections::BTreeMap;
use std::sync::Arc;

/// The rows of one node and the unknowns they use: T's diagonal block there (square).
#[derive(Debug)]
struct NodeBlock {
    rows: Vec<usize>,
    /// Original unknowns, then (in [`TrailingSweeps`]) their positions in the trailing block.
    unknowns: Vec<usize>,
    /// T_b, r × r row-major: entry (row a, unknown i).
    t: Vec<f64>,
    /// T_b⁻¹, r × r row-major: entry (unknown i, row a).
    inverse: Vec<f64>,
}

/// T's blocks by node, when every node's rows use exactly as many unknowns (non-zero
/// coefficients) as there are rows and the block is well conditioned (None otherwise).
fn node_blocks<const D: usize>(nodes: &ContactNodes<D>) -> Option<Vec<NodeBlock>> {
    let mut by_node: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (p, &node) in nodes.nodes.iter().enumerate() {
        by_node.entry(node).or_default().push(p);
    }
    let rows = nodes.rows();
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
pub fn trailing_block_applies<const D: usize>(nodes: &ContactNodes<D>) -> bool {
    node_blocks(nodes).is_some()
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
    // (Bᵀ X)ᵗ = Xᵀ B: row p of the result from row p of Xᵗ, into M's storage
    s.fill(0.0);
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

/// The split sweeps with Q read off the trailing block (docs/method.md §9.4).
pub struct TrailingSweeps {
    factor: Arc<Factor>,
    block: TrailingBlock,
    /// Row p of T: (trailing position, coefficient).
    rows: Vec<Vec<(usize, f64)>>,
    stiffness: DenseNormalStiffness,
    y: Forward,
    /// A vector over the trailing block.
    work: Vec<f64>,
}

impl TrailingSweeps {
    /// Q (and W when `with_w`) from the factor's trailing block. None when the path does not
    /// apply: nothing was ordered last, the rows use other unknowns than those, or T is not
    /// square by node.
    pub fn new<const D: usize>(nodes: &ContactNodes<D>, factor: Arc<Factor>, with_w: bool) -> Option<Self> {
        let mut blocks = node_blocks(nodes)?;
        let block = factor.trailing_block()?;
        let k = block.len();
        if k != nodes.len() {
            return None;
        }
        for b in &mut blocks {
            for u in &mut b.unknowns {
                *u = block.position(&factor, *u).filter(|&q| q < k)?;
            }
        }
        let rows: Vec<Vec<(usize, f64)>> = nodes
            .rows()
            .iter()
            .map(|row| {
                row.iter()
                    .filter(|(_, c)| *c != 0.0)
                    .map(|&(i, c)| block.position(&factor, i).map(|q| (q, c)))
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
        Some(TrailingSweeps {
            y: Forward::zeros(factor.n()),
            factor,
            work: vec![0.0; k],
            block,
            rows,
            stiffness: DenseNormalStiffness {
                w,
                q,
                m: k,
                q_inverts_w: true,
            },
        })
    }
}

impl Condensation for TrailingSweeps {
    fn name(&self) -> &'static str {
        "split sweeps (Q = T⁻ᵀ L_cc L_ccᵀ T⁻¹ read off the factor's trailing block, one solve per step)"
    }

    fn stiffness(&self) -> &DenseNormalStiffness {
        &self.stiffness
    }

    fn stiffness_mut(&mut self) -> &mut DenseNormalStiffness {
        &mut self.stiffness
    }

    fn free_normal(&mut self, rhs: &[f64], d: &mut [f64], _counters: &Counters) {
        self.factor.forward_into(rhs, &mut self.y);
        self.work.copy_from_slice(self.block.part(&self.y));
        self.block.solve_upper(&mut self.work);
        for (dp, row) in d.iter_mut().zip(&self.rows) {
            *dp = row.iter().map(|&(q, c)| c * self.work[q]).sum();
        }
    }

    fn recover(&mut self, lambda: &[f64], u: &mut [f64], counters: &Counters) {
        self.work.fill(0.0);
        for (&l, row) in lambda.iter().zip(&self.rows) {
            for &(q, c) in row {
                self.work[q] += c * l;
            }
        }
        self.block.solve_lower(&mut self.work);
        for (y, z) in self.block.part_mut(&mut self.y).iter_mut().zip(&self.work) {
            *y -= z;
        }
        self.factor.backward_from(&mut self.y, u, counters);
    }

    /// W x by two triangular solves where W was not formed.
    fn apply_w(&self, x: &[f64], y: &mut [f64]) {
        if !self.stiffness.w.is_empty() {
            return matvec_row_major(&self.stiffness.w, self.stiffness.m, x, y);
        }
        let mut z = vec![0.0; self.block.len()];
        for (&l, row) in x.iter().zip(&self.rows) {
            for &(q, c) in row {
                z[q] += c * l;
            }
        }
        self.block.solve_lower(&mut z);
        self.block.solve_upper(&mut z);
        for (yp, row) in y.iter_mut().zip(&self.rows) {
            *yp = row.iter().map(|&(q, c)| c * z[q]).sum();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::SplitSweeps;
    use crate::fem::{assembly::assemble_stiffness, DofMap};
    use crate::material::Elasticity;
    use crate::mesh::structured::{block, SolidShape};
    use crate::mesh::GroupSelector;

    /// An elastic box clamped at x = 0 with rows on its face y = 0: the normal (0, −1, 0) alone,
    /// or each node's frame (the normal and two tangents turned by 30° about it), or a normal
    /// that is not along an axis (two unknowns for one row). The factor orders the rows'
    /// unknowns last.
    fn case(rows: &str) -> (ContactNodes<3>, Arc<Factor>) {
        let mesh = block([2.0, 1.0, 0.5], [6, 3, 2], SolidShape::Hex);
        let clamped = mesh.group_nodes(&GroupSelector::Name("Gamma1".into())).unwrap();
        let dofs = DofMap::<3>::new(mesh.points.len(), &clamped);
        let elasticity = Elasticity {
            youngs_modulus: 1.0,
            poisson_ratio: 0.3,
            plane: None,
        };
        let [k] = assemble_stiffness(&mesh.cells, &mesh.points, &dofs, &[elasticity.tensor()]);
        let k = k.with_identity_rows(&dofs);
        let surface = mesh.group_nodes(&GroupSelector::Name("Gamma3".into())).unwrap();
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let frame: Vec<[f64; 3]> = match rows {
            "normal" => vec![[0.0, -1.0, 0.0]],
            "frame" => vec![[0.0, -1.0, 0.0], [c, 0.0, s], [-s, 0.0, c]],
            _ => vec![[0.6, -0.8, 0.0]],
        };
        let (mut nodes, mut directions) = (Vec::new(), Vec::new());
        for &p in &surface {
            for d in &frame {
                nodes.push(p);
                directions.push(*d);
            }
        }
        let weights = vec![1.0; nodes.len()];
        let (rows, _) = ContactNodes::from_rows(&nodes, &weights, &directions, &dofs);
        let mut last: Vec<usize> = rows
            .rows()
            .iter()
            .flatten()
            .filter(|(_, c)| *c != 0.0)
            .map(|&(i, _)| i)
            .collect();
        last.sort_unstable();
        last.dedup();
        let analysis = Factor::analyse_with_last(&k, &last).unwrap();
        let factor = Factor::new(&analysis, &k, &Counters::default()).unwrap();
        (rows, Arc::new(factor))
    }

    fn max_relative(a: &[f64], b: &[f64]) -> f64 {
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
    }

    /// Q, W, the free normal displacements and the recovery of the trailing block against the
    /// sparse sweeps' G on the same factor.
    #[test]
    fn the_trailing_block_agrees_with_the_sparse_sweeps() {
        for rows in ["normal", "frame"] {
            let (nodes, factor) = case(rows);
            let m = nodes.len();
            assert!(trailing_block_applies(&nodes));
            let counters = Counters::default();
            let mut split = SplitSweeps::new(&nodes, factor.clone(), &counters).unwrap();
            let mut trailing = TrailingSweeps::new(&nodes, factor.clone(), true).unwrap();
            let lean = TrailingSweeps::new(&nodes, factor.clone(), false).unwrap();
            let (a, b) = (trailing.stiffness(), split.stiffness());
            assert!(
                max_relative(&a.q, &b.q) < 1e-11,
                "{rows}: Q {:e}",
                max_relative(&a.q, &b.q)
            );
            assert!(
                max_relative(&a.w, &b.w) < 1e-11,
                "{rows}: W {:e}",
                max_relative(&a.w, &b.w)
            );
            assert!(lean.stiffness().w.is_empty());
            // W x without W formed: by two triangular solves
            let x: Vec<f64> = (0..m).map(|p| ((p as f64) * 0.71).sin()).collect();
            let (mut wx, mut wx_lean) = (vec![0.0; m], vec![0.0; m]);
            split.apply_w(&x, &mut wx);
            lean.apply_w(&x, &mut wx_lean);
            assert!(max_relative(&wx_lean, &wx) < 1e-12);
            let weights: Vec<f64> = (0..m).map(|p| 1.0 + (p % 3) as f64).collect();
            let (t_split, t_lean) = (split.trace_constant(&weights), lean.trace_constant(&weights));
            assert!((t_split - t_lean).abs() < 1e-9 * t_split, "{t_split} {t_lean}");
            // a step: d, then u for some forces
            let n = factor.n();
            let rhs: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.37).cos()).collect();
            let lambda: Vec<f64> = (0..m).map(|p| ((p as f64) * 1.3).sin().max(0.0)).collect();
            let (mut d_split, mut d_trailing) = (vec![0.0; m], vec![0.0; m]);
            split.free_normal(&rhs, &mut d_split, &counters);
            trailing.free_normal(&rhs, &mut d_trailing, &counters);
            assert!(max_relative(&d_trailing, &d_split) < 1e-12);
            let (mut u_split, mut u_trailing) = (vec![0.0; n], vec![0.0; n]);
            split.recover(&lambda, &mut u_split, &counters);
            trailing.recover(&lambda, &mut u_trailing, &counters);
            assert!(max_relative(&u_trailing, &u_split) < 1e-12);
            // and u is the displacement of those forces: C u = d − W λ
            let mut u_nu = vec![0.0; m];
            nodes.normal_displacements(&u_trailing, &mut u_nu);
            let mut w_lambda = vec![0.0; m];
            trailing.apply_w(&lambda, &mut w_lambda);
            let expected: Vec<f64> = d_split.iter().zip(&w_lambda).map(|(d, w)| d - w).collect();
            assert!(max_relative(&u_nu, &expected) < 1e-12);
        }
    }

    #[test]
    fn a_row_over_two_unknowns_is_left_to_the_sparse_sweeps() {
        let (nodes, factor) = case("oblique");
        assert!(!trailing_block_applies(&nodes));
        assert!(TrailingSweeps::new(&nodes, factor, true).is_none());
    }
}
