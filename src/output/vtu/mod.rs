//! One frame as a VTK XML file — an UnstructuredGrid (`.vtu`, the body) or a PolyData (`.vtp`,
//! a boundary part: lines in 2D, faces in 3D) — and reading it back.
//!
//! Layout: FieldData `TimeValue` (`Float64`, the frame's time, which ParaView's XML readers
//! report as the time of the file) and `step` (`Int32`); `Float64` points (x, y, 0 in 2D);
//! `UInt64` connectivity and offsets, and for a grid `UInt8` types (5 triangle, 9 quad, 10
//! tetrahedron, 12 hexahedron); each field a `Float64` or `Int32` array with its number of
//! components and their names (`ComponentName0`…: x y z for 3, xx xy xz yx yy yz zx zy zz for
//! a row-major 9-tensor); little-endian, header type `UInt64`, every array in one raw appended
//! block, zlib-compressed if asked. The first 3-component array of the point (cell) data is
//! marked as the active vectors (so ParaView's Warp By Vector picks `displacement`), the first
//! 9-component one as the active tensors, the first scalar as the active scalars (the caller
//! orders its fields so that this is the one to colour by: `von_mises` for hvi's body).
//!
//! - this file: the checks of a frame before anything is written ([`validate_view`]), the
//!   buffers kept across frames ([`VtuBuffer`]), and [`write_vtu`], which encodes and writes the
//!   bytes atomically;
//! - [`raw`]: the layout, written by hand, and why it is not written through vtkio;
//! - [`read`]: [`read_vtu_arrays`] and [`VtuContents`]: the markup by quick-xml, the arrays of
//!   the raw appended block (compressed or not) and inline ones (hvi's earlier layout, base64
//!   or ASCII) decoded there;
//! - [`pvtu`]: frames in pieces (one per process of a PETSc run) and their `.pvtu`, and
//!   [`read_pvtu_arrays`], which puts the pieces back together.

pub(crate) mod pvtu;

mod raw;

mod read;

mod view;

mod write;

pub use pvtu::{pvtu_pieces, read_pvtu_arrays, CELL_IDS, NODE_IDS};

pub use read::{read_vtu_arrays, VtuContents};

pub(crate) use view::{component_names, Topology, View, VtuBuffer};

#[cfg(test)]
pub(crate) use view::Parts;

pub(crate) use write::write_vtu;
