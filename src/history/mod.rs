//! The memory term of the trapezoidal rule (docs/method.md §2–3, §5):
//!
//! ```text
//!     h_n = k Σ_{i=0}^{n−1} ω_i b(t_n − t_i) u_i,    ω_0 = ½, ω_i = 1 (i ≥ 1),
//! ```
//!
//! so that step n solves (K_A + (k/2) b(0) K_B) u_n = F_n − K_B h_n. The kernel's structure
//! picks the algorithm:
//!
//! * Prony series b(s) = Σ c_m e^{−s/τ_m}: accumulators H^m_n = Σ_{i<n} ω_i e^{−(t_n−t_i)/τ_m} u_i
//!   with H^m_{n+1} = e^{−k/τ_m}(H^m_n + ω_n u_n) — exact, O(#terms · n_dof) memory.
//! * Polynomials b(s) = Σ a_j s^j: moments P_j(n) = Σ_{i<n} ω_i (t_n − t_i)^j u_i with the
//!   binomial shift P_j(n+1) = Σ_{l≤j} C(j,l) k^{j−l} (P_l(n) + δ_{l0} ω_n u_n) — exact up to
//!   round-off, all coefficients positive (no cancellation), O(degree · n_dof) memory.
//! * Any other kernel: the direct sum over all stored u_i (exact, O(N) memory and work per step).

use crate::material::RelaxationKernel;

/// How the history is accumulated.
#[derive(Clone, Debug)]
enum Accumulator {
    Exponentials {
        terms: Vec<(f64, f64)>,
        sums: Vec<Vec<f64>>,
    },
    Polynomial {
        coefficients: Vec<f64>,
        moments: Vec<Vec<f64>>,
    },
    Direct {
        kernel: RelaxationKernel,
        past: Vec<Vec<f64>>,
    },
}

/// The history term of a run with a fixed time step k.
#[derive(Clone, Debug)]
pub struct History {
    step: f64,
    /// Index n of the next step (h_n is ready for it).
    next: usize,
    acc: Accumulator,
    n_dof: usize,
}

impl History {
    /// An empty history (before step 0) for `n_dof` unknowns and time step `k`.
    pub fn new(kernel: &RelaxationKernel, n_dof: usize, k: f64) -> Self {
        let acc = match kernel {
            RelaxationKernel::Exponentials { terms } => Accumulator::Exponentials {
                terms: terms.clone(),
                sums: vec![vec![0.0; n_dof]; terms.len()],
            },
            RelaxationKernel::Polynomial { coefficients } => Accumulator::Polynomial {
                coefficients: coefficients.clone(),
                moments: vec![vec![0.0; n_dof]; coefficients.len()],
            },
            RelaxationKernel::General { .. } => Accumulator::Direct {
                kernel: kernel.clone(),
                past: Vec::new(),
            },
        };
        History {
            step: k,
            next: 0,
            acc,
            n_dof,
        }
    }

    /// "recursive (exponentials)", "recursive (polynomial moments)" or "direct sum".
    pub fn algorithm(&self) -> &'static str {
        match self.acc {
            Accumulator::Exponentials { .. } => "recursive (exponential accumulators)",
            Accumulator::Polynomial { .. } => "recursive (polynomial moments)",
            Accumulator::Direct { .. } => "direct sum",
        }
    }

    /// Bytes of displacement history held now.
    pub fn bytes_held(&self) -> usize {
        let vectors = match &self.acc {
            Accumulator::Exponentials { sums, .. } => sums.len(),
            Accumulator::Polynomial { moments, .. } => moments.len(),
            Accumulator::Direct { past, .. } => past.len(),
        };
        vectors * self.n_dof * std::mem::size_of::<f64>()
    }

    /// h_n for the next step n (zero for n = 0), written into `out`.
    pub fn memory_load(&self, out: &mut [f64]) {
        let k = self.step;
        out.iter_mut().for_each(|v| *v = 0.0);
        match &self.acc {
            Accumulator::Exponentials { terms, sums } => {
                for ((c, _), s) in terms.iter().zip(sums) {
                    axpy(k * c, s, out);
                }
            }
            Accumulator::Polynomial { coefficients, moments } => {
                for (a, p) in coefficients.iter().zip(moments) {
                    axpy(k * a, p, out);
                }
            }
            Accumulator::Direct { kernel, past } => {
                let n = self.next;
                for (i, u) in past.iter().enumerate() {
                    let w = if i == 0 { 0.5 } else { 1.0 };
                    axpy(k * w * kernel.value((n - i) as f64 * k), u, out);
                }
            }
        }
    }

    /// Records u_n of the step just solved and advances to n + 1.
    pub fn push(&mut self, u: &[f64]) {
        let k = self.step;
        let omega = if self.next == 0 { 0.5 } else { 1.0 };
        match &mut self.acc {
            Accumulator::Exponentials { terms, sums } => {
                for ((_, tau), s) in terms.iter().zip(sums.iter_mut()) {
                    let decay = (-k / tau).exp();
                    for (sv, uv) in s.iter_mut().zip(u) {
                        *sv = decay * (*sv + omega * uv);
                    }
                }
            }
            Accumulator::Polynomial { moments, .. } => {
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
            Accumulator::Direct { past, .. } => past.push(u.to_vec()),
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

    /// The reference: h_n by its definition, for scalar "displacements".
    fn direct(kernel: &RelaxationKernel, us: &[f64], n: usize, k: f64) -> f64 {
        (0..n)
            .map(|i| k * if i == 0 { 0.5 } else { 1.0 } * kernel.value((n - i) as f64 * k) * us[i])
            .sum()
    }

    fn check(kernel: RelaxationKernel) {
        let k = 1.0 / 64.0;
        let us: Vec<f64> = (0..200).map(|i| (0.37 * i as f64).sin() + 0.1 * i as f64 * k).collect();
        let mut h = History::new(&kernel, 1, k);
        let mut out = [0.0];
        for (n, u) in us.iter().enumerate() {
            h.memory_load(&mut out);
            let want = direct(&kernel, &us, n, k);
            assert!(
                (out[0] - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "{} n={n}: {} vs {want}",
                h.algorithm(),
                out[0]
            );
            h.push(&[*u]);
        }
    }

    #[test]
    fn recursions_equal_direct_sum() {
        check(RelaxationKernel::Polynomial {
            coefficients: vec![0.25, 1.0, 1.0],
        });
        check(RelaxationKernel::Polynomial {
            coefficients: vec![1.0, -2.0, 0.5, 0.3],
        });
        check(RelaxationKernel::Exponentials {
            terms: vec![(1.0, 0.5), (0.3, 0.01), (2.0, 10.0)],
        });
    }
}
