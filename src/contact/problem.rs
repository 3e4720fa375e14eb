//! The contact problem of one time step on its m condensed rows (docs/method.md §4.1): with
//! u_ν = r and the condensed stiffness Q = W⁻¹,
//!
//! ```text
//!     minimise  E(r) = ½ rᵀQr − qᵀr + Σ_p w_p j_ε(r_p − o_p)   subject to  r_p ≤ g_p,
//! ```
//!
//! q the free contact forces (Q d for the free normal displacements d), o_p a law's origin (an
//! obstacle's initial gap), g_p the bound. Its KKT conditions are the contact law:
//! λ = q − Q r = ξ + η, ξ_p = w_p j_ε'(r_p − o_p), η ≥ 0, r ≤ g, η(r − g) = 0. This file holds the
//! problem's data and what the solver measures on it: the laws' forces, the gradient, the
//! complementarity residual, the energy's change and the force scale.

use super::condensed::NormalStiffness;
use super::nodal::NodalLaws;

/// The data of a step's contact problem: the condensed operator, the rows' laws (with their nodal
/// weights) and what each row is (its origin, its bound, whether it is held, its pair).
#[derive(Clone, Copy)]
pub struct ContactProblem<'a> {
    pub operator: &'a dyn NormalStiffness,
    /// Σ_t w_t j_t per row (empty: no law).
    pub laws: &'a NodalLaws,
    /// o_p: the laws act on the penetration r_p − o_p (the initial gap to an obstacle);
    /// `None` for o = 0.
    pub offset: Option<&'a [f64]>,
    /// g_p per row (∞ where a row has none), or `None` for no bound.
    pub bound: Option<&'a [f64]>,
    /// Q may be singular along rigid motions that only the laws and the bound hold (rigid
    /// parameters eliminated from it, docs/method.md §7.7): the Newton matrix then gets a
    /// proximal shift.
    pub singular: bool,
    /// Per row, its partner in a pair whose law acts on the pair's length, or `None` for no
    /// pairs: 3D friction's two tangential rows, whose slip is a vector in the tangent plane
    /// (docs/method.md §17.3). Paired rows have no bound and the same one term; their energy is
    /// w j(|(s_p, s_q)|).
    pub pairs: Option<&'a [Option<usize>]>,
    /// Per row, whether it is held at its bound from both sides (bilateral contact, u_ν = g_p:
    /// always active, its force of either sign; docs/method.md §17.4), or `None` for none.
    pub fixed: Option<&'a [bool]>,
    /// The first of friction's tangential rows whose kink takes the branch model
    /// (docs/method.md §17.2), or `None`.
    pub branch_from: Option<usize>,
}

impl<'a> ContactProblem<'a> {
    /// The problem of `operator` and `laws` alone: no origin, no bound, no pairs, no held rows.
    pub fn new(operator: &'a dyn NormalStiffness, laws: &'a NodalLaws) -> Self {
        ContactProblem {
            operator,
            laws,
            offset: None,
            bound: None,
            singular: false,
            pairs: None,
            fixed: None,
            branch_from: None,
        }
    }

    /// The number of rows m.
    pub fn m(&self) -> usize {
        self.operator.m()
    }

    /// g_p (∞ without a bound).
    #[inline]
    pub fn g(&self, p: usize) -> f64 {
        self.bound.map_or(f64::INFINITY, |g| g[p])
    }

    /// True if row p is held at its bound (bilateral).
    #[inline]
    pub fn is_fixed(&self, p: usize) -> bool {
        self.fixed.is_some_and(|f| f[p])
    }

    /// o_p.
    #[inline]
    pub fn origin(&self, p: usize) -> f64 {
        self.offset.map_or(0.0, |o| o[p])
    }

    /// Row p's partner in a pair (docs/method.md §17.3).
    #[inline]
    pub fn partner(&self, p: usize) -> Option<usize> {
        self.pairs.and_then(|q| q[p])
    }

    /// Q_pp, the row's stiffness (c_p of the active-set rule).
    #[inline]
    pub fn c(&self, p: usize) -> f64 {
        self.operator.q(p, p)
    }

    /// The pair (s_p, s_q) of penetrations past the origins and its length ρ.
    #[inline]
    pub fn pair_at(&self, r: &[f64], p: usize, q: usize) -> ([f64; 2], f64) {
        let x = [r[p] - self.origin(p), r[q] - self.origin(q)];
        (x, length(x[0], x[1]))
    }

    /// The laws' force on row p at r: w j'(s_p), or for a pair the component
    /// w j'(ρ) s_p / ρ of the force along the pair's vector (docs/method.md §17.3).
    #[inline]
    pub fn law_force(&self, r: &[f64], p: usize) -> f64 {
        match self.partner(p) {
            None => self.laws.force(p, r[p] - self.origin(p)),
            Some(q) => {
                let (x, rho) = self.pair_at(r, p, q);
                if rho > 0.0 {
                    self.laws.force(p, rho) * x[0] / rho
                } else {
                    0.0
                }
            }
        }
    }

    /// Q r − q (minus the contact force λ, by a product by Q) and the gradient
    /// G = (Q r − q) + λ_law(r) of E at r.
    pub fn gradient(&self, r: &[f64], q: &[f64], qrd: &mut [f64], grad: &mut [f64]) {
        self.operator.apply_q(r, qrd);
        qrd.iter_mut().zip(q).for_each(|(a, b)| *a -= b);
        for p in 0..self.m() {
            grad[p] = qrd[p] + self.law_force(r, p);
        }
    }

    /// Row p's share of the complementarity residual: |min(c_p(g_p − r_p), −G_p)| (|G_p| without
    /// a bound, c_p |g_p − r_p| on a held row), in force units.
    pub fn row_residual(&self, r: &[f64], grad: &[f64], p: usize) -> f64 {
        let g = self.g(p);
        if self.is_fixed(p) {
            self.c(p) * (g - r[p]).abs()
        } else if g.is_finite() {
            (self.c(p) * (g - r[p])).min(-grad[p]).abs()
        } else {
            grad[p].abs()
        }
    }

    /// max_p of [`Self::row_residual`].
    pub fn complementarity_residual(&self, r: &[f64], grad: &[f64]) -> f64 {
        (0..self.m()).map(|p| self.row_residual(r, grad, p)).fold(0.0, f64::max)
    }

    /// E(r + Δ) − E(r), formed from differences to avoid cancellation:
    /// GᵀΔ + ½ΔᵀQΔ + Σ_p w_p [j(r_p + Δ_p) − j(r_p) − j'(r_p)Δ_p], the bracket from its
    /// Taylor expansion ½ j''(r_p) Δ_p² when Δ_p is tiny (the difference of j values would be
    /// below their rounding near convergence, and Armijo could not see the decrease).
    /// `qdelta` is Q Δ.
    pub fn energy_change(&self, r: &[f64], delta: &[f64], grad: &[f64], qdelta: &[f64]) -> f64 {
        let mut change = 0.0;
        for p in 0..self.m() {
            change += delta[p] * (grad[p] + 0.5 * qdelta[p]);
            if !self.laws.is_empty() {
                change += match self.partner(p) {
                    None => self.laws.energy_increment(p, r[p] - self.origin(p), delta[p]),
                    Some(q) if q > p => self.pair_energy_increment(r, delta, p, q),
                    Some(_) => 0.0,
                };
            }
        }
        change
    }

    /// A pair's w [j(ρ') − j(ρ) − j'(ρ) n·Δ], ρ' = |x + Δ|: the radial part from
    /// [`NodalLaws::energy_increment`], plus w j'(ρ) [(ρ' − ρ) − n·Δ] written as
    /// |Δ|²/(ρ + ρ') + (x·Δ)(ρ − ρ')/(ρ(ρ + ρ')), second order with no cancellation.
    fn pair_energy_increment(&self, r: &[f64], delta: &[f64], p: usize, q: usize) -> f64 {
        let (x, rho) = self.pair_at(r, p, q);
        let dx = [delta[p], delta[q]];
        let moved = length(x[0] + dx[0], x[1] + dx[1]);
        let radial = self.laws.energy_increment(p, rho, moved - rho);
        if rho == 0.0 {
            return radial;
        }
        let (dd, xd) = (dx[0] * dx[0] + dx[1] * dx[1], x[0] * dx[0] + x[1] * dx[1]);
        let sum = rho + moved;
        radial + self.laws.force(p, rho) * (dd / sum + xd * (rho - moved) / (rho * sum))
    }

    /// The force scale of the step: max(‖q‖∞, ‖Q v‖∞, max_p w_p S sup μ), v_p = min(0, g_p, o_p)
    /// the interference of rows that start past their bound or their obstacle's surface (a body
    /// placed into an obstacle is pushed out by forces of that size even without load; without
    /// the term an unloaded step with interference had a scale of 0 and could not converge).
    pub fn force_scale(&self, q: &[f64]) -> f64 {
        let m = self.m();
        let load = q.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let interference: Vec<f64> = (0..m)
            .map(|p| {
                let g = self.g(p);
                0.0f64.min(if g.is_finite() { g } else { 0.0 }).min(self.origin(p))
            })
            .collect();
        let overlap = if interference.iter().any(|v| *v < 0.0) {
            let mut qv = vec![0.0; m];
            self.operator.apply_q(&interference, &mut qv);
            qv.iter().fold(0.0f64, |a, b| a.max(b.abs()))
        } else {
            0.0
        };
        let law = self.laws.force_scale(m);
        load.max(overlap).max(law).max(f64::MIN_POSITIVE)
    }

    /// m and the bits of Σ_p Q_pp: a kept factorisation of another operator (step 0's K_A, or
    /// another run's) is not reused.
    pub fn fingerprint(&self) -> Fingerprint {
        let m = self.m();
        Fingerprint(m, (0..m).map(|p| self.c(p)).sum::<f64>().to_bits())
    }
}

/// |(a, b)| as √(a² + b²): a pair's slip length, never near f64's overflow or underflow.
#[inline]
fn length(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

/// What tells one condensed operator from another for a kept factorisation: m and the bits of
/// Σ_p Q_pp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fingerprint(usize, u64);
