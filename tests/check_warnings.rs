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
    let report = hvi::app::check(&mesh(mesh_name), scene_path.as_deref(), &overrides, false)
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

/// The paper's scene with its one `[contact]` table written as `copies` `[[contact]]` sections on
/// Gamma3, the law's scale `scale` in each.
fn paper_with_contact_sections(copies: usize, scale: f64) -> String {
    let paper = hvi::scene::DEFAULT_SCENE_TOML;
    let start = paper
        .find("[contact]\n")
        .expect("the paper scene has a [contact] table");
    let end = paper.find("[solver]").expect("the paper scene has a [solver] table");
    let section = paper[start..end]
        .replacen("[contact]\n", "[[contact]]\ngroup = \"Gamma3\"\n", 1)
        .replace("scale = 0.1 ", &format!("scale = {scale} "));
    assert!(section.contains(&format!("scale = {scale} ")), "{section}");
    let head = paper[..start].replace("contact = \"Gamma3\"", "");
    format!("{head}{}{}", section.repeat(copies), &paper[end..])
}

#[test]
fn two_sections_on_one_contact_group_are_named_and_their_laws_add_up() {
    let w = warnings("rect_q1_h16.msh", Some(&paper_with_contact_sections(2, 0.1)), &[]);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("sections 0 and 1") && w[0].contains("Gamma3"), "{w:?}");
    assert!(warnings("rect_q1_h16.msh", Some(&paper_with_contact_sections(1, 0.1)), &[]).is_empty());
    // what the warning says: the two laws act together, as one section with twice the scale
    // (the paper's law is linear in its scale; both runs are solved to the same 1e-10
    // complementarity tolerance, so they agree to about that, relative)
    let solve = |text: &str| {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, text).unwrap();
        let scene = hvi::scene::Scene::load(Some(&path), &[]).unwrap();
        let mesh = match hvi::app::read_mesh(&mesh("rect_q1_h16.msh")).unwrap() {
            hvi::mesh::AnyMesh::Two(m) => m,
            _ => unreachable!("a 2D mesh"),
        };
        let (_, _, sink) = hvi::app::solve_in_memory(&scene, mesh).unwrap();
        sink.steps.last().unwrap().displacement.clone()
    };
    let twice = solve(&paper_with_contact_sections(2, 0.1));
    let doubled = solve(&paper_with_contact_sections(1, 0.2));
    let once = solve(&paper_with_contact_sections(1, 0.1));
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let diff = |a: &[f64], b: &[f64]| norm(&a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>());
    assert!(
        diff(&twice, &doubled) <= 1e-8 * norm(&doubled),
        "{}",
        diff(&twice, &doubled) / norm(&doubled)
    );
    // and the law matters here: doubling it changes the solution far beyond that
    assert!(
        diff(&once, &doubled) > 1e-4 * norm(&doubled),
        "{}",
        diff(&once, &doubled) / norm(&doubled)
    );
}

/// A nearly incompressible material is named (docs/troubleshooting.md): from A's ν in plane strain
/// and 3D, from the long-term moduli of a relaxation modulus whose shear relaxes while its bulk
/// stays, with the plain element forced, which locks; not where mean dilatation holds the body
/// (per cell on quadrilaterals, over patches of cells on triangles, whose pressure converges:
/// docs/method.md §8.4), not in plane stress and not at ν = 0.3.
#[test]
fn a_nearly_incompressible_material_is_named() {
    let strain = |mesh: &str, nu: &str, formulation: &str| {
        warnings(
            mesh,
            None,
            &[
                "material.plane=\"strain\"",
                &format!("material.poisson_ratio={nu}"),
                &format!("material.formulation=\"{formulation}\""),
            ],
        )
    };
    assert_eq!(strain("rect_p1_h16.msh", "0.3", "auto"), Vec::<String>::new());
    assert_eq!(strain("rect_p1_h16.msh", "0.4999", "auto"), Vec::<String>::new());
    let w = strain("rect_p1_h16.msh", "0.4999", "standard");
    assert!(
        w.len() == 1 && w[0].contains("lock") && w[0].contains("K/G = 5.000e3"),
        "{w:?}"
    );
    // quadrilaterals: mean dilatation by default at this K/G, the plain element when forced
    assert_eq!(strain("rect_q1_h16.msh", "0.4999", "auto"), Vec::<String>::new());
    let w = strain("rect_q1_h16.msh", "0.4999", "standard");
    assert!(w.len() == 1 && w[0].contains("lock"), "{w:?}");
    // plane stress does not lock
    let stress = warnings("rect_p1_h16.msh", None, &["material.poisson_ratio=0.4999"]);
    assert_eq!(stress, Vec::<String>::new());
    // a relaxing material: ν = 0.3 at t = 0 (κ(0)/G(0) = 2.17), κ∞/G∞ = 2 164 relaxed (ν∞ = 0.4998)
    let relaxing = "[material]\nplane = \"strain\"\nformulation = \"standard\"\n\
                    relaxation_modulus = { bulk = { long_term = 0.8333 }, shear = { long_term = 0.000385, \
                    terms = [{ modulus = 0.384, relaxation_time = 0.5 }] } }\n";
    let scene = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/paper.toml")).unwrap();
    // the paper's scene with its [material] and [memory] replaced by the relaxing material
    let mut without_material = String::new();
    let mut skip = false;
    for line in scene.lines() {
        if line.starts_with('[') {
            skip = line.starts_with("[material]") || line.starts_with("[memory]") || line.starts_with("[[memory]]");
        }
        if !skip {
            without_material.push_str(line);
            without_material.push('\n');
        }
    }
    // the exact rule (the default for a relaxation modulus) sums its long-term moduli exactly
    let w = warnings("rect_p1_h16.msh", Some(&format!("{without_material}{relaxing}")), &[]);
    let locking: Vec<&String> = w.iter().filter(|l| l.contains("nearly incompressible")).collect();
    assert_eq!(locking.len(), 1, "{w:?}");
    assert!(
        locking[0].contains("once relaxed") && locking[0].contains("K/G = 2.164e3"),
        "{w:?}"
    );
    assert!(
        !w.iter().any(|l| l.contains("does not resolve the relaxation")),
        "{w:?}"
    );
    // the trapezoid over-sums its relaxation by 1 000× on the paper's 32 steps: the long-term warning
    let w = warnings(
        "rect_p1_h16.msh",
        Some(&format!("{without_material}{relaxing}")),
        &["time.quadrature=\"trapezoid\""],
    );
    assert!(
        w.iter()
            .any(|l| l.contains("does not resolve the relaxation") && l.contains("time.quadrature = \"exact\"")),
        "{w:?}"
    );
}
