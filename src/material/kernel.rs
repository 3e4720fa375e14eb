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

/// A coefficient as the plan shows it: six significant digits, in exponent form far from 1.
pub(super) fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    if (1e-3..1e5).contains(&x.abs()) {
        let digits = (5 - x.abs().log10().floor() as i32).max(0) as usize;
        let s = format!("{x:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x:.5e}")
    }
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
                        0 => short(*c),
                        1 => format!("{}·s", short(*c)),
                        _ => format!("{}·s^{j}", short(*c)),
                    })
                    .collect();
                format!("polynomial b(s) = {}", terms.join(" + "))
            }
            RelaxationKernel::Exponentials { terms } => {
                let t: Vec<String> = terms
                    .iter()
                    .map(|(c, tau)| format!("{}·exp(−s/{})", short(*c), short(*tau)))
                    .collect();
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
