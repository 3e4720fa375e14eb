//! Reference elements and the geometry map: shape functions, their physical gradients and
//! the Jacobian determinant at a quadrature point.

use super::quadrature::{QuadPoint, QUAD_GAUSS_2X2, TRI_3POINT, TRI_CENTROID};
use crate::mesh::Cell;

/// Largest number of nodes of a supported cell (Q1).
pub const MAX_NODES: usize = 4;

/// Shape function values and physical gradients at one point of one cell.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShapeAt {
    /// Number of nodes (3 or 4).
    pub n: usize,
    /// N_a(ξ).
    pub value: [f64; MAX_NODES],
    /// ∇_x N_a.
    pub grad: [[f64; 2]; MAX_NODES],
    /// det J (positive for a counter-clockwise cell).
    pub det_j: f64,
    /// Physical coordinates of the point.
    pub x: [f64; 2],
}

/// Reference shape functions and their ξ-gradients.
fn reference(cell: &Cell, xi: [f64; 2]) -> (usize, [f64; MAX_NODES], [[f64; 2]; MAX_NODES]) {
    let mut v = [0.0; MAX_NODES];
    let mut g = [[0.0; 2]; MAX_NODES];
    match cell {
        Cell::Tri3(_) => {
            v[..3].copy_from_slice(&[1.0 - xi[0] - xi[1], xi[0], xi[1]]);
            g[..3].copy_from_slice(&[[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]);
            (3, v, g)
        }
        Cell::Quad4(_) => {
            const CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
            for (a, c) in CORNERS.iter().enumerate() {
                let (sx, sy) = (1.0 + c[0] * xi[0], 1.0 + c[1] * xi[1]);
                v[a] = 0.25 * sx * sy;
                g[a] = [0.25 * c[0] * sy, 0.25 * c[1] * sx];
            }
            (4, v, g)
        }
    }
}

/// Evaluates shape functions, physical gradients and det J of `cell` at reference point `xi`.
pub fn shape_at(cell: &Cell, points: &[[f64; 2]], xi: [f64; 2]) -> ShapeAt {
    let (n, value, gref) = reference(cell, xi);
    let nodes = cell.nodes();
    // J = Σ_a x_a ⊗ ∇_ξ N_a
    let mut j = [[0.0; 2]; 2];
    let mut x = [0.0; 2];
    for a in 0..n {
        let p = points[nodes[a]];
        for r in 0..2 {
            x[r] += value[a] * p[r];
            for c in 0..2 {
                j[r][c] += p[r] * gref[a][c];
            }
        }
    }
    let det_j = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    let inv = [[j[1][1] / det_j, -j[0][1] / det_j], [-j[1][0] / det_j, j[0][0] / det_j]];
    // ∇_x N = J^{-T} ∇_ξ N
    let mut grad = [[0.0; 2]; MAX_NODES];
    for a in 0..n {
        grad[a] = [
            inv[0][0] * gref[a][0] + inv[1][0] * gref[a][1],
            inv[0][1] * gref[a][0] + inv[1][1] * gref[a][1],
        ];
    }
    ShapeAt {
        n,
        value,
        grad,
        det_j,
        x,
    }
}

/// The quadrature rule for the stiffness of a cell (exact for P1; 2×2 Gauss for Q1).
pub fn stiffness_rule(cell: &Cell) -> &'static [QuadPoint] {
    match cell {
        Cell::Tri3(_) => &TRI_CENTROID,
        Cell::Quad4(_) => &QUAD_GAUSS_2X2,
    }
}

/// The quadrature rule for loads and error integrals on a cell.
pub fn load_rule(cell: &Cell) -> &'static [QuadPoint] {
    match cell {
        Cell::Tri3(_) => &TRI_3POINT,
        Cell::Quad4(_) => &QUAD_GAUSS_2X2,
    }
}

/// The cell's centroid in reference coordinates.
pub fn reference_centroid(cell: &Cell) -> [f64; 2] {
    match cell {
        Cell::Tri3(_) => [1.0 / 3.0, 1.0 / 3.0],
        Cell::Quad4(_) => [0.0, 0.0],
    }
}

/// Small-strain tensor in Voigt form [ε₁₁, ε₂₂, γ₁₂ = 2ε₁₂] from nodal displacements.
pub fn strain(shape: &ShapeAt, u: &[[f64; 2]]) -> [f64; 3] {
    let mut e = [0.0; 3];
    for (g, ua) in shape.grad.iter().zip(u).take(shape.n) {
        e[0] += g[0] * ua[0];
        e[1] += g[1] * ua[1];
        e[2] += g[1] * ua[0] + g[0] * ua[1];
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_of_unity_and_linear_reproduction() {
        let pts = [[0.1, 0.0], [1.3, 0.2], [1.0, 1.1], [-0.1, 0.9]];
        for cell in [Cell::Quad4([0, 1, 2, 3]), Cell::Tri3([0, 1, 2])] {
            let s = shape_at(&cell, &pts, [0.2, 0.3]);
            let sum: f64 = s.value[..s.n].iter().sum();
            assert!((sum - 1.0).abs() < 1e-14);
            // ∇ of the field x ↦ 2x - 3y interpolated at the nodes
            let mut g = [0.0; 2];
            for a in 0..s.n {
                let p = pts[cell.nodes()[a]];
                let f = 2.0 * p[0] - 3.0 * p[1];
                g[0] += f * s.grad[a][0];
                g[1] += f * s.grad[a][1];
            }
            assert!((g[0] - 2.0).abs() < 1e-13 && (g[1] + 3.0).abs() < 1e-13);
            assert!(s.det_j > 0.0);
        }
    }
}
