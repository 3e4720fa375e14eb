//! The PETSc backend over MPI (docs/method.md §13), behind the cargo feature `petsc`.
//!
//! `mpirun -np P hvi solve mesh.msh --backend petsc [--solver mumps|gamg]` runs the serial time
//! loop ([`crate::solver::timeloop`]) on every rank with the step matrices solved by PETSc:
//!
//! * every rank reads the mesh and the scene; rank 0 partitions the nodes with METIS and
//!   broadcasts the partition; the nodes of rank r are numbered contiguously, so rank r owns the
//!   rows of its nodes' unknowns, and each cell belongs to the lowest rank among its nodes;
//! * each rank assembles its own cells into one MPIAIJ matrix per distinct step matrix
//!   K = K_A + c K_B (identity rows at the prescribed unknowns, as in serial), which PETSc
//!   factorises once (MUMPS Cholesky) or gives a GAMG hierarchy once (CG + GAMG with the
//!   rigid-body modes as near null space), reused by every step;
//! * contact: W = C K⁻¹ Cᵀ from blocks of right-hand sides (`KSPMatSolve`), each rank summing
//!   its rows' share; the active-set solve runs on rank 0 and its forces λ are broadcast; per
//!   step one free solve d = C K⁻¹ r and one recovery solve u = K⁻¹ (r − Cᵀ λ) ([`TwoSolves`]);
//! * rank 0 writes the output, the other ranks wait for its verdict on every frame.
//!
//! Known shortfall of this first version: the vectors of a step (loads, history, displacement)
//! are replicated on every rank (each solution is gathered whole), and the serial K_A (and K_B
//! with memory) are assembled on every rank too for the memory load and the reactions. What is
//! distributed is the factor or preconditioner, the part that outgrows one machine first.
//!
//! Failures: a rank that fails before the time loop (unreadable or different mesh, bad scene)
//! tells all ranks at one agreement point and every rank stops with that rank's message; PETSc
//! failures inside the loop are collective (the same converged reason on every rank); a panic
//! aborts all ranks through MPI_Abort. Nothing waits forever on a rank that has stopped.

use crate::app::{self, FileSink, SolveOptions, Summary};
use crate::contact::active_set::{ContactOutcome, ContactState};
use crate::contact::{Condensation, ContactNodes, DenseNormalStiffness};
use crate::fem::assembly::local_stiffness;
use crate::linalg::{Counters, LinearSolver};
use crate::material::{Isotropic, IDENTITY_TENSOR};
use crate::mesh::{AnyMesh, Mesh};
use crate::output;
use crate::scene::Scene;
use crate::solver::timeloop::{self, Backend};
use crate::solver::{FrameSink, RunStats, Simulation, SolveError, StepView};
use hvi_petsc::mpi::collective::SystemOperation;
use hvi_petsc::mpi::topology::SimpleCommunicator;
use hvi_petsc::mpi::traits::*;
use hvi_petsc::{AllGather, DenseBlock, Int, Matrix, Method, Petsc, Solver, Vector};
use serde::Serialize;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Which PETSc solver `--solver` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverChoice {
    /// MUMPS Cholesky: a direct factor, exact to round-off (the default).
    Mumps,
    /// CG preconditioned by GAMG to the relative residual [`GAMG_RTOL`].
    Gamg,
}

/// The relative residual CG + GAMG solves to: ten orders below the data, so that the solver
/// error stays far below the discretisation error of any mesh hvi runs (docs/method.md §13).
/// PETSc's option `-hvi_ksp_rtol` (in `PETSC_OPTIONS`) overrides it.
pub const GAMG_RTOL: f64 = 1e-10;

/// Right-hand sides per `KSPMatSolve` block when forming W (bounds the dense blocks held at
/// once to 32 columns of the local rows).
const BLOCK: usize = 32;

/// The partition of the mesh nodes over the ranks.
#[derive(Clone, Debug)]
pub struct Partition {
    pub ranks: usize,
    /// Owning rank of each mesh node.
    pub owner: Vec<usize>,
    /// PETSc node number of each mesh node (rank r's nodes are offsets[r]..offsets[r + 1]).
    pub position: Vec<usize>,
    pub offsets: Vec<usize>,
    /// Owning rank of each cell: the lowest owner among its nodes.
    pub cell_owner: Vec<usize>,
}

impl Partition {
    /// The partition of given node owners (ascending mesh number within a rank).
    pub fn from_owners<const D: usize>(mesh: &Mesh<D>, ranks: usize, owner: Vec<usize>) -> Self {
        let mut offsets = vec![0; ranks + 1];
        for &o in &owner {
            offsets[o + 1] += 1;
        }
        for r in 0..ranks {
            offsets[r + 1] += offsets[r];
        }
        let mut next = offsets.clone();
        let position = owner
            .iter()
            .map(|&o| {
                next[o] += 1;
                next[o] - 1
            })
            .collect();
        let cell_owner = mesh
            .cells
            .iter()
            .map(|c| c.nodes().iter().map(|&p| owner[p]).min().unwrap_or(0))
            .collect();
        Partition {
            ranks,
            owner,
            position,
            offsets,
            cell_owner,
        }
    }

    /// METIS's k-way partition of the node graph into `ranks` parts (everything on rank 0 for
    /// one rank).
    pub fn metis<const D: usize>(mesh: &Mesh<D>, ranks: usize) -> Result<Vec<usize>, String> {
        let n = mesh.points.len();
        if ranks <= 1 || n == 0 {
            return Ok(vec![0; n]);
        }
        use metis_sys::idx_t;
        let mut adjacency: Vec<Vec<usize>> = vec![Vec::new(); n];
        for cell in &mesh.cells {
            let nodes = cell.nodes();
            for &a in nodes {
                adjacency[a].extend(nodes.iter().copied().filter(|&b| b != a));
            }
        }
        let mut xadj: Vec<idx_t> = Vec::with_capacity(n + 1);
        let mut adjncy: Vec<idx_t> = Vec::new();
        xadj.push(0);
        for a in adjacency.iter_mut() {
            a.sort_unstable();
            a.dedup();
            adjncy.extend(a.iter().map(|&b| b as idx_t));
            xadj.push(adjncy.len() as idx_t);
        }
        let mut options = [0 as idx_t; metis_sys::METIS_NOPTIONS as usize];
        let (mut nvtxs, mut ncon, mut nparts, mut cut) = (n as idx_t, 1 as idx_t, ranks as idx_t, 0 as idx_t);
        let mut part = vec![0 as idx_t; n];
        // SAFETY: CSR arrays of the sizes METIS expects; null optional weights.
        let status = unsafe {
            metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
            metis_sys::METIS_PartGraphKway(
                &mut nvtxs,
                &mut ncon,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                &mut nparts,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                &mut cut,
                part.as_mut_ptr(),
            )
        };
        if status != metis_sys::rstatus_et_METIS_OK {
            return Err(format!(
                "METIS could not partition the {n} mesh nodes into {ranks} parts (status {status})"
            ));
        }
        Ok(part.into_iter().map(|p| p as usize).collect())
    }

    /// Nodes owned by `rank`.
    pub fn nodes_of(&self, rank: usize) -> usize {
        self.offsets[rank + 1] - self.offsets[rank]
    }
}

/// The row layout of the PETSc matrices: hvi unknown D·p + c is PETSc row D·position[p] + c.
struct Layout {
    /// Global rows (all unknowns, prescribed ones included).
    n: usize,
    lo: usize,
    hi: usize,
    dof_of_row: Vec<usize>,
    row_of_dof: Vec<usize>,
}

/// The time loop's [`Backend`] on PETSc.
pub struct PetscBackend<'p, const D: usize> {
    petsc: &'p Petsc,
    partition: Partition,
    layout: Arc<Layout>,
    method: Method,
    /// Preallocation of the owned rows (diagonal and off-diagonal block entries).
    diagonal_nnz: Vec<Int>,
    off_diagonal_nnz: Vec<Int>,
    own_cells: Vec<usize>,
    /// The first PETSc failure of a solve (solves cannot return errors through
    /// [`LinearSolver`]: they fill the solution with NaN, which stops the step).
    failure: Arc<Mutex<Option<String>>>,
}

// SAFETY: the backend is used from the time loop's thread only; `Sync` is required because the
// Stepper holds it by reference.
unsafe impl<const D: usize> Sync for PetscBackend<'_, D> {}

impl<'p, const D: usize> PetscBackend<'p, D> {
    pub fn new(petsc: &'p Petsc, sim: &Simulation<D>, partition: Partition, choice: SolverChoice) -> Self {
        let rank = petsc.rank();
        let n_nodes = sim.mesh.points.len();
        let n = D * n_nodes;
        let mut row_of_dof = vec![0; n];
        let mut dof_of_row = vec![0; n];
        for p in 0..n_nodes {
            for c in 0..D {
                row_of_dof[D * p + c] = D * partition.position[p] + c;
                dof_of_row[D * partition.position[p] + c] = D * p + c;
            }
        }
        let (first, last) = (partition.offsets[rank], partition.offsets[rank + 1]);
        // Each owned node couples with every node of every cell it is in (whichever rank
        // owns the cell: entries of other ranks' cells arrive at assembly).
        let mut coupled: Vec<Vec<usize>> = vec![Vec::new(); last - first];
        for cell in &sim.mesh.cells {
            let nodes = cell.nodes();
            for &a in nodes {
                if partition.owner[a] == rank {
                    coupled[partition.position[a] - first].extend_from_slice(nodes);
                }
            }
        }
        let mut diagonal_nnz = Vec::with_capacity(D * (last - first));
        let mut off_diagonal_nnz = Vec::with_capacity(D * (last - first));
        for list in coupled.iter_mut() {
            list.sort_unstable();
            list.dedup();
            let own = list.iter().filter(|&&b| partition.owner[b] == rank).count().max(1);
            let other = list.len().saturating_sub(own);
            for _ in 0..D {
                diagonal_nnz.push((D * own) as Int);
                off_diagonal_nnz.push((D * other) as Int);
            }
        }
        let own_cells = (0..sim.mesh.cells.len())
            .filter(|&e| partition.cell_owner[e] == rank)
            .collect();
        let method = match choice {
            SolverChoice::Mumps => Method::MumpsCholesky,
            SolverChoice::Gamg => Method::CgGamg {
                rtol: GAMG_RTOL,
                max_iterations: 10_000,
            },
        };
        PetscBackend {
            petsc,
            layout: Arc::new(Layout {
                n,
                lo: D * first,
                hi: D * last,
                dof_of_row,
                row_of_dof,
            }),
            partition,
            method,
            diagonal_nnz,
            off_diagonal_nnz,
            own_cells,
            failure: Arc::new(Mutex::new(None)),
        }
    }

    pub fn partition(&self) -> &Partition {
        &self.partition
    }

    /// The first PETSc failure a solve recorded, if any.
    pub fn failure(&self) -> Option<String> {
        self.failure.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Assembles this rank's cells of K = K_A + c K_B (identity rows at the prescribed
    /// unknowns) and sets up the solver.
    fn build(&self, sim: &Simulation<D>, memory: Option<f64>) -> Result<PetscSolver, hvi_petsc::Error> {
        let layout = &self.layout;
        let mut matrix = Matrix::mpiaij(
            self.petsc,
            layout.hi - layout.lo,
            layout.n,
            D,
            &self.diagonal_nnz,
            &self.off_diagonal_nnz,
        )?;
        let a = sim.elasticity.tensor();
        // K_B is the stiffness of B₀ = I (docs/method.md §3): the local stiffness is linear in
        // (λ, μ), so K_A + c K_B is the stiffness of (λ_A + c λ_I, μ_A + c μ_I).
        let tensor = match memory {
            Some(c) => Isotropic {
                lambda: a.lambda + c * IDENTITY_TENSOR.lambda,
                mu: a.mu + c * IDENTITY_TENSOR.mu,
            },
            None => a,
        };
        let (points, cells) = (&sim.mesh.points, &sim.mesh.cells);
        let nl_max = D * cells.iter().map(|c| c.nodes().len()).max().unwrap_or(0);
        let mut local = vec![0.0; nl_max * nl_max];
        let mut index: Vec<Int> = Vec::with_capacity(nl_max);
        for &e in &self.own_cells {
            let cell = &cells[e];
            let nl = D * cell.nodes().len();
            local_stiffness(cell, points, &[tensor], &mut [&mut local[..]]);
            index.clear();
            for &p in cell.nodes() {
                for c in 0..D {
                    let d = D * p + c;
                    // PETSc ignores negative indices: prescribed rows and columns stay empty.
                    index.push(if sim.dofs.is_prescribed(d) {
                        -1
                    } else {
                        layout.row_of_dof[d] as Int
                    });
                }
            }
            matrix.add(&index, &index, &local[..nl * nl])?;
        }
        for row in layout.lo..layout.hi {
            if sim.dofs.is_prescribed(layout.dof_of_row[row]) {
                let r = [row as Int];
                matrix.add(&r, &r, &[1.0])?;
            }
        }
        matrix.assemble_spd()?;
        if let Method::CgGamg { .. } = self.method {
            let mut coords = matrix.vector()?;
            coords.with_local_mut(|x| {
                for (k, v) in x.iter_mut().enumerate() {
                    let d = layout.dof_of_row[layout.lo + k];
                    *v = points[d / D][d % D];
                }
            })?;
            matrix.set_rigid_body_modes(&mut coords, D)?;
        }
        let solver = Solver::new(&matrix, self.method, "hvi_")?;
        let b = matrix.vector()?;
        let x = matrix.vector()?;
        let gather = AllGather::new(&x)?;
        Ok(PetscSolver {
            layout: layout.clone(),
            name: solver.name(),
            inner: Mutex::new(Inner {
                matrix,
                solver,
                b,
                x,
                gather,
            }),
            failure: self.failure.clone(),
        })
    }

    fn error(&self, sim: &Simulation<D>, e: hvi_petsc::Error) -> SolveError {
        SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail: format!("the PETSc backend ({}) failed: {e}", method_name(self.method)),
        }
    }
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::MumpsCholesky => "MUMPS Cholesky",
        Method::CgGamg { .. } => "CG + GAMG",
    }
}

impl<const D: usize> Backend<D> for PetscBackend<'_, D> {
    fn operator(
        &self,
        sim: &Simulation<D>,
        memory: Option<f64>,
        counters: &Counters,
    ) -> Result<(Arc<dyn LinearSolver>, Option<Box<dyn Condensation>>), SolveError> {
        let solver = Arc::new(self.build(sim, memory).map_err(|e| self.error(sim, e))?);
        counters.factorisations.fetch_add(1, Ordering::Relaxed);
        let error = solver.probe().map_err(|e| self.error(sim, e))?;
        timeloop::singularity_verdict(error).map_err(|detail| SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail,
        })?;
        let condensed: Option<Box<dyn Condensation>> = match &sim.contact {
            Some(c) if !c.nodes.is_empty() => Some(Box::new(
                TwoSolves::new(&c.nodes, solver.clone(), counters).map_err(|e| match e {
                    Ok(e) => self.error(sim, e),
                    Err(detail) => SolveError::Setup(detail),
                })?,
            )),
            _ => None,
        };
        Ok((solver, condensed))
    }

    fn solves_contact(&self) -> bool {
        self.petsc.rank() == 0
    }

    fn share_contact(
        &self,
        state: &mut ContactState,
        local: Result<ContactOutcome, SolveError>,
    ) -> Result<ContactOutcome, SolveError> {
        let world = self.petsc.world();
        let root = world.process_at_rank(0);
        let m = state.force.len();
        // header: [ok, message length]
        let mut header = [0u64; 2];
        let mut message = Vec::new();
        if self.solves_contact() {
            match &local {
                Ok(_) => header[0] = 1,
                Err(e) => message = e.to_string().into_bytes(),
            }
            header[1] = message.len() as u64;
        }
        root.broadcast_into(&mut header[..]);
        if header[0] == 0 {
            if !self.solves_contact() {
                message = vec![0u8; header[1] as usize];
            }
            root.broadcast_into(&mut message[..]);
            return match local {
                Err(e) if self.solves_contact() => Err(e),
                _ => Err(SolveError::Setup(format!(
                    "the contact solve on rank 0 failed: {}",
                    String::from_utf8_lossy(&message)
                ))),
            };
        }
        let mut numbers = vec![0.0f64; 6 + m];
        if let (true, Ok(o)) = (self.solves_contact(), &local) {
            numbers[..6].copy_from_slice(&[
                o.iterations as f64,
                o.residual,
                o.line_search_cuts as f64,
                o.convexified as f64,
                o.iterative as f64,
                o.active as f64,
            ]);
            numbers[6..].copy_from_slice(&state.force);
        }
        root.broadcast_into(&mut numbers[..]);
        if self.solves_contact() {
            return local;
        }
        state.force.copy_from_slice(&numbers[6..]);
        Ok(ContactOutcome {
            iterations: numbers[0] as usize,
            residual: numbers[1],
            line_search_cuts: numbers[2] as usize,
            convexified: numbers[3] as usize,
            iterative: numbers[4] as usize,
            active: numbers[5] as usize,
        })
    }
}

struct Inner {
    matrix: Matrix,
    solver: Solver,
    b: Vector,
    x: Vector,
    gather: AllGather,
}

/// One PETSc solver of one step matrix as a [`LinearSolver`] over hvi's unknowns (every rank
/// passes the whole right-hand side and gets the whole solution).
pub struct PetscSolver {
    layout: Arc<Layout>,
    name: &'static str,
    inner: Mutex<Inner>,
    failure: Arc<Mutex<Option<String>>>,
}

impl PetscSolver {
    fn inner(&self) -> std::sync::MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn solve_checked(&self, rhs: &[f64], x: &mut [f64]) -> Result<(), hvi_petsc::Error> {
        let l = &self.layout;
        let mut inner = self.inner();
        let Inner {
            solver,
            b,
            x: xv,
            gather,
            ..
        } = &mut *inner;
        b.with_local_mut(|a| {
            for (k, v) in a.iter_mut().enumerate() {
                *v = rhs[l.dof_of_row[l.lo + k]];
            }
        })?;
        solver.solve(b, xv)?;
        gather.gather(xv, |all| {
            for (row, v) in all.iter().enumerate() {
                x[l.dof_of_row[row]] = *v;
            }
        })
    }

    /// max |K⁻¹(K v) − v| / max |v| for the pseudo-random v of the serial probe (collective).
    fn probe(&self) -> Result<f64, hvi_petsc::Error> {
        let l = &self.layout;
        let mut inner = self.inner();
        let Inner {
            matrix, solver, b, x, ..
        } = &mut *inner;
        let mut v = x.duplicate()?;
        v.with_local_mut(|a| {
            for (k, e) in a.iter_mut().enumerate() {
                let i = l.dof_of_row[l.lo + k];
                *e = ((i as f64 + 1.0) * 0.618_033_988_749_895).fract() - 0.5;
            }
        })?;
        matrix.mult(&v, b)?;
        solver.solve(b, x)?;
        let scale = v.norm_max()?;
        x.axpy(-1.0, &v)?;
        Ok(x.norm_max()? / scale)
    }

    /// W = C K⁻¹ Cᵀ (m × m, row-major) for the rows of C over hvi's unknowns: blocks of right-
    /// hand sides by `KSPMatSolve`, each rank summing the share of its rows (collective).
    fn normal_responses(&self, rows: &[Vec<(usize, f64)>]) -> Result<Vec<f64>, hvi_petsc::Error> {
        let l = &self.layout;
        let m = rows.len();
        let mut w = vec![0.0; m * m];
        let inner = self.inner();
        let owned = |d: usize| {
            let r = l.row_of_dof[d];
            (l.lo..l.hi).contains(&r).then(|| r - l.lo)
        };
        let world = SimpleCommunicator::world();
        for start in (0..m).step_by(BLOCK) {
            let cols = BLOCK.min(m - start);
            let mut b = DenseBlock::like(&inner.matrix, cols)?;
            b.with_local_mut(|a, lda| {
                for j in 0..cols {
                    for &(d, c) in &rows[start + j] {
                        if let Some(r) = owned(d) {
                            a[j * lda + r] = c;
                        }
                    }
                }
            })?;
            let mut x = DenseBlock::like(&inner.matrix, cols)?;
            inner.solver.solve_block(&b, &mut x)?;
            let mut part = vec![0.0; m * cols];
            x.with_local_mut(|a, lda| {
                for (p, row) in rows.iter().enumerate() {
                    for &(d, c) in row {
                        if let Some(r) = owned(d) {
                            for j in 0..cols {
                                part[p * cols + j] += c * a[j * lda + r];
                            }
                        }
                    }
                }
            })?;
            let mut sum = vec![0.0; m * cols];
            world.all_reduce_into(&part[..], &mut sum[..], SystemOperation::sum());
            for p in 0..m {
                w[p * m + start..p * m + start + cols].copy_from_slice(&sum[p * cols..(p + 1) * cols]);
            }
        }
        for p in 0..m {
            for q in 0..p {
                let v = 0.5 * (w[p * m + q] + w[q * m + p]);
                w[p * m + q] = v;
                w[q * m + p] = v;
            }
        }
        Ok(w)
    }
}

impl LinearSolver for PetscSolver {
    fn n(&self) -> usize {
        self.layout.n
    }

    fn solve(&self, rhs: &[f64], x: &mut [f64], counters: &Counters) {
        counters.solves.fetch_add(1, Ordering::Relaxed);
        if let Err(e) = self.solve_checked(rhs, x) {
            let mut f = self.failure.lock().unwrap_or_else(|e| e.into_inner());
            f.get_or_insert_with(|| format!("the PETSc backend ({}) failed in a solve: {e}", self.name));
            x.fill(f64::NAN);
        }
    }
}

/// The condensation of the PETSc backend: W by blocks of solves, then per step a free solve
/// d = C K⁻¹ r and a recovery solve u = K⁻¹ (r − Cᵀ λ) (docs/method.md §13). Z = K⁻¹ Cᵀ is
/// never stored whole.
pub struct TwoSolves {
    solver: Arc<PetscSolver>,
    rows: Vec<Vec<(usize, f64)>>,
    stiffness: DenseNormalStiffness,
    rhs: Vec<f64>,
    u_free: Vec<f64>,
}

impl TwoSolves {
    /// Err(Ok(e)): PETSc failed; Err(Err(detail)): W is not positive definite.
    fn new<const D: usize>(
        nodes: &ContactNodes<D>,
        solver: Arc<PetscSolver>,
        counters: &Counters,
    ) -> Result<Self, Result<hvi_petsc::Error, String>> {
        let rows = nodes.rows().to_vec();
        let w = solver.normal_responses(&rows).map_err(Ok)?;
        counters.solves.fetch_add(rows.len(), Ordering::Relaxed);
        let stiffness = DenseNormalStiffness::from_w(w, rows.len()).map_err(Err)?;
        let n = solver.n();
        Ok(TwoSolves {
            solver,
            rows,
            stiffness,
            rhs: vec![0.0; n],
            u_free: vec![0.0; n],
        })
    }
}

impl Condensation for TwoSolves {
    fn name(&self) -> &'static str {
        "PETSc: W by KSPMatSolve, a free and a recovery solve per step"
    }

    fn stiffness(&self) -> &DenseNormalStiffness {
        &self.stiffness
    }

    fn free_normal(&mut self, rhs: &[f64], d: &mut [f64], counters: &Counters) {
        self.rhs.copy_from_slice(rhs);
        self.solver.solve(rhs, &mut self.u_free, counters);
        for (dp, row) in d.iter_mut().zip(&self.rows) {
            *dp = row.iter().map(|&(i, c)| c * self.u_free[i]).sum();
        }
    }

    fn recover(&mut self, lambda: &[f64], u: &mut [f64], counters: &Counters) {
        for (&l, row) in lambda.iter().zip(&self.rows) {
            for &(i, c) in row {
                self.rhs[i] -= c * l;
            }
        }
        self.solver.solve(&self.rhs, u, counters);
    }
}

/// Every rank's outcome of a phase, agreed on by all (collective): Ok on every rank, or on
/// every rank the message of the lowest rank that failed.
fn agree(world: &SimpleCommunicator, local: Result<(), String>) -> Result<(), String> {
    let (rank, size) = (world.rank(), world.size());
    let mine = if local.is_err() { rank } else { size };
    let mut first = size;
    world.all_reduce_into(&mine, &mut first, SystemOperation::min());
    if first == size {
        return Ok(());
    }
    let mut message = match &local {
        Err(m) if rank == first => m.clone().into_bytes(),
        _ => Vec::new(),
    };
    let root = world.process_at_rank(first);
    let mut len = message.len() as u64;
    root.broadcast_into(&mut len);
    message.resize(len as usize, 0);
    root.broadcast_into(&mut message[..]);
    let text = String::from_utf8_lossy(&message).into_owned();
    Err(if size > 1 {
        format!("rank {first} of {size}: {text}")
    } else {
        text
    })
}

/// What identifies a mesh for the ranks' agreement that they all read the same one.
fn fingerprint<const D: usize>(mesh: &Mesh<D>) -> [u64; 3] {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for p in &mesh.points {
        for v in p {
            v.to_bits().hash(&mut h);
        }
    }
    for c in &mesh.cells {
        c.nodes().hash(&mut h);
    }
    [mesh.points.len() as u64, mesh.cells.len() as u64, h.finish()]
}

/// Rank 0 writes the frames; every rank learns whether it could.
struct CollectiveSink<'a, const D: usize> {
    world: &'a SimpleCommunicator,
    inner: Option<&'a mut FileSink<D>>,
}

impl<const D: usize> FrameSink<D> for CollectiveSink<'_, D> {
    fn step_done(&mut self, sim: &Simulation<D>, view: &StepView) {
        if let Some(s) = self.inner.as_mut() {
            s.step_done(sim, view);
        }
    }

    fn write_frame(&mut self, sim: &Simulation<D>, view: &StepView) -> Result<(), SolveError> {
        let local = match self.inner.as_mut() {
            Some(s) => s.write_frame(sim, view),
            None => Ok(()),
        };
        let mut ok = u8::from(local.is_ok());
        self.world.process_at_rank(0).broadcast_into(&mut ok);
        match (local, ok) {
            (Err(e), _) => Err(e),
            (Ok(()), 1) => Ok(()),
            _ => Err(SolveError::Setup("rank 0 could not write the output".into())),
        }
    }
}

/// What `summary.json` holds for a PETSc run.
#[derive(Serialize)]
struct MpiSummary<'a> {
    #[serde(flatten)]
    summary: Summary<'a>,
    backend: &'static str,
    ranks: usize,
    petsc_solver: &'static str,
    /// Mesh nodes owned by each rank.
    nodes_per_rank: Vec<usize>,
}

/// The outcome of `hvi solve --backend petsc` on one rank.
pub struct MpiRun {
    pub rank: usize,
    pub ranks: usize,
    pub result: Result<RunStats, SolveError>,
}

/// `hvi solve --backend petsc`: initialises MPI and PETSc, runs the scene on every rank, and
/// finalises. Only rank 0 should print the result (every rank holds the same error).
pub fn solve(opts: &SolveOptions, choice: SolverChoice) -> Result<MpiRun, String> {
    let petsc = Petsc::init(&[]).map_err(|e| format!("could not start PETSc over MPI: {e}"))?;
    let (rank, ranks) = (petsc.rank(), petsc.size());
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        default_hook(info);
        eprintln!("hvi: rank {rank} of {ranks} stopped on an internal error; ending all ranks");
        SimpleCommunicator::world().abort(101);
    }));
    let result = run(&petsc, opts, choice);
    Ok(MpiRun { rank, ranks, result })
}

fn run(petsc: &Petsc, opts: &SolveOptions, choice: SolverChoice) -> Result<RunStats, SolveError> {
    let world = petsc.world();
    let t0 = Instant::now();
    let read = Scene::load(opts.scene.as_deref(), &opts.overrides)
        .map_err(SolveError::from)
        .and_then(|scene| Ok((scene, app::read_mesh(&opts.mesh)?)));
    let mesh_seconds = t0.elapsed().as_secs_f64();
    let collective = |r: Result<(), String>| agree(world, r).map_err(SolveError::Setup);
    collective(read.as_ref().map(|_| ()).map_err(|e| e.to_string()))?;
    let (scene, mesh) = read?;
    // Every rank must hold the mesh rank 0 holds.
    let mut reference = match &mesh {
        AnyMesh::Two(m) => fingerprint(m),
        AnyMesh::Three(m) => fingerprint(m),
    };
    let mine = reference;
    world.process_at_rank(0).broadcast_into(&mut reference[..]);
    collective(if mine == reference {
        Ok(())
    } else {
        Err(format!(
            "{} reads differently here ({} nodes, {} cells) than on rank 0 ({} nodes, {} cells): every rank must read the same mesh file",
            opts.mesh.display(),
            mine[0],
            mine[1],
            reference[0],
            reference[1]
        ))
    })?;
    match mesh {
        AnyMesh::Two(m) => run_dim(petsc, opts, &scene, m, mesh_seconds, choice),
        AnyMesh::Three(m) => run_dim(petsc, opts, &scene, m, mesh_seconds, choice),
    }
}

fn run_dim<const D: usize>(
    petsc: &Petsc,
    opts: &SolveOptions,
    scene: &Scene,
    mesh: Mesh<D>,
    mesh_seconds: f64,
    choice: SolverChoice,
) -> Result<RunStats, SolveError> {
    let world = petsc.world();
    let (rank, ranks) = (petsc.rank(), petsc.size());
    let collective = |r: Result<(), String>| agree(world, r).map_err(SolveError::Setup);
    // The scene on the mesh (deterministic: the same verdict on every rank, but agreed on all
    // the same so that no rank goes on alone).
    let sim = Simulation::new(scene, mesh);
    collective(sim.as_ref().map(|_| ()).map_err(|e| e.to_string()))?;
    let sim = sim?;
    // Rank 0 partitions, every rank receives the owners.
    let mut owner: Vec<u64> = vec![0; sim.mesh.points.len()];
    let parts = if rank == 0 {
        Partition::metis(&sim.mesh, ranks).map(|o| owner = o.into_iter().map(|v| v as u64).collect())
    } else {
        Ok(())
    };
    collective(parts)?;
    world.process_at_rank(0).broadcast_into(&mut owner[..]);
    let partition = Partition::from_owners(&sim.mesh, ranks, owner.into_iter().map(|v| v as usize).collect());
    let nodes_per_rank: Vec<usize> = (0..ranks).map(|r| partition.nodes_of(r)).collect();
    let backend = PetscBackend::new(petsc, &sim, partition, choice);
    // Rank 0 prepares the output directory (checked writable before any solving).
    let mut file_sink = None;
    let prepared = if rank == 0 {
        // as app::solve does
        output::RunManifest::start(&opts.out, opts.overwrite)
            .map_err(SolveError::from)
            .and_then(|manifest| {
                FileSink::create(
                    &opts.out,
                    manifest,
                    &sim,
                    &scene.output.fields,
                    std::slice::from_ref(&scene.groups.contact),
                    scene.output.compression_level(),
                    opts.progress,
                )
            })
            .and_then(|mut s| {
                s.manifest.add("scene.toml")?;
                s.manifest.add("summary.json")?;
                output::write_atomic(&opts.out.join("scene.toml"), scene.to_toml_string().as_bytes())?;
                file_sink = Some(s);
                Ok(())
            })
            .map_err(|e| e.to_string())
    } else {
        Ok(())
    };
    collective(prepared)?;
    let mut sink = CollectiveSink {
        world,
        inner: file_sink.as_mut(),
    };
    let result = timeloop::run_with(&sim, &mut sink, None, Some(&backend));
    if let Some(s) = &file_sink {
        s.finish();
    }
    // A solve that failed in PETSc left NaN behind: report PETSc's reason instead.
    let result = match (result, backend.failure()) {
        (Err(SolveError::NonFinite { .. }), Some(f)) | (Err(SolveError::ContactFailed { .. }), Some(f)) => {
            Err(SolveError::Singular {
                mesh: sim.mesh.path.display().to_string(),
                detail: f,
            })
        }
        (r, _) => r,
    };
    // Every rank ends the loop at the same step; agree all the same.
    let local = match &result {
        Ok(_) => Ok(()),
        Err(e) => Err(e.to_string()),
    };
    if let Err(e) = collective(local) {
        return Err(match result {
            Err(own) => own,
            Ok(_) => e,
        });
    }
    let mut stats = result?;
    stats.phases.mesh = mesh_seconds;
    stats.phases.total += mesh_seconds;
    stats.peak_memory_bytes = crate::solver::stats::peak_memory_bytes();
    if let Some(s) = &file_sink {
        stats.phases.stress = s.stress_seconds;
        let summary = MpiSummary {
            summary: Summary::new(opts, s.steps_done, s.last_written, Some(&stats)),
            backend: "petsc",
            ranks,
            petsc_solver: method_name(backend.method),
            nodes_per_rank,
        };
        let written = output::write_json_atomic(&opts.out.join("summary.json"), &summary).map_err(|e| e.to_string());
        collective(written)?;
    } else {
        collective(Ok(()))?;
    }
    Ok(stats)
}
