//! A time series on disk (docs/method.md §12): one file per output step, written atomically, and
//! the `.pvd` index that lists them.

use crate::output::pvd;
use crate::output::vtu;
use crate::output::Frame;
use crate::output::OutputError;
use crate::output::SurfaceFrame;
use crate::output::DEFAULT_COMPRESSION_LEVEL;
use crate::output::MAX_COMPRESSION_LEVEL;
use std::fs::{self, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Writes a ParaView time series: one `.vtu` per frame and the `.pvd`/`.vtu.series` indexes.
#[derive(Debug)]
pub struct SeriesWriter {
    pub(super) dir: PathBuf,
    pub(super) basename: String,
    pub(super) pvd: PathBuf,
    pub(super) series: PathBuf,
    /// `vtu` or `vtp`.
    pub(super) extension: &'static str,
    pub(super) frames: Vec<(f64, PathBuf)>,
    pub(super) compression_level: u32,
    /// The bytes of the last uncompressed frame, reused for the next one.
    pub(super) buffer: vtu::VtuBuffer,
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

    pub(super) fn create_with(dir: &Path, basename: &str, extension: &'static str) -> Result<Self, OutputError> {
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
    use crate::output::{read_pvd, OutputError};

    /// A series whose name needs every escape reads back with the names written, in a
    /// directory whose name needs them too (it is not in the `.pvd`, which lists bare names).
    #[test]
    fn pvd_reads_back_the_names_written() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("run &<\"'>");
        let basename = "a&b \"q\" <x>'";
        let mut series = super::SeriesWriter::create(&dir, basename).unwrap();
        let points = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let cells = [crate::mesh::Cell::Tri3([0, 1, 2])];
        for (step, time) in [(0, 0.0), (1, 0.1 + 0.2), (2, 5e-324)] {
            let frame = crate::output::Frame {
                step,
                time,
                points: &points,
                cells: &cells,
                point_fields: vec![],
                cell_fields: vec![],
            };
            series.write_frame(&frame).unwrap();
        }
        let text = std::fs::read_to_string(series.pvd_path()).unwrap();
        assert!(
            text.contains("file=\"a&amp;b &quot;q&quot; &lt;x&gt;&apos;_00000.vtu\""),
            "{text}"
        );
        let frames = read_pvd(series.pvd_path()).unwrap();
        let expected: Vec<(f64, String)> = series
            .frames()
            .iter()
            .map(|(t, p)| (*t, p.file_name().unwrap().to_string_lossy().into_owned()))
            .collect();
        assert_eq!(frames, expected);
        assert_eq!(frames[1], (0.1 + 0.2, format!("{basename}_00001.vtu")));
        for (_, name) in &frames {
            assert!(dir.join(name).is_file(), "{name}");
        }

        // what is wrong is named with the file
        let pvd = dir.join("bad.pvd");
        for (text, what) in [
            (text.replace("timestep=\"0\"", "timestep=\"zero\""), "\"zero\""),
            (text.replace("</Collection>", ""), "malformed XML"),
            (text[..text.len() / 2].to_string(), "truncated"),
            (text.replace("Collection", "PolyData"), "not a .pvd written by hvi"),
            (text.replacen(" file=", " name=", 1), "without file"),
        ] {
            std::fs::write(&pvd, text).unwrap();
            let e = read_pvd(&pvd).unwrap_err().to_string();
            assert!(e.contains("bad.pvd") && e.contains(what), "{what}: {e}");
        }
        let e = read_pvd(&dir.join("none.pvd")).unwrap_err();
        assert!(matches!(e, OutputError::Read { .. }), "{e}");
    }
}
