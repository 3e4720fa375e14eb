//! Global equilibrium at every output step (docs/method.md §14.4): the reactions at the
//! prescribed components, the total contact force of every contact group and the applied loads
//! (traction and body force as assembled) add up to zero. In the discrete equation of a step,
//! K_A u_n + K_B m_n + Cᵀλ = F_n + R at every unknown; a rigid translation e_c is in the kernel
//! of K_A and of K_B (the memory term: K_B is a stiffness of the same strains), so summing
//! component c over all nodes leaves Σ R_c + Σ F_c − Σ (Cᵀλ)_c = 0, exactly up to round-off:
//! the memory term balances itself and appears in the reactions only. Tolerance 1e-10 relative to
//! the largest of the three totals (round-off of sums of O(10³) terms is ~1e-13).

mod common;

use common::scene;
use hvi::app::solve_in_memory;
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::{Facet, Mesh, PhysicalGroup};
use hvi::solver::{RunStats, Simulation};

fn check<const D: usize>(name: &str, sim: &Simulation<D>, stats: &RunStats) {
    let times: Vec<f64> = {
        let mut t: Vec<f64> = stats.contact_forces.iter().map(|r| r.time).collect();
        t.dedup();
        t
    };
    assert!(
        times.len() >= 2,
        "{name}: {} output steps with contact forces",
        times.len()
    );
    let c = sim.contact.as_ref().unwrap();
    let mut worst = 0.0f64;
    for &t in &times {
        let mut load = vec![0.0; sim.dofs.n()];
        sim.loads.assemble(t, &sim.dofs, &mut load).unwrap();
        let mut totals = Vec::new();
        for (k, comp) in ["x", "y", "z"][..D].iter().enumerate() {
            let applied: f64 = (0..sim.mesh.points.len()).map(|p| load[sim.dofs.index(p, k)]).sum();
            let at = |v: &[hvi::solver::stats::Reaction]| -> f64 {
                v.iter()
                    .filter(|r| r.time == t && r.component == *comp)
                    .map(|r| r.force)
                    .sum()
            };
            let groups = stats
                .contact_forces
                .iter()
                .filter(|r| r.time == t && r.component == *comp)
                .count();
            assert_eq!(groups, c.groups.len());
            totals.push((comp, at(&stats.reactions), at(&stats.contact_forces), applied));
        }
        // relative to the step's largest total force (a component without load is ~0 = 0)
        let scale = totals
            .iter()
            .map(|(_, r, c, f)| r.abs().max(c.abs()).max(f.abs()))
            .fold(0.0, f64::max);
        if scale == 0.0 {
            continue;
        }
        for (comp, reactions, contact, applied) in totals {
            let residual = (reactions + contact + applied).abs() / scale;
            worst = worst.max(residual);
            assert!(
                residual < 1e-10,
                "{name}, t = {t}, {comp}: reactions {reactions:e} + contact {contact:e} + loads {applied:e} = {:e}",
                reactions + contact + applied
            );
        }
    }
    println!("{name}: worst relative residual {worst:.1e} over {} steps", times.len());
}

/// The paper's example (2D, memory, odd law and bound), h = 1/16.
#[test]
fn paper_example_is_in_equilibrium_at_every_step() {
    let mesh = hvi::mesh::read_mesh::<2>(std::path::Path::new("meshes/rect_q1_h16.msh")).unwrap();
    let s = hvi::scene::Scene::load(None, &["time.steps = 16".into()]).unwrap();
    let (sim, stats, _) = solve_in_memory(&s, mesh).unwrap();
    // the contact does carry load: the check is not 0 = 0
    assert!(stats.contact_forces.iter().any(|r| r.force.abs() > 1e-3));
    check("paper", &sim, &stats);
}

/// The slab (3D, the paper's data extruded, u_z = 0 on the z faces).
#[test]
fn slab_is_in_equilibrium_at_every_step() {
    let mesh = hvi::mesh::read_mesh::<3>(std::path::Path::new("meshes/slab_q1_h8_z1.msh")).unwrap();
    let s = hvi::scene::Scene::load(
        Some(std::path::Path::new("examples/slab.toml")),
        &["time.steps = 8".into()],
    )
    .unwrap();
    let (sim, stats, _) = solve_in_memory(&s, mesh).unwrap();
    assert!(stats.contact_forces.iter().any(|r| r.force.abs() > 1e-3));
    check("slab", &sim, &stats);
}

/// The rectangle with its bottom split into two contact groups at x = 1/2 (one node shared):
/// "Left" on the paper's layer, "Right" on a plane obstacle at a gap with a power law; the paper's
/// memory and a downward traction on the top.
pub fn two_zone_mesh() -> Mesh<2> {
    let mut mesh = rectangle(1.0, 0.5, 16, 8, CellShape::Quad);
    let bottom: Vec<Facet> = mesh
        .groups
        .iter()
        .find(|g| g.name.as_deref() == Some("Gamma3"))
        .unwrap()
        .facets
        .clone();
    for (name, tag, left) in [("Left", 91, true), ("Right", 92, false)] {
        let facets = bottom
            .iter()
            .copied()
            .filter(|f| {
                f.nodes()
                    .iter()
                    .all(|&p| (mesh.points[p][0] <= 0.5 + 1e-12) == left || mesh.points[p][0] == 0.5)
            })
            .collect();
        mesh.groups.push(PhysicalGroup {
            dim: 1,
            tag,
            name: Some(name.into()),
            facets,
            cells: vec![],
            nodes: vec![],
        });
    }
    mesh
}

const TWO_ZONES: &str = "[groups]\nclamped = \"Gamma1\"\n[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
    [memory]\nkind = \"polynomial\"\ncoefficients = [0.25, 1.0, 1.0]\n[time]\nfinal_time = 1.0\nsteps = 8\n\
    [[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"0.01\", \"-0.2*t\"]\n\
    [[contact]]\ngroup = \"Left\"\nbound = 0.02\n[contact.law]\nkind = \"paper\"\nscale = 0.1\na = 0.04\nb = 0.02\nalpha = 100.0\n\
    [[contact]]\ngroup = \"Right\"\nobstacle = { kind = \"plane\", point = [0.0, -0.01], normal = [0.0, 1.0] }\n\
    [contact.law]\nkind = \"power\"\nscale = 5.0\nexponent = 1.0\n";

#[test]
fn two_contact_groups_are_in_equilibrium_at_every_step() {
    let (sim, stats, _) = solve_in_memory(&scene(TWO_ZONES), two_zone_mesh()).unwrap();
    let c = sim.contact.as_ref().unwrap();
    assert_eq!(c.groups, vec!["Left".to_string(), "Right".to_string()]);
    // the shared node x = 1/2 is one row (same wall), carrying both groups' laws
    let mid = sim.mesh.points.iter().position(|x| *x == [0.5, 0.0]).unwrap();
    let rows: Vec<usize> = (0..c.nodes.len()).filter(|&k| c.nodes.nodes[k] == mid).collect();
    assert_eq!(rows.len(), 1);
    assert_eq!(c.laws.terms(rows[0]).len(), 2);
    for g in ["Left", "Right"] {
        assert!(
            stats
                .contact_forces
                .iter()
                .any(|r| r.group == g && r.component == "y" && r.force > 1e-4),
            "{g} carries load"
        );
    }
    check("two zones", &sim, &stats);
}
