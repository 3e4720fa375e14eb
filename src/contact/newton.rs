//! The contact solve of one time step: the globalised primal–dual active-set method (a projected
//! semismooth Newton method) of docs/method.md §4.4 on the problem of `problem.rs`. Each iteration
//!
//! 1. forms the gradient G and the complementarity residual, and stops below the tolerance;
//! 2. takes the active set: the rows held at their bound (`active_set.rs`);
//! 3. solves the Newton system on the free rows for the direction (`direction/`), the branch
//!    model's where a friction row leaves its kink (`branch.rs`), the held rows moved onto their
//!    bound;
//! 4. backtracks along the projected path until the energy decreases (`line_search.rs`).
//!
//! After a capped number of iterations it reports failure instead of looping.

use super::active_set;
use super::branch;
use super::direction::{self, Direction, NewtonSystem};
use super::hessian::LawHessian;
use super::line_search::{self, Path, Search, Trial};
use super::outcome::{ContactFailure, ContactOutcome};
use super::problem::ContactProblem;
use super::settings::{ContactSettings, TUNING};
use super::state::{ContactState, NodeStatus, SolverCache};
use super::trace::Trace;

/// The solver: its settings and where it reports.
#[derive(Clone, Copy)]
pub struct ActiveSetSolver<'a> {
    pub settings: ContactSettings,
    pub trace: &'a dyn Trace,
}

/// What the solve tracks between iterations besides r: Q r − q, the gradient, the smallest
/// residual and whether the last step was a full one.
struct Iterate {
    qrd: Vec<f64>,
    grad: Vec<f64>,
    /// The smallest residual so far (where a solve that stalls stalled).
    best_residual: f64,
    /// Whether the last step was a full one (the branch model is taken only after one: where
    /// the line search cut the last step, taking it again cycled, docs/method.md §17.2).
    full_step: bool,
}

impl ActiveSetSolver<'_> {
    /// Solves the step for free normal displacements `d` = C K⁻¹ F̃, warm-started from `state`.
    pub fn solve(
        &self,
        problem: &ContactProblem,
        d: &[f64],
        state: &mut ContactState,
        cache: &mut SolverCache,
    ) -> Result<ContactOutcome, ContactFailure> {
        let mut q = vec![0.0; d.len()];
        problem.operator.apply_q(d, &mut q);
        self.solve_forces(problem, &q, state, cache)
    }

    /// [`Self::solve`] for the free contact forces q = Q d (E(r) = ½ rᵀQr − qᵀr + Σ w j(r) up to
    /// a constant): the form that rigid parameters eliminated from Q need, whose q is not Q d
    /// for any d (docs/method.md §7.7).
    pub fn solve_forces(
        &self,
        problem: &ContactProblem,
        q: &[f64],
        state: &mut ContactState,
        cache: &mut SolverCache,
    ) -> Result<ContactOutcome, ContactFailure> {
        let m = problem.m();
        let r = &mut state.normal_displacement;
        onto_bounds(problem, r);
        let scale = problem.force_scale(q);
        let tol = self.settings.tolerance * scale;
        let mut outcome = ContactOutcome::default();
        // A kink of j at r = 0 (∂j(0) an interval, e.g. [−Sa, Sa]): the smoothed j_ε bends within
        // ~ε of 0, which a Newton model taken farther out cannot see. The path stops a node at 0
        // instead of carrying it across (it may cross at the next iteration, from inside the
        // smoothing zone); otherwise it zig-zags across the kink without converging.
        let kink: Vec<f64> = (0..m).map(|p| problem.laws.kink_width(p)).collect();
        let mut it = Iterate {
            qrd: vec![0.0; m],
            grad: vec![0.0; m],
            best_residual: f64::INFINITY,
            full_step: true,
        };
        let mut direction = vec![0.0; m];
        let mut work = Trial::new(m);
        loop {
            // 1. gradient and residual
            let residual = it.measure(problem, r, q);
            outcome.residual = residual / scale;
            self.trace_iteration(problem, (r, &it.grad), (residual, scale, tol), &outcome);
            if residual <= tol {
                break;
            }
            if outcome.iterations == self.settings.max_iterations {
                let reason = format!("no convergence in {} iterations", self.settings.max_iterations);
                return Err(failure(outcome, it.best_residual / scale, reason));
            }
            outcome.iterations += 1;

            // 2. active set
            let held = active_set::held_rows(problem, r, &it.grad);
            let free = active_set::free_rows(&held);

            // 3. Newton direction on the free rows, G_p/c_p on the held ones
            let hessian = LawHessian::at(problem, r, &free);
            let proximal: Vec<f64> = self.proximal(problem, &free, residual / scale);
            let system = NewtonSystem {
                free: &free,
                hessian: &hessian,
                proximal: &proximal,
                gradient: &it.grad,
                forcing: self.forcing(residual / scale, tol / residual),
            };
            let step = self.newton_direction(problem, &system, (r, &kink, it.full_step), cache, &mut outcome);
            let slope = spread(problem, (&system, &held), &step, &mut direction);

            // 4. projected Armijo backtracking on the energy
            let path = Path {
                problem,
                r,
                direction: &direction,
                held: &held,
                kink: &kink,
                grad: &it.grad,
                stops: self.settings.strategies.kink_stops,
            };
            match line_search::search(&path, slope, &mut work, &mut outcome) {
                Search::Accepted(alpha) => it.take(problem, r, &work, alpha == 1.0),
                // at the round-off floor the energy cannot decrease measurably
                Search::Floor => return Err(failure(outcome, it.best_residual / scale, STALLED.into())),
            }
        }
        finish(problem, &it.qrd, state, &mut outcome);
        Ok(outcome)
    }

    /// The direction of the Newton system: the branch model's (docs/method.md §17.2) after a full
    /// step where some friction row takes it and its direction descends, else the laws' own.
    fn newton_direction(
        &self,
        problem: &ContactProblem,
        system: &NewtonSystem,
        (r, kink, full_step): (&[f64], &[f64], bool),
        cache: &mut SolverCache,
        outcome: &mut ContactOutcome,
    ) -> Direction {
        let slope = |d: &[f64]| {
            system
                .free
                .iter()
                .zip(d)
                .map(|(&p, d)| system.gradient[p] * d)
                .sum::<f64>()
        };
        let branch = full_step && self.settings.strategies.branch_model;
        let model = branch
            .then(|| branch::model(problem, r, system.free, (system.hessian, system.gradient), kink))
            .flatten();
        if let Some((hessian, gradient)) = model {
            let modelled = NewtonSystem {
                hessian: &hessian,
                gradient: &gradient,
                ..*system
            };
            let step = direction::newton_direction(problem, &modelled, &self.settings, cache, outcome);
            if slope(&step.x) > 0.0 {
                return step;
            }
            self.trace.line(format_args!(
                "  the branch model's direction does not descend: the law's own"
            ));
        }
        direction::newton_direction(problem, system, &self.settings, cache, outcome)
    }

    /// The proximal shift per free row where Q is singular (docs/method.md §7.7): min(10⁻⁶, the
    /// relative residual) · Q_pp, which bounds the first steps of a body not yet touching and
    /// vanishes as the solve converges; 0 elsewhere.
    fn proximal(&self, problem: &ContactProblem, free: &[usize], relative: f64) -> Vec<f64> {
        let shift = if problem.singular && self.settings.strategies.proximal_shift {
            relative.min(TUNING.proximal)
        } else {
            0.0
        };
        free.iter().map(|&p| shift * problem.c(p)).collect()
    }

    /// The relative accuracy of an iterative direction (inexact Newton, docs/method.md §9.2): the
    /// relative residual ρ, which keeps the convergence quadratic, at most 10⁻² and no finer than
    /// a tenth of what the last step needs to pass the tolerance (τ/ρ = `needed`).
    fn forcing(&self, relative: f64, needed: f64) -> f64 {
        match self.settings.strategies.inexact_newton {
            true => relative
                .max(0.1 * needed)
                .clamp(TUNING.forcing_floor, TUNING.forcing_cap),
            false => TUNING.forcing_floor,
        }
    }

    /// The iteration's report: its residual and cuts, and where the trace listens, the rows that
    /// hold the residual up.
    fn trace_iteration(
        &self,
        problem: &ContactProblem,
        (r, grad): (&[f64], &[f64]),
        (residual, scale, tol): (f64, f64, f64),
        outcome: &ContactOutcome,
    ) {
        if !self.trace.on() {
            return;
        }
        self.trace.line(format_args!(
            "  contact it {} residual {:.3e} cuts {}",
            outcome.iterations,
            residual / scale,
            outcome.line_search_cuts
        ));
        if residual <= tol {
            return;
        }
        for p in (0..problem.m()).filter(|&p| problem.row_residual(r, grad, p) > 0.5 * residual) {
            self.trace.line(format_args!(
                "    node {p}: r {:.6e} g-r {:.3e} G {:.3e} j'' {:.3e} c {:.3e}",
                r[p],
                problem.g(p) - r[p],
                grad[p],
                problem.laws.stiffness(p, r[p] - problem.origin(p)),
                problem.c(p)
            ));
        }
    }
}

impl Iterate {
    /// Q r − q, the gradient and the complementarity residual at r.
    fn measure(&mut self, problem: &ContactProblem, r: &[f64], q: &[f64]) -> f64 {
        problem.gradient(r, q, &mut self.qrd, &mut self.grad);
        let residual = problem.complementarity_residual(r, &self.grad);
        self.best_residual = self.best_residual.min(residual);
        residual
    }

    /// Takes the line search's step: r += Δ, kept below the bound.
    fn take(&mut self, problem: &ContactProblem, r: &mut [f64], work: &Trial, full: bool) {
        for p in 0..problem.m() {
            r[p] += work.trial[p];
            if r[p] > problem.g(p) {
                r[p] = problem.g(p);
            }
        }
        self.full_step = full;
    }
}

/// r moved onto the bound where it is past it, and onto it where the row is held (bilateral).
fn onto_bounds(problem: &ContactProblem, r: &mut [f64]) {
    for (p, rp) in r.iter_mut().enumerate() {
        *rp = if problem.is_fixed(p) {
            problem.g(p)
        } else {
            rp.min(problem.g(p))
        };
    }
}

/// The direction d over all rows: the Newton step's on the free rows, G_p/c_p on the held ones
/// (which the path moves onto their bound); returns the predicted slope Gᵀd on the free rows.
fn spread(problem: &ContactProblem, (system, held): (&NewtonSystem, &[bool]), step: &Direction, d: &mut [f64]) -> f64 {
    for (k, &p) in system.free.iter().enumerate() {
        d[p] = step.x[k];
    }
    for p in (0..problem.m()).filter(|&p| held[p]) {
        d[p] = system.gradient[p] / problem.c(p);
    }
    (system.free.iter().zip(&step.x))
        .map(|(&p, x)| system.gradient[p] * x)
        .sum()
}

/// Why a solve stalls at the line search's floor.
const STALLED: &str = "the line search could not decrease the energy (the regularised law may be too steep: \
                       increase `contact.law.regularisation` or reduce the time step)";

/// A failed solve's report: its work, the smallest relative residual it reached and why it stopped.
fn failure(outcome: ContactOutcome, smallest_residual: f64, reason: String) -> ContactFailure {
    ContactFailure {
        outcome,
        reason,
        smallest_residual,
    }
}

/// Forces and statuses at the converged r, given Q r − q there (`qrd`): λ = q − Q r, ξ = w j_ε'(r),
/// η = λ − ξ on the bound and 0 elsewhere.
fn finish(problem: &ContactProblem, qrd: &[f64], state: &mut ContactState, outcome: &mut ContactOutcome) {
    outcome.active = 0;
    for p in 0..problem.m() {
        let r = state.normal_displacement[p];
        let lambda = -qrd[p];
        let xi = problem.law_force(&state.normal_displacement, p);
        let on_bound = r >= problem.g(p);
        state.force[p] = lambda;
        state.compliance_force[p] = xi;
        state.bound_force[p] = if on_bound { lambda - xi } else { 0.0 };
        state.status[p] = if on_bound {
            outcome.active += 1;
            NodeStatus::OnBound
        } else if r > problem.origin(p) {
            NodeStatus::InLayer
        } else {
            NodeStatus::Separated
        };
    }
}
