//! The times of a run (docs/method.md §20): the stepping a scene asks for (`[time]`), and the
//! schedule a run follows, a fixed grid of levels or automatic steps to a tolerance.

pub mod automatic;
pub mod grid;

pub use automatic::{Automatic, Controller, Proposal};
pub use grid::{Growth, TimeGrid};

/// How a scene asks its steps to be taken (`[time]`, docs/scenes.md).
#[derive(Clone, Debug, PartialEq)]
pub enum Stepping {
    /// `steps = N`: N uniform steps.
    Uniform { steps: usize },
    /// `first_step` with `steps_per_decade` or `growth`: steps growing geometrically.
    Geometric { first: f64, growth: f64 },
    /// `times = [...]`: the levels listed.
    Listed { times: Vec<f64> },
    /// `tolerance`: automatic steps to a local error tolerance.
    Automatic {
        tolerance: f64,
        first: Option<f64>,
        min: Option<f64>,
        max: Option<f64>,
    },
}

impl Stepping {
    /// Times at which a scene's data are checked before anything depends on the materials
    /// (docs/method.md §16.3): the levels [`Schedule::sample`] would check, with a geometric grid
    /// grown smoothly and automatic steps spread in log t from the first step (or T·10⁻⁶).
    pub fn sample_times(&self, final_time: f64) -> Vec<f64> {
        let schedule = match self {
            Stepping::Uniform { steps } => Schedule::Fixed(TimeGrid::uniform(final_time, *steps)),
            Stepping::Listed { times } => match TimeGrid::listed(final_time, times) {
                Ok(g) => Schedule::Fixed(g),
                Err(_) => return vec![0.0, final_time],
            },
            Stepping::Geometric { first, growth } => {
                match TimeGrid::geometric(final_time, *first, *growth, Growth::Smooth, &[], 100_000_000) {
                    Ok(g) => Schedule::Fixed(g),
                    Err(_) => return vec![0.0, final_time],
                }
            }
            Stepping::Automatic {
                first,
                min,
                max,
                tolerance,
            } => Schedule::Automatic(Automatic {
                final_time,
                tolerance: *tolerance,
                first_step: first.unwrap_or(1e-6 * final_time),
                min_step: min.unwrap_or(0.0),
                max_step: max.unwrap_or(final_time),
                stops: Vec::new(),
                ladder: false,
            }),
        };
        schedule.sample().into_iter().map(|(_, t)| t).collect()
    }
}

/// The schedule a run follows.
#[derive(Clone, Debug)]
pub enum Schedule {
    Fixed(TimeGrid),
    Automatic(Automatic),
}

impl Schedule {
    /// T.
    pub fn final_time(&self) -> f64 {
        match self {
            Schedule::Fixed(g) => g.final_time(),
            Schedule::Automatic(a) => a.final_time,
        }
    }

    /// The fixed grid (None for automatic steps).
    pub fn grid(&self) -> Option<&TimeGrid> {
        match self {
            Schedule::Fixed(g) => Some(g),
            Schedule::Automatic(_) => None,
        }
    }

    /// The first step's size (a fixed grid's k_1, or the automatic steps' first).
    pub fn first_step(&self) -> f64 {
        match self {
            Schedule::Fixed(g) => g.step_size(1),
            Schedule::Automatic(a) => a.first_step,
        }
    }

    /// The largest step a run may take (a fixed grid's largest, the automatic steps' bound).
    pub fn largest_step(&self) -> f64 {
        match self {
            Schedule::Fixed(g) => g.step_range().1,
            Schedule::Automatic(a) => a.max_step.min(a.final_time),
        }
    }

    /// N for a fixed grid.
    pub fn steps(&self) -> Option<usize> {
        self.grid().map(TimeGrid::steps)
    }

    /// One line for `hvi check` and the run's header: the levels, or the automatic steps' settings.
    pub fn describe(&self) -> String {
        match self {
            Schedule::Fixed(g) if g.is_uniform() => format!(
                "T = {}, {} steps of k = {:.4e}",
                g.final_time(),
                g.steps(),
                g.step_size(1)
            ),
            Schedule::Fixed(g) => {
                let (lo, hi) = g.step_range();
                format!(
                    "T = {}, {} steps from k = {lo:.3e} to {hi:.3e} ({} distinct sizes)",
                    g.final_time(),
                    g.steps(),
                    g.distinct_steps().len()
                )
            }
            Schedule::Automatic(a) => format!(
                "T = {}, automatic steps to a local error of {:e} (first {:.3e}, from {:.3e} to {:.3e}{})",
                a.final_time,
                a.tolerance,
                a.first_step,
                a.min_step,
                a.max_step,
                if a.ladder { ", sizes k₁·2^j" } else { "" }
            ),
        }
    }

    /// The times at which the data are checked before a run (docs/method.md §16.3), with the
    /// step of each on a fixed grid: up to 16 levels of a fixed grid; for automatic steps t = 0,
    /// T, the output times and times spread evenly in log t between the first step and T.
    pub fn sample(&self) -> Vec<(Option<usize>, f64)> {
        match self {
            Schedule::Fixed(g) => g.sample().into_iter().map(|n| (Some(n), g.time(n))).collect(),
            Schedule::Automatic(a) => {
                let (lo, hi) = (a.first_step.ln(), a.final_time.ln());
                let mut times: Vec<f64> = (0..12).map(|i| (lo + (hi - lo) * i as f64 / 11.0).exp()).collect();
                times.push(0.0);
                times.push(a.final_time);
                times.extend(a.stops.iter().copied());
                times.sort_by(f64::total_cmp);
                times.dedup();
                times.into_iter().map(|t| (None, t)).collect()
            }
        }
    }
}
