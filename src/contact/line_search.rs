//! The line search of an iteration (docs/method.md §4.4): backtracking along the projected path
//! r − α d from α = 1, halving α until the energy decreases by Armijo's rule.

use super::outcome::ContactOutcome;
use super::problem::ContactProblem;
use super::settings::TUNING;

/// The projected path of an iteration: r − α d with every row kept at or below its bound, the
/// held rows moved onto it, and the stops of docs/method.md §4.4 and §17.3.
pub struct Path<'a> {
    pub problem: &'a ContactProblem<'a>,
    pub r: &'a [f64],
    /// d over all rows: the Newton direction on the free rows, G_p/c_p on the held ones.
    pub direction: &'a [f64],
    pub held: &'a [bool],
    /// Each row's kink width ε (∞: none).
    pub kink: &'a [f64],
    pub grad: &'a [f64],
    /// Whether the path stops at kinks and a pair's origin.
    pub stops: bool,
}

impl Path<'_> {
    /// The move `trial` to the point α along the path: rows held at or pushed past their bound
    /// stay at it, a single row that would cross its kink from outside its smoothing zone stops
    /// at the kink, and a pair's path x − s d stops where it passes the origin, at its nearest
    /// point s* = x·d/|d|² (docs/method.md §4.4, §17.3). `stopped` lists the rows whose move is
    /// not −α d. Returns the first-order decrease those stops add to α Gᵀd (the path's own, for
    /// Armijo).
    pub fn at(&self, alpha: f64, trial: &mut [f64], stopped: &mut Vec<usize>) -> f64 {
        let (problem, r, direction, grad) = (self.problem, self.r, self.direction, self.grad);
        let mut decrease = 0.0;
        stopped.clear();
        for p in 0..problem.m() {
            let along = r[p] - alpha * direction[p];
            let mut moved = if problem.is_fixed(p) {
                problem.g(p)
            } else {
                along.min(problem.g(p))
            };
            let o = problem.origin(p);
            let single = problem.partner(p).is_none();
            let crosses = (r[p] - o).abs() > self.kink[p] && (moved - o) * (r[p] - o) < 0.0;
            if self.stops && single && !self.held[p] && crosses {
                // stop at the kink: the first-order decrease is that of the shorter move
                decrease += grad[p] * (r[p] - o - alpha * direction[p]);
                moved = o;
            }
            if moved != along {
                stopped.push(p);
            }
            trial[p] = moved - r[p];
            if self.held[p] {
                decrease -= grad[p] * trial[p];
            }
        }
        let pairs = (0..problem.m()).filter_map(|p| problem.partner(p).filter(|&q| q > p).map(|q| (p, q)));
        for (p, q) in pairs {
            let (x, rho) = problem.pair_at(r, p, q);
            let d = [direction[p], direction[q]];
            let along = x[0] * d[0] + x[1] * d[1];
            if self.stops && rho > self.kink[p] && rho * rho < alpha * along {
                let nearest = along / (d[0] * d[0] + d[1] * d[1]);
                decrease += (nearest - alpha) * (grad[p] * d[0] + grad[q] * d[1]);
                trial[p] = -nearest * d[0];
                trial[q] = -nearest * d[1];
                stopped.extend([p, q]);
            }
        }
        stopped.sort_unstable();
        stopped.dedup();
        decrease
    }
}

/// How the search ended.
pub enum Search {
    /// The step α was taken: the move is in the work's `trial`.
    Accepted(f64),
    /// α fell below [`TUNING`]`.min_step`: at the energy's round-off.
    Floor,
}

/// The trial move Δ = `trial` and Q Δ = `q_trial` of the search, and the rows the path stopped.
pub struct Trial {
    pub trial: Vec<f64>,
    q_trial: Vec<f64>,
    stopped: Vec<usize>,
}

impl Trial {
    pub fn new(m: usize) -> Self {
        Trial {
            trial: vec![0.0; m],
            q_trial: vec![0.0; m],
            stopped: Vec::new(),
        }
    }
}

/// Backtracks along `path` from α = 1: accepts the first α whose energy change is at most
/// −Armijo × (α Gᵀd + the stops' decrease), `predicted_slope` = Gᵀd on the free rows.
pub fn search(path: &Path, predicted_slope: f64, work: &mut Trial, outcome: &mut ContactOutcome) -> Search {
    let problem = path.problem;
    let mut alpha = 1.0;
    loop {
        let decrease_bound = alpha * predicted_slope + path.at(alpha, &mut work.trial, &mut work.stopped);
        problem.operator.apply_q(&work.trial, &mut work.q_trial);
        let change = problem.energy_change(path.r, &work.trial, path.grad, &work.q_trial);
        if change <= -TUNING.armijo * decrease_bound || (change <= 0.0 && decrease_bound <= 1e-300) {
            return Search::Accepted(alpha);
        }
        alpha *= 0.5;
        outcome.line_search_cuts += 1;
        if alpha < TUNING.min_step {
            return Search::Floor;
        }
    }
}
