//! The manifest of a run's files (`.hvi-run`) and what it allows: refusing to write into a
//! directory that holds an earlier run, or (asked to overwrite) removing exactly the files that
//! run wrote, so that no stale frame of it survives, listed or not, and no file hvi did not
//! write is touched.
//!
//! The manifest is a hidden text file in the output directory: a first line naming the format,
//! then one file name per line, appended (and flushed) *before* hvi creates the file, so that
//! even an interrupted or killed run leaves a manifest covering everything it wrote. `hvi plot`
//! adds the pictures it writes into a run's directory ([`record_in_run`]; docs/method.md §12.2).

use super::OutputError;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The manifest's file name.
pub const MANIFEST_NAME: &str = ".hvi-run";

const FIRST_LINE: &str = "hvi run manifest v1";

/// The manifest of the run being written.
#[derive(Debug)]
pub struct RunManifest {
    path: PathBuf,
    file: File,
    /// The directory's lock, held as long as the manifest (the run) lives.
    _lock: super::RunLock,
}

/// True if `name` is a plain file name (no separator, not `.` or `..`): the only names a
/// manifest may list.
fn plain(name: &str) -> bool {
    !name.is_empty()
        && name != "."
        && name != ".."
        && !name.contains(['/', '\\'])
        && !name.chars().any(char::is_control)
}

impl RunManifest {
    /// Starts the manifest of a new run in `dir` (created if needed), holding the directory's
    /// lock ([`super::RunLock`]) as long as it lives: an error naming the holder if another run
    /// holds it. If `dir` holds an earlier
    /// run (a manifest, or a `solution.pvd` of an hvi without manifests) this is an error naming
    /// the directory and the flag, unless `overwrite`: then the files the earlier manifest lists
    /// are removed first (an earlier run without a manifest is an error even then, since which
    /// files it wrote is not known).
    pub fn start(dir: &Path, overwrite: bool) -> Result<Self, OutputError> {
        fs::create_dir_all(dir).map_err(|e| OutputError::directory(dir, e))?;
        // first the lock, so that the check for an earlier run and its removal below are not
        // raced by another run into the same directory
        let lock = super::RunLock::acquire(dir)?;
        let path = dir.join(MANIFEST_NAME);
        let earlier = path.exists();
        if earlier || dir.join("solution.pvd").exists() {
            if !overwrite {
                return Err(OutputError::EarlierRun {
                    dir: dir.to_path_buf(),
                    detail: format!(
                        "it holds an earlier hvi run ({}); pass --overwrite to remove that run's files first \
                         (only those: its manifest {MANIFEST_NAME} lists them), or choose another --out",
                        if earlier { MANIFEST_NAME } else { "solution.pvd" }
                    ),
                });
            }
            if !earlier {
                return Err(OutputError::EarlierRun {
                    dir: dir.to_path_buf(),
                    detail: format!(
                        "it holds solution.pvd but no manifest {MANIFEST_NAME} (a run of an earlier hvi), so which \
                         files that run wrote is not known and --overwrite cannot remove exactly those; remove them \
                         yourself or choose another --out"
                    ),
                });
            }
            remove_listed(dir, &path)?;
        }
        fs::write(&path, format!("{FIRST_LINE}\n")).map_err(|e| OutputError::write(&path, e))?;
        // appending (O_APPEND), so that names another command records meanwhile
        // ([`record_in_run`]) are never overwritten by this run's next line
        let file = OpenOptions::new()
            .append(true)
            .open(&path)
            .map_err(|e| OutputError::write(&path, e))?;
        Ok(RunManifest {
            path,
            file,
            _lock: lock,
        })
    }

    /// Records that the run writes `name` (a file of the output directory). Call before
    /// creating the file; recording a name twice is harmless.
    pub fn add(&mut self, name: &str) -> Result<(), OutputError> {
        if !plain(name) {
            return Err(OutputError::InvalidArgument {
                path: self.path.clone(),
                detail: format!("{name:?} is not a plain file name of the output directory"),
            });
        }
        self.file
            .write_all(format!("{name}\n").as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| OutputError::write(&self.path, e))
    }

    /// The manifest file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Records that a later command (`hvi plot`) writes the files `names` into the run directory
/// `dir`, so that `--overwrite` removes them with the run's own files and a rerun leaves no stale
/// picture. Call before creating the files. Each name not yet listed is appended to the run's
/// manifest as one line in one `write` on a file opened for appending (O_APPEND: concurrent
/// appenders, e.g. a run still writing its frames, never interleave within a line), flushed.
/// Returns false, recording nothing, when `dir` holds no manifest: no run, or a run of an hvi
/// before manifests, which `--overwrite` refuses anyway (a manifest started here would make
/// such a run's frames look unlisted, hence survivable).
pub fn record_in_run(dir: &Path, names: &[&str]) -> Result<bool, OutputError> {
    let path = dir.join(MANIFEST_NAME);
    if !path.is_file() {
        return Ok(false);
    }
    let listed = read_manifest(&path)?;
    let mut file = OpenOptions::new()
        .append(true)
        .open(&path)
        .map_err(|e| OutputError::write(&path, e))?;
    for name in names {
        if !plain(name) {
            return Err(OutputError::InvalidArgument {
                path: path.clone(),
                detail: format!("{name:?} is not a plain file name of the output directory"),
            });
        }
        if listed.iter().any(|l| l == name) {
            continue;
        }
        file.write_all(format!("{name}\n").as_bytes())
            .and_then(|()| file.flush())
            .map_err(|e| OutputError::write(&path, e))?;
    }
    Ok(true)
}

/// The file names a manifest lists (its first line checked).
pub fn read_manifest(path: &Path) -> Result<Vec<String>, OutputError> {
    let text = fs::read_to_string(path).map_err(|e| OutputError::read(path, e))?;
    let mut lines = text.lines();
    if lines.next() != Some(FIRST_LINE) {
        return Err(OutputError::format(
            path,
            format!("not an hvi run manifest (its first line is not \"{FIRST_LINE}\"); remove the earlier run's files yourself or choose another --out"),
        ));
    }
    Ok(lines.filter(|l| !l.is_empty()).map(str::to_string).collect())
}

/// Removes every regular file `manifest` lists (names that are not plain file names, and
/// directories or links, are left alone), then the manifest.
fn remove_listed(dir: &Path, manifest: &Path) -> Result<(), OutputError> {
    for name in read_manifest(manifest)? {
        if !plain(&name) {
            continue;
        }
        let p = dir.join(&name);
        match fs::symlink_metadata(&p) {
            Ok(m) if m.is_file() => fs::remove_file(&p).map_err(|e| OutputError::write(&p, e))?,
            Ok(_) => {}
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(OutputError::write(&p, e)),
        }
    }
    fs::remove_file(manifest).map_err(|e| OutputError::write(manifest, e))
}
