//! One run per output directory (docs/method.md §12.2): a run holds an exclusive OS lock
//! (`flock`) on the directory's hidden `.hvi-lock` for its whole life, so that a second run into
//! the same directory — started alongside, or with `--overwrite` while the first still writes —
//! is refused instead of mixing its files with the first run's. The OS drops the lock when the
//! process ends, however it ends (a killed run leaves no stale lock to clean up). The file
//! holds the holder's process id, for the message; it is never removed (removing a lock file
//! while another process waits on it would let two holders exist) and never listed in the
//! manifest, so `--overwrite` leaves it alone.

use super::OutputError;
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The lock file's name.
pub const LOCK_NAME: &str = ".hvi-lock";

/// The held lock on an output directory: released when dropped (or the process ends).
#[derive(Debug)]
pub struct RunLock {
    _file: File,
}

impl RunLock {
    /// Takes the lock on `dir` (which must exist), without waiting: an error naming the holder's
    /// process id when another run holds it.
    pub fn acquire(dir: &Path) -> Result<RunLock, OutputError> {
        let path = dir.join(LOCK_NAME);
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| OutputError::write(&path, e))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut text = String::new();
                let _ = file.read_to_string(&mut text);
                return Err(busy(dir, &path, text.trim()));
            }
            Err(TryLockError::Error(e)) => return Err(OutputError::write(&path, e)),
        }
        // ours now: record who holds it
        file.set_len(0)
            .and_then(|()| file.seek(SeekFrom::Start(0)))
            .and_then(|_| file.write_all(format!("{}\n", std::process::id()).as_bytes()))
            .and_then(|()| file.flush())
            .map_err(|e| OutputError::write(&path, e))?;
        Ok(RunLock { _file: file })
    }
}

fn busy(dir: &Path, path: &PathBuf, holder: &str) -> OutputError {
    let who = match holder.parse::<u32>() {
        Ok(pid) => format!("another hvi run (process {pid}) is writing into it"),
        Err(_) => "another hvi run is writing into it".to_string(),
    };
    OutputError::Busy {
        dir: dir.to_path_buf(),
        detail: format!(
            "{who} (it holds the lock {}); wait for that run to end, or choose another --out",
            path.display()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_holder_is_refused_naming_the_first_and_admitted_after_it_ends() {
        let dir = tempfile::tempdir().unwrap();
        let first = RunLock::acquire(dir.path()).unwrap();
        let e = RunLock::acquire(dir.path()).unwrap_err().to_string();
        assert!(e.contains(&format!("process {}", std::process::id())), "{e}");
        assert!(e.contains("choose another --out"), "{e}");
        drop(first);
        RunLock::acquire(dir.path()).expect("free again once the holder is gone");
    }
}
