//! Patch tests at ν = 0.4999 (K/G ≈ 5 000) with the locking-free formulation forced on
//! (`material.formulation = "mean_dilatation"`, docs/method.md §8.4): the cell's mean dilatation
//! (B-bar) on quadrilaterals, hexahedra, prisms and pyramids, the mean over patches of cells on
//! triangles and tetrahedra, and the cell mean with the hoop strain over 2πr on a
//! body of revolution (docs/method.md §8.6). On distorted meshes of every element kind a linear
//! field u = G x is reproduced to round-off, the stress written — the cells' σ = K θ̄ I + 2μ dev ε
//! and the nodal (recovered) average of it — is the exact uniform stress, its pressure −tr σ/3
//! the exact −K tr ε; and so for a relaxing material (the bulk modulus held or relaxing a little,
//! the shear modulus relaxing 10×) at every step, against the scheme's own relaxation.
//!
//! Why each check can fail. The patch test alone does not tell the projected formulation from
//! the plain one (the plain element reproduces a linear field too, only at worse conditioning),
//! so each case also asserts that the run's material is the projected one and that its
//! stiffness is not the plain one: a random field's energy under the run's K_A is well below the
//! plain element's (the projection only removes bulk energy, docs/method.md §8.4). The patch
//! test then fails if the projected bulk part is not consistent — b̄ = (1/|c|) ∫ ∂N not
//! integrated exactly on a distorted or non-affine cell (pyramids' rational basis, bent prism
//! faces), a patch's V_P not its cells' measure, the hoop strain or the 2πr measure left out of the mean,
//! the memory tensors' bulk part projected differently from A's — most visibly when loaded by
//! tractions, where the bulk part carries the load; and the stress and pressure checks fail if
//! the dilatation the stress is written with is not the field's (a cell mean or a patch's θ_P
//! that leaves out u_r/r or is not normalised by its own measure), or if the memory's stress
//! is not the scheme's. (For a linear field θ̄ = tr ε, so they cannot tell θ̄ from tr ε: that the
//! written stress uses θ̄ is asserted by tests/pressure.rs's nearly incompressible rings.)
//!
//! Tolerances: a direct solve's relative forward error is bounded by a modest multiple of
//! ε_mach · κ(K), and the bulk modulus scales the part of κ(K) the volumetric modes see by
//! K/G ≈ 5 000 against ν = 0.3 (ε_mach · K/G ≈ 1.1e-12). The interior displacement must be within
//! 1e-13 · K/G ≈ 5e-10 of max |G x|, and every stress component (cells' and nodes') and every
//! cell's pressure within the same of the largest exact component and of the exact pressure:
//! about 450 ε_mach · K/G, room for the meshes' own (L/h)² ≈ 16–64 in κ(K) and the solve's
//! constant. Measured (printed with `--nocapture`): displacements 2e-15 to 5e-12, stresses and
//! pressures 3e-15 to 9e-14 — the plain element's are alike (it passes a patch test too).

mod common;

use common::{distort_interior, distort_off_groups, nodal_error, rectangle_with_sides, scene};
use hvi::app::{memory_fields, solve_in_memory, MemorySink};
use hvi::fem::assembly::Volumetric;
use hvi::fem::materials::{BodyMaterial, Materials};
use hvi::fem::stress::{cell_measures, cell_stresses, nodal_stresses};
use hvi::mesh::structured::{block, CellShape, SolidShape};
use hvi::mesh::{read_mesh, Cell, Mesh};
use hvi::solver::Simulation;
use std::path::Path;

const NU: f64 = 0.4999;

/// λ, μ of E = 1 and ν.
fn lame(nu: f64) -> (f64, f64) {
    ((nu / ((1.0 + nu) * (1.0 - 2.0 * nu))), 1.0 / (2.0 * (1.0 + nu)))
}

/// K/G at ν = 0.4999: 2(1 + ν)/(3(1 − 2ν)) ≈ 5 000.
fn bulk_to_shear() -> f64 {
    let (l, m) = lame(NU);
    (l + 2.0 * m / 3.0) / m
}

/// Round-off scaled by the conditioning (the module's comment): 1e-13 · K/G ≈ 5e-10.
fn tolerance() -> f64 {
    1e-13 * bulk_to_shear()
}

/// The 2D or 3D model of a case.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Model {
    PlaneStrain,
    Axisymmetric,
    Solid,
}

impl Model {
    fn plane(self) -> &'static str {
        match self {
            Model::PlaneStrain => "plane = \"strain\"\n",
            Model::Axisymmetric => "plane = \"axisymmetric\"\n",
            Model::Solid => "",
        }
    }
}

/// A mesh of one kind, the groups that hold its whole boundary, and for the loaded variant the
/// group clamped to the linear field and those that carry its traction σν.
struct Case<const D: usize> {
    name: &'static str,
    mesh: Mesh<D>,
    model: Model,
    boundary: &'static [&'static str],
    clamped: &'static str,
    loaded: &'static [&'static str],
}

/// The exact strain of u = G x as a 3×3 tensor: the symmetric part of G, ε₃₃ = 0 in plane strain
/// and ε_θθ = u_r/r = G₀₀ on a body of revolution (G = diag(a, b) there).
fn strain<const D: usize>(g: &[[f64; D]; D], model: Model) -> [[f64; 3]; 3] {
    let mut e = [[0.0; 3]; 3];
    for i in 0..D {
        for j in 0..D {
            e[i][j] = 0.5 * (g[i][j] + g[j][i]);
        }
    }
    if model == Model::Axisymmetric {
        e[2][2] = g[0][0];
    }
    e
}

/// σ = (κ − 2μ/3) tr ε I + 2μ ε.
fn stress(e: &[[f64; 3]; 3], kappa: f64, mu: f64) -> [[f64; 3]; 3] {
    let tr = e[0][0] + e[1][1] + e[2][2];
    std::array::from_fn(|i| {
        std::array::from_fn(|j| 2.0 * mu * e[i][j] + if i == j { (kappa - 2.0 * mu / 3.0) * tr } else { 0.0 })
    })
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// The scene: `material` (constants or a relaxation modulus) with the formulation, `steps` steps
/// on [0, 1], u = G x on every group of `boundary` (`loaded`: on the clamped group only, the
/// traction σ(G)ν on the others).
fn scene_text<const D: usize>(
    case: &Case<D>,
    g: &[[f64; D]; D],
    material: &str,
    formulation: &str,
    steps: usize,
    loaded: bool,
) -> String {
    let mut t = format!(
        "[material]\n{}formulation = \"{formulation}\"\n{material}\n[time]\nfinal_time = 1.0\nsteps = {steps}\n",
        case.model.plane()
    );
    let value: Vec<String> = (0..D)
        .map(|i| {
            (0..D)
                .map(|j| format!("{:e}*{}", g[i][j], AXES[j]))
                .collect::<Vec<_>>()
                .join(" + ")
        })
        .collect();
    let components: Vec<String> = AXES[..D].iter().map(|a| format!("\"{a}\"")).collect();
    let prescribe = |group: &str| {
        format!(
            "[[dirichlet]]\ngroup = \"{group}\"\ncomponents = [{}]\nvalue = [{}]\n",
            components.join(", "),
            value.iter().map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", ")
        )
    };
    if loaded {
        let (l, m) = lame(NU);
        let s = stress(&strain(g, case.model), l + 2.0 * m / 3.0, m);
        t += &prescribe(case.clamped);
        for group in case.loaded {
            let traction: Vec<String> = (0..D)
                .map(|i| {
                    let terms: Vec<String> = (0..D).map(|j| format!("{:e}*n{}", s[i][j], AXES[j])).collect();
                    format!("\"{}\"", terms.join(" + "))
                })
                .collect();
            t += &format!("[[traction]]\ngroup = \"{group}\"\nvalue = [{}]\n", traction.join(", "));
        }
    } else {
        for group in case.boundary {
            t += &prescribe(group);
        }
    }
    t
}

/// The largest errors over the steps of a run: (displacement relative to max |G x|, cell and
/// nodal stress components relative to the largest exact one, cell pressure relative to the
/// exact one). `moduli(t)` is the (κ, μ) the scheme's stress has at time t.
fn errors<const D: usize>(
    sim: &Simulation<D>,
    sink: &MemorySink,
    g: &[[f64; D]; D],
    model: Model,
    moduli: impl Fn(f64) -> (f64, f64),
) -> (f64, f64, f64) {
    let linear = |x: &[f64; D]| -> [f64; D] { std::array::from_fn(|i| (0..D).map(|j| g[i][j] * x[j]).sum()) };
    let scale = sim
        .mesh
        .points
        .iter()
        .flat_map(linear)
        .fold(0.0f64, |v, c| v.max(c.abs()));
    let measures = cell_measures(&sim.mesh.cells, &sim.mesh.points);
    let (mut eu, mut es, mut ep) = (0.0f64, 0.0f64, 0.0f64);
    assert!(!sink.steps.is_empty());
    for step in &sink.steps {
        let u = sim.dofs.to_nodal(&step.displacement);
        eu = eu.max(nodal_error(&sim.mesh.points, &u, linear) / scale);
        let memory = memory_fields(sim, step.memory_displacement.as_deref());
        let cells = cell_stresses(
            &sim.mesh.cells,
            &sim.mesh.points,
            &sim.materials,
            None,
            &u,
            Some(&memory),
        );
        let nodes = nodal_stresses(&sim.mesh.cells, &measures, &cells.tensor, sim.mesh.points.len());
        let (kappa, mu) = moduli(step.time);
        let e = strain(g, model);
        let exact = stress(&e, kappa, mu);
        let largest = exact.iter().flatten().fold(0.0f64, |v, s| v.max(s.abs()));
        let pressure = -kappa * (e[0][0] + e[1][1] + e[2][2]);
        for s in cells.tensor.chunks_exact(9).chain(nodes.tensor.chunks_exact(9)) {
            for k in 0..9 {
                es = es.max((s[k] - exact[k / 3][k % 3]).abs() / largest);
            }
        }
        for s in cells.tensor.chunks_exact(9) {
            let p = -(s[0] + s[4] + s[8]) / 3.0;
            ep = ep.max((p - pressure).abs() / pressure.abs());
        }
    }
    (eu, es, ep)
}

/// Asserts that the run's single material takes the projected volumetric strain — the cell mean
/// on the cells that are no simplices, its patch's on every simplex — and returns a
/// random field's energy under the run's K_A over the plain element's (below 1: the projection
/// removes bulk energy and adds none).
fn projected<const D: usize>(sim: &Simulation<D>, name: &str) -> f64 {
    let material = &sim.materials.list()[0];
    assert_eq!(material.volumetric, Volumetric::Mean, "{name}: the formulation");
    let simplex = |c: &Cell| matches!(c, Cell::Tri3(_) | Cell::Tet4(_));
    let patches = sim.materials.patches();
    for (c, cell) in sim.mesh.cells.iter().enumerate() {
        assert_eq!(
            patches.of_cell(c).is_some(),
            simplex(cell),
            "{name}: a patch for every simplex, for nothing else (cell {c})"
        );
    }
    let plain = Materials::one(
        BodyMaterial {
            volumetric: Volumetric::Pointwise,
            ..material.clone()
        },
        &sim.mesh.cells,
    );
    let (cells, points) = (&sim.mesh.cells, &sim.mesh.points);
    let k = sim.materials.assemble_elastic(cells, points, &sim.dofs);
    let kp = plain.assemble_elastic(cells, points, &sim.dofs);
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let v: Vec<f64> = (0..k.n())
        .map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 2001) as f64 / 1000.0 - 1.0
        })
        .collect();
    let energy = |m: &hvi::fem::SymmetricMatrix| {
        let mut y = vec![0.0; v.len()];
        m.matvec(&v, &mut y);
        v.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>()
    };
    energy(&k) / energy(&kp)
}

fn msh<const D: usize>(name: &str) -> Mesh<D> {
    read_mesh::<D>(&Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes").join(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// The rectangle (0, 2) × (0, 1) in 8 × 4 cells, its interior nodes moved by up to 0.3 h
/// (tests/elasticity.rs): every cell a general quadrilateral or triangle. As a meridian section
/// it starts on the axis r = 0.
fn rectangle_case(name: &'static str, shape: CellShape, model: Model) -> Case<2> {
    let mut mesh = rectangle_with_sides(2.0, 1.0, 8, 4, shape);
    distort_interior(&mut mesh, 2.0, 1.0, 0.25, 0.6);
    let (clamped, loaded): (&str, &[&str]) = match model {
        // the axis carries no traction (its measure 2πr is zero); z = 0 holds the axial motion
        Model::Axisymmetric => ("Gamma3", &["Gamma2"]),
        _ => ("Gamma1", &["Gamma2", "Gamma3"]),
    };
    Case {
        name,
        mesh,
        model,
        boundary: &["Gamma1", "Gamma2", "Gamma3"],
        clamped,
        loaded,
    }
}

/// The box (0, 1) × (0, 0.8) × (0, 0.6) in 4 × 3 × 3 grid boxes of `shape`, its interior nodes
/// (the pyramids' apexes too) moved by up to 0.2 h: hexahedra and pyramids with warped faces,
/// prisms with bent sides, tetrahedra of every shape.
fn block_case(name: &'static str, shape: SolidShape) -> Case<3> {
    let mut mesh = block([1.0, 0.8, 0.6], [4, 3, 3], shape);
    distort_off_groups(&mut mesh, 0.2);
    Case {
        name,
        mesh,
        model: Model::Solid,
        boundary: &["Gamma1", "Gamma2", "Gamma3", "Sides"],
        clamped: "Gamma1",
        loaded: &["Gamma2", "Gamma3", "Sides"],
    }
}

/// gmsh's mixed meshes (prisms on tetrahedra; hexahedra, pyramids and tetrahedra), distorted as
/// tests/three_d.rs and tests/real_geometry.rs do: cell means and patches of cells side by side.
fn gmsh_case(name: &'static str, file: &str) -> Case<3> {
    let mut mesh = msh::<3>(file);
    distort_off_groups(&mut mesh, 0.2);
    Case {
        name,
        mesh,
        model: Model::Solid,
        boundary: &["Gamma1", "Gamma2", "Gamma3"],
        clamped: "Gamma1",
        loaded: &["Gamma2", "Gamma3"],
    }
}

const G2: [[f64; 2]; 2] = [[0.01, 0.02], [0.003, -0.004]];
const G_AXI: [[f64; 2]; 2] = [[0.01, 0.0], [0.0, -0.004]];
const G3: [[f64; 3]; 3] = [[0.01, 0.02, -0.005], [0.003, -0.01, 0.004], [0.002, 0.006, 0.008]];

/// Runs both variants (u prescribed on the whole boundary; clamped on one group, loaded by σν on
/// the rest) with the elastic material and the projected formulation, asserts the errors and
/// the formulation, and runs the plain formulation for contrast (printed, not asserted: it passes
/// a patch test too).
fn elastic_patch_test<const D: usize>(case: Case<D>, g: &[[f64; D]; D]) {
    let material = format!("youngs_modulus = 1.0\npoisson_ratio = {NU}");
    let (l, m) = lame(NU);
    for loaded in [false, true] {
        let variant = if loaded { "loaded" } else { "prescribed" };
        let run = |formulation: &str| {
            let text = scene_text(&case, g, &material, formulation, 1, loaded);
            solve_in_memory(&scene(&text), case.mesh.clone()).unwrap_or_else(|e| panic!("{}: {e}", case.name))
        };
        let (sim, _, sink) = run("mean_dilatation");
        let free = sim.dofs.prescribed().iter().filter(|p| !**p).count();
        assert!(free >= D * 8, "{}: interior unknowns to test ({free})", case.name);
        let share = projected(&sim, case.name);
        let (eu, es, ep) = errors(&sim, &sink, g, case.model, |_| (l + 2.0 * m / 3.0, m));
        let (psim, _, psink) = run("standard");
        let plain = errors(&psim, &psink, g, case.model, |_| (l + 2.0 * m / 3.0, m));
        eprintln!(
            "{} ({variant}): u {eu:.1e}, stress {es:.1e}, pressure {ep:.1e}; energy share {share:.3}; \
             the plain element: u {:.1e}, stress {:.1e}, pressure {:.1e}",
            case.name, plain.0, plain.1, plain.2
        );
        assert!(
            share < 0.9,
            "{}: the projected stiffness is the plain one ({share})",
            case.name
        );
        assert!(eu < tolerance(), "{} ({variant}): displacement error {eu:e}", case.name);
        assert!(es < tolerance(), "{} ({variant}): stress error {es:e}", case.name);
        assert!(ep < tolerance(), "{} ({variant}): pressure error {ep:e}", case.name);
    }
}

/// Triangles (patches of cells) and quadrilaterals (cell means), plane strain.
#[test]
fn plane_strain_triangles_and_quadrilaterals_pass_the_patch_test_at_nu_04999() {
    elastic_patch_test(
        rectangle_case("triangles, plane strain", CellShape::Tri, Model::PlaneStrain),
        &G2,
    );
    elastic_patch_test(
        rectangle_case("quadrilaterals, plane strain", CellShape::Quad, Model::PlaneStrain),
        &G2,
    );
}

/// Quadrilaterals as the meridian section of a body of revolution from the axis r = 0 on: the
/// uniform state u_r = a r, u_z = b z (ε_rr = ε_θθ = a, ε_zz = b; a shear or u_r ∝ z would not be
/// uniform, u_r/r varying), with the cell mean of tr ε + u_r/r over 2πr (docs/method.md §8.6).
#[test]
fn axisymmetric_quadrilaterals_pass_the_patch_test_at_nu_04999() {
    elastic_patch_test(
        rectangle_case("quadrilaterals, axisymmetric", CellShape::Quad, Model::Axisymmetric),
        &G_AXI,
    );
}

/// Triangles of a body of revolution: their patches average tr ε + u_r/r over 2πr
/// (docs/method.md §8.4, §8.6). (Before 2026-12-06 their node patches took the planar divergence
/// over the plain area: with u prescribed every pressure was 63 % off, clamped and loaded by σν
/// the displacement 1.5e3 × max |G x|.)
#[test]
fn axisymmetric_triangles_pass_the_patch_test_at_nu_04999() {
    elastic_patch_test(
        rectangle_case("triangles, axisymmetric", CellShape::Tri, Model::Axisymmetric),
        &G_AXI,
    );
}

/// Tetrahedra (patches of cells) and hexahedra (cell means), structured and distorted.
#[test]
fn tetrahedra_and_hexahedra_pass_the_patch_test_at_nu_04999() {
    elastic_patch_test(block_case("tetrahedra", SolidShape::Tet), &G3);
    elastic_patch_test(block_case("hexahedra", SolidShape::Hex), &G3);
}

/// Prisms and pyramids (cell means; the pyramids' rational basis at work on their warped bases),
/// structured, and gmsh's mixed meshes where they meet tetrahedra's patches.
#[test]
fn prisms_and_pyramids_pass_the_patch_test_at_nu_04999() {
    elastic_patch_test(block_case("prisms", SolidShape::Prism), &G3);
    elastic_patch_test(block_case("pyramids", SolidShape::Pyramid), &G3);
    elastic_patch_test(gmsh_case("prisms and tetrahedra (prism_tet.msh)", "prism_tet.msh"), &G3);
    elastic_patch_test(
        gmsh_case(
            "hexahedra, pyramids, tetrahedra (pyramid_hex_tet.msh)",
            "pyramid_hex_tet.msh",
        ),
        &G3,
    );
}

/// A relaxing material: κ(t) = κ₀ (1 − s + s e^{−t/τ}) with s = 0 (the bulk modulus held) and
/// s = 0.1, G(t) = G₀ (0.1 + 0.9 e^{−t/τ}) (κ₀/G₀ ≈ 5 000 as ν = 0.4999, K/G ≈ 50 000 once
/// relaxed), τ = 1/4, u = G x held on the whole boundary from t = 0, 8 steps. The displacement
/// stays the linear field at every step (the memory's K_j is projected as K_A is, so it passes
/// the patch test too), and every cell's stress is the material's: the moduli
/// m(t_n) = m₀ + m₁ (e^{−t_n/τ} − 1), which the exact rule (the default for a relaxation modulus,
/// docs/method.md §20.2) integrates a held strain to on any steps. On triangles, quadrilaterals,
/// tetrahedra and hexahedra.
#[test]
fn relaxing_materials_pass_the_patch_test_at_every_step() {
    let (l, m) = lame(NU);
    let (kappa0, g0, tau, steps) = (l + 2.0 * m / 3.0, m, 0.25, 8);
    // ∫₀ᵗ β = e^{−t/τ} − 1: what the exact rule integrates a held strain to, on any steps
    let relaxed = |t: f64| (-t / tau).exp() - 1.0;
    for bulk_share in [0.0, 0.1] {
        let material = format!(
            "relaxation_modulus = {{ bulk = {{ long_term = {:e}, terms = [{{ modulus = {:e}, relaxation_time = {tau} }}] }}, \
             shear = {{ long_term = {:e}, terms = [{{ modulus = {:e}, relaxation_time = {tau} }}] }} }}",
            kappa0 * (1.0 - bulk_share),
            kappa0 * bulk_share,
            0.1 * g0,
            0.9 * g0
        )
        // a bulk term of modulus 0 is no term
        .replace("terms = [{ modulus = 0e0, relaxation_time = 0.25 }]", "terms = []");
        let moduli = |t: f64| {
            let s = relaxed(t);
            (kappa0 * (1.0 + bulk_share * s), g0 * (1.0 + 0.9 * s))
        };
        let check = |name: &str, run: &dyn Fn() -> (f64, f64, f64, f64, usize)| {
            let (eu, es, ep, share, n) = run();
            eprintln!(
                "relaxing (bulk share {bulk_share}) {name}: u {eu:.1e}, stress {es:.1e}, pressure {ep:.1e} over {n} steps; \
                 energy share {share:.3}"
            );
            assert!(n >= steps, "{name}: every step is checked ({n})");
            assert!(
                share < 0.9,
                "{name}: the projected stiffness is the plain one ({share})"
            );
            assert!(eu < tolerance(), "{name}: displacement error {eu:e}");
            assert!(es < tolerance(), "{name}: stress error {es:e}");
            assert!(ep < tolerance(), "{name}: pressure error {ep:e}");
        };
        for (name, shape) in [("triangles", CellShape::Tri), ("quadrilaterals", CellShape::Quad)] {
            check(name, &|| {
                let case = rectangle_case("relaxing", shape, Model::PlaneStrain);
                let text = scene_text(&case, &G2, &material, "mean_dilatation", steps, false);
                let (sim, _, sink) = solve_in_memory(&scene(&text), case.mesh.clone()).unwrap();
                assert!(sim.materials.memory().is_some(), "a relaxing material has memory");
                let (eu, es, ep) = errors(&sim, &sink, &G2, Model::PlaneStrain, moduli);
                (eu, es, ep, projected(&sim, name), sink.steps.len())
            });
        }
        for (name, shape) in [("tetrahedra", SolidShape::Tet), ("hexahedra", SolidShape::Hex)] {
            check(name, &|| {
                let case = block_case("relaxing", shape);
                let text = scene_text(&case, &G3, &material, "mean_dilatation", steps, false);
                let (sim, _, sink) = solve_in_memory(&scene(&text), case.mesh.clone()).unwrap();
                let (eu, es, ep) = errors(&sim, &sink, &G3, Model::Solid, moduli);
                (eu, es, ep, projected(&sim, name), sink.steps.len())
            });
        }
    }
}
