//! Contact between two deformable bodies of one mesh (docs/method.md §18):
//! a `[[contact]]` section with `target` pairs its group (the slave surface) with the target (the
//! master surface); each paired slave node carries the mortar row u_ν = (Σ c_i u_i − u_S)·n ≤ g
//! (docs/method.md §18.2); each test runs on first-order meshes and on their second-order ones
//! (§18.6).

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

/// Every slave row of the last step carries the pressure `p` (negative: a traction) to 1e-9
/// (`label` names the case in messages).
fn assert_slave_pressures<const D: usize>(
    sim: &hvi::solver::Simulation<D>,
    sink: &hvi::app::MemorySink,
    p: f64,
    label: &str,
) {
    let c = sim.contact.as_ref().unwrap();
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    for (k, &f) in state.force.iter().enumerate() {
        let pressure = f / c.nodes.weights[k];
        assert!(
            (pressure - p).abs() < 1e-9 * p.abs(),
            "{label}: pressure {pressure} at slave row {k}"
        );
    }
}

/// The patch test's contact: every slave row carries the uniform pressure p = δE/(2(1 − ν²))
/// (δ = 0.01, E = 1, ν = 0.3), and the total contact force is the lower base's reaction to 1e-12.
fn assert_uniform_contact<const D: usize>(
    sim: &hvi::solver::Simulation<D>,
    stats: &hvi::solver::RunStats,
    sink: &hvi::app::MemorySink,
    label: &str,
) {
    assert_slave_pressures(sim, sink, 0.01 / (2.0 * (1.0 - 0.09)), label);
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let total: f64 = state.force.iter().sum();
    let reaction = common::reaction(stats, "LowerBottom", "y", 1.0);
    assert!(
        (total.abs() - reaction.abs()).abs() < 1e-12 * total.abs(),
        "{label}: the lower body's balance"
    );
}

/// Solves the stack of `text` on `mesh` and asserts the patch test: every node in the uniform
/// state ([`uniform`], u_z = 0 in 3D) to 1e-10 of δ, and the uniform contact.
fn patch_test<const D: usize>(text: &str, mesh: hvi::mesh::Mesh<D>, label: &str) {
    let scene = Scene::from_toml_str(text, label).unwrap_or_else(|e| panic!("{e}"));
    let (sim, stats, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let error = common::nodal_error(&sim.mesh.points, &u, |x| {
        let [ux, uy] = uniform(&[x[0], x[1]]);
        std::array::from_fn(|k| [ux, uy, 0.0][k])
    });
    assert!(error < 1e-10 * 0.01, "{label}: nodal error {error:e} of δ = 0.01");
    assert_uniform_contact(&sim, &stats, &sink, label);
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
    let p = 0.01 / (2.0 * (1.0 - 0.09));
    assert_slave_pressures(&sim, &sink, p, "pressure");
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
        let mesh = stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0);
        for (order, mesh) in orders(mesh) {
            patch_test(&text, mesh, &format!("{slave} on {master}, {order}"));
        }
    }
}

/// A mesh of first-order cells and its second-order meshes (docs/method.md §18.6): `elevate`'s
/// complete (9-node quadrangles, 27-node hexahedra) and serendipity ones (8 and 20 nodes; 6-node
/// triangles and 10-node tetrahedra in both), each named.
fn orders<const D: usize>(mesh: hvi::mesh::Mesh<D>) -> [(&'static str, hvi::mesh::Mesh<D>); 3] {
    use hvi::mesh::structured::elevate;
    let (complete, serendipity) = (elevate(&mesh, true), elevate(&mesh, false));
    [
        ("first order", mesh),
        ("second order", complete),
        ("serendipity", serendipity),
    ]
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
        let mesh = hvi::mesh::structured::stack(
            block([2.0, 1.0, 1.0], [4, 2, 3], SolidShape::Hex),
            block([2.0, 1.0, 1.0], [3, 2, 2], SolidShape::Tet),
            1.0,
        );
        for (order, mesh) in orders(mesh) {
            patch_test(&text, mesh, &format!("{slave} on {master} (3D), {order}"));
        }
    }
}

/// The upper block dragged over the lower one: the lower bottom clamped, the upper top pressed
/// down by 0.002 and moved sideways by 0.01 t, Coulomb friction μ = 0.3 between them
/// (non-matching meshes, the tangential rows carry the master's mortar coefficients too). Once
/// the whole interface slides (the last two of 10 steps) the total friction force is μ times the
/// total normal force to 1e-10, the forces on the two sides (the slave's, and the master's through
/// the rows' master coefficients) are equal and opposite to 1e-12, and each body balances: the
/// contact forces on the slave side equal the upper top's reactions, and the lower bottom's
/// reactions are their opposite, in both components, to 1e-10 of the normal force.
#[test]
fn a_block_dragged_over_another_slides_with_coulomb_friction() {
    const MU: f64 = 0.3;
    let text = format!(
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
         [time]\nfinal_time = 1.0\nsteps = 10\n\
         [[dirichlet]]\ngroup = \"LowerBottom\"\ncomponents = [\"x\", \"y\"]\n\
         [[dirichlet]]\ngroup = \"UpperTop\"\ncomponents = [\"x\", \"y\"]\nvalue = [\"0.01*t\", \"-0.002\"]\n\
         [[contact]]\ngroup = \"UpperBottom\"\ntarget = \"LowerTop\"\n\
         friction = {{ kind = \"coulomb\", coefficient = {MU} }}\n\
         [solver]\ntolerance = 1e-13\n"
    );
    let scene = Scene::from_toml_str(&text, "dragged blocks").unwrap_or_else(|e| panic!("{e}"));
    for (order, mesh) in orders(stacked((16, 4, CellShape::Quad), (13, 4, CellShape::Tri), 1.0)) {
        dragged_blocks_balance(&scene, mesh, MU, order);
    }
}

/// The dragged blocks' run on `mesh`: see [`a_block_dragged_over_another_slides_with_coulomb_friction`].
fn dragged_blocks_balance(scene: &Scene, mesh: hvi::mesh::Mesh<2>, mu: f64, order: &str) {
    let (sim, stats, sink) = solve_in_memory(scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let c = sim.contact.as_ref().unwrap();
    let m = c.nodes.len();
    assert_eq!(c.friction.as_ref().expect("friction rows").normal_row.len(), m);
    for step in &sink.steps[sink.steps.len() - 2..] {
        let state = step.contact.as_ref().unwrap();
        let normal: f64 = state.force[..m].iter().sum();
        let tangential: f64 = state.force[m..].iter().sum();
        assert!(normal > 0.0, "{order}, t = {}: the blocks are pressed", step.time);
        assert!(
            (tangential.abs() - mu * normal).abs() <= 1e-10 * mu * normal,
            "{order}, t = {}: friction {tangential:e} against μ × {normal:e}",
            step.time
        );
        let forces = c.group_forces(state, None);
        let (on_slave, on_master) = (forces[0], forces[1]);
        assert_eq!(c.force_names(), ["UpperBottom", "LowerTop"]);
        for k in 0..2 {
            assert!(
                (on_slave[k] + on_master[k]).abs() <= 1e-12 * normal,
                "{order}, t = {}: the two sides' forces along {k}: {:e} and {:e}",
                step.time,
                on_slave[k],
                on_master[k]
            );
        }
        for (k, axis) in ["x", "y"].iter().enumerate() {
            let top = common::reaction(&stats, "UpperTop", axis, step.time);
            let bottom = common::reaction(&stats, "LowerBottom", axis, step.time);
            assert!(
                (top + on_slave[k]).abs() <= 1e-10 * normal,
                "{order}, t = {}: the upper body's balance along {axis}: reaction {top:e}, contact {:e}",
                step.time,
                on_slave[k]
            );
            assert!(
                (bottom - on_slave[k]).abs() <= 1e-10 * normal,
                "{order}, t = {}: the lower body's balance along {axis}: reaction {bottom:e}, contact {:e}",
                step.time,
                -on_slave[k]
            );
        }
    }
}

/// Two blocks with matching meshes tied to each other (`tied = true`: the slave surface glued to
/// the master in every direction, docs/method.md §18.3) are the one merged block: the same
/// displacement at every node to 1e-10 of the largest, under a load that shears and stretches
/// the interface (the upper top moved by (0.01, 0.005) t, the lower bottom clamped) and a body
/// force.
#[test]
fn tied_blocks_are_the_merged_block() {
    let load = "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                [time]\nfinal_time = 1.0\nsteps = 2\n\
                [body_force]\nvalue = [\"0.001*y\", \"-0.002\"]\n";
    let tied = format!(
        "{load}[[dirichlet]]\ngroup = \"LowerBottom\"\ncomponents = [\"x\", \"y\"]\n\
         [[dirichlet]]\ngroup = \"UpperTop\"\ncomponents = [\"x\", \"y\"]\nvalue = [\"0.01*t\", \"0.005*t\"]\n\
         [[contact]]\ngroup = \"UpperBottom\"\ntarget = \"LowerTop\"\ntied = true\n"
    );
    let merged = format!(
        "{load}[[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"x\", \"y\"]\n\
         [[dirichlet]]\ngroup = \"Gamma2_top\"\ncomponents = [\"x\", \"y\"]\nvalue = [\"0.01*t\", \"0.005*t\"]\n"
    );
    let scene = |text: &str| Scene::from_toml_str(text, "tied").unwrap_or_else(|e| panic!("{e}"));
    let stack = orders(stacked((8, 4, CellShape::Quad), (8, 4, CellShape::Quad), 1.0));
    let one = orders(hvi::mesh::structured::rectangle(2.0, 2.0, 8, 8, CellShape::Quad));
    for ((order, stack), (_, one)) in stack.into_iter().zip(one) {
        tied_is_merged(&scene(&tied), stack, &scene(&merged), one, order);
    }
}

/// The tied stack `a` against the merged block `b`: see [`tied_blocks_are_the_merged_block`].
fn tied_is_merged(tied: &Scene, stack: hvi::mesh::Mesh<2>, merged: &Scene, one: hvi::mesh::Mesh<2>, order: &str) {
    let (a, _, sink_a) = solve_in_memory(tied, stack).unwrap_or_else(|e| panic!("{e}"));
    let (b, _, sink_b) = solve_in_memory(merged, one).unwrap_or_else(|e| panic!("{e}"));
    let ua = a.dofs.to_nodal(&sink_a.steps.last().unwrap().displacement);
    let ub = b.dofs.to_nodal(&sink_b.steps.last().unwrap().displacement);
    let largest = ub.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for (x, u) in a.mesh.points.iter().zip(&ua) {
        let q = b
            .mesh
            .points
            .iter()
            .position(|y| (x[0] - y[0]).abs() + (x[1] - y[1]).abs() < 1e-12)
            .expect("every node of the stack is a node of the merged block");
        worst = worst.max((u[0] - ub[q][0]).abs().max((u[1] - ub[q][1]).abs()));
    }
    assert!(
        worst < 1e-10 * largest,
        "{order}: tied against merged: {worst:e} of {largest:e}"
    );
}

/// The non-matching stack as an MSH 2.2 file and [`SCENE`] written into `dir`: (mesh, scene).
fn stack_files(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let (mesh, scene) = (dir.join("stacked.msh"), dir.join("stacked.toml"));
    let stack = stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0);
    std::fs::write(&mesh, common::msh22(&stack)).unwrap();
    std::fs::write(&scene, SCENE).unwrap();
    (mesh, scene)
}

/// `hvi check` lists the pair (slave nodes paired, off the target, the largest initial gap and
/// penetration), warns when the slave's facets are finer than the target's (swap them), and
/// refuses a pair whose surfaces face the same way, naming both groups.
#[test]
fn check_lists_the_pair_and_refuses_surfaces_facing_the_same_way() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, scene) = stack_files(dir.path());
    let report = hvi::app::check(&mesh, Some(&scene), &[], false).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        report
            .contains("pair contact[0]: \"UpperBottom\" against \"LowerTop\": 8 slave nodes paired, 0 off the target"),
        "{report}"
    );
    assert!(!report.contains("finer than the target"), "{report}");
    // the slave's 13 edges on the target's 8: the warning to swap them
    let fine = stacked((8, 4, CellShape::Quad), (13, 4, CellShape::Tri), 1.0);
    std::fs::write(&mesh, common::msh22(&fine)).unwrap();
    let report = hvi::app::check(&mesh, Some(&scene), &[], false).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        report.contains("finer than the target's") && report.contains("swap group and target"),
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

/// A bilateral pair (`bilateral = true` beside `target`) holds the bodies together in tension
/// too: the upper top pulled up by δ, the non-matching stack is stretched uniformly (the patch
/// test with the sign of δ turned), every node to 1e-10 of δ, every slave node pulled by the
/// uniform traction.
#[test]
fn a_bilateral_pair_holds_in_tension() {
    let text = SCENE.replace("-0.01*t", "0.01*t") + "bilateral = true\n";
    let scene = Scene::from_toml_str(&text, "stacked blocks").unwrap_or_else(|e| panic!("{e}"));
    let mesh = stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0);
    let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let error = common::nodal_error(&sim.mesh.points, &u, |x| uniform(x).map(|v| -v));
    assert!(error < 1e-10 * 0.01, "nodal error {error:e} of δ");
    let p = 0.01 / (2.0 * (1.0 - 0.09));
    assert_slave_pressures(&sim, &sink, -p, "traction");
}

/// A body held only by its contact with another, on the master side: the upper block has no
/// prescribed component at all, only the pressure p on its top, and rests on the lower block
/// (on rollers) through the pair LowerTop (slave) → UpperBottom (master). Its rigid motions are
/// pinned among its contact nodes (docs/method.md §7.6, §18), its sideways one held by nothing
/// but the pin (frictionless, balanced loads): the lower block takes the uniform compression
/// exactly — every node to 1e-10 of its largest displacement — and every slave node the pressure
/// p to 1e-9.
#[test]
fn a_master_body_held_only_by_its_contact_rests_on_the_other() {
    let p = 0.005;
    let text = format!(
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
         [time]\nfinal_time = 1.0\nsteps = 1\n\
         [[dirichlet]]\ngroup = \"LowerBottom\"\ncomponents = [\"y\"]\n\
         [[dirichlet]]\ngroup = \"LowerLeft\"\ncomponents = [\"x\"]\n\
         [[traction]]\ngroup = \"UpperTop\"\npressure = \"{p}\"\n\
         [[contact]]\ngroup = \"LowerTop\"\ntarget = \"UpperBottom\"\n"
    );
    let scene = Scene::from_toml_str(&text, "resting block").unwrap_or_else(|e| panic!("{e}"));
    let mesh = stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0);
    let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    // the lower block under σ_yy = −p, rollers at x = 0 and y = 0, plane strain
    let (exx, eyy) = (p * 0.3 * 1.3, -p * (1.0 - 0.09));
    // the lower block's nodes come first in the stack: 9 × 5 of its 8 × 4 quadrilaterals
    let mut worst = 0.0f64;
    for (x, v) in sim.mesh.points.iter().zip(&u).take(9 * 5) {
        worst = worst.max((v[0] - exx * x[0]).abs().max((v[1] - eyy * x[1]).abs()));
    }
    assert!(worst < 1e-10 * p, "the lower block's nodes: {worst:e}");
    assert_slave_pressures(&sim, &sink, p, "pressure");
}

/// What a run of two bodies writes (docs/method.md §18.4): contact_forces.csv has the slave
/// group's force and the target's, equal and opposite to 1e-12 of their size; the contact
/// dataset's `target_point` at every slave node is the displaced point of the target its row is
/// measured against, which in the patch test (the bodies touching, the state uniform) is the
/// displaced slave node itself, to 1e-12.
#[test]
fn a_run_writes_both_sides_forces_and_the_target_points() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, scene) = stack_files(dir.path());
    let out = dir.path().join("run");
    common::hvi_ok(&[
        "solve",
        mesh.to_str().unwrap(),
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let csv = std::fs::read_to_string(out.join("contact_forces.csv")).unwrap();
    let force = |group: &str, axis: &str| -> f64 {
        csv.lines()
            .map(|l| l.split(',').collect::<Vec<_>>())
            .find(|r| r[0] == "1" && r[1] == group && r[2] == axis)
            .unwrap_or_else(|| panic!("no row {group} {axis} in {csv}"))[3]
            .parse()
            .unwrap()
    };
    let (slave, master) = (force("UpperBottom", "y"), force("LowerTop", "y"));
    assert!(
        slave > 0.0 && (slave + master).abs() <= 1e-12 * slave,
        "{slave:e} and {master:e}"
    );
    let pvd = std::fs::read_to_string(out.join("contact.pvd")).unwrap();
    let last = pvd.rsplit("file=\"").next().unwrap().split('"').next().unwrap();
    let frame = hvi::output::read_vtu_arrays(&out.join(last)).unwrap();
    let (_, target) = &frame.point_data["target_point"];
    let (_, u) = &frame.point_data["displacement"];
    for (i, x) in frame.points.iter().enumerate() {
        for d in 0..2 {
            let slave_at = x[d] + u[3 * i + d];
            assert!(
                (target[3 * i + d] - slave_at).abs() <= 1e-12,
                "slave node {i}: target point {} against {slave_at}",
                target[3 * i + d]
            );
        }
    }
}

/// Where two bodies touch with matching meshes, each slave node shares its position with a master
/// node: `hvi plot` places gamma3.csv's rows on the nodes of the row's own group (its `group`
/// column), so that Γ₃'s curve is the slave surface — here the lower block's top, whose nodes come
/// first in the mesh (by position alone the upper block's, the later ones, were taken).
#[test]
fn plot_places_the_slave_rows_on_the_slave_surface() {
    let dir = tempfile::tempdir().unwrap();
    let stack = stacked((8, 4, CellShape::Quad), (8, 4, CellShape::Quad), 1.0);
    let (mesh, scene) = (dir.path().join("stacked.msh"), dir.path().join("stacked.toml"));
    std::fs::write(&mesh, common::msh22(&stack)).unwrap();
    let swapped = SCENE.replace(
        "group = \"UpperBottom\"\ntarget = \"LowerTop\"",
        "group = \"LowerTop\"\ntarget = \"UpperBottom\"",
    );
    std::fs::write(&scene, swapped).unwrap();
    let out = dir.path().join("run");
    let [m, s, o] = [&mesh, &scene, &out].map(|p| p.to_str().unwrap().to_string());
    common::hvi_ok(&["solve", &m, "--scene", &s, "--out", &o]);
    let read = hvi::mesh::read_mesh::<2>(&mesh).unwrap();
    let csv = std::fs::read_to_string(out.join("gamma3.csv")).unwrap();
    let gamma3 = hvi::plot::read_gamma3(&csv, &read).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(gamma3.nodes.len(), 9);
    let lower = 9 * 5;
    assert!(
        gamma3.nodes.iter().all(|&p| p < lower),
        "nodes {:?}: not all of the lower block's top",
        gamma3.nodes
    );
}

/// An interference fit: the upper block starts 0.002 inside the lower one (lifted by 1 − ε), and
/// the pair pushes them apart at the first step. The stack then carries the uniform compression
/// of δ + ε over its two heights, p = (δ + ε)E/(2(1 − ν²)), each block its own affine field
/// (the lower from its base, the upper from its pushed top), on non-matching meshes to 1e-10 of
/// δ: the mortar rows' weighted gap of a flat offset is −ε exactly. `hvi check`'s deepest initial
/// penetration is ε.
#[test]
fn an_interference_fit_is_pushed_apart_exactly() {
    let (delta, eps) = (0.01, 0.002);
    let scene = Scene::from_toml_str(SCENE, "interference").unwrap_or_else(|e| panic!("{e}"));
    let mesh = stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0 - eps);
    let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let pair = &sim.contact.as_ref().unwrap().pairs[0].1;
    assert!((pair.deepest_penetration - eps).abs() < 1e-14, "{pair:?}");
    let p = (delta + eps) / (2.0 * (1.0 - 0.09));
    let (exx, eyy) = (p * 0.3 * 1.3, -p * (1.0 - 0.09));
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let mut worst = 0.0f64;
    for (k, (x, v)) in sim.mesh.points.iter().zip(&u).enumerate() {
        // the lower block's 9 × 5 nodes first, its base fixed; the upper's top at 2 − ε moved by −δ
        let uy = if k < 9 * 5 {
            eyy * x[1]
        } else {
            eyy * (x[1] - (2.0 - eps)) - delta
        };
        worst = worst.max((v[0] - exx * x[0]).abs().max((v[1] - uy).abs()));
    }
    assert!(worst < 1e-10 * delta, "nodal error {worst:e}");
    assert_slave_pressures(&sim, &sink, p, "interference");
}

/// A target that is no group of the mesh is an error naming the key and the group; a group paired
/// with itself faces its own way and is refused naming it.
#[test]
fn a_missing_target_or_the_group_itself_is_refused() {
    let mesh = || stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0);
    let missing = SCENE.replace("target = \"LowerTop\"", "target = \"LowerTopp\"");
    let scene = Scene::from_toml_str(&missing, "missing").unwrap_or_else(|e| panic!("{e}"));
    let err = solve_in_memory(&scene, mesh()).map(|_| ()).unwrap_err().to_string();
    assert!(err.contains("contact[0].target") && err.contains("LowerTopp"), "{err}");
    let itself = SCENE.replace("target = \"LowerTop\"", "target = \"UpperBottom\"");
    let scene = Scene::from_toml_str(&itself, "itself").unwrap_or_else(|e| panic!("{e}"));
    let err = solve_in_memory(&scene, mesh()).map(|_| ()).unwrap_err().to_string();
    assert!(
        err.contains("UpperBottom") && err.contains("face the same way"),
        "{err}"
    );
}

/// The contact patch test on a body of revolution (x = r, y = z): two stacked cylinders of radius
/// 2, non-matching meshes, the upper top pushed down by δ, the lateral surface free: uniaxial
/// stress σ_zz = −Eδ/2, u_r = νδr/2, u_z = −δz/2, exact on linear elements, to 1e-10 of δ; every
/// slave row carries the pressure Eδ/2 to 1e-9 — the mortar integrals carry 2πr
/// (docs/method.md §18.2).
#[test]
fn stacked_cylinders_of_revolution_pass_the_patch_test() {
    let text = SCENE.replace("plane = \"strain\"", "plane = \"axisymmetric\"");
    let scene = Scene::from_toml_str(&text, "stacked cylinders").unwrap_or_else(|e| panic!("{e}"));
    let mesh = stacked((8, 4, CellShape::Quad), (7, 4, CellShape::Tri), 1.0);
    for (order, mesh) in orders(mesh) {
        let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
        let delta = 0.01;
        let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
        let error = common::nodal_error(&sim.mesh.points, &u, |x| {
            [0.3 * delta * x[0] / 2.0, -delta * x[1] / 2.0]
        });
        assert!(error < 1e-10 * delta, "{order}: nodal error {error:e} of δ");
        assert_slave_pressures(&sim, &sink, delta / 2.0, &format!("cylinders, {order}"));
    }
}

/// Coulomb friction between two bodies in 3D: the tetrahedral box dragged diagonally over the
/// hexahedral one (non-matching faces), pressed by 0.002, moved by (0.01, ·, 0.006) t; each slave
/// node has two tangential rows with the master's coefficients. Once the interface slides (the
/// last two of 8 steps) the friction forces' magnitudes add up to μ times the normal force to
/// 1e-10 (their vector sum falls short by 1.7e-7: the slip's direction varies a little across the
/// interface), and the two sides' forces are equal and opposite to 1e-12 in every component.
#[test]
fn boxes_dragged_over_each_other_slide_with_coulomb_friction() {
    use hvi::mesh::structured::{block, SolidShape};
    const MU: f64 = 0.3;
    let text = format!(
        "[material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
         [time]\nfinal_time = 1.0\nsteps = 8\n\
         [[dirichlet]]\ngroup = \"LowerBottom\"\ncomponents = [\"x\", \"y\", \"z\"]\n\
         [[dirichlet]]\ngroup = \"UpperTop\"\ncomponents = [\"x\", \"y\", \"z\"]\n\
         value = [\"0.01*t\", \"-0.002\", \"0.006*t\"]\n\
         [[contact]]\ngroup = \"UpperBottom\"\ntarget = \"LowerTop\"\n\
         friction = {{ kind = \"coulomb\", coefficient = {MU} }}\n\
         [solver]\ntolerance = 1e-13\n"
    );
    let scene = Scene::from_toml_str(&text, "dragged boxes").unwrap_or_else(|e| panic!("{e}"));
    let mesh = hvi::mesh::structured::stack(
        block([2.0, 1.0, 1.0], [6, 2, 3], SolidShape::Hex),
        block([2.0, 1.0, 1.0], [5, 2, 2], SolidShape::Tet),
        1.0,
    );
    for (order, mesh) in orders(mesh) {
        boxes_slide(&scene, mesh, MU, order);
    }
}

/// The dragged boxes' run on `mesh`: see [`boxes_dragged_over_each_other_slide_with_coulomb_friction`].
fn boxes_slide(scene: &Scene, mesh: hvi::mesh::Mesh<3>, mu: f64, order: &str) {
    let (sim, _, sink) = solve_in_memory(scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let c = sim.contact.as_ref().unwrap();
    let m = c.nodes.len();
    for step in &sink.steps[sink.steps.len() - 2..] {
        let state = step.contact.as_ref().unwrap();
        let normal: f64 = state.force[..m].iter().sum();
        let forces = c.group_forces(state, None);
        let (on_slave, on_master) = (forces[0], forces[1]);
        // Σ_p |λ_τ,p|: each node's two tangential rows make its friction vector
        let f = c.friction.as_ref().expect("friction rows");
        let mut per_node = vec![0.0f64; m];
        for (k, &p) in f.normal_row.iter().enumerate() {
            per_node[p] += state.force[m + k].powi(2);
        }
        let friction: f64 = per_node.iter().map(|v| v.sqrt()).sum();
        assert!(normal > 0.0, "{order}, t = {}: the boxes are pressed", step.time);
        assert!(
            (friction - mu * normal).abs() <= 1e-10 * mu * normal,
            "{order}, t = {}: friction {friction:e} against μ × {normal:e}",
            step.time
        );
        for k in 0..3 {
            assert!(
                (on_slave[k] + on_master[k]).abs() <= 1e-12 * normal,
                "{order}, t = {}: the two sides along {k}",
                step.time
            );
        }
    }
}

/// What a target does not take yet is refused by name (docs/scenes.md): an obstacle or a bound
/// beside it; a target outside a [[contact]] section with a group; `tied` without a target or
/// with a law, friction or bilateral beside it.
#[test]
fn what_a_target_does_not_take_yet_is_refused() {
    for extra in [
        "bound = 0.1",
        "obstacle = { kind = \"plane\", point = [0.0, 1.0], normal = [0.0, 1.0] }",
    ] {
        let text = format!("{SCENE}{extra}\n");
        let err = Scene::from_toml_str(&text, "stacked").expect_err(extra).to_string();
        assert!(
            err.contains("contact[0].target") && err.contains("not supported"),
            "{extra}: {err}"
        );
    }
    let one_table = "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                     [time]\nfinal_time = 1.0\nsteps = 1\n[contact]\ntarget = \"LowerTop\"\n";
    let err = Scene::from_toml_str(one_table, "one table")
        .expect_err("refused")
        .to_string();
    assert!(err.contains("group"), "{err}");
    for (extra, needs) in [
        (
            "tied = true\nfriction = { kind = \"coulomb\", coefficient = 0.3 }",
            "remove its law, friction",
        ),
        ("tied = true\nbilateral = true", "remove its law, friction"),
    ] {
        let err = Scene::from_toml_str(&format!("{SCENE}{extra}\n"), "tied")
            .expect_err(extra)
            .to_string();
        assert!(err.contains("contact[0].tied") && err.contains(needs), "{extra}: {err}");
    }
    let untargeted = SCENE.replace("target = \"LowerTop\"\n", "tied = true\n");
    let err = Scene::from_toml_str(&untargeted, "tied")
        .expect_err("untargeted")
        .to_string();
    assert!(err.contains("contact[0].tied") && err.contains("`target`"), "{err}");
}
