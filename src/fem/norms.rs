//! Error norms of a finite-element displacement against a known field: the L² norm and the
//! H¹ seminorm, by cell quadrature (3×3 Gauss on quads, 6-point on triangles).

use super::element::shape_at;
use crate::mesh::Cell;

const G3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// A 6-point rule on the reference triangle, exact for quartics.
const TRI6: [([f64; 2], f64); 6] = [
    ([0.445_948_490_915_965, 0.445_948_490_915_965], 0.111_690_794_839_005),
    ([0.445_948_490_915_965, 0.108_103_018_168_070], 0.111_690_794_839_005),
    ([0.108_103_018_168_070, 0.445_948_490_915_965], 0.111_690_794_839_005),
    ([0.091_576_213_509_771, 0.091_576_213_509_771], 0.054_975_871_827_661),
    ([0.091_576_213_509_771, 0.816_847_572_980_459], 0.054_975_871_827_661),
    ([0.816_847_572_980_459, 0.091_576_213_509_771], 0.054_975_871_827_661),
];

fn error_rule(cell: &Cell) -> Vec<([f64; 2], f64)> {
    match cell {
        Cell::Tri3(_) => TRI6.to_vec(),
        Cell::Quad4(_) => G3
            .iter()
            .flat_map(|&(a, wa)| G3.iter().map(move |&(b, wb)| ([a, b], wa * wb)))
            .collect(),
    }
}

/// Errors of a nodal field u_h against an exact field.
#[derive(Clone, Copy, Debug, Default)]
pub struct FieldErrors {
    /// ‖u − u_h‖_{L²}
    pub l2: f64,
    /// |u − u_h|_{H¹} = ‖∇(u − u_h)‖_{L²}
    pub h1_seminorm: f64,
}

/// Integrates the L² and H¹-seminorm errors of `u_h` (nodal) against `exact(x) = (u, ∇u)`,
/// where ∇u is [[∂u₁/∂x, ∂u₁/∂y], [∂u₂/∂x, ∂u₂/∂y]].
pub fn errors(
    cells: &[Cell],
    points: &[[f64; 2]],
    u_h: &[[f64; 2]],
    exact: impl Fn([f64; 2]) -> ([f64; 2], [[f64; 2]; 2]),
) -> FieldErrors {
    let (mut l2, mut h1) = (0.0, 0.0);
    for cell in cells {
        for (xi, w) in error_rule(cell) {
            let s = shape_at(cell, points, xi);
            let (u, g) = exact(s.x);
            let mut uh = [0.0; 2];
            let mut gh = [[0.0; 2]; 2];
            for a in 0..s.n {
                let v = u_h[cell.nodes()[a]];
                for c in 0..2 {
                    uh[c] += s.value[a] * v[c];
                    gh[c][0] += s.grad[a][0] * v[c];
                    gh[c][1] += s.grad[a][1] * v[c];
                }
            }
            let dw = w * s.det_j;
            l2 += dw * ((u[0] - uh[0]).powi(2) + (u[1] - uh[1]).powi(2));
            h1 += dw
                * (0..2)
                    .flat_map(|c| (0..2).map(move |d| (c, d)))
                    .map(|(c, d)| (g[c][d] - gh[c][d]).powi(2))
                    .sum::<f64>();
        }
    }
    FieldErrors {
        l2: l2.sqrt(),
        h1_seminorm: h1.sqrt(),
    }
}

/// Least-squares slope of log(error) against log(h): the observed convergence order.
pub fn fitted_order(h: &[f64], e: &[f64]) -> f64 {
    let n = h.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = (h.iter().map(|v| v.ln()).collect(), e.iter().map(|v| v.ln()).collect());
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}
