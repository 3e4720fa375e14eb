//! A new user's mesh (issue 10, first item): the embedded default scene — the paper's example —
//! runs on a mesh with exactly the groups the paper names, Gamma1, Gamma2 and Gamma3, and gives
//! the same result as the paper's load written on the top side alone.

use hvi::app::solve_in_memory;
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::Mesh;
use hvi::scene::{Scene, DEFAULT_SCENE_TOML};

/// The paper's rectangle with only Gamma1, Gamma2, Gamma3 and Omega (no Gamma2_top).
fn paper_groups_only(shape: CellShape) -> Mesh<2> {
    let mut mesh = rectangle(2.0, 1.0, 16, 8, shape);
    mesh.groups
        .retain(|g| matches!(g.name.as_deref(), Some("Gamma1" | "Gamma2" | "Gamma3" | "Omega")));
    assert_eq!(
        mesh.groups.len(),
        4,
        "{:?}",
        mesh.groups.iter().map(|g| &g.name).collect::<Vec<_>>()
    );
    mesh
}

/// The embedded default with the top load written the old way: on Gamma2_top, without ny.
fn top_only_scene() -> Scene {
    let text = DEFAULT_SCENE_TOML.replace(
        "group = \"Gamma2\"\nvalue = [\"0\", \"-0.1*(1 - exp(-2*t))*x*ny\"]",
        "group = \"Gamma2_top\"\nvalue = [\"0\", \"-0.1*(1 - exp(-2*t))*x\"]",
    );
    assert_ne!(text, DEFAULT_SCENE_TOML, "the default scene's Γ₂ load was not found");
    Scene::from_toml_str(&text, "top-only variant").unwrap()
}

#[test]
fn default_scene_runs_on_gamma123_mesh_and_equals_the_top_side_load() {
    for shape in [CellShape::Quad, CellShape::Tri] {
        let steps = ["time.steps=8".to_string()];
        let scene = Scene::load(None, &steps).unwrap();
        let (_, stats, ours) = solve_in_memory(&scene, paper_groups_only(shape)).expect("runs on Gamma1/2/3 only");
        let mut old = top_only_scene();
        old.time.steps = Some(8);
        let (_, _, theirs) = solve_in_memory(&old, rectangle(2.0, 1.0, 16, 8, shape)).unwrap();
        assert_eq!(ours.steps.len(), theirs.steps.len());
        let scale = theirs
            .steps
            .iter()
            .flat_map(|s| s.displacement.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 1e-3, "the load moved the body ({scale:e})");
        for (a, b) in ours.steps.iter().zip(&theirs.steps) {
            // The right side adds exact zeros; the top facets may be summed in another order.
            let diff = a
                .displacement
                .iter()
                .zip(&b.displacement)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(diff <= 1e-13 * scale, "{shape:?} step {}: {diff:e}", a.step);
        }
        assert!(stats.newton_iterations.iter().sum::<usize>() > 0, "contact was solved");
    }
}

#[test]
fn a_missing_group_names_the_groups_the_mesh_has() {
    let mut mesh = paper_groups_only(CellShape::Quad);
    mesh.groups.retain(|g| g.name.as_deref() != Some("Gamma2"));
    let scene = Scene::load(None, &["time.steps=2".to_string()]).unwrap();
    let err = solve_in_memory(&scene, mesh)
        .err()
        .expect("Gamma2 is missing")
        .to_string();
    assert!(err.contains("Gamma2") && err.contains("Gamma3"), "{err}");
}
