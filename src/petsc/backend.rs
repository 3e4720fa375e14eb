//! The time loop's [`Backend`] on PETSc (docs/method.md §13): distributed step matrices, their
//! factor or preconditioner, the unmodified K_A and K_B for the products, and the condensation
//! of the contact normals: one distributed solve per step with the stored responses Z = K⁻¹Cᵀ
//! when they fit the budget of [`keeps_responses`], two otherwise.
//!
//! Over 600 lines because it is one backend (docs/method.md §13): the solvers, their products,
//! the distributed condensation and the collective agreement of its failures.

use super::common::SolverChoice;
use super::partition::Partition;
use crate::contact::condensed::{subtract_normal_forces, subtract_responses};
use crate::contact::{Condensation, ContactNodes, DenseNormalStiffness};
use crate::contact::{ContactOutcome, ContactState};
use crate::fem::assembly::local_stiffness;
use crate::linalg::{Counters, LinearSolver};
use crate::material::Isotropic;
use crate::scene::CondensationKind;
use crate::solver::operator::StepOperator;
use crate::solver::reactions::Reactions;
use crate::solver::stats::{timed, RunStats};
use crate::solver::{singularity_verdict, Backend, Stiffness};
use crate::solver::{Simulation, SolveError};
use hvi_petsc::mpi::collective::SystemOperation;
use hvi_petsc::mpi::topology::SimpleCommunicator;
use hvi_petsc::mpi::traits::*;
use hvi_petsc::{DenseBlock, Int, Matrix, Method, MumpsMemory, Petsc, Solver, Vector};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};

/// The relative residual CG + GAMG solves to: ten orders below the data, so that the solver
/// error stays far below the discretisation error of any mesh hvi runs (docs/method.md §13).
/// PETSc's option `-hvi_ksp_rtol` (in `PETSC_OPTIONS`) overrides it.
pub const GAMG_RTOL: f64 = 1e-10;

/// Right-hand sides per `KSPMatSolve` block when forming W (bounds the dense blocks held at
/// once to 32 columns of the local rows).
pub(super) const BLOCK: usize = 32;

/// Whether the condensation keeps each rank's rows of Z = K⁻¹Cᵀ (8 · local unknowns · m bytes),
/// so that a step recovers u = u_free − Zλ instead of a second distributed solve (docs/method.md
/// §13) — decided here for the run and for `hvi check --backend petsc` (collective): never with
/// `solver.condensation = "recovery_solve"`, always with `"stored_responses"`; otherwise when on
/// every rank Z takes at most half of what the rank's solver holds already (`solver_bytes`:
/// MUMPS's memory on the rank, or the step matrix under GAMG, whose hierarchy is about as large
/// again). Below that budget the product also reads fewer bytes than the solve it replaces (a
/// forward and a backward pass over the rank's share of L).
pub(super) fn keeps_responses(kind: CondensationKind, local_unknowns: usize, m: usize, solver_bytes: f64) -> bool {
    let mine = match kind {
        CondensationKind::RecoverySolve => return false,
        CondensationKind::StoredResponses => true,
        CondensationKind::SplitSweeps => 8.0 * local_unknowns as f64 * m as f64 <= 0.5 * solver_bytes,
    };
    let world = SimpleCommunicator::world();
    let mut all = 0u8;
    world.all_reduce_into(&u8::from(mine), &mut all, SystemOperation::min());
    all == 1
}

/// The row layout of the PETSc matrices: hvi unknown D·p + c is PETSc row D·position[p] + c;
/// this rank owns rows lo..hi, the unknowns of its nodes.
pub(super) struct Layout {
    /// Global rows (all unknowns, prescribed ones included).
    pub n: usize,
    pub lo: usize,
    pub hi: usize,
    /// hvi's number of each owned row (row lo + k at k): the order of this rank's vectors.
    pub unknowns: Vec<usize>,
    pub row_of_dof: Vec<usize>,
}

impl Layout {
    /// The local index of hvi unknown `d` if this rank owns it.
    fn local(&self, d: usize) -> Option<usize> {
        let r = self.row_of_dof[d];
        (self.lo..self.hi).contains(&r).then(|| r - self.lo)
    }
}

/// The unmodified K_A and K_B as distributed matrices, with the vectors of their products.
struct Products {
    elastic: Option<Matrix>,
    memory: Option<Matrix>,
    x: Vector,
    y: Vector,
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
    products: Mutex<Option<Products>>,
    /// The first PETSc failure of a solve or product (they cannot return errors through
    /// [`LinearSolver`] and [`Backend`]: they fill their result with NaN, which stops the step
    /// on every rank).
    failure: Arc<Mutex<Option<String>>>,
    /// MUMPS's memory of the last factor built.
    mumps: Mutex<Option<MumpsMemory>>,
    /// Bytes of the PETSc matrices this rank holds now (step matrices, K_A, K_B).
    matrix_bytes: Mutex<f64>,
}

// SAFETY: the backend is used from the time loop's thread only; `Sync` is required because the
// Stepper holds it by reference.

unsafe impl<const D: usize> Sync for PetscBackend<'_, D> {}

/// Which stiffness [`PetscBackend::assemble`] builds, cell by cell with the cell's material
/// (docs/method.md §8.5).
#[derive(Clone, Copy, Debug)]
enum Tensors {
    /// K_A.
    Elastic,
    /// K_B of the memory's one channel (the time loop refuses two with a backend,
    /// docs/method.md §15.1): its tensor T on its material's cells, zero elsewhere.
    Memory,
    /// The step matrix K_A + c K_B (c None: K_A). Linear in (λ, μ): the stiffness of
    /// (λ_A + c λ_T, μ_A + c μ_T) on the channel's material, of A elsewhere (docs/method.md §3, §15.1).
    Step(Option<f64>),
}

impl Tensors {
    /// The tensor on cell `e` of the mesh.
    fn of_cell<const D: usize>(self, sim: &Simulation<D>, e: usize) -> Isotropic {
        let a = sim.materials.of_cell(e).elasticity.tensor();
        let channel = sim
            .materials
            .memory()
            .and_then(|m| m.channels().first())
            .filter(|_| sim.materials.channel_owner(0) == sim.materials.id_of_cell(e))
            .map(|c| c.tensor);
        match (self, channel) {
            (Tensors::Elastic, _) | (Tensors::Step(None), _) => a,
            (Tensors::Memory, Some(t)) => t,
            (Tensors::Memory, None) => Isotropic { lambda: 0.0, mu: 0.0 },
            (Tensors::Step(Some(c)), Some(t)) => Isotropic {
                lambda: a.lambda + c * t.lambda,
                mu: a.mu + c * t.mu,
            },
            (Tensors::Step(Some(_)), None) => a,
        }
    }
}

impl<'p, const D: usize> PetscBackend<'p, D> {
    pub fn new(petsc: &'p Petsc, sim: &Simulation<D>, partition: Partition, choice: SolverChoice) -> Self {
        let rank = petsc.rank();
        let n_nodes = sim.mesh.points.len();
        let n = D * n_nodes;
        let mut row_of_dof = vec![0; n];
        for p in 0..n_nodes {
            for c in 0..D {
                row_of_dof[D * p + c] = D * partition.position[p] + c;
            }
        }
        let own_nodes = partition.nodes_owned_by(rank);
        let unknowns = own_nodes.iter().flat_map(|&p| (0..D).map(move |c| D * p + c)).collect();
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
        let own_cells = partition.cells_owned_by(rank);
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
                unknowns,
                row_of_dof,
            }),
            partition,
            method,
            diagonal_nnz,
            off_diagonal_nnz,
            own_cells,
            products: Mutex::new(None),
            failure: Arc::new(Mutex::new(None)),
            mumps: Mutex::new(None),
            matrix_bytes: Mutex::new(0.0),
        }
    }

    pub fn partition(&self) -> &Partition {
        &self.partition
    }

    pub fn method(&self) -> Method {
        self.method
    }

    /// The first PETSc failure a solve or product recorded, if any.
    pub fn failure(&self) -> Option<String> {
        self.failure.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// MUMPS's memory of the last factor built (None with GAMG).
    pub fn mumps_memory(&self) -> Option<MumpsMemory> {
        *self.mumps.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Bytes of the K_A and K_B this rank holds for the products.
    pub fn product_bytes(&self) -> f64 {
        *self.matrix_bytes.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Assembles the unmodified K_A (when reactions or non-zero prescribed values need it) and
    /// K_B (with memory) as distributed matrices, for [`Backend::product`] (collective).
    pub fn prepare_products(&self, sim: &Simulation<D>) -> Result<(), SolveError> {
        let elastic = !sim.dirichlet.reaction_groups.is_empty() || sim.dirichlet.is_nonzero();
        let build = || -> Result<Products, hvi_petsc::Error> {
            let elastic = elastic
                .then(|| self.assemble(sim, Tensors::Elastic, false))
                .transpose()?;
            let memory = sim
                .materials
                .memory()
                .is_some()
                .then(|| self.assemble(sim, Tensors::Memory, false))
                .transpose()?;
            let bytes = elastic
                .iter()
                .chain(&memory)
                .map(|m| m.local_bytes())
                .sum::<Result<f64, _>>()?;
            *self.matrix_bytes.lock().unwrap_or_else(|e| e.into_inner()) = bytes;
            let local = self.layout.hi - self.layout.lo;
            Ok(Products {
                elastic,
                memory,
                x: Vector::mpi(self.petsc, local)?,
                y: Vector::mpi(self.petsc, local)?,
            })
        };
        let products = build().map_err(|e| self.error(sim, e))?;
        *self.products.lock().unwrap_or_else(|e| e.into_inner()) = Some(products);
        Ok(())
    }

    /// This rank's cells of the stiffness `tensors` as an MPIAIJ matrix (collective): with
    /// `identity_rows`, the prescribed rows and columns are left empty and get a unit diagonal
    /// (docs/method.md §7.2); without, the matrix is the unmodified one.
    fn assemble(&self, sim: &Simulation<D>, tensors: Tensors, identity_rows: bool) -> Result<Matrix, hvi_petsc::Error> {
        let layout = &self.layout;
        let mut matrix = Matrix::mpiaij(
            self.petsc,
            layout.hi - layout.lo,
            layout.n,
            D,
            &self.diagonal_nnz,
            &self.off_diagonal_nnz,
        )?;
        let (points, cells) = (&sim.mesh.points, &sim.mesh.cells);
        let nl_max = D * cells.iter().map(|c| c.nodes().len()).max().unwrap_or(0);
        let mut local = vec![0.0; nl_max * nl_max];
        let mut index: Vec<Int> = Vec::with_capacity(nl_max);
        let axisymmetric = sim.materials.plane() == Some(crate::material::PlaneModel::Axisymmetric);
        for &e in &self.own_cells {
            let cell = &cells[e];
            let nl = D * cell.nodes().len();
            let volumetric = sim.materials.of_cell(e).volumetric;
            let tensor = tensors.of_cell(sim, e);
            local_stiffness(cell, points, &[tensor], volumetric, axisymmetric, &mut [&mut local[..]]);
            index.clear();
            for &p in cell.nodes() {
                for c in 0..D {
                    let d = D * p + c;
                    // PETSc ignores negative indices: prescribed rows and columns stay empty.
                    index.push(if identity_rows && sim.dofs.is_prescribed(d) {
                        -1
                    } else {
                        layout.row_of_dof[d] as Int
                    });
                }
            }
            matrix.add(&index, &index, &local[..nl * nl])?;
        }
        if identity_rows {
            for (k, &d) in layout.unknowns.iter().enumerate() {
                if sim.dofs.is_prescribed(d) {
                    let r = [(layout.lo + k) as Int];
                    matrix.add(&r, &r, &[1.0])?;
                }
            }
        }
        matrix.assemble_spd()?;
        Ok(matrix)
    }

    /// For `hvi check`: assembles the step matrix (K̃ = K_A + (k/2) b(0) K_B with memory) and
    /// returns the bytes PETSc holds for it on this rank and, with `mumps`, MUMPS's analysis of
    /// it (collective; nothing is factorised).
    pub fn analyse(&self, sim: &Simulation<D>, mumps: bool) -> Result<(f64, Option<MumpsMemory>), String> {
        let memory = sim
            .materials
            .memory()
            .and_then(|m| m.step_coefficients(sim.time.first_step(), sim.rules).first().copied());
        let matrix = self
            .assemble(sim, Tensors::Step(memory), true)
            .map_err(|e| e.to_string())?;
        let bytes = matrix.local_bytes().map_err(|e| e.to_string())?;
        let estimate = mumps
            .then(|| matrix.mumps_estimate())
            .transpose()
            .map_err(|e| format!("MUMPS's analysis failed: {e}"))?;
        Ok((bytes, estimate))
    }

    /// The step matrix K = K_A + c K_B with identity rows, and its solver (collective).
    fn build(&self, sim: &Simulation<D>, memory: Option<f64>) -> Result<PetscSolver, hvi_petsc::Error> {
        let layout = &self.layout;
        let mut matrix = self.assemble(sim, Tensors::Step(memory), true)?;
        if let Method::CgGamg { .. } = self.method {
            let mut coords = matrix.vector()?;
            let points = &sim.mesh.points;
            coords.with_local_mut(|x| {
                for (v, &d) in x.iter_mut().zip(&layout.unknowns) {
                    *v = points[d / D][d % D];
                }
            })?;
            matrix.set_rigid_body_modes(&mut coords, D)?;
        }
        let solver = Solver::new(&matrix, self.method, "hvi_")?;
        *self.mumps.lock().unwrap_or_else(|e| e.into_inner()) = solver.mumps_memory()?;
        let b = matrix.vector()?;
        let x = matrix.vector()?;
        Ok(PetscSolver {
            layout: layout.clone(),
            name: solver.name(),
            inner: Mutex::new(Inner { matrix, solver, b, x }),
            failure: self.failure.clone(),
        })
    }

    /// What the rank's solver of `solver` holds, for [`keeps_responses`]: MUMPS's memory on the
    /// rank, or the step matrix's bytes under GAMG.
    fn solver_bytes(&self, solver: &PetscSolver) -> f64 {
        match self.mumps_memory() {
            Some(m) => m.this_rank_mb as f64 * 1e6,
            None => solver.inner().matrix.local_bytes().unwrap_or(0.0),
        }
    }

    fn error(&self, sim: &Simulation<D>, e: hvi_petsc::Error) -> SolveError {
        SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail: format!("the PETSc backend ({}) failed: {e}", method_name(self.method)),
        }
    }

    fn record(&self, what: &str, e: hvi_petsc::Error) {
        let mut f = self.failure.lock().unwrap_or_else(|e| e.into_inner());
        f.get_or_insert_with(|| format!("the PETSc backend ({}) failed in {what}: {e}", method_name(self.method)));
    }
}

pub(super) fn method_name(m: Method) -> &'static str {
    match m {
        Method::MumpsCholesky => "MUMPS Cholesky",
        Method::CgGamg { .. } => "CG + GAMG",
    }
}

impl<const D: usize> PetscBackend<'_, D> {
    /// The unknowns this rank holds, in the order of every vector of the time loop.
    pub fn unknowns(&self) -> &[usize] {
        &self.layout.unknowns
    }

    /// A solver (and, with contact nodes, a condensation) for the step matrix
    /// K = K_A + c K_B with identity rows at the prescribed unknowns, c = `memory` (None: K_A).
    #[allow(clippy::type_complexity)]
    fn distributed_operator(
        &self,
        sim: &Simulation<D>,
        memory: Option<f64>,
        counters: &Counters,
    ) -> Result<(Arc<dyn LinearSolver>, Option<Box<dyn Condensation>>), SolveError> {
        let solver = Arc::new(self.build(sim, memory).map_err(|e| self.error(sim, e))?);
        counters.factorisations.fetch_add(1, Ordering::Relaxed);
        let error = solver.probe().map_err(|e| self.error(sim, e))?;
        singularity_verdict(error).map_err(|what| crate::solver::singular(sim, what))?;
        let condensed: Option<Box<dyn Condensation>> = match &sim.contact {
            Some(c) if !c.nodes.is_empty() => {
                let keep = keeps_responses(sim.condensation, solver.n(), c.nodes.len(), self.solver_bytes(&solver));
                Some(Box::new(
                    DistributedCondensation::new(
                        c.condensed_rows(),
                        solver.clone(),
                        self.petsc.rank() == 0,
                        keep,
                        counters,
                    )
                    .map_err(|e| match e {
                        Ok(e) => self.error(sim, e),
                        Err(detail) => SolveError::Setup(detail),
                    })?,
                ))
            }
            _ => None,
        };
        Ok((solver, condensed))
    }
}

impl<const D: usize> Backend<D> for PetscBackend<'_, D> {
    fn operator(
        &mut self,
        sim: &Simulation<D>,
        memory: &[f64],
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<StepOperator, SolveError> {
        if memory.len() > 1 {
            return Err(SolveError::Setup(format!(
                "this memory has {} channels (tensors that are not proportional make two, docs/method.md §15.1; \
                 each material with memory has its own, §8.5), and the PETSc backend runs memory of one channel \
                 only: run it without --backend petsc, or give one material memory terms whose tensors are \
                 proportional (e.g. all \"identity\" or all \"elasticity\", or bulk and shear relaxing \
                 proportionally)",
                memory.len()
            )));
        }
        let c = memory.first().copied();
        let (solver, condensed) = timed(&mut stats.phases.factorisation, || {
            self.distributed_operator(sim, c, counters)
        })?;
        Ok(StepOperator::distributed(sim, solver, condensed, memory, stats))
    }

    fn reactions(&mut self, sim: &Simulation<D>) -> Reactions {
        Reactions::over_products(sim, Some(&self.layout.unknowns))
    }

    fn held_unknowns(&self) -> Option<&[usize]> {
        Some(&self.layout.unknowns)
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
        const N: usize = ContactOutcome::NUMBERS;
        let mut numbers = vec![0.0f64; N + m];
        if let (true, Ok(o)) = (self.solves_contact(), &local) {
            numbers[..N].copy_from_slice(&o.to_numbers());
            numbers[N..].copy_from_slice(&state.force);
        }
        root.broadcast_into(&mut numbers[..]);
        if self.solves_contact() {
            return local;
        }
        state.force.copy_from_slice(&numbers[N..]);
        Ok(ContactOutcome::from_numbers(&numbers[..N]))
    }

    fn product(&self, _sim: &Simulation<D>, matrix: Stiffness, x: &[f64], y: &mut [f64]) {
        let mut guard = self.products.lock().unwrap_or_else(|e| e.into_inner());
        let result = match guard.as_mut() {
            None => Err(hvi_petsc::Error {
                code: -1,
                message: "K_A and K_B were not assembled (prepare_products)".into(),
            }),
            Some(p) => {
                // one memory channel only (operator refuses two)
                let (m, name) = match matrix {
                    Stiffness::Elastic => (p.elastic.as_ref(), "Elastic"),
                    Stiffness::Memory(0) => (p.memory.as_ref(), "Memory"),
                    Stiffness::Memory(_) => (None, "a second memory channel's"),
                };
                match m {
                    None => Err(hvi_petsc::Error {
                        code: -1,
                        message: format!("{name} stiffness was not assembled"),
                    }),
                    Some(m) => {
                        p.x.set_local(x)
                            .and_then(|()| m.mult(&p.x, &mut p.y))
                            .and_then(|()| p.y.get_local(y))
                    }
                }
            }
        };
        if let Err(e) = result {
            self.record("a matrix product", e);
            y.fill(f64::NAN);
        }
    }

    fn sum(&self, values: &mut [f64]) {
        let world = self.petsc.world();
        let mine = values.to_vec();
        world.all_reduce_into(&mine[..], values, SystemOperation::sum());
    }
}

struct Inner {
    matrix: Matrix,
    solver: Solver,
    b: Vector,
    x: Vector,
}

/// One PETSc solver of one step matrix as a [`LinearSolver`] over this rank's unknowns (the
/// right-hand side and the solution of a solve are this rank's share, in [`Layout`] order).
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
        let mut inner = self.inner();
        let Inner { solver, b, x: xv, .. } = &mut *inner;
        b.set_local(rhs)?;
        solver.solve(b, xv)?;
        xv.get_local(x)
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
            for (e, &i) in a.iter_mut().zip(&l.unknowns) {
                *e = ((i as f64 + 1.0) * 0.618_033_988_749_895).fract() - 0.5;
            }
        })?;
        matrix.mult(&v, b)?;
        solver.solve(b, x)?;
        let scale = v.norm_max()?;
        x.axpy(-1.0, &v)?;
        Ok(x.norm_max()? / scale)
    }

    /// W = C K⁻¹ Cᵀ (m × m, row-major) on rank 0 (`root`; empty elsewhere) for the rows of C
    /// over hvi's unknowns: blocks of right-hand sides by `KSPMatSolve`, each rank summing the
    /// share of its rows (collective). With `keep`, also this rank's rows of Z = K⁻¹Cᵀ
    /// (column-major, a column per row of C, in [`Layout`] order).
    fn normal_responses(
        &self,
        rows: &[Vec<(usize, f64)>],
        root: bool,
        keep: bool,
    ) -> Result<(Vec<f64>, Option<Vec<f64>>), hvi_petsc::Error> {
        let l = &self.layout;
        let m = rows.len();
        let nl = l.hi - l.lo;
        let mut w = if root { vec![0.0; m * m] } else { Vec::new() };
        let mut z = if keep {
            let mut z = Vec::new();
            crate::alloc::fallible(|| z.try_reserve_exact(nl * m)).map_err(|_| hvi_petsc::Error {
                code: -1,
                message: format!("out of memory for the stored responses Z ({nl} × {m} on this rank)"),
            })?;
            z.resize(nl * m, 0.0);
            Some(z)
        } else {
            None
        };
        let inner = self.inner();
        let world = SimpleCommunicator::world();
        let rank0 = world.process_at_rank(0);
        for start in (0..m).step_by(BLOCK) {
            let cols = BLOCK.min(m - start);
            let mut b = DenseBlock::like(&inner.matrix, cols)?;
            b.with_local_mut(|a, lda| {
                for j in 0..cols {
                    for &(d, c) in &rows[start + j] {
                        if let Some(r) = l.local(d) {
                            a[j * lda + r] = c;
                        }
                    }
                }
            })?;
            let mut x = DenseBlock::like(&inner.matrix, cols)?;
            inner.solver.solve_block(&b, &mut x)?;
            let mut part = vec![0.0; m * cols];
            x.with_local_mut(|a, lda| {
                if let Some(z) = z.as_mut() {
                    for j in 0..cols {
                        z[(start + j) * nl..(start + j + 1) * nl].copy_from_slice(&a[j * lda..j * lda + nl]);
                    }
                }
                for (p, row) in rows.iter().enumerate() {
                    for &(d, c) in row {
                        if let Some(r) = l.local(d) {
                            for j in 0..cols {
                                part[p * cols + j] += c * a[j * lda + r];
                            }
                        }
                    }
                }
            })?;
            if root {
                let mut sum = vec![0.0; m * cols];
                rank0.reduce_into_root(&part[..], &mut sum[..], SystemOperation::sum());
                for p in 0..m {
                    w[p * m + start..p * m + start + cols].copy_from_slice(&sum[p * cols..(p + 1) * cols]);
                }
            } else {
                rank0.reduce_into(&part[..], SystemOperation::sum());
            }
        }
        if root {
            crate::linalg::dense::symmetrise_row_major(&mut w, m);
        }
        Ok((w, z))
    }
}

impl LinearSolver for PetscSolver {
    fn n(&self) -> usize {
        self.layout.unknowns.len()
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

/// The condensation of the PETSc backend (docs/method.md §13): W by blocks of solves (held on
/// rank 0 only, where the contact solve runs), then per step a free solve d = C K⁻¹ r and the
/// recovery: u = u_free − Zλ from this rank's rows of the stored responses Z = K⁻¹Cᵀ when
/// [`keeps_responses`] allows them, else a second solve u = K⁻¹ (r − Cᵀ λ).
pub struct DistributedCondensation {
    solver: Arc<PetscSolver>,
    /// The rows of C restricted to this rank's unknowns: (local index, coefficient).
    rows: Vec<Vec<(usize, f64)>>,
    /// This rank's rows of Z, column-major (None: the recovery is a solve).
    responses: Option<Vec<f64>>,
    stiffness: DenseNormalStiffness,
    rhs: Vec<f64>,
    u_free: Vec<f64>,
}

impl DistributedCondensation {
    /// Err(Ok(e)): PETSc failed; Err(Err(detail)): W is not positive definite (on every rank:
    /// rank 0 decides and tells the others).
    fn new<const D: usize>(
        nodes: &ContactNodes<D>,
        solver: Arc<PetscSolver>,
        root: bool,
        keep: bool,
        counters: &Counters,
    ) -> Result<Self, Result<hvi_petsc::Error, String>> {
        let m = nodes.len();
        let (w, responses) = solver.normal_responses(nodes.rows(), root, keep).map_err(Ok)?;
        counters.solves.fetch_add(m, Ordering::Relaxed);
        let stiffness = match root {
            true => DenseNormalStiffness::from_w(w, m),
            // Only rank 0 runs the active set (docs/method.md §13): the others hold no W.
            false => Ok(DenseNormalStiffness {
                w: Vec::new(),
                q: Vec::new(),
                m: 0,
                q_inverts_w: false,
            }),
        };
        let mut message = match &stiffness {
            Err(e) if root => e.clone().into_bytes(),
            _ => Vec::new(),
        };
        let world = SimpleCommunicator::world();
        let rank0 = world.process_at_rank(0);
        let mut len = message.len() as u64;
        rank0.broadcast_into(&mut len);
        if len > 0 {
            message.resize(len as usize, 0);
            rank0.broadcast_into(&mut message[..]);
            return Err(Err(String::from_utf8_lossy(&message).into_owned()));
        }
        let stiffness = stiffness.map_err(Err)?;
        let l = &solver.layout;
        let rows = nodes
            .rows()
            .iter()
            .map(|row| row.iter().filter_map(|&(d, c)| l.local(d).map(|k| (k, c))).collect())
            .collect();
        let n = solver.n();
        Ok(DistributedCondensation {
            solver,
            rows,
            responses,
            stiffness,
            rhs: vec![0.0; n],
            u_free: vec![0.0; n],
        })
    }
}

impl Condensation for DistributedCondensation {
    fn name(&self) -> &'static str {
        match self.responses {
            Some(_) => "PETSc: W and the stored responses Z by KSPMatSolve, one solve per step (u = u_free − Zλ)",
            None => "PETSc: W by KSPMatSolve, a free and a recovery solve per step",
        }
    }

    fn stiffness(&self) -> &DenseNormalStiffness {
        &self.stiffness
    }

    fn stiffness_mut(&mut self) -> &mut DenseNormalStiffness {
        &mut self.stiffness
    }

    fn free_normal(&mut self, rhs: &[f64], d: &mut [f64], counters: &Counters) {
        self.rhs.copy_from_slice(rhs);
        self.solver.solve(rhs, &mut self.u_free, counters);
        let part: Vec<f64> = self
            .rows
            .iter()
            .map(|row| row.iter().map(|&(k, c)| c * self.u_free[k]).sum())
            .collect();
        SimpleCommunicator::world().all_reduce_into(&part[..], d, SystemOperation::sum());
    }

    fn recover(&mut self, lambda: &[f64], u: &mut [f64], counters: &Counters) {
        match &self.responses {
            Some(z) => subtract_responses(&self.u_free, z, lambda, u),
            None => {
                subtract_normal_forces(&mut self.rhs, &self.rows, lambda);
                self.solver.solve(&self.rhs, u, counters);
            }
        }
    }
}
