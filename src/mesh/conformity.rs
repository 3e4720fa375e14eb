//! Is the mesh one conforming body, and is each group where the scene needs it (docs/method.md
//! §16.3)? A mesh can parse, have only positively oriented cells, and still be broken in ways
//! that give a wrong answer without any other error: a duplicated node that cuts the body (a
//! crack), a hexahedron whose face no longer matches its neighbour's, cells that overlap, or a
//! clamped group whose facets are not faces of the body. Everything here is combinatorial (faces
//! matched by their node sets) except the coincident nodes, found by hashing coordinates.
//!
//! * Every facet (edge in 2D, face in 3D) of a cell is a facet of one cell (on the boundary) or
//!   of exactly two cells, which hold it with opposite orientations (they lie on its two sides).
//! * A boundary facet whose nodes are all nodes of another cell, without being one of its
//!   facets, is a non-conforming interface (a rotated face, a triangle on a quadrangle).
//! * Two nodes of cells at the same point are an internal boundary (a crack).
//! * Disconnected pieces are legitimate (two bodies, each held), but reported.

use super::model::fmt_point;
use super::{Facet, GroupSelector, Mesh, MeshError, PhysicalGroup};
use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};

/// Something wrong with the mesh as a body.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshDefect {
    /// True if the mesh is broken (the result would be wrong); false if it is only unusual
    /// (disconnected pieces).
    pub severe: bool,
    /// One sentence: how many, the first place, what to do.
    pub message: String,
}

/// How many of the cells' facets share each node set, and who holds the first two.
struct FacetUse {
    count: u32,
    /// (cell, the facet as that cell orients it)
    first: (usize, Facet),
    second: Option<(usize, Facet)>,
}

impl<const D: usize> Mesh<D> {
    /// Every cell facet by its node set (sorted key).
    fn facet_uses(&self) -> HashMap<[usize; 4], FacetUse> {
        let mut uses: HashMap<[usize; 4], FacetUse> =
            HashMap::with_capacity_and_hasher(self.cells.len() * (D + 1), Default::default());
        for (c, cell) in self.cells.iter().enumerate() {
            for f in cell.facets() {
                uses.entry(f.key())
                    .and_modify(|u| {
                        u.count += 1;
                        if u.second.is_none() {
                            u.second = Some((c, f));
                        }
                    })
                    .or_insert(FacetUse {
                        count: 1,
                        first: (c, f),
                        second: None,
                    });
            }
        }
        uses
    }

    /// The boundary facets of the body: the cell facets that belong to one cell (oriented
    /// outward).
    pub fn boundary_facets(&self) -> Vec<Facet> {
        let mut out: Vec<(usize, Facet)> = self
            .facet_uses()
            .into_values()
            .filter(|u| u.count == 1)
            .map(|u| u.first)
            .collect();
        out.sort_unstable_by_key(|(c, f)| (*c, f.key()));
        out.into_iter().map(|(_, f)| f).collect()
    }

    /// What is wrong with the mesh as one conforming body (empty: nothing). Severe defects
    /// first; each kind once, with its count and first place.
    pub fn defects(&self) -> Vec<MeshDefect> {
        self.defects_besides(&[])
    }

    /// [`Mesh::defects`], where nodes of `interface` that coincide are not a cut: the two sides of
    /// contact between two bodies (docs/method.md §18); with an interface, the mesh holds several
    /// bodies on purpose, and disconnected pieces are not reported (each is held on its own or
    /// refused by name, §7.6).
    pub fn defects_besides(&self, interface: &[usize]) -> Vec<MeshDefect> {
        let mut out = Vec::new();
        let uses = self.facet_uses();
        let what = if D == 2 { "edge" } else { "face" };
        let place = |f: &Facet| {
            let corners: Vec<String> = f.nodes().iter().map(|&p| fmt_point(self.points[p])).collect();
            corners.join("–")
        };
        let tag = |c: usize| self.cell_tags.get(c).copied().unwrap_or(c + 1);

        // facets of more than two cells, and shared facets both cells hold the same way round
        let (mut crowded, mut folded) = (Vec::new(), Vec::new());
        for u in uses.values() {
            if u.count > 2 {
                crowded.push(u);
            } else if let Some((c2, f2)) = u.second {
                if !opposite(&u.first.1, &f2) {
                    folded.push((u.first.0, c2, u.first.1));
                }
            }
        }
        crowded.sort_unstable_by_key(|u| u.first.0);
        folded.sort_unstable_by_key(|&(c, _, _)| c);
        if let Some(u) = crowded.first() {
            out.push(MeshDefect {
                severe: true,
                message: format!(
                    "{} {what}(s) are shared by more than two cells (the first, {}, by {} cells, among them elements {} \
                     and {}): cells overlap or are listed twice; mesh the geometry again (in gmsh: Coherence, or \
                     BooleanFragments for touching volumes)",
                    crowded.len(),
                    place(&u.first.1),
                    u.count,
                    tag(u.first.0),
                    tag(u.second.map_or(u.first.0, |s| s.0))
                ),
            });
        }
        if let Some(&(a, b, f)) = folded.first() {
            out.push(MeshDefect {
                severe: true,
                message: format!(
                    "{} {what}(s) have both their cells on the same side (the first, {}, of elements {} and {}): the \
                     cells overlap there (the mesh folds over itself); mesh the geometry again",
                    folded.len(),
                    place(&f),
                    tag(a),
                    tag(b)
                ),
            });
        }

        // boundary facets lying on another cell's nodes without being its facet
        let mut node_cells: Vec<Vec<usize>> = vec![Vec::new(); self.points.len()];
        for (c, cell) in self.cells.iter().enumerate() {
            for &p in cell.nodes() {
                node_cells[p].push(c);
            }
        }
        let mut mismatched = Vec::new();
        for u in uses.values().filter(|u| u.count == 1) {
            let (c, f) = u.first;
            let nodes = f.nodes();
            if let Some(&other) = node_cells[nodes[0]]
                .iter()
                .find(|&&o| o != c && nodes.iter().all(|p| self.cells[o].nodes().contains(p)))
            {
                mismatched.push((c, other, f));
            }
        }
        mismatched.sort_unstable_by_key(|&(c, _, _)| c);
        if let Some(&(a, b, f)) = mismatched.first() {
            out.push(MeshDefect {
                severe: true,
                message: format!(
                    "{} cell {what}(s) do not match their neighbour's (the first, {} of element {}, has all its nodes in \
                     element {} but is not one of its {what}s): the mesh is not conforming there (a rotated or \
                     renumbered {what}, or {}); mesh the geometry again",
                    mismatched.len(),
                    place(&f),
                    tag(a),
                    tag(b),
                    if D == 2 {
                        "an edge split on one side only"
                    } else {
                        "triangles against a quadrangle, where a pyramid belongs: gmsh puts one on every interface \
                         quadrangle when it meshes both volumes in one run"
                    }
                ),
            });
        }

        // coincident nodes of cells: an internal boundary
        let used: Vec<bool> = node_cells.iter().map(|c| !c.is_empty()).collect();
        let mut on_interface = vec![false; self.points.len()];
        interface.iter().for_each(|&p| on_interface[p] = true);
        if let Some((p, q, n)) = coincident_nodes(&self.points, &used, &on_interface) {
            out.push(MeshDefect {
                severe: true,
                message: format!(
                    "{n} node(s) coincide with another node of the cells (the first at {}, nodes {} and {} of the \
                     file's order): the body is cut there (an internal boundary, a crack); in gmsh join the pieces \
                     (Coherence, BooleanFragments, or Geometry.Tolerance) and mesh again",
                    fmt_point(self.points[p]),
                    p + 1,
                    q + 1
                ),
            });
        }

        // pieces connected through shared nodes
        let pieces = pieces(self.cells.iter().map(|c| c.nodes()), self.points.len());
        if pieces.len() > 1 && interface.is_empty() {
            let sizes: Vec<String> = pieces
                .iter()
                .take(4)
                .map(|(first, n)| format!("{n} cells from element {}", tag(*first)))
                .collect();
            out.push(MeshDefect {
                severe: false,
                message: format!(
                    "the mesh has {} disconnected pieces ({}{}); each must be held on its own (clamped, or pressed \
                     on its contact); if they should be one body, join them in gmsh (Coherence, BooleanFragments)",
                    pieces.len(),
                    sizes.join("; "),
                    if pieces.len() > 4 { "; …" } else { "" }
                ),
            });
        }
        out
    }

    /// The nodes of a group the scene prescribes displacements on (`groups.clamped`,
    /// `[[dirichlet]]`): of dimension D − 1 if there is one of that name or tag, else of a lower
    /// dimension (curves of a 3D mesh, points). Every facet, edge or point of the group must be
    /// on the boundary of the body: a facet of exactly one cell, an edge of a boundary face, a
    /// node of a boundary facet. Otherwise an error naming the first that is not.
    pub fn boundary_group_nodes(&self, sel: &GroupSelector) -> Result<Vec<usize>, MeshError> {
        let mut first_error = None;
        for dim in (0..D as u8).rev() {
            match self.group(sel, dim) {
                Ok(g) => {
                    self.check_on_boundary(g)?;
                    return self.group_nodes(sel);
                }
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        Err(first_error.expect("D ≥ 1"))
    }

    /// An error unless every element of the group (of a dimension below D) is on the boundary.
    fn check_on_boundary(&self, g: &PhysicalGroup) -> Result<(), MeshError> {
        let not_boundary = |detail: String| MeshError::NotBoundary {
            path: self.path.clone(),
            group: g.label(),
            detail,
        };
        let side = if D == 2 { "edge" } else { "face" };
        if g.dim as usize == D - 1 {
            // each facet once, in the group's order, with the number of cells that have it
            let mut slot: HashMap<[usize; 4], usize> =
                HashMap::with_capacity_and_hasher(g.facets.len(), Default::default());
            let mut facets: Vec<Facet> = Vec::with_capacity(g.facets.len());
            for &f in &g.facets {
                slot.entry(f.key()).or_insert_with(|| {
                    facets.push(f);
                    facets.len() - 1
                });
            }
            let as_given = facets.clone();
            let cells = super::topology::orient_by_cells(self, &mut facets, &slot);
            for (f, &n) in as_given.iter().zip(&cells) {
                if f.dim() != D - 1 || n != 1 {
                    let corners: Vec<String> = f.nodes().iter().map(|&p| fmt_point(self.points[p])).collect();
                    let why = if n > 1 {
                        format!("is shared by {n} cells, so it lies inside the body")
                    } else {
                        format!("is not {} of any cell", if D == 2 { "an edge" } else { "a face" })
                    };
                    return Err(not_boundary(format!(
                        "its {} {} {why}; a group that prescribes displacements must be made of {side}s of the mesh on \
                         its boundary (check the group in the .geo, or that the mesh was made from this geometry)",
                        if f.len() == 2 { "edge" } else { "facet" },
                        corners.join("–"),
                    )));
                }
            }
            return Ok(());
        }
        let boundary = self.boundary_facets();
        let mut nodes = HashSet::default();
        let mut edges = HashSet::default();
        for f in &boundary {
            let n = f.nodes();
            for (i, &a) in n.iter().enumerate() {
                nodes.insert(a);
                let b = n[(i + 1) % n.len()];
                edges.insert((a.min(b), a.max(b)));
            }
        }
        if g.dim == 1 {
            for f in &g.facets {
                let n = f.nodes();
                if f.len() != 2 || !edges.contains(&(n[0].min(n[1]), n[0].max(n[1]))) {
                    let corners: Vec<String> = n.iter().map(|&p| fmt_point(self.points[p])).collect();
                    return Err(not_boundary(format!(
                        "its line {} is not an edge of a boundary face of the mesh (it lies inside the body or is not \
                         a cell edge); a curve that prescribes displacements must be made of edges of the boundary",
                        corners.join("–")
                    )));
                }
            }
        } else {
            for &p in &g.nodes {
                if !nodes.contains(&p) {
                    return Err(not_boundary(format!(
                        "its point {} is not a node of the boundary (it lies inside the body or is not a node of any \
                         cell); a point that prescribes displacements must be a node of the boundary",
                        fmt_point(self.points[p])
                    )));
                }
            }
        }
        Ok(())
    }
}

/// True if two orientations of one facet are opposite (as the facets of two cells on its two
/// sides are): the second runs through the corners in the reverse cyclic order. The corners
/// alone carry the orientation; a second-order facet lists its midside nodes after them in an
/// order of its own (docs/method.md §19.1), which reversed is no cyclic reversal of the list.
fn opposite(a: &Facet, b: &Facet) -> bool {
    let (a, b) = (a.corners(), b.corners());
    let n = a.len();
    if b.len() != n {
        return false;
    }
    if n == 2 {
        // edges are directed: the reverse edge
        return b[0] == a[1] && b[1] == a[0];
    }
    let Some(i) = b.iter().position(|&p| p == a[0]) else {
        return false;
    };
    (0..n).all(|k| b[(i + n - k) % n] == a[k])
}

/// The number of used nodes that coincide with an earlier used node (both on the `interface`
/// excepted), with the first pair: coordinates hashed on a grid of the tolerance (10⁻¹² of the
/// extent), neighbours compared.
fn coincident_nodes<const D: usize>(
    points: &[[f64; D]],
    used: &[bool],
    interface: &[bool],
) -> Option<(usize, usize, usize)> {
    let mut lo = [f64::INFINITY; D];
    let mut hi = [f64::NEG_INFINITY; D];
    for x in points.iter().zip(used).filter(|(_, &u)| u).map(|(x, _)| x) {
        for k in 0..D {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
    let extent = (0..D).map(|k| hi[k] - lo[k]).fold(0.0_f64, f64::max);
    if !(extent > 0.0 && extent.is_finite()) {
        return None;
    }
    let tol = 1e-12 * extent;
    let cell = |x: &[f64; D]| -> [i64; D] { std::array::from_fn(|k| ((x[k] - lo[k]) / tol).floor() as i64) };
    let mut grid: HashMap<[i64; D], Vec<usize>> = HashMap::default();
    let (mut first, mut count) = (None, 0);
    for (p, x) in points.iter().enumerate() {
        if !used[p] {
            continue;
        }
        let c = cell(x);
        let mut hit = None;
        for offset in 0..3_i64.pow(D as u32) {
            let mut n = c;
            let mut o = offset;
            for nk in n.iter_mut() {
                *nk += o % 3 - 1;
                o /= 3;
            }
            if let Some(list) = grid.get(&n) {
                if let Some(&q) = list
                    .iter()
                    .find(|&&q| (0..D).all(|k| (points[q][k] - x[k]).abs() <= tol))
                {
                    hit = Some(q);
                    break;
                }
            }
        }
        if let Some(q) = hit.filter(|&q| !(interface[p] && interface[q])) {
            count += 1;
            first.get_or_insert((q, p));
        }
        grid.entry(c).or_default().push(p);
    }
    first.map(|(q, p)| (q, p, count))
}

impl<const D: usize> Mesh<D> {
    /// The bodies of the mesh: its pieces of cells connected through shared nodes, each as its
    /// nodes (ascending), in the order of their first cell.
    pub fn bodies(&self) -> Vec<Vec<usize>> {
        let cells: Vec<&[usize]> = self.cells.iter().map(|c| c.nodes()).collect();
        let mut parent = union_of_cells(&cells, self.points.len());
        let mut index: HashMap<usize, usize> = HashMap::default();
        let mut out: Vec<Vec<usize>> = Vec::new();
        for nodes in &cells {
            let r = root(&mut parent, nodes[0]);
            let next = index.len();
            index.entry(r).or_insert_with(|| {
                out.push(Vec::new());
                next
            });
        }
        let mut seen = vec![false; self.points.len()];
        for nodes in &cells {
            for &p in nodes.iter() {
                if !seen[p] {
                    seen[p] = true;
                    let r = root(&mut parent, p);
                    out[index[&r]].push(p);
                }
            }
        }
        out.iter_mut().for_each(|b| b.sort_unstable());
        out
    }
}

fn root(parent: &mut [usize], mut p: usize) -> usize {
    while parent[p] != p {
        parent[p] = parent[parent[p]];
        p = parent[p];
    }
    p
}

/// Union–find over the nodes, joined through each cell's nodes.
fn union_of_cells(cells: &[&[usize]], n_points: usize) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..n_points).collect();
    for nodes in cells {
        let a = root(&mut parent, nodes[0]);
        for &q in &nodes[1..] {
            let b = root(&mut parent, q);
            if a != b {
                parent[b] = a;
            }
        }
    }
    parent
}

/// The connected pieces of cells (through shared nodes): (first cell, number of cells) of each,
/// largest first.
fn pieces<'a>(cells: impl Iterator<Item = &'a [usize]>, n_points: usize) -> Vec<(usize, usize)> {
    let cells: Vec<&[usize]> = cells.collect();
    let mut parent = union_of_cells(&cells, n_points);
    let mut by_root: HashMap<usize, (usize, usize)> = HashMap::default();
    for (c, nodes) in cells.iter().enumerate() {
        let r = root(&mut parent, nodes[0]);
        by_root.entry(r).or_insert((c, 0)).1 += 1;
    }
    let mut out: Vec<(usize, usize)> = by_root.into_values().collect();
    out.sort_unstable_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    out
}

#[cfg(test)]
mod tests {
    use crate::mesh::structured::{block, rectangle, CellShape, SolidShape};
    use crate::mesh::Cell;

    #[test]
    fn structured_meshes_have_no_defects() {
        for shape in [CellShape::Quad, CellShape::Tri] {
            assert!(rectangle(2.0, 1.0, 6, 3, shape).defects().is_empty());
        }
        for shape in [
            SolidShape::Hex,
            SolidShape::Tet,
            SolidShape::Prism,
            SolidShape::Pyramid,
            SolidShape::HexPyramid,
        ] {
            let m = block([2.0, 1.0, 0.5], [4, 2, 2], shape);
            assert!(m.defects().is_empty(), "{shape:?}: {:?}", m.defects());
        }
    }

    /// Tetrahedra against a hexahedron's face without the pyramid between them: the face does
    /// not match, and the message says a pyramid belongs there; with the box beside the
    /// hexahedron split into pyramids instead, the faces match (a pyramid's base against the
    /// hexahedron's face, its triangles against each other).
    #[test]
    fn triangles_against_a_quadrangle_need_a_pyramid() {
        let hexes = block([2.0, 1.0, 1.0], [2, 1, 1], SolidShape::Hex);
        let tets = block([2.0, 1.0, 1.0], [2, 1, 1], SolidShape::Tet);
        let mut m = hexes.clone();
        // the second box's six tetrahedra in place of its hexahedron
        m.cells.truncate(1);
        m.cells.extend(tets.cells[6..].iter().copied());
        m.cell_tags = (1..=m.cells.len()).collect();
        let d = m.defects();
        assert!(
            d.iter()
                .any(|d| d.severe && d.message.contains("do not match") && d.message.contains("pyramid")),
            "{d:?}"
        );
        let pyramids = block([2.0, 1.0, 1.0], [2, 1, 1], SolidShape::HexPyramid);
        assert!(matches!(pyramids.cells[0], Cell::Hex8(_)) && matches!(pyramids.cells[1], Cell::Pyr5(_)));
        assert!(pyramids.defects().is_empty(), "{:?}", pyramids.defects());
    }

    #[test]
    fn a_duplicated_node_is_a_crack() {
        let mut m = rectangle(2.0, 1.0, 4, 2, CellShape::Quad);
        // the middle node (1, 0.5) duplicated for the cells right of x = 1
        let mid = m.points.iter().position(|p| p == &[1.0, 0.5]).unwrap();
        m.points.push([1.0, 0.5]);
        let dup = m.points.len() - 1;
        for c in &mut m.cells {
            if let Cell::Quad4(n) = c {
                let right = n.iter().all(|&p| m.points[p][0] >= 1.0);
                for p in n.iter_mut() {
                    if *p == mid && right {
                        *p = dup;
                    }
                }
            }
        }
        let d = m.defects();
        assert!(d.iter().any(|d| d.severe && d.message.contains("coincide")), "{d:?}");
    }

    #[test]
    fn a_rotated_hexahedron_face_does_not_match() {
        let mut m = block([2.0, 1.0, 1.0], [2, 1, 2], SolidShape::Hex);
        // rotate the top face of the first cell (its nodes 4..8 by one place)
        if let Cell::Hex8(n) = &mut m.cells[0] {
            n[4..8].rotate_left(1);
        }
        let d = m.defects();
        assert!(
            d.iter().any(|d| d.severe && d.message.contains("do not match")),
            "{d:?}"
        );
    }

    #[test]
    fn a_cell_listed_twice_and_a_fold_are_found() {
        let mut m = rectangle(2.0, 1.0, 2, 1, CellShape::Tri);
        m.cells.push(m.cells[0]);
        m.cell_tags.push(99);
        let d = m.defects();
        assert!(d.iter().any(|d| d.severe && d.message.contains("same side")), "{d:?}");
        let mut m = block([1.0, 1.0, 1.0], [1, 1, 3], SolidShape::Hex);
        m.cells.push(m.cells[1]);
        m.cell_tags.push(99);
        let d = m.defects();
        assert!(
            d.iter().any(|d| d.severe && d.message.contains("more than two")),
            "{d:?}"
        );
    }

    /// Second-order cells list their midside nodes after the corners in an order of their own:
    /// two cells on the two sides of a face hold it in opposite orientations all the same
    /// (before the corners alone were compared, every interior face of a 3D second-order mesh
    /// was a fold); a cell listed twice is still one.
    #[test]
    fn second_order_meshes_conform_and_their_folds_are_found() {
        use crate::mesh::structured::elevate;
        let mut meshes = Vec::new();
        for complete in [true, false] {
            for shape in [SolidShape::Hex, SolidShape::Tet, SolidShape::Prism] {
                meshes.push(elevate(&block([2.0, 1.0, 1.0], [2, 2, 2], shape), complete));
            }
        }
        for mut m in meshes {
            let kind = m.cells[0].kind();
            assert!(m.defects().is_empty(), "{kind:?}: {:?}", m.defects());
            m.cells.push(m.cells[3]);
            m.cell_tags.push(99);
            let d = m.defects();
            assert!(
                d.iter().any(|d| d.severe && d.message.contains("same side")),
                "{kind:?}: {d:?}"
            );
        }
        for shape in [CellShape::Tri, CellShape::Quad] {
            for complete in [true, false] {
                let m = elevate(&rectangle(2.0, 1.0, 2, 2, shape), complete);
                assert!(m.defects().is_empty(), "{:?}: {:?}", m.cells[0].kind(), m.defects());
            }
        }
    }

    #[test]
    fn disconnected_pieces_are_reported_but_not_severe() {
        let mut m = rectangle(1.0, 1.0, 2, 2, CellShape::Quad);
        let n = m.points.len();
        let shifted: Vec<[f64; 2]> = m.points.iter().map(|p| [p[0] + 5.0, p[1]]).collect();
        m.points.extend(shifted);
        let more: Vec<Cell> = m.cells.iter().map(|c| c.renumbered(|p| p + n)).collect();
        m.cell_tags.extend((0..more.len()).map(|i| 100 + i));
        m.cells.extend(more);
        let d = m.defects();
        assert_eq!(d.len(), 1, "{d:?}");
        assert!(!d[0].severe && d[0].message.contains("2 disconnected pieces"), "{d:?}");
    }
}
