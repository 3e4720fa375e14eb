//! `mpirun -np P hvi check mesh.msh --backend petsc` (docs/method.md §13.4): the serial check's
//! mesh and scene report, then the partition (cells, unknowns and contact nodes per rank) and
//! the memory each rank will need, predicted from what is measured here — the process as it is
//! after reading and partitioning, the PETSc step matrix as assembled — and from MUMPS's own
//! analysis of that matrix (INFO(15), its estimate of the factorisation's memory on the rank).
//! Nothing is factorised.

use super::backend::{method_name, PetscBackend};
use super::common::{agree, read_everywhere, simulation_and_partition, start, RankShare, SolverChoice};
use crate::app;
use crate::history::History;
use crate::mesh::{AnyMesh, Mesh};
use crate::scene::Scene;
use crate::solver::timeloop;
use crate::solver::{Simulation, SolveError};
use hvi_petsc::mpi::traits::*;
use hvi_petsc::Petsc;
use std::fmt::Write;
use std::path::Path;

/// MiB.
const MIB: f64 = 1048576.0;

/// What one rank will need, in bytes, by part.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RankMemory {
    /// The process after reading the mesh and the scene and partitioning (VmRSS): the mesh, the
    /// simulation's quadrature and contact data, the partition.
    pub base: f64,
    /// PETSc matrices: the step matrices and K_A, K_B for the products (MatGetInfo of the step
    /// matrix, times their number), and the copy of each factored one PETSc hands MUMPS (its
    /// upper triangle as (row, column, value) triples, 16 bytes each: ≈ 2/3 of the matrix).
    pub matrices: f64,
    /// MUMPS's INFO(15) per factor, times the factors held at once.
    pub factor: f64,
    /// W and its inverse on rank 0 (and the dense work of inverting it); on every rank the two
    /// dense blocks of right-hand sides that form W and, when kept, its rows of Z = K⁻¹Cᵀ per
    /// factor.
    pub contact: f64,
    /// The history's vectors (docs/method.md §5) over the rank's unknowns.
    pub history: f64,
    /// The step vectors, the vectors kept over all unknowns (prescribed values, the load while it
    /// is assembled, rank 0's Γ₃ output), and the output piece's arrays.
    pub vectors: f64,
}

impl RankMemory {
    pub fn total(&self) -> f64 {
        self.base + self.matrices + self.factor + self.contact + self.history + self.vectors
    }
}

/// VmRSS of this process, bytes.
fn resident_bytes() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))
        .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        .map_or(0.0, |kb| kb * 1024.0)
}

/// The outcome of `hvi check --backend petsc` on one rank: rank 0 holds the report.
pub struct MpiCheck {
    pub rank: usize,
    pub result: Result<String, SolveError>,
}

/// `hvi check --backend petsc`: every rank reads, partitions and assembles its part of the step
/// matrix; MUMPS analyses it (with `--solver mumps`); rank 0 prints the report.
pub fn check(
    mesh_path: &Path,
    scene_path: Option<&Path>,
    overrides: &[String],
    choice: SolverChoice,
    accept_mesh_defects: bool,
) -> Result<MpiCheck, String> {
    let petsc = start()?;
    let rank = petsc.rank();
    let result =
        read_everywhere(petsc.world(), mesh_path, scene_path, overrides).and_then(|(scene, mesh)| match mesh {
            AnyMesh::Two(m) => check_dim(&petsc, mesh_path, scene_path, &scene, m, choice, accept_mesh_defects),
            AnyMesh::Three(m) => check_dim(&petsc, mesh_path, scene_path, &scene, m, choice, accept_mesh_defects),
        });
    Ok(MpiCheck { rank, result })
}

fn check_dim<const D: usize>(
    petsc: &Petsc,
    mesh_path: &Path,
    scene_path: Option<&Path>,
    scene: &Scene,
    mesh: Mesh<D>,
    choice: SolverChoice,
    accept_mesh_defects: bool,
) -> Result<String, SolveError> {
    let world = petsc.world();
    let (rank, ranks) = (petsc.rank(), petsc.size());
    let mut out = app::check::check_mesh_report(mesh_path, &mesh);
    let (sim, partition, warnings) = simulation_and_partition(world, scene_path, scene, mesh, accept_mesh_defects)?;
    sim.check_data()?;
    out.push_str(&app::check::check_scene_report(scene_path, &sim));
    let shares = RankShare::all(&sim, &partition);
    let backend = PetscBackend::new(petsc, &sim, partition, choice);
    let base = resident_bytes();
    let analysed = backend.analyse(&sim, choice == SolverChoice::Mumps);
    agree(world, analysed.as_ref().map(|_| ()).map_err(|e| e.to_string())).map_err(SolveError::Setup)?;
    let (matrix_bytes, mumps) = analysed.map_err(SolveError::Setup)?;
    let factors = factors_held(&sim);
    let m_contact = sim.contact.as_ref().map_or(0, |c| c.nodes.len());
    let responses = m_contact > 0
        && super::backend::keeps_responses(
            sim.condensation,
            backend.unknowns().len(),
            m_contact,
            mumps.map_or(matrix_bytes, |m| m.this_rank_mb as f64 * 1e6),
        );
    let memory = predict(
        &sim,
        &backend,
        rank,
        base,
        matrix_bytes,
        mumps.map(|m| m.this_rank_mb),
        Held { factors, responses },
    );
    // Every rank's prediction on rank 0.
    let parts = [
        memory.base,
        memory.matrices,
        memory.factor,
        memory.contact,
        memory.history,
        memory.vectors,
    ];
    let mut all = vec![0.0; 6 * ranks];
    world.all_gather_into(&parts[..], &mut all[..]);
    let _ = writeln!(
        out,
        "PETSc over MPI: {ranks} rank(s), {}; METIS partition of the nodes, each cell on the lowest rank of its nodes",
        method_name(backend.method())
    );
    let _ = writeln!(
        out,
        "  rank      nodes      cells   unknowns  contact | predicted memory [MiB]: base matrices  factor contact history vectors   total"
    );
    for (r, (share, p)) in shares.iter().zip(all.chunks_exact(6)).enumerate() {
        let m = RankMemory {
            base: p[0],
            matrices: p[1],
            factor: p[2],
            contact: p[3],
            history: p[4],
            vectors: p[5],
        };
        let _ = writeln!(
            out,
            "  {r:>4} {:>10} {:>10} {:>10} {:>8} | {:>28.0} {:>8.0} {:>7.0} {:>7.0} {:>7.0} {:>7.0} {:>7.0}",
            share.nodes,
            share.cells,
            share.unknowns,
            share.contact_nodes,
            m.base / MIB,
            m.matrices / MIB,
            m.factor / MIB,
            m.contact / MIB,
            m.history / MIB,
            m.vectors / MIB,
            m.total() / MIB
        );
    }
    match mumps {
        Some(m) => {
            let _ = writeln!(
                out,
                "  MUMPS analysis: about {} factor entries (INFOG(3)); factorisation memory {} MB on the largest rank (INFOG(16)), {} MB in all (INFOG(17)); {} factor(s) held at once",
                m.factor_entries,
                m.largest_rank_mb,
                m.total_mb,
                factors
            );
        }
        None => {
            let _ = writeln!(
                out,
                "  CG + GAMG: the multigrid hierarchy is not predicted (about 1–2 times the step matrix per level set; measure with a short run)"
            );
        }
    }
    let _ = writeln!(
        out,
        "  base = this process now (mesh, scene, partition: VmRSS); matrices = the step matrix as assembled × {} (step matrices, K_A, K_B) + PETSc's copy for MUMPS (2/3 of it per factor); factor = MUMPS's INFO(15) × factors; contact = W's right-hand-side blocks, the stored responses (if kept), W and its inverse on rank 0",
        matrices_held(&sim, factors)
    );
    if let Some(c) = &sim.contact {
        let _ = writeln!(
            out,
            "contact: {} nodes (the active-set solve runs on rank 0; the smallness condition needs a serial factor: run `hvi check` without --backend)",
            c.nodes.len()
        );
        let _ = writeln!(
            out,
            "  recovery: {}",
            if responses {
                "the stored responses Z = K⁻¹Cᵀ (each rank its rows, in contact), one solve per step"
            } else {
                "a second solve per step (Z = K⁻¹Cᵀ would take more than half of the solver's memory on a rank; solver.condensation = \"stored_responses\" keeps it anyway)"
            }
        );
    }
    for w in warnings {
        let _ = writeln!(out, "warning: {w}");
    }
    Ok(out)
}

/// Step matrices and factors held at once: K̃ and, with memory, K_A for step 0 (its factor is
/// made while K̃'s exists) unless u_0 = 0 solves step 0 (docs/method.md §3).
fn factors_held<const D: usize>(sim: &Simulation<D>) -> usize {
    if sim.materials.memory().is_none() {
        return 1;
    }
    let mut load = vec![0.0; sim.dofs.n()];
    let mut g = vec![0.0; sim.dofs.n()];
    // (a load or value that cannot be evaluated fails the run's step 0; count the factor)
    let rhs_zero = sim.loads.assemble(0.0, &sim.dofs, &mut load).is_ok() && load.iter().all(|v| *v == 0.0);
    let prescribed_zero = sim.dirichlet.values(0.0, &mut g).is_ok() && g.iter().all(|v| *v == 0.0);
    if timeloop::zero_solves_step_zero(sim, rhs_zero, prescribed_zero) {
        1
    } else {
        2
    }
}

/// PETSc matrices of the step matrix's size held at once: the step matrices, and K_A (for the
/// reactions and the lifting) and K_B (memory) for the products.
fn matrices_held<const D: usize>(sim: &Simulation<D>, factors: usize) -> usize {
    let elastic = !sim.dirichlet.reaction_groups.is_empty() || sim.dirichlet.is_nonzero();
    factors + usize::from(elastic) + usize::from(sim.materials.memory().is_some())
}

/// What a run holds at once: its factors, and whether its condensation keeps its rows of Z.
struct Held {
    factors: usize,
    responses: bool,
}

/// The memory rank `rank` will need (docs/method.md §13.4).
fn predict<const D: usize>(
    sim: &Simulation<D>,
    backend: &PetscBackend<'_, D>,
    rank: usize,
    base: f64,
    matrix_bytes: f64,
    mumps_mb: Option<i64>,
    Held { factors, responses }: Held,
) -> RankMemory {
    let local = backend.unknowns().len() as f64;
    let all = sim.dofs.n() as f64;
    let m = sim.contact.as_ref().map_or(0, |c| c.nodes.len()) as f64;
    let history = sim.materials.memory().map_or(0.0, |b| {
        let h = History::new(b, backend.unknowns().len(), sim.rules);
        if h.bytes_held() > 0 {
            h.bytes_held() as f64
        } else {
            // the direct sum keeps every step's displacement
            8.0 * local * sim.time.steps().map_or(1, |n| n + 1) as f64
        }
    });
    // Step vectors (≈ 8 over the rank's unknowns, PETSc's work vectors included); over all
    // unknowns: the prescribed values, the load while assembled, rank 0's Γ₃ output; the piece
    // (≈ 40 numbers per node and cell of a 3D piece: displacement, stresses, sums).
    let piece = 40.0 * 8.0 * (local / D as f64 + backend.partition().cells_owned_by(rank).len() as f64);
    let vectors = 8.0 * (8.0 * local + 3.0 * all) + piece;
    RankMemory {
        base,
        matrices: matrix_bytes * (matrices_held(sim, factors) as f64 + 2.0 / 3.0 * factors as f64),
        factor: mumps_mb.map_or(0.0, |mb| mb as f64 * 1e6) * factors as f64,
        contact: if m > 0.0 {
            2.0 * 8.0 * super::backend::BLOCK as f64 * local
                + if responses {
                    8.0 * local * m * factors as f64
                } else {
                    0.0
                }
                + if rank == 0 { 4.0 * 8.0 * m * m } else { 0.0 }
        } else {
            0.0
        },
        history,
        vectors,
    }
}
