//! Reading a `.vtu` (`.vtp`) back into [`VtuContents`].
//!
//! Reading ([`read_vtu_arrays`]): the markup by quick-xml ([`crate::output::xml`]), the arrays
//! here: raw appended data (the layout [`super::raw`] writes, compressed or not), which no XML
//! crate decodes, and inline base64 (hvi's earlier layout, written through vtkio, compressed or
//! not) or ASCII arrays. A truncated or foreign file is an error naming the file.

use crate::output::xml::{parse_tags, Tag};
use crate::output::OutputError;
use base64::Engine as _;
use std::collections::BTreeMap;
use std::path::Path;

/// The arrays of a `.vtu` file read back by [`read_vtu_arrays`]; every numeric array as `f64`
/// (integer arrays convert exactly).
#[derive(Clone, Debug, PartialEq)]
pub struct VtuContents {
    /// Point coordinates (z = 0 for files written by hvi).
    pub points: Vec<[f64; 3]>,
    /// VTK cell type of each cell (5 triangle, 9 quad, 10 tetrahedron, 12 hexahedron; in a
    /// PolyData `.vtp`, 3 for a line and 7 for a polygon).
    pub cell_types: Vec<u8>,
    /// Node indices of each cell.
    pub connectivity: Vec<Vec<usize>>,
    /// Point data: name → (number of components, values point-major).
    pub point_data: BTreeMap<String, (usize, Vec<f64>)>,
    /// Cell data: name → (number of components, values cell-major).
    pub cell_data: BTreeMap<String, (usize, Vec<f64>)>,
    /// Field data (hvi writes `TimeValue` and `step`): name → (number of components, values).
    pub field_data: BTreeMap<String, (usize, Vec<f64>)>,
}

/// Reads back a `.vtu` written by [`crate::output`] (one piece: raw appended binary as written
/// now, or inline binary or ASCII, compressed or not, as written through vtkio), checking that
/// every array has the length its header announces. A missing, foreign or truncated file is an
/// error.
pub fn read_vtu_arrays(path: &Path) -> Result<VtuContents, OutputError> {
    let bytes = std::fs::read(path).map_err(|e| OutputError::read(path, e))?;
    // The markup up to the raw appended data, if any; the rest is not XML.
    let (tags, appended) = parse_tags(&bytes, Some("AppendedData")).map_err(|e| OutputError::format(path, e))?;
    read_tags(path, &bytes, &tags, appended)
}

/// Splits `conn` at the cell end `offsets` into the node lists of the cells, checking that the
/// offsets increase within `conn` and that every node exists.
fn split_connectivity(
    path: &Path,
    conn: &[u64],
    offsets: &[u64],
    n_points: usize,
) -> Result<Vec<Vec<usize>>, OutputError> {
    let mut connectivity = Vec::with_capacity(offsets.len());
    let mut start = 0usize;
    for &end in offsets {
        let end = usize::try_from(end).unwrap_or(usize::MAX);
        if end < start || end > conn.len() {
            return Err(OutputError::format(path, "cell offsets out of range"));
        }
        let nodes: Vec<usize> = conn[start..end]
            .iter()
            .map(|&i| usize::try_from(i).unwrap_or(usize::MAX))
            .collect();
        if let Some(&bad) = nodes.iter().find(|&&i| i >= n_points) {
            return Err(OutputError::format(
                path,
                format!("a cell refers to missing node {bad}"),
            ));
        }
        connectivity.push(nodes);
        start = end;
    }
    Ok(connectivity)
}

/// The scalar types of VTK XML data arrays.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

/// Decodes little-endian `bytes` (a whole number of `$t`) as `$t`, each converted by `$conv`.
macro_rules! decode_le {
    ($t:ty, $bytes:expr, $conv:expr) => {
        $bytes
            .chunks_exact(std::mem::size_of::<$t>())
            .map(|c| <$t>::from_le_bytes(c.try_into().expect("chunk of the type's size")))
            .map($conv)
            .collect()
    };
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "Int8" => Scalar::I8,
            "UInt8" => Scalar::U8,
            "Int16" => Scalar::I16,
            "UInt16" => Scalar::U16,
            "Int32" => Scalar::I32,
            "UInt32" => Scalar::U32,
            "Int64" => Scalar::I64,
            "UInt64" => Scalar::U64,
            "Float32" => Scalar::F32,
            "Float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// The values as `f64` (exact for every type hvi writes).
    fn to_f64(self, bytes: &[u8]) -> Vec<f64> {
        match self {
            Scalar::I8 => decode_le!(i8, bytes, f64::from),
            Scalar::U8 => decode_le!(u8, bytes, f64::from),
            Scalar::I16 => decode_le!(i16, bytes, f64::from),
            Scalar::U16 => decode_le!(u16, bytes, f64::from),
            Scalar::I32 => decode_le!(i32, bytes, f64::from),
            Scalar::U32 => decode_le!(u32, bytes, f64::from),
            Scalar::I64 => decode_le!(i64, bytes, |x| x as f64),
            Scalar::U64 => decode_le!(u64, bytes, |x| x as f64),
            Scalar::F32 => decode_le!(f32, bytes, f64::from),
            Scalar::F64 => decode_le!(f64, bytes, |x| x),
        }
    }

    /// The values of an integer array as `u64`; `None` for a float type or a negative value.
    fn to_u64(self, bytes: &[u8]) -> Option<Vec<u64>> {
        let signed = |v: Vec<i64>| v.into_iter().map(|x| u64::try_from(x).ok()).collect();
        match self {
            Scalar::I8 => signed(decode_le!(i8, bytes, i64::from)),
            Scalar::I16 => signed(decode_le!(i16, bytes, i64::from)),
            Scalar::I32 => signed(decode_le!(i32, bytes, i64::from)),
            Scalar::I64 => signed(decode_le!(i64, bytes, |x| x)),
            Scalar::U8 => Some(decode_le!(u8, bytes, u64::from)),
            Scalar::U16 => Some(decode_le!(u16, bytes, u64::from)),
            Scalar::U32 => Some(decode_le!(u32, bytes, u64::from)),
            Scalar::U64 => Some(decode_le!(u64, bytes, |x| x)),
            Scalar::F32 | Scalar::F64 => None,
        }
    }
}

/// Where a `DataArray` of the header belongs.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Section {
    FieldData,
    PointData,
    CellData,
    Points,
    Cells,
    Lines,
    Polys,
}

/// A `DataArray` declared in the header.
struct DeclaredArray {
    section: Section,
    name: String,
    scalar: Scalar,
    components: usize,
    /// Where its bytes are.
    source: Source,
    /// `NumberOfTuples` (field data).
    tuples: Option<usize>,
}

/// Where the bytes of a `DataArray` are.
enum Source {
    /// In the appended block, at this offset (of its byte count or its compression header).
    Appended(usize),
    /// Inline, base64 (`format="binary"`): the text of the element.
    Base64(String),
    /// Inline, ASCII (`format="ascii"`): the text of the element.
    Ascii(String),
}

/// The bytes of one array of the appended block `data` at `offset`: a byte count and the bytes,
/// or (zlib) VTK's block header and the compressed blocks; `None` if the block is too short.
fn appended_bytes(data: &[u8], offset: usize, zlib: bool) -> Result<(Vec<u8>, usize), String> {
    let word = |at: usize| -> Result<usize, String> {
        let b = data.get(at..at + 8).ok_or("truncated")?;
        usize::try_from(u64::from_le_bytes(b.try_into().expect("8 bytes"))).map_err(|_| "truncated".to_string())
    };
    if !zlib {
        let len = word(offset)?;
        let start = offset + 8;
        let end = start.checked_add(len).filter(|&e| e <= data.len()).ok_or("truncated")?;
        return Ok((data[start..end].to_vec(), end));
    }
    let (blocks, block_size, last) = (word(offset)?, word(offset + 8)?, word(offset + 16)?);
    if blocks > data.len() / 8 || block_size == 0 || last >= block_size.max(1) {
        return Err(format!(
            "a compressed array header with {blocks} blocks of {block_size} bytes (last {last}) is not valid"
        ));
    }
    let mut at = offset + 24 + 8 * blocks;
    if at > data.len() {
        return Err("truncated".into());
    }
    let mut out = Vec::with_capacity(blocks * block_size);
    for b in 0..blocks {
        let size = word(offset + 24 + 8 * b)?;
        let end = at.checked_add(size).filter(|&e| e <= data.len()).ok_or("truncated")?;
        let want = if b + 1 == blocks && last > 0 { last } else { block_size };
        let before = out.len();
        let decoder = flate2::read::ZlibDecoder::new(&data[at..end]);
        std::io::Read::read_to_end(&mut std::io::Read::take(decoder, want as u64 + 1), &mut out)
            .map_err(|e| format!("a compressed block does not decompress ({e})"))?;
        if out.len() - before != want {
            return Err(format!(
                "a compressed block holds {} bytes, its header announces {want}",
                out.len() - before
            ));
        }
        at = end;
    }
    Ok((out, at))
}

/// The bytes of an inline base64 array (VTK's `format="binary"`, header type `UInt64`): one
/// base64 stream of a byte count and the bytes, or (zlib) VTK's block header in a base64 stream
/// of its own followed by the compressed blocks in another.
fn base64_bytes(text: &str, zlib: bool) -> Result<Vec<u8>, String> {
    let b64: Vec<u8> = text.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    let decode = |s: &[u8]| {
        base64::engine::general_purpose::STANDARD
            .decode(s)
            .map_err(|e| format!("its base64 data do not decode ({e})"))
    };
    let buffer = if zlib {
        // the header's first three words (24 bytes, 32 characters) give its length
        let first = decode(
            b64.get(..32)
                .ok_or("its base64 data end inside the compression header")?,
        )?;
        let blocks = u64::from_le_bytes(first[..8].try_into().expect("8 bytes"));
        let header_chars = usize::try_from(blocks)
            .ok()
            .and_then(|n| n.checked_add(3))
            .and_then(|n| n.checked_mul(8))
            .map(|n| n.div_ceil(3) * 4)
            .filter(|&n| n <= b64.len())
            .ok_or_else(|| format!("its compression header announces {blocks} blocks, more than its data hold"))?;
        let mut header = decode(&b64[..header_chars])?;
        header.extend(decode(&b64[header_chars..])?);
        header
    } else {
        decode(&b64)?
    };
    let (bytes, end) = appended_bytes(&buffer, 0, zlib).map_err(|e| {
        if e == "truncated" {
            "its base64 data are shorter than its header announces".to_string()
        } else {
            e
        }
    })?;
    if end != buffer.len() {
        return Err("its base64 data are longer than its header announces".into());
    }
    Ok(bytes)
}

/// The values of an inline ASCII array as little-endian bytes of `scalar` (so that they decode
/// as a binary array does).
fn ascii_bytes(text: &str, scalar: Scalar) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(text.len());
    for word in text.split_ascii_whitespace() {
        let bad = || format!("its value {word:?} is not a value of its type");
        let integer = || word.parse::<i128>().map_err(|_| bad());
        macro_rules! int {
            ($t:ty) => {
                out.extend(<$t>::try_from(integer()?).map_err(|_| bad())?.to_le_bytes())
            };
        }
        match scalar {
            Scalar::I8 => int!(i8),
            Scalar::U8 => int!(u8),
            Scalar::I16 => int!(i16),
            Scalar::U16 => int!(u16),
            Scalar::I32 => int!(i32),
            Scalar::U32 => int!(u32),
            Scalar::I64 => int!(i64),
            Scalar::U64 => int!(u64),
            Scalar::F32 => out.extend(word.parse::<f32>().map_err(|_| bad())?.to_le_bytes()),
            Scalar::F64 => out.extend(word.parse::<f64>().map_err(|_| bad())?.to_le_bytes()),
        }
    }
    Ok(out)
}

/// Reads the arrays of a `.vtu` (`.vtp`) from its `tags`; `appended` is the position after the
/// `<AppendedData>` start tag, whose raw block (the layout written by [`super::raw`]) follows.
fn read_tags(path: &Path, bytes: &[u8], tags: &[Tag], appended: Option<usize>) -> Result<VtuContents, OutputError> {
    let fail = |detail: String| OutputError::format(path, detail);
    let truncated = || fail("the file ends inside its appended data; it is truncated".into());

    // The <AppendedData ...> tag, then whitespace and the '_' that starts the block.
    let data = match appended {
        None => None,
        Some(after) => {
            // parsing stopped at the <AppendedData> tag
            match tags.last().and_then(|t| t.attr("encoding")) {
                Some("raw") => {}
                other => {
                    return Err(fail(format!(
                        "appended data with encoding {other:?} is not supported; only raw appended data is"
                    )))
                }
            }
            let mut start = after;
            while bytes.get(start).is_some_and(u8::is_ascii_whitespace) {
                start += 1;
            }
            match bytes.get(start) {
                Some(b'_') => {}
                Some(_) => return Err(fail("the appended data does not start with '_'".into())),
                None => return Err(truncated()),
            }
            Some(&bytes[start + 1..])
        }
    };

    // The header: one UnstructuredGrid piece and its arrays.
    let mut grid = false;
    let mut poly = false;
    let mut zlib = false;
    let mut piece: Option<(usize, usize)> = None;
    let mut section = None;
    let mut arrays = Vec::new();
    for tag in tags {
        if tag.closing {
            if matches!(
                tag.name.as_str(),
                "FieldData" | "PointData" | "CellData" | "Points" | "Cells" | "Lines" | "Polys"
            ) {
                section = None;
            }
            continue;
        }
        match tag.name.as_str() {
            "VTKFile" => {
                poly = match tag.attr("type") {
                    Some("UnstructuredGrid") => false,
                    Some("PolyData") => true,
                    other => {
                        return Err(fail(format!(
                            "a VTKFile of type {:?}, not an UnstructuredGrid or a PolyData",
                            other.unwrap_or("(none)")
                        )))
                    }
                };
                for (key, want) in [("byte_order", "LittleEndian"), ("header_type", "UInt64")] {
                    if tag.attr(key) != Some(want) {
                        return Err(fail(format!(
                            "{key} {:?} is not supported; hvi writes and reads {want}",
                            tag.attr(key).unwrap_or("(none)")
                        )));
                    }
                }
                match tag.attr("compressor") {
                    None => {}
                    Some("vtkZLibDataCompressor") => zlib = true,
                    Some(c) => return Err(fail(format!("data compressed by {c} are not supported"))),
                }
            }
            "UnstructuredGrid" | "PolyData" => grid = true,
            "Piece" => {
                if piece.is_some() {
                    return Err(fail("expected exactly one piece, found more".into()));
                }
                let count = |key: &str| {
                    tag.attr(key)
                        .and_then(|v| v.trim().parse::<usize>().ok())
                        .ok_or_else(|| fail(format!("the Piece has no valid {key}")))
                };
                piece = Some(if poly {
                    for key in ["NumberOfVerts", "NumberOfStrips"] {
                        if tag.attr(key).is_some_and(|v| v.trim() != "0") {
                            return Err(fail(format!(
                                "a PolyData with {key} is not supported (hvi writes lines or polygons)"
                            )));
                        }
                    }
                    let (lines, polys) = (count("NumberOfLines")?, count("NumberOfPolys")?);
                    if lines > 0 && polys > 0 {
                        return Err(fail("a PolyData with both lines and polygons is not supported".into()));
                    }
                    (count("NumberOfPoints")?, lines + polys)
                } else {
                    (count("NumberOfPoints")?, count("NumberOfCells")?)
                });
            }
            "FieldData" if !tag.self_closing => section = Some(Section::FieldData),
            "Lines" if !tag.self_closing => section = Some(Section::Lines),
            "Polys" if !tag.self_closing => section = Some(Section::Polys),
            "PointData" if !tag.self_closing => section = Some(Section::PointData),
            "CellData" if !tag.self_closing => section = Some(Section::CellData),
            "Points" if !tag.self_closing => section = Some(Section::Points),
            "Cells" if !tag.self_closing => section = Some(Section::Cells),
            "DataArray" => {
                let name = tag.attr("Name").unwrap_or("").to_string();
                let section =
                    section.ok_or_else(|| fail(format!("the DataArray \"{name}\" is outside the piece's data")))?;
                let ty = tag.attr("type").unwrap_or("(none)");
                let scalar = Scalar::parse(ty)
                    .ok_or_else(|| fail(format!("the DataArray \"{name}\" has the unknown type {ty:?}")))?;
                let components = match tag.attr("NumberOfComponents") {
                    None => 1,
                    Some(c) => c
                        .trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|&c| c > 0)
                        .ok_or_else(|| fail(format!("the DataArray \"{name}\" has {c:?} components")))?,
                };
                let source = match tag.attr("format") {
                    Some("appended") => Source::Appended(
                        tag.attr("offset")
                            .and_then(|o| o.trim().parse::<usize>().ok())
                            .ok_or_else(|| fail(format!("the DataArray \"{name}\" has no valid offset")))?,
                    ),
                    Some("binary") => Source::Base64(tag.text.clone()),
                    Some("ascii") => Source::Ascii(tag.text.clone()),
                    other => {
                        return Err(fail(format!(
                            "the DataArray \"{name}\" has the unknown format {:?}",
                            other.unwrap_or("(none)")
                        )))
                    }
                };
                let tuples = match tag.attr("NumberOfTuples") {
                    None => None,
                    Some(t) => Some(
                        t.trim()
                            .parse::<usize>()
                            .map_err(|_| fail(format!("the DataArray \"{name}\" has {t:?} tuples")))?,
                    ),
                };
                arrays.push(DeclaredArray {
                    section,
                    name,
                    scalar,
                    components,
                    source,
                    tuples,
                });
            }
            _ => {}
        }
    }
    if !grid {
        return Err(fail("not an UnstructuredGrid".into()));
    }
    let (n_points, n_cells) = piece.ok_or_else(|| fail("no piece".into()))?;

    // The bytes of each array (decompressed); those of the appended block all inside `data`.
    let mut data_end = 0;
    let mut array_bytes = |a: &DeclaredArray, count: Option<usize>| -> Result<Vec<u8>, OutputError> {
        let in_array = |e: String| fail(format!("the array \"{}\": {e}", a.name));
        let bytes = match (&a.source, data) {
            (Source::Appended(offset), Some(data)) => {
                let (bytes, end) = appended_bytes(data, *offset, zlib).map_err(|e| {
                    if e == "truncated" {
                        truncated()
                    } else {
                        in_array(e)
                    }
                })?;
                data_end = data_end.max(end);
                bytes
            }
            // A raw-appended file cut before its data block.
            (Source::Appended(_), None) => return Err(fail(
                "the arrays are declared as appended data but the file has no <AppendedData> block; it is truncated"
                    .into(),
            )),
            (Source::Base64(text), _) => base64_bytes(text, zlib).map_err(in_array)?,
            (Source::Ascii(text), _) => ascii_bytes(text, a.scalar).map_err(in_array)?,
        };
        let len = bytes.len();
        let expected = count.map(|n| n.saturating_mul(a.components).saturating_mul(a.scalar.size()));
        if expected.is_some_and(|e| e != len) || len % (a.components * a.scalar.size()) != 0 {
            return Err(fail(format!(
                "the array \"{}\" has {len} bytes, which is not {} value(s) of {} component(s) of {} bytes",
                a.name,
                count.map_or("a whole number of".to_string(), |n| n.to_string()),
                a.components,
                a.scalar.size()
            )));
        }
        Ok(bytes)
    };
    let find = |section: Section, name: &str| {
        arrays
            .iter()
            .find(|a| a.section == section && (section == Section::Points || a.name == name))
            .ok_or_else(|| fail(format!("no {name} array")))
    };

    let points_array = find(Section::Points, "Points")?;
    if points_array.components != 3 {
        return Err(fail(format!(
            "points with {} coordinates, not 3",
            points_array.components
        )));
    }
    let coords = points_array.scalar.to_f64(&array_bytes(points_array, Some(n_points))?);
    let points: Vec<[f64; 3]> = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();

    let integers = |a: &DeclaredArray, bytes: &[u8]| {
        a.scalar.to_u64(bytes).ok_or_else(|| {
            fail(format!(
                "the cell array \"{}\" is not a non-negative integer array",
                a.name
            ))
        })
    };
    let cells_section = if !poly {
        Section::Cells
    } else if arrays.iter().any(|a| a.section == Section::Lines) {
        Section::Lines
    } else {
        Section::Polys
    };
    let cell_types = if poly {
        vec![if cells_section == Section::Lines { 3 } else { 7 }; n_cells]
    } else {
        let types_array = find(Section::Cells, "types")?;
        integers(types_array, &array_bytes(types_array, Some(n_cells))?)?
            .into_iter()
            .map(|t| u8::try_from(t).map_err(|_| fail(format!("the cell type {t} is not a VTK cell type"))))
            .collect::<Result<Vec<u8>, _>>()?
    };
    let offsets_array = find(cells_section, "offsets")?;
    let offsets = integers(offsets_array, &array_bytes(offsets_array, Some(n_cells))?)?;
    let conn_array = find(cells_section, "connectivity")?;
    let conn = integers(conn_array, &array_bytes(conn_array, None)?)?;
    if offsets.last().is_some_and(|&end| end != conn.len() as u64) {
        return Err(fail(format!(
            "the cell offsets end at {} but there are {} connectivity entries",
            offsets.last().copied().unwrap_or(0),
            conn.len()
        )));
    }
    let connectivity = split_connectivity(path, &conn, &offsets, n_points)?;

    let mut point_data = BTreeMap::new();
    let mut cell_data = BTreeMap::new();
    let mut field_data = BTreeMap::new();
    for a in &arrays {
        let (map, count, location) = match a.section {
            Section::PointData => (&mut point_data, n_points, "point"),
            Section::CellData => (&mut cell_data, n_cells, "cell"),
            Section::FieldData => (&mut field_data, a.tuples.unwrap_or(1), "field"),
            Section::Points | Section::Cells | Section::Lines | Section::Polys => continue,
        };
        let values = a.scalar.to_f64(&array_bytes(a, Some(count))?);
        if map.insert(a.name.clone(), (a.components, values)).is_some() {
            return Err(fail(format!("two {location} arrays are named \"{}\"", a.name)));
        }
    }

    // Nothing but the end tags may follow the last array of the appended data.
    if let Some(data) = data {
        let tail = std::str::from_utf8(&data[data_end..]).unwrap_or("");
        let tail: Vec<&str> = tail.split_ascii_whitespace().collect();
        if tail != ["</AppendedData>", "</VTKFile>"] {
            return Err(if "</AppendedData></VTKFile>".starts_with(&tail.concat()) {
                truncated()
            } else {
                fail("unexpected bytes after the last array of the appended data".into())
            });
        }
    }
    Ok(VtuContents {
        points,
        cell_types,
        connectivity,
        point_data,
        cell_data,
        field_data,
    })
}

#[cfg(test)]
mod tests {
    use super::super::{write_vtu, Parts, VtuBuffer};
    use super::*;
    use crate::output::{Field, Frame};

    /// Files in hvi's earlier layout (inline base64, uncompressed and zlib-compressed at level 6,
    /// written through vtkio 0.7.0-rc2 from this frame and kept in `testdata/`) still read, and
    /// give what the raw layout gives.
    #[test]
    fn earlier_base64_files_read_as_the_raw_layout() {
        let p = Parts::new();
        let frame = Frame {
            step: 0,
            time: 0.0,
            points: &p.points,
            cells: &p.cells,
            point_fields: vec![
                Field::f64("displacement", 3, &p.u),
                Field::i32("contact_status", 1, &p.status),
            ],
            cell_fields: vec![Field::f64("stress", 9, &p.stress)],
        };
        let dir = tempfile::tempdir().unwrap();
        let new = dir.path().join("new.vtu");
        write_vtu(&new, &frame.view(), 0, &mut VtuBuffer::default()).unwrap();
        let mut b = read_vtu_arrays(&new).unwrap();
        // the earlier layout had no field data
        assert_eq!(b.field_data["TimeValue"], (1, vec![0.0]));
        b.field_data.clear();
        assert_eq!(
            b.point_data["contact_status"],
            (1, vec![-1.0, 0.0, 1.0, 2.0, i32::MAX as f64])
        );
        for (name, bytes) in [
            ("old.vtu", &include_bytes!("testdata/vtkio_base64.vtu")[..]),
            ("old_zlib.vtu", &include_bytes!("testdata/vtkio_base64_zlib.vtu")[..]),
        ] {
            assert!(String::from_utf8_lossy(bytes).contains("format=\"binary\""));
            let old = dir.path().join(name);
            std::fs::write(&old, bytes).unwrap();
            assert_eq!(read_vtu_arrays(&old).unwrap(), b, "{name}");
            // cut anywhere, or with a byte of the data changed, it is an error naming the file
            for len in 0..bytes.len() - 1 {
                std::fs::write(&old, &bytes[..len]).unwrap();
                let e = read_vtu_arrays(&old).unwrap_err().to_string();
                assert!(e.contains(name), "{e}");
            }
            let at = bytes.windows(4).position(|w| w == b"eAAA" || w == b"AQAA").unwrap();
            let mut bad = bytes.to_vec();
            bad[at] = b'B';
            std::fs::write(&old, &bad).unwrap();
            let e = read_vtu_arrays(&old).unwrap_err().to_string();
            assert!(e.contains(name) && e.contains("displacement"), "{e}");
        }
    }

    /// The same arrays written inline as ASCII read as the binary ones.
    #[test]
    fn ascii_arrays_read() {
        let text = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid><Piece NumberOfPoints=\"3\" NumberOfCells=\"1\">\n<PointData><DataArray type=\"Int32\" Name=\"s&amp;t\" format=\"ascii\">-1 0\n 7</DataArray></PointData>\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1.5 0</DataArray></Points>\n<Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2</DataArray><DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">3</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">5</DataArray></Cells>\n</Piece></UnstructuredGrid></VTKFile>\n";
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ascii.vtu");
        std::fs::write(&path, text).unwrap();
        let c = read_vtu_arrays(&path).unwrap();
        assert_eq!(c.points, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.5, 0.0]]);
        assert_eq!((c.cell_types, c.connectivity), (vec![5], vec![vec![0, 1, 2]]));
        assert_eq!(c.point_data["s&t"], (1, vec![-1.0, 0.0, 7.0]));
        std::fs::write(&path, text.replace("-1 0", "-1 x")).unwrap();
        let e = read_vtu_arrays(&path).unwrap_err().to_string();
        assert!(e.contains("ascii.vtu") && e.contains("\"x\""), "{e}");
    }
}
