//! A fixed grid of time levels 0 = t_0 < t_1 < … < t_N = T and the step sizes k_n = t_n − t_{n−1}
//! (docs/method.md §20.1): uniform, growing geometrically, or listed; the output times are levels
//! of every grid.
//!
//! The step sizes are kept beside the times, not recomputed as differences: the memory's weights
//! and the step matrix depend on k_n, and two steps of one size must have the same bits so that
//! their step matrix is factorised once (docs/method.md §20.3). A uniform grid's steps are all
//! T/N exactly, and its times n·(T/N) with t_N = T, as they always were.

/// Relative distance (to the step it falls in) within which an output time is taken to be a time
/// level already on the grid rather than splitting a step: round-off of decimal times.
pub const SNAP: f64 = 1e-9;

/// How the steps of a geometric grid grow (docs/method.md §20.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Growth {
    /// k_n = k_1 g^{n−1} exactly: each step a size of its own.
    Smooth,
    /// k_n = k_1 2^⌊(n−1) log₂ g⌋: sizes on the ladder k_1 2^j, each held for about 1/log₂ g steps,
    /// so that a run meets about 3.3 distinct sizes a decade (a step matrix that needs a
    /// factorisation per size).
    Ladder,
}

/// A fixed grid of time levels.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeGrid {
    levels: Levels,
    /// The levels asked for as output times (besides `output.every`), increasing.
    marked: Vec<usize>,
}

/// The levels themselves: a uniform grid in O(1) memory (it may have 10⁸ steps), any other as
/// its lists.
#[derive(Clone, Debug, PartialEq)]
enum Levels {
    Uniform {
        final_time: f64,
        steps: usize,
    },
    Listed {
        /// t_0 = 0, …, t_N = T.
        times: Vec<f64>,
        /// k_0 = 0, k_n = t_n − t_{n−1} (n ≥ 1).
        steps: Vec<f64>,
    },
}

/// A grid that cannot be built: what is wrong, for the scene's message.
#[derive(Clone, Debug, PartialEq)]
pub struct GridError(pub String);

impl TimeGrid {
    /// N uniform steps of k = T/N: t_n = n k, t_N = T exactly.
    pub fn uniform(final_time: f64, steps: usize) -> Self {
        TimeGrid {
            levels: Levels::Uniform { final_time, steps },
            marked: Vec::new(),
        }
    }

    fn from_lists(times: Vec<f64>, steps: Vec<f64>) -> Self {
        TimeGrid {
            levels: Levels::Listed { times, steps },
            marked: Vec::new(),
        }
    }

    /// Steps growing from `first` by `growth` per step up to T, landing on every time of `stops`
    /// (a step that would pass one is cut to end there, and the growth goes on from the size it
    /// had). `at_most` bounds the number of steps.
    pub fn geometric(
        final_time: f64,
        first: f64,
        growth: f64,
        kind: Growth,
        stops: &[f64],
        at_most: usize,
    ) -> Result<Self, GridError> {
        let mut times = vec![0.0];
        let mut steps = vec![0.0];
        let mut stops: Vec<f64> = stops.iter().copied().filter(|&s| s > 0.0 && s < final_time).collect();
        stops.push(final_time);
        stops.sort_by(f64::total_cmp);
        stops.dedup();
        let mut next_stop = 0;
        let (mut t, mut n) = (0.0f64, 0usize);
        let log2_growth = growth.log2();
        while t < final_time {
            let k = match kind {
                Growth::Smooth => first * growth.powi(n as i32),
                Growth::Ladder => first * 2f64.powi((n as f64 * log2_growth + 1e-9).floor() as i32),
            };
            let stop = stops[next_stop];
            // land on the stop when this step reaches it, or falls short of it by a sliver
            let (end, size) = if t + k * (1.0 + SNAP) >= stop || stop - (t + k) < 1e-3 * k {
                next_stop += 1;
                (stop, stop - t)
            } else {
                (t + k, k)
            };
            times.push(end);
            steps.push(size);
            t = end;
            n += 1;
            if n > at_most {
                return Err(GridError(format!(
                    "the steps from {first:e}, growing by {growth} a step, need more than {at_most} steps to reach \
                     T = {final_time:e}"
                )));
            }
        }
        let mut grid = Self::from_lists(times, steps);
        // the stops are levels: they were asked for as output times
        grid.marked = (1..grid.steps())
            .filter(|&n| stops[..stops.len() - 1].contains(&grid.time(n)))
            .collect();
        Ok(grid)
    }

    /// The levels `times` (increasing, positive; T appended when it is not the last).
    pub fn listed(final_time: f64, listed: &[f64]) -> Result<Self, GridError> {
        let mut times = vec![0.0];
        for (i, &t) in listed.iter().enumerate() {
            if t == 0.0 && i == 0 {
                continue;
            }
            let last = *times.last().expect("t_0");
            if t <= last || t.is_nan() {
                return Err(GridError(format!(
                    "times[{i}] = {t:e} does not follow {last:e}: the times must increase from 0"
                )));
            }
            if t > final_time * (1.0 + SNAP) {
                return Err(GridError(format!(
                    "times[{i}] = {t:e} is after time.final_time = {final_time:e}"
                )));
            }
            times.push(t.min(final_time));
        }
        let last = *times.last().expect("t_0");
        if last < final_time {
            if final_time - last <= SNAP * (last - times[times.len().saturating_sub(2)]) {
                *times.last_mut().expect("t_0") = final_time;
            } else {
                times.push(final_time);
            }
        }
        let steps = std::iter::once(0.0)
            .chain(times.windows(2).map(|w| w[1] - w[0]))
            .collect();
        Ok(Self::from_lists(times, steps))
    }

    /// Marks every time of `outputs` as an output level: a time on the grid (within [`SNAP`] of
    /// its step) is marked, any other splits the step it falls in (a uniform grid then keeps its
    /// levels as lists). Times outside [0, T] are errors (index and value).
    pub fn with_outputs(mut self, outputs: &[f64]) -> Result<Self, GridError> {
        let t_end = self.final_time();
        for (i, &t) in outputs.iter().enumerate() {
            if !(t >= 0.0 && t <= t_end * (1.0 + SNAP)) {
                return Err(GridError(format!(
                    "output.times[{i}] = {t:e} is outside the run's times [0, {t_end:e}]"
                )));
            }
            let n = self.level_at_or_after(t);
            let near = |g: &TimeGrid, m: usize| m <= g.steps() && (g.time(m) - t).abs() <= SNAP * g.step_size(m.max(1));
            let at = if near(&self, n) {
                n
            } else if n > 0 && near(&self, n - 1) {
                n - 1
            } else {
                self.split(n, t);
                n
            };
            if let Err(p) = self.marked.binary_search(&at) {
                self.marked.insert(p, at);
            }
        }
        Ok(self)
    }

    /// The first level at or after t.
    fn level_at_or_after(&self, t: f64) -> usize {
        match &self.levels {
            Levels::Uniform { final_time, steps } => {
                let k = final_time / *steps as f64;
                let guess = ((t / k).floor().max(0.0) as usize).min(*steps);
                (guess.saturating_sub(1)..=*steps)
                    .find(|&n| self.time(n) >= t)
                    .unwrap_or(*steps)
            }
            Levels::Listed { times, .. } => times.partition_point(|&s| s < t),
        }
    }

    /// Splits step n (t_{n−1} < t < t_n) at t; the marks after it move up by one.
    fn split(&mut self, n: usize, t: f64) {
        if let Levels::Uniform { .. } = self.levels {
            let times: Vec<f64> = (0..=self.steps()).map(|m| self.time(m)).collect();
            let steps: Vec<f64> = (0..=self.steps()).map(|m| self.step_size(m)).collect();
            self.levels = Levels::Listed { times, steps };
        }
        if let Levels::Listed { times, steps } = &mut self.levels {
            times.insert(n, t);
            let right = times[n + 1] - t;
            steps[n] = t - times[n - 1];
            steps.insert(n + 1, right);
        }
        for m in self.marked.iter_mut().filter(|m| **m >= n) {
            *m += 1;
        }
    }

    /// N, the number of steps (step 0 is the level t = 0, so a run solves N + 1 levels).
    pub fn steps(&self) -> usize {
        match &self.levels {
            Levels::Uniform { steps, .. } => *steps,
            Levels::Listed { times, .. } => times.len() - 1,
        }
    }

    /// T.
    pub fn final_time(&self) -> f64 {
        match &self.levels {
            Levels::Uniform { final_time, .. } => *final_time,
            Levels::Listed { times, .. } => *times.last().expect("t_0"),
        }
    }

    /// t_n (exactly T at n = N).
    pub fn time(&self, n: usize) -> f64 {
        match &self.levels {
            Levels::Uniform { final_time, steps } if n == *steps => *final_time,
            Levels::Uniform { final_time, steps } => n as f64 * (final_time / *steps as f64),
            Levels::Listed { times, .. } => times[n],
        }
    }

    /// k_n = t_n − t_{n−1}, and k_0 = 0.
    pub fn step_size(&self, n: usize) -> f64 {
        match &self.levels {
            Levels::Uniform { .. } if n == 0 => 0.0,
            Levels::Uniform { final_time, steps } => final_time / *steps as f64,
            Levels::Listed { steps, .. } => steps[n],
        }
    }

    /// Whether level n was asked for by `output.times`.
    pub fn is_marked(&self, n: usize) -> bool {
        self.marked.binary_search(&n).is_ok()
    }

    /// Whether any level was asked for by `output.times`.
    pub fn has_marks(&self) -> bool {
        !self.marked.is_empty()
    }

    /// True for the uniform grid of `steps = N`.
    pub fn is_uniform(&self) -> bool {
        matches!(self.levels, Levels::Uniform { .. })
    }

    /// The steps as runs of one size: (the first step of the run, its size), in order.
    pub fn size_runs(&self) -> Vec<(usize, f64)> {
        match &self.levels {
            Levels::Uniform { .. } => vec![(1, self.step_size(1))],
            Levels::Listed { steps, .. } => {
                let mut runs: Vec<(usize, f64)> = Vec::new();
                for (n, &k) in steps.iter().enumerate().skip(1) {
                    if runs.last().is_none_or(|&(_, last)| last.to_bits() != k.to_bits()) {
                        runs.push((n, k));
                    }
                }
                runs
            }
        }
    }

    /// The distinct step sizes k_n, n ≥ 1 (by their bits), in the order they first appear.
    pub fn distinct_steps(&self) -> Vec<f64> {
        let mut seen: Vec<f64> = Vec::new();
        for (_, k) in self.size_runs() {
            if !seen.iter().any(|s| s.to_bits() == k.to_bits()) {
                seen.push(k);
            }
        }
        seen
    }

    /// The smallest and the largest step.
    pub fn step_range(&self) -> (f64, f64) {
        self.size_runs()
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), &(_, k)| (lo.min(k), hi.max(k)))
    }

    /// The levels at which data are checked before a run: every level up to 16 steps, else t_0,
    /// t_1, t_N and evenly spaced levels between (16 in all at most).
    pub fn sample(&self) -> Vec<usize> {
        let steps = self.steps();
        let mut at: Vec<usize> = if steps <= 16 {
            (0..=steps).collect()
        } else {
            (0..14).map(|i| 1 + i * (steps - 1) / 13).chain([0]).collect()
        };
        at.sort_unstable();
        at.dedup();
        at
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_uniform_grid_is_the_old_one_bit_for_bit() {
        let g = TimeGrid::uniform(1.0, 3);
        assert_eq!(g.steps(), 3);
        for n in 1..3 {
            assert_eq!(g.time(n).to_bits(), (n as f64 * (1.0 / 3.0)).to_bits());
            assert_eq!(g.step_size(n).to_bits(), (1.0f64 / 3.0).to_bits());
        }
        assert_eq!(g.time(3), 1.0);
        assert_eq!(g.distinct_steps().len(), 1);
        assert!(g.is_uniform());
    }

    #[test]
    fn geometric_steps_grow_and_land_on_every_stop() {
        let g = TimeGrid::geometric(1e4, 1e-3, 10f64.powf(0.1), Growth::Smooth, &[1.0, 100.0], 10_000).unwrap();
        assert_eq!(g.final_time(), 1e4);
        for stop in [1.0, 100.0] {
            assert!((0..=g.steps()).any(|n| g.time(n) == stop), "{stop} is a level");
        }
        // 7 decades at 10 a decade, and a few cut steps
        assert!((65..=80).contains(&g.steps()), "{} steps", g.steps());
        for n in 1..=g.steps() {
            assert!(g.step_size(n) > 0.0);
            assert!((g.time(n) - g.time(n - 1) - g.step_size(n)).abs() <= 1e-12 * g.time(n));
        }
    }

    #[test]
    fn ladder_steps_take_few_sizes() {
        let g = TimeGrid::geometric(1e6, 1e-6, 10f64.powf(0.1), Growth::Ladder, &[], 10_000).unwrap();
        let distinct = g.distinct_steps().len();
        // 12 decades: about 3.3 sizes a decade on the ladder, and the last cut step
        assert!(distinct <= 42, "{distinct} sizes");
        for k in g.distinct_steps() {
            let j = (k / 1e-6).log2();
            assert!(
                (j - j.round()).abs() < 1e-9 || k == g.step_size(g.steps()),
                "{k} is on the ladder"
            );
        }
    }

    #[test]
    fn output_times_split_or_mark_levels() {
        let g = TimeGrid::uniform(1.0, 4).with_outputs(&[0.5, 0.6]).unwrap();
        assert_eq!(g.steps(), 5);
        assert!(g.is_marked(2) && g.is_marked(3) && !g.is_marked(4));
        assert!(!g.is_uniform());
        assert!((g.step_size(3) - 0.1).abs() < 1e-15 && (g.step_size(4) - 0.15).abs() < 1e-15);
        assert!(TimeGrid::uniform(1.0, 4).with_outputs(&[2.0]).is_err());
    }

    #[test]
    fn listed_times_must_increase() {
        let g = TimeGrid::listed(10.0, &[1.0, 2.0, 5.0]).unwrap();
        assert_eq!(g.steps(), 4);
        assert_eq!(g.final_time(), 10.0);
        assert!(TimeGrid::listed(10.0, &[1.0, 1.0]).is_err());
        assert!(TimeGrid::listed(10.0, &[1.0, 20.0]).is_err());
    }
}
