//! The uncompressed `.vtu` layout: raw appended binary, written by hand.
//!
//! Uncompressed (the default, [`DEFAULT_COMPRESSION_LEVEL`]), the file is written by
//! hand here, not through vtkio: an XML header whose `DataArray`s are all `format="appended"`
//! with an `offset`, then one `<AppendedData encoding="raw">` block, `_` followed by, per
//! array, its byte count (`UInt64`) and its little-endian bytes. vtkio 0.7.0-rc2 cannot write
//! that layout: it always base64-encodes binary data, and quick_xml then escapes the whole
//! base64 text; with the copies into vtkio's own buffers this cost ~74 ms per frame of 33k
//! points / 32k quads (8.6 MB). The raw layout is 3/4 of the size and is built in one buffer
//! (sized up front and kept across frames by [`VtuBuffer`]) that is written in one go.
//!
//! [`DEFAULT_COMPRESSION_LEVEL`]: crate::output::DEFAULT_COMPRESSION_LEVEL
//! [`VtuBuffer`]: super::VtuBuffer

use crate::mesh::Cell;
use crate::output::pvd::xml_escape;
use crate::output::{Field, FieldValues, Frame};

/// The end of a raw-appended file, after the last array's bytes.
const RAW_FOOTER: &str = "\n  </AppendedData>\n</VTKFile>\n";

/// The XML header of a raw-appended file: every `DataArray` declared with the offset of its
/// byte count in the appended block, in the order the arrays follow there.
struct RawHeader {
    text: String,
    /// Bytes of the appended block declared so far (byte counts included).
    appended: usize,
}

impl RawHeader {
    /// Declares the next array. `NumberOfComponents` is left out for one component (VTK's
    /// default), as VTK and vtkio do: meshio reads an explicit 1 as an n × 1 array instead of n.
    fn array(&mut self, vtk_type: &str, name: &str, components: usize, bytes: usize) {
        use std::fmt::Write as _;
        let _ = write!(
            self.text,
            "        <DataArray type=\"{vtk_type}\" Name=\"{}\"",
            xml_escape(name)
        );
        if components != 1 {
            let _ = write!(self.text, " NumberOfComponents=\"{components}\"");
        }
        let _ = writeln!(self.text, " format=\"appended\" offset=\"{}\"/>", self.appended);
        self.appended += 8 + bytes;
    }

    /// `<PointData`/`<CellData` with the active scalars, vectors and tensors, its arrays, and
    /// the closing tag.
    fn fields(&mut self, tag: &str, fields: &[Field]) {
        self.text.push_str("      <");
        self.text.push_str(tag);
        for (attr, components) in [("Scalars", 1), ("Vectors", 3), ("Tensors", 9)] {
            if let Some(f) = fields.iter().find(|f| f.components == components) {
                self.text.push_str(&format!(" {attr}=\"{}\"", xml_escape(f.name)));
            }
        }
        self.text.push_str(">\n");
        for f in fields {
            let (vtk_type, size) = match f.values {
                FieldValues::F64(_) => ("Float64", 8),
                FieldValues::I32(_) => ("Int32", 4),
            };
            // (= size × components × count for a validated frame)
            self.array(vtk_type, f.name, f.components, size * f.values.len());
        }
        self.text.push_str(&format!("      </{tag}>\n"));
    }
}

/// Appends `count` items of `N` bytes each to `buf`: one resize, then each item's bytes in
/// place (`items` must yield exactly `count` items).
fn put_items<const N: usize, T>(
    buf: &mut Vec<u8>,
    count: usize,
    items: impl Iterator<Item = T>,
    bytes: impl Fn(T) -> [u8; N],
) {
    let start = buf.len();
    buf.resize(start + N * count, 0);
    let mut written = 0;
    for (dst, item) in buf[start..].chunks_exact_mut(N).zip(items) {
        dst.copy_from_slice(&bytes(item));
        written += 1;
    }
    debug_assert_eq!(written, count);
}

/// Appends the `UInt64` byte count that precedes every array in the appended block.
fn put_byte_count(buf: &mut Vec<u8>, bytes: usize) {
    buf.extend_from_slice(&(bytes as u64).to_le_bytes());
}

fn put_field(buf: &mut Vec<u8>, f: &Field) {
    match f.values {
        FieldValues::F64(v) => {
            put_byte_count(buf, 8 * v.len());
            put_items(buf, v.len(), v.iter(), |x| x.to_le_bytes());
        }
        FieldValues::I32(v) => {
            put_byte_count(buf, 4 * v.len());
            put_items(buf, v.len(), v.iter(), |x| x.to_le_bytes());
        }
    }
}

/// Encodes a (validated) frame into `buf` (cleared first, reserved to the exact size) as a
/// `.vtu` with raw appended binary data; see the module documentation for the layout.
pub(super) fn encode_vtu_raw<const D: usize>(frame: &Frame<D>, buf: &mut Vec<u8>) {
    let (n_points, n_cells) = (frame.points.len(), frame.cells.len());
    let n_conn: usize = frame.cells.iter().map(|c| c.nodes().len()).sum();
    let mut h = RawHeader {
        text: String::with_capacity(4096),
        appended: 0,
    };
    h.text.push_str(concat!(
        "<?xml version=\"1.0\"?>\n",
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n",
        "  <UnstructuredGrid>\n",
    ));
    h.text.push_str(&format!(
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">\n"
    ));
    h.fields("PointData", &frame.point_fields);
    h.fields("CellData", &frame.cell_fields);
    h.text.push_str("      <Points>\n");
    h.array("Float64", "Points", 3, 24 * n_points);
    h.text.push_str("      </Points>\n      <Cells>\n");
    h.array("UInt64", "connectivity", 1, 8 * n_conn);
    h.array("UInt64", "offsets", 1, 8 * n_cells);
    h.array("UInt8", "types", 1, n_cells);
    h.text.push_str(concat!(
        "      </Cells>\n",
        "    </Piece>\n",
        "  </UnstructuredGrid>\n",
        "  <AppendedData encoding=\"raw\">\n",
        "   _",
    ));

    let total = h.text.len() + h.appended + RAW_FOOTER.len();
    buf.clear();
    buf.reserve_exact(total);
    buf.extend_from_slice(h.text.as_bytes());
    for f in frame.point_fields.iter().chain(&frame.cell_fields) {
        put_field(buf, f);
    }
    put_byte_count(buf, 24 * n_points);
    put_items(buf, n_points, frame.points.iter(), |p| {
        let mut b = [0u8; 24];
        b[..8].copy_from_slice(&p[0].to_le_bytes());
        b[8..16].copy_from_slice(&p[1].to_le_bytes());
        b[16..].copy_from_slice(&p.get(2).copied().unwrap_or(0.0).to_le_bytes());
        b
    });
    put_byte_count(buf, 8 * n_conn);
    let nodes = frame.cells.iter().flat_map(|c| c.nodes().iter());
    put_items(buf, n_conn, nodes, |&i| (i as u64).to_le_bytes());
    put_byte_count(buf, 8 * n_cells);
    let ends = frame.cells.iter().scan(0u64, |end, c| {
        *end += c.nodes().len() as u64;
        Some(*end)
    });
    put_items(buf, n_cells, ends, u64::to_le_bytes);
    put_byte_count(buf, n_cells);
    buf.extend(frame.cells.iter().map(Cell::vtk_type));
    buf.extend_from_slice(RAW_FOOTER.as_bytes());
    debug_assert_eq!(buf.len(), total);
}

#[cfg(test)]
mod tests {
    use super::super::Parts;
    use super::*;

    #[test]
    fn buffer_is_sized_exactly_and_reused() {
        let p = Parts::new();
        let frame = Frame {
            step: 0,
            time: 0.0,
            points: &p.points,
            cells: &p.cells,
            point_fields: vec![Field::f64("displacement", 3, &p.u)],
            cell_fields: vec![],
        };
        let mut buf = Vec::new();
        encode_vtu_raw(&frame, &mut buf);
        assert_eq!(buf.len(), buf.capacity());
        assert!(buf.ends_with(RAW_FOOTER.as_bytes()));
        let (ptr, len) = (buf.as_ptr(), buf.len());
        encode_vtu_raw(&frame, &mut buf);
        assert_eq!((buf.as_ptr(), buf.len()), (ptr, len));
    }
}
