//! The memory term B(s) = Σ_m b_m(s) B_m (docs/method.md §15): each term a scalar kernel b_m
//! and an isotropic tensor B_m — the identity (the paper), the elasticity tensor A, or a tensor
//! with its own bulk and shear moduli — reduced to at most two *channels* (T_j, b_j):
//!
//! * all B_m proportional to one tensor T (B_m = c_m T): ONE channel, tensor T and kernel
//!   Σ_m c_m b_m — the cost of a single kernel (the paper's scene takes exactly this path);
//! * otherwise TWO channels on the basis tensors (λ, μ) = (1, 0) and (0, 1) with kernels
//!   Σ_m λ_m b_m and Σ_m μ_m b_m, whatever the number of terms.
//!
//! A relaxation modulus (Prony series for bulk and shear) becomes terms of this form
//! ([`Memory::from_relaxation_modulus`]): A = G(0), B = G′.

use super::elasticity::{Elasticity, Isotropic, PlaneModel, IDENTITY_TENSOR};
use super::kernel::{short, RelaxationKernel};
use super::quadrature::{self, Quadrature, Rules};

/// The share of u_n in one term's memory integral over a step of size k, by its rule: its
/// kernel's atoms' `current` weights (src/material/quadrature.rs).
fn term_share(kernel: &RelaxationKernel, k: f64, rules: Rules) -> f64 {
    match kernel {
        RelaxationKernel::Exponentials { terms } => terms
            .iter()
            .map(|&(c, tau)| c * quadrature::exponential(rules.exponential, k, tau).current)
            .sum(),
        RelaxationKernel::Polynomial { coefficients } => coefficients
            .iter()
            .enumerate()
            .map(|(d, a)| a * quadrature::monomial(rules.polynomial, k, d).current)
            .sum(),
        RelaxationKernel::General { .. } => 0.5 * k * kernel.value(0.0),
    }
}

/// Relative tolerance below which two tensors count as proportional (their 2 × 2 determinant
/// against the product of their norms): round-off of a tensor written out in decimals, far
/// below any intended difference.
const PARALLEL_TOLERANCE: f64 = 1e-12;

/// The step tensor's eigenvalues must stay above this fraction of A's (docs/method.md §15.3): at
/// the exact bound K is singular, and within round-off of it a factorisation still "succeeds".
pub const STABILITY_MARGIN: f64 = 1e-6;

/// How far (relative) the scheme's long-term moduli of a relaxing material may be from the
/// material's before `hvi check` warns (docs/method.md §15.3): they set the creep's end value,
/// and a refusal names the steps that bring them this close.
pub const LONG_TERM_TOLERANCE: f64 = 0.01;

/// The tensor B_m of one memory term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MemoryTensor {
    /// B_m = I, B_m ε = ε (the paper).
    Identity,
    /// B_m = A (in 2D plane stress A's own λ*, docs/method.md §8.2).
    Elasticity,
    /// Isotropic with bulk modulus κ and shear modulus G: λ = κ − 2G/3, μ = G (the 3D
    /// relations; also in 2D plane strain).
    Moduli { bulk: f64, shear: f64 },
}

impl MemoryTensor {
    fn describe(&self) -> String {
        match self {
            MemoryTensor::Identity => "I".into(),
            MemoryTensor::Elasticity => "A".into(),
            MemoryTensor::Moduli { bulk, shear } => format!("(κ = {}, G = {})", short(*bulk), short(*shear)),
        }
    }
}

/// One term b_m(s) B_m.
#[derive(Clone, Debug)]
pub struct MemoryTerm {
    pub kernel: RelaxationKernel,
    pub tensor: MemoryTensor,
}

/// One channel: the tensor T_j and the weights w_jm of its kernel b_j(s) = Σ_m w_jm b_m(s).
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub tensor: Isotropic,
    pub weights: Vec<f64>,
}

/// The memory term of a material: its terms and the channels they reduce to.
#[derive(Clone, Debug)]
pub struct Memory {
    terms: Vec<MemoryTerm>,
    channels: Vec<Channel>,
    /// Built from a relaxation modulus (for the description).
    from_relaxation_modulus: bool,
}

/// A Prony series f(t) = f∞ + Σ_m f_m e^{−t/τ_m}: `long_term` f∞ and the terms (f_m, τ_m).
#[derive(Clone, Debug, PartialEq)]
pub struct Prony {
    pub long_term: f64,
    pub terms: Vec<(f64, f64)>,
}

impl Prony {
    /// f(t).
    pub fn value(&self, t: f64) -> f64 {
        self.long_term + self.terms.iter().map(|(f, tau)| f * (-t / tau).exp()).sum::<f64>()
    }
}

fn norm(t: Isotropic) -> f64 {
    t.lambda.hypot(t.mu)
}

/// c with t = c r when t and r are proportional (None otherwise): the one test of
/// proportionality (channels, plane stress).
pub fn proportional(t: Isotropic, r: Isotropic) -> Option<f64> {
    let cross = t.lambda * r.mu - t.mu * r.lambda;
    let scale = norm(t) * norm(r);
    if scale == 0.0 || cross.abs() > PARALLEL_TOLERANCE * scale {
        return None;
    }
    if t == r {
        return Some(1.0);
    }
    Some((t.lambda * r.lambda + t.mu * r.mu) / (r.lambda * r.lambda + r.mu * r.mu))
}

impl Memory {
    /// Resolves the tensors of `terms` for the material `elasticity` and reduces them to
    /// channels. Errors: an own-moduli tensor in plane stress that is not proportional to A (it
    /// has no isotropic plane-stress reduction, docs/method.md §15.1), a zero tensor.
    /// The error names the index of the term.
    pub fn new(terms: Vec<MemoryTerm>, elasticity: &Elasticity) -> Result<Memory, (usize, String)> {
        let a = elasticity.tensor();
        let (l3, m3) = elasticity.lame();
        let a3 = Isotropic { lambda: l3, mu: m3 };
        let mut resolved = Vec::with_capacity(terms.len());
        for (i, term) in terms.iter().enumerate() {
            let t = match term.tensor {
                MemoryTensor::Identity => IDENTITY_TENSOR,
                MemoryTensor::Elasticity => a,
                MemoryTensor::Moduli { bulk, shear } => {
                    let t = Isotropic::from_moduli(bulk, shear);
                    match elasticity.plane {
                        Some(PlaneModel::Stress) => match proportional(t, a3) {
                            // c·A in 3D reduces to c·A* in plane stress (docs/method.md §15.1)
                            Some(c) => Isotropic {
                                lambda: c * a.lambda,
                                mu: c * a.mu,
                            },
                            None => {
                                return Err((
                                    i,
                                    format!(
                                        "{{ bulk = {bulk}, shear = {shear} }}: a tensor with its own moduli has no \
                                         isotropic plane-stress reduction unless it is proportional to A (bulk/shear \
                                         = {:.6} here); use material.plane = \"strain\", or a tensor proportional \
                                         to A (tensor = \"elasticity\", with the factor in the kernel)",
                                        (a3.lambda + 2.0 * a3.mu / 3.0) / a3.mu
                                    ),
                                ))
                            }
                        },
                        _ => t,
                    }
                }
            };
            if norm(t) == 0.0 || !norm(t).is_finite() {
                return Err((
                    i,
                    format!("{}: the tensor is zero or not finite", term.tensor.describe()),
                ));
            }
            resolved.push(t);
        }
        let channels = if resolved.is_empty() {
            Vec::new()
        } else {
            let reference = resolved[0];
            let weights: Option<Vec<f64>> = resolved.iter().map(|t| proportional(*t, reference)).collect();
            match weights {
                Some(weights) => vec![Channel {
                    tensor: reference,
                    weights,
                }],
                None => vec![
                    Channel {
                        tensor: Isotropic { lambda: 1.0, mu: 0.0 },
                        weights: resolved.iter().map(|t| t.lambda).collect(),
                    },
                    Channel {
                        tensor: Isotropic { lambda: 0.0, mu: 1.0 },
                        weights: resolved.iter().map(|t| t.mu).collect(),
                    },
                ],
            }
        };
        Ok(Memory {
            terms,
            channels,
            from_relaxation_modulus: false,
        })
    }

    /// The paper's form B(s) = b(s) I.
    pub fn identity(kernel: RelaxationKernel, elasticity: &Elasticity) -> Memory {
        Memory::new(
            vec![MemoryTerm {
                kernel,
                tensor: MemoryTensor::Identity,
            }],
            elasticity,
        )
        .expect("the identity is a valid memory tensor")
    }

    /// The memory of a relaxation modulus with bulk κ(t) and shear G(t) (Prony series), and
    /// the elasticity A = (κ(0), G(0)) it goes with (docs/method.md §15.2):
    ///
    /// ```text
    ///   σ(t) = ∫₀ᵗ 2G(t−s) dev ε̇ + κ(t−s) tr ε̇ I ds = A ε(t) + ∫₀ᵗ B(t−s) ε(s) ds,
    ///   B(s) = (λ, μ) = (κ′(s) − 2G′(s)/3, G′(s)),
    /// ```
    ///
    /// one term per distinct relaxation time τ: b(s) = −e^{−s/τ}/τ on the tensor with the
    /// moduli (κ_τ, G_τ) of that τ — so a relaxing material has negative kernels. Bulk and shear
    /// relaxing proportionally (κ_τ/κ(0) = G_τ/G(0) for every τ) give one channel ∝ A, also in
    /// plane stress. `None` when no term relaxes (a purely elastic material).
    pub fn from_relaxation_modulus(
        bulk: &Prony,
        shear: &Prony,
        plane: Option<PlaneModel>,
    ) -> Result<(Elasticity, Option<Memory>), String> {
        let (k0, g0) = (bulk.value(0.0), shear.value(0.0));
        let elasticity = Elasticity {
            youngs_modulus: 9.0 * k0 * g0 / (3.0 * k0 + g0),
            poisson_ratio: (3.0 * k0 - 2.0 * g0) / (2.0 * (3.0 * k0 + g0)),
            plane,
        };
        // (τ, κ_τ, G_τ) over the distinct relaxation times, in the order of first appearance
        let mut times: Vec<(f64, f64, f64)> = Vec::new();
        for (&(f, tau), is_bulk) in bulk
            .terms
            .iter()
            .map(|t| (t, true))
            .chain(shear.terms.iter().map(|t| (t, false)))
        {
            let at = match times.iter().position(|(t, _, _)| *t == tau) {
                Some(p) => p,
                None => {
                    times.push((tau, 0.0, 0.0));
                    times.len() - 1
                }
            };
            if is_bulk {
                times[at].1 += f;
            } else {
                times[at].2 += f;
            }
        }
        if times.is_empty() {
            return Ok((elasticity, None));
        }
        let terms = times
            .iter()
            .map(|&(tau, k, g)| MemoryTerm {
                kernel: RelaxationKernel::Exponentials {
                    terms: vec![(-1.0 / tau, tau)],
                },
                tensor: MemoryTensor::Moduli { bulk: k, shear: g },
            })
            .collect();
        let mut memory = Memory::new(terms, &elasticity).map_err(|_| {
            "bulk and shear relax differently (κ_m/κ(0) ≠ G_m/G(0) at some relaxation time), which has no \
             isotropic plane-stress reduction; use material.plane = \"strain\", or proportional bulk and shear \
             terms"
                .to_string()
        })?;
        memory.from_relaxation_modulus = true;
        Ok((elasticity, Some(memory)))
    }

    /// The memories of several materials as one, for the time loop (docs/method.md §8.5): their
    /// terms one after another, and each material's channels with weights on its own terms only
    /// (zero on the others'), so that the history's accumulators are shared where relaxation
    /// times coincide. Returns it and, per channel, the index in `parts` of the memory it came
    /// from. One part is returned as it is (the same bits).
    pub fn combined(parts: &[&Memory]) -> (Memory, Vec<usize>) {
        if let [one] = parts {
            return ((*one).clone(), vec![0; one.channels.len()]);
        }
        let total: usize = parts.iter().map(|m| m.terms.len()).sum();
        let (mut terms, mut channels, mut owner) = (Vec::with_capacity(total), Vec::new(), Vec::new());
        for (p, m) in parts.iter().enumerate() {
            let offset = terms.len();
            terms.extend(m.terms.iter().cloned());
            for c in &m.channels {
                let mut weights = vec![0.0; total];
                weights[offset..offset + c.weights.len()].copy_from_slice(&c.weights);
                channels.push(Channel {
                    tensor: c.tensor,
                    weights,
                });
                owner.push(p);
            }
        }
        let memory = Memory {
            terms,
            channels,
            from_relaxation_modulus: parts.iter().all(|m| m.from_relaxation_modulus),
        };
        (memory, owner)
    }

    /// True when built from a relaxation modulus (A = G(0), B = G′).
    pub fn is_from_relaxation_modulus(&self) -> bool {
        self.from_relaxation_modulus
    }

    /// The terms b_m B_m.
    pub fn terms(&self) -> &[MemoryTerm] {
        &self.terms
    }

    /// The channels (one or two).
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// b_j(s) = Σ_m w_jm b_m(s) of channel j.
    pub fn kernel_value(&self, j: usize, s: f64) -> f64 {
        let w = &self.channels[j].weights;
        if let ([t], [w]) = (&self.terms[..], &w[..]) {
            if *w == 1.0 {
                return t.kernel.value(s); // the single-kernel path, exactly
            }
        }
        self.terms.iter().zip(w).map(|(t, w)| w * t.kernel.value(s)).sum()
    }

    /// β_j of every channel j: the share of u_n in the memory of a step of size k, so that the step
    /// matrix is K = K_A + Σ_j β_j K_j (docs/method.md §3, §20.2). With the trapezoid for every
    /// atom it is (k/2) b_j(0), computed as the uniform scheme always did; otherwise each atom's
    /// weight of u_n by its rule ([`quadrature`]).
    pub fn step_coefficients(&self, k: f64, rules: Rules) -> Vec<f64> {
        let all_trapezoid = self.terms.iter().all(|t| match &t.kernel {
            RelaxationKernel::Exponentials { .. } => rules.exponential == Quadrature::Trapezoid,
            RelaxationKernel::Polynomial { .. } => rules.polynomial == Quadrature::Trapezoid,
            RelaxationKernel::General { .. } => true,
        });
        (0..self.channels.len())
            .map(|j| {
                if all_trapezoid {
                    return 0.5 * k * self.kernel_value(j, 0.0);
                }
                self.terms
                    .iter()
                    .zip(&self.channels[j].weights)
                    .map(|(t, w)| w * term_share(&t.kernel, k, rules))
                    .sum()
            })
            .collect()
    }

    /// The memory share of the step matrix's tensor, Σ_j β_j T_j: K = K_A + Σ_j β_j K_{T_j} is the
    /// stiffness of A plus this (docs/method.md §15.3).
    pub fn step_share(&self, k: f64, rules: Rules) -> Isotropic {
        let mut s = Isotropic { lambda: 0.0, mu: 0.0 };
        for (c, beta) in self.channels.iter().zip(self.step_coefficients(k, rules)) {
            s.lambda += beta * c.tensor.lambda;
            s.mu += beta * c.tensor.mu;
        }
        s
    }

    /// The step tensor A + Σ_j β_j T_j's eigenvalues on symmetric D × D tensors, (2μ, 2μ + Dλ),
    /// each over A's: the step matrix is positive definite when both are above
    /// [`STABILITY_MARGIN`] (docs/method.md §15.3).
    pub fn step_stiffness_ratio(&self, a: Isotropic, dim: usize, k: f64, rules: Rules) -> f64 {
        let s = self.step_share(k, rules);
        let d = dim as f64;
        let (mu, lambda) = (a.mu + s.mu, a.lambda + s.lambda);
        let at0 = [2.0 * a.mu, 2.0 * a.mu + d * a.lambda];
        let at_k = [2.0 * mu, 2.0 * mu + d * lambda];
        at_k.iter()
            .zip(&at0)
            .map(|(x, x0)| x / x0)
            .fold(f64::INFINITY, f64::min)
    }

    /// With the trapezoid for every atom, the largest time step k for which the step tensor
    /// A + Σ_j (k/2) b_j(0) T_j stays positive definite (linear in k) with the margin
    /// [`STABILITY_MARGIN`]: each eigenvalue at least that fraction of A's; `None`: every k. The
    /// exact rule's share is not linear in k (and for a relaxation modulus positive for every k):
    /// ask [`Self::step_stiffness_ratio`] at the steps of the run.
    pub fn largest_stable_step(&self, a: Isotropic, dim: usize) -> Option<f64> {
        let v = self.step_share(1.0, Rules::TRAPEZOID); // the share per unit k: ½ Σ_j b_j(0) T_j
        let d = dim as f64;
        [
            (2.0 * a.mu, 2.0 * v.mu),
            (2.0 * a.mu + d * a.lambda, 2.0 * v.mu + d * v.lambda),
        ]
        .iter()
        .filter(|(_, slope)| *slope < 0.0)
        .map(|(at0, slope)| -(1.0 - STABILITY_MARGIN) * at0 / slope)
        .reduce(f64::min)
    }

    /// The long-term memory tensor Σ_j T_j ∫₀^∞ b_j: as the continuum has it (`k` None), or as the
    /// scheme sums it on steps of k: exactly with the exact rule, and with the trapezoid's
    /// weights k (b_j(0)/2 + Σ_{n≥1} b_j(nk)), which for a term c e^{−s/τ} is c τ (r/2) coth(r/2),
    /// r = k/τ: the relaxation over-integrated by about r²/12 (docs/method.md §15.3). None unless
    /// every kernel is a Prony series (the others do not decay).
    pub fn long_term_share(&self, k: Option<f64>, rules: Rules) -> Option<Isotropic> {
        let k = k.filter(|_| rules.exponential == Quadrature::Trapezoid);
        let integral = |kernel: &RelaxationKernel| match kernel {
            RelaxationKernel::Exponentials { terms } => Some(
                terms
                    .iter()
                    .map(|&(c, tau)| {
                        let half = k.map_or(0.0, |k| 0.5 * k / tau);
                        let factor = if half > 0.0 { half / half.tanh() } else { 1.0 };
                        c * tau * factor
                    })
                    .sum::<f64>(),
            ),
            _ => None,
        };
        let integrals: Vec<f64> = self.terms.iter().map(|t| integral(&t.kernel)).collect::<Option<_>>()?;
        let mut s = Isotropic { lambda: 0.0, mu: 0.0 };
        for c in &self.channels {
            let b: f64 = c.weights.iter().zip(&integrals).map(|(w, i)| w * i).sum();
            s.lambda += b * c.tensor.lambda;
            s.mu += b * c.tensor.mu;
        }
        Some(s)
    }

    /// The long-term tensor's eigenvalues on symmetric D × D tensors, (2μ, 2μ + Dλ), of A plus
    /// [`Self::long_term_share`]: the continuum's (`k` None) or the scheme's on steps of k.
    pub fn long_term_eigenvalues(&self, a: Isotropic, dim: usize, k: Option<f64>, rules: Rules) -> Option<[f64; 2]> {
        let s = self.long_term_share(k, rules)?;
        let (mu, lambda) = (a.mu + s.mu, a.lambda + s.lambda);
        Some([2.0 * mu, 2.0 * mu + dim as f64 * lambda])
    }

    /// How far (relative, the larger of the two eigenvalues) the scheme's long-term moduli on
    /// steps of k are from the continuum's; None without Prony kernels or when the continuum's
    /// long-term tensor is not positive. Zero with the exact rule.
    pub fn long_term_error(&self, a: Isotropic, dim: usize, k: f64, rules: Rules) -> Option<f64> {
        let exact = self.long_term_eigenvalues(a, dim, None, rules)?;
        if exact.iter().any(|&e| e <= 0.0) {
            return None;
        }
        let discrete = self.long_term_eigenvalues(a, dim, Some(k), rules)?;
        Some(
            discrete
                .iter()
                .zip(&exact)
                .map(|(d, e)| (d / e - 1.0).abs())
                .fold(0.0, f64::max),
        )
    }

    /// The largest step whose long-term eigenvalues are within `tolerance` (relative) of the
    /// continuum's (bisection; the trapezoid's over-integration grows with k). None where
    /// [`Self::long_term_error`] is.
    pub fn largest_accurate_step(
        &self,
        a: Isotropic,
        dim: usize,
        tolerance: f64,
        k_max: f64,
        rules: Rules,
    ) -> Option<f64> {
        let off = |k: f64| self.long_term_error(a, dim, k, rules);
        if off(k_max)? <= tolerance {
            return Some(k_max);
        }
        let (mut lo, mut hi) = (0.0, k_max);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if off(mid)? <= tolerance {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(lo)
    }

    /// The smallest relaxation time of the Prony terms (None without them).
    pub fn shortest_relaxation_time(&self) -> Option<f64> {
        self.terms
            .iter()
            .filter_map(|t| match &t.kernel {
                RelaxationKernel::Exponentials { terms } => terms.iter().map(|&(_, tau)| tau).reduce(f64::min),
                _ => None,
            })
            .reduce(f64::min)
    }

    /// True if some term is an expression kernel (no exact rule: its history is the direct sum).
    pub fn has_expression_kernel(&self) -> bool {
        self.terms
            .iter()
            .any(|t| matches!(t.kernel, RelaxationKernel::General { .. }))
    }

    /// The scalar c with every memory tensor T_j = c_j A and one channel: then K = (1 + β c) K_A
    /// for every step, a multiple of one matrix (docs/method.md §20.3). None otherwise.
    pub fn proportional_to_elasticity(&self, a: Isotropic) -> Option<f64> {
        match &self.channels[..] {
            [one] => proportional(one.tensor, a),
            _ => None,
        }
    }

    /// A one-line description: the terms, and how many channels they make.
    pub fn describe(&self) -> String {
        let terms: Vec<String> = self
            .terms
            .iter()
            .map(|t| format!("[{}]·{}", t.kernel.describe(), t.tensor.describe()))
            .collect();
        let channels = match self.channels.len() {
            1 => "one channel".to_string(),
            n => format!("{n} channels (λ and μ parts)"),
        };
        format!(
            "{}B(s) = {}; {channels}",
            if self.from_relaxation_modulus {
                "from the relaxation modulus: "
            } else {
                ""
            },
            terms.join(" + ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn material(plane: Option<PlaneModel>) -> Elasticity {
        Elasticity {
            youngs_modulus: 2.0,
            poisson_ratio: 0.3,
            plane,
        }
    }

    fn exp(c: f64, tau: f64) -> RelaxationKernel {
        RelaxationKernel::Exponentials { terms: vec![(c, tau)] }
    }

    #[test]
    fn proportional_terms_make_one_channel() {
        let e = material(Some(PlaneModel::Strain));
        let m = Memory::new(
            vec![
                MemoryTerm {
                    kernel: exp(1.0, 0.5),
                    tensor: MemoryTensor::Elasticity,
                },
                MemoryTerm {
                    kernel: exp(2.0, 0.1),
                    tensor: MemoryTensor::Moduli {
                        bulk: 3.0 * (e.lame().0 + 2.0 * e.lame().1 / 3.0),
                        shear: 3.0 * e.lame().1,
                    },
                },
            ],
            &e,
        )
        .unwrap();
        assert_eq!(m.channels().len(), 1);
        assert_eq!(m.channels()[0].tensor, e.tensor());
        assert!((m.channels()[0].weights[1] - 3.0).abs() < 1e-14);
    }

    #[test]
    fn other_terms_make_two_channels_with_the_same_tensor_sum() {
        let e = material(None);
        let m = Memory::new(
            vec![
                MemoryTerm {
                    kernel: exp(1.0, 0.5),
                    tensor: MemoryTensor::Identity,
                },
                MemoryTerm {
                    kernel: exp(-2.0, 0.1),
                    tensor: MemoryTensor::Moduli { bulk: 1.0, shear: 0.0 },
                },
            ],
            &e,
        )
        .unwrap();
        assert_eq!(m.channels().len(), 2);
        // B(s) = b₁(s) I + b₂(s) (1, 0): λ = b₂, μ = b₁/2
        for s in [0.0, 0.3] {
            let (b1, b2) = ((-s / 0.5f64).exp(), -2.0 * (-s / 0.1f64).exp());
            assert!((m.kernel_value(0, s) - b2).abs() < 1e-15);
            assert!((m.kernel_value(1, s) - 0.5 * b1).abs() < 1e-15);
        }
    }

    #[test]
    fn plane_stress_refuses_own_moduli_unless_proportional_to_a() {
        let e = material(Some(PlaneModel::Stress));
        let term = |bulk, shear| MemoryTerm {
            kernel: exp(1.0, 0.5),
            tensor: MemoryTensor::Moduli { bulk, shear },
        };
        let (i, err) = Memory::new(vec![term(1.0, 0.2)], &e).unwrap_err();
        assert!(
            i == 0 && err.contains("plane-stress") && err.contains("strain"),
            "{err}"
        );
        let (l, m) = e.lame();
        let ok = Memory::new(vec![term(2.0 * (l + 2.0 * m / 3.0), 2.0 * m)], &e).unwrap();
        let t = ok.channels()[0].tensor;
        let want = e.tensor();
        assert!((t.lambda - 2.0 * want.lambda).abs() < 1e-14 && (t.mu - 2.0 * want.mu).abs() < 1e-14);
    }

    #[test]
    fn relaxation_modulus_gives_a_and_g_prime() {
        let bulk = Prony {
            long_term: 1.0,
            terms: vec![(0.5, 0.2)],
        };
        let shear = Prony {
            long_term: 0.3,
            terms: vec![(0.4, 0.2), (0.2, 1.0)],
        };
        let (e, m) = Memory::from_relaxation_modulus(&bulk, &shear, None).unwrap();
        let a = e.tensor();
        let (k0, g0) = (1.5, 0.9);
        assert!((a.mu - g0).abs() < 1e-14 && (a.lambda - (k0 - 2.0 * g0 / 3.0)).abs() < 1e-14);
        let m = m.unwrap();
        assert_eq!(m.channels().len(), 2);
        // λ(s) = κ′ − 2G′/3, μ(s) = G′
        for s in [0.0, 0.1, 2.0] {
            let dk = -0.5 / 0.2 * (-s / 0.2f64).exp();
            let dg = -0.4 / 0.2 * (-s / 0.2f64).exp() - 0.2 / 1.0 * (-s / 1.0f64).exp();
            assert!((m.kernel_value(0, s) - (dk - 2.0 * dg / 3.0)).abs() < 1e-14);
            assert!((m.kernel_value(1, s) - dg).abs() < 1e-14);
        }
        // the shear modulus of the step tensor vanishes at k = 2 G(0) / Σ G_m/τ_m
        let k = m.largest_stable_step(a, 3).unwrap();
        let shear_bound = 2.0 * g0 / (0.4 / 0.2 + 0.2);
        let bulk_bound = 2.0 * (3.0 * k0) / (3.0 * 0.5 / 0.2);
        let want = (1.0 - STABILITY_MARGIN) * shear_bound.min(bulk_bound);
        assert!((k - want).abs() < 1e-14, "{k} vs {want}");
    }
}
