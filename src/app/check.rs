//! `hvi check`: what a run would do and cost, without running it (docs/usage.md "Checking and solving").

use super::solve::read_mesh;
use crate::mesh::{AnyMesh, Mesh};
use crate::scene::Scene;
use crate::solver::faer::ElasticCheck;
use crate::solver::memory::{memory_limit, MemoryEstimate};
use crate::solver::{Plan, Simulation, SolveError};
use std::path::Path;

/// The report of `hvi check`. Severe mesh defects are an error unless `accept_mesh_defects`
/// (then warnings, as in a run).
pub fn check(
    mesh_path: &Path,
    scene_path: Option<&Path>,
    overrides: &[String],
    accept_mesh_defects: bool,
) -> Result<String, SolveError> {
    let scene = Scene::load(scene_path, overrides)?;
    match read_mesh(mesh_path)? {
        AnyMesh::Two(m) => check_dim(mesh_path, scene_path, &scene, m, accept_mesh_defects),
        AnyMesh::Three(m) => check_dim(mesh_path, scene_path, &scene, m, accept_mesh_defects),
    }
}

/// [`check`] on a mesh of dimension D.
fn check_dim<const D: usize>(
    mesh_path: &Path,
    scene_path: Option<&Path>,
    scene: &Scene,
    mesh: Mesh<D>,
    accept_mesh_defects: bool,
) -> Result<String, SolveError> {
    use std::fmt::Write;
    let mut out = check_mesh_report(mesh_path, &mesh);
    let mesh_warnings = super::warnings::mesh_warnings(&mesh, scene, accept_mesh_defects)?;
    let sim = Simulation::new(scene, mesh)?;
    sim.check_data()?;
    out.push_str(&check_scene_report(scene_path, &sim));
    // The factor: symbolic analysis only (cheap), so its size is known before solving.
    // (the solver layer's own assembly and analysis of K_A, as a run does them)
    let elastic = ElasticCheck::new(&sim)?;
    let analysis = elastic.analysis();
    let _ = writeln!(
        out,
        "factor: {} ordering, nnz(L) = {} ({})",
        analysis.ordering(),
        analysis.factor_entries(),
        crate::solver::memory::size(8 * analysis.factor_entries() as u64)
    );
    // the run's own prediction and refusal (docs/method.md §16.1)
    let estimate = MemoryEstimate::new(&sim, analysis, elastic.matrix_entries());
    let _ = writeln!(out, "memory: predicted peak {}", estimate.describe());
    if let Some(limit) = memory_limit() {
        let _ = writeln!(
            out,
            "  this process may use {} ({})",
            crate::solver::memory::size(limit.bytes),
            limit.what
        );
    }
    estimate
        .check_fits(sim.contact.as_ref().map_or(0, |c| c.condensed_rows().len()))
        .map_err(|e| SolveError::OutOfMemory(format!("{}: {e}", mesh_path.display())))?;
    if let Some(c) = &sim.contact {
        // rows per group (a corner node counts once per wall, docs/method.md §14.3)
        let per_group: Vec<String> = c
            .groups
            .iter()
            .enumerate()
            .map(|(i, g)| format!("\"{g}\" ({})", c.row_group.iter().filter(|&&r| r == i).count()))
            .collect();
        let _ = writeln!(out, "contact: {} rows on {}", c.nodes.len(), per_group.join(", "));
        // contact with another body: the pairing (docs/method.md §18)
        for (name, s) in &c.pairs {
            let _ = writeln!(
                out,
                "  pair {name}: {} slave nodes paired, {} off the target (no row); largest initial gap {:.3e}, deepest \
                 initial penetration {:.3e}; facets {:.3e} on the target's {:.3e}",
                s.paired, s.unpaired, s.largest_gap, s.deepest_penetration, s.slave_size, s.master_size
            );
        }
        if !c.laws.is_empty() {
            let ratio = elastic.smallness_ratio(&sim)?;
            let _ = writeln!(
                out,
                "  smallness condition (discrete, energy norm of A): α_j·c² = {:.3} ({})",
                ratio,
                if ratio < 1.0 && softening_memory(&sim) {
                    "holds with A; but b(0) < 0 makes the step matrix K softer than K_A, so the step energy is convex \
                     only if it also holds with K: see `smallness` in the run's summary.json (docs/method.md §15.3)"
                } else if ratio < 1.0 {
                    "holds: every step's energy is convex"
                } else {
                    "FAILS: the step energy is non-convex; the globalised solver handles it, but uniqueness is not guaranteed"
                }
            );
        }
    }
    for w in &super::warnings::warnings(mesh_warnings, scene, &sim) {
        let _ = writeln!(out, "warning: {w}");
    }
    Ok(out)
}

/// The mesh part of `hvi check`'s report: counts, cell sizes, physical groups.
pub(crate) fn check_mesh_report<const D: usize>(mesh_path: &Path, mesh: &Mesh<D>) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(out, "mesh {}", mesh_path.display());
    let count = |name: &str| mesh.cells.iter().filter(|c| c.name() == name).count();
    let kinds: Vec<String> = if D == 2 {
        vec![
            format!("{} triangles", count("triangle")),
            format!("{} quadrilaterals", count("quadrangle")),
        ]
    } else {
        let mut kinds = vec![
            format!("{} tetrahedra", count("tetrahedron")),
            format!("{} hexahedra", count("hexahedron")),
        ];
        if count("prism") > 0 {
            kinds.push(format!("{} prisms", count("prism")));
        }
        if count("pyramid") > 0 {
            kinds.push(format!("{} pyramids", count("pyramid")));
        }
        kinds
    };
    let _ = writeln!(
        out,
        "  {D}D: {} nodes, {} cells ({})",
        mesh.points.len(),
        mesh.cells.len(),
        kinds.join(", ")
    );
    let (hmin, hmax) = mesh.cell_size();
    let _ = writeln!(out, "  cell size h: {hmin:.4e} … {hmax:.4e}");
    let _ = writeln!(out, "  physical groups:");
    for g in &mesh.groups {
        let _ = writeln!(
            out,
            "    dim {} tag {:>3} {:<14} {} facets, {} cells",
            g.dim,
            g.tag,
            g.name.as_deref().unwrap_or("(no name)"),
            g.facets.len(),
            g.cells.len()
        );
    }
    out
}

/// The scene part of `hvi check`'s report: unknowns, time steps and the plan.
pub(crate) fn check_scene_report<const D: usize>(scene_path: Option<&Path>, sim: &Simulation<D>) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "scene {}",
        scene_path.map_or("<embedded default: examples/paper.toml>".to_string(), |p| p
            .display()
            .to_string())
    );
    let _ = writeln!(
        out,
        "  unknowns: {} free ({} prescribed components kept as identity rows)",
        sim.dofs.n_free(),
        sim.dofs.n_prescribed()
    );
    let _ = writeln!(out, "  time: {}", sim.time.describe());
    let counts = sim.materials.cell_counts(sim.mesh.cells.len());
    let _ = writeln!(out, "  materials (docs/method.md §8.5):");
    for (m, count) in sim.materials.list().iter().zip(counts) {
        let _ = writeln!(
            out,
            "    {:<24} {count} cells, E = {}, ν = {}{}",
            m.name,
            m.elasticity.youngs_modulus,
            m.elasticity.poisson_ratio,
            if m.memory.is_some() { ", with memory" } else { "" }
        );
    }
    let _ = writeln!(out, "plan:");
    let _ = write!(out, "{}", Plan::new(sim));
    out
}

/// True when the memory's share of the step matrix, Σ_j β_j T_j, has a negative eigenvalue at
/// the first step (b(0) < 0, a relaxing material): K is then softer than K_A in some strain.
fn softening_memory<const D: usize>(sim: &Simulation<D>) -> bool {
    let k = sim.time.first_step();
    sim.materials.list().iter().filter_map(|m| m.memory.as_ref()).any(|m| {
        let s = m.step_share(k, sim.rules);
        s.mu < 0.0 || 2.0 * s.mu + D as f64 * s.lambda < 0.0
    })
}
