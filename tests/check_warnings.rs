//! `hvi check` warnings (src/solver/advice.rs, docs/method.md §14.5): each set-up that is valid
//! but probably unintended gets its warning, and the same set-up done right gets none.

use std::path::{Path, PathBuf};

fn mesh(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes").join(name)
}

/// The warning lines of `hvi check` on a mesh with a scene file (or the default) and overrides.
fn warnings(mesh_name: &str, scene: Option<&str>, overrides: &[&str]) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = scene.map(|text| {
        let p = dir.path().join("scene.toml");
        std::fs::write(&p, text).unwrap();
        p
    });
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let report = hvi::app::check(&mesh(mesh_name), scene_path.as_deref(), &overrides)
        .unwrap_or_else(|e| panic!("hvi check {mesh_name}: {e}"));
    report
        .lines()
        .filter(|l| l.starts_with("warning: "))
        .map(str::to_string)
        .collect()
}

const RING: &str = "[[dirichlet]]\ngroup = \"SymX\"\ncomponents = [\"x\"]\n[[dirichlet]]\ngroup = \"SymY\"\n\
                    components = [\"y\"]\n[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                    [time]\nfinal_time = 1.0\nsteps = 2\n[[contact]]\ngroup = \"Outer\"\nbound = 0.01\n";

#[test]
fn the_paper_scene_has_no_warning() {
    assert_eq!(warnings("rect_q1_h16.msh", None, &[]), Vec::<String>::new());
}

#[test]
fn a_traction_on_a_clamped_group_is_named() {
    let w = warnings(
        "rect_q1_h16.msh",
        None,
        &["traction=[{group=\"Gamma1\", value=[\"1\", \"0\"]}]"],
    );
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("Gamma1") && w[0].contains("prescribed"), "{w:?}");
}

#[test]
fn a_constant_bound_on_a_curved_contact_group_is_named_unless_there_is_an_obstacle() {
    let w = warnings("ring_q1_n4.msh", Some(RING), &[]);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("Outer") && w[0].contains("curved"), "{w:?}");
    // the quarter ring's outer arc r = 2 against a plane touching it at (2, 0): no longer a
    // layer following the curve, so no warning
    let with_obstacle = format!("{RING}obstacle = {{ kind = \"plane\", point = [2.0, 0.0], normal = [-1.0, 0.0] }}\n");
    let w = warnings("ring_q1_n4.msh", Some(&with_obstacle), &[]);
    assert!(!w.iter().any(|l| l.contains("curved")), "{w:?}");
}

#[test]
fn contact_nodes_that_can_never_touch_are_named() {
    // a plane 100 below a body of size 2.2: every node starts farther than the body's size
    let far = warnings(
        "rect_q1_h16.msh",
        None,
        &["contact.obstacle={kind=\"plane\", point=[0.0, -100.0], normal=[0.0, 1.0]}"],
    );
    assert_eq!(far.len(), 1, "{far:?}");
    assert!(far[0].contains("Gamma3") && far[0].contains("farther"), "{far:?}");
    let near = warnings(
        "rect_q1_h16.msh",
        None,
        &["contact.obstacle={kind=\"plane\", point=[0.0, -0.01], normal=[0.0, 1.0]}"],
    );
    assert_eq!(near, Vec::<String>::new());
    // a small disc below the middle of Γ₃, along the body's normals: the nodes beside it never
    // meet it (|x − 1| > 0.5 of the 33 nodes of 0 ≤ x ≤ 2)
    let never = warnings(
        "rect_q1_h16.msh",
        None,
        &[
            "contact.obstacle={kind=\"circle\", centre=[1.0, -1.0], radius=0.5}",
            "contact.direction=\"body\"",
        ],
    );
    assert!(never.iter().any(|l| l.contains("never meet")), "{never:?}");
}
