//! The step matrices of a run and their operators (docs/method.md §20.3). The step matrix of a
//! step of size k is K(k) = K_A + Σ_j β_j(k) K_j; the operator of each distinct K is built once
//! and kept while it will be used again:
//!
//! * **one channel proportional to A** (a relaxation modulus whose bulk and shear relax alike,
//!   `tensor = "elasticity"`): K_j = c K_A, so K(k) = (1 + c β(k)) K_A for every k — one
//!   factorisation and one condensation for the run, rescaled by O(m²) work when k changes;
//! * otherwise one operator per distinct β (by its bits), at most [`CAPACITY`] held at once; on a
//!   fixed grid the one not needed for the longest is dropped, with automatic steps the one used
//!   least recently.

use super::backend::Backend;
use super::error::SolveError;
use super::operator::StepOperator;
use super::setup::Simulation;
use super::stats::RunStats;
use crate::linalg::Counters;

/// The most step operators held at once (each a factor and its condensation; the memory
/// prediction counts them, docs/method.md §16.1). Two keep a landing step's size and the size
/// around it (a fixed grid cut to land on an output time; an automatic step cut and grown back).
pub(crate) const CAPACITY: usize = 2;

/// How many step operators `sim`'s run holds at once at most after step 0: one when every step
/// matrix is a multiple of K_A (or there is no memory), else up to [`CAPACITY`] (a fixed grid's
/// distinct step matrices, when fewer).
pub(super) fn held_at_most<const D: usize>(sim: &Simulation<D>) -> usize {
    let Some(memory) = sim.materials.memory() else {
        return 1;
    };
    if sim.proportional_memory().is_some() {
        return 1;
    }
    match sim.time.grid() {
        Some(grid) => {
            // (K_A of a loaded step 0 is dropped before step 1: not counted, as before variable steps)
            let runs: Vec<(usize, Vec<f64>)> = grid
                .size_runs()
                .into_iter()
                .map(|(n, k)| (n, memory.step_coefficients(k, sim.rules)))
                .collect();
            Operators::count(false, &runs).0.min(CAPACITY)
        }
        None => CAPACITY,
    }
}

/// β's bits: the key of a step matrix (two steps of one size have the same bits); all zero is
/// K_A alone, the empty key.
fn key(beta: &[f64]) -> Vec<u64> {
    if beta.iter().all(|&b| b == 0.0) {
        return Vec::new();
    }
    beta.iter().map(|b| b.to_bits()).collect()
}

/// Runs of steps with one step matrix: (the first step of the run, its key), in order.
type Runs = Vec<(usize, Vec<u64>)>;

/// The first step after `step` that uses the key `k` (usize::MAX: none).
fn next_use(runs: &Runs, step: usize, k: &[u64]) -> usize {
    for (r, (start, key)) in runs.iter().enumerate() {
        let end = runs.get(r + 1).map_or(usize::MAX, |(s, _)| *s);
        if end > step + 1 && key == k {
            return (*start).max(step + 1);
        }
    }
    usize::MAX
}

struct Held {
    key: Vec<u64>,
    operator: StepOperator,
    /// The step that last used it (for least-recently-used eviction).
    used: usize,
}

/// The operators of a run's step matrices.
pub(super) struct Operators {
    /// K_j = c K_A for the one channel: K = (1 + c β) K_A.
    proportional: Option<f64>,
    held: Vec<Held>,
    /// For a fixed grid, the runs of its step matrices (for dropping the one used last).
    future: Option<Runs>,
    /// How many step matrices were factorised.
    pub built: usize,
}

impl Operators {
    /// The operators of `sim`'s run: `future` the runs of a fixed grid's β, (first step, β)
    /// (None for automatic steps).
    pub(super) fn new<const D: usize>(sim: &Simulation<D>, future: Option<Vec<(usize, Vec<f64>)>>) -> Self {
        Operators {
            proportional: sim.proportional_memory(),
            held: Vec::new(),
            future: future.map(|f| f.iter().map(|(n, b)| (*n, key(b))).collect()),
            built: 0,
        }
    }

    /// K = s K_A with this s for the coefficients β (one channel ∝ A), None otherwise.
    pub(super) fn scale(&self, beta: &[f64]) -> Option<f64> {
        self.proportional.map(|c| 1.0 + c * beta.iter().sum::<f64>())
    }

    /// The operator of the step matrix with coefficients `beta` at step `step` (built, or
    /// rescaled, when needed).
    pub(super) fn get<const D: usize>(
        &mut self,
        beta: &[f64],
        step: usize,
        backend: &mut dyn Backend<D>,
        sim: &Simulation<D>,
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<&mut StepOperator, SolveError> {
        // the one matrix of a proportional memory is K_A (no coefficients)
        let (wanted, scale) = match self.scale(beta) {
            Some(s) => (Vec::new(), Some(s)),
            None if beta.iter().all(|&b| b == 0.0) => (Vec::new(), None),
            None => (beta.to_vec(), None),
        };
        let k = key(&wanted);
        // on a fixed grid, an operator no step will use again is dropped at once (K_A of a
        // loaded step 0 after it, a landing step's after it)
        if let Some(runs) = &self.future {
            self.held
                .retain(|h| h.key == k || next_use(runs, step.saturating_sub(1), &h.key) != usize::MAX);
        }
        let at = match self.held.iter().position(|h| h.key == k) {
            Some(at) => at,
            None => {
                if self.held.len() >= CAPACITY {
                    let drop = self.to_drop(step);
                    self.held.swap_remove(drop);
                }
                let operator = backend.operator(sim, &wanted, counters, stats)?;
                self.built += 1;
                self.held.push(Held {
                    key: k,
                    operator,
                    used: step,
                });
                self.held.len() - 1
            }
        };
        let held = &mut self.held[at];
        held.used = step;
        if let Some(s) = scale {
            held.operator.rescale_to(s);
        }
        Ok(&mut held.operator)
    }

    /// The held operator to drop for a new one at `step`: on a fixed grid the one whose next use
    /// is farthest (or never), else the least recently used.
    fn to_drop(&self, step: usize) -> usize {
        match &self.future {
            Some(runs) => (0..self.held.len())
                .max_by_key(|&i| next_use(runs, step, &self.held[i].key))
                .expect("held operators"),
            None => (0..self.held.len())
                .min_by_key(|&i| self.held[i].used)
                .expect("held operators"),
        }
    }

    /// How many distinct step matrices a fixed grid's runs of coefficients (first step, β) need,
    /// and how many factorisations the holding rule makes of them (for the plan).
    pub(super) fn count(proportional: bool, runs: &[(usize, Vec<f64>)]) -> (usize, usize) {
        if proportional {
            return (1, 1);
        }
        let runs: Runs = runs.iter().map(|(n, b)| (*n, key(b))).collect();
        let mut distinct: Vec<&Vec<u64>> = Vec::new();
        let (mut held, mut built): (Vec<&Vec<u64>>, usize) = (Vec::new(), 0);
        for (start, k) in &runs {
            if !distinct.contains(&k) {
                distinct.push(k);
            }
            if held.contains(&k) {
                continue;
            }
            if held.len() >= CAPACITY {
                let far = (0..held.len())
                    .max_by_key(|&i| next_use(&runs, *start, held[i]))
                    .expect("held");
                held.swap_remove(far);
            }
            held.push(k);
            built += 1;
        }
        (distinct.len(), built)
    }
}
