//! Reference elements and the geometry map in any dimension D (docs/method.md §2, §8): shape
//! functions, their physical gradients and the Jacobian determinant at a quadrature point.

use super::quadrature::{
    prism_rule, pyramid_collapsed_27, tensor_gauss, tet_duffy, triangle_duffy, QuadPoint, HEX_GAUSS_2X2X2,
    PRISM_6POINT, PYRAMID_8POINT, QUAD_GAUSS_2X2, TET_4POINT, TET_CENTROID, TRI_3POINT, TRI_6POINT, TRI_CENTROID,
};
use super::second_order::reference_nodes;
use crate::mesh::{Cell, CellKind};
use std::sync::OnceLock;

/// Largest number of nodes of a supported cell (the 27-node hexahedron).
pub const MAX_NODES: usize = 27;

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
        c if c.kind().order() == 2 => {
            super::second_order::shape_functions(c.kind(), xi, &mut v, &mut g);
            (c.nodes().len(), v, g)
        }
        Cell::Tri3(_) => {
            v[..3].copy_from_slice(&[1.0 - x - y, x, y]);
            g[..3].copy_from_slice(&[[-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
            (3, v, g)
        }
        Cell::Quad4(_) => {
            for (a, c) in reference_nodes(CellKind::Quad4).iter().enumerate() {
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
            for (a, c) in reference_nodes(CellKind::Hex8).iter().enumerate() {
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
        Cell::Pyr5(_) => {
            // The rational basis (docs/method.md §8.1): with u = ξ/(1 − ζ), v = η/(1 − ζ),
            //   N_a = (1 − ζ)(1 + ξ_a u)(1 + η_a v)/4 = ((1 − ζ) + ξ_a ξ + η_a η + ξ_a η_a ξη/(1 − ζ))/4
            // at the base corners (ξ_a, η_a) = (±1, ±1) and N_4 = ζ at the apex: Q1 on the base,
            // P1 on the triangles, and Σ N_a = 1, Σ ξ_a N_a = ξ, Σ η_a N_a = η, N_4 = ζ (linear
            // completeness). Its gradients are bounded but have no limit at the apex, where the
            // value along the axis (u = v = 0) is taken; no quadrature point lies there.
            let s = 1.0 - z;
            // (u, v) of the collapsed coordinates; `v` holds the values
            let (cu, cv) = if s.abs() > 1e-14 { (x / s, y / s) } else { (0.0, 0.0) };
            // the base corners (ξ_a, η_a): the quadrangle's
            for (a, c) in reference_nodes(CellKind::Quad4).iter().enumerate() {
                let (su, sv) = (1.0 + c[0] * cu, 1.0 + c[1] * cv);
                v[a] = 0.25 * s * su * sv;
                g[a] = [0.25 * c[0] * sv, 0.25 * c[1] * su, 0.25 * (c[0] * c[1] * cu * cv - 1.0)];
            }
            v[4] = z;
            g[4] = [0.0, 0.0, 1.0];
            (5, v, g)
        }
        _ => unreachable!("the second-order kinds are the first arm"),
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

/// The quadrature rule for the stiffness of a cell (docs/method.md §19.2): exact for P1; 2^D
/// Gauss for Q1; on the second-order cells exact for their stiffness on straight-sided
/// (affine) cells — the 6-point rule on 6-node triangles (quartics: curved cells' non-constant
/// J too), the 4-point rule on 10-node tetrahedra (quadratics, what straight tetrahedra need),
/// 3 Gauss points per direction on quadrangles, hexahedra and in ζ on prisms.
pub fn stiffness_rule(cell: &Cell) -> &'static [QuadPoint] {
    static GAUSS_3X3: OnceLock<Vec<QuadPoint>> = OnceLock::new();
    static GAUSS_3X3X3: OnceLock<Vec<QuadPoint>> = OnceLock::new();
    static PRISM_18: OnceLock<Vec<QuadPoint>> = OnceLock::new();
    match cell.kind() {
        CellKind::Tri3 => &TRI_CENTROID,
        CellKind::Quad4 => &QUAD_GAUSS_2X2,
        CellKind::Tet4 => &TET_CENTROID,
        CellKind::Hex8 => &HEX_GAUSS_2X2X2,
        CellKind::Prism6 => &PRISM_6POINT,
        CellKind::Pyr5 => &PYRAMID_8POINT,
        CellKind::Tri6 => &TRI_6POINT,
        CellKind::Quad8 | CellKind::Quad9 => GAUSS_3X3.get_or_init(|| tensor_gauss(3, 2)),
        CellKind::Tet10 => &TET_4POINT,
        CellKind::Hex20 | CellKind::Hex27 => GAUSS_3X3X3.get_or_init(|| tensor_gauss(3, 3)),
        CellKind::Prism15 | CellKind::Prism18 => PRISM_18.get_or_init(|| prism_rule(&TRI_6POINT, 3)),
    }
}

/// The quadrature rule for loads on a cell (on second-order cells: the stiffness rule, but the
/// 27-point collapsed rule on 10-node tetrahedra, so that N_a f is integrated to degree 3).
pub fn load_rule(cell: &Cell) -> &'static [QuadPoint] {
    static TET_27: OnceLock<Vec<QuadPoint>> = OnceLock::new();
    match cell.kind() {
        CellKind::Tri3 => &TRI_3POINT,
        CellKind::Tet4 => &TET_4POINT,
        CellKind::Tet10 => TET_27.get_or_init(|| tet_duffy(3)),
        _ => stiffness_rule(cell),
    }
}

/// The rule for error integrals (exact beyond the degree the error norms need: 4 Gauss points
/// per direction on the second-order cells, whose errors fall at order 3 in L²).
pub fn error_rule(cell: &Cell) -> Vec<QuadPoint> {
    match cell.kind() {
        CellKind::Tri3 => TRI_6POINT.to_vec(),
        CellKind::Quad4 => tensor_gauss(3, 2),
        CellKind::Tet4 => tet_duffy(3),
        CellKind::Hex8 => tensor_gauss(3, 3),
        // the triangle's 6-point rule times 3-point Gauss in ζ
        CellKind::Prism6 => prism_rule(&TRI_6POINT, 3),
        CellKind::Pyr5 => pyramid_collapsed_27(),
        CellKind::Tri6 => triangle_duffy(4),
        CellKind::Quad8 | CellKind::Quad9 => tensor_gauss(4, 2),
        CellKind::Tet10 => tet_duffy(4),
        CellKind::Hex20 | CellKind::Hex27 => tensor_gauss(4, 3),
        CellKind::Prism15 | CellKind::Prism18 => prism_rule(&triangle_duffy(4), 4),
    }
}

/// The cell's centroid in reference coordinates (its first-order kind's).
pub fn reference_centroid(cell: &Cell) -> [f64; 3] {
    match cell.kind().linear() {
        CellKind::Tri3 | CellKind::Prism6 => [1.0 / 3.0, 1.0 / 3.0, 0.0],
        CellKind::Tet4 => [0.25, 0.25, 0.25],
        // the centroid of the reference pyramid (ζ̄ = ∫ζ(1 − ζ)²/∫(1 − ζ)² = 1/4)
        CellKind::Pyr5 => [0.0, 0.0, 0.25],
        _ => [0.0, 0.0, 0.0],
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
        check(Cell::Pyr5([0, 1, 2, 3, 6]), &p3, [0.2, -0.3, 0.4], [2.0, -3.0, 0.5]);
    }

    /// A pyramid with a non-planar, non-parallelogram base and a tilted apex (its map is not
    /// affine, so the rational term ξη/(1 − ζ) matters), and the unit-square right pyramid.
    const PYRAMIDS: [[[f64; 3]; 5]; 2] = [
        [
            [0.0, 0.0, 0.05],
            [1.2, 0.1, 0.0],
            [1.0, 0.9, -0.1],
            [-0.1, 1.1, 0.02],
            [0.7, 0.3, 0.8],
        ],
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.5, 0.5],
        ],
    ];

    const PYR: Cell = Cell::Pyr5([0, 1, 2, 3, 4]);

    /// Reference points spread over the pyramid {0 ≤ ζ < 1, |ξ|, |η| ≤ 1 − ζ} by a fixed
    /// xorshift sequence (on faces and near the apex too).
    fn pyramid_points(n: usize) -> Vec<[f64; 3]> {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 1_000_001) as f64 / 1_000_000.0
        };
        let mut out = vec![[1.0, -1.0, 0.0], [0.0, 0.0, 0.999_999], [0.3, -0.5, 0.5]];
        while out.len() < n {
            let z = 0.999 * next();
            out.push([(2.0 * next() - 1.0) * (1.0 - z), (2.0 * next() - 1.0) * (1.0 - z), z]);
        }
        out
    }

    /// The rational pyramid basis (docs/method.md §8.1): a partition of unity, 1 at its own node
    /// and 0 at the others (the apex included), the isoparametric map reproduces every linear
    /// field and its gradient exactly at points all over the cell, and the reference gradients
    /// are the derivatives of the values (central differences, step 1e-6: their error is
    /// O(step²) times third derivatives of order 1, so 1e-8 leaves room for round-off 1e-16/1e-6).
    #[test]
    fn pyramid_basis_is_linear_complete_with_consistent_gradients() {
        const NODES: [[f64; 3]; 5] = [
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        for (b, &xi) in NODES.iter().enumerate() {
            let (n, v, _) = reference(&PYR, xi);
            assert_eq!(n, 5);
            for a in 0..5 {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((v[a] - want).abs() < 1e-15, "N_{a} at node {b}: {}", v[a]);
            }
        }
        let slope = [2.0, -3.0, 0.5];
        for pts in &PYRAMIDS {
            for xi in pyramid_points(200) {
                let s = shape_at(&PYR, pts, xi);
                let sum: f64 = s.value[..5].iter().sum();
                assert!((sum - 1.0).abs() < 1e-14, "Σ N = {sum} at {xi:?}");
                let f = |p: [f64; 3]| 0.7 + (0..3).map(|k| slope[k] * p[k]).sum::<f64>();
                let (mut value, mut grad) = (0.0, [0.0; 3]);
                for a in 0..5 {
                    value += f(pts[a]) * s.value[a];
                    for k in 0..3 {
                        grad[k] += f(pts[a]) * s.grad[a][k];
                    }
                }
                assert!((value - f(s.x)).abs() < 1e-13, "value at {xi:?}: {value} vs {}", f(s.x));
                for k in 0..3 {
                    assert!((grad[k] - slope[k]).abs() < 1e-12, "gradient at {xi:?}: {grad:?}");
                }
                assert!(s.det_j > 0.0);
                // the reference gradients against central differences
                if xi[2] < 0.99 {
                    let (_, _, g) = reference(&PYR, xi);
                    let h = 1e-6;
                    for d in 0..3 {
                        let (mut lo, mut hi) = (xi, xi);
                        lo[d] -= h;
                        hi[d] += h;
                        let (vl, vh) = (reference(&PYR, lo).1, reference(&PYR, hi).1);
                        for a in 0..5 {
                            let fd = (vh[a] - vl[a]) / (2.0 * h);
                            assert!(
                                (g[a][d] - fd).abs() < 1e-8,
                                "∂N_{a}/∂ξ_{d} at {xi:?}: {} vs {fd}",
                                g[a][d]
                            );
                        }
                    }
                }
            }
        }
        // the apex: values exact, gradients finite (the limit along the axis)
        let s = shape_at(&PYR, &PYRAMIDS[0], [0.0, 0.0, 1.0]);
        assert!((s.value[4] - 1.0).abs() < 1e-15 && s.grad[..5].iter().flatten().all(|g| g.is_finite()));
    }

    /// The basis restricted to the base is the Q1 quadrangle's and to each triangle the P1
    /// triangle's (so a pyramid conforms to a hexahedron's face and a tetrahedron's face), the
    /// nodes off the face vanishing there.
    #[test]
    fn pyramid_basis_is_q1_on_the_base_and_p1_on_the_triangles() {
        for (s, t) in [(-0.6, 0.3), (0.2, 0.9), (1.0, -1.0), (0.0, 0.0)] {
            let (_, v, _) = reference(&PYR, [s, t, 0.0]);
            let (_, q, _) = reference(&Cell::Quad4([0, 1, 2, 3]), [s, t, 0.0]);
            for a in 0..4 {
                assert!((v[a] - q[a]).abs() < 1e-15);
            }
            assert_eq!(v[4], 0.0);
        }
        // the face through nodes (a, b, 4): a + (b − a) λ₁ + (apex − a) λ₂ in reference coordinates
        const BASE: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
        for a in 0..4 {
            let b = (a + 1) % 4;
            for (l1, l2) in [(0.2, 0.3), (0.5, 0.5), (0.0, 0.7), (0.9, 0.05)] {
                let xi = [
                    BASE[a][0] + (BASE[b][0] - BASE[a][0]) * l1 - BASE[a][0] * l2,
                    BASE[a][1] + (BASE[b][1] - BASE[a][1]) * l1 - BASE[a][1] * l2,
                    l2,
                ];
                let (_, v, _) = reference(&PYR, xi);
                let want = |k: usize| match k {
                    _ if k == a => 1.0 - l1 - l2,
                    _ if k == b => l1,
                    4 => l2,
                    _ => 0.0,
                };
                for k in 0..5 {
                    assert!(
                        (v[k] - want(k)).abs() < 1e-15,
                        "face {a}{b}4, N_{k} = {} vs {}",
                        v[k],
                        want(k)
                    );
                }
            }
        }
    }

    /// ∮ N_a n ds over the pyramid's faces (outward: [`Cell::facets`]): the base by 2 × 2 Gauss
    /// (the integrand is a bicubic there), the flat triangles by the vertex rule (N_a linear).
    fn pyramid_boundary_integrals(pts: &[[f64; 3]; 5]) -> [[f64; 3]; 5] {
        let cross = |u: [f64; 3], v: [f64; 3]| {
            [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ]
        };
        let mut out = [[0.0; 3]; 5];
        for f in PYR.facets() {
            let x = |k: usize| pts[f[k]];
            if f.len() == 3 {
                let e = |k: usize| std::array::from_fn(|d| x(k)[d] - x(0)[d]);
                let area = cross(e(1), e(2));
                for &p in f.nodes() {
                    for d in 0..3 {
                        out[p][d] += area[d] / 6.0;
                    }
                }
            } else {
                // the bilinear base: N_k (∂x/∂s × ∂x/∂t) at 2 × 2 Gauss points
                for q in &QUAD_GAUSS_2X2 {
                    let (_, v, g) = reference(&Cell::Quad4([0, 1, 2, 3]), q.xi);
                    let t = |c: usize| std::array::from_fn(|d| (0..4).map(|k| g[k][c] * x(k)[d]).sum::<f64>());
                    let area = cross(t(0), t(1));
                    for (k, &p) in f.nodes().iter().enumerate() {
                        for d in 0..3 {
                            out[p][d] += q.weight * v[k] * area[d];
                        }
                    }
                }
            }
        }
        out
    }

    /// The pyramid rules: the volume (by the divergence theorem, (1/3)∮ x·n ds) and ∫ ∇N_a dx =
    /// ∮ N_a n ds (the identity the patch test rests on) exact on the distorted pyramid with both
    /// rules, and on the affine one the 8-point stiffness ∫ ∇N_a·∇N_b dx equal to the 27-point
    /// one's (both exact there: quadratics in the collapsed coordinates). Round-off: 1e-14.
    #[test]
    fn pyramid_rules_integrate_volume_gradients_and_affine_stiffness_exactly() {
        for (i, pts) in PYRAMIDS.iter().enumerate() {
            let boundary = pyramid_boundary_integrals(pts);
            // (1/3) ∮ x·n ds = (1/3) Σ_a x_a·∮ N_a n ds (x = Σ N_a x_a on the faces)
            let volume: f64 = (0..5)
                .map(|a| (0..3).map(|d| pts[a][d] * boundary[a][d]).sum::<f64>())
                .sum::<f64>()
                / 3.0;
            let rules: [Vec<QuadPoint>; 2] = [PYRAMID_8POINT.to_vec(), error_rule(&PYR)];
            let mut stiffness = [[[0.0; 5]; 5]; 2];
            for (r, rule) in rules.iter().enumerate() {
                let (mut v, mut grad) = (0.0, [[0.0; 3]; 5]);
                for q in rule {
                    let s = shape_at(&PYR, pts, q.xi);
                    v += q.weight * s.det_j;
                    for a in 0..5 {
                        for d in 0..3 {
                            grad[a][d] += q.weight * s.det_j * s.grad[a][d];
                        }
                        for b in 0..5 {
                            stiffness[r][a][b] +=
                                q.weight * s.det_j * (0..3).map(|d| s.grad[a][d] * s.grad[b][d]).sum::<f64>();
                        }
                    }
                }
                assert!(
                    (v - volume).abs() < 1e-14,
                    "pyramid {i}, rule {r}: volume {v} vs {volume}"
                );
                for a in 0..5 {
                    for d in 0..3 {
                        assert!(
                            (grad[a][d] - boundary[a][d]).abs() < 1e-14,
                            "pyramid {i}, rule {r}: ∫∇N_{a} {:?} vs ∮N n {:?}",
                            grad[a],
                            boundary[a]
                        );
                    }
                }
            }
            if i == 1 {
                assert!(
                    (volume - 1.0 / 6.0).abs() < 1e-15,
                    "the right pyramid's volume {volume}"
                );
                for a in 0..5 {
                    for b in 0..5 {
                        let (k8, k27) = (stiffness[0][a][b], stiffness[1][a][b]);
                        assert!((k8 - k27).abs() < 1e-14, "K[{a}][{b}]: {k8} vs {k27}");
                    }
                }
            }
        }
    }
}
