//! The contact nodes of Γ₃ and the condensed operator W = C K⁻¹ Cᵀ (METHOD.md §4, "the fast
//! path"): with the cached factor of K, the contact problem of each step lives on the m
//! contact normals, u_ν = d − W λ, and K is never refactorised.

use crate::fem::DofMap;
use crate::linalg::{Counters, Factor};
use crate::mesh::BoundaryPart;
use faer::linalg::solvers::Solve;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::Mat;

/// The contact nodes with their nodal quadrature weights w_p, normals ν_p and bounds g_p,
/// and the rows of C (u ↦ u_ν at the nodes).
#[derive(Clone, Debug)]
pub struct ContactNodes {
    /// Mesh node indices.
    pub nodes: Vec<usize>,
    /// w_p: the share of Γ₃'s length carried by node p.
    pub weights: Vec<f64>,
    /// ν_p: unit outward nodal normals.
    pub normals: Vec<[f64; 2]>,
    /// Rows of C: (free dof, coefficient) pairs.
    rows: Vec<Vec<(usize, f64)>>,
    /// Γ₃ nodes dropped because they are clamped (u = 0 there, nothing to solve).
    pub clamped_nodes: Vec<usize>,
}

impl ContactNodes {
    /// The contact nodes of a boundary part; nodes whose normal displacement is fixed by Γ₁
    /// are set aside (they would make W singular).
    pub fn new(part: &BoundaryPart, dofs: &DofMap) -> Self {
        let mut out = ContactNodes {
            nodes: Vec::new(),
            weights: Vec::new(),
            normals: Vec::new(),
            rows: Vec::new(),
            clamped_nodes: Vec::new(),
        };
        for (k, &p) in part.nodes.iter().enumerate() {
            let nu = part.normals[k];
            let row: Vec<(usize, f64)> = (0..2).filter_map(|c| dofs.get(p, c).map(|d| (d, nu[c]))).collect();
            if row.iter().all(|(_, v)| v.abs() < 1e-12) {
                out.clamped_nodes.push(p);
                continue;
            }
            out.nodes.push(p);
            out.weights.push(part.weights[k]);
            out.normals.push(nu);
            out.rows.push(row);
        }
        out
    }

    /// m, the number of contact nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True if there are no contact nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// C u: the normal displacements at the contact nodes.
    pub fn normal_displacements(&self, u: &[f64], out: &mut [f64]) {
        for (o, row) in out.iter_mut().zip(&self.rows) {
            *o = row.iter().map(|(d, c)| c * u[*d]).sum();
        }
    }

    /// f ← f − Cᵀ λ.
    pub fn subtract_transpose(&self, lambda: &[f64], f: &mut [f64]) {
        for (l, row) in lambda.iter().zip(&self.rows) {
            for (d, c) in row {
                f[*d] -= c * l;
            }
        }
    }
}

/// W = C K⁻¹ Cᵀ and its inverse Q = W⁻¹ (both m × m, dense, symmetric positive definite).
pub struct CondensedOperator {
    /// W (row-major m × m): normal displacement at p per unit normal force at q.
    pub w: Vec<f64>,
    /// Q = W⁻¹ (row-major m × m): the Schur-complement stiffness on the contact normals.
    pub q: Vec<f64>,
    pub m: usize,
}

/// Right-hand sides per block when forming K⁻¹ Cᵀ (bounds the n × block work array).
const BLOCK: usize = 128;

impl CondensedOperator {
    /// Forms W with m solves against the cached factor, in blocks of right-hand sides.
    pub fn new(nodes: &ContactNodes, factor: &Factor, counters: &Counters) -> Result<Self, String> {
        let (m, n) = (nodes.len(), factor.n());
        let mut w = vec![0.0; m * m];
        let mut block = Mat::<f64>::zeros(n, BLOCK.min(m.max(1)));
        let mut start = 0;
        while start < m {
            let cols = BLOCK.min(m - start);
            let mut z = block.as_mut().subcols_mut(0, cols);
            z.fill(0.0);
            for j in 0..cols {
                for (d, c) in &nodes.rows[start + j] {
                    z[(*d, j)] = *c;
                }
            }
            factor.solve_block_in_place(z.rb_mut(), counters);
            for j in 0..cols {
                let col = z.rb().col(j);
                for (p, row) in nodes.rows.iter().enumerate() {
                    w[p * m + start + j] = row.iter().map(|(d, c)| c * col[*d]).sum();
                }
            }
            start += cols;
        }
        // Symmetrise away round-off.
        for p in 0..m {
            for q in 0..p {
                let avg = 0.5 * (w[p * m + q] + w[q * m + p]);
                w[p * m + q] = avg;
                w[q * m + p] = avg;
            }
        }
        let wm = Mat::<f64>::from_fn(m, m, |i, j| w[i * m + j]);
        let llt = wm
            .llt(faer::Side::Lower)
            .map_err(|_| "the condensed contact operator W = C K⁻¹ Cᵀ is not positive definite (are two contact nodes sharing one position, or is a contact node's normal fully constrained?)".to_string())?;
        let inv = llt.solve(Mat::<f64>::identity(m, m));
        let mut q = vec![0.0; m * m];
        for p in 0..m {
            for r in 0..m {
                q[p * m + r] = 0.5 * (inv[(p, r)] + inv[(r, p)]);
            }
        }
        Ok(CondensedOperator { w, q, m })
    }

    /// y = Q x.
    pub fn apply_q(&self, x: &[f64], y: &mut [f64]) {
        for (p, yp) in y.iter_mut().enumerate() {
            let row = &self.q[p * self.m..(p + 1) * self.m];
            *yp = row.iter().zip(x).map(|(a, b)| a * b).sum();
        }
    }
}

impl CondensedOperator {
    /// λ_max(D^{1/2} W D^{1/2}) with D = diag(w): the largest ratio Σ_p w_p u_ν,p² / (uᵀ K u).
    /// The step energy ½uᵀKu + Σ w_p j(u_ν,p) is convex when α_j times this is below 1 —
    /// the discrete form of the smallness condition α_j c_j² < m_A (METHOD.md §1).
    pub fn trace_constant(&self, weights: &[f64]) -> f64 {
        let m = self.m;
        if m == 0 {
            return 0.0;
        }
        let sq: Vec<f64> = weights.iter().map(|w| w.sqrt()).collect();
        let mut x = vec![1.0 / (m as f64).sqrt(); m];
        let mut lambda = 0.0;
        for _ in 0..500 {
            let y: Vec<f64> = (0..m)
                .map(|p| sq[p] * (0..m).map(|q| self.w[p * m + q] * sq[q] * x[q]).sum::<f64>())
                .collect();
            let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm == 0.0 {
                return 0.0;
            }
            let next = y.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>();
            x = y.iter().map(|v| v / norm).collect();
            if (next - lambda).abs() <= 1e-10 * next.abs() {
                return next;
            }
            lambda = next;
        }
        lambda
    }
}
