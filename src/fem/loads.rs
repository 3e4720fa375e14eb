//! Load vectors F(t) = ∫_Ω f₀·v dx + Σ_groups ∫_Γ f₂·v ds (METHOD.md §1), from expressions
//! in (x, y, z, t) and, for tractions, the facet's outward normal (nx, ny, nz) (the variables
//! of [`crate::scene::TRACTION_VARIABLES`]). Quadrature points and shape values are computed once; each time step only
//! evaluates the expressions, and a load that does not depend on t is assembled once.

use super::dofs::DofMap;
use super::element::{load_rule, shape_at};
use super::quadrature::EDGE_GAUSS_3;
use crate::mesh::{BoundaryPart, Cell};
use crate::scene::Expr;

/// One quadrature point of a load integral: position, weight (with the Jacobian), and the
/// free dofs × shape values it contributes to.
#[derive(Clone, Debug)]
struct LoadPoint {
    x: [f64; 2],
    /// The facet's outward unit normal (zero for a body force).
    normal: [f64; 2],
    weight: f64,
    /// (node, N_node(x)) for the nodes of the cell or facet.
    shape: Vec<(usize, f64)>,
}

/// A vector-valued load density f = (f_x, f_y) integrated over a set of points.
#[derive(Clone, Debug)]
struct LoadTerm {
    /// Where the load comes from, for messages (e.g. the scene key).
    label: String,
    value: [Expr; 2],
    points: Vec<LoadPoint>,
}

/// The load vector assembler of a scene.
#[derive(Clone, Debug, Default)]
pub struct Loads {
    terms: Vec<LoadTerm>,
}

impl Loads {
    /// No loads.
    pub fn new() -> Self {
        Loads::default()
    }

    /// Adds a traction density on a boundary part (2-node facets, 3-point Gauss per facet).
    pub fn add_traction(&mut self, part: &BoundaryPart, points: &[[f64; 2]], value: [Expr; 2], label: &str) {
        let mut qp = Vec::with_capacity(part.facets.len() * EDGE_GAUSS_3.len());
        for (f, len) in part.facets.iter().zip(&part.facet_lengths) {
            let (a, b) = (points[f[0]], points[f[1]]);
            // the facet is oriented with the body on its left: outward normal (dy, −dx)/len
            let normal = [(b[1] - a[1]) / len, -(b[0] - a[0]) / len];
            for &(s, w) in &EDGE_GAUSS_3 {
                qp.push(LoadPoint {
                    x: [(1.0 - s) * a[0] + s * b[0], (1.0 - s) * a[1] + s * b[1]],
                    normal,
                    weight: w * len,
                    shape: vec![(f[0], 1.0 - s), (f[1], s)],
                });
            }
        }
        self.terms.push(LoadTerm {
            label: label.to_string(),
            value,
            points: qp,
        });
    }

    /// Adds a body force density on every cell.
    pub fn add_body_force(&mut self, cells: &[Cell], points: &[[f64; 2]], value: [Expr; 2], label: &str) {
        let mut qp = Vec::new();
        for cell in cells {
            for q in load_rule(cell) {
                let s = shape_at(cell, points, q.xi);
                qp.push(LoadPoint {
                    x: s.x,
                    normal: [0.0; 2],
                    weight: q.weight * s.det_j,
                    shape: cell.nodes().iter().zip(&s.value).map(|(&n, &v)| (n, v)).collect(),
                });
            }
        }
        self.terms.push(LoadTerm {
            label: label.to_string(),
            value,
            points: qp,
        });
    }

    /// True if any load density depends on t.
    pub fn is_time_dependent(&self) -> bool {
        self.terms.iter().any(|t| t.value.iter().any(|e| e.depends_on("t")))
    }

    /// True if there are no loads at all.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// F(t) restricted to the free unknowns, written into `out` (overwritten). A load density
    /// that is not finite at some quadrature point is an error naming the load, the point and t.
    pub fn assemble(&self, t: f64, dofs: &DofMap, out: &mut [f64]) -> Result<(), String> {
        out.iter_mut().for_each(|v| *v = 0.0);
        for term in &self.terms {
            for p in &term.points {
                // TRACTION_VARIABLES (x, y, z, t, nx, ny, nz); a body force uses the first four.
                let vars = [p.x[0], p.x[1], 0.0, t, p.normal[0], p.normal[1], 0.0];
                let f = [term.value[0].eval(&vars), term.value[1].eval(&vars)];
                if let Some(c) = f.iter().position(|v| !v.is_finite()) {
                    return Err(format!(
                        "{}[{c}] = \"{}\" is {} at (x, y) = ({}, {}), t = {t}; make the expression finite on the whole group",
                        term.label,
                        term.value[c].source(),
                        f[c],
                        p.x[0],
                        p.x[1]
                    ));
                }
                for &(node, n) in &p.shape {
                    for (c, fc) in f.iter().enumerate() {
                        if let Some(d) = dofs.get(node, c) {
                            out[d] += p.weight * fc * n;
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
