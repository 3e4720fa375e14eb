//! The scene's material as constitutive data (docs/method.md §15): the elasticity A and the
//! memory B(s) = Σ_m b_m(s) B_m, from Young's modulus, Poisson's ratio and the `[memory]`
//! sections, or from a relaxation modulus; and the time-step bound a relaxing memory sets. Used
//! by the scene's checks (so that an error names the scene file) and by the solver's set-up.

use super::types::{Constants, MemoryKernelSpec, PronySeriesSpec, Scene, TensorSpec};
use crate::expr::Expr;
use crate::material::memory::STABILITY_MARGIN;
use crate::material::{Elasticity, Isotropic, Memory, MemoryTensor, MemoryTerm, PlaneModel, Prony, RelaxationKernel};
use crate::time::Stepping;

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
            let Some((bulk, shear)) = r.bulk_and_shear() else {
                return Err(MaterialError {
                    key: self.key("relaxation_modulus"),
                    value: "(incomplete)".into(),
                    fix: "give bulk and shear, or youngs and poisson_ratio".into(),
                });
            };
            return Memory::from_relaxation_modulus(&prony(&bulk), &prony(&shear), plane).map_err(|e| MaterialError {
                key: self.key("relaxation_modulus"),
                value: "(bulk and shear terms)".into(),
                fix: format!("with material.plane = \"stress\": {e}"),
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
    /// Step sizes that stand for the run's (docs/method.md §15.3): each size of a uniform or
    /// listed grid, the sizes of a geometric one (at most 1 000 of them, spread in log k), and for
    /// automatic steps sizes spread in log k from the smallest step to the largest.
    fn sizes_to_check(&self, stepping: &Stepping) -> Vec<f64> {
        let t = self.time.final_time;
        let spread = |lo: f64, hi: f64| -> Vec<f64> {
            let n = 200;
            (0..=n).map(|i| lo * (hi / lo).powf(i as f64 / n as f64)).collect()
        };
        match stepping {
            Stepping::Uniform { steps } => vec![t / *steps as f64],
            Stepping::Listed { times } => {
                let mut last = 0.0;
                let mut sizes = Vec::new();
                for &v in times.iter().chain([t].iter()) {
                    if v > last {
                        sizes.push(v - last);
                        last = v;
                    }
                }
                sizes
            }
            Stepping::Geometric { first, .. } => spread(*first, t),
            Stepping::Automatic { first, min, max, .. } => {
                let lo = min.or(*first).unwrap_or(t * 1e-12).min(t);
                spread(lo, max.unwrap_or(t).min(t))
            }
        }
    }

    /// The step matrix K = K_A + Σ_j β_j K_j must be positive definite: with a negative kernel (a
    /// relaxing material) the trapezoid's β_j = (k/2) b_j(0) bounds the time step (docs/method.md
    /// §15.3); the exact rule's share of a relaxation modulus is positive for every k, and other
    /// Prony kernels are checked at the run's sizes. Checked on the tensors (A = `a`, in dimension
    /// `dim`), before anything is assembled.
    pub fn check_time_step(
        &self,
        memory: &Memory,
        a: Isotropic,
        dim: usize,
        stepping: &Stepping,
    ) -> Result<(), MaterialError> {
        let rules = self.time.rules();
        let t = self.time.final_time;
        let sizes = self.sizes_to_check(stepping);
        let Some(&k) = sizes
            .iter()
            .find(|&&k| memory.step_stiffness_ratio(a, dim, k, rules) < STABILITY_MARGIN)
        else {
            return self.check_long_term_moduli(memory, a, dim, &sizes);
        };
        let bound = memory
            .largest_stable_step(a, dim)
            .filter(|_| rules == crate::material::Rules::TRAPEZOID);
        let fix = match (stepping, bound) {
            (Stepping::Uniform { .. }, Some(k_max)) => {
                let n_min = (t / k_max).floor();
                if !n_min.is_finite() || n_min >= 1e8 {
                    format!(
                        "the memory term makes the step matrix K = K_A + (k/2) Σ_j b_j(0) K_j positive definite only \
                         for k < {k_max:e}, which needs more than 10⁸ time steps: b(0) is far too negative for the \
                         material's A (a relaxing material has b(0) = G′(0), docs/method.md §15.3); check the \
                         memory's coefficients, or take time.quadrature = \"exact\" (positive for every step)"
                    )
                } else {
                    format!(
                        "the time step k = T/N = {k:e} is too large for this memory term with the trapezoid: the step \
                         matrix K = K_A + (k/2) Σ_j b_j(0) K_j is positive definite only for k < {k_max:e} (b(0) < \
                         0, a relaxing material; the bound keeps K's tensor at ≥ 10⁻⁶ of A's, docs/method.md \
                         §15.3); give time.steps ≥ {}, or take time.quadrature = \"exact\" (positive for every \
                         step)",
                        n_min as usize + 1
                    )
                }
            }
            (_, Some(k_max)) => format!(
                "a step of {k:e} is too large for this memory term with the trapezoid: the step matrix is positive \
                 definite only for k < {k_max:e} (docs/method.md §15.3); keep the steps below it, or take \
                 time.quadrature = \"exact\""
            ),
            (_, None) => format!(
                "on a step of {k:e} the memory term makes the step matrix K = K_A + Σ_j β_j K_j not positive definite \
                 (its tensor below 10⁻⁶ of A's, docs/method.md §15.3): the memory's coefficients relax more than A \
                 holds; check their signs and sizes"
            ),
        };
        Err(MaterialError {
            key: match stepping {
                Stepping::Uniform { .. } => "time.steps",
                Stepping::Geometric { .. } => "time.first_step",
                Stepping::Listed { .. } => "time.times",
                Stepping::Automatic { .. } => "time.max_step",
            }
            .into(),
            value: match (stepping, self.time.steps) {
                (Stepping::Uniform { .. }, Some(n)) => n.to_string(),
                _ => format!("(a step of {k:e})"),
            },
            fix,
        })
    }

    /// The scheme's long-term moduli (docs/method.md §15.3) must be positive where the material's
    /// are: the trapezoid's weights over-integrate a relaxation by ≈ (k/τ)²/12 of its strength,
    /// which eats a small long-term modulus (G(0)/G∞ = 100 at k = τ: 2μ∞ < 0, and the run grows
    /// without bound). Prony kernels on the trapezoid only (the exact rule sums them exactly, the
    /// others do not decay); the largest of `sizes` decides.
    pub fn check_long_term_moduli(
        &self,
        memory: &Memory,
        a: Isotropic,
        dim: usize,
        sizes: &[f64],
    ) -> Result<(), MaterialError> {
        let rules = self.time.rules();
        let t = self.time.final_time;
        let k = sizes.iter().copied().fold(0.0, f64::max);
        let (Some(exact), Some(discrete)) = (
            memory.long_term_eigenvalues(a, dim, None, rules),
            memory.long_term_eigenvalues(a, dim, Some(k), rules),
        ) else {
            return Ok(());
        };
        if exact.iter().any(|&e| e <= 0.0) || discrete.iter().all(|&d| d > 0.0) {
            return Ok(());
        }
        let needed = memory
            .largest_accurate_step(a, dim, crate::material::LONG_TERM_TOLERANCE, k, rules)
            .map_or(String::new(), |k1| match self.time.steps {
                Some(_) => format!(
                    "; give time.steps ≥ {} (its long-term moduli within 1 %)",
                    (t / k1).ceil()
                ),
                None => format!("; keep the steps below {k1:e} (its long-term moduli within 1 %)"),
            });
        Err(MaterialError {
            key: if self.time.steps.is_some() {
                "time.steps"
            } else {
                "time.quadrature"
            }
            .into(),
            value: self.time.steps.map_or("\"trapezoid\"".to_string(), |n| n.to_string()),
            fix: format!(
                "the time step k = {k:e} is too coarse for this relaxation with the trapezoid: on it the scheme's \
                 long-term moduli (eigenvalues {:.3e}, {:.3e}) are not positive where the material's ({:.3e}, {:.3e}) \
                 are, so the run would grow without bound (the trapezoid rule over-integrates each relaxation term by \
                 about (k/τ)²/12 of its strength, docs/method.md §15.3){needed}; or take time.quadrature = \"exact\", \
                 exact for every step",
                discrete[0], discrete[1], exact[0], exact[1]
            ),
        })
    }
}
