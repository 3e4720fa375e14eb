//! The bound g of u_ν ≤ g at the contact nodes (docs/method.md §10): a number, or an expression
//! g(x, y, z) evaluated at each node's reference position. Imposing the constraint at the nodes
//! is the paper's external approximation: between nodes the discrete u_ν may exceed g by
//! O(h²) where g is not concave.

use super::error::SolveError;
use crate::scene::{BoundSpec, Expr, BOUND_VARIABLES};

/// g_p at each of `nodes` (mesh node indices into `points`), checked finite and ≥ 0. `origin`
/// (the mesh) and `key` (the scene key) name the place in messages.
pub fn nodal_bound<const D: usize>(
    spec: &BoundSpec,
    nodes: &[usize],
    points: &[[f64; D]],
    origin: &str,
    key: &str,
) -> Result<Vec<f64>, SolveError> {
    let expr = match spec {
        BoundSpec::Number(g) => return Ok(vec![*g; nodes.len()]),
        BoundSpec::Expression(source) => Expr::parse(source, &BOUND_VARIABLES)
            .map_err(|e| SolveError::Setup(format!("{origin}: {key} = \"{source}\": {e}")))?,
    };
    let mut values = Vec::with_capacity(nodes.len());
    for &p in nodes {
        let mut xyz = [0.0; 3];
        xyz[..D].copy_from_slice(&points[p]);
        let g = expr.eval(&xyz);
        if !(g.is_finite() && g >= 0.0) {
            let at = xyz[..D].iter().map(|c| format!("{c}")).collect::<Vec<_>>().join(", ");
            let names = BOUND_VARIABLES[..D].join(", ");
            return Err(SolveError::Setup(format!(
                "{origin}: {key} = \"{}\" is g = {g} at the contact node {p} ({names}) = ({at}); the bound (a layer \
                 thickness) must be finite and ≥ 0 at every node of the contact group: change the expression or \
                 the group",
                expr.source()
            )));
        }
        values.push(g);
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_expression_is_the_number_bit_for_bit() {
        let points = [[0.0, 0.0], [0.3, 1.0], [2.0, 1.0]];
        let nodes = [0, 1, 2];
        for g in [0.2, 1e-3, 0.0, 0.1 + 0.2, 1.0 / 3.0] {
            let number = nodal_bound(&BoundSpec::Number(g), &nodes, &points, "m", "contact.bound").unwrap();
            let text = format!("{g:?}");
            let expr = nodal_bound(
                &BoundSpec::Expression(text.clone()),
                &nodes,
                &points,
                "m",
                "contact.bound",
            )
            .unwrap();
            for (a, b) in number.iter().zip(&expr) {
                assert_eq!(a.to_bits(), b.to_bits(), "{text}");
            }
        }
    }

    #[test]
    fn an_expression_is_evaluated_at_each_node_and_a_negative_value_names_it() {
        let points = [[0.0, 0.0, 0.0], [0.5, 1.0, 2.0], [2.0, 1.0, -1.0]];
        let g = nodal_bound(
            &BoundSpec::Expression("x + 2*y + 3*z + 4".into()),
            &[2, 1],
            &points,
            "m",
            "contact.bound",
        )
        .unwrap();
        assert_eq!(g, vec![2.0 + 2.0 - 3.0 + 4.0, 0.5 + 2.0 + 6.0 + 4.0]);
        let e = nodal_bound(
            &BoundSpec::Expression("x - 1".into()),
            &[1, 0, 2],
            &points,
            "m.msh",
            "contact.bound",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("m.msh") && e.contains("contact.bound") && e.contains("x - 1") && e.contains("(0.5, 1, 2)"),
            "{e}"
        );
        // outside its domain (sqrt of a negative) the value is NaN: also refused, with the node
        let e = nodal_bound(
            &BoundSpec::Expression("sqrt(1 - x)".into()),
            &[2],
            &points,
            "m",
            "contact.bound",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("NaN") && e.contains("(2, 1, -1)"), "{e}");
    }
}
