//! The contact rows of a run (docs/method.md §14): every contact group contributes, at each of
//! its nodes, one row u_ν = d·u per cluster of the node's facets whose normals lie within 45° of
//! each other (one row on a smooth part, one per face at a corner of the group); rows of a node
//! whose directions lie within 45° are then merged into one (the stricter wall's, carrying the
//! laws of all of them), the others stay separate constraints. A node never carries more than D
//! rows.

use super::nodal::LawTerm;
use super::obstacle::Obstacle;
use crate::mesh::vector::dot;
use crate::mesh::BoundaryPart;

/// Directions closer than this (cos 45°) are one wall; farther apart, two.
pub const CORNER_COSINE: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// What one contact group brings.
pub struct GroupRows<'a, const D: usize> {
    /// How messages name the group's obstacle (e.g. `contact[1].obstacle`).
    pub key: String,
    pub part: &'a BoundaryPart<D>,
    pub obstacle: Option<&'a Obstacle<D>>,
    /// Along the obstacle's normal (else the body's).
    pub along_obstacle: bool,
    /// The group's law as given and its one-sided version (indices into the run's laws), used at
    /// rows in initial contact and at rows with an initial gap respectively.
    pub law: Option<(usize, usize)>,
    /// The layer g between first contact and the rigid bound, per node of `part` (∞: none).
    pub layer: Vec<f64>,
    /// Index of the obstacle's rigid motion a(t), if it moves.
    pub motion: Option<usize>,
}

/// The merged rows.
#[derive(Clone, Debug, Default)]
pub struct Rows<const D: usize> {
    pub nodes: Vec<usize>,
    pub weights: Vec<f64>,
    pub directions: Vec<[f64; D]>,
    /// The group whose wall the row is (the stricter one where several meet).
    pub group: Vec<usize>,
    /// gap₀ (0 without an obstacle).
    pub gap: Vec<f64>,
    /// The layer g: the rigid bound is at gap + g (∞: no bound).
    pub layer: Vec<f64>,
    /// (motion index, ∂gap/∂a) of a moving obstacle.
    pub motion: Vec<Option<(usize, [f64; D])>>,
    pub terms: Vec<Vec<LawTerm>>,
    /// A row of second-order faces (docs/method.md §19.3): u_ν = Σ_i c_i d·u_i over the nodes of
    /// its node's faces, as (node, c_i) with Σ c_i = 1 (its gap and layer the same means of the
    /// nodes' ones); empty for a row u_ν = d·u of its node.
    pub spread: Vec<Vec<(usize, f64)>>,
    /// Rows dropped because their normal never meets the obstacle: (node, group).
    pub never_touching: Vec<(usize, usize)>,
}

struct Candidate<const D: usize> {
    node: usize,
    weight: f64,
    normal: [f64; D],
    spread: Vec<(usize, f64)>,
}

fn unit<const D: usize>(v: [f64; 3]) -> [f64; D] {
    let n = v[..D].iter().map(|x| x * x).sum::<f64>().sqrt();
    std::array::from_fn(|k| v[k] / n)
}

/// The (weight, normal) clusters of a group's facets at each node: one per node unless the
/// node is at a corner of the group.
fn clusters<const D: usize>(part: &BoundaryPart<D>, points: &[[f64; D]]) -> Vec<Candidate<D>> {
    // per node: the facets' (∫N, ∫N n ds) contributions
    let mut at: Vec<Vec<(f64, [f64; 3])>> = vec![Vec::new(); part.nodes.len()];
    for f in &part.facets {
        let (w, nv, _) = crate::mesh::facet_integrals(points, f);
        for (a, &p) in f.nodes().iter().enumerate() {
            if let Some(k) = part.local(p) {
                at[k].push((w[a], nv[a]));
            }
        }
    }
    let mut out = Vec::with_capacity(part.nodes.len());
    for (k, contributions) in at.iter().enumerate() {
        let mut groups: Vec<(f64, [f64; 3])> = Vec::new();
        for &(w, nv) in contributions {
            let n: [f64; D] = unit(nv);
            match groups.iter_mut().find(|(_, s)| dot(&unit::<D>(*s), &n) > CORNER_COSINE) {
                Some((gw, s)) => {
                    *gw += w;
                    for c in 0..3 {
                        s[c] += nv[c];
                    }
                }
                None => groups.push((w, nv)),
            }
        }
        if groups.len() <= 1 {
            // a smooth node: the part's own weight and normal (bit for bit the one-group rows)
            out.push(Candidate {
                node: part.nodes[k],
                weight: part.weights[k],
                normal: part.normals[k],
                spread: Vec::new(),
            });
        } else {
            for (w, s) in groups {
                out.push(Candidate {
                    node: part.nodes[k],
                    weight: w,
                    normal: unit(s),
                    spread: Vec::new(),
                });
            }
        }
    }
    out
}

/// The rows of a part made of second-order faces (docs/method.md §19.3): one at each node j of
/// the faces, its multiplier function ψ_j that of [`crate::mesh::topology::row_functions`] (on a
/// face the dual basis of its own or transformed functions, on an edge the split's first-order
/// functions; [`crate::mesh::topology::row_rule`] integrates them): the weight D_j = ∫ψ_j ds, the
/// direction the mean of n weighted by ψ_j, and the row u_ν = Σ_i c_ji d·u_i with
/// c_ji = ∫ψ_j N_i ds / D_j over the nodes i of j's faces (N_i their own functions) — a uniform
/// pressure then loads node i with ∫N_i p ds, the patch test. On a body of revolution the
/// measure is 2πr ds.
fn node_rows<const D: usize>(part: &BoundaryPart<D>, points: &[[f64; D]]) -> Vec<Candidate<D>> {
    use crate::mesh::topology::{facet_map, row_rule};
    // per node: D_j, ∫ψ_j n ds and the (node, ∫ψ_j N_i ds) of its faces' nodes
    type Sums = (f64, [f64; 3], Vec<(usize, f64)>);
    let mut at: std::collections::BTreeMap<usize, Sums> = Default::default();
    for f in &part.facets {
        let nodes = f.nodes();
        for (xi, weight, psi) in row_rule(f) {
            let (value, dn, x) = facet_map(points, f, xi);
            let revolved = if part.revolved {
                2.0 * std::f64::consts::PI * x[0]
            } else {
                1.0
            };
            let (da, scale) = (crate::mesh::vector::norm(&dn) * weight * revolved, weight * revolved);
            for (a, &p) in nodes.iter().enumerate() {
                let (w, nv, terms) = at.entry(p).or_default();
                *w += psi[a] * da;
                for k in 0..3 {
                    nv[k] += psi[a] * dn[k] * scale;
                }
                for (i, &node) in nodes.iter().enumerate() {
                    match terms.iter_mut().find(|t| t.0 == node) {
                        Some(t) => t.1 += psi[a] * value[i] * da,
                        None => terms.push((node, psi[a] * value[i] * da)),
                    }
                }
            }
        }
    }
    // a row's weight is positive by construction (§19.3); keep the guard against a degenerate face
    at.into_iter()
        .filter(|(_, (weight, _, _))| *weight > 0.0)
        .map(|(node, (weight, nv, mut terms))| {
            terms.sort_unstable_by_key(|t| t.0);
            terms.iter_mut().for_each(|t| t.1 /= weight);
            Candidate {
                node,
                weight,
                normal: unit(nv),
                spread: terms,
            }
        })
        .collect()
}

/// The coefficients of a row over its nodes: its spread, or its own node with 1.
fn spread_of(node: usize, spread: &[(usize, f64)]) -> Vec<(usize, f64)> {
    if spread.is_empty() {
        vec![(node, 1.0)]
    } else {
        spread.to_vec()
    }
}

/// Two rows of one node merged into one wall: their coefficients weighted by their weights.
fn merged_spread(a: (&[(usize, f64)], f64), b: (&[(usize, f64)], f64), node: usize) -> Vec<(usize, f64)> {
    if a.0.is_empty() && b.0.is_empty() {
        return Vec::new();
    }
    let mut out: Vec<(usize, f64)> = Vec::new();
    for (terms, w) in [a, b] {
        for (q, c) in spread_of(node, terms) {
            let share = c * w / (a.1 + b.1);
            match out.iter_mut().find(|t| t.0 == q) {
                Some(t) => t.1 += share,
                None => out.push((q, share)),
            }
        }
    }
    out.sort_unstable_by_key(|t| t.0);
    out
}

/// Builds the merged rows of all groups; `length` is the body's size (tolerances), `points` the
/// mesh's nodes.
pub fn build<const D: usize>(groups: &[GroupRows<D>], points: &[[f64; D]], length: f64) -> Result<Rows<D>, String> {
    struct Row<const D: usize> {
        node: usize,
        weight: f64,
        direction: [f64; D],
        group: usize,
        gap: f64,
        layer: f64,
        motion: Option<(usize, [f64; D])>,
        terms: Vec<LawTerm>,
        spread: Vec<(usize, f64)>,
    }
    let mut rows: Vec<Row<D>> = Vec::new();
    let mut never = Vec::new();
    for (gi, g) in groups.iter().enumerate() {
        let candidates = if g.part.facets.iter().any(|f| f.is_second_order()) {
            node_rows(g.part, points)
        } else {
            clusters(g.part, points)
        };
        for c in candidates {
            let x = &points[c.node];
            let (direction, mut gap, motion) = match g.obstacle {
                None => (c.normal, 0.0, None),
                Some(o) => {
                    let gap = o
                        .gap(x, &c.normal, g.along_obstacle, length)
                        .map_err(|e| format!("{}: {e}", g.key))?;
                    (gap.direction, gap.gap, g.motion.map(|m| (m, gap.motion)))
                }
            };
            let k = g.part.local(c.node).expect("a node of the part");
            let mut layer = g.layer[k];
            if !c.spread.is_empty() {
                // a spread row's gap and layer are its weighted ones, Σ_i c_i g_i (docs/method.md
                // §19.3): the row is a weighted mean of u_ν, so is its bound
                let (mut weighted_gap, mut weighted_layer) = (0.0, 0.0);
                for &(i, ci) in &c.spread {
                    if let Some(o) = g.obstacle {
                        let at_i = o
                            .gap(&points[i], &c.normal, g.along_obstacle, length)
                            .map_err(|e| format!("{}: {e}", g.key))?;
                        weighted_gap += ci * at_i.gap;
                    }
                    weighted_layer += ci * g.layer[g.part.local(i).expect("a node of the part")];
                }
                if g.obstacle.is_some() {
                    gap = weighted_gap;
                }
                if weighted_layer.is_finite() {
                    layer = weighted_layer;
                }
            }
            if !gap.is_finite() {
                never.push((c.node, gi));
                continue;
            }
            let terms = match g.law {
                // a row with an initial gap never touched: its law is one-sided
                Some((given, one_sided)) => vec![LawTerm {
                    law: if gap > 1e-9 * length { one_sided } else { given },
                    weight: c.weight,
                    group: gi,
                }],
                None => Vec::new(),
            };
            rows.push(Row {
                node: c.node,
                weight: c.weight,
                direction,
                group: gi,
                gap,
                layer,
                motion,
                terms,
                spread: c.spread,
            });
        }
    }
    // merge the rows of a node whose directions are one wall
    rows.sort_by_key(|r| r.node); // stable: groups keep their order at a node
    let mut out = Rows {
        never_touching: never,
        ..Default::default()
    };
    let mut rest = rows.into_iter().peekable();
    while let Some(first) = rest.next() {
        let node = first.node;
        let mut merged: Vec<Row<D>> = vec![first];
        while let Some(r) = rest.next_if(|r| r.node == node) {
            match merged
                .iter_mut()
                .find(|m| dot(&m.direction, &r.direction) > CORNER_COSINE)
            {
                None => merged.push(r),
                Some(m) => {
                    // the stricter wall: the smaller gap sets direction and origin; the rigid bound
                    // is the nearer of the two
                    let limit = (m.gap + m.layer).min(r.gap + r.layer);
                    let mut terms = std::mem::take(&mut m.terms);
                    terms.extend(r.terms.iter().copied());
                    let weight = m.weight + r.weight;
                    let spread = merged_spread((&m.spread, m.weight), (&r.spread, r.weight), node);
                    if r.gap < m.gap {
                        *m = r;
                    }
                    m.layer = limit - m.gap;
                    m.terms = terms;
                    m.weight = weight;
                    m.spread = spread;
                }
            }
        }
        if merged.len() > D {
            return Err(format!(
                "the contact node at {:?} meets {} walls (contact groups or faces more than 45° apart); a node can \
                 carry at most {D} independent constraints in {D}D: merge some of its groups",
                points[merged[0].node],
                merged.len()
            ));
        }
        for r in merged {
            out.nodes.push(r.node);
            out.weights.push(r.weight);
            out.directions.push(r.direction);
            out.group.push(r.group);
            out.gap.push(r.gap);
            out.layer.push(r.layer);
            out.motion.push(r.motion);
            out.terms.push(r.terms);
            out.spread.push(r.spread);
        }
    }
    Ok(out)
}
