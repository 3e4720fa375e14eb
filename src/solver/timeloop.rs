//! The time loop (docs/method.md §3–4, §20): a run prepared once, then its steps — every level of
//! a fixed grid in order here, automatic steps in src/solver/automatic.rs — each solved by the
//! [`Stepper`] (src/solver/stepper.rs) and handed to a sink.

use super::backend::Backend;
use super::error::SolveError;
use super::faer::FaerBackend;
use super::setup::Simulation;
use super::stats::RunStats;
use super::stepper::Written;
pub use super::stepper::{zero_solves_step_zero, FrameSink, Step, StepView, Stepper};
use crate::time::Schedule;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Runs the whole time series on the faer backend, handing every step to `sink`. `stop` is
/// polled once per step.
pub fn run<const D: usize>(
    sim: &Simulation<D>,
    sink: &mut dyn FrameSink<D>,
    stop: Option<&AtomicBool>,
) -> Result<RunStats, SolveError> {
    run_with(sim, sink, stop, Box::new(FaerBackend::default()))
}

/// [`run`] with the step matrices solved by `backend` (docs/method.md §3–4): prepare once, then
/// per step advance (history, free solve, contact, recovery) and hand the step to the sink; on
/// a fixed grid every level in order, with automatic steps as src/solver/automatic.rs decides.
pub fn run_with<'s, const D: usize>(
    sim: &'s Simulation<D>,
    sink: &mut dyn FrameSink<D>,
    stop: Option<&AtomicBool>,
    backend: Box<dyn Backend<D> + 's>,
) -> Result<RunStats, SolveError> {
    let started = Instant::now();
    sim.check_data()?;
    let mut stepper = Stepper::prepare_with(sim, backend)?;
    let mut written = Written {
        frames: 0,
        last: None,
        seconds: 0.0,
    };
    match &sim.time {
        Schedule::Fixed(grid) => {
            for n in 0..=grid.steps() {
                if written.stopped(&*stepper.backend, stop) {
                    return Err(SolveError::Interrupted {
                        last_written: written.last,
                    });
                }
                let step = Step {
                    index: n,
                    time: grid.time(n),
                    size: grid.step_size(n),
                    output: sim.is_output_step(n),
                };
                let view = stepper.advance(step)?;
                written.step(sim, sink, &view)?;
            }
        }
        Schedule::Automatic(spec) => super::automatic::run(&mut stepper, spec, sink, stop, &mut written)?,
    }
    let mut stats = stepper.finish();
    stats.phases.output += written.seconds;
    stats.frames_written = written.frames;
    stats.phases.total = started.elapsed().as_secs_f64();
    Ok(stats)
}
