//! MSH 2.2 ASCII (also 2.0 and 2.1, which have the same sections), read by hand.
//!
//! ```text
//! $Nodes
//! number-of-nodes
//! node-tag x y z
//! ...
//! $EndNodes
//! $Elements
//! number-of-elements
//! element-tag type number-of-tags physical-tag elementary-tag ... node-tags ...
//! ...
//! $EndElements
//! ```
//!
//! The first tag of an element is its physical group (0 or no tags: none). gmsh writes an
//! element once per physical group it belongs to (with a new element tag each time): such
//! copies (same type, same nodes) are merged into one element in all of those groups.

use super::physical_names;
use super::{element_type_info, trim, Lines, MeshError, Origin, Places, RawMesh};
use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::path::Path;

pub(crate) fn parse<'a>(path: &Path, bytes: &'a [u8], body: usize) -> Result<RawMesh<'a>, MeshError> {
    let syntax = |line: usize, section: &str, detail: String| MeshError::Syntax {
        path: path.to_path_buf(),
        place: if section.is_empty() {
            format!("line {line}")
        } else {
            format!("line {line} ({section})")
        },
        detail,
    };
    let names = physical_names::parse(path, bytes, body)?;

    let mut node_tags = Vec::new();
    let mut coords = Vec::new();
    let mut node_lines = Vec::new();
    let mut element_tags = Vec::new();
    let mut element_types = Vec::new();
    let mut offsets = vec![0usize];
    let mut element_nodes: Vec<u64> = Vec::new();
    // First tag of each element (0: none), and the further groups of merged copies.
    let mut element_physical: Vec<i32> = Vec::new();
    let mut merged: HashMap<usize, Vec<i32>> = HashMap::new();
    let mut element_entity: Vec<Option<(i32, i32)>> = Vec::new();
    let mut element_lines = Vec::new();
    let (mut seen_nodes, mut seen_elements) = (false, false);

    let mut lines = Lines::new(bytes, body);
    while let Some((line, l)) = lines.next_nonblank() {
        let l = trim(l);
        let text = String::from_utf8_lossy(l);
        let Some(name) = text.strip_prefix('$') else {
            return Err(syntax(
                line,
                "",
                format!("expected a section such as $Nodes, found \"{text}\""),
            ));
        };
        match name {
            "Nodes" => {
                if seen_nodes {
                    return Err(syntax(
                        line,
                        "$Nodes",
                        "a second $Nodes section; hvi reads files with one".into(),
                    ));
                }
                seen_nodes = true;
                let count = read_count(&mut lines, path, "$Nodes", 8)?;
                node_tags.reserve(count);
                coords.reserve(count);
                node_lines.reserve(count);
                for k in 0..count {
                    let Some((line, l)) = lines.next_line() else {
                        return Err(syntax(
                            lines.line,
                            "$Nodes",
                            format!("the file ends after {k} of {count} nodes: it is truncated; re-export it"),
                        ));
                    };
                    let text = String::from_utf8_lossy(l);
                    let mut tokens = [""; 4];
                    let mut ntok = 0;
                    for t in text.split_whitespace() {
                        if ntok < 4 {
                            tokens[ntok] = t;
                        }
                        ntok += 1;
                    }
                    let cut = if lines.remaining() == 0 {
                        "; the file ends here: it is truncated"
                    } else {
                        ""
                    };
                    let bad = || {
                        syntax(
                            line,
                            "$Nodes",
                            format!(
                                "expected `node-tag x y z` (node {} of {count}), found \"{}\"{cut}",
                                k + 1,
                                text.trim()
                            ),
                        )
                    };
                    if ntok != 4 {
                        return Err(bad());
                    }
                    let tag: u64 = tokens[0].parse().map_err(|_| bad())?;
                    if tag == 0 {
                        return Err(syntax(
                            line,
                            "$Nodes",
                            "node tag 0 is not allowed (tags start at 1)".into(),
                        ));
                    }
                    let mut c = [0.0; 3];
                    for (d, t) in c.iter_mut().zip(&tokens[1..]) {
                        *d = t.parse().map_err(|_| bad())?;
                    }
                    node_tags.push(tag);
                    coords.push(c);
                    node_lines.push((line, line));
                }
                expect_end(&mut lines, path, "$Nodes", count, "nodes")?;
            }
            "Elements" => {
                if seen_elements {
                    return Err(syntax(
                        line,
                        "$Elements",
                        "a second $Elements section; hvi reads files with one".into(),
                    ));
                }
                seen_elements = true;
                let count = read_count(&mut lines, path, "$Elements", 8)?;
                // Copies of an element (same type and nodes) for further physical groups.
                let mut copies: HashMap<(i32, [u64; 4]), usize> = HashMap::new();
                let mut numbers = Vec::new();
                for k in 0..count {
                    let Some((line, l)) = lines.next_line() else {
                        return Err(syntax(
                            lines.line,
                            "$Elements",
                            format!("the file ends after {k} of {count} elements: it is truncated; re-export it"),
                        ));
                    };
                    let text = String::from_utf8_lossy(l);
                    let cut = if lines.remaining() == 0 {
                        "; the file ends here: it is truncated"
                    } else {
                        ""
                    };
                    let bad = |why: &str| {
                        syntax(
                            line,
                            "$Elements",
                            format!(
                                "{why}: expected `element-tag type number-of-tags tags... nodes...` (element {} of {count}), found \"{}\"{cut}",
                                k + 1,
                                text.trim()
                            ),
                        )
                    };
                    numbers.clear();
                    for t in text.split_whitespace() {
                        numbers.push(
                            t.parse::<i64>()
                                .map_err(|_| bad(&format!("\"{t}\" is not an integer")))?,
                        );
                    }
                    if numbers.len() < 3 {
                        return Err(bad("too few numbers"));
                    }
                    let (tag, ty, ntags) = (numbers[0], numbers[1], numbers[2]);
                    if tag <= 0 || ntags < 0 || ty <= 0 || ty > i32::MAX as i64 {
                        return Err(bad("invalid element tag, type or number of tags"));
                    }
                    let ty = ty as i32;
                    let ntags = ntags as usize;
                    if 3 + ntags > numbers.len() {
                        return Err(bad("fewer tags than the number of tags says"));
                    }
                    let tags = &numbers[3..3 + ntags];
                    let nodes = &numbers[3 + ntags..];
                    if let Some((name, want, _)) = element_type_info(ty) {
                        if nodes.len() != want {
                            return Err(bad(&format!(
                                "a {name} (type {ty}) has {want} nodes, found {}",
                                nodes.len()
                            )));
                        }
                    }
                    if nodes.iter().any(|&v| v <= 0) {
                        return Err(bad("node tags must be positive"));
                    }
                    let to_i32 = |v: i64| i32::try_from(v).map_err(|_| bad("tag out of range"));
                    let physical = match tags.first() {
                        Some(&p) => to_i32(p)?,
                        None => 0,
                    };
                    let dim = element_type_info(ty).map_or(2, |i| i.2) as i32;
                    let entity = match tags.get(1) {
                        Some(&t) => Some((dim, to_i32(t)?)),
                        None => None,
                    };
                    if nodes.len() <= 4 {
                        let mut key = (ty, [0u64; 4]);
                        for (k, &v) in key.1.iter_mut().zip(nodes) {
                            *k = v as u64;
                        }
                        match copies.entry(key) {
                            Entry::Occupied(e) => {
                                let e = *e.get();
                                if physical != 0 && element_physical[e] != physical {
                                    let more = merged.entry(e).or_default();
                                    if !more.contains(&physical) {
                                        more.push(physical);
                                    }
                                }
                                continue;
                            }
                            Entry::Vacant(v) => {
                                v.insert(element_tags.len());
                            }
                        }
                    }
                    element_tags.push(tag as u64);
                    element_types.push(ty);
                    element_nodes.extend(nodes.iter().map(|&v| v as u64));
                    offsets.push(element_nodes.len());
                    element_physical.push(physical);
                    element_entity.push(entity);
                    element_lines.push(line);
                }
                expect_end(&mut lines, path, "$Elements", count, "elements")?;
            }
            "ParametricNodes" => {
                return Err(MeshError::UnsupportedFormat {
                    path: path.to_path_buf(),
                    detail: format!(
                        "line {line}: $ParametricNodes is not supported; re-export the mesh with gmsh -format msh41"
                    ),
                })
            }
            _ => {
                // Any other section ($PhysicalNames, read separately; $Periodic; $NodeData, ...): skip.
                let end = format!("$End{name}");
                loop {
                    match lines.next_line() {
                        Some((_, l)) if trim(l) == end.as_bytes() => break,
                        Some(_) => {}
                        None => {
                            return Err(syntax(
                                line,
                                &format!("${name}"),
                                format!("the section ${name} has no {end}: the file is truncated"),
                            ))
                        }
                    }
                }
            }
        }
    }
    if !seen_nodes || !seen_elements {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            place: format!("line {}", lines.line.saturating_sub(1).max(1)),
            detail: format!(
                "the file has no {} section: it is truncated, or was saved before meshing (gmsh -2 body.geo)",
                if seen_nodes { "$Elements" } else { "$Nodes" }
            ),
        });
    }

    // Intern (physical tags, entity) pairs.
    let mut origins: Vec<Origin> = Vec::new();
    type Entity = Option<(i32, i32)>;
    let mut origin_index: HashMap<(Vec<i32>, Entity), u32> = HashMap::new();
    let mut simple_index: HashMap<(i32, Option<(i32, i32)>), u32> = HashMap::new();
    let mut element_origin = Vec::with_capacity(element_tags.len());
    for (e, (&first, &entity)) in element_physical.iter().zip(&element_entity).enumerate() {
        let mut intern = |physical: Vec<i32>| {
            *origin_index.entry((physical.clone(), entity)).or_insert_with(|| {
                origins.push(Origin { physical, entity });
                origins.len() as u32 - 1
            })
        };
        let o = match merged.get(&e) {
            Some(more) => {
                let mut physical: Vec<i32> = if first != 0 { vec![first] } else { Vec::new() };
                physical.extend(more.iter().copied().filter(|&p| p != first));
                intern(physical)
            }
            None => *simple_index
                .entry((first, entity))
                .or_insert_with(|| intern(if first != 0 { vec![first] } else { Vec::new() })),
        };
        element_origin.push(o);
    }

    Ok(RawMesh {
        node_tags,
        coords,
        element_tags,
        element_types,
        offsets,
        element_nodes,
        element_origin,
        origins,
        names,
        places: Places {
            node_lines: Some(node_lines),
            element_line: Box::new(move |e, _| element_lines.get(e).copied()),
        },
    })
}

/// Reads the count line of a section and checks it against the bytes left (each item takes
/// at least `min_bytes`).
fn read_count(lines: &mut Lines<'_>, path: &Path, section: &str, min_bytes: usize) -> Result<usize, MeshError> {
    let place = |line: usize| format!("line {line} ({section})");
    let Some((line, l)) = lines.next_nonblank() else {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            place: place(lines.line),
            detail: format!("the file ends inside {section}: it is truncated"),
        });
    };
    let text = String::from_utf8_lossy(trim(l)).into_owned();
    let count: u64 = text.parse().map_err(|_| MeshError::Syntax {
        path: path.to_path_buf(),
        place: place(line),
        detail: format!("expected the number of entries, found \"{text}\""),
    })?;
    if count.saturating_mul(min_bytes as u64) > lines.remaining() as u64 {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            place: place(line),
            detail: format!(
                "the section says {count} entries, but only {} bytes follow (at least {min_bytes} per entry): \
                 the file is truncated or its header is corrupt; re-export it",
                lines.remaining()
            ),
        });
    }
    Ok(count as usize)
}

fn expect_end(lines: &mut Lines<'_>, path: &Path, section: &str, count: usize, what: &str) -> Result<(), MeshError> {
    let end = format!("$End{}", &section[1..]);
    let line_no = lines.line;
    match lines.next_nonblank() {
        Some((_, l)) if trim(l) == end.as_bytes() => Ok(()),
        Some((line, l)) => Err(MeshError::Syntax {
            path: path.to_path_buf(),
            place: format!("line {line} ({section})"),
            detail: format!(
                "expected {end} after {count} {what}, found \"{}\": the count in the section header is wrong",
                String::from_utf8_lossy(trim(l))
            ),
        }),
        None => Err(MeshError::Syntax {
            path: path.to_path_buf(),
            place: format!("line {line_no} ({section})"),
            detail: format!("the file ends before {end}: it is truncated; re-export it"),
        }),
    }
}
