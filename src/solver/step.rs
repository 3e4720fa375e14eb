//! The operator of a step (docs/method.md §3–4, §7, §9): the factor of a step matrix and its
//! condensation, the lifting of prescribed values, and one step's solve d = C K⁻¹ rhs,
//! contact → λ, u_n = K⁻¹ (rhs − Cᵀ λ).

use super::backend::{Backend, Stiffness};
use super::error::SolveError;
use super::setup::{ContactSetup, Simulation};
use super::stats::{timed, RunStats};
use crate::contact::active_set::{ActiveSetSolver, ContactOutcome, ContactState};
use crate::contact::{Condensation, SplitSweeps, StoredResponses};
use crate::fem::SymmetricMatrix;
use crate::linalg::{Analysis, Counters, Factor, LinearSolver};
use crate::scene::CondensationKind;
use std::sync::Arc;

/// The columns of the prescribed unknowns of an unmodified matrix (all rows): what the
/// prescribed part of the system contributes (docs/method.md §7).
pub(super) struct PrescribedColumns {
    /// (prescribed unknown j, its column entries (i, K_ij)).
    pub(super) columns: Vec<(usize, Vec<(usize, f64)>)>,
}

impl PrescribedColumns {
    pub(super) fn new<const D: usize>(matrix: &SymmetricMatrix, dofs: &crate::fem::DofMap<D>) -> Self {
        let columns = (0..matrix.n())
            .filter(|&j| dofs.is_prescribed(j))
            .map(|j| (j, matrix.column(j).collect()))
            .collect();
        PrescribedColumns { columns }
    }

    /// rhs_i −= Σ_j K_ij g_j at the free rows i.
    pub(super) fn lift<const D: usize>(&self, g: &[f64], dofs: &crate::fem::DofMap<D>, rhs: &mut [f64]) {
        for (j, col) in &self.columns {
            if g[*j] != 0.0 {
                for &(i, v) in col {
                    if !dofs.is_prescribed(i) {
                        rhs[i] -= v * g[*j];
                    }
                }
            }
        }
    }

    /// (K x)_j at each prescribed j, added into `out` (indexed like the columns).
    pub(super) fn add_product(&self, x: &[f64], out: &mut [f64]) {
        for ((_, col), o) in self.columns.iter().zip(out.iter_mut()) {
            *o += col.iter().map(|&(i, v)| v * x[i]).sum::<f64>();
        }
    }
}

/// How a step operator lifts non-zero prescribed values (docs/method.md §7.2).
pub(super) enum Lifting {
    /// The unmodified columns of the prescribed unknowns (serial).
    Columns(PrescribedColumns),
    /// rhs −= (K_A + c K_B) g at the free unknowns through [`Backend::product`] (c = `memory`).
    Products { memory: Option<f64> },
}

/// A factor of a step matrix and, with contact, its condensation.
pub(super) struct StepOperator {
    pub(super) solver: Arc<dyn LinearSolver>,
    pub(super) condensed: Option<Box<dyn Condensation>>,
    /// How non-zero prescribed values are lifted (None when they are all zero).
    pub(super) lifting: Option<Lifting>,
}

/// The matrix a factor is built from (identity rows at the prescribed unknowns, docs/method.md
/// §7) and, when some prescribed value is non-zero, the unmodified columns that lift them.
pub(super) fn system_matrix<const D: usize>(
    sim: &Simulation<D>,
    matrix: &SymmetricMatrix,
) -> (SymmetricMatrix, Option<Lifting>) {
    let lifting = sim
        .dirichlet
        .is_nonzero()
        .then(|| Lifting::Columns(PrescribedColumns::new(matrix, &sim.dofs)));
    (matrix.with_identity_rows(&sim.dofs), lifting)
}

impl StepOperator {
    /// Factors `matrix` (from [`system_matrix`]) and condenses the contact normals.
    pub(super) fn new<const D: usize>(
        sim: &Simulation<D>,
        symbolic: &Analysis,
        (matrix, lifting): (SymmetricMatrix, Option<Lifting>),
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Self, SolveError> {
        // The probe's product K v is taken before the factorisation, which consumes the matrix:
        // K is not held next to its factor (docs/method.md §9.3).
        let probe = timed(&mut stats.phases.factorisation, || Probe::new(&matrix));
        let factor = timed(&mut stats.phases.factorisation, || {
            Factor::new_consuming(symbolic, matrix, counters)
        })
        .map_err(|e| SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail: e.to_string(),
        })?;
        timed(&mut stats.phases.factorisation, || probe.verdict(&factor)).map_err(|detail| SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail,
        })?;
        let factor = Arc::new(factor);
        let condensed: Option<Box<dyn Condensation>> = match &sim.contact {
            Some(c) if !c.nodes.is_empty() => Some(
                timed(
                    &mut stats.phases.condensation,
                    || -> Result<Box<dyn Condensation>, String> {
                        Ok(match sim.condensation {
                            CondensationKind::SplitSweeps => {
                                Box::new(SplitSweeps::new(&c.nodes, factor.clone(), counters)?)
                            }
                            kind @ (CondensationKind::StoredResponses | CondensationKind::RecoverySolve) => {
                                let solver: Arc<dyn LinearSolver> = factor.clone();
                                let keep = kind == CondensationKind::StoredResponses;
                                Box::new(StoredResponses::new(&c.nodes, solver, keep, counters)?)
                            }
                        })
                    },
                )
                .map_err(SolveError::Setup)?,
            ),
            _ => None,
        };
        if let Some(c) = &condensed {
            stats.condensation = Some(c.name().to_string());
        }
        Ok(StepOperator {
            solver: factor,
            condensed,
            lifting,
        })
    }

    /// The operator of a [`Backend`] for K = K_A + c K_B (c = `memory`), lifting through the
    /// backend's products.
    pub(super) fn with_backend<const D: usize>(
        sim: &Simulation<D>,
        backend: &dyn Backend<D>,
        memory: Option<f64>,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Self, SolveError> {
        let lifting = sim.dirichlet.is_nonzero().then_some(Lifting::Products { memory });
        let (solver, condensed) = timed(&mut stats.phases.factorisation, || {
            backend.operator(sim, memory, counters)
        })?;
        if let Some(c) = &condensed {
            stats.condensation = Some(c.name().to_string());
        }
        Ok(StepOperator {
            solver,
            condensed,
            lifting,
        })
    }

    /// Solves one step: d = C K⁻¹ rhs, contact → λ, u_n = K⁻¹ (rhs − Cᵀ λ). `offset` is the
    /// prescribed part of u_ν (None when it is zero); `u` receives u_n.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn solve<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        step: usize,
        rhs: &[f64],
        offset: Option<&[f64]>,
        u: &mut [f64],
        state: Option<&mut ContactState>,
        backend: Option<&dyn Backend<D>>,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Option<ContactOutcome>, SolveError> {
        match (&sim.contact, self.condensed.as_mut(), state) {
            (Some(setup), Some(op), Some(state)) => {
                let mut d = vec![0.0; setup.nodes.len()];
                timed(&mut stats.phases.forward_sweep, || {
                    op.free_normal(rhs, &mut d, counters)
                });
                if let Some(g) = offset {
                    setup.nodes.prescribed_offset(g, &mut d);
                }
                let outcome = timed(&mut stats.phases.contact, || match backend {
                    None => contact_solve(sim, setup, op.as_ref(), step, &d, state),
                    Some(b) => {
                        let local = if b.solves_contact() {
                            contact_solve(sim, setup, op.as_ref(), step, &d, state)
                        } else {
                            Ok(ContactOutcome::default())
                        };
                        b.share_contact(state, local)
                    }
                })?;
                stats.contact_solves += 1;
                timed(&mut stats.phases.backward_sweep, || {
                    op.recover(&state.force, u, counters)
                });
                Ok(Some(outcome))
            }
            _ => {
                timed(&mut stats.phases.backward_sweep, || self.solver.solve(rhs, u, counters));
                Ok(None)
            }
        }
    }
}

/// A Cholesky factorisation of a singular matrix can succeed on round-off pivots (a body held
/// at a single point can still rotate about it). One probe solve, K⁻¹(K v) against v for a fixed
/// pseudo-random v, tells: an error far above round-off means the matrix is (nearly) singular.
/// The probe is not counted among the run's solves.
struct Probe {
    v: Vec<f64>,
    /// K v.
    product: Vec<f64>,
}

impl Probe {
    /// The probe vector v and K v.
    fn new(matrix: &SymmetricMatrix) -> Self {
        let n = matrix.n();
        let v: Vec<f64> = (0..n)
            .map(|i| ((i as f64 + 1.0) * 0.618_033_988_749_895).fract() - 0.5)
            .collect();
        let mut product = vec![0.0; n];
        matrix.matvec(&v, &mut product);
        Probe { v, product }
    }

    /// K⁻¹(K v) against v with the factor of K.
    fn verdict(mut self, factor: &Factor) -> Result<(), String> {
        factor.solve_in_place(&mut self.product, &Counters::default());
        let scale = self.v.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let error = self
            .product
            .iter()
            .zip(&self.v)
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()))
            / scale;
        singularity_verdict(error)
    }
}

/// The verdict of a probe solve whose relative error is `error` (any backend's probe).
pub fn singularity_verdict(error: f64) -> Result<(), String> {
    if error.is_finite() && error <= 1e-6 {
        Ok(())
    } else {
        Err(format!(
            "the stiffness matrix is singular or nearly so (a probe solve is off by {error:.1e} relative): the body is not held against rigid motions; clamp a part of the boundary (groups.clamped) that stops translations and rotations"
        ))
    }
}

fn contact_solve<const D: usize>(
    sim: &Simulation<D>,
    setup: &ContactSetup<D>,
    op: &dyn Condensation,
    step: usize,
    d: &[f64],
    state: &mut ContactState,
) -> Result<ContactOutcome, SolveError> {
    // a moving obstacle moves the laws' origins and the bounds (docs/method.md §14.2)
    let t = sim.time.time(step);
    let moved = setup
        .gaps_at(t)
        .map_err(|detail| SolveError::NonFiniteLoad { step, time: t, detail })?;
    let (offset, bound) = match &moved {
        Some((o, g)) => (Some(&o[..]), Some(&g[..])),
        None => (setup.gap.as_deref(), setup.bound.as_deref()),
    };
    let solver = ActiveSetSolver {
        operator: op.stiffness(),
        laws: &setup.laws,
        offset,
        bound,
        settings: setup.settings,
    };
    solver.solve(d, state).map_err(|f| SolveError::ContactFailed {
        step,
        time: sim.time.time(step),
        iterations: f.outcome.iterations,
        residual: f.outcome.residual,
        tolerance: setup.settings.tolerance,
        reason: f.reason,
    })
}

/// The prescribed components in a right-hand side (docs/method.md §7): rhs_f −= K_fp g at the
/// free rows, rhs_p = g_p at the prescribed ones (zero without non-zero values). `g` is over
/// all unknowns, `rhs` over this process's ([`Backend::unknowns`] with a backend).
pub(super) fn lift<const D: usize>(
    op: &StepOperator,
    sim: &Simulation<D>,
    g: Option<&[f64]>,
    rhs: &mut [f64],
    backend: Option<&dyn Backend<D>>,
) {
    match (g, &op.lifting, backend) {
        (Some(g), Some(Lifting::Columns(columns)), _) => columns.lift(g, &sim.dofs, rhs),
        (Some(g), Some(Lifting::Products { memory }), Some(b)) => {
            // K g with g zero at the free unknowns is Σ_j K_ij g_j over the prescribed j.
            let held: Vec<f64> = b.unknowns().iter().map(|&d| g[d]).collect();
            let mut kg = vec![0.0; held.len()];
            b.product(sim, Stiffness::Elastic, &held, &mut kg);
            if let Some(c) = memory {
                let mut y = vec![0.0; held.len()];
                b.product(sim, Stiffness::Memory, &held, &mut y);
                kg.iter_mut().zip(&y).for_each(|(a, v)| *a += c * v);
            }
            for ((r, &d), v) in rhs.iter_mut().zip(b.unknowns()).zip(&kg) {
                if !sim.dofs.is_prescribed(d) {
                    *r -= v;
                }
            }
        }
        _ => {}
    }
    for (k, r) in rhs.iter_mut().enumerate() {
        let d = backend.map_or(k, |b| b.unknowns()[k]);
        if sim.dofs.is_prescribed(d) {
            *r = g.map_or(0.0, |g| g[d]);
        }
    }
}
