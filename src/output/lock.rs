//! One run per output directory (docs/method.md §12.2): a run holds an exclusive OS lock
//! (`flock`) on the output directory itself for its whole life, so that a second run into the
//! same directory — started alongside, or with `--overwrite` while the first still writes — is
//! refused instead of mixing its files with the first run's. The OS drops the lock when the
//! process ends, however it ends (a killed run leaves nothing stale behind), and no lock file is
//! left in the directory. The holder's process id, for the message, is read from the kernel's
//! table of locks (`/proc/locks`, by the directory's inode).

use super::OutputError;
use std::fs::{File, TryLockError};
use std::path::Path;

/// The held lock on an output directory: released when dropped (or the process ends).
#[derive(Debug)]
pub struct RunLock {
    _dir: File,
}

impl RunLock {
    /// Takes the lock on `dir` (which must exist), without waiting: an error naming the holder's
    /// process id when another run holds it.
    pub fn acquire(dir: &Path) -> Result<RunLock, OutputError> {
        let handle = File::open(dir).map_err(|e| OutputError::directory(dir, e))?;
        match handle.try_lock() {
            Ok(()) => Ok(RunLock { _dir: handle }),
            Err(TryLockError::WouldBlock) => Err(busy(dir, &handle)),
            Err(TryLockError::Error(e)) => Err(OutputError::directory(dir, e)),
        }
    }
}

fn busy(dir: &Path, handle: &File) -> OutputError {
    let who = match holder(handle) {
        Some(pid) => format!("another hvi run (process {pid}) is writing into it"),
        None => "another hvi run is writing into it".to_string(),
    };
    OutputError::Busy {
        dir: dir.to_path_buf(),
        detail: format!("{who}; wait for that run to end, or choose another --out"),
    }
}

/// The process holding a `flock` on the file `handle` refers to, from `/proc/locks` (Linux;
/// None elsewhere or if it cannot be told).
fn holder(handle: &File) -> Option<u32> {
    use std::os::unix::fs::MetadataExt;
    let inode = handle.metadata().ok()?.ino();
    let table = std::fs::read_to_string("/proc/locks").ok()?;
    // "1: FLOCK  ADVISORY  WRITE 1234 08:01:5678 0 EOF": kind, pid, major:minor:inode
    table.lines().find_map(|line| {
        let fields: Vec<&str> = line.split_whitespace().collect();
        let at = fields.iter().position(|f| *f == "FLOCK")?;
        let pid = fields.get(at + 3)?.parse().ok()?;
        let ino: u64 = fields.get(at + 4)?.rsplit(':').next()?.parse().ok()?;
        (ino == inode).then_some(pid)
    })
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
        // no file is left in the directory
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        drop(first);
        RunLock::acquire(dir.path()).expect("free again once the holder is gone");
    }
}
