//! Automatic steps to a tolerance (docs/method.md §20.4): after each step its local error
//! estimate over the tolerance, ρ, accepts it (ρ ≤ 1) or rejects it, and sets the next step
//! from the error's order in k: k ← k · clamp(SAFETY ρ^{−1/3}). Steps land on every stop (the
//! output times) and on T; where each size costs a factorisation they are held on the ladder
//! k_1 2^j, so that sizes repeat and their factors are reused.

use super::grid::SNAP;

/// The controller's constants (docs/method.md §20.4): the usual choices of step-size control
/// for a method whose local error is O(k³) (Hairer, Nørsett & Wanner, II.4).
pub const SAFETY: f64 = 0.9;
/// The most a step grows by (one rung of the ladder).
pub const GROWTH_AT_MOST: f64 = 2.0;
/// The most a rejected step shrinks by at once.
pub const SHRINK_AT_MOST: f64 = 0.125;
/// The power of ρ in the new size: the local error is O(k³).
pub const EXPONENT: f64 = 1.0 / 3.0;

/// Automatic steps: what a scene's `[time]` asks for, resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct Automatic {
    pub final_time: f64,
    /// The local error allowed per step, relative to the largest displacement so far.
    pub tolerance: f64,
    pub first_step: f64,
    pub min_step: f64,
    pub max_step: f64,
    /// The times landed on (output times), increasing, in (0, T).
    pub stops: Vec<f64>,
    /// Sizes held on the ladder k_1 2^j (each size's step matrix is factorised).
    pub ladder: bool,
}

/// A step the controller proposes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proposal {
    /// t_n.
    pub time: f64,
    /// k_n.
    pub size: f64,
    /// Whether t_n is one of the stops (or T).
    pub stop: bool,
}

/// The state of the step-size control.
#[derive(Clone, Debug)]
pub struct Controller {
    spec: Automatic,
    /// t_{n−1}.
    time: f64,
    /// The size wanted for the next step (before landing and the ladder).
    wanted: f64,
    next_stop: usize,
    /// The last step was rejected: the next accepted one does not grow.
    rejected_last: bool,
    pub accepted: usize,
    pub rejected: usize,
}

impl Controller {
    /// Starts at t = 0 with the first step.
    pub fn new(spec: Automatic) -> Self {
        Controller {
            wanted: spec.first_step,
            spec,
            time: 0.0,
            next_stop: 0,
            rejected_last: false,
            accepted: 0,
            rejected: 0,
        }
    }

    /// The automatic steps' settings.
    pub fn spec(&self) -> &Automatic {
        &self.spec
    }

    /// True once T is reached.
    pub fn finished(&self) -> bool {
        self.time >= self.spec.final_time
    }

    /// The largest rung k_1 2^j ≤ k (k itself off the ladder).
    fn rung(&self, k: f64) -> f64 {
        if !self.spec.ladder {
            return k;
        }
        let first = self.spec.first_step;
        first * 2f64.powi((k / first).log2().floor() as i32)
    }

    /// The next step: the size wanted (on the ladder, within the bounds), cut to land on the next
    /// stop, or stretched to it when it would leave a sliver of less than a tenth of a step.
    pub fn propose(&self) -> Proposal {
        let k = self.rung(self.wanted.clamp(self.spec.min_step, self.spec.max_step));
        let stop = self
            .spec
            .stops
            .get(self.next_stop)
            .copied()
            .unwrap_or(self.spec.final_time);
        let left = stop - self.time;
        if k * (1.0 + SNAP) >= left || left - k < 0.1 * k {
            Proposal {
                time: stop,
                size: left,
                stop: true,
            }
        } else {
            Proposal {
                time: self.time + k,
                size: k,
                stop: false,
            }
        }
    }

    /// Accepts the step `p` whose error over the tolerance was `ratio` (≤ 1): moves to its time
    /// and sets the next size.
    pub fn accept(&mut self, p: &Proposal, ratio: f64) {
        self.accepted += 1;
        self.time = p.time;
        if p.stop && self.next_stop < self.spec.stops.len() {
            self.next_stop += 1;
        }
        let mut factor = (SAFETY * ratio.max(1e-12).powf(-EXPONENT)).min(GROWTH_AT_MOST);
        if self.rejected_last {
            factor = factor.min(1.0);
        }
        self.rejected_last = false;
        // a step cut short to land says little about the size wanted: keep it
        self.wanted = if p.stop && p.size < self.wanted {
            self.wanted.max(factor * p.size)
        } else {
            factor * p.size
        };
    }

    /// Rejects the step `p` whose error over the tolerance was `ratio` (> 1) and shrinks the
    /// next try; Err(the size it would take) when that is below the smallest step.
    pub fn reject(&mut self, p: &Proposal, ratio: f64) -> Result<(), f64> {
        self.rejected += 1;
        self.rejected_last = true;
        let factor = (SAFETY * ratio.powf(-EXPONENT)).clamp(SHRINK_AT_MOST, 0.5);
        let k = factor * p.size;
        if self.rung(k) < self.spec.min_step * (1.0 - SNAP) || p.size <= self.spec.min_step * (1.0 + SNAP) {
            return Err(k);
        }
        self.wanted = k;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(ladder: bool) -> Automatic {
        Automatic {
            final_time: 10.0,
            tolerance: 1e-3,
            first_step: 1e-3,
            min_step: 1e-9,
            max_step: 10.0,
            stops: vec![1.0, 5.0],
            ladder,
        }
    }

    /// Steps whose error is a twentieth of the tolerance grow (doubling: the ideal factor
    /// 0.9·20^{1/3} = 2.4 is above the next rung) to the end, land on every stop, and stay on
    /// the ladder.
    #[test]
    fn steps_grow_and_land() {
        let mut c = Controller::new(spec(true));
        let mut times = Vec::new();
        while !c.finished() {
            let p = c.propose();
            if !p.stop {
                let j = (p.size / 1e-3).log2();
                assert!((j - j.round()).abs() < 1e-12, "{} is on the ladder", p.size);
            }
            c.accept(&p, 0.05);
            times.push(p.time);
        }
        for stop in [1.0, 5.0, 10.0] {
            assert!(times.contains(&stop), "lands on {stop}: {times:?}");
        }
        assert!(times.len() < 30, "{} steps", times.len());
    }

    /// A rejected step shrinks; below the smallest step the controller says so.
    #[test]
    fn rejections_shrink_down_to_the_smallest_step() {
        let mut c = Controller::new(spec(false));
        let p = c.propose();
        c.reject(&p, 1000.0).unwrap();
        assert!(c.propose().size <= 0.125 * p.size * 1.0000001);
        let mut result = Ok(());
        for _ in 0..40 {
            let p = c.propose();
            result = c.reject(&p, 1e6);
            if result.is_err() {
                break;
            }
        }
        assert!(result.is_err(), "stops at the smallest step");
    }
}
