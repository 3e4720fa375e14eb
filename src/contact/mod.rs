//! Contact on Γ₃ (docs/method.md §4, §14): the normal-compliance law j_ν with its
//! regularisation, the condensed operator W = C K⁻¹ Cᵀ on the contact normals, the contact rows
//! of several groups and rigid obstacles, and the contact solve of one time step: a globalised
//! primal–dual active-set (projected semismooth Newton) method.
//!
//! The solve, file by file: `problem.rs` (the step's problem and what is measured on it),
//! `newton.rs` (the Newton loop), `active_set.rs` (the held rows), `hessian.rs` (the laws'
//! curvature), `branch.rs` (friction's branch model), `direction/` (the Newton system and its
//! solvers), `line_search.rs` (the projected path and Armijo), `friction/` (the tangential
//! rows and Coulomb's rounds), `state.rs` (what a step leaves, and the caches beside it), `settings.rs` (settings,
//! strategies and tuning constants), `trace.rs` (where the solve reports).

pub mod active_set;
pub mod branch;
pub mod condensed;
pub mod direction;
pub mod facet_grid;
pub mod friction;
pub mod hessian;
pub mod law;
pub mod line_search;
pub mod mortar;
pub mod newton;
pub mod nodal;
pub mod obstacle;
pub mod outcome;
pub mod pairing;
pub mod problem;
pub mod rows;
pub mod settings;
pub mod state;
pub mod trace;
mod trailing;

pub use condensed::{
    Condensation, ContactNodes, DenseNormalStiffness, NormalStiffness, SplitSweeps, StoredResponses, WithCompliance,
};
pub use law::{ComplianceProfile, ContactLaw, PiecewiseLinear, Symmetry};
pub use newton::ActiveSetSolver;
pub use nodal::{LawTerm, NodalLaws};
pub use obstacle::{Gap, Obstacle};
pub use outcome::{ContactFailure, ContactOutcome};
pub use problem::ContactProblem;
pub use settings::{ContactSettings, Strategies};
pub use state::{ContactState, FrictionRows, FrictionStatus, NodeStatus, SolverCache};
pub use trace::Trace;

#[cfg(test)]
mod solve_tests;
