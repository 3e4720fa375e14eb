//! The `.vtu`/`.vtp` layout: raw appended binary, optionally zlib-compressed, written by hand.
//!
//! The file is an XML header whose `DataArray`s are all `format="appended"` with an `offset`,
//! then one `<AppendedData encoding="raw">` block, `_` followed by, per array, its bytes:
//! - uncompressed (level 0, the default): a `UInt64` byte count and the little-endian values;
//! - compressed (`compressor="vtkZLibDataCompressor"`, level 1–9): VTK's block layout, a
//!   `UInt64` header (number of blocks, block size 32 KiB, size of the last partial block or 0
//!   if it is full, the compressed size of each block), then each 32 KiB block zlib-compressed.
//!
//! Why by hand and not through vtkio 0.7.0-rc2: vtkio cannot write that layout (it always
//! base64-encodes binary data, and quick_xml then escapes the whole base64 text; with the
//! copies into vtkio's own buffers this cost ~74 ms per frame of 33k points / 32k quads, 8.6 MB,
//! and the raw layout is 3/4 of the size), and its XML model has neither FieldData (the
//! `TimeValue` ParaView reads a frame's time from) nor component names. Its compressed writer
//! also appended an empty zlib block to arrays whose size is a multiple of 32 KiB (announced as
//! a full block), which this layout avoids. The header is built as text and the appended block
//! in a buffer kept across frames ([`VtuBuffer`]), written one after the other.
//!
//! [`VtuBuffer`]: super::VtuBuffer

use super::{component_names, Topology, View, VtuBuffer};
use crate::output::pvd::xml_escape;
use crate::output::{Field, FieldValues};
use std::fmt::Write as _;

/// The end of a raw-appended file, after the last array's bytes.
pub(super) const RAW_FOOTER: &str = "\n  </AppendedData>\n</VTKFile>\n";

/// The uncompressed size of a compressed block (VTK's default).
pub(super) const BLOCK_SIZE: usize = 32 * 1024;

/// The appended block being built: each array's bytes, compressed or not.
struct Appended<'b> {
    data: &'b mut Vec<u8>,
    scratch: &'b mut Vec<u8>,
    level: u32,
}

impl Appended<'_> {
    /// Appends one array whose little-endian bytes `fill` writes into the vector it gets;
    /// returns the array's offset in the appended block.
    fn array(&mut self, fill: impl FnOnce(&mut Vec<u8>)) -> usize {
        let offset = self.data.len();
        if self.level == 0 {
            self.data.extend_from_slice(&[0; 8]);
            fill(self.data);
            let bytes = (self.data.len() - offset - 8) as u64;
            self.data[offset..offset + 8].copy_from_slice(&bytes.to_le_bytes());
            return offset;
        }
        self.scratch.clear();
        fill(self.scratch);
        let blocks = self.scratch.len().div_ceil(BLOCK_SIZE);
        let header_at = self.data.len();
        let words = [blocks, BLOCK_SIZE, self.scratch.len() % BLOCK_SIZE];
        for w in words {
            self.data.extend_from_slice(&(w as u64).to_le_bytes());
        }
        self.data.resize(header_at + 8 * (3 + blocks), 0);
        let level = flate2::Compression::new(self.level.min(9));
        for (b, chunk) in self.scratch.chunks(BLOCK_SIZE).enumerate() {
            let start = self.data.len();
            let mut z = flate2::write::ZlibEncoder::new(&mut *self.data, level);
            // Writing into a Vec cannot fail.
            let _ = std::io::Write::write_all(&mut z, chunk);
            let _ = z.finish();
            let size = (self.data.len() - start) as u64;
            let at = header_at + 8 * (3 + b);
            self.data[at..at + 8].copy_from_slice(&size.to_le_bytes());
        }
        offset
    }

    fn field(&mut self, f: &Field) -> usize {
        self.array(|buf| match f.values {
            FieldValues::F64(v) => put_items(buf, v.iter(), |x| x.to_le_bytes()),
            FieldValues::I32(v) => put_items(buf, v.iter(), |x| x.to_le_bytes()),
        })
    }
}

/// Appends the bytes of every item (one resize, then each item's bytes in place).
fn put_items<const N: usize, T>(
    buf: &mut Vec<u8>,
    items: impl ExactSizeIterator<Item = T>,
    bytes: impl Fn(T) -> [u8; N],
) {
    let start = buf.len();
    buf.resize(start + N * items.len(), 0);
    for (dst, item) in buf[start..].chunks_exact_mut(N).zip(items) {
        dst.copy_from_slice(&bytes(item));
    }
}

/// The VTK type name of a field's values.
pub(super) fn vtk_type(values: &FieldValues) -> &'static str {
    match values {
        FieldValues::F64(_) => "Float64",
        FieldValues::I32(_) => "Int32",
    }
}

/// Opens a `<PointData`/`<CellData` section (or the `.pvtu`'s `<PPointData`/`<PCellData`, pvtu.rs)
/// indented by `indent`, with the active scalars, vectors and tensors: a field marked active, else
/// the first with one component; the first with 3 and with 9 components.
pub(super) fn open_section(text: &mut String, indent: &str, tag: &str, fields: &[Field]) {
    let _ = write!(text, "{indent}<{tag}");
    for (attr, components) in [("Scalars", 1), ("Vectors", 3), ("Tensors", 9)] {
        let marked = (attr == "Scalars").then(|| fields.iter().find(|f| f.active)).flatten();
        if let Some(f) = marked.or_else(|| fields.iter().find(|f| f.components == components)) {
            let _ = write!(text, " {attr}=\"{}\"", xml_escape(f.name));
        }
    }
    text.push_str(">\n");
}

/// Starts the declaration of one array, `<{element} type= Name= [NumberOfComponents=]
/// ComponentNameI=...` (the caller closes it). `NumberOfComponents` is left out for one
/// component (VTK's default), as VTK and vtkio do: meshio reads an explicit 1 as an n × 1 array
/// instead of n.
pub(super) fn start_array(text: &mut String, element: &str, vtk_type: &str, name: &str, components: usize) {
    let _ = write!(text, "<{element} type=\"{vtk_type}\" Name=\"{}\"", xml_escape(name));
    if components != 1 {
        let _ = write!(text, " NumberOfComponents=\"{components}\"");
    }
    for (i, c) in component_names(components).iter().enumerate() {
        let _ = write!(text, " ComponentName{i}=\"{c}\"");
    }
}

/// Declares one `DataArray` of the header ([`start_array`]).
fn declare(text: &mut String, vtk_type: &str, name: &str, components: usize, extra: &str, offset: usize) {
    text.push_str("        ");
    start_array(text, "DataArray", vtk_type, name, components);
    let _ = writeln!(text, "{extra} format=\"appended\" offset=\"{offset}\"/>");
}

/// `<PointData`/`<CellData` with the active scalars, vectors and tensors, its arrays, and the
/// closing tag.
fn fields(text: &mut String, a: &mut Appended, tag: &str, fields: &[Field]) {
    open_section(text, "      ", tag, fields);
    for f in fields {
        let offset = a.field(f);
        declare(text, vtk_type(&f.values), f.name, f.components, "", offset);
    }
    let _ = writeln!(text, "      </{tag}>");
}

/// Encodes a (validated) frame: returns the XML header (up to and including the `_` that
/// starts the appended block) and leaves the appended block in `buffer.data` (cleared first);
/// [`RAW_FOOTER`] follows it.
pub(super) fn encode<const D: usize>(frame: &View<D>, level: u32, buffer: &mut VtuBuffer) -> String {
    buffer.data.clear();
    let mut a = Appended {
        data: &mut buffer.data,
        scratch: &mut buffer.scratch,
        level,
    };
    let (n_points, n_cells) = (frame.points.len(), frame.topology.len());
    let (kind, cells_tag) = match frame.topology {
        Topology::Cells(_) => ("UnstructuredGrid", "Cells"),
        Topology::Facets(f) if f.first().is_some_and(|x| x.len() == 2) => ("PolyData", "Lines"),
        Topology::Facets(_) => ("PolyData", "Polys"),
    };
    let mut text = String::with_capacity(4096);
    let compressor = if level > 0 {
        " compressor=\"vtkZLibDataCompressor\""
    } else {
        ""
    };
    let _ = write!(
        text,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\"{compressor}>\n  <{kind}>\n    <FieldData>\n"
    );
    let offset = a.array(|b| b.extend_from_slice(&frame.time.to_le_bytes()));
    declare(&mut text, "Float64", "TimeValue", 1, " NumberOfTuples=\"1\"", offset);
    // (validated to fit)
    let step = i32::try_from(frame.step).unwrap_or(i32::MAX);
    let offset = a.array(|b| b.extend_from_slice(&step.to_le_bytes()));
    declare(&mut text, "Int32", "step", 1, " NumberOfTuples=\"1\"", offset);
    text.push_str("    </FieldData>\n");
    match frame.topology {
        Topology::Cells(_) => {
            let _ = writeln!(
                text,
                "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
            );
        }
        Topology::Facets(_) => {
            let (lines, polys) = if cells_tag == "Lines" {
                (n_cells, 0)
            } else {
                (0, n_cells)
            };
            let _ = writeln!(
                text,
                "    <Piece NumberOfPoints=\"{n_points}\" NumberOfVerts=\"0\" NumberOfLines=\"{lines}\" \
                 NumberOfStrips=\"0\" NumberOfPolys=\"{polys}\">"
            );
        }
    }
    fields(&mut text, &mut a, "PointData", frame.point_fields);
    fields(&mut text, &mut a, "CellData", frame.cell_fields);
    text.push_str("      <Points>\n");
    let offset = a.array(|buf| {
        put_items(buf, frame.points.iter(), |p| {
            let mut b = [0u8; 24];
            b[..8].copy_from_slice(&p[0].to_le_bytes());
            b[8..16].copy_from_slice(&p[1].to_le_bytes());
            b[16..].copy_from_slice(&p.get(2).copied().unwrap_or(0.0).to_le_bytes());
            b
        })
    });
    declare(&mut text, "Float64", "Points", 3, "", offset);
    let _ = writeln!(text, "      </Points>\n      <{cells_tag}>");
    let topology = frame.topology;
    let offset = a.array(|buf| {
        for c in 0..n_cells {
            put_items(buf, topology.vtk_nodes(c), |i| (i as u64).to_le_bytes());
        }
    });
    declare(&mut text, "UInt64", "connectivity", 1, "", offset);
    let ends = (0..n_cells).scan(0u64, |end, c| {
        *end += topology.nodes(c).len() as u64;
        Some(*end)
    });
    let offset = a.array(|buf| {
        buf.reserve(8 * n_cells);
        for e in ends {
            buf.extend_from_slice(&e.to_le_bytes());
        }
    });
    declare(&mut text, "UInt64", "offsets", 1, "", offset);
    if let Topology::Cells(cells) = topology {
        let offset = a.array(|buf| buf.extend(cells.iter().map(crate::mesh::Cell::vtk_type)));
        declare(&mut text, "UInt8", "types", 1, "", offset);
    }
    let _ = write!(
        text,
        "      </{cells_tag}>\n    </Piece>\n  </{kind}>\n  <AppendedData encoding=\"raw\">\n   _"
    );
    text
}

#[cfg(test)]
mod tests {
    use super::super::Parts;
    use super::*;
    use crate::output::Frame;

    #[test]
    fn buffer_is_reused() {
        let p = Parts::new();
        let u = vec![0.0; 3 * p.points.len()];
        let frame = Frame {
            step: 0,
            time: 0.0,
            points: &p.points,
            cells: &p.cells,
            point_fields: vec![Field::f64("displacement", 3, &u)],
            cell_fields: vec![],
        };
        let mut buf = VtuBuffer::default();
        let header = encode(&frame.view(), 0, &mut buf);
        assert!(header.ends_with('_'));
        assert!(header.contains("<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\""));
        assert!(header.contains("Name=\"displacement\" NumberOfComponents=\"3\" ComponentName0=\"x\""));
        let (ptr, len) = (buf.data.as_ptr(), buf.data.len());
        encode(&frame.view(), 0, &mut buf);
        assert_eq!((buf.data.as_ptr(), buf.data.len()), (ptr, len));
    }
}
