//! From what a reader found to a [`Mesh`]: dense 0-based points, cells of the body's dimension,
//! physical groups, and the orientation checks (every cell positively oriented, or every cell
//! flipped; docs/method.md §8).

use super::model::longest_edge;
use crate::mesh::element_type_info;
use crate::mesh::fmt_point;
use crate::mesh::physical_names;
use crate::mesh::Facet;
use crate::mesh::Mesh;
use crate::mesh::MeshError;
use crate::mesh::Origin;
use crate::mesh::PhysicalGroup;
use crate::mesh::Places;
use crate::mesh::{Cell, CellKind};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// What a reader hands to [`build`]: everything in file order, tags unresolved.
pub(crate) struct RawMesh<'a> {
    pub node_tags: Vec<u64>,
    pub coords: Vec<[f64; 3]>,
    pub element_tags: Vec<u64>,
    pub element_types: Vec<i32>,
    /// `element_nodes[offsets[e]..offsets[e + 1]]` are the node tags of element `e`.
    pub offsets: Vec<usize>,
    pub element_nodes: Vec<u64>,
    /// Index into `origins` of each element.
    pub element_origin: Vec<u32>,
    pub origins: Vec<Origin>,
    pub names: Vec<physical_names::PhysicalName>,
    pub places: Places<'a>,
}

impl RawMesh<'_> {
    fn node_place(&self, i: usize, coordinates: bool) -> String {
        match &self.places.node_lines {
            Some(l) => format!(
                "line {} (node {})",
                if coordinates { l[i].1 } else { l[i].0 },
                self.node_tags[i]
            ),
            None => format!("$Nodes, node {}", self.node_tags[i]),
        }
    }

    fn element_place(&self, e: usize) -> String {
        let tag = self.element_tags[e];
        match (self.places.element_line)(e, tag) {
            Some(l) => format!("line {l} (element {tag})"),
            None => format!("$Elements, element {tag}"),
        }
    }
}

/// Node tag → dense index, by a table when the tags are dense enough, else a hash map.
enum TagIndex {
    Dense { min: u64, index: Vec<usize> },
    Sparse(HashMap<u64, usize>),
}

impl TagIndex {
    fn new(tags: &[u64], rank: &[usize]) -> Self {
        let min = tags.iter().copied().min().unwrap_or(0);
        let max = tags.iter().copied().max().unwrap_or(0);
        let span = max - min;
        if span < 4 * tags.len() as u64 + 64 {
            let mut index = vec![usize::MAX; span as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                index[(t - min) as usize] = rank[i];
            }
            TagIndex::Dense { min, index }
        } else {
            TagIndex::Sparse(tags.iter().zip(rank).map(|(&t, &r)| (t, r)).collect())
        }
    }

    fn get(&self, tag: u64) -> Option<usize> {
        match self {
            TagIndex::Dense { min, index } => {
                let i = tag.checked_sub(*min)?;
                index
                    .get(usize::try_from(i).ok()?)
                    .copied()
                    .filter(|&r| r != usize::MAX)
            }
            TagIndex::Sparse(m) => m.get(&tag).copied(),
        }
    }
}

fn signed_area(points: &[[f64; 2]], nodes: &[usize]) -> f64 {
    let n = nodes.len();
    let mut a = 0.0;
    for i in 0..n {
        let p = points[nodes[i]];
        let q = points[nodes[(i + 1) % n]];
        a += p[0] * q[1] - q[0] * p[1];
    }
    0.5 * a
}

/// The smallest det J of a cell over its stiffness quadrature points and its nodes (a
/// pyramid's base corners instead of its apex), and where it is (reference coordinates).
fn min_det<const D: usize>(points: &[[f64; D]], cell: &Cell) -> (f64, [f64; 3]) {
    let mut at: Vec<[f64; 3]> = crate::mesh::element::stiffness_rule(cell)
        .iter()
        .map(|q| q.xi)
        .collect();
    match cell.kind() {
        // det J of a pyramid depends on (ξ, η)/(1 − ζ) only (docs/method.md §8.1): its values
        // at the base corners are also its limits at the apex along the four edges
        CellKind::Pyr5 => at.extend([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]),
        kind => at.extend(super::second_order::reference_nodes(kind)),
    }
    at.iter()
        .map(|&xi| (crate::mesh::element::shape_at(cell, points, xi).det_j, xi))
        .fold((f64::INFINITY, [0.0; 3]), |a, b| if b.0 < a.0 { b } else { a })
}

/// Turns what a reader found into a [`Mesh`] of dimension D, validating it.
pub(super) fn build_mesh<const D: usize>(path: &Path, raw: RawMesh<'_>) -> Result<Mesh<D>, MeshError> {
    let invalid = |place: String, detail: String| MeshError::Invalid {
        path: path.to_path_buf(),
        place,
        detail,
    };
    let n = raw.node_tags.len();
    if n == 0 {
        return Err(invalid(
            "$Nodes".into(),
            "the mesh has no nodes; mesh the geometry (gmsh -2 or -3) before saving".into(),
        ));
    }

    // Coordinates: finite; planar in 2D.
    for (i, c) in raw.coords.iter().enumerate() {
        if !c.iter().all(|v| v.is_finite()) {
            return Err(invalid(
                raw.node_place(i, true),
                format!(
                    "node {} has a non-finite coordinate ({}, {}, {}); the file is corrupt: re-export it",
                    raw.node_tags[i], c[0], c[1], c[2]
                ),
            ));
        }
    }
    if D == 2 {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for c in &raw.coords {
            for k in 0..2 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f64::MIN_POSITIVE);
        let z0 = raw.coords[0][2];
        if let Some(i) = raw
            .coords
            .iter()
            .position(|c| (c[2] - z0).abs() > 1e-9 * extent.max(z0.abs()))
        {
            return Err(invalid(
                raw.node_place(i, true),
                format!(
                    "node {} has z = {:?} but node {} has z = {:?}, and the file has no volume elements: a 2D mesh \
                     must lie in a plane z = const. If this is a volume mesh, its volume is in no physical group, so \
                     gmsh saved only the surfaces: add `Physical Volume(\"Omega\", 5) = {{...}};` to the .geo (or set \
                     Mesh.SaveAll = 1) and mesh again; if the volume was never meshed, mesh it (gmsh -3); for a 2D \
                     body mesh a plane surface (gmsh -2)",
                    raw.node_tags[i], raw.coords[i][2], raw.node_tags[0], z0
                ),
            ));
        }
    }

    // Dense numbering in ascending tag order; duplicate tags are an error.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&i| (raw.node_tags[i], i));
    for w in order.windows(2) {
        if raw.node_tags[w[0]] == raw.node_tags[w[1]] {
            return Err(invalid(
                raw.node_place(w[1], false),
                format!(
                    "node tag {} is defined twice (also at {}); node tags must be unique: re-export the mesh from gmsh \
                     (or renumber it: gmsh file.msh -renumber -save)",
                    raw.node_tags[w[1]],
                    raw.node_place(w[0], false)
                ),
            ));
        }
    }
    let mut rank = vec![0usize; n];
    for (r, &i) in order.iter().enumerate() {
        rank[i] = r;
    }
    let points: Vec<[f64; D]> = order
        .iter()
        .map(|&i| std::array::from_fn(|k| raw.coords[i][k]))
        .collect();
    let index = TagIndex::new(&raw.node_tags, &rank);

    // Elements.
    let mut groups: BTreeMap<(u8, i32), PhysicalGroup> = BTreeMap::new();
    fn group(groups: &mut BTreeMap<(u8, i32), PhysicalGroup>, dim: u8, tag: i32) -> &mut PhysicalGroup {
        groups.entry((dim, tag)).or_insert_with(|| PhysicalGroup {
            dim,
            tag,
            name: None,
            facets: Vec::new(),
            cells: Vec::new(),
            nodes: Vec::new(),
        })
    }
    let name_of = |dim: u8, tag: i32| {
        raw.names
            .iter()
            .find(|p| p.dim == dim && p.tag == tag)
            .map(|p| p.name.clone())
    };
    let mut cells = Vec::new();
    let mut cell_tags = Vec::new();
    let mut cell_element = Vec::new();
    let mut facet_elements = Vec::new();
    let mut nodes = [0usize; crate::mesh::element::MAX_NODES];
    for e in 0..raw.element_tags.len() {
        let ty = raw.element_types[e];
        let origin = &raw.origins[raw.element_origin[e] as usize];
        let info = element_type_info(ty);
        if !matches!(ty, 1 | 8 | 15) && CellKind::from_gmsh(ty).is_none() {
            let dim = info.map_or(2, |i| i.2);
            let group_text = if origin.physical.is_empty() {
                match origin.entity {
                    Some((d, t)) => {
                        format!("in no physical group (elementary entity of dim {d}, tag {t})")
                    }
                    None => "in no physical group".to_string(),
                }
            } else {
                let names: Vec<String> = origin
                    .physical
                    .iter()
                    .map(|&t| match name_of(dim, t) {
                        Some(n) => format!("\"{n}\" (tag {t})"),
                        None => format!("tag {t}"),
                    })
                    .collect();
                format!("in physical group {}", names.join(", "))
            };
            let (name, fix) = match info {
                Some((name, _, _)) if matches!(ty, 14 | 19) => (
                    name,
                    "hvi has no second-order pyramids (docs/method.md §19): mesh the volume with tetrahedra only, or \
                     with hexahedra and prisms only (no pyramids between them), or with -order 1",
                ),
                Some((name, _, _)) => (
                    name,
                    "hvi computes with first- and second-order elements: mesh with gmsh -order 1 or -order 2 \
                     (Mesh.ElementOrder = 1 or 2)",
                ),
                None => (
                    "an element type hvi does not know",
                    "hvi reads only points (15), 2-node lines (1), 3-node triangles (2), 4-node quadrangles (3), \
                     4-node tetrahedra (4), 8-node hexahedra (5), 6-node prisms (6), 5-node pyramids (7) and their \
                     second-order companions (8, 9, 10, 11, 12, 13, 16, 17, 18): mesh with gmsh -2 -order 1 or 2 (-3 \
                     for a volume)",
                ),
            };
            return Err(MeshError::UnsupportedElement {
                path: path.to_path_buf(),
                place: raw.element_place(e),
                element_type: ty,
                detail: format!(
                    "element {} is of type {ty} ({name}), {group_text}; {fix}",
                    raw.element_tags[e]
                ),
            });
        }
        let tags = &raw.element_nodes[raw.offsets[e]..raw.offsets[e + 1]];
        let want = info.map_or(0, |i| i.1);
        if tags.len() != want {
            return Err(MeshError::Syntax {
                path: path.to_path_buf(),
                place: raw.element_place(e),
                detail: format!(
                    "element {} of type {ty} has {} nodes, expected {want}",
                    raw.element_tags[e],
                    tags.len()
                ),
            });
        }
        for (k, &t) in tags.iter().enumerate() {
            nodes[k] = index.get(t).ok_or_else(|| {
                invalid(
                    raw.element_place(e),
                    format!(
                        "element {} refers to node {t}, which is not in $Nodes; the file is corrupt or was edited: \
                         re-export it from gmsh",
                        raw.element_tags[e]
                    ),
                )
            })?;
        }
        let nodes = &nodes[..tags.len()];
        for i in 0..nodes.len() {
            if nodes[i + 1..].contains(&nodes[i]) {
                return Err(invalid(
                    raw.element_place(e),
                    format!(
                        "element {} uses node {} twice: it is degenerate; re-mesh",
                        raw.element_tags[e], tags[i]
                    ),
                ));
            }
        }
        let element_dim = info.map_or(0, |i| i.2) as usize;
        match ty {
            15 => {
                for &p in &origin.physical {
                    group(&mut groups, 0, p).nodes.push(nodes[0]);
                }
            }
            _ if element_dim < D => {
                // lines (1, 8), triangles (2, 9) and quadrangles (3, 16, 10) by their corners
                let corners = match ty {
                    1 | 8 => 2,
                    2 | 9 => 3,
                    _ => 4,
                };
                facet_elements.push(e);
                for &p in &origin.physical {
                    group(&mut groups, element_dim as u8, p)
                        .facets
                        .push(Facet::with_corners(nodes, corners));
                }
            }
            _ => {
                let c = cells.len();
                let kind = CellKind::from_gmsh(ty).expect("the element types are checked above");
                cells.push(Cell::new(kind, nodes));
                cell_tags.push(raw.element_tags[e] as usize);
                cell_element.push(e);
                for &p in &origin.physical {
                    group(&mut groups, D as u8, p).cells.push(c);
                }
            }
        }
    }
    if cells.is_empty() {
        return Err(invalid(
            "$Elements".into(),
            "the mesh has no 2D elements (triangles or quadrangles). gmsh saves only elements of physical groups: \
             add Physical Surface(\"Omega\", 5) = {...}; to the .geo (or set Mesh.SaveAll = 1), and mesh in 2D (gmsh -2)"
                .into(),
        ));
    }
    let places = CellPlaces {
        path,
        raw: &raw,
        tags: &cell_tags,
        elements: &cell_element,
    };
    one_order(&places, &cells, &facet_elements)?;
    if D == 2 {
        let points2: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
        orient_2d(&places, &points2, &mut cells)?;
    } else {
        let points3: Vec<[f64; 3]> = points.iter().map(|p| [p[0], p[1], p[2]]).collect();
        orient_3d(&places, &points3, &mut cells)?;
    }

    // Every node must be in a cell, or the stiffness matrix is singular.
    let mut used = vec![false; n];
    for c in &cells {
        for &p in c.nodes() {
            used[p] = true;
        }
    }
    if let Some(r) = used.iter().position(|u| !u) {
        let i = order[r];
        return Err(invalid(
            raw.node_place(i, false),
            format!(
                "node {} at {} belongs to no {D}D element, so its displacement would be undetermined; remove \
                 unmeshed points from the geometry, or save without Mesh.SaveAll = 1",
                raw.node_tags[i],
                fmt_point(points[r])
            ),
        ));
    }

    for p in &raw.names {
        group(&mut groups, p.dim, p.tag).name = Some(p.name.clone());
    }
    Ok(Mesh {
        path: path.to_path_buf(),
        points,
        cells,
        cell_tags,
        groups: groups.into_values().collect(),
    })
}

/// All cells of one order and the boundary elements of the same: a mesh of first- and
/// second-order cells together does not conform (a midside node of one cell's edge is no node of
/// its neighbour), and a first-order line on a second-order body misses the midside nodes
/// (`facet_elements`: the file indices of the boundary elements).
fn one_order(at: &CellPlaces<'_, '_>, cells: &[Cell], facet_elements: &[usize]) -> Result<(), MeshError> {
    let order = cells[0].kind().order();
    if let Some(c) = cells.iter().position(|c| c.kind().order() != order) {
        return Err(at.invalid(
            c,
            format!(
                "element {} is a {} (order {}) while element {} is a {} (order {order}): hvi does not mix first- and \
                 second-order cells in one mesh (they do not conform); mesh the whole model with one -order",
                at.tags[c],
                cells[c].name(),
                cells[c].kind().order(),
                at.tags[0],
                cells[0].name()
            ),
        ));
    }
    let raw = at.raw;
    for &e in facet_elements {
        let ty = raw.element_types[e];
        if matches!(ty, 8 | 9 | 10 | 16) != (order == 2) {
            let origin = &raw.origins[raw.element_origin[e] as usize];
            let dim = element_type_info(ty).map_or(0, |i| i.2);
            let groups: Vec<String> = origin
                .physical
                .iter()
                .map(|&t| match raw.names.iter().find(|p| p.tag == t && p.dim == dim) {
                    Some(p) => format!("\"{}\" (tag {t})", p.name),
                    None => format!("tag {t}"),
                })
                .collect();
            return Err(MeshError::Invalid {
                path: at.path.to_path_buf(),
                place: raw.element_place(e),
                detail: format!(
                    "element {} is of type {ty} ({}), in physical group {}, on a mesh of order-{order} cells ({}s): its \
                     nodes do not match the cells' faces; mesh the whole model with one order (gmsh -order {order})",
                    raw.element_tags[e],
                    element_type_info(ty).map_or("?", |i| i.0),
                    groups.join(", "),
                    cells[0].name()
                ),
            });
        }
    }
    Ok(())
}

/// Where the cells of a file are, for the orientation checks' messages.
struct CellPlaces<'a, 'b> {
    pub(super) path: &'a Path,
    pub(super) raw: &'a RawMesh<'b>,
    /// gmsh element tag and file element index of each cell
    pub(super) tags: &'a [usize],
    pub(super) elements: &'a [usize],
}

impl CellPlaces<'_, '_> {
    /// An invalid-mesh error at cell c.
    fn invalid(&self, c: usize, detail: String) -> MeshError {
        MeshError::Invalid {
            path: self.path.to_path_buf(),
            place: self.raw.element_place(self.elements[c]),
            detail,
        }
    }
}

/// 2D orientation: all counter-clockwise, or all clockwise (then flipped), else an error; no
/// zero-area cells; convex quadrangles.
fn orient_2d(at: &CellPlaces<'_, '_>, points: &[[f64; 2]], cells: &mut [Cell]) -> Result<(), MeshError> {
    let cell_tags = at.tags;
    let areas: Vec<f64> = cells.iter().map(|c| signed_area(points, c.corners())).collect();
    for (c, &a) in areas.iter().enumerate() {
        let longest = longest_edge(points, &cells[c]);
        if a.abs() <= 1e-14 * longest * longest {
            return Err(at.invalid(
                c,
                format!("element {} has zero area (degenerate cell); re-mesh", cell_tags[c]),
            ));
        }
    }
    let clockwise = areas.iter().filter(|&&a| a < 0.0).count();
    if clockwise == cells.len() {
        for c in cells.iter_mut() {
            *c = c.flipped();
        }
    } else if clockwise > 0 {
        let c = areas.iter().position(|&a| a < 0.0).unwrap_or(0);
        return Err(at.invalid(
            c,
            format!(
                "element {} is inverted (clockwise, signed area {:e}) while other cells are counter-clockwise; \
                 {clockwise} of {} cells are clockwise. Fix the mesh: re-mesh, or make all surfaces in the .geo \
                 oriented alike (Reverse Surface{{...}};)",
                cell_tags[c],
                areas[c],
                cells.len()
            ),
        ));
    }
    for (c, cell) in cells.iter().enumerate() {
        if cell.kind().linear() == CellKind::Quad4 {
            let q = cell.corners();
            for i in 0..4 {
                let (p0, p1, p2) = (points[q[i]], points[q[(i + 1) % 4]], points[q[(i + 2) % 4]]);
                let cross = (p1[0] - p0[0]) * (p2[1] - p1[1]) - (p1[1] - p0[1]) * (p2[0] - p1[0]);
                if cross <= 1e-14 * areas[c].abs() {
                    return Err(at.invalid(
                        c,
                        format!(
                            "quadrangle {} is not convex (or self-intersecting) at its corner {}: the bilinear map is \
                             not invertible there; re-mesh (e.g. Mesh.RecombinationAlgorithm, or triangles)",
                            cell_tags[c],
                            fmt_point(p1)
                        ),
                    ));
                }
            }
        }
        if cell.kind().order() == 2 {
            // a curved cell can fold where its corners do not: det J at its nodes and points
            let (det, xi) = min_det(points, cell);
            let h = longest_edge(points, cell);
            if det <= 1e-12 * h * h {
                let s = crate::mesh::element::shape_at(cell, points, xi);
                return Err(at.invalid(
                    c,
                    format!(
                        "{} {} folds over itself (det J = {det:e} at {}): a midside node is too far off its edge's \
                         middle; re-mesh (finer near curved boundaries, or Mesh.HighOrderOptimize = 2)",
                        cell.name(),
                        cell_tags[c],
                        fmt_point(s.x)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// 3D orientation: det J > 0 at every stiffness quadrature point (and hexahedron corner) of
/// every cell, or < 0 everywhere in every cell (then all are flipped); else an error naming the
/// element and the point.
fn orient_3d(at: &CellPlaces<'_, '_>, points: &[[f64; 3]], cells: &mut [Cell]) -> Result<(), MeshError> {
    let cell_tags = at.tags;
    let check = |cells: &[Cell]| -> Vec<(f64, [f64; 3], f64)> {
        cells
            .iter()
            .map(|c| {
                let (det, xi) = min_det(points, c);
                let h = longest_edge(points, c);
                (det, xi, h)
            })
            .collect()
    };
    let mut dets = check(cells);
    let inverted = dets.iter().filter(|d| d.0 < 0.0).count();
    if inverted == cells.len() {
        for c in cells.iter_mut() {
            *c = c.flipped();
        }
        dets = check(cells);
    }
    for (c, &(det, xi, h)) in dets.iter().enumerate() {
        if det <= 1e-12 * h * h * h {
            let s = crate::mesh::element::shape_at(&cells[c], points, xi);
            return Err(at.invalid(
                c,
                format!(
                    "{} {} is {} (det J = {det:e} at {}); {} of {} cells are inverted. Re-mesh (check the \
                     orientation of extruded or transfinite volumes, or let gmsh mesh the volume with tetrahedra)",
                    cells[c].name(),
                    cell_tags[c],
                    if det < 0.0 { "inverted" } else { "degenerate" },
                    fmt_point(s.x),
                    dets.iter().filter(|d| d.0 <= 0.0).count(),
                    cells.len()
                ),
            ));
        }
    }
    Ok(())
}
