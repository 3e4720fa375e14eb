//! Scalar relaxation kernels b_m(s) of the memory term B(s) = Σ_m b_m(s) B_m (docs/method.md §1,
//! §5, §15).
//!
//! The kernel's *structure* decides how the history sum is computed: polynomials and sums of
//! exponentials separate in (t_n − t_i) and admit exact O(1)-per-step recursions; anything
//! else uses the exact direct sum.

use crate::expr::Expr;

/// A scalar relaxation kernel b(s), s ≥ 0.
#[derive(Clone, Debug)]
pub enum RelaxationKernel {
    /// b(s) = Σ_j c_j s^j (the paper's (0.5 + s)² = 0.25 + s + s²).
    Polynomial { coefficients: Vec<f64> },
    /// Prony series b(s) = Σ_m c_m e^{−s/τ_m}.
    Exponentials { terms: Vec<(f64, f64)> },
    /// Any expression of s (direct sum).
    General { expression: Box<Expr> },
}

impl RelaxationKernel {
    /// b(s).
    pub fn value(&self, s: f64) -> f64 {
        match self {
            RelaxationKernel::Polynomial { coefficients } => coefficients.iter().rev().fold(0.0, |acc, c| acc * s + c),
            RelaxationKernel::Exponentials { terms } => terms.iter().map(|(c, tau)| c * (-s / tau).exp()).sum(),
            RelaxationKernel::General { expression } => expression.eval(&[s]),
        }
    }

    /// A short human-readable description.
    pub fn describe(&self) -> String {
        match self {
            RelaxationKernel::Polynomial { coefficients } => {
                let terms: Vec<String> = coefficients
                    .iter()
                    .enumerate()
                    .map(|(j, c)| match j {
                        0 => format!("{c}"),
                        1 => format!("{c}·s"),
                        _ => format!("{c}·s^{j}"),
                    })
                    .collect();
                format!("polynomial b(s) = {}", terms.join(" + "))
            }
            RelaxationKernel::Exponentials { terms } => {
                let t: Vec<String> = terms.iter().map(|(c, tau)| format!("{c}·exp(−s/{tau})")).collect();
                format!("Prony series b(s) = {}", t.join(" + "))
            }
            RelaxationKernel::General { expression } => format!("b(s) = {} (direct sum)", expression.source()),
        }
    }

    /// True when b ≡ 0 (a neutral kernel: the memory term vanishes).
    pub fn is_zero(&self) -> bool {
        match self {
            RelaxationKernel::Polynomial { coefficients } => coefficients.iter().all(|c| *c == 0.0),
            RelaxationKernel::Exponentials { terms } => terms.iter().all(|(c, _)| *c == 0.0),
            RelaxationKernel::General { .. } => false,
        }
    }
}
