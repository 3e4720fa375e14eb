//! A mesh of several bodies (pieces connected through their nodes; docs/method.md §7.6–7.7):
//! each is held on its own — by its prescribed components, or by its contact with its free
//! motions pinned as rigid parameters — and one that nothing holds is refused by name.

mod common;

use hvi::app::solve_in_memory;
use hvi::mesh::structured::CellShape;
use hvi::mesh::Mesh;
use hvi::scene::Scene;

/// Two blocks 2 × 1 apart in one mesh: the lower (0, 2) × (0, 1) on quadrilaterals, the upper
/// (0, 2) × (2, 3) on triangles ([`common::stacked`]).
fn two_blocks() -> Mesh<2> {
    common::stacked((8, 4, CellShape::Quad), (6, 3, CellShape::Tri), 2.0)
}

const BASE: &str = "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                    [time]\nfinal_time = 1.0\nsteps = 1\n\
                    [[dirichlet]]\ngroup = \"LowerLeft\"\ncomponents = [\"x\", \"y\"]\n\
                    [[traction]]\ngroup = \"UpperTop\"\nvalue = [\"0\", \"-0.01\"]\n";

/// The lower block clamped, the upper one loaded and held by nothing: refused, naming the
/// second body and its free motions (before, the whole mesh's rigid motions were all stopped by
/// the lower block's clamp, and the run went on with a singular matrix).
#[test]
fn a_body_nothing_holds_is_named() {
    let scene = Scene::from_toml_str(BASE, "two blocks").unwrap();
    let err = solve_in_memory(&scene, two_blocks())
        .err()
        .expect("refused")
        .to_string();
    for part in [
        "2 bodies",
        "body 2",
        "translation in x of body 2",
        "translation in y of body 2",
    ] {
        assert!(err.contains(part), "{part:?} in {err}");
    }
}

/// The upper block resting on a rigid foundation (u_ν ≤ 0 on its bottom, frictionless) under
/// a uniform pressure on its top, the lower one clamped: the upper body's motions are pinned
/// (docs/method.md §7.7) and held by its contact; its state is the uniform compression
/// σ_yy = −0.01, so the contact force equals the load (0.02 per unit thickness) to the contact
/// solve's tolerance, and every contact node carries the same pressure.
#[test]
fn a_body_held_by_its_contact_beside_a_clamped_one() {
    let text = format!("{BASE}[[contact]]\ngroup = \"UpperBottom\"\nbound = 0.0\n");
    let scene = Scene::from_toml_str(&text, "two blocks").unwrap();
    let (sim, _, sink) = solve_in_memory(&scene, two_blocks()).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        sim.dirichlet.held_by_contact.iter().all(|m| m.ends_with("of body 2")),
        "{:?}",
        sim.dirichlet.held_by_contact
    );
    let c = sim.contact.as_ref().unwrap();
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let total: f64 = state.force.iter().sum();
    assert!(
        (total - 0.02).abs() < 1e-10,
        "contact force {total} against the load 0.02"
    );
    for (k, &f) in state.force.iter().enumerate() {
        let pressure = f / c.nodes.weights[k];
        assert!(
            (pressure - 0.01).abs() < 1e-9,
            "pressure {pressure} at contact node {k}"
        );
    }
}
