//! One frame as a VTK XML UnstructuredGrid (`.vtu`), and reading it back.
//!
//! Layout: `Float64` points (x, y, 0), `UInt64` connectivity and offsets, `UInt8` types
//! (5 triangle, 9 quad), each field a `Float64` or `Int32` array with its number of components;
//! little-endian, header type `UInt64`. The first 3-component array of the point (cell) data is
//! marked as the active vectors (so ParaView's Warp By Vector picks `displacement`), the first
//! 9-component one as the active tensors, the first scalar as the active scalars.
//!
//! - this file: the checks of a [`Frame`] before anything is written ([`validate_frame`]), the
//!   buffer kept across frames ([`VtuBuffer`]), and [`write_vtu`], which picks the writer and
//!   writes its bytes atomically;
//! - [`raw`]: the uncompressed layout (the default), raw appended binary written by hand, and
//!   why it is not written through vtkio;
//! - [`vtkio_writer`]: the zlib-compressed layout, inline base64 through vtkio, and why its
//!   bytes are serialised into memory rather than written by vtkio's file writer;
//! - [`read`]: [`read_vtu_arrays`] and [`VtuContents`]; inline files through vtkio, raw appended
//!   ones by a small parser of exactly the layout [`raw`] writes.

mod raw;
mod read;
mod vtkio_writer;

pub use read::{read_vtu_arrays, VtuContents};

use super::atomic::write_atomic;
use super::{Field, FieldValues, Frame, OutputError};
#[cfg(test)]
use crate::mesh::Cell;
use raw::encode_vtu_raw;
use std::collections::BTreeSet;
use std::path::Path;
use vtkio_writer::encode_vtu_vtkio;

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
pub(crate) fn validate_frame<const D: usize>(path: &Path, frame: &Frame<D>) -> Result<(), OutputError> {
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
    if let Some(p) = frame.points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
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

/// The byte buffer a [`super::SeriesWriter`] keeps across frames, so that every frame after the
/// first is built in memory that is already allocated and mapped.
#[derive(Default)]
pub(crate) struct VtuBuffer(Vec<u8>);

impl std::fmt::Debug for VtuBuffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "VtuBuffer({} bytes reserved)", self.0.capacity())
    }
}

/// Validates `frame` and writes it to `path` atomically: raw appended binary built in `buffer`
/// if `compression_level` is 0, else through vtkio (zlib, inline base64).
pub(crate) fn write_vtu<const D: usize>(
    path: &Path,
    frame: &Frame<D>,
    compression_level: u32,
    buffer: &mut VtuBuffer,
) -> Result<(), OutputError> {
    validate_frame(path, frame)?;
    if compression_level > 0 {
        let bytes = encode_vtu_vtkio(path, frame, compression_level)?;
        return write_atomic(path, &bytes);
    }
    encode_vtu_raw(frame, &mut buffer.0);
    write_atomic(path, &buffer.0)
}

/// The arrays of a small two-cell frame, for the tests of the submodules.
#[cfg(test)]
struct Parts {
    points: Vec<[f64; 2]>,
    cells: Vec<Cell>,
    u: Vec<f64>,
    status: Vec<i32>,
    stress: Vec<f64>,
}

#[cfg(test)]
impl Parts {
    fn new() -> Self {
        Parts {
            points: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.5]],
            cells: vec![Cell::Quad4([0, 1, 2, 3]), Cell::Tri3([1, 4, 2])],
            u: (0..15)
                .map(|k| if k % 3 == 2 { 0.0 } else { 0.1 * k as f64 - 0.7 })
                .collect(),
            status: vec![-1, 0, 1, 2, i32::MAX],
            stress: (0..18).map(|k| (k as f64).sqrt() - 2.0).collect(),
        }
    }
}
