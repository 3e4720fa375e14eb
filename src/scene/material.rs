//! The scene's material as constitutive data (docs/method.md §15): the elasticity A and the
//! memory B(s) = Σ_m b_m(s) B_m, from Young's modulus, Poisson's ratio and the `[memory]`
//! sections, or from a relaxation modulus; and the time-step bound a relaxing memory sets. Used
//! by the scene's checks (so that an error names the scene file) and by the solver's set-up.

use super::types::{Constants, MemoryKernelSpec, PronySeriesSpec, Scene, TensorSpec};
use crate::expr::Expr;
use crate::material::{Elasticity, Isotropic, Memory, MemoryTensor, MemoryTerm, PlaneModel, Prony, RelaxationKernel};

/// What is wrong with the material of a scene: the key, its value and the fix.
#[derive(Clone, Debug)]
pub struct MaterialError {
    pub key: String,
    pub value: String,
    pub fix: String,
}

impl MaterialError {
    /// The error of material `c` among several: the fix names it (`[material]`, or
    /// `materials[1]` and its group).
    pub fn of(self, c: &Constants, several: bool) -> MaterialError {
        if !several {
            return self;
        }
        let which = match c.group {
            Some(g) => format!("{} (group {g})", c.table()),
            None => "[material]".into(),
        };
        MaterialError {
            fix: format!("for the material of {which}: {}", self.fix),
            ..self
        }
    }
}

impl std::fmt::Display for MaterialError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "`{}` = {}: {}", self.key, self.value, self.fix)
    }
}

impl Constants<'_> {
    /// A and the memory of this material for the 2D model `plane` (None: 3D). The values are
    /// those `check_values` accepts (a missing E or ν reads as NaN).
    pub fn model(&self, plane: Option<PlaneModel>) -> Result<(Elasticity, Option<Memory>), MaterialError> {
        let m = self;
        if let Some(r) = m.relaxation_modulus {
            let prony = |p: &PronySeriesSpec| Prony {
                long_term: p.long_term,
                terms: p.terms.iter().map(|t| (t.modulus, t.relaxation_time)).collect(),
            };
            return Memory::from_relaxation_modulus(&prony(&r.bulk), &prony(&r.shear), plane).map_err(|e| {
                MaterialError {
                    key: self.key("relaxation_modulus"),
                    value: "(bulk and shear terms)".into(),
                    fix: format!("with material.plane = \"stress\": {e}"),
                }
            });
        }
        let elasticity = Elasticity {
            youngs_modulus: m.youngs_modulus.unwrap_or(f64::NAN),
            poisson_ratio: m.poisson_ratio.unwrap_or(f64::NAN),
            plane,
        };
        if self.memory.is_empty() {
            return Ok((elasticity, None));
        }
        let mut terms = Vec::with_capacity(self.memory.len());
        for (i, spec) in self.memory.iter().enumerate() {
            let kernel = match &spec.kernel {
                MemoryKernelSpec::Polynomial { coefficients } => RelaxationKernel::Polynomial {
                    coefficients: coefficients.clone(),
                },
                MemoryKernelSpec::Exponential { terms } => RelaxationKernel::Exponentials {
                    terms: terms.iter().map(|t| (t.coefficient, t.relaxation_time)).collect(),
                },
                MemoryKernelSpec::Expression { expression } => RelaxationKernel::General {
                    expression: Box::new(Expr::parse(expression, &super::KERNEL_VARIABLES).map_err(|e| {
                        MaterialError {
                            key: format!("{}.expression", self.memory_key(i)),
                            value: format!("\"{expression}\""),
                            fix: e,
                        }
                    })?),
                },
            };
            let tensor = match spec.tensor {
                None | Some(TensorSpec::Identity) => MemoryTensor::Identity,
                Some(TensorSpec::Elasticity) => MemoryTensor::Elasticity,
                Some(TensorSpec::Moduli { bulk, shear }) => MemoryTensor::Moduli { bulk, shear },
            };
            terms.push(MemoryTerm { kernel, tensor });
        }
        let memory = Memory::new(terms, &elasticity).map_err(|(i, e)| {
            let (value, fix) = e.split_once(": ").unwrap_or(("", &e));
            MaterialError {
                key: format!("{}.tensor", self.memory_key(i)),
                value: value.to_string(),
                fix: match plane {
                    Some(PlaneModel::Stress) => format!("with material.plane = \"stress\": {fix}"),
                    _ => fix.to_string(),
                },
            }
        })?;
        Ok((elasticity, Some(memory)))
    }
}

impl Scene {
    /// The step matrix K = K_A + Σ_j (k/2) b_j(0) K_j must be positive definite: with a negative
    /// b_j(0) (a relaxing material) that bounds the time step (docs/method.md §15.3). Checked on
    /// the tensors (A = `a`, in dimension `dim`), before anything is assembled.
    pub fn check_time_step(&self, memory: &Memory, a: Isotropic, dim: usize) -> Result<(), MaterialError> {
        let (t, n) = (self.time.final_time, self.time.steps);
        let k = t / n as f64;
        let Some(k_max) = memory.largest_stable_step(a, dim).filter(|&k_max| k >= k_max) else {
            return self.check_long_term_moduli(memory, a, dim);
        };
        let n_min = (t / k_max).floor();
        let fix = if !n_min.is_finite() || n_min >= 1e8 {
            format!(
                "the memory term makes the step matrix K = K_A + (k/2) Σ_j b_j(0) K_j positive definite only for \
                 k < {k_max:e}, which needs more than 10⁸ time steps: b(0) is far too negative for the material's A \
                 (a relaxing material has b(0) = G′(0), docs/method.md §15.3); check the memory's coefficients"
            )
        } else {
            format!(
                "the time step k = T/N = {k:e} is too large for this memory term: the step matrix K = K_A + (k/2) \
                 Σ_j b_j(0) K_j is positive definite only for k < {k_max:e} (b(0) < 0, a relaxing material; the \
                 bound keeps K's tensor at ≥ 10⁻⁶ of A's, docs/method.md §15.3); give time.steps ≥ {}",
                n_min as usize + 1
            )
        };
        Err(MaterialError {
            key: "time.steps".into(),
            value: n.to_string(),
            fix,
        })
    }
    /// The scheme's long-term moduli (docs/method.md §15.3) must be positive where the material's
    /// are: the trapezoid weights over-integrate a relaxation by ≈ (k/τ)²/12 of its strength,
    /// which eats a small long-term modulus (G(0)/G∞ = 100 at k = τ: 2μ∞ < 0, and the run grows
    /// without bound). Prony kernels only (the others do not decay).
    pub fn check_long_term_moduli(&self, memory: &Memory, a: Isotropic, dim: usize) -> Result<(), MaterialError> {
        let (t, n) = (self.time.final_time, self.time.steps);
        let k = t / n as f64;
        let (Some(exact), Some(discrete)) = (
            memory.long_term_eigenvalues(a, dim, None),
            memory.long_term_eigenvalues(a, dim, Some(k)),
        ) else {
            return Ok(());
        };
        if exact.iter().any(|&e| e <= 0.0) || discrete.iter().all(|&d| d > 0.0) {
            return Ok(());
        }
        let needed = memory
            .largest_accurate_step(a, dim, crate::material::LONG_TERM_TOLERANCE, k)
            .map_or(String::new(), |k1| {
                format!(
                    "; give time.steps ≥ {} (its long-term moduli within 1 %)",
                    (t / k1).ceil()
                )
            });
        Err(MaterialError {
            key: "time.steps".into(),
            value: n.to_string(),
            fix: format!(
                "the time step k = T/N = {k:e} is too coarse for this relaxation: on it the scheme's long-term moduli \
                 (eigenvalues {:.3e}, {:.3e}) are not positive where the material's ({:.3e}, {:.3e}) are, so the run \
                 would grow without bound (the trapezoid rule over-integrates each relaxation term by about (k/τ)²/12 \
                 of its strength, docs/method.md §15.3){needed}",
                discrete[0], discrete[1], exact[0], exact[1]
            ),
        })
    }
}
