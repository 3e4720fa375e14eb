//! The cells hvi computes on and their reference tables (docs/method.md §2, §8): 3-node
//! triangles (P1) and 4-node quadrilaterals (Q1) in 2D, 4-node tetrahedra (P1), 8-node
//! hexahedra (Q1), 6-node prisms and 5-node pyramids in 3D, with gmsh's node order.
//!
//! Node indices are dense, 0-based indices into [`super::Mesh::points`]. Cells are stored with
//! positive orientation (det J > 0); the reader rejects inverted cells. Each cell type lists its
//! facets (edges in 2D, faces in 3D) in the reference element's table, oriented so that the
//! outward normal follows from the node order: for an edge `[a, b]` it is `(dy, −dx)`, for a face
//! the right-hand rule (counter-clockwise seen from outside).

use std::fmt;
use std::ops::Index;

/// One cell of the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cell {
    /// Linear triangle, nodes counter-clockwise (gmsh element type 2).
    Tri3([usize; 3]),
    /// Bilinear quadrilateral, nodes counter-clockwise (gmsh element type 3).
    Quad4([usize; 4]),
    /// Linear tetrahedron (gmsh element type 4), (x₁−x₀)×(x₂−x₀)·(x₃−x₀) > 0.
    Tet4([usize; 4]),
    /// Trilinear hexahedron (gmsh element type 5): nodes 0–3 the face ζ = −1, 4–7 the face ζ = +1.
    Hex8([usize; 8]),
    /// Linear prism (wedge; gmsh element type 6, what an extruded triangulation gives): nodes 0–2
    /// the triangle ζ = −1, 3–5 the triangle ζ = +1, node k + 3 above node k; triangle × segment.
    Prism6([usize; 6]),
    /// Linear pyramid (gmsh element type 7, what gmsh puts between hexahedra and tetrahedra):
    /// nodes 0–3 the quadrangular base ζ = 0, counter-clockwise seen from the apex, node 4 the
    /// apex ζ = 1; the rational basis of docs/method.md §8.1 (Q1 on the base, P1 on the
    /// triangles).
    Pyr5([usize; 5]),
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

/// A cell as an element of a sparse pattern: its node list.
impl AsRef<[usize]> for Cell {
    fn as_ref(&self) -> &[usize] {
        self.nodes()
    }
}

impl Cell {
    /// The cell's node indices, in gmsh's order.
    pub fn nodes(&self) -> &[usize] {
        match self {
            Cell::Tri3(n) => n,
            Cell::Quad4(n) => n,
            Cell::Tet4(n) => n,
            Cell::Hex8(n) => n,
            Cell::Prism6(n) => n,
            Cell::Pyr5(n) => n,
        }
    }

    /// The spatial dimension of the cell (2 or 3).
    pub fn dim(&self) -> usize {
        match self {
            Cell::Tri3(_) | Cell::Quad4(_) => 2,
            Cell::Tet4(_) | Cell::Hex8(_) | Cell::Prism6(_) | Cell::Pyr5(_) => 3,
        }
    }

    /// The same cell on renumbered nodes: node p becomes `number(p)` (e.g. a mesh piece's own
    /// numbering).
    pub fn renumbered(&self, number: impl Fn(usize) -> usize) -> Cell {
        match *self {
            Cell::Tri3(n) => Cell::Tri3(n.map(number)),
            Cell::Quad4(n) => Cell::Quad4(n.map(number)),
            Cell::Tet4(n) => Cell::Tet4(n.map(number)),
            Cell::Hex8(n) => Cell::Hex8(n.map(number)),
            Cell::Prism6(n) => Cell::Prism6(n.map(number)),
            Cell::Pyr5(n) => Cell::Pyr5(n.map(number)),
        }
    }

    /// The cell with the opposite orientation (a mirror of its node order).
    pub fn flipped(&self) -> Cell {
        match *self {
            Cell::Tri3([a, b, c]) => Cell::Tri3([a, c, b]),
            Cell::Quad4([a, b, c, d]) => Cell::Quad4([a, d, c, b]),
            Cell::Tet4([a, b, c, d]) => Cell::Tet4([a, c, b, d]),
            Cell::Hex8([a, b, c, d, e, f, g, h]) => Cell::Hex8([a, d, c, b, e, h, g, f]),
            Cell::Prism6([a, b, c, d, e, f]) => Cell::Prism6([a, c, b, d, f, e]),
            Cell::Pyr5([a, b, c, d, e]) => Cell::Pyr5([a, d, c, b, e]),
        }
    }

    /// The boundary facets of the cell (edges in 2D, faces in 3D), oriented outward.
    pub fn facets(&self) -> impl Iterator<Item = Facet> + '_ {
        let n = self.nodes();
        let table: &[&[usize]] = match self {
            Cell::Tri3(_) => &[&TRI_EDGES[0], &TRI_EDGES[1], &TRI_EDGES[2]],
            Cell::Quad4(_) => &[&QUAD_EDGES[0], &QUAD_EDGES[1], &QUAD_EDGES[2], &QUAD_EDGES[3]],
            Cell::Tet4(_) => &[&TET_FACES[0], &TET_FACES[1], &TET_FACES[2], &TET_FACES[3]],
            Cell::Hex8(_) => &[
                &HEX_FACES[0],
                &HEX_FACES[1],
                &HEX_FACES[2],
                &HEX_FACES[3],
                &HEX_FACES[4],
                &HEX_FACES[5],
            ],
            Cell::Prism6(_) => &PRISM_FACES,
            Cell::Pyr5(_) => &PYRAMID_FACES,
        };
        table
            .iter()
            .map(move |local| Facet::from_slice(&local.iter().map(|&i| n[i]).collect::<Vec<_>>()))
    }

    /// The edges of the cell (the 1D skeleton), for the cell size h.
    pub fn edges(&self) -> Vec<[usize; 2]> {
        let n = self.nodes();
        let local: &[[usize; 2]] = match self {
            Cell::Tri3(_) => &TRI_EDGES,
            Cell::Quad4(_) => &QUAD_EDGES,
            Cell::Tet4(_) => &[[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]],
            Cell::Hex8(_) => &[
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
            Cell::Prism6(_) => &[[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3], [0, 3], [1, 4], [2, 5]],
            Cell::Pyr5(_) => &[[0, 1], [1, 2], [2, 3], [3, 0], [0, 4], [1, 4], [2, 4], [3, 4]],
        };
        local.iter().map(|&[a, b]| [n[a], n[b]]).collect()
    }

    /// VTK cell type id (5 triangle, 9 quad, 10 tetra, 12 hexahedron, 13 wedge, 14 pyramid).
    pub fn vtk_type(&self) -> u8 {
        match self {
            Cell::Tri3(_) => 5,
            Cell::Quad4(_) => 9,
            Cell::Tet4(_) => 10,
            Cell::Hex8(_) => 12,
            Cell::Prism6(_) => 13,
            Cell::Pyr5(_) => 14,
        }
    }

    /// The positions of [`Cell::nodes`] in VTK's order: gmsh's, except for the prism, whose base
    /// triangle VTK orients with its normal away from the other triangle (gmsh: towards it). A
    /// pyramid is the same in both: the base, its right-hand normal towards the apex, then the
    /// apex.
    pub fn vtk_order(&self) -> &'static [usize] {
        match self {
            Cell::Prism6(_) => &[0, 2, 1, 3, 5, 4],
            c => &[0, 1, 2, 3, 4, 5, 6, 7][..c.nodes().len()],
        }
    }

    /// A short name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Cell::Tri3(_) => "triangle",
            Cell::Quad4(_) => "quadrangle",
            Cell::Tet4(_) => "tetrahedron",
            Cell::Hex8(_) => "hexahedron",
            Cell::Prism6(_) => "prism",
            Cell::Pyr5(_) => "pyramid",
        }
    }
}

/// A facet of the boundary: a 2-node edge (2D), a 3-node triangle or a 4-node quadrilateral
/// face (3D), with its nodes in order.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Facet {
    nodes: [usize; 4],
    len: u8,
}

impl Facet {
    /// A facet from 2, 3 or 4 node indices.
    ///
    /// # Panics
    /// If `nodes` has another length (a programming error).
    pub fn from_slice(nodes: &[usize]) -> Facet {
        assert!((2..=4).contains(&nodes.len()), "a facet has 2, 3 or 4 nodes");
        let mut n = [0; 4];
        n[..nodes.len()].copy_from_slice(nodes);
        Facet {
            nodes: n,
            len: nodes.len() as u8,
        }
    }

    /// The facet's nodes in order.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes[..self.len as usize]
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Never true: a facet has at least two nodes.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The dimension of the facet (1 for an edge, 2 for a face).
    pub fn dim(&self) -> usize {
        if self.len == 2 {
            1
        } else {
            2
        }
    }

    /// The nodes sorted: the same key for a facet and its reverse.
    pub fn key(&self) -> [usize; 4] {
        let mut k = [usize::MAX; 4];
        k[..self.len()].copy_from_slice(self.nodes());
        k.sort_unstable();
        k
    }
}

impl From<[usize; 2]> for Facet {
    fn from(n: [usize; 2]) -> Self {
        Facet::from_slice(&n)
    }
}

impl From<[usize; 3]> for Facet {
    fn from(n: [usize; 3]) -> Self {
        Facet::from_slice(&n)
    }
}

impl From<[usize; 4]> for Facet {
    fn from(n: [usize; 4]) -> Self {
        Facet::from_slice(&n)
    }
}

impl<const N: usize> PartialEq<[usize; N]> for Facet {
    fn eq(&self, other: &[usize; N]) -> bool {
        self.nodes() == other
    }
}

impl Index<usize> for Facet {
    type Output = usize;
    fn index(&self, i: usize) -> &usize {
        &self.nodes()[i]
    }
}

impl fmt::Debug for Facet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?}", self.nodes())
    }
}
