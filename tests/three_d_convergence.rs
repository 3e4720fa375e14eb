//! Convergence in 3D: a manufactured solution on the unit cube with hexahedra, tetrahedra,
//! prisms and pyramids (H¹ order 1, L² order 2, as tests/elasticity.rs does in 2D), and the
//! reaction of a fully prescribed homogeneous uniaxial strain under a Prony memory kernel
//! against its closed form (order 2 in k, docs/method.md §2–3, §7.5).

#![allow(clippy::needless_range_loop)] // component loops read like the formulas

mod common;

use common::{nodal_error, reaction, scene};
use hvi::app::solve_in_memory;
use hvi::fem::norms::{errors, fitted_order};
use hvi::mesh::structured::{block, SolidShape};
use hvi::scene::{Expr, BODY_FORCE_VARIABLES};
use std::f64::consts::PI;
use std::time::Instant;

const E: f64 = 1.0;
const NU: f64 = 0.3;

/// Lamé parameters (λ, μ) of E, ν in 3D.
fn lame() -> (f64, f64) {
    (E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU)), E / (2.0 * (1.0 + NU)))
}

/// Observed order between two levels.
fn order(p: [f64; 2], e: [f64; 2]) -> f64 {
    (e[0] / e[1]).ln() / (p[0] / p[1]).ln()
}

// ---------------------------------------------------------------------------------------------
// 1. Manufactured solution
// ---------------------------------------------------------------------------------------------

/// u = (sin πx sin πy sin πz, x² y z, z cos πy) and ∇u[c][d] = ∂u_c/∂x_d.
fn exact(x: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let [x, y, z] = x;
    let (sx, cx) = (PI * x).sin_cos();
    let (sy, cy) = (PI * y).sin_cos();
    let (sz, cz) = (PI * z).sin_cos();
    (
        [sx * sy * sz, x * x * y * z, cy * z],
        [
            [PI * cx * sy * sz, PI * sx * cy * sz, PI * sx * sy * cz],
            [2.0 * x * y * z, x * x * z, x * x * y],
            [0.0, -PI * sy * z, cy],
        ],
    )
}

/// σ(u) = λ div u I + μ (∇u + ∇uᵀ) of the exact field.
fn exact_stress(x: [f64; 3]) -> [[f64; 3]; 3] {
    let (l, m) = lame();
    let g = exact(x).1;
    let div = g[0][0] + g[1][1] + g[2][2];
    let mut s = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            s[i][j] = m * (g[i][j] + g[j][i]) + if i == j { l * div } else { 0.0 };
        }
    }
    s
}

/// f = −div σ = −(λ + μ) ∇(div u) − μ Δu, derived by hand:
///   div u = π cx sy sz + x² z + cy,
///   ∇ div u = (−π² sx sy sz + 2xz, π² cx cy sz − π sy, π² cx sy cz + x²),
///   Δu = (−3π² sx sy sz, 2yz, −π² z cy).
fn body_force(x: [f64; 3]) -> [f64; 3] {
    let (l, m) = lame();
    let [x, y, z] = x;
    let (sx, cx) = (PI * x).sin_cos();
    let (sy, cy) = (PI * y).sin_cos();
    let (sz, cz) = (PI * z).sin_cos();
    let p2 = PI * PI;
    [
        (l + m) * (p2 * sx * sy * sz - 2.0 * x * z) + 3.0 * m * p2 * sx * sy * sz,
        -(l + m) * (p2 * cx * cy * sz - PI * sy) - 2.0 * m * y * z,
        -(l + m) * (p2 * cx * sy * cz + x * x) + m * p2 * z * cy,
    ]
}

/// The scene's expressions of u (Dirichlet data) and f (body force), with the same formulas.
fn exact_expressions() -> ([String; 3], [String; 3]) {
    let (l, m) = lame();
    let p = format!("{PI:e}");
    let (sx, cx) = (format!("sin({p}*x)"), format!("cos({p}*x)"));
    let (sy, cy) = (format!("sin({p}*y)"), format!("cos({p}*y)"));
    let (sz, cz) = (format!("sin({p}*z)"), format!("cos({p}*z)"));
    let p2 = format!("{:e}", PI * PI);
    let lm = format!("{:e}", l + m);
    let m = format!("{m:e}");
    let u = [format!("{sx}*{sy}*{sz}"), "x^2*y*z".to_string(), format!("{cy}*z")];
    let f = [
        format!("{lm}*({p2}*{sx}*{sy}*{sz} - 2*x*z) + 3*{m}*{p2}*{sx}*{sy}*{sz}"),
        format!("-({lm}*({p2}*{cx}*{cy}*{sz} - {p}*{sy})) - 2*{m}*y*z"),
        format!("-({lm}*({p2}*{cx}*{sy}*{cz} + x^2)) + {m}*{p2}*z*{cy}"),
    ];
    (u, f)
}

/// Points of the cube where the checks of the derivation are made.
const PROBES: [[f64; 3]; 5] = [
    [0.3, 0.7, 0.2],
    [0.9, 0.1, 0.55],
    [0.5, 0.5, 0.5],
    [0.12, 0.83, 0.91],
    [0.66, 0.41, 0.07],
];

/// A derivation mistake fails loudly: −div σ by fourth-order central differences of σ (σ from
/// the analytic gradient) equals the hand-derived f, ∇u equals the differences of u, and the
/// scene's expressions evaluate to the same u and f.
fn check_manufactured_data() {
    let (u_text, f_text) = exact_expressions();
    let parse = |s: &String| Expr::parse(s, &BODY_FORCE_VARIABLES).unwrap_or_else(|e| panic!("{s}: {e}"));
    let u_expr: Vec<Expr> = u_text.iter().map(parse).collect();
    let f_expr: Vec<Expr> = f_text.iter().map(parse).collect();
    let h = 1e-3;
    // d/dx_d of g at x by the five-point stencil (error O(h⁴))
    let diff = |g: &dyn Fn([f64; 3]) -> f64, x: [f64; 3], d: usize| {
        let at = |s: f64| {
            let mut y = x;
            y[d] += s * h;
            g(y)
        };
        (-at(2.0) + 8.0 * at(1.0) - 8.0 * at(-1.0) + at(-2.0)) / (12.0 * h)
    };
    for x in PROBES {
        let f = body_force(x);
        let (u, g) = exact(x);
        for i in 0..3 {
            let div: f64 = (0..3).map(|j| diff(&|y| exact_stress(y)[i][j], x, j)).sum();
            assert!(
                (f[i] + div).abs() <= 1e-8 * (1.0 + f[i].abs()),
                "body force component {i} at {x:?}: hand-derived {} vs −div σ by differences {}",
                f[i],
                -div
            );
            for d in 0..3 {
                let fd = diff(&|y| exact(y).0[i], x, d);
                assert!(
                    (g[i][d] - fd).abs() <= 1e-9,
                    "∂u_{i}/∂x_{d} at {x:?}: {} vs {fd}",
                    g[i][d]
                );
            }
            let vars = [x[0], x[1], x[2], 0.0];
            assert!((u_expr[i].eval(&vars) - u[i]).abs() <= 1e-13, "u expression {i}");
            assert!(
                (f_expr[i].eval(&vars) - f[i]).abs() <= 1e-12 * (1.0 + f[i].abs()),
                "f expression {i}"
            );
        }
    }
}

fn manufactured_scene() -> hvi::scene::Scene {
    let (u, f) = exact_expressions();
    let mut toml = format!(
        "[material]\nyoungs_modulus = {E}\npoisson_ratio = {NU}\n[time]\nfinal_time = 1.0\nsteps = 1\n\
         [body_force]\nvalue = [\"{}\", \"{}\", \"{}\"]\n",
        f[0], f[1], f[2]
    );
    for g in ["Gamma1", "Gamma2", "Gamma3", "Sides"] {
        toml += &format!(
            "[[dirichlet]]\ngroup = \"{g}\"\ncomponents = [\"x\", \"y\", \"z\"]\nvalue = [\"{}\", \"{}\", \"{}\"]\n",
            u[0], u[1], u[2]
        );
    }
    scene(&toml)
}

/// u = (sin πx sin πy sin πz, x² y z, z cos πy) on the unit cube, E = 1, ν = 0.3, no memory and
/// no contact, prescribed on all six faces (nodal interpolation), body force −div σ(u) derived by
/// hand and checked by finite differences first. Asserted: the orders of the last pair of levels
/// and the fitted orders over the three finest levels, H¹ 1 ± 0.1 and L² 2 ± 0.1.
///
/// Measured (release), |e|_H¹ and ‖e‖_L² with pairwise orders:
///
/// | cells | n = 2 | 4 | 8 | 16 | 24 |
/// |---|---|---|---|---|---|
/// | Q1 H¹ | 1.068 | 0.528 (1.02) | 0.263 (1.00) | 0.132 (1.00) | |
/// | Q1 L² | 0.130 | 0.0336 (1.95) | 0.00854 (1.98) | 0.00214 (1.99) | |
/// | P1 H¹ | 1.792 | 1.036 (0.79) | 0.537 (0.95) | 0.271 (0.99) | 0.181 (1.00) |
/// | P1 L² | 0.257 | 0.0933 (1.46) | 0.0274 (1.77) | 0.00725 (1.92) | 0.00326 (1.97) |
///
/// | pyramids H¹ | 1.154 | 0.579 (1.00) | 0.290 (1.00) | 0.145 (1.00) | |
/// | pyramids L² | 0.129 | 0.0326 (1.98) | 0.00823 (1.99) | 0.00206 (2.00) | |
/// | hex + pyramids H¹ | 1.126 | 0.556 (1.02) | 0.277 (1.01) | 0.138 (1.00) | |
/// | hex + pyramids L² | 0.133 | 0.0335 (1.99) | 0.00848 (1.98) | 0.00213 (1.99) | |
/// | warped pyramids H¹ | 1.210 | 0.610 (0.99) | 0.307 (0.99) | 0.153 (1.00) | |
/// | warped pyramids L² | 0.140 | 0.0362 (1.95) | 0.00930 (1.96) | 0.00234 (1.99) | |
///
/// The Kuhn tetrahedra are pre-asymptotic in L² up to n = 8 (1.46, 1.77), so they run one level
/// further, n = 24 (2.3 s; n = 32 gives 1.98 but takes 11 s): fitted over n = 8, 16, 24 the L²
/// order is 1.93. Hexahedra stop at n = 16 (0.4 s; fitted over n = 4, 8, 16: 1.985). Pyramids
/// (six per box around its centre, docs/method.md §8.1) stop there too (0.6 s at n = 16, 24 576
/// pyramids).
#[test]
fn manufactured_solution_converges_in_3d_on_hexes_and_tets() {
    check_manufactured_data();
    let scene = manufactured_scene();
    for (shape, warp, levels) in [
        (SolidShape::Hex, 0.0, &[2usize, 4, 8, 16][..]),
        (SolidShape::Tet, 0.0, &[2, 4, 8, 16, 24][..]),
        // linear prisms (issue 20): triangle × segment, the orders of Q1
        (SolidShape::Prism, 0.0, &[2, 4, 8, 16][..]),
        // linear pyramids (issue 20, docs/method.md §8.1): six per box, hexahedra and pyramids
        // alternately, and six per box on a smoothly warped grid (non-planar bases, apexes off
        // their bases' centres: the map is not affine, the basis's rational term matters)
        (SolidShape::Pyramid, 0.0, &[2, 4, 8, 16][..]),
        (SolidShape::HexPyramid, 0.0, &[2, 4, 8, 16][..]),
        (SolidShape::Pyramid, 0.08, &[2, 4, 8, 16][..]),
    ] {
        let label = format!("{shape:?}{}", if warp > 0.0 { " (warped)" } else { "" });
        let (mut hs, mut h1, mut l2) = (vec![], vec![], vec![]);
        for &n in levels {
            let start = Instant::now();
            let mut mesh = block([1.0, 1.0, 1.0], [n, n, n], shape);
            // x + warp·sin πx sin πy sin πz (1, −1, 1): the cube's faces stay where they are,
            // and the map's Jacobian determinant 1 + warp·(1, −1, 1)·∇(sin πx sin πy sin πz) is at
            // least 1 − 3π·warp > 0
            for p in &mut mesh.points {
                let s = warp * (PI * p[0]).sin() * (PI * p[1]).sin() * (PI * p[2]).sin();
                *p = [p[0] + s, p[1] - s, p[2] + s];
            }
            let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap();
            let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
            // the boundary data are nodal interpolants of u: exact at the boundary nodes
            let e = errors(&sim.mesh.cells, &sim.mesh.points, &u, exact);
            hs.push(1.0 / n as f64);
            h1.push(e.h1_seminorm);
            l2.push(e.l2);
            let i = hs.len() - 1;
            let (o1, o2) = if i > 0 {
                (
                    order([hs[i - 1], hs[i]], [h1[i - 1], h1[i]]),
                    order([hs[i - 1], hs[i]], [l2[i - 1], l2[i]]),
                )
            } else {
                (f64::NAN, f64::NAN)
            };
            eprintln!(
                "{label} h = 1/{n:<2}  |e|_H1 = {:.4e} (order {o1:.3})  ‖e‖_L2 = {:.4e} (order {o2:.3})  {:.2} s",
                e.h1_seminorm,
                e.l2,
                start.elapsed().as_secs_f64()
            );
        }
        let m = hs.len();
        let (p1, p2) = (
            order([hs[m - 2], hs[m - 1]], [h1[m - 2], h1[m - 1]]),
            order([hs[m - 2], hs[m - 1]], [l2[m - 2], l2[m - 1]]),
        );
        let (q1, q2) = (
            fitted_order(&hs[m - 3..], &h1[m - 3..]),
            fitted_order(&hs[m - 3..], &l2[m - 3..]),
        );
        eprintln!(
            "{label}: last-pair orders H¹ {p1:.3}, L² {p2:.3}; fitted over the three finest: H¹ {q1:.3}, L² {q2:.3}"
        );
        assert!((p1 - 1.0).abs() <= 0.1, "{label}: H¹ order {p1} (errors {h1:?})");
        assert!((p2 - 2.0).abs() <= 0.1, "{label}: L² order {p2} (errors {l2:?})");
        assert!((q1 - 1.0).abs() <= 0.1, "{label}: fitted H¹ order {q1} (errors {h1:?})");
        assert!((q2 - 2.0).abs() <= 0.1, "{label}: fitted L² order {q2} (errors {l2:?})");
    }
}

/// The same manufactured solution on second-order cells (docs/method.md §19.4): 10-node
/// tetrahedra, 27- and 20-node hexahedra, 18- and 15-node prisms on the structured cube
/// (mesh::structured::elevate), n = 2, 4, 8: H¹ order 2 and L² order 3 between the last pair
/// within 0.2 (measured in the eprintln; the coarse pair is pre-asymptotic).
#[test]
fn manufactured_solution_converges_at_orders_two_and_three_on_second_order_cells() {
    let scene = manufactured_scene();
    for (shape, complete) in [
        (SolidShape::Tet, true),
        (SolidShape::Hex, true),
        (SolidShape::Hex, false),
        (SolidShape::Prism, true),
        (SolidShape::Prism, false),
    ] {
        let (mut hs, mut h1, mut l2) = (vec![], vec![], vec![]);
        let mut label = String::new();
        for n in [2usize, 4, 8] {
            let start = Instant::now();
            let mesh = hvi::mesh::structured::elevate(&block([1.0, 1.0, 1.0], [n, n, n], shape), complete);
            label = format!("{:?}", mesh.cells[0].kind());
            let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap();
            let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
            let e = errors(&sim.mesh.cells, &sim.mesh.points, &u, exact);
            hs.push(1.0 / n as f64);
            h1.push(e.h1_seminorm);
            l2.push(e.l2);
            eprintln!(
                "{label} h = 1/{n}: |e|_H1 = {:.4e}, ‖e‖_L2 = {:.4e}, {:.2} s",
                e.h1_seminorm,
                e.l2,
                start.elapsed().as_secs_f64()
            );
        }
        let (p1, p2) = (
            order([hs[1], hs[2]], [h1[1], h1[2]]),
            order([hs[1], hs[2]], [l2[1], l2[2]]),
        );
        eprintln!("{label}: last-pair orders H¹ {p1:.3}, L² {p2:.3}");
        assert!((p1 - 2.0).abs() <= 0.2, "{label}: H¹ order {p1} (errors {h1:?})");
        assert!((p2 - 3.0).abs() <= 0.2, "{label}: L² order {p2} (errors {l2:?})");
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Relaxation under a prescribed displacement
// ---------------------------------------------------------------------------------------------

const EPS0: f64 = 0.01;
const C: f64 = 0.5;
const TAU: f64 = 0.3;

fn kernel(s: f64) -> f64 {
    C * (-s / TAU).exp()
}

/// The unit cube (2 × 2 × 2 hexahedra) with u = (ε₀ x, 0, 0) prescribed on every face,
/// optionally with the memory kernel b(s) = c e^{−s/τ}, N steps on [0, 1].
fn relaxation_scene(steps: usize, memory: bool) -> hvi::scene::Scene {
    relaxation_scene_with(steps, memory, "trapezoid")
}

/// [`relaxation_scene`] with the memory's `quadrature` ("trapezoid" or "exact").
fn relaxation_scene_with(steps: usize, memory: bool, quadrature: &str) -> hvi::scene::Scene {
    let mut toml = format!(
        "[material]\nyoungs_modulus = {E}\npoisson_ratio = {NU}\n[time]\nfinal_time = 1.0\nsteps = {steps}\n\
         quadrature = \"{quadrature}\"\n"
    );
    if memory {
        toml += &format!(
            "[memory]\nkind = \"exponential\"\nterms = [ {{ coefficient = {C}, relaxation_time = {TAU} }} ]\n"
        );
    }
    for g in ["Gamma1", "Gamma2", "Gamma3", "Sides"] {
        toml += &format!(
            "[[dirichlet]]\ngroup = \"{g}\"\ncomponents = [\"x\", \"y\", \"z\"]\nvalue = [\"{EPS0:e}*x\", \"0\", \"0\"]\n"
        );
    }
    scene(&toml)
}

/// u = (ε₀ x, 0, 0), ε₀ = 0.01, prescribed on every face of the unit cube and held from t = 0:
/// the displacement is exact for every t and the stress is homogeneous,
/// σ_xx(t) = (λ + 2μ) ε₀ + ε₀ ∫₀ᵗ b(s) ds (B₀ = I), shear stresses zero.
///
/// The reaction of Gamma1 (x = 0) in x is Σ over its nodes a of ∫ σ_xj ∂_j φ_a = ∫ σ_xx ∂_x Ψ
/// with Ψ = Σ_{a on x=0} φ_a = (1 − x/h)⁺ (on Q1 and on the structured P1 mesh), i.e.
/// −σ_xx · area = −σ_xx: the edge nodes of x = 0 that also belong to other groups carry no share
/// of the other faces' tractions, because a reaction is an internal nodal force, not a face
/// integral. (For Gamma2 = (x = 1) ∪ (y = 1) the same argument gives σ_xx (1 − h/2) in x:
/// its nodes on the edge x = 0, y = 1 contribute −σ_xx h/2. Checked too.)
///
/// Discretely, m_n = h_n + (k/2) b(0) u_n = k Σ'_{i=0..n} b(t_n − t_i) u, so the reaction at
/// t_N = T is −ε₀ [(λ + 2μ) + Tr_N], Tr_N the trapezoidal rule of ∫₀ᵀ b, which is checked to
/// round-off; its error to the closed form cτ(1 − e^{−T/τ}) is (k²/12)(b'(T) − b'(0)) + O(k⁴),
/// i.e. order 2 in k with the constant (c/τ)(1 − e^{−T/τ})/12 ≈ 0.134 (relative to the
/// reaction: ≈ 0.090 k²). That leading constant puts the relative error at N = 64 at
/// 2.2 × 10⁻⁵, so the 10⁻⁵ bound needs N = 128 (5.5 × 10⁻⁶); N = 8 … 128 is run. The exact rule
/// integrates the held strain exactly: its reaction is the closed form to round-off at every N
/// (docs/method.md §20.2).
#[test]
fn relaxation_with_a_prescribed_displacement_matches_its_closed_form() {
    let (l, m) = lame();
    let stiff = l + 2.0 * m;
    let start = Instant::now();

    // No memory: the derivation of the reaction at t = 0, on hexahedra, tetrahedra, prisms and
    // pyramids (a uniform strain: the patch test, exact on every cell kind).
    for shape in [
        SolidShape::Hex,
        SolidShape::Tet,
        SolidShape::Prism,
        SolidShape::Pyramid,
        SolidShape::HexPyramid,
    ] {
        let (sim, stats, sink) =
            solve_in_memory(&relaxation_scene(1, false), block([1.0; 3], [2, 2, 2], shape)).unwrap();
        let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
        let err = nodal_error(&sim.mesh.points, &u, |x| [EPS0 * x[0], 0.0, 0.0]);
        assert!(err < 1e-15, "{shape:?}: field error {err:e}");
        let rx = reaction(&stats, "Gamma1", "x", 0.0);
        eprintln!(
            "{shape:?} no memory: Gamma1 x reaction {rx:.15e}, −(λ+2μ)ε₀ = {:.15e}",
            -stiff * EPS0
        );
        assert!((rx + stiff * EPS0).abs() <= 1e-14, "{shape:?}: Gamma1 x reaction {rx}");
        for c in ["y", "z"] {
            let r = reaction(&stats, "Gamma1", c, 0.0);
            assert!(r.abs() <= 1e-15, "{shape:?}: Gamma1 {c} reaction {r}");
        }
        if shape == SolidShape::Hex {
            let r2 = reaction(&stats, "Gamma2", "x", 0.0);
            assert!((r2 - stiff * EPS0 * 0.75).abs() <= 1e-14, "Gamma2 x reaction {r2}");
        }
    }

    // With memory: N = 8 … 128 steps on T = 1.
    let t_end = 1.0;
    let closed = -EPS0 * (stiff + C * TAU * (1.0 - (-t_end / TAU).exp()));
    let (mut ks, mut errs) = (vec![], vec![]);
    for steps in [8usize, 16, 32, 64, 128] {
        let (sim, stats, sink) = solve_in_memory(
            &relaxation_scene(steps, true),
            block([1.0; 3], [2, 2, 2], SolidShape::Hex),
        )
        .unwrap();
        assert_eq!(stats.factorisations, 2, "K and, for the prescribed step 0, K_A");
        let k = t_end / steps as f64;
        // step 0: K_A alone, no memory
        let r0 = reaction(&stats, "Gamma1", "x", 0.0);
        assert!((r0 + stiff * EPS0).abs() <= 1e-14, "step 0 reaction {r0}");
        // the field stays exact at every step
        for s in &sink.steps {
            let u = sim.dofs.to_nodal(&s.displacement);
            let err = nodal_error(&sim.mesh.points, &u, |x| [EPS0 * x[0], 0.0, 0.0]);
            assert!(err < 1e-15, "step {}: field error {err:e}", s.step);
        }
        // the discrete value: the trapezoidal rule of ∫₀ᵀ b
        let trapezoid =
            k * (0.5 * kernel(0.0) + (1..steps).map(|i| kernel(i as f64 * k)).sum::<f64>() + 0.5 * kernel(t_end));
        let discrete = -EPS0 * (stiff + trapezoid);
        let r = reaction(&stats, "Gamma1", "x", sim.time.final_time());
        assert!(
            (r - discrete).abs() <= 1e-13 * discrete.abs(),
            "N = {steps}: reaction {r:.15e}, trapezoidal value {discrete:.15e}"
        );
        for c in ["y", "z"] {
            let v = reaction(&stats, "Gamma1", c, sim.time.final_time());
            assert!(v.abs() <= 1e-15, "N = {steps}: Gamma1 {c} reaction {v}");
        }
        let (_, exact_stats, _) = solve_in_memory(
            &relaxation_scene_with(steps, true, "exact"),
            block([1.0; 3], [2, 2, 2], SolidShape::Hex),
        )
        .unwrap();
        let exact = reaction(&exact_stats, "Gamma1", "x", t_end);
        assert!(
            (exact - closed).abs() <= 1e-13 * closed.abs(),
            "N = {steps}: the exact rule's reaction {exact:.15e} against the closed form {closed:.15e}"
        );
        let err = (r - closed).abs() / closed.abs();
        ks.push(k);
        errs.push(err);
        let i = ks.len() - 1;
        let o = if i > 0 {
            order([ks[i - 1], ks[i]], [errs[i - 1], errs[i]])
        } else {
            f64::NAN
        };
        eprintln!(
            "N = {steps:<3} k = {k:.5}  R(T) = {r:.12e}  closed form {closed:.12e}  relative error {err:.4e} (order {o:.3})  err/k² = {:.5}",
            err / (k * k)
        );
    }
    let n = ks.len();
    let last = order([ks[n - 2], ks[n - 1]], [errs[n - 2], errs[n - 1]]);
    let fitted = fitted_order(&ks, &errs);
    eprintln!(
        "order in k: last pair {last:.4}, fitted {fitted:.4}; {:.2} s",
        start.elapsed().as_secs_f64()
    );
    assert!((last - 2.0).abs() <= 0.15, "order in k {last}, errors {errs:?}");
    assert!(
        (fitted - 2.0).abs() <= 0.15,
        "fitted order in k {fitted}, errors {errs:?}"
    );
    assert!(errs[n - 1] < 1e-5, "finest relative error {}", errs[n - 1]);
    // the leading error term of the trapezoidal rule, (k²/12)(b'(T) − b'(0)) ε₀ / |closed|
    let lead = EPS0 * (C / TAU) * (1.0 - (-t_end / TAU).exp()) / 12.0 / closed.abs();
    let observed = errs[n - 1] / (ks[n - 1] * ks[n - 1]);
    assert!(
        (observed / lead - 1.0).abs() < 1e-3,
        "error constant {observed} vs {lead}"
    );
}
