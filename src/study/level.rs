//! The time levels of a study's run (docs/method.md §6 for the orders, §20 for the levels): N
//! uniform steps, steps growing geometrically at s per decade from the study's first step, or
//! automatic steps to a tolerance; each with the parameter its order is measured against.

use crate::scene::TimeSpec;

/// How one run of a study steps in time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeLevel {
    /// N uniform steps, k = T/N.
    Steps(usize),
    /// Steps growing from the study's `first_step` by 10^{1/s} a step, s steps per decade.
    PerDecade(f64),
    /// Automatic steps to this local error tolerance.
    Tolerance(f64),
}

/// Which way a path's levels step (all levels of a `[[k_paths]]` entry are of one kind).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LevelKind {
    Steps,
    PerDecade,
    Tolerance,
}

impl LevelKind {
    /// The study file's key of this kind.
    pub fn key(self) -> &'static str {
        match self {
            LevelKind::Steps => "steps",
            LevelKind::PerDecade => "steps_per_decade",
            LevelKind::Tolerance => "tolerance",
        }
    }

    /// The parameter the orders are measured against, in words (for a table's sentence).
    pub fn parameter_words(self) -> &'static str {
        match self {
            LevelKind::Steps => "k = T/N",
            LevelKind::PerDecade => {
                "r = 10^(1/s) − 1, the relative growth of a step at s steps per decade (steps of size r·t near \
                 time t: a second-order rule shows order 2 in r)"
            }
            LevelKind::Tolerance => "tol, the local error the automatic steps allow per step (their tolerance)",
        }
    }

    /// The parameter's symbol in the order formulas.
    pub fn symbol(self) -> &'static str {
        match self {
            LevelKind::Steps => "k",
            LevelKind::PerDecade => "r",
            LevelKind::Tolerance => "tol",
        }
    }
}

impl TimeLevel {
    /// The kind of the level.
    pub fn kind(&self) -> LevelKind {
        match self {
            TimeLevel::Steps(_) => LevelKind::Steps,
            TimeLevel::PerDecade(_) => LevelKind::PerDecade,
            TimeLevel::Tolerance(_) => LevelKind::Tolerance,
        }
    }

    /// `N=32`, `10/decade`, `tol 1e-3`.
    pub fn label(&self) -> String {
        match self {
            TimeLevel::Steps(n) => format!("N={n}"),
            TimeLevel::PerDecade(s) => format!("{s}/decade"),
            TimeLevel::Tolerance(e) => format!("tol {e:e}"),
        }
    }

    /// The parameter the order is observed and fitted against (docs/method.md §6): T/N for
    /// uniform steps; the relative step 10^{1/s} − 1 for s steps per decade (the step at time t is
    /// about r·t, so a second-order rule's error falls as r²); the tolerance itself for automatic
    /// steps.
    pub fn parameter(&self, final_time: f64) -> f64 {
        match *self {
            TimeLevel::Steps(n) => final_time / n as f64,
            TimeLevel::PerDecade(s) => 10f64.powf(1.0 / s) - 1.0,
            TimeLevel::Tolerance(e) => e,
        }
    }

    /// True for N uniform steps.
    pub fn is_uniform(&self) -> bool {
        matches!(self, TimeLevel::Steps(_))
    }

    /// N of uniform steps (None for the others).
    pub fn steps(&self) -> Option<usize> {
        match *self {
            TimeLevel::Steps(n) => Some(n),
            _ => None,
        }
    }

    /// The scene's `[time]` for this level: `old`'s final time and quadrature, the level's way of
    /// stepping (docs/method.md §20), `first_step` for steps per decade (required) and automatic
    /// steps (their first step when given).
    pub fn time_spec(&self, old: &TimeSpec, first_step: Option<f64>) -> TimeSpec {
        let base = TimeSpec {
            final_time: old.final_time,
            quadrature: old.quadrature,
            ..Default::default()
        };
        match *self {
            TimeLevel::Steps(n) => TimeSpec { steps: Some(n), ..base },
            TimeLevel::PerDecade(s) => TimeSpec {
                first_step,
                steps_per_decade: Some(s),
                ..base
            },
            TimeLevel::Tolerance(e) => TimeSpec {
                first_step,
                tolerance: Some(e),
                ..base
            },
        }
    }
}

/// The times compared by default when some level is not uniform (docs/studies.md, "Refining steps
/// that grow with time"): one a decade, 10^j for the integers j with `first` < 10^j < T, and T.
pub fn decade_times(first: f64, final_time: f64) -> Vec<f64> {
    let mut times = Vec::new();
    if first > 0.0 && first.is_finite() && final_time.is_finite() {
        let (lo, hi) = (first.log10().floor() as i32, final_time.log10().ceil() as i32);
        for j in lo..=hi {
            // the decimal 1ej, as a scene's output time would be written
            let t: f64 = format!("1e{j}").parse().expect("a decimal power of ten");
            if t > first * (1.0 + 1e-9) && t < final_time * (1.0 - 1e-9) {
                times.push(t);
            }
        }
    }
    times.push(final_time);
    times
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_labels_and_decades() {
        assert_eq!(TimeLevel::Steps(32).parameter(2.0), 2.0 / 32.0);
        assert!((TimeLevel::PerDecade(10.0).parameter(1.0) - (10f64.powf(0.1) - 1.0)).abs() < 1e-15);
        assert_eq!(TimeLevel::Tolerance(1e-3).parameter(5.0), 1e-3);
        assert_eq!(TimeLevel::PerDecade(10.0).label(), "10/decade");
        assert_eq!(TimeLevel::PerDecade(2.5).label(), "2.5/decade");
        assert_eq!(TimeLevel::Tolerance(1e-3).label(), "tol 1e-3");
        assert_eq!(TimeLevel::Steps(64).label(), "N=64");
        assert_eq!(decade_times(1e-4, 100.0), [1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0]);
        // 10^j equal to the first step or to T is not repeated
        assert_eq!(decade_times(1e-3, 10.0), [1e-2, 1e-1, 1.0, 10.0]);
        assert_eq!(decade_times(0.3, 0.9), [0.9]);
        let spec = TimeSpec {
            final_time: 3.0,
            steps: Some(7),
            ..Default::default()
        };
        let t = TimeLevel::PerDecade(5.0).time_spec(&spec, Some(1e-3));
        assert_eq!(
            (t.final_time, t.steps, t.first_step, t.steps_per_decade),
            (3.0, None, Some(1e-3), Some(5.0))
        );
        let t = TimeLevel::Tolerance(1e-4).time_spec(&spec, None);
        assert_eq!((t.tolerance, t.first_step, t.steps), (Some(1e-4), None, None));
    }
}
