//! Contact on Γ₃ (docs/method.md §4): the normal-compliance law j_ν with its regularisation, the
//! condensed operator W = C K⁻¹ Cᵀ on the contact normals, and the globalised primal–dual
//! active-set (projected semismooth Newton) solver of one time step.

pub mod active_set;
pub mod condensed;
pub mod law;

pub use active_set::{ActiveSetSolver, ContactOutcome, ContactSettings, NodeStatus};
pub use condensed::{Condensation, ContactNodes, DenseNormalStiffness, NormalStiffness, SplitSweeps, StoredResponses};
pub use law::{ComplianceProfile, ContactLaw, PiecewiseLinear, Symmetry};
