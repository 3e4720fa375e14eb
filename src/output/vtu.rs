//! One frame as a VTK XML UnstructuredGrid (`.vtu`), through vtkio 0.7.0-rc2, and reading it
//! back.
//!
//! Layout: `Float64` points (x, y, 0), `UInt64` connectivity and offsets, `UInt8` types
//! (5 triangle, 9 quad), each field a `Float64` or `Int32` array with its number of components;
//! base64 binary, uncompressed or zlib-compressed (header type `UInt64`). vtkio marks the first
//! 3-component array as the active vectors (so ParaView's Warp By Vector picks
//! `displacement`), the first 9-component one as the active tensors, the first scalar as the
//! active scalars.
//!
//! vtkio's own file writer (`VTKFile::export`/`write`) wraps the destination in a `BufWriter`
//! that it drops without checking the final flush, and writes with `write` rather than
//! `write_all`, so a full disk could produce a silently truncated file. We therefore serialise
//! into memory (which cannot fail that way) and write the bytes ourselves, atomically.

use super::atomic::write_atomic;
use super::{Field, FieldValues, Frame, OutputError};
use crate::mesh::Cell;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};
use vtkio::xml::{Compressor, VTKFile};

/// The arrays of a `.vtu` file read back by [`read_vtu_arrays`]; every numeric array as `f64`
/// (integer arrays convert exactly).
#[derive(Clone, Debug, PartialEq)]
pub struct VtuContents {
    /// Point coordinates (z = 0 for files written by hvi).
    pub points: Vec<[f64; 3]>,
    /// VTK cell type of each cell (5 triangle, 9 quad).
    pub cell_types: Vec<u8>,
    /// Node indices of each cell.
    pub connectivity: Vec<Vec<usize>>,
    /// Point data: name → (number of components, values point-major).
    pub point_data: BTreeMap<String, (usize, Vec<f64>)>,
    /// Cell data: name → (number of components, values cell-major).
    pub cell_data: BTreeMap<String, (usize, Vec<f64>)>,
}

impl FieldValues<'_> {
    /// The number of values (components × entities).
    pub fn len(&self) -> usize {
        match self {
            FieldValues::F64(v) => v.len(),
            FieldValues::I32(v) => v.len(),
        }
    }

    /// True if there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Checks everything that would make a broken or misleading file, before anything is written.
pub(crate) fn validate_frame(path: &Path, frame: &Frame) -> Result<(), OutputError> {
    if !frame.time.is_finite() {
        return Err(OutputError::invalid_frame(
            path,
            format!(
                "step {} has the non-finite time {}; the time series needs a real time for every frame",
                frame.step, frame.time
            ),
        ));
    }
    let n_points = frame.points.len();
    if let Some(p) = frame
        .points
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(OutputError::invalid_frame(
            path,
            format!("point {p} has a non-finite coordinate {:?}", frame.points[p]),
        ));
    }
    for (c, cell) in frame.cells.iter().enumerate() {
        if let Some(&bad) = cell.nodes().iter().find(|&&i| i >= n_points) {
            return Err(OutputError::invalid_frame(
                path,
                format!("cell {c} refers to node {bad}, but the frame has only {n_points} points"),
            ));
        }
    }
    check_fields(path, "point", &frame.point_fields, n_points)?;
    check_fields(path, "cell", &frame.cell_fields, frame.cells.len())
}

fn check_fields(path: &Path, location: &'static str, fields: &[Field], count: usize) -> Result<(), OutputError> {
    let mut seen = BTreeSet::new();
    for f in fields {
        if f.name.is_empty() || f.name.chars().any(char::is_control) {
            return Err(OutputError::invalid_frame(
                path,
                format!("{location} field name {:?} is empty or has control characters", f.name),
            ));
        }
        if !seen.insert(f.name) {
            return Err(OutputError::invalid_frame(
                path,
                format!("two {location} fields are named \"{}\"", f.name),
            ));
        }
        if f.components == 0 {
            return Err(OutputError::invalid_frame(
                path,
                format!("{location} field \"{}\" has 0 components", f.name),
            ));
        }
        let expected = f.components.saturating_mul(count);
        if f.values.len() != expected {
            return Err(OutputError::FieldLength {
                path: path.to_path_buf(),
                location,
                name: f.name.to_string(),
                components: f.components,
                count,
                expected,
                got: f.values.len(),
            });
        }
    }
    Ok(())
}

fn attribute(f: &Field) -> Attribute {
    let elem = match f.components {
        1 => ElementType::Scalars {
            num_comp: 1,
            lookup_table: None,
        },
        3 => ElementType::Vectors,
        9 => ElementType::Tensors,
        n => ElementType::Generic(n as u32),
    };
    let data = match f.values {
        FieldValues::F64(v) => IOBuffer::F64(v.to_vec()),
        FieldValues::I32(v) => IOBuffer::I32(v.to_vec()),
    };
    Attribute::DataArray(DataArray {
        name: f.name.to_string(),
        elem,
        data,
    })
}

/// Encodes a (validated) frame as the bytes of a `.vtu` file.
pub(crate) fn encode_vtu(path: &Path, frame: &Frame, compression_level: u32) -> Result<Vec<u8>, OutputError> {
    let points: Vec<f64> = frame.points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    let n_conn = frame.cells.iter().map(|c| c.nodes().len()).sum();
    let mut connectivity = Vec::with_capacity(n_conn);
    let mut offsets = Vec::with_capacity(frame.cells.len());
    let mut types = Vec::with_capacity(frame.cells.len());
    for cell in frame.cells {
        connectivity.extend(cell.nodes().iter().map(|&i| i as u64));
        offsets.push(connectivity.len() as u64);
        types.push(match cell {
            Cell::Tri3(_) => CellType::Triangle,
            Cell::Quad4(_) => CellType::Quad,
        });
        debug_assert_eq!(*types.last().unwrap() as u8, cell.vtk_type());
    }
    let piece = UnstructuredGridPiece {
        points: IOBuffer::F64(points),
        cells: Cells {
            cell_verts: VertexNumbers::XML { connectivity, offsets },
            types,
        },
        data: Attributes {
            point: frame.point_fields.iter().map(attribute).collect(),
            cell: frame.cell_fields.iter().map(attribute).collect(),
        },
    };
    let vtk = Vtk {
        version: Version::new(),
        title: String::new(),
        byte_order: ByteOrder::native(),
        file_path: None,
        data: DataSet::inline(piece),
    };
    let compressor = if compression_level == 0 {
        Compressor::None
    } else {
        Compressor::ZLib
    };
    let vtk_err = |e: &dyn std::fmt::Display| OutputError::Vtk {
        path: path.to_path_buf(),
        action: "encoding",
        detail: e.to_string(),
    };
    let xml = vtk
        .try_into_xml_format(compressor, compression_level.min(9))
        .map_err(|e| vtk_err(&e))?;
    let mut bytes = Vec::new();
    xml.write(&mut bytes).map_err(|e| vtk_err(&e))?;
    bytes.push(b'\n');
    Ok(bytes)
}

/// Validates `frame` and writes it to `path` atomically.
pub(crate) fn write_vtu(path: &Path, frame: &Frame, compression_level: u32) -> Result<(), OutputError> {
    validate_frame(path, frame)?;
    let bytes = encode_vtu(path, frame, compression_level)?;
    write_atomic(path, &bytes)
}

/// Reads back a `.vtu` written by [`crate::output`] (one inline piece, binary or ASCII,
/// compressed or not), checking that every array has the length its header announces.
pub fn read_vtu_arrays(path: &Path) -> Result<VtuContents, OutputError> {
    use vtkio::xml;
    let bytes = std::fs::read(path).map_err(|e| OutputError::read(path, e))?;
    // vtkio silently drops arrays it fails to decode: count what the file announces.
    let text = String::from_utf8_lossy(&bytes);
    let announced = (
        count_data_arrays(&text, "PointData"),
        count_data_arrays(&text, "CellData"),
    );
    let file = VTKFile::parse(&bytes[..]).map_err(|e| match e {
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
    let mut connectivity = Vec::with_capacity(n_cells);
    let mut start = 0usize;
    for &end in &offsets {
        let end = end as usize;
        if end < start || end > conn.len() {
            return Err(OutputError::format(path, "cell offsets out of range"));
        }
        let nodes: Vec<usize> = conn[start..end].iter().map(|&i| i as usize).collect();
        if let Some(&bad) = nodes.iter().find(|&&i| i >= points.len()) {
            return Err(OutputError::format(
                path,
                format!("a cell refers to missing node {bad}"),
            ));
        }
        connectivity.push(nodes);
        start = end;
    }

    let point_data = collect_arrays(path, "point", piece.data.point, points.len(), announced.0)?;
    let cell_data = collect_arrays(path, "cell", piece.data.cell, n_cells, announced.1)?;
    Ok(VtuContents {
        points,
        cell_types,
        connectivity,
        point_data,
        cell_data,
    })
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
