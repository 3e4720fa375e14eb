//! The application layer behind the `hvi` commands: reading inputs, running, and the sinks
//! that turn steps into files (VTK series, Γ₃ CSV, summary) or keep them in memory (tests).
//!
//! * [`sink`]: [`FileSink`] and [`MemorySink`], the frame sinks of a run;
//! * [`solve`]: `hvi solve`; [`check`]: `hvi check`;
//! * [`summary`]: `summary.json` and the closing report; [`options`]: [`SolveOptions`].

pub mod check;

pub mod options;

pub mod sink;

pub mod solve;

pub mod summary;

pub mod warnings;

pub use check::check;

pub use options::SolveOptions;

pub use sink::{memory_fields, FileSink, MemorySink, StoredStep};

pub use solve::{read_mesh, solve, solve_in_memory};

pub use summary::{report, Summary};
