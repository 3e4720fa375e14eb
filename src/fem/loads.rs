//! Load vectors F(t) = ∫_Ω f₀·v dx + Σ_groups ∫_Γ f₂·v ds (docs/method.md §1), from expressions
//! in (x, y, z, t) and, for tractions, the facet's outward normal (nx, ny, nz) (the variables
//! of [`crate::expr::TRACTION_VARIABLES`]). A pressure p is the traction f₂ = −p ν
//! (docs/method.md §11.2). Quadrature points and shape values are computed
//! once; each time step only evaluates the expressions, and a load that does not depend on t is
//! assembled once.

use super::dofs::DofMap;
use crate::expr::Expr;
use crate::mesh::element::{load_rule, shape_at};
use crate::mesh::topology::{facet_map, facet_rule};
use crate::mesh::vector::norm;
use crate::mesh::{BoundaryPart, Cell, Facet};

/// One quadrature point of a load integral: position, outward normal, weight (with the
/// Jacobian), and the nodes × shape values it contributes to.
#[derive(Clone, Debug)]
struct LoadPoint<const D: usize> {
    x: [f64; D],
    /// The facet's outward unit normal (zero for a body force).
    normal: [f64; D],
    weight: f64,
    /// (node, N_node(x)) for the nodes of the cell or facet.
    shape: Vec<(usize, f64)>,
}

/// A load density: its D components, or a pressure p (the traction −p ν).
#[derive(Clone, Debug)]
enum Density<const D: usize> {
    Vector([Expr; D]),
    Pressure(Box<Expr>),
}

impl<const D: usize> Density<D> {
    fn expressions(&self) -> &[Expr] {
        match self {
            Density::Vector(v) => v,
            Density::Pressure(p) => std::slice::from_ref(p.as_ref()),
        }
    }
}

/// A vector-valued load density f (D components) integrated over a set of points.
#[derive(Clone, Debug)]
struct LoadTerm<const D: usize> {
    /// Where the load comes from, for messages (e.g. the scene key).
    label: String,
    value: Density<D>,
    points: Vec<LoadPoint<D>>,
}

/// The load vector assembler of a scene.
#[derive(Clone, Debug)]
pub struct Loads<const D: usize> {
    terms: Vec<LoadTerm<D>>,
    /// A body of revolution (x = r): every weight carries 2πr (docs/method.md §8.6).
    axisymmetric: bool,
}

impl<const D: usize> Default for Loads<D> {
    fn default() -> Self {
        Loads {
            terms: Vec::new(),
            axisymmetric: false,
        }
    }
}

/// Quadrature points of one facet: (position, outward unit normal, weight, shape values).
type FacetPoint<const D: usize> = ([f64; D], [f64; D], f64, Vec<(usize, f64)>);

/// Quadrature on a facet ([`facet_rule`]: 3-point Gauss on an edge, the 3-point rule on a
/// triangle, 2×2 Gauss on a quadrilateral, richer rules on second-order facets; exact for the
/// products of shape functions with smooth loads to the order the elements need).
fn facet_points<const D: usize>(points: &[[f64; D]], f: &Facet) -> Vec<FacetPoint<D>> {
    let nodes = f.nodes();
    facet_rule(f)
        .iter()
        .map(|q| {
            let (value, c, x) = facet_map(points, f, q.xi);
            let da = norm(&c);
            let normal = std::array::from_fn(|k| c[k] / da);
            let shape = (0..nodes.len()).map(|a| (nodes[a], value[a])).collect();
            (x, normal, q.weight * da, shape)
        })
        .collect()
}

impl<const D: usize> Loads<D> {
    /// No loads.
    pub fn new() -> Self {
        Loads::default()
    }

    /// No loads on a body of revolution about the y axis (x = r): the loads added integrate
    /// over the surfaces and the volume it sweeps, with the measure 2πr (docs/method.md §8.6).
    pub fn axisymmetric() -> Self {
        Loads {
            terms: Vec::new(),
            axisymmetric: true,
        }
    }

    /// The weight of a quadrature point at x: `weight`, times 2π x₀ on a body of revolution.
    fn revolved(&self, x: &[f64; D], weight: f64) -> f64 {
        if self.axisymmetric {
            weight * 2.0 * std::f64::consts::PI * x[0]
        } else {
            weight
        }
    }

    /// Adds a traction density on a boundary part.
    pub fn add_traction(&mut self, part: &BoundaryPart<D>, points: &[[f64; D]], value: [Expr; D], label: &str) {
        self.add_boundary_term(part, points, Density::Vector(value), label);
    }

    /// Adds a pressure p on a boundary part: the traction −p ν, ν the facet's outward unit normal.
    pub fn add_pressure(&mut self, part: &BoundaryPart<D>, points: &[[f64; D]], pressure: Expr, label: &str) {
        self.add_boundary_term(part, points, Density::Pressure(Box::new(pressure)), label);
    }

    fn add_boundary_term(&mut self, part: &BoundaryPart<D>, points: &[[f64; D]], value: Density<D>, label: &str) {
        let mut qp = Vec::with_capacity(part.facets.len() * 4);
        for f in &part.facets {
            for (x, normal, weight, shape) in facet_points(points, f) {
                qp.push(LoadPoint {
                    weight: self.revolved(&x, weight),
                    x,
                    normal,
                    shape,
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
    pub fn add_body_force(&mut self, cells: &[Cell], points: &[[f64; D]], value: [Expr; D], label: &str) {
        let mut qp = Vec::new();
        for cell in cells {
            for q in load_rule(cell) {
                let s = shape_at(cell, points, q.xi);
                qp.push(LoadPoint {
                    x: s.x,
                    normal: [0.0; D],
                    weight: self.revolved(&s.x, q.weight * s.det_j),
                    shape: cell.nodes().iter().zip(&s.value).map(|(&n, &v)| (n, v)).collect(),
                });
            }
        }
        self.terms.push(LoadTerm {
            label: label.to_string(),
            value: Density::Vector(value),
            points: qp,
        });
    }

    /// True if any load density depends on t.
    pub fn is_time_dependent(&self) -> bool {
        self.terms
            .iter()
            .any(|t| t.value.expressions().iter().any(|e| e.depends_on("t")))
    }

    /// True if there are no loads at all.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// F(t) over all unknowns (prescribed components included: their share enters the
    /// reactions), written into `out` (overwritten).
    /// A load density that is not finite at some quadrature point is an error naming the load,
    /// the point and t.
    pub fn assemble(&self, t: f64, dofs: &DofMap<D>, out: &mut [f64]) -> Result<(), String> {
        out.iter_mut().for_each(|v| *v = 0.0);
        for term in &self.terms {
            for p in &term.points {
                // TRACTION_VARIABLES (x, y, z, t, nx, ny, nz); a body force uses the first four.
                let mut vars = [0.0; 7];
                vars[..D].copy_from_slice(&p.x);
                vars[4..4 + D].copy_from_slice(&p.normal);
                vars[3] = t;
                let (f, bad): ([f64; D], Option<(String, &Expr, f64)>) = match &term.value {
                    Density::Vector(value) => {
                        let f: [f64; D] = std::array::from_fn(|c| value[c].eval(&vars));
                        let bad = f
                            .iter()
                            .position(|v| !v.is_finite())
                            .map(|c| (format!("{}[{c}]", term.label), &value[c], f[c]));
                        (f, bad)
                    }
                    Density::Pressure(pressure) => {
                        let pv = pressure.eval(&vars);
                        let bad = (!pv.is_finite()).then(|| (term.label.clone(), pressure.as_ref(), pv));
                        (std::array::from_fn(|c| -pv * p.normal[c]), bad)
                    }
                };
                if let Some((key, e, v)) = bad {
                    let at: Vec<String> = p.x.iter().map(|v| v.to_string()).collect();
                    return Err(format!(
                        "{key} = \"{}\" is {v} at (x, y{}) = ({}), t = {t}; make the expression finite on the whole group",
                        e.source(),
                        if D == 3 { ", z" } else { "" },
                        at.join(", ")
                    ));
                }
                for &(node, n) in &p.shape {
                    for (c, fc) in f.iter().enumerate() {
                        out[dofs.index(node, c)] += p.weight * fc * n;
                    }
                }
            }
        }
        Ok(())
    }
}
