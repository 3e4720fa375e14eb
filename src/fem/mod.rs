//! Finite elements on a mesh: the degree-of-freedom map, the sparse pattern built once from the
//! cells, and global assembly of stiffness matrices, load vectors and stresses. The reference
//! cells, their maps and quadrature live beside [`crate::mesh::Cell`] in [`crate::mesh::element`].
//!
//! docs/method.md §2: P1 on triangles, Q1 on quadrilaterals, nodal basis. Every component of
//! every node stays an unknown, Γ₁'s (clamped) and other prescribed ones included (chosen in
//! `solver::dirichlet`): the solver lifts them (docs/method.md §7.2), setting their rows and
//! columns to the identity's and moving their values to the right-hand side, so the matrices
//! keep their pattern and are symmetric positive definite once the prescribed components stop
//! every rigid motion.

pub mod assembly;
pub mod dofs;
pub mod loads;
pub mod materials;
pub mod node_blocks;
pub mod norms;
pub mod patch_dilatation;
pub mod stress;

pub use crate::linalg::sparse::{Pattern, SymmetricMatrix};
pub use assembly::assemble_stiffness;
pub use dofs::DofMap;
pub use node_blocks::NodeBlockMatrix;
