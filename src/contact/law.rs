//! Normal-compliance laws j_ν of the deformable layer and their regularisation
//! (docs/method.md §4, docs/example.md (5.2)–(5.3)).
//!
//! A law is a *profile* φ(s), s ≥ 0, φ(0) = 0, scaled by S and composed with a smooth
//! "magnitude" ρ_ε(r) of the normal displacement r = u_ν:
//!
//! * odd law (the paper's):   j(r) = S φ(|r|),       ρ_ε(r) = √(r² + ε²) − ε
//! * one-sided law:           j(r) = S φ(max(r, 0)), ρ_ε(r) = (r + √(r² + ε²) − ε) / 2
//!
//! Both satisfy |ρ_ε(r) − ρ(r)| ≤ ε, so the regularised law is within O(ε) of the exact one;
//! ∂j is set-valued at r = 0 (e.g. [−Sa, Sa] for the paper's odd law), and j_ε' passes
//! through that interval smoothly over a width ~ε.

/// The profile φ of a law: value, slope μ = φ' and curvature φ''.
#[derive(Clone, Debug, PartialEq)]
pub enum ComplianceProfile {
    /// φ(s) = b s + (a − b)(1 − e^{−αs})/α, i.e. μ(s) = (a − b)e^{−αs} + b (docs/example.md (5.3)).
    Paper { a: f64, b: f64, alpha: f64 },
    /// μ(s) = s^p (classical normal compliance c·(u_ν)₊^p, with c = S), p ≥ 1.
    Power { exponent: f64 },
    /// μ piecewise linear through (s_i, μ_i), s_0 = 0 < s_1 < …, constant beyond the last
    /// point: any non-monotone law, several local maxima included (also used for tabulated laws).
    PiecewiseLinear { table: PiecewiseLinear },
}

/// A piecewise-linear μ with its exact integral φ (piecewise quadratic).
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseLinear {
    s: Vec<f64>,
    mu: Vec<f64>,
    /// φ(s_i), the integral of μ up to each breakpoint.
    phi: Vec<f64>,
}

impl PiecewiseLinear {
    /// From breakpoints (s_i, μ_i) with s_0 = 0 and s strictly increasing.
    pub fn new(points: &[(f64, f64)]) -> Result<Self, String> {
        if points.is_empty() || points[0].0 != 0.0 {
            return Err("the table must start at s = 0".into());
        }
        if points.windows(2).any(|w| w[1].0 <= w[0].0) {
            return Err("the table's s values must increase strictly".into());
        }
        if points.iter().any(|(s, m)| !s.is_finite() || !m.is_finite()) {
            return Err("the table has a non-finite entry".into());
        }
        let s: Vec<f64> = points.iter().map(|p| p.0).collect();
        let mu: Vec<f64> = points.iter().map(|p| p.1).collect();
        let mut phi = vec![0.0];
        for i in 1..s.len() {
            phi.push(phi[i - 1] + 0.5 * (mu[i] + mu[i - 1]) * (s[i] - s[i - 1]));
        }
        Ok(PiecewiseLinear { s, mu, phi })
    }

    /// (φ, μ, μ') at s ≥ 0 (μ extended by μ_0 for s < 0, by its last value beyond the table).
    fn eval(&self, s: f64) -> (f64, f64, f64) {
        if s <= 0.0 {
            return (self.mu[0] * s, self.mu[0], 0.0);
        }
        let last = self.s.len() - 1;
        if s >= self.s[last] {
            return (self.phi[last] + self.mu[last] * (s - self.s[last]), self.mu[last], 0.0);
        }
        let i = self.s.partition_point(|v| *v <= s) - 1;
        let slope = (self.mu[i + 1] - self.mu[i]) / (self.s[i + 1] - self.s[i]);
        let ds = s - self.s[i];
        (
            self.phi[i] + self.mu[i] * ds + 0.5 * slope * ds * ds,
            self.mu[i] + slope * ds,
            slope,
        )
    }
}

impl ComplianceProfile {
    /// φ(s) (analytic, also used slightly below 0 by the one-sided smoothing).
    pub fn value(&self, s: f64) -> f64 {
        match self {
            ComplianceProfile::Paper { a, b, alpha } => b * s - (a - b) * (-alpha * s).exp_m1() / alpha,
            ComplianceProfile::Power { exponent } => s.max(0.0).powf(exponent + 1.0) / (exponent + 1.0),
            ComplianceProfile::PiecewiseLinear { table } => table.eval(s).0,
        }
    }
    /// μ(s) = φ'(s).
    pub fn slope(&self, s: f64) -> f64 {
        match self {
            ComplianceProfile::Paper { a, b, alpha } => (a - b) * (-alpha * s).exp() + b,
            ComplianceProfile::Power { exponent } => s.max(0.0).powf(*exponent),
            ComplianceProfile::PiecewiseLinear { table } => table.eval(s).1,
        }
    }
    /// φ''(s).
    pub fn curvature(&self, s: f64) -> f64 {
        match self {
            ComplianceProfile::Paper { a, b, alpha } => -alpha * (a - b) * (-alpha * s).exp(),
            ComplianceProfile::Power { exponent } if s > 0.0 => exponent * s.powf(exponent - 1.0),
            ComplianceProfile::Power { .. } => 0.0,
            ComplianceProfile::PiecewiseLinear { table } => table.eval(s).2,
        }
    }
    /// A short human-readable description.
    pub fn describe(&self) -> String {
        match self {
            ComplianceProfile::Paper { a, b, alpha } => format!("paper μ-law (a = {a}, b = {b}, α = {alpha})"),
            ComplianceProfile::Power { exponent } => format!("power law μ(s) = s^{exponent}"),
            ComplianceProfile::PiecewiseLinear { table } => format!("piecewise-linear μ ({} points)", table.s.len()),
        }
    }

    /// sup_s max(0, −φ''(s)): how non-convex the profile is (relaxed monotonicity, per unit S).
    pub fn max_negative_curvature(&self) -> f64 {
        match self {
            ComplianceProfile::Paper { a, b, alpha } => (alpha * (a - b)).max(0.0),
            ComplianceProfile::Power { .. } => 0.0,
            ComplianceProfile::PiecewiseLinear { table } => table
                .s
                .windows(2)
                .zip(table.mu.windows(2))
                .map(|(s, m)| -(m[1] - m[0]) / (s[1] - s[0]))
                .fold(0.0, f64::max),
        }
    }
    /// sup_s |φ'(s)| (over the table, or at s = 1 for the unbounded power law): a force scale
    /// per unit length and unit S.
    pub fn max_slope(&self) -> f64 {
        match self {
            ComplianceProfile::Paper { a, b, .. } => a.abs().max(b.abs()),
            ComplianceProfile::Power { .. } => 1.0,
            ComplianceProfile::PiecewiseLinear { table } => table.mu.iter().fold(0.0, |a, m| a.max(m.abs())),
        }
    }
}

/// Whether the layer also pulls a separating node back (the paper's odd law) or not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symmetry {
    /// j(r) = S φ(|r|): force S μ(|r|) sign r on both sides.
    Odd,
    /// j(r) = S φ(max(r, 0)): no force in separation.
    OneSided,
}

/// A regularised normal-compliance law j_ε.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactLaw {
    pub scale: f64,
    pub profile: ComplianceProfile,
    pub symmetry: Symmetry,
    pub epsilon: f64,
}

impl ContactLaw {
    /// The odd law of constant profile μ ≡ 1 and smoothing width ε: ρ_ε(r) = √(r² + ε²) − ε, the
    /// smoothed |r| that Tresca's and Coulomb's F ρ_ε(Δu_τ) scale by the bound force F
    /// (docs/method.md §17.2).
    pub fn smoothed_magnitude(epsilon: f64) -> Self {
        ContactLaw {
            scale: 1.0,
            profile: ComplianceProfile::PiecewiseLinear {
                table: PiecewiseLinear::new(&[(0.0, 1.0)]).expect("a constant profile"),
            },
            symmetry: Symmetry::Odd,
            epsilon,
        }
    }

    /// (ρ_ε, ρ_ε', ρ_ε'') at r, computed without cancellation.
    #[inline]
    fn magnitude(&self, r: f64) -> (f64, f64, f64) {
        let eps = self.epsilon;
        let root = r.hypot(eps);
        // √(r²+ε²) − ε = r² / (√(r²+ε²) + ε)
        let excess = r * r / (root + eps);
        let curv = eps * eps / (root * root * root);
        match self.symmetry {
            Symmetry::Odd => (excess, r / root, curv),
            // (r + √(r²+ε²) − ε)/2 = (r + excess)/2
            Symmetry::OneSided => (0.5 * (r + excess), 0.5 * (1.0 + r / root), 0.5 * curv),
        }
    }

    /// j_ε(r).
    pub fn potential(&self, r: f64) -> f64 {
        self.scale * self.profile.value(self.magnitude(r).0)
    }

    /// j_ε'(r): the compliance force per unit length at normal displacement r.
    pub fn derivative(&self, r: f64) -> f64 {
        let (s, ds, _) = self.magnitude(r);
        self.scale * self.profile.slope(s) * ds
    }

    /// j_ε''(r) (may be negative: the law is non-monotone).
    pub fn second_derivative(&self, r: f64) -> f64 {
        let (s, ds, dds) = self.magnitude(r);
        self.scale * (self.profile.curvature(s) * ds * ds + self.profile.slope(s) * dds)
    }

    /// The Clarke subdifferential ∂j(r) of the *unregularised* law, as an interval.
    pub fn clarke_interval(&self, r: f64) -> (f64, f64) {
        let s = self.scale;
        match self.symmetry {
            Symmetry::Odd if r > 0.0 => (s * self.profile.slope(r), s * self.profile.slope(r)),
            Symmetry::Odd if r < 0.0 => (-s * self.profile.slope(-r), -s * self.profile.slope(-r)),
            Symmetry::Odd => (-s * self.profile.slope(0.0), s * self.profile.slope(0.0)),
            Symmetry::OneSided if r > 0.0 => (s * self.profile.slope(r), s * self.profile.slope(r)),
            Symmetry::OneSided if r < 0.0 => (0.0, 0.0),
            Symmetry::OneSided => (0.0, s * self.profile.slope(0.0)),
        }
    }

    /// α_j: the relaxed-monotonicity constant of j (S · sup(−φ'')); uniqueness of the
    /// continuous problem needs α_j c_j² < m_A (docs/method.md §1).
    pub fn relaxed_monotonicity(&self) -> f64 {
        self.scale * self.profile.max_negative_curvature()
    }

    /// A force-per-length scale of the law (S · sup|μ|), for tolerances.
    pub fn force_scale(&self) -> f64 {
        self.scale * self.profile.max_slope()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn paper(symmetry: Symmetry, epsilon: f64) -> ContactLaw {
        ContactLaw {
            scale: 0.1,
            profile: ComplianceProfile::Paper {
                a: 0.04,
                b: 0.02,
                alpha: 100.0,
            },
            symmetry,
            epsilon,
        }
    }

    #[test]
    fn piecewise_linear_integrates_its_slope() {
        let t = PiecewiseLinear::new(&[(0.0, 1.0), (0.1, 3.0), (0.2, 0.5), (0.3, 2.0)]).unwrap();
        let p = ComplianceProfile::PiecewiseLinear { table: t };
        // φ(0.3) = ∫ μ = 0.1·(1+3)/2 + 0.1·(3+0.5)/2 + 0.1·(0.5+2)/2; beyond the table μ = 2
        assert!((p.value(0.3) - 0.5).abs() < 1e-15);
        assert!((p.value(0.4) - 0.7).abs() < 1e-15);
        assert!((p.max_negative_curvature() - 25.0).abs() < 1e-12);
        assert!(PiecewiseLinear::new(&[(0.0, 1.0), (0.0, 2.0)]).is_err());
        assert!(PiecewiseLinear::new(&[(0.1, 1.0)]).is_err());
    }

    #[test]
    fn paper_potential_matches_closed_form() {
        let law = paper(Symmetry::Odd, 1e-14);
        for r in [-0.3, -0.01, 0.005, 0.2] {
            let x: f64 = f64::abs(r);
            let exact = 0.1 * (0.02 * x + 0.02 * (1.0 - (-100.0 * x).exp()) / 100.0);
            assert!((law.potential(r) - exact).abs() < 1e-15, "r = {r}");
        }
    }

    proptest! {
        /// j_ε' and j_ε'' are the derivatives of j_ε (central differences), for both symmetries.
        #[test]
        fn derivatives_are_consistent(r in -0.5f64..0.5, log_eps in -8.0f64..-2.0, odd in any::<bool>()) {
            let law = paper(if odd { Symmetry::Odd } else { Symmetry::OneSided }, 10f64.powf(log_eps));
            let h = 1e-6 * law.epsilon.max(r.abs()).max(1e-6);
            let d1 = (law.potential(r + h) - law.potential(r - h)) / (2.0 * h);
            let d2 = (law.derivative(r + h) - law.derivative(r - h)) / (2.0 * h);
            prop_assert!((d1 - law.derivative(r)).abs() <= 1e-6 * (1.0 + law.derivative(r).abs()) );
            prop_assert!((d2 - law.second_derivative(r)).abs() <= 1e-4 * (1.0 + law.second_derivative(r).abs()));
        }

        /// The regularised force lies within O(ε) of the Clarke subdifferential: away from 0 it
        /// converges to the exact force, and at any r it stays inside the interval's hull.
        #[test]
        fn regularised_force_is_close_to_clarke(r in -0.5f64..0.5, odd in any::<bool>()) {
            let eps = 1e-9;
            let law = paper(if odd { Symmetry::Odd } else { Symmetry::OneSided }, eps);
            let (lo, hi) = law.clarke_interval(r);
            let f = law.derivative(r);
            let slack = if r.abs() > 1e-6 { 1e-4 * law.scale * 0.04 } else { 1e-12 };
            let lo_hull = lo.min(law.clarke_interval(0.0).0) - slack;
            let hi_hull = hi.max(law.clarke_interval(0.0).1) + slack;
            prop_assert!(f >= lo_hull && f <= hi_hull);
            if r.abs() > 1e-6 { prop_assert!((f - lo).abs() <= 1e-3 * law.scale * 0.04 * (eps / 1e-9) + 1e-9); }
        }
    }
}
