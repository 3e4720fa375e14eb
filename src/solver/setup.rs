//! The discrete problem of a scene on a mesh of dimension D, holding only the effects the scene
//! names: no `[memory]` (or relaxation modulus) → no kernel, no `[contact]` → no contact nodes, no load → no load terms,
//! no non-zero prescribed value → no lifting.

use super::dirichlet::Dirichlet;
use super::error::SolveError;
use crate::fem::loads::Loads;
use crate::fem::DofMap;
use crate::material::{Elasticity, Memory, MemoryTensor, MemoryTerm, PlaneModel, Prony, RelaxationKernel};
use crate::mesh::{GroupSelector, Mesh};
use crate::scene::{self, Expr, Scene};

/// Uniform time steps t_n = n k, k = T / N (docs/method.md §2).
#[derive(Clone, Copy, Debug)]
pub struct TimeGrid {
    pub final_time: f64,
    pub steps: usize,
}

impl TimeGrid {
    /// k = T / N.
    pub fn step(&self) -> f64 {
        self.final_time / self.steps as f64
    }
    /// t_n (exactly T at n = N).
    pub fn time(&self, n: usize) -> f64 {
        if n == self.steps {
            self.final_time
        } else {
            n as f64 * self.step()
        }
    }
}

pub use super::contact::ContactSetup;

/// Everything a run needs, built once from scene + mesh.
pub struct Simulation<const D: usize = 2> {
    pub mesh: Mesh<D>,
    pub dofs: DofMap<D>,
    /// The prescribed components and their values (docs/method.md §7).
    pub dirichlet: Dirichlet<D>,
    pub elasticity: Elasticity,
    /// The memory term B(s) = Σ_m b_m(s) B_m and its channels (docs/method.md §15).
    pub memory: Option<Memory>,
    pub loads: Loads<D>,
    pub contact: Option<ContactSetup<D>>,
    pub time: TimeGrid,
    pub output_every: usize,
    pub threads: usize,
    /// How a step is condensed onto the contact normals.
    pub condensation: scene::CondensationKind,
}

fn exprs<const D: usize>(
    value: &[String],
    variables: &[&str],
    origin: &str,
    key: &str,
) -> Result<[Expr; D], SolveError> {
    if value.len() != D {
        return Err(SolveError::Setup(format!(
            "{origin}: {key} has {} components but the mesh is {D}D: give {D} expressions ({})",
            value.len(),
            ["x", "y", "z"][..D].join(", ")
        )));
    }
    let parse = |i: usize| {
        Expr::parse(&value[i], variables)
            .map_err(|e| SolveError::Setup(format!("{origin}: {key}[{i}] = \"{}\": {e}", value[i])))
    };
    let mut out = Vec::with_capacity(D);
    for i in 0..D {
        out.push(parse(i)?);
    }
    Ok(out.try_into().unwrap_or_else(|_| unreachable!("D expressions")))
}

/// The elasticity A and the memory term of the scene's material: Young's modulus and
/// Poisson's ratio with the `[memory]` terms, or a relaxation modulus (docs/method.md §15).
fn memory_of(
    scene: &Scene,
    plane: Option<PlaneModel>,
    origin: &str,
) -> Result<(Elasticity, Option<Memory>), SolveError> {
    let m = &scene.material;
    if let Some(r) = &m.relaxation_modulus {
        let prony = |p: &scene::PronySeriesSpec| Prony {
            long_term: p.long_term,
            terms: p.terms.iter().map(|t| (t.modulus, t.relaxation_time)).collect(),
        };
        return Memory::from_relaxation_modulus(&prony(&r.bulk), &prony(&r.shear), plane).map_err(|e| {
            SolveError::Setup(format!(
                "{origin}: material.relaxation_modulus with material.plane = \"stress\": {e}"
            ))
        });
    }
    // check_values has made sure both are given
    let elasticity = Elasticity {
        youngs_modulus: m.youngs_modulus.unwrap_or(f64::NAN),
        poisson_ratio: m.poisson_ratio.unwrap_or(f64::NAN),
        plane,
    };
    if scene.memory.is_empty() {
        return Ok((elasticity, None));
    }
    let mut terms = Vec::with_capacity(scene.memory.len());
    for (i, spec) in scene.memory.iter().enumerate() {
        let kernel = match &spec.kernel {
            scene::MemoryKernelSpec::Polynomial { coefficients } => RelaxationKernel::Polynomial {
                coefficients: coefficients.clone(),
            },
            scene::MemoryKernelSpec::Exponential { terms } => RelaxationKernel::Exponentials {
                terms: terms.iter().map(|t| (t.coefficient, t.relaxation_time)).collect(),
            },
            scene::MemoryKernelSpec::Expression { expression } => RelaxationKernel::General {
                expression: Box::new(Expr::parse(expression, &scene::KERNEL_VARIABLES).map_err(|e| {
                    SolveError::Setup(format!("{}.expression = \"{expression}\": {e}", scene.memory_key(i)))
                })?),
            },
        };
        let tensor = match spec.tensor {
            None | Some(scene::TensorSpec::Identity) => MemoryTensor::Identity,
            Some(scene::TensorSpec::Elasticity) => MemoryTensor::Elasticity,
            Some(scene::TensorSpec::Moduli { bulk, shear }) => MemoryTensor::Moduli { bulk, shear },
        };
        terms.push(MemoryTerm { kernel, tensor });
    }
    let memory = Memory::new(terms, &elasticity)
        .map_err(|(i, e)| SolveError::Setup(format!("{origin}: `{}.tensor` = {e}", scene.memory_key(i))))?;
    Ok((elasticity, Some(memory)))
}

/// The step matrix K = K_A + Σ_j (k/2) b_j(0) K_{T_j} must be positive definite: with a negative
/// b_j(0) (a relaxing material) that bounds the time step (docs/method.md §15.3). Checked on the
/// tensors, before anything is assembled.
fn check_step(memory: &Memory, elasticity: &Elasticity, dim: usize, scene: &Scene) -> Result<(), SolveError> {
    let (t, n) = (scene.time.final_time, scene.time.steps);
    let k = t / n as f64;
    let Some(k_max) = memory.largest_stable_step(elasticity.tensor(), dim) else {
        return Ok(());
    };
    if k < k_max {
        return Ok(());
    }
    let n_min = (t / k_max).floor();
    if !n_min.is_finite() || n_min >= 1e8 {
        return Err(SolveError::Setup(format!(
            "the scene's memory term makes the step matrix K = K_A + (k/2) Σ_j b_j(0) K_j positive definite only for \
             k < {k_max:e}, which needs more than 10⁸ time steps: b(0) is far too negative for the material's A \
             (a relaxing material has b(0) = G′(0), docs/method.md §15.3); check the memory's coefficients"
        )));
    }
    let n_min = n_min as usize + 1;
    Err(SolveError::Setup(format!(
        "`time.steps` = {n}: the time step k = T/N = {k:e} is too large for this memory term: the step matrix \
         K = K_A + (k/2) Σ_j b_j(0) K_j is positive definite only for k < {k_max:e} (b(0) < 0, a relaxing material; \
         the bound keeps K's tensor at ≥ 10⁻⁶ of A's, docs/method.md §15.3); give time.steps ≥ {n_min}"
    )))
}

impl<const D: usize> Simulation<D> {
    /// Whether the state of step 0 stands for every step (one solve for the run): no memory and
    /// nothing that changes in time — loads, prescribed values, a moving obstacle
    /// (docs/method.md §14.2). The plan and the time loop both ask here.
    pub fn is_static(&self) -> bool {
        self.memory.is_none()
            && !self.loads.is_time_dependent()
            && !self.dirichlet.is_time_dependent()
            && self.contact.as_ref().is_none_or(|c| c.motion.is_none())
    }

    /// Builds the discrete problem of `scene` on `mesh`.
    pub fn new(scene: &Scene, mesh: Mesh<D>) -> Result<Self, SolveError> {
        let origin = mesh.path.display().to_string();
        let clamped: Option<GroupSelector> = scene.clamped_group();
        let (dofs, dirichlet) = Dirichlet::new(&mesh, clamped.as_ref(), &scene.dirichlet)?;
        let plane = match (D, scene.material.plane) {
            (2, Some(p)) => Some(match p {
                scene::Plane::Stress => PlaneModel::Stress,
                scene::Plane::Strain => PlaneModel::Strain,
            }),
            (2, None) => {
                return Err(SolveError::Setup(format!(
                    "{origin} is a 2D mesh: say which 2D model in the scene, material.plane = \"stress\" or \"strain\""
                )))
            }
            (_, Some(_)) => {
                return Err(SolveError::Setup(format!(
                    "{origin} is a 3D mesh, but the scene sets material.plane: plane stress and plane strain are 2D \
                     models; remove material.plane for a 3D body"
                )))
            }
            (_, None) => None,
        };
        let (elasticity, memory) = memory_of(scene, plane, &origin)?;
        if let Some(m) = &memory {
            check_step(m, &elasticity, D, scene)?;
        }
        let mut loads = Loads::new();
        for (i, t) in scene.traction.iter().enumerate() {
            let part = mesh.boundary(&t.group)?;
            if let Some(p) = &t.pressure {
                let key = format!("traction[{i}].pressure");
                let p = Expr::parse(p, &scene::TRACTION_VARIABLES)
                    .map_err(|e| SolveError::Setup(format!("{origin}: {key} = \"{p}\": {e}")))?;
                loads.add_pressure(&part, &mesh.points, p, &key);
                continue;
            }
            let key = format!("traction[{i}].value");
            loads.add_traction(
                &part,
                &mesh.points,
                exprs(&t.value, &scene::TRACTION_VARIABLES, &origin, &key)?,
                &key,
            );
        }
        if let Some(f) = &scene.body_force {
            loads.add_body_force(
                &mesh.cells,
                &mesh.points,
                exprs(&f.value, &scene::BODY_FORCE_VARIABLES, &origin, "body_force.value")?,
                "body_force.value",
            );
        }
        let contact = super::contact::build(scene, &mesh, &dofs, &origin)?;
        Ok(Simulation {
            mesh,
            dofs,
            dirichlet,
            elasticity,
            memory,
            loads,
            contact,
            time: TimeGrid {
                final_time: scene.time.final_time,
                steps: scene.time.steps,
            },
            output_every: scene.output.every,
            threads: 1,
            condensation: scene.solver.condensation,
        })
    }

    /// The unknowns the factor orders last: in 3D, with up to 2 000 contact nodes, those of the
    /// contact normals (docs/method.md §9.1: G and W then live in the factor's trailing block),
    /// else none. Measured: m = 1 248 (slab 96x48x12) condensation 12.0 s → 3.4 s; m = 4 096 (box
    /// 64x4x63) 16.5 s → 49 s, because the sparse sweeps then run through a dense m × m block.
    pub fn unknowns_ordered_last(&self) -> Vec<usize> {
        match &self.contact {
            Some(c) if D == 3 && c.nodes.len() <= 2000 => {
                let mut dofs: Vec<usize> = c.nodes.rows().iter().flatten().map(|&(d, _)| d).collect();
                dofs.sort_unstable();
                dofs.dedup();
                dofs
            }
            _ => Vec::new(),
        }
    }

    /// True if step n is written (every `output_every`-th step and always the last).
    pub fn is_output_step(&self, n: usize) -> bool {
        n % self.output_every == 0 || n == self.time.steps
    }
}
