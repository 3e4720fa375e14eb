//! The reference nodes of every cell kind as gmsh places them (`gmsh.model.mesh.
//! getElementProperties`), the tables derived from them — a facet's second-order nodes, VTK's
//! node order, the mirror that flips a cell — and the second-order shape functions
//! (docs/method.md §19.1). One table of coordinates per kind is the single source: a facet's
//! midside node is the cell node at the midpoint of its corners, VTK's nodes are named by the
//! corners they are the centroid of (VTK's documentation of each type), and a mirror is the
//! swap ξ ↔ η of the reference coordinates.

mod shapes;

pub(crate) use shapes::second_order as shape_functions;

use super::kind::CellKind;
use std::sync::OnceLock;

const TRI3: [[f64; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
const QUAD4: [[f64; 3]; 4] = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]];
const TET4: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
const HEX8: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];
const PRISM6: [[f64; 3]; 6] = [
    [0.0, 0.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
];
const PYR5: [[f64; 3]; 5] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
const TRI6: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.5, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.0],
];
const QUAD8: [[f64; 3]; 8] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [-1.0, 0.0, 0.0],
];
const QUAD9: [[f64; 3]; 9] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 0.0, 0.0],
];
const TET10: [[f64; 3]; 10] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.0],
    [0.0, 0.0, 0.5],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
];
const HEX20: [[f64; 3]; 20] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [0.0, -1.0, -1.0],
    [-1.0, 0.0, -1.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, -1.0],
    [1.0, -1.0, 0.0],
    [0.0, 1.0, -1.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
];
const HEX27: [[f64; 3]; 27] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [0.0, -1.0, -1.0],
    [-1.0, 0.0, -1.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, -1.0],
    [1.0, -1.0, 0.0],
    [0.0, 1.0, -1.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [0.0, 0.0, -1.0],
    [0.0, -1.0, 0.0],
    [-1.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, 0.0],
];
const PRISM15: [[f64; 3]; 15] = [
    [0.0, 0.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [0.5, 0.0, -1.0],
    [0.0, 0.5, -1.0],
    [0.0, 0.0, 0.0],
    [0.5, 0.5, -1.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.5, 0.0, 1.0],
    [0.0, 0.5, 1.0],
    [0.5, 0.5, 1.0],
];
const PRISM18: [[f64; 3]; 18] = [
    [0.0, 0.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [0.5, 0.0, -1.0],
    [0.0, 0.5, -1.0],
    [0.0, 0.0, 0.0],
    [0.5, 0.5, -1.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.5, 0.0, 1.0],
    [0.0, 0.5, 1.0],
    [0.5, 0.5, 1.0],
    [0.5, 0.0, 0.0],
    [0.0, 0.5, 0.0],
    [0.5, 0.5, 0.0],
];

/// The reference coordinates of `kind`'s nodes, in gmsh's order (2D kinds leave ζ = 0).
pub fn reference_nodes(kind: CellKind) -> &'static [[f64; 3]] {
    match kind {
        CellKind::Tri3 => &TRI3,
        CellKind::Quad4 => &QUAD4,
        CellKind::Tet4 => &TET4,
        CellKind::Hex8 => &HEX8,
        CellKind::Prism6 => &PRISM6,
        CellKind::Pyr5 => &PYR5,
        CellKind::Tri6 => &TRI6,
        CellKind::Quad8 => &QUAD8,
        CellKind::Quad9 => &QUAD9,
        CellKind::Tet10 => &TET10,
        CellKind::Hex20 => &HEX20,
        CellKind::Hex27 => &HEX27,
        CellKind::Prism15 => &PRISM15,
        CellKind::Prism18 => &PRISM18,
    }
}

/// VTK's nodes of each kind's type, each as the VTK corners it is the centroid of (a corner as
/// itself): the node lists of VTK's documentation for types 22, 23, 28, 24, 25, 29, 26 and 32,
/// checked against `vtkCell::GetParametricCoords` of VTK 9.
fn vtk_nodes(kind: CellKind) -> Vec<Vec<usize>> {
    let corners = (0..kind.corners()).map(|c| vec![c]);
    // VTK lists its midside nodes in the order of hvi's first-order edge tables (kind.rs), read in
    // VTK's own corner numbering: 01, 12, 20 (23, 30 on a quadrangle), then a tetrahedron's 03, 13,
    // 23, a hexahedron's top 45, 56, 67, 74 and verticals 04, 15, 26, 37, a prism's top 34, 45, 53
    // and verticals 03, 14, 25
    let edges: &[[usize; 2]] = if kind.order() == 2 { kind.linear_edges() } else { &[] };
    let faces: &[&[usize]] = match kind {
        CellKind::Quad9 => &[&[0, 1, 2, 3]],
        // x = 0, x = 1, y = 0, y = 1, z = 0, z = 1 in VTK's parametric coordinates, then the centre
        CellKind::Hex27 => &[
            &[0, 3, 7, 4],
            &[1, 2, 6, 5],
            &[0, 1, 5, 4],
            &[3, 2, 6, 7],
            &[0, 1, 2, 3],
            &[4, 5, 6, 7],
            &[0, 1, 2, 3, 4, 5, 6, 7],
        ],
        CellKind::Prism18 => &[&[0, 1, 4, 3], &[1, 2, 5, 4], &[2, 0, 3, 5]],
        _ => &[],
    };
    corners
        .chain(edges.iter().map(|e| e.to_vec()))
        .chain(faces.iter().map(|f| f.to_vec()))
        .collect()
}

/// What follows from a kind's reference nodes.
pub(super) struct Derived {
    /// Per facet (the first-order kind's facets, in their order): the local nodes, corners first
    /// (oriented outward), then the facet's own second-order nodes in gmsh's order for its type
    /// (the midpoints of its edges 01, 12, …, then a quadrangle's centre where the cell has one).
    pub facets: Vec<Vec<usize>>,
    /// The local node written at each VTK position.
    pub vtk_order: Vec<usize>,
    /// The local node that goes to each position of the mirrored cell (ξ ↔ η).
    pub mirror: Vec<usize>,
    /// Per node: the corners it is the centroid of (a corner: itself; a midside node: its
    /// edge's two; a face centre: the face's four; a hexahedron's centre: all eight).
    pub support: Vec<Vec<usize>>,
}

/// The local node of `kind` at the reference point `x` (the tables hold exact binary fractions,
/// so a tolerance of 1e-12 only absorbs the averaging).
fn node_at(kind: CellKind, x: [f64; 3]) -> usize {
    reference_nodes(kind)
        .iter()
        .position(|n| (0..3).all(|k| (n[k] - x[k]).abs() < 1e-12))
        .unwrap_or_else(|| panic!("{kind:?} has no node at {x:?}"))
}

/// The centroid of local nodes `of` of `kind`.
fn centroid(kind: CellKind, of: &[usize]) -> [f64; 3] {
    let r = reference_nodes(kind);
    std::array::from_fn(|k| of.iter().map(|&a| r[a][k]).sum::<f64>() / of.len() as f64)
}

fn derive(kind: CellKind) -> Derived {
    let has = |x: [f64; 3]| {
        reference_nodes(kind)
            .iter()
            .any(|n| (0..3).all(|k| (n[k] - x[k]).abs() < 1e-12))
    };
    let facets = kind
        .linear_facets()
        .iter()
        .map(|corners| {
            let mut nodes = corners.to_vec();
            if kind.order() == 2 {
                let m = corners.len();
                let edges = if m == 2 { 1 } else { m };
                for i in 0..edges {
                    nodes.push(node_at(kind, centroid(kind, &[corners[i], corners[(i + 1) % m]])));
                }
                let centre = centroid(kind, corners);
                if m == 4 && has(centre) {
                    nodes.push(node_at(kind, centre));
                }
            }
            nodes
        })
        .collect();
    // VTK's corners: gmsh's, except the prism's triangles, which VTK orients the other way
    let vtk_corner = |c: usize| match kind.linear() {
        CellKind::Prism6 => [0, 2, 1, 3, 5, 4][c],
        _ => c,
    };
    let vtk_order = vtk_nodes(kind)
        .iter()
        .map(|of| {
            let gmsh: Vec<usize> = of.iter().map(|&c| vtk_corner(c)).collect();
            node_at(kind, centroid(kind, &gmsh))
        })
        .collect();
    let mirror = reference_nodes(kind)
        .iter()
        .map(|x| node_at(kind, [x[1], x[0], x[2]]))
        .collect();
    let corner_sets = (0..kind.corners())
        .map(|c| vec![c])
        .chain(kind.linear_edges().iter().map(|e| e.to_vec()))
        .chain(kind.linear_facets().iter().map(|f| f.to_vec()))
        .chain(std::iter::once((0..kind.corners()).collect()));
    let corner_sets: Vec<Vec<usize>> = corner_sets.collect();
    let support = (0..kind.nodes())
        .map(|a| {
            let r = reference_nodes(kind)[a];
            corner_sets
                .iter()
                .find(|set| {
                    let c = centroid(kind, set);
                    (0..3).all(|k| (c[k] - r[k]).abs() < 1e-12)
                })
                .unwrap_or_else(|| panic!("{kind:?}'s node {a} is no centroid of its corners"))
                .clone()
        })
        .collect();
    Derived {
        facets,
        vtk_order,
        mirror,
        support,
    }
}

/// The derived tables of `kind`, made once.
pub(super) fn derived(kind: CellKind) -> &'static Derived {
    static TABLES: OnceLock<Vec<Derived>> = OnceLock::new();
    &TABLES.get_or_init(|| CellKind::ALL.iter().map(|&k| derive(k)).collect())[kind.index()]
}

/// The corners (local indices) node `a` of `kind` is the centroid of.
pub fn corner_support(kind: CellKind, a: usize) -> &'static [usize] {
    &derived(kind).support[a]
}

#[cfg(test)]
mod tests;
