//! Where a contact solve reports what it does, iteration by iteration: nowhere unless a caller
//! hands it a listening sink (`HVI_TRACE_CONTACT=1`, docs/troubleshooting.md). The solve
//! never asks the environment; it writes to the sink it was given.

/// A sink for the contact solve's report.
pub trait Trace {
    /// Whether anything listens (a report that costs work is skipped where nothing does).
    fn on(&self) -> bool;
    /// One line of the report.
    fn line(&self, line: std::fmt::Arguments);
}

/// The sink that drops everything: the default.
pub struct Silent;

impl Trace for Silent {
    fn on(&self) -> bool {
        false
    }
    fn line(&self, _: std::fmt::Arguments) {}
}

/// The sink that writes every line to standard error.
pub struct ToStderr;

impl Trace for ToStderr {
    fn on(&self) -> bool {
        true
    }
    fn line(&self, line: std::fmt::Arguments) {
        eprintln!("{line}");
    }
}

/// The sink of a run's settings: standard error where `trace` is set, else [`Silent`].
pub fn sink(trace: bool) -> &'static dyn Trace {
    match trace {
        true => &ToStderr,
        false => &Silent,
    }
}
