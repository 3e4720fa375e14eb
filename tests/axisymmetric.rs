//! Bodies of revolution (docs/method.md §8.6): `material.plane = "axisymmetric"`, x = r, y = z,
//! the hoop strain u_r/r and the measure 2πr. A solid cylinder squeezed radially with its ends on
//! rollers holds the uniform state exactly (its axis r = 0 held without a word from the user); a
//! thick-walled cylinder under internal pressure converges to Lamé's solution at order 2, and at
//! ν = 0.4999 on quadrilaterals (mean dilatation with the hoop strain) every cell's pressure is
//! Lamé's constant.

mod common;

use common::{nodal_error, rectangle_with_sides, scene};
use hvi::app::solve_in_memory;
use hvi::mesh::structured::CellShape;
use hvi::mesh::Mesh;

/// The meridian section [r0, r0 + lr] × [0, lz] in `n` × `m` cells (groups of
/// [`rectangle_with_sides`]: Gamma1 at r = r0, Right at r = r0 + lr, Gamma3 bottom, Gamma2_top top).
fn section(r0: f64, lr: f64, lz: f64, n: usize, m: usize, shape: CellShape) -> Mesh<2> {
    let mut mesh = rectangle_with_sides(lr, lz, n, m, shape);
    mesh.points.iter_mut().for_each(|p| p[0] += r0);
    mesh
}

fn cylinder_scene(nu: f64, pressure_on: &str, extra: &str) -> String {
    format!(
        r#"
[material]
plane = "axisymmetric"
youngs_modulus = 1.0
poisson_ratio = {nu}
{extra}

[time]
final_time = 1.0
steps = 1

[[dirichlet]]
group = "Gamma3"
components = ["y"]

[[dirichlet]]
group = "Gamma2_top"
components = ["y"]

[[traction]]
group = "{pressure_on}"
pressure = "0.01"
"#
    )
}

/// A solid cylinder 0 ≤ r ≤ 1 pressed by p on its mantle, its ends on rollers: σ_rr = σ_θθ = −p,
/// u_r = −p (1 + ν)(1 − 2ν) r / E — linear, so exact on any mesh of P1 or Q1, and the nodes on
/// the axis keep u_r = 0 by themselves (no group names them).
#[test]
fn a_solid_cylinder_squeezed_radially_holds_the_uniform_state() {
    let (nu, p) = (0.3, 0.01);
    for shape in [CellShape::Quad, CellShape::Tri] {
        let mesh = section(0.0, 1.0, 0.5, 6, 3, shape);
        let (sim, _, sink) = solve_in_memory(&scene(&cylinder_scene(nu, "Right", "")), mesh).unwrap();
        let u = sim.dofs.to_nodal(&sink.steps[0].displacement);
        let error = nodal_error(&sim.mesh.points, &u, |x| {
            [-p * (1.0 + nu) * (1.0 - 2.0 * nu) * x[0], 0.0]
        });
        let scale = p * (1.0 + nu) * (1.0 - 2.0 * nu);
        assert!(error < 1e-12 * scale.max(1.0), "{shape:?}: nodal error {error:e}");
        let stress =
            hvi::fem::stress::cell_stresses(&sim.mesh.cells, &sim.mesh.points, &sim.materials, None, &u, None).tensor;
        for s in stress.chunks_exact(9) {
            // σ_rr, σ_θθ = −p; σ_zz = ν (σ_rr + σ_θθ) (the ends held); σ_rz = 0
            assert!((s[0] + p).abs() < 1e-12 && (s[8] + p).abs() < 1e-12, "{shape:?}: {s:?}");
            assert!(
                (s[4] + 2.0 * nu * p).abs() < 1e-12 && s[1].abs() < 1e-12,
                "{shape:?}: {s:?}"
            );
        }
    }
}

/// Lamé, plane strain in z: a ≤ r ≤ b = 2a under internal pressure p,
/// u_r = p a² / (E (b² − a²)) ((1 + ν)(1 − 2ν) r + (1 + ν) b² / r).
fn lame_ur(r: f64, nu: f64, p: f64) -> f64 {
    let (a, b) = (1.0, 2.0);
    p * a * a / (b * b - a * a) * ((1.0 + nu) * (1.0 - 2.0 * nu) * r + (1.0 + nu) * b * b / r)
}

/// The thick-walled cylinder 1 ≤ r ≤ 2 (its meridian section, 4, 8, 16 cells across the wall),
/// ends on rollers: the nodal error falls at order 2 on Q1 (P1 approaches it from below, as in
/// plane strain); at ν = 0.4999 on Q1 (mean
/// dilatation, the cell mean of div u including u_r/r over the measure 2πr) too, with every
/// cell's pressure −tr σ/3 within 1 % of Lamé's constant −2(1 + ν) p a²/(3(b² − a²)), where the
/// plain Q1 element locks.
#[test]
fn a_thick_walled_cylinder_converges_to_lame() {
    let p = 0.01;
    for (nu, shape, formulation) in [
        (0.3, CellShape::Quad, "auto"),
        (0.3, CellShape::Tri, "auto"),
        (0.4999, CellShape::Quad, "auto"),
        (0.4999, CellShape::Quad, "standard"),
    ] {
        let extra = format!("formulation = \"{formulation}\"");
        let run = |n: usize| {
            let mesh = section(1.0, 1.0, 0.5, n, n.div_ceil(2), shape);
            let (sim, _, sink) = solve_in_memory(&scene(&cylinder_scene(nu, "Gamma1", &extra)), mesh).unwrap();
            let u = sim.dofs.to_nodal(&sink.steps[0].displacement);
            let error = nodal_error(&sim.mesh.points, &u, |x| [lame_ur(x[0], nu, p), 0.0]) / lame_ur(1.0, nu, p);
            let exact_pressure = -2.0 * (1.0 + nu) * p / (3.0 * 3.0);
            let stress =
                hvi::fem::stress::cell_stresses(&sim.mesh.cells, &sim.mesh.points, &sim.materials, None, &u, None)
                    .tensor;
            let pressure = stress
                .chunks_exact(9)
                .map(|s| ((-(s[0] + s[4] + s[8]) / 3.0) / exact_pressure - 1.0).abs())
                .fold(0.0, f64::max);
            (error, pressure)
        };
        let results: Vec<(f64, f64)> = [4, 8, 16].iter().map(|&n| run(n)).collect();
        let orders: Vec<f64> = results.windows(2).map(|w| (w[0].0 / w[1].0).log2()).collect();
        eprintln!("ν = {nu} {shape:?} {formulation}: (error, pressure error) {results:.3?}, orders {orders:.2?}");
        if formulation == "standard" {
            assert!(results[0].0 > 0.3, "the plain Q1 element locks: {results:?}");
            continue;
        }
        if shape == CellShape::Quad {
            assert!(orders.iter().all(|q| (q - 2.0).abs() < 0.2), "orders {orders:?}");
        } else {
            // structured triangles are pre-asymptotic here as in plane strain (tests/pressure.rs):
            // measured 1.43, 1.60 (and 1.70, 1.75 on to 64 cells across)
            assert!(
                orders[0] > 1.3 && orders[1] > orders[0] && orders[1] < 2.2,
                "orders {orders:?}"
            );
        }
        assert!(results[2].0 < 1e-2, "{results:?}");
        if nu > 0.49 {
            assert!(results.iter().all(|r| r.1 < 1e-2), "pressure {results:?}");
        }
    }
}

/// Memory on a body of revolution: the solid cylinder under a constant radial pressure with a
/// relaxation modulus relaxing bulk and shear alike, φ(t) = φ∞ + (1 − φ∞) e^{−t/τ}: the state
/// stays uniform and creeps as the standard linear solid's compliance,
/// u(t) = u(0) [1/φ∞ − (1/φ∞ − 1) e^{−φ∞ t/τ}], which the scheme follows at order 2 in k.
#[test]
fn a_relaxing_solid_cylinder_creeps_as_the_standard_linear_solid() {
    let (nu, p, tau, long_term) = (0.3, 0.01, 0.5, 0.4);
    let (k0, g0) = (1.0 / (3.0 * (1.0 - 2.0 * nu)), 1.0 / (2.0 * (1.0 + nu)));
    let relaxing = format!(
        "relaxation_modulus = {{ bulk = {{ long_term = {}, terms = [{{ modulus = {}, relaxation_time = {tau} }}] }}, \
         shear = {{ long_term = {}, terms = [{{ modulus = {}, relaxation_time = {tau} }}] }} }}",
        k0 * long_term,
        k0 * (1.0 - long_term),
        g0 * long_term,
        g0 * (1.0 - long_term)
    );
    let creep = |t: f64| 1.0 / long_term - (1.0 / long_term - 1.0) * (-long_term * t / tau).exp();
    let error = |steps: usize| {
        let text = cylinder_scene(nu, "Right", "")
            .replace("youngs_modulus = 1.0\npoisson_ratio = 0.3\n", &format!("{relaxing}\n"))
            .replace(
                "final_time = 1.0\nsteps = 1",
                &format!("final_time = 2.0\nsteps = {steps}"),
            );
        let mesh = section(0.0, 1.0, 0.5, 4, 2, CellShape::Quad);
        let (sim, _, sink) = solve_in_memory(&scene(&text), mesh).unwrap();
        let at_once = -p * (1.0 + nu) * (1.0 - 2.0 * nu);
        sink.steps
            .iter()
            .map(|step| {
                let u = sim.dofs.to_nodal(&step.displacement);
                nodal_error(&sim.mesh.points, &u, |x| [at_once * creep(step.time) * x[0], 0.0])
                    / (at_once.abs() * creep(2.0))
            })
            .fold(0.0, f64::max)
    };
    let (coarse, fine) = (error(20), error(40));
    let order = (coarse / fine).log2();
    eprintln!("axisymmetric creep: {coarse:.3e} (k = 0.1), {fine:.3e} (k = 0.05), order {order:.2}");
    assert!(coarse < 1e-2, "{coarse:e}");
    assert!((order - 2.0).abs() < 0.2, "order {order}");
}
