//! MSH 4.1, ASCII and binary (either byte order, size_t of 4 or 8 bytes), read by hand in one
//! pass that validates as it reads.
//!
//! ```text
//! $Entities
//! numPoints numCurves numSurfaces numVolumes
//! pointTag X Y Z numPhysicalTags physicalTag ...                       (each point)
//! tag minX minY minZ maxX maxY maxZ numPhysicalTags physicalTag ...
//!     numBoundingEntities boundingTag ...                              (each curve, surface, volume)
//! $EndEntities
//! $Nodes
//! numEntityBlocks numNodes minNodeTag maxNodeTag
//! entityDim entityTag parametric numNodesInBlock                       (each block)
//! nodeTag ...                                                          (numNodesInBlock of them)
//! x y z ...                                                            (numNodesInBlock of them)
//! $EndNodes
//! $Elements
//! numEntityBlocks numElements minElementTag maxElementTag
//! entityDim entityTag elementType numElementsInBlock                   (each block)
//! elementTag nodeTag ...                                               (each element)
//! $EndElements
//! ```
//!
//! In binary files the numbers are raw: ints of 4 bytes, doubles of 8, size_t of the header's
//! data size; `$PhysicalNames` is text in both (read by [`super::physical_names`]). ASCII is read
//! token by token (line breaks do not matter, as in gmsh), binary item by item. Physical tags
//! live on the entities: an element block gets those of its (entity dim, entity tag). Other
//! sections are skipped.
//!
//! Every count in a header is checked against the bytes that follow before anything is
//! allocated for it, so a corrupt header claiming 10¹² nodes is a clean error. Node tags are kept
//! as written, in file order (duplicates are found by `build`).
//!
//! Over 600 lines because it is one reader: the sections hvi needs, each in ASCII and in binary
//! of either byte order and size_t width, validated as they are read.

use super::physical_names::{self, find_section};
use super::{element_type_info, line_of, trim, Header, MeshError, Origin, Places, RawMesh};
use std::collections::HashMap;
use std::path::Path;

pub(crate) fn parse<'a>(path: &Path, bytes: &'a [u8], header: &Header) -> Result<RawMesh<'a>, MeshError> {
    let names = physical_names::parse(path, bytes, header.body)?;
    let mut r = Reader {
        path,
        bytes,
        pos: header.body,
        line: line_of(bytes, header.body),
        binary: header.binary.then_some((header.data_size, header.little_endian)),
        section: String::new(),
        section_at: 0,
    };
    let mut physical: Option<HashMap<(i32, i32), Vec<i32>>> = None;
    let mut nodes: Option<NodesRead> = None;
    let mut elements: Option<ElementsRead> = None;
    while let Some((name, at)) = r.section_tag()? {
        let seen = match name.as_str() {
            "Entities" => physical.is_some(),
            "Nodes" => nodes.is_some(),
            "Elements" => elements.is_some(),
            _ => false,
        };
        r.section = format!("${name}");
        r.section_at = at;
        if seen {
            return Err(r.error(at, format!("a second ${name} section; hvi reads files with one")));
        }
        match name.as_str() {
            "Entities" => {
                physical = Some(read_entities(&mut r)?);
            }
            "Nodes" => {
                nodes = Some(read_nodes(&mut r)?);
            }
            "Elements" => {
                elements = Some(read_elements(&mut r)?);
            }
            _ => {
                r.skip_section(&name)?;
                continue;
            }
        }
        r.end_tag(&name)?;
    }
    let end = if r.binary.is_some() {
        bytes.len()
    } else {
        r.line.saturating_sub(1).max(1)
    };
    let Some(nodes) = nodes else {
        return Err(r.error_at(
            end,
            "end of file",
            "the file has no $Nodes section: it is truncated".into(),
        ));
    };
    let Some(elements) = elements else {
        return Err(r.error_at(
            end,
            "end of file",
            "the file has no $Elements section: it is truncated".into(),
        ));
    };

    // Each element block takes the physical tags of its entity.
    let physical = physical.unwrap_or_default();
    let origins = elements
        .blocks
        .iter()
        .map(|&key| Origin {
            physical: physical.get(&key).cloned().unwrap_or_default(),
            entity: Some(key),
        })
        .collect();
    let element_line: Box<dyn Fn(usize, u64) -> Option<usize> + 'a> = match elements.lines {
        Some(lines) => Box::new(move |e, _| lines.get(e).copied()),
        None => Box::new(|_, _| None),
    };
    Ok(RawMesh {
        node_tags: nodes.tags,
        coords: nodes.coords,
        element_tags: elements.tags,
        element_types: elements.types,
        offsets: elements.offsets,
        element_nodes: elements.nodes,
        element_origin: elements.origin,
        origins,
        names,
        places: Places {
            node_lines: nodes.lines,
            element_line,
        },
    })
}

/// The `$Entities` section: (dim, tag) → physical tags. A repeated entity keeps its last line.
fn read_entities(r: &mut Reader<'_>) -> Result<HashMap<(i32, i32), Vec<i32>>, MeshError> {
    let h = r.mark();
    let mut counts = [0u64; 4];
    for (c, what) in counts.iter_mut().zip([
        "the number of points",
        "the number of curves",
        "the number of surfaces",
        "the number of volumes",
    ]) {
        *c = r.size_t(what)?;
    }
    let total = counts.iter().fold(0u64, |a, &c| a.saturating_add(c));
    // the smallest entity, a point: tag, x, y, z, numPhysicalTags
    let point = r.int_bytes() + 3 * r.float_bytes() + r.size_t_bytes();
    r.check_fits(h, "entities", total, point)?;
    let mut physical = HashMap::with_capacity(total as usize);
    for (dim, &count) in counts.iter().enumerate() {
        for _ in 0..count {
            let tag = r.int("an entity tag")?;
            let coordinates = if dim == 0 { 3 } else { 6 };
            for _ in 0..coordinates {
                r.float("a coordinate of an entity")?;
            }
            let at = r.mark();
            let n = r.size_t("the number of physical tags of an entity")?;
            r.check_fits(at, "physical tags of an entity", n, r.int_bytes())?;
            let mut tags = Vec::with_capacity(n as usize);
            for _ in 0..n {
                tags.push(r.int("a physical tag")?);
            }
            if dim > 0 {
                let at = r.mark();
                let n = r.size_t("the number of bounding entities of an entity")?;
                r.check_fits(at, "bounding entities of an entity", n, r.int_bytes())?;
                for _ in 0..n {
                    r.int("a bounding entity tag")?;
                }
            }
            physical.insert((dim as i32, tag), tags);
        }
    }
    Ok(physical)
}

/// What `$Nodes` holds, in file order.
struct NodesRead {
    tags: Vec<u64>,
    coords: Vec<[f64; 3]>,
    /// ASCII: line of each node's tag and of its coordinates.
    lines: Option<Vec<(usize, usize)>>,
}

fn read_nodes(r: &mut Reader<'_>) -> Result<NodesRead, MeshError> {
    let h = r.mark();
    let blocks = r.size_t("the number of node blocks")?;
    let count = r.size_t("the number of nodes")?;
    r.size_t("the minimum node tag")?;
    r.size_t("the maximum node tag")?;
    if count == 0 {
        return Err(r.error(
            h,
            "the file has no nodes; mesh the geometry (gmsh -2) before saving".into(),
        ));
    }
    let block = 3 * r.int_bytes() + r.size_t_bytes();
    let node = r.size_t_bytes() + 3 * r.float_bytes();
    r.check_fits(h, "node blocks", blocks, block)?;
    r.check_fits(h, "nodes", count, node)?;
    let count = count as usize;
    let mut tags = Vec::with_capacity(count);
    let mut coords = Vec::with_capacity(count);
    let mut lines = r.binary.is_none().then(|| Vec::with_capacity(count));
    for b in 0..blocks {
        let bh = r.mark();
        r.int("the entity dimension of a node block")?;
        r.int("the entity tag of a node block")?;
        let parametric = r.int("the parametric flag of a node block")?;
        let n = r.size_t("the number of nodes in a node block")?;
        if parametric != 0 {
            return Err(MeshError::UnsupportedFormat {
                path: r.path.to_path_buf(),
                detail: format!(
                    "{}: node block {} has parametric coordinates, which hvi does not read; \
                     re-export with Mesh.SaveParametric = 0",
                    r.place(bh),
                    b + 1
                ),
            });
        }
        r.check_fits(bh, "nodes in a block", n, node)?;
        if tags.len() as u64 + n > count as u64 {
            return Err(r.error(
                bh,
                format!("the node blocks hold more than the {count} nodes the section header says"),
            ));
        }
        let first = tags.len();
        for _ in 0..n {
            let at = r.mark();
            let tag = r.size_t("a node tag")?;
            if tag == 0 {
                return Err(r.error(at, "node tag 0 is not allowed (tags start at 1)".into()));
            }
            tags.push(tag);
            if let Some(l) = &mut lines {
                l.push((at, 0));
            }
        }
        for k in first..tags.len() {
            let at = r.mark();
            let c = [
                r.float("an x coordinate")?,
                r.float("a y coordinate")?,
                r.float("a z coordinate")?,
            ];
            coords.push(c);
            if let Some(l) = &mut lines {
                l[k].1 = at;
            }
        }
    }
    if tags.len() != count {
        return Err(r.error(
            h,
            format!(
                "the section header says {count} nodes but its blocks hold {}",
                tags.len()
            ),
        ));
    }
    Ok(NodesRead { tags, coords, lines })
}

/// What `$Elements` holds, in file order, as [`RawMesh`] wants it.
struct ElementsRead {
    tags: Vec<u64>,
    types: Vec<i32>,
    offsets: Vec<usize>,
    nodes: Vec<u64>,
    /// The block of each element.
    origin: Vec<u32>,
    /// (entity dim, entity tag) of each block.
    blocks: Vec<(i32, i32)>,
    /// ASCII: line of each element.
    lines: Option<Vec<usize>>,
}

fn read_elements(r: &mut Reader<'_>) -> Result<ElementsRead, MeshError> {
    let h = r.mark();
    let blocks = r.size_t("the number of element blocks")?;
    let count = r.size_t("the number of elements")?;
    r.size_t("the minimum element tag")?;
    r.size_t("the maximum element tag")?;
    if count == 0 {
        return Err(r.error(
            h,
            "the file has no elements; mesh the geometry (gmsh -2) before saving".into(),
        ));
    }
    let block = 3 * r.int_bytes() + r.size_t_bytes();
    r.check_fits(h, "element blocks", blocks, block)?;
    // the smallest element, a point: its tag and one node
    r.check_fits(h, "elements", count, 2 * r.size_t_bytes())?;
    let mut e = ElementsRead {
        tags: Vec::new(),
        types: Vec::new(),
        offsets: vec![0],
        nodes: Vec::new(),
        origin: Vec::new(),
        blocks: Vec::new(),
        lines: r.binary.is_none().then(Vec::new),
    };
    // (where, entity dim, type) of each block, checked once the section is read
    let mut headers = Vec::new();
    for b in 0..blocks {
        let bh = r.mark();
        let dim = r.int("the entity dimension of an element block")?;
        let entity = r.int("the entity tag of an element block")?;
        let ty = r.int("the element type of an element block")?;
        let n = r.size_t("the number of elements in an element block")?;
        let Some((_, per, _)) = element_type_info(ty) else {
            return Err(MeshError::UnsupportedElement {
                path: r.path.to_path_buf(),
                place: format!("{} ($Elements)", r.place(bh)),
                element_type: ty,
                detail: format!(
                    "element block {} is of type {ty}, an element type hvi does not know (so its elements cannot \
                     even be read); hvi reads only points (15), 2-node lines (1), 3-node triangles (2), 4-node \
                     quadrangles (3), 4-node tetrahedra (4), 8-node hexahedra (5), 6-node prisms (6) and 5-node \
                     pyramids (7): mesh with gmsh -2 -order 1 (-3 for a volume)",
                    b + 1
                ),
            });
        };
        // Nothing is reserved for the n elements: they are pushed as they are read, so a wrong n
        // costs no more memory than the file holds (and the error is where the content stops
        // matching it).
        let o = e.blocks.len() as u32;
        e.blocks.push((dim, entity));
        headers.push((bh, dim, ty));
        for k in 0..n {
            let what = |item: String| format!("{item} of element {} of {n} in element block {}", k + 1, b + 1);
            let at = r.mark();
            let tag = r.element_item(&what("the tag".into()), at)?;
            for j in 0..per {
                let t = r.element_item(&what(format!("node {} of {per}", j + 1)), at)?;
                e.nodes.push(t);
            }
            e.tags.push(tag);
            e.types.push(ty);
            e.offsets.push(e.nodes.len());
            e.origin.push(o);
            if let Some(l) = &mut e.lines {
                l.push(at);
            }
        }
    }
    let held = e.tags.len() as u64;
    if held != count {
        return Err(r.error(
            h,
            format!(
                "the section header says {count} elements but its blocks hold {held}; re-export the mesh from gmsh"
            ),
        ));
    }
    for (at, dim, ty) in headers {
        if let Some((name, _, d)) = element_type_info(ty) {
            if i32::from(d) != dim {
                return Err(r.error(
                    at,
                    format!(
                        "an element block of {name}s (type {ty}, dimension {d}) is on an entity of dimension {dim}; \
                         re-export the mesh from gmsh"
                    ),
                ));
            }
        }
    }
    Ok(e)
}

/// Reads the file after `$EndMeshFormat`: section tags as text lines, the content of the sections
/// as whitespace-separated tokens (ASCII) or raw numbers (binary). Places are line numbers
/// (ASCII) or byte offsets (binary).
struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    pos: usize,
    /// ASCII: line number of `pos`.
    line: usize,
    /// Binary: (size of size_t, little endian).
    binary: Option<(usize, bool)>,
    /// The section being read (`$Nodes`) and where its tag is.
    section: String,
    section_at: usize,
}

impl Reader<'_> {
    fn place(&self, at: usize) -> String {
        if self.binary.is_some() {
            format!("byte {at}")
        } else {
            format!("line {at}")
        }
    }

    fn error_at(&self, at: usize, section: &str, detail: String) -> MeshError {
        MeshError::Syntax {
            path: self.path.to_path_buf(),
            place: format!("{} ({section})", self.place(at)),
            detail,
        }
    }

    /// An error at `at` (a [`Reader::mark`]) in the current section.
    fn error(&self, at: usize, detail: String) -> MeshError {
        self.error_at(at, &self.section, detail)
    }

    /// Where the next item is: its line (ASCII), its byte offset (binary).
    fn mark(&mut self) -> usize {
        if self.binary.is_some() {
            self.pos
        } else {
            self.skip_whitespace();
            self.line
        }
    }

    fn skip_whitespace(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// Moves to `to` (forward), counting lines.
    fn seek(&mut self, to: usize) {
        let to = to.min(self.bytes.len());
        self.line += self.bytes[self.pos.min(to)..to].iter().filter(|&&b| b == b'\n').count();
        self.pos = to;
    }

    /// The rest of the line from `pos` (trimmed), moving past its line break.
    fn text_line(&mut self) -> &[u8] {
        let rest = &self.bytes[self.pos.min(self.bytes.len())..];
        let len = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.seek(self.pos + (len + 1).min(rest.len()));
        trim(&rest[..len])
    }

    /// The next section tag (`$Nodes` → `Nodes`) and where it is; `None` at the end of the file.
    fn section_tag(&mut self) -> Result<Option<(String, usize)>, MeshError> {
        self.skip_whitespace();
        if self.pos >= self.bytes.len() {
            return Ok(None);
        }
        let at = if self.binary.is_some() { self.pos } else { self.line };
        let text = String::from_utf8_lossy(self.text_line()).into_owned();
        match text.strip_prefix('$') {
            Some(name) => Ok(Some((name.to_string(), at))),
            None => {
                let shown: String = text.chars().take(40).collect();
                let detail = format!("expected a section such as $Nodes, found \"{shown}\"");
                Err(match self.binary {
                    Some(_) => self.error_at(at, "between sections", detail),
                    None => MeshError::Syntax {
                        path: self.path.to_path_buf(),
                        place: format!("line {at}"),
                        detail,
                    },
                })
            }
        }
    }

    /// Skips a section hvi does not read, up to and including its `$End` line.
    fn skip_section(&mut self, name: &str) -> Result<(), MeshError> {
        let end = format!("$End{name}");
        match find_section(self.bytes, self.pos, end.as_bytes()) {
            Some(p) => {
                self.seek(p);
                self.text_line();
                Ok(())
            }
            None => Err(self.error(
                self.section_at,
                format!("the section ${name} has no {end}: the file is truncated; re-export it"),
            )),
        }
    }

    /// The `$End` tag that must follow a section's content.
    fn end_tag(&mut self, name: &str) -> Result<(), MeshError> {
        let end = format!("$End{name}");
        self.skip_whitespace();
        let at = if self.binary.is_some() { self.pos } else { self.line };
        if self.pos >= self.bytes.len() {
            return Err(self.truncated(&end));
        }
        let found = self.text_line();
        if found == end.as_bytes() {
            return Ok(());
        }
        let shown: String = String::from_utf8_lossy(found).chars().take(40).collect();
        Err(self.error(
            at,
            format!("expected {end}, found \"{shown}\": the counts in the section do not match its content"),
        ))
    }

    /// The file ends where `what` was expected.
    fn truncated(&self, what: &str) -> MeshError {
        let s = &self.section;
        let detail = if self.binary.is_some() {
            format!(
                "the file ends inside this section, where {what} was expected: it is truncated (or a count in the \
                 section is wrong); re-export it"
            )
        } else {
            let end = s.replacen('$', "$End", 1);
            format!(
                "the section {s} has no {end}: the file is truncated (it ends at line {}, where {what} was \
                 expected); re-export it",
                self.line
            )
        };
        self.error(self.section_at, detail)
    }

    /// Errors if `count` items of at least `min_bytes` each cannot fit in the rest of the file.
    fn check_fits(&self, at: usize, what: &str, count: u64, min_bytes: u64) -> Result<(), MeshError> {
        let remaining = self.bytes.len().saturating_sub(self.pos);
        if count.saturating_mul(min_bytes) > remaining as u64 {
            return Err(self.error(
                at,
                format!(
                    "the header says {count} {what}, but only {remaining} bytes follow (at least {min_bytes} per \
                     item): the file is truncated or its header is corrupt; re-export it"
                ),
            ));
        }
        Ok(())
    }

    // The least number of bytes an item takes: a digit and a separator in ASCII.
    fn size_t_bytes(&self) -> u64 {
        self.binary.map_or(2, |(s, _)| s as u64)
    }

    fn int_bytes(&self) -> u64 {
        self.binary.map_or(2, |_| 4)
    }

    fn float_bytes(&self) -> u64 {
        self.binary.map_or(2, |_| 8)
    }

    /// ASCII: the next token, parsed; the error says what was expected and what was found. In an
    /// element (`element_at`: the line where it starts), the error is placed at its start.
    fn token<T: std::str::FromStr>(&mut self, what: &str, element_at: Option<usize>) -> Result<T, MeshError> {
        self.skip_whitespace();
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let tok = &self.bytes[start..self.pos];
        if tok.is_empty() {
            return Err(self.truncated(what));
        }
        match std::str::from_utf8(tok).ok().and_then(|s| s.parse().ok()) {
            Some(v) => Ok(v),
            // a number cut off by the end of the file
            None if self.pos == self.bytes.len() => Err(self.truncated(what)),
            None => {
                let shown: String = String::from_utf8_lossy(tok).chars().take(40).collect();
                Err(match element_at {
                    None => self.error(self.line, format!("expected {what}, found \"{shown}\"")),
                    Some(at) => self.error(
                        at,
                        format!(
                            "invalid element definition: expected {what}, found \"{shown}\" (line {}); the counts in \
                             the section do not match its content, or the file is malformed: re-export it from gmsh \
                             (gmsh -format msh41)",
                            self.line
                        ),
                    ),
                })
            }
        }
    }

    /// Binary: the next N bytes in file byte order.
    fn raw<const N: usize>(&mut self, what: &str) -> Result<[u8; N], MeshError> {
        let Some(s) = self.bytes.get(self.pos..self.pos.saturating_add(N)) else {
            return Err(self.truncated(what));
        };
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        if self.binary.is_some_and(|(_, little)| !little) {
            a.reverse();
        }
        self.pos += N;
        Ok(a)
    }

    /// A size_t (binary) or non-negative integer (ASCII).
    fn size_t(&mut self, what: &str) -> Result<u64, MeshError> {
        self.size_t_in(what, None)
    }

    fn size_t_in(&mut self, what: &str, element_at: Option<usize>) -> Result<u64, MeshError> {
        match self.binary {
            None => self.token(what, element_at),
            Some((4, _)) => Ok(u64::from(u32::from_le_bytes(self.raw(what)?))),
            Some(_) => Ok(u64::from_le_bytes(self.raw(what)?)),
        }
    }

    /// The tag or a node tag of the element that starts at `at`.
    fn element_item(&mut self, what: &str, at: usize) -> Result<u64, MeshError> {
        self.size_t_in(what, Some(at))
    }

    fn int(&mut self, what: &str) -> Result<i32, MeshError> {
        match self.binary {
            None => self.token(what, None),
            Some(_) => Ok(i32::from_le_bytes(self.raw(what)?)),
        }
    }

    fn float(&mut self, what: &str) -> Result<f64, MeshError> {
        match self.binary {
            None => self.token(what, None),
            Some(_) => Ok(f64::from_le_bytes(self.raw(what)?)),
        }
    }
}
