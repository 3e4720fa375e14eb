//! Pairing two surfaces of the mesh for contact between deformable bodies (docs/method.md §18.1):
//! each node of the slave surface S is projected onto the master surface M, in the reference
//! configuration (small strain, small sliding: once per run). A projection is the closest point
//! x_M(ξ) = Σ N_i(ξ) x_i (first- or second-order facets: docs/method.md §18.6) on a facet of M
//! whose reference coordinates ξ lie in the facet (within
//! [`INSIDE`], or [`RIM_CONE`]); its gap is g₀ = (x_S − x_M)·n, n the master facet's outward unit
//! normal there (positive: apart; negative: the slave node starts inside the master body).
//!
//! This is the geometry: `hvi check` lists a pair with [`PairSummary`] and refuses surfaces that
//! face the same way or do not overlap; the rows with their mortar weights are
//! src/contact/mortar.rs's. The facets near a node come from a grid over the master facets'
//! bounding boxes (src/contact/facet_grid.rs), nearest first.

use super::facet_grid::FacetGrid;
use crate::mesh::topology::facet_shape;
use crate::mesh::vector::{self, distance, dot, norm};
use crate::mesh::{BoundaryPart, Facet};

/// How far outside a facet's reference domain (in reference units) a projection still counts as
/// on it, clamped onto the facet's edge: a node of S above an edge or the rim of M projects onto
/// the facets there only to round-off, or, above a warped quadrilateral, to the warp's slope times
/// the gap (a node 0.01 above the rim of faces warped by 1e-3 over 0.5 lands 1e-4 outside).
pub const INSIDE: f64 = 1e-3;

/// Beyond [`INSIDE`], a node still projects onto a facet whose edge it lies beyond by at most this
/// share of its distance to the facet: on a faceted curved surface cut by a symmetry plane the
/// facets' normals tilt off the plane, and a node on the plane at a gap d lands beyond their edge
/// by about d times the tilt (tests/two_body_hertz.rs: 16 of 324 slave nodes on the spheres'
/// symmetry planes, 5e-3 beyond in reference units, had no row with INSIDE alone).
pub const RIM_CONE: f64 = 0.1;

/// A slave node's projection onto the master surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Projection<const D: usize> {
    /// The master facet (index into the master part's facets).
    pub facet: usize,
    /// The master nodes of the facet and their shape values N_i(ξ) at the projection.
    pub shape: Vec<(usize, f64)>,
    /// x_M(ξ).
    pub point: [f64; D],
    /// The master facet's outward unit normal at ξ.
    pub normal: [f64; D],
    /// g₀ = (x_S − x_M)·n.
    pub gap: f64,
}

/// The pairing of a slave surface with a master surface: per slave node (in the order of the
/// slave part's nodes) its projection, None where it falls off the master surface.
#[derive(Clone, Debug)]
pub struct SurfacePair<const D: usize> {
    pub slave: BoundaryPart<D>,
    pub master: BoundaryPart<D>,
    pub projections: Vec<Option<Projection<D>>>,
}

/// What `hvi check` says of a pair.
#[derive(Clone, Debug, PartialEq)]
pub struct PairSummary {
    /// Slave nodes with a projection, and without.
    pub paired: usize,
    pub unpaired: usize,
    /// The largest initial gap (≥ 0) and the deepest initial penetration (≥ 0) over the paired
    /// slave nodes.
    pub largest_gap: f64,
    pub deepest_penetration: f64,
    /// Paired slave nodes whose own outward normal points along the master's (n_S·n_M > 0): the
    /// surfaces face the same way there.
    pub facing_away: usize,
    /// The mean size (length, or the square root of the area) of the slave facets with a paired
    /// node, and of the master facets the slave nodes project onto (0 without a paired node).
    pub slave_size: f64,
    pub master_size: f64,
}

/// Why two surfaces cannot be paired.
#[derive(Clone, Debug, PartialEq)]
pub enum PairingError {
    /// No slave node projects onto the master surface.
    NoOverlap,
    /// Most paired slave nodes' normals point along the master's.
    SameWay { facing_away: usize, paired: usize },
}

/// A facet's geometry at reference coordinates ξ (an edge: ξ₀ ∈ [0, 1] from its first node; a
/// triangle: the unit triangle; a quadrilateral: [−1, 1]²).
pub(crate) struct FacetAt<const D: usize> {
    /// The facet's shape values N_i(ξ), in the order of its nodes (the first `len` of 9).
    pub shape: [f64; 9],
    /// x(ξ) = Σ N_i(ξ) x_i.
    pub point: [f64; D],
    /// ∂x/∂ξ₀ and ∂x/∂ξ₁ (zero on an edge).
    pub tangents: [[f64; D]; 2],
}

impl<const D: usize> FacetAt<D> {
    /// The outward unit normal: (dy, −dx) on an edge (the body on its left), t₀ × t₁ on a face.
    pub fn normal(&self) -> [f64; D] {
        let t = &self.tangents;
        if D == 2 {
            let l = norm(&t[0]);
            std::array::from_fn(|k| if k == 0 { t[0][1] / l } else { -t[0][0] / l })
        } else {
            let c = cross(t);
            let l = norm(&c);
            std::array::from_fn(|k| c[k] / l)
        }
    }

    /// ds/dξ: the length or area element of the reference coordinates.
    pub fn measure(&self) -> f64 {
        if D == 2 {
            norm(&self.tangents[0])
        } else {
            norm(&cross(&self.tangents))
        }
    }
}

/// t₀ × t₁ of a face's tangents (D = 3 only).
fn cross<const D: usize>(t: &[[f64; D]; 2]) -> [f64; 3] {
    vector::cross(std::array::from_fn(|k| t[0][k]), std::array::from_fn(|k| t[1][k]))
}

/// The geometry of facet `f` at ξ, of first or second order.
pub(crate) fn facet_at<const D: usize>(points: &[[f64; D]], f: &Facet, xi: [f64; 2]) -> FacetAt<D> {
    let (n, value, grad) = facet_shape(f, [xi[0], xi[1], 0.0]);
    let mut at = FacetAt {
        shape: std::array::from_fn(|i| if i < n { value[i] } else { 0.0 }),
        point: [0.0; D],
        tangents: [[0.0; D]; 2],
    };
    for (i, &node) in f.nodes().iter().enumerate() {
        let p = points[node];
        for k in 0..D {
            at.point[k] += value[i] * p[k];
            at.tangents[0][k] += grad[i][0] * p[k];
            at.tangents[1][k] += grad[i][1] * p[k];
        }
    }
    at
}

/// The reference coordinates of the closest point to `x` of the surface through facet `f`
/// (extended beyond its edges), by Gauss–Newton: exact in one step on an edge or a triangle, a
/// few on a warped quadrilateral or a curved second-order facet (to 1e-12 in reference units).
pub(crate) fn closest<const D: usize>(points: &[[f64; D]], f: &Facet, x: &[f64; D]) -> [f64; 2] {
    let affine = f.len() <= 3 && !f.is_second_order();
    let mut xi = match f.corners().len() {
        2 => [0.5, 0.0],
        3 => [1.0 / 3.0, 1.0 / 3.0],
        _ => [0.0, 0.0],
    };
    for _ in 0..30 {
        let FacetAt { point, tangents: t, .. } = facet_at(points, f, xi);
        let r: [f64; D] = std::array::from_fn(|k| x[k] - point[k]);
        // normal equations of the tangents: (TᵀT) Δξ = Tᵀ r
        let (a00, a01, a11) = (dot(&t[0], &t[0]), dot(&t[0], &t[1]), dot(&t[1], &t[1]));
        let (b0, b1) = (dot(&t[0], &r), dot(&t[1], &r));
        let step = if f.dim() == 1 {
            [b0 / a00, 0.0]
        } else {
            let det = a00 * a11 - a01 * a01;
            [(a11 * b0 - a01 * b1) / det, (a00 * b1 - a01 * b0) / det]
        };
        xi[0] += step[0];
        xi[1] += step[1];
        // an edge or a triangle is affine: one step is exact; a quadrilateral's or a curved
        // facet's steps shrink quadratically to round-off, which in reference units is 1e-16
        // times the point's distance over the facet's size (so an absolute 1e-14 could never be
        // met far away)
        if affine || step[0].abs().max(step[1].abs()) < 1e-12 {
            break;
        }
    }
    xi
}

/// The closest point of facet `f` to `x`, if it lies on the facet — within [`INSIDE`], or within
/// the cone of [`RIM_CONE`] of the distance to it, then clamped onto it: the facet's shape values
/// there, the point and the outward unit normal.
fn project<const D: usize>(points: &[[f64; D]], f: &Facet, x: &[f64; D]) -> Option<FacetAt<D>> {
    let xi = closest(points, f, x);
    // a curved facet's extension can fold far from it, where Gauss–Newton has no foot to find
    if !xi.iter().all(|v| v.is_finite()) {
        return None;
    }
    // how far outside the reference domain, in reference units
    let outside = match f.corners().len() {
        2 => (-xi[0]).max(xi[0] - 1.0),
        3 => (-xi[0]).max(-xi[1]).max(xi[0] + xi[1] - 1.0),
        _ => ((xi[0].abs() - 1.0).max(xi[1].abs() - 1.0)) / 2.0,
    };
    if outside > INSIDE {
        let away = distance(x, &facet_at(points, f, xi).point);
        let nodes = f.corners();
        let size = (0..nodes.len())
            .flat_map(|i| (0..i).map(move |j| (i, j)))
            .map(|(i, j)| distance(&points[nodes[i]], &points[nodes[j]]))
            .fold(0.0, f64::max);
        if outside * size > INSIDE * size + RIM_CONE * away {
            return None;
        }
    }
    // onto the facet: a point just beyond its edge is the edge's
    let xi = match f.corners().len() {
        2 => [xi[0].clamp(0.0, 1.0), 0.0],
        3 => {
            let (a, b) = (xi[0].max(0.0), xi[1].max(0.0));
            let over = (a + b - 1.0).max(0.0) / 2.0;
            [a - over, b - over]
        }
        _ => [xi[0].clamp(-1.0, 1.0), xi[1].clamp(-1.0, 1.0)],
    };
    Some(facet_at(points, f, xi))
}

impl<const D: usize> SurfacePair<D> {
    /// Projects every node of `slave` onto `master` (both parts of the mesh with `points`): of the
    /// facets the node projects onto, the nearest.
    pub fn new(points: &[[f64; D]], slave: BoundaryPart<D>, master: BoundaryPart<D>) -> Result<Self, PairingError> {
        // each master facet's bounding box, for a cheap distance bound
        let boxes: Vec<([f64; D], [f64; D])> = master
            .facets
            .iter()
            .map(|f| {
                let mut lo = [f64::INFINITY; D];
                let mut hi = [f64::NEG_INFINITY; D];
                for &p in f.nodes() {
                    for k in 0..D {
                        lo[k] = lo[k].min(points[p][k]);
                        hi[k] = hi[k].max(points[p][k]);
                    }
                }
                (lo, hi)
            })
            .collect();
        let grid = FacetGrid::new(boxes);
        let projections: Vec<Option<Projection<D>>> = slave
            .nodes
            .iter()
            .map(|&s| {
                let x = points[s];
                let mut best: Option<(f64, Projection<D>)> = None;
                grid.visit(&x, |batch, bound| {
                    for &(d2, i) in batch {
                        // the batch is sorted: the rest of it is no nearer
                        if best.as_ref().is_some_and(|(b, _)| d2 > b * b * (1.0 + 1e-12)) {
                            break;
                        }
                        let f = &master.facets[i];
                        if let Some(at) = project(points, f, &x) {
                            let (point, normal) = (at.point, at.normal());
                            let distance = distance(&x, &point);
                            if best.as_ref().is_none_or(|(b, _)| distance < *b) {
                                let gap = (0..D).map(|k| (x[k] - point[k]) * normal[k]).sum();
                                let shape = f.nodes().iter().copied().zip(at.shape).collect();
                                best = Some((
                                    distance,
                                    Projection {
                                        facet: i,
                                        shape,
                                        point,
                                        normal,
                                        gap,
                                    },
                                ));
                            }
                        }
                    }
                    // every facet still to come lies at least `bound` away
                    !best.as_ref().is_some_and(|(b, _)| *b < bound)
                });
                best.map(|(_, p)| p)
            })
            .collect();
        let pair = SurfacePair {
            slave,
            master,
            projections,
        };
        let summary = pair.summary();
        if summary.paired == 0 {
            return Err(PairingError::NoOverlap);
        }
        if 2 * summary.facing_away > summary.paired {
            return Err(PairingError::SameWay {
                facing_away: summary.facing_away,
                paired: summary.paired,
            });
        }
        Ok(pair)
    }

    /// The pair's numbers for `hvi check`.
    pub fn summary(&self) -> PairSummary {
        let mut s = PairSummary {
            paired: 0,
            unpaired: 0,
            largest_gap: 0.0,
            deepest_penetration: 0.0,
            facing_away: 0,
            slave_size: 0.0,
            master_size: 0.0,
        };
        let mut onto = Vec::new();
        for (k, p) in self.projections.iter().enumerate() {
            match p {
                Some(p) => {
                    s.paired += 1;
                    s.largest_gap = s.largest_gap.max(p.gap);
                    s.deepest_penetration = s.deepest_penetration.max(-p.gap);
                    if dot(&self.slave.normals[k], &p.normal) > 0.0 {
                        s.facing_away += 1;
                    }
                    onto.push(p.facet);
                }
                None => s.unpaired += 1,
            }
        }
        onto.sort_unstable();
        onto.dedup();
        let size = |measure: f64| if D == 2 { measure } else { measure.sqrt() };
        let paired: Vec<usize> = (0..self.slave.facets.len())
            .filter(|&f| {
                self.slave.facets[f]
                    .nodes()
                    .iter()
                    .any(|&q| self.slave.local(q).is_some_and(|k| self.projections[k].is_some()))
            })
            .collect();
        let mean = |facets: &[usize], lengths: &[f64]| {
            facets.iter().map(|&f| size(lengths[f])).sum::<f64>() / facets.len().max(1) as f64
        };
        s.slave_size = mean(&paired, &self.slave.facet_lengths);
        s.master_size = mean(&onto, &self.master.facet_lengths);
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured::{rectangle, CellShape};
    use crate::mesh::{GroupSelector, Mesh};

    /// Two bodies in one mesh: the rectangle (0, 2) × (0, 1) and a copy of it with `nx_top` cells
    /// across shifted by (`shift`, 1 + `gap`), so that the lower body's top (Gamma2_top) is the
    /// master and the upper body's bottom (Gamma3) the slave.
    fn two_blocks(nx_top: usize, gap: f64, shift: f64) -> (Mesh<2>, BoundaryPart<2>, BoundaryPart<2>) {
        let lower = rectangle(2.0, 1.0, 4, 2, CellShape::Quad);
        let upper = rectangle(2.0, 1.0, nx_top, 2, CellShape::Tri);
        let master = lower.boundary(&GroupSelector::Name("Gamma2_top".into())).unwrap();
        let mut slave = upper.boundary(&GroupSelector::Name("Gamma3".into())).unwrap();
        let offset = lower.points.len();
        let mut points = lower.points.clone();
        points.extend(upper.points.iter().map(|x| [x[0] + shift, x[1] + 1.0 + gap]));
        slave.nodes.iter_mut().for_each(|p| *p += offset);
        for f in slave.facets.iter_mut() {
            let nodes: Vec<usize> = f.nodes().iter().map(|p| p + offset).collect();
            *f = Facet::from_slice(&nodes);
        }
        let mesh = Mesh { points, ..lower };
        (mesh, slave, master)
    }

    /// Non-matching flat surfaces a gap apart: every slave node pairs, with the gap, the master's
    /// upward normal, and shape values that interpolate its x on the master's edge.
    #[test]
    fn flat_surfaces_pair_with_their_gap_and_the_interpolating_weights() {
        let (mesh, slave, master) = two_blocks(7, 0.01, 0.0);
        let pair = SurfacePair::new(&mesh.points, slave, master).unwrap();
        let s = pair.summary();
        assert_eq!((s.paired, s.unpaired, s.facing_away), (8, 0, 0));
        for (k, p) in pair.projections.iter().enumerate() {
            let p = p.as_ref().unwrap();
            let x = mesh.points[pair.slave.nodes[k]];
            assert!((p.gap - 0.01).abs() < 1e-14, "gap {}", p.gap);
            assert!((p.normal[1] - 1.0).abs() < 1e-14 && p.normal[0].abs() < 1e-14);
            let xm: f64 = p.shape.iter().map(|&(n, v)| v * mesh.points[n][0]).sum();
            assert!((xm - x[0]).abs() < 1e-14, "interpolates x: {xm} against {}", x[0]);
            assert!((p.shape.iter().map(|s| s.1).sum::<f64>() - 1.0).abs() < 1e-14);
        }
        // an overlap is a negative gap, the penetration
        let (mesh, slave, master) = two_blocks(7, -0.003, 0.0);
        let s = SurfacePair::new(&mesh.points, slave, master).unwrap().summary();
        assert!((s.deepest_penetration - 0.003).abs() < 1e-14, "{s:?}");
        // shifted half a body along x: the nodes beyond the master's end are unpaired
        let (mesh, slave, master) = two_blocks(8, 0.0, 1.0);
        let s = SurfacePair::new(&mesh.points, slave, master).unwrap().summary();
        assert_eq!((s.paired, s.unpaired), (5, 4), "{s:?}");
    }

    /// A surface paired with itself faces the same way; surfaces that do not overlap are refused.
    #[test]
    fn surfaces_facing_the_same_way_or_apart_are_refused() {
        let (mesh, _, master) = two_blocks(3, 0.0, 0.0);
        assert!(matches!(
            SurfacePair::new(&mesh.points, master.clone(), master.clone()),
            Err(PairingError::SameWay { .. })
        ));
        let (mesh, slave, master) = two_blocks(3, 0.0, 10.0);
        assert_eq!(
            SurfacePair::new(&mesh.points, slave, master).unwrap_err(),
            PairingError::NoOverlap
        );
    }

    /// A curved master: the slave node above a circle's arc (a polygon of 64 edges, radius 1)
    /// projects onto the chord under it, its gap the distance to the chord along the chord's normal.
    #[test]
    fn a_node_projects_onto_the_nearest_of_several_facets() {
        let n = 64;
        let mut points: Vec<[f64; 2]> = (0..=n)
            .map(|i| {
                let a = std::f64::consts::PI * i as f64 / n as f64;
                [a.cos(), a.sin()]
            })
            .collect();
        points.push([0.3 * 1.5, 0.4 * 1.5]);
        // the arc's edges counter-clockwise, the disc on their left: (dy, −dx) points out of it
        let facets: Vec<Facet> = (0..n).map(|i| Facet::from_slice(&[i, i + 1])).collect();
        let master = BoundaryPart {
            label: "arc".into(),
            facet_lengths: vec![0.0; n],
            nodes: (0..=n).collect(),
            weights: vec![0.0; n + 1],
            normals: vec![[0.0, 0.0]; n + 1],
            facets,
            revolved: false,
        };
        let slave = BoundaryPart {
            label: "point".into(),
            facets: Vec::new(),
            facet_lengths: Vec::new(),
            nodes: vec![n + 1],
            weights: vec![1.0],
            normals: vec![[-0.6, -0.8]],
            revolved: false,
        };
        let pair = SurfacePair::new(&points, slave, master).unwrap();
        let p = pair.projections[0].as_ref().unwrap();
        // the node at radius 0.75, angle atan2(0.6, 0.45)
        let (r, angle) = (0.75f64, 0.6f64.atan2(0.45));
        let edge = (angle / (std::f64::consts::PI / n as f64)).floor() as usize;
        assert_eq!(p.facet, edge, "the edge under the node");
        let half = std::f64::consts::PI / n as f64 / 2.0;
        let chord = half.cos();
        // the node is inside the disc (r < 1): a negative gap, the chord's distance minus r's
        // component along the chord's normal
        let mid = (edge as f64 + 0.5) * 2.0 * half;
        let along = r * (angle - mid).cos();
        assert!(
            (p.gap - (along - chord)).abs() < 1e-13,
            "gap {} against {}",
            p.gap,
            along - chord
        );
    }

    /// In 3D: the top of a hexahedral block (warped: its top nodes moved up and down by 1e-3,
    /// so its quadrilaterals are not flat) against the bottom of a tetrahedral block above it with
    /// another grid: every slave node pairs (those above the rim clamped onto it), the point is
    /// the orthogonal foot (to 1e-9 inside), near the node's x and z, and the gap its height above
    /// the warped face along the face's normal.
    #[test]
    fn three_dimensional_faces_pair_on_warped_quadrilaterals_and_triangles() {
        use crate::mesh::structured::{block, SolidShape};
        let lower = block([2.0, 1.0, 1.0], [4, 2, 3], SolidShape::Hex);
        let upper = block([2.0, 1.0, 1.0], [3, 2, 5], SolidShape::Tet);
        let master = lower.boundary(&GroupSelector::Name("Gamma2_top".into())).unwrap();
        let mut slave = upper.boundary(&GroupSelector::Name("Gamma3".into())).unwrap();
        let offset = lower.points.len();
        let mut points = lower.points.clone();
        for (i, x) in points.iter_mut().enumerate() {
            if (x[1] - 1.0).abs() < 1e-12 {
                x[1] += if i % 2 == 0 { 1e-3 } else { -1e-3 };
            }
        }
        points.extend(upper.points.iter().map(|x| [x[0], x[1] + 1.01, x[2]]));
        slave.nodes.iter_mut().for_each(|p| *p += offset);
        let pair = SurfacePair::new(&points, slave, master).unwrap();
        let s = pair.summary();
        assert_eq!((s.paired, s.unpaired, s.facing_away), (24, 0, 0), "{s:?}");
        for (k, p) in pair.projections.iter().enumerate() {
            let p = p.as_ref().unwrap();
            let x = points[pair.slave.nodes[k]];
            for axis in [0, 2] {
                let xm: f64 = p.shape.iter().map(|&(n, v)| v * points[n][axis]).sum();
                // the foot on a tilted face lies off the vertical by the slope (4e-3) × the gap
                assert!((xm - x[axis]).abs() < 1e-4, "axis {axis}: {xm} against {}", x[axis]);
            }
            let along: f64 = (0..3).map(|k| (x[k] - p.point[k]) * p.normal[k]).sum();
            let across: f64 = (0..3)
                .map(|k| (x[k] - p.point[k] - along * p.normal[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            // inside, the orthogonal foot; on the rim, clamped onto the edge (warp slope × gap)
            let rim = x[0] < 1e-12 || x[0] > 2.0 - 1e-12 || x[2] < 1e-12 || x[2] > 1.0 - 1e-12;
            let tolerance = if rim { 1e-4 } else { 1e-9 };
            assert!(
                across < tolerance,
                "the closest point: x − x_M along the normal, off by {across:e}"
            );
            assert!(
                (p.gap - along).abs() < 1e-15 && (p.gap - 0.01).abs() < 1.5e-3,
                "gap {}",
                p.gap
            );
        }
    }
}
