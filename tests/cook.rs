//! Cook's membrane, plane strain, nearly incompressible (issue 43; docs/method.md §8.4, "Cook's
//! membrane"): the tapered panel with corners (0, 0), (48, 44), (48, 60), (0, 44), clamped on its
//! left edge x = 0 (`Gamma1`), a uniform vertical shear traction on its right edge x = 48
//! (`Gamma2`), the slanted top and bottom free. Linear elasticity, one step, no contact.
//!
//! The variant: E = 250, ν = 0.4999 (K/G = 5 000), traction (0, 6.25) on the right edge of length
//! 16, i.e. a total load F = 100 (per unit thickness); the quantity is the vertical deflection of
//! the tip, the corner (48, 60).
//!
//! Its reference, 7.7706, is hvi's own converged value: the locking-free runs on the nested
//! structured meshes of meshes/cook.geo with N = 64, 128, 256 cells per edge gave
//! quadrilaterals (mean dilatation) 7.736898, 7.755319, 7.763723 and triangles (the node patches
//! hvi had before its cell patches, docs/method.md §8.4) 7.704827, 7.740235, 7.756532; the Aitken
//! (three-point Richardson) extrapolations are 7.77077 and 7.77043, which agree to 0.005 % (the
//! observed order is 1.1–1.2 on both: the clamped corners' singularities). Today's cell patches
//! come to it from above (7.791 at N = 64). No published tip value for this variant could be found to quote, hence the
//! second, sourced check below.
//!
//! The sourced check: P. Krysl's FinEALE (github.com/PetrKryslUCSD/FinEALE,
//! fineale/examples/deformation_linear/statics/2-d/cookstrain.m and 3-d/Cook_3D_strain.m) poses
//! the same membrane in plane strain with G = 0.375, λ = 7.5e3 (3D; 7.5e6 in 2D), a total load of
//! 1 on the right edge, and gives the deflection of the right edge's midpoint (48, 52) as
//! `convutip=16.432584376299037; % NICE-T6 t3block2d with Richardson`. hvi's extrapolation of the
//! same (N = 64, 128, 256, λ = 7.5e3) is 16.4530 on both kinds, 0.12 % above it. In the
//! incompressible limit the deflection scales as F/G, so FinEALE's value is 7.394 at (48, 52) for
//! the variant above (G = 250/(2·1.4999) = 83.34, F = 100), against hvi's 7.4044.
//!
//! The plain P1 and Q1 elements (`formulation = "standard"`, what hvi had before issue 43) lock
//! on the same meshes: at N = 64 they give 75 % (P1) and 52 % (Q1) of the reference, where the
//! locking-free ones are within 0.26 % and 0.43 %.
//!
//! Meshes: meshes/cook/cook_{p1,q1}_n{4,8,16,32,64}.msh (meshes/generate.sh; meshes/README.md).

use hvi::app::solve_in_memory;
use hvi::mesh::read_mesh;
use hvi::scene::Scene;
use std::path::Path;

/// The tip deflection of the variant (E = 250, ν = 0.4999, F = 100): hvi's extrapolated value
/// (see the module's comment).
const TIP_REFERENCE: f64 = 7.7706;

/// FinEALE's converged deflection of the loaded edge's midpoint (48, 52) for G = 0.375, F = 1.
const FINEALE_MID_EDGE: f64 = 16.432584376299037;

/// Cells per edge of the committed meshes.
const NS: [usize; 5] = [4, 8, 16, 32, 64];

/// The vertical displacements at the tip (48, 60) and at the loaded edge's midpoint (48, 52) of
/// the membrane in plane strain with Young's modulus `e`, Poisson's ratio `nu`, the traction
/// (0, `t`) on `Gamma2` and the volumetric `formulation` of docs/scenes.md.
fn deflections(file: &str, formulation: &str, e: f64, nu: f64, t: f64) -> (f64, f64) {
    let toml = format!(
        "[material]\nplane = \"strain\"\nyoungs_modulus = {e:e}\npoisson_ratio = {nu:e}\nformulation = \"{formulation}\"\n\
         [time]\nfinal_time = 1.0\nsteps = 1\n[[traction]]\ngroup = \"Gamma2\"\nvalue = [\"0\", \"{t:e}\"]\n"
    );
    let scene = Scene::from_toml_str(&toml, "cook test").unwrap_or_else(|e| panic!("{e}"));
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cook").join(file);
    let mesh = read_mesh::<2>(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
    let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{file}: {e}"));
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let at = |y: f64| {
        let k = sim
            .mesh
            .points
            .iter()
            .position(|x| (x[0] - 48.0).abs() < 1e-9 && (x[1] - y).abs() < 1e-9)
            .unwrap_or_else(|| panic!("{file}: no node at (48, {y})"));
        u[k][1]
    };
    (at(60.0), at(52.0))
}

/// The tip deflection of the variant E = 250, ν = 0.4999, F = 100.
fn tip(kind: &str, n: usize, formulation: &str) -> f64 {
    deflections(&format!("cook_{kind}_n{n}.msh"), formulation, 250.0, 0.4999, 6.25).0
}

/// On triangles (patches of cells) and quadrilaterals (mean dilatation per cell), both chosen by
/// `formulation = "auto"` at K/G = 5 000 (docs/method.md §8.4), the tip deflection converges to
/// the reference, from above on triangles and from below on quadrilaterals; the plain P1/Q1
/// elements on the same meshes stay far below it.
///
/// Measured (tip deflection, % of 7.7706):
///
/// | N  | P1 plain | P1 cell patches | Q1 plain | Q1 mean dilatation |
/// |----|----------|-----------------|----------|--------------------|
/// | 4  | 3.785 (48.7) | 7.843 (100.9) | 2.083 (26.8) | 6.545 (84.2) |
/// | 8  | 4.152 (53.4) | 7.932 (102.1) | 2.140 (27.5) | 7.317 (94.2) |
/// | 16 | 4.459 (57.4) | 7.852 (101.1) | 2.311 (29.7) | 7.591 (97.7) |
/// | 32 | 4.989 (64.2) | 7.811 (100.5) | 2.833 (36.5) | 7.695 (99.0) |
/// | 64 | 5.836 (75.1) | 7.791 (100.3) | 4.030 (51.9) | 7.737 (99.6) |
///
/// Tolerances: on the finest mesh within 1 % of the reference (the bar; measured +0.26 %
/// and −0.43 %, so a formulation that is off by more than the discretisation fails), and the two
/// kinds within 1 % of each other (measured 0.69 %). Every refinement must divide the error by
/// more than 1.8 (measured 2.2–2.7 on quadrilaterals, 1.98–2.04 on triangles from N = 8 on; the
/// order ≈ 1 the corner singularities allow): an error that stalls (a wrong reference, or a
/// formulation converging to another limit) fails. The plain
/// elements must stay below 80 % (P1) and 55 % (Q1) of the reference on every mesh, and below the
/// locking-free one of the same mesh by more than 5 × its error from N = 16 on (measured ≥ 10 ×):
/// they creep up as the mesh refines but are far from converged at N = 64 (measured 75 % and
/// 52 %, bounds with a margin of 5 and 3 points).
#[test]
fn tip_deflection_converges_without_locking_on_triangles_and_quadrilaterals() {
    let relative = |v: f64| v / TIP_REFERENCE - 1.0;
    let mut rows = Vec::new();
    for n in NS {
        rows.push((
            n,
            tip("p1", n, "standard"),
            tip("p1", n, "auto"),
            tip("q1", n, "standard"),
            tip("q1", n, "auto"),
        ));
    }
    println!("Cook's membrane, E = 250, ν = 0.4999, F = 100: tip deflection (% of {TIP_REFERENCE})");
    println!("| N | P1 plain | P1 cell patches | Q1 plain | Q1 mean dilatation |");
    println!("|---|---|---|---|---|");
    for &(n, p_plain, p_free, q_plain, q_free) in &rows {
        let cell = |v: f64| format!("{v:.3} ({:.1})", 100.0 * v / TIP_REFERENCE);
        println!(
            "| {n} | {} | {} | {} | {} |",
            cell(p_plain),
            cell(p_free),
            cell(q_plain),
            cell(q_free)
        );
    }

    for (kind, free, plain, plain_bound) in [
        (
            "P1",
            rows.iter().map(|r| r.2).collect::<Vec<_>>(),
            rows.iter().map(|r| r.1).collect::<Vec<_>>(),
            0.80,
        ),
        (
            "Q1",
            rows.iter().map(|r| r.4).collect(),
            rows.iter().map(|r| r.3).collect(),
            0.55,
        ),
    ] {
        let errors: Vec<f64> = free.iter().map(|&v| relative(v).abs()).collect();
        let finest = *errors.last().unwrap();
        assert!(
            finest < 1e-2,
            "{kind}: the locking-free tip deflection at N = 64 is {:+.2} % off {TIP_REFERENCE}",
            100.0 * relative(*free.last().unwrap())
        );
        let ratios: Vec<f64> = errors.windows(2).map(|w| w[0] / w[1]).collect();
        // the patches' triangles come from above from N = 8 on (N = 4's three patches across
        // the panel's height are not yet in the asymptotic range)
        let from = if kind == "Q1" { 0 } else { 1 };
        assert!(
            ratios[from..].iter().all(|&r| r > 1.8),
            "{kind}: the error must shrink by > 1.8 per refinement: errors {errors:.4?}, ratios {ratios:.2?}"
        );
        for (k, (&p, &f)) in plain.iter().zip(&free).enumerate() {
            let n = NS[k];
            assert!(
                p < plain_bound * TIP_REFERENCE,
                "{kind} N = {n}: the plain element gives {p:.4}, {:.1} % of the reference: it no longer locks?",
                100.0 * p / TIP_REFERENCE
            );
            if n >= 16 {
                assert!(
                    relative(p).abs() > 5.0 * relative(f).abs(),
                    "{kind} N = {n}: plain {p:.4} against locking-free {f:.4}"
                );
            }
        }
    }

    let (p1, q1) = (rows.last().unwrap().2, rows.last().unwrap().4);
    assert!(
        (p1 / q1 - 1.0).abs() < 1e-2,
        "triangles {p1:.4} and quadrilaterals {q1:.4} at N = 64 differ by more than 1 %"
    );
}

/// FinEALE's variant (G = 0.375, λ = 7.5e3, so ν = 0.499975 and K/G = 2·10⁴; a total load of 1 on
/// the right edge): the deflection of the loaded edge's midpoint (48, 52) on the finest meshes is
/// within 1 % of FinEALE's converged 16.4326 on both kinds (measured at N = 64: triangles
/// 16.452, +0.12 %; quadrilaterals 16.412, −0.13 %; hvi's extrapolation from N = 64–256 is 16.453,
/// +0.12 %, so 1 % is the bar with room for the discretisation, not a loose fit). The
/// plain elements stay far below: measured 10.82 (P1, 66 %) and 6.32 (Q1, 38 %); asserted below
/// 80 %.
#[test]
fn mid_edge_deflection_matches_fineales_converged_value() {
    let (lambda, g) = (7.5e3, 0.375);
    let e = g * (3.0 * lambda + 2.0 * g) / (lambda + g);
    let nu = lambda / (2.0 * (lambda + g));
    for kind in ["p1", "q1"] {
        let file = format!("cook_{kind}_n64.msh");
        let free = deflections(&file, "auto", e, nu, 1.0 / 16.0).1;
        let plain = deflections(&file, "standard", e, nu, 1.0 / 16.0).1;
        println!(
            "FinEALE's variant, {kind} N = 64: mid-edge deflection {free:.4} ({:+.2} % of {FINEALE_MID_EDGE:.4}), plain {plain:.4}",
            100.0 * (free / FINEALE_MID_EDGE - 1.0)
        );
        assert!(
            (free / FINEALE_MID_EDGE - 1.0).abs() < 1e-2,
            "{kind}: mid-edge deflection {free} against FinEALE's {FINEALE_MID_EDGE}"
        );
        assert!(
            plain < 0.8 * FINEALE_MID_EDGE,
            "{kind}: the plain element gives {plain}"
        );
    }
}
