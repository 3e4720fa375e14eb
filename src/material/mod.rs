//! Constitutive data: the elasticity tensor A and the memory term B(s) = Σ_m b_m(s) B_m
//! (docs/method.md §1, §15).

pub mod elasticity;
pub mod kernel;
pub mod memory;
pub mod quadrature;

pub use elasticity::{Elasticity, Isotropic, PlaneModel, IDENTITY_TENSOR};
pub use kernel::RelaxationKernel;
pub use memory::{Channel, Memory, MemoryTensor, MemoryTerm, Prony, LONG_TERM_TOLERANCE};
pub use quadrature::{Quadrature, Rules};
