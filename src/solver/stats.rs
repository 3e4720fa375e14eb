//! Run statistics: sizes, per-phase wall time, counters and per-step contact iterations,
//! written to `summary.json` (docs/README.md: timing per phase is collected in one place).

use crate::contact::ContactOutcome;
use serde::Serialize;
use std::time::{Duration, Instant};

/// Wall time per phase, in seconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PhaseTimes {
    pub mesh: f64,
    pub assembly: f64,
    pub factorisation: f64,
    pub condensation: f64,
    pub loads: f64,
    pub history: f64,
    /// Forward sweeps y = L⁻¹ P r.
    pub forward_sweep: f64,
    pub contact: f64,
    /// Backward sweeps u = Pᵀ L⁻ᵀ (y − G λ), with the contact forces folded in.
    pub backward_sweep: f64,
    pub stress: f64,
    pub output: f64,
    pub total: f64,
}

/// Adds the elapsed time of a closure to a phase.
pub fn timed<T>(slot: &mut f64, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let out = f();
    *slot += start.elapsed().as_secs_f64();
    out
}

/// Seconds of a duration.
pub fn secs(d: Duration) -> f64 {
    d.as_secs_f64()
}

/// Everything `summary.json` reports about a run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct RunStats {
    pub nodes: usize,
    pub cells: usize,
    pub unknowns: usize,
    pub matrix_nonzeros: usize,
    pub contact_nodes: usize,
    /// Whether some contact row has a rigid bound (a bound, or a rigid obstacle): then the
    /// nodes on it are counted.
    #[serde(skip)]
    pub contact_bound: bool,
    /// Steps after step 0 (accepted ones, with automatic steps).
    pub steps: usize,
    /// The first step's size (every step's on a uniform grid).
    pub time_step: f64,
    /// The smallest and largest step taken, and how many sizes (docs/method.md §20).
    pub smallest_step: f64,
    pub largest_step: f64,
    pub distinct_steps: usize,
    /// Automatic steps taken back for their error (docs/method.md §20.4).
    pub rejected_steps: usize,
    pub final_time: f64,
    pub effects: Vec<String>,
    pub history_algorithm: Option<String>,
    pub history_bytes: usize,
    pub factorisations: usize,
    /// Distinct step matrices factorised (docs/method.md §20.3; besides the factorisations, which
    /// also count `hvi check`'s).
    pub step_matrices: usize,
    /// Whole solves (one forward and one backward sweep over the factor).
    pub solves: usize,
    /// Sparse forward sweeps forming G = L⁻¹ P Cᵀ (one per contact node, once per factor).
    pub sparse_forward_sweeps: usize,
    pub contact_solves: usize,
    pub frames_written: usize,
    pub newton_iterations: Vec<usize>,
    pub contact: Vec<ContactOutcome>,
    pub max_contact_residual: f64,
    pub smallness: Option<f64>,
    /// The fill-reducing ordering of the factor and its number of stored entries nnz(L).
    pub ordering: Option<String>,
    pub factor_entries: usize,
    /// Which condensation of the contact normals ran (docs/method.md §9), if any.
    pub condensation: Option<String>,
    /// Reaction forces at every output step: one row per (time, group, component).
    pub reactions: Vec<Reaction>,
    /// The total contact force on the body per contact group at every output step, one row per
    /// (time, group, component) (docs/method.md §14.4).
    pub contact_forces: Vec<Reaction>,
    /// Peak resident memory of the process (VmHWM, Linux), in bytes.
    pub peak_memory_bytes: Option<u64>,
    /// The peak predicted before the factorisation (docs/method.md §16.1), in bytes.
    pub predicted_peak_bytes: Option<u64>,
    pub phases: PhaseTimes,
}

/// The reaction force of one prescribed (group, component) at one output time (docs/method.md §7),
/// or the total contact force of one contact group (§14.4).
#[derive(Clone, Debug, Serialize)]
pub struct Reaction {
    pub time: f64,
    pub group: String,
    pub component: &'static str,
    pub force: f64,
}

/// The process's peak resident set size (VmHWM from /proc/self/status), if available.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
