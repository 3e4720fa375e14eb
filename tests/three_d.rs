//! The dimension-generic core in 3D (issue 9): the extruded slab equals the 2D plane-strain
//! solution at every contact node and step, constant strain is reproduced on distorted
//! tetrahedra and hexahedra, rollers with a uniaxial traction give the exact linear field and
//! the analytic reaction in 2D and 3D, the contact law holds at every node of every step of a
//! 3D run, and the two condensation backends give the same steps.

mod common;

use common::{nodal_error, reaction, step_differences};
use hvi::app::{solve_in_memory, MemorySink};
use hvi::contact::NodeStatus;
use hvi::mesh::{read_mesh, Mesh};
use hvi::scene::Scene;
use hvi::solver::Simulation;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn mesh<const D: usize>(name: &str) -> Mesh<D> {
    read_mesh::<D>(&root().join("meshes").join(name)).unwrap_or_else(|e| panic!("{e}"))
}

fn slab_scene(extra: &[&str]) -> Scene {
    let sets: Vec<String> = extra.iter().map(|s| s.to_string()).collect();
    Scene::load(Some(&root().join("examples/slab.toml")), &sets).unwrap_or_else(|e| panic!("{e}"))
}

/// The paper's example in 2D plane strain on rect_q1_h8 (the slab's x–y grid).
fn plane_strain_2d(steps: usize) -> (Simulation<2>, MemorySink) {
    let scene = Scene::load(
        None,
        &[format!("time.steps={steps}"), "material.plane=\"strain\"".to_string()],
    )
    .unwrap();
    let (sim, _, sink) = solve_in_memory(&scene, mesh::<2>("rect_q1_h8.msh")).unwrap();
    (sim, sink)
}

/// max over steps and contact nodes of |u_ν(3D) − u_ν(2D)| and |λ/w (3D) − λ/w (2D)| (pressure),
/// relative to the largest u_ν and pressure, and of |u_z|.
fn compare_extruded(file: &str, steps: usize) -> (f64, f64, f64) {
    let (sim2, sink2) = plane_strain_2d(steps);
    let scene = slab_scene(&[&format!("time.steps={steps}")]);
    let (sim3, _, sink3) = solve_in_memory(&scene, mesh::<3>(file)).unwrap();
    let c2 = sim2.contact.as_ref().unwrap();
    let c3 = sim3.contact.as_ref().unwrap();
    // 2D contact node of each 3D contact node, by x (the grids coincide node for node).
    let partner: Vec<usize> = c3
        .nodes
        .nodes
        .iter()
        .map(|&p| {
            let x = sim3.mesh.points[p][0];
            c2.nodes
                .nodes
                .iter()
                .position(|&q| (sim2.mesh.points[q][0] - x).abs() < 1e-9)
                .unwrap_or_else(|| panic!("no 2D contact node at x = {x}"))
        })
        .collect();
    let (mut du, mut dp, mut uz) = (0.0f64, 0.0f64, 0.0f64);
    let (mut su, mut sp) = (0.0f64, 0.0f64);
    assert_eq!(sink2.steps.len(), sink3.steps.len());
    for (a, b) in sink2.steps.iter().zip(&sink3.steps) {
        let (s2, s3) = (a.contact.as_ref().unwrap(), b.contact.as_ref().unwrap());
        for (k, &q) in partner.iter().enumerate() {
            let p2 = s2.force[q] / c2.nodes.weights[q];
            let p3 = s3.force[k] / c3.nodes.weights[k];
            du = du.max((s3.normal_displacement[k] - s2.normal_displacement[q]).abs());
            dp = dp.max((p3 - p2).abs());
            su = su.max(s2.normal_displacement[q].abs());
            sp = sp.max(p2.abs());
        }
        for u in b.displacement.chunks(3) {
            uz = uz.max(u[2].abs());
        }
    }
    assert!(
        su > 0.1 && sp > 1e-3,
        "the comparison is not vacuous: max u_ν {su}, max pressure {sp}"
    );
    (du / su, dp / sp, uz)
}

/// The paper's example on the slab with u_z = 0 on both z faces is the 2D plane-strain
/// solution: one layer and three layers of hexahedra, every contact node, every step.
#[test]
fn extruded_slab_equals_the_2d_plane_strain_solution() {
    for file in ["slab_q1_h8_z1.msh", "slab_q1_h8_z3.msh"] {
        let (du, dp, uz) = compare_extruded(file, 16);
        eprintln!("{file}: relative |Δu_ν| {du:e}, |Δp| {dp:e}, max |u_z| {uz:e}");
        assert!(du <= 1e-10 && dp <= 1e-10, "{file}: u_ν {du:e}, pressure {dp:e}");
        assert!(uz <= 1e-12, "{file}: u_z = {uz:e}");
    }
}

/// The contact law at every contact node of every step of a 3D run (as tests/hard_cases.rs does
/// in 2D), and the three condensations (split sweeps, stored responses, a recovery solve) give the
/// same steps.
#[test]
fn contact_law_holds_in_3d_and_both_backends_agree() {
    let steps = 16;
    let run = |kind: &str| {
        let scene = slab_scene(&[
            &format!("time.steps={steps}"),
            &format!("solver.condensation=\"{kind}\""),
        ]);
        solve_in_memory(&scene, mesh::<3>("slab_q1_h8_z3.msh")).unwrap()
    };
    let (sim, stats, split) = run("split_sweeps");
    let (_, stats_z, stored) = run("stored_responses");
    let (_, stats_r, recovered) = run("recovery_solve");
    assert!(stats.condensation.as_deref().unwrap().starts_with("split"));
    assert!(stats_z.condensation.as_deref().unwrap().starts_with("stored"));
    assert!(stats_r.condensation.as_deref().unwrap().starts_with("a recovery solve"));
    let c = sim.contact.as_ref().unwrap();
    let (g, law, w) = (c.bound.as_ref().unwrap(), c.law().unwrap(), &c.nodes.weights);
    let scale = w.iter().fold(0.0f64, |m, v| m.max(*v)) * law.force_scale();
    let mut on_bound = 0;
    for s in &split.steps {
        let st = s.contact.as_ref().unwrap();
        for p in 0..c.nodes.len() {
            let (r, eta) = (st.normal_displacement[p], st.bound_force[p]);
            assert!(r <= g[p] + 1e-12, "step {}: u_ν = {r} > g", s.step);
            assert!(eta >= -1e-9 * scale, "step {}: η = {eta}", s.step);
            assert!(
                (eta * (r - g[p])).abs() <= 1e-9 * scale,
                "complementarity at step {}",
                s.step
            );
            if st.status[p] == NodeStatus::OnBound {
                on_bound += 1;
            } else {
                let xi = w[p] * law.derivative(r);
                assert!(
                    (st.force[p] - xi).abs() <= 1e-8 * scale,
                    "law off the bound at step {}",
                    s.step
                );
            }
        }
    }
    assert!(on_bound > 0, "the bound is reached");
    for other in [&stored, &recovered] {
        for (step, diff) in step_differences(&split, other) {
            assert!(diff <= 1e-10, "step {step}: condensations differ by {diff:e}");
        }
    }
    assert_eq!(stats.newton_iterations, stats_z.newton_iterations);
    assert_eq!(stats.newton_iterations, stats_r.newton_iterations);
}

/// u = A x with a constant (non-symmetric) A, prescribed on every boundary face, is
/// reproduced to round-off at the interior nodes of distorted tetrahedra and hexahedra.
#[test]
fn patch_test_on_distorted_tetrahedra_and_hexahedra() {
    let a = [[0.01, 0.02, -0.005], [0.003, -0.01, 0.004], [0.002, 0.006, 0.008]];
    let value: Vec<String> = (0..3)
        .map(|i| format!("{:e}*x + {:e}*y + {:e}*z", a[i][0], a[i][1], a[i][2]))
        .collect();
    for (file, groups) in [
        ("block_q1_h8.msh", vec!["Gamma1", "Gamma2", "Gamma3"]),
        ("block_p1.msh", vec!["Gamma1", "Gamma2", "Gamma3"]),
        ("slab_p1_h4.msh", vec!["Gamma1", "Gamma2", "Gamma3", "Sides"]),
        // prisms (an extruded triangulation) under tetrahedra on the same interface (issue 20)
        ("prism_tet.msh", vec!["Gamma1", "Gamma2", "Gamma3"]),
    ] {
        let mut m = mesh::<3>(file);
        common::distort_off_groups(&mut m, 0.2);
        let mut toml = String::from(
            "[material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n",
        );
        for g in &groups {
            toml += &format!(
                "[[dirichlet]]\ngroup = \"{g}\"\ncomponents = [\"x\", \"y\", \"z\"]\nvalue = [\"{}\", \"{}\", \"{}\"]\n",
                value[0], value[1], value[2]
            );
        }
        let scene = Scene::from_toml_str(&toml, "patch").unwrap();
        let points = m.points.clone();
        let (sim, _, sink) = solve_in_memory(&scene, m).unwrap();
        assert!(sim.dofs.n_free() > 0, "{file}: interior nodes to test");
        let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
        let err = nodal_error(&points, &u, |x| {
            std::array::from_fn(|i| (0..3).map(|j| a[i][j] * x[j]).sum())
        });
        assert!(err < 1e-13, "{file}: patch test error {err:e}");
    }
}

/// Rollers (u_x = 0 on x = 0, u_y = 0 on y = 0, and in 3D u_z = 0 on both z faces) and a
/// uniaxial traction σ on x = 2: the exact linear field and the reaction −σ·A on x = 0.
#[test]
fn rollers_under_uniaxial_traction_give_the_exact_field_and_reaction() {
    let (e, nu, sigma) = (2.0, 0.25, 0.01);
    let base = "[[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\"]\n[[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n\
         [time]\nfinal_time = 1.0\nsteps = 2\n";
    // 2D plane stress: ε_xx = σ/E, ε_yy = −νσ/E; area of x = 0: 1.
    let toml2 = format!(
        "{base}[material]\nplane = \"stress\"\nyoungs_modulus = {e}\npoisson_ratio = {nu}\n\
         [[traction]]\ngroup = \"Gamma2\"\nvalue = [\"{sigma}*nx*t\", \"0\"]\n"
    );
    let (sim, stats, sink) = solve_in_memory(
        &Scene::from_toml_str(&toml2, "rollers 2D").unwrap(),
        mesh::<2>("rect_p1_h8_plain.msh"),
    )
    .unwrap();
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let err = nodal_error(&sim.mesh.points, &u, |x| [sigma / e * x[0], -nu * sigma / e * x[1]]);
    assert!(err < 1e-14, "2D field error {err:e}");
    let rx = reaction(&stats, "Gamma1", "x", 1.0);
    assert!((rx + sigma).abs() < 1e-13, "2D reaction {rx}");
    // 3D plane strain on the slab (Lz = 0.125): ε_xx = σ(1−ν²)/E, ε_yy = −σν(1+ν)/E.
    let toml3 = format!(
        "{base}[[dirichlet]]\ngroup = \"Sides\"\ncomponents = [\"z\"]\n[material]\nyoungs_modulus = {e}\npoisson_ratio = {nu}\n\
         [[traction]]\ngroup = \"Gamma2\"\nvalue = [\"{sigma}*nx*t\", \"0\", \"0\"]\n"
    );
    let (sim, stats, sink) = solve_in_memory(
        &Scene::from_toml_str(&toml3, "rollers 3D").unwrap(),
        mesh::<3>("slab_q1_h8_z1.msh"),
    )
    .unwrap();
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let (exx, eyy) = (sigma * (1.0 - nu * nu) / e, -sigma * nu * (1.0 + nu) / e);
    let err = nodal_error(&sim.mesh.points, &u, |x| [exx * x[0], eyy * x[1], 0.0]);
    assert!(err < 1e-14, "3D field error {err:e}");
    let at_t = |group: &str, c: &str| reaction(&stats, group, c, 1.0);
    assert!(
        (at_t("Gamma1", "x") + sigma * 0.125).abs() < 1e-14,
        "3D reaction {}",
        at_t("Gamma1", "x")
    );
    assert!(at_t("Gamma3", "y").abs() < 1e-14);
}

/// A scene whose prescribed components leave a rigid motion free says which.
#[test]
fn free_rigid_motions_are_named() {
    let toml = "[[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n[material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                [time]\nfinal_time = 1.0\nsteps = 1\n";
    let err = solve_in_memory(
        &Scene::from_toml_str(toml, "free").unwrap(),
        mesh::<3>("slab_q1_h8_z1.msh"),
    )
    .err()
    .expect("singular")
    .to_string();
    for part in ["translation in x", "translation in z", "rotation", "not held"] {
        assert!(err.contains(part), "{part}: {err}");
    }
    // plane stress is a 2D model
    let toml = "[material]\nplane = \"stress\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n";
    let err = solve_in_memory(
        &Scene::from_toml_str(toml, "plane").unwrap(),
        mesh::<3>("slab_q1_h8_z1.msh"),
    )
    .err()
    .expect("an error")
    .to_string();
    assert!(err.contains("2D models"), "{err}");
}

/// The built-in block mesher: every cell shape fills the box, every group is a boundary part
/// whose weights add up to its area, and the slab mesh of gmsh equals it node for node.
#[test]
fn structured_block_matches_the_gmsh_slab() {
    use hvi::mesh::structured::{block, SolidShape};
    use hvi::mesh::GroupSelector;
    for shape in [
        SolidShape::Hex,
        SolidShape::Tet,
        SolidShape::Prism,
        SolidShape::Pyramid,
        SolidShape::HexPyramid,
    ] {
        let m = block([2.0, 1.0, 0.25], [8, 4, 2], shape);
        let volume = m.measure();
        assert!((volume - 0.5).abs() < 1e-13, "{shape:?}: volume {volume}");
        for (name, area) in [("Gamma1", 0.25), ("Gamma2", 0.75), ("Gamma3", 0.5), ("Sides", 4.0)] {
            let part = m
                .boundary(&GroupSelector::from(name))
                .unwrap_or_else(|e| panic!("{shape:?}: {e}"));
            let w: f64 = part.weights.iter().sum();
            assert!((w - area).abs() < 1e-13, "{shape:?} {name}: {w}");
        }
    }
    let gmsh = mesh::<3>("slab_q1_h8_z1.msh");
    let ours = block([2.0, 1.0, 0.125], [16, 8, 1], SolidShape::Hex);
    let key = |p: &[f64; 3]| {
        [
            (p[0] * 1e6).round() as i64,
            (p[1] * 1e6).round() as i64,
            (p[2] * 1e6).round() as i64,
        ]
    };
    let mut a: Vec<_> = gmsh.points.iter().map(key).collect();
    let mut b: Vec<_> = ours.points.iter().map(key).collect();
    a.sort();
    b.sort();
    assert_eq!(a, b);
}

/// The Newton directions through a reused factorisation (conjugate gradients preconditioned by
/// an earlier Newton matrix's Cholesky factor, used above `solver.dense_newton_limit` free contact
/// nodes; docs/method.md §9.2) give the same steps as a dense Cholesky factorisation per
/// direction, on the 3D slab with its paper law (whose curvature changes as nodes enter the
/// layer), with every direction sent that way: fewer factorisations than directions.
#[test]
fn conjugate_gradient_newton_directions_equal_the_dense_ones() {
    let run = |limit: usize| {
        let scene = slab_scene(&["time.steps=8", &format!("solver.dense_newton_limit={limit}")]);
        solve_in_memory(&scene, mesh::<3>("slab_q1_h8_z3.msh")).unwrap()
    };
    let (_, dense_stats, dense) = run(100_000);
    let (_, cg_stats, cg) = run(0);
    let iterative: usize = cg_stats.contact.iter().map(|o| o.iterative).sum();
    assert!(iterative > 0, "CG was used");
    let directions: usize = cg_stats.contact.iter().map(|o| o.iterations).sum();
    let factorisations: usize = cg_stats.contact.iter().map(|o| o.factorisations).sum();
    assert!(
        factorisations < directions,
        "{factorisations} factorisations for {directions} directions"
    );
    assert_eq!(dense_stats.contact.iter().map(|o| o.iterative).sum::<usize>(), 0);
    for (step, diff) in step_differences(&dense, &cg) {
        assert!(diff <= 1e-9, "step {step}: {diff:e}");
    }
    assert!(cg_stats.max_contact_residual <= 1e-10);
}

/// The same with Coulomb friction (μ = 0.3) on the slab: the tangential rows' curvature moves
/// with their slip, so the reused factor's directions go through its low-rank (Woodbury) update,
/// the branch model of docs/method.md §17.2 and, at the step's start, the slip predictor; and
/// conjugate gradients stop at the inexact-Newton accuracy of §9.2 (the relative residual, not
/// 10⁻¹³). The steps are the dense path's to 1e-9 and every step's residual is within the
/// tolerance (10⁻¹⁰).
#[test]
fn conjugate_gradient_newton_directions_equal_the_dense_ones_with_friction() {
    let run = |limit: usize| {
        let scene = slab_scene(&[
            "time.steps=6",
            "contact.friction={ kind = \"coulomb\", coefficient = 0.3 }",
            &format!("solver.dense_newton_limit={limit}"),
        ]);
        solve_in_memory(&scene, mesh::<3>("slab_q1_h8_z3.msh")).unwrap()
    };
    let (_, dense_stats, dense) = run(100_000);
    let (_, cg_stats, cg) = run(0);
    let iterative: usize = cg_stats.contact.iter().map(|o| o.iterative).sum();
    let directions: usize = cg_stats.contact.iter().map(|o| o.iterations).sum();
    let factorisations: usize = cg_stats.contact.iter().map(|o| o.factorisations).sum();
    eprintln!("{directions} directions: {iterative} by CG, {factorisations} factorisations");
    assert!(iterative > 0 && factorisations < directions);
    for (step, diff) in step_differences(&dense, &cg) {
        assert!(diff <= 1e-9, "step {step}: {diff:e}");
    }
    assert!(cg_stats.max_contact_residual <= 1e-10);
    assert!(dense_stats.max_contact_residual <= 1e-10);
}
