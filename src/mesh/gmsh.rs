//! What the MSH readers share (docs/method.md §2, §8): the file header and format version, lines
//! with their numbers, gmsh's element types, and where an element or node was read (for
//! messages).

use crate::mesh::MeshError;
use std::path::Path;

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
    pub(super) fn parse(path: &Path, bytes: &[u8]) -> Result<Header, MeshError> {
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
    pub(super) bytes: &'a [u8],
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
