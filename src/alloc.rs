//! Running out of memory ends a run with a message and a summary, never a panic or an abort
//! (docs/method.md §16.2).
//!
//! Rust aborts the process when an allocation fails (SIGABRT, no message of ours, no
//! summary.json), and libraries that allocate fallibly (faer's workspaces) `unwrap` the error
//! into a panic. hvi refuses up front a run whose predicted peak does not fit
//! (`crate::solver::memory`), but a prediction can be wrong and the memory can be taken by
//! another process meanwhile. So the `hvi` binary installs [`Guarded`] as its global
//! allocator: the system allocator, except that when an allocation fails outside a
//! [`fallible`] section it writes the message to stderr and the armed [`FailureReport`] (the
//! run's summary.json with `"status": "failed: out of memory …"`) with raw system calls that
//! allocate nothing, and ends the process with exit code 1. Code that handles a failed
//! allocation itself (`try_reserve` with its own message) runs inside [`fallible`].

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::ffi::CString;
use std::fmt::Write as _;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

/// The global allocator of the `hvi` binary: the system's, with a clean end on failure.
pub struct Guarded;

thread_local! {
    /// Depth of [`fallible`] sections on this thread: a failure there is returned to the caller.
    static FALLIBLE: Cell<u32> = const { Cell::new(0) };
}

/// Set by the first failure that ends the process (a second one, while it reports, aborts).
static FAILING: AtomicBool = AtomicBool::new(false);

/// The file to leave when an allocation fails, armed by the run ([`arm`]).
static REPORT: Mutex<Option<FailureReport>> = Mutex::new(None);

/// The run's progress for the report: steps done, and the last step written (`usize::MAX`:
/// none), as of the last call of [`record_progress`].
static STEPS_DONE: AtomicUsize = AtomicUsize::new(0);
static LAST_WRITTEN: AtomicUsize = AtomicUsize::new(usize::MAX);

/// Placeholders of a report's template ([`FailureReport::from_template`]).
pub const STATUS_MARK: &str = "@@hvi-status@@";
pub const STEPS_MARK: usize = usize::MAX - 1;
pub const LAST_MARK: usize = usize::MAX - 2;

/// A file written on an allocation failure: the template's pieces with the status text and the
/// progress between them, written to `temporary` and renamed to `path` (so that no reader sees
/// half of it).
pub struct FailureReport {
    path: CString,
    temporary: CString,
    /// before the status, between it and the steps done, between those and the last step
    /// written, after it
    pieces: [Vec<u8>; 4],
}

/// Records the run's progress for the report (an atomic store each: cheap enough per step).
pub fn record_progress(steps_done: usize, last_written: Option<usize>) {
    STEPS_DONE.store(steps_done, Ordering::Relaxed);
    LAST_WRITTEN.store(last_written.unwrap_or(usize::MAX), Ordering::Relaxed);
}

impl FailureReport {
    /// A report for the file `path` from `template`, a text holding, in this order, the
    /// [`STATUS_MARK`], the number [`STEPS_MARK`] and the number [`LAST_MARK`] (e.g. a summary's
    /// JSON rendered with those values). None if the template lacks one or the path cannot be a
    /// C string.
    pub fn from_template(path: &std::path::Path, template: &str) -> Option<Self> {
        let (a, rest) = template.split_once(STATUS_MARK)?;
        let (b, rest) = rest.split_once(&STEPS_MARK.to_string())?;
        let (c, d) = rest.split_once(&LAST_MARK.to_string())?;
        Self::new(path, [a, b, c, d])
    }

    fn new(path: &std::path::Path, pieces: [&str; 4]) -> Option<Self> {
        use std::os::unix::ffi::OsStrExt;
        let name = path.file_name()?.as_bytes();
        let mut tmp = path.as_os_str().as_bytes().to_vec();
        tmp.truncate(tmp.len() - name.len());
        tmp.extend_from_slice(b".");
        tmp.extend_from_slice(name);
        tmp.extend_from_slice(b".tmp.oom");
        Some(FailureReport {
            path: CString::new(path.as_os_str().as_bytes()).ok()?,
            temporary: CString::new(tmp).ok()?,
            pieces: pieces.map(|p| p.as_bytes().to_vec()),
        })
    }
}

/// Arms (Some) or disarms (None) the file written when an allocation fails.
pub fn arm(report: Option<FailureReport>) {
    *REPORT.lock().unwrap_or_else(|e| e.into_inner()) = report;
}

/// Runs `f` with allocation failures returned to it (null pointers, `try_reserve` errors)
/// instead of ending the process: for code that reports them itself.
pub fn fallible<T>(f: impl FnOnce() -> T) -> T {
    struct Depth;
    impl Drop for Depth {
        fn drop(&mut self) {
            FALLIBLE.with(|c| c.set(c.get() - 1));
        }
    }
    FALLIBLE.with(|c| c.set(c.get() + 1));
    let _depth = Depth;
    f()
}

/// The status text of an allocation failure of `size` bytes.
pub fn status(size: usize, out: &mut impl std::fmt::Write) {
    let _ = write!(
        out,
        "failed: out of memory: an allocation of {:.1} MiB failed; the run needs more memory than this process may \
         use (its limit is the smallest of the free memory, ulimit -v and the cgroup's limit; `hvi check` prints \
         the predicted peak): use fewer contact nodes, a coarser mesh, or --backend petsc on more ranks",
        size as f64 / 1048576.0
    );
}

/// A fixed buffer that formats without allocating (text beyond its size is dropped).
struct StackText {
    bytes: [u8; 1024],
    len: usize,
}

impl StackText {
    const fn new() -> Self {
        StackText {
            bytes: [0; 1024],
            len: 0,
        }
    }

    fn text(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

impl std::fmt::Write for StackText {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let n = s.len().min(self.bytes.len() - self.len);
        self.bytes[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
        Ok(())
    }
}

fn write_all(fd: libc::c_int, mut bytes: &[u8]) -> bool {
    while !bytes.is_empty() {
        // SAFETY: a valid buffer of bytes.len() bytes.
        let n = unsafe { libc::write(fd, bytes.as_ptr().cast(), bytes.len()) };
        if n <= 0 {
            return false;
        }
        bytes = &bytes[n as usize..];
    }
    true
}

/// An allocation of `size` bytes failed outside a [`fallible`] section: report and end the
/// process (exit code 1). Returns only when already reporting (the caller then aborts).
fn out_of_memory(size: usize) {
    if FAILING.swap(true, Ordering::SeqCst) {
        return;
    }
    let mut text = StackText::new();
    status(size, &mut text);
    let message = text.text();
    let _ = write_all(2, b"error: ");
    let _ = write_all(2, message.strip_prefix(b"failed: ").unwrap_or(message));
    let _ = write_all(2, b"\n");
    if let Ok(guard) = REPORT.try_lock() {
        if let Some(r) = guard.as_ref() {
            // SAFETY: NUL-terminated paths; raw calls, nothing allocated.
            unsafe {
                let fd = libc::open(
                    r.temporary.as_ptr(),
                    libc::O_WRONLY | libc::O_CREAT | libc::O_TRUNC,
                    0o644,
                );
                if fd >= 0 {
                    let mut steps = StackText::new();
                    let _ = write!(steps, "{}", STEPS_DONE.load(Ordering::Relaxed));
                    let mut last = StackText::new();
                    let _ = match LAST_WRITTEN.load(Ordering::Relaxed) {
                        usize::MAX => write!(last, "null"),
                        n => write!(last, "{n}"),
                    };
                    let p = &r.pieces;
                    let ok = write_all(fd, &p[0])
                        && write_all(fd, message)
                        && write_all(fd, &p[1])
                        && write_all(fd, steps.text())
                        && write_all(fd, &p[2])
                        && write_all(fd, last.text())
                        && write_all(fd, &p[3]);
                    libc::close(fd);
                    if ok {
                        libc::rename(r.temporary.as_ptr(), r.path.as_ptr());
                    } else {
                        libc::unlink(r.temporary.as_ptr());
                    }
                }
            }
        }
    }
    // SAFETY: ends the process without running anything that could allocate.
    unsafe { libc::_exit(1) }
}

fn checked(p: *mut u8, size: usize) -> *mut u8 {
    if p.is_null() && FALLIBLE.with(|c| c.get()) == 0 {
        out_of_memory(size);
    }
    p
}

// SAFETY: every call is forwarded to the system allocator unchanged; only a null result is
// acted on.
unsafe impl GlobalAlloc for Guarded {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        checked(System.alloc(layout), layout.size())
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        checked(System.alloc_zeroed(layout), layout.size())
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        checked(System.realloc(ptr, layout, new_size), new_size)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_report_is_written_beside_its_file_and_the_status_names_the_size() {
        let template = format!("{{\"status\": \"{STATUS_MARK}\", \"steps\": {STEPS_MARK}, \"last\": {LAST_MARK}}}");
        let r = FailureReport::from_template(std::path::Path::new("/x/run/summary.json"), &template).unwrap();
        assert_eq!(r.temporary.to_str().unwrap(), "/x/run/.summary.json.tmp.oom");
        assert_eq!(r.pieces[0], b"{\"status\": \"");
        assert_eq!(r.pieces[3], b"}");
        let mut s = String::new();
        status(64 << 20, &mut s);
        assert!(
            s.starts_with("failed: out of memory: an allocation of 64.0 MiB failed"),
            "{s}"
        );
        // nothing in it needs escaping in JSON
        assert!(!s.contains(['"', '\\']));
    }

    #[test]
    fn a_fallible_section_gets_the_error_back() {
        let r = fallible(|| Vec::<u8>::new().try_reserve_exact(usize::MAX / 2));
        assert!(r.is_err());
        assert_eq!(FALLIBLE.with(|c| c.get()), 0);
    }
}
