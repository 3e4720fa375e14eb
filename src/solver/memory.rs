//! The memory a run will need, predicted from the symbolic analysis before the numeric
//! factorisation, and the memory this process may use (docs/method.md §16.1). `hvi check`
//! prints the prediction; a run refuses to start its factorisation when the prediction does not
//! fit, naming the figures and what would make it fit.
//!
//! The parts, each from what the run will allocate (bytes):
//! * the factor: 8 per stored entry of L (faer's supernodal storage), times the factors of step
//!   matrices held at once (two where steps of several sizes need their own, docs/method.md §20.3);
//! * the matrices: K_A (kept without a memory term, for the products and K_A alone), the step
//!   matrix while it is factorised, the memory terms' K_j (node blocks): 16 per stored entry of
//!   K_A each;
//! * G = L⁻¹PCᵀ: 8 per value of its supernode paths ([`forward_columns_entries`]), twice while
//!   its columns are gathered; or, where Q is read off the factor's trailing block
//!   (docs/method.md §9.4), L_cc, 8·m²; or Z = K⁻¹Cᵀ, 8·n·m, when the scene stores the responses;
//! * the dense contact matrices: W and its Cholesky inverse Q, the partial W of each thread
//!   while W = GᵀG is summed, the Newton matrix of the active-set method and its factor (kept
//!   above `solver.dense_newton_limit` free nodes): 8·m² each, `DENSE_COPIES` of them
//!   (`TRAILING_COPIES` where Q is read off the trailing block without W, §9.7);
//! * the history (the memory term's vectors), the step vectors and the output of one frame;
//! * the process itself (code, thread stacks, allocator arenas): `BASE`.
//!
//! The constants are fitted to the peaks (VmHWM) measured on the cases of docs/performance.md's cost tables;
//! docs/troubleshooting.md lists them against the prediction.

use super::setup::Simulation;
use crate::linalg::{forward_columns_entries, Analysis};
use crate::scene::CondensationKind;

/// The resident memory of the process apart from the problem's data (measured: 9 MiB for a
/// 153-node run; thread stacks and allocator arenas of the two sweep threads).
const BASE: u64 = 24 << 20;

/// How many m × m dense matrices exist at the peak of the contact solve (fitted at m = 4 096:
/// 4.2 on the dense path, 5.2 when the Newton matrix's factor is kept above
/// `solver.dense_newton_limit` free nodes).
const DENSE_COPIES: f64 = 4.0;

/// The same where Q is read off the factor's trailing block and W is not formed (no friction):
/// Q, then the Schur complement beside it while Q is formed, and the Newton matrix's storage
/// (docs/method.md §9.7; measured at m = 4 096: 927 MiB against 1 372 MiB predicted with
/// `DENSE_COPIES`).
const TRAILING_COPIES: f64 = 2.0;

/// Copies of K_A's entries (16 bytes each: value and index) held at the peak, per matrix kind:
/// K_A, the step matrix while it is factorised, the memory terms' node blocks (fitted: 2.9 in
/// 2D, 2.0 in 3D with one memory channel, while K_A was still held beside the factor in runs
/// with memory; since it is not, the prediction is above 3D memory runs' peaks by up to a
/// fifth: slab n = 40 978 MiB against 817 MiB measured, n = 24 within 1 %).
const MATRIX_COPIES: f64 = 2.5;

/// The predicted peak of a run, by part.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// (part, bytes), in the order of the module's list.
    pub parts: Vec<(&'static str, u64)>,
}

impl MemoryEstimate {
    /// The prediction for `sim` whose step matrix has `matrix_entries` stored entries (K_A's)
    /// and the symbolic analysis `analysis`.
    pub fn new<const D: usize>(sim: &Simulation<D>, analysis: &Analysis, matrix_entries: usize) -> Self {
        let n = sim.dofs.n() as u64;
        // the step matrices' factors held at once (docs/method.md §20.3)
        let factor = 8 * analysis.factor_entries() as u64 * super::operators::held_at_most(sim) as u64;
        let channels = sim.materials.memory().map_or(0, |m| m.channels().len()) as u64;
        let matrices = (16.0 * matrix_entries as f64 * (MATRIX_COPIES + channels.saturating_sub(1) as f64)) as u64;
        let mut parts = vec![("factor", factor), ("matrices", matrices)];
        if let Some(c) = &sim.contact {
            let m = c.condensed_rows().len() as u64;
            let responses = match sim.condensation {
                // L_cc, dense (docs/method.md §9.4); its products are among the dense copies
                CondensationKind::SplitSweeps if sim.trailing_block() => {
                    ("L_cc (the factor's trailing block)", 8 * m * m)
                }
                CondensationKind::SplitSweeps => (
                    "G = L⁻¹PCᵀ",
                    2 * 8 * forward_columns_entries(analysis, c.condensed_rows().rows()) as u64,
                ),
                CondensationKind::StoredResponses | CondensationKind::RecoverySolve => ("Z = K⁻¹Cᵀ", 8 * n * m),
            };
            parts.push(responses);
            let kept = (m as usize > c.settings.dense_limit) as u8 as f64;
            // off the trailing block without friction only Q and the Newton matrix's storage
            // (docs/method.md §9.7): no W, no GᵀG, no inverse
            let copies = match sim.trailing_block() && !sim.forms_w_off_trailing_block() {
                true => TRAILING_COPIES,
                false => DENSE_COPIES,
            };
            parts.push((
                "dense contact matrices",
                ((copies + kept) * 8.0 * (m * m) as f64) as u64,
            ));
        }
        let history = sim.materials.memory().map_or(0, |_| 8 * n * (2 + 3 * channels.max(1)));
        // step vectors (load, right-hand side, displacement, forward sweep) and one frame's
        // fields (nodal and cell stresses, 9 components each)
        let cells = sim.mesh.cells.len() as u64;
        let points = sim.mesh.points.len() as u64;
        let vectors = 8 * (6 * n + 2 * 9 * (cells + points));
        parts.push(("history, vectors and one frame", history + vectors));
        parts.push(("the process", BASE));
        MemoryEstimate { parts }
    }

    /// The predicted peak (bytes).
    pub fn total(&self) -> u64 {
        self.parts.iter().map(|(_, b)| b).sum()
    }

    /// One line for `hvi check` and messages: `1.2 GiB (factor 0.8, matrices 0.1, …)`.
    pub fn describe(&self) -> String {
        let parts: Vec<String> = self
            .parts
            .iter()
            .filter(|(_, b)| *b > 0)
            .map(|(name, b)| format!("{name} {}", size(*b)))
            .collect();
        format!("{} ({})", size(self.total()), parts.join(", "))
    }

    /// Err naming the figures and the remedies when the prediction exceeds what the process may
    /// use ([`memory_limit`]); Ok when it fits or no limit is known. The environment variable
    /// `HVI_IGNORE_MEMORY_ESTIMATE=1` turns the refusal off (an allocation that then fails still
    /// ends the run cleanly, src/alloc.rs).
    pub fn check_fits(&self, contact_nodes: usize) -> Result<(), String> {
        if std::env::var_os("HVI_IGNORE_MEMORY_ESTIMATE").is_some_and(|v| v == "1") {
            return Ok(());
        }
        let Some(limit) = memory_limit() else {
            return Ok(());
        };
        if self.total() <= limit.bytes {
            return Ok(());
        }
        let dense = self
            .parts
            .iter()
            .find(|(n, _)| *n == "dense contact matrices")
            .map_or(0, |p| p.1);
        let remedy = if dense > self.total() / 3 {
            format!(
                "fewer contact nodes (the dense contact matrices grow like m², m = {contact_nodes}), a coarser mesh, or \
                 --backend petsc on more ranks"
            )
        } else {
            "a coarser mesh (fewer unknowns), or --backend petsc on more ranks (docs/cluster.md)".into()
        };
        Err(format!(
            "the run needs about {} of memory at its peak, but this process may use {} ({}); use {remedy} \
             (HVI_IGNORE_MEMORY_ESTIMATE=1 tries anyway)",
            self.describe(),
            size(limit.bytes),
            limit.what
        ))
    }
}

/// A size in MiB or GiB.
pub fn size(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.2} GiB", b / (1u64 << 30) as f64)
    } else if b >= (10u64 << 20) as f64 {
        format!("{:.0} MiB", b / (1u64 << 20) as f64)
    } else {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    }
}

/// What this process may still allocate, and which limit says so.
#[derive(Clone, Debug, PartialEq)]
pub struct MemoryLimit {
    pub bytes: u64,
    pub what: String,
}

/// The smallest of: the free memory (MemAvailable) plus what the process holds already, the
/// address-space limit (`ulimit -v`, RLIMIT_AS), and the cgroup's limit (cgroup v2
/// `memory.max`, v1 `memory.limit_in_bytes`), compared with the whole predicted peak. None if
/// none can be read (not Linux).
pub fn memory_limit() -> Option<MemoryLimit> {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let field = |name: &str| -> Option<u64> {
        let line = status.lines().find(|l| l.starts_with(name))?;
        Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
    };
    let resident = field("VmRSS:").unwrap_or(0);
    let virtual_size = field("VmSize:").unwrap_or(0);
    let mut limits: Vec<MemoryLimit> = Vec::new();
    if let Some(available) = meminfo("MemAvailable:") {
        limits.push(MemoryLimit {
            bytes: available + resident,
            what: format!("{} free on this machine", size(available)),
        });
    }
    if let Some(cap) = address_space_limit() {
        // the address space holds more than the resident pages (code, stacks, reserved arenas):
        // what is reserved beyond the resident set now stays reserved
        let overhead = virtual_size.saturating_sub(resident);
        limits.push(MemoryLimit {
            bytes: cap.saturating_sub(overhead),
            what: format!("ulimit -v is {}", size(cap)),
        });
    }
    if let Some(cap) = cgroup_limit() {
        limits.push(MemoryLimit {
            bytes: cap,
            what: format!("the cgroup's memory limit is {}", size(cap)),
        });
    }
    limits.into_iter().min_by_key(|l| l.bytes)
}

fn meminfo(name: &str) -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with(name))?;
    Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

/// RLIMIT_AS (soft), if set.
fn address_space_limit() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits.lines().find(|l| l.starts_with("Max address space"))?;
    // "Max address space  <soft> <hard> bytes"
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// The memory limit of this process's cgroup, if it has one.
fn cgroup_limit() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    for line in groups.lines() {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        let file = if controllers.is_empty() {
            format!("/sys/fs/cgroup{path}/memory.max")
        } else if controllers.split(',').any(|c| c == "memory") {
            format!("/sys/fs/cgroup/memory{path}/memory.limit_in_bytes")
        } else {
            continue;
        };
        // inside a container the path may not resolve: the root of the namespace then
        let text = std::fs::read_to_string(&file)
            .or_else(|_| {
                std::fs::read_to_string(if controllers.is_empty() {
                    "/sys/fs/cgroup/memory.max"
                } else {
                    "/sys/fs/cgroup/memory/memory.limit_in_bytes"
                })
            })
            .ok()?;
        let value: u64 = text.trim().parse().ok()?;
        // v1 reports "no limit" as a huge number
        if value < 1 << 60 {
            return Some(value);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_as_people_write_them() {
        assert_eq!(size(512 << 20), "512 MiB");
        assert_eq!(size(3 << 30), "3.00 GiB");
    }

    #[test]
    fn the_limit_is_known_on_linux_and_positive() {
        if cfg!(target_os = "linux") {
            let l = memory_limit().expect("MemAvailable is readable on Linux");
            assert!(l.bytes > 0, "{l:?}");
        }
    }
}
