//! Boundary parts: a group of facets (curves in 2D, surfaces in 3D: Γ₁, Γ₂, Γ₃) as oriented
//! facets with outward normals and nodal quadrature weights (docs/method.md §2, §8).

use super::element::{reference, MAX_NODES};
use super::quadrature::{tensor_gauss, QuadPoint, EDGE_GAUSS_3, TRI_3POINT};
use super::vector::{cross, norm};
use super::{fmt_point, Facet, GroupSelector, Mesh, MeshError, PhysicalGroup};
use super::{Cell, CellKind};
use crate::mesh::quadrature::QUAD_GAUSS_2X2;
use rustc_hash::FxHashMap as HashMap;

/// A group of facets as a part of the boundary of the body.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryPart<const D: usize> {
    /// How messages name it, e.g. `Gamma3 (tag 3)`.
    pub label: String,
    /// The group's facets (duplicates removed), each oriented like the facet of its cell, so
    /// that its outward normal follows from the node order ((dy, −dx) for an edge, the
    /// right-hand rule for a face).
    pub facets: Vec<Facet>,
    /// Measure of each facet: length in 2D, area in 3D.
    pub facet_lengths: Vec<f64>,
    /// Sorted unique node indices on the part.
    pub nodes: Vec<usize>,
    /// Per node of `nodes`: the lumped facet mass ∫ N_p ds over the part (half of each adjacent
    /// edge in 2D, a third of each adjacent triangle, ∫ N_p over each adjacent quadrilateral;
    /// they sum to the measure of the part).
    pub weights: Vec<f64>,
    /// Per node of `nodes`: the normalised sum over the adjacent facets of ∫ N_p ν ds — the
    /// facet-measure-weighted mean of the outward unit normals. On a smooth boundary meshed
    /// with smoothly varying facets this is the boundary's normal to O(h²); at an edge or a
    /// corner of the part it bisects.
    pub normals: Vec<[f64; D]>,
    /// True once [`BoundaryPart::revolve`] made the weights those of the swept surface.
    pub revolved: bool,
}

impl<const D: usize> BoundaryPart<D> {
    /// The part of a 2D mesh as the surface it sweeps about the y axis (x = r ≥ 0): each node's
    /// weight becomes ∫ N_p 2πr ds — on an edge of length L from r_a to r_b, 2πL (2r_a + r_b)/6
    /// to its first node (exact for the linear N and r). Only for D = 2 (edges).
    pub fn revolve(&mut self, points: &[[f64; D]]) {
        assert_eq!(D, 2, "a body of revolution is a 2D mesh");
        let two_pi = 2.0 * std::f64::consts::PI;
        self.revolved = true;
        self.weights.iter_mut().for_each(|w| *w = 0.0);
        for (f, &length) in self.facets.iter().zip(&self.facet_lengths) {
            if f.is_second_order() {
                // ∫ N_a 2πr ds by the edge's rule
                for q in facet_rule(f) {
                    let (value, dn, x) = facet_map(points, f, q.xi);
                    let da = two_pi * x[0] * norm(&dn) * q.weight;
                    for (a, &p) in f.nodes().iter().enumerate() {
                        let k = self.nodes.binary_search(&p).expect("a facet's node is on its part");
                        self.weights[k] += value[a] * da;
                    }
                }
                continue;
            }
            let [a, b] = [f.nodes()[0], f.nodes()[1]];
            let (ra, rb) = (points[a][0], points[b][0]);
            for (p, (r1, r2)) in [(a, (ra, rb)), (b, (rb, ra))] {
                let k = self.nodes.binary_search(&p).expect("a facet's node is on its part");
                self.weights[k] += two_pi * length * (2.0 * r1 + r2) / 6.0;
            }
        }
    }

    /// Position of node index `p` in [`BoundaryPart::nodes`], if it is on the part.
    pub fn local(&self, p: usize) -> Option<usize> {
        self.nodes.binary_search(&p).ok()
    }

    /// The total measure (length or area) of the part.
    pub fn length(&self) -> f64 {
        self.facet_lengths.iter().sum()
    }
}

fn sub<const D: usize>(a: &[f64; D], b: &[f64; D]) -> [f64; 3] {
    let mut v = [0.0; 3];
    for k in 0..D {
        v[k] = a[k] - b[k];
    }
    v
}

impl<const D: usize> Mesh<D> {
    /// A group of facets (dimension D − 1) as an oriented boundary part (see [`BoundaryPart`]).
    /// Every facet of the group must be a facet of exactly one cell.
    pub fn boundary(&self, sel: &GroupSelector) -> Result<BoundaryPart<D>, MeshError> {
        let group = self.group(sel, (D - 1) as u8)?;
        boundary_part(self, group)
    }
}

/// An edge's outward normal times its length, (dy, −dx, 0), for an edge a → b oriented with the
/// body on its left; and the length.
pub fn edge_area_vector<const D: usize>(a: &[f64; D], b: &[f64; D]) -> ([f64; 3], f64) {
    let d = sub(b, a);
    ([d[1], -d[0], 0.0], norm(&d))
}

/// The reference cell of a face: a triangle or a quadrangle of the face's nodes' count.
fn face_reference(face: &Facet) -> Cell {
    let kind = match (face.corners().len(), face.len()) {
        (3, 3) => CellKind::Tri3,
        (3, _) => CellKind::Tri6,
        (4, 4) => CellKind::Quad4,
        (4, 8) => CellKind::Quad8,
        _ => CellKind::Quad9,
    };
    Cell::new(kind, &[0, 1, 2, 3, 4, 5, 6, 7, 8][..face.len()])
}

/// A quadrature rule on a facet's reference: on an edge, s ∈ [0, 1] with weights summing to 1
/// (3-point Gauss: quintics); on a face, its reference cell's (the 3-point rule or 2 × 2 Gauss
/// on first-order faces, the 6-point rule or 3 × 3 Gauss on second-order ones, docs/method.md §19.2).
pub fn facet_rule(f: &Facet) -> &'static [QuadPoint] {
    const EDGE: [QuadPoint; 3] = [
        QuadPoint {
            xi: [EDGE_GAUSS_3[0].0, 0.0, 0.0],
            weight: EDGE_GAUSS_3[0].1,
        },
        QuadPoint {
            xi: [EDGE_GAUSS_3[1].0, 0.0, 0.0],
            weight: EDGE_GAUSS_3[1].1,
        },
        QuadPoint {
            xi: [EDGE_GAUSS_3[2].0, 0.0, 0.0],
            weight: EDGE_GAUSS_3[2].1,
        },
    ];
    match (f.dim(), f.len()) {
        (1, _) => &EDGE,
        (_, 3) => &TRI_3POINT,
        (_, 4) => &QUAD_GAUSS_2X2,
        _ => crate::mesh::element::stiffness_rule(&face_reference(f)),
    }
}

/// A facet's shape functions at the reference point `xi` (an edge: s ∈ [0, 1] from its first
/// corner; a face: its reference cell's ξ, η): their number, values and reference gradients.
pub(crate) fn facet_shape(f: &Facet, xi: [f64; 3]) -> (usize, [f64; MAX_NODES], [[f64; 3]; MAX_NODES]) {
    if f.dim() > 1 {
        return reference(&face_reference(f), xi);
    }
    let s = xi[0];
    let (mut v, mut g) = ([0.0; MAX_NODES], [[0.0; 3]; MAX_NODES]);
    if f.len() == 2 {
        v[..2].copy_from_slice(&[1.0 - s, s]);
        (g[0][0], g[1][0]) = (-1.0, 1.0);
    } else {
        // the 3-node line: its ends, then its midpoint
        v[..3].copy_from_slice(&[(1.0 - s) * (1.0 - 2.0 * s), s * (2.0 * s - 1.0), 4.0 * s * (1.0 - s)]);
        (g[0][0], g[1][0], g[2][0]) = (4.0 * s - 3.0, 4.0 * s - 1.0, 4.0 - 8.0 * s);
    }
    (f.len(), v, g)
}

/// A facet's map at the reference point `xi` (an edge: s = ξ ∈ [0, 1] from its first corner to
/// its second; a face: its reference cell's ξ, η): the shape values, the area vector (the
/// outward normal times ds/ds_ref: (dy, −dx)/ds on an edge, ∂x/∂ξ × ∂x/∂η on a face) and the
/// point, as x₀ + Σ_a N_a (x_a − x₀) (a point of a facet in a plane x_k = c gets exactly c).
pub fn facet_map<const D: usize>(
    points: &[[f64; D]],
    f: &Facet,
    xi: [f64; 3],
) -> ([f64; MAX_NODES], [f64; 3], [f64; D]) {
    let (n, value, grad) = facet_shape(f, xi);
    let nodes = f.nodes();
    let x0 = points[nodes[0]];
    let (mut t1, mut t2, mut x) = ([0.0; 3], [0.0; 3], x0);
    for a in 0..n {
        let p = points[nodes[a]];
        for k in 0..D {
            t1[k] += grad[a][0] * p[k];
            t2[k] += grad[a][1] * p[k];
            if a > 0 {
                x[k] += value[a] * (p[k] - x0[k]);
            }
        }
    }
    let area = if f.dim() == 1 {
        [t1[1], -t1[0], 0.0]
    } else {
        cross(t1, t2)
    };
    (value, area, x)
}

/// The first-order functions of a facet's corners at its reference point `xi` (an edge's
/// (1 − s, s), a triangle's barycentric coordinates, a quadrangle's bilinear functions): the
/// vertex basis of contact on second-order faces (docs/method.md §19.3).
pub(crate) fn corner_basis(f: &Facet, xi: [f64; 3]) -> [f64; 4] {
    let mut out = [0.0; 4];
    match f.corners().len() {
        2 => out[..2].copy_from_slice(&[1.0 - xi[0], xi[0]]),
        3 => out[..3].copy_from_slice(&reference(&Cell::Tri3([0, 1, 2]), xi).1[..3]),
        _ => out.copy_from_slice(&reference(&Cell::Quad4([0, 1, 2, 3]), xi).1[..4]),
    }
    out
}

/// The pieces of a second-order facet on which its contact rows' multiplier functions are of
/// first order (docs/method.md §19.3), each as its corners (facet-local nodes, counter-clockwise
/// on a face): an edge's halves, a 9-node quadrangle's or a 6-node triangle's quarters split at
/// the midside and centre nodes, an 8-node quadrangle whole (its corners' bilinear functions).
fn piece_nodes(f: &Facet) -> &'static [&'static [usize]] {
    match (f.dim(), f.len()) {
        (1, _) => &[&[0, 2], &[2, 1]],
        (_, 8) => &[&[0, 1, 2, 3]],
        (_, 9) => &[&[0, 4, 8, 7], &[4, 1, 5, 8], &[8, 5, 2, 6], &[7, 8, 6, 3]],
        _ => &[&[0, 3, 5], &[3, 1, 4], &[5, 4, 2], &[4, 5, 3]],
    }
}

/// The reference coordinates of node `a` of a second-order facet (an edge: s ∈ [0, 1]).
fn reference_point(f: &Facet, a: usize) -> [f64; 2] {
    if f.dim() == 1 {
        return [[0.0, 1.0, 0.5][a], 0.0];
    }
    let x = crate::mesh::second_order::reference_nodes(face_reference(f).kind())[a];
    [x[0], x[1]]
}

/// The pieces of [`piece_nodes`] as polygons in the facet's reference coordinates: an interval
/// (two points) on an edge, a counter-clockwise triangle or axis-aligned quadrangle on a face.
pub(crate) fn row_pieces(f: &Facet) -> Vec<Vec<[f64; 2]>> {
    piece_nodes(f)
        .iter()
        .map(|piece| piece.iter().map(|&a| reference_point(f, a)).collect())
        .collect()
}

/// The first-order functions of a piece's corners at `xi` and how far inside the piece `xi` lies
/// (the least of them; negative outside): an interval's (1 − t, t), a triangle's barycentric
/// coordinates, an axis-aligned quadrangle's bilinear functions (corners from its lower left).
fn piece_functions(piece: &[[f64; 2]], xi: [f64; 2]) -> ([f64; 4], f64) {
    let mut hats = [0.0; 4];
    match piece.len() {
        2 => {
            let t = (xi[0] - piece[0][0]) / (piece[1][0] - piece[0][0]);
            hats[..2].copy_from_slice(&[1.0 - t, t]);
        }
        3 => {
            let (p, e, g) = (piece[0], sub2(piece[1], piece[0]), sub2(piece[2], piece[0]));
            let r = sub2(xi, p);
            let det = e[0] * g[1] - e[1] * g[0];
            let (b1, b2) = ((r[0] * g[1] - r[1] * g[0]) / det, (e[0] * r[1] - e[1] * r[0]) / det);
            hats[..3].copy_from_slice(&[1.0 - b1 - b2, b1, b2]);
        }
        _ => {
            let (lo, hi) = (piece[0], piece[2]);
            let u = (xi[0] - lo[0]) / (hi[0] - lo[0]);
            let v = (xi[1] - lo[1]) / (hi[1] - lo[1]);
            hats = [(1.0 - u) * (1.0 - v), u * (1.0 - v), u * v, (1.0 - u) * v];
        }
    }
    let inside = match piece.len() {
        2 => hats[0].min(hats[1]),
        3 => hats[0].min(hats[1]).min(hats[2]),
        // the bilinear functions' least is not the distance inside: the coordinates' is
        _ => {
            let (lo, hi) = (piece[0], piece[2]);
            let u = (xi[0] - lo[0]) / (hi[0] - lo[0]);
            let v = (xi[1] - lo[1]) / (hi[1] - lo[1]);
            u.min(1.0 - u).min(v).min(1.0 - v)
        }
    };
    (hats, inside)
}

fn sub2(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// The contact rows' multiplier functions ψ_j of a second-order facet at its reference point
/// `xi` (docs/method.md §19.3): the first-order function of node j on the piece of
/// [`row_pieces`] that holds `xi` (beyond the facet, the nearest piece's, extended) —
/// P1-iso-P2, positive on the facet, Σ_j ψ_j = 1; on an 8-node quadrangle its corners' bilinear
/// functions (its midside nodes carry no row).
pub(crate) fn row_functions(f: &Facet, xi: [f64; 2]) -> [f64; 9] {
    let pieces = row_pieces(f);
    let (k, (hats, _)) = pieces
        .iter()
        .map(|piece| piece_functions(piece, xi))
        .enumerate()
        .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .expect("a facet has pieces");
    let mut psi = [0.0; 9];
    for (&a, h) in piece_nodes(f)[k].iter().zip(hats) {
        psi[a] += h;
    }
    psi
}

/// A rule on a piece (an interval, a triangle or an axis-aligned quadrangle of reference
/// coordinates): 3-point Gauss, the 6-point rule, 3 × 3 Gauss mapped onto it, weights scaled by
/// its measure — exact for quintics on an interval or a triangle and bicubics on a quadrangle.
pub(crate) fn piece_rule(piece: &[[f64; 2]]) -> Vec<([f64; 2], f64)> {
    match piece.len() {
        2 => {
            let (a, b) = (piece[0][0], piece[1][0]);
            EDGE_GAUSS_3
                .iter()
                .map(|&(t, w)| ([a + t * (b - a), 0.0], w * (b - a).abs()))
                .collect()
        }
        3 => {
            let (p, e, g) = (piece[0], sub2(piece[1], piece[0]), sub2(piece[2], piece[0]));
            let det = (e[0] * g[1] - e[1] * g[0]).abs();
            crate::mesh::quadrature::TRI6
                .iter()
                .map(|&(q, w)| {
                    (
                        [p[0] + q[0] * e[0] + q[1] * g[0], p[1] + q[0] * e[1] + q[1] * g[1]],
                        w * det,
                    )
                })
                .collect()
        }
        _ => {
            let (lo, hi) = (piece[0], piece[2]);
            let scale = [(hi[0] - lo[0]) / 2.0, (hi[1] - lo[1]) / 2.0];
            tensor_gauss(3, 2)
                .into_iter()
                .map(|q| {
                    (
                        [lo[0] + (q.xi[0] + 1.0) * scale[0], lo[1] + (q.xi[1] + 1.0) * scale[1]],
                        q.weight * (scale[0] * scale[1]).abs(),
                    )
                })
                .collect()
        }
    }
}

/// The contact rows' multiplier functions on a second-order facet (docs/method.md §19.3,
/// [`row_functions`]) with the rule that integrates them piece by piece ([`piece_rule`]) — exact
/// for ψ_j N_i on a flat facet. Returns (point in the facet's reference coordinates, weight, ψ
/// at it).
pub(crate) fn row_rule(f: &Facet) -> Vec<([f64; 3], f64, [f64; 9])> {
    row_pieces(f)
        .iter()
        .flat_map(|piece| piece_rule(piece))
        .map(|(xi, w)| ([xi[0], xi[1], 0.0], w, row_functions(f, xi)))
        .collect()
}

/// Quadrature of one facet: for each node, ∫ N_a ds and ∫ N_a n ds (n the outward unit normal,
/// so the second is an area vector), and the facet's measure. On a second-order facet the first
/// are the integrals of its own shape functions over the curved facet (a 6-node triangle's
/// corners get 0, an 8-node quadrangle's corners a negative share: docs/method.md §19.3), the
/// second weigh n with non-negative functions — the corners' first-order ones, the other nodes'
/// own — so that every node's normal is a mean of its facets' normals.
pub(crate) fn facet_integrals<const D: usize>(points: &[[f64; D]], f: &Facet) -> (Vec<f64>, Vec<[f64; 3]>, f64) {
    let x = |i: usize| points[f.nodes()[i]];
    // a bilinear face (2 × 2 Gauss, its corner functions its own) or a second-order facet
    if f.is_second_order() || f.len() == 4 {
        let (n, m) = (f.len(), f.corners().len());
        let (mut w, mut nv, mut measure) = (vec![0.0; n], vec![[0.0; 3]; n], 0.0);
        for q in facet_rule(f) {
            let (value, dn, _) = facet_map(points, f, q.xi);
            let psi = corner_basis(f, q.xi);
            let da = norm(&dn) * q.weight;
            measure += da;
            for a in 0..n {
                w[a] += value[a] * da;
                let positive = if a < m { psi[a] } else { value[a] };
                for k in 0..3 {
                    nv[a][k] += positive * dn[k] * q.weight;
                }
            }
        }
        return (w, nv, measure);
    }
    match f.len() {
        2 => {
            let (d, len) = edge_area_vector(&x(0), &x(1));
            let n = [d[0] / 2.0, d[1] / 2.0, 0.0];
            (vec![len / 2.0; 2], vec![n; 2], len)
        }
        3 => {
            let a = cross(sub(&x(1), &x(0)), sub(&x(2), &x(0)));
            let area = 0.5 * norm(&a);
            let share = [a[0] / 6.0, a[1] / 6.0, a[2] / 6.0];
            (vec![area / 3.0; 3], vec![share; 3], area)
        }
        _ => unreachable!("a face of 4 nodes or more takes the rule above"),
    }
}

/// How many cells have each of `facets` (found by node set through `slot`, the position of each
/// facet's key), each facet turned as its (last) cell orients it: outward when it is a facet of
/// exactly one cell. What [`boundary_part`] and the check of prescribed groups
/// ([`Mesh::boundary_group_nodes`]) ask of the cells.
pub(super) fn orient_by_cells<const D: usize>(
    mesh: &Mesh<D>,
    facets: &mut [Facet],
    slot: &HashMap<[usize; 4], usize>,
) -> Vec<u32> {
    let mut count = vec![0u32; facets.len()];
    for cell in &mesh.cells {
        for e in cell.facets() {
            if let Some(&k) = slot.get(&e.key()) {
                count[k] += 1;
                facets[k] = e;
            }
        }
    }
    count
}

pub(crate) fn boundary_part<const D: usize>(
    mesh: &Mesh<D>,
    group: &PhysicalGroup,
) -> Result<BoundaryPart<D>, MeshError> {
    let label = group.label();
    let pts = &mesh.points;
    let not_boundary = |detail: String| MeshError::NotBoundary {
        path: mesh.path.clone(),
        group: label.clone(),
        detail,
    };

    // The group's facets, each once, in the group's order.
    let mut slot: HashMap<[usize; 4], usize> =
        HashMap::with_capacity_and_hasher(group.facets.len(), Default::default());
    let mut facets: Vec<Facet> = Vec::with_capacity(group.facets.len());
    for &f in &group.facets {
        if f.dim() != D - 1 {
            return Err(not_boundary(format!(
                "the group holds a {}-node element; a boundary part of a {D}D body is made of {}",
                f.len(),
                if D == 2 {
                    "2-node lines"
                } else {
                    "triangles and quadrangles"
                }
            )));
        }
        if f.nodes().iter().any(|&p| p >= pts.len()) {
            return Err(not_boundary(format!(
                "facet {f:?} refers to a node that does not exist"
            )));
        }
        slot.entry(f.key()).or_insert_with(|| {
            facets.push(f);
            facets.len() - 1
        });
    }
    if facets.is_empty() {
        return Err(not_boundary(format!(
            "the group has no {} elements; give it the boundary {} in the .geo and mesh again",
            if D == 2 { "line" } else { "surface" },
            if D == 2 {
                "curves (Physical Curve)"
            } else {
                "surfaces (Physical Surface)"
            }
        )));
    }

    // Orient each facet like the outward facet of its (single) cell.
    let as_given = facets.clone();
    let count = orient_by_cells(mesh, &mut facets, &slot);
    let show = |f: &Facet| {
        let corners: Vec<String> = f.nodes().iter().map(|&p| fmt_point(pts[p])).collect();
        format!("facet {}", corners.join("–"))
    };
    for (k, &c) in count.iter().enumerate() {
        match c {
            1 => {}
            0 => {
                return Err(not_boundary(format!(
                    "{} is not {} of any cell; the group must be made of {} of the mesh on its boundary",
                    show(&as_given[k]),
                    if D == 2 { "an edge" } else { "a face" },
                    if D == 2 { "edges" } else { "faces" }
                )))
            }
            _ => {
                return Err(not_boundary(format!(
                    "{} is shared by {} cells, so it is inside the body; a boundary part must be on the outer boundary \
                     (check the {} of this group in the .geo)",
                    show(&as_given[k]),
                    if c == 2 { "two".to_string() } else { c.to_string() },
                    if D == 2 { "Physical Curve" } else { "Physical Surface" }
                )))
            }
        }
    }

    let mut nodes: Vec<usize> = facets.iter().flat_map(|f| f.nodes().to_vec()).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let mut weights = vec![0.0; nodes.len()];
    let mut sums = vec![[0.0; 3]; nodes.len()];
    let mut facet_lengths = Vec::with_capacity(facets.len());
    for f in &facets {
        let (w, nv, measure) = facet_integrals(pts, f);
        facet_lengths.push(measure);
        for (a, &p) in f.nodes().iter().enumerate() {
            let i = nodes.binary_search(&p).unwrap_or(0);
            weights[i] += w[a];
            for k in 0..3 {
                sums[i][k] += nv[a][k];
            }
        }
    }
    let mut normals = Vec::with_capacity(nodes.len());
    for (i, s) in sums.iter().enumerate() {
        let len = norm(s);
        if len.is_nan() || len <= 1e-12 * weights[i].abs() || len == 0.0 {
            return Err(not_boundary(format!(
                "at node {} the outward normals of its facets cancel: the part folds back on itself",
                fmt_point(pts[nodes[i]])
            )));
        }
        normals.push(std::array::from_fn(|k| s[k] / len));
    }
    Ok(BoundaryPart {
        label,
        facets,
        facet_lengths,
        nodes,
        weights,
        normals,
        revolved: false,
    })
}
