//! A built-in mesher for the rectangle (0, lx) × (0, ly), with the physical groups of
//! `meshes/rectangle.geo`, so studies and tests need no gmsh.
//!
//! Groups: `Gamma1` (dim 1, tag 1, x = 0), `Gamma2` (dim 1, tag 2, x = lx and y = ly),
//! `Gamma3` (dim 1, tag 3, y = 0), `Gamma2_top` (dim 1, tag 4, y = ly only; its facets are also
//! in Gamma2) and `Omega` (dim 2, tag 5, every cell).

use super::second_order::corner_support;
use super::{Cell, Facet, Mesh, PhysicalGroup};
use std::collections::HashMap;
use std::path::PathBuf;

/// The cell shape of [`rectangle`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellShape {
    /// Bilinear quadrilaterals (Q1), one per grid square.
    Quad,
    /// Linear triangles (P1): each grid square split along its diagonal from lower right to
    /// upper left into two counter-clockwise triangles (as gmsh's transfinite meshes of
    /// `rectangle.geo` do).
    Tri,
}

/// A structured mesh of (0, lx) × (0, ly) with `nx` × `ny` grid squares.
///
/// Point `i + j (nx + 1)` is at `(i lx / nx, j ly / ny)`; cells run row by row from the
/// bottom left, counter-clockwise; `cell_tags` are 1, 2, … like gmsh's. The path is
/// `<rectangle NXxNY>`.
///
/// # Panics
/// If `nx` or `ny` is 0, or `lx` or `ly` is not positive and finite (a programming error, not
/// bad input).
pub fn rectangle(lx: f64, ly: f64, nx: usize, ny: usize, kind: CellShape) -> Mesh<2> {
    assert!(
        nx > 0 && ny > 0,
        "rectangle: nx and ny must be positive (got {nx} x {ny})"
    );
    assert!(
        lx > 0.0 && ly > 0.0 && lx.is_finite() && ly.is_finite(),
        "rectangle: lx, ly must be positive (got {lx}, {ly})"
    );
    let id = |i: usize, j: usize| i + j * (nx + 1);
    let mut points = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            points.push([lx * i as f64 / nx as f64, ly * j as f64 / ny as f64]);
        }
    }
    let mut cells = Vec::with_capacity(nx * ny * if kind == CellShape::Tri { 2 } else { 1 });
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            match kind {
                CellShape::Quad => cells.push(Cell::Quad4([a, b, c, d])),
                CellShape::Tri => {
                    cells.push(Cell::Tri3([a, b, d]));
                    cells.push(Cell::Tri3([d, b, c]));
                }
            }
        }
    }
    let cell_tags = (1..=cells.len()).collect();
    // Facets oriented counter-clockwise around the body.
    let bottom: Vec<[usize; 2]> = (0..nx).map(|i| [id(i, 0), id(i + 1, 0)]).collect();
    let right: Vec<[usize; 2]> = (0..ny).map(|j| [id(nx, j), id(nx, j + 1)]).collect();
    let top: Vec<[usize; 2]> = (0..nx).rev().map(|i| [id(i + 1, ny), id(i, ny)]).collect();
    let left: Vec<[usize; 2]> = (0..ny).rev().map(|j| [id(0, j + 1), id(0, j)]).collect();
    let curve = |tag: i32, name: &str, facets: Vec<[usize; 2]>| {
        boundary_group(1, tag, name, facets.into_iter().map(Facet::from).collect())
    };
    let groups = vec![
        curve(1, "Gamma1", left),
        curve(2, "Gamma2", right.iter().chain(&top).copied().collect()),
        curve(3, "Gamma3", bottom),
        curve(4, "Gamma2_top", top),
        body_group(2, cells.len()),
    ];
    Mesh {
        path: PathBuf::from(format!("<rectangle {nx}x{ny}>")),
        points,
        cells,
        cell_tags,
        groups,
    }
}

/// The cell shape of [`block`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SolidShape {
    /// Trilinear hexahedra (Q1), one per grid box.
    Hex,
    /// Linear tetrahedra (P1): each grid box split into six around its diagonal from the
    /// corner (0, 0, 0) to (1, 1, 1) (conforming across boxes).
    Tet,
    /// Linear prisms (wedges, extruded triangles): each grid box split into two along its
    /// diagonal from (0, 0) to (1, 1) in x, y, extruded in z.
    Prism,
    /// Linear pyramids: each grid box split into six, one on each of its faces, with their
    /// apex at a node added at the box's centre.
    Pyramid,
    /// Hexahedra and pyramids alternately, like a chessboard: the boxes with i + j + k even are
    /// hexahedra, the others split into six pyramids as [`SolidShape::Pyramid`] (each hexahedron's
    /// faces against pyramids' bases).
    HexPyramid,
}

/// A structured mesh of the box (0, lx) × (0, ly) × (0, lz) with `nx` × `ny` × `nz` grid boxes and
/// the groups of `meshes/slab.geo`: `Gamma1` (dim 2, tag 1, x = 0), `Gamma2` (tag 2, x = lx and
/// y = ly), `Gamma3` (tag 3, y = 0), `Gamma2_top` (tag 4, y = ly only), `Sides` (tag 6, z = 0 and
/// z = lz) and `Omega` (dim 3, tag 5). Point `i + (nx + 1)(j + (ny + 1) k)` is at
/// `(i lx / nx, j ly / ny, k lz / nz)`; the pyramids' box centres follow the grid's points. The
/// path is `<block NXxNYxNZ>`.
///
/// # Panics
/// If a count is 0 or a length is not positive and finite (a programming error, not bad input).
pub fn block(l: [f64; 3], n: [usize; 3], kind: SolidShape) -> Mesh<3> {
    assert!(n.iter().all(|&v| v > 0), "block: counts must be positive (got {n:?})");
    assert!(
        l.iter().all(|&v| v > 0.0 && v.is_finite()),
        "block: lengths must be positive (got {l:?})"
    );
    let [nx, ny, nz] = n;
    let id = |i: usize, j: usize, k: usize| i + (nx + 1) * (j + (ny + 1) * k);
    let mut points = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                points.push([
                    l[0] * i as f64 / nx as f64,
                    l[1] * j as f64 / ny as f64,
                    l[2] * k as f64 / nz as f64,
                ]);
            }
        }
    }
    let mut cells = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let c = [
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ];
                let pyramids = match kind {
                    SolidShape::Pyramid => true,
                    SolidShape::HexPyramid => (i + j + k) % 2 == 1,
                    _ => false,
                };
                match kind {
                    _ if pyramids => {
                        // the apex at the box's centre, each base a box face turned so that its
                        // right-hand normal points into the box, towards the apex
                        let apex = points.len();
                        let centre = |d: usize| 0.5 * (points[c[0]][d] + points[c[6]][d]);
                        points.push([centre(0), centre(1), centre(2)]);
                        for f in [
                            [0, 1, 2, 3],
                            [4, 7, 6, 5],
                            [0, 4, 5, 1],
                            [2, 6, 7, 3],
                            [0, 3, 7, 4],
                            [1, 5, 6, 2],
                        ] {
                            cells.push(Cell::Pyr5([c[f[0]], c[f[1]], c[f[2]], c[f[3]], apex]));
                        }
                    }
                    // a whole box (also HexPyramid's boxes with i + j + k even)
                    SolidShape::Hex | SolidShape::HexPyramid | SolidShape::Pyramid => cells.push(Cell::Hex8(c)),
                    SolidShape::Prism => {
                        cells.push(Cell::Prism6([c[0], c[1], c[2], c[4], c[5], c[6]]));
                        cells.push(Cell::Prism6([c[0], c[2], c[3], c[4], c[6], c[7]]));
                    }
                    SolidShape::Tet => {
                        // Six tetrahedra sharing the diagonal c0–c6 (Kuhn's split), each positive.
                        for [a, b] in [[1, 2], [2, 3], [3, 7], [7, 4], [4, 5], [5, 1]] {
                            let t = Cell::Tet4([c[0], c[a], c[b], c[6]]);
                            let (p0, p1, p2, p3) = (points[c[0]], points[c[a]], points[c[b]], points[c[6]]);
                            let d = |p: [f64; 3], q: [f64; 3]| [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                            let (u, v, w) = (d(p0, p1), d(p0, p2), d(p0, p3));
                            let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                                + u[2] * (v[0] * w[1] - v[1] * w[0]);
                            cells.push(if det > 0.0 { t } else { t.flipped() });
                        }
                    }
                }
            }
        }
    }
    let cell_tags = (1..=cells.len()).collect();
    // Boundary faces, each oriented outward (counter-clockwise seen from outside).
    let faces = |fixed: usize, at_max: bool| -> Vec<Facet> {
        let mut out = Vec::new();
        let (a, b) = match fixed {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        for q in 0..n[b] {
            for p in 0..n[a] {
                let corner = |dp: usize, dq: usize| {
                    let mut ijk = [0usize; 3];
                    ijk[fixed] = if at_max { n[fixed] } else { 0 };
                    ijk[a] = p + dp;
                    ijk[b] = q + dq;
                    id(ijk[0], ijk[1], ijk[2])
                };
                // (a, b, fixed) is a right-handed cyclic triple: a × b points along +fixed.
                let ccw = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                match kind {
                    // hexahedra and pyramids: the boxes' faces
                    SolidShape::Hex | SolidShape::Pyramid | SolidShape::HexPyramid => {
                        out.push(Facet::from(if at_max { ccw } else { [ccw[0], ccw[3], ccw[2], ccw[1]] }))
                    }
                    // prisms: quadrangles on the sides, the triangles of the split at z = const
                    SolidShape::Prism if fixed != 2 => {
                        out.push(Facet::from(if at_max { ccw } else { [ccw[0], ccw[3], ccw[2], ccw[1]] }))
                    }
                    SolidShape::Tet | SolidShape::Prism => {
                        // The faces of the six tetrahedra on a box face: split along the diagonal
                        // through the box's corner nearest (0, 0, 0) or farthest from it.
                        // (every box face holds exactly one end of the diagonal c0–c6: ccw[0]–ccw[2])
                        for t in [[ccw[0], ccw[1], ccw[2]], [ccw[0], ccw[2], ccw[3]]] {
                            out.push(Facet::from(if at_max { t } else { [t[0], t[2], t[1]] }));
                        }
                    }
                }
            }
        }
        out
    };
    let (x0, x1, y0, y1, z0, z1) = (
        faces(0, false),
        faces(0, true),
        faces(1, false),
        faces(1, true),
        faces(2, false),
        faces(2, true),
    );
    let surface = |tag: i32, name: &str, facets: Vec<Facet>| boundary_group(2, tag, name, facets);
    let groups = vec![
        surface(1, "Gamma1", x0),
        surface(2, "Gamma2", x1.iter().chain(&y1).copied().collect()),
        surface(3, "Gamma3", y0),
        surface(4, "Gamma2_top", y1),
        body_group(3, cells.len()),
        surface(6, "Sides", z0.into_iter().chain(z1).collect()),
    ];
    Mesh {
        path: PathBuf::from(format!("<block {nx}x{ny}x{nz}>")),
        points,
        cells,
        cell_tags,
        groups,
    }
}

/// Two bodies in one mesh (docs/method.md §18): `upper` lifted by `lift` along y onto `lower`
/// (both from this module, sharing no nodes): their groups Gamma3, Gamma1, Gamma2_top (and in 3D
/// Sides) become LowerBottom, LowerLeft, LowerTop, LowerSides, UpperBottom, …, each body's cells
/// the group Lower (tag 21) or Upper (tag 22).
pub fn stack<const D: usize>(lower: Mesh<D>, upper: Mesh<D>, lift: f64) -> Mesh<D> {
    let offset = lower.points.len();
    let renamed = |m: &Mesh<D>, shift: usize, prefix: &str, tag: i32| -> Vec<PhysicalGroup> {
        [
            ("Gamma3", "Bottom"),
            ("Gamma1", "Left"),
            ("Gamma2_top", "Top"),
            ("Sides", "Sides"),
        ]
        .iter()
        .enumerate()
        .filter_map(|(k, (old, new))| {
            let g = m.groups.iter().find(|g| g.name.as_deref() == Some(*old))?;
            Some(PhysicalGroup {
                dim: g.dim,
                tag: tag + k as i32,
                name: Some(format!("{prefix}{new}")),
                facets: g
                    .facets
                    .iter()
                    .map(|f| Facet::from_slice(&f.nodes().iter().map(|p| p + shift).collect::<Vec<_>>()))
                    .collect(),
                cells: vec![],
                nodes: vec![],
            })
        })
        .collect()
    };
    let mut points = lower.points.clone();
    points.extend(upper.points.iter().map(|x| {
        let mut y = *x;
        y[1] += lift;
        y
    }));
    let mut cells = lower.cells.clone();
    cells.extend(upper.cells.iter().map(|c| c.renumbered(|p| p + offset)));
    let body = |tag: i32, name: &str, cells: Vec<usize>| PhysicalGroup {
        dim: D as u8,
        tag,
        name: Some(name.into()),
        facets: vec![],
        cells,
        nodes: vec![],
    };
    let mut groups = renamed(&lower, 0, "Lower", 11);
    groups.extend(renamed(&upper, offset, "Upper", 15));
    groups.push(body(21, "Lower", (0..lower.cells.len()).collect()));
    groups.push(body(22, "Upper", (lower.cells.len()..cells.len()).collect()));
    Mesh {
        path: PathBuf::from("<stacked blocks>"),
        points,
        cell_tags: (1..=cells.len()).collect(),
        cells,
        groups,
    }
}

/// The second-order mesh on the cells of a first-order `mesh` (docs/method.md §19): a node at
/// the midpoint of every edge, and with `complete` at the centre of every quadrangular face and
/// hexahedron (9-node quadrangles, 27-node hexahedra, 18-node prisms; else 8, 20 and 15 nodes).
/// The geometry stays the first-order one (straight edges); a curved map can move the points
/// afterwards. Boundary groups get their facets' second-order nodes.
///
/// # Panics
/// If the mesh is already of second order or has pyramids (a programming error).
pub fn elevate<const D: usize>(mesh: &Mesh<D>, complete: bool) -> Mesh<D> {
    let mut points = mesh.points.clone();
    let mut added: HashMap<Vec<usize>, usize> = HashMap::new();
    let mut node_at = |corners: &[usize]| -> usize {
        if let [p] = corners {
            return *p;
        }
        let mut key = corners.to_vec();
        key.sort_unstable();
        *added.entry(key).or_insert_with(|| {
            points.push(std::array::from_fn(|k| {
                corners.iter().map(|&p| points[p][k]).sum::<f64>() / corners.len() as f64
            }));
            points.len() - 1
        })
    };
    let cells: Vec<Cell> = mesh
        .cells
        .iter()
        .map(|c| {
            let kind = c
                .kind()
                .second_order(complete)
                .expect("a first-order cell other than a pyramid");
            let n = c.nodes();
            let nodes: Vec<usize> = (0..kind.nodes())
                .map(|a| node_at(&corner_support(kind, a).iter().map(|&i| n[i]).collect::<Vec<_>>()))
                .collect();
            Cell::new(kind, &nodes)
        })
        .collect();
    let groups = mesh
        .groups
        .iter()
        .map(|g| {
            let facets = g
                .facets
                .iter()
                .map(|f| {
                    let c = f.nodes();
                    let m = c.len();
                    let mut nodes = c.to_vec();
                    for i in 0..if m == 2 { 1 } else { m } {
                        nodes.push(node_at(&[c[i], c[(i + 1) % m]]));
                    }
                    if m == 4 && complete {
                        nodes.push(node_at(c));
                    }
                    Facet::with_corners(&nodes, m)
                })
                .collect();
            PhysicalGroup { facets, ..g.clone() }
        })
        .collect();
    Mesh {
        path: PathBuf::from(format!("{} (second order)", mesh.path.display())),
        points,
        cells,
        cell_tags: mesh.cell_tags.clone(),
        groups,
    }
}

/// A named boundary group of dimension `dim` (tags as in the `.geo` files).
fn boundary_group(dim: u8, tag: i32, name: &str, facets: Vec<Facet>) -> PhysicalGroup {
    PhysicalGroup {
        dim,
        tag,
        name: Some(name.to_string()),
        facets,
        cells: Vec::new(),
        nodes: Vec::new(),
    }
}

/// `Omega` (tag 5): every cell.
fn body_group(dim: u8, cells: usize) -> PhysicalGroup {
    PhysicalGroup {
        dim,
        tag: 5,
        name: Some("Omega".to_string()),
        facets: Vec::new(),
        cells: (0..cells).collect(),
        nodes: Vec::new(),
    }
}
