//! The contact nodes of Γ₃ and the condensation of a step onto their normals (docs/method.md
//! §4.5, §9): with a factor of K, the contact problem of each step lives on the m contact
//! normals, u_ν = d − W λ with W = C K⁻¹ Cᵀ, and K is never refactorised.
//!
//! A [`Condensation`] is the seam between the time loop and the linear algebra: it turns a
//! step's right-hand side into the free normal displacements d = C K⁻¹ r and, once the contact
//! forces λ are known, recovers u = K⁻¹ (r − Cᵀ λ). Two implementations:
//!
//! * [`SplitSweeps`]: the faer factor's forward sweep y = L⁻¹ P r, d = Gᵀ y with G = L⁻¹ P Cᵀ,
//!   then y ← y − G λ and the backward sweep: one solve per step.
//! * [`StoredResponses`]: any [`LinearSolver`] and the stored responses Z = K⁻¹ Cᵀ: a whole
//!   solve u_free = K⁻¹ r, d = C u_free, then u = u_free − Z λ. Simple, and what a backend that
//!   cannot split its solves (an iterative or a distributed one) can offer.
//!
//! The active set sees only the [`NormalStiffness`] (Q = W⁻¹ and W).

use super::trailing::TrailingColumns;
use crate::fem::DofMap;
use crate::linalg::dense::{matvec_row_major, symmetrise_row_major, DenseCholesky};
use crate::linalg::{Counters, Factor, Forward, ForwardColumns, LinearSolver};
use crate::mesh::BoundaryPart;
use rustc_hash::FxHashMap as HashMap;
use std::sync::Arc;

/// The contact nodes with their nodal quadrature weights w_p, normals ν_p, and the rows of C
/// (u ↦ u_ν at the nodes) split into free and prescribed components.
#[derive(Clone, Debug)]
pub struct ContactNodes<const D: usize> {
    /// Mesh node indices.
    pub nodes: Vec<usize>,
    /// w_p: the share of Γ₃'s measure carried by node p.
    pub weights: Vec<f64>,
    /// ν_p: unit outward nodal normals.
    pub normals: Vec<[f64; D]>,
    /// Rows of C over the free unknowns: (unknown, coefficient) pairs.
    rows: Vec<Vec<(usize, f64)>>,
    /// The prescribed components of each node's normal displacement: (unknown, coefficient).
    prescribed: Vec<Vec<(usize, f64)>>,
    /// Γ₃ nodes set aside because their normal displacement is prescribed (nothing to solve).
    pub clamped_nodes: Vec<usize>,
}

/// A row whose free part keeps less than this share of its length off the span of its node's
/// earlier rows is dependent on them: a dependent row leaves round-off (1e-16), the weakest
/// independent rows of the tests two walls a few degrees apart (1e-2).
const DEPENDENT_ROW: f64 = 1e-8;

impl<const D: usize> ContactNodes<D> {
    /// The contact nodes of a boundary part; nodes whose normal displacement is fully
    /// prescribed are set aside (they would make W singular).
    pub fn new(part: &BoundaryPart<D>, dofs: &DofMap<D>) -> Self {
        Self::from_rows(&part.nodes, &part.weights, &part.normals, dofs).0
    }

    /// The contact rows u_ν = d_p·u at `nodes` (a node may carry several rows, docs/method.md
    /// §14) with their weights and directions; rows whose direction is fully prescribed are set
    /// aside, and so is a row whose free part at its node lies in the span of the free parts of
    /// that node's earlier rows (docs/method.md §17.3: a node on a symmetry plane of a curved
    /// zone, whose mean normal leans off the plane, has one free component for its normal and
    /// its tangential row; both kept, W would be singular). Also returns the indices of the rows
    /// kept.
    pub fn from_rows(
        nodes: &[usize],
        weights: &[f64],
        directions: &[[f64; D]],
        dofs: &DofMap<D>,
    ) -> (Self, Vec<usize>) {
        let mut kept = Vec::with_capacity(nodes.len());
        let mut out = ContactNodes {
            nodes: Vec::new(),
            weights: Vec::new(),
            normals: Vec::new(),
            rows: Vec::new(),
            prescribed: Vec::new(),
            clamped_nodes: Vec::new(),
        };
        // per node, an orthonormal basis of its kept rows' free parts
        let mut spans: HashMap<usize, Vec<[f64; D]>> = HashMap::default();
        for (k, &p) in nodes.iter().enumerate() {
            let nu = directions[k];
            // the direction's free part at its node (zero on prescribed components)
            let mut free: [f64; D] = std::array::from_fn(|c| if dofs.get(p, c).is_some() { nu[c] } else { 0.0 });
            if free.iter().all(|v| v.abs() < 1e-12) {
                out.clamped_nodes.push(p);
                continue;
            }
            // its component off the node's earlier rows (Gram–Schmidt, twice)
            let span = spans.entry(p).or_default();
            let size = free.iter().map(|v| v * v).sum::<f64>().sqrt();
            for _ in 0..2 {
                for b in span.iter() {
                    let along: f64 = (0..D).map(|c| free[c] * b[c]).sum();
                    for c in 0..D {
                        free[c] -= along * b[c];
                    }
                }
            }
            let rest = free.iter().map(|v| v * v).sum::<f64>().sqrt();
            if rest <= DEPENDENT_ROW * size {
                continue;
            }
            span.push(free.map(|v| v / rest));
            let row = (0..D).filter_map(|c| dofs.get(p, c).map(|d| (d, nu[c]))).collect();
            let fixed = (0..D)
                .filter(|&c| dofs.get(p, c).is_none() && nu[c] != 0.0)
                .map(|c| (dofs.index(p, c), nu[c]))
                .collect();
            out.nodes.push(p);
            out.weights.push(weights[k]);
            out.normals.push(nu);
            out.rows.push(row);
            out.prescribed.push(fixed);
            kept.push(k);
        }
        (out, kept)
    }

    /// Adds to row k (direction d) the terms −c_q d·u_q of other nodes q (`terms`: (q, c_q)): the
    /// master nodes of a row of contact between two bodies, d·(u_S − Σ c_i u_i) — for the normal
    /// row (d = −n) u_ν = (Σ c_i u_i − u_S)·n, for a tangential one the slip relative to the master
    /// (docs/method.md §18).
    pub fn add_master_terms(&mut self, k: usize, terms: &[(usize, f64)], dofs: &DofMap<D>) {
        self.push_terms(k, terms, -1.0, dofs);
    }

    /// Appends sign · c_q d·u_q of each (q, c_q) in `terms` to row k (direction d): its free
    /// components to the row, its prescribed ones to the row's prescribed part.
    fn push_terms(&mut self, k: usize, terms: &[(usize, f64)], sign: f64, dofs: &DofMap<D>) {
        let d = self.normals[k];
        for &(q, c) in terms {
            for (i, &v) in d.iter().enumerate() {
                let v = sign * c * v;
                match dofs.get(q, i) {
                    Some(dof) => self.rows[k].push((dof, v)),
                    None if v != 0.0 => self.prescribed[k].push((dofs.index(q, i), v)),
                    None => {}
                }
            }
        }
    }

    /// Makes row k (direction d) the row Σ_q c_q d·u_q over `terms` ((q, c_q), its own node among
    /// them) instead of d·u of its node: a row of second-order faces (docs/method.md §19.3). It
    /// replaces every term of the row, so a pair's master terms are added after it (§18.6).
    pub fn spread(&mut self, k: usize, terms: &[(usize, f64)], dofs: &DofMap<D>) {
        self.rows[k].clear();
        self.prescribed[k].clear();
        self.push_terms(k, terms, 1.0, dofs);
    }

    /// m, the number of contact nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True if there are no contact nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The rows of C over the free unknowns.
    pub fn rows(&self) -> &[Vec<(usize, f64)>] {
        &self.rows
    }

    /// The free unknowns the rows use (a non-zero coefficient), ascending: what the factor orders
    /// last (docs/method.md §9.1). A row lists every free component of its node, zeros too.
    pub fn unknowns(&self) -> Vec<usize> {
        let mut unknowns: Vec<usize> = self
            .rows
            .iter()
            .flatten()
            .filter(|&&(_, c)| c != 0.0)
            .map(|&(i, _)| i)
            .collect();
        unknowns.sort_unstable();
        unknowns.dedup();
        unknowns
    }

    /// Whether each node's rows use exactly as many unknowns as there are rows (a face normal to
    /// an axis; with friction, a frame per node): then Q can be read off the factor's trailing
    /// block (docs/method.md §9.4).
    pub fn trailing_block_applies(&self) -> bool {
        super::trailing::applies(&self.nodes, &self.rows)
    }

    /// The normal displacements u_ν = ν·u at the contact nodes of a full displacement vector.
    pub fn normal_displacements(&self, u: &[f64], out: &mut [f64]) {
        for ((o, row), fixed) in out.iter_mut().zip(&self.rows).zip(&self.prescribed) {
            *o = row.iter().chain(fixed).map(|(d, c)| c * u[*d]).sum();
        }
    }

    /// The prescribed components of each row's normal displacement: (unknown, coefficient).
    pub fn prescribed_rows(&self) -> &[Vec<(usize, f64)>] {
        &self.prescribed
    }

    /// The part of u_ν that prescribed components contribute (zero when none is prescribed
    /// on a contact node or the prescribed values are zero): added to d = C K⁻¹ r.
    pub fn prescribed_offset(&self, values: &[f64], d: &mut [f64]) {
        for (dp, fixed) in d.iter_mut().zip(&self.prescribed) {
            *dp += fixed.iter().map(|(i, c)| c * values[*i]).sum::<f64>();
        }
    }

    /// Cᵀ λ over all unknowns (prescribed components included: their share is a reaction).
    pub fn add_forces(&self, lambda: &[f64], out: &mut [f64]) {
        for ((l, row), fixed) in lambda.iter().zip(&self.rows).zip(&self.prescribed) {
            for (d, c) in row.iter().chain(fixed) {
                out[*d] += l * c;
            }
        }
    }
}

/// The condensed stiffness of the contact normals as the active set uses it.
pub trait NormalStiffness {
    /// m.
    fn m(&self) -> usize;
    /// y = Q x, Q = W⁻¹.
    fn apply_q(&self, x: &[f64], y: &mut [f64]);
    /// Entry (p, r) of Q.
    fn q(&self, p: usize, r: usize) -> f64;
    /// W (row-major), where Q = W⁻¹ exactly: Δ = W G (docs/method.md §4.6).
    fn w(&self) -> Option<&[f64]> {
        None
    }
    /// y = W x where Q = W⁻¹ exactly, whether or not W was formed; false where that product is
    /// not at hand.
    fn apply_w(&self, _x: &[f64], _y: &mut [f64]) -> bool {
        false
    }
}

/// W and Q = W⁻¹, dense (m × m, row-major).
#[derive(Clone, Debug)]
pub struct DenseNormalStiffness {
    /// W: normal displacement at p per unit normal force at q.
    pub w: Vec<f64>,
    /// Q = W⁻¹: the Schur-complement stiffness on the contact normals.
    pub q: Vec<f64>,
    pub m: usize,
    /// Whether Q is W⁻¹ (false once rigid parameters are eliminated from Q, docs/method.md §7.7).
    pub q_inverts_w: bool,
}

impl DenseNormalStiffness {
    /// Inverts W (symmetric positive definite) by a dense Cholesky factorisation.
    pub fn from_w(w: Vec<f64>, m: usize) -> Result<Self, String> {
        let llt = DenseCholesky::new(m, |i, j| w[i * m + j])
            .ok_or_else(|| "the condensed contact operator W = C K⁻¹ Cᵀ is not positive definite (are two contact nodes sharing one position, or is a contact node's normal fully constrained?)".to_string())?;
        let q = llt.symmetric_inverse();
        Ok(DenseNormalStiffness {
            w,
            q,
            m,
            q_inverts_w: true,
        })
    }
}

impl NormalStiffness for DenseNormalStiffness {
    fn m(&self) -> usize {
        self.m
    }

    /// faer's SIMD product, on two threads from m = 512 on: the contact solve's products by Q
    /// were its largest cost at m in the thousands (docs/method.md §9.2).
    fn apply_q(&self, x: &[f64], y: &mut [f64]) {
        matvec_row_major(&self.q, self.m, x, y);
    }

    fn q(&self, p: usize, r: usize) -> f64 {
        self.q[p * self.m + r]
    }

    fn w(&self) -> Option<&[f64]> {
        (self.q_inverts_w && !self.w.is_empty()).then_some(&self.w[..])
    }
}

/// A condensation's stiffness with its products by W, formed or not (a product by W without W
/// is two triangular solves with L_cc, docs/method.md §9.4, §9.7): what the frictionless
/// active set solves with.
pub struct WithCompliance<'a>(pub &'a dyn Condensation);

impl NormalStiffness for WithCompliance<'_> {
    fn m(&self) -> usize {
        self.0.stiffness().m
    }

    fn apply_q(&self, x: &[f64], y: &mut [f64]) {
        self.0.stiffness().apply_q(x, y)
    }

    fn q(&self, p: usize, r: usize) -> f64 {
        self.0.stiffness().q(p, r)
    }

    fn w(&self) -> Option<&[f64]> {
        self.0.stiffness().w()
    }

    fn apply_w(&self, x: &[f64], y: &mut [f64]) -> bool {
        if self.0.stiffness().q_inverts_w {
            self.0.apply_w(x, y);
        }
        self.0.stiffness().q_inverts_w
    }
}

/// The condensation of a step onto the contact normals (docs/method.md §9).
pub trait Condensation: Send {
    /// Which implementation ran (for the plan and summary.json).
    fn name(&self) -> &'static str;
    /// W and Q.
    fn stiffness(&self) -> &DenseNormalStiffness;
    /// W and Q, to eliminate rigid parameters from Q (docs/method.md §7.7).
    fn stiffness_mut(&mut self) -> &mut DenseNormalStiffness;
    /// Starts a step: d = C K⁻¹ rhs over the free unknowns, keeping what [`Self::recover`] needs.
    fn free_normal(&mut self, rhs: &[f64], d: &mut [f64], counters: &Counters);
    /// Completes it: u = K⁻¹ (rhs − Cᵀ λ) for the rhs of the last [`Self::free_normal`].
    fn recover(&mut self, lambda: &[f64], u: &mut [f64], counters: &Counters);

    /// The step matrix is now `ratio` times the one condensed (docs/method.md §20.3): W and Q
    /// follow (W/ratio, ratio·Q), while the solves go on with the factor condensed — the caller
    /// divides the right-hand side and λ by the matrix's scale.
    fn rescale(&mut self, ratio: f64) {
        let s = self.stiffness_mut();
        s.w.iter_mut().for_each(|v| *v /= ratio);
        s.q.iter_mut().for_each(|v| *v *= ratio);
    }

    /// y = W x (W = C K⁻¹ Cᵀ, whether or not it was formed).
    fn apply_w(&self, x: &[f64], y: &mut [f64]) {
        let s = self.stiffness();
        matvec_row_major(&s.w, s.m, x, y);
    }

    /// λ_max(D^{1/2} W D^{1/2}) with D = diag(w): the largest ratio Σ_p w_p u_ν,p² / (uᵀ K u).
    /// The step energy ½uᵀKu + Σ w_p j(u_ν,p) is convex when α_j times this is below 1 —
    /// the discrete form of the smallness condition α_j c_j² < m_A (docs/method.md §1).
    /// A power iteration, each step a product by W.
    /// Zero where this process holds no contact matrices (the PETSc backend's ranks but the first).
    fn trace_constant(&self, weights: &[f64]) -> f64 {
        let m = self.stiffness().m;
        if m == 0 || weights.iter().all(|&w| w == 0.0) {
            return 0.0;
        }
        debug_assert_eq!(weights.len(), m, "a weight per condensed row");
        let sq: Vec<f64> = weights.iter().map(|w| w.sqrt()).collect();
        let mut x = vec![1.0 / (m as f64).sqrt(); m];
        let (mut v, mut y) = (vec![0.0; m], vec![0.0; m]);
        let mut lambda = 0.0;
        for _ in 0..500 {
            for ((vp, s), xp) in v.iter_mut().zip(&sq).zip(&x) {
                *vp = s * xp;
            }
            self.apply_w(&v, &mut y);
            for (yp, s) in y.iter_mut().zip(&sq) {
                *yp *= s;
            }
            let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm == 0.0 {
                return 0.0;
            }
            let next = y.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>();
            for (xp, yp) in x.iter_mut().zip(&y) {
                *xp = yp / norm;
            }
            if (next - lambda).abs() <= 1e-10 * next.abs() {
                return next;
            }
            lambda = next;
        }
        lambda
    }
}

/// The one-solve path of the faer factor: forward sweep, contact, backward sweep.
pub struct SplitSweeps {
    factor: Arc<Factor>,
    columns: Columns,
    stiffness: DenseNormalStiffness,
    y: Forward,
    /// The step matrix over the one factorised (docs/method.md §20.3): W by triangular solves
    /// with L_cc is divided by it.
    scale: f64,
}

/// How the split sweeps reach the contact rows from a forward-swept vector.
enum Columns {
    /// G = L⁻¹ P Cᵀ, one sparse column per contact row.
    Sparse(ForwardColumns),
    /// L_cc, the factor's trailing block (docs/method.md §9.4).
    Trailing(TrailingColumns),
}

impl SplitSweeps {
    /// Forms G with one sparse forward sweep per contact node and W = Gᵀ G.
    pub fn new<const D: usize>(
        nodes: &ContactNodes<D>,
        factor: Arc<Factor>,
        counters: &Counters,
    ) -> Result<Self, String> {
        let columns = ForwardColumns::new(&factor, nodes.rows(), counters);
        let stiffness = DenseNormalStiffness::from_w(columns.gram(), nodes.len())?;
        Ok(Self::with(factor, Columns::Sparse(columns), stiffness))
    }

    /// Q (and W with `with_w`) read off the factor's trailing block (docs/method.md §9.4); None
    /// where that does not apply ([`ContactNodes::trailing_block_applies`], or the rows'
    /// unknowns were not ordered last).
    pub fn off_trailing_block<const D: usize>(
        nodes: &ContactNodes<D>,
        factor: Arc<Factor>,
        with_w: bool,
    ) -> Option<Self> {
        let (columns, q, w) = TrailingColumns::new(&nodes.nodes, nodes.rows(), &factor, with_w)?;
        let stiffness = DenseNormalStiffness {
            w,
            q,
            m: nodes.len(),
            q_inverts_w: true,
        };
        Some(Self::with(factor, Columns::Trailing(columns), stiffness))
    }

    fn with(factor: Arc<Factor>, columns: Columns, stiffness: DenseNormalStiffness) -> Self {
        SplitSweeps {
            y: Forward::zeros(factor.n()),
            factor,
            columns,
            stiffness,
            scale: 1.0,
        }
    }
}

impl Condensation for SplitSweeps {
    fn name(&self) -> &'static str {
        match self.columns {
            Columns::Sparse(_) => "split sweeps (G = L⁻¹PCᵀ, one solve per step)",
            Columns::Trailing(_) => {
                "split sweeps (Q = T⁻ᵀ L_cc L_ccᵀ T⁻¹ read off the factor's trailing block, one solve per step)"
            }
        }
    }

    fn stiffness(&self) -> &DenseNormalStiffness {
        &self.stiffness
    }

    fn stiffness_mut(&mut self) -> &mut DenseNormalStiffness {
        &mut self.stiffness
    }

    fn free_normal(&mut self, rhs: &[f64], d: &mut [f64], _counters: &Counters) {
        self.factor.forward_into(rhs, &mut self.y);
        match &mut self.columns {
            Columns::Sparse(g) => g.transpose_apply(&self.y, d),
            Columns::Trailing(t) => t.free_normal(&self.y, d),
        }
    }

    fn recover(&mut self, lambda: &[f64], u: &mut [f64], counters: &Counters) {
        match &mut self.columns {
            Columns::Sparse(g) => g.subtract_apply(lambda, &mut self.y),
            Columns::Trailing(t) => t.subtract(lambda, &mut self.y),
        }
        self.factor.backward_from(&mut self.y, u, counters);
    }

    /// W x from W where it was formed, else by two triangular solves with L_cc.
    fn apply_w(&self, x: &[f64], y: &mut [f64]) {
        match &self.columns {
            Columns::Trailing(t) if self.stiffness.w.is_empty() => {
                t.apply_w(x, y);
                if self.scale != 1.0 {
                    y.iter_mut().for_each(|v| *v /= self.scale);
                }
            }
            _ => matvec_row_major(&self.stiffness.w, self.stiffness.m, x, y),
        }
    }

    fn rescale(&mut self, ratio: f64) {
        let s = &mut self.stiffness;
        s.w.iter_mut().for_each(|v| *v /= ratio);
        s.q.iter_mut().for_each(|v| *v *= ratio);
        self.scale *= ratio;
    }
}

/// u = u_free − Z λ for the responses Z (column-major, a column of `u_free.len()` numbers per
/// row of C): only the columns of non-zero forces are read. Shared by every condensation that
/// stores Z (here and the PETSc backend's rows of it).
pub fn subtract_responses(u_free: &[f64], z: &[f64], lambda: &[f64], u: &mut [f64]) {
    let n = u_free.len();
    u.copy_from_slice(u_free);
    for (p, &l) in lambda.iter().enumerate() {
        if l != 0.0 {
            for (ui, zi) in u.iter_mut().zip(&z[p * n..(p + 1) * n]) {
                *ui -= l * zi;
            }
        }
    }
}

/// r ← r − Cᵀ λ for the rows of C as (unknown, coefficient): the right-hand side of a recovery
/// solve u = K⁻¹ (r − Cᵀ λ).
pub fn subtract_normal_forces(rhs: &mut [f64], rows: &[Vec<(usize, f64)>], lambda: &[f64]) {
    for (&l, row) in lambda.iter().zip(rows) {
        for &(i, c) in row {
            rhs[i] -= c * l;
        }
    }
}

/// The simple path for any linear solver: stored responses Z = K⁻¹ Cᵀ (n × m), or, without
/// `keep`, Z only while W is formed and a recovery solve per step.
pub struct StoredResponses {
    solver: Arc<dyn LinearSolver>,
    rows: Vec<Vec<(usize, f64)>>,
    /// Z column-major: column p is K⁻¹ (row p of C)ᵀ (empty: the recovery is a solve).
    z: Vec<f64>,
    stiffness: DenseNormalStiffness,
    u_free: Vec<f64>,
    /// The step's right-hand side, for the recovery solve.
    rhs: Vec<f64>,
}

impl StoredResponses {
    /// m solves for Z (in blocks of right-hand sides) and W = C Z; Z is kept with `keep`.
    pub fn new<const D: usize>(
        nodes: &ContactNodes<D>,
        solver: Arc<dyn LinearSolver>,
        keep: bool,
        counters: &Counters,
    ) -> Result<Self, String> {
        let (n, m) = (solver.n(), nodes.len());
        let mut z = Vec::new();
        crate::alloc::fallible(|| z.try_reserve_exact(n * m))
            .map_err(|_| format!("out of memory for the stored responses Z ({n} × {m})"))?;
        z.resize(n * m, 0.0);
        for (p, row) in nodes.rows().iter().enumerate() {
            for &(d, c) in row {
                z[p * n + d] = c;
            }
        }
        solver.solve_many(&mut z, m, counters);
        let rows = nodes.rows().to_vec();
        let mut w = vec![0.0; m * m];
        for (p, row) in rows.iter().enumerate() {
            for q in 0..m {
                w[p * m + q] = row.iter().map(|&(d, c)| c * z[q * n + d]).sum();
            }
        }
        symmetrise_row_major(&mut w, m);
        Ok(StoredResponses {
            solver,
            rows,
            z: if keep { z } else { Vec::new() },
            stiffness: DenseNormalStiffness::from_w(w, m)?,
            u_free: vec![0.0; n],
            rhs: if keep { Vec::new() } else { vec![0.0; n] },
        })
    }
}

impl Condensation for StoredResponses {
    fn name(&self) -> &'static str {
        if self.z.is_empty() {
            "a recovery solve (W from Z = K⁻¹Cᵀ once, a free and a recovery solve per step)"
        } else {
            "stored responses (Z = K⁻¹Cᵀ, one whole solve per step)"
        }
    }

    fn stiffness(&self) -> &DenseNormalStiffness {
        &self.stiffness
    }

    fn stiffness_mut(&mut self) -> &mut DenseNormalStiffness {
        &mut self.stiffness
    }

    fn free_normal(&mut self, rhs: &[f64], d: &mut [f64], counters: &Counters) {
        if self.z.is_empty() {
            self.rhs.copy_from_slice(rhs);
        }
        self.solver.solve(rhs, &mut self.u_free, counters);
        for (dp, row) in d.iter_mut().zip(&self.rows) {
            *dp = row.iter().map(|&(i, c)| c * self.u_free[i]).sum();
        }
    }

    fn recover(&mut self, lambda: &[f64], u: &mut [f64], counters: &Counters) {
        if self.z.is_empty() {
            subtract_normal_forces(&mut self.rhs, &self.rows, lambda);
            self.solver.solve(&self.rhs, u, counters);
        } else {
            subtract_responses(&self.u_free, &self.z, lambda, u);
        }
    }
}

#[cfg(test)]
mod trailing_tests {
    //! The split sweeps off the trailing block (docs/method.md §9.4) against the sparse sweeps.
    use super::*;
    use crate::fem::{assembly::assemble_stiffness, DofMap};
    use crate::linalg::sparse::test_matrices::relative_difference;
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
        let analysis = Factor::analyse_with_last(&k, &rows.unknowns()).unwrap();
        let factor = Factor::new(&analysis, &k, &Counters::default()).unwrap();
        (rows, Arc::new(factor))
    }

    /// Q, W, the free normal displacements and the recovery of the trailing block against the
    /// sparse sweeps' G on the same factor.
    #[test]
    fn the_trailing_block_agrees_with_the_sparse_sweeps() {
        for rows in ["normal", "frame"] {
            let (nodes, factor) = case(rows);
            let m = nodes.len();
            assert!(nodes.trailing_block_applies());
            let counters = Counters::default();
            let mut split = SplitSweeps::new(&nodes, factor.clone(), &counters).unwrap();
            let mut trailing = SplitSweeps::off_trailing_block(&nodes, factor.clone(), true).unwrap();
            let lean = SplitSweeps::off_trailing_block(&nodes, factor.clone(), false).unwrap();
            let (a, b) = (trailing.stiffness(), split.stiffness());
            assert!(
                relative_difference(&a.q, &b.q) < 1e-11,
                "{rows}: Q {:e}",
                relative_difference(&a.q, &b.q)
            );
            assert!(
                relative_difference(&a.w, &b.w) < 1e-11,
                "{rows}: W {:e}",
                relative_difference(&a.w, &b.w)
            );
            assert!(lean.stiffness().w.is_empty());
            // W x without W formed: by two triangular solves
            let x: Vec<f64> = (0..m).map(|p| ((p as f64) * 0.71).sin()).collect();
            let (mut wx, mut wx_lean) = (vec![0.0; m], vec![0.0; m]);
            split.apply_w(&x, &mut wx);
            lean.apply_w(&x, &mut wx_lean);
            assert!(relative_difference(&wx_lean, &wx) < 1e-12);
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
            assert!(relative_difference(&d_trailing, &d_split) < 1e-12);
            let (mut u_split, mut u_trailing) = (vec![0.0; n], vec![0.0; n]);
            split.recover(&lambda, &mut u_split, &counters);
            trailing.recover(&lambda, &mut u_trailing, &counters);
            assert!(relative_difference(&u_trailing, &u_split) < 1e-12);
            // and u is the displacement of those forces: C u = d − W λ
            let mut u_nu = vec![0.0; m];
            nodes.normal_displacements(&u_trailing, &mut u_nu);
            let mut w_lambda = vec![0.0; m];
            trailing.apply_w(&lambda, &mut w_lambda);
            let expected: Vec<f64> = d_split.iter().zip(&w_lambda).map(|(d, w)| d - w).collect();
            assert!(relative_difference(&u_nu, &expected) < 1e-12);
        }
    }

    #[test]
    fn a_row_over_two_unknowns_is_left_to_the_sparse_sweeps() {
        let (nodes, factor) = case("oblique");
        assert!(!nodes.trailing_block_applies());
        assert!(SplitSweeps::off_trailing_block(&nodes, factor, true).is_none());
    }

    /// A node with y prescribed and rows along n = (cos α, sin α) and t = (sin α, −cos α): both
    /// have free parts, along x alone, so t is set aside; with both components free both stay,
    /// and a row along n again at the free node is set aside too.
    #[test]
    fn a_row_dependent_on_its_nodes_earlier_rows_is_set_aside() {
        let mut dofs = DofMap::<2>::new(2, &[]);
        dofs.prescribe(0, 1);
        let a = 0.05f64;
        let (n, t) = ([a.cos(), a.sin()], [a.sin(), -a.cos()]);
        let (rows, kept) = ContactNodes::from_rows(&[0, 0, 1, 1, 1], &[1.0; 5], &[n, t, n, t, n], &dofs);
        assert_eq!(kept, vec![0, 2, 3]);
        assert_eq!(rows.nodes, vec![0, 1, 1]);
        assert!(rows.clamped_nodes.is_empty());
    }
}
