//! The mesh as hvi computes with it: points, positively oriented cells, physical groups, and
//! what is asked of them (a group by name or tag, its nodes, measures, the longest edge).

use crate::mesh::vector::distance;
use crate::mesh::Cell;
use crate::mesh::Facet;
use crate::mesh::GroupSelector;
use crate::mesh::MeshError;
use std::fmt::Write as _;
use std::path::PathBuf;

/// A mesh of a body in D = 2 or 3 dimensions with its physical groups.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh<const D: usize> {
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

impl<const D: usize> Mesh<D> {
    /// The longest cell edge (h of the mesh).
    pub fn longest_edge(&self) -> f64 {
        self.cells
            .iter()
            .map(|c| longest_edge(&self.points, c))
            .fold(0.0_f64, f64::max)
    }
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
        let available = match (sel, self.nearest_group_name(sel)) {
            (GroupSelector::Name(_), Some(near)) => format!(
                "{available}; did you mean \"{near}\"? (names are case-sensitive; a group's tag number works too)"
            ),
            _ => format!("{available} (a group's name or its tag number works)"),
        };
        MeshError::GroupNotFound {
            path: self.path.clone(),
            wanted: sel.to_string(),
            dim,
            available,
        }
    }

    /// The group name nearest to a wanted name: equal ignoring case, or within two edits of it
    /// (ignoring case), the closest first.
    fn nearest_group_name(&self, sel: &GroupSelector) -> Option<&str> {
        let GroupSelector::Name(wanted) = sel else {
            return None;
        };
        let wanted = wanted.to_lowercase();
        self.groups
            .iter()
            .filter_map(|g| g.name.as_deref())
            .map(|n| (edit_distance(&n.to_lowercase(), &wanted), n))
            .filter(|&(d, _)| d <= 2)
            .min_by_key(|&(d, _)| d)
            .map(|(_, n)| n)
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

/// The longest edge of cell `c`.
pub(super) fn longest_edge<const D: usize>(points: &[[f64; D]], c: &Cell) -> f64 {
    c.edges()
        .iter()
        .map(|&[a, b]| distance(&points[a], &points[b]))
        .fold(0.0_f64, f64::max)
}

/// A point for messages: `(x, y)` or `(x, y, z)`.
pub(crate) fn fmt_point<const D: usize>(p: [f64; D]) -> String {
    let parts: Vec<String> = p.iter().map(|v| format!("{v:?}")).collect();
    format!("({})", parts.join(", "))
}

/// The Levenshtein distance of two strings (by characters).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (above + 1).min(row[j] + 1).min(diagonal + usize::from(ca != cb));
            diagonal = above;
        }
    }
    row[b.len()]
}
