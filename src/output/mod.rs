//! Output files: the ParaView time series of 2D and 3D solutions, CSV tables, atomic file writes.
//!
//! A run writes, into one directory:
//! - `<basename>_<step:05>.vtu` per output step: a VTK XML UnstructuredGrid (raw appended
//!   binary, zlib-compressed if [`SeriesWriter::with_compression`] asks for it) with the frame's
//!   time and step as FieldData (`TimeValue`, `step`), the points (z = 0 in 2D), the cells, and
//!   the point and cell fields of the [`Frame`]; or, for a boundary series
//!   ([`SeriesWriter::create_surface`]), `<basename>_<step:05>.vtp`, a PolyData of a
//!   [`SurfaceFrame`];
//! - `<basename>.pvd` and `<basename>.vtu.series` (`.vtp.series`): the two index files ParaView opens as one
//!   time series, rewritten atomically after every frame so that they list exactly the frames
//!   written so far with their real times, even when the run is interrupted;
//! - for a run in pieces (PETSc over MPI, [`SeriesWriter::create_parallel`]): per frame one
//!   `<basename>_<step:05>_<rank>.vtu` per process and a `<basename>_<step:05>.pvtu` listing them,
//!   indexed by `<basename>.pvd` and `<basename>.pvtu.series`;
//! - any [`CsvTable`] and JSON/other files written with [`write_json_atomic`]/[`write_atomic`].
//!
//! Every file that is replaced is written to a hidden temporary sibling first
//! (`.<name>.tmp.<pid>.<n>`) and renamed into place, so no reader ever sees half a file.
//!
//! ```no_run
//! use hvi::mesh::Cell;
//! use hvi::output::{Field, FieldValues, Frame, SeriesWriter};
//! let points = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
//! let cells = [Cell::Quad4([0, 1, 2, 3])];
//! let u = [0.0; 12];
//! let mut series = SeriesWriter::create(std::path::Path::new("runs/a"), "solution").unwrap();
//! series
//!     .write_frame(&Frame {
//!         step: 0,
//!         time: 0.0,
//!         points: &points,
//!         cells: &cells,
//!         point_fields: vec![Field { name: "displacement", components: 3, values: FieldValues::F64(&u), active: false }],
//!         cell_fields: vec![],
//!     })
//!     .unwrap();
//! ```

mod atomic;

mod boundary;

mod csv;

mod error;

mod frame;

mod lock;

mod manifest;

mod pvd;

mod series;

mod vtu;

mod xml;

pub use atomic::{is_temporary_name, write_atomic, write_json_atomic};

pub use boundary::ContactBoundary;

pub use csv::CsvTable;

pub use error::OutputError;

pub use frame::{
    format_number, Field, FieldValues, Frame, SurfaceFrame, DEFAULT_COMPRESSION_LEVEL, MAX_COMPRESSION_LEVEL,
};

pub use lock::RunLock;

pub use manifest::{read_manifest, record_in_run, RunManifest, MANIFEST_NAME};

pub use pvd::{pvd_text, read_pvd};

pub use series::SeriesWriter;

pub use vtu::{pvtu_pieces, read_pvtu_arrays, read_vtu_arrays, VtuContents, CELL_IDS, NODE_IDS};
