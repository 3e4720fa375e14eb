//! The warnings `hvi check` prints and `hvi solve` prints before running (and keeps in
//! summary.json): the mesh's defects as one body (docs/method.md §16.3), then the scene's
//! set-ups that are valid but probably unintended (docs/method.md §14.5).

use crate::mesh::Mesh;
use crate::scene::Scene;
use crate::solver::{Simulation, SolveError};

/// The mesh's defects as one conforming body (docs/method.md §16.3): an error naming the severe
/// ones unless `accept`; else every defect as a warning (what `hvi check` and `hvi solve` print).
pub fn mesh_warnings<const D: usize>(mesh: &Mesh<D>, scene: &Scene, accept: bool) -> Result<Vec<String>, SolveError> {
    // the surfaces of contact between two bodies may share coordinates (docs/method.md §18)
    let interface: Vec<usize> = scene
        .contact
        .iter()
        .filter(|c| c.target.is_some())
        .flat_map(|c| c.group.iter().chain(c.target.iter()))
        .filter_map(|g| mesh.group_nodes(g).ok())
        .flatten()
        .collect();
    let defects = mesh.defects_besides(&interface);
    let severe: Vec<&str> = defects
        .iter()
        .filter(|d| d.severe)
        .map(|d| d.message.as_str())
        .collect();
    if !severe.is_empty() && !accept {
        return Err(SolveError::Mesh(crate::mesh::MeshError::Defects {
            path: mesh.path.clone(),
            detail: severe.join("; "),
        }));
    }
    Ok(defects.into_iter().map(|d| d.message).collect())
}

/// Everything `hvi check` warns about and `hvi solve` prints before running: the mesh's
/// accepted defects, then the scene's set-ups that are valid but probably unintended.
pub fn warnings<const D: usize>(mesh_warnings: Vec<String>, scene: &Scene, sim: &Simulation<D>) -> Vec<String> {
    let mut out = mesh_warnings;
    out.extend(crate::solver::advice::warnings(scene, sim));
    out
}
