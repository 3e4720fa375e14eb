//! The memory term of the trapezoidal rule (docs/method.md §2–3, §5):
//!
//! ```text
//!     h_n = k Σ_{i=0}^{n−1} ω_i b(t_n − t_i) u_i,    ω_0 = ½, ω_i = 1 (i ≥ 1),
//! ```
//!
//! so that step n solves (K_A + (k/2) b(0) K_B) u_n = F_n − K_B h_n; with several memory channels
//! (docs/method.md §15) one h_n^j per channel j, each from its own kernel b_j. The kernels'
//! structure picks the algorithm, per *atom* of all of them (each distinct τ, each degree, each
//! expression), whose accumulators the channels share:
//!
//! * Prony series b(s) = Σ c_m e^{−s/τ_m}: accumulators H^m_n = Σ_{i<n} ω_i e^{−(t_n−t_i)/τ_m} u_i
//!   with H^m_{n+1} = e^{−k/τ_m}(H^m_n + ω_n u_n) — exact, O(#terms · n_dof) memory.
//! * Polynomials b(s) = Σ a_j s^j: moments P_j(n) = Σ_{i<n} ω_i (t_n − t_i)^j u_i with the
//!   binomial shift P_j(n+1) = Σ_{l≤j} C(j,l) k^{j−l} (P_l(n) + δ_{l0} ω_n u_n) — exact up to
//!   round-off, all coefficients positive (no cancellation), O(degree · n_dof) memory.
//! * Any other kernel: the direct sum over all stored u_i (exact, O(N) memory and work per step).

use crate::material::{Memory, RelaxationKernel};

/// What channel j takes of each accumulated atom: its kernel b_j(s) = Σ c_τ e^{−s/τ} +
/// Σ a_d s^d + Σ w_g e_g(s) on the atoms of the whole memory (docs/method.md §15.3).
#[derive(Clone, Debug)]
struct ChannelCoefficients {
    exponential: Vec<f64>,
    polynomial: Vec<f64>,
    general: Vec<f64>,
}

/// The history term of a run with a fixed time step k: accumulators of the atoms of all the
/// memory's kernels — one per distinct relaxation time, one per monomial degree, and the stored
/// displacements if some kernel is a general expression — shared by the channels, each of
/// which combines them with its own coefficients.
#[derive(Clone, Debug)]
pub struct History {
    step: f64,
    /// Index n of the next step (h_n is ready for it).
    next: usize,
    n_dof: usize,
    /// (τ, H_n) per distinct relaxation time.
    exponentials: Vec<(f64, Vec<f64>)>,
    /// P_d(n), d = 0..=degree.
    moments: Vec<Vec<f64>>,
    /// The general kernels e_g (direct sum) and the displacements u_0, u_1, … they need.
    general: Vec<RelaxationKernel>,
    past: Vec<Vec<f64>>,
    channels: Vec<ChannelCoefficients>,
}

impl History {
    /// An empty history (before step 0) of `memory`'s channels for `n_dof` unknowns and time
    /// step `k`.
    pub fn new(memory: &Memory, n_dof: usize, k: f64) -> Self {
        let terms = memory.terms();
        let mut taus: Vec<f64> = Vec::new();
        let mut degree = 0;
        let mut general = Vec::new();
        for t in terms {
            match &t.kernel {
                RelaxationKernel::Exponentials { terms } => {
                    for (_, tau) in terms {
                        if !taus.contains(tau) {
                            taus.push(*tau);
                        }
                    }
                }
                RelaxationKernel::Polynomial { coefficients } => degree = degree.max(coefficients.len()),
                RelaxationKernel::General { .. } => general.push(t.kernel.clone()),
            }
        }
        let channels = memory
            .channels()
            .iter()
            .map(|c| {
                let mut coefficients = ChannelCoefficients {
                    exponential: vec![0.0; taus.len()],
                    polynomial: vec![0.0; degree],
                    general: Vec::new(),
                };
                for (t, &w) in terms.iter().zip(&c.weights) {
                    // w = 1 (a single kernel) keeps the kernel's own coefficients exactly
                    match &t.kernel {
                        RelaxationKernel::Exponentials { terms } => {
                            for (c, tau) in terms {
                                let at = taus.iter().position(|t| t == tau).expect("collected above");
                                coefficients.exponential[at] += w * c;
                            }
                        }
                        RelaxationKernel::Polynomial { coefficients: a } => {
                            for (d, a) in a.iter().enumerate() {
                                coefficients.polynomial[d] += w * a;
                            }
                        }
                        RelaxationKernel::General { .. } => coefficients.general.push(w),
                    }
                }
                coefficients
            })
            .collect();
        History {
            step: k,
            next: 0,
            n_dof,
            exponentials: taus.into_iter().map(|tau| (tau, vec![0.0; n_dof])).collect(),
            moments: vec![vec![0.0; n_dof]; degree],
            general,
            past: Vec::new(),
            channels,
        }
    }

    /// How the history is accumulated: "recursive (exponential accumulators)", "recursive
    /// (polynomial moments)", both, "direct sum", or a recursion and the direct sum.
    pub fn algorithm(&self) -> String {
        let recursive: Vec<&str> = [
            (!self.exponentials.is_empty()).then_some("exponential accumulators"),
            (!self.moments.is_empty()).then_some("polynomial moments"),
        ]
        .into_iter()
        .flatten()
        .collect();
        match (recursive.is_empty(), self.general.is_empty()) {
            (false, true) => format!("recursive ({})", recursive.join(" + ")),
            (true, _) => "direct sum".to_string(),
            (false, false) => format!("recursive ({}) + direct sum", recursive.join(" + ")),
        }
    }

    /// Bytes of displacement history held now.
    pub fn bytes_held(&self) -> usize {
        let vectors = self.exponentials.len() + self.moments.len() + self.past.len();
        vectors * self.n_dof * std::mem::size_of::<f64>()
    }

    /// The number of channels.
    pub fn channels(&self) -> usize {
        self.channels.len()
    }

    /// h_n of channel `j` for the next step n (zero for n = 0), written into `out`.
    pub fn memory_load(&self, j: usize, out: &mut [f64]) {
        let k = self.step;
        let c = &self.channels[j];
        out.iter_mut().for_each(|v| *v = 0.0);
        for (cm, (_, s)) in c.exponential.iter().zip(&self.exponentials) {
            if *cm != 0.0 {
                axpy(k * cm, s, out);
            }
        }
        for (a, p) in c.polynomial.iter().zip(&self.moments) {
            if *a != 0.0 {
                axpy(k * a, p, out);
            }
        }
        if !self.general.is_empty() {
            let n = self.next;
            for (i, u) in self.past.iter().enumerate() {
                let w = if i == 0 { 0.5 } else { 1.0 };
                let s = (n - i) as f64 * k;
                let b = match (&self.general[..], &c.general[..]) {
                    ([g], [w]) if *w == 1.0 => g.value(s),
                    _ => self.general.iter().zip(&c.general).map(|(g, w)| w * g.value(s)).sum(),
                };
                axpy(k * w * b, u, out);
            }
        }
    }

    /// Records u_n of the step just solved and advances to n + 1.
    pub fn push(&mut self, u: &[f64]) {
        let k = self.step;
        let omega = if self.next == 0 { 0.5 } else { 1.0 };
        for (tau, s) in self.exponentials.iter_mut() {
            let decay = (-k / *tau).exp();
            for (sv, uv) in s.iter_mut().zip(u) {
                *sv = decay * (*sv + omega * uv);
            }
        }
        let moments = &mut self.moments;
        if !moments.is_empty() {
            moments[0].iter_mut().zip(u).for_each(|(p, uv)| *p += omega * uv);
            // P_j(n+1) = Σ_{l ≤ j} C(j,l) k^{j−l} P_l(n) in descending j (uses old P_l, l < j).
            for j in (1..moments.len()).rev() {
                let (lower, upper) = moments.split_at_mut(j);
                let pj = &mut upper[0];
                let mut binom = 1.0;
                for l in (0..j).rev() {
                    // C(j, l) built incrementally from C(j, j) = 1.
                    binom = binom * (l + 1) as f64 / (j - l) as f64;
                    let coef = binom * k.powi((j - l) as i32);
                    axpy(coef, &lower[l], pj);
                }
            }
        }
        if !self.general.is_empty() {
            self.past.push(u.to_vec());
        }
        self.next += 1;
    }
}

fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    y.iter_mut().zip(x).for_each(|(yv, xv)| *yv += a * xv);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{Expr, KERNEL_VARIABLES};
    use crate::material::{Elasticity, MemoryTensor, MemoryTerm, PlaneModel};

    /// The reference: h_n by its definition, for scalar "displacements".
    fn direct(kernel: &dyn Fn(f64) -> f64, us: &[f64], n: usize, k: f64) -> f64 {
        (0..n)
            .map(|i| k * if i == 0 { 0.5 } else { 1.0 } * kernel((n - i) as f64 * k) * us[i])
            .sum()
    }

    fn elasticity() -> Elasticity {
        Elasticity {
            youngs_modulus: 1.0,
            poisson_ratio: 0.3,
            plane: Some(PlaneModel::Strain),
        }
    }

    fn check(memory: Memory) {
        let k = 1.0 / 64.0;
        let us: Vec<f64> = (0..200).map(|i| (0.37 * i as f64).sin() + 0.1 * i as f64 * k).collect();
        let mut h = History::new(&memory, 1, k);
        let mut out = [0.0];
        for (n, u) in us.iter().enumerate() {
            for j in 0..memory.channels().len() {
                h.memory_load(j, &mut out);
                let want = direct(&|s| memory.kernel_value(j, s), &us, n, k);
                assert!(
                    (out[0] - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "{} channel {j} n={n}: {} vs {want}",
                    h.algorithm(),
                    out[0]
                );
            }
            h.push(&[*u]);
        }
    }

    #[test]
    fn recursions_equal_direct_sum() {
        for kernel in [
            RelaxationKernel::Polynomial {
                coefficients: vec![0.25, 1.0, 1.0],
            },
            RelaxationKernel::Polynomial {
                coefficients: vec![1.0, -2.0, 0.5, 0.3],
            },
            RelaxationKernel::Exponentials {
                terms: vec![(1.0, 0.5), (0.3, 0.01), (2.0, 10.0)],
            },
        ] {
            check(Memory::identity(kernel, &elasticity()));
        }
    }

    /// Two channels from terms of every kind, sharing a relaxation time: each channel's
    /// recursion equals the direct sum of its own kernel, and the shared atoms are held once.
    #[test]
    fn channels_share_the_atoms_and_equal_their_direct_sums() {
        let term = |kernel, tensor| MemoryTerm { kernel, tensor };
        let memory = Memory::new(
            vec![
                term(
                    RelaxationKernel::Exponentials {
                        terms: vec![(-1.0, 0.5), (0.3, 0.05)],
                    },
                    MemoryTensor::Moduli { bulk: 1.0, shear: 0.0 },
                ),
                term(
                    RelaxationKernel::Exponentials {
                        terms: vec![(-2.0, 0.5)],
                    },
                    MemoryTensor::Moduli { bulk: 0.0, shear: 1.0 },
                ),
                term(
                    RelaxationKernel::Polynomial {
                        coefficients: vec![0.25, 1.0],
                    },
                    MemoryTensor::Identity,
                ),
                term(
                    RelaxationKernel::General {
                        expression: Box::new(Expr::parse("1/(1 + s)", &KERNEL_VARIABLES).unwrap()),
                    },
                    MemoryTensor::Elasticity,
                ),
            ],
            &elasticity(),
        )
        .unwrap();
        assert_eq!(memory.channels().len(), 2);
        let h = History::new(&memory, 3, 0.1);
        assert_eq!(h.exponentials.len(), 2, "τ = 0.5 is shared");
        assert_eq!(
            h.algorithm(),
            "recursive (exponential accumulators + polynomial moments) + direct sum"
        );
        check(memory);
    }
}
