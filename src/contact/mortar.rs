//! Mortar weights of a surface pair with dual multipliers (docs/method.md §18.2): the row of a
//! slave node p is the mortar constraint ∫_S ψ_p (u_M∘π − u_S)·n_p ds ≤ ∫_S ψ_p g ds divided by
//! D_p = ∫_S ψ_p ds, where ψ_p is the dual basis function of p, biorthogonal to the slave shape
//! functions on each slave facet (∫ ψ_p N_q = δ_pq ∫ N_p; Wohlmuth 2000). Biorthogonality turns
//! the slave side into the node's own displacement, so the row keeps the form of the node-to-segment
//! row, u_ν = (Σ_i c_pi u_i − u_S)·n_p ≤ g_p, with c_pi = ∫ ψ_p N_i∘π / D_p in place of N_i(ξ_p)
//! and the weighted gap g_p = ∫ ψ_p (x_S − x_M∘π)·n_p / D_p. The master node i then receives
//! Σ_p λ_p c_pi: for a uniform pressure (λ_p = p D_p) that is p ∫ N_i (Σ_p ψ_p = 1), the
//! consistent load, which is why the contact patch test passes on non-matching meshes.
//!
//! The integrals run over the overlap of each slave facet with each master facet, segment by
//! segment (in 2D the master edge's end points projected onto the slave edge cut it; in 3D the
//! master face's corners projected onto the slave face make a polygon, clipped to the slave face
//! by Sutherland–Hodgman and cut into triangles), so that the integrands are smooth on every piece
//! and the rules are exact on flat surfaces. Written by hand: no crate does segment-to-segment
//! mortar integration.
//!
//! On a slave facet of second order (docs/method.md §18.6) ψ_p is the contact rows' function of
//! §19.3 (`topology::row_functions`): on a face the dual basis of its own functions, transformed
//! first on 6-node triangles and 8-node quadrangles (whose corners have ∫ N_p ≤ 0), taken on the
//! reference face; on a 3-node edge the first-order functions of its halves (the overlap is cut
//! at its midpoint too). These are not biorthogonal to N, so the slave side of the row is the
//! weighted mean of the slave nodes of a one-body row (`Rows::spread`, src/contact/rows.rs) — on
//! an affine 9-node quadrangle the node's own.

use super::pairing::{closest, facet_at, SurfacePair};
use crate::mesh::quadrature::{tensor_gauss, EDGE_GAUSS_3, TRI6};
use crate::mesh::topology::{dual_of, row_functions};
use crate::mesh::Facet;
use nalgebra::DMatrix;
use std::collections::HashMap;

/// The least share D_p / ∫ N_p of a slave node's support that must lie over the master for its
/// row to take mortar weights; a node at the rim of the overlap with less (its dual function,
/// negative in part, would divide by a small D_p) keeps the node-to-segment row. The patch tests
/// (tests/two_bodies.rs) have full overlap; the choice only matters at a rim.
pub const LEAST_SHARE: f64 = 0.5;

/// A slave node's mortar row: u_ν = (Σ_i c_i u_i − u_S)·n ≤ gap.
#[derive(Clone, Debug, PartialEq)]
pub struct MortarRow {
    /// The master nodes and their coefficients c_i (summing to 1).
    pub terms: Vec<(usize, f64)>,
    /// The weighted gap g_p.
    pub gap: f64,
}

/// What is integrated for one slave node.
#[derive(Clone)]
struct Sums<const D: usize> {
    /// D_p = ∫ ψ_p over the overlap.
    share: f64,
    /// ∫ ψ_p N_i∘π per master node i.
    master: Vec<(usize, f64)>,
    /// ∫ ψ_p (x_S − x_M∘π).
    gap: [f64; D],
}

/// A quadrature rule on a facet's reference domain: (ξ, weight) — exact for the products of two
/// functions of a flat facet of either order.
fn facet_rule(f: &Facet) -> Vec<([f64; 2], f64)> {
    match f.corners().len() {
        2 => EDGE_GAUSS_3.iter().map(|&(s, w)| ([s, 0.0], w)).collect(),
        3 => TRI6.to_vec(),
        _ => tensor_gauss(3, 2)
            .into_iter()
            .map(|q| ([q.xi[0], q.xi[1]], q.weight))
            .collect(),
    }
}

/// A rule over a whole slave facet exact for its multiplier functions times its own: the
/// facet's rule, on a 3-node edge its halves' (docs/method.md §19.3).
fn whole_rule(f: &Facet) -> Vec<([f64; 2], f64)> {
    if f.dim() == 1 && f.is_second_order() {
        return crate::mesh::topology::row_rule(f)
            .into_iter()
            .map(|(xi, w, _)| ([xi[0], xi[1]], w))
            .collect();
    }
    facet_rule(f)
}

/// The measure factor at a point x: 2πr on a body of revolution, else 1.
fn revolved_factor<const D: usize>(x: &[f64; D], revolved: bool) -> f64 {
    if revolved {
        2.0 * std::f64::consts::PI * x[0]
    } else {
        1.0
    }
}

/// The dual basis of a first-order facet `f`: ψ_j = Σ_k A_jk N_k with A = D M⁻¹ (M the facet's
/// mass matrix, D its row sums), so that ∫ ψ_j N_k = δ_jk ∫ N_j on the facet.
fn dual_basis<const D: usize>(points: &[[f64; D]], f: &Facet, revolved: bool) -> DMatrix<f64> {
    let n = f.len();
    let mut mass = DMatrix::<f64>::zeros(n, n);
    for (xi, w) in facet_rule(f) {
        let at = facet_at(points, f, xi);
        let dw = w * at.measure() * revolved_factor(&at.point, revolved);
        for i in 0..n {
            for j in 0..n {
                mass[(i, j)] += at.shape[i] * at.shape[j] * dw;
            }
        }
    }
    dual_of(mass)
}

/// The multiplier functions ψ_j of a slave facet: the dual basis of a first-order facet, the
/// contact rows' functions of a second-order one (docs/method.md §18.6).
enum Multipliers {
    Dual(DMatrix<f64>),
    Rows,
}

impl Multipliers {
    fn of<const D: usize>(points: &[[f64; D]], f: &Facet, revolved: bool) -> Self {
        if f.is_second_order() {
            Multipliers::Rows
        } else {
            Multipliers::Dual(dual_basis(points, f, revolved))
        }
    }

    /// ψ_j at reference point `xi` of facet `f`, whose shape values there are `shape`.
    fn at(&self, f: &Facet, xi: [f64; 2], shape: &[f64; 9]) -> [f64; 9] {
        match self {
            Multipliers::Dual(a) => std::array::from_fn(|j| {
                if j < f.len() {
                    (0..f.len()).map(|l| a[(j, l)] * shape[l]).sum()
                } else {
                    0.0
                }
            }),
            Multipliers::Rows => row_functions(f, xi),
        }
    }
}

/// The reference domain of a facet as a convex polygon, counter-clockwise (2D: the interval).
fn domain(f: &Facet) -> Vec<[f64; 2]> {
    match f.corners().len() {
        2 => vec![[0.0, 0.0], [1.0, 0.0]],
        3 => vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
        _ => vec![[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]],
    }
}

/// Clips `subject` to the convex counter-clockwise polygon `clip` (Sutherland–Hodgman).
fn clip_polygon(subject: &[[f64; 2]], clip: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out = subject.to_vec();
    for e in 0..clip.len() {
        if out.is_empty() {
            break;
        }
        let (a, b) = (clip[e], clip[(e + 1) % clip.len()]);
        let side = |p: &[f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let input = std::mem::take(&mut out);
        for i in 0..input.len() {
            let (p, q) = (input[i], input[(i + 1) % input.len()]);
            let (sp, sq) = (side(&p), side(&q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
    }
    out
}

/// The quadrature points, in the slave facet's reference coordinates, of the part of slave facet
/// `s` over master facet `m` (empty if they do not overlap): the master's corners projected onto
/// the slave cut it (on a curved master face the cut between two of them is taken straight in the
/// slave's coordinates).
fn overlap<const D: usize>(points: &[[f64; D]], s: &Facet, m: &Facet) -> Vec<([f64; 2], f64)> {
    let corners: Vec<[f64; 2]> = m.corners().iter().map(|&q| closest(points, s, &points[q])).collect();
    // a corner with no foot on a curved slave facet's extension: no overlap to integrate
    if corners.iter().flatten().any(|v| !v.is_finite()) {
        return Vec::new();
    }
    if s.dim() == 1 {
        // a 3-node slave edge's functions are first order on its halves: cut at its midpoint too
        let halves: &[(f64, f64)] = if s.is_second_order() {
            &[(0.0, 0.5), (0.5, 1.0)]
        } else {
            &[(0.0, 1.0)]
        };
        let mut rule = Vec::new();
        for &(from, to) in halves {
            let (lo, hi) = (
                corners[0][0].min(corners[1][0]).max(from),
                corners[0][0].max(corners[1][0]).min(to),
            );
            if hi - lo > 1e-12 {
                rule.extend(
                    EDGE_GAUSS_3
                        .iter()
                        .map(|&(t, w)| ([lo + t * (hi - lo), 0.0], w * (hi - lo))),
                );
            }
        }
        return rule;
    }
    let polygon = clip_polygon(&corners, &domain(s));
    let mut rule = Vec::new();
    for k in 1..polygon.len().saturating_sub(1) {
        let (a, b, c) = (polygon[0], polygon[k], polygon[k + 1]);
        let (e, f) = ([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]);
        let det = (e[0] * f[1] - e[1] * f[0]).abs();
        if det <= 1e-14 {
            continue;
        }
        rule.extend(TRI6.iter().map(|&(xi, w)| {
            (
                [a[0] + xi[0] * e[0] + xi[1] * f[0], a[1] + xi[0] * e[1] + xi[1] * f[1]],
                w * det,
            )
        }));
    }
    rule
}

/// The mortar row of each slave node of `pair` (in the order of the slave part's nodes): None for
/// a node off the master, or over it by less than [`LEAST_SHARE`] of its support.
pub fn rows<const D: usize>(points: &[[f64; D]], pair: &SurfacePair<D>, revolved: bool) -> Vec<Option<MortarRow>> {
    let (slave, master) = (&pair.slave, &pair.master);
    let mut around: HashMap<usize, Vec<usize>> = HashMap::new();
    for (i, f) in master.facets.iter().enumerate() {
        for &q in f.nodes() {
            around.entry(q).or_default().push(i);
        }
    }
    let mut sums = vec![
        Sums::<D> {
            share: 0.0,
            master: Vec::new(),
            gap: [0.0; D],
        };
        slave.nodes.len()
    ];
    let mut support = vec![0.0; slave.nodes.len()];
    for s in &slave.facets {
        let local: Vec<usize> = s
            .nodes()
            .iter()
            .map(|&p| slave.local(p).expect("on the part"))
            .collect();
        // the master facets over this one: from those its nodes project onto, by neighbours
        let mut queue: Vec<usize> = local
            .iter()
            .filter_map(|&k| pair.projections[k].as_ref().map(|p| p.facet))
            .collect();
        queue.sort_unstable();
        queue.dedup();
        let psi = Multipliers::of(points, s, revolved);
        // each slave node's whole support ∫ψ_p, against which its share over the master is read
        for (xi, w) in whole_rule(s) {
            let at = facet_at(points, s, xi);
            let dw = w * at.measure() * revolved_factor(&at.point, revolved);
            for (&k, value) in local.iter().zip(psi.at(s, xi, &at.shape)) {
                support[k] += value * dw;
            }
        }
        if queue.is_empty() {
            continue;
        }
        let mut seen: Vec<usize> = queue.clone();
        while let Some(mi) = queue.pop() {
            let m = &master.facets[mi];
            let rule = overlap(points, s, m);
            if rule.is_empty() {
                continue;
            }
            for (xi, w) in rule {
                let at = facet_at(points, s, xi);
                let on = facet_at(points, m, closest(points, m, &at.point));
                let dw = w * at.measure() * revolved_factor(&at.point, revolved);
                let values = psi.at(s, xi, &at.shape);
                for (j, &k) in local.iter().enumerate() {
                    let psi_j = values[j] * dw;
                    if psi_j == 0.0 {
                        continue;
                    }
                    let sum = &mut sums[k];
                    sum.share += psi_j;
                    for c in 0..D {
                        sum.gap[c] += psi_j * (at.point[c] - on.point[c]);
                    }
                    for (&q, &n) in m.nodes().iter().zip(&on.shape) {
                        match sum.master.iter_mut().find(|(r, _)| *r == q) {
                            Some((_, v)) => *v += psi_j * n,
                            None => sum.master.push((q, psi_j * n)),
                        }
                    }
                }
            }
            for &q in m.nodes() {
                for &next in &around[&q] {
                    if !seen.contains(&next) {
                        seen.push(next);
                        queue.push(next);
                    }
                }
            }
        }
    }
    sums.into_iter()
        .enumerate()
        .map(|(k, sum)| {
            let projection = pair.projections[k].as_ref()?;
            if sum.share <= 0.0 || sum.share < LEAST_SHARE * support[k] {
                return None;
            }
            let mut terms: Vec<(usize, f64)> = sum.master.iter().map(|&(q, v)| (q, v / sum.share)).collect();
            terms.sort_unstable_by_key(|&(q, _)| q);
            let n = projection.normal;
            Some(MortarRow {
                terms,
                gap: (0..D).map(|c| sum.gap[c] * n[c]).sum::<f64>() / sum.share,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured::{rectangle, CellShape};
    use crate::mesh::{BoundaryPart, GroupSelector, Mesh};

    fn part<const D: usize>(mesh: &Mesh<D>, name: &str) -> BoundaryPart<D> {
        mesh.boundary(&GroupSelector::Name(name.into())).unwrap()
    }

    /// Two rectangles (0, 2) × (0, 1) with 8 and `n` cells across, the second lifted by 1 + gap:
    /// the lower top is the master, the upper bottom the slave.
    fn stacked(n: usize, gap: f64) -> (Vec<[f64; 2]>, BoundaryPart<2>, BoundaryPart<2>) {
        let lower = rectangle(2.0, 1.0, 8, 2, CellShape::Quad);
        let upper = rectangle(2.0, 1.0, n, 2, CellShape::Tri);
        let mut points = lower.points.clone();
        let offset = points.len();
        points.extend(upper.points.iter().map(|x| [x[0], x[1] + 1.0 + gap]));
        let master = part(&lower, "Gamma2_top");
        let mut slave = part(&upper, "Gamma3");
        slave.nodes.iter_mut().for_each(|p| *p += offset);
        slave.facets = slave
            .facets
            .iter()
            .map(|f| Facet::from_slice(&f.nodes().iter().map(|p| p + offset).collect::<Vec<_>>()))
            .collect();
        (points, slave, master)
    }

    /// On non-matching flat surfaces each row's coefficients sum to 1, its gap is the uniform gap,
    /// and the master nodes receive the consistent load of a uniform pressure: Σ_p D_p c_pi = ∫ N_i
    /// (the master's lumped weights) — the discrete statement of the contact patch test.
    #[test]
    fn flat_non_matching_surfaces_transmit_a_uniform_pressure_consistently() {
        for n in [3, 7, 8, 13] {
            let (points, slave, master) = stacked(n, 0.01);
            let pair = SurfacePair::new(&points, slave.clone(), master.clone()).unwrap();
            let rows = rows(&points, &pair, false);
            let mut load = vec![0.0; points.len()];
            for (k, row) in rows.iter().enumerate() {
                let row = row.as_ref().expect("full overlap: every node is a mortar row");
                let total: f64 = row.terms.iter().map(|t| t.1).sum();
                assert!((total - 1.0).abs() < 1e-13, "n = {n}: Σ c = {total}");
                assert!((row.gap - 0.01).abs() < 1e-13, "n = {n}: gap {}", row.gap);
                for &(q, c) in &row.terms {
                    load[q] += slave.weights[k] * c;
                }
            }
            for (k, &q) in master.nodes.iter().enumerate() {
                assert!(
                    (load[q] - master.weights[k]).abs() < 1e-13,
                    "n = {n}: master node {q} receives {} for {}",
                    load[q],
                    master.weights[k]
                );
            }
        }
    }

    /// Clipping a square by the unit triangle leaves the triangle's part of it.
    #[test]
    fn sutherland_hodgman_clips_to_the_reference_triangle() {
        let square = [[0.5, -0.5], [0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5]];
        let clipped = clip_polygon(&square, &domain(&Facet::from_slice(&[0, 1, 2])));
        let area: f64 = (0..clipped.len())
            .map(|i| {
                let (p, q) = (clipped[i], clipped[(i + 1) % clipped.len()]);
                p[0] * q[1] - p[1] * q[0]
            })
            .sum::<f64>()
            / 2.0;
        // the square [0, 0.5]² minus nothing: x + y ≤ 1 holds on all of it
        assert!((area.abs() - 0.25).abs() < 1e-15, "area {area}");
    }
}
