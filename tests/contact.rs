//! Contact against hand-derivable answers, and the contact law and complementarity at every
//! node of every step of the paper's example.
//!
//! The column: Ω = (0,1)², clamped on top, contact on the bottom, plane stress with ν = 0,
//! body force (0, −ρ). Then u = (0, v(y)) with E v'' = ρ, v(1) = 0, σ₂₂ = E v' exactly (the
//! sides are traction-free), and the bottom contact pressure p = −σ₂₂(0) with r = u_ν = −v(0):
//! r = ρ/(2E) − p/E. Q1 elements are nodally exact for this 1D problem, and the nodal
//! contact quadrature is exact for a uniform r, so every bottom node must show the exact r.
//! (Not P1 on the structured triangulation: there the bottom corners carry unequal shares of
//! the body force, h²/6 and h²/3, so the discrete solution is not a 1D column.)

mod common;

use common::scene;
use hvi::app::solve_in_memory;
use hvi::mesh::structured::{rectangle, CellShape};

const LAW: &str =
    "[contact.law]\nkind = \"paper\"\nscale = 0.1\na = 0.04\nb = 0.02\nalpha = 100.0\nregularisation = 1e-12\n";

fn column_scene(rho: f64, contact: &str) -> String {
    format!(
        "[groups]\nclamped = \"Gamma2_top\"\ncontact = \"Gamma3\"\n[material]\nplane = \"stress\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.0\n[time]\nfinal_time = 1.0\nsteps = 1\n[body_force]\nvalue = [\"0\", \"{}\"]\n{contact}",
        -rho
    )
}

/// μ(s) of the paper's law with S = 0.1.
fn paper_force(r: f64) -> f64 {
    0.1 * (0.02 * (-100.0 * r).exp() + 0.02)
}

fn run_column(rho: f64, contact: &str, shape: CellShape) -> Vec<(f64, f64, f64)> {
    let mesh = rectangle(1.0, 1.0, 6, 6, shape);
    let (sim, _, sink) = solve_in_memory(&scene(&column_scene(rho, contact)), mesh).unwrap();
    let c = sim.contact.as_ref().unwrap();
    let last = sink.steps.last().unwrap();
    let state = last.contact.as_ref().unwrap();
    let mut normal = vec![0.0; c.nodes.len()];
    c.nodes.normal_displacements(&last.displacement, &mut normal);
    // the callers assert over every row: no row would prove nothing
    assert!(!c.nodes.is_empty(), "no contact node");
    (0..c.nodes.len())
        .map(|k| (normal[k], state.force[k] / c.nodes.weights[k], state.bound_force[k]))
        .collect()
}

/// Compliance only (no bound): r = ρ/2 − S μ(r), solved by bisection.
#[test]
fn column_on_the_compliant_layer() {
    let rho = 0.2;
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid - (rho / 2.0 - paper_force(mid)) > 0.0 {
            hi = mid
        } else {
            lo = mid
        }
    }
    let r = 0.5 * (lo + hi);
    {
        let shape = CellShape::Quad;
        for (un, p, _) in run_column(rho, &format!("[contact]\n{LAW}"), shape) {
            assert!((un - r).abs() < 1e-10, "u_ν {un} vs exact {r}");
            assert!((p - paper_force(r)).abs() < 1e-10, "pressure {p} vs {}", paper_force(r));
        }
    }
}

/// A load that stays below the bound g = 0.2: the bound is inactive, same answer as above.
#[test]
fn column_below_the_bound() {
    let rho = 0.2;
    let free = run_column(rho, &format!("[contact]\n{LAW}"), CellShape::Quad);
    let bounded = run_column(rho, &format!("[contact]\nbound = 0.2\n{LAW}"), CellShape::Quad);
    assert_eq!(free.len(), bounded.len(), "the runs have different contact nodes");
    assert!(!free.is_empty(), "no contact node: nothing compared");
    for ((a, pa, _), (b, pb, eta)) in free.iter().zip(&bounded) {
        assert!(*b < 0.2 && (a - b).abs() < 1e-12 && (pa - pb).abs() < 1e-12 && *eta == 0.0);
    }
}

/// A load that reaches the bound: r = g and p = ρ/2 − E g, of which S μ(g) is the layer's and
/// the rest η = p − S μ(g) ≥ 0 the rigid bound's.
#[test]
fn column_reaching_the_bound() {
    let (rho, g) = (0.6, 0.2);
    {
        let shape = CellShape::Quad;
        for (un, p, eta_nodal) in run_column(rho, &format!("[contact]\nbound = {g}\n{LAW}"), shape) {
            assert!((un - g).abs() < 1e-12, "u_ν {un}");
            let p_exact = rho / 2.0 - g;
            assert!((p - p_exact).abs() < 1e-10, "pressure {p} vs {p_exact}");
            assert!(eta_nodal > 0.0);
        }
    }
}

/// Bound only (no compliance): rigid contact, p = ρ/2 − E g.
#[test]
fn column_on_a_rigid_bound() {
    let (rho, g) = (0.6, 0.2);
    for (un, p, _) in run_column(rho, &format!("[contact]\nbound = {g}\n"), CellShape::Quad) {
        assert!((un - g).abs() < 1e-12 && (p - (rho / 2.0 - g)).abs() < 1e-10);
    }
}

/// The paper's example at h = k = 1/16 (Q1, square cells): at every contact node of every
/// step, u_ν ≤ g, (u_ν − g)·η = 0 to 1e-10, the force is at least the compliance law's, and
/// off the bound the force equals it (to the solver tolerance); the bound is reached on the
/// right part of Γ₃ at T.
#[test]
fn paper_example_satisfies_the_contact_law_at_every_node_and_step() {
    let mesh = hvi::mesh::read_mesh::<2>(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/meshes/rect_q1_h16.msh"
    )))
    .unwrap();
    let sc = hvi::scene::Scene::load(None, &["time.steps=16".to_string()]).unwrap();
    let (sim, stats, sink) = solve_in_memory(&sc, mesh).unwrap();
    assert_eq!(sink.steps.len(), 17);
    let c = sim.contact.as_ref().unwrap();
    let law = c.law().unwrap();
    let g = c.bound.as_ref().unwrap();
    for s in &sink.steps {
        let st = s.contact.as_ref().unwrap();
        let mut un = vec![0.0; c.nodes.len()];
        c.nodes.normal_displacements(&s.displacement, &mut un);
        let scale = st.force.iter().fold(1e-300f64, |a, f| a.max(f.abs()));
        for k in 0..c.nodes.len() {
            let xi = c.nodes.weights[k] * law.derivative(un[k]);
            assert!(un[k] <= g[k] + 1e-12, "step {} node {k}: u_ν {} > g", s.step, un[k]);
            assert!(
                ((un[k] - g[k]) * st.bound_force[k]).abs() <= 1e-10,
                "complementarity at step {} node {k}",
                s.step
            );
            assert!(st.bound_force[k] >= -1e-9 * scale, "η < 0 at step {} node {k}", s.step);
            assert!(
                st.force[k] - xi >= -1e-8 * scale,
                "force below the law at step {} node {k}",
                s.step
            );
            if st.bound_force[k] == 0.0 {
                assert!(
                    (st.force[k] - xi).abs() <= 1e-8 * scale,
                    "law violated off the bound at step {} node {k}",
                    s.step
                );
            }
        }
    }
    // The body rests on the bound over the right part of Γ₃ at T, not on the left.
    let last = sink.steps.last().unwrap().contact.as_ref().unwrap();
    for (k, &p) in c.nodes.nodes.iter().enumerate() {
        let x = sim.mesh.points[p][0];
        let on = last.status[k] == hvi::contact::NodeStatus::OnBound;
        if x > 1.6 {
            assert!(on, "node at x = {x} should be on the bound");
        }
        if x < 1.0 {
            assert!(!on, "node at x = {x} should be off the bound");
        }
    }
    assert!(
        stats.newton_iterations.iter().all(|&i| i <= 30),
        "{:?}",
        stats.newton_iterations
    );
}
