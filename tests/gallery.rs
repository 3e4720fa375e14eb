//! The gallery of README's "Problems you can pose": each entry run as README says, with a check
//! of what it shows. (The Hertz entries, examples/gallery/hertz_2d and hertz_3d, are run and
//! checked against the closed forms by tests/hertz.rs.)

use hvi::app::{solve, solve_in_memory, SolveOptions};
use hvi::mesh::read_mesh;
use hvi::scene::Scene;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn run_files(mesh: &str, scene: Option<&str>, out: &Path) -> hvi::solver::RunStats {
    let opts = SolveOptions {
        mesh: root().join(mesh),
        scene: scene.map(|s| root().join(s)),
        out: out.to_path_buf(),
        overrides: vec![],
        progress: false,
        overwrite: false,
    };
    solve(&opts, None).unwrap_or_else(|e| panic!("{e}"))
}

/// The paper's example on a mesh with only the paper's groups (Gamma1, Gamma2, Gamma3, Omega):
/// `hvi solve meshes/rect_q1_h16_plain.msh` runs with the embedded scene and gives the same
/// solution as the mesh with the extra group Gamma2_top (same nodes, same cells): the load on
/// Gamma2 is written with the facet normal, so no extra group is needed. Agreement to 1e-12
/// relative: the two runs assemble the same numbers, up to the order of summation.
#[test]
fn paper_on_a_gamma1_2_3_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let stats = run_files("meshes/rect_q1_h16_plain.msh", None, &dir.path().join("paper"));
    assert!(dir.path().join("paper/solution.pvd").exists());
    let scene = Scene::load(None, &[]).unwrap();
    let plain = read_mesh::<2>(&root().join("meshes/rect_q1_h16_plain.msh")).unwrap();
    let full = read_mesh::<2>(&root().join("meshes/rect_q1_h16.msh")).unwrap();
    assert_eq!(plain.points, full.points);
    let (_, _, a) = solve_in_memory(&scene, plain).unwrap();
    let (_, full_stats, b) = solve_in_memory(&scene, full).unwrap();
    let (ua, ub) = (
        &a.steps.last().unwrap().displacement,
        &b.steps.last().unwrap().displacement,
    );
    let scale = ub.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = ua.iter().zip(ub).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(scale > 0.0 && diff <= 1e-12 * scale, "max difference {diff} of {scale}");
    assert_eq!(
        stats.contact.last().unwrap().active,
        full_stats.contact.last().unwrap().active
    );
}

/// A layer of varying thickness: examples/gallery/layer/layer.toml on meshes/rect_q1_h32.msh.
/// The nodes on the bound at T have u_ν = g(x_p) to the solver's tolerance (1e-10 relative, so
/// 1e-9 g), there are some, and they lie in the valleys of g (sin 6πx < 0), where g is convex.
#[test]
fn layer_of_varying_thickness() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = "meshes/rect_q1_h32.msh";
    let scene_file = "examples/gallery/layer/layer.toml";
    run_files(mesh, Some(scene_file), &dir.path().join("layer"));
    let scene = Scene::load(Some(&root().join(scene_file)), &[]).unwrap();
    let (sim, _, sink) = solve_in_memory(&scene, read_mesh::<2>(&root().join(mesh)).unwrap()).unwrap();
    let c = sim.contact.as_ref().unwrap();
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let mut on_bound = 0;
    for (k, &p) in c.nodes.nodes.iter().enumerate() {
        let x = sim.mesh.points[p][0];
        let g = 0.2 + 0.02 * (6.0 * std::f64::consts::PI * x).sin();
        let r = state.normal_displacement[k];
        assert!(r <= g * (1.0 + 1e-9), "node at x = {x}: u_ν = {r} > g = {g}");
        if state.status[k] == hvi::contact::NodeStatus::OnBound {
            on_bound += 1;
            assert!(
                (r - g).abs() <= 1e-9 * g,
                "node at x = {x}: u_ν = {r} on the bound g = {g}"
            );
            assert!(
                (6.0 * std::f64::consts::PI * x).sin() < 0.0,
                "node on the bound at x = {x} off a valley"
            );
        }
    }
    assert!(on_bound >= 5, "only {on_bound} nodes on the bound");
}

/// The 2D Hertz entry through files, as README's command runs it: the scene's groups exist in
/// the mesh and some nodes end on the obstacle.
#[test]
fn hertz_entries_run_as_readme_says() {
    let dir = tempfile::tempdir().unwrap();
    // (the 3D entry reads its scene the same way in tests/hertz.rs; not run twice)
    let (mesh, scene) = (
        "examples/gallery/hertz_2d/hertz_2d_h1.msh",
        "examples/gallery/hertz_2d/hertz_2d.toml",
    );
    let out: PathBuf = dir.path().join("hertz_2d");
    let stats = run_files(mesh, Some(scene), &out);
    assert!(
        stats.contact.last().unwrap().active > 0,
        "{mesh}: no node on the obstacle"
    );
    assert!(out.join("solution.pvd").exists());
}

/// A pressure-loaded body: examples/gallery/ring/ring.toml on meshes/ring_q1_n16.msh, run through
/// files as README says. The displacement at T is the Lamé solution to the mesh's accuracy (the
/// nodal error on this mesh is 1.0e-3 of u_r(a), tests/pressure.rs; 2e-3 allows for nothing but
/// a wrong load or normal), and the frames are written.
#[test]
fn pressure_loaded_ring() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, scene_file) = ("meshes/ring_q1_n16.msh", "examples/gallery/ring/ring.toml");
    run_files(mesh, Some(scene_file), &dir.path().join("ring"));
    assert!(dir.path().join("ring/solution.pvd").exists());
    let scene = Scene::load(Some(&root().join(scene_file)), &[]).unwrap();
    let (sim, _, sink) = solve_in_memory(&scene, read_mesh::<2>(&root().join(mesh)).unwrap()).unwrap();
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let (e, nu, p, a, b) = (1.0, 0.3, 0.01, 1.0, 2.0);
    let ur = |r: f64| p * a * a / (e * (b * b - a * a)) * ((1.0 + nu) * (1.0 - 2.0 * nu) * r + (1.0 + nu) * b * b / r);
    let mut worst = 0.0f64;
    for (x, v) in sim.mesh.points.iter().zip(&u) {
        let r = (x[0] * x[0] + x[1] * x[1]).sqrt();
        let exact = [ur(r) * x[0] / r, ur(r) * x[1] / r];
        worst = worst.max((v[0] - exact[0]).abs().max((v[1] - exact[1]).abs()));
    }
    assert!(worst < 2e-3 * ur(a), "nodal error {worst:e} of u_r(a) = {:e}", ur(a));
}
