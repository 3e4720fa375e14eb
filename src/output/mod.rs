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
mod manifest;
mod pvd;
mod vtu;
mod xml;

pub use atomic::{is_temporary_name, write_atomic, write_json_atomic};
pub use boundary::ContactBoundary;
pub use csv::CsvTable;
pub use error::OutputError;
pub use manifest::{read_manifest, record_in_run, RunManifest, MANIFEST_NAME};
pub use pvd::{pvd_text, read_pvd};
pub use vtu::{pvtu_pieces, read_pvtu_arrays, read_vtu_arrays, VtuContents, CELL_IDS, NODE_IDS};

/// The largest zlib level of [`SeriesWriter::with_compression`].
pub const MAX_COMPRESSION_LEVEL: u32 = 9;

use std::fs::{self, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The values of a field, point- (or cell-) major: entity 0's components, then entity 1's, ...
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldValues<'a> {
    /// Written as `Float64`.
    F64(&'a [f64]),
    /// Written as `Int32` (status codes, flags, ids).
    I32(&'a [i32]),
}

/// A named field on the points or cells of a frame; `values.len()` must be
/// `components × count` (count of points or of cells), else writing the frame is an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field<'a> {
    pub name: &'a str,
    /// 1 for a scalar, 3 for a vector (ParaView's Warp By Vector wants 3), 9 for a tensor.
    pub components: usize,
    pub values: FieldValues<'a>,
    /// Marked as the active scalars of its PointData/CellData (`Scalars="…"`, what ParaView
    /// colours by) whatever its components; without a marked field the first 1-component one is.
    pub active: bool,
}

impl<'a> Field<'a> {
    /// The same field marked as the active scalars.
    pub fn active(self) -> Self {
        Field { active: true, ..self }
    }

    /// A `Float64` field.
    pub fn f64(name: &'a str, components: usize, values: &'a [f64]) -> Self {
        Field {
            name,
            components,
            values: FieldValues::F64(values),
            active: false,
        }
    }

    /// An `Int32` field.
    pub fn i32(name: &'a str, components: usize, values: &'a [i32]) -> Self {
        Field {
            name,
            components,
            values: FieldValues::I32(values),
            active: false,
        }
    }
}

/// One output step of a 2D solution.
#[derive(Clone, Debug)]
pub struct Frame<'a, const D: usize = 2> {
    /// Names the file: `<basename>_<step:05>.vtu`.
    pub step: usize,
    /// The physical time, listed in the `.pvd` and `.vtu.series`; must be finite.
    pub time: f64,
    /// Written as 3D points (z = 0 for a 2D frame).
    pub points: &'a [[f64; D]],
    pub cells: &'a [crate::mesh::Cell],
    /// E.g. "displacement" with 3 components (z = 0) for ParaView's Warp By Vector.
    pub point_fields: Vec<Field<'a>>,
    /// E.g. "stress" with 9 components (a tensor), "von_mises" with 1.
    pub cell_fields: Vec<Field<'a>>,
}

/// One output step of a boundary part (e.g. Γ₃), written as a PolyData `.vtp`: its points are
/// the part's nodes only, its cells the part's facets (lines in 2D, triangles or quadrilaterals
/// in 3D), indexing into `points`.
#[derive(Clone, Debug)]
pub struct SurfaceFrame<'a, const D: usize = 2> {
    /// Names the file: `<basename>_<step:05>.vtp`.
    pub step: usize,
    /// The physical time; must be finite.
    pub time: f64,
    pub points: &'a [[f64; D]],
    /// All edges (2D) or all faces (3D).
    pub facets: &'a [crate::mesh::Facet],
    pub point_fields: Vec<Field<'a>>,
    pub cell_fields: Vec<Field<'a>>,
}

/// Formats a number so that parsing it gives back the same `f64`: the shortest round-trip
/// decimal, plain (`0.25`, `1`, `-3.5e-3` → `-0.0035`) for magnitudes in [1e-5, 1e16) and zero,
/// in scientific notation (`1e-7`, `2.5e20`) otherwise; `NaN`, `inf`, `-inf` for the rest.
pub fn format_number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The default zlib level of the `.vtu` files: 0, uncompressed (levels 1–9: zlib blocks of
/// 32 KiB, VTK's `vtkZLibDataCompressor` layout; the scene's `output.compress`). Measured sizes
/// and times: README, "Output files".
pub const DEFAULT_COMPRESSION_LEVEL: u32 = 0;

/// Writes a ParaView time series: one `.vtu` per frame and the `.pvd`/`.vtu.series` indexes.
#[derive(Debug)]
pub struct SeriesWriter {
    dir: PathBuf,
    basename: String,
    pvd: PathBuf,
    series: PathBuf,
    /// `vtu` or `vtp`.
    extension: &'static str,
    frames: Vec<(f64, PathBuf)>,
    compression_level: u32,
    /// The bytes of the last uncompressed frame, reused for the next one.
    buffer: vtu::VtuBuffer,
}

impl SeriesWriter {
    /// Creates `dir` (and parents) if needed and proves it writable by creating and removing a
    /// probe file, so that an unusable directory is reported before any solving happens. The
    /// error names the directory and the fix. Nothing else is written yet: the index files of an
    /// earlier run in `dir` stay until this writer's first frame replaces them (they then list
    /// only this writer's frames; earlier `.vtu` files are left alone).
    pub fn create(dir: &Path, basename: &str) -> Result<Self, OutputError> {
        Self::create_with(dir, basename, "vtu")
    }

    /// As [`SeriesWriter::create`], for a series of boundary frames (`.vtp`,
    /// `<basename>.vtp.series`) written by [`SeriesWriter::write_surface_frame`].
    pub fn create_surface(dir: &Path, basename: &str) -> Result<Self, OutputError> {
        Self::create_with(dir, basename, "vtp")
    }

    fn create_with(dir: &Path, basename: &str, extension: &'static str) -> Result<Self, OutputError> {
        if basename.is_empty()
            || basename.starts_with('.')
            || basename.contains(['/', '\\'])
            || basename.chars().any(char::is_control)
        {
            return Err(OutputError::InvalidArgument {
                path: dir.join(basename),
                detail: format!(
                    "the series name {basename:?} must be a plain, non-hidden file name without path separators"
                ),
            });
        }
        if dir.exists() && !dir.is_dir() {
            return Err(OutputError::directory(
                dir,
                io::Error::new(io::ErrorKind::AlreadyExists, "not a directory"),
            ));
        }
        fs::create_dir_all(dir).map_err(|e| OutputError::directory(dir, e))?;
        probe_writable(dir)?;
        Ok(SeriesWriter {
            dir: dir.to_path_buf(),
            basename: basename.to_string(),
            pvd: dir.join(format!("{basename}.pvd")),
            series: dir.join(format!("{basename}.{extension}.series")),
            extension,
            frames: Vec::new(),
            compression_level: DEFAULT_COMPRESSION_LEVEL,
            buffer: vtu::VtuBuffer::default(),
        })
    }

    /// Sets the zlib level of the `.vtu` files (0: uncompressed, the default; 1 fastest … 9
    /// smallest). See [`DEFAULT_COMPRESSION_LEVEL`] for the costs.
    pub fn with_compression(mut self, level: u32) -> Self {
        self.compression_level = level.min(MAX_COMPRESSION_LEVEL);
        self
    }

    /// Validates `frame` (field lengths, cell node indices, names, finite time: an error, and
    /// nothing written, if wrong), writes `<basename>_<step:05>.vtu` atomically (temporary name
    /// in the same directory, then rename), then rewrites `<basename>.pvd` and
    /// `<basename>.vtu.series` atomically, listing every frame written so far with its time.
    /// Writing a step again replaces its file and its entry. Returns the `.vtu` path.
    pub fn write_frame<const D: usize>(&mut self, frame: &Frame<D>) -> Result<PathBuf, OutputError> {
        self.write_view(&frame.view(), "vtu")
    }

    /// As [`SeriesWriter::write_frame`], for a writer made by [`SeriesWriter::create_surface`]:
    /// `<basename>_<step:05>.vtp`.
    pub fn write_surface_frame<const D: usize>(&mut self, frame: &SurfaceFrame<D>) -> Result<PathBuf, OutputError> {
        self.write_view(&frame.view(), "vtp")
    }

    /// The file name of step `step`'s frame: `<basename>_<step:05>.vtu` (`.vtp`).
    pub fn frame_name(&self, step: usize) -> String {
        format!("{}_{step:05}.{}", self.basename, self.extension)
    }

    fn write_view<const D: usize>(&mut self, view: &vtu::View<D>, extension: &str) -> Result<PathBuf, OutputError> {
        let path = self.dir.join(format!("{}_{:05}.{extension}", self.basename, view.step));
        if extension != self.extension {
            return Err(OutputError::InvalidArgument {
                path,
                detail: format!(
                    "this series writes .{} files; a .{extension} frame belongs to another series",
                    self.extension
                ),
            });
        }
        vtu::write_vtu(&path, view, self.compression_level, &mut self.buffer)?;
        let mut frames = self.frames.clone();
        match frames.iter_mut().find(|(_, p)| *p == path) {
            Some(entry) => entry.0 = view.time,
            None => frames.push((view.time, path.clone())),
        }
        pvd::write_index(&self.pvd, &self.series, &frames)?;
        self.frames = frames;
        Ok(path)
    }

    /// Every frame written so far: (time, `.vtu` path), in the order written.
    pub fn frames(&self) -> &[(f64, PathBuf)] {
        &self.frames
    }

    /// The output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The `.pvd` file.
    pub fn pvd_path(&self) -> &Path {
        &self.pvd
    }

    /// The file names of the two index files (`.pvd`, `.series`).
    pub fn index_names(&self) -> [String; 2] {
        [&self.pvd, &self.series].map(|p| {
            p.file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
        })
    }

    /// The `.vtu.series` (`.vtp.series`) file.
    pub fn series_path(&self) -> &Path {
        &self.series
    }
}

/// Creates, writes and removes a hidden probe file in `dir`.
fn probe_writable(dir: &Path) -> Result<(), OutputError> {
    let probe = dir.join(format!(".hvi-write-probe.tmp.{}", std::process::id()));
    let result = OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(&probe)
        .and_then(|mut f| f.write_all(b"hvi"));
    let removed = fs::remove_file(&probe);
    result.and(removed).map_err(|e| OutputError::directory(dir, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.25,
            0.1 + 0.2,
            1e-7,
            -3.5e-3,
            2.5e20,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
        ] {
            let s = format_number(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(format_number(1.0), "1");
        assert_eq!(format_number(0.25), "0.25");
        assert_eq!(format_number(1e-7), "1e-7");
    }
}
