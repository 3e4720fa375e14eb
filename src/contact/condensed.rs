//! The contact nodes of Γ₃ and the condensed operator W = C K⁻¹ Cᵀ (METHOD.md §4, "the fast
//! path"): with the cached factor of K, the contact problem of each step lives on the m
//! contact normals, u_ν = d − W λ, and K is never refactorised.

use crate::fem::DofMap;
use crate::linalg::{Counters, Factor, Forward, ForwardColumns};
use crate::mesh::BoundaryPart;
use faer::linalg::solvers::Solve;
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
}

/// W = C K⁻¹ Cᵀ and its inverse Q = W⁻¹ (both m × m, dense, symmetric positive definite),
/// and G = L⁻¹ P Cᵀ, which moves a step between C and the factor's forward sweep:
/// d = C K⁻¹ r = Gᵀ (L⁻¹ P r), and K⁻¹ (r − Cᵀ λ) = Pᵀ L⁻ᵀ (L⁻¹ P r − G λ).
pub struct CondensedOperator {
    /// W (row-major m × m): normal displacement at p per unit normal force at q.
    pub w: Vec<f64>,
    /// Q = W⁻¹ (row-major m × m): the Schur-complement stiffness on the contact normals.
    pub q: Vec<f64>,
    pub m: usize,
    /// G = L⁻¹ P Cᵀ, one sparse column per contact node.
    pub columns: ForwardColumns,
}

impl CondensedOperator {
    /// Forms G with one sparse forward sweep per contact node and W = Gᵀ G.
    pub fn new(nodes: &ContactNodes, factor: &Factor, counters: &Counters) -> Result<Self, String> {
        let m = nodes.len();
        let columns = ForwardColumns::new(factor, &nodes.rows, counters);
        let w = columns.gram();
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
        Ok(CondensedOperator { w, q, m, columns })
    }

    /// d = C K⁻¹ r from the forward sweep y = L⁻¹ P r.
    pub fn normal_displacements(&self, y: &Forward, d: &mut [f64]) {
        self.columns.transpose_apply(y, d);
    }

    /// y ← y − G λ: afterwards the backward sweep of y is K⁻¹ (r − Cᵀ λ).
    pub fn subtract_forces(&self, lambda: &[f64], y: &mut Forward) {
        self.columns.subtract_apply(lambda, y);
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
