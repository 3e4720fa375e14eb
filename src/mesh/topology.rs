//! Boundary parts: a group of facets (curves in 2D, surfaces in 3D: Γ₁, Γ₂, Γ₃) as oriented
//! facets with outward normals and nodal quadrature weights (docs/method.md §2, §8).

use super::element::{reference, MAX_NODES};
use super::quadrature::{QuadPoint, EDGE_GAUSS_3, TRI_3POINT};
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

/// The transformation of a 6-node triangle's and an 8-node quadrangle's basis before its dual is
/// taken (Popp, Wohlmuth, Gee & Wall 2012; docs/method.md §19.3): each corner's function gains α
/// of its two edges' ones, each edge's keeps 1 − 2α. Their own functions' lumped weights are zero
/// or negative at the corners (no dual basis); with α = 1/5 they become 2/15 and 1/5 of a
/// triangle, 1/20 and 1/5 of a quadrangle. Measured (Hertz 3D, a and p₀ against the closed form,
/// tests/hertz.rs): 10-node tetrahedra a/7 and a/10 with α = 0.1: −0.10 %, +0.03 % and −0.03 %,
/// +0.08 %; 0.2: +0.02 %, +0.03 % and +0.00 %, +0.09 %; 0.3: +0.31 %, −0.05 % and +0.25 %,
/// −0.03 %. 20-node hexahedra a/3.8, a/5.1, a/6.3: with 0.1 the corners' weights stay negative
/// (no rows there: p₀ −6.3 to −6.4 %); 0.2: a +1.95, +0.60, +0.31 %, p₀ −1.04, −0.30, −0.19 %;
/// 0.3: a +1.79, +1.05, +0.20 %, p₀ −2.27, −1.21, −0.57 %.
pub const TRANSFORMED_ALPHA: f64 = 0.2;

/// The contact rows' multiplier functions ψ_j of a second-order facet at its reference point `xi`
/// (docs/method.md §19.3). On a 3-node edge, the split functions of [`edge_row_functions`]. On a
/// face, the dual basis of the face's own functions N, transformed first where their lumped
/// weights are not positive — ψ = A T N(ξ), with N' = T N ([`TRANSFORMED_ALPHA`] on 6-node
/// triangles and 8-node quadrangles, T = I on 9-node quadrangles) and
/// A = D' M'⁻¹ (M' the reference facet's mass matrix of N', D' its row sums), so that
/// ∫ψ_j N'_k = δ_jk ∫N'_j on an affine facet. Σ_j ψ_j = 1 and the weights ∫ψ_j = ∫N'_j are
/// positive; ψ_j itself changes sign.
pub(crate) fn row_functions(f: &Facet, xi: [f64; 2]) -> [f64; 9] {
    use std::sync::OnceLock;
    if f.dim() == 1 {
        return edge_row_functions(xi[0]);
    }
    // B = A T per face kind: 6-node triangle, 8- and 9-node quadrangle
    static B: [OnceLock<[[f64; 9]; 9]>; 3] = [const { OnceLock::new() }; 3];
    let n = f.len();
    let kind = match n {
        6 => 0,
        8 => 1,
        _ => 2,
    };
    let b = B[kind].get_or_init(|| {
        let mut t = nalgebra::DMatrix::<f64>::identity(n, n);
        if n != 9 {
            // each midside node e between corners c: N'_c += α N_e, N'_e = (1 − 2α) N_e
            let face = face_reference(f).kind();
            for e in f.corners().len()..n {
                t[(e, e)] = 1.0 - 2.0 * TRANSFORMED_ALPHA;
                for &c in crate::mesh::second_order::corner_support(face, e) {
                    t[(c, e)] = TRANSFORMED_ALPHA;
                }
            }
        }
        let mut mass = nalgebra::DMatrix::<f64>::zeros(n, n);
        for q in facet_rule(f) {
            let v = facet_shape(f, q.xi).1;
            let v = &t * nalgebra::DVector::from_fn(n, |i, _| v[i]);
            mass += &v * v.transpose() * q.weight;
        }
        let b = dual_of(mass) * t;
        std::array::from_fn(|j| std::array::from_fn(|k| if j < n && k < n { b[(j, k)] } else { 0.0 }))
    });
    let v = facet_shape(f, [xi[0], xi[1], 0.0]).1;
    std::array::from_fn(|j| (0..n).map(|k| b[j][k] * v[k]).sum())
}

/// The coefficients A = D M⁻¹ of the dual basis ψ_j = Σ_k A_jk φ_k of functions φ with the mass
/// matrix M (D its row sums, the lumped weights, which must be positive): ∫ψ_j φ_k = δ_jk D_j
/// (Wohlmuth 2000; docs/method.md §18.2, §19.3).
pub(crate) fn dual_of(mass: nalgebra::DMatrix<f64>) -> nalgebra::DMatrix<f64> {
    let n = mass.nrows();
    let lumped = nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_fn(n, |i, _| mass.row(i).sum()));
    lumped
        * mass
            .try_inverse()
            .expect("independent functions on a facet of positive measure: an invertible mass matrix")
}

/// The contact rows' functions of a 3-node edge at s ∈ [0, 1] (ends, then midpoint): the
/// first-order functions of the edge split at its midpoint — positive, so that on a body of
/// revolution the node on the axis keeps a positive weight ∫ψ 2πr ds, which no dual basis of the
/// edge's own functions has there (∫N 2πr ds is 0 at that node). docs/method.md §19.3.
fn edge_row_functions(s: f64) -> [f64; 9] {
    let mut psi = [0.0; 9];
    (psi[0], psi[1], psi[2]) = (
        (1.0 - 2.0 * s).max(0.0),
        (2.0 * s - 1.0).max(0.0),
        1.0 - (2.0 * s - 1.0).abs(),
    );
    psi
}

/// The contact rows' multiplier functions on a second-order facet ([`row_functions`]) at the
/// points of a rule exact for ψ_j N_i on a flat facet (on an edge, its halves' rules: ψ is first
/// order on each): (point in the facet's reference coordinates, weight, ψ at it).
pub(crate) fn row_rule(f: &Facet) -> Vec<([f64; 3], f64, [f64; 9])> {
    if f.dim() == 1 {
        return [0.0, 0.5]
            .iter()
            .flat_map(|&half| {
                facet_rule(f).iter().map(move |q| {
                    let s = half + 0.5 * q.xi[0];
                    ([s, 0.0, 0.0], 0.5 * q.weight, edge_row_functions(s))
                })
            })
            .collect();
    }
    facet_rule(f)
        .iter()
        .map(|q| (q.xi, q.weight, row_functions(f, [q.xi[0], q.xi[1]])))
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
