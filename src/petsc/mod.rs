//! The PETSc backend over MPI (docs/method.md §13), behind the cargo feature `petsc`.
//!
//! `mpirun -np P hvi solve mesh.msh --backend petsc [--solver mumps|gamg]` runs the serial time
//! loop ([`crate::solver::timeloop`]) on every rank with the step matrices solved by PETSc:
//!
//! * every rank reads the mesh and the scene; rank 0 partitions the nodes with METIS and
//!   broadcasts the partition ([`partition`]); the nodes of rank r are numbered contiguously, so
//!   rank r owns the rows of its nodes' unknowns, and each cell belongs to the lowest rank
//!   among its nodes;
//! * each rank assembles its own cells into one MPIAIJ matrix per distinct step matrix
//!   K = K_A + c K_B (identity rows at the prescribed unknowns, as in serial), which PETSc
//!   factorises once (MUMPS Cholesky) or gives a GAMG hierarchy once (CG + GAMG with the
//!   rigid-body modes as near null space), reused by every step ([`backend`]);
//! * the step vectors — loads, history, displacement — are held by each rank over its own
//!   unknowns only, and K_A and K_B (for the memory load, the lifting and the reactions) only as
//!   distributed matrices (docs/method.md §13.2);
//! * contact: W = C K⁻¹ Cᵀ from blocks of right-hand sides (`KSPMatSolve`), summed onto rank 0,
//!   which runs the active-set solve and broadcasts its forces λ; per step one free solve
//!   d = C K⁻¹ r and one recovery solve u = K⁻¹ (r − Cᵀ λ);
//! * every rank writes its piece of each frame, rank 0 the `.pvtu`, the index and the tables
//!   ([`files`], docs/method.md §13.3);
//! * `hvi check --backend petsc` prints the partition and the memory each rank will need
//!   ([`check`], docs/method.md §13.4).
//!
//! Failures: a rank that fails before the time loop (unreadable or different mesh, bad scene)
//! tells all ranks at one agreement point and every rank stops with that rank's message; PETSc
//! failures inside the loop are collective (the same converged reason on every rank), and the
//! time loop's decisions (a non-finite solution, a stop) are summed over the ranks; a panic
//! aborts all ranks through MPI_Abort. Nothing waits forever on a rank that has stopped.

mod backend;

mod check;

mod common;

mod files;

mod partition;

mod run;

pub use backend::{PetscBackend, GAMG_RTOL};

pub use check::check;

pub use common::{RankShare, SolverChoice};

pub use partition::Partition;

pub use run::{solve, MpiRun};
