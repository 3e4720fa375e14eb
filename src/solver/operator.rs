//! The operator of a step matrix (docs/method.md §3, §7, §9): its solver, the condensation of
//! the contact normals, how it lifts prescribed values, and the probe that tells a singular
//! matrix. Built by a backend; `step.rs` solves with it.

use super::columns::PrescribedColumns;
use super::error::SolveError;
use super::setup::Simulation;
use super::stats::{timed, RunStats};
use crate::contact::{Condensation, SplitSweeps, StoredResponses};
use crate::fem::SymmetricMatrix;
use crate::linalg::{Analysis, Counters, Factor, FactorError, LinearSolver};
use crate::scene::CondensationKind;
use std::sync::Arc;

/// How a step operator lifts non-zero prescribed values (docs/method.md §7.2).
pub(super) enum Lifting {
    /// The unmodified columns of the prescribed unknowns (the faer factor's).
    Columns(PrescribedColumns),
    /// rhs −= (K_A + Σ_j c_j K_j) g at the free unknowns through the backend's products
    /// (c = `memory`).
    Products { memory: Vec<f64> },
}

/// The operator of a step matrix: its solver and, with contact, its condensation, and how it
/// lifts non-zero prescribed values.
pub struct StepOperator {
    pub(super) solver: Arc<dyn LinearSolver>,
    pub(super) condensed: Option<Box<dyn Condensation>>,
    /// How non-zero prescribed values are lifted (None when they are all zero).
    pub(super) lifting: Option<Lifting>,
    /// The responses of the rigid parameters (force control, pins; docs/method.md §7.7).
    pub(super) rigid: Option<super::rigid::RigidResponses>,
    /// The step matrix is this times the matrix factorised (docs/method.md §20.3): the solves
    /// divide the right-hand side's free rows and the contact forces by it.
    pub(super) scale: f64,
}

/// A step matrix as a factor is built from it (docs/method.md §7): identity rows at the
/// prescribed unknowns, the unmodified columns that lift non-zero prescribed values, and those
/// of the rigid parameters' unknowns (§7.7).
pub(super) struct SystemMatrix {
    pub(super) matrix: SymmetricMatrix,
    pub(super) lifting: Option<Lifting>,
    pub(super) rigid_columns: Option<PrescribedColumns>,
}

/// The matrix a factor is built from (identity rows at the prescribed unknowns, docs/method.md
/// §7) and, when some prescribed value is non-zero, the unmodified columns that lift them.
pub(super) fn system_matrix<const D: usize>(sim: &Simulation<D>, matrix: &SymmetricMatrix) -> SystemMatrix {
    let lifting = sim
        .dirichlet
        .is_nonzero()
        .then(|| Lifting::Columns(PrescribedColumns::new(matrix, &sim.dofs)));
    let rigid = &sim.dirichlet.rigid;
    let rigid_columns = (!rigid.is_empty())
        .then(|| PrescribedColumns::of(matrix, rigid.iter().flat_map(|p| p.unknowns.iter().copied())));
    SystemMatrix {
        matrix: matrix.with_identity_rows(&sim.dofs),
        lifting,
        rigid_columns,
    }
}

impl StepOperator {
    /// Factors `matrix` (from [`system_matrix`]) and condenses the contact normals.
    pub(super) fn factored<const D: usize>(
        sim: &Simulation<D>,
        symbolic: &Analysis,
        SystemMatrix {
            matrix,
            lifting,
            rigid_columns,
        }: SystemMatrix,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<Self, SolveError> {
        // The probe's product K v is taken before the factorisation, which consumes the matrix:
        // K is not held next to its factor (docs/method.md §9.3).
        let probe = timed(&mut stats.phases.factorisation, || Probe::new(&matrix));
        let factor = timed(&mut stats.phases.factorisation, || {
            Factor::new_consuming(symbolic, matrix, counters)
        })
        .map_err(|e| factor_failed(sim, e))?;
        timed(&mut stats.phases.factorisation, || probe.verdict(&factor)).map_err(|what| singular(sim, what))?;
        let factor = Arc::new(factor);
        let mut condensed: Option<Box<dyn Condensation>> = match &sim.contact {
            Some(c) if !c.nodes.is_empty() => Some(
                timed(
                    &mut stats.phases.condensation,
                    || -> Result<Box<dyn Condensation>, String> { condensation(sim, &factor, counters) },
                )
                .map_err(SolveError::Setup)?,
            ),
            _ => None,
        };
        if let Some(c) = &condensed {
            stats.condensation = Some(c.name().to_string());
        }
        let rigid = match rigid_columns {
            Some(columns) => Some(timed(&mut stats.phases.condensation, || {
                let contact = match (&sim.contact, condensed.as_mut()) {
                    (Some(c), Some(op)) => Some((c.condensed_rows(), op)),
                    _ => None,
                };
                super::rigid::RigidResponses::new(
                    &sim.dirichlet.rigid,
                    &sim.dofs,
                    columns,
                    factor.as_ref(),
                    contact,
                    counters,
                )
            })),
            None => None,
        };
        Ok(StepOperator {
            solver: factor,
            condensed,
            lifting,
            rigid,
            scale: 1.0,
        })
    }

    /// The operator of a backend's own solver and condensation for K = K_A + Σ_j c_j K_j
    /// (c = `memory`), lifting through the backend's products.
    pub fn distributed<const D: usize>(
        sim: &Simulation<D>,
        solver: Arc<dyn LinearSolver>,
        condensed: Option<Box<dyn Condensation>>,
        memory: &[f64],
        stats: &mut RunStats,
    ) -> Self {
        if let Some(c) = &condensed {
            stats.condensation = Some(c.name().to_string());
        }
        let lifting = sim.dirichlet.is_nonzero().then(|| Lifting::Products {
            memory: memory.to_vec(),
        });
        StepOperator {
            solver,
            condensed,
            lifting,
            rigid: None,
            scale: 1.0,
        }
    }

    /// Makes this the operator of `scale` times the matrix factorised (docs/method.md §20.3): the
    /// condensed W and Q and the rigid parameters' responses follow, by O(m²) work.
    pub(super) fn rescale_to(&mut self, scale: f64) {
        if scale == self.scale {
            return;
        }
        let ratio = scale / self.scale;
        if let Some(c) = &mut self.condensed {
            c.rescale(ratio);
        }
        if let Some(r) = &mut self.rigid {
            r.rescale(ratio);
        }
        self.scale = scale;
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
    fn verdict(mut self, factor: &Factor) -> Result<(), Singularity> {
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

/// From this K/G on, a (nearly) singular matrix is put down to the material before the supports
/// (ν ≥ 0.49995): the probe's error grows like K/G times the mesh's own condition number, and
/// 2D runs of the paper's mesh fail it from ν = 1 − 10⁻¹⁰ (K/G ≈ 10¹⁰) while ν = 0.49999999 still
/// passes.
pub const MATERIAL_SINGULAR_BULK_TO_SHEAR: f64 = 1e4;

/// What showed the step matrix (nearly) singular, before its likely cause is named.
#[derive(Clone, Copy, Debug)]
pub enum Singularity {
    /// A pivot of the Cholesky factorisation failed.
    Pivot,
    /// A probe solve was off by this much (relative).
    Probe(f64),
}

/// The supports' cause of a singular matrix, as a probe names it.
const NOT_HELD: &str =
    "the body is not held against rigid motions; clamp a part of the boundary (groups.clamped) that stops translations and rotations";

/// The error of a singular step matrix (`what` showed it): with a nearly incompressible
/// material (K/G ≥ [`MATERIAL_SINGULAR_BULK_TO_SHEAR`], not in plane stress) the message names
/// the material first, the supports second; otherwise the supports.
pub fn singular<const D: usize>(sim: &Simulation<D>, what: Singularity) -> SolveError {
    let m = sim.materials.most_incompressible();
    let e = &m.elasticity;
    let ratio = e.bulk_to_shear();
    let material = e.plane != Some(crate::material::PlaneModel::Stress) && ratio >= MATERIAL_SINGULAR_BULK_TO_SHEAR;
    let which = match sim.materials.list().len() {
        1 => "the material".to_string(),
        _ => format!("the material of {}", m.name),
    };
    let symptom = match what {
        Singularity::Pivot => {
            "the stiffness matrix is not positive definite (pivot failed in the Cholesky factorisation)".to_string()
        }
        Singularity::Probe(error) => {
            format!("the stiffness matrix is singular or nearly so (a probe solve is off by {error:.1e} relative)")
        }
    };
    let detail = match (material, what) {
        (true, _) => format!(
            "{symptom}: {which} is nearly incompressible (ν = {}, K/G = {ratio:.3e}), so the matrix is ill-conditioned \
             by the material rather than by the supports; lower ν (hvi's elements lock from about ν = 0.495, K/G = 100, \
             on: docs/troubleshooting.md), and if that does not help, the body is not held: clamp a part of its boundary",
            e.poisson_ratio
        ),
        (false, Singularity::Pivot) => FactorError::NotPositiveDefinite.to_string(),
        (false, Singularity::Probe(_)) => format!("{symptom}: {NOT_HELD}"),
    };
    SolveError::Singular {
        mesh: sim.mesh.path.display().to_string(),
        detail,
    }
}

/// The error of a factorisation that failed: a failed pivot is a [`singular`] matrix, anything
/// else (memory, the analysis) is said as it is.
pub fn factor_failed<const D: usize>(sim: &Simulation<D>, e: FactorError) -> SolveError {
    match e {
        FactorError::NotPositiveDefinite => singular(sim, Singularity::Pivot),
        other => SolveError::Singular {
            mesh: sim.mesh.path.display().to_string(),
            detail: other.to_string(),
        },
    }
}

/// The verdict of a probe solve whose relative error is `error` (any backend's probe).
pub fn singularity_verdict(error: f64) -> Result<(), Singularity> {
    if error.is_finite() && error <= 1e-6 {
        Ok(())
    } else {
        Err(Singularity::Probe(error))
    }
}

/// The condensation of `sim` on `factor` (docs/method.md §9): Q read off the factor's trailing
/// block where [`Simulation::trailing_block`] says so, with W beside it only with friction
/// (Coulomb's unloaded round reads it, §17.2; elsewhere W is applied by triangular solves);
/// else G by sparse sweeps, or the stored responses the scene asks for.
pub fn condensation<const D: usize>(
    sim: &Simulation<D>,
    factor: &Arc<Factor>,
    counters: &crate::linalg::Counters,
) -> Result<Box<dyn Condensation>, String> {
    let Some(c) = &sim.contact else {
        return Err("no contact to condense".into());
    };
    let rows = c.condensed_rows();
    Ok(match sim.condensation {
        CondensationKind::SplitSweeps => {
            // (None only when L_cc's k² numbers cannot be allocated: the sweeps then)
            let trailing = sim
                .trailing_block()
                .then(|| SplitSweeps::off_trailing_block(rows, factor.clone(), sim.forms_w_off_trailing_block()));
            match trailing.flatten() {
                Some(op) => Box::new(op),
                None => Box::new(SplitSweeps::new(rows, factor.clone(), counters)?),
            }
        }
        kind @ (CondensationKind::StoredResponses | CondensationKind::RecoverySolve) => {
            let solver: Arc<dyn LinearSolver> = factor.clone();
            let keep = kind == CondensationKind::StoredResponses;
            Box::new(StoredResponses::new(rows, solver, keep, counters)?)
        }
    })
}
