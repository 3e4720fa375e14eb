//! The mesh: gmsh MSH files (4.1 ASCII and binary, 2.2 ASCII) and built-in structured meshers,
//! in two or three dimensions (docs/method.md §2, §8).
//!
//! [`read_msh`] reads a file into an [`AnyMesh`]: a [`Mesh<2>`] when the file has only points,
//! lines, triangles and quadrangles in a plane z = const, a [`Mesh<3>`] when it has tetrahedra or
//! hexahedra. Points are dense and 0-based (in ascending order of the gmsh node tags), every cell of
//! the body's dimension is a positively oriented [`Cell`], and the physical groups keep their
//! `$PhysicalNames`. A scene refers to a group by name or tag ([`GroupSelector`]);
//! [`Mesh::boundary`] turns a group of facets (curves in 2D, surfaces in 3D) into an oriented
//! [`BoundaryPart`] with outward normals and nodal quadrature weights.
//!
//! Only first-order elements are read: points (gmsh type 15), 2-node lines (1), 3-node
//! triangles (2), 4-node quadrilaterals (3), 4-node tetrahedra (4) and 8-node hexahedra (5);
//! anything else is an error that says how to re-mesh. Every problem found is reported with the
//! file, the place (line number for ASCII files, node or element tag) and what to do: hvi never
//! panics on a bad file and never allocates in proportion to a count in a header that the file
//! is too short to hold.
//!
//! Cells are not reordered or repaired, with one exception: if *every* cell of the file is
//! inverted (a 2D surface whose normal points to −z, a 3D mesh written with the other
//! handedness), all cells are flipped. A mesh with only some inverted cells is an error naming
//! the first of them.

mod cell;
pub mod element;
mod error;
mod group;
mod msh22;
mod msh41;
mod physical_names;
pub mod quadrature;
pub mod structured;
mod topology;

pub use cell::{Cell, Facet};
pub use error::MeshError;
pub use group::GroupSelector;
pub(crate) use topology::facet_integrals;
pub use topology::BoundaryPart;

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A mesh of a body in D = 2 or 3 dimensions with its physical groups.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh<const D: usize = 2> {
    /// The file read (or a label such as `<rectangle 16x8>` for a generated mesh).
    pub path: PathBuf,
    /// Node coordinates, dense and 0-based (the file's node tags in ascending order); a 2D
    /// file's constant z is dropped.
    pub points: Vec<[f64; D]>,
    /// Every D-dimensional element of the file, positively oriented, in file order.
    pub cells: Vec<Cell>,
    /// The gmsh element tag of each cell, for messages.
    pub cell_tags: Vec<usize>,
    /// The physical groups, sorted by (dimension, tag).
    pub groups: Vec<PhysicalGroup>,
}

/// A mesh of either dimension, as read from a file: the caller dispatches once on it.
#[derive(Clone, Debug, PartialEq)]
pub enum AnyMesh {
    Two(Mesh<2>),
    Three(Mesh<3>),
}

impl AnyMesh {
    /// The spatial dimension.
    pub fn dim(&self) -> usize {
        match self {
            AnyMesh::Two(_) => 2,
            AnyMesh::Three(_) => 3,
        }
    }
}

/// A physical group: a `Physical Point` (dim 0), `Physical Curve` (dim 1), `Physical Surface`
/// (dim 2) or `Physical Volume` (dim 3) of the `.geo`.
#[derive(Clone, Debug, PartialEq)]
pub struct PhysicalGroup {
    pub dim: u8,
    pub tag: i32,
    /// The name given in `$PhysicalNames`, if any.
    pub name: Option<String>,
    /// Groups of a dimension below the body's: the group's line, triangle or quadrangle
    /// elements (node indices, as written in the file).
    pub facets: Vec<Facet>,
    /// Groups of the body's dimension: indices into [`Mesh::cells`].
    pub cells: Vec<usize>,
    /// Dim 0: the group's point elements (node indices).
    pub nodes: Vec<usize>,
}

impl PhysicalGroup {
    /// How messages name the group: `Gamma3 (tag 3)`, or `tag 7` for an unnamed group.
    pub fn label(&self) -> String {
        match &self.name {
            Some(n) => format!("{n} (tag {})", self.tag),
            None => format!("tag {}", self.tag),
        }
    }

    fn matches(&self, sel: &GroupSelector) -> bool {
        match sel {
            GroupSelector::Tag(t) => self.tag == *t,
            GroupSelector::Name(n) => self.name.as_deref() == Some(n.as_str()),
        }
    }
}

/// Reads a gmsh MSH file: 4.1 (ASCII or binary) or 2.2 (ASCII), chosen from `$MeshFormat`; the
/// dimension from its elements.
pub fn read_msh(path: &Path) -> Result<AnyMesh, MeshError> {
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_msh(path, &bytes)
}

/// Reads a gmsh MSH file that must hold a D-dimensional body; a file of the other dimension is
/// an error that says so.
pub fn read_mesh<const D: usize>(path: &Path) -> Result<Mesh<D>, MeshError> {
    into_dim(read_msh(path)?, path)
}

/// Parses the bytes of an MSH file already in memory; `path` is used in messages only.
pub fn parse_msh(path: &Path, bytes: &[u8]) -> Result<AnyMesh, MeshError> {
    let header = Header::parse(path, bytes)?;
    let raw = match header.version {
        Version::V2 => msh22::parse(path, bytes, header.body)?,
        Version::V41 => msh41::parse(path, bytes, &header)?,
    };
    if raw.element_types.iter().any(|&t| matches!(t, 4 | 5)) {
        build::<3>(path, raw).map(AnyMesh::Three)
    } else {
        build::<2>(path, raw).map(AnyMesh::Two)
    }
}

/// [`parse_msh`] for a body of dimension D.
pub fn parse_mesh<const D: usize>(path: &Path, bytes: &[u8]) -> Result<Mesh<D>, MeshError> {
    into_dim(parse_msh(path, bytes)?, path)
}

fn into_dim<const D: usize>(mesh: AnyMesh, path: &Path) -> Result<Mesh<D>, MeshError> {
    let got = mesh.dim();
    let any: Box<dyn std::any::Any> = match mesh {
        AnyMesh::Two(m) => Box::new(m),
        AnyMesh::Three(m) => Box::new(m),
    };
    any.downcast::<Mesh<D>>().map(|m| *m).map_err(|_| MeshError::Invalid {
        path: path.to_path_buf(),
        place: "$Elements".into(),
        detail: format!("this is a {got}D mesh, but a {D}D mesh is needed here"),
    })
}

impl<const D: usize> Mesh<D> {
    /// The physical group of dimension `dim` that `sel` names. A name that is not found but
    /// reads as an integer is also tried as a tag. If there is none, the error lists every
    /// group the mesh has.
    pub fn group(&self, sel: &GroupSelector, dim: u8) -> Result<&PhysicalGroup, MeshError> {
        if let Some(g) = self.groups.iter().find(|g| g.dim == dim && g.matches(sel)) {
            return Ok(g);
        }
        if let GroupSelector::Name(n) = sel {
            if let Ok(t) = n.trim().parse::<i32>() {
                if let Some(g) = self.groups.iter().find(|g| g.dim == dim && g.tag == t) {
                    return Ok(g);
                }
            }
        }
        Err(self.group_not_found(sel, dim))
    }

    fn group_not_found(&self, sel: &GroupSelector, dim: u8) -> MeshError {
        let available = if self.groups.is_empty() {
            "no physical groups at all: define them in the .geo (Physical Curve(\"Gamma3\", 3) = {...}; \
             Physical Surface(\"Omega\", 5) = {...};) and mesh again"
                .to_string()
        } else {
            let mut s = String::from("these groups: ");
            for (i, g) in self.groups.iter().enumerate() {
                if i > 0 {
                    s.push_str(", ");
                }
                let _ = write!(s, "dim {} tag {}", g.dim, g.tag);
                if let Some(n) = &g.name {
                    let _ = write!(s, " \"{n}\"");
                }
            }
            s
        };
        MeshError::GroupNotFound {
            path: self.path.clone(),
            wanted: sel.to_string(),
            dim,
            available,
        }
    }

    /// A group of facets (dimension D − 1) as an oriented boundary part (see [`BoundaryPart`]).
    /// Every facet of the group must be a facet of exactly one cell.
    pub fn boundary(&self, sel: &GroupSelector) -> Result<BoundaryPart<D>, MeshError> {
        let group = self.group(sel, (D - 1) as u8)?;
        topology::boundary_part(self, group)
    }

    /// The sorted, unique node indices of a group: of dimension D − 1 (facets) if there is one
    /// of that name or tag, else of a lower dimension (curves of a 3D mesh, points).
    pub fn group_nodes(&self, sel: &GroupSelector) -> Result<Vec<usize>, MeshError> {
        let mut first_error = None;
        for dim in (0..D as u8).rev() {
            match self.group(sel, dim) {
                Ok(g) => {
                    let mut nodes: Vec<usize> = if dim == 0 {
                        g.nodes.clone()
                    } else {
                        g.facets.iter().flat_map(|f| f.nodes().to_vec()).collect()
                    };
                    nodes.sort_unstable();
                    nodes.dedup();
                    return Ok(nodes);
                }
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        Err(first_error.expect("D ≥ 1"))
    }

    /// The measure of the body (area in 2D, volume in 3D), by the stiffness quadrature of each
    /// cell (exact for straight-sided simplices, parallelograms and parallelepipeds).
    pub fn measure(&self) -> f64 {
        self.cells
            .iter()
            .map(|c| {
                crate::mesh::element::stiffness_rule(c)
                    .iter()
                    .map(|q| q.weight * crate::mesh::element::shape_at(c, &self.points, q.xi).det_j)
                    .sum::<f64>()
            })
            .sum()
    }

    /// (min, max) over the cells of the longest cell edge: the mesh size h. (0, 0) if there
    /// are no cells.
    pub fn cell_size(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = 0.0_f64;
        for c in &self.cells {
            let longest = longest_edge(&self.points, c);
            lo = lo.min(longest);
            hi = hi.max(longest);
        }
        if self.cells.is_empty() {
            (0.0, 0.0)
        } else {
            (lo, hi)
        }
    }
}

fn distance<const D: usize>(p: &[f64; D], q: &[f64; D]) -> f64 {
    (0..D).map(|k| (q[k] - p[k]).powi(2)).sum::<f64>().sqrt()
}

fn longest_edge<const D: usize>(points: &[[f64; D]], c: &Cell) -> f64 {
    c.edges()
        .iter()
        .map(|&[a, b]| distance(&points[a], &points[b]))
        .fold(0.0_f64, f64::max)
}

// ---------------------------------------------------------------------------------------------
// Shared by the readers: the $MeshFormat header, line/token scanning, the element type table,
// and the raw data a reader hands to `build`.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Version {
    V2,
    V41,
}

/// The `$MeshFormat` section.
#[derive(Clone, Debug)]
pub(crate) struct Header {
    pub version: Version,
    pub binary: bool,
    /// sizeof(size_t) in binary files.
    pub data_size: usize,
    pub little_endian: bool,
    /// Byte offset just after `$EndMeshFormat`.
    pub body: usize,
}

impl Header {
    fn parse(path: &Path, bytes: &[u8]) -> Result<Header, MeshError> {
        let unsupported = |detail: String| MeshError::UnsupportedFormat {
            path: path.to_path_buf(),
            detail,
        };
        let syntax = |line: usize, detail: String| MeshError::Syntax {
            path: path.to_path_buf(),
            place: format!("line {line} ($MeshFormat)"),
            detail,
        };
        let mut start = 0;
        if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
            start = 3;
        }
        let mut lines = Lines::new(bytes, start);
        let first = lines.next_nonblank();
        match first {
            Some((_, l)) if trim(l) == b"$MeshFormat" => {}
            Some((_, l)) if trim(l).starts_with(b"$NOD") => {
                return Err(unsupported(
                    "this is an MSH 1 file ($NOD), which hvi does not read; re-export it as MSH 4.1: \
                     gmsh file.msh -save -format msh41 -o new.msh"
                        .into(),
                ))
            }
            _ => {
                return Err(unsupported(
                    "not a gmsh MSH file: it does not start with $MeshFormat; mesh the geometry with \
                     gmsh (gmsh -2 body.geo -format msh41) and give the .msh file"
                        .into(),
                ))
            }
        }
        let Some((line, l)) = lines.next_line() else {
            return Err(syntax(2, "the file ends inside $MeshFormat: it is truncated".into()));
        };
        let text = String::from_utf8_lossy(l);
        let tokens: Vec<&str> = text.split_whitespace().collect();
        if tokens.len() < 3 {
            return Err(syntax(
                line,
                format!(
                    "expected \"version file-type data-size\" (e.g. \"4.1 0 8\"), found \"{}\"",
                    text.trim()
                ),
            ));
        }
        let version = match tokens[0] {
            "4.1" => Version::V41,
            "2" | "2.0" | "2.1" | "2.2" => Version::V2,
            "4" | "4.0" => {
                return Err(unsupported(
                    "MSH version 4.0 is not supported (hvi reads 4.1 and 2.2); re-export with gmsh -format msh41 \
                     (or Mesh.MshFileVersion = 4.1 in the .geo)"
                        .into(),
                ))
            }
            v => {
                return Err(unsupported(format!(
                    "MSH version {v} is not supported (hvi reads 4.1 ASCII/binary and 2.2 ASCII); \
                     re-export with gmsh -format msh41"
                )))
            }
        };
        let binary = match tokens[1] {
            "0" => false,
            "1" => true,
            t => {
                return Err(syntax(
                    line,
                    format!("file type must be 0 (ASCII) or 1 (binary), found \"{t}\""),
                ))
            }
        };
        let data_size: usize = match tokens[2].parse() {
            Ok(d) => d,
            Err(_) => {
                return Err(syntax(
                    line,
                    format!("data size must be an integer, found \"{}\"", tokens[2]),
                ))
            }
        };
        if binary && version == Version::V2 {
            return Err(unsupported(format!(
                "binary MSH {} is not supported (hvi reads 2.2 only as ASCII); re-export as MSH 4.1: \
                 gmsh file.msh -save -format msh41 -o new.msh (add -bin for binary 4.1)",
                tokens[0]
            )));
        }
        let mut little_endian = true;
        let mut pos = lines.pos;
        if binary {
            if data_size != 4 && data_size != 8 {
                return Err(syntax(
                    line,
                    format!("binary data size {data_size} is not supported (gmsh writes 8)"),
                ));
            }
            let Some(one) = bytes.get(pos..pos + 4) else {
                return Err(syntax(
                    line + 1,
                    "the file ends inside $MeshFormat: it is truncated".into(),
                ));
            };
            let one: [u8; 4] = [one[0], one[1], one[2], one[3]];
            if i32::from_le_bytes(one) == 1 {
                little_endian = true;
            } else if i32::from_be_bytes(one) == 1 {
                little_endian = false;
            } else {
                return Err(syntax(
                    line + 1,
                    "binary endianness marker (the integer 1) not found after the version line".into(),
                ));
            }
            pos += 4;
            while pos < bytes.len() && (bytes[pos] == b'\n' || bytes[pos] == b'\r') {
                pos += 1;
            }
        }
        let mut lines = Lines::new(bytes, pos);
        match lines.next_nonblank() {
            Some((_, l)) if trim(l) == b"$EndMeshFormat" => {}
            Some((n, l)) => {
                return Err(syntax(
                    n,
                    format!(
                        "expected $EndMeshFormat, found \"{}\"",
                        String::from_utf8_lossy(trim(l))
                    ),
                ))
            }
            None => {
                return Err(syntax(
                    line + 1,
                    "the file ends inside $MeshFormat: it is truncated".into(),
                ))
            }
        }
        Ok(Header {
            version,
            binary,
            data_size,
            little_endian,
            body: lines.pos,
        })
    }
}

/// 1-based line number of byte `offset`.
pub(crate) fn line_of(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset.min(bytes.len())].iter().filter(|&&b| b == b'\n').count()
}

pub(crate) fn trim(l: &[u8]) -> &[u8] {
    let s = l.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(l.len());
    let e = l.iter().rposition(|b| !b.is_ascii_whitespace()).map_or(s, |e| e + 1);
    &l[s..e.max(s)]
}

/// Line-by-line reading with 1-based line numbers.
pub(crate) struct Lines<'a> {
    bytes: &'a [u8],
    /// Offset of the next line.
    pub pos: usize,
    /// Number of the next line.
    pub line: usize,
}

impl<'a> Lines<'a> {
    pub fn new(bytes: &'a [u8], pos: usize) -> Self {
        Lines {
            bytes,
            pos,
            line: line_of(bytes, pos),
        }
    }

    /// The next line (without its line break) and its number.
    pub fn next_line(&mut self) -> Option<(usize, &'a [u8])> {
        if self.pos >= self.bytes.len() {
            return None;
        }
        let rest = &self.bytes[self.pos..];
        let len = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        let mut l = &rest[..len];
        if l.last() == Some(&b'\r') {
            l = &l[..l.len() - 1];
        }
        self.pos += (len + 1).min(rest.len());
        let n = self.line;
        self.line += 1;
        Some((n, l))
    }

    /// The next line that is not blank.
    pub fn next_nonblank(&mut self) -> Option<(usize, &'a [u8])> {
        loop {
            let (n, l) = self.next_line()?;
            if !trim(l).is_empty() {
                return Some((n, l));
            }
        }
    }

    /// Bytes left from the next line on.
    pub fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }
}

/// Name, node count and dimension of a gmsh element type (points, lines, triangles, quadrangles
/// up to order 10, the common 3D ones; `None` if unknown: the MSH 4.1 reader cannot read a block of
/// an unknown type).
pub(crate) fn element_type_info(t: i32) -> Option<(&'static str, usize, u8)> {
    Some(match t {
        1 => ("2-node line", 2, 1),
        2 => ("3-node triangle", 3, 2),
        3 => ("4-node quadrangle", 4, 2),
        4 => ("4-node tetrahedron", 4, 3),
        5 => ("8-node hexahedron", 8, 3),
        6 => ("6-node prism", 6, 3),
        7 => ("5-node pyramid", 5, 3),
        8 => ("3-node second-order line", 3, 1),
        9 => ("6-node second-order triangle", 6, 2),
        10 => ("9-node second-order quadrangle", 9, 2),
        11 => ("10-node second-order tetrahedron", 10, 3),
        12 => ("27-node second-order hexahedron", 27, 3),
        13 => ("18-node second-order prism", 18, 3),
        14 => ("14-node second-order pyramid", 14, 3),
        15 => ("1-node point", 1, 0),
        16 => ("8-node second-order quadrangle", 8, 2),
        17 => ("20-node second-order hexahedron", 20, 3),
        18 => ("15-node second-order prism", 15, 3),
        19 => ("13-node second-order pyramid", 13, 3),
        20 => ("9-node third-order incomplete triangle", 9, 2),
        21 => ("10-node third-order triangle", 10, 2),
        22 => ("12-node fourth-order incomplete triangle", 12, 2),
        23 => ("15-node fourth-order triangle", 15, 2),
        24 => ("15-node fifth-order incomplete triangle", 15, 2),
        25 => ("21-node fifth-order triangle", 21, 2),
        26 => ("4-node third-order line", 4, 1),
        27 => ("5-node fourth-order line", 5, 1),
        28 => ("6-node fifth-order line", 6, 1),
        29 => ("20-node third-order tetrahedron", 20, 3),
        30 => ("35-node fourth-order tetrahedron", 35, 3),
        31 => ("56-node fifth-order tetrahedron", 56, 3),
        32 => ("22-node fourth-order incomplete tetrahedron", 22, 3),
        33 => ("28-node fifth-order incomplete tetrahedron", 28, 3),
        36 => ("16-node third-order quadrangle", 16, 2),
        37 => ("25-node fourth-order quadrangle", 25, 2),
        38 => ("36-node fifth-order quadrangle", 36, 2),
        39 => ("12-node third-order incomplete quadrangle", 12, 2),
        40 => ("16-node fourth-order incomplete quadrangle", 16, 2),
        41 => ("20-node fifth-order incomplete quadrangle", 20, 2),
        42 => ("28-node sixth-order triangle", 28, 2),
        43 => ("36-node seventh-order triangle", 36, 2),
        44 => ("45-node eighth-order triangle", 45, 2),
        45 => ("55-node ninth-order triangle", 55, 2),
        46 => ("66-node tenth-order triangle", 66, 2),
        47 => ("49-node sixth-order quadrangle", 49, 2),
        48 => ("64-node seventh-order quadrangle", 64, 2),
        49 => ("81-node eighth-order quadrangle", 81, 2),
        50 => ("100-node ninth-order quadrangle", 100, 2),
        51 => ("121-node tenth-order quadrangle", 121, 2),
        52 => ("18-node sixth-order incomplete triangle", 18, 2),
        53 => ("21-node seventh-order incomplete triangle", 21, 2),
        54 => ("24-node eighth-order incomplete triangle", 24, 2),
        55 => ("27-node ninth-order incomplete triangle", 27, 2),
        56 => ("30-node tenth-order incomplete triangle", 30, 2),
        57 => ("24-node sixth-order incomplete quadrangle", 24, 2),
        58 => ("28-node seventh-order incomplete quadrangle", 28, 2),
        59 => ("32-node eighth-order incomplete quadrangle", 32, 2),
        60 => ("36-node ninth-order incomplete quadrangle", 36, 2),
        61 => ("40-node tenth-order incomplete quadrangle", 40, 2),
        62 => ("7-node sixth-order line", 7, 1),
        63 => ("8-node seventh-order line", 8, 1),
        64 => ("9-node eighth-order line", 9, 1),
        65 => ("10-node ninth-order line", 10, 1),
        66 => ("11-node tenth-order line", 11, 1),
        92 => ("64-node third-order hexahedron", 64, 3),
        93 => ("125-node fourth-order hexahedron", 125, 3),
        _ => return None,
    })
}

/// Where the physical tags of a run of elements come from.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Origin {
    /// Physical tags (the dimension is the element's).
    pub physical: Vec<i32>,
    /// The elementary entity (dim, tag), for messages.
    pub entity: Option<(i32, i32)>,
}

/// Where things are in the file, for messages.
pub(crate) struct Places<'a> {
    /// Per node (file order): line of its tag and line of its coordinates (ASCII only).
    pub node_lines: Option<Vec<(usize, usize)>>,
    /// Line of element `index` (file order) with tag `tag`, if it can be found.
    pub element_line: Box<dyn Fn(usize, u64) -> Option<usize> + 'a>,
}

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

fn fmt_point<const D: usize>(p: [f64; D]) -> String {
    let parts: Vec<String> = p.iter().map(|v| format!("{v:?}")).collect();
    format!("({})", parts.join(", "))
}

/// The smallest det J of a 3D cell over its stiffness quadrature points and its corners, and
/// where it is (reference coordinates).
fn min_det_3d(points: &[[f64; 3]], cell: &Cell) -> (f64, [f64; 3]) {
    let mut at: Vec<[f64; 3]> = crate::mesh::element::stiffness_rule(cell)
        .iter()
        .map(|q| q.xi)
        .collect();
    if let Cell::Hex8(_) = cell {
        for &x in &[-1.0, 1.0] {
            for &y in &[-1.0, 1.0] {
                for &z in &[-1.0, 1.0] {
                    at.push([x, y, z]);
                }
            }
        }
    }
    at.iter()
        .map(|&xi| (crate::mesh::element::shape_at(cell, points, xi).det_j, xi))
        .fold((f64::INFINITY, [0.0; 3]), |a, b| if b.0 < a.0 { b } else { a })
}

/// Turns what a reader found into a [`Mesh`] of dimension D, validating it.
fn build<const D: usize>(path: &Path, raw: RawMesh<'_>) -> Result<Mesh<D>, MeshError> {
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
                    "node {} has z = {:?} but node {} has z = {:?}, and the mesh has no tetrahedra or hexahedra: a 2D \
                     mesh must lie in a plane z = const; mesh a plane surface (gmsh -2), or mesh the volume (gmsh -3) \
                     for a 3D body",
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
    let mut nodes = [0usize; 8];
    for e in 0..raw.element_tags.len() {
        let ty = raw.element_types[e];
        let origin = &raw.origins[raw.element_origin[e] as usize];
        let info = element_type_info(ty);
        if !matches!(ty, 1 | 2 | 3 | 4 | 5 | 15) {
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
                Some((name, _, 3)) if matches!(ty, 6 | 7) => (
                    name,
                    "hvi computes on tetrahedra and hexahedra only: mesh the volume with tetrahedra (no Recombine in \
                     the extrusion, Mesh.Algorithm3D = 1) or with hexahedra throughout (transfinite volumes with \
                     Recombine)",
                ),
                Some((name, _, _)) => (
                    name,
                    "hvi computes with first-order elements only: mesh with gmsh -order 1 (Mesh.ElementOrder = 1), \
                     without Mesh.SecondOrderIncomplete",
                ),
                None => (
                    "an element type hvi does not know",
                    "hvi reads only points (15), 2-node lines (1), 3-node triangles (2), 4-node quadrangles (3), \
                     4-node tetrahedra (4) and 8-node hexahedra (5): mesh with gmsh -2 -order 1 (-3 for a volume)",
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
                for &p in &origin.physical {
                    group(&mut groups, element_dim as u8, p)
                        .facets
                        .push(Facet::from_slice(nodes));
                }
            }
            _ => {
                let c = cells.len();
                cells.push(match ty {
                    2 => Cell::Tri3([nodes[0], nodes[1], nodes[2]]),
                    3 => Cell::Quad4([nodes[0], nodes[1], nodes[2], nodes[3]]),
                    4 => Cell::Tet4([nodes[0], nodes[1], nodes[2], nodes[3]]),
                    _ => Cell::Hex8(std::array::from_fn(|k| nodes[k])),
                });
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

/// Where the cells of a file are, for the orientation checks' messages.
struct CellPlaces<'a, 'b> {
    path: &'a Path,
    raw: &'a RawMesh<'b>,
    /// gmsh element tag and file element index of each cell
    tags: &'a [usize],
    elements: &'a [usize],
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
    let areas: Vec<f64> = cells.iter().map(|c| signed_area(points, c.nodes())).collect();
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
        if let Cell::Quad4(q) = cell {
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
                let (det, xi) = min_det_3d(points, c);
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
