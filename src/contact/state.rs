//! What a contact solve carries from step to step: the contact state (the physics: displacements,
//! forces and statuses of the rows, the warm start of the next step and what is written out) and,
//! beside it, the solver's caches, which only save work: dropped, the next solve does that work
//! again and gives the same solution to its tolerance.

use super::direction::kept::KeptFactor;

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
    /// Per tangential row of a contact with friction, after the step (empty without friction;
    /// docs/method.md §17).
    pub friction: FrictionRows,
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
            friction: FrictionRows::default(),
        }
    }
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
    /// [`FrictionStatus`] codes.
    pub status: Vec<i32>,
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

/// The contact solver's caches, kept beside a run's [`ContactState`]: none is physics, and a
/// fresh one (`SolverCache::default()`) costs only the work it would have saved.
#[derive(Debug, Default)]
pub struct SolverCache {
    /// The last factorisation of the Newton matrix, kept above `dense_limit` free rows as the
    /// preconditioner of later Newton systems (docs/method.md §9.2).
    pub(crate) kept: Option<KeptFactor>,
    /// How the last step with friction moved, for the next step's load-following predictor
    /// (docs/method.md §17.2): empty before the first such step.
    pub(crate) trend: StepTrend,
}

/// How a step with friction moved, which the next step extrapolates where its load moves on the
/// same way (docs/method.md §17.2).
#[derive(Clone, Debug, Default)]
pub(crate) struct StepTrend {
    /// The free contact forces q of the step (all rows) and their change over it.
    pub load: Vec<f64>,
    pub load_change: Vec<f64>,
    /// The normal rows' displacements' change over the step.
    pub normal_change: Vec<f64>,
    /// The tangential rows' bound forces' change over the step.
    pub bound_change: Vec<f64>,
}
