//! Reference elements and the geometry map in any dimension D (docs/method.md §2, §8): shape
//! functions, their physical gradients and the Jacobian determinant at a quadrature point.

use super::quadrature::{
    tensor_gauss_3, tet_duffy_27, QuadPoint, HEX_GAUSS_2X2X2, PRISM_6POINT, QUAD_GAUSS_2X2, TET_4POINT, TET_CENTROID,
    TRI_3POINT, TRI_CENTROID,
};
use crate::mesh::Cell;

/// Largest number of nodes of a supported cell (the hexahedron).
pub const MAX_NODES: usize = 8;

/// Shape function values and physical gradients at one point of one cell.
#[derive(Clone, Copy, Debug)]
pub struct ShapeAt<const D: usize> {
    /// Number of nodes.
    pub n: usize,
    /// N_a(ξ).
    pub value: [f64; MAX_NODES],
    /// ∇_x N_a.
    pub grad: [[f64; D]; MAX_NODES],
    /// det J (positive for a positively oriented cell).
    pub det_j: f64,
    /// Physical coordinates of the point.
    pub x: [f64; D],
}

/// Reference shape functions and their ξ-gradients (3 components; the third is 0 in 2D).
pub fn reference(cell: &Cell, xi: [f64; 3]) -> (usize, [f64; MAX_NODES], [[f64; 3]; MAX_NODES]) {
    let mut v = [0.0; MAX_NODES];
    let mut g = [[0.0; 3]; MAX_NODES];
    let [x, y, z] = xi;
    match cell {
        Cell::Tri3(_) => {
            v[..3].copy_from_slice(&[1.0 - x - y, x, y]);
            g[..3].copy_from_slice(&[[-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
            (3, v, g)
        }
        Cell::Quad4(_) => {
            const CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
            for (a, c) in CORNERS.iter().enumerate() {
                let (sx, sy) = (1.0 + c[0] * x, 1.0 + c[1] * y);
                v[a] = 0.25 * sx * sy;
                g[a] = [0.25 * c[0] * sy, 0.25 * c[1] * sx, 0.0];
            }
            (4, v, g)
        }
        Cell::Tet4(_) => {
            v[..4].copy_from_slice(&[1.0 - x - y - z, x, y, z]);
            g[..4].copy_from_slice(&[[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
            (4, v, g)
        }
        Cell::Hex8(_) => {
            const CORNERS: [[f64; 3]; 8] = [
                [-1.0, -1.0, -1.0],
                [1.0, -1.0, -1.0],
                [1.0, 1.0, -1.0],
                [-1.0, 1.0, -1.0],
                [-1.0, -1.0, 1.0],
                [1.0, -1.0, 1.0],
                [1.0, 1.0, 1.0],
                [-1.0, 1.0, 1.0],
            ];
            for (a, c) in CORNERS.iter().enumerate() {
                let (sx, sy, sz) = (1.0 + c[0] * x, 1.0 + c[1] * y, 1.0 + c[2] * z);
                v[a] = 0.125 * sx * sy * sz;
                g[a] = [0.125 * c[0] * sy * sz, 0.125 * c[1] * sx * sz, 0.125 * c[2] * sx * sy];
            }
            (8, v, g)
        }
        Cell::Prism6(_) => {
            // the triangle's (1 − ξ − η, ξ, η) times the segment's (1 ∓ ζ)/2
            let l = [1.0 - x - y, x, y];
            let dl = [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
            for a in 0..3 {
                for (b, s) in [(a, -1.0), (a + 3, 1.0)] {
                    let h = 0.5 * (1.0 + s * z);
                    v[b] = l[a] * h;
                    g[b] = [dl[a][0] * h, dl[a][1] * h, 0.5 * s * l[a]];
                }
            }
            (6, v, g)
        }
    }
}

/// The inverse and determinant of a D × D matrix (D = 2 or 3).
pub fn invert<const D: usize>(j: &[[f64; D]; D]) -> ([[f64; D]; D], f64) {
    // nalgebra's closed forms (cofactors over the determinant); a singular J gives NaN entries
    // and det 0, which the callers test
    fn fill<const D: usize>(det: f64, entry: impl Fn(usize, usize) -> Option<f64>) -> ([[f64; D]; D], f64) {
        (
            std::array::from_fn(|r| std::array::from_fn(|c| entry(r, c).unwrap_or(f64::NAN))),
            det,
        )
    }
    match D {
        2 => {
            let m = nalgebra::Matrix2::from_fn(|r, c| j[r][c]);
            let inv = m.try_inverse();
            fill(m.determinant(), |r, c| inv.map(|i| i[(r, c)]))
        }
        3 => {
            let m = nalgebra::Matrix3::from_fn(|r, c| j[r][c]);
            let inv = m.try_inverse();
            fill(m.determinant(), |r, c| inv.map(|i| i[(r, c)]))
        }
        _ => unreachable!("hvi computes in 2 or 3 dimensions"),
    }
}

/// The point x(ξ) = Σ_a N_a x_a of `cell`'s map and its Jacobian J = Σ_a x_a ⊗ ∇_ξ N_a, from the
/// reference values and gradients of the `n` shape functions at ξ ([`reference`]).
#[inline]
pub fn map_at<const D: usize>(
    cell: &Cell,
    points: &[[f64; D]],
    n: usize,
    value: &[f64; MAX_NODES],
    gref: &[[f64; 3]; MAX_NODES],
) -> ([f64; D], [[f64; D]; D]) {
    let nodes = cell.nodes();
    let mut j = [[0.0; D]; D];
    let mut x = [0.0; D];
    for a in 0..n {
        let p = points[nodes[a]];
        for r in 0..D {
            x[r] += value[a] * p[r];
            for c in 0..D {
                j[r][c] += p[r] * gref[a][c];
            }
        }
    }
    (x, j)
}

/// Evaluates shape functions, physical gradients and det J of `cell` at reference point `xi`.
pub fn shape_at<const D: usize>(cell: &Cell, points: &[[f64; D]], xi: [f64; 3]) -> ShapeAt<D> {
    let (n, value, gref) = reference(cell, xi);
    let (x, j) = map_at(cell, points, n, &value, &gref);
    let (inv, det_j) = invert(&j);
    // ∇_x N = J^{-T} ∇_ξ N
    let mut grad = [[0.0; D]; MAX_NODES];
    for a in 0..n {
        for (c, g) in grad[a].iter_mut().enumerate() {
            *g = (0..D).map(|r| inv[r][c] * gref[a][r]).sum();
        }
    }
    ShapeAt {
        n,
        value,
        grad,
        det_j,
        x,
    }
}

/// The quadrature rule for the stiffness of a cell (exact for P1; 2^D Gauss for Q1).
pub fn stiffness_rule(cell: &Cell) -> &'static [QuadPoint] {
    match cell {
        Cell::Tri3(_) => &TRI_CENTROID,
        Cell::Quad4(_) => &QUAD_GAUSS_2X2,
        Cell::Tet4(_) => &TET_CENTROID,
        Cell::Hex8(_) => &HEX_GAUSS_2X2X2,
        Cell::Prism6(_) => &PRISM_6POINT,
    }
}

/// The quadrature rule for loads on a cell.
pub fn load_rule(cell: &Cell) -> &'static [QuadPoint] {
    match cell {
        Cell::Tri3(_) => &TRI_3POINT,
        Cell::Quad4(_) => &QUAD_GAUSS_2X2,
        Cell::Tet4(_) => &TET_4POINT,
        Cell::Hex8(_) => &HEX_GAUSS_2X2X2,
        Cell::Prism6(_) => &PRISM_6POINT,
    }
}

/// The rule for error integrals (exact beyond the degree the error norms need).
pub fn error_rule(cell: &Cell) -> Vec<QuadPoint> {
    match cell {
        Cell::Tri3(_) => TRI6
            .iter()
            .map(|&(xi, w)| QuadPoint {
                xi: [xi[0], xi[1], 0.0],
                weight: w,
            })
            .collect(),
        Cell::Quad4(_) => tensor_gauss_3(2),
        Cell::Tet4(_) => tet_duffy_27(),
        Cell::Hex8(_) => tensor_gauss_3(3),
        Cell::Prism6(_) => {
            // the triangle's 6-point rule times 3-point Gauss in ζ
            let gauss = [
                (-(0.6f64).sqrt(), 5.0 / 9.0),
                (0.0, 8.0 / 9.0),
                ((0.6f64).sqrt(), 5.0 / 9.0),
            ];
            TRI6.iter()
                .flat_map(|&(xi, w)| {
                    gauss.iter().map(move |&(z, wz)| QuadPoint {
                        xi: [xi[0], xi[1], z],
                        weight: w * wz,
                    })
                })
                .collect()
        }
    }
}

/// A 6-point rule on the reference triangle, exact for quartics.
const TRI6: [([f64; 2], f64); 6] = [
    ([0.445_948_490_915_965, 0.445_948_490_915_965], 0.111_690_794_839_005),
    ([0.445_948_490_915_965, 0.108_103_018_168_070], 0.111_690_794_839_005),
    ([0.108_103_018_168_070, 0.445_948_490_915_965], 0.111_690_794_839_005),
    ([0.091_576_213_509_771, 0.091_576_213_509_771], 0.054_975_871_827_661),
    ([0.091_576_213_509_771, 0.816_847_572_980_459], 0.054_975_871_827_661),
    ([0.816_847_572_980_459, 0.091_576_213_509_771], 0.054_975_871_827_661),
];

/// The cell's centroid in reference coordinates.
pub fn reference_centroid(cell: &Cell) -> [f64; 3] {
    match cell {
        Cell::Tri3(_) | Cell::Prism6(_) => [1.0 / 3.0, 1.0 / 3.0, 0.0],
        Cell::Quad4(_) | Cell::Hex8(_) => [0.0, 0.0, 0.0],
        Cell::Tet4(_) => [0.25, 0.25, 0.25],
    }
}

/// Small-strain tensor ε = sym ∇u (full D × D) from nodal displacements.
pub fn strain<const D: usize>(shape: &ShapeAt<D>, u: &[[f64; D]]) -> [[f64; D]; D] {
    let mut g = [[0.0; D]; D]; // ∂u_i/∂x_j
    for (grad, ua) in shape.grad.iter().zip(u).take(shape.n) {
        for i in 0..D {
            for j in 0..D {
                g[i][j] += ua[i] * grad[j];
            }
        }
    }
    let mut e = [[0.0; D]; D];
    for i in 0..D {
        for j in 0..D {
            e[i][j] = 0.5 * (g[i][j] + g[j][i]);
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check<const D: usize>(cell: Cell, pts: &[[f64; D]], xi: [f64; 3], slope: [f64; D]) {
        let s = shape_at(&cell, pts, xi);
        let sum: f64 = s.value[..s.n].iter().sum();
        assert!((sum - 1.0).abs() < 1e-14, "{cell:?}");
        // ∇ of a linear field interpolated at the nodes is its slope
        let mut g = [0.0; D];
        for a in 0..s.n {
            let p = pts[cell.nodes()[a]];
            let f: f64 = (0..D).map(|k| slope[k] * p[k]).sum();
            for k in 0..D {
                g[k] += f * s.grad[a][k];
            }
        }
        for k in 0..D {
            assert!((g[k] - slope[k]).abs() < 1e-13, "{cell:?} {g:?}");
        }
        assert!(s.det_j > 0.0, "{cell:?}");
    }

    #[test]
    fn partition_of_unity_and_linear_reproduction() {
        let pts = [[0.1, 0.0], [1.3, 0.2], [1.0, 1.1], [-0.1, 0.9]];
        check(Cell::Quad4([0, 1, 2, 3]), &pts, [0.2, 0.3, 0.0], [2.0, -3.0]);
        check(Cell::Tri3([0, 1, 2]), &pts, [0.2, 0.3, 0.0], [2.0, -3.0]);
        let p3 = [
            [0.0, 0.0, 0.0],
            [1.1, 0.1, 0.0],
            [1.0, 1.2, 0.1],
            [0.0, 0.9, -0.1],
            [0.1, 0.0, 1.0],
            [1.0, 0.0, 1.1],
            [1.2, 1.0, 0.9],
            [-0.1, 1.0, 1.0],
        ];
        check(
            Cell::Hex8([0, 1, 2, 3, 4, 5, 6, 7]),
            &p3,
            [0.2, -0.3, 0.4],
            [2.0, -3.0, 0.5],
        );
        check(Cell::Tet4([0, 1, 3, 4]), &p3, [0.2, 0.3, 0.1], [2.0, -3.0, 0.5]);
        check(
            Cell::Prism6([0, 1, 3, 4, 5, 7]),
            &p3,
            [0.2, 0.3, -0.4],
            [2.0, -3.0, 0.5],
        );
    }
}
