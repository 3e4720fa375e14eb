//! The kinds of cells hvi computes on, without their nodes (docs/method.md §2, §8, §19): what
//! each kind is (gmsh and VTK type, node and corner counts, dimension, order) and the first-order
//! tables of its corners' facets and edges. mesh/second_order derives the rest from the reference
//! nodes; mesh/cell.rs puts nodes on them.

/// The kind of a cell without its nodes: what the per-kind tables are indexed by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellKind {
    Tri3,
    Quad4,
    Tet4,
    Hex8,
    Prism6,
    Pyr5,
    Tri6,
    Quad8,
    Quad9,
    Tet10,
    Hex20,
    Hex27,
    Prism15,
    Prism18,
}

impl CellKind {
    /// Every kind, in the order of [`CellKind::index`].
    pub const ALL: [CellKind; 14] = [
        CellKind::Tri3,
        CellKind::Quad4,
        CellKind::Tet4,
        CellKind::Hex8,
        CellKind::Prism6,
        CellKind::Pyr5,
        CellKind::Tri6,
        CellKind::Quad8,
        CellKind::Quad9,
        CellKind::Tet10,
        CellKind::Hex20,
        CellKind::Hex27,
        CellKind::Prism15,
        CellKind::Prism18,
    ];

    /// Position in [`CellKind::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The gmsh element type (2, 3, 4, 5, 6, 7, 9, 16, 10, 11, 17, 12, 18, 13).
    pub fn gmsh_type(self) -> i32 {
        [2, 3, 4, 5, 6, 7, 9, 16, 10, 11, 17, 12, 18, 13][self.index()]
    }

    /// The kind of a gmsh element type of dimension ≥ 2, if hvi computes on it.
    pub fn from_gmsh(t: i32) -> Option<CellKind> {
        CellKind::ALL.into_iter().find(|k| k.gmsh_type() == t)
    }

    /// The number of nodes.
    pub fn nodes(self) -> usize {
        [3, 4, 4, 8, 6, 5, 6, 8, 9, 10, 20, 27, 15, 18][self.index()]
    }

    /// The spatial dimension (2 or 3).
    pub fn dim(self) -> usize {
        match self.linear() {
            CellKind::Tri3 | CellKind::Quad4 => 2,
            _ => 3,
        }
    }

    /// The polynomial order of the geometry and the displacement (1 or 2).
    pub fn order(self) -> u8 {
        if self.linear() == self {
            1
        } else {
            2
        }
    }

    /// The first-order kind with the same corners (itself for a first-order kind).
    pub fn linear(self) -> CellKind {
        match self {
            CellKind::Tri6 => CellKind::Tri3,
            CellKind::Quad8 | CellKind::Quad9 => CellKind::Quad4,
            CellKind::Tet10 => CellKind::Tet4,
            CellKind::Hex20 | CellKind::Hex27 => CellKind::Hex8,
            CellKind::Prism15 | CellKind::Prism18 => CellKind::Prism6,
            k => k,
        }
    }

    /// The second-order kind on the same corners: the complete (Lagrange) one, or the
    /// serendipity one (`complete = false`: 8-node quadrangle, 20-node hexahedron, 15-node
    /// prism; a triangle and a tetrahedron have only one). None for a pyramid.
    pub fn second_order(self, complete: bool) -> Option<CellKind> {
        Some(match (self.linear(), complete) {
            (CellKind::Tri3, _) => CellKind::Tri6,
            (CellKind::Quad4, true) => CellKind::Quad9,
            (CellKind::Quad4, false) => CellKind::Quad8,
            (CellKind::Tet4, _) => CellKind::Tet10,
            (CellKind::Hex8, true) => CellKind::Hex27,
            (CellKind::Hex8, false) => CellKind::Hex20,
            (CellKind::Prism6, true) => CellKind::Prism18,
            (CellKind::Prism6, false) => CellKind::Prism15,
            _ => return None,
        })
    }

    /// The number of corners (the first nodes).
    pub fn corners(self) -> usize {
        self.linear().nodes()
    }

    /// A triangle or a tetrahedron, of either order.
    pub fn is_simplex(self) -> bool {
        matches!(self.linear(), CellKind::Tri3 | CellKind::Tet4)
    }

    /// A short name for messages.
    pub fn name(self) -> &'static str {
        [
            "triangle",
            "quadrangle",
            "tetrahedron",
            "hexahedron",
            "prism",
            "pyramid",
            "6-node triangle",
            "8-node quadrangle",
            "9-node quadrangle",
            "10-node tetrahedron",
            "20-node hexahedron",
            "27-node hexahedron",
            "15-node prism",
            "18-node prism",
        ][self.index()]
    }

    /// VTK cell type id (5 triangle, 9 quad, 10 tetra, 12 hexahedron, 13 wedge, 14 pyramid; 22
    /// quadratic triangle, 23 quadratic quad, 28 biquadratic quad, 24 quadratic tetra, 25
    /// quadratic hexahedron, 29 triquadratic hexahedron, 26 quadratic wedge, 32 biquadratic
    /// quadratic wedge).
    pub fn vtk_type(self) -> u8 {
        [5, 9, 10, 12, 13, 14, 22, 23, 28, 24, 25, 29, 26, 32][self.index()]
    }

    /// The corners' facets of the first-order kind (local corner indices), oriented outward.
    pub(crate) fn linear_facets(self) -> &'static [&'static [usize]] {
        match self.linear() {
            CellKind::Tri3 => &[&TRI_EDGES[0], &TRI_EDGES[1], &TRI_EDGES[2]],
            CellKind::Quad4 => &[&QUAD_EDGES[0], &QUAD_EDGES[1], &QUAD_EDGES[2], &QUAD_EDGES[3]],
            CellKind::Tet4 => &[&TET_FACES[0], &TET_FACES[1], &TET_FACES[2], &TET_FACES[3]],
            CellKind::Hex8 => &[
                &HEX_FACES[0],
                &HEX_FACES[1],
                &HEX_FACES[2],
                &HEX_FACES[3],
                &HEX_FACES[4],
                &HEX_FACES[5],
            ],
            CellKind::Prism6 => &PRISM_FACES,
            _ => &PYRAMID_FACES,
        }
    }

    /// The corners' edges (local corner indices): the 1D skeleton.
    pub(crate) fn linear_edges(self) -> &'static [[usize; 2]] {
        match self.linear() {
            CellKind::Tri3 => &TRI_EDGES,
            CellKind::Quad4 => &QUAD_EDGES,
            CellKind::Tet4 => &[[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]],
            CellKind::Hex8 => &[
                [0, 1],
                [1, 2],
                [2, 3],
                [3, 0],
                [4, 5],
                [5, 6],
                [6, 7],
                [7, 4],
                [0, 4],
                [1, 5],
                [2, 6],
                [3, 7],
            ],
            CellKind::Prism6 => &[[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3], [0, 3], [1, 4], [2, 5]],
            _ => &[[0, 1], [1, 2], [2, 3], [3, 0], [0, 4], [1, 4], [2, 4], [3, 4]],
        }
    }
}

/// Edges of a triangle and a quadrilateral (counter-clockwise cells: outward = (dy, −dx)).
const TRI_EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];

const QUAD_EDGES: [[usize; 2]; 4] = [[0, 1], [1, 2], [2, 3], [3, 0]];

/// Faces of a tetrahedron, counter-clockwise seen from outside (opposite nodes 3, 2, 1, 0).
const TET_FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

/// Faces of a prism, counter-clockwise seen from outside: ζ = −1, ζ = +1, η = 0, ξ + η = 1,
/// ξ = 0.
const PRISM_FACES: [&[usize]; 5] = [&[0, 2, 1], &[3, 4, 5], &[0, 1, 4, 3], &[1, 2, 5, 4], &[2, 0, 3, 5]];

/// Faces of a pyramid, counter-clockwise seen from outside: the base ζ = 0, then the triangles
/// η = −(1 − ζ), ξ = 1 − ζ, η = 1 − ζ, ξ = −(1 − ζ).
const PYRAMID_FACES: [&[usize]; 5] = [&[0, 3, 2, 1], &[0, 1, 4], &[1, 2, 4], &[2, 3, 4], &[3, 0, 4]];

/// Faces of a hexahedron, counter-clockwise seen from outside: ζ = −1, ζ = +1, η = −1, η = +1,
/// ξ = −1, ξ = +1.
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [2, 3, 7, 6],
    [0, 4, 7, 3],
    [1, 2, 6, 5],
];
