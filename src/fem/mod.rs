//! Finite elements: reference elements, quadrature, the degree-of-freedom map, the sparse
//! pattern built once, and global assembly of stiffness matrices and load vectors.
//!
//! docs/method.md §2: P1 on triangles, Q1 on quadrilaterals, nodal basis; Γ₁ (clamped) is
//! eliminated from the unknowns so the assembled matrices stay symmetric positive definite.

pub mod assembly;
pub mod dofs;
pub mod element;
pub mod loads;
pub mod node_blocks;
pub mod norms;
pub mod pattern;
pub mod quadrature;
pub mod stress;

pub use assembly::{assemble_stiffness, StiffnessPair};
pub use dofs::DofMap;
pub use node_blocks::NodeBlockMatrix;
pub use pattern::SymmetricMatrix;
