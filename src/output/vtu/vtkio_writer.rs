//! hvi's earlier `.vtu` layout, inline base64 through vtkio (compressed or not), kept only for
//! the test that checks such files still read.

use crate::mesh::Cell;
use crate::output::{Field, FieldValues, Frame, OutputError};
use std::path::Path;
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};
use vtkio::xml::Compressor;

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

/// Encodes a (validated) frame through vtkio as inline base64 binary, zlib-compressed if
/// `compression_level` > 0 (the raw appended layout of [`encode_vtu_raw`] is uncompressed only).
///
/// [`encode_vtu_raw`]: super::raw::encode_vtu_raw
pub(super) fn encode_vtu_vtkio<const D: usize>(
    path: &Path,
    frame: &Frame<D>,
    compression_level: u32,
) -> Result<Vec<u8>, OutputError> {
    let points: Vec<f64> = frame
        .points
        .iter()
        .flat_map(|p| [p[0], p[1], p.get(2).copied().unwrap_or(0.0)])
        .collect();
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
            Cell::Tet4(_) => CellType::Tetra,
            Cell::Hex8(_) => CellType::Hexahedron,
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
