//! The memory term against closed forms. With ν = 0 in plane stress, A = E·B₀ (docs/example.md's
//! B₀ = I), so K_A = E K_B and a load F(t) = F̂ gives u(t) = φ(t) û with K_A û = F̂ and the
//! scalar Volterra equation E φ(t) + ∫₀ᵗ b(t − s) φ(s) ds = 1.

mod common;

use common::scene;
use hvi::app::solve_in_memory;
use hvi::fem::norms::fitted_order;
use hvi::mesh::structured::{rectangle, CellShape};

fn memory_scene(kernel: &str, steps: usize) -> String {
    format!(
        "[material]\nplane = \"stress\"\nyoungs_modulus = 2.0\npoisson_ratio = 0.0\n[memory]\n{kernel}\n[time]\nfinal_time = 1.0\nsteps = {steps}\n[[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"0.02\", \"-0.1\"]\n"
    )
}

/// φ_n / φ_0 from the FE run, read at the node of largest displacement.
fn amplitude_ratios(kernel: &str, steps: usize) -> Vec<f64> {
    let mesh = rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
    let (_, stats, sink) = solve_in_memory(&scene(&memory_scene(kernel, steps)), mesh).unwrap();
    // B₀ = I = A/E: every step matrix is (1 + β/E) K_A, the loaded step 0's K_A among them
    // (docs/method.md §20.3)
    assert_eq!(stats.factorisations, 1, "one factorisation, K_A's, rescaled");
    let u0 = &sink.steps[0].displacement;
    let i = (0..u0.len())
        .max_by(|a, b| u0[*a].abs().total_cmp(&u0[*b].abs()))
        .unwrap();
    sink.steps
        .iter()
        .map(|s| {
            // every dof carries the same ratio: u_n = φ_n û
            let r = s.displacement[i] / u0[i];
            let spread = s
                .displacement
                .iter()
                .zip(u0)
                .map(|(a, b)| (a - r * b).abs())
                .fold(0.0, f64::max);
            assert!(
                spread <= 1e-12 * u0[i].abs(),
                "u_n is not a multiple of u_0 (spread {spread:e})"
            );
            r
        })
        .collect()
}

/// Constant kernel b ≡ b₀: the trapezoidal rule gives φ_n = φ_0 ρⁿ with
/// ρ = (E − k b₀/2)/(E + k b₀/2) exactly (the known discrete solution), and the continuous
/// solution is e^{−b₀ t / E}: error O(k²).
#[test]
fn constant_kernel_matches_discrete_and_continuous_solutions() {
    let (e, b0) = (2.0, 3.0);
    let mut ks = vec![];
    let mut errs = vec![];
    for steps in [4, 8, 16, 32] {
        let ratios = amplitude_ratios("kind = \"polynomial\"\ncoefficients = [3.0]", steps);
        let k = 1.0 / steps as f64;
        let rho = (e - k * b0 / 2.0) / (e + k * b0 / 2.0);
        for (n, r) in ratios.iter().enumerate() {
            assert!(
                (r - rho.powi(n as i32)).abs() < 1e-12,
                "step {n}: {r} vs {}",
                rho.powi(n as i32)
            );
        }
        ks.push(k);
        errs.push((ratios[steps] - (-b0 / e).exp()).abs());
    }
    let order = fitted_order(&ks, &errs);
    assert!((order - 2.0).abs() <= 0.1, "order in k {order}, errors {errs:?}");
}

/// Prony kernel b(s) = c e^{−s/τ}: φ(t) = φ∞ + (1/E − φ∞) e^{−βt}, φ∞ = 1/(E + cτ),
/// β = c/E + 1/τ; the recursive history reaches it at order 2 in k.
#[test]
fn exponential_kernel_converges_at_order_two() {
    let (e, c, tau): (f64, f64, f64) = (2.0, 1.5, 0.4);
    let phi_inf = 1.0 / (e + c * tau);
    let beta = c / e + 1.0 / tau;
    let exact = (phi_inf + (1.0 / e - phi_inf) * (-beta).exp()) * e; // relative to φ_0 = 1/E
    let (mut ks, mut errs) = (vec![], vec![]);
    for steps in [8, 16, 32, 64] {
        let ratios = amplitude_ratios(
            "kind = \"exponential\"\nterms = [ { coefficient = 1.5, relaxation_time = 0.4 } ]",
            steps,
        );
        ks.push(1.0 / steps as f64);
        errs.push((ratios[steps] - exact).abs());
    }
    let order = fitted_order(&ks, &errs);
    assert!((order - 2.0).abs() <= 0.1, "order in k {order}, errors {errs:?}");
}

/// The same kernel given as a polynomial, as an expression (direct sum) and as a one-term
/// Prony series with τ → ∞ approximated by its polynomial: the polynomial and expression
/// routes agree to round-off.
#[test]
fn polynomial_and_expression_kernels_agree() {
    let a = amplitude_ratios("kind = \"polynomial\"\ncoefficients = [0.25, 1.0, 1.0]", 16);
    let b = amplitude_ratios("kind = \"expression\"\nexpression = \"(0.5 + s)^2\"", 16);
    assert_eq!(a.len(), b.len());
    assert!(!a.is_empty(), "no step: nothing compared");
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-12, "{x} vs {y}");
    }
}
