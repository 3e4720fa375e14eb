//! Constitutive data: the elasticity tensor A and the relaxation kernel B(s) = b(s)·B₀.

pub mod elasticity;
pub mod kernel;

pub use elasticity::{Elasticity, Isotropic, PlaneModel, IDENTITY_TENSOR};
pub use kernel::RelaxationKernel;
