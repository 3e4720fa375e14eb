//! The 2D cells hvi computes on: 3-node triangles (P1) and 4-node quadrilaterals (Q1).
//!
//! Node indices are dense, 0-based indices into [`super::Mesh::points`]. Cells are stored
//! counter-clockwise (positive signed area); the reader rejects inverted cells.

/// One 2D cell of the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cell {
    /// Linear triangle, nodes counter-clockwise (gmsh element type 2).
    Tri3([usize; 3]),
    /// Bilinear quadrilateral, nodes counter-clockwise (gmsh element type 3).
    Quad4([usize; 4]),
}

impl Cell {
    /// The cell's node indices, in counter-clockwise order.
    pub fn nodes(&self) -> &[usize] {
        match self {
            Cell::Tri3(n) => n,
            Cell::Quad4(n) => n,
        }
    }

    /// The boundary edges of the cell, each oriented counter-clockwise, so that the
    /// outward normal of edge `[a, b]` is `(y_b - y_a, -(x_b - x_a))` normalised.
    pub fn edges(&self) -> impl Iterator<Item = [usize; 2]> + '_ {
        let n = self.nodes();
        (0..n.len()).map(move |i| [n[i], n[(i + 1) % n.len()]])
    }

    /// VTK cell type id (5 = triangle, 9 = quad).
    pub fn vtk_type(&self) -> u8 {
        match self {
            Cell::Tri3(_) => 5,
            Cell::Quad4(_) => 9,
        }
    }
}
