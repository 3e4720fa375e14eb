//! Shared helpers of the integration tests.
#![allow(dead_code)]

use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::{Mesh, PhysicalGroup};
use hvi::scene::Scene;

/// A scene from TOML text (panics with the error, which names the key).
pub fn scene(toml: &str) -> Scene {
    Scene::from_toml_str(toml, "<test scene>").unwrap_or_else(|e| panic!("{e}"))
}

/// The rectangle (0, lx) × (0, ly) with nx × ny cells and its groups (Gamma1 left, Gamma2
/// right+top, Gamma3 bottom, Gamma2_top top) plus a "Right" group for the right side.
pub fn rectangle_with_sides(lx: f64, ly: f64, nx: usize, ny: usize, shape: CellShape) -> Mesh {
    let mut mesh = rectangle(lx, ly, nx, ny, shape);
    let right: Vec<[usize; 2]> = mesh
        .groups
        .iter()
        .find(|g| g.name.as_deref() == Some("Gamma2"))
        .expect("Gamma2")
        .facets
        .iter()
        .copied()
        .filter(|f| f.iter().all(|&p| (mesh.points[p][0] - lx).abs() < 1e-12))
        .collect();
    mesh.groups.push(PhysicalGroup {
        dim: 1,
        tag: 90,
        name: Some("Right".into()),
        facets: right,
        cells: vec![],
        nodes: vec![],
    });
    mesh
}

/// Moves interior nodes by a smooth, deterministic perturbation of amplitude `amp`·h.
pub fn distort_interior(mesh: &mut Mesh, lx: f64, ly: f64, h: f64, amp: f64) {
    for (k, p) in mesh.points.iter_mut().enumerate() {
        let on_boundary =
            p[0].abs() < 1e-12 || p[1].abs() < 1e-12 || (p[0] - lx).abs() < 1e-12 || (p[1] - ly).abs() < 1e-12;
        if !on_boundary {
            let s = (k as f64 * 12.9898).sin() * 43758.5453;
            let t = (k as f64 * 78.233).sin() * 12345.678;
            p[0] += amp * h * (s - s.floor() - 0.5);
            p[1] += amp * h * (t - t.floor() - 0.5);
        }
    }
}
