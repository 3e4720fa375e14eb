//! Contact between two deformable bodies of one mesh (issue 44, in progress; docs/method.md §18):
//! a `[[contact]]` section with `target` pairs its group (the slave surface) with the target (the
//! master surface); each paired slave node carries the mortar row u_ν = (Σ c_i u_i − u_S)·n ≤ g
//! (docs/method.md §18.2).

mod common;

use common::stacked;
use hvi::app::solve_in_memory;
use hvi::mesh::structured::CellShape;
use hvi::scene::Scene;

/// The two blocks on rollers (both left sides u_x = 0, the lower bottom u_y = 0), the upper top
/// pushed down by δ = 0.01, frictionless contact of the upper bottom with the lower top.
const SCENE: &str = "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                     [time]\nfinal_time = 1.0\nsteps = 1\n\
                     [[dirichlet]]\ngroup = \"LowerBottom\"\ncomponents = [\"y\"]\n\
                     [[dirichlet]]\ngroup = \"LowerLeft\"\ncomponents = [\"x\"]\n\
                     [[dirichlet]]\ngroup = \"UpperLeft\"\ncomponents = [\"x\"]\n\
                     [[dirichlet]]\ngroup = \"UpperTop\"\ncomponents = [\"y\"]\nvalue = [\"-0.01*t\"]\n\
                     [[contact]]\ngroup = \"UpperBottom\"\ntarget = \"LowerTop\"\n";

/// The uniform compression of the stack: σ_yy = −p with p = δ E / (2 (1 − ν²)), ε_xx = p ν (1 + ν)/E.
fn uniform(x: &[f64; 2]) -> [f64; 2] {
    let (e, nu, delta) = (1.0, 0.3, 0.01);
    let p = delta * e / (2.0 * (1.0 - nu * nu));
    let (exx, eyy) = (p * nu * (1.0 + nu) / e, -p * (1.0 - nu * nu) / e);
    [exx * x[0], eyy * x[1]]
}

/// Matching meshes (the same grid on both sides of the interface): each slave node sits on a
/// master node, the stack's uniform compression is the discrete solution, reproduced to 1e-10 of
/// δ, and every slave node carries the uniform pressure p w_p.
#[test]
fn stacked_blocks_with_matching_meshes_hold_the_uniform_state() {
    let scene = Scene::from_toml_str(SCENE, "stacked blocks").unwrap_or_else(|e| panic!("{e}"));
    let mesh = stacked((8, 4, CellShape::Quad), (8, 4, CellShape::Quad), 1.0);
    let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let error = common::nodal_error(&sim.mesh.points, &u, uniform);
    assert!(error < 1e-10 * 0.01, "nodal error {error:e}");
    let c = sim.contact.as_ref().unwrap();
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let p = 0.01 / (2.0 * (1.0 - 0.09));
    for (k, &f) in state.force.iter().enumerate() {
        assert!(
            (f / c.nodes.weights[k] - p).abs() < 1e-9 * p,
            "pressure at slave node {k}"
        );
    }
}

/// The contact patch test (Taylor & Papadopoulos 1991) on non-matching meshes, 7 triangles'
/// edges against 8 quadrilaterals' along the interface, with either side as the slave: the
/// mortar rows (docs/method.md §18.2) transmit the uniform pressure exactly, so the discrete
/// solution is the stack's uniform compression — every node to 1e-10 of δ, every slave node's
/// pressure to 1e-9 (round-off of the solve, well inside the 1e-8) — and each body
/// balances its load to round-off. Node-to-segment rows were 1.7 % of δ off here.
#[test]
fn stacked_blocks_with_non_matching_meshes_pass_the_patch_test_either_way() {
    for (slave, master) in [("UpperBottom", "LowerTop"), ("LowerTop", "UpperBottom")] {
        let text = SCENE.replace(
            "group = \"UpperBottom\"\ntarget = \"LowerTop\"",
            &format!("group = \"{slave}\"\ntarget = \"{master}\""),
        );
        let scene = Scene::from_toml_str(&text, "stacked blocks").unwrap_or_else(|e| panic!("{e}"));
        let mesh = stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0);
        let (sim, stats, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
        let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
        let error = common::nodal_error(&sim.mesh.points, &u, uniform);
        assert!(
            error < 1e-10 * 0.01,
            "{slave} on {master}: nodal error {error:e} of δ = 0.01"
        );
        let c = sim.contact.as_ref().unwrap();
        let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
        let p = 0.01 / (2.0 * (1.0 - 0.09));
        for (k, &f) in state.force.iter().enumerate() {
            let pressure = f / c.nodes.weights[k];
            assert!(
                (pressure - p).abs() < 1e-9 * p,
                "{slave} on {master}: pressure {pressure} at slave row {k}"
            );
        }
        let total: f64 = state.force.iter().sum();
        for group in ["LowerBottom", "UpperTop"] {
            let reaction = common::reaction(&stats, group, "y", 1.0).abs();
            assert!(
                (total - reaction).abs() < 1e-12 * total,
                "{slave} on {master}: {group}'s balance"
            );
        }
    }
}

/// The contact patch test in 3D: hexahedra (4 × 3 faces across the interface) below, tetrahedra
/// (3 × 2 boxes, split in six) above, in plane strain along z; either side as the slave. The
/// mortar integrals clip each master face against each slave face, so the uniform state is again
/// the discrete solution: every node to 1e-10 of δ, every slave pressure to 1e-9.
#[test]
fn stacked_boxes_with_non_matching_meshes_pass_the_patch_test_either_way() {
    use hvi::mesh::structured::{block, SolidShape};
    for (slave, master) in [("UpperBottom", "LowerTop"), ("LowerTop", "UpperBottom")] {
        let text = format!(
            "[material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
             [time]\nfinal_time = 1.0\nsteps = 1\n\
             [[dirichlet]]\ngroup = \"LowerBottom\"\ncomponents = [\"y\"]\n\
             [[dirichlet]]\ngroup = \"LowerLeft\"\ncomponents = [\"x\"]\n\
             [[dirichlet]]\ngroup = \"LowerSides\"\ncomponents = [\"z\"]\n\
             [[dirichlet]]\ngroup = \"UpperLeft\"\ncomponents = [\"x\"]\n\
             [[dirichlet]]\ngroup = \"UpperSides\"\ncomponents = [\"z\"]\n\
             [[dirichlet]]\ngroup = \"UpperTop\"\ncomponents = [\"y\"]\nvalue = [\"-0.01*t\"]\n\
             [[contact]]\ngroup = \"{slave}\"\ntarget = \"{master}\"\n"
        );
        let scene = Scene::from_toml_str(&text, "stacked boxes").unwrap_or_else(|e| panic!("{e}"));
        let mesh = common::stack(
            block([2.0, 1.0, 1.0], [4, 2, 3], SolidShape::Hex),
            block([2.0, 1.0, 1.0], [3, 2, 2], SolidShape::Tet),
            1.0,
        );
        let (sim, stats, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
        let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
        let error = common::nodal_error(&sim.mesh.points, &u, |x| {
            let [ux, uy] = uniform(&[x[0], x[1]]);
            [ux, uy, 0.0]
        });
        assert!(
            error < 1e-10 * 0.01,
            "{slave} on {master}: nodal error {error:e} of δ = 0.01"
        );
        let c = sim.contact.as_ref().unwrap();
        let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
        let p = 0.01 / (2.0 * (1.0 - 0.09));
        for (k, &f) in state.force.iter().enumerate() {
            let pressure = f / c.nodes.weights[k];
            assert!(
                (pressure - p).abs() < 1e-9 * p,
                "{slave} on {master}: pressure {pressure} at slave row {k}"
            );
        }
        let total: f64 = state.force.iter().sum();
        let reaction = common::reaction(&stats, "LowerBottom", "y", 1.0).abs();
        assert!(
            (total - reaction).abs() < 1e-12 * total,
            "{slave} on {master}: the lower body's balance"
        );
    }
}

/// `hvi check` lists the pair (slave nodes paired, off the target, the largest initial gap and
/// penetration); a pair whose surfaces face the same way is refused naming both groups.
#[test]
fn check_lists_the_pair_and_refuses_surfaces_facing_the_same_way() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("stacked.msh");
    std::fs::write(
        &mesh,
        common::msh22(&stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0)),
    )
    .unwrap();
    let scene = dir.path().join("stacked.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let report = hvi::app::check(&mesh, Some(&scene), &[], false).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        report
            .contains("pair contact[0]: \"UpperBottom\" against \"LowerTop\": 8 slave nodes paired, 0 off the target"),
        "{report}"
    );
    let same_way = format!("{SCENE}[[contact]]\ngroup = \"UpperTop\"\ntarget = \"LowerTop\"\n");
    std::fs::write(&scene, same_way).unwrap();
    let err = hvi::app::check(&mesh, Some(&scene), &[], false)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("UpperTop") && err.contains("LowerTop") && err.contains("face the same way"),
        "{err}"
    );
}

/// What a target does not take yet is refused by name (docs/scenes.md): friction, an obstacle, a
/// bound, bilateral contact beside it; and a target outside a [[contact]] section with a group.
#[test]
fn what_a_target_does_not_take_yet_is_refused() {
    for extra in [
        "friction = { kind = \"coulomb\", coefficient = 0.3 }",
        "bound = 0.1",
        "bilateral = true",
        "obstacle = { kind = \"plane\", point = [0.0, 1.0], normal = [0.0, 1.0] }",
    ] {
        let text = format!("{SCENE}{extra}\n");
        let err = Scene::from_toml_str(&text, "stacked").expect_err(extra).to_string();
        assert!(
            err.contains("contact[0].target") && err.contains("issue 44"),
            "{extra}: {err}"
        );
    }
    let one_table = "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                     [time]\nfinal_time = 1.0\nsteps = 1\n[contact]\ntarget = \"LowerTop\"\n";
    let err = Scene::from_toml_str(one_table, "one table")
        .expect_err("refused")
        .to_string();
    assert!(err.contains("group"), "{err}");
}
