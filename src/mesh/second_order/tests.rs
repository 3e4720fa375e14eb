//! The second-order kinds' tables and shape functions against their definitions.

use super::*;
use crate::mesh::element::{reference, shape_at, stiffness_rule};
use crate::mesh::Cell;

/// The second-order kinds.
fn second_order() -> impl Iterator<Item = CellKind> {
    CellKind::ALL.into_iter().filter(|k| k.order() == 2)
}

fn reference_cell(kind: CellKind) -> Cell {
    Cell::new(kind, &(0..kind.nodes()).collect::<Vec<_>>())
}

/// Points inside the reference cell of `kind` by a fixed xorshift sequence.
fn inside(kind: CellKind, n: usize) -> Vec<[f64; 3]> {
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % 1_000_001) as f64 / 1_000_000.0
    };
    (0..n)
        .map(|_| {
            let (a, b, c) = (next(), next(), next());
            match kind.linear() {
                CellKind::Tri3 => [a * (1.0 - b), b, 0.0],
                CellKind::Tet4 => [a * (1.0 - b) * (1.0 - c), b * (1.0 - c), c],
                CellKind::Prism6 => [a * (1.0 - b), b, 2.0 * c - 1.0],
                CellKind::Quad4 => [2.0 * a - 1.0, 2.0 * b - 1.0, 0.0],
                _ => [2.0 * a - 1.0, 2.0 * b - 1.0, 2.0 * c - 1.0],
            }
        })
        .collect()
}

/// Each function is 1 at its node and 0 at the others, the functions sum to 1, reproduce every
/// quadratic in (ξ, η, ζ) of total degree ≤ 2 (the serendipity kinds too), and their gradients
/// are the derivatives of their values (central differences of step 1e-6: 1e-8 leaves room for
/// the O(h²) truncation and round-off 1e-16/1e-6).
#[test]
fn shape_functions_are_nodal_complete_and_consistent() {
    for kind in second_order() {
        let cell = reference_cell(kind);
        let nodes = reference_nodes(kind);
        for (b, &x) in nodes.iter().enumerate() {
            let (n, v, _) = reference(&cell, x);
            assert_eq!(n, kind.nodes());
            for a in 0..n {
                let want = if a == b { 1.0 } else { 0.0 };
                assert!((v[a] - want).abs() < 1e-14, "{kind:?}: N_{a} at node {b} = {}", v[a]);
            }
        }
        let dim = kind.dim();
        for xi in inside(kind, 50) {
            let (n, v, g) = reference(&cell, xi);
            assert!(
                (v[..n].iter().sum::<f64>() - 1.0).abs() < 1e-14,
                "{kind:?}: Σ N at {xi:?}"
            );
            // every monomial ξ_i ξ_j and ξ_i
            for i in 0..dim {
                for j in i..dim {
                    let f = |x: &[f64; 3]| x[i] * x[j] + 0.3 * x[i] - 0.7 * x[j];
                    let interp: f64 = (0..n).map(|a| v[a] * f(&nodes[a])).sum();
                    assert!((interp - f(&xi)).abs() < 1e-13, "{kind:?}: ξ{i}ξ{j} at {xi:?}");
                }
            }
            let h = 1e-6;
            for d in 0..dim {
                let (mut lo, mut hi) = (xi, xi);
                lo[d] -= h;
                hi[d] += h;
                let (vl, vh) = (reference(&cell, lo).1, reference(&cell, hi).1);
                for a in 0..n {
                    let fd = (vh[a] - vl[a]) / (2.0 * h);
                    assert!((g[a][d] - fd).abs() < 1e-8, "{kind:?}: ∂N_{a}/∂ξ_{d} at {xi:?}");
                }
            }
        }
    }
}

/// The derived tables: each facet's extra nodes lie at the midpoints of its edges (and a
/// 9-node face's last at its centre); VTK's order is a permutation; the mirror is an involution
/// that reverses the orientation (det J < 0 on the mirrored reference cell) and keeps the
/// facets (as node sets).
#[test]
fn derived_tables_follow_the_reference_nodes() {
    for kind in CellKind::ALL {
        let r = reference_nodes(kind);
        let d = derived(kind);
        for (f, corners) in d.facets.iter().zip(kind.linear_facets()) {
            assert_eq!(&f[..corners.len()], *corners);
            let m = corners.len();
            for (i, &node) in f[m..].iter().enumerate() {
                let want = if i < m.max(2) - usize::from(m == 2) {
                    let (a, b) = (corners[i], corners[(i + 1) % m]);
                    std::array::from_fn(|k| 0.5 * (r[a][k] + r[b][k]))
                } else {
                    std::array::from_fn(|k| corners.iter().map(|&c| r[c][k]).sum::<f64>() / m as f64)
                };
                assert_eq!(r[node], want, "{kind:?}: facet {f:?}, node {node}");
            }
        }
        let mut order = d.vtk_order.clone();
        order.sort_unstable();
        assert_eq!(order, (0..kind.nodes()).collect::<Vec<_>>(), "{kind:?}");
        for a in 0..kind.nodes() {
            assert_eq!(d.mirror[d.mirror[a]], a, "{kind:?}");
        }
        if kind != CellKind::Pyr5 {
            let pts: Vec<[f64; 3]> = r.to_vec();
            let cell = reference_cell(kind).flipped();
            let xi = stiffness_rule(&cell)[0].xi;
            if kind.dim() == 3 {
                assert!(shape_at(&cell, &pts, xi).det_j < 0.0, "{kind:?}");
            } else {
                let p2: Vec<[f64; 2]> = pts.iter().map(|p| [p[0], p[1]]).collect();
                assert!(shape_at(&cell, &p2, xi).det_j < 0.0, "{kind:?}");
            }
        }
    }
}

/// VTK's positions hold the nodes VTK's documentation puts there: spot checks of the types
/// whose order differs from gmsh's (the 10-node tetrahedron's last two, the hexahedra's edge
/// midpoints and face centres, the prisms' mirrored corners).
#[test]
fn vtk_orders_match_vtk_documentation() {
    assert_eq!(derived(CellKind::Tet10).vtk_order, [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]);
    assert_eq!(
        derived(CellKind::Hex20).vtk_order,
        [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15]
    );
    assert_eq!(derived(CellKind::Hex27).vtk_order[20..], [22, 23, 21, 24, 20, 25, 26]);
    assert_eq!(derived(CellKind::Prism6).vtk_order, [0, 2, 1, 3, 5, 4]);
    assert_eq!(derived(CellKind::Quad9).vtk_order, (0..9).collect::<Vec<_>>());
}

/// The contact rows' functions on second-order facets (docs/method.md §19.3,
/// `topology::row_functions`): on each kind they sum to 1 at every point of the rule and
/// integrate to the table's positive weights — on a 3-node edge the split's (and they are
/// non-negative there), the lumped weights of the face's own functions on 9-node quadrangles, of
/// the transformed ones (α = 1/5) on 6-node triangles and 8-node quadrangles.
#[test]
fn contact_row_functions_are_a_partition_with_the_tabled_weights() {
    use crate::mesh::topology::row_rule;
    use crate::mesh::Facet;
    // (facet, its reference measure, each node's weight as a share of it)
    let cases: [(Facet, f64, Vec<f64>); 4] = [
        (Facet::with_corners(&[0, 1, 2], 2), 1.0, vec![0.25, 0.25, 0.5]),
        (
            Facet::with_corners(&[0, 1, 2, 3, 4, 5, 6, 7, 8], 4),
            4.0,
            [[1.0 / 36.0; 4], [1.0 / 9.0; 4]]
                .concat()
                .into_iter()
                .chain([4.0 / 9.0])
                .collect(),
        ),
        (
            Facet::with_corners(&[0, 1, 2, 3, 4, 5], 3),
            0.5,
            [[2.0 / 15.0; 3], [0.2; 3]].concat(),
        ),
        (
            Facet::with_corners(&[0, 1, 2, 3, 4, 5, 6, 7], 4),
            4.0,
            [[0.05; 4], [0.2; 4]].concat(),
        ),
    ];
    for (f, measure, shares) in cases {
        let mut weights = vec![0.0; f.len()];
        for (_, w, psi) in row_rule(&f) {
            let sum: f64 = psi[..f.len()].iter().sum();
            assert!((sum - 1.0).abs() < 1e-13, "{} nodes: Σψ = {sum}", f.len());
            if f.dim() == 1 {
                assert!(psi.iter().all(|&p| p >= 0.0), "3-node edge: ψ {psi:?}");
            }
            for (a, wa) in weights.iter_mut().enumerate() {
                *wa += w * psi[a];
            }
        }
        for (a, (w, s)) in weights.iter().zip(&shares).enumerate() {
            assert!(
                (w / measure - s).abs() < 1e-13,
                "{} nodes: node {a} weight {w} against {s}",
                f.len()
            );
        }
    }
}

/// On an affine face the rows' coefficients c_jk = ∫ψ_j N_k / ∫ψ_j (docs/method.md §19.3) are
/// those of the transformation's inverse: row j is node j's own displacement on 9-node
/// quadrangles and at the corners of 6-node triangles and 8-node quadrangles (the dual basis is
/// biorthogonal), and at their midside nodes 5/3 of its own and −1/3 of each of its edge's
/// corners (1/(1 − 2α) and −α/(1 − 2α), α = 1/5).
#[test]
fn contact_rows_on_an_affine_facet_are_the_transformations_inverse() {
    use crate::mesh::topology::{facet_shape, row_rule};
    use crate::mesh::Facet;
    let kinds = [
        (Facet::with_corners(&[0, 1, 2, 3, 4, 5, 6, 7, 8], 4), vec![]),
        (
            Facet::with_corners(&[0, 1, 2, 3, 4, 5], 3),
            vec![(3, 0, 1), (4, 1, 2), (5, 2, 0)],
        ),
        (
            Facet::with_corners(&[0, 1, 2, 3, 4, 5, 6, 7], 4),
            vec![(4, 0, 1), (5, 1, 2), (6, 2, 3), (7, 3, 0)],
        ),
    ];
    for (f, edges) in kinds {
        let n = f.len();
        let mut integral = vec![vec![0.0; n]; n];
        let mut weight = vec![0.0; n];
        for (xi, w, psi) in row_rule(&f) {
            let value = facet_shape(&f, xi).1;
            for j in 0..n {
                weight[j] += w * psi[j];
                for k in 0..n {
                    integral[j][k] += w * psi[j] * value[k];
                }
            }
        }
        for j in 0..n {
            for k in 0..n {
                let want = match edges.iter().find(|e| e.0 == j) {
                    Some(&(e, _, _)) if k == e => 5.0 / 3.0,
                    Some(&(_, c1, c2)) if k == c1 || k == c2 => -1.0 / 3.0,
                    Some(_) => 0.0,
                    None => f64::from(u8::from(j == k)),
                };
                let c = integral[j][k] / weight[j];
                assert!((c - want).abs() < 1e-12, "{n} nodes: c_{j}{k} = {c} against {want}");
            }
        }
    }
}
