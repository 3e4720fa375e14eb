//! The contact problem of one time step on the m contact normals, solved by a globalised
//! primal–dual active-set method (docs/method.md §4).
//!
//! With u_ν = r and the condensed stiffness Q = W⁻¹, one step is the bound-constrained
//! minimisation (docs/method.md §3, condensed)
//!
//! ```text
//!     minimise  E(r) = ½ (r − d)ᵀ Q (r − d) + Σ_p w_p j_ε(r_p)   subject to  r_p ≤ g_p,
//! ```
//!
//! whose KKT conditions are the contact law: λ = Q(d − r) = ξ + η, ξ_p = w_p j_ε'(r_p),
//! η ≥ 0, r ≤ g, η(r − g) = 0. Each iteration
//!
//! 1. computes the gradient G = Q(r − d) + w j_ε'(r) and the multiplier estimate η = −G;
//! 2. takes the active set of the PDAS rule 𝒜 = {p : η_p + c_p(r_p − g_p) > 0}, c_p = Q_pp,
//!    enlarged by the nodes within δ of the bound that are pushed into it (this keeps every
//!    direction a descent direction, Bertsekas' projected Newton);
//! 3. solves the Newton system on the inactive set ℐ with the Hessian Q_ℐℐ + diag(w j_ε''),
//!    replacing j_ε'' by max(j_ε'', 0) when the non-monotone law makes it indefinite (the
//!    convex part only: still a descent direction), and moves 𝒜 onto the bound;
//! 4. backtracks along the projected path until the energy E decreases (Armijo).
//!
//! It stops when the complementarity residual is below tolerance, and after a capped number
//! of iterations reports failure instead of looping.

use super::condensed::NormalStiffness;
use super::nodal::NodalLaws;
use faer::linalg::solvers::Solve;
use faer::Mat;

/// Tolerance and iteration cap of the contact solve.
#[derive(Clone, Copy, Debug)]
pub struct ContactSettings {
    /// Relative complementarity residual at which a step is converged.
    pub tolerance: f64,
    /// Newton iterations per step before giving up.
    pub max_iterations: usize,
    /// Above this many free (inactive) contact nodes the Newton system is solved by Jacobi-
    /// preconditioned conjugate gradients with products by Q instead of a dense Cholesky
    /// factorisation of its inactive block (docs/method.md §9.2).
    pub dense_limit: usize,
}

/// Where a contact node ends a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeStatus {
    /// u_ν ≤ 0: not pressing into the layer.
    Separated,
    /// 0 < u_ν < g: compressing the layer.
    InLayer,
    /// u_ν = g: on the rigid bound (active).
    OnBound,
}

impl NodeStatus {
    /// Integer code for output files.
    pub fn code(self) -> i32 {
        match self {
            NodeStatus::Separated => 0,
            NodeStatus::InLayer => 1,
            NodeStatus::OnBound => 2,
        }
    }
}

/// The contact unknowns of one step, kept between steps as the warm start.
#[derive(Clone, Debug)]
pub struct ContactState {
    /// r = u_ν at the contact nodes.
    pub normal_displacement: Vec<f64>,
    /// λ = ξ + η: total nodal contact force (positive pushes the body back).
    pub force: Vec<f64>,
    /// ξ_p = w_p j_ε'(r_p): the compliance of the layer.
    pub compliance_force: Vec<f64>,
    /// η_p ≥ 0: the reaction of the rigid bound (zero off the bound).
    pub bound_force: Vec<f64>,
    /// Status of each node.
    pub status: Vec<NodeStatus>,
}

impl ContactState {
    /// An initial state with no contact.
    pub fn new(m: usize) -> Self {
        ContactState {
            normal_displacement: vec![0.0; m],
            force: vec![0.0; m],
            compliance_force: vec![0.0; m],
            bound_force: vec![0.0; m],
            status: vec![NodeStatus::Separated; m],
        }
    }
}

/// What one contact solve did.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct ContactOutcome {
    pub iterations: usize,
    /// Final complementarity residual relative to the force scale.
    pub residual: f64,
    /// Line-search step halvings over the solve.
    pub line_search_cuts: usize,
    /// Iterations whose Hessian was indefinite and was convexified.
    pub convexified: usize,
    /// Newton directions computed by conjugate gradients (more free nodes than `dense_limit`).
    pub iterative: usize,
    /// Nodes on the bound at the end.
    pub active: usize,
}

/// Why a contact solve stopped without converging.
#[derive(Clone, Debug)]
pub struct ContactFailure {
    pub outcome: ContactOutcome,
    pub reason: String,
}

/// The contact problem data of a step: condensed operator, the rows' laws (with their nodal
/// weights), the laws' origins and the bound (docs/method.md §14).
pub struct ActiveSetSolver<'a> {
    pub operator: &'a dyn NormalStiffness,
    /// Σ_t w_t j_t per row (empty: no law).
    pub laws: &'a NodalLaws,
    /// o_p: the laws act on the penetration r_p − o_p (the initial gap to an obstacle);
    /// `None` for o = 0.
    pub offset: Option<&'a [f64]>,
    /// g_p per row (∞ where a row has none), or `None` for no bound.
    pub bound: Option<&'a [f64]>,
    pub settings: ContactSettings,
}

const ARMIJO: f64 = 1e-4;
const MIN_STEP: f64 = 1e-12;

impl ActiveSetSolver<'_> {
    fn m(&self) -> usize {
        self.operator.m()
    }

    fn g(&self, p: usize) -> f64 {
        self.bound.map_or(f64::INFINITY, |g| g[p])
    }

    #[inline]
    fn origin(&self, p: usize) -> f64 {
        self.offset.map_or(0.0, |o| o[p])
    }

    #[inline]
    fn law_derivative(&self, p: usize, r: f64) -> f64 {
        self.laws.force(p, r - self.origin(p))
    }

    /// Q(r − d) and the gradient G of E at r.
    fn gradient(&self, r: &[f64], d: &[f64], qrd: &mut [f64], grad: &mut [f64]) {
        let diff: Vec<f64> = r.iter().zip(d).map(|(a, b)| a - b).collect();
        self.operator.apply_q(&diff, qrd);
        for p in 0..self.m() {
            grad[p] = qrd[p] + self.law_derivative(p, r[p]);
        }
    }

    /// max_p |min(c_p(g_p − r_p), −G_p)| (|G_p| without a bound), in force units.
    fn complementarity_residual(&self, r: &[f64], grad: &[f64]) -> f64 {
        (0..self.m())
            .map(|p| {
                let g = self.g(p);
                if g.is_finite() {
                    (self.c(p) * (g - r[p])).min(-grad[p]).abs()
                } else {
                    grad[p].abs()
                }
            })
            .fold(0.0, f64::max)
    }

    fn c(&self, p: usize) -> f64 {
        self.operator.q(p, p)
    }

    /// E(r + Δ) − E(r), formed from differences to avoid cancellation:
    /// GᵀΔ + ½ΔᵀQΔ + Σ_p w_p [j(r_p + Δ_p) − j(r_p) − j'(r_p)Δ_p], the bracket from its
    /// Taylor expansion ½ j''(r_p) Δ_p² when Δ_p is tiny (the difference of j values would be
    /// below their rounding near convergence, and Armijo could not see the decrease).
    fn energy_change(&self, r: &[f64], delta: &[f64], grad: &[f64]) -> f64 {
        let m = self.m();
        let mut qdelta = vec![0.0; m];
        self.operator.apply_q(delta, &mut qdelta);
        let mut change = 0.0;
        for p in 0..m {
            change += delta[p] * (grad[p] + 0.5 * qdelta[p]);
            if !self.laws.is_empty() {
                change += self.laws.energy_increment(p, r[p] - self.origin(p), delta[p]);
            }
        }
        change
    }

    /// The complementarity residual at r + Δ.
    fn trial_residual(&self, r: &[f64], delta: &[f64], d: &[f64]) -> f64 {
        let m = self.m();
        let moved: Vec<f64> = (0..m).map(|p| r[p] + delta[p]).collect();
        let (mut qrd, mut grad) = (vec![0.0; m], vec![0.0; m]);
        self.gradient(&moved, d, &mut qrd, &mut grad);
        self.complementarity_residual(&moved, &grad)
    }

    /// The force scale of the step: max(‖Q d‖∞, ‖Q v‖∞, max_p w_p S sup μ), v_p = min(0, g_p, o_p)
    /// the interference of rows that start past their bound or their obstacle's surface (a body
    /// placed into an obstacle is pushed out by forces of that size even without load; without
    /// the term an unloaded step with interference had a scale of 0 and could not converge).
    fn force_scale(&self, d: &[f64]) -> f64 {
        let m = self.m();
        let mut qd = vec![0.0; m];
        self.operator.apply_q(d, &mut qd);
        let load = qd.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let interference: Vec<f64> = (0..m)
            .map(|p| {
                let g = self.g(p);
                0.0f64.min(if g.is_finite() { g } else { 0.0 }).min(self.origin(p))
            })
            .collect();
        let overlap = if interference.iter().any(|v| *v < 0.0) {
            self.operator.apply_q(&interference, &mut qd);
            qd.iter().fold(0.0f64, |a, b| a.max(b.abs()))
        } else {
            0.0
        };
        let law = self.laws.force_scale(m);
        load.max(overlap).max(law).max(f64::MIN_POSITIVE)
    }

    /// Solves the step for free normal displacements `d` = C K⁻¹ F̃, warm-started from `state`.
    pub fn solve(&self, d: &[f64], state: &mut ContactState) -> Result<ContactOutcome, ContactFailure> {
        let m = self.m();
        let r = &mut state.normal_displacement;
        for (p, rp) in r.iter_mut().enumerate() {
            *rp = rp.min(self.g(p));
        }
        let scale = self.force_scale(d);
        let tol = self.settings.tolerance * scale;
        let (mut qrd, mut grad) = (vec![0.0; m], vec![0.0; m]);
        let mut outcome = ContactOutcome::default();
        let mut direction = vec![0.0; m];
        let mut trial = vec![0.0; m];
        // A kink of j at r = 0 (∂j(0) an interval, e.g. [−Sa, Sa]): the smoothed j_ε bends
        // within ~ε of 0, which a Newton model taken farther out cannot see. The path stops
        // a node at 0 instead of carrying it across (it may cross at the next iteration, from
        // inside the smoothing zone); otherwise it zig-zags across the kink without converging.
        let kink: Vec<f64> = (0..m).map(|p| self.laws.kink_width(p)).collect();
        // The smallest residual so far: a full step that raises the energy is accepted only if
        // it halves this (a watchdog: such steps cannot cycle).
        let mut best_residual = f64::INFINITY;
        loop {
            // 1. gradient and residual
            self.gradient(r, d, &mut qrd, &mut grad);
            let residual = self.complementarity_residual(r, &grad);
            best_residual = best_residual.min(residual);
            outcome.residual = residual / scale;
            if std::env::var_os("HVI_TRACE_CONTACT").is_some() {
                eprintln!(
                    "  contact it {} residual {:.3e} cuts {}",
                    outcome.iterations,
                    residual / scale,
                    outcome.line_search_cuts
                );
                for p in 0..m {
                    let g = self.g(p);
                    let phi = if g.is_finite() {
                        (self.c(p) * (g - r[p])).min(-grad[p]).abs()
                    } else {
                        grad[p].abs()
                    };
                    if phi > 0.5 * residual && residual > tol {
                        eprintln!(
                            "    node {p}: r {:.6e} g-r {:.3e} G {:.3e} j'' {:.3e} c {:.3e}",
                            r[p],
                            g - r[p],
                            grad[p],
                            self.laws.stiffness(p, r[p] - self.origin(p)),
                            self.c(p)
                        );
                    }
                }
            }
            if residual <= tol {
                break;
            }
            if outcome.iterations == self.settings.max_iterations {
                return Err(ContactFailure {
                    outcome,
                    reason: format!("no convergence in {} iterations", self.settings.max_iterations),
                });
            }
            outcome.iterations += 1;

            // 2. active set: the PDAS rule, plus nodes within δ of the bound pushed into it
            let projected_step = (0..m)
                .map(|p| (r[p] - (r[p] - grad[p] / self.c(p)).min(self.g(p))).abs())
                .fold(0.0, f64::max);
            let delta = projected_step.min(
                1e-3 * self.bound.map_or(1.0, |g| {
                    g.iter()
                        .filter(|v| v.is_finite())
                        .fold(0.0f64, |a, b| a.max(b.abs()))
                        .max(1e-3)
                }),
            );
            let active: Vec<bool> = (0..m)
                .map(|p| {
                    let g = self.g(p);
                    g.is_finite() && (r[p] - grad[p] / self.c(p) >= g || (g - r[p] <= delta && grad[p] < 0.0))
                })
                .collect();
            let free: Vec<usize> = (0..m).filter(|&p| !active[p]).collect();

            // 3. Newton direction on the inactive set, diagonal scaling on the active set
            let curvature: Vec<f64> = free
                .iter()
                .map(|&p| self.laws.stiffness(p, r[p] - self.origin(p)))
                .collect();
            let free_dir = self.newton_direction(&free, &curvature, &grad, &mut outcome);
            let mut predicted_slope = 0.0;
            for (k, &p) in free.iter().enumerate() {
                direction[p] = free_dir[k];
                predicted_slope += grad[p] * free_dir[k];
            }
            for p in (0..m).filter(|&p| active[p]) {
                direction[p] = grad[p] / self.c(p);
            }

            // 4. projected Armijo backtracking on the energy
            let mut alpha = 1.0;
            loop {
                let mut decrease_bound = alpha * predicted_slope;
                for p in 0..m {
                    let mut moved = (r[p] - alpha * direction[p]).min(self.g(p));
                    let o = self.origin(p);
                    if !active[p] && (r[p] - o).abs() > kink[p] && (moved - o) * (r[p] - o) < 0.0 {
                        // stop at the kink: the first-order decrease is that of the shorter move
                        decrease_bound += grad[p] * (r[p] - o - alpha * direction[p]);
                        moved = o;
                    }
                    trial[p] = moved - r[p];
                    if active[p] {
                        decrease_bound -= grad[p] * trial[p];
                    }
                }
                let change = self.energy_change(r, &trial, &grad);
                if change <= -ARMIJO * decrease_bound || (change <= 0.0 && decrease_bound <= 1e-300) {
                    break;
                }
                // Local phase: a full step that halves the complementarity residual is kept
                // even where the energy change is below its rounding.
                if alpha == 1.0 && self.trial_residual(r, &trial, d) <= 0.5 * best_residual {
                    break;
                }
                alpha *= 0.5;
                outcome.line_search_cuts += 1;
                if alpha < MIN_STEP {
                    // At the round-off floor the energy cannot decrease measurably: accept a
                    // residual within 100× the tolerance, otherwise report the stall.
                    if residual <= 100.0 * tol {
                        self.finish(d, state, &mut outcome);
                        return Ok(outcome);
                    }
                    return Err(ContactFailure {
                        outcome,
                        reason: "the line search could not decrease the energy (the regularised law may be too steep: increase `contact.law.regularisation` or reduce the time step)".into(),
                    });
                }
            }
            for p in 0..m {
                r[p] += trial[p];
                if r[p] > self.g(p) {
                    r[p] = self.g(p);
                }
            }
        }
        self.finish(d, state, &mut outcome);
        Ok(outcome)
    }

    /// Solves (Q_ℐℐ + diag(curvature)) x = G_ℐ, convexifying when indefinite.
    fn newton_direction(
        &self,
        free: &[usize],
        curvature: &[f64],
        grad: &[f64],
        outcome: &mut ContactOutcome,
    ) -> Vec<f64> {
        let nf = free.len();
        if nf == 0 {
            return Vec::new();
        }
        if nf > self.settings.dense_limit {
            if let Some(x) = self.conjugate_gradients(free, curvature, grad, outcome) {
                outcome.iterative += 1;
                return x;
            }
        }
        let rhs = Mat::<f64>::from_fn(nf, 1, |i, _| grad[free[i]]);
        let build = |diag: &dyn Fn(usize) -> f64| {
            Mat::<f64>::from_fn(nf, nf, |i, j| {
                self.operator.q(free[i], free[j]) + if i == j { diag(i) } else { 0.0 }
            })
        };
        if let Ok(llt) = build(&|i| curvature[i]).llt(faer::Side::Lower) {
            let x = llt.solve(&rhs);
            return (0..nf).map(|i| x[(i, 0)]).collect();
        }
        outcome.convexified += 1;
        let mut shift = 0.0;
        loop {
            let h = build(&|i| curvature[i].max(0.0) + shift);
            if let Ok(llt) = h.llt(faer::Side::Lower) {
                let x = llt.solve(&rhs);
                return (0..nf).map(|i| x[(i, 0)]).collect();
            }
            shift = if shift == 0.0 {
                1e-12 * self.c(free[0])
            } else {
                shift * 10.0
            };
        }
    }

    /// (Q_ℐℐ + diag(curvature)) x = G_ℐ by Jacobi-preconditioned conjugate gradients, each product
    /// one m × m product by Q, to a relative residual of 1e-13. None if a direction of
    /// non-positive curvature turns up or it does not converge in 4·n_free iterations: then the
    /// dense path (with its convexification) decides, so both paths give the same direction.
    fn conjugate_gradients(
        &self,
        free: &[usize],
        curvature: &[f64],
        grad: &[f64],
        outcome: &mut ContactOutcome,
    ) -> Option<Vec<f64>> {
        let _ = outcome;
        let (m, nf) = (self.m(), free.len());
        let diag: Vec<f64> = curvature[..nf].to_vec();
        let (mut full, mut product) = (vec![0.0; m], vec![0.0; m]);
        let mut apply = |x: &[f64], y: &mut [f64]| {
            full.fill(0.0);
            for (i, &p) in free.iter().enumerate() {
                full[p] = x[i];
            }
            self.operator.apply_q(&full, &mut product);
            for (i, &p) in free.iter().enumerate() {
                y[i] = product[p] + diag[i] * x[i];
            }
        };
        let precondition: Vec<f64> = (0..nf)
            .map(|i| 1.0 / (self.c(free[i]) + diag[i]).max(f64::MIN_POSITIVE))
            .collect();
        let b: Vec<f64> = free.iter().map(|&p| grad[p]).collect();
        let norm_b = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut x = vec![0.0; nf];
        if norm_b == 0.0 {
            return Some(x);
        }
        let mut r = b.clone();
        let mut z: Vec<f64> = r.iter().zip(&precondition).map(|(a, p)| a * p).collect();
        let mut dir = z.clone();
        let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let mut ad = vec![0.0; nf];
        for _ in 0..4 * nf {
            apply(&dir, &mut ad);
            let curvature_along: f64 = dir.iter().zip(&ad).map(|(a, b)| a * b).sum();
            if curvature_along <= 0.0 {
                return None;
            }
            let alpha = rz / curvature_along;
            for i in 0..nf {
                x[i] += alpha * dir[i];
                r[i] -= alpha * ad[i];
            }
            if r.iter().map(|v| v * v).sum::<f64>().sqrt() <= 1e-13 * norm_b {
                return Some(x);
            }
            for i in 0..nf {
                z[i] = r[i] * precondition[i];
            }
            let next: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = next / rz;
            rz = next;
            for i in 0..nf {
                dir[i] = z[i] + beta * dir[i];
            }
        }
        None
    }

    /// Forces and statuses at the converged r: λ = Q(d − r), ξ = w j_ε'(r), η = λ − ξ on the
    /// bound and 0 elsewhere.
    #[allow(clippy::needless_range_loop)] // p indexes five per-node arrays at once
    fn finish(&self, d: &[f64], state: &mut ContactState, outcome: &mut ContactOutcome) {
        let m = self.m();
        let mut qrd_final = vec![0.0; m];
        let diff: Vec<f64> = state.normal_displacement.iter().zip(d).map(|(a, b)| a - b).collect();
        self.operator.apply_q(&diff, &mut qrd_final);
        outcome.active = 0;
        for p in 0..m {
            let r = state.normal_displacement[p];
            let lambda = -qrd_final[p];
            let xi = self.law_derivative(p, r);
            let on_bound = r >= self.g(p);
            state.force[p] = lambda;
            state.compliance_force[p] = xi;
            state.bound_force[p] = if on_bound { lambda - xi } else { 0.0 };
            state.status[p] = if on_bound {
                outcome.active += 1;
                NodeStatus::OnBound
            } else if r > self.origin(p) {
                NodeStatus::InLayer
            } else {
                NodeStatus::Separated
            };
        }
    }
}
