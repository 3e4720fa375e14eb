//! A mesh of several bodies (pieces connected through their nodes; docs/method.md §7.6–7.7):
//! each is held on its own — by its prescribed components, or by its contact with its free
//! motions pinned as rigid parameters — and one that nothing holds is refused by name.

mod common;

use hvi::app::solve_in_memory;
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::{Cell, Facet, Mesh, PhysicalGroup};
use hvi::scene::Scene;

/// Two blocks 2 × 1 apart in one mesh: the lower (0, 2) × (0, 1) on quadrilaterals, the upper
/// (0, 2) × (2, 3) on triangles, with the groups LowerLeft (x = 0 of the lower), UpperBottom and
/// UpperTop (y = 2 and y = 3 of the upper) and the body Omega.
fn two_blocks() -> Mesh<2> {
    let lower = rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
    let upper = rectangle(2.0, 1.0, 6, 3, CellShape::Tri);
    let offset = lower.points.len();
    let group = |m: &Mesh<2>, name: &str, shift: usize, new: &str, tag: i32| {
        let g = m.groups.iter().find(|g| g.name.as_deref() == Some(name)).unwrap();
        PhysicalGroup {
            dim: 1,
            tag,
            name: Some(new.into()),
            facets: g
                .facets
                .iter()
                .map(|f| Facet::from_slice(&f.nodes().iter().map(|p| p + shift).collect::<Vec<_>>()))
                .collect(),
            cells: vec![],
            nodes: vec![],
        }
    };
    let mut points = lower.points.clone();
    points.extend(upper.points.iter().map(|x| [x[0], x[1] + 2.0]));
    let mut cells = lower.cells.clone();
    cells.extend(upper.cells.iter().map(|c| match c {
        Cell::Tri3(n) => Cell::Tri3(n.map(|p| p + offset)),
        _ => unreachable!("triangles"),
    }));
    let groups = vec![
        group(&lower, "Gamma1", 0, "LowerLeft", 11),
        group(&upper, "Gamma3", offset, "UpperBottom", 13),
        group(&upper, "Gamma2_top", offset, "UpperTop", 14),
        PhysicalGroup {
            dim: 2,
            tag: 5,
            name: Some("Omega".into()),
            facets: vec![],
            cells: (0..cells.len()).collect(),
            nodes: vec![],
        },
    ];
    Mesh {
        path: "<two blocks>".into(),
        points,
        cell_tags: (1..=cells.len()).collect(),
        cells,
        groups,
    }
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
