//! Rigid obstacles, initial gaps, the direction of the constraint and corners (docs/method.md
//! §14), against answers known exactly.

mod common;

use common::{scene, step_differences};
use hvi::app::solve_in_memory;
use hvi::contact::NodeStatus;
use hvi::mesh::structured::{rectangle, CellShape};

/// A 1 × 0.5 block whose top is pushed down by δ(t) = 0.2 t (x held), contact on the bottom.
fn pushed_block(contact: &str) -> String {
    format!(
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 10\n\
         [[dirichlet]]\ngroup = \"Gamma2_top\"\ncomponents = [\"x\", \"y\"]\nvalue = [\"0\", \"-0.2*t\"]\n{contact}"
    )
}

/// A flat body over a plane at a gap of 0.05: no force at all while the gap is open (δ ≤ 0.04,
/// the body only translates), then every bottom node on the plane (u_y = −0.05) — and the same
/// run as the layer of the paper with bound g = 0.05 (on a flat face the obstacle's normal is the
/// body's, so the two problems are one).
#[test]
fn plane_at_a_gap_carries_nothing_until_it_closes_then_is_the_bound() {
    let mesh = rectangle(1.0, 0.5, 8, 4, CellShape::Quad);
    let obstacle = "[contact]\nobstacle = { kind = \"plane\", point = [0.0, -0.05], normal = [0.0, 1.0] }\n";
    let (sim, _, sink) = solve_in_memory(&scene(&pushed_block(obstacle)), mesh.clone()).unwrap();
    let c = sim.contact.as_ref().unwrap();
    assert_eq!(c.nodes.len(), 9);
    for g in c.gap.as_ref().unwrap() {
        assert!((g - 0.05).abs() < 1e-15, "gap {g}");
    }
    for s in &sink.steps {
        let state = s.contact.as_ref().unwrap();
        let delta = 0.2 * s.time;
        let u = sim.dofs.to_nodal(&s.displacement);
        if delta < 0.05 - 1e-9 {
            // a rigid translation: K u = 0, so the forces are round-off of the solve
            assert!(
                state.force.iter().all(|f| f.abs() < 1e-14),
                "t = {}: {:?}",
                s.time,
                state.force
            );
            assert!(state.status.iter().all(|st| *st == NodeStatus::Separated));
            for x in &u {
                assert!((x[1] + delta).abs() < 1e-13);
            }
        } else if delta > 0.05 + 1e-9 {
            assert!(
                state.status.iter().all(|st| *st == NodeStatus::OnBound),
                "t = {}",
                s.time
            );
            assert!(state.force.iter().all(|f| *f > 0.0));
            for &p in &c.nodes.nodes {
                assert!((u[p][1] + 0.05).abs() < 1e-13, "t = {}: u_y = {}", s.time, u[p][1]);
            }
        }
    }
    let layer = "[contact]\nbound = 0.05\n";
    let (_, _, twin) = solve_in_memory(&scene(&pushed_block(layer)), mesh).unwrap();
    for (n, d) in step_differences(&sink, &twin) {
        assert!(d < 1e-12, "step {n}: obstacle and layer differ by {d:e}");
    }
}

/// The paper's example with its foundation written as an obstacle touching Γ₃ (a plane through
/// y = 0 with the layer's law and bound on it) is the paper's example.
#[test]
fn paper_with_a_touching_plane_is_the_paper() {
    let mesh = hvi::mesh::read_mesh::<2>(std::path::Path::new("meshes/rect_q1_h16.msh")).unwrap();
    let paper = hvi::scene::Scene::load(None, &["time.steps = 8".into()]).unwrap();
    let plane = hvi::scene::Scene::load(
        None,
        &[
            "time.steps = 8".into(),
            "contact.obstacle = { kind = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }".into(),
        ],
    )
    .unwrap();
    let (_, _, a) = solve_in_memory(&paper, mesh.clone()).unwrap();
    let (sim, _, b) = solve_in_memory(&plane, mesh).unwrap();
    assert!(sim
        .contact
        .as_ref()
        .unwrap()
        .gap
        .as_ref()
        .unwrap()
        .iter()
        .all(|g| *g == 0.0));
    for (n, d) in step_differences(&a, &b) {
        assert!(d < 1e-12, "step {n}: {d:e}");
    }
}

/// The paper's odd law pulls a node back toward the layer it is glued to. A node that starts at
/// a gap never touched: pulled away from the obstacle (a traction upward on the top), it feels no
/// force, and the body moves as without contact.
#[test]
fn a_gapped_node_is_not_pulled_by_the_odd_law() {
    let contact = |obstacle: &str| {
        format!(
            "[groups]\nclamped = \"Gamma1\"\n[material]\nplane = \"stress\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
             [time]\nfinal_time = 1.0\nsteps = 2\n[[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"0\", \"0.01*t\"]\n\
             [contact]\n{obstacle}[contact.law]\nkind = \"paper\"\nscale = 0.1\na = 0.04\nb = 0.02\nalpha = 100.0\n"
        )
    };
    let mesh = rectangle(1.0, 0.5, 8, 4, CellShape::Quad);
    let gapped = contact("obstacle = { kind = \"plane\", point = [0.0, -0.01], normal = [0.0, 1.0] }\n");
    let (_, _, a) = solve_in_memory(&scene(&gapped), mesh.clone()).unwrap();
    let touching = contact("obstacle = { kind = \"plane\", point = [0.0, 0.0], normal = [0.0, 1.0] }\n");
    let (_, _, b) = solve_in_memory(&scene(&touching), mesh.clone()).unwrap();
    let last = |s: &hvi::app::MemorySink| s.steps.last().unwrap().contact.clone().unwrap();
    // gapped: the one-sided law at a separation of ≥ 0.01 ≫ ε exerts exactly nothing
    assert!(last(&a).force.iter().all(|f| f.abs() < 1e-15), "{:?}", last(&a).force);
    // touching: the glued layer holds the bottom back (the paper's adhesion)
    assert!(last(&b).force.iter().any(|f| *f < -1e-4), "{:?}", last(&b).force);
    let free = "[groups]\nclamped = \"Gamma1\"\n[material]\nplane = \"stress\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                [time]\nfinal_time = 1.0\nsteps = 2\n[[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"0\", \"0.01*t\"]\n";
    let (_, _, c) = solve_in_memory(&scene(free), mesh).unwrap();
    for (n, d) in step_differences(&a, &c) {
        assert!(d < 1e-12, "step {n}: {d:e}");
    }
}

/// A disc below a flat face: along the obstacle's normal the gap is the distance to the disc,
/// |x − c| − R, along the body's normal (straight down) it is the vertical distance to the arc,
/// −c_y − √(R² − (x − c_x)²) (a different number everywhere but under the centre). Pressed down,
/// each run meets its own constraint d·u ≤ gap with equality on the bound.
#[test]
fn the_two_directions_differ_on_a_disc_and_each_holds() {
    let (cx, cy, r) = (0.5, -0.8, 0.75);
    let run = |direction: &str| {
        let text = pushed_block(&format!(
            "[contact]\nobstacle = {{ kind = \"circle\", centre = [{cx}, {cy}], radius = {r} }}\ndirection = \"{direction}\"\n"
        ));
        solve_in_memory(&scene(&text), rectangle(1.0, 0.5, 16, 4, CellShape::Quad)).unwrap()
    };
    for direction in ["obstacle", "body"] {
        let (sim, _, sink) = run(direction);
        let c = sim.contact.as_ref().unwrap();
        let gap = c.gap.as_ref().unwrap();
        for (k, &p) in c.nodes.nodes.iter().enumerate() {
            let x = sim.mesh.points[p];
            let (dx, dy) = (x[0] - cx, x[1] - cy);
            let expected = if direction == "obstacle" {
                (dx * dx + dy * dy).sqrt() - r
            } else {
                -cy - (r * r - dx * dx).sqrt() - x[1]
            };
            assert!(
                (gap[k] - expected).abs() < 1e-13,
                "{direction}: gap {} vs {expected}",
                gap[k]
            );
            let d = c.nodes.normals[k];
            if direction == "obstacle" {
                let len = (dx * dx + dy * dy).sqrt();
                assert!((d[0] + dx / len).abs() < 1e-13 && (d[1] + dy / len).abs() < 1e-13);
            } else {
                assert!((d[0]).abs() < 1e-15 && (d[1] + 1.0).abs() < 1e-15);
            }
        }
        let last = sink.steps.last().unwrap();
        let state = last.contact.as_ref().unwrap();
        let mut un = vec![0.0; c.nodes.len()];
        c.nodes.normal_displacements(&last.displacement, &mut un);
        let on = state.status.iter().filter(|s| **s == NodeStatus::OnBound).count();
        assert!(on >= 3 && on < c.nodes.len(), "{direction}: {on} nodes on the disc");
        for k in 0..un.len() {
            assert!(un[k] <= gap[k] + 1e-12, "{direction}: row {k} penetrates");
            if state.status[k] == NodeStatus::OnBound {
                assert!((un[k] - gap[k]).abs() < 1e-12);
            } else {
                assert!(state.force[k].abs() < 1e-12);
            }
        }
    }
}

/// Corners. One group around a corner of the body (Gamma2 = right side + top): the corner node
/// gets one row per face, along each face's normal, each with its face's share of the weight
/// (together the node's weight); pushed into both walls, the corner stays inside both.
#[test]
fn corners_get_a_constraint_per_wall() {
    let text = "[groups]\nclamped = \"Gamma1\"\ncontact = \"Gamma2\"\n[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\n\
                poisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n[body_force]\nvalue = [\"1\", \"1\"]\n[contact]\nbound = 0.01\n";
    let mesh = rectangle(1.0, 1.0, 4, 4, CellShape::Quad);
    let (sim, _, sink) = solve_in_memory(&scene(text), mesh).unwrap();
    let c = sim.contact.as_ref().unwrap();
    let corner = sim.mesh.points.iter().position(|x| *x == [1.0, 1.0]).unwrap();
    let rows: Vec<usize> = (0..c.nodes.len()).filter(|&k| c.nodes.nodes[k] == corner).collect();
    assert_eq!(rows.len(), 2, "the corner carries one row per face");
    let mut dirs: Vec<[f64; 2]> = rows.iter().map(|&k| c.nodes.normals[k]).collect();
    dirs.sort_by(|a, b| a[0].partial_cmp(&b[0]).unwrap());
    assert_eq!(dirs, vec![[0.0, 1.0], [1.0, 0.0]]);
    for &k in &rows {
        assert!((c.nodes.weights[k] - 0.125).abs() < 1e-15, "half an edge of each face");
    }
    let total: f64 = c.nodes.weights.iter().sum();
    assert!(
        (total - 1.875).abs() < 1e-14,
        "the weights add up to |Γ₃| less the clamped node's share: {total}"
    );
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    assert!(u[corner][0] <= 0.01 + 1e-13 && u[corner][1] <= 0.01 + 1e-13);
    assert!(
        (u[corner][0] - 0.01).abs() < 1e-12 && (u[corner][1] - 0.01).abs() < 1e-12,
        "{:?}",
        u[corner]
    );
}
