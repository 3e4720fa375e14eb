//! Error norms of a finite-element displacement against a known field: the L² norm and the
//! H¹ seminorm, by cell quadrature (rules of [`crate::mesh::element::error_rule`]), in any dimension.

use crate::mesh::element::{error_rule, shape_at};
use crate::mesh::Cell;

/// Errors of a nodal field u_h against an exact field.
#[derive(Clone, Copy, Debug, Default)]
pub struct FieldErrors {
    /// ‖u − u_h‖_{L²}
    pub l2: f64,
    /// |u − u_h|_{H¹} = ‖∇(u − u_h)‖_{L²}
    pub h1_seminorm: f64,
}

/// Integrates the L² and H¹-seminorm errors of `u_h` (nodal) against `exact(x) = (u, ∇u)`,
/// where ∇u[c][d] = ∂u_c/∂x_d.
pub fn errors<const D: usize>(
    cells: &[Cell],
    points: &[[f64; D]],
    u_h: &[[f64; D]],
    exact: impl Fn([f64; D]) -> ([f64; D], [[f64; D]; D]),
) -> FieldErrors {
    let (mut l2, mut h1) = (0.0, 0.0);
    for cell in cells {
        for q in error_rule(cell) {
            let s = shape_at(cell, points, q.xi);
            let (u, g) = exact(s.x);
            let mut uh = [0.0; D];
            let mut gh = [[0.0; D]; D];
            for a in 0..s.n {
                let v = u_h[cell.nodes()[a]];
                for c in 0..D {
                    uh[c] += s.value[a] * v[c];
                    for d in 0..D {
                        gh[c][d] += s.grad[a][d] * v[c];
                    }
                }
            }
            let dw = q.weight * s.det_j;
            l2 += dw * (0..D).map(|c| (u[c] - uh[c]).powi(2)).sum::<f64>();
            h1 += dw
                * (0..D)
                    .flat_map(|c| (0..D).map(move |d| (c, d)))
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
