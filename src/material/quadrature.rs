//! How the memory integral ∫₀ᵗ b(t − s) u(s) ds is integrated over one time step of size k
//! (docs/method.md §5, §20.2), per *atom* of the kernels: the exponential e^{−s/τ} and the
//! monomial s^d.
//!
//! Over the step [t_{n−1}, t_n] the integral at t_n takes `previous`·u_{n−1} + `current`·u_n, and
//! what was integrated up to t_{n−1} is carried to t_n (for an exponential, multiplied by
//! `decay` = e^{−k/τ}; for the monomials, the binomial shift of src/history). Two rules:
//!
//! * **the trapezoid** (the paper's (3.2)): previous = (k/2) b(k), current = (k/2) b(0);
//! * **exact** for a displacement linear in t over the step (Taylor, Pister & Goudreau 1970; Simo
//!   & Hughes §10.3): with r = k/τ and φ(r) = (1 − e^{−r})/r,
//!   previous = τ (φ(r) − e^{−r}), current = τ (1 − φ(r)) for e^{−s/τ}, and
//!   previous = k^{d+1}/(d + 2), current = k^{d+1}/((d + 1)(d + 2)) for s^d.
//!
//! The exact weights of an exponential add up to τ (1 − e^{−r}), so a held displacement gives
//! the integral τ (1 − e^{−t/τ}) exactly on any steps, and for every k the step's share
//! A + c τ (1 − φ(r)) T of a relaxing term (c = −G_m/τ) is G∞ + G_m φ(r) > 0: the relaxed tangent.

/// The rule of an atom (docs/method.md §20.2): `time.quadrature`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quadrature {
    /// The paper's trapezoid, order 2 in k on uniform steps.
    Trapezoid,
    /// Exact for a displacement linear over each step.
    Exact,
}

impl Quadrature {
    /// Its name in a scene and in messages.
    pub fn name(self) -> &'static str {
        match self {
            Quadrature::Trapezoid => "trapezoid",
            Quadrature::Exact => "exact",
        }
    }
}

/// The rule of each kind of atom (expressions always take the trapezoid: their history is the
/// direct sum).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rules {
    pub exponential: Quadrature,
    pub polynomial: Quadrature,
}

impl Rules {
    /// The paper's trapezoid for every atom.
    pub const TRAPEZOID: Rules = Rules {
        exponential: Quadrature::Trapezoid,
        polynomial: Quadrature::Trapezoid,
    };

    /// The rules of `time.quadrature` (None: the default, exact for exponentials and the
    /// trapezoid for polynomials, the paper's kernel).
    pub fn asked(asked: Option<Quadrature>) -> Rules {
        Rules {
            exponential: asked.unwrap_or(Quadrature::Exact),
            polynomial: asked.unwrap_or(Quadrature::Trapezoid),
        }
    }
}

/// The weights of one step for one atom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepWeights {
    /// e^{−k/τ} for an exponential (1 for a monomial, whose carry is the binomial shift).
    pub decay: f64,
    /// The weight of u_{n−1}.
    pub previous: f64,
    /// The weight of u_n: the atom's share of the step matrix.
    pub current: f64,
}

/// Below this r = k/τ the exact weights are summed as series (their closed forms cancel).
const SERIES_BELOW: f64 = 0.1;

/// Σ_{n ≥ 1} (−r)^n a_n for the coefficient `a` of n (up to n = 12: r¹³/13! < 10⁻²² at r = 0.1).
fn series(r: f64, a: impl Fn(u32) -> f64) -> f64 {
    let (mut sum, mut power) = (0.0, 1.0);
    for n in 1..=12 {
        power *= -r;
        sum += power * a(n);
    }
    sum
}

fn factorial(n: u32) -> f64 {
    (1..=n).map(f64::from).product()
}

/// The weights of e^{−s/τ} on a step of size k ≥ 0.
pub fn exponential(rule: Quadrature, k: f64, tau: f64) -> StepWeights {
    let decay = (-k / tau).exp();
    match rule {
        Quadrature::Trapezoid => StepWeights {
            decay,
            previous: 0.5 * k * decay,
            current: 0.5 * k,
        },
        Quadrature::Exact => {
            let r = k / tau;
            let (previous, current) = if r < SERIES_BELOW {
                // φ − e^{−r} = Σ_{n≥1} (−r)^n (−n)/(n+1)!,  1 − φ = Σ_{n≥1} (−r)^n (−1)/(n+1)!
                (
                    series(r, |n| -f64::from(n) / factorial(n + 1)),
                    series(r, |n| -1.0 / factorial(n + 1)),
                )
            } else {
                let phi = -(-r).exp_m1() / r;
                (phi - decay, 1.0 - phi)
            };
            StepWeights {
                decay,
                previous: tau * previous,
                current: tau * current,
            }
        }
    }
}

/// The weights of s^d on a step of size k ≥ 0 (the carry of the older integral is the binomial
/// shift, done by the history).
pub fn monomial(rule: Quadrature, k: f64, d: usize) -> StepWeights {
    let kd = k.powi(d as i32);
    let (previous, current) = match rule {
        Quadrature::Trapezoid => (0.5 * k * kd, if d == 0 { 0.5 * k } else { 0.0 }),
        Quadrature::Exact => {
            let d = d as f64;
            (k * kd / (d + 2.0), k * kd / ((d + 1.0) * (d + 2.0)))
        }
    };
    StepWeights {
        decay: 1.0,
        previous,
        current,
    }
}

/// ∫₀ᵏ e^{−σ/τ} σ (k − σ) dσ = τ³ (r − 2 + (r + 2) e^{−r}): what the quadratic through
/// u_{n−2}, u_{n−1}, u_n adds to the step's integral per unit of its second divided difference
/// (with the sign −1), the local error estimate of automatic steps (docs/method.md §20.4).
pub fn exponential_curvature(k: f64, tau: f64) -> f64 {
    let r = k / tau;
    let g = if r < SERIES_BELOW {
        // Σ_{n≥3} (−1)^{n+1} (n − 2) rⁿ/n!
        -series(r, |n| if n < 3 { 0.0 } else { f64::from(n - 2) / factorial(n) })
    } else {
        r - 2.0 + (r + 2.0) * (-r).exp()
    };
    tau * tau * tau * g
}

/// ∫₀ᵏ σ^d σ (k − σ) dσ = k^{d+3}/((d + 2)(d + 3)), as [`exponential_curvature`].
pub fn monomial_curvature(k: f64, d: usize) -> f64 {
    let d = d as f64;
    k.powf(d + 3.0) / ((d + 2.0) * (d + 3.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫₀ᵏ f(σ) dσ by composite Simpson on 20 000 panels.
    fn simpson(k: f64, f: impl Fn(f64) -> f64) -> f64 {
        let n = 20000;
        let h = k / n as f64;
        (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * f(i as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0
    }

    /// The exact weights integrate e^{−σ/τ} times the linear interpolant: σ = t_n − s, so u_n
    /// has the hat 1 − σ/k and u_{n−1} the hat σ/k. Checked across the switch to the series.
    #[test]
    fn exact_exponential_weights_integrate_the_linear_interpolant() {
        let tau = 2.0;
        for r in [1e-8, 1e-4, 0.05, 0.0999, 0.1001, 0.7, 3.0, 40.0] {
            let k = r * tau;
            let w = exponential(Quadrature::Exact, k, tau);
            let kernel = |s: f64| (-s / tau).exp();
            let current = simpson(k, |s| kernel(s) * (1.0 - s / k));
            let previous = simpson(k, |s| kernel(s) * s / k);
            assert!(
                (w.current / current - 1.0).abs() < 1e-9,
                "r = {r}: {} vs {current}",
                w.current
            );
            assert!(
                (w.previous / previous - 1.0).abs() < 1e-9,
                "r = {r}: {} vs {previous}",
                w.previous
            );
            // they add up to τ (1 − e^{−r}) to round-off
            let sum = tau * -(-r).exp_m1();
            assert!(((w.current + w.previous) / sum - 1.0).abs() < 1e-14, "r = {r}");
        }
    }

    #[test]
    fn exact_monomial_weights_integrate_the_linear_interpolant() {
        let k = 0.3;
        for d in 0..4 {
            let w = monomial(Quadrature::Exact, k, d);
            let current = simpson(k, |s| s.powi(d as i32) * (1.0 - s / k));
            let previous = simpson(k, |s| s.powi(d as i32) * s / k);
            assert!((w.current - current).abs() < 1e-14, "d = {d}");
            assert!((w.previous - previous).abs() < 1e-14, "d = {d}");
        }
    }

    #[test]
    fn curvature_integrals_match_quadrature() {
        let tau = 0.5;
        for r in [1e-5, 0.05, 0.2, 5.0] {
            let k = r * tau;
            let want = simpson(k, |s| (-s / tau).exp() * s * (k - s));
            let got = exponential_curvature(k, tau);
            assert!((got / want - 1.0).abs() < 1e-9, "r = {r}: {got} vs {want}");
        }
        for d in 0..3 {
            let want = simpson(0.4, |s| s.powi(d as i32) * s * (0.4 - s));
            assert!((monomial_curvature(0.4, d) - want).abs() < 1e-14);
        }
    }

    /// The trapezoid's weights are the paper's: (k/2) b(k) and (k/2) b(0).
    #[test]
    fn trapezoid_weights_are_the_papers() {
        let w = exponential(Quadrature::Trapezoid, 0.2, 0.5);
        assert_eq!(w.current, 0.1);
        assert_eq!(w.previous, 0.1 * (-0.4f64).exp());
        let m = monomial(Quadrature::Trapezoid, 0.2, 2);
        assert_eq!((m.previous, m.current), (0.5 * 0.2 * 0.2f64.powi(2), 0.0));
    }
}
