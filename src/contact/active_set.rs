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
//!
//! Over 600 lines because it is one algorithm (docs/method.md §4.4): the Newton step, its
//! convexification, the line search, the watchdog and the reused factor; a hundred of them are
//! its unit tests.

use super::condensed::NormalStiffness;
use super::newton_w::{self, Curvature};
use super::nodal::NodalLaws;
pub use super::settings::{ContactSettings, Strategies};
use crate::linalg::dense::{
    subtract_product, transpose_product, DenseCholesky, DenseLu, FactorBuffer, SingleCholesky, SingleMatrix,
};
use crate::linalg::krylov;

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
    /// The last factorisation of the Newton matrix, kept above `dense_limit` free nodes as the
    /// preconditioner of later Newton systems (docs/method.md §9.2).
    pub newton_factor: KeptFactor,
    /// The storage of the Newton system in W, kept between its factorisations (§4.6).
    pub buffer: FactorBuffer,
    /// Per tangential row of a contact with friction, after the step (empty without friction;
    /// docs/method.md §17).
    pub friction: FrictionRows,
    /// The r and d at which the last solve formed `force` = d − Q r: a solve from the same r
    /// and d (the next round of Coulomb's fixed point, whose laws only changed) starts from it
    /// instead of a product by Q.
    pub balanced_at: Option<(Vec<f64>, Vec<f64>)>,
}

/// What a step leaves on the tangential rows of a contact with friction (docs/method.md §17):
/// row k belongs to the normal row `Friction::normal_row[k]`.
#[derive(Clone, Debug, Default)]
pub struct FrictionRows {
    /// Δu_τ, the slip increment of the step along the row's tangent.
    pub slip: Vec<f64>,
    /// Σ |Δu_τ| over the steps so far.
    pub accumulated: Vec<f64>,
    /// The bound force F of the row (w_p F_b for Tresca, μ λ_ν for Coulomb).
    pub bound: Vec<f64>,
    /// How the step moved, for the next step's predictor.
    pub trend: StepTrend,
    /// [`FrictionStatus`] codes.
    pub status: Vec<i32>,
}

/// How a step with friction moved, which the next step extrapolates where its load moves on the
/// same way (docs/method.md §17.2): empty before the first such step.
#[derive(Clone, Debug, Default)]
pub struct StepTrend {
    /// The free contact forces q of the step (all rows) and their change over it.
    pub load: Vec<f64>,
    pub load_change: Vec<f64>,
    /// The normal rows' displacements' change over the step.
    pub normal_change: Vec<f64>,
    /// The tangential rows' bound forces' change over the step.
    pub bound_change: Vec<f64>,
}

/// Where a tangential row ends a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrictionStatus {
    /// Its normal row is separated.
    Separated = 0,
    /// |λ_τ| below the bound force: no slip.
    Stick = 1,
    /// |λ_τ| at the bound force: slipping against Δu_τ.
    Slip = 2,
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
            newton_factor: KeptFactor::default(),
            buffer: FactorBuffer::default(),
            friction: FrictionRows::default(),
            balanced_at: None,
        }
    }
}

/// The kept factorisation of [`ContactState`]: a cache of up to m² numbers, so a clone (a step
/// recorded by a sink) starts without it.
#[derive(Debug, Default)]
pub struct KeptFactor(Option<ReusedFactor>);

impl Clone for KeptFactor {
    fn clone(&self) -> Self {
        KeptFactor(None)
    }
}

/// The dense Cholesky factor of a Newton matrix Q_ℱℱ + diag(e) on the free set ℱ it was formed
/// on, kept above `dense_limit` free nodes to precondition later Newton systems (docs/method.md
/// §9.2). Only a preconditioner: a stale one costs iterations, never accuracy.
#[derive(Debug)]
pub struct ReusedFactor {
    /// m and the bits of Σ_p Q_pp of the operator it was formed with.
    fingerprint: (usize, u64),
    /// The factor's row of each contact node (usize::MAX: not in ℱ).
    row: Vec<usize>,
    /// e on the factor's diagonal, per row.
    diagonal: Vec<f64>,
    /// A pair's coupling on the factor's off-diagonal, per row (0 where the row has no pair).
    coupling: Vec<f64>,
    factor: DenseCholesky,
    /// The factor in single precision for the preconditioner's sweeps (docs/method.md §9.2),
    /// rounded at the first of them: a factor that only solves its own direction never is.
    single: std::sync::OnceLock<SingleCholesky>,
    /// Q in single precision for CG's products where its accuracy asks no more (formed at the
    /// first such product, handed on to the next factor of the same operator).
    q_single: Option<std::sync::Arc<SingleMatrix>>,
    /// The directions it has given (a fresh factor's first CG runs in double precision: its
    /// single copies would cost more than one use saves).
    served: usize,
    /// The columns A₀⁻¹ e_k of the rows k the low-rank update has needed so far (column-major,
    /// n numbers each; they depend on the factor only, so they are kept with it), and each
    /// row's column (usize::MAX: none yet).
    columns: Vec<f64>,
    column_of: Vec<usize>,
    /// For the rows outside the factor that joined the free set since: Q's column on the
    /// factor's rows a_p and A₀⁻¹ a_p (n numbers each), and each contact row's place (usize::MAX:
    /// none yet) (the border of [`ActiveSetSolver::preconditioned_cg`]).
    bordered: Vec<f64>,
    bordered_of: Vec<usize>,
}

impl ReusedFactor {
    /// The factor in single precision, rounded at the first call.
    fn single(&self) -> &SingleCholesky {
        self.single.get_or_init(|| self.factor.single())
    }

    /// X ← A₀⁻¹ X for the n × k column-major X, by the single-precision sweeps or the double ones.
    fn solve_columns(&self, x: &mut [f64], k: usize, single: bool) {
        match single {
            true => self.single().solve_columns_in_place(x, k),
            false => self.factor.solve_columns_in_place(x, k),
        }
    }

    /// Appends A₀⁻¹ e_k for the factor's rows `rows` to the kept columns.
    fn unit_columns(&mut self, rows: &[usize], single: bool) {
        if single {
            let factor = &self.factor;
            (self.single.get_or_init(|| factor.single())).solve_unit_columns(rows, &mut self.columns);
            return;
        }
        let n = self.diagonal.len();
        let start = self.columns.len();
        self.columns.resize(start + n * rows.len(), 0.0);
        let x = &mut self.columns[start..];
        for (b, &k) in rows.iter().enumerate() {
            x[b * n + k] = 1.0;
        }
        self.factor.solve_columns_in_place(x, rows.len());
    }
}

/// P = A₀ + UΔUᵀ of [`ActiveSetSolver::preconditioned_cg`] on the kept factor's rows `rows`.
struct LowRankUpdate {
    rows: Vec<usize>,
    /// Per row: Δ's diagonal, the pair partner's place in `rows` (usize::MAX: none) and Δ there.
    delta: Vec<(f64, usize, f64)>,
    /// I + Δ Uᵀ Z.
    capacitance: DenseLu,
    /// Per row, its column of Z among the kept factor's (`ReusedFactor::columns`), read in
    /// place: gathering them was a copy of n × |𝒰| numbers per direction.
    columns: Vec<usize>,
}

impl LowRankUpdate {
    /// T = Δ Uᵀ Y for the n × c column-major Y (a pinned row: its row of Y, the limit of
    /// Δ Uᵀ Y divided by Δ, as its capacitance row is).
    fn rhs(&self, y: &[f64], n: usize, c: usize) -> Vec<f64> {
        let u = self.rows.len();
        let mut t = vec![0.0; u * c];
        for (column, tc) in y.chunks_exact(n).zip(t.chunks_exact_mut(u)) {
            for (a, (&(d, partner, off), &k)) in self.delta.iter().zip(&self.rows).enumerate() {
                tc[a] = if d.is_infinite() {
                    column[k]
                } else {
                    d * column[k]
                        + if partner == usize::MAX {
                            0.0
                        } else {
                            off * column[self.rows[partner]]
                        }
                };
            }
        }
        t
    }

    /// Y ← P⁻¹ R from Y = A₀⁻¹ R for the n × c column-major Y: Y − Z (I + Δ Uᵀ Z)⁻¹ Δ Uᵀ Y,
    /// Z's columns read from the kept ones (`kept`, n × each).
    fn correct_columns(&self, kept: &[f64], y: &mut [f64], c: usize) {
        let (n, u) = (y.len() / c, self.rows.len());
        let mut t = self.rhs(y, n, c);
        self.capacitance.solve_columns_in_place(&mut t, c);
        let column = |a: usize| &kept[self.columns[a] * n..(self.columns[a] + 1) * n];
        if c == 1 {
            // (CG's preconditioner: one column, each of Z's read once)
            for (a, &ta) in t.iter().enumerate() {
                y.iter_mut().zip(column(a)).for_each(|(y, z)| *y -= ta * z);
            }
            return;
        }
        let mut z = vec![0.0; n * u];
        for (a, za) in z.chunks_exact_mut(n).enumerate() {
            za.copy_from_slice(column(a));
        }
        subtract_product(y, &z, &t, (n, u, c));
    }
}

/// The rows that joined the free set since the kept factor was formed, bordered onto
/// P = A₀ + UΔUᵀ of [`ActiveSetSolver::preconditioned_cg`] by their Schur complement
/// S = A_JJ − A_JK P⁻¹ A_KJ (docs/method.md §9.2).
struct Border {
    /// The joined rows (free indices) and a flag per free row.
    rows: Vec<usize>,
    is_row: Vec<bool>,
    /// A_KJ (n × |J| column-major, on the kept factor's rows) and X = P⁻¹ A_KJ.
    a: Vec<f64>,
    x: Vec<f64>,
    schur: DenseLu,
}

impl Border {
    /// From t = P⁻¹ r_K (in `kept`): z_J = S⁻¹ (r_J − A_JK t), t ← t − X z_J.
    fn correct(&self, r: &[f64], kept: &mut [f64], z: &mut [f64]) {
        let (n, k) = (kept.len(), self.rows.len());
        let coupled = transpose_product(&self.a, kept, (n, k, 1));
        let mut w: Vec<f64> = (self.rows.iter().zip(&coupled)).map(|(&j, c)| r[j] - c).collect();
        self.schur.solve_in_place(&mut w);
        subtract_product(kept, &self.x, &w, (n, k, 1));
        for (&j, &v) in self.rows.iter().zip(&w) {
            z[j] = v;
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
    /// Newton directions computed by conjugate gradients preconditioned with an earlier
    /// factorisation (more free nodes than `dense_limit`).
    pub iterative: usize,
    /// Dense Cholesky factorisations of the Newton matrix (one per direction below
    /// `dense_limit`; above it, only when the reused one no longer serves).
    pub factorisations: usize,
    /// Of those, the factorisations of the Newton system in W (docs/method.md §4.6).
    pub in_w: usize,
    /// Nodes on the bound at the end.
    pub active: usize,
}

impl ContactOutcome {
    /// Adds another solve's work (its iterations, cuts, convexifications, iterative directions
    /// and factorisations) to this one's; the residual and the active count stay this one's.
    pub fn add_work(&mut self, other: &ContactOutcome) {
        self.iterations += other.iterations;
        self.line_search_cuts += other.line_search_cuts;
        self.convexified += other.convexified;
        self.iterative += other.iterative;
        self.factorisations += other.factorisations;
        self.in_w += other.in_w;
    }

    /// How many numbers [`Self::to_numbers`] gives (a broadcast of the outcome, src/petsc).
    pub const NUMBERS: usize = 8;

    /// The outcome as numbers, in the order [`Self::from_numbers`] reads them.
    pub fn to_numbers(&self) -> [f64; Self::NUMBERS] {
        [
            self.iterations as f64,
            self.residual,
            self.line_search_cuts as f64,
            self.convexified as f64,
            self.iterative as f64,
            self.factorisations as f64,
            self.in_w as f64,
            self.active as f64,
        ]
    }

    /// The outcome of [`Self::to_numbers`]'s numbers.
    pub fn from_numbers(n: &[f64]) -> Self {
        ContactOutcome {
            iterations: n[0] as usize,
            residual: n[1],
            line_search_cuts: n[2] as usize,
            convexified: n[3] as usize,
            iterative: n[4] as usize,
            factorisations: n[5] as usize,
            in_w: n[6] as usize,
            active: n[7] as usize,
        }
    }
}

/// Why a contact solve stopped without converging.
#[derive(Clone, Debug)]
pub struct ContactFailure {
    pub outcome: ContactOutcome,
    pub reason: String,
    /// The smallest relative residual the solve reached: where it stalled, if it did.
    pub smallest_residual: f64,
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
    /// Q may be singular along rigid motions that only the laws and the bound hold (rigid
    /// parameters eliminated from it, docs/method.md §7.7): the Newton matrix then gets a
    /// proximal shift min(10⁻⁶, relative residual) · Q_pp, which bounds the first steps of a body
    /// not yet touching and vanishes as the solve converges.
    pub singular: bool,
    /// Per row, its partner in a pair whose law acts on the pair's length (usize::MAX: none), or
    /// `None` for no pairs: 3D friction's two tangential rows, whose slip is a vector in the
    /// tangent plane (docs/method.md §17.3). Paired rows have no bound and the same one term;
    /// their energy is w j(|(s_p, s_q)|).
    pub pairs: Option<&'a [usize]>,
    /// Per row, whether it is held at its bound from both sides (bilateral contact, u_ν = g_p:
    /// always active, its force of either sign; docs/method.md §17.4), or `None` for none.
    pub fixed: Option<&'a [bool]>,
    /// Rows from this index on are friction's tangential rows (usize::MAX: none): inside their
    /// kink's smoothing zone, where the elastic force asks for more than the kink gives, they
    /// take the Newton model of the branch they leave for ([`Self::branch_model`],
    /// docs/method.md §17.2).
    pub branch_from: usize,
}

/// A row within this many kink widths ε of its kink is inside the smoothing zone for
/// [`ActiveSetSolver::branch_model`] (10 and 100 measured alike on the slab with Coulomb
/// friction, 10³ and 10⁵ worse).
const BRANCH_ZONE: f64 = 10.0;

/// Where [`ActiveSetSolver::branch_model`] reads the branch a row leaves for: 10³ ε from the
/// kink, where the smoothed |·| gives F (1 − 5·10⁻⁷) and a curvature of 10⁻⁹ F/ε.
const BRANCH_EDGE: f64 = 1e3;

/// The Hessian of the laws on the Newton system's free rows: diagonal, the coupling of each
/// row to its pair's other row (at `partner`, the free index, usize::MAX: none), and both
/// convexified (the laws' negative curvatures dropped).
#[derive(Clone)]
struct LawHessian {
    diagonal: Vec<f64>,
    coupling: Vec<f64>,
    convex_diagonal: Vec<f64>,
    convex_coupling: Vec<f64>,
    partner: Vec<usize>,
    /// Per row of a pair: a, b and the pair's unit vector n (the block a nnᵀ + b (I − nnᵀ)).
    pair: Vec<(f64, f64, [f64; 2])>,
}

/// A Krylov solve's result: x on the free rows, the iterations taken and, from CG, Q x over
/// all rows (x zero off the free rows): the sum of CG's own products, which spares the line
/// search its product by Q (docs/method.md §9.2).
type Krylov = (Vec<f64>, usize, Option<Vec<f64>>);

const ARMIJO: f64 = 1e-4;
/// A row whose law curvature is this many times its stiffness Q_pp (a pair: both of its
/// curvatures) is left out of a kept factor and preconditioned by Jacobi (docs/method.md §9.2).
const STIFF: f64 = 100.0;
/// A kept factor's row whose curvature (or pair coupling) moved by more than this share of
/// Q_pp + e_p is updated by Woodbury's identity (docs/method.md §9.2).
const MOVED: f64 = 0.4;
/// CG's products by Q are formed in single precision (the sums in double) where the relative
/// accuracy it must reach is at least this, a hundred times the products' rounding relative to
/// a row's terms (docs/method.md §9.2).
const SINGLE_FORCING: f64 = 1e-5;

/// A pair's block a nnᵀ + b (I − nnᵀ) seen from its row whose component of n is n[0]: that row's
/// diagonal entry and the coupling to the other row (docs/method.md §17.3).
fn pair_block(a: f64, b: f64, n: [f64; 2]) -> (f64, f64) {
    (b + (a - b) * n[0] * n[0], (a - b) * n[0] * n[1])
}

/// Whether k of Q's m columns are few enough (an eighth) to add to a product one by one instead
/// of forming a product by Q (the line search's trial products, docs/method.md §9.2).
fn few_columns(k: usize, m: usize) -> bool {
    8 * k <= m
}

/// |(a, b)| as √(a² + b²): a pair's slip length, which is never near f64's overflow or the
/// underflow that `hypot` guards against, at a fraction of glibc's `hypot` cost (a tenth of a
/// second of the slab's Coulomb run went to it).
#[inline]
fn length(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

/// Whether a solve ended at r under the free contact forces q ([`ContactState::balanced_at`]):
/// the state's forces are then q − Q r, and no product by Q need form them.
fn is_balanced(balanced_at: &Option<(Vec<f64>, Vec<f64>)>, r: &[f64], q: &[f64]) -> bool {
    balanced_at
        .as_ref()
        .is_some_and(|(at, load)| at[..] == r[..] && load[..] == q[..])
}

/// HVI_TRACE_CONTACT set: the solve prints its iterations to stderr.
fn tracing() -> bool {
    std::env::var_os("HVI_TRACE_CONTACT").is_some()
}
const MIN_STEP: f64 = 1e-12;

impl ActiveSetSolver<'_> {
    fn m(&self) -> usize {
        self.operator.m()
    }

    /// Gives a factor's storage back to `buffer` for the next factorisation (where storage is
    /// recycled; else it is freed).
    fn recycle(&self, buffer: &mut FactorBuffer, factor: DenseCholesky) {
        if self.on().recycled_storage {
            buffer.recycle(factor);
        }
    }

    /// The strategies this solve uses.
    fn on(&self) -> &Strategies {
        &self.settings.strategies
    }

    fn g(&self, p: usize) -> f64 {
        self.bound.map_or(f64::INFINITY, |g| g[p])
    }

    /// True if row p is held at its bound (bilateral).
    #[inline]
    fn is_fixed(&self, p: usize) -> bool {
        self.fixed.is_some_and(|f| f[p])
    }

    #[inline]
    fn origin(&self, p: usize) -> f64 {
        self.offset.map_or(0.0, |o| o[p])
    }

    /// Row p's partner in a pair (docs/method.md §17.3).
    #[inline]
    fn partner(&self, p: usize) -> Option<usize> {
        self.pairs.map(|q| q[p]).filter(|&q| q != usize::MAX)
    }

    /// The pair (s_p, s_q) of penetrations past the origins and its length ρ.
    #[inline]
    fn pair_at(&self, r: &[f64], p: usize, q: usize) -> ([f64; 2], f64) {
        let x = [r[p] - self.origin(p), r[q] - self.origin(q)];
        (x, length(x[0], x[1]))
    }

    /// The laws' force on row p at r: w j'(s_p), or for a pair the component
    /// w j'(ρ) s_p / ρ of the force along the pair's vector (docs/method.md §17.3).
    #[inline]
    fn law_force(&self, r: &[f64], p: usize) -> f64 {
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

    /// Q r − q (= Q(r − d), minus the contact force λ) and the gradient G of E at r.
    fn gradient(&self, r: &[f64], q: &[f64], qrd: &mut [f64], grad: &mut [f64]) {
        self.residual_force(r, q, qrd);
        self.gradient_from(r, qrd, grad);
    }

    /// Q r − q, by a product by Q.
    fn residual_force(&self, r: &[f64], q: &[f64], qrd: &mut [f64]) {
        self.operator.apply_q(r, qrd);
        qrd.iter_mut().zip(q).for_each(|(a, b)| *a -= b);
    }

    /// G = (Q r − d) + λ_law(r), given Q r − d.
    fn gradient_from(&self, r: &[f64], qrd: &[f64], grad: &mut [f64]) {
        for p in 0..self.m() {
            grad[p] = qrd[p] + self.law_force(r, p);
        }
    }

    /// The laws' Hessian on the free rows at r. A pair's block is a n nᵀ + b (I − n nᵀ), n the
    /// unit vector of the pair, a = w j''(ρ) along it and b = w j'(ρ)/ρ across it (the slip
    /// direction's turning stiffness; w j''(0) at ρ = 0, where the smoothed law is isotropic);
    /// convexified, a and b each by max(·, 0) (docs/method.md §17.3).
    fn law_hessian(&self, r: &[f64], free: &[usize]) -> LawHessian {
        let nf = free.len();
        let mut h = LawHessian {
            diagonal: vec![0.0; nf],
            coupling: vec![0.0; nf],
            convex_diagonal: vec![0.0; nf],
            convex_coupling: vec![0.0; nf],
            partner: vec![usize::MAX; nf],
            pair: vec![(0.0, 0.0, [1.0, 0.0]); nf],
        };
        let mut index = Vec::new();
        if self.pairs.is_some() {
            index = vec![usize::MAX; self.m()];
            for (i, &p) in free.iter().enumerate() {
                index[p] = i;
            }
        }
        for (i, &p) in free.iter().enumerate() {
            match self.partner(p) {
                None => {
                    let e = self.laws.stiffness(p, r[p] - self.origin(p));
                    h.diagonal[i] = e;
                    h.convex_diagonal[i] = e.max(0.0);
                }
                Some(q) => {
                    let (x, rho) = self.pair_at(r, p, q);
                    let a = self.laws.stiffness(p, rho);
                    let (b, n) = if rho > 0.0 {
                        (self.laws.force(p, rho) / rho, [x[0] / rho, x[1] / rho])
                    } else {
                        (a, [1.0, 0.0])
                    };
                    (h.diagonal[i], h.coupling[i]) = pair_block(a, b, n);
                    (h.convex_diagonal[i], h.convex_coupling[i]) = pair_block(a.max(0.0), b.max(0.0), n);
                    h.partner[i] = index[q];
                    h.pair[i] = (a, b, n);
                }
            }
        }
        h
    }

    /// The Newton model of the slip branch for the tangential rows that leave their kink
    /// (docs/method.md §17.2), or None where no row does. A row inside the smoothing zone of its
    /// kink (|s| ≤ 10 ε) feels the smoothed law's curvature F/ε there, so a Newton step from it
    /// moves it by about ε, the next by a few ε more: a row about to slip crept out of the zone
    /// over four or five directions, each a change of hundreds of rows' curvature for the kept
    /// factor. Where the elastic force on the row, t = λ_law − G (a pair: the vector), asks for
    /// more than the kink's force F, the row takes instead the model of the branch it leaves for,
    /// read 10³ ε out along t: the force F t/|t| in place of the law's in the right-hand side,
    /// and the branch's curvature along t (the pair's across t kept). Where t asks for less than F
    /// the row sticks inside its kink, at the s_t where the law's force is t (a few ε out), which
    /// the law's concave force there lets Newton reach only by steps that each fall short: it takes
    /// the law's tangent at s_t instead (force t + j''(s_t)(s − s_t); a pair the Hessian of
    /// w j(|x|) at s_t t/|t|), the stick side of the model. Only the direction changes:
    /// the line search still measures the energy and its true slope, and a direction that does
    /// not descend is replaced by the law's own.
    fn branch_model(
        &self,
        r: &[f64],
        free: &[usize],
        hessian: &LawHessian,
        grad: &[f64],
        kink: &[f64],
    ) -> Option<(LawHessian, Vec<f64>)> {
        if self.branch_from >= self.m() {
            return None;
        }
        let mut h = hessian.clone();
        let mut g = grad.to_vec();
        let mut changed = 0;
        for (i, &p) in free.iter().enumerate() {
            let kw = kink[p];
            if p < self.branch_from || !kw.is_finite() {
                continue;
            }
            let edge = BRANCH_EDGE * kw;
            match self.partner(p) {
                None => {
                    let s = r[p] - self.origin(p);
                    if s.abs() > BRANCH_ZONE * kw {
                        continue;
                    }
                    let law = self.laws.force(p, s);
                    let t = law - grad[p];
                    let f = self.laws.force(p, t.signum() * edge);
                    let (f, k) = if t.abs() <= f.abs() {
                        // the stick side: the law's tangent where it balances t
                        let Some(st) = self.balancing_point(p, t.abs(), edge) else {
                            continue;
                        };
                        let st = t.signum() * st;
                        let k = self.laws.stiffness(p, st);
                        (t + k * (s - st), k)
                    } else {
                        (f, self.laws.stiffness(p, t.signum() * edge))
                    };
                    if k.is_nan() || k <= 0.0 {
                        continue;
                    }
                    g[p] = grad[p] - law + f;
                    h.diagonal[i] = k;
                    h.convex_diagonal[i] = k.max(0.0);
                    changed += 1;
                }
                Some(q) if q > p => {
                    let j = h.partner[i];
                    if j == usize::MAX {
                        continue;
                    }
                    let (x, rho) = self.pair_at(r, p, q);
                    if rho > BRANCH_ZONE * kw {
                        continue;
                    }
                    let fl = if rho > 0.0 { self.laws.force(p, rho) / rho } else { 0.0 };
                    let t = [fl * x[0] - grad[p], fl * x[1] - grad[q]];
                    let tn = t[0].hypot(t[1]);
                    let f = self.laws.force(p, edge);
                    if tn == 0.0 {
                        continue;
                    }
                    let n = [t[0] / tn, t[1] / tn];
                    let (a, b) = if tn <= f {
                        // the stick side: the law's tangent at x_t = ρ_t t/|t|, where it balances t
                        let Some(rt) = self.balancing_point(p, tn, edge) else {
                            continue;
                        };
                        let (a, b) = (self.laws.stiffness(p, rt), tn / rt);
                        let (d, c) = pair_block(a, b, n);
                        let e = [x[0] - rt * n[0], x[1] - rt * n[1]];
                        g[p] = grad[p] - fl * x[0] + t[0] + d * e[0] + c * e[1];
                        let (d, c) = pair_block(a, b, [n[1], n[0]]);
                        g[q] = grad[q] - fl * x[1] + t[1] + d * e[1] + c * e[0];
                        (a, b)
                    } else {
                        g[p] = grad[p] - fl * x[0] + f * n[0];
                        g[q] = grad[q] - fl * x[1] + f * n[1];
                        (self.laws.stiffness(p, edge), h.pair[i].1)
                    };
                    if !(a > 0.0 && b > 0.0) {
                        continue;
                    }
                    // row q sees the pair from its side (n with its components swapped); the
                    // two rows share row p's coupling
                    for (row, n) in [(i, n), (j, [n[1], n[0]])] {
                        (h.diagonal[row], h.coupling[row]) = pair_block(a, b, n);
                        (h.convex_diagonal[row], h.convex_coupling[row]) = pair_block(a.max(0.0), b.max(0.0), n);
                        h.pair[row] = (a, b, n);
                    }
                    (h.coupling[j], h.convex_coupling[j]) = (h.coupling[i], h.convex_coupling[i]);
                    changed += 2;
                }
                _ => {}
            }
        }
        if tracing() {
            eprintln!("  branch model on {changed} rows");
        }
        (changed > 0).then_some((h, g))
    }

    /// The ρ in (0, edge) where row p's law gives the force `target` (0 < target below its
    /// force at `edge`), by bisection (the law's force grows from 0 at the kink), or None.
    fn balancing_point(&self, p: usize, target: f64, edge: f64) -> Option<f64> {
        if target.is_nan() || target <= 0.0 {
            return None;
        }
        let (mut lo, mut hi) = (0.0f64, edge);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.laws.force(p, mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (hi > 0.0).then_some(0.5 * (lo + hi))
    }

    /// max_p |min(c_p(g_p − r_p), −G_p)| (|G_p| without a bound), in force units.
    fn complementarity_residual(&self, r: &[f64], grad: &[f64]) -> f64 {
        (0..self.m())
            .map(|p| {
                let g = self.g(p);
                if self.is_fixed(p) {
                    self.c(p) * (g - r[p]).abs()
                } else if g.is_finite() {
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
    /// `qdelta` is Q Δ ([`Self::trial_product`]).
    fn energy_change(&self, r: &[f64], delta: &[f64], grad: &[f64], qdelta: &[f64]) -> f64 {
        let m = self.m();
        let mut change = 0.0;
        for p in 0..m {
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

    /// Q Δ for the line search's trial Δ = −α d off the rows in `stops` (the path's stops), into
    /// `qdelta`: from Q d where the direction brought it (`qd`, CG's own products) and Q's
    /// columns on the stops where those are few, else by a product — by the single-precision Q
    /// where one is given (§9.2: the trial's energy and residual decide a step only; Q r − q
    /// carried by it is formed afresh before the solve is declared converged).
    fn trial_product(
        &self,
        (delta, direction, alpha, stops): (&[f64], &[f64], f64, &[usize]),
        (qd, single): (Option<&[f64]>, Option<&SingleMatrix>),
        qdelta: &mut [f64],
    ) {
        if let Some(qd) = qd.filter(|_| few_columns(stops.len(), self.m())) {
            qdelta.iter_mut().zip(qd).for_each(|(y, q)| *y = -alpha * q);
            if self.add_columns(stops.iter().map(|&p| (p, delta[p] + alpha * direction[p])), qdelta) {
                return;
            }
        }
        match single {
            Some(q) => q.apply(delta, qdelta),
            None => self.operator.apply_q(delta, qdelta),
        }
    }

    /// y += Σ a Q[:, p] over `columns` (p, a) where Q's rows are at hand (false, y untouched,
    /// where they are not).
    fn add_columns(&self, columns: impl Iterator<Item = (usize, f64)>, y: &mut [f64]) -> bool {
        let rows: Option<Vec<(&[f64], f64)>> = columns
            .map(|(p, a)| self.operator.q_row(p).map(|row| (row, a)))
            .collect();
        let Some(rows) = rows else {
            return false;
        };
        for (row, a) in rows.into_iter().filter(|&(_, a)| a != 0.0) {
            y.iter_mut().zip(row).for_each(|(y, q)| *y += a * q);
        }
        true
    }

    /// The complementarity residual at r + Δ.
    fn trial_residual(&self, r: &[f64], delta: &[f64], (qrd, qdelta): (&[f64], &[f64])) -> f64 {
        let m = self.m();
        let moved: Vec<f64> = (0..m).map(|p| r[p] + delta[p]).collect();
        let moved_qrd: Vec<f64> = qrd.iter().zip(qdelta).map(|(a, b)| a + b).collect();
        let mut grad = vec![0.0; m];
        self.gradient_from(&moved, &moved_qrd, &mut grad);
        self.complementarity_residual(&moved, &grad)
    }

    /// The force scale of the step: max(‖q‖∞, ‖Q v‖∞, max_p w_p S sup μ), v_p = min(0, g_p, o_p)
    /// the interference of rows that start past their bound or their obstacle's surface (a body
    /// placed into an obstacle is pushed out by forces of that size even without load; without
    /// the term an unloaded step with interference had a scale of 0 and could not converge).
    fn force_scale(&self, q: &[f64]) -> f64 {
        let m = self.m();
        let mut qd = vec![0.0; m];
        let load = q.iter().fold(0.0f64, |a, b| a.max(b.abs()));
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
        let mut q = vec![0.0; d.len()];
        self.operator.apply_q(d, &mut q);
        self.solve_forces(&q, state)
    }

    /// [`Self::solve`] for the free contact forces q = Q d (E(r) = ½ rᵀQr − qᵀr + Σ w j(r) up to
    /// a constant): the form that rigid parameters eliminated from Q need, whose q is not Q d
    /// for any d (docs/method.md §7.7).
    pub fn solve_forces(&self, d: &[f64], state: &mut ContactState) -> Result<ContactOutcome, ContactFailure> {
        let m = self.m();
        let fingerprint = self.fingerprint();
        let r = &mut state.normal_displacement;
        for (p, rp) in r.iter_mut().enumerate() {
            *rp = if self.is_fixed(p) { self.g(p) } else { rp.min(self.g(p)) };
        }
        let scale = self.force_scale(d);
        let tol = self.settings.tolerance * scale;
        let (mut qrd, mut grad) = (vec![0.0; m], vec![0.0; m]);
        let mut outcome = ContactOutcome::default();
        let mut direction = vec![0.0; m];
        let (mut trial, mut stops) = (vec![0.0; m], Vec::new());
        // A kink of j at r = 0 (∂j(0) an interval, e.g. [−Sa, Sa]): the smoothed j_ε bends
        // within ~ε of 0, which a Newton model taken farther out cannot see. The path stops
        // a node at 0 instead of carrying it across (it may cross at the next iteration, from
        // inside the smoothing zone); otherwise it zig-zags across the kink without converging.
        let kink: Vec<f64> = (0..m).map(|p| self.laws.kink_width(p)).collect();
        // The smallest residual so far: a full step that raises the energy is accepted only if
        // it halves this (a watchdog: such steps cannot cycle).
        let mut best_residual = f64::INFINITY;
        // The branch model is taken only after a full step: where the line search had to cut the
        // last step, some rows it sent out of their kink came back, and taking it again cycled
        // (docs/method.md §17.2).
        let mut full_step = true;
        // Q r − d is carried from iteration to iteration by the accepted step's Q Δ, which the line
        // search formed (one product by Q per direction fewer); it is formed afresh every eighth
        // iteration, after a cut step and before the solve is declared converged or stalled, so
        // rounding cannot accumulate
        let mut qtrial = vec![0.0; m];
        let mut carried = 0;
        loop {
            // 1. gradient and residual
            if outcome.iterations == 0 && self.on().product_reuse && is_balanced(&state.balanced_at, r, d) {
                qrd.iter_mut().zip(&state.force).for_each(|(a, f)| *a = -f);
            } else if carried == 0 {
                self.residual_force(r, d, &mut qrd);
            }
            self.gradient_from(r, &qrd, &mut grad);
            let mut residual = self.complementarity_residual(r, &grad);
            if residual <= tol && carried > 0 {
                self.gradient(r, d, &mut qrd, &mut grad);
                residual = self.complementarity_residual(r, &grad);
            }
            best_residual = best_residual.min(residual);
            outcome.residual = residual / scale;
            if tracing() {
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
                    smallest_residual: best_residual / scale,
                });
            }
            outcome.iterations += 1;

            // 2. active set
            let active = self.active_set(r, &grad);
            let free: Vec<usize> = (0..m).filter(|&p| !active[p]).collect();

            // 3. Newton direction on the inactive set, diagonal scaling on the active set
            let proximal = if self.singular && self.on().proximal_shift {
                (residual / scale).min(1e-6)
            } else {
                0.0
            };
            let hessian = self.law_hessian(r, &free);
            // (kept through the convexification, which drops only the laws' negative part)
            let proximal: Vec<f64> = free.iter().map(|&p| proximal * self.c(p)).collect();
            // (rows leaving their kink: the branch model's direction where it descends, §17.2)
            let slope = |d: &[f64]| free.iter().zip(d).map(|(&p, d)| grad[p] * d).sum::<f64>();
            // the relative accuracy of an iterative direction (inexact Newton): the relative
            // residual, which keeps the convergence quadratic, at most 10⁻² and no finer than a
            // tenth of what the last step needs to pass the tolerance (docs/method.md §9.2)
            let forcing = match self.on().inexact_newton {
                true => (residual / scale).max(0.1 * tol / residual).clamp(1e-13, 1e-2),
                false => 1e-13,
            };
            let mut direct = |h: &LawHessian, g: &[f64]| {
                let kept = (&mut state.newton_factor, &mut state.buffer);
                self.newton_direction(&free, (h, &proximal, forcing), g, &mut outcome, kept, fingerprint)
            };
            let branch = full_step && self.on().branch_model;
            let mut free_dir = (branch.then(|| self.branch_model(r, &free, &hessian, &grad, &kink)))
                .flatten()
                .map(|(h, g)| direct(&h, &g));
            if free_dir.as_ref().is_some_and(|(d, _)| slope(d) <= 0.0) {
                if tracing() {
                    eprintln!("  the branch model's direction does not descend: the law's own");
                }
                free_dir = None;
            }
            let (free_dir, q_free) = free_dir.unwrap_or_else(|| direct(&hessian, &grad));
            let predicted_slope = slope(&free_dir);
            for (k, &p) in free.iter().enumerate() {
                direction[p] = free_dir[k];
            }
            for p in (0..m).filter(|&p| active[p]) {
                direction[p] = grad[p] / self.c(p);
            }
            // Q d from CG's own products on the free rows and Q's columns on the held ones, where
            // those are few: the line search's trials then need no product (docs/method.md §9.2)
            let reuse = self.on().product_reuse;
            let qdir = q_free
                .filter(|_| reuse && few_columns(m - free.len(), m))
                .and_then(|mut qd| {
                    let held = (0..m).filter(|&p| active[p]).map(|p| (p, direction[p]));
                    self.add_columns(held, &mut qd).then_some(qd)
                });

            // 4. projected Armijo backtracking on the energy
            let single = (state.newton_factor.0.as_ref())
                .filter(|k| k.fingerprint == fingerprint)
                .and_then(|k| k.q_single.clone());
            let mut alpha = 1.0;
            loop {
                let path = (&direction[..], &active[..], &kink[..], &grad[..]);
                let decrease_bound = alpha * predicted_slope + self.path(r, path, alpha, (&mut trial, &mut stops));
                let trial_at = (&trial[..], &direction[..], alpha, &stops[..]);
                self.trial_product(trial_at, (qdir.as_deref(), single.as_deref()), &mut qtrial);
                let change = self.energy_change(r, &trial, &grad, &qtrial);
                if change <= -ARMIJO * decrease_bound || (change <= 0.0 && decrease_bound <= 1e-300) {
                    break;
                }
                // Local phase: a full step that halves the complementarity residual is kept
                // even where the energy change is below its rounding.
                let watchdog = self.on().watchdog && alpha == 1.0;
                if watchdog && self.trial_residual(r, &trial, (&qrd, &qtrial)) <= 0.5 * best_residual {
                    break;
                }
                alpha *= 0.5;
                outcome.line_search_cuts += 1;
                if alpha < MIN_STEP {
                    // At the round-off floor the energy cannot decrease measurably: accept a
                    // residual within 100× the tolerance (measured with Q r − d formed afresh),
                    // otherwise report the stall.
                    let floor = if carried > 0 {
                        self.gradient(r, d, &mut qrd, &mut grad);
                        self.complementarity_residual(r, &grad)
                    } else {
                        residual
                    };
                    if self.on().round_off_acceptance && floor <= 100.0 * tol {
                        self.finish((d, &qrd), state, &mut outcome);
                        return Ok(outcome);
                    }
                    return Err(ContactFailure {
                        outcome,
                        smallest_residual: best_residual / scale,
                        reason: "the line search could not decrease the energy (the regularised law may be too steep: increase `contact.law.regularisation` or reduce the time step)".into(),
                    });
                }
            }
            full_step = alpha == 1.0;
            for p in 0..m {
                r[p] += trial[p];
                if r[p] > self.g(p) {
                    r[p] = self.g(p);
                }
                qrd[p] += qtrial[p];
            }
            // (after a cut step afresh: near the round-off floor, where the line search cuts,
            // the residual and the smallest one reported are measured exactly)
            carried = if full_step && reuse { (carried + 1) % 8 } else { 0 };
        }
        self.finish((d, &qrd), state, &mut outcome);
        Ok(outcome)
    }

    /// The move `trial` to the point α along the projected path r − α d (`direction`): rows
    /// held at or pushed past their bound stay at it, a single row that would cross its kink
    /// from outside its smoothing zone stops at the kink, and a pair's path x − s d stops where
    /// it passes the origin, at its nearest point s* = x·d/|d|² (docs/method.md §4.4, §17.3).
    /// Returns the first-order decrease those stops add to α Gᵀd (the path's own, for Armijo).
    fn path(
        &self,
        r: &[f64],
        (direction, active, kink, grad): (&[f64], &[bool], &[f64], &[f64]),
        alpha: f64,
        (trial, stops): (&mut [f64], &mut Vec<usize>),
    ) -> f64 {
        let mut decrease = 0.0;
        let stops_on = self.on().kink_stops;
        stops.clear();
        for p in 0..self.m() {
            let along = r[p] - alpha * direction[p];
            let mut moved = if self.is_fixed(p) {
                self.g(p)
            } else {
                along.min(self.g(p))
            };
            let o = self.origin(p);
            let single = self.partner(p).is_none();
            if stops_on && single && !active[p] && (r[p] - o).abs() > kink[p] && (moved - o) * (r[p] - o) < 0.0 {
                // stop at the kink: the first-order decrease is that of the shorter move
                decrease += grad[p] * (r[p] - o - alpha * direction[p]);
                moved = o;
            }
            if moved != along {
                stops.push(p);
            }
            trial[p] = moved - r[p];
            if active[p] {
                decrease -= grad[p] * trial[p];
            }
        }
        for (p, q) in (0..self.m()).filter_map(|p| self.partner(p).filter(|&q| q > p).map(|q| (p, q))) {
            let (x, rho) = self.pair_at(r, p, q);
            let d = [direction[p], direction[q]];
            let along = x[0] * d[0] + x[1] * d[1];
            if stops_on && rho > kink[p] && rho * rho < alpha * along {
                let nearest = along / (d[0] * d[0] + d[1] * d[1]);
                decrease += (nearest - alpha) * (grad[p] * d[0] + grad[q] * d[1]);
                trial[p] = -nearest * d[0];
                trial[q] = -nearest * d[1];
                stops.extend([p, q]);
            }
        }
        stops.sort_unstable();
        stops.dedup();
        decrease
    }

    /// The active set at r: the PDAS rule, plus the rows within δ of their bound pushed into it
    /// (and the bilateral rows, always held).
    fn active_set(&self, r: &[f64], grad: &[f64]) -> Vec<bool> {
        let m = self.m();
        let enlarged = self.on().enlarged_active_set;
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
        (0..m)
            .map(|p| {
                let g = self.g(p);
                self.is_fixed(p)
                    || g.is_finite()
                        && (r[p] - grad[p] / self.c(p) >= g || (enlarged && g - r[p] <= delta && grad[p] < 0.0))
            })
            .collect()
    }

    /// One Newton step on Coulomb's coupled law from the point a round of the fixed point left
    /// (docs/method.md §17.2): the tangential rows' bound forces F_k = μ_k π(λ_p) follow the
    /// normal forces λ = q − Q r in the step instead of being held. `coulomb` lists per Coulomb
    /// row k its normal row p, the round's bound force F_k and μ_k. The residual is
    /// R = (Q r − q) + λ_law with F_k = μ_k π(λ_p), its Jacobian on the free rows
    /// Q + H − E Q (E_kp = μ_k π'(λ_p) φ_k, φ_k = the row's law force over F_k), solved by GMRES
    /// preconditioned by the kept factor; the full step is taken (the next round's solve is the
    /// globalisation) and λ formed at the new r. Returns GMRES's iterations (0: the coupled
    /// residual already met the tolerance, no step taken); None, and nothing changed, where no
    /// kept factor of this operator serves, Q is singular or GMRES fails.
    pub fn coupled_step(
        &self,
        q: &[f64],
        state: &mut ContactState,
        coulomb: &[(usize, usize, f64, f64)],
    ) -> Option<usize> {
        let m = self.m();
        let fingerprint = self.fingerprint();
        if self.singular || (state.newton_factor.0.as_ref()).is_none_or(|k| k.fingerprint != fingerprint) {
            return None;
        }
        let r = state.normal_displacement.clone();
        let mut qrd = vec![0.0; m];
        if self.on().product_reuse && is_balanced(&state.balanced_at, &r, q) {
            qrd.iter_mut().zip(&state.force).for_each(|(a, f)| *a = -f);
        } else {
            self.residual_force(&r, q, &mut qrd);
        }
        let mut grad = vec![0.0; m];
        self.gradient_from(&r, &qrd, &mut grad);
        // the coupled residual and E's entries, per Coulomb row
        let mut coefficient = vec![(usize::MAX, 0.0); m];
        for &(k, p, force, mu) in coulomb {
            let lambda = -qrd[p];
            let (pressing, slope) = match self.is_fixed(p) {
                true => (lambda.abs(), lambda.signum()),
                false if lambda > 0.0 => (lambda, 1.0),
                false => (0.0, 0.0),
            };
            let phi = if force > 0.0 {
                self.law_force(&r, k) / force
            } else {
                0.0
            };
            grad[k] += (mu * pressing - force) * phi;
            coefficient[k] = (p, mu * slope * phi);
        }
        let active = self.active_set(&r, &grad);
        let free: Vec<usize> = (0..m).filter(|&p| !active[p]).collect();
        let hessian = self.law_hessian(&r, &free);
        let coupled: Vec<(usize, f64)> = free.iter().map(|&p| coefficient[p]).collect();
        // no step where the coupled residual meets this solver's tolerance already
        let scale = self.force_scale(q);
        let residual = self.complementarity_residual(&r, &grad);
        let tol = self.settings.tolerance * scale;
        if residual <= tol {
            return Some(0);
        }
        // (10⁻⁴: solve_forces' adaptive rule took 268 directions on the slab against 256)
        let forcing = 1e-4;
        let kept = state.newton_factor.0.as_mut()?;
        let (x, iterations, _) = self.preconditioned_cg(
            kept,
            &free,
            (&hessian.diagonal, &hessian),
            &grad,
            (forcing, Some(&coupled)),
        )?;
        // the step along the solver's path (kink and pair stops), the held rows kept
        let mut direction = vec![0.0; m];
        for (i, &p) in free.iter().enumerate() {
            direction[p] = x[i];
        }
        let kink: Vec<f64> = (0..m).map(|p| self.laws.kink_width(p)).collect();
        let mut trial = vec![0.0; m];
        self.path(
            &r,
            (&direction, &active, &kink, &grad),
            1.0,
            (&mut trial, &mut Vec::new()),
        );
        let r = &mut state.normal_displacement;
        for p in 0..m {
            if !active[p] {
                r[p] = (r[p] + trial[p]).min(self.g(p));
            }
        }
        self.residual_force(r, q, &mut qrd);
        state.force.iter_mut().zip(&qrd).for_each(|(f, a)| *f = -a);
        state.balanced_at = Some((r.clone(), q.to_vec()));
        Some(iterations)
    }

    /// Solves (Q_ℐℐ + H + diag(proximal)) x = G_ℐ, H the laws' Hessian (diagonal, and 2 × 2
    /// blocks on pairs), convexifying H when the matrix is indefinite. Above
    /// `dense_limit` free nodes the factorisation is kept in `kept` and reused by
    /// [`Self::preconditioned_cg`] until it no longer serves; it is formed without the rows a law
    /// holds stiffly ([`STIFF`]), and its own direction is then CG's (docs/method.md §9.2).
    fn newton_direction(
        &self,
        free: &[usize],
        (hessian, proximal, forcing): (&LawHessian, &[f64], f64),
        grad: &[f64],
        outcome: &mut ContactOutcome,
        (kept, buffer): (&mut KeptFactor, &mut FactorBuffer),
        fingerprint: (usize, u64),
    ) -> (Vec<f64>, Option<Vec<f64>>) {
        let nf = free.len();
        if nf == 0 {
            return (Vec::new(), Some(vec![0.0; self.m()]));
        }
        if let Some(x) = self.direction_in_w(free, hessian, grad, buffer) {
            outcome.factorisations += 1;
            outcome.in_w += 1;
            return (x, None);
        }
        let exact: Vec<f64> = hessian.diagonal.iter().zip(proximal).map(|(e, p)| e + p).collect();
        let reuse = nf > self.settings.dense_limit && self.on().kept_factor;
        let reused = (kept.0.as_mut())
            .filter(|k| reuse && k.fingerprint == fingerprint)
            .and_then(|k| self.preconditioned_cg(k, free, (&exact, hessian), grad, (forcing, None)));
        if let Some((x, _, qx)) = reused {
            outcome.iterative += 1;
            return (x, qx);
        }
        outcome.factorisations += 1;
        let rhs = |rows: &[usize]| -> Vec<f64> { rows.iter().map(|&p| grad[p]).collect() };
        if !reuse {
            let all: Vec<usize> = (0..nf).collect();
            let llt = self
                .factor_rows(free, &all, (hessian, proximal), (buffer, fingerprint), (outcome, true))
                .factor;
            let x = llt.solve(&rhs(free));
            self.recycle(buffer, llt);
            return (x, None);
        }
        // the kept factor leaves out the rows a law holds stiffly (Jacobi preconditions them,
        // docs/method.md §9.2): its direction is then CG's on it
        let mut factored: Vec<usize> = (0..nf)
            .filter(|&i| !self.on().jacobi_rows || !self.stiff(free, (&exact, hessian), i, STIFF))
            .collect();
        if factored.is_empty() {
            factored = (0..nf).collect();
        }
        let convexified = outcome.convexified;
        // the kept factor is replaced: its storage serves the new one (no fresh n² allocation,
        // and the two are not alive together), its single-precision Q is carried over
        let old = kept.0.take();
        let q_single = (old.as_ref())
            .filter(|k| k.fingerprint == fingerprint)
            .and_then(|k| k.q_single.clone());
        if let Some(old) = old {
            self.recycle(buffer, old.factor);
        }
        let mut fresh = self.factor_rows(
            free,
            &factored,
            (hessian, proximal),
            (buffer, fingerprint),
            (outcome, true),
        );
        fresh.q_single = q_single;
        // where the exact Newton matrix on the factored rows is not positive definite, neither is
        // the one on all free rows (it holds it as a principal submatrix): the refactorisation
        // below does not try it again
        let indefinite = outcome.convexified > convexified;
        let mut x = None;
        if factored.len() < nf {
            x = self.preconditioned_cg(&mut fresh, free, (&exact, hessian), grad, (forcing, None));
            if x.is_none() {
                // CG met a direction of non-positive curvature or did not converge: the dense
                // direction on every free row
                self.recycle(buffer, fresh.factor);
                outcome.factorisations += 1;
                let all: Vec<usize> = (0..nf).collect();
                let (tries, q_single) = ((outcome, !indefinite), fresh.q_single.take());
                fresh = self.factor_rows(free, &all, (hessian, proximal), (buffer, fingerprint), tries);
                fresh.q_single = q_single;
            }
        }
        let x = x.map_or_else(|| (fresh.factor.solve(&rhs(free)), None), |(x, _, qx)| (x, qx));
        kept.0 = Some(fresh);
        x
    }

    /// The Newton matrix Q + H on the free rows `factored` (indices into `free`) factored, as a
    /// [`ReusedFactor`]: H the laws' exact Hessian with the proximal term, else (where that is not
    /// positive definite, or not `exact_first`) the convexified one, shifted as §4.4 says until
    /// Cholesky succeeds.
    fn factor_rows(
        &self,
        free: &[usize],
        factored: &[usize],
        (hessian, proximal): (&LawHessian, &[f64]),
        (buffer, fingerprint): (&mut FactorBuffer, (usize, u64)),
        (outcome, exact_first): (&mut ContactOutcome, bool),
    ) -> ReusedFactor {
        let rows: Vec<usize> = factored.iter().map(|&i| free[i]).collect();
        let n = rows.len();
        let mut place = vec![usize::MAX; free.len()];
        for (a, &i) in factored.iter().enumerate() {
            place[i] = a;
        }
        let on_rows = |v: &[f64]| -> Vec<f64> { factored.iter().map(|&i| v[i]).collect() };
        let partner: Vec<usize> = (factored.iter())
            .map(|&i| place.get(hessian.partner[i]).copied().unwrap_or(usize::MAX))
            .collect();
        // the matrix's lower triangle column by column, column j from Q's row rows[j] (Q is
        // symmetric), in storage kept between factorisations (docs/method.md §9.7)
        let mut build = |diag: &[f64], coupling: &[f64]| {
            buffer.factor(n, |matrix| {
                for (j, column) in matrix.chunks_exact_mut(n).enumerate() {
                    let p = rows[j];
                    for (i, v) in column.iter_mut().enumerate().skip(j) {
                        *v = self.operator.q(p, rows[i]);
                    }
                    column[j] += diag[j];
                    if partner[j] != usize::MAX && partner[j] > j {
                        column[partner[j]] += coupling[partner[j]];
                    }
                }
            })
        };
        let exact: Vec<f64> = factored.iter().map(|&i| hessian.diagonal[i] + proximal[i]).collect();
        let coupling = on_rows(&hessian.coupling);
        let (factor, diagonal, coupling) = match exact_first.then(|| build(&exact, &coupling)).flatten() {
            Some(llt) => (llt, exact, coupling),
            None => {
                outcome.convexified += 1;
                let mut shift = 0.0;
                loop {
                    let diagonal: Vec<f64> = (factored.iter())
                        .map(|&i| hessian.convex_diagonal[i] + proximal[i] + shift)
                        .collect();
                    let coupling = on_rows(&hessian.convex_coupling);
                    if let Some(llt) = build(&diagonal, &coupling) {
                        break (llt, diagonal, coupling);
                    }
                    shift = if shift == 0.0 {
                        1e-12 * self.c(rows[0])
                    } else {
                        shift * 10.0
                    };
                }
            }
        };
        let mut row = vec![usize::MAX; self.m()];
        for (a, &p) in rows.iter().enumerate() {
            row[p] = a;
        }
        ReusedFactor {
            fingerprint,
            row,
            diagonal,
            coupling,
            single: std::sync::OnceLock::new(),
            factor,
            q_single: None,
            served: 0,
            columns: Vec::new(),
            column_of: vec![usize::MAX; n],
            bordered: Vec::new(),
            bordered_of: vec![usize::MAX; self.m()],
        }
    }

    /// The Newton direction in W (docs/method.md §4.6, src/contact/newton_w.rs) where it applies and
    /// pays: Q = W⁻¹ exactly (no rigid parameter eliminated from Q), the laws' curvature H ≥ 0
    /// (no convexification to decide), and few enough directions of positive curvature beside
    /// the held rows.
    fn direction_in_w(
        &self,
        free: &[usize],
        hessian: &LawHessian,
        grad: &[f64],
        buffer: &mut FactorBuffer,
    ) -> Option<Vec<f64>> {
        if self.singular {
            return None;
        }
        let m = self.m();
        let Some(w) = self.operator.w() else {
            return self.direction_without_w(free, hessian, grad).filter(|_| self.on().w_product);
        };
        // a curvature below 10⁻⁸ of the direction's least stiffness 1/(eᵀWe) counts as none
        let negligible = |h: f64, e: &Curvature| h * e.compliance(w, m) <= 1e-8;
        let mut curvature: Vec<Curvature> = Vec::new();
        for (i, &p) in free.iter().enumerate() {
            let j = hessian.partner[i];
            if j == usize::MAX {
                let h = hessian.diagonal[i];
                if h < 0.0 {
                    return None;
                }
                let e = Curvature::row(p, 1.0 / h);
                if !negligible(h, &e) {
                    curvature.push(e);
                }
            } else if i < j {
                // a pair's block a nnᵀ + b (I − nnᵀ): directions n and t = n rotated by 90°,
                // both curved (sticking): its two rows coupled by the block's inverse
                let (a, b, n) = hessian.pair[i];
                if a < 0.0 || b < 0.0 {
                    return None;
                }
                let rows = [p, free[j]];
                let t = [-n[1], n[0]];
                let along = Curvature::pair(rows, n, 1.0 / a);
                let across = Curvature::pair(rows, t, 1.0 / b);
                match (negligible(a, &along), negligible(b, &across)) {
                    (true, true) => {}
                    (false, true) => curvature.push(along),
                    (true, false) => curvature.push(across),
                    (false, false) => {
                        let (ia, ib) = (1.0 / a, 1.0 / b);
                        let k = curvature.len();
                        let coupling = (ia - ib) * n[0] * n[1];
                        for (r, (row, partner)) in [(p, k + 1), (free[j], k)].into_iter().enumerate() {
                            curvature.push(Curvature {
                                partner,
                                coupling,
                                ..Curvature::row(row, ib + (ia - ib) * n[r] * n[r])
                            });
                        }
                    }
                }
            }
        }
        if tracing() {
            let singles = curvature.iter().filter(|c| c.rows[1] == usize::MAX).count();
            eprintln!(
                "  in W: free {} directions {} (single rows {singles}) held {}",
                free.len(),
                curvature.len(),
                m - free.len()
            );
        }
        if !newton_w::pays(m, free.len(), curvature.len()) {
            return None;
        }
        let rows = curvature.len() + m - free.len();
        if (rows == 0 && !self.on().w_product) || (rows > 0 && !self.on().system_in_w) {
            return None;
        }
        let b: Vec<f64> = free.iter().map(|&p| grad[p]).collect();
        let mut fresh = FactorBuffer::default();
        let buffer = if self.on().recycled_storage { buffer } else { &mut fresh };
        newton_w::direction((w, m), free, &curvature, &b, buffer)
    }

    /// The direction in W where W was not formed (docs/method.md §9.7): where no row is
    /// held and none has curvature (a surface that starts a step apart, under a law without
    /// curvature off contact) the system in W has no rows and Δ = W G, two triangular solves
    /// in place of a factorisation of Q; elsewhere None (the caller solves in Q).
    fn direction_without_w(&self, free: &[usize], hessian: &LawHessian, grad: &[f64]) -> Option<Vec<f64>> {
        let m = self.m();
        let curved = hessian.diagonal.iter().any(|&h| h != 0.0) || hessian.partner.iter().any(|&j| j != usize::MAX);
        if free.len() != m || curved {
            return None;
        }
        let mut x = vec![0.0; m];
        self.operator
            .apply_w(grad, &mut x)
            .then(|| free.iter().map(|&p| x[p]).collect())
    }

    /// Whether free row i's law curvature is `share` times its stiffness Q_pp or more (a pair:
    /// both of its block's curvatures beside both rows' stiffness), so that Jacobi's 1/(Q_pp + e_p)
    /// preconditions it well and the kept factor can leave it out (docs/method.md §9.2).
    fn stiff(&self, free: &[usize], (curvature, hessian): (&[f64], &LawHessian), i: usize, share: f64) -> bool {
        let p = free[i];
        match hessian.partner.get(i).copied().unwrap_or(usize::MAX) {
            usize::MAX => curvature[i] > share * self.c(p),
            j => {
                let (a, b, _) = hessian.pair[i];
                a.min(b) > share * self.c(p).max(self.c(free[j]))
            }
        }
    }

    /// m and the bits of Σ_p Q_pp: a kept factorisation of another operator (step 0's K_A, or
    /// another run's) is not reused.
    fn fingerprint(&self) -> (usize, u64) {
        let m = self.m();
        (m, (0..m).map(|p| self.c(p)).sum::<f64>().to_bits())
    }

    /// (Q_ℐℐ + diag(curvature)) x = G_ℐ by conjugate gradients preconditioned with the kept
    /// factorisation of an earlier Newton matrix A₀ = Q_ℱℱ + diag(e) (docs/method.md §9.2), ℱ the
    /// rows it was formed on: the free rows then, less those a law held stiffly.
    ///
    /// The preconditioner is A₀ brought to the present free set and curvatures:
    /// * **updated** on the rows of ℱ whose curvature moved by more than [`MOVED`] of their
    ///   stiffness (𝒰, with a pair's partner): P = A₀ + UΔUᵀ, Δ the change of the diagonal and the pairs'
    ///   coupling there, and **pinned** (Δ = ∞, the row held at 0) on the rows of ℱ that left the
    ///   free set, applied by Woodbury's identity P⁻¹ = A₀⁻¹ − Z (I + Δ Uᵀ Z)⁻¹ Δ Uᵀ A₀⁻¹ with
    ///   Z = A₀⁻¹ U, whose columns are kept with the factor (one blocked solve for the rows new to
    ///   𝒰; a pinned row's capacitance row is its limit Uᵀ Z);
    /// * **bordered** by the free rows outside ℱ that no law holds stiffly (𝒥: joined the free set
    ///   or left a law's stiff part since): their Schur complement S = A_𝒥𝒥 − A_𝒥ℱ P⁻¹ A_ℱ𝒥, with
    ///   A₀⁻¹ A_ℱ𝒥 kept with the factor per row;
    /// * Jacobi's 1/(Q_pp + e_p) on the rows still held stiffly outside ℱ.
    ///
    /// P is then the Newton matrix up to the other rows' small changes and the stiff rows'
    /// coupling (below 1/√10 of their diagonal), so CG needs a few iterations; each costs a
    /// product by Q, two triangular solves and products by Z and the border, where a
    /// factorisation costs O(|ℐ|³). None past |ℱ|/8 new columns of Z (they would cost most of a
    /// factorisation), |ℱ|/4 rows in 𝒰 with the pinned ones, |ℱ|/4 kept columns (a quarter of the
    /// factor's memory), |ℱ|/8 rows in 𝒥 or |ℱ|/4 bordered rows kept. CG stops at the relative
    /// residual `forcing` (inexact Newton, docs/method.md §9.2).
    ///
    /// None (the caller refactors) also when a direction of non-positive curvature turns up, or
    /// when the relative residual has not reached `forcing` within 10 + |ℐ|/200 iterations (about
    /// the cost of one factorisation at |ℐ| = 4 000, measured in docs/method.md §9.2).
    ///
    /// The products by Q are in single precision (the sums in double, [`SingleMatrix`]) where
    /// `forcing` ≥ [`SINGLE_FORCING`]. With `coupled` (per free row: Coulomb's normal row p and
    /// the entry a of E, usize::MAX for none) the system is the coupled law's
    /// (Q + H − E Q) x = G, not symmetric, and GMRES solves it with the same preconditioner
    /// ([`Self::coupled_step`]). Returns x, the iterations and, from CG, Q x over all rows ([`Krylov`]).
    fn preconditioned_cg(
        &self,
        kept: &mut ReusedFactor,
        free: &[usize],
        (curvature, hessian): (&[f64], &LawHessian),
        grad: &[f64],
        (forcing, coupled): (f64, Option<&[(usize, f64)]>),
    ) -> Option<Krylov> {
        let (m, nf) = (self.m(), free.len());
        let joined_rows: Vec<usize> = (0..nf)
            .filter(|&i| {
                kept.row[free[i]] == usize::MAX
                    && (!self.on().jacobi_rows || !self.stiff(free, (curvature, hessian), i, STIFF / 10.0))
            })
            .collect();
        let joined = joined_rows.len();
        // the kept rows that left the free set: pinned at 0 by the update (an infinite Δ)
        let mut now_free = vec![false; kept.diagonal.len()];
        for &p in free {
            if kept.row[p] != usize::MAX {
                now_free[kept.row[p]] = true;
            }
        }
        let pinned: Vec<usize> = (0..now_free.len()).filter(|&k| !now_free[k]).collect();
        let moved = |i: usize| {
            let (p, k) = (free[i], kept.row[free[i]]);
            if k == usize::MAX {
                return false;
            }
            let limit = MOVED * (self.c(p) + kept.diagonal[k].abs());
            (curvature[i] - kept.diagonal[k]).abs() > limit
                || hessian.partner[i] != usize::MAX && (hessian.coupling[i] - kept.coupling[k]).abs() > limit
        };
        let mut in_u: Vec<bool> = (0..nf).map(moved).collect();
        for i in 0..nf {
            if in_u[i] && hessian.partner[i] != usize::MAX && kept.row[free[hessian.partner[i]]] != usize::MAX {
                in_u[hessian.partner[i]] = true;
            }
        }
        let u: Vec<usize> = (0..nf).filter(|&i| in_u[i]).collect();
        if tracing() {
            eprintln!(
                "  reused factor: updated on {} of {nf} rows, {} pinned, {joined} joined",
                u.len(),
                pinned.len()
            );
        }
        let n = kept.diagonal.len();
        let bordered = kept.bordered.len() / (2 * n).max(1);
        if 8 * joined > n || 4 * (bordered + joined) > n {
            return None;
        }
        if (joined > 0 && !self.on().border) || (!(u.is_empty() && pinned.is_empty()) && !self.on().low_rank_update) {
            return None;
        }
        let update = if u.is_empty() && pinned.is_empty() {
            None
        } else {
            Some(self.low_rank_update(kept, free, (curvature, hessian), (&u, &pinned))?)
        };
        let border = if joined_rows.is_empty() {
            None
        } else {
            Some(self.border(kept, update.as_ref(), free, (curvature, hessian), &joined_rows))
        };
        // single precision only for a factor reused (not a fresh one's first direction) where it
        // is not the Newton matrix itself: with an exact preconditioner CG's first iteration gives
        // the direction to double precision, which a problem linear in the step (a soft layer)
        // needs to finish in one direction (docs/method.md §9.2)
        let exact = update.is_none() && border.is_none() && free.iter().all(|&p| kept.row[p] != usize::MAX);
        let single = !exact && kept.served > 0 && self.on().single_precision;
        let solved = self.iterate(
            kept,
            free,
            (curvature, hessian),
            grad,
            (forcing, coupled, single),
            (update.as_ref(), border.as_ref()),
        );
        if solved.is_some() {
            kept.served += 1;
            // Q in single precision for the next directions, once a reused factor has served one
            // whose accuracy allowed it
            if single && forcing >= SINGLE_FORCING && kept.q_single.is_none() {
                let rows: Option<Vec<&[f64]>> = (0..m).map(|p| self.operator.q_row(p)).collect();
                let single = match rows {
                    Some(rows) => SingleMatrix::from_rows(m, |p| rows[p]),
                    None => SingleMatrix::new(m, |p, r| self.operator.q(p, r)),
                };
                kept.q_single = Some(std::sync::Arc::new(single));
            }
        }
        solved
    }

    /// The iteration of [`Self::preconditioned_cg`] (CG, or GMRES on the coupled system) with the
    /// kept factor updated and bordered.
    fn iterate(
        &self,
        kept: &ReusedFactor,
        free: &[usize],
        (curvature, hessian): (&[f64], &LawHessian),
        grad: &[f64],
        (forcing, coupled, low): (f64, Option<&[(usize, f64)]>, bool),
        (update, border): (Option<&LowRankUpdate>, Option<&Border>),
    ) -> Option<Krylov> {
        let (m, nf) = (self.m(), free.len());
        let iterations = 10 + nf / 200;
        // the products in single precision where the accuracy asked is well above its rounding
        let single = kept.q_single.clone().filter(|_| low && forcing >= SINGLE_FORCING);
        let mut full = vec![0.0; m];
        // the last product by Q over all rows (CG sums them into Q x)
        let product = std::cell::RefCell::new(vec![0.0; m]);
        let mut apply = |x: &[f64], y: &mut [f64]| {
            full.fill(0.0);
            for (i, &p) in free.iter().enumerate() {
                full[p] = x[i];
            }
            let mut product = product.borrow_mut();
            match &single {
                Some(q) => q.apply(&full, &mut product),
                None => self.operator.apply_q(&full, &mut product),
            }
            for (i, &p) in free.iter().enumerate() {
                y[i] = product[p] + curvature[i] * x[i];
                if let Some(&j) = hessian.partner.get(i).filter(|&&j| j != usize::MAX) {
                    y[i] += hessian.coupling[i] * x[j];
                }
                if let Some(&(p, a)) = coupled.map(|c| &c[i]).filter(|c| c.0 != usize::MAX) {
                    y[i] -= a * product[p];
                }
            }
        };
        let mut kept_rhs = vec![0.0; kept.diagonal.len()];
        let mut precondition = |r: &[f64], z: &mut [f64]| {
            kept_rhs.fill(0.0);
            for (i, &p) in free.iter().enumerate() {
                if kept.row[p] != usize::MAX {
                    kept_rhs[kept.row[p]] = r[i];
                }
            }
            // (one column on the run's threads: a preconditioner's rounding only changes CG's path)
            match low {
                true => kept.single().solve_columns_in_place(&mut kept_rhs, 1),
                false => kept.factor.solve_columns_in_place(&mut kept_rhs, 1),
            }
            if let Some(update) = update {
                update.correct_columns(&kept.columns, &mut kept_rhs, 1);
            }
            if let Some(border) = border {
                border.correct(r, &mut kept_rhs, z);
            }
            for (i, &p) in free.iter().enumerate() {
                if border.as_ref().is_some_and(|b| b.is_row[i]) {
                    continue;
                }
                z[i] = match kept.row[p] {
                    usize::MAX => r[i] / (self.c(p) + curvature[i].max(0.0)),
                    k => kept_rhs[k],
                };
            }
        };
        let b: Vec<f64> = free.iter().map(|&p| grad[p]).collect();
        if coupled.is_some() {
            let solved = krylov::gmres(apply, precondition, &b, forcing, iterations);
            if tracing() {
                eprintln!("  coupled step: GMRES {:?}", solved.as_ref().map(|s| s.1));
            }
            return solved.map(|(x, k)| (x, k, None));
        }
        let norm_b = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut x = vec![0.0; nf];
        let mut qx = vec![0.0; m];
        if norm_b == 0.0 {
            return Some((x, 0, Some(qx)));
        }
        let mut r = b;
        let mut z = vec![0.0; nf];
        precondition(&r, &mut z);
        let mut dir = z.clone();
        let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let mut ad = vec![0.0; nf];
        for k in 0..iterations {
            apply(&dir, &mut ad);
            let curvature_along: f64 = dir.iter().zip(&ad).map(|(a, b)| a * b).sum();
            // (rz ≤ 0: the updated preconditioner is not positive definite)
            if curvature_along <= 0.0 || rz <= 0.0 {
                return None;
            }
            let alpha = rz / curvature_along;
            for i in 0..nf {
                x[i] += alpha * dir[i];
                r[i] -= alpha * ad[i];
            }
            qx.iter_mut()
                .zip(product.borrow().iter())
                .for_each(|(y, q)| *y += alpha * q);
            if r.iter().map(|v| v * v).sum::<f64>().sqrt() <= forcing * norm_b {
                if tracing() {
                    eprintln!("  reused factor: {} conjugate-gradient iterations", k + 1);
                }
                return Some((x, k + 1, Some(qx)));
            }
            precondition(&r, &mut z);
            let next: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = next / rz;
            rz = next;
            for i in 0..nf {
                dir[i] = z[i] + beta * dir[i];
            }
        }
        if tracing() {
            eprintln!("  reused factor: no convergence in {iterations} iterations, refactoring");
        }
        None
    }

    /// The border of [`Self::preconditioned_cg`] for the free rows `joined` outside the kept
    /// factor: A_ℱ𝒥 (Q's columns on the factor's rows; its rows pinned by the update drop out of
    /// P⁻¹), X = P⁻¹ A_ℱ𝒥 (A₀⁻¹ A_ℱ𝒥 kept with the factor, new rows' by one blocked solve, then
    /// the update's correction, blocked) and S = A_𝒥𝒥 − A_𝒥ℱ X, factored.
    fn border(
        &self,
        kept: &mut ReusedFactor,
        update: Option<&LowRankUpdate>,
        free: &[usize],
        (curvature, hessian): (&[f64], &LawHessian),
        joined: &[usize],
    ) -> Border {
        let n = kept.diagonal.len();
        let k = joined.len();
        // A_KJ's columns: Q's on the factor's rows (a pair's coupling across K and J left out:
        // dropping a PSD block's off-diagonal keeps it PSD), and A₀⁻¹ a_p kept with the factor
        let fresh: Vec<usize> = (joined.iter().map(|&j| free[j]))
            .filter(|&p| kept.bordered_of[p] == usize::MAX)
            .collect();
        if !fresh.is_empty() {
            let mut rows_of = vec![usize::MAX; n];
            for (p, &row) in kept.row.iter().enumerate() {
                if row != usize::MAX {
                    rows_of[row] = p;
                }
            }
            let mut a = vec![0.0; n * fresh.len()];
            for (column, &p) in a.chunks_exact_mut(n).zip(&fresh) {
                for (v, &r) in column.iter_mut().zip(&rows_of) {
                    *v = self.operator.q(p, r);
                }
            }
            let mut x = a.clone();
            kept.solve_columns(&mut x, fresh.len(), self.on().single_precision);
            for (b, &p) in fresh.iter().enumerate() {
                kept.bordered_of[p] = kept.bordered.len();
                kept.bordered.extend_from_slice(&a[b * n..(b + 1) * n]);
                kept.bordered.extend_from_slice(&x[b * n..(b + 1) * n]);
            }
        }
        let mut a = vec![0.0; n * k];
        let mut x = vec![0.0; n * k];
        for (b, &j) in joined.iter().enumerate() {
            let at = kept.bordered_of[free[j]];
            a[b * n..(b + 1) * n].copy_from_slice(&kept.bordered[at..at + n]);
            x[b * n..(b + 1) * n].copy_from_slice(&kept.bordered[at + n..at + 2 * n]);
        }
        if let Some(update) = update {
            update.correct_columns(&kept.columns, &mut x, k);
        }
        let coupled = transpose_product(&a, &x, (n, k, k));
        let schur = DenseLu::new(k, |i, b| {
            let (p, q) = (free[joined[i]], free[joined[b]]);
            let mut v = self.operator.q(p, q);
            if i == b {
                v += curvature[joined[i]];
            }
            if hessian.partner[joined[i]] == joined[b] {
                v += hessian.coupling[joined[i]];
            }
            v - coupled[b * k + i]
        });
        let mut is_row = vec![false; free.len()];
        for &j in joined {
            is_row[j] = true;
        }
        Border {
            rows: joined.to_vec(),
            is_row,
            a,
            x,
            schur,
        }
    }

    /// The low-rank update of [`Self::preconditioned_cg`] on the free rows `u` and the factor's
    /// rows `pinned` (no longer free; Δ = ∞): the columns of Z = A₀⁻¹ U not kept yet (one blocked
    /// solve), gathered, Δ and the capacitance matrix I + Δ Uᵀ Z (a pinned row's: Uᵀ Z), factored.
    /// None past |ℱ|/8 new columns or |ℱ|/4 rows, or where the kept columns would pass |ℱ|/4 (a
    /// quarter of the factor's size; a refactorisation starts them afresh).
    fn low_rank_update(
        &self,
        kept: &mut ReusedFactor,
        free: &[usize],
        (curvature, hessian): (&[f64], &LawHessian),
        (u, pinned): (&[usize], &[usize]),
    ) -> Option<LowRankUpdate> {
        let n = kept.diagonal.len();
        let rows: Vec<usize> = (u.iter().map(|&i| kept.row[free[i]]))
            .chain(pinned.iter().copied())
            .collect();
        let fresh: Vec<usize> = rows
            .iter()
            .copied()
            .filter(|&k| kept.column_of[k] == usize::MAX)
            .collect();
        if 8 * fresh.len() > n || 4 * rows.len() > n || 4 * (kept.columns.len() / n + fresh.len()) > n {
            return None;
        }
        if !fresh.is_empty() {
            let start = kept.columns.len();
            for (a, &k) in fresh.iter().enumerate() {
                kept.column_of[k] = start / n + a;
            }
            let single = self.on().single_precision;
            kept.unit_columns(&fresh, single);
        }
        // Δ: per row of 𝒰 its diagonal change and, for a pair, its partner's place in 𝒰 and the
        // change of their coupling
        let place: std::collections::HashMap<usize, usize> = u.iter().enumerate().map(|(a, &i)| (i, a)).collect();
        let delta: Vec<(f64, usize, f64)> = (u.iter().zip(&rows))
            .map(|(&i, &k)| match place.get(&hessian.partner[i]) {
                None => (curvature[i] - kept.diagonal[k], usize::MAX, 0.0),
                Some(&a) => (
                    curvature[i] - kept.diagonal[k],
                    a,
                    hessian.coupling[i] - kept.coupling[k],
                ),
            })
            .chain(pinned.iter().map(|_| (f64::INFINITY, usize::MAX, 0.0)))
            .collect();
        let columns: Vec<usize> = rows.iter().map(|&k| kept.column_of[k]).collect();
        let capacitance = DenseLu::from_columns(rows.len(), |b, out| {
            let zb = &kept.columns[columns[b] * n..(columns[b] + 1) * n];
            for (a, v) in out.iter_mut().enumerate() {
                let (d, partner, off) = delta[a];
                *v = if d.is_infinite() {
                    // a pinned row, (I + ΔUᵀZ) divided by Δ → ∞: Uᵀ Z
                    zb[rows[a]]
                } else {
                    let mut v = d * zb[rows[a]];
                    if partner != usize::MAX {
                        v += off * zb[rows[partner]];
                    }
                    v + if a == b { 1.0 } else { 0.0 }
                };
            }
        });
        Some(LowRankUpdate {
            rows,
            delta,
            capacitance,
            columns,
        })
    }

    /// Forces and statuses at the converged r, given Q r − q there (`qrd_final`): λ = q − Q r
    /// (= Q(d − r)), ξ = w j_ε'(r), η = λ − ξ on the bound and 0 elsewhere; the r and q are kept
    /// as [`ContactState::balanced_at`].
    #[allow(clippy::needless_range_loop)] // p indexes five per-node arrays at once
    fn finish(&self, (q, qrd_final): (&[f64], &[f64]), state: &mut ContactState, outcome: &mut ContactOutcome) {
        let m = self.m();
        state.balanced_at = Some((state.normal_displacement.clone(), q.to_vec()));
        outcome.active = 0;
        for p in 0..m {
            let r = state.normal_displacement[p];
            let lambda = -qrd_final[p];
            let xi = self.law_force(&state.normal_displacement, p);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::condensed::DenseNormalStiffness;

    /// A smooth SPD compliance on m nodes of a line: W_pq = e^{−|x_p − x_q|/ℓ} + 0.05 δ_pq, so
    /// that Q = W⁻¹ couples every pair, as a contact surface's condensed stiffness does.
    fn operator(m: usize) -> DenseNormalStiffness {
        let x = |p: usize| p as f64 / m as f64;
        let w: Vec<f64> = (0..m * m)
            .map(|k| {
                let (p, q) = (k / m, k % m);
                (-(x(p) - x(q)).abs() / 0.1).exp() + if p == q { 0.05 } else { 0.0 }
            })
            .collect();
        DenseNormalStiffness::from_w(w, m).unwrap()
    }

    /// A solver of the tests' surfaces: tolerance 1e-12, at most 100 iterations.
    fn solver<'a>(
        operator: &'a dyn NormalStiffness,
        laws: &'a NodalLaws,
        bound: &'a [f64],
        pairs: Option<&'a [usize]>,
        dense_limit: usize,
    ) -> ActiveSetSolver<'a> {
        ActiveSetSolver {
            operator,
            laws,
            offset: None,
            bound: Some(bound),
            singular: false,
            pairs,
            fixed: None,
            branch_from: usize::MAX,
            settings: ContactSettings {
                tolerance: 1e-12,
                max_iterations: 100,
                dense_limit,
                ..ContactSettings::default()
            },
        }
    }

    /// A growing load's shape along the surface, x ∈ [0, 1) at time t: a moving middle part.
    fn shape(x: f64, t: f64) -> f64 {
        t * (std::f64::consts::PI * x).sin() * (1.0 + 0.3 * (7.0 * x + t).cos())
    }

    /// Steps n = 1..=steps with free displacements d(t_n), t_n = n / steps, from a surface
    /// apart: per step d, the state after it and what the solve did.
    fn run_steps(
        solver: &ActiveSetSolver,
        steps: usize,
        d: impl Fn(f64) -> Vec<f64>,
    ) -> Vec<(Vec<f64>, ContactState, ContactOutcome)> {
        let mut state = ContactState::new(solver.m());
        (1..=steps)
            .map(|n| {
                let d = d(n as f64 / steps as f64);
                let outcome = solver.solve(&d, &mut state).unwrap();
                (d, state.clone(), outcome)
            })
            .collect()
    }

    /// Σ of one count of the outcomes.
    fn total(run: &[(Vec<f64>, ContactState, ContactOutcome)], count: impl Fn(&ContactOutcome) -> usize) -> usize {
        run.iter().map(|(_, _, o)| count(o)).sum()
    }

    /// The numbers a PETSc run broadcasts give back the outcome, field by field.
    #[test]
    fn outcome_numbers_round_trip() {
        let o = ContactOutcome {
            iterations: 1,
            residual: 2.5e-11,
            line_search_cuts: 3,
            convexified: 4,
            iterative: 5,
            factorisations: 6,
            in_w: 7,
            active: 8,
        };
        let back = ContactOutcome::from_numbers(&o.to_numbers());
        assert_eq!(format!("{back:?}"), format!("{o:?}"));
    }

    /// Steps of a growing load that pushes a moving middle part onto the bound: the active set
    /// changes from step to step and within steps. Directions through the reused factorisation
    /// (dense_limit = 0) give the dense path's solutions to 1e-10, with fewer factorisations than
    /// directions; the contact law (r ≤ g, η ≥ 0 on the bound, λ = 0 off it) holds at the end.
    #[test]
    fn reused_factorisation_gives_the_dense_directions() {
        let m = 240;
        let op = operator(m);
        let bound = vec![0.2; m];
        let laws = NodalLaws::default();
        let load = |t: f64| (0..m).map(|p| 0.5 * shape(p as f64 / m as f64, t)).collect();
        let dense = run_steps(&solver(&op, &laws, &bound, None, usize::MAX), 8, load);
        let reused = run_steps(&solver(&op, &laws, &bound, None, 0), 8, load);
        assert_eq!(total(&dense, |o| o.iterative), 0);
        assert_eq!(total(&dense, |o| o.factorisations), total(&dense, |o| o.iterations));
        let (directions, factorisations) = (total(&reused, |o| o.iterations), total(&reused, |o| o.factorisations));
        assert!(
            total(&reused, |o| o.iterative) > 0 && factorisations < directions,
            "{factorisations} of {directions}"
        );
        let mut active_sets = std::collections::HashSet::new();
        for ((d, a, _), (_, b, _)) in dense.iter().zip(&reused) {
            let scale = a.normal_displacement.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            for p in 0..m {
                assert!((a.normal_displacement[p] - b.normal_displacement[p]).abs() <= 1e-10 * scale);
                assert!(b.normal_displacement[p] <= bound[p]);
                match b.status[p] {
                    NodeStatus::OnBound => assert!(b.force[p] >= -1e-10 * scale),
                    _ => assert!(b.force[p].abs() <= 1e-9 * scale, "λ off the bound at {p}"),
                }
            }
            assert!(d.iter().any(|v| *v > 0.2) == (b.status.contains(&NodeStatus::OnBound)));
            active_sets.insert(b.status.iter().filter(|s| **s == NodeStatus::OnBound).count());
        }
        assert!(active_sets.len() >= 4, "the active set moved: {active_sets:?}");
    }

    /// The kept factor updated on the rows whose curvature moved (a single row stiffened ten
    /// thousand times, one dropped to 0, a pair's coupling turned over) is the new Newton matrix:
    /// CG converges at once, to the fresh factorisation's direction; Z's columns are kept, so a
    /// second change on the same rows needs none; the other rows' small changes (5 %) cost a few
    /// iterations more, not a refactorisation.
    #[test]
    fn a_low_rank_update_of_the_kept_factor_is_the_new_newton_matrix() {
        let m = 120;
        let op = operator(m);
        let (bound, laws) = (vec![0.2; m], NodalLaws::default());
        let s = solver(&op, &laws, &bound, None, 0);
        let free: Vec<usize> = (0..m).collect();
        let mut partner = vec![usize::MAX; m];
        for (p, q) in [(10, 11), (40, 41)] {
            (partner[p], partner[q]) = (q, p);
        }
        let e0: Vec<f64> = (0..m).map(|p| 0.3 * s.c(p) * (1 + p % 7) as f64).collect();
        let c0: Vec<f64> = (0..m)
            .map(|p| if partner[p] == usize::MAX { 0.0 } else { 0.05 * s.c(p) })
            .collect();
        let matrix = |e: &[f64], c: &[f64]| {
            let (e, c, partner) = (e.to_vec(), c.to_vec(), partner.clone());
            let q = op.clone();
            move |i: usize, j: usize| {
                q.q(i, j)
                    + if i == j {
                        e[i]
                    } else if partner[i] == j {
                        c[i]
                    } else {
                        0.0
                    }
            }
        };
        let mut kept = ReusedFactor {
            fingerprint: s.fingerprint(),
            row: (0..m).collect(),
            diagonal: e0.clone(),
            coupling: c0.clone(),
            single: std::sync::OnceLock::new(),
            q_single: None,
            served: 0,
            factor: DenseCholesky::new(m, matrix(&e0, &c0)).unwrap(),
            columns: Vec::new(),
            column_of: vec![usize::MAX; m],
            bordered: Vec::new(),
            bordered_of: vec![usize::MAX; m],
        };
        let grad: Vec<f64> = (0..m).map(|p| (0.37 * p as f64).sin()).collect();
        let solve = |e: &[f64], c: &[f64], kept: &mut ReusedFactor| {
            let hessian = LawHessian {
                diagonal: e.to_vec(),
                coupling: c.to_vec(),
                convex_diagonal: e.to_vec(),
                convex_coupling: c.to_vec(),
                partner: partner.clone(),
                pair: vec![(0.0, 0.0, [1.0, 0.0]); m],
            };
            let (x, iterations, qx) = s
                .preconditioned_cg(kept, &free, (e, &hessian), &grad, (1e-13, None))
                .unwrap();
            let exact = DenseCholesky::new(m, matrix(e, c)).unwrap().solve(&grad);
            let scale = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (a, b) in x.iter().zip(&exact) {
                assert!((a - b).abs() <= 1e-10 * scale, "{a} against {b}");
            }
            // CG's sum of its own products is Q x (all rows free here), to the products' rounding
            let mut product = vec![0.0; m];
            s.operator.apply_q(&x, &mut product);
            let bound = product.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (a, b) in qx.unwrap().iter().zip(&product) {
                assert!((a - b).abs() <= 1e-12 * bound, "Q x {a} against {b}");
            }
            iterations
        };
        let (mut e, mut c) = (e0.clone(), c0.clone());
        e[3] *= 1e4;
        // a row dropped to 0 from 2.1 Q_pp, and the pair's coupling turned over, past MOVED of its
        // rows' Q_pp + e_p
        e[55] = 0.0;
        (c[40], c[41]) = (-1.2 * s.c(40), -1.2 * s.c(40));
        assert!(solve(&e, &c, &mut kept) <= 2);
        // the rows of 𝒰: 3, 55 and both rows of the pair (40, 41)
        assert_eq!(kept.columns.len(), 4 * m);
        e[3] *= 2.0;
        e[55] = 5.0 * s.c(55);
        assert!(solve(&e, &c, &mut kept) <= 2);
        assert_eq!(kept.columns.len(), 4 * m, "no new columns for the same rows");
        for p in (0..m).step_by(5) {
            e[p] *= 1.05;
        }
        let iterations = solve(&e, &c, &mut kept);
        assert!((3..=12).contains(&iterations), "{iterations} iterations");
    }

    /// The kept factor serves a free set that moved since it was formed (docs/method.md §9.2):
    /// rows that left the free set are pinned by the update, rows that joined it are bordered on,
    /// rows a law holds stiffly stay outside the factor (Jacobi), a row whose curvature moved is
    /// updated; CG reaches the dense direction of the new free set to 10⁻¹³ in a few iterations
    /// (4: the stiff rows' coupling left to CG is about 1/√(10⁵) of their diagonal).
    #[test]
    fn the_kept_factor_serves_a_free_set_that_moved() {
        let m = 120;
        let op = operator(m);
        let (bound, laws) = (vec![0.2; m], NodalLaws::default());
        let s = solver(&op, &laws, &bound, None, 0);
        let hessian = |e: &[f64]| LawHessian {
            diagonal: e.to_vec(),
            coupling: vec![0.0; e.len()],
            convex_diagonal: e.to_vec(),
            convex_coupling: vec![0.0; e.len()],
            partner: vec![usize::MAX; e.len()],
            pair: vec![(0.0, 0.0, [1.0, 0.0]); e.len()],
        };
        // formed with every row free and rows 100..120 held stiffly: those stay out of it
        let mut e: Vec<f64> = (0..m).map(|p| 0.3 * s.c(p) * (1 + p % 7) as f64).collect();
        for v in &mut e[100..] {
            *v *= 1e5;
        }
        let all: Vec<usize> = (0..m).collect();
        let factored: Vec<usize> = (0..m)
            .filter(|&i| !s.stiff(&all, (&e, &hessian(&e)), i, STIFF))
            .collect();
        assert_eq!(factored, (0..100).collect::<Vec<_>>());
        let (mut buffer, mut outcome) = (FactorBuffer::default(), ContactOutcome::default());
        let zeros = vec![0.0; m];
        let mut kept = s.factor_rows(
            &all,
            &factored,
            (&hessian(&e), &zeros),
            (&mut buffer, s.fingerprint()),
            (&mut outcome, true),
        );
        // now rows 0..5, 30 and 31 are on their bound, rows 100..106 left the stiff part of their
        // law (106..120 did not) and row 50 stiffened a hundred times
        let free: Vec<usize> = (5..m).filter(|p| ![30, 31].contains(p)).collect();
        for p in 100..106 {
            e[p] = 0.5 * s.c(p);
        }
        e[50] *= 100.0;
        let curvature: Vec<f64> = free.iter().map(|&p| e[p]).collect();
        let grad: Vec<f64> = (0..m).map(|p| (0.37 * p as f64).sin()).collect();
        let (x, iterations, qx) = s
            .preconditioned_cg(
                &mut kept,
                &free,
                (&curvature, &hessian(&curvature)),
                &grad,
                (1e-13, None),
            )
            .unwrap();
        let exact = DenseCholesky::new(free.len(), |i, j| {
            op.q(free[i], free[j]) + if i == j { curvature[i] } else { 0.0 }
        })
        .unwrap()
        .solve(&free.iter().map(|&p| grad[p]).collect::<Vec<_>>());
        let scale = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in x.iter().zip(&exact) {
            assert!((a - b).abs() <= 1e-10 * scale, "{a} against {b}");
        }
        assert!(iterations <= 6, "{iterations} iterations");
        // CG's sum of its own products is Q x on every row, the held ones too (x zero there)
        let mut full = vec![0.0; m];
        for (i, &p) in free.iter().enumerate() {
            full[p] = x[i];
        }
        let mut product = vec![0.0; m];
        op.apply_q(&full, &mut product);
        let bound = product.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (a, b) in qx.unwrap().iter().zip(&product) {
            assert!((a - b).abs() <= 1e-12 * bound, "Q x {a} against {b}");
        }
        assert_eq!(
            kept.bordered.len(),
            2 * 100 * 6,
            "the six joined rows' columns are kept"
        );
    }

    /// Q without W formed: the solver cannot take the Newton system in W, except (with
    /// `products`, as on the trailing block's condensation, docs/method.md §9.7) where the
    /// system has no rows and a product by W is all it needs.
    struct WithoutW<'a> {
        op: &'a DenseNormalStiffness,
        products: bool,
    }

    impl NormalStiffness for WithoutW<'_> {
        fn m(&self) -> usize {
            self.op.m
        }
        fn apply_q(&self, x: &[f64], y: &mut [f64]) {
            self.op.apply_q(x, y)
        }
        fn q(&self, p: usize, r: usize) -> f64 {
            self.op.q(p, r)
        }
        fn apply_w(&self, x: &[f64], y: &mut [f64]) -> bool {
            if self.products {
                crate::linalg::dense::matvec_row_major(&self.op.w, self.op.m, x, y);
            }
            self.products
        }
    }

    /// A surface that starts apart against a rigid bound, no law: the first direction has every
    /// row free and none curved, so with products by W (and no W) it is Δ = W G. Over steps of a
    /// growing load that moves the active set, the solutions are those of the path in Q to
    /// 1e-10 with the same Newton iterations, and only such directions go by W (the others need
    /// W's entries).
    #[test]
    fn a_direction_without_rows_in_w_is_a_product_by_w() {
        let m = 240;
        let op = operator(m);
        let bound = vec![0.2; m];
        let laws = NodalLaws::default();
        // the direction itself: Q Δ = G on all rows, to round-off
        let products = WithoutW {
            op: &op,
            products: true,
        };
        let by_products = solver(&products, &laws, &bound, None, usize::MAX);
        let free: Vec<usize> = (0..m).collect();
        let g: Vec<f64> = (0..m).map(|p| (0.05 * p as f64).cos()).collect();
        let hessian = by_products.law_hessian(&vec![0.0; m], &free);
        let x = by_products
            .direction_in_w(&free, &hessian, &g, &mut FactorBuffer::default())
            .unwrap();
        let mut qx = vec![0.0; m];
        op.apply_q(&x, &mut qx);
        for (a, b) in qx.iter().zip(&g) {
            assert!((a - b).abs() <= 1e-11, "Q Δ = {a} against G = {b}");
        }
        // a held row: the system in W has a row, whose entries W would have to give
        let hessian = by_products.law_hessian(&vec![0.0; m], &free[1..]);
        assert!(by_products
            .direction_in_w(&free[1..], &hessian, &g, &mut FactorBuffer::default())
            .is_none());
        let load = |t: f64| (0..m).map(|p| 0.5 * shape(p as f64 / m as f64, t)).collect();
        let only_q = WithoutW {
            op: &op,
            products: false,
        };
        let in_q = run_steps(&solver(&only_q, &laws, &bound, None, usize::MAX), 6, load);
        let by_w = run_steps(&by_products, 6, load);
        assert_eq!(total(&in_q, |o| o.in_w), 0);
        let (in_w, directions) = (total(&by_w, |o| o.in_w), total(&by_w, |o| o.iterations));
        assert_eq!(total(&in_q, |o| o.iterations), directions);
        // step 1 starts apart (every row free, no curvature); later steps start from a held set
        assert!(in_w >= 1 && in_w < directions, "{in_w} of {directions} directions by W");
        let scale = in_q.last().unwrap().1.force.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for ((_, a, _), (_, b, _)) in in_q.iter().zip(&by_w) {
            assert_eq!(a.status, b.status);
            for (x, y) in a.force.iter().zip(&b.force) {
                assert!((x - y).abs() <= 1e-10 * scale, "{x} against {y}");
            }
            for (x, y) in a.normal_displacement.iter().zip(&b.normal_displacement) {
                assert!((x - y).abs() <= 1e-10, "{x} against {y}");
            }
        }
    }

    /// The Newton system in W (docs/method.md §4.6) against the one in Q: k nodes with a normal
    /// row on a bound and two tangential rows with Tresca's pair law, a bound force on a third
    /// of the nodes only (the others' tangential rows and the separated normal rows carry no
    /// curvature and drop out of the system in W). Over steps of a growing load that moves the
    /// active set, both give the same solution to 1e-10 — while the system in W is used for
    /// most directions, with the same number of Newton iterations — and the law holds at every
    /// pair. (src/contact/newton_w.rs tests the direction itself.)
    #[test]
    fn the_newton_system_in_w_gives_the_directions_in_q() {
        use crate::contact::law::ContactLaw;
        let k = 60;
        let m = 3 * k;
        let op = operator(m);
        let epsilon = 1e-8;
        let force = |i: usize| if i < k / 3 { 0.05 } else { 0.0 };
        let weights: Vec<f64> = (0..m).map(|p| if p < k { 0.0 } else { force((p - k) / 2) }).collect();
        let laws = NodalLaws::uniform(ContactLaw::smoothed_magnitude(epsilon), &weights);
        let pairs: Vec<usize> = (0..m)
            .map(|p| if p < k { usize::MAX } else { k + ((p - k) ^ 1) })
            .collect();
        let bound: Vec<f64> = (0..m).map(|p| if p < k { 0.2 } else { f64::INFINITY }).collect();
        let load = |t: f64| {
            (0..m)
                .map(|p| {
                    let shape = shape((p % k) as f64 / k as f64, t);
                    if p < k {
                        0.5 * shape
                    } else {
                        0.1 * shape * if p % 2 == 0 { 1.0 } else { -0.5 }
                    }
                })
                .collect()
        };
        let only_q = WithoutW {
            op: &op,
            products: false,
        };
        let in_q = run_steps(&solver(&only_q, &laws, &bound, Some(&pairs), usize::MAX), 6, load);
        let with_w = run_steps(&solver(&op, &laws, &bound, Some(&pairs), usize::MAX), 6, load);
        assert_eq!(total(&in_q, |o| o.in_w), 0);
        // the same directions up to rounding: the same iterates
        let (in_w, directions) = (total(&with_w, |o| o.in_w), total(&with_w, |o| o.iterations));
        assert_eq!(total(&in_q, |o| o.iterations), directions);
        assert!(2 * in_w > directions, "{in_w} of {directions} directions in W");
        let mut active_sets = std::collections::HashSet::new();
        let (mut stick, mut slip) = (0, 0);
        for ((_, a, _), (_, b, _)) in in_q.iter().zip(&with_w) {
            let scale = a.normal_displacement.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            for p in 0..m {
                let (x, y) = (a.normal_displacement[p], b.normal_displacement[p]);
                assert!((x - y).abs() <= 1e-10 * scale, "row {p}: {x} in Q, {y} in W");
            }
            for i in 0..k / 3 {
                let (p, q) = (k + 2 * i, k + 2 * i + 1);
                let length = b.force[p].hypot(b.force[q]);
                assert!(length <= force(i) * (1.0 + 1e-9), "pair {i}: |λ_τ| {length}");
                if length < force(i) * (1.0 - 1e-6) {
                    stick += 1;
                } else {
                    slip += 1;
                }
            }
            active_sets.insert(b.status[..k].iter().filter(|s| **s == NodeStatus::OnBound).count());
        }
        assert!(stick > 0 && slip > 0, "stick {stick}, slip {slip}");
        assert!(active_sets.len() >= 3, "the active set moved: {active_sets:?}");
    }

    /// [`solver`] for the tests' tangential rows: no bound, tolerance 1e-13, dense directions.
    fn tangential_rows<'a>(
        operator: &'a DenseNormalStiffness,
        laws: &'a NodalLaws,
        pairs: Option<&'a [usize]>,
        branch_from: usize,
    ) -> ActiveSetSolver<'a> {
        let base = solver(operator, laws, &[], pairs, usize::MAX);
        ActiveSetSolver {
            bound: None,
            branch_from,
            settings: ContactSettings {
                tolerance: 1e-13,
                ..base.settings
            },
            ..base
        }
    }

    /// The branch-model tests' tangential rows under the load q, solved with the laws' own model
    /// and with the branch model.
    fn with_and_without_branch_model(
        operator: &DenseNormalStiffness,
        laws: &NodalLaws,
        pairs: Option<&[usize]>,
        q: &[f64],
    ) -> [(ContactState, ContactOutcome); 2] {
        [usize::MAX, 0].map(|branch_from| {
            let mut state = ContactState::new(q.len());
            let outcome = tangential_rows(operator, laws, pairs, branch_from)
                .solve_forces(q, &mut state)
                .unwrap();
            (state, outcome)
        })
    }

    /// The tests' operator on k nodes (single rows), and the same for k nodes of two uncoupled
    /// tangential rows each (3D pairs), with the pairing.
    fn single_and_paired(k: usize) -> (DenseNormalStiffness, DenseNormalStiffness, Vec<usize>) {
        let scalar = operator(k);
        let w: Vec<f64> = (0..4 * k * k)
            .map(|i| {
                let (p, q) = (i / (2 * k), i % (2 * k));
                if p % 2 == q % 2 {
                    scalar.w[(p / 2) * k + q / 2]
                } else {
                    0.0
                }
            })
            .collect();
        let paired = DenseNormalStiffness::from_w(w, 2 * k).unwrap();
        (scalar, paired, (0..2 * k).map(|p| p ^ 1).collect())
    }

    /// The vector law of a pair (docs/method.md §17.3): k pairs with an isotropic compliance
    /// W = W₁ ⊗ I₂ (each pair's two rows see the same scalar coupling) and Tresca's law F ρ_ε(|s|).
    /// The problem is then equivariant under a rotation of every pair's plane: the free
    /// displacements rotated by θ give the solution rotated by θ (to 1e-12), which two scalar
    /// laws on the rows would break (their square cone has axes). At every pair the force is the
    /// law's, F ρ/√(ρ² + ε²) along the slip where it slips, shorter than F where it sticks, and
    /// both kinds occur.
    #[test]
    fn a_pair_law_acts_on_the_vector_and_is_isotropic() {
        use crate::contact::law::ContactLaw;
        let k = 40;
        let m = 2 * k;
        let (_, op, pairs) = single_and_paired(k);
        let epsilon = 1e-8;
        let law = ContactLaw::smoothed_magnitude(epsilon);
        let bound_force = 0.3;
        let laws = NodalLaws::uniform(law, &vec![bound_force; m]);
        let solve = |theta: f64| {
            let (c, s) = (theta.cos(), theta.sin());
            // a slip field that is large at one end and small at the other: both zones
            let d: Vec<f64> = (0..k)
                .flat_map(|i| {
                    let x = i as f64 / k as f64;
                    let (a, b) = (1.2 * x * x, 0.4 * x);
                    [c * a - s * b, s * a + c * b]
                })
                .collect();
            let mut state = ContactState::new(m);
            tangential_rows(&op, &laws, Some(&pairs), usize::MAX)
                .solve(&d, &mut state)
                .unwrap();
            state
        };
        let base = solve(0.0);
        let theta: f64 = 0.7;
        let turned = solve(theta);
        let (c, s) = (theta.cos(), theta.sin());
        let scale = base.normal_displacement.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let (mut stick, mut slip) = (0, 0);
        for i in 0..k {
            let (x, y) = (base.normal_displacement[2 * i], base.normal_displacement[2 * i + 1]);
            let (u, v) = (turned.normal_displacement[2 * i], turned.normal_displacement[2 * i + 1]);
            assert!((c * x - s * y - u).abs() <= 1e-12 * scale && (s * x + c * y - v).abs() <= 1e-12 * scale);
            let (f, g) = (base.force[2 * i], base.force[2 * i + 1]);
            let rho = x.hypot(y);
            let along = bound_force / rho.hypot(epsilon);
            if f.hypot(g) < bound_force * (1.0 - 1e-6) {
                stick += 1;
            } else {
                slip += 1;
                assert!((f - along * x).abs() <= 1e-10 * bound_force && (g - along * y).abs() <= 1e-10 * bound_force);
            }
        }
        assert!(stick > 0 && slip > 0, "{stick} stick, {slip} slip");
    }

    /// Rows that start a solve at their kink (the slip increments' origin, as every step of
    /// Tresca or Coulomb friction does) and must slip: with the branch model (docs/method.md
    /// §17.2) the solve reaches the law's own solution (to 10⁻¹² of the largest slip) in fewer
    /// directions, for single rows and for the pairs of 3D, where the slip field mixes stick
    /// and slip.
    #[test]
    fn rows_leaving_their_kink_take_the_branch_model() {
        use crate::contact::law::ContactLaw;
        let k = 40;
        let (scalar, paired, pairs) = single_and_paired(k);
        let single = |i: usize| 1.2 * (i as f64 / k as f64).powi(2) - 0.3;
        // (operator, pairs, free displacements d)
        type Case<'a> = (&'a DenseNormalStiffness, Option<&'a [usize]>, Vec<f64>);
        let cases: [Case; 2] = [
            (&scalar, None, (0..k).map(single).collect()),
            (
                &paired,
                Some(&pairs),
                (0..k).flat_map(|i| [single(i), 0.4 * i as f64 / k as f64]).collect(),
            ),
        ];
        for (op, pairs, d) in cases {
            let m = d.len();
            let laws = NodalLaws::uniform(ContactLaw::smoothed_magnitude(1e-8), &vec![0.3; m]);
            let mut q = vec![0.0; m];
            op.apply_q(&d, &mut q);
            let [(own, own_outcome), (branch, branch_outcome)] = with_and_without_branch_model(op, &laws, pairs, &q);
            let scale = own.normal_displacement.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (a, b) in own.normal_displacement.iter().zip(&branch.normal_displacement) {
                assert!((a - b).abs() <= 1e-12 * scale, "{a} against {b}");
            }
            let stuck = own
                .normal_displacement
                .iter()
                .filter(|v| v.abs() < 1e-6 * scale)
                .count();
            assert!(stuck > 0 && stuck < m, "{stuck} of {m} rows stick");
            eprintln!(
                "pairs {}: {} directions with the branch model, {} with the law's own",
                pairs.is_some(),
                branch_outcome.iterations,
                own_outcome.iterations
            );
            assert!(branch_outcome.iterations < own_outcome.iterations);
        }
    }

    /// Rows that stick, pressed by less than their bound force F (here 0.5 F to 0.99 F): the
    /// smoothed law's solution lies inside its kink, at |s| = ε t/√(F² − t²) (up to 7 ε), which
    /// the law's own Newton model, concave there, reaches only by steps that fall short each time.
    /// The stick side of the branch model (the law's tangent where it balances t, docs/method.md
    /// §17.2) reaches the same solution (to 10⁻⁹ of its largest |s|) in fewer directions, for
    /// single rows and for pairs.
    #[test]
    fn rows_that_stick_inside_their_kink_take_the_stick_side_model() {
        use crate::contact::law::ContactLaw;
        let k = 40;
        let (scalar, paired, pairs) = single_and_paired(k);
        let bound = 0.3;
        // the demand of node i: between 0.5 F and 0.99 F, its sign (its direction) turning
        let share = |i: usize| 0.5 + 0.49 * (i as f64 / (k - 1) as f64);
        let angle = |i: usize| 0.37 * i as f64;
        type Case<'a> = (&'a DenseNormalStiffness, Option<&'a [usize]>, Vec<f64>);
        let cases: [Case; 2] = [
            (
                &scalar,
                None,
                (0..k).map(|i| bound * share(i) * angle(i).cos().signum()).collect(),
            ),
            (
                &paired,
                Some(&pairs),
                (0..k)
                    .flat_map(|i| [bound * share(i) * angle(i).cos(), bound * share(i) * angle(i).sin()])
                    .collect(),
            ),
        ];
        for (op, pairs, q) in cases {
            let m = q.len();
            let laws = NodalLaws::uniform(ContactLaw::smoothed_magnitude(1e-8), &vec![bound; m]);
            let [(own, own_outcome), (model, model_outcome)] = with_and_without_branch_model(op, &laws, pairs, &q);
            let largest = own.normal_displacement.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            // every row inside its kink: |s| of a few ε, the largest about 7 ε
            assert!(largest > 3e-8 && largest < 1e-7, "largest |s| {largest}");
            for (a, b) in own.normal_displacement.iter().zip(&model.normal_displacement) {
                assert!((a - b).abs() <= 1e-9 * largest, "{a} against {b}");
            }
            eprintln!(
                "pairs {}: {} directions with the stick-side model, {} with the law's own",
                pairs.is_some(),
                model_outcome.iterations,
                own_outcome.iterations
            );
            assert!(model_outcome.iterations < own_outcome.iterations);
        }
    }

    /// One Newton step on Coulomb's coupled law (docs/method.md §17.2) from where a round of the
    /// fixed point F ← μ λ_ν ended: nodes of a normal row pressed against a rigid bound (its force
    /// the multiplier) and a tangential row under a Coulomb bound force, the two coupled in Q
    /// (W = W₀ ⊗ [[1, κ], [κ, 1]]), the slip field mixing stick and slip. From bound forces 1 %
    /// off the fixed point, a plain round contracts their error by about μκ; the coupled step,
    /// one GMRES solve with the kept factor, leaves the square of it — below 10⁻³ of the plain
    /// round's error — and its r is the fixed point's to the same order.
    #[test]
    fn a_coupled_step_beats_a_round_of_the_fixed_point() {
        use crate::contact::law::ContactLaw;
        let (k, mu, kappa) = (60, 0.4, 0.3);
        let m = 2 * k;
        let base = operator(k);
        let w: Vec<f64> = (0..m * m)
            .map(|i| {
                let (p, q) = (i / m, i % m);
                base.w[(p % k) * k + q % k] * if (p < k) == (q < k) { 1.0 } else { kappa }
            })
            .collect();
        let op = DenseNormalStiffness::from_w(w, m).unwrap();
        let hidden = WithoutW {
            op: &op,
            products: false,
        };
        let bound: Vec<f64> = (0..m).map(|p| if p < k { 0.0 } else { f64::INFINITY }).collect();
        let d: Vec<f64> = (0..m)
            .map(|p| {
                let x = (p % k) as f64 / k as f64;
                if p < k {
                    0.5 + 0.3 * x
                } else {
                    0.9 * x * x - 0.2
                }
            })
            .collect();
        let mut q = vec![0.0; m];
        op.apply_q(&d, &mut q);
        let laws_of = |f: &[f64]| {
            let weights: Vec<f64> = (0..m).map(|p| if p < k { 0.0 } else { f[p - k] }).collect();
            NodalLaws::uniform(ContactLaw::smoothed_magnitude(1e-8), &weights)
        };
        let next = |state: &ContactState| -> Vec<f64> { (0..k).map(|i| mu * state.force[i].max(0.0)).collect() };
        let round = |f: &[f64], state: &mut ContactState| {
            let laws = laws_of(f);
            solver(&hidden, &laws, &bound, None, 0).solve_forces(&q, state).unwrap();
        };
        // the fixed point, to round-off
        let mut state = ContactState::new(m);
        let mut f = vec![0.1; k];
        for _ in 0..200 {
            round(&f, &mut state);
            let g = next(&state);
            let change = g.iter().zip(&f).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            f = g;
            if change < 1e-14 {
                break;
            }
        }
        let (fixed, r_fixed) = (f.clone(), state.normal_displacement.clone());
        let slipping = (0..k).filter(|&i| state.force[k + i].abs() > 0.999 * fixed[i]).count();
        assert!(slipping > 5 && slipping < k - 5, "{slipping} of {k} nodes slip");
        let error = |g: &[f64]| g.iter().zip(&fixed).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        // a round from bound forces 1 % off, then the plain next round's forces and the coupled step
        let f0: Vec<f64> = (0..k)
            .map(|i| fixed[i] * (1.0 + 0.01 * (0.7 * i as f64).sin()))
            .collect();
        round(&f0, &mut state);
        let plain = error(&next(&state));
        let laws = laws_of(&f0);
        let s = solver(&hidden, &laws, &bound, None, 0);
        let coupling: Vec<(usize, usize, f64, f64)> = (0..k).map(|i| (k + i, i, f0[i], mu)).collect();
        let iterations = s
            .coupled_step(&q, &mut state, &coupling)
            .expect("the kept factor serves");
        let coupled = error(&next(&state));
        let r_error = (state.normal_displacement.iter().zip(&r_fixed)).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        let r_scale = r_fixed.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(
            plain > 1e-2 * error(&f0) && plain < 0.5 * error(&f0),
            "a plain round: {:e} -> {plain:e}",
            error(&f0)
        );
        assert!(
            coupled < 1e-3 * plain && r_error < 1e-6 * r_scale,
            "coupled step ({iterations} GMRES iterations): {coupled:e} against the round's {plain:e}, r within {r_error:e}"
        );
    }
}
