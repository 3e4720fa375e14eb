//! MSH 4.1, ASCII and binary, parsed by mshio 0.4.2 after a pre-scan of our own.
//!
//! mshio has traps this module works around:
//! * Physical tags live on the entities (`$Entities`), not on elements: element blocks are
//!   mapped through (entity dim, entity tag).
//! * mshio ignores `$PhysicalNames` (parsed in [`super::physical_names`]).
//! * When the node tags of a file form one contiguous range, mshio drops them and assumes they
//!   are in order; with gaps it keeps per-block maps. Neither notices duplicate tags. So the
//!   pre-scan reads the node tags itself (in file order, with their line numbers in ASCII
//!   files) and mshio supplies only the coordinates, block by block.
//! * mshio panics on some malformed headers (a zero node or element count, a binary data size
//!   other than 1, 2, 4, 8, 16): the pre-scan rejects those first. It also checks every count
//!   in a section header against the bytes that follow, so a corrupt header claiming 10¹² nodes
//!   is a clean error.

use super::physical_names::{self, find_section};
use super::{element_type_info, line_of, trim, Header, Lines, MeshError, Origin, Places, RawMesh};
use std::collections::HashMap;
use std::path::Path;

/// What the pre-scan learns: node tags in file order, block sizes, and where they are.
struct Prescan {
    node_tags: Vec<u64>,
    block_sizes: Vec<usize>,
    node_lines: Option<Vec<(usize, usize)>>,
}

pub(crate) fn parse<'a>(path: &Path, bytes: &'a [u8], header: &Header) -> Result<RawMesh<'a>, MeshError> {
    let names = physical_names::parse(path, bytes, header.body)?;
    let pre = if header.binary {
        prescan_binary(path, bytes, header)?
    } else {
        prescan_ascii(path, bytes, header.body)?
    };

    let msh = match std::panic::catch_unwind(|| mshio::parse_msh_bytes(bytes)) {
        Ok(Ok(m)) => m,
        Ok(Err(e)) => return Err(mshio_error(path, bytes, header.binary, &e)),
        Err(_) => {
            return Err(MeshError::Syntax {
                path: path.to_path_buf(),
                place: "MSH 4.1 parser".into(),
                detail: "the file is malformed (the parser stopped on it); re-export it from gmsh".into(),
            })
        }
    };
    let syntax = |place: &str, detail: String| MeshError::Syntax {
        path: path.to_path_buf(),
        place: place.into(),
        detail,
    };
    let Some(nodes) = msh.data.nodes else {
        return Err(syntax("$Nodes", "the file has no $Nodes section".into()));
    };
    let Some(elements) = msh.data.elements else {
        return Err(syntax("$Elements", "the file has no $Elements section".into()));
    };

    // Coordinates from mshio, tags from the pre-scan, block by block.
    if nodes.node_blocks.len() != pre.block_sizes.len() {
        return Err(syntax(
            "$Nodes",
            format!(
                "{} node blocks were parsed but the section lists {}",
                nodes.node_blocks.len(),
                pre.block_sizes.len()
            ),
        ));
    }
    let mut coords = Vec::with_capacity(pre.node_tags.len());
    for (b, (block, &size)) in nodes.node_blocks.iter().zip(&pre.block_sizes).enumerate() {
        if block.nodes.len() != size {
            return Err(syntax(
                "$Nodes",
                format!(
                    "node block {} holds {} nodes, expected {size}",
                    b + 1,
                    block.nodes.len()
                ),
            ));
        }
        coords.extend(block.nodes.iter().map(|n| [n.x, n.y, n.z]));
    }

    // Physical tags of each entity.
    let mut physical: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
    if let Some(ent) = &msh.data.entities {
        for p in &ent.points {
            physical.insert((0, p.tag), p.physical_tags.clone());
        }
        for c in &ent.curves {
            physical.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &ent.surfaces {
            physical.insert((2, s.tag), s.physical_tags.clone());
        }
        for v in &ent.volumes {
            physical.insert((3, v.tag), v.physical_tags.clone());
        }
    }

    let mut element_tags = Vec::new();
    let mut element_types = Vec::new();
    let mut offsets = vec![0usize];
    let mut element_nodes = Vec::new();
    let mut element_origin = Vec::new();
    let mut origins = Vec::new();
    for block in &elements.element_blocks {
        let ty = block.element_type as i32;
        if let Some((name, _, dim)) = element_type_info(ty) {
            if i32::from(dim) != block.entity_dim {
                return Err(syntax(
                    "$Elements",
                    format!(
                        "an element block of {name}s (type {ty}, dimension {dim}) is on an entity of dimension {}",
                        block.entity_dim
                    ),
                ));
            }
        }
        let key = (block.entity_dim, block.entity_tag);
        let o = origins.len() as u32;
        origins.push(Origin {
            physical: physical.get(&key).cloned().unwrap_or_default(),
            entity: Some(key),
        });
        for el in &block.elements {
            element_tags.push(el.element_tag);
            element_types.push(ty);
            element_nodes.extend_from_slice(&el.nodes);
            offsets.push(element_nodes.len());
            element_origin.push(o);
        }
    }

    let element_line: Box<dyn Fn(usize, u64) -> Option<usize> + 'a> = if header.binary {
        Box::new(|_, _| None)
    } else {
        let body = header.body;
        Box::new(move |_, tag| element_line_ascii(bytes, body, tag))
    };
    Ok(RawMesh {
        node_tags: pre.node_tags,
        coords,
        element_tags,
        element_types,
        offsets,
        element_nodes,
        element_origin,
        origins,
        names,
        places: Places {
            node_lines: pre.node_lines,
            element_line,
        },
    })
}

/// Turns an mshio error into a [`MeshError::Syntax`] with a line number (ASCII) or byte offset
/// (binary) and the chain of what was being parsed (never mshio's hex dump of the file).
fn mshio_error(path: &Path, bytes: &[u8], binary: bool, e: &mshio::MshParserError<&[u8]>) -> MeshError {
    let bt = e.filtered_backtrace();
    let Some((input, kind)) = bt.first() else {
        return MeshError::Syntax {
            path: path.to_path_buf(),
            place: "MSH 4.1".into(),
            detail: "the file could not be parsed; re-export it from gmsh".into(),
        };
    };
    let start = bytes.as_ptr() as usize;
    let at = input.as_ptr() as usize;
    let offset = if at >= start && at <= start + bytes.len() {
        at - start
    } else {
        bytes.len()
    };
    let place = if binary {
        format!("byte {offset}")
    } else {
        format!("line {}", line_of(bytes, offset))
    };
    let chain: Vec<String> = bt[1..]
        .iter()
        .rev()
        .map(|(_, k)| k.context().map_or_else(|| k.to_string(), str::to_string))
        .collect();
    let mut detail = kind.to_string();
    if !chain.is_empty() {
        detail = format!("{detail} (while reading: {})", chain.join(" > "));
    }
    if trim(input).is_empty() {
        detail.push_str("; the file ends early: it is truncated, re-export it");
    } else {
        detail.push_str("; the file is malformed: re-export it from gmsh (gmsh -format msh41)");
    }
    MeshError::Syntax {
        path: path.to_path_buf(),
        place,
        detail,
    }
}

// ---------------------------------------------------------------------------------------------
// ASCII pre-scan

/// Whitespace-separated tokens with line numbers.
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Tokens<'a> {
    fn next(&mut self) -> Option<(&'a [u8], usize)> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            if self.bytes[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= self.bytes.len() {
            return None;
        }
        let s = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some((&self.bytes[s..self.pos], self.line))
    }

    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
}

fn prescan_ascii(path: &Path, bytes: &[u8], body: usize) -> Result<Prescan, MeshError> {
    let syntax = |line: usize, section: &str, detail: String| MeshError::Syntax {
        path: path.to_path_buf(),
        place: format!("line {line} ({section})"),
        detail,
    };
    let mut lines = Lines::new(bytes, body);
    let mut found: Option<Prescan> = None;
    let mut seen_elements = false;
    while let Some((line, l)) = lines.next_nonblank() {
        let text = String::from_utf8_lossy(trim(l)).into_owned();
        let Some(name) = text.strip_prefix('$') else {
            return Err(MeshError::Syntax {
                path: path.to_path_buf(),
                place: format!("line {line}"),
                detail: format!("expected a section such as $Nodes, found \"{text}\""),
            });
        };
        let section = format!("${name}");
        match name {
            "Nodes" => {
                if found.is_some() {
                    return Err(syntax(
                        line,
                        &section,
                        "a second $Nodes section; hvi reads files with one".into(),
                    ));
                }
                let mut t = Tokens {
                    bytes,
                    pos: lines.pos,
                    line: lines.line,
                };
                found = Some(scan_nodes_ascii(path, &mut t)?);
                match t.next() {
                    Some((tok, _)) if tok == b"$EndNodes" => {}
                    Some((tok, l)) => {
                        return Err(syntax(
                            l,
                            &section,
                            format!(
                                "expected $EndNodes, found \"{}\": the counts in the section do not match its content",
                                String::from_utf8_lossy(tok)
                            ),
                        ))
                    }
                    None => {
                        return Err(syntax(
                            t.line,
                            &section,
                            "the file ends before $EndNodes: it is truncated".into(),
                        ))
                    }
                }
                lines = Lines {
                    bytes,
                    pos: t.pos,
                    line: t.line,
                };
                continue;
            }
            "Elements" => {
                seen_elements = true;
                let (hline, counts) = header_numbers(&mut lines, path, &section)?;
                let (blocks, count) = (counts[0], counts[1]);
                if count == 0 {
                    return Err(syntax(
                        hline,
                        &section,
                        "the file has no elements; mesh the geometry (gmsh -2) before saving".into(),
                    ));
                }
                check_fits(
                    path,
                    hline,
                    &section,
                    "element blocks",
                    blocks,
                    8,
                    lines.remaining(),
                    true,
                )?;
                check_fits(path, hline, &section, "elements", count, 4, lines.remaining(), true)?;
                // The header's total must equal what the blocks hold (mshio does not check it).
                let mut walk = Lines {
                    bytes,
                    pos: lines.pos,
                    line: lines.line,
                };
                let mut held: u64 = 0;
                let mut complete = true;
                for _ in 0..blocks {
                    let in_block = walk.next_nonblank().and_then(|(_, bh)| {
                        String::from_utf8_lossy(bh)
                            .split_whitespace()
                            .nth(3)
                            .and_then(|v| v.parse::<u64>().ok())
                    });
                    let Some(n) = in_block else {
                        complete = false;
                        break;
                    };
                    held = held.saturating_add(n);
                    for _ in 0..n {
                        if walk.next_nonblank().is_none() {
                            complete = false;
                            break;
                        }
                    }
                }
                if complete && held != count {
                    return Err(syntax(
                        hline,
                        &section,
                        format!("the section header says {count} elements but its blocks hold {held}; re-export the mesh from gmsh"),
                    ));
                }
            }
            "Entities" => {
                let (hline, counts) = header_numbers(&mut lines, path, &section)?;
                let total = counts.iter().fold(0u64, |a, &c| a.saturating_add(c));
                check_fits(path, hline, &section, "entities", total, 10, lines.remaining(), true)?;
            }
            _ => {}
        }
        skip_to_end(&mut lines, path, name, line)?;
    }
    let Some(pre) = found else {
        return Err(syntax(
            lines.line.saturating_sub(1).max(1),
            "end of file",
            "the file has no $Nodes section: it is truncated".into(),
        ));
    };
    if !seen_elements {
        return Err(syntax(
            lines.line.saturating_sub(1).max(1),
            "end of file",
            "the file has no $Elements section: it is truncated".into(),
        ));
    }
    Ok(pre)
}

/// Skips lines up to and including `$End<name>`.
fn skip_to_end(lines: &mut Lines<'_>, path: &Path, name: &str, start_line: usize) -> Result<(), MeshError> {
    let end = format!("$End{name}");
    loop {
        match lines.next_line() {
            Some((_, l)) if trim(l) == end.as_bytes() => return Ok(()),
            Some(_) => {}
            None => {
                return Err(MeshError::Syntax {
                    path: path.to_path_buf(),
                    place: format!("line {start_line} (${name})"),
                    detail: format!("the section ${name} has no {end}: the file is truncated; re-export it"),
                })
            }
        }
    }
}

/// The four numbers of a section header line.
fn header_numbers(lines: &mut Lines<'_>, path: &Path, section: &str) -> Result<(usize, [u64; 4]), MeshError> {
    let Some((line, l)) = lines.next_nonblank() else {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            place: format!("line {} ({section})", lines.line),
            detail: format!("the file ends inside {section}: it is truncated"),
        });
    };
    let text = String::from_utf8_lossy(l);
    let numbers: Vec<u64> = text.split_whitespace().filter_map(|t| t.parse().ok()).collect();
    if numbers.len() != 4 || text.split_whitespace().count() != 4 {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            place: format!("line {line} ({section})"),
            detail: format!(
                "expected four non-negative integers (the section header), found \"{}\"",
                text.trim()
            ),
        });
    }
    Ok((line, [numbers[0], numbers[1], numbers[2], numbers[3]]))
}

/// Errors if `count` items of at least `min_bytes` each cannot fit in `remaining` bytes.
#[allow(clippy::too_many_arguments)]
fn check_fits(
    path: &Path,
    where_: usize,
    section: &str,
    what: &str,
    count: u64,
    min_bytes: u64,
    remaining: usize,
    ascii: bool,
) -> Result<(), MeshError> {
    if count.saturating_mul(min_bytes) > remaining as u64 {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            place: if ascii {
                format!("line {where_} ({section})")
            } else {
                format!("byte {where_} ({section})")
            },
            detail: format!(
                "the header says {count} {what}, but only {remaining} bytes follow (at least {min_bytes} per item): \
                 the file is truncated or its header is corrupt; re-export it"
            ),
        });
    }
    Ok(())
}

fn scan_nodes_ascii(path: &Path, t: &mut Tokens<'_>) -> Result<Prescan, MeshError> {
    let syntax = |line: usize, detail: String| MeshError::Syntax {
        path: path.to_path_buf(),
        place: format!("line {line} ($Nodes)"),
        detail,
    };
    fn number<T: std::str::FromStr>(
        t: &mut Tokens<'_>,
        what: &str,
        syntax: &dyn Fn(usize, String) -> MeshError,
    ) -> Result<(T, usize), MeshError> {
        match t.next() {
            Some((tok, line)) => match std::str::from_utf8(tok).ok().and_then(|s| s.parse().ok()) {
                Some(v) => Ok((v, line)),
                None => Err(syntax(
                    line,
                    format!("expected {what}, found \"{}\"", String::from_utf8_lossy(tok)),
                )),
            },
            None => Err(syntax(
                t.line,
                format!("the file ends where {what} was expected: it is truncated; re-export it"),
            )),
        }
    }
    let (blocks, hline) = number::<u64>(t, "the number of node blocks", &syntax)?;
    let (count, _) = number::<u64>(t, "the number of nodes", &syntax)?;
    let _ = number::<u64>(t, "the minimum node tag", &syntax)?;
    let _ = number::<u64>(t, "the maximum node tag", &syntax)?;
    if count == 0 {
        return Err(syntax(
            hline,
            "the file has no nodes; mesh the geometry (gmsh -2) before saving".into(),
        ));
    }
    check_fits(path, hline, "$Nodes", "node blocks", blocks, 8, t.remaining(), true)?;
    check_fits(path, hline, "$Nodes", "nodes", count, 8, t.remaining(), true)?;
    let count = count as usize;
    let mut node_tags = Vec::with_capacity(count);
    let mut node_lines = Vec::with_capacity(count);
    let mut block_sizes = Vec::with_capacity(blocks as usize);
    for b in 0..blocks {
        let (_, bline) = number::<i32>(t, "the entity dimension of a node block", &syntax)?;
        let _ = number::<i32>(t, "the entity tag of a node block", &syntax)?;
        let (parametric, _) = number::<i32>(t, "the parametric flag of a node block", &syntax)?;
        let (n, _) = number::<u64>(t, "the number of nodes in a node block", &syntax)?;
        if parametric != 0 {
            return Err(MeshError::UnsupportedFormat {
                path: path.to_path_buf(),
                detail: format!(
                    "line {bline}: node block {} has parametric coordinates, which hvi does not read; \
                     re-export with Mesh.SaveParametric = 0",
                    b + 1
                ),
            });
        }
        check_fits(path, bline, "$Nodes", "nodes in a block", n, 8, t.remaining(), true)?;
        if node_tags.len() as u64 + n > count as u64 {
            return Err(syntax(
                bline,
                format!("the node blocks hold more than the {count} nodes the section header says"),
            ));
        }
        let first = node_tags.len();
        for _ in 0..n {
            let (tag, line) = number::<u64>(t, "a node tag", &syntax)?;
            if tag == 0 {
                return Err(syntax(line, "node tag 0 is not allowed (tags start at 1)".into()));
            }
            node_tags.push(tag);
            node_lines.push((line, 0));
        }
        for lines in &mut node_lines[first..] {
            let (_, line) = number::<f64>(t, "an x coordinate", &syntax)?;
            let _ = number::<f64>(t, "a y coordinate", &syntax)?;
            let _ = number::<f64>(t, "a z coordinate", &syntax)?;
            lines.1 = line;
        }
        block_sizes.push(n as usize);
    }
    if node_tags.len() != count {
        return Err(syntax(
            hline,
            format!(
                "the section header says {count} nodes but its blocks hold {}",
                node_tags.len()
            ),
        ));
    }
    Ok(Prescan {
        node_tags,
        block_sizes,
        node_lines: Some(node_lines),
    })
}

/// Line of the element with `tag` in an ASCII MSH 4.1 file (only computed for messages).
fn element_line_ascii(bytes: &[u8], body: usize, tag: u64) -> Option<usize> {
    let start = find_section(bytes, body, b"$Elements")?;
    let mut lines = Lines::new(bytes, start);
    lines.next_line()?;
    let (_, h) = lines.next_nonblank()?;
    let blocks: u64 = String::from_utf8_lossy(h).split_whitespace().next()?.parse().ok()?;
    let want = tag.to_string();
    for _ in 0..blocks {
        let (_, bh) = lines.next_nonblank()?;
        let count: u64 = String::from_utf8_lossy(bh).split_whitespace().nth(3)?.parse().ok()?;
        for _ in 0..count {
            let (n, l) = lines.next_nonblank()?;
            if String::from_utf8_lossy(l).split_whitespace().next() == Some(want.as_str()) {
                return Some(n);
            }
        }
    }
    None
}

// ---------------------------------------------------------------------------------------------
// Binary pre-scan

struct Binary<'a> {
    bytes: &'a [u8],
    pos: usize,
    size_t: usize,
    little: bool,
}

impl Binary<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let s = self.bytes.get(self.pos..self.pos.checked_add(N)?)?;
        self.pos += N;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Some(a)
    }

    fn size_t(&mut self) -> Option<u64> {
        if self.size_t == 4 {
            let a = self.take::<4>()?;
            Some(u64::from(if self.little {
                u32::from_le_bytes(a)
            } else {
                u32::from_be_bytes(a)
            }))
        } else {
            let a = self.take::<8>()?;
            Some(if self.little {
                u64::from_le_bytes(a)
            } else {
                u64::from_be_bytes(a)
            })
        }
    }

    fn int(&mut self) -> Option<i32> {
        let a = self.take::<4>()?;
        Some(if self.little {
            i32::from_le_bytes(a)
        } else {
            i32::from_be_bytes(a)
        })
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    fn skip_whitespace(&mut self) {
        while self.pos < self.bytes.len() && matches!(self.bytes[self.pos], b'\n' | b'\r' | b' ' | b'\t') {
            self.pos += 1;
        }
    }

    /// The text line at `pos` (a section tag), and moves past it.
    fn line(&mut self) -> &[u8] {
        let rest = &self.bytes[self.pos.min(self.bytes.len())..];
        let len = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.pos += (len + 1).min(rest.len());
        trim(&rest[..len])
    }
}

fn prescan_binary(path: &Path, bytes: &[u8], header: &Header) -> Result<Prescan, MeshError> {
    let syntax = |at: usize, section: &str, detail: String| MeshError::Syntax {
        path: path.to_path_buf(),
        place: format!("byte {at} ({section})"),
        detail,
    };
    let truncated = |at: usize, section: &str| {
        syntax(
            at,
            section,
            "the file ends inside this section: it is truncated; re-export it".into(),
        )
    };
    let mut r = Binary {
        bytes,
        pos: header.body,
        size_t: header.data_size,
        little: header.little_endian,
    };
    let st = header.data_size as u64;
    let mut found: Option<Prescan> = None;
    let mut seen_elements = false;
    loop {
        r.skip_whitespace();
        if r.remaining() == 0 {
            break;
        }
        let at = r.pos;
        let tag = String::from_utf8_lossy(r.line()).into_owned();
        let Some(name) = tag.strip_prefix('$').map(str::to_string) else {
            let shown: String = tag.chars().take(40).collect();
            return Err(syntax(
                at,
                "between sections",
                format!("expected a section such as $Nodes, found \"{shown}\""),
            ));
        };
        let section = format!("${name}");
        match name.as_str() {
            "Nodes" => {
                if found.is_some() {
                    return Err(syntax(
                        at,
                        &section,
                        "a second $Nodes section; hvi reads files with one".into(),
                    ));
                }
                let h = r.pos;
                let blocks = r.size_t().ok_or_else(|| truncated(h, &section))?;
                let count = r.size_t().ok_or_else(|| truncated(h, &section))?;
                let _min = r.size_t().ok_or_else(|| truncated(h, &section))?;
                let _max = r.size_t().ok_or_else(|| truncated(h, &section))?;
                if count == 0 {
                    return Err(syntax(
                        h,
                        &section,
                        "the file has no nodes; mesh the geometry (gmsh -2) before saving".into(),
                    ));
                }
                check_fits(path, h, &section, "node blocks", blocks, 12 + st, r.remaining(), false)?;
                check_fits(path, h, &section, "nodes", count, st + 24, r.remaining(), false)?;
                let mut node_tags = Vec::with_capacity(count as usize);
                let mut block_sizes = Vec::with_capacity(blocks as usize);
                for b in 0..blocks {
                    let bh = r.pos;
                    let _dim = r.int().ok_or_else(|| truncated(bh, &section))?;
                    let _tag = r.int().ok_or_else(|| truncated(bh, &section))?;
                    let parametric = r.int().ok_or_else(|| truncated(bh, &section))?;
                    let n = r.size_t().ok_or_else(|| truncated(bh, &section))?;
                    if parametric != 0 {
                        return Err(MeshError::UnsupportedFormat {
                            path: path.to_path_buf(),
                            detail: format!(
                                "byte {bh}: node block {} has parametric coordinates, which hvi does not read; \
                                 re-export with Mesh.SaveParametric = 0",
                                b + 1
                            ),
                        });
                    }
                    check_fits(path, bh, &section, "nodes in a block", n, st + 24, r.remaining(), false)?;
                    if node_tags.len() as u64 + n > count {
                        return Err(syntax(
                            bh,
                            &section,
                            format!("the node blocks hold more than the {count} nodes the section header says"),
                        ));
                    }
                    for _ in 0..n {
                        let tp = r.pos;
                        let t = r.size_t().ok_or_else(|| truncated(tp, &section))?;
                        if t == 0 {
                            return Err(syntax(
                                tp,
                                &section,
                                "node tag 0 is not allowed (tags start at 1)".into(),
                            ));
                        }
                        node_tags.push(t);
                    }
                    // n ≤ remaining / 32 was checked above, so this cannot overflow.
                    r.pos += 24 * n as usize;
                    if r.pos > bytes.len() {
                        return Err(truncated(bh, &section));
                    }
                    block_sizes.push(n as usize);
                }
                if node_tags.len() as u64 != count {
                    return Err(syntax(
                        h,
                        &section,
                        format!(
                            "the section header says {count} nodes but its blocks hold {}",
                            node_tags.len()
                        ),
                    ));
                }
                r.skip_whitespace();
                let e = r.pos;
                if r.line() != b"$EndNodes" {
                    return Err(syntax(
                        e,
                        &section,
                        "expected $EndNodes: the counts in the section do not match its content".into(),
                    ));
                }
                found = Some(Prescan {
                    node_tags,
                    block_sizes,
                    node_lines: None,
                });
                continue;
            }
            "Elements" => {
                seen_elements = true;
                let h = r.pos;
                let blocks = r.size_t().ok_or_else(|| truncated(h, &section))?;
                let count = r.size_t().ok_or_else(|| truncated(h, &section))?;
                if count == 0 {
                    return Err(syntax(
                        h,
                        &section,
                        "the file has no elements; mesh the geometry (gmsh -2) before saving".into(),
                    ));
                }
                check_fits(
                    path,
                    h,
                    &section,
                    "element blocks",
                    blocks,
                    12 + st,
                    r.remaining(),
                    false,
                )?;
                check_fits(path, h, &section, "elements", count, 2 * st, r.remaining(), false)?;
            }
            "Entities" => {
                let h = r.pos;
                let mut total = 0u64;
                for _ in 0..4 {
                    total = total.saturating_add(r.size_t().ok_or_else(|| truncated(h, &section))?);
                }
                check_fits(path, h, &section, "entities", total, 28 + st, r.remaining(), false)?;
            }
            _ => {}
        }
        let end = format!("$End{name}");
        match find_section(bytes, r.pos, end.as_bytes()) {
            Some(p) => {
                r.pos = p;
                r.line();
            }
            None => {
                return Err(syntax(
                    at,
                    &section,
                    format!("the section {section} has no {end}: the file is truncated; re-export it"),
                ))
            }
        }
    }
    let Some(pre) = found else {
        return Err(syntax(
            bytes.len(),
            "end of file",
            "the file has no $Nodes section: it is truncated".into(),
        ));
    };
    if !seen_elements {
        return Err(syntax(
            bytes.len(),
            "end of file",
            "the file has no $Elements section: it is truncated".into(),
        ));
    }
    Ok(pre)
}
