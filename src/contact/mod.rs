//! Contact on Γ₃ (docs/method.md §4, §14): the normal-compliance law j_ν with its
//! regularisation, the condensed operator W = C K⁻¹ Cᵀ on the contact normals, the globalised
//! primal–dual active-set (projected semismooth Newton) solver of one time step, and the contact
//! rows of several groups and rigid obstacles.

pub mod active_set;
pub mod condensed;
pub mod law;
pub mod newton_w;
pub mod nodal;
pub mod obstacle;
pub mod rows;
pub mod settings;
mod trailing;

pub use active_set::{
    ActiveSetSolver, ContactOutcome, ContactSettings, FrictionRows, FrictionStatus, NodeStatus, StepTrend,
};
pub use condensed::{
    Condensation, ContactNodes, DenseNormalStiffness, NormalStiffness, SplitSweeps, StoredResponses, WithCompliance,
};
pub use law::{ComplianceProfile, ContactLaw, PiecewiseLinear, Symmetry};
pub use nodal::{LawTerm, NodalLaws};
pub use obstacle::{Gap, Obstacle};
pub use settings::Strategies;
