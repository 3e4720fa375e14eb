//! The one error type of [`crate::output`]: every message names the file or directory, what
//! went wrong, and what to do about it, because `hvi` prints it as the whole report.

use std::io;
use std::path::{Path, PathBuf};

/// What can go wrong while writing (or reading back) output files.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The output directory cannot be created or written to.
    #[error("cannot write to {}: {}; {}", dir.display(), describe_io(source), directory_fix(source))]
    Directory {
        dir: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A file (or its temporary sibling) could not be created, written or renamed.
    #[error("cannot write {}: {}; {}", path.display(), describe_io(source), file_fix(source))]
    Write {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A file could not be read.
    #[error("cannot read {}: {}; check the path and its permissions", path.display(), describe_io(source))]
    Read {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A field's value count does not match its component count times the number of
    /// points (or cells).
    #[error(
        "{}: {location} field \"{name}\" has {got} values, but {components} component(s) × {count} {location}s = {expected}; \
         this is a bug in the code that assembles the frame (the field belongs to another mesh or has the wrong component count)",
        path.display()
    )]
    FieldLength {
        path: PathBuf,
        location: &'static str,
        name: String,
        components: usize,
        count: usize,
        expected: usize,
        got: usize,
    },
    /// A frame that cannot be written as a valid file (bad cell index, empty or duplicate
    /// field name, zero components, non-finite time, ...).
    #[error("{}: invalid frame: {detail}", path.display())]
    InvalidFrame { path: PathBuf, detail: String },
    /// A CSV row whose length does not match the header.
    #[error(
        "{}: row {row} of the block has {got} values but the header has {expected} columns; nothing of this block was written",
        path.display()
    )]
    CsvRow {
        path: PathBuf,
        row: usize,
        got: usize,
        expected: usize,
    },
    /// A caller-supplied argument that cannot work (an empty CSV header, a base name with a
    /// path separator, ...).
    #[error("{}: {detail}", path.display())]
    InvalidArgument { path: PathBuf, detail: String },
    /// A value could not be serialised as JSON.
    #[error("{}: cannot serialise as JSON: {source}", path.display())]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    /// The output directory holds an earlier run that may not (or cannot) be replaced.
    #[error("cannot write into {}: {detail}", dir.display())]
    EarlierRun { dir: PathBuf, detail: String },
    /// Another run holds the output directory's lock.
    #[error("cannot write into {}: {detail}", dir.display())]
    Busy { dir: PathBuf, detail: String },
    /// A `.vtu` (`.vtp`, `.pvtu`, `.pvd`) file that was read back does not have the expected
    /// structure.
    #[error("{}: not a {} written by hvi: {detail}", path.display(), kind(path))]
    Format { path: PathBuf, detail: String },
}

impl OutputError {
    pub(crate) fn write(path: &Path, source: io::Error) -> Self {
        OutputError::Write {
            path: path.to_path_buf(),
            source,
        }
    }

    pub(crate) fn read(path: &Path, source: io::Error) -> Self {
        OutputError::Read {
            path: path.to_path_buf(),
            source,
        }
    }

    pub(crate) fn directory(dir: &Path, source: io::Error) -> Self {
        OutputError::Directory {
            dir: dir.to_path_buf(),
            source,
        }
    }

    pub(crate) fn invalid_frame(path: &Path, detail: impl Into<String>) -> Self {
        OutputError::InvalidFrame {
            path: path.to_path_buf(),
            detail: detail.into(),
        }
    }

    pub(crate) fn format(path: &Path, detail: impl Into<String>) -> Self {
        OutputError::Format {
            path: path.to_path_buf(),
            detail: detail.into(),
        }
    }
}

/// `.vtu`, `.pvd`, ... as the extension of `path` says (`.vtu` without one).
fn kind(path: &Path) -> String {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e @ ("vtu" | "vtp" | "pvtu" | "pvd")) => format!(".{e}"),
        _ => ".vtu".into(),
    }
}

/// A short lower-case description of an I/O error (the OS text as a fallback).
fn describe_io(e: &io::Error) -> String {
    use io::ErrorKind::*;
    match e.kind() {
        PermissionDenied => "permission denied".into(),
        NotFound => "no such file or directory".into(),
        AlreadyExists => "a file of that name already exists".into(),
        NotADirectory => "a component of the path is a file, not a directory".into(),
        IsADirectory => "it is a directory".into(),
        ReadOnlyFilesystem => "read-only file system".into(),
        StorageFull => "no space left on device".into(),
        _ => e.to_string(),
    }
}

fn directory_fix(e: &io::Error) -> &'static str {
    use io::ErrorKind::*;
    match e.kind() {
        StorageFull => "free some disk space or choose another --out directory",
        PermissionDenied | ReadOnlyFilesystem => "fix its permissions or choose another --out directory",
        _ => "choose another --out directory",
    }
}

fn file_fix(e: &io::Error) -> &'static str {
    use io::ErrorKind::*;
    match e.kind() {
        StorageFull => "free some disk space or choose another --out directory",
        NotFound => "the directory may have been removed during the run; choose another --out directory",
        _ => "check the directory's permissions or choose another --out directory",
    }
}

/// A sink's write failing stops the run with the write's own message.
impl From<OutputError> for crate::solver::SolveError {
    fn from(e: OutputError) -> Self {
        crate::solver::SolveError::Sink(Box::new(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_path_reason_and_fix() {
        let e = OutputError::directory(Path::new("runs/a"), io::Error::from(io::ErrorKind::PermissionDenied));
        assert_eq!(
            e.to_string(),
            "cannot write to runs/a: permission denied; fix its permissions or choose another --out directory"
        );
        fn assert_send_sync<T: Send + Sync + 'static>() {}
        assert_send_sync::<OutputError>();
    }
}
