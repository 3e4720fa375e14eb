//! Reading a `.vtu` back into [`VtuContents`].
//!
//! Reading ([`read_vtu_arrays`]): vtkio 0.7.0-rc2 cannot read raw appended data (its support
//! sits behind a `binary` cfg feature its manifest does not declare; it rejects
//! `encoding="raw"` with "unknown variant `raw`, expected `base64`"), so files with raw
//! appended data are read by a small parser of exactly the layout [`super::raw`] writes, which
//! reports a truncated or foreign file as an error; inline base64 files (hvi's earlier
//! uncompressed layout, and the compressed one) are still read through vtkio.

use crate::output::OutputError;
use std::collections::BTreeMap;
use std::path::Path;
use vtkio::model::{Attribute, DataSet, Vtk};
use vtkio::xml::VTKFile;

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
    match find_bytes(&bytes, b"<AppendedData") {
        Some(at) => read_raw_appended(path, &bytes, at),
        // A raw-appended file cut before its data block: report that, not vtkio's confusion.
        None if find_bytes(&bytes, b"format=\"appended\"").is_some() => Err(OutputError::format(
            path,
            "the arrays are declared as appended data but the file has no <AppendedData> block; it is truncated",
        )),
        None => read_vtkio(path, &bytes),
    }
}

/// Reads an inline (base64 or ASCII, possibly compressed) `.vtu` through vtkio.
fn read_vtkio(path: &Path, bytes: &[u8]) -> Result<VtuContents, OutputError> {
    use vtkio::xml;
    // vtkio silently drops arrays it fails to decode: count what the file announces.
    let text = String::from_utf8_lossy(bytes);
    let announced = (
        count_data_arrays(&text, "PointData"),
        count_data_arrays(&text, "CellData"),
    );
    let file = VTKFile::parse(bytes).map_err(|e| match e {
        xml::Error::IO(source) => OutputError::read(path, source),
        e => OutputError::Vtk {
            path: path.to_path_buf(),
            action: "parsing",
            detail: e.to_string(),
        },
    })?;
    let vtk = Vtk::try_from(file).map_err(|e| OutputError::Vtk {
        path: path.to_path_buf(),
        action: "decoding",
        detail: e.to_string(),
    })?;
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err(OutputError::format(path, "not an UnstructuredGrid"));
    };
    if pieces.len() != 1 {
        return Err(OutputError::format(
            path,
            format!("expected exactly one piece, found {}", pieces.len()),
        ));
    }
    let piece = pieces
        .into_iter()
        .next()
        .ok_or_else(|| OutputError::format(path, "no piece"))?
        .into_loaded_piece_data(None)
        .map_err(|e| OutputError::Vtk {
            path: path.to_path_buf(),
            action: "loading the piece",
            detail: e.to_string(),
        })?;

    let coords = piece
        .points
        .cast_into::<f64>()
        .ok_or_else(|| OutputError::format(path, "points are not numeric"))?;
    if coords.len() % 3 != 0 {
        return Err(OutputError::format(path, "point coordinates are not triples"));
    }
    let points: Vec<[f64; 3]> = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();

    let cell_types: Vec<u8> = piece.cells.types.iter().map(|t| *t as u8).collect();
    let n_cells = cell_types.len();
    let (conn, mut offsets) = piece.cells.cell_verts.into_xml();
    if offsets.len() == n_cells + 1 && offsets.first() == Some(&0) {
        offsets.remove(0);
    }
    if offsets.len() != n_cells {
        return Err(OutputError::format(
            path,
            format!("{} cell offsets for {} cell types", offsets.len(), n_cells),
        ));
    }
    let connectivity = split_connectivity(path, &conn, &offsets, points.len())?;

    let point_data = collect_arrays(path, "point", piece.data.point, points.len(), announced.0)?;
    let cell_data = collect_arrays(path, "cell", piece.data.cell, n_cells, announced.1)?;
    Ok(VtuContents {
        points,
        cell_types,
        connectivity,
        point_data,
        cell_data,
        field_data: BTreeMap::new(),
    })
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

fn collect_arrays(
    path: &Path,
    location: &str,
    attributes: Vec<Attribute>,
    count: usize,
    announced: usize,
) -> Result<BTreeMap<String, (usize, Vec<f64>)>, OutputError> {
    let mut out = BTreeMap::new();
    for a in attributes {
        let Attribute::DataArray(a) = a else { continue };
        let components = a.elem.num_comp() as usize;
        let values = a
            .data
            .cast_into::<f64>()
            .ok_or_else(|| OutputError::format(path, format!("{location} array \"{}\" is not numeric", a.name)))?;
        if values.len() != components * count {
            return Err(OutputError::format(
                path,
                format!(
                    "{location} array \"{}\" has {} values, expected {components} × {count}",
                    a.name,
                    values.len()
                ),
            ));
        }
        out.insert(a.name, (components, values));
    }
    if out.len() != announced {
        return Err(OutputError::format(
            path,
            format!(
                "the file announces {announced} {location} arrays but {} could be decoded",
                out.len()
            ),
        ));
    }
    Ok(out)
}

/// The number of `<DataArray` elements inside the first `<tag>` element of `text` (0 if the
/// element is absent or empty).
fn count_data_arrays(text: &str, tag: &str) -> usize {
    let Some(start) = text.find(&format!("<{tag}")) else {
        return 0;
    };
    let rest = &text[start..];
    let open_end = rest.find('>').unwrap_or(rest.len());
    if rest[..open_end].ends_with('/') {
        return 0;
    }
    let end = rest.find(&format!("</{tag}>")).unwrap_or(rest.len());
    rest[..end].matches("<DataArray").count()
}

/// The first position of `needle` in `hay`.
fn find_bytes(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
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

/// One tag of the XML header: `<name a="v" ...>`, `<name .../>` or `</name>`.
pub(super) struct Tag<'a> {
    pub(super) name: &'a str,
    attrs: Vec<(&'a str, String)>,
    pub(super) closing: bool,
    self_closing: bool,
}

impl Tag<'_> {
    pub(super) fn attr(&self, key: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| *k == key).map(|(_, v)| v.as_str())
    }
}

/// Undoes the escapes [`xml_escape`] makes (other entities are kept as they are).
///
/// [`xml_escape`]: crate::output::pvd::xml_escape
fn xml_unescape(s: &str) -> String {
    if !s.contains('&') {
        return s.to_string();
    }
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// Parses the inside of a tag (between `<` and `>`); `None` if it is not a well-formed tag.
fn parse_tag(inner: &str) -> Option<Tag<'_>> {
    let (closing, inner) = match inner.strip_prefix('/') {
        Some(rest) => (true, rest),
        None => (false, inner),
    };
    let (self_closing, inner) = match inner.strip_suffix('/') {
        Some(rest) => (true, rest),
        None => (false, inner),
    };
    let name_end = inner.find(|c: char| c.is_ascii_whitespace()).unwrap_or(inner.len());
    let name = &inner[..name_end];
    if name.is_empty() {
        return None;
    }
    let mut attrs = Vec::new();
    let mut rest = inner[name_end..].trim_start();
    while !rest.is_empty() {
        let eq = rest.find('=')?;
        let key = rest[..eq].trim_end();
        let value = rest[eq + 1..].trim_start();
        let quote = value.chars().next().filter(|&q| q == '"' || q == '\'')?;
        let len = value[1..].find(quote)?;
        attrs.push((key, xml_unescape(&value[1..1 + len])));
        rest = value[len + 2..].trim_start();
    }
    Some(Tag {
        name,
        attrs,
        closing,
        self_closing,
    })
}

/// The tags of `text` in order, skipping the XML declaration, comments and text between tags.
pub(super) fn parse_tags(text: &str) -> Result<Vec<Tag<'_>>, String> {
    let mut tags = Vec::new();
    let mut rest = text;
    while let Some(open) = rest.find('<') {
        rest = &rest[open + 1..];
        if let Some(comment) = rest.strip_prefix("!--") {
            let end = comment.find("-->").ok_or("an unterminated XML comment")?;
            rest = &comment[end + 3..];
            continue;
        }
        let close = rest.find('>').ok_or("an unterminated XML tag")?;
        let inner = &rest[..close];
        rest = &rest[close + 1..];
        if inner.starts_with('?') {
            continue;
        }
        tags.push(parse_tag(inner).ok_or_else(|| format!("a malformed XML tag <{inner}>"))?);
    }
    Ok(tags)
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

/// A `DataArray` declared in the header of a raw-appended file.
struct AppendedArray {
    section: Section,
    name: String,
    scalar: Scalar,
    components: usize,
    /// Offset of the array's byte count in the appended block.
    offset: usize,
    /// `NumberOfTuples` (field data).
    tuples: Option<usize>,
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

/// Reads a `.vtu` whose arrays are in a raw `<AppendedData>` block (the layout written by
/// [`encode_vtu_raw`]); `at` is the position of `<AppendedData`.
///
/// [`encode_vtu_raw`]: super::raw::encode_vtu_raw
fn read_raw_appended(path: &Path, bytes: &[u8], at: usize) -> Result<VtuContents, OutputError> {
    let fail = |detail: String| OutputError::format(path, detail);
    let truncated = || fail("the file ends inside its appended data; it is truncated".into());
    let header = std::str::from_utf8(&bytes[..at]).map_err(|_| fail("the XML header is not UTF-8".into()))?;
    let tags = parse_tags(header).map_err(|e| fail(format!("the XML header has {e}")))?;

    // The <AppendedData ...> tag, then whitespace and the '_' that starts the block.
    let tag_len = bytes[at..].iter().position(|&b| b == b'>').ok_or_else(truncated)?;
    let tag_text = std::str::from_utf8(&bytes[at + 1..at + tag_len])
        .map_err(|_| fail("the <AppendedData> tag is not UTF-8".into()))?;
    let appended_tag = parse_tag(tag_text).ok_or_else(|| fail("a malformed <AppendedData> tag".into()))?;
    match appended_tag.attr("encoding") {
        Some("raw") => {}
        other => {
            return Err(fail(format!(
                "appended data with encoding {other:?} is not supported; only raw appended data is"
            )))
        }
    }
    let mut start = at + tag_len + 1;
    while bytes.get(start).is_some_and(u8::is_ascii_whitespace) {
        start += 1;
    }
    match bytes.get(start) {
        Some(b'_') => {}
        Some(_) => return Err(fail("the appended data does not start with '_'".into())),
        None => return Err(truncated()),
    }
    let data = &bytes[start + 1..];

    // The header: one UnstructuredGrid piece and its arrays.
    let mut grid = false;
    let mut poly = false;
    let mut zlib = false;
    let mut piece: Option<(usize, usize)> = None;
    let mut section = None;
    let mut arrays = Vec::new();
    for tag in &tags {
        if tag.closing {
            if matches!(
                tag.name,
                "FieldData" | "PointData" | "CellData" | "Points" | "Cells" | "Lines" | "Polys"
            ) {
                section = None;
            }
            continue;
        }
        match tag.name {
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
                    Some(c) => return Err(fail(format!("raw appended data compressed by {c} is not supported"))),
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
                if tag.attr("format") != Some("appended") {
                    return Err(fail(format!(
                        "the DataArray \"{name}\" is not in the appended data (format {:?})",
                        tag.attr("format").unwrap_or("(none)")
                    )));
                }
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
                let offset = tag
                    .attr("offset")
                    .and_then(|o| o.trim().parse::<usize>().ok())
                    .ok_or_else(|| fail(format!("the DataArray \"{name}\" has no valid offset")))?;
                let tuples = match tag.attr("NumberOfTuples") {
                    None => None,
                    Some(t) => Some(
                        t.trim()
                            .parse::<usize>()
                            .map_err(|_| fail(format!("the DataArray \"{name}\" has {t:?} tuples")))?,
                    ),
                };
                arrays.push(AppendedArray {
                    section,
                    name,
                    scalar,
                    components,
                    offset,
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

    // The bytes of each array (decompressed), all inside `data`.
    let mut data_end = 0;
    let mut array_bytes = |a: &AppendedArray, count: Option<usize>| -> Result<Vec<u8>, OutputError> {
        let (bytes, end) = appended_bytes(data, a.offset, zlib).map_err(|e| {
            if e == "truncated" {
                truncated()
            } else {
                fail(format!("the array \"{}\": {e}", a.name))
            }
        })?;
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
        data_end = data_end.max(end);
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

    let integers = |a: &AppendedArray, bytes: &[u8]| {
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

    // Nothing but the end tags may follow the last array.
    let tail = std::str::from_utf8(&data[data_end..]).unwrap_or("");
    let tail: Vec<&str> = tail.split_ascii_whitespace().collect();
    if tail != ["</AppendedData>", "</VTKFile>"] {
        return Err(if "</AppendedData></VTKFile>".starts_with(&tail.concat()) {
            truncated()
        } else {
            fail("unexpected bytes after the last array of the appended data".into())
        });
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
    use super::super::vtkio_writer::encode_vtu_vtkio;
    use super::super::{write_vtu, Parts, VtuBuffer};
    use super::*;
    use crate::output::{Field, Frame};

    /// Files in hvi's earlier layout (inline base64 through vtkio, uncompressed) still read,
    /// and give what the raw layout gives.
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
        let (old, new) = (dir.path().join("old.vtu"), dir.path().join("new.vtu"));
        let bytes = encode_vtu_vtkio(&old, &frame, 0).unwrap();
        assert!(String::from_utf8_lossy(&bytes).contains("format=\"binary\""));
        std::fs::write(&old, bytes).unwrap();
        write_vtu(&new, &frame.view(), 0, &mut VtuBuffer::default()).unwrap();
        let (a, mut b) = (read_vtu_arrays(&old).unwrap(), read_vtu_arrays(&new).unwrap());
        // the earlier layout had no field data
        assert_eq!(b.field_data["TimeValue"], (1, vec![0.0]));
        b.field_data.clear();
        assert_eq!(a, b);
        assert_eq!(
            b.point_data["contact_status"],
            (1, vec![-1.0, 0.0, 1.0, 2.0, i32::MAX as f64])
        );
    }

    #[test]
    fn tags_parse_with_escapes() {
        let tags =
            parse_tags("<?xml version=\"1.0\"?>\n<!-- c > d --><A x=\"1\" y='a&amp;b &quot;q&quot; &lt;&gt;'/></A>")
                .unwrap();
        assert_eq!(tags.len(), 2);
        assert_eq!(
            (tags[0].name, tags[0].self_closing, tags[0].closing),
            ("A", true, false)
        );
        assert_eq!(tags[0].attr("y"), Some("a&b \"q\" <>"));
        assert!(tags[1].closing);
        assert!(parse_tags("<A x=\"1>").is_err());
        assert!(parse_tags("<A x=1>").is_err());
    }
}
