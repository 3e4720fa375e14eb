//! Second-order cells (docs/method.md §19): 6-node triangles, 8- and 9-node quadrangles, 10-node
//! tetrahedra, 20- and 27-node hexahedra, 15- and 18-node prisms. Patch tests (a quadratic field
//! exact on distorted meshes), manufactured solutions (H¹ order 2, L² order 3), the Lamé
//! cylinder on curved (isoparametric) gmsh meshes against their linear companions, gmsh files
//! of every kind read and refused where they must be, and VTK's quadratic cells written.

#![allow(clippy::needless_range_loop)] // component loops read like the formulas

mod common;

use common::{distort_off_groups, manufactured_exact, manufactured_scene, nodal_error, rectangle_with_sides, scene};
use hvi::app::solve_in_memory;
use hvi::fem::norms::{errors, fitted_order};
use hvi::mesh::structured::{block, elevate, rectangle, CellShape, SolidShape};
use hvi::mesh::{read_mesh, CellKind, Mesh};
use std::path::Path;

const E: f64 = 1.0;
const NU: f64 = 0.3;

/// Lamé parameters (λ, μ) of E, ν (3D and plane strain).
fn lame_parameters() -> (f64, f64) {
    (E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU)), E / (2.0 * (1.0 + NU)))
}

/// A quadratic field u_i = ½ xᵀA_i x + b_i·x in D dimensions, its gradient, the expressions of
/// the scene and the constant body force f = −div σ(u) = −(λ + μ) ∇ div u − μ Δu.
struct Quadratic<const D: usize> {
    a: [[[f64; D]; D]; D],
    b: [[f64; D]; D],
}

impl<const D: usize> Quadratic<D> {
    fn new() -> Self {
        // symmetric A_i with entries of order 1, distinct per component
        let a = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                std::array::from_fn(|k| 0.3 + 0.2 * ((i + 2 * j + 2 * k) % 5) as f64 - 0.1 * ((j * k) as f64))
            })
        });
        let b = std::array::from_fn(|i| std::array::from_fn(|j| 0.1 * (1 + i + 3 * j) as f64));
        Quadratic { a, b }
    }

    fn value(&self, x: &[f64; D]) -> [f64; D] {
        std::array::from_fn(|i| {
            (0..D)
                .map(|j| self.b[i][j] * x[j] + (0..D).map(|k| 0.5 * self.a[i][j][k] * x[j] * x[k]).sum::<f64>())
                .sum()
        })
    }

    fn expression(&self, i: usize) -> String {
        const X: [&str; 3] = ["x", "y", "z"];
        let mut terms = Vec::new();
        for j in 0..D {
            terms.push(format!("{:e}*{}", self.b[i][j], X[j]));
            for k in 0..D {
                terms.push(format!("{:e}*{}*{}", 0.5 * self.a[i][j][k], X[j], X[k]));
            }
        }
        terms.join(" + ")
    }

    fn body_force(&self) -> [f64; D] {
        let (l, m) = lame_parameters();
        std::array::from_fn(|i| {
            let grad_div: f64 = (0..D).map(|j| self.a[j][j][i]).sum();
            let laplace: f64 = (0..D).map(|j| self.a[i][j][j]).sum();
            -(l + m) * grad_div - m * laplace
        })
    }

    /// The scene: the field prescribed on `groups`, the body force, plane strain in 2D.
    fn scene(&self, groups: &[&str]) -> hvi::scene::Scene {
        let components = ["\"x\"", "\"y\"", "\"z\""][..D].join(", ");
        let u: Vec<String> = (0..D).map(|i| format!("\"{}\"", self.expression(i))).collect();
        let f: Vec<String> = self.body_force().iter().map(|v| format!("\"{v:e}\"")).collect();
        let mut toml = format!(
            "[material]\nyoungs_modulus = {E}\npoisson_ratio = {NU}\n{}[time]\nfinal_time = 1.0\nsteps = 1\n\
             [body_force]\nvalue = [{}]\n",
            if D == 2 { "plane = \"strain\"\n" } else { "" },
            f.join(", ")
        );
        for g in groups {
            toml += &format!(
                "[[dirichlet]]\ngroup = \"{g}\"\ncomponents = [{components}]\nvalue = [{}]\n",
                u.join(", ")
            );
        }
        scene(&toml)
    }
}

/// Solves and returns the largest nodal error against the quadratic field.
fn patch_error<const D: usize>(q: &Quadratic<D>, groups: &[&str], mesh: Mesh<D>) -> f64 {
    let (sim, _, sink) = solve_in_memory(&q.scene(groups), mesh).unwrap_or_else(|e| panic!("{e}"));
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    nodal_error(&sim.mesh.points, &u, |x| q.value(x))
}

/// A shear and a stretch of the whole mesh: parallelograms stay parallelograms (the map of
/// every cell stays affine), what the serendipity kinds need to hold quadratics.
fn skew<const D: usize>(m: &mut Mesh<D>) {
    for p in &mut m.points {
        p[0] += 0.4 * p[1];
        p[1] *= 1.3;
        if D == 3 {
            p[2] += 0.2 * p[0];
        }
    }
}

/// The patch test of docs/method.md §19.4: u quadratic, prescribed on the whole boundary, the
/// constant body force −div σ(u): the complete (Lagrange) kinds reproduce it on meshes whose
/// interior corners are moved by up to 30 % of h (their straight-sided, non-affine cells still
/// hold every quadratic of x), the serendipity kinds (8-node quadrangle, 20-node hexahedron,
/// 15-node prism) on skewed meshes of parallelograms (on a non-affine cell they miss the term
/// ξ²η² that x² needs — their known loss on distorted meshes). Tolerance 1e-11: the solve's
/// round-off on fields of order 1 (condition numbers ≤ 1e4 on these meshes).
#[test]
fn quadratic_fields_are_exact_on_every_second_order_kind() {
    let q2 = Quadratic::<2>::new();
    for (shape, complete) in [
        (CellShape::Tri, true),
        (CellShape::Quad, true),
        (CellShape::Quad, false),
    ] {
        let mut linear = rectangle(2.0, 1.0, 6, 4, shape);
        if complete {
            distort_off_groups(&mut linear, 0.3);
        } else {
            skew(&mut linear);
        }
        let mesh = elevate(&linear, complete);
        let kind = mesh.cells[0].kind();
        let err = patch_error(&q2, &["Gamma1", "Gamma2", "Gamma3"], mesh);
        eprintln!("{kind:?}: nodal error {err:.2e}");
        assert!(err < 1e-11, "{kind:?}: nodal error {err:e}");
    }
    let q3 = Quadratic::<3>::new();
    for (shape, complete) in [
        (SolidShape::Tet, true),
        (SolidShape::Hex, true),
        (SolidShape::Prism, true),
        (SolidShape::Hex, false),
        (SolidShape::Prism, false),
    ] {
        let mut linear = block([1.0, 1.0, 1.0], [3, 3, 3], shape);
        if complete {
            distort_off_groups(&mut linear, 0.3);
        } else {
            skew(&mut linear);
        }
        let mesh = elevate(&linear, complete);
        let kind = mesh.cells[0].kind();
        let err = patch_error(&q3, &["Gamma1", "Gamma2", "Gamma3", "Sides"], mesh);
        eprintln!("{kind:?}: nodal error {err:.2e}");
        assert!(err < 1e-11, "{kind:?}: nodal error {err:e}");
    }
}

/// The serendipity kinds do miss quadratics on distorted cells (so the skew above is needed, and
/// the test above could fail): an 8-node quadrangle mesh with moved corners is off by more than
/// 1e-6.
#[test]
fn serendipity_quadrangles_lose_quadratics_on_distorted_cells() {
    let q2 = Quadratic::<2>::new();
    let mut linear = rectangle(2.0, 1.0, 6, 4, CellShape::Quad);
    distort_off_groups(&mut linear, 0.3);
    let err = patch_error(&q2, &["Gamma1", "Gamma2", "Gamma3"], elevate(&linear, false));
    assert!(err > 1e-6, "nodal error {err:e}");
}
