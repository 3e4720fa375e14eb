//! A viscoelastic body pressed on an elastic one and held (issue 44, docs/method.md §18 with the
//! memory of §15): two stacked blocks in frictionless contact, the upper one relaxing, the lower
//! one elastic, both on rollers so that the state is uniform — uniaxial stress in y, plane
//! strain — and the total force is that of a standard linear solid in series with a spring, which
//! the correspondence principle gives in closed form (the derivation is at `Stack`).
//!
//! What is compared, at every step of the run: the reactions of the upper top and the lower
//! bottom and the total contact force with 2σ(t) (the blocks are 2 wide); first with the scheme's
//! own scalar recursion (the trapezoid rule of docs/method.md §3 on the uniform state: exact in
//! space on P1/Q1, so the finite-element run is that recursion to round-off), then with the
//! continuum's closed form, where the only error is the trapezoid rule's: order 2 in k, with the
//! leading term predicted from the modified equation of the recursion.

mod common;

use common::{reaction, scene, stacked};
use hvi::app::{solve_in_memory, MemorySink};
use hvi::mesh::structured::CellShape;
use hvi::mesh::Mesh;
use hvi::solver::RunStats;

/// The upper (viscoelastic) block: E(0), ν (constant: bulk and shear relax alike), the relaxing
/// share g and the relaxation time τ; height h₁.
const E_UPPER: f64 = 1.0;
const NU_UPPER: f64 = 0.3;
const SHARE: f64 = 0.7;
const TAU: f64 = 0.5;
const H_UPPER: f64 = 0.5;
/// The lower (elastic) block: E₂, ν₂; height h₂ (`stacked`'s).
const E_LOWER: f64 = 2.0;
const NU_LOWER: f64 = 0.25;
const H_LOWER: f64 = 1.0;
/// The blocks' width (`stacked`'s).
const WIDTH: f64 = 2.0;
/// The top moves down by δ(t) = δ₀ min(t/t_r, 1): a ramp over t_r, then held until T.
const DELTA: f64 = 0.01;
const RAMP: f64 = 0.25;
const FINAL_TIME: f64 = 2.0;

/// The plane-strain modulus of uniaxial stress (σ_xx = 0, ε_zz = 0): σ_yy = E/(1 − ν²) ε_yy.
fn uniaxial_modulus(e: f64, nu: f64) -> f64 {
    e / (1.0 - nu * nu)
}

/// The stack and its closed form.
///
/// **The model.** With bulk and shear relaxing alike, κ(t) = κ₀φ(t), G(t) = G₀φ(t),
/// φ(t) = 1 − g + g e^{−t/τ}, the Laplace transforms of all moduli are their t = 0 values times
/// sφ̂(s): ν is constant and the plane-strain uniaxial modulus of the upper block is
/// M(t) = M₀φ(t) = M∞ + M₁e^{−t/τ}, M₀ = E/(1 − ν²), M∞ = (1 − g)M₀, M₁ = gM₀ (its lateral strain
/// is −ν/(1 − ν) ε_yy at every t, so the rollers and the free sides keep the state uniform). The
/// lower block is a spring M₂ = E₂/(1 − ν₂²). In series (ε₁, ε₂ the compressive strains, σ the
/// compressive stress, uniform through both blocks, frictionless interface):
///
///   σ = M ∗ dε₁ (Stieltjes, from t = 0⁻),   σ = M₂ε₂,   h₁ε₁ + h₂ε₂ = δ(t).
///
/// **Laplace.** σ̂ = sM̂ ε̂₁ = M₂ ε̂₂ and δ̂ = h₁ε̂₁ + h₂ε̂₂ = σ̂ (h₁/(sM̂) + h₂/M₂), with
/// sM̂ = (M₀s + M∞/τ)/(s + 1/τ):
///
///   σ̂ = δ̂ · M₂(M₀s + M∞/τ) / [(h₁M₂ + h₂M₀) s + (h₁M₂ + h₂M∞)/τ] = δ̂ · sŜ(s),
///
///   sŜ(s) = (S₀s + S∞/τ′)/(s + 1/τ′),   i.e.   S(t) = S∞ + (S₀ − S∞) e^{−t/τ′},
///
///   S₀ = M₀M₂/(h₁M₂ + h₂M₀),   S∞ = M∞M₂/(h₁M₂ + h₂M∞),   τ′ = τ (h₁M₂ + h₂M₀)/(h₁M₂ + h₂M∞):
///
/// the series is again a standard linear solid, its moduli the springs' in series at t = 0 and at
/// t = ∞ and its relaxation time longer than τ. (For h₁ = h₂ = 1 these are tests/materials.rs's
/// bonded halves.) σ = S ∗ dδ; for the ramp, δ̇ = δ₀/t_r on (0, t_r) and 0 after:
///
///   t ≤ t_r:  σ(t) = (δ₀/t_r) [S∞ t + (S₀ − S∞) τ′ (1 − e^{−t/τ′})],
///   t ≥ t_r:  σ(t) = (δ₀/t_r) [S∞ t_r + (S₀ − S∞) τ′ (e^{−(t−t_r)/τ′} − e^{−t/τ′})].
///
/// **The scheme's leading error** (what bounds the comparison). With q(t) = ∫₀ᵗ e^{−(t−s)/τ} ε₁ ds,
/// σ = M₀(ε₁ − (g/τ) q) and ε₁ = (δ + c g q/τ)/(h₁ + c), c = h₂M₀/M₂, so q′ = −q/τ′ + δ/(h₁ + c).
/// The scheme's Q_n = k Σ'_{i≤n} e^{−(t_n−t_i)/τ} ε₁,ᵢ obeys Q_n = aQ_{n−1} + (k/2)(aε_{n−1} + ε_n),
/// a = e^{−k/τ}: the exact step of that ODE with its forcing integral ∫ e^{−(t_n−s)/τ} ε₁(s) ds taken
/// by the trapezoid rule, which adds (k³/12) F″ per step, F″ = ε₁/τ² + 2ε₁′/τ + ε₁″. The error
/// E = Q − q then follows E′ = −E/τ′ + (k²/12) F″(t) (t_r is on every grid, so the kink of ε₁ falls
/// between steps and adds nothing), and the stress's error is
///
///   σ_k − σ ≈ −M₀ (g/τ) h₁/(h₁ + c) · (k²/12) ∫₀ᵗ e^{−(t−s)/τ′} F″(s) ds,
///
/// O(k²) with an O(k⁴) remainder. The test computes this integral (Simpson's rule per smooth
/// piece) and checks the measured error against it.
struct Stack {
    m0: f64,
    m2: f64,
    s0: f64,
    s_inf: f64,
    tau_series: f64,
}

impl Stack {
    fn new() -> Self {
        let m0 = uniaxial_modulus(E_UPPER, NU_UPPER);
        let m_inf = (1.0 - SHARE) * m0;
        let m2 = uniaxial_modulus(E_LOWER, NU_LOWER);
        let series = |m: f64| m * m2 / (H_UPPER * m2 + H_LOWER * m);
        Stack {
            m0,
            m2,
            s0: series(m0),
            s_inf: series(m_inf),
            tau_series: TAU * (H_UPPER * m2 + H_LOWER * m0) / (H_UPPER * m2 + H_LOWER * m_inf),
        }
    }

    /// The prescribed squeeze δ(t) and its rate.
    fn delta(t: f64) -> (f64, f64) {
        if t < RAMP {
            (DELTA * t / RAMP, DELTA / RAMP)
        } else {
            (DELTA, 0.0)
        }
    }

    /// The closed form's compressive stress σ(t) and its first two derivatives (one-sided at t_r:
    /// from the left up to t_r, then from the right).
    fn stress(&self, t: f64) -> [f64; 3] {
        let (rate, tau) = (DELTA / RAMP, self.tau_series);
        let s1 = self.s0 - self.s_inf;
        if t <= RAMP {
            let decay = (-t / tau).exp();
            [
                rate * (self.s_inf * t + s1 * tau * (1.0 - decay)),
                rate * (self.s_inf + s1 * decay),
                -rate * s1 / tau * decay,
            ]
        } else {
            let d = (-(t - RAMP) / tau).exp() - (-t / tau).exp();
            [
                rate * (self.s_inf * RAMP + s1 * tau * d),
                -rate * s1 * d,
                rate * s1 * d / tau,
            ]
        }
    }

    /// F″ = ε₁/τ² + 2ε₁′/τ + ε₁″ of the upper strain ε₁ = (δ − h₂σ/M₂)/h₁ (δ″ = 0 on each piece).
    fn forcing_curvature(&self, t: f64) -> f64 {
        let [s, ds, dds] = self.stress(t);
        let (d, dd) = Stack::delta(t);
        let e = (d - H_LOWER * s / self.m2) / H_UPPER;
        let de = (dd - H_LOWER * ds / self.m2) / H_UPPER;
        let dde = -H_LOWER * dds / self.m2 / H_UPPER;
        e / (TAU * TAU) + 2.0 * de / TAU + dde
    }

    /// The leading term of the scheme's stress error at t on steps of size k (the doc comment
    /// above): ∫₀ᵗ e^{−(t−s)/τ′} F″(s) ds by Simpson's rule on (0, min(t, t_r)) and (t_r, t).
    fn leading_error(&self, k: f64, t: f64) -> f64 {
        let weight = |s: f64| (-(t - s) / self.tau_series).exp() * self.forcing_curvature(s);
        let simpson = |a: f64, b: f64| {
            let n = 400;
            let h = (b - a) / n as f64;
            let inner: f64 = (1..n)
                .map(|i| (if i % 2 == 1 { 4.0 } else { 2.0 }) * weight(a + i as f64 * h))
                .sum();
            // the end points from inside their piece (F″ jumps at t_r)
            let ends = weight(a + 1e-12 * (b - a)) + weight(b - 1e-12 * (b - a));
            h / 3.0 * (ends + inner)
        };
        let integral = if t <= RAMP {
            simpson(0.0, t)
        } else {
            simpson(0.0, RAMP) + simpson(RAMP, t)
        };
        let c = H_LOWER * self.m0 / self.m2;
        -self.m0 * SHARE / TAU * H_UPPER / (H_UPPER + c) * k * k / 12.0 * integral
    }

    /// The scheme's compressive stress σ_n, n = 0 … N: hvi's step (docs/method.md §3) on the
    /// uniform state, σ_n = M₀ (ε₁,ₙ + k Σ'_{i=0..n} b(t_n − t_i) ε₁,ᵢ), b(s) = −(g/τ) e^{−s/τ}
    /// (the trapezoid weights ½ at i = 0 and i = n; step 0 has no history), with
    /// h₁ε₁,ₙ + h₂σ_n/M₂ = δ(t_n) solved for ε₁,ₙ at each step.
    fn scheme(&self, steps: usize) -> Vec<f64> {
        let k = FINAL_TIME / steps as f64;
        let b = |s: f64| -SHARE / TAU * (-s / TAU).exp();
        let c = H_LOWER * self.m0 / self.m2;
        let mut strain: Vec<f64> = Vec::with_capacity(steps + 1);
        let mut stress = Vec::with_capacity(steps + 1);
        for n in 0..=steps {
            let delta = Stack::delta(n as f64 * k).0;
            let (own, history) = if n == 0 {
                (1.0, 0.0)
            } else {
                let history: f64 = (0..n)
                    .map(|i| k * if i == 0 { 0.5 } else { 1.0 } * b((n - i) as f64 * k) * strain[i])
                    .sum();
                (1.0 + 0.5 * k * b(0.0), history)
            };
            let e = (delta - c * history) / (H_UPPER + c * own);
            strain.push(e);
            stress.push(self.m0 * (own * e + history));
        }
        stress
    }
}

/// `common::stacked` (a cell group per body, "Lower" and "Upper", for their `[[materials]]`
/// entries) with the upper block squeezed to height h₁.
fn two_bodies(lower: (usize, usize, CellShape), upper: (usize, usize, CellShape)) -> Mesh<2> {
    let mut mesh = stacked(lower, upper, 1.0);
    for p in mesh.points.iter_mut().filter(|p| p[1] > 1.0 + 1e-12) {
        p[1] = 1.0 + H_UPPER * (p[1] - 1.0);
    }
    mesh
}

/// The scene: the lower block elastic, the upper one relaxing (κ and G ∝ φ), both left sides on
/// rollers (u_x = 0), the lower bottom u_y = 0, the upper top u_y = −δ(t), the right sides free;
/// the upper bottom (slave) against the lower top (master), frictionless. The memory on the
/// paper's trapezoid (`time.quadrature`), whose modified equation the checks predict.
fn text(steps: usize) -> String {
    let (k0, g0) = (
        E_UPPER / (3.0 * (1.0 - 2.0 * NU_UPPER)),
        E_UPPER / (2.0 * (1.0 + NU_UPPER)),
    );
    let series = |m: f64| {
        format!(
            "{{ long_term = {:e}, terms = [{{ modulus = {:e}, relaxation_time = {TAU:e} }}] }}",
            (1.0 - SHARE) * m,
            SHARE * m
        )
    };
    format!(
        "[material]\nplane = \"strain\"\n\
         [[materials]]\ngroup = \"Lower\"\nyoungs_modulus = {E_LOWER:e}\npoisson_ratio = {NU_LOWER:e}\n\
         [[materials]]\ngroup = \"Upper\"\nrelaxation_modulus = {{ bulk = {}, shear = {} }}\n\
         [time]\nfinal_time = {FINAL_TIME:e}\nsteps = {steps}\nquadrature = \"trapezoid\"\n\
         [[dirichlet]]\ngroup = \"LowerBottom\"\ncomponents = [\"y\"]\n\
         [[dirichlet]]\ngroup = \"LowerLeft\"\ncomponents = [\"x\"]\n\
         [[dirichlet]]\ngroup = \"UpperLeft\"\ncomponents = [\"x\"]\n\
         [[dirichlet]]\ngroup = \"UpperTop\"\ncomponents = [\"y\"]\nvalue = [\"-{DELTA:e}*min(t/{RAMP:e}, 1)\"]\n\
         [[contact]]\ngroup = \"UpperBottom\"\ntarget = \"LowerTop\"\n",
        series(k0),
        series(g0)
    )
}

/// Per step: (t, the total contact force, the lower bottom's reaction, minus the upper top's).
fn forces(stats: &RunStats, sink: &MemorySink) -> Vec<(f64, f64, f64, f64)> {
    sink.steps
        .iter()
        .map(|s| {
            let contact: f64 = s.contact.as_ref().map_or(0.0, |c| c.force.iter().sum());
            (
                s.time,
                contact,
                reaction(stats, "LowerBottom", "y", s.time),
                -reaction(stats, "UpperTop", "y", s.time),
            )
        })
        .collect()
}

/// Each body's balance at every step: the contact force on the lower body is its bottom's
/// reaction, the one on the upper body its top's, to 1e-10 of the largest force (the reactions are
/// the residuals of the step equations with the memory displacement, docs/method.md §7.5, so only
/// round-off separates them).
fn assert_balance(what: &str, forces: &[(f64, f64, f64, f64)]) {
    let scale = forces.iter().map(|f| f.1).fold(0.0, f64::max);
    assert!(scale > 0.0, "{what}: no contact force");
    let worst = forces
        .iter()
        .map(|&(_, c, b, t)| (c - b).abs().max((c - t).abs()))
        .fold(0.0, f64::max);
    eprintln!(
        "{what}: balance of each body to {:.2e} of the largest force",
        worst / scale
    );
    for &(t, contact, bottom, top) in forces {
        assert!(
            (contact - bottom).abs() <= 1e-10 * scale && (contact - top).abs() <= 1e-10 * scale,
            "{what}, t = {t}: contact force {contact:e}, lower bottom {bottom:e}, upper top {top:e}"
        );
    }
}

/// Matching meshes (the interface's 8 edges on both sides; Q1 below, P1 above): N = 40, 80, 160
/// steps on [0, 2] (k = 0.05 … 0.0125, t_r = 0.25 a node of each grid, k/τ′ ≤ 0.065).
///
/// 1. Each body's balance at every step (`assert_balance`).
/// 2. The three forces are 2σ_n of the scheme's scalar recursion (`Stack::scheme`) to 1e-10 of the
///    largest: the uniform state is exact on P1/Q1 and the node-to-segment rows are exact on
///    matching meshes, so nothing but round-off may remain (measured ≤ 4e-15, and each body's
///    balance to 3e-15).
/// 3. Against the closed form, the error is the trapezoid rule's: at every step it is the
///    predicted leading term (`Stack::leading_error`) up to the O(k⁴) remainder, about (k/τ′)²
///    of it (2.6e-4 on the finest grid; Simpson's rule on 400 intervals adds ≲ 1e-9), asserted
///    to 1e-3 of its largest value on the finest grid. Hence the largest error over the steps
///    falls by 4 (1 + ρ(k))/(1 + ρ(k/2)) when k halves, ρ ≈ (k/τ′)² ≲ 4e-3, i.e. by 4 within
///    ±0.05 (an order-1 slip, e.g. a rectangle rule or a dropped half weight, would give 2),
///    and on the finest grid the absolute error is below 1.001 times the largest predicted term.
///    Measured: errors 1.48e-5, 3.70e-6, 9.24e-7 (the last 4.6e-5 of the largest force 2.0e-2),
///    ratios 4.0009 and 4.0002, measured − predicted 1.8e-5 of the predicted term.
#[test]
fn a_relaxing_block_pressed_on_an_elastic_one_relaxes_as_a_solid_in_series() {
    let stack = Stack::new();
    let start = std::time::Instant::now();
    let mut errors = vec![];
    let mut last = (0.0, vec![]);
    for steps in [40usize, 80, 160] {
        let (sim, stats, sink) = solve_in_memory(
            &scene(&text(steps)),
            two_bodies((8, 4, CellShape::Quad), (8, 2, CellShape::Tri)),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(sim.materials.list().len(), 2, "two materials");
        assert_eq!(sink.steps.len(), steps + 1, "every step is written");
        let forces = forces(&stats, &sink);
        assert_balance(&format!("N = {steps}"), &forces);
        let scheme = stack.scheme(steps);
        let scale = WIDTH * scheme.iter().fold(0.0f64, |m, s| m.max(s.abs()));
        let (mut off_scheme, mut error) = (0.0f64, 0.0f64);
        let mut signed = vec![];
        for (n, &(t, contact, bottom, top)) in forces.iter().enumerate() {
            let want = WIDTH * scheme[n];
            for f in [contact, bottom, top] {
                off_scheme = off_scheme.max((f - want).abs() / scale);
            }
            let exact = WIDTH * stack.stress(t)[0];
            error = error.max((top - exact).abs());
            signed.push((t, top - exact));
        }
        let k = FINAL_TIME / steps as f64;
        eprintln!(
            "N = {steps} (k = {k}): off the scheme's recursion {off_scheme:.2e} of the largest force; \
             error to the closed form {error:.4e} (force 2σ, largest {scale:.4e}), error/k² = {:.5}",
            error / (k * k)
        );
        assert!(
            off_scheme < 1e-10,
            "N = {steps}: the run is not the scheme ({off_scheme:e})"
        );
        errors.push(error);
        last = (k, signed);
    }
    let ratios = [errors[0] / errors[1], errors[1] / errors[2]];
    eprintln!("error ratios when k halves: {:.4}, {:.4}", ratios[0], ratios[1]);
    for r in ratios {
        assert!((r - 4.0).abs() < 0.05, "order 2 in k: ratio {r} (errors {errors:?})");
    }
    let (k, signed) = last;
    let predicted: Vec<f64> = signed.iter().map(|&(t, _)| WIDTH * stack.leading_error(k, t)).collect();
    let largest = predicted.iter().fold(0.0f64, |m, p| m.max(p.abs()));
    let off = signed
        .iter()
        .zip(&predicted)
        .map(|(&(_, e), p)| (e - p).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "k = {k}: measured error {:.4e}, predicted leading term up to {largest:.4e}, \
         measured − predicted up to {off:.3e} ({:.2e} of it); run time {:.2} s",
        errors[2],
        off / largest,
        start.elapsed().as_secs_f64()
    );
    assert!(
        off < 1e-3 * largest,
        "the error is not the trapezoid's leading term: {off:e} of {largest:e}"
    );
    assert!(errors[2] < 1.001 * largest, "error {:e} at k = {k}", errors[2]);
}

/// Non-matching meshes (7 edges of P1 above against 8 of Q1 below): the mortar rows pass the
/// patch test (docs/method.md §18.2), so the state stays uniform and the force is the series'
/// discrete recursion to round-off (asserted 1e-10 of the largest force) at every step, each body
/// balanced (the distance to the closed form is then the step's, as on matching meshes).
/// Node-to-segment rows were 3.8e-4 off the recursion here.
#[test]
fn non_matching_meshes_relax_as_the_series_too() {
    let stack = Stack::new();
    let steps = 80;
    let (_, stats, sink) = solve_in_memory(
        &scene(&text(steps)),
        two_bodies((8, 4, CellShape::Quad), (7, 2, CellShape::Tri)),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let forces = forces(&stats, &sink);
    assert_balance("non-matching", &forces);
    let scheme = stack.scheme(steps);
    let scale = WIDTH * scheme.iter().fold(0.0f64, |m, s| m.max(s.abs()));
    let (mut off_scheme, mut off_exact) = (0.0f64, 0.0f64);
    for (n, &(t, _, _, top)) in forces.iter().enumerate() {
        off_scheme = off_scheme.max((top - WIDTH * scheme[n]).abs() / scale);
        off_exact = off_exact.max((top - WIDTH * stack.stress(t)[0]).abs() / scale);
    }
    eprintln!(
        "non-matching, N = {steps}: force off the scheme's uniform recursion by {off_scheme:.3e}, \
         off the closed form by {off_exact:.3e} of the largest force"
    );
    assert!(off_scheme < 1e-10, "non-matching: {off_scheme:e} off the recursion");
}
