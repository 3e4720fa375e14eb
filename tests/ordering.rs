//! Which unknowns the factor orders last (docs/method.md §9.1, §9.9): the contact normals only
//! where Q is read off the factor's trailing block, so that a contact face whose normals are
//! oblique (a sphere's) leaves the ordering unconstrained; and the blocked sweeps that form G
//! there give the steps of the stored responses.

mod common;

use common::step_differences;
use hvi::app::solve_in_memory;
use hvi::linalg::Factor;
use hvi::mesh::{read_mesh, Mesh};
use hvi::scene::Scene;
use hvi::solver::Simulation;
use std::path::{Path, PathBuf};

fn gallery() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/hertz_3d")
}

fn hertz_mesh() -> Mesh<3> {
    read_mesh::<3>(&gallery().join("hertz_3d.msh")).unwrap_or_else(|e| panic!("{e}"))
}

/// The gallery's 3D Hertz scene, with `sets` (e.g. the sphere as an obstacle).
fn hertz_scene(sets: &[&str]) -> Scene {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::load(Some(&gallery().join("hertz_3d.toml")), &sets).unwrap_or_else(|e| panic!("{e}"))
}

/// The sphere of the Hertz scene as a rigid obstacle instead of the gap along the top's normal:
/// each contact row then runs along the sphere's normal, over a node's three unknowns.
const SPHERE: [&str; 2] = [
    "contact.bound=0.0",
    "contact.obstacle={ kind = \"sphere\", centre = [0.0, 0.0, 1.0], radius = 1.0 }",
];

/// nnz(L) of the run's analysis and of the unconstrained one, and how many unknowns go last.
fn fill(sim: &Simulation<3>) -> (usize, usize, usize) {
    let k = sim
        .materials
        .assemble_elastic(&sim.mesh.cells, &sim.mesh.points, &sim.dofs)
        .with_identity_rows(&sim.dofs);
    let last = sim.unknowns_ordered_last();
    let run = Factor::analyse_with_last(&k, &last).unwrap().factor_entries();
    let free = Factor::analyse(&k).unwrap().factor_entries();
    (run, free, last.len())
}

#[test]
fn the_normals_go_last_only_where_q_is_read_off_the_trailing_block() {
    // the top's normal, along z: one unknown per row, Q off the trailing block, normals last
    let axis = Simulation::new(&hertz_scene(&[]), hertz_mesh()).unwrap();
    assert!(axis.trailing_block());
    let (_, _, last) = fill(&axis);
    assert_eq!(last, axis.contact.as_ref().unwrap().nodes.len());
    // the sphere's normals: three unknowns per row, no constraint, the factor of the
    // unconstrained ordering (with the normals last it held 1.7× as many entries)
    let sphere = Simulation::new(&hertz_scene(&SPHERE), hertz_mesh()).unwrap();
    assert!(!sphere.trailing_block());
    let (run, free, last) = fill(&sphere);
    assert_eq!(last, 0);
    assert_eq!(run, free);
}

#[test]
fn blocked_sweeps_give_the_steps_of_the_stored_responses() {
    let run = |kind: &str| {
        let mut sets = SPHERE.to_vec();
        let condensation = format!("solver.condensation=\"{kind}\"");
        sets.push(&condensation);
        solve_in_memory(&hertz_scene(&sets), hertz_mesh()).unwrap()
    };
    let (sim, stats, split) = run("split_sweeps");
    let (_, stats_z, stored) = run("stored_responses");
    let m = sim.contact.as_ref().unwrap().condensed_rows().len();
    assert!(
        m >= hvi::linalg::BLOCKED_FROM_COLUMNS,
        "{m} rows: the sweeps are blocked"
    );
    assert_eq!(stats.sparse_forward_sweeps, m);
    assert!(stats_z.condensation.as_deref().unwrap().starts_with("stored"));
    for (step, diff) in step_differences(&split, &stored) {
        assert!(diff <= 1e-10, "step {step}: condensations differ by {diff:e}");
    }
    let touching = split
        .steps
        .last()
        .unwrap()
        .contact
        .as_ref()
        .unwrap()
        .bound_force
        .iter()
        .filter(|&&f| f > 0.0)
        .count();
    assert!(touching > 10, "the sphere is pressed in ({touching} nodes)");
}

/// METIS keeps its random state in process globals: calls from several threads at once raced
/// and gave orderings that differed from run to run (CI saw this file's first test's nnz(L)
/// move by 0.4 %). Every call holds one lock; the same pattern gives the same factor.
#[test]
fn nested_dissection_is_the_same_on_threads_at_once() {
    let sim = Simulation::new(&hertz_scene(&SPHERE), hertz_mesh()).unwrap();
    let k = sim
        .materials
        .assemble_elastic(&sim.mesh.cells, &sim.mesh.points, &sim.dofs)
        .with_identity_rows(&sim.dofs);
    let entries = || {
        Factor::analyse_with(&k, hvi::linalg::NodeOrdering::NestedDissection)
            .unwrap()
            .factor_entries()
    };
    let alone = entries();
    let at_once: Vec<usize> = std::thread::scope(|s| {
        let threads: Vec<_> = (0..4)
            .map(|_| s.spawn(|| (0..3).map(|_| entries()).collect::<Vec<_>>()))
            .collect();
        threads.into_iter().flat_map(|t| t.join().unwrap()).collect()
    });
    assert!(
        at_once.iter().all(|&e| e == alone),
        "{alone} alone, {at_once:?} at once"
    );
}
