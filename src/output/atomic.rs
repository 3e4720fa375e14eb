//! Whole-file replacement: write a hidden temporary sibling, then rename it over the target.
//!
//! A reader (ParaView, a script, a crashed-and-restarted run) therefore sees either the old
//! file or the new one, never a truncated one. The rename is not preceded by an fsync: this
//! protects against an interrupted *process* (Ctrl-C, a panic, an error), not against a power
//! cut, which is the trade-off hvi wants for files rewritten every step.
//!
//! Temporary names are `.<file name>.tmp.<pid>.<n>`: the leading dot hides them from ParaView's
//! file dialog and from its numbered-file grouping, the process id keeps concurrent runs
//! apart, and `n` (a per-process counter) keeps threads apart. They are removed on failure.

use super::OutputError;
use serde::Serialize;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// True if `name` is a temporary file name made by this module (used by tests and tooling).
pub fn is_temporary_name(name: &str) -> bool {
    name.starts_with('.') && name.contains(".tmp.")
}

/// The directory `path` lives in ("." for a bare file name).
pub(crate) fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Removes the temporary file when dropped, unless disarmed after a successful rename.
struct TempGuard {
    path: Option<PathBuf>,
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if let Some(p) = self.path.take() {
            let _ = fs::remove_file(p);
        }
    }
}

/// Creates a fresh temporary sibling of `path` (never an existing file).
pub(crate) fn create_temp_sibling(path: &Path) -> Result<(File, PathBuf), OutputError> {
    let name = path.file_name().ok_or_else(|| OutputError::InvalidArgument {
        path: path.to_path_buf(),
        detail: "the path has no file name; give a file path, not a directory".into(),
    })?;
    let dir = parent_dir(path);
    let pid = std::process::id();
    let mut last_err = None;
    for _ in 0..16 {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{}.tmp.{pid}.{n}", name.to_string_lossy()));
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((f, tmp)),
            // A stale file of a crashed process that had our pid: try the next counter value.
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last_err = Some(e),
            Err(e) => return Err(OutputError::write(path, e)),
        }
    }
    Err(OutputError::write(
        path,
        last_err.unwrap_or_else(|| io::Error::other("no free temporary name")),
    ))
}

/// Writes `path` atomically through `fill`, which receives a buffered writer on the temporary
/// file. Errors of `fill` pass through unchanged; the temporary file is removed on any failure.
pub(crate) fn write_atomic_with<F>(path: &Path, fill: F) -> Result<(), OutputError>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
{
    let (file, tmp) = create_temp_sibling(path)?;
    let mut guard = TempGuard {
        path: Some(tmp.clone()),
    };
    let mut w = BufWriter::new(file);
    fill(&mut w)?;
    let file = w.into_inner().map_err(|e| OutputError::write(path, e.into_error()))?;
    drop(file);
    fs::rename(&tmp, path).map_err(|e| OutputError::write(path, e))?;
    guard.path = None;
    Ok(())
}

/// Replaces `path` with `bytes`: a temporary file in the same directory, then a rename (no
/// fsync). On failure the temporary file is removed and `path` is left as it was.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomic_with(path, |w| w.write_all(bytes).map_err(|e| OutputError::write(path, e)))
}

/// Replaces `path` with `value` as pretty-printed JSON (and a final newline), atomically as
/// [`write_atomic`].
pub fn write_json_atomic<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), OutputError> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|source| OutputError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failure_inside_fill_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("a.txt");
        write_atomic(&target, b"old").unwrap();
        let r = write_atomic_with(&target, |w| {
            w.write_all(b"partial").unwrap();
            Err(OutputError::invalid_frame(&target, "simulated"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read(&target).unwrap(), b"old");
        let names: Vec<_> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.txt")]);
    }

    #[test]
    fn temporary_names_are_hidden_and_distinct() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("solution.pvd");
        let (_f1, a) = create_temp_sibling(&p).unwrap();
        let (_f2, b) = create_temp_sibling(&p).unwrap();
        assert_ne!(a, b);
        let an = a.file_name().unwrap().to_str().unwrap();
        assert!(is_temporary_name(an) && an.starts_with(".solution.pvd.tmp."), "{an}");
    }
}
