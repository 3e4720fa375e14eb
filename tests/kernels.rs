//! Viscoelastic kernels with their own tensors and the relaxation modulus (docs/method.md §15):
//! relaxation and creep against closed forms on the paper's trapezoid (`time.quadrature =
//! "trapezoid"`: order 2 in k, 2D and 3D; the exact rule, the default for Prony terms, is tested
//! in tests/time_scales.rs), the channel reduction
//! (one channel against two channels, the identity against the default), and the errors of the
//! new keys.

#![allow(clippy::needless_range_loop)] // component loops read like the formulas

mod common;

use common::{reaction, rectangle_with_sides, scene, sub_group};
use hvi::app::{solve_in_memory, MemorySink};
use hvi::fem::norms::fitted_order;
use hvi::fem::stress::cell_stresses;
use hvi::material::{Channel, IDENTITY_TENSOR};
use hvi::mesh::structured::{block, rectangle, CellShape, SolidShape};
use hvi::mesh::Mesh;
use hvi::scene::{Scene, DEFAULT_SCENE_TOML};
use hvi::solver::Simulation;

/// A Prony series f(t) = f∞ + Σ f_m e^{−t/τ_m} and its derivative.
#[derive(Clone)]
struct Series {
    long_term: f64,
    terms: Vec<(f64, f64)>,
}

impl Series {
    fn at(&self, t: f64) -> f64 {
        self.long_term + self.terms.iter().map(|(f, tau)| f * (-t / tau).exp()).sum::<f64>()
    }
    fn rate(&self, t: f64) -> f64 {
        self.terms.iter().map(|(f, tau)| -f / tau * (-t / tau).exp()).sum()
    }
    fn toml(&self) -> String {
        let terms: Vec<String> = self
            .terms
            .iter()
            .map(|(f, tau)| format!("{{ modulus = {f:e}, relaxation_time = {tau:e} }}"))
            .collect();
        format!("{{ long_term = {:e}, terms = [{}] }}", self.long_term, terms.join(", "))
    }
}

/// `[material]` with a relaxation modulus (bulk κ(t), shear G(t)); `plane` None in 3D.
fn relaxing_material(plane: Option<&str>, bulk: &Series, shear: &Series) -> String {
    format!(
        "[material]\n{}relaxation_modulus = {{ bulk = {}, shear = {} }}\n",
        plane.map_or(String::new(), |p| format!("plane = \"{p}\"\n")),
        bulk.toml(),
        shear.toml()
    )
}

/// The trapezoidal rule k Σ'_{i=0..n} f(t_n − t_i) of ∫₀^{t_n} f (what the scheme computes).
fn trapezoid(f: &dyn Fn(f64) -> f64, n: usize, k: f64) -> f64 {
    if n == 0 {
        return 0.0;
    }
    k * (0.5 * f(0.0) + (1..n).map(|i| f(i as f64 * k)).sum::<f64>() + 0.5 * f(n as f64 * k))
}

/// Observed order between the last two of (k, error) pairs.
fn last_order(ks: &[f64], errs: &[f64]) -> f64 {
    let n = ks.len();
    (errs[n - 2] / errs[n - 1]).ln() / (ks[n - 2] / ks[n - 1]).ln()
}

/// Prints and checks an order-2 convergence in k. The tolerance ±0.1: the error is the
/// trapezoidal rule's, (k²/12)(f′(t) − f′(0)) + O(k⁴) for smooth exponentials, and the O(k⁴)
/// part moves the observed order by about (k/τ)²/10 ≲ 0.01 at the step sizes used (k ≤ τ_min/6),
/// so a wrong scheme (order 1, e.g. a rectangle rule or a dropped half weight) is far outside.
fn assert_order_two(what: &str, ks: &[f64], errs: &[f64]) {
    let last = last_order(ks, errs);
    let fitted = fitted_order(ks, errs);
    for (k, e) in ks.iter().zip(errs) {
        eprintln!("{what}: k = {k:.5}  error {e:.4e}  error/k² = {:.5}", e / (k * k));
    }
    eprintln!("{what}: order in k, last pair {last:.4}, fitted {fitted:.4}");
    assert!((last - 2.0).abs() <= 0.1, "{what}: order {last} (errors {errs:?})");
    assert!(
        (fitted - 2.0).abs() <= 0.1,
        "{what}: fitted order {fitted} (errors {errs:?})"
    );
}

/// Prescribes `value` (expressions of x, y, z, t) in every component on `groups`.
fn prescribed(groups: &[&str], value: &[&str]) -> String {
    let comps = ["\"x\"", "\"y\"", "\"z\""][..value.len()].join(", ");
    let vals: Vec<String> = value.iter().map(|v| format!("\"{v}\"")).collect();
    groups
        .iter()
        .map(|g| {
            format!(
                "[[dirichlet]]\ngroup = \"{g}\"\ncomponents = [{comps}]\nvalue = [{}]\n",
                vals.join(", ")
            )
        })
        .collect()
}

/// The stress of every cell at the last output step, memory channels included (the output path).
fn last_cell_stresses<const D: usize>(sim: &Simulation<D>, sink: &MemorySink) -> Vec<f64> {
    let last = sink.steps.last().unwrap();
    let u = sim.dofs.to_nodal(&last.displacement);
    let memory = hvi::app::memory_fields(sim, last.memory_displacement.as_deref());
    cell_stresses(
        &sim.mesh.cells,
        &sim.mesh.points,
        &sim.materials,
        None,
        &u,
        Some(&memory),
    )
    .tensor
}

/// A standard material of the tests: bulk and shear relax with different times, shear with two.
fn two_channel_moduli() -> (Series, Series) {
    (
        Series {
            long_term: 1.0,
            terms: vec![(0.5, 0.3)],
        },
        Series {
            long_term: 0.3,
            terms: vec![(0.4, 0.2), (0.3, 1.0)],
        },
    )
}

// ---------------------------------------------------------------------------------------------
// 1. Shear relaxation

/// A simple shear u = (γ y, 0) prescribed on the whole boundary of (0,2)×(0,1) and held from
/// t = 0 (plane strain): the field is exact for every t, the stress homogeneous,
/// σ_xy(t) = G(t) γ with G(t) = G∞ + Σ G_m e^{−t/τ_m}, σ_xx = σ_yy = σ_zz = 0 (tr ε = 0).
///
/// The reaction of Gamma3 (y = 0) in x is Σ over its nodes a of ∫ σ_xj ∂_j φ_a = ∫ σ_xy ∂_y Ψ with
/// Ψ = Σ_{a on y=0} φ_a = (1 − y/h)⁺, i.e. −σ_xy · L, L = 2 (the corner nodes count in every group
/// they belong to: a reaction is an internal nodal force). Discretely σ_xy = γ (G(0) +
/// k Σ' G′(t_n − t_i)) — the trapezoidal rule of ∫ G′ = G(t) − G(0) — checked to round-off; its
/// error to the closed form is order 2 in k. The material has bulk and shear with different
/// relaxation times: two channels, of which only the μ part is strained here.
#[test]
fn shear_relaxation_matches_g_of_t_at_order_two() {
    let (bulk, shear) = two_channel_moduli();
    let gamma = 0.01;
    let length = 2.0;
    let closed = |t: f64| -length * gamma * shear.at(t);
    for shape in [CellShape::Quad, CellShape::Tri] {
        let (mut ks, mut errs) = (vec![], vec![]);
        for steps in [8usize, 16, 32, 64] {
            let text = format!(
                "{}[time]\nfinal_time = 1.0\nsteps = {steps}\nquadrature = \"trapezoid\"\n{}",
                relaxing_material(Some("strain"), &bulk, &shear),
                prescribed(&["Gamma1", "Gamma2", "Gamma3"], &[&format!("{gamma:e}*y"), "0"])
            );
            let (sim, stats, sink) = solve_in_memory(&scene(&text), rectangle(2.0, 1.0, 4, 2, shape)).unwrap();
            assert_eq!(
                sim.materials.memory().unwrap().channels().len(),
                2,
                "bulk and shear differ"
            );
            let k = 1.0 / steps as f64;
            let mut err: f64 = 0.0;
            for n in 0..=steps {
                let t = sim.time.grid().unwrap().time(n);
                let r = reaction(&stats, "Gamma3", "x", t);
                let discrete = -length * gamma * (shear.at(0.0) + trapezoid(&|s| shear.rate(s), n, k));
                assert!(
                    (r - discrete).abs() <= 1e-13 * discrete.abs(),
                    "{shape:?} N = {steps}, step {n}: reaction {r:.15e}, trapezoidal value {discrete:.15e}"
                );
                err = err.max((r - closed(t)).abs() / closed(0.0).abs());
            }
            // the memory stress of the output: σ_xy = the same value, the other components 0
            let s = last_cell_stresses(&sim, &sink);
            let want = -closed(1.0) / length;
            let trap = gamma * (shear.at(0.0) + trapezoid(&|s| shear.rate(s), steps, k));
            for c in s.chunks_exact(9) {
                assert!(
                    (c[1] - trap).abs() <= 1e-13 * want,
                    "{shape:?}: σ_xy {} vs {trap}",
                    c[1]
                );
                for i in [0, 4, 8] {
                    assert!(c[i].abs() <= 1e-15, "{shape:?}: σ_{i} = {}", c[i]);
                }
            }
            ks.push(k);
            errs.push(err);
        }
        assert_order_two(&format!("shear relaxation, {shape:?}"), &ks, &errs);
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Volumetric relaxation

/// A dilation u = ε₀ (x, y, z) prescribed on every face of the unit cube (hexahedra and
/// tetrahedra), bulk and shear relaxing with different times (two channels): dev ε = 0, so the
/// stress is the mean stress σ = κ(t) tr ε I = 3 ε₀ κ(t) I. In the channels the G′ parts of the
/// λ channel (−2G′/3 · 3ε₀) and of the μ channel (2G′ ε₀) cancel — a check that they are summed
/// right. The reaction of Gamma1 (x = 0) in x is −σ_xx (area 1, as in tests/three_d_convergence.rs);
/// discretely −3ε₀ (κ(0) + k Σ' κ′), checked to round-off; order 2 in k against the closed form.
#[test]
fn volumetric_relaxation_in_3d_matches_kappa_of_t_at_order_two() {
    let bulk = Series {
        long_term: 1.0,
        terms: vec![(0.8, 0.3)],
    };
    let shear = Series {
        long_term: 0.4,
        terms: vec![(0.5, 0.1)],
    };
    let eps0 = 0.01;
    let closed = |t: f64| -3.0 * eps0 * bulk.at(t);
    for shape in [SolidShape::Hex, SolidShape::Tet] {
        let (mut ks, mut errs) = (vec![], vec![]);
        for steps in [8usize, 16, 32, 64] {
            let e = format!("{eps0:e}");
            let text = format!(
                "{}[time]\nfinal_time = 1.0\nsteps = {steps}\nquadrature = \"trapezoid\"\n{}",
                relaxing_material(None, &bulk, &shear),
                prescribed(
                    &["Gamma1", "Gamma2", "Gamma3", "Sides"],
                    &[&format!("{e}*x"), &format!("{e}*y"), &format!("{e}*z")]
                )
            );
            let (sim, stats, sink) = solve_in_memory(&scene(&text), block([1.0; 3], [2, 2, 2], shape)).unwrap();
            assert_eq!(sim.materials.memory().unwrap().channels().len(), 2);
            let k = 1.0 / steps as f64;
            let mut err: f64 = 0.0;
            for n in 0..=steps {
                let t = sim.time.grid().unwrap().time(n);
                let r = reaction(&stats, "Gamma1", "x", t);
                let discrete = -3.0 * eps0 * (bulk.at(0.0) + trapezoid(&|s| bulk.rate(s), n, k));
                assert!(
                    (r - discrete).abs() <= 1e-12 * discrete.abs(),
                    "{shape:?} N = {steps}, step {n}: reaction {r:.15e}, trapezoidal value {discrete:.15e}"
                );
                err = err.max((r - closed(t)).abs() / closed(0.0).abs());
            }
            let s = last_cell_stresses(&sim, &sink);
            let mean = 3.0 * eps0 * (bulk.at(0.0) + trapezoid(&|s| bulk.rate(s), steps, k));
            for c in s.chunks_exact(9) {
                for i in 0..3 {
                    assert!(
                        (c[4 * i] - mean).abs() <= 1e-12 * mean,
                        "{shape:?}: σ_{i}{i} {} vs {mean}",
                        c[4 * i]
                    );
                }
                for i in [1, 2, 3, 5, 6, 7] {
                    assert!(c[i].abs() <= 1e-14 * mean, "{shape:?}: shear component {i} = {}", c[i]);
                }
            }
            ks.push(k);
            errs.push(err);
        }
        assert_order_two(&format!("volumetric relaxation 3D, {shape:?}"), &ks, &errs);
    }
}

/// The same in 2D plane strain: u = ε₀ (x, y), ε_zz = 0, so tr ε = 2ε₀ and dev ε ≠ 0:
/// σ_xx = σ_yy = 2ε₀ (κ(t) + G(t)/3), σ_zz = 2ε₀ (κ(t) − 2G(t)/3) (the out-of-plane stress of
/// the memory channels included), and the mean stress (σ_xx + σ_yy + σ_zz)/3 = κ(t) tr ε.
/// Reaction of Gamma1 (x = 0, height 1) in x: −σ_xx; order 2 in k.
#[test]
fn volumetric_relaxation_in_plane_strain_gives_the_mean_stress() {
    let (bulk, shear) = two_channel_moduli();
    let eps0 = 0.01;
    let sxx = |k: f64, g: f64| 2.0 * eps0 * (k + g / 3.0);
    let (mut ks, mut errs) = (vec![], vec![]);
    for steps in [8usize, 16, 32, 64] {
        let e = format!("{eps0:e}");
        let text = format!(
            "{}[time]\nfinal_time = 1.0\nsteps = {steps}\nquadrature = \"trapezoid\"\n{}",
            relaxing_material(Some("strain"), &bulk, &shear),
            prescribed(&["Gamma1", "Gamma2", "Gamma3"], &[&format!("{e}*x"), &format!("{e}*y")])
        );
        let (sim, stats, sink) = solve_in_memory(&scene(&text), rectangle(2.0, 1.0, 4, 2, CellShape::Quad)).unwrap();
        let k = 1.0 / steps as f64;
        let mut err: f64 = 0.0;
        for n in 0..=steps {
            let t = sim.time.grid().unwrap().time(n);
            let r = reaction(&stats, "Gamma1", "x", t);
            let (kt, gt) = (
                bulk.at(0.0) + trapezoid(&|s| bulk.rate(s), n, k),
                shear.at(0.0) + trapezoid(&|s| shear.rate(s), n, k),
            );
            assert!(
                (r + sxx(kt, gt)).abs() <= 1e-13 * sxx(kt, gt),
                "N = {steps}, step {n}: {r} vs {}",
                -sxx(kt, gt)
            );
            err = err.max((r + sxx(bulk.at(t), shear.at(t))).abs() / sxx(bulk.at(0.0), shear.at(0.0)));
        }
        let kt = bulk.at(0.0) + trapezoid(&|s| bulk.rate(s), steps, k);
        let gt = shear.at(0.0) + trapezoid(&|s| shear.rate(s), steps, k);
        for c in last_cell_stresses(&sim, &sink).chunks_exact(9) {
            let szz = 2.0 * eps0 * (kt - 2.0 * gt / 3.0);
            assert!((c[8] - szz).abs() <= 1e-13 * szz.abs(), "σ_zz {} vs {szz}", c[8]);
            let mean = (c[0] + c[4] + c[8]) / 3.0;
            assert!((mean - kt * 2.0 * eps0).abs() <= 1e-13 * mean, "mean stress {mean}");
        }
        ks.push(k);
        errs.push(err);
    }
    assert_order_two("volumetric relaxation, plane strain", &ks, &errs);
}

// ---------------------------------------------------------------------------------------------
// 3. Creep of a standard linear solid

/// The standard linear solid with proportional relaxation: κ(t) = κ₀ φ(t), G(t) = G₀ φ(t),
/// φ(t) = 1 − g (1 − e^{−t/τ}), so E(t) = E₀ φ(t) and ν is constant. B(s) = φ′(s) A₀: one channel
/// ∝ A.
const E0: f64 = 1.0;
const NU: f64 = 0.3;
const G_REL: f64 = 0.6;
const TAU: f64 = 0.5;
const SIGMA0: f64 = 0.01;

fn sls() -> (Series, Series) {
    let (k0, g0) = (E0 / (3.0 * (1.0 - 2.0 * NU)), E0 / (2.0 * (1.0 + NU)));
    let series = |m0: f64| Series {
        long_term: (1.0 - G_REL) * m0,
        terms: vec![(G_REL * m0, TAU)],
    };
    (series(k0), series(g0))
}

/// The creep function of the SLS normalised by the instantaneous compliance: under a constant
/// stress applied at t = 0, ε(t) = ε_el ψ(t) with ε_el the elastic strain of A₀ and
///   ψ(t) = E₀/E∞ − (E₀/E∞ − 1) e^{−t E∞/(E₀ τ)},   E∞ = (1 − g) E₀,
/// i.e. ε(t) = σ₀/E∞ − (σ₀/E∞ − σ₀/E₀) e^{−t E∞/(E₀τ)} for a uniaxial bar. (Laplace: the relaxation
/// φ̂(p) = (1−g)/p + g/(p + 1/τ) and the creep ψ̂ = 1/(p² φ̂), whose inverse is the above.)
fn creep(t: f64) -> f64 {
    let ratio = 1.0 / (1.0 - G_REL);
    ratio - (ratio - 1.0) * (-t * (1.0 - G_REL) / TAU).exp()
}

/// The discrete creep of the scheme: the trapezoidal Volterra equation
/// x_n + k Σ'_{i=0..n} φ′(t_n − t_i) x_i = 1 (x_0 = 1: step 0 has no history), solved directly.
fn discrete_creep(steps: usize, k: f64) -> Vec<f64> {
    let dphi = |s: f64| -G_REL / TAU * (-s / TAU).exp();
    let mut x = vec![1.0];
    for n in 1..=steps {
        let history: f64 = (0..n)
            .map(|i| k * if i == 0 { 0.5 } else { 1.0 } * dphi((n - i) as f64 * k) * x[i])
            .sum();
        x.push((1.0 - history) / (1.0 + 0.5 * k * dphi(0.0)));
    }
    x
}

/// Runs the creep problems at N = 8 … 64 steps on [0, 2] (the creep time E₀τ/E∞ = 1.25) and
/// returns (k, max over steps and nodes of |u − u_exact| / max |u_exact|); `exact(x, ψ)` is the
/// displacement at x for creep factor ψ. The scheme's own discrete value is checked to 1e-12.
fn creep_errors<const D: usize>(
    text: &dyn Fn(usize) -> String,
    mesh: &dyn Fn() -> Mesh<D>,
    exact: &dyn Fn(&[f64; D], f64) -> [f64; D],
) -> (Vec<f64>, Vec<f64>) {
    let t_end = 2.0;
    let (mut ks, mut errs) = (vec![], vec![]);
    for steps in [8usize, 16, 32, 64] {
        let (sim, _, sink) = solve_in_memory(&scene(&text(steps)), mesh()).unwrap();
        let memory = sim.materials.memory().unwrap();
        assert_eq!(memory.channels().len(), 1, "proportional relaxation: one channel");
        let a = sim.materials.list()[0].elasticity.tensor();
        let t = memory.channels()[0].tensor;
        assert!(
            (t.lambda * a.mu - t.mu * a.lambda).abs() <= 1e-12 * a.mu * a.mu,
            "the channel is ∝ A"
        );
        let k = t_end / steps as f64;
        let xs = discrete_creep(steps, k);
        let scale = sim
            .mesh
            .points
            .iter()
            .map(|p| exact(p, creep(t_end)).iter().fold(0.0f64, |m, v| m.max(v.abs())))
            .fold(0.0, f64::max);
        let mut err: f64 = 0.0;
        for s in &sink.steps {
            let u = sim.dofs.to_nodal(&s.displacement);
            for (p, u) in sim.mesh.points.iter().zip(&u) {
                let (want, scheme) = (exact(p, creep(s.time)), exact(p, xs[s.step]));
                for c in 0..D {
                    assert!(
                        (u[c] - scheme[c]).abs() <= 1e-12 * scale,
                        "N = {steps}, step {}: u_{c} = {} vs the discrete creep {}",
                        s.step,
                        u[c],
                        scheme[c]
                    );
                    err = err.max((u[c] - want[c]).abs() / scale);
                }
            }
        }
        ks.push(k);
        errs.push(err);
    }
    (ks, errs)
}

/// 2D plane strain: the block (0,2)×(0,1) on rollers (u_x = 0 on x = 0, u_y = 0 on y = 0), pulled
/// by σ₀ on x = 2, the top free: a uniaxial in-plane stress σ_xx = σ₀, σ_yy = 0. With ε_zz = 0,
/// σ_zz = ν(σ_xx + σ_yy), so ε_xx = (σ_xx − ν(σ_yy + σ_zz))/E = σ₀(1 − ν²)/E: the plane-strain
/// modulus E′ = E/(1 − ν²) (ν is constant under proportional relaxation, so E′(t) = E′₀ φ(t)), and
/// ε_yy = −ν/(1 − ν) ε_xx. Hence u = ε_xx(t) (x, −ν/(1 − ν) y) with ε_xx(t) = σ₀/E′∞ −
/// (σ₀/E′∞ − σ₀/E′₀) e^{−t E∞/(E₀τ)} = (σ₀/E′₀) ψ(t). The displacement is computed (not prescribed),
/// so the whole step — K with b(0) < 0, the history load, the channel — is exercised.
#[test]
fn creep_of_a_standard_linear_solid_in_plane_strain() {
    let (bulk, shear) = sls();
    let text = |steps: usize| {
        format!(
            "{}[time]\nfinal_time = 2.0\nsteps = {steps}\nquadrature = \"trapezoid\"\n\
             [[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\"]\n\
             [[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n\
             [[traction]]\ngroup = \"Right\"\nvalue = [\"{SIGMA0:e}\", \"0\"]\n",
            relaxing_material(Some("strain"), &bulk, &shear)
        )
    };
    let e_plane = E0 / (1.0 - NU * NU);
    for shape in [CellShape::Quad, CellShape::Tri] {
        let (ks, errs) = creep_errors(
            &text,
            &|| rectangle_with_sides(2.0, 1.0, 4, 2, shape),
            &|p: &[f64; 2], psi| {
                let exx = SIGMA0 / e_plane * psi;
                [exx * p[0], -NU / (1.0 - NU) * exx * p[1]]
            },
        );
        assert_order_two(&format!("SLS creep, plane strain {shape:?}"), &ks, &errs);
    }
    // plane stress works too for proportional relaxation (one channel ∝ A*): ε_xx = σ₀/E, ε_yy = −ν ε_xx
    let (ks, errs) = creep_errors(
        &|steps| text(steps).replace("plane = \"strain\"", "plane = \"stress\""),
        &|| rectangle_with_sides(2.0, 1.0, 4, 2, CellShape::Quad),
        &|p: &[f64; 2], psi| {
            let exx = SIGMA0 / E0 * psi;
            [exx * p[0], -NU * exx * p[1]]
        },
    );
    assert_order_two("SLS creep, plane stress", &ks, &errs);
}

/// 3D: the unit cube on rollers (u_x = 0 on x = 0, u_y = 0 on y = 0, u_z = 0 on z = 0), pulled by
/// σ₀ on x = 1, the other faces free: uniaxial stress, u = ε(t) (x, −ν y, −ν z) with
/// ε(t) = σ₀/E∞ − (σ₀/E∞ − σ₀/E₀) e^{−t E∞/(E₀τ)}.
#[test]
fn creep_of_a_standard_linear_solid_in_3d() {
    let (bulk, shear) = sls();
    let text = |steps: usize| {
        format!(
            "{}[time]\nfinal_time = 2.0\nsteps = {steps}\nquadrature = \"trapezoid\"\n\
             [[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\"]\n\
             [[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n\
             [[dirichlet]]\ngroup = \"Z0\"\ncomponents = [\"z\"]\n\
             [[traction]]\ngroup = \"X1\"\nvalue = [\"{SIGMA0:e}\", \"0\", \"0\"]\n",
            relaxing_material(None, &bulk, &shear)
        )
    };
    for shape in [SolidShape::Hex, SolidShape::Tet] {
        let mesh = || {
            let mut m = block([1.0; 3], [2, 2, 2], shape);
            sub_group(&mut m, "Gamma2", "X1", |p| (p[0] - 1.0).abs() < 1e-12);
            sub_group(&mut m, "Sides", "Z0", |p| p[2].abs() < 1e-12);
            m
        };
        let (ks, errs) = creep_errors(&text, &mesh, &|p: &[f64; 3], psi| {
            let e = SIGMA0 / E0 * psi;
            [e * p[0], -NU * e * p[1], -NU * e * p[2]]
        });
        assert_order_two(&format!("SLS creep, 3D {shape:?}"), &ks, &errs);
    }
}

// ---------------------------------------------------------------------------------------------
// 4. Equivalences

/// The paper's scene text with `[material]` (None: the paper's, in plane strain) and `[memory]`
/// replaced, `steps` steps.
fn paper_text(material: Option<&str>, memory: &str, steps: usize) -> String {
    let m = DEFAULT_SCENE_TOML.find("[material]").unwrap();
    let start = DEFAULT_SCENE_TOML.find("[memory]").unwrap();
    let end = DEFAULT_SCENE_TOML.find("[time]").unwrap();
    let paper_material = DEFAULT_SCENE_TOML[m..start].replace("plane = \"stress\"", "plane = \"strain\"");
    format!(
        "{}{}\n{memory}\n{}",
        &DEFAULT_SCENE_TOML[..m],
        material.unwrap_or(&paper_material),
        &DEFAULT_SCENE_TOML[end..]
    )
    .replace("steps = 32", &format!("steps = {steps}"))
}

/// The paper's scene with `[memory]` replaced, in plane strain (so that every tensor form is valid).
fn paper_with_memory(memory: &str, steps: usize) -> Scene {
    scene(&paper_text(None, memory, steps))
}

/// max over frames and unknowns of |u_a − u_b| and of the contact forces, relative to the
/// largest |u_a| and |λ_a|.
fn run_difference(a: &MemorySink, b: &MemorySink) -> (f64, f64) {
    let du = common::step_differences(a, b)
        .iter()
        .map(|(_, d)| *d)
        .fold(0.0, f64::max);
    let scale = a
        .steps
        .iter()
        .flat_map(|s| s.contact.as_ref().unwrap().force.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let dl = a
        .steps
        .iter()
        .zip(&b.steps)
        .flat_map(|(x, y)| {
            x.contact
                .as_ref()
                .unwrap()
                .force
                .iter()
                .zip(&y.contact.as_ref().unwrap().force)
                .map(|(p, q)| (p - q).abs())
        })
        .fold(0.0, f64::max)
        / scale;
    (du, dl)
}

fn mesh() -> Mesh<2> {
    rectangle(2.0, 1.0, 16, 8, CellShape::Quad)
}

/// `tensor = "identity"` is the default: the same single channel (I, weight 1), so the same
/// arithmetic — the runs agree exactly (asserted to 1e-12, the bound of the brief). The paper's
/// own scene takes this path: one channel on IDENTITY_TENSOR with weight 1, the polynomial
/// moments, one K_B product per step.
#[test]
fn identity_tensor_is_the_default_and_the_papers_path() {
    let paper = Scene::from_toml_str(DEFAULT_SCENE_TOML, "paper").unwrap();
    let sim = Simulation::new(&paper, mesh()).unwrap();
    let m = sim.materials.memory().unwrap();
    assert_eq!(
        m.channels(),
        &[Channel {
            tensor: IDENTITY_TENSOR,
            weights: vec![1.0]
        }]
    );
    let kernel = "[memory]\nkind = \"polynomial\"\ncoefficients = [0.25, 1.0, 1.0]\n";
    let (_, sa, a) = solve_in_memory(&paper_with_memory(kernel, 16), mesh()).unwrap();
    let (_, sb, b) = solve_in_memory(
        &paper_with_memory(&format!("{kernel}tensor = \"identity\"\n"), 16),
        mesh(),
    )
    .unwrap();
    assert_eq!(sa.history_algorithm.as_deref(), Some("recursive (polynomial moments)"));
    assert_eq!(sa.history_algorithm, sb.history_algorithm);
    let (du, dl) = run_difference(&a, &b);
    eprintln!("identity vs default: relative difference of u {du:.2e}, of contact forces {dl:.2e}");
    assert!(du <= 1e-12 && dl <= 1e-12, "{du:e} {dl:e}");
}

/// A kernel on A (`tensor = "elasticity"`, one channel) equals the same memory posed with own
/// moduli: as one tensor (κ_A, G_A) = A (recognised as ∝ A: one channel), and split into the
/// two terms (κ = λ_A, G = 0) + (κ = 2μ_A/3, G = μ_A), whose tensors (λ_A, 0) and (0, μ_A) are
/// not proportional: two channels, two K_B products, kernels λ_A b and μ_A b. Contact and the
/// paper's load: the solutions agree to 1e-12 (round-off: the two-channel run sums the same
/// stiffness from two matrices).
#[test]
fn a_kernel_on_a_equals_own_moduli_with_one_or_two_channels() {
    let kernel = "kind = \"exponential\"\nterms = [{ coefficient = 0.8, relaxation_time = 0.3 }, { coefficient = -0.2, relaxation_time = 0.05 }]\n";
    let on_a = paper_with_memory(&format!("[memory]\n{kernel}tensor = \"elasticity\"\n"), 16);
    let sim = Simulation::new(&on_a, mesh()).unwrap();
    let (l, m) = sim.materials.list()[0].elasticity.lame();
    let one = paper_with_memory(
        &format!(
            "[memory]\n{kernel}tensor = {{ bulk = {:e}, shear = {m:e} }}\n",
            l + 2.0 * m / 3.0
        ),
        16,
    );
    let two = paper_with_memory(
        &format!(
            "[[memory]]\n{kernel}tensor = {{ bulk = {l:e}, shear = 0.0 }}\n[[memory]]\n{kernel}tensor = {{ bulk = {:e}, shear = {m:e} }}\n",
            2.0 * m / 3.0
        ),
        16,
    );
    let (sa, _, a) = solve_in_memory(&on_a, mesh()).unwrap();
    assert_eq!(sa.materials.memory().unwrap().channels().len(), 1);
    for (what, s, channels) in [("one own-moduli tensor", one, 1), ("two own-moduli terms", two, 2)] {
        let (sb, stats, b) = solve_in_memory(&s, mesh()).unwrap();
        assert_eq!(sb.materials.memory().unwrap().channels().len(), channels, "{what}");
        // the two kernels share their exponential atoms: 2 accumulators, not 4, and u_{n−1}
        assert_eq!(stats.history_bytes, (2 + 1) * sb.dofs.n() * 8, "{what}");
        let (du, dl) = run_difference(&a, &b);
        eprintln!(
            "A·b vs {what} ({channels} channel(s)): relative difference of u {du:.2e}, of contact forces {dl:.2e}"
        );
        assert!(du <= 1e-12 && dl <= 1e-12, "{what}: {du:e} {dl:e}");
    }
}

/// A relaxation modulus is the memory B = G′ on A = G(0): the same as writing E₀, ν₀ by hand
/// and one `[[memory]]` term per relaxation time, b(s) = −e^{−s/τ}/τ on the tensor with that
/// time's moduli (κ_τ, G_τ) (docs/method.md §15.2). Equal to 1e-12 with contact.
#[test]
fn relaxation_modulus_equals_its_memory_written_by_hand() {
    let (bulk, shear) = two_channel_moduli();
    let relaxing = scene(&paper_text(
        Some(&relaxing_material(Some("strain"), &bulk, &shear)),
        "",
        16,
    ));
    let (sa, _, a) = solve_in_memory(&relaxing, mesh()).unwrap();
    let (k0, g0) = (bulk.at(0.0), shear.at(0.0));
    let (e, nu) = (
        9.0 * k0 * g0 / (3.0 * k0 + g0),
        (3.0 * k0 - 2.0 * g0) / (2.0 * (3.0 * k0 + g0)),
    );
    let term = |tau: f64, k: f64, g: f64| {
        format!(
            "[[memory]]\nkind = \"exponential\"\nterms = [{{ coefficient = {:e}, relaxation_time = {tau:e} }}]\ntensor = {{ bulk = {k:e}, shear = {g:e} }}\n",
            -1.0 / tau
        )
    };
    let by_hand = scene(&paper_text(
        Some(&format!(
            "[material]\nplane = \"strain\"\nyoungs_modulus = {e:e}\npoisson_ratio = {nu:e}\n"
        )),
        &[term(0.3, 0.5, 0.0), term(0.2, 0.0, 0.4), term(1.0, 0.0, 0.3)].concat(),
        16,
    ));
    let (sb, _, b) = solve_in_memory(&by_hand, mesh()).unwrap();
    assert_eq!(sa.materials.memory().unwrap().channels().len(), 2);
    assert_eq!(sb.materials.memory().unwrap().channels().len(), 2);
    let (du, dl) = run_difference(&a, &b);
    eprintln!("relaxation modulus vs by hand: relative difference of u {du:.2e}, of contact forces {dl:.2e}");
    assert!(du <= 1e-12 && dl <= 1e-12, "{du:e} {dl:e}");
}

// ---------------------------------------------------------------------------------------------
// 5. Errors

fn scene_error(text: &str) -> String {
    match Scene::from_toml_str(text, "bad.toml") {
        Ok(_) => panic!("expected an error:\n{text}"),
        Err(e) => e.to_string(),
    }
}

fn assert_contains(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "`{p}` missing from: {msg}");
    }
}

const TIME: &str = "[time]\nfinal_time = 1.0\nsteps = 4\n";

#[test]
fn bad_relaxation_moduli_name_the_key_the_value_and_the_range() {
    let good = Series {
        long_term: 1.0,
        terms: vec![(0.5, 0.2)],
    };
    let with = |bulk: &str, shear: &str| {
        format!("[material]\nplane = \"strain\"\nrelaxation_modulus = {{ bulk = {bulk}, shear = {shear} }}\n{TIME}")
    };
    let ok = good.toml();
    for (text, parts) in [
        (
            with("{ long_term = -1.0 }", &ok),
            vec!["bad.toml", "`material.relaxation_modulus.bulk.long_term` = -1", "finite and ≥ 0"],
        ),
        (
            with(&ok, "{ long_term = nan }"),
            vec!["`material.relaxation_modulus.shear.long_term` = NaN", "≥ 0"],
        ),
        (
            with(&ok, "{ long_term = 0.0 }"),
            vec!["`material.relaxation_modulus.shear.long_term` = 0", "zero at every time", "positive"],
        ),
        (
            with(&ok, "{ long_term = 1.0, terms = [{ modulus = 0.0, relaxation_time = 1.0 }] }"),
            vec!["`material.relaxation_modulus.shear.terms[0].modulus` = 0", "positive and finite"],
        ),
        (
            with(
                "{ long_term = 1.0, terms = [{ modulus = 1.0, relaxation_time = 1.0 }, { modulus = 1.0, relaxation_time = -2.0 }] }",
                &ok,
            ),
            vec!["`material.relaxation_modulus.bulk.terms[1].relaxation_time` = -2", "positive and finite"],
        ),
        (
            with(&ok, "{ long_term = 1.0, terms = [{ modulus = 1.0, relaxation_time = inf }] }"),
            vec!["`material.relaxation_modulus.shear.terms[0].relaxation_time` = inf"],
        ),
        (
            with(&ok, "{ long_time = 1.0 }"),
            vec!["unknown key `long_time`", "did you mean `long_term`?", "long_term, terms"],
        ),
        (
            with(&ok, "{ long_term = 1.0, terms = [{ modulus = 1.0, time = 1.0 }] }"),
            vec!["unknown key `time`", "modulus, relaxation_time"],
        ),
        (
            format!("[material]\nplane = \"strain\"\nrelaxation_modulus = {{ bulk = {ok} }}\n{TIME}"),
            vec!["bad.toml", "`material.relaxation_modulus` = (with bulk)", "bulk and shear", "youngs"],
        ),
        (
            format!("[material]\nplane = \"strain\"\nrelaxation_modulus = {{ youngs = {ok}, shear = {ok} }}\n{TIME}"),
            vec!["`material.relaxation_modulus` = (with shear, youngs)", "poisson_ratio = ν"],
        ),
        (
            format!("[material]\nplane = \"strain\"\nrelaxation_modulus = {{ youngs = {ok}, poisson_ratio = 0.5 }}\n{TIME}"),
            vec!["`material.relaxation_modulus.poisson_ratio` = 0.5", "(−1, 0.5)"],
        ),
        (
            format!("[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\nrelaxation_modulus = {{ bulk = {ok}, shear = {ok} }}\n{TIME}"),
            vec!["`material.youngs_modulus` = 1", "relaxation_modulus is given too", "either youngs_modulus and poisson_ratio, or relaxation_modulus"],
        ),
        (
            format!("{}[memory]\nkind = \"polynomial\"\ncoefficients = [1.0]\n", with(&ok, &ok)),
            vec!["`memory`", "relaxation_modulus is given too", "not both"],
        ),
        (
            format!("[material]\nplane = \"strain\"\npoisson_ratio = 0.3\n{TIME}"),
            vec!["`material.youngs_modulus` = (missing)", "or a relaxation_modulus"],
        ),
        (
            // plane stress with bulk and shear relaxing differently
            with(&ok, "{ long_term = 1.0, terms = [{ modulus = 1.0, relaxation_time = 0.7 }] }")
                .replace("\"strain\"", "\"stress\""),
            vec!["`material.relaxation_modulus`", "plane = \"stress\"", "relax differently", "plane = \"strain\""],
        ),
    ] {
        let msg = scene_error(&text);
        assert_contains(&msg, &parts);
    }
}

#[test]
fn bad_memory_tensors_name_the_key_the_value_and_the_range() {
    let base = |tensor: &str| {
        format!(
            "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n{TIME}\
             [memory]\nkind = \"exponential\"\nterms = [{{ coefficient = -1.0, relaxation_time = 0.5 }}]\ntensor = {tensor}\n"
        )
    };
    for (text, parts) in
        [
            (
                base("\"identiy\""),
                vec![
                    "bad.toml",
                    "memory.tensor = \"identiy\"",
                    "\"identity\"",
                    "\"elasticity\"",
                    "bulk = κ, shear = G",
                ],
            ),
            (
                base("{ bulk = 0.0, shear = 0.0 }"),
                vec!["`memory.tensor` = { bulk = 0, shear = 0 }", "not both zero"],
            ),
            (
                base("{ bulk = 1.0, shear = nan }"),
                vec!["`memory.tensor` = { bulk = 1, shear = NaN }", "finite"],
            ),
            (base("{ bulk = 1.0 }"), vec!["bad.toml", "missing field `shear`"]),
            (
                base("{ bulk = 1.0, shear = 1.0, lambda = 2.0 }"),
                vec!["unknown key `lambda`", "bulk, shear"],
            ),
            (base("3"), vec!["bad.toml", "memory.tensor"]),
            (
                // plane stress and own moduli that are not ∝ A
                base("{ bulk = 1.0, shear = 1.0 }").replace("\"strain\"", "\"stress\""),
                vec![
                    "`memory.tensor` = { bulk = 1, shear = 1 }",
                    "plane-stress",
                    "proportional to A",
                    "plane = \"strain\"",
                    "tensor = \"elasticity\"",
                ],
            ),
            (
                format!(
                "{}[[memory]]\nkind = \"polynomial\"\ncoefficients = [1.0]\ntensor = {{ bulk = 2.0, shear = 1.0 }}\n",
                base("\"elasticity\"").replace("[memory]", "[[memory]]").replace("\"strain\"", "\"stress\"")
            ),
                vec!["`memory[1].tensor` = { bulk = 2, shear = 1 }", "plane-stress"],
            ),
            (
                base("\"identity\"").replace("relaxation_time = 0.5", "relaxation_time = 0.5, tensor = \"identity\""),
                vec!["unknown key `tensor` in memory.terms[0]"],
            ),
        ]
    {
        let msg = scene_error(&text);
        assert_contains(&msg, &parts);
    }
    // own moduli ∝ A are fine in plane stress (they mean c·A*)
    let (l, m) = (1.0 * 0.3 / (1.3 * 0.4), 1.0 / 2.6);
    let text = base(&format!(
        "{{ bulk = {:e}, shear = {:e} }}",
        2.0 * (l + 2.0 * m / 3.0),
        2.0 * m
    ))
    .replace("\"strain\"", "\"stress\"");
    let s = scene(&text);
    let sim = Simulation::new(&s, rectangle(2.0, 1.0, 2, 1, CellShape::Quad)).unwrap();
    let t = sim.materials.memory().unwrap().channels()[0].tensor;
    let a = sim.materials.list()[0].elasticity.tensor();
    assert!(
        (t.lambda - 2.0 * a.lambda).abs() < 1e-14 && (t.mu - 2.0 * a.mu).abs() < 1e-14,
        "{t:?} vs 2·{a:?}"
    );
}

/// A relaxing material makes b(0) < 0 and K = K_A + (k/2) b(0) K_B softer than K_A; past the
/// bound it stops being positive definite. The shear modulus of the step tensor is
/// G(0) − (k/2) Σ G_m/τ_m: here 1 − (k/2)·6, zero at k = 1/3; the bulk part 3κ(0) − (k/2)·3Σκ_m/τ_m
/// stays positive. So T = 1 needs N > 3: N = 3 is refused naming the bound, N = 4 runs.
#[test]
fn a_time_step_too_large_for_a_relaxing_material_is_refused_with_the_bound() {
    let bulk = Series {
        long_term: 2.0,
        terms: vec![],
    };
    let shear = Series {
        long_term: 0.1,
        terms: vec![(0.9, 0.15)],
    };
    let text = |steps: usize| {
        format!(
            "{}[time]\nfinal_time = 1.0\nsteps = {steps}\nquadrature = \"trapezoid\"\n{}",
            relaxing_material(Some("strain"), &bulk, &shear),
            prescribed(&["Gamma1"], &["0", "0"])
        ) + "[[traction]]\ngroup = \"Gamma2\"\nvalue = [\"0.01\", \"0\"]\n"
    };
    let small = || rectangle(2.0, 1.0, 4, 2, CellShape::Quad);
    for steps in [1, 2, 3] {
        let err = scene_error(&text(steps));
        assert_contains(
            &err,
            &[
                "bad.toml",
                &format!("`time.steps` = {steps}"),
                "positive definite only for k < 3.33",
                "time.steps ≥ 4",
            ],
        );
    }
    // 4 steps keep K positive definite, but on k = 1.7τ the scheme's long-term shear modulus
    // G(0) − 0.9 (r/2) coth(r/2) is negative (docs/method.md §15.3): refused, naming the steps
    // that bring it within 1 % (58 here)
    assert_contains(
        &scene_error(&text(4)),
        &["`time.steps` = 4", "would grow without bound", "time.steps ≥ 58"],
    );
    let (_, stats, sink) = solve_in_memory(&scene(&text(58)), small()).unwrap();
    assert_eq!(stats.factorisations, 2);
    assert!(sink.steps.iter().all(|s| s.displacement.iter().all(|v| v.is_finite())));
    // the same check guards a scene changed in code, which the set-up checks again
    let mut changed = scene(&text(58));
    changed.time.steps = Some(3);
    let err = Simulation::new(&changed, small()).err().expect("refused").to_string();
    assert_contains(&err, &["the scene's `time.steps` = 3", "time.steps ≥ 4"]);
    // 3D: the same bound (the shear modulus limits it in any dimension)
    let text3 = |steps: usize| {
        format!(
            "{}[time]\nfinal_time = 1.0\nsteps = {steps}\nquadrature = \"trapezoid\"\n{}",
            relaxing_material(None, &bulk, &shear),
            prescribed(&["Gamma1"], &["0", "0", "0"])
        )
    };
    assert_contains(&scene_error(&text3(3)), &["`time.steps` = 3", "time.steps ≥ 4"]);
    assert!(Simulation::new(&scene(&text3(58)), block([1.0; 3], [1, 1, 1], SolidShape::Hex)).is_ok());
    // a kernel far too negative for any reasonable N says so
    let huge = format!(
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n{TIME}quadrature = \"trapezoid\"\n\
         [memory]\nkind = \"exponential\"\nterms = [{{ coefficient = -1e12, relaxation_time = 1.0 }}]\n"
    );
    assert_contains(
        &scene_error(&huge),
        &["`time.steps` = 4", "more than 10⁸ time steps", "far too negative"],
    );
    // the exact rule's share of it is not positive either (c τ (1 − φ(k/τ)) ≈ −1e11 at k = 1/4)
    assert_contains(
        &scene_error(&huge.replace("quadrature = \"trapezoid\"\n", "")),
        &[
            "`time.steps` = 4",
            "not positive definite",
            "check their signs and sizes",
        ],
    );
    // while the exact rule keeps the relaxation modulus above positive on every step, N = 1 included
    assert!(Simulation::new(&scene(&text(1).replace("quadrature = \"trapezoid\"\n", "")), small()).is_ok());
}

/// The TOML examples of docs/scenes.md "Viscoelastic memory" are valid scenes (with a `[time]` added)
/// and build what the text says: the first one channel ∝ A with b(0) = −1.2, the second A =
/// (κ(0), G(0)) with one channel (only shear relaxes).
#[test]
fn the_readme_examples_are_valid_scenes() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scenes.md")).unwrap();
    let start = readme.find("### Viscoelastic memory").expect("docs/scenes.md section");
    let section = &readme[start..start + readme[start..].find("### Expression language").unwrap()];
    let blocks: Vec<&str> = section
        .split("```toml\n")
        .skip(1)
        .map(|b| &b[..b.find("```").unwrap()])
        .collect();
    assert_eq!(blocks.len(), 2);
    for (i, b) in blocks.iter().enumerate() {
        let s = scene(&format!("{b}{TIME}"));
        let sim = Simulation::new(&s, rectangle(2.0, 1.0, 2, 1, CellShape::Quad)).unwrap();
        let m = sim.materials.memory().unwrap();
        assert_eq!(m.channels().len(), 1, "block {i}");
        if i == 0 {
            assert_eq!(m.channels()[0].tensor, sim.materials.list()[0].elasticity.tensor());
            assert_eq!(m.kernel_value(0, 0.0), -1.2);
        } else {
            let a = sim.materials.list()[0].elasticity.tensor();
            assert!((a.mu - 0.385).abs() < 1e-12 && (a.lambda + 2.0 * a.mu / 3.0 - 0.833).abs() < 1e-12);
        }
    }
}
