//! The cells hvi computes on and their reference tables (docs/method.md §2, §8, §19): 3-node
//! triangles (P1) and 4-node quadrilaterals (Q1) in 2D, 4-node tetrahedra (P1), 8-node
//! hexahedra (Q1), 6-node prisms and 5-node pyramids in 3D, and their second-order
//! (isoparametric) companions — 6-node triangles, 8- and 9-node quadrilaterals, 10-node
//! tetrahedra, 20- and 27-node hexahedra, 15- and 18-node prisms — with gmsh's node order.
//!
//! Node indices are dense, 0-based indices into [`super::Mesh::points`]. Cells are stored with
//! positive orientation (det J > 0); the reader rejects inverted cells. Each cell type lists its
//! facets (edges in 2D, faces in 3D) in the reference element's table, oriented so that the
//! outward normal follows from the order of the facet's corners: for an edge `[a, b]` it is
//! `(dy, −dx)`, for a face the right-hand rule (counter-clockwise seen from outside). A facet of
//! a second-order cell lists its corners first, then its own second-order nodes in gmsh's order
//! for the facet's type (mesh/second_order.rs derives these tables from the reference nodes).

use super::kind::CellKind;
use super::second_order::derived;
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
    /// Quadratic triangle (gmsh type 9): the corners, then the midpoints of 01, 12, 20.
    Tri6([usize; 6]),
    /// Serendipity quadrilateral (gmsh type 16): the corners, then the midpoints of 01, 12, 23, 30.
    Quad8([usize; 8]),
    /// Biquadratic quadrilateral (gmsh type 10): Quad8's nodes and the centre.
    Quad9([usize; 9]),
    /// Quadratic tetrahedron (gmsh type 11): the corners, then the midpoints of 01, 12, 20, 30,
    /// 32, 31.
    Tet10([usize; 10]),
    /// Serendipity hexahedron (gmsh type 17): the corners, then twelve edge midpoints.
    Hex20([usize; 20]),
    /// Triquadratic hexahedron (gmsh type 12): Hex20's nodes, six face centres and the centre.
    Hex27([usize; 27]),
    /// Quadratic (serendipity) prism (gmsh type 18): the corners, then nine edge midpoints.
    Prism15([usize; 15]),
    /// Biquadratic–quadratic prism (gmsh type 13): Prism15's nodes and the three quadrangular
    /// faces' centres.
    Prism18([usize; 18]),
}

/// A cell as an element of a sparse pattern: its node list.
impl AsRef<[usize]> for Cell {
    fn as_ref(&self) -> &[usize] {
        self.nodes()
    }
}

/// Applies `$body` to the node array of whichever variant `$cell` is.
macro_rules! each_variant {
    ($cell:expr, $n:ident => $body:expr) => {
        match $cell {
            Cell::Tri3($n) => $body,
            Cell::Quad4($n) => $body,
            Cell::Tet4($n) => $body,
            Cell::Hex8($n) => $body,
            Cell::Prism6($n) => $body,
            Cell::Pyr5($n) => $body,
            Cell::Tri6($n) => $body,
            Cell::Quad8($n) => $body,
            Cell::Quad9($n) => $body,
            Cell::Tet10($n) => $body,
            Cell::Hex20($n) => $body,
            Cell::Hex27($n) => $body,
            Cell::Prism15($n) => $body,
            Cell::Prism18($n) => $body,
        }
    };
}

impl Cell {
    /// A cell of `kind` on `nodes` (in gmsh's order).
    ///
    /// # Panics
    /// If `nodes` does not hold [`CellKind::nodes`] indices (a programming error).
    pub fn new(kind: CellKind, nodes: &[usize]) -> Cell {
        assert_eq!(
            nodes.len(),
            kind.nodes(),
            "a {} has {} nodes",
            kind.name(),
            kind.nodes()
        );
        fn take<const N: usize>(nodes: &[usize]) -> [usize; N] {
            std::array::from_fn(|k| nodes[k])
        }
        match kind {
            CellKind::Tri3 => Cell::Tri3(take(nodes)),
            CellKind::Quad4 => Cell::Quad4(take(nodes)),
            CellKind::Tet4 => Cell::Tet4(take(nodes)),
            CellKind::Hex8 => Cell::Hex8(take(nodes)),
            CellKind::Prism6 => Cell::Prism6(take(nodes)),
            CellKind::Pyr5 => Cell::Pyr5(take(nodes)),
            CellKind::Tri6 => Cell::Tri6(take(nodes)),
            CellKind::Quad8 => Cell::Quad8(take(nodes)),
            CellKind::Quad9 => Cell::Quad9(take(nodes)),
            CellKind::Tet10 => Cell::Tet10(take(nodes)),
            CellKind::Hex20 => Cell::Hex20(take(nodes)),
            CellKind::Hex27 => Cell::Hex27(take(nodes)),
            CellKind::Prism15 => Cell::Prism15(take(nodes)),
            CellKind::Prism18 => Cell::Prism18(take(nodes)),
        }
    }

    /// The cell's kind.
    pub fn kind(&self) -> CellKind {
        match self {
            Cell::Tri3(_) => CellKind::Tri3,
            Cell::Quad4(_) => CellKind::Quad4,
            Cell::Tet4(_) => CellKind::Tet4,
            Cell::Hex8(_) => CellKind::Hex8,
            Cell::Prism6(_) => CellKind::Prism6,
            Cell::Pyr5(_) => CellKind::Pyr5,
            Cell::Tri6(_) => CellKind::Tri6,
            Cell::Quad8(_) => CellKind::Quad8,
            Cell::Quad9(_) => CellKind::Quad9,
            Cell::Tet10(_) => CellKind::Tet10,
            Cell::Hex20(_) => CellKind::Hex20,
            Cell::Hex27(_) => CellKind::Hex27,
            Cell::Prism15(_) => CellKind::Prism15,
            Cell::Prism18(_) => CellKind::Prism18,
        }
    }

    /// The cell's node indices, in gmsh's order.
    pub fn nodes(&self) -> &[usize] {
        each_variant!(self, n => &n[..])
    }

    /// The cell's corners: its first [`CellKind::corners`] nodes.
    pub fn corners(&self) -> &[usize] {
        &self.nodes()[..self.kind().corners()]
    }

    /// The spatial dimension of the cell (2 or 3).
    pub fn dim(&self) -> usize {
        self.kind().dim()
    }

    /// The same cell on renumbered nodes: node p becomes `number(p)` (e.g. a mesh piece's own
    /// numbering).
    pub fn renumbered(&self, number: impl Fn(usize) -> usize) -> Cell {
        let mut c = *self;
        each_variant!(&mut c, n => n.iter_mut().for_each(|p| *p = number(*p)));
        c
    }

    /// The cell with the opposite orientation (a mirror of its node order: ξ ↔ η).
    pub fn flipped(&self) -> Cell {
        let (nodes, mirror) = (self.nodes(), &derived(self.kind()).mirror);
        let mut c = *self;
        each_variant!(&mut c, n => n.iter_mut().zip(mirror).for_each(|(p, &m)| *p = nodes[m]));
        c
    }

    /// The boundary facets of the cell (edges in 2D, faces in 3D), oriented outward, with their
    /// second-order nodes on a second-order cell.
    pub fn facets(&self) -> impl Iterator<Item = Facet> + '_ {
        let n = self.nodes();
        let kind = self.kind();
        derived(kind)
            .facets
            .iter()
            .zip(kind.linear_facets())
            .map(move |(local, corners)| {
                let mut f = Facet {
                    nodes: [0; MAX_FACET_NODES],
                    len: local.len() as u8,
                    corners: corners.len() as u8,
                };
                for (slot, &i) in f.nodes.iter_mut().zip(local) {
                    *slot = n[i];
                }
                f
            })
    }

    /// The edges between the cell's corners (the 1D skeleton), for the cell size h.
    pub fn edges(&self) -> Vec<[usize; 2]> {
        let n = self.nodes();
        self.kind().linear_edges().iter().map(|&[a, b]| [n[a], n[b]]).collect()
    }

    /// VTK cell type id ([`CellKind::vtk_type`]).
    pub fn vtk_type(&self) -> u8 {
        self.kind().vtk_type()
    }

    /// The positions of [`Cell::nodes`] in VTK's order: gmsh's corners, except the prism's, whose
    /// base triangle VTK orients with its normal away from the other triangle (gmsh: towards
    /// it), then VTK's own order of the second-order nodes (mesh/second_order). A pyramid is the
    /// same in both: the base, its right-hand normal towards the apex, then the apex.
    pub fn vtk_order(&self) -> &'static [usize] {
        &derived(self.kind()).vtk_order
    }

    /// A short name for messages.
    pub fn name(&self) -> &'static str {
        self.kind().name()
    }
}

/// The most nodes of a facet (the 9-node quadrangle face of a 27-node hexahedron).
const MAX_FACET_NODES: usize = 9;

/// A facet of the boundary: an edge (2D) or a triangle or quadrilateral face (3D), with its
/// corners first, then (on a second-order facet: a 3-node line, a 6-node triangle, an 8- or
/// 9-node quadrangle) its second-order nodes in gmsh's order.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Facet {
    nodes: [usize; MAX_FACET_NODES],
    len: u8,
    corners: u8,
}

impl Facet {
    /// A first-order facet from 2, 3 or 4 node indices.
    ///
    /// # Panics
    /// If `nodes` has another length (a programming error).
    pub fn from_slice(nodes: &[usize]) -> Facet {
        assert!((2..=4).contains(&nodes.len()), "a facet has 2, 3 or 4 nodes");
        Facet::with_corners(nodes, nodes.len())
    }

    /// A facet with `corners` corners (2, 3 or 4) and, after them, its second-order nodes (none,
    /// or 1 on a line, 3 on a triangle, 4 or 5 on a quadrangle).
    ///
    /// # Panics
    /// If the counts do not fit one of those (a programming error).
    pub fn with_corners(nodes: &[usize], corners: usize) -> Facet {
        let extra = nodes.len() - corners;
        assert!(
            matches!((corners, extra), (2, 0 | 1) | (3, 0 | 3) | (4, 0 | 4 | 5)),
            "a facet of {corners} corners with {extra} more nodes"
        );
        let mut n = [0; MAX_FACET_NODES];
        n[..nodes.len()].copy_from_slice(nodes);
        Facet {
            nodes: n,
            len: nodes.len() as u8,
            corners: corners as u8,
        }
    }

    /// The facet's nodes: its corners, then its second-order nodes.
    pub fn nodes(&self) -> &[usize] {
        &self.nodes[..self.len as usize]
    }

    /// The facet's corners, in order.
    pub fn corners(&self) -> &[usize] {
        &self.nodes[..self.corners as usize]
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// True on a second-order facet (nodes beyond its corners).
    pub fn is_second_order(&self) -> bool {
        self.len > self.corners
    }

    /// Never true: a facet has at least two nodes.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The dimension of the facet (1 for an edge, 2 for a face).
    pub fn dim(&self) -> usize {
        if self.corners == 2 {
            1
        } else {
            2
        }
    }

    /// The corners sorted: the same key for a facet and its reverse, of either order.
    pub fn key(&self) -> [usize; 4] {
        let mut k = [usize::MAX; 4];
        k[..self.corners().len()].copy_from_slice(self.corners());
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
