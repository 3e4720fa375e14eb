//! What a run leaves to be read: `summary.json` and the one-screen report of `hvi solve`.

use super::options::SolveOptions;
use crate::solver::{RunStats, SolveError};
use serde::Serialize;
use std::path::Path;

/// What `summary.json` holds: written when a run completes and also when it stops early
/// (interrupted, or an error after the output directory was prepared), then without the run's
/// statistics.
#[derive(Serialize)]
pub struct Summary<'a> {
    pub hvi_version: &'static str,
    pub mesh: String,
    pub scene: String,
    pub output: String,
    /// "completed", "interrupted", or "failed: <the error>".
    pub status: String,
    /// Steps computed (of `time.steps + 1`, step 0 included), and the last step written.
    pub steps_done: usize,
    pub last_step_written: Option<usize>,
    /// What `hvi check` warns about, printed before the run (empty: nothing).
    pub warnings: Vec<String>,
    #[serde(flatten)]
    pub stats: Option<&'a RunStats>,
}

impl<'a> Summary<'a> {
    /// The summary of a run of `opts` with `warnings` that has computed `steps_done` steps and
    /// written up to `last_step_written`; `status` "completed" until the caller says otherwise
    /// ([`Summary::stopped_by`]).
    pub fn new(
        opts: &SolveOptions,
        warnings: Vec<String>,
        steps_done: usize,
        last_step_written: Option<usize>,
        stats: Option<&'a RunStats>,
    ) -> Self {
        Summary {
            hvi_version: env!("CARGO_PKG_VERSION"),
            mesh: opts.mesh.display().to_string(),
            scene: opts
                .scene
                .as_ref()
                .map_or("<embedded default: examples/paper.toml>".into(), |p| {
                    p.display().to_string()
                }),
            output: opts.out.display().to_string(),
            status: "completed".into(),
            steps_done,
            last_step_written,
            warnings,
            stats,
        }
    }
}

impl Summary<'_> {
    /// The status of a run that `e` stopped: "interrupted", or "failed: <the error>".
    pub fn stopped_by(&mut self, e: &SolveError) {
        self.status = match e {
            SolveError::Interrupted { .. } => "interrupted".into(),
            e => format!("failed: {e}"),
        };
    }
}

/// The one-screen summary printed at the end of `hvi solve`.
pub fn report(stats: &RunStats, out: &Path) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let p = &stats.phases;
    // one size for every step (a uniform grid), or the range and how many sizes (docs/method.md §20)
    let steps = if stats.distinct_steps <= 1 {
        format!("{} steps of k = {:.4e}", stats.steps, stats.time_step)
    } else {
        format!(
            "{} steps from k = {:.3e} to {:.3e} ({} sizes{})",
            stats.steps,
            stats.smallest_step,
            stats.largest_step,
            stats.distinct_steps,
            if stats.rejected_steps > 0 {
                format!(", {} rejected", stats.rejected_steps)
            } else {
                String::new()
            }
        )
    };
    let _ = writeln!(
        s,
        "hvi: {steps} to T = {} on {} nodes / {} cells ({} unknowns, {} contact nodes)",
        stats.final_time, stats.nodes, stats.cells, stats.unknowns, stats.contact_nodes
    );
    let _ = writeln!(s, "  effects: {}", stats.effects.join(", "));
    if !stats.newton_iterations.is_empty() {
        let total: usize = stats.newton_iterations.iter().sum();
        let max = stats.newton_iterations.iter().max().copied().unwrap_or(0);
        let active = stats.contact.last().map_or(0, |o| o.active);
        // (a run whose laws have no rigid bound behind them has no node on one to count)
        let on_bound = if stats.contact_bound {
            format!(", {active} nodes on the bound or the rigid obstacle at T")
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  contact: {total} Newton iterations in all (max {max} per step){on_bound}, max residual {:.2e}",
            stats.max_contact_residual
        );
    }
    if let Some(h) = &stats.history_algorithm {
        let _ = writeln!(
            s,
            "  memory: {h}, {:.1} MiB held",
            stats.history_bytes as f64 / 1048576.0
        );
    }
    let _ = writeln!(
        s,
        "  work: {} factorisation(s), {} sparse solves, {} sparse forward sweeps; peak memory {}",
        stats.factorisations,
        stats.solves,
        stats.sparse_forward_sweeps,
        stats
            .peak_memory_bytes
            .map_or("unknown".into(), |b| format!("{:.0} MiB", b as f64 / 1048576.0))
    );
    let _ = writeln!(
        s,
        "  time [s]: mesh {:.3}, assembly {:.3}, factorisation {:.3}, condensation {:.3}, steps {:.3} (history {:.3}, solves {:.3}, contact {:.3}), output {:.3}; total {:.3}",
        p.mesh, p.assembly, p.factorisation, p.condensation,
        p.loads + p.history + p.forward_sweep + p.contact + p.backward_sweep, p.history, p.forward_sweep + p.backward_sweep, p.contact, p.output, p.total
    );
    let _ = write!(
        s,
        "  wrote {} frames to {} (solution.pvd, contact.pvd, gamma3.csv, summary.json)",
        stats.frames_written,
        out.display()
    );
    s
}
