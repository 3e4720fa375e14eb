//! The 3D mesh mutation campaign (issue 23): 3 000 deterministic mutations of the 3D base meshes
//! (`block_p1.msh` and `block_q1_h8.msh` in ASCII MSH 4.1, `block_p1_bin.msh` in binary MSH 4.1,
//! `block_p1_v22.msh` in ASCII MSH 2.2) are read in-process, and the campaign must end with
//! 0 panics, 0 hangs and 0 accepted meshes whose groups are not faces of the mesh.
//!
//! Why: a mesh that reads but whose boundary group is not made of faces of the body gives a
//! wrong answer without any error (a load on facets that no cell holds, a prescribed node inside
//! the body). The most likely way to get one is a node tag changed in `$Elements`, so besides
//! byte-level edits (set a byte or a digit, delete a span, insert a token, duplicate or swap
//! lines, truncate) about half of the edits rewrite the node tags of one element: another node
//! tag (random, of the same element, of a nearby or any element, missing, 0), two nodes of an
//! element swapped, or a surface element given the nodes of a face of a volume element (mostly
//! an interior face). In the binary file these edits rewrite the 8-byte node tags in place.
//!
//! Each case: `parse_msh` under `catch_unwind` (a panic is a failure, reported with its case,
//! base, edit list and message; the first three also with a backtrace; the campaign goes on).
//! A mesh that is accepted is asked, also under `catch_unwind`, for `defects()`, and for each
//! group a scene can name (Gamma1–3 and Omega by name, up to six other groups by tag) for
//! `boundary` (contact and load groups) and `boundary_group_nodes` (prescribed groups); a
//! [`Simulation`] of a small scene using Gamma1–3 is built on it too. Every group accepted by
//! `boundary` or `boundary_group_nodes` is checked here with the test's own face tables of
//! tetrahedra and hexahedra (by sorted node set): every facet of the group is a face of exactly
//! one cell (curves: edges of such faces; points: their nodes); every facet of a part returned by
//! `boundary` is a cell's face of one cell, in that cell's outward order; the nodes returned are
//! on the boundary.
//!
//! Hangs: the campaign runs on a worker thread that publishes, before each case, the case number,
//! its description and its start time (atomics and a mutex); the test thread polls every 20 ms
//! and fails, naming the case and its edits, as soon as one case has run for more than 10 s. A
//! hung worker cannot be stopped, so the first hang ends the campaign (the worker is left behind
//! and ends with the test process).
//!
//! The mutated bytes of the first eight failing cases are written to `target/tmp/mesh_mutations_3d/` to be
//! reproduced with `hvi check FILE --scene ...`; the case is also reproducible from its number
//! alone (the edits of case i depend only on [`SEED`] and i).

use hvi::mesh::{parse_msh, AnyMesh, Cell, GroupSelector, Mesh, MeshError, PhysicalGroup};
use hvi::scene::Scene;
use hvi::solver::Simulation;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, Once};
use std::time::{Duration, Instant};

/// Mutations in all, spread over the bases by [`BASES`]' shares.
const CASES: usize = 3000;
/// The seed of the campaign: case i's edits come from a generator seeded with (SEED, i).
const SEED: u64 = 0x0023_3d3d_5eed_0023;
/// A case that runs longer than this is a hang.
const HANG: Duration = Duration::from_secs(10);
/// The name of the worker thread (the panic hook records only its panics).
const WORKER: &str = "mesh-mutations-3d";

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii41,
    Binary41,
    Ascii22,
}

/// The base meshes (in `meshes/`), their format and their share of the cases: the large ASCII
/// tetrahedra (5 301 cells) get fewer cases, as each accepted one costs more to check.
const BASES: &[(&str, Format, usize)] = &[
    ("block_p1.msh", Format::Ascii41, 500),
    ("block_q1_h8.msh", Format::Ascii41, 850),
    ("block_p1_bin.msh", Format::Binary41, 850),
    ("block_p1_v22.msh", Format::Ascii22, 800),
];

struct Base {
    name: &'static str,
    format: Format,
    bytes: Vec<u8>,
    /// The largest node tag of the unmutated file's elements.
    max_node: u64,
}

fn bases() -> Vec<Base> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes");
    BASES
        .iter()
        .map(|&(name, format, _)| {
            let bytes = std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
            let max_node = elements(&bytes, format)
                .iter()
                .flat_map(|e| e.nodes.iter().map(|s| s.value))
                .max()
                .unwrap_or_else(|| panic!("{name}: no elements found"));
            Base {
                name,
                format,
                bytes,
                max_node,
            }
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Random numbers: splitmix64, no crate.

struct Rng(u64);

impl Rng {
    fn new(seed: u64, stream: u64) -> Rng {
        let mut r = Rng(seed ^ stream.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        r.next();
        r
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }

    /// One of `choices` with probability proportional to its weight.
    fn pick<T: Copy>(&mut self, choices: &[(u64, T)]) -> T {
        let total: u64 = choices.iter().map(|c| c.0).sum();
        let mut r = self.below(total);
        for &(w, t) in choices {
            if r < w {
                return t;
            }
            r -= w;
        }
        unreachable!("r < total")
    }
}

// ---------------------------------------------------------------------------------------------
// The edits. Positions are raw random numbers taken modulo the current length (or element
// count) when applied, so an edit list describes its mutation completely.

/// Tokens that make interesting nonsense in an MSH file.
const TOKENS: &[&str] = &[
    "0",
    "-1",
    "1",
    "4",
    "5",
    "1e999",
    "-1e999",
    "nan",
    "inf",
    "1e-300",
    "18446744073709551616",
    "18446744073709551615",
    "4294967296",
    "2147483648",
    "1000000000000",
    "$EndNodes",
    "$Nodes",
    "$Elements",
    "$EndElements",
    "$PhysicalNames",
    "$EndPhysicalNames",
    "$Entities",
    "$EndEntities",
    "$MeshFormat",
    "\"",
    "\n",
    " ",
    "\r\n",
    "\t",
    "2 3 ",
    "\0",
    "é",
];

/// The new value of a node tag.
#[derive(Clone, Copy, Debug)]
enum NewTag {
    /// 1 + r mod (largest node tag of the base).
    Any(u64),
    /// Another node of the same element (a degenerate element).
    SameElement(u64),
    /// A node of an element a few places away (most likely a neighbour: nearly a face).
    Nearby(i64, u64),
    /// A node of any element.
    OtherElement(u64, u64),
    /// One past the largest node tag (no such node).
    Missing,
    Zero,
}

#[derive(Clone, Debug)]
enum Edit {
    SetByte {
        at: u64,
        byte: u8,
    },
    /// The first digit at or after `at` (wrapping) set to another digit.
    SetDigit {
        at: u64,
        digit: u8,
    },
    Delete {
        at: u64,
        len: usize,
    },
    Insert {
        at: u64,
        token: &'static str,
    },
    DuplicateLine {
        at: u64,
    },
    SwapLines {
        a: u64,
        b: u64,
    },
    Truncate {
        at: u64,
    },
    /// One node tag of one element of `$Elements` rewritten.
    NodeTag {
        element: u64,
        slot: u64,
        to: NewTag,
    },
    /// Two node tags of one element swapped.
    SwapNodes {
        element: u64,
        i: u64,
        j: u64,
    },
    /// A surface element (triangle, quadrangle) given the nodes of a face of a volume element.
    CopyFace {
        surface: u64,
        volume: u64,
        face: u64,
    },
}

#[derive(Clone, Copy)]
enum Kind {
    SetByte,
    SetDigit,
    Delete,
    Insert,
    DuplicateLine,
    SwapLines,
    Truncate,
    NodeTag,
    SwapNodes,
    CopyFace,
}

fn random_edit(rng: &mut Rng, format: Format) -> Edit {
    let bytewise = if format == Format::Binary41 { 24 } else { 8 };
    let digit = if format == Format::Binary41 { 4 } else { 16 };
    let kind = rng.pick(&[
        (bytewise, Kind::SetByte),
        (digit, Kind::SetDigit),
        (6, Kind::Delete),
        (12, Kind::Insert),
        (5, Kind::DuplicateLine),
        (5, Kind::SwapLines),
        (3, Kind::Truncate),
        (30, Kind::NodeTag),
        (6, Kind::SwapNodes),
        (9, Kind::CopyFace),
    ]);
    match kind {
        Kind::SetByte => Edit::SetByte {
            at: rng.next(),
            byte: rng.next() as u8,
        },
        Kind::SetDigit => Edit::SetDigit {
            at: rng.next(),
            digit: rng.below(10) as u8,
        },
        Kind::Delete => {
            let longest = if rng.below(4) == 0 { 400 } else { 24 };
            Edit::Delete {
                at: rng.next(),
                len: 1 + rng.below(longest) as usize,
            }
        }
        Kind::Insert => Edit::Insert {
            at: rng.next(),
            token: TOKENS[rng.below(TOKENS.len() as u64) as usize],
        },
        Kind::DuplicateLine => Edit::DuplicateLine { at: rng.next() },
        Kind::SwapLines => Edit::SwapLines {
            a: rng.next(),
            b: rng.next(),
        },
        Kind::Truncate => Edit::Truncate { at: rng.next() },
        Kind::NodeTag => {
            let to = match rng.below(12) {
                0..=3 => NewTag::Any(rng.next()),
                4 => NewTag::SameElement(rng.next()),
                5..=8 => NewTag::Nearby(rng.below(7) as i64 - 3, rng.next()),
                9 => NewTag::OtherElement(rng.next(), rng.next()),
                10 => NewTag::Missing,
                _ => NewTag::Zero,
            };
            Edit::NodeTag {
                element: rng.next(),
                slot: rng.next(),
                to,
            }
        }
        Kind::SwapNodes => Edit::SwapNodes {
            element: rng.next(),
            i: rng.next(),
            j: rng.next(),
        },
        Kind::CopyFace => Edit::CopyFace {
            surface: rng.next(),
            volume: rng.next(),
            face: rng.next(),
        },
    }
}

/// The byte range of the line holding byte `i` (with its newline).
fn line_at(bytes: &[u8], i: usize) -> (usize, usize) {
    let i = i.min(bytes.len());
    let start = bytes[..i].iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
    let end = bytes[i..]
        .iter()
        .position(|&c| c == b'\n')
        .map_or(bytes.len(), |p| i + p + 1);
    (start, end)
}

fn apply(bytes: &mut Vec<u8>, edit: &Edit, base: &Base) {
    let n = bytes.len().max(1) as u64;
    let pos = |at: u64| (at % n) as usize;
    match *edit {
        Edit::SetByte { at, byte } => {
            if !bytes.is_empty() {
                let i = pos(at);
                bytes[i] = byte;
            }
        }
        Edit::SetDigit { at, digit } => {
            if bytes.is_empty() {
                return;
            }
            let start = pos(at);
            let len = bytes.len();
            if let Some(k) = (0..len).map(|k| (start + k) % len).find(|&k| bytes[k].is_ascii_digit()) {
                let d = b'0' + digit;
                bytes[k] = if bytes[k] == d { b'0' + (digit + 1) % 10 } else { d };
            }
        }
        Edit::Delete { at, len } => {
            let i = pos(at).min(bytes.len());
            let end = (i + len).min(bytes.len());
            bytes.drain(i..end);
        }
        Edit::Insert { at, token } => {
            let i = pos(at).min(bytes.len());
            bytes.splice(i..i, token.bytes());
        }
        Edit::DuplicateLine { at } => {
            let (s, e) = line_at(bytes, pos(at));
            let line = bytes[s..e].to_vec();
            bytes.splice(s..s, line);
        }
        Edit::SwapLines { a, b } => {
            let (a, b) = (line_at(bytes, pos(a)), line_at(bytes, pos(b)));
            let (first, second) = if a.0 <= b.0 { (a, b) } else { (b, a) };
            if first.1 <= second.0 && first != second {
                let mut out = Vec::with_capacity(bytes.len());
                out.extend_from_slice(&bytes[..first.0]);
                out.extend_from_slice(&bytes[second.0..second.1]);
                out.extend_from_slice(&bytes[first.1..second.0]);
                out.extend_from_slice(&bytes[first.0..first.1]);
                out.extend_from_slice(&bytes[second.1..]);
                *bytes = out;
            }
        }
        Edit::Truncate { at } => {
            let i = pos(at);
            bytes.truncate(i);
        }
        Edit::NodeTag { element, slot, to } => {
            let els = elements(bytes, base.format);
            let nonempty: Vec<usize> = (0..els.len()).filter(|&k| !els[k].nodes.is_empty()).collect();
            if nonempty.is_empty() {
                return;
            }
            let idx = nonempty[(element % nonempty.len() as u64) as usize];
            let e = &els[idx];
            let target = &e.nodes[(slot % e.nodes.len() as u64) as usize];
            let node_of = |el: &Element, k: u64| {
                if el.nodes.is_empty() {
                    0
                } else {
                    el.nodes[(k % el.nodes.len() as u64) as usize].value
                }
            };
            let value = match to {
                NewTag::Any(r) => 1 + r % base.max_node,
                NewTag::SameElement(k) => node_of(e, k),
                NewTag::Nearby(off, k) => {
                    let j = (idx as i64 + off).clamp(0, els.len() as i64 - 1) as usize;
                    node_of(&els[j], k)
                }
                NewTag::OtherElement(j, k) => node_of(&els[(j % els.len() as u64) as usize], k),
                NewTag::Missing => base.max_node + 1,
                NewTag::Zero => 0,
            };
            write_tags(bytes, base.format, vec![(target.clone(), value)]);
        }
        Edit::SwapNodes { element, i, j } => {
            let els = elements(bytes, base.format);
            let candidates: Vec<&Element> = els.iter().filter(|e| e.nodes.len() >= 2).collect();
            if candidates.is_empty() {
                return;
            }
            let e = candidates[(element % candidates.len() as u64) as usize];
            let m = e.nodes.len() as u64;
            let (a, b) = (&e.nodes[(i % m) as usize], &e.nodes[(j % m) as usize]);
            if a.start != b.start {
                write_tags(bytes, base.format, vec![(a.clone(), b.value), (b.clone(), a.value)]);
            }
        }
        Edit::CopyFace { surface, volume, face } => {
            let els = elements(bytes, base.format);
            let surfaces: Vec<&Element> = els
                .iter()
                .filter(|e| matches!(e.ty, 2 | 3) && e.nodes.len() >= 3)
                .collect();
            let volumes: Vec<&Element> = els
                .iter()
                .filter(|e| (e.ty == 4 && e.nodes.len() == 4) || (e.ty == 5 && e.nodes.len() == 8))
                .collect();
            if surfaces.is_empty() || volumes.is_empty() {
                return;
            }
            let s = surfaces[(surface % surfaces.len() as u64) as usize];
            let v = volumes[(volume % volumes.len() as u64) as usize];
            let local: &[usize] = if v.ty == 4 {
                &TET_FACES[(face % 4) as usize]
            } else {
                &HEX_FACES[(face % 6) as usize]
            };
            let writes = s
                .nodes
                .iter()
                .zip(local)
                .map(|(slot, &k)| (slot.clone(), v.nodes[k].value))
                .collect();
            write_tags(bytes, base.format, writes);
        }
    }
}

/// Where one node tag of an element is in the file.
#[derive(Clone, Debug)]
struct Slot {
    start: usize,
    end: usize,
    value: u64,
}

/// An element of `$Elements` as found in the (possibly mutated) bytes: its gmsh type and the
/// places of its node tags.
struct Element {
    ty: u32,
    nodes: Vec<Slot>,
}

/// Nodes of the gmsh element types of the bases.
fn nodes_of(ty: u32) -> Option<usize> {
    match ty {
        15 => Some(1),
        1 => Some(2),
        2 => Some(3),
        3 | 4 => Some(4),
        5 => Some(8),
        _ => None,
    }
}

fn find(bytes: &[u8], pattern: &[u8], from: usize) -> Option<usize> {
    bytes
        .get(from..)?
        .windows(pattern.len())
        .position(|w| w == pattern)
        .map(|p| p + from)
}

/// The elements of the `$Elements` section, read as far as the mutated bytes allow (an edit
/// may have broken the structure: then those read before the break).
fn elements(bytes: &[u8], format: Format) -> Vec<Element> {
    let Some(section) = find(bytes, b"\n$Elements", 0) else {
        return Vec::new();
    };
    let Some(body) = find(bytes, b"\n", section + 1).map(|p| p + 1) else {
        return Vec::new();
    };
    match format {
        Format::Binary41 => binary_elements(bytes, body),
        Format::Ascii41 | Format::Ascii22 => ascii_elements(bytes, body, format),
    }
}

/// The whitespace-separated tokens of a line, with their byte ranges.
fn tokens(bytes: &[u8], start: usize, end: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = start;
    while i < end {
        while i < end && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let s = i;
        while i < end && !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if s < i {
            out.push((s, i));
        }
    }
    out
}

fn ascii_elements(bytes: &[u8], body: usize, format: Format) -> Vec<Element> {
    let number = |(s, e): (usize, usize)| -> Option<u64> { std::str::from_utf8(&bytes[s..e]).ok()?.parse().ok() };
    let mut lines = Vec::new();
    let mut i = body;
    while i < bytes.len() {
        let end = bytes[i..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(bytes.len(), |p| i + p);
        if bytes[i..end].starts_with(b"$End") {
            break;
        }
        lines.push((i, end));
        i = end + 1;
    }
    let slots = |toks: &[(usize, usize)]| -> Vec<Slot> {
        toks.iter()
            .map(|&(s, e)| Slot {
                start: s,
                end: e,
                value: number((s, e)).unwrap_or(0),
            })
            .collect()
    };
    let mut out = Vec::new();
    match format {
        Format::Ascii22 => {
            for &(s, e) in lines.iter().skip(1) {
                let t = tokens(bytes, s, e);
                let (Some(ty), Some(ntags)) = (t.get(1).and_then(|&x| number(x)), t.get(2).and_then(|&x| number(x)))
                else {
                    continue;
                };
                let first = 3usize.saturating_add(ntags as usize).min(t.len());
                out.push(Element {
                    ty: ty as u32,
                    nodes: slots(&t[first..]),
                });
            }
        }
        _ => {
            // the section header, then blocks: "dim entity type count" and count element lines
            let mut k = 1;
            while k < lines.len() {
                let header = tokens(bytes, lines[k].0, lines[k].1);
                k += 1;
                let (Some(ty), Some(count)) = (
                    header.get(2).and_then(|&x| number(x)),
                    header.get(3).and_then(|&x| number(x)),
                ) else {
                    break;
                };
                for _ in 0..count.min(lines.len() as u64) {
                    let Some(&(s, e)) = lines.get(k) else { break };
                    k += 1;
                    let t = tokens(bytes, s, e);
                    let n = nodes_of(ty as u32).unwrap_or(usize::MAX);
                    let last = t.len().min(n.saturating_add(1));
                    out.push(Element {
                        ty: ty as u32,
                        nodes: slots(&t[1.min(last)..last]),
                    });
                }
            }
        }
    }
    out
}

fn binary_elements(bytes: &[u8], body: usize) -> Vec<Element> {
    let u64_at = |p: usize| -> Option<u64> { Some(u64::from_le_bytes(bytes.get(p..p + 8)?.try_into().ok()?)) };
    let i32_at = |p: usize| -> Option<i32> { Some(i32::from_le_bytes(bytes.get(p..p + 4)?.try_into().ok()?)) };
    let mut out = Vec::new();
    let Some(blocks) = u64_at(body) else { return out };
    let mut p = body + 32;
    for _ in 0..blocks.min(1 << 20) {
        let (Some(ty), Some(count)) = (i32_at(p + 8), u64_at(p + 12)) else {
            break;
        };
        p += 20;
        let Some(n) = nodes_of(ty as u32) else { break };
        let size = 8 * (1 + n);
        for _ in 0..count.min((bytes.len() / size) as u64) {
            if p + size > bytes.len() {
                return out;
            }
            let nodes = (0..n)
                .map(|a| {
                    let s = p + 8 * (1 + a);
                    Slot {
                        start: s,
                        end: s + 8,
                        value: u64_at(s).unwrap_or(0),
                    }
                })
                .collect();
            out.push(Element { ty: ty as u32, nodes });
            p += size;
        }
    }
    out
}

/// Writes node tags into their slots (decimal in ASCII files, 8 bytes little-endian in binary
/// ones), from the last slot to the first so that the earlier places stay valid.
fn write_tags(bytes: &mut Vec<u8>, format: Format, mut writes: Vec<(Slot, u64)>) {
    writes.sort_by_key(|w| std::cmp::Reverse(w.0.start));
    for (slot, value) in writes {
        match format {
            Format::Binary41 => bytes[slot.start..slot.end].copy_from_slice(&value.to_le_bytes()),
            _ => {
                bytes.splice(slot.start..slot.end, value.to_string().bytes());
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The test's own faces of the cells (not hvi's tables): outward-oriented (counter-clockwise seen
// from outside) for a positively oriented cell with gmsh's node order.

/// Tetrahedron (x₁−x₀)×(x₂−x₀)·(x₃−x₀) > 0: the faces opposite nodes 3, 2, 1, 0.
const TET_FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
/// Hexahedron, nodes 0–3 at ζ = −1 and 4–7 at ζ = +1: the faces ζ = ∓1, η = ∓1, ξ = ∓1.
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [3, 7, 6, 2],
    [0, 4, 7, 3],
    [1, 2, 6, 5],
];
const TRI_EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];
const QUAD_EDGES: [[usize; 2]; 4] = [[0, 1], [1, 2], [2, 3], [3, 0]];

fn cell_faces(cell: &Cell) -> Vec<Vec<usize>> {
    let n = cell.nodes();
    let map = |local: &[usize]| local.iter().map(|&k| n[k]).collect::<Vec<usize>>();
    match cell {
        Cell::Tet4(_) => TET_FACES.iter().map(|f| map(f)).collect(),
        Cell::Hex8(_) => HEX_FACES.iter().map(|f| map(f)).collect(),
        Cell::Tri3(_) => TRI_EDGES.iter().map(|f| map(f)).collect(),
        Cell::Quad4(_) => QUAD_EDGES.iter().map(|f| map(f)).collect(),
        // prism: the triangles ζ = ∓1 and the three side quadrangles
        Cell::Prism6(_) => [&[0, 2, 1][..], &[3, 4, 5], &[0, 1, 4, 3], &[1, 2, 5, 4], &[2, 0, 3, 5]]
            .iter()
            .map(|f| map(f))
            .collect(),
        // pyramid: the base and the four triangles up to the apex
        Cell::Pyr5(_) => [&[0, 3, 2, 1][..], &[0, 1, 4], &[1, 2, 4], &[2, 3, 4], &[3, 0, 4]]
            .iter()
            .map(|f| map(f))
            .collect(),
        _ => unreachable!("these tests mutate first-order meshes"),
    }
}

fn key(nodes: &[usize]) -> Vec<usize> {
    let mut k = nodes.to_vec();
    k.sort_unstable();
    k
}

/// The faces of a mesh's cells by node set: how many cells hold each, and the outward face of
/// the first; the nodes and edges of the boundary faces (those of one cell).
struct Faces {
    count: HashMap<Vec<usize>, (u32, Vec<usize>)>,
    boundary_nodes: HashSet<usize>,
    boundary_edges: HashSet<(usize, usize)>,
}

impl Faces {
    fn of<const D: usize>(mesh: &Mesh<D>) -> Faces {
        let mut count: HashMap<Vec<usize>, (u32, Vec<usize>)> = HashMap::new();
        for cell in &mesh.cells {
            for f in cell_faces(cell) {
                count.entry(key(&f)).or_insert((0, f)).0 += 1;
            }
        }
        let (mut boundary_nodes, mut boundary_edges) = (HashSet::new(), HashSet::new());
        for (c, f) in count.values() {
            if *c == 1 {
                for (i, &a) in f.iter().enumerate() {
                    boundary_nodes.insert(a);
                    let b = f[(i + 1) % f.len()];
                    boundary_edges.insert((a.min(b), a.max(b)));
                }
            }
        }
        Faces {
            count,
            boundary_nodes,
            boundary_edges,
        }
    }

    fn holders(&self, nodes: &[usize]) -> u32 {
        self.count.get(&key(nodes)).map_or(0, |c| c.0)
    }

    /// Why the group is not on the boundary of the body, if it is not: a facet (of dimension
    /// D − 1) that is not a face of exactly one cell, a line that is not an edge of such a face,
    /// a point that is not a node of one.
    fn group_defect<const D: usize>(&self, mesh: &Mesh<D>, g: &PhysicalGroup) -> Option<String> {
        let n = mesh.points.len();
        if g.dim as usize == D - 1 {
            for f in &g.facets {
                let nodes = f.nodes();
                if nodes.iter().any(|&p| p >= n) {
                    return Some(format!("facet {nodes:?} refers to a node past the {n} points"));
                }
                let holders = self.holders(nodes);
                if holders != 1 {
                    return Some(format!("facet {nodes:?} is a face of {holders} cells"));
                }
            }
        } else if g.dim == 1 {
            for f in &g.facets {
                let e = f.nodes();
                if e.len() != 2 || !self.boundary_edges.contains(&(e[0].min(e[1]), e[0].max(e[1]))) {
                    return Some(format!("line {e:?} is not an edge of a boundary face"));
                }
            }
        } else if g.dim == 0 {
            if let Some(p) = g.nodes.iter().find(|p| !self.boundary_nodes.contains(p)) {
                return Some(format!("point {p} is not a node of a boundary face"));
            }
        } else {
            return Some(format!("a group of dimension {} used as a boundary group", g.dim));
        }
        None
    }
}

/// True if `b` runs through the same nodes as `a` in the same cyclic order.
fn same_cycle(a: &[usize], b: &[usize]) -> bool {
    let n = a.len();
    n == b.len() && (0..n).any(|r| (0..n).all(|k| a[k] == b[(k + r) % n]))
}

// ---------------------------------------------------------------------------------------------
// One case.

/// What one case found.
#[derive(Default)]
struct Outcome {
    accepted: bool,
    /// The kind of error a rejected mesh got.
    rejected_as: Option<&'static str>,
    /// A rejection whose message does not name the file.
    unnamed_error: Option<String>,
    panics: Vec<String>,
    /// Accepted groups that are not faces of the mesh (or parts that are wrong).
    bad_groups: Vec<String>,
    parts_accepted: usize,
    parts_rejected_not_boundary: usize,
    prescribed_accepted: usize,
    prescribed_rejected_not_boundary: usize,
    severe_defects: bool,
    simulation_built: bool,
}

static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);
static BACKTRACES: AtomicUsize = AtomicUsize::new(0);
static HOOK: Once = Once::new();

/// Records the worker's panics (message, place, and for the first three a backtrace) instead
/// of printing them; other threads' panics go to the previous hook.
fn install_panic_hook() {
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if std::thread::current().name() == Some(WORKER) {
                let trace = if BACKTRACES.fetch_add(1, Ordering::SeqCst) < 3 {
                    format!("\n{}", std::backtrace::Backtrace::force_capture())
                } else {
                    String::new()
                };
                *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{info}{trace}"));
            } else {
                previous(info);
            }
        }));
    });
}

/// Runs `f`, turning a panic into an entry of `out.panics` named by `stage`.
fn guarded<T>(out: &mut Outcome, stage: &str, f: impl FnOnce() -> T) -> Option<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(v) => Some(v),
        Err(payload) => {
            let hooked = LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()).take();
            let message = hooked.unwrap_or_else(|| {
                payload
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "(a panic without a message)".into())
            });
            out.panics.push(format!("{stage}: {message}"));
            None
        }
    }
}

/// The scene whose simulation is built on every accepted 3D mesh: Gamma1 clamped, a traction
/// on Gamma2, contact on Gamma3.
const SCENE: &str = "[groups]\nclamped = \"Gamma1\"\ncontact = \"Gamma3\"\n\
    [material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n\
    [[traction]]\ngroup = \"Gamma2\"\nvalue = [\"0\", \"0\", \"-0.01\"]\n[contact]\nbound = 0.1\n";

fn run_case(name: &str, bytes: &[u8], scene: &Scene) -> Outcome {
    let mut out = Outcome::default();
    let path = PathBuf::from(name);
    let Some(parsed) = guarded(&mut out, "parse_msh", || parse_msh(&path, bytes)) else {
        return out;
    };
    match parsed {
        Err(e) => {
            out.rejected_as = Some(match e {
                MeshError::Io { .. } => "Io",
                MeshError::UnsupportedFormat { .. } => "UnsupportedFormat",
                MeshError::Syntax { .. } => "Syntax",
                MeshError::UnsupportedElement { .. } => "UnsupportedElement",
                MeshError::Invalid { .. } => "Invalid",
                MeshError::GroupNotFound { .. } => "GroupNotFound",
                MeshError::Defects { .. } => "Defects",
                MeshError::NotBoundary { .. } => "NotBoundary",
            });
            let message = e.to_string();
            if !message.contains(name) {
                out.unnamed_error = Some(message);
            }
        }
        Ok(AnyMesh::Three(mesh)) => {
            out.accepted = true;
            check_mesh(&mesh, &mut out);
            if let Some(Ok(_)) = guarded(&mut out, "Simulation::new", || Simulation::new(scene, mesh)) {
                out.simulation_built = true;
            }
        }
        Ok(AnyMesh::Two(mesh)) => {
            out.accepted = true;
            check_mesh(&mesh, &mut out);
        }
    }
    out
}

/// The groups a scene could name: Gamma1–3 and Omega by name, every other group by its tag.
fn selectors<const D: usize>(mesh: &Mesh<D>) -> Vec<GroupSelector> {
    let names = ["Gamma1", "Gamma2", "Gamma3", "Omega"];
    let mut out: Vec<GroupSelector> = names.iter().map(|&n| GroupSelector::from(n)).collect();
    let mut tags: Vec<i32> = mesh
        .groups
        .iter()
        .filter(|g| !g.name.as_deref().is_some_and(|n| names.contains(&n)))
        .map(|g| g.tag)
        .collect();
    tags.sort_unstable();
    tags.dedup();
    out.extend(tags.into_iter().take(6).map(GroupSelector::Tag));
    out
}

fn check_mesh<const D: usize>(mesh: &Mesh<D>, out: &mut Outcome) {
    let n = mesh.points.len();
    if let Some(c) = mesh.cells.iter().find(|c| c.nodes().iter().any(|&p| p >= n)) {
        out.bad_groups
            .push(format!("cell {:?} refers to a node past the {n} points", c.nodes()));
        return;
    }
    if let Some(defects) = guarded(out, "defects", || mesh.defects()) {
        out.severe_defects = defects.iter().any(|d| d.severe);
    }
    let faces = Faces::of(mesh);
    for sel in selectors(mesh) {
        // contact and load groups
        match guarded(out, &format!("boundary({sel})"), || mesh.boundary(&sel)) {
            Some(Ok(part)) => {
                out.parts_accepted += 1;
                let group = mesh.group(&sel, (D - 1) as u8).expect("boundary found it");
                if let Some(why) = faces.group_defect(mesh, group) {
                    out.bad_groups
                        .push(format!("boundary({sel}) accepted {}: {why}", group.label()));
                }
                for f in &part.facets {
                    let ok = faces
                        .count
                        .get(&key(f.nodes()))
                        .is_some_and(|(c, outward)| *c == 1 && same_cycle(outward, f.nodes()));
                    if !ok {
                        out.bad_groups.push(format!(
                            "boundary({sel}): its facet {:?} is not the outward face of one cell",
                            f.nodes()
                        ));
                        break;
                    }
                }
                let mut nodes: Vec<usize> = group.facets.iter().flat_map(|f| f.nodes().to_vec()).collect();
                nodes.sort_unstable();
                nodes.dedup();
                if part.nodes != nodes || part.weights.len() != nodes.len() || part.normals.len() != nodes.len() {
                    out.bad_groups
                        .push(format!("boundary({sel}): its nodes are not the group's"));
                }
            }
            Some(Err(MeshError::NotBoundary { .. })) => out.parts_rejected_not_boundary += 1,
            _ => {}
        }
        // prescribed groups: the group boundary_group_nodes resolves (dimension D − 1 first)
        match guarded(out, &format!("boundary_group_nodes({sel})"), || {
            mesh.boundary_group_nodes(&sel)
        }) {
            Some(Ok(nodes)) => {
                out.prescribed_accepted += 1;
                let group = (0..D as u8)
                    .rev()
                    .find_map(|dim| mesh.group(&sel, dim).ok())
                    .expect("boundary_group_nodes found it");
                if let Some(why) = faces.group_defect(mesh, group) {
                    out.bad_groups
                        .push(format!("boundary_group_nodes({sel}) accepted {}: {why}", group.label()));
                }
                if let Some(p) = nodes.iter().find(|p| !faces.boundary_nodes.contains(p)) {
                    out.bad_groups.push(format!(
                        "boundary_group_nodes({sel}) returned node {p}, not on the boundary"
                    ));
                }
            }
            Some(Err(MeshError::NotBoundary { .. })) => out.prescribed_rejected_not_boundary += 1,
            _ => {}
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The campaign.

/// What the worker publishes for the hang watch.
struct Progress {
    /// Milliseconds from the campaign's start at which the current case started.
    since_ms: AtomicU64,
    /// The current case, described (base, number, edits).
    current: Mutex<String>,
    done: AtomicBool,
}

#[derive(Default, Clone)]
struct Tally {
    cases: usize,
    accepted: usize,
    rejected: usize,
    panics: usize,
    bad: usize,
    severe_defects: usize,
    simulations: usize,
}

struct Report {
    tallies: Vec<Tally>,
    failures: Vec<String>,
    panics: usize,
    bad_cases: usize,
    unnamed: usize,
    /// Rejected meshes by the kind of error.
    rejections: BTreeMap<&'static str, usize>,
    parts_accepted: usize,
    parts_rejected_not_boundary: usize,
    prescribed_accepted: usize,
    prescribed_rejected_not_boundary: usize,
    slowest: (Duration, String),
}

fn campaign(progress: &Progress, epoch: Instant) -> Report {
    let bases = bases();
    let scene = Scene::from_toml_str(SCENE, "mutations.toml").expect("the campaign's scene");
    let dump = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh_mutations_3d");
    let mut report = Report {
        tallies: vec![Tally::default(); bases.len()],
        failures: Vec::new(),
        panics: 0,
        bad_cases: 0,
        unnamed: 0,
        rejections: BTreeMap::new(),
        parts_accepted: 0,
        parts_rejected_not_boundary: 0,
        prescribed_accepted: 0,
        prescribed_rejected_not_boundary: 0,
        slowest: (Duration::ZERO, String::new()),
    };
    // case i goes to the base whose share covers i mod (sum of shares): interleaved, so that a
    // hang in one base does not hide the others' cases
    let shares: usize = BASES.iter().map(|b| b.2).sum();
    assert_eq!(shares, CASES);
    let owner: Vec<usize> = BASES.iter().enumerate().flat_map(|(k, b)| vec![k; b.2]).collect();
    let mut order: Vec<usize> = (0..CASES).collect();
    let mut shuffle = Rng::new(SEED, u64::MAX);
    for i in (1..order.len()).rev() {
        order.swap(i, shuffle.below(i as u64 + 1) as usize);
    }
    for case in 0..CASES {
        let b = owner[order[case]];
        let base = &bases[b];
        let mut rng = Rng::new(SEED, case as u64);
        let edits: Vec<Edit> = (0..1 + rng.below(3))
            .map(|_| random_edit(&mut rng, base.format))
            .collect();
        let describe = format!("case {case} on {} with edits {edits:?}", base.name);
        *progress.current.lock().unwrap() = describe.clone();
        let start = Instant::now();
        progress
            .since_ms
            .store(start.duration_since(epoch).as_millis() as u64, Ordering::SeqCst);

        let mut bytes = base.bytes.clone();
        for e in &edits {
            apply(&mut bytes, e, base);
        }
        let out = run_case(base.name, &bytes, &scene);

        let took = start.elapsed();
        if took > report.slowest.0 {
            report.slowest = (took, describe.clone());
        }
        let t = &mut report.tallies[b];
        t.cases += 1;
        if out.accepted {
            t.accepted += 1;
        } else {
            t.rejected += 1;
        }
        if let Some(kind) = out.rejected_as {
            *report.rejections.entry(kind).or_default() += 1;
        }
        t.severe_defects += out.severe_defects as usize;
        t.simulations += out.simulation_built as usize;
        report.parts_accepted += out.parts_accepted;
        report.parts_rejected_not_boundary += out.parts_rejected_not_boundary;
        report.prescribed_accepted += out.prescribed_accepted;
        report.prescribed_rejected_not_boundary += out.prescribed_rejected_not_boundary;
        let mut problems: Vec<String> = Vec::new();
        if !out.panics.is_empty() {
            t.panics += 1;
            report.panics += 1;
            problems.extend(out.panics.iter().map(|p| format!("PANIC in {p}")));
        }
        if !out.bad_groups.is_empty() {
            t.bad += 1;
            report.bad_cases += 1;
            problems.extend(out.bad_groups.iter().map(|g| format!("BAD GROUP: {g}")));
        }
        if let Some(m) = out.unnamed_error {
            report.unnamed += 1;
            problems.push(format!("an error that does not name the file: {m}"));
        }
        if !problems.is_empty() && report.failures.len() < 8 {
            let file = dump.join(format!("case{case}_{}", base.name));
            let saved = std::fs::create_dir_all(&dump).and_then(|_| std::fs::write(&file, &bytes));
            let saved = match saved {
                Ok(()) => format!("mutated bytes in {}", file.display()),
                Err(e) => format!("could not save the bytes: {e}"),
            };
            report
                .failures
                .push(format!("{describe} ({saved}):\n  {}", problems.join("\n  ")));
        }
    }
    progress.done.store(true, Ordering::SeqCst);
    report
}

/// The 3 000-case campaign: 0 panics, 0 hangs, 0 accepted groups that are not faces of the
/// mesh (see the module doc for how each is found).
#[test]
fn mutated_3d_meshes_never_panic_hang_or_accept_groups_that_are_not_faces() {
    install_panic_hook();
    let progress = Arc::new(Progress {
        since_ms: AtomicU64::new(0),
        current: Mutex::new("(starting)".into()),
        done: AtomicBool::new(false),
    });
    let epoch = Instant::now();
    let worker = {
        let progress = Arc::clone(&progress);
        std::thread::Builder::new()
            .name(WORKER.into())
            .stack_size(16 << 20)
            .spawn(move || campaign(&progress, epoch))
            .expect("spawn the campaign's worker")
    };
    // the hang watch: fail as soon as one case runs longer than HANG
    while !progress.done.load(Ordering::SeqCst) && !worker.is_finished() {
        std::thread::sleep(Duration::from_millis(20));
        let since = Duration::from_millis(progress.since_ms.load(Ordering::SeqCst));
        let running = epoch.elapsed().saturating_sub(since);
        if running > HANG && !progress.done.load(Ordering::SeqCst) && !worker.is_finished() {
            let current = progress.current.lock().unwrap_or_else(|e| e.into_inner()).clone();
            panic!("HANG: {current} has run for {running:?} (more than {HANG:?}); the campaign stops here (1 hang)");
        }
    }
    let report = match worker.join() {
        Ok(r) => r,
        Err(_) => panic!("the campaign's worker panicked outside a guarded call (a bug of this test)"),
    };
    let total = |f: fn(&Tally) -> usize| report.tallies.iter().map(f).sum::<usize>();
    for (base, t) in BASES.iter().zip(&report.tallies) {
        eprintln!(
            "mesh_mutations_3d: {:<18} {:>4} cases, {:>4} accepted ({} with severe defects, {} simulations built), \
             {:>4} rejected, {} panics, {} with bad groups",
            base.0, t.cases, t.accepted, t.severe_defects, t.simulations, t.rejected, t.panics, t.bad
        );
    }
    let (cases, accepted, rejected) = (total(|t| t.cases), total(|t| t.accepted), total(|t| t.rejected));
    eprintln!(
        "mesh_mutations_3d: {cases} cases, {accepted} accepted, {rejected} rejected, {} panics, 0 hangs, {} cases with \
         accepted groups that are not faces, {} errors not naming the file; rejected as {:?}; boundary(): {} parts accepted, {} \
         rejected as not on the boundary; boundary_group_nodes(): {} accepted, {} rejected as not on the boundary; \
         slowest case {:?} ({}); {:?} in all",
        report.panics,
        report.bad_cases,
        report.unnamed,
        report.rejections,
        report.parts_accepted,
        report.parts_rejected_not_boundary,
        report.prescribed_accepted,
        report.prescribed_rejected_not_boundary,
        report.slowest.0,
        report.slowest.1.chars().take(200).collect::<String>(),
        epoch.elapsed()
    );
    for f in &report.failures {
        eprintln!("mesh_mutations_3d: {f}");
    }
    assert_eq!(cases, CASES);
    assert!(
        report.panics == 0 && report.bad_cases == 0 && report.unnamed == 0,
        "{} panics, {} cases with accepted groups that are not faces of the mesh, {} errors that do not name the \
         file; the first:\n{}",
        report.panics,
        report.bad_cases,
        report.unnamed,
        report.failures.join("\n")
    );
    // not vacuous: many meshes rejected, many accepted, and groups both ways
    assert!(rejected >= CASES / 5, "only {rejected} of {CASES} cases rejected");
    assert!(accepted >= CASES / 20, "only {accepted} of {CASES} cases accepted");
    assert!(
        report.parts_rejected_not_boundary >= 100 && report.prescribed_rejected_not_boundary >= 100,
        "too few groups rejected as not on the boundary: the campaign misses its main class"
    );
    assert!(report.parts_accepted >= 3 * accepted / 2, "too few groups accepted");
}

/// The campaign's instruments: the unmutated bases read with their groups on the boundary (by
/// hvi and by this test's own face tables), and the element edits find and rewrite elements.
#[test]
fn the_bases_read_and_the_checks_see_a_group_that_is_not_faces() {
    let scene = Scene::from_toml_str(SCENE, "mutations.toml").unwrap();
    for base in bases() {
        let out = run_case(base.name, &base.bytes, &scene);
        assert!(
            out.accepted && out.panics.is_empty() && out.bad_groups.is_empty(),
            "{}",
            base.name
        );
        assert!(!out.severe_defects && out.simulation_built, "{}", base.name);
        // Gamma1–3 by name for both calls; nothing else is a boundary group
        assert_eq!((out.parts_accepted, out.prescribed_accepted), (3, 3), "{}", base.name);
        let els = elements(&base.bytes, base.format);
        let volumes = els.iter().filter(|e| matches!(e.ty, 4 | 5)).count();
        let surfaces = els.iter().filter(|e| matches!(e.ty, 2 | 3)).count();
        let AnyMesh::Three(mesh) = parse_msh(Path::new(base.name), &base.bytes).unwrap() else {
            panic!("{}: not 3D", base.name)
        };
        assert_eq!(volumes, mesh.cells.len(), "{}", base.name);
        let facets: usize = mesh.groups.iter().map(|g| g.facets.len()).sum();
        assert_eq!(surfaces, facets, "{}", base.name);

        // the checker sees a facet moved inside the body, and one that is no face at all
        let faces = Faces::of(&mesh);
        let gamma3 = mesh
            .groups
            .iter()
            .position(|g| g.name.as_deref() == Some("Gamma3"))
            .unwrap();
        let interior = faces.count.iter().find(|(_, (c, _))| *c == 2).unwrap().1 .1.clone();
        let mut m = mesh.clone();
        m.groups[gamma3].facets[0] = hvi::mesh::Facet::from_slice(&interior);
        assert!(faces.group_defect(&m, &m.groups[gamma3]).is_some(), "{}", base.name);
        let mut m = mesh.clone();
        let mut nodes = m.groups[gamma3].facets[0].nodes().to_vec();
        nodes[0] = (nodes[0] + 1) % m.points.len();
        m.groups[gamma3].facets[0] = hvi::mesh::Facet::from_slice(&nodes);
        assert!(faces.group_defect(&m, &m.groups[gamma3]).is_some(), "{}", base.name);

        // a node tag rewritten in $Elements changes the mesh (binary in place, ASCII in text)
        let mut bytes = base.bytes.clone();
        let edit = Edit::NodeTag {
            element: 0,
            slot: 0,
            to: NewTag::Missing,
        };
        apply(&mut bytes, &edit, &base);
        assert_ne!(bytes, base.bytes, "{}", base.name);
        assert!(
            parse_msh(Path::new(base.name), &bytes).is_err(),
            "{}: a missing node",
            base.name
        );
    }
}
