//! A built-in mesher for the rectangle (0, lx) × (0, ly), with the physical groups of
//! `meshes/rectangle.geo`, so studies and tests need no gmsh.
//!
//! Groups: `Gamma1` (dim 1, tag 1, x = 0), `Gamma2` (dim 1, tag 2, x = lx and y = ly),
//! `Gamma3` (dim 1, tag 3, y = 0), `Gamma2_top` (dim 1, tag 4, y = ly only; its facets are also
//! in Gamma2) and `Omega` (dim 2, tag 5, every cell).

use super::{Cell, Facet, Mesh, PhysicalGroup};
use std::path::PathBuf;

/// The cell shape of [`rectangle`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellShape {
    /// Bilinear quadrilaterals (Q1), one per grid square.
    Quad,
    /// Linear triangles (P1): each grid square split along its diagonal from lower right to
    /// upper left into two counter-clockwise triangles (as gmsh's transfinite meshes of
    /// `rectangle.geo` do).
    Tri,
}

/// A structured mesh of (0, lx) × (0, ly) with `nx` × `ny` grid squares.
///
/// Point `i + j (nx + 1)` is at `(i lx / nx, j ly / ny)`; cells run row by row from the
/// bottom left, counter-clockwise; `cell_tags` are 1, 2, … like gmsh's. The path is
/// `<rectangle NXxNY>`.
///
/// # Panics
/// If `nx` or `ny` is 0, or `lx` or `ly` is not positive and finite (a programming error, not
/// bad input).
pub fn rectangle(lx: f64, ly: f64, nx: usize, ny: usize, kind: CellShape) -> Mesh {
    assert!(
        nx > 0 && ny > 0,
        "rectangle: nx and ny must be positive (got {nx} x {ny})"
    );
    assert!(
        lx > 0.0 && ly > 0.0 && lx.is_finite() && ly.is_finite(),
        "rectangle: lx, ly must be positive (got {lx}, {ly})"
    );
    let id = |i: usize, j: usize| i + j * (nx + 1);
    let mut points = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            points.push([lx * i as f64 / nx as f64, ly * j as f64 / ny as f64]);
        }
    }
    let mut cells = Vec::with_capacity(nx * ny * if kind == CellShape::Tri { 2 } else { 1 });
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            match kind {
                CellShape::Quad => cells.push(Cell::Quad4([a, b, c, d])),
                CellShape::Tri => {
                    cells.push(Cell::Tri3([a, b, d]));
                    cells.push(Cell::Tri3([d, b, c]));
                }
            }
        }
    }
    let cell_tags = (1..=cells.len()).collect();
    // Facets oriented counter-clockwise around the body.
    let bottom: Vec<[usize; 2]> = (0..nx).map(|i| [id(i, 0), id(i + 1, 0)]).collect();
    let right: Vec<[usize; 2]> = (0..ny).map(|j| [id(nx, j), id(nx, j + 1)]).collect();
    let top: Vec<[usize; 2]> = (0..nx).rev().map(|i| [id(i + 1, ny), id(i, ny)]).collect();
    let left: Vec<[usize; 2]> = (0..ny).rev().map(|j| [id(0, j + 1), id(0, j)]).collect();
    let curve = |tag: i32, name: &str, facets: Vec<[usize; 2]>| PhysicalGroup {
        dim: 1,
        tag,
        name: Some(name.to_string()),
        facets: facets.into_iter().map(Facet::from).collect(),
        cells: Vec::new(),
        nodes: Vec::new(),
    };
    let groups = vec![
        curve(1, "Gamma1", left),
        curve(2, "Gamma2", right.iter().chain(&top).copied().collect()),
        curve(3, "Gamma3", bottom),
        curve(4, "Gamma2_top", top),
        PhysicalGroup {
            dim: 2,
            tag: 5,
            name: Some("Omega".to_string()),
            facets: Vec::new(),
            cells: (0..cells.len()).collect(),
            nodes: Vec::new(),
        },
    ];
    Mesh {
        path: PathBuf::from(format!("<rectangle {nx}x{ny}>")),
        points,
        cells,
        cell_tags,
        groups,
    }
}
