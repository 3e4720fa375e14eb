//! A factorisation of the Newton matrix kept between directions (of this step and the next ones)
//! above `dense_limit` free rows, and used as the preconditioner of conjugate gradients on the
//! later Newton systems (docs/method.md §9.2). Only a preconditioner: a stale one costs
//! iterations, never accuracy.
//!
//! The kept factor of A₀ = Q_ℱℱ + diag(e), ℱ the rows it was formed on (the free rows then, less
//! those a law held stiffly), is brought to the present free set and curvatures:
//! * **updated** on the rows of ℱ whose curvature moved by more than [`TUNING`]`.moved` of their
//!   stiffness, and **pinned** on the rows of ℱ that left the free set (`update.rs`);
//! * Jacobi's 1/(Q_pp + e_p) on the free rows outside ℱ that a law holds stiffly.
//!
//! P is then the Newton matrix up to the other rows' small changes and the stiff rows' coupling,
//! so CG needs a few iterations; each costs a product by Q, two triangular solves and a product by
//! the update's columns, where a factorisation costs O(|ℐ|³). Where a free row outside ℱ is not
//! stiff, past the update's size limits, or where CG meets non-positive curvature or does not
//! converge within its iterations, the solver refactors.

use super::super::outcome::ContactOutcome;
use super::super::problem::{ContactProblem, Fingerprint};
use super::super::settings::{ContactSettings, Strategies, TUNING};
use super::dense::{factor_rows, FactoredRows};
use super::system::{Direction, DirectionSolver, NewtonSystem};
use super::update::{DeltaRow, KeptColumns, LowRankUpdate};

/// The kept factorisation and what it has computed that depends on it alone.
#[derive(Debug)]
pub struct KeptFactor {
    /// The operator it was formed with.
    fingerprint: Fingerprint,
    factored: FactoredRows,
    /// The factor's row of each contact row (None: not in ℱ).
    row: Vec<Option<usize>>,
    /// The columns A₀⁻¹ e_k the updates have needed so far.
    columns: KeptColumns,
}

impl KeptFactor {
    /// The factor of the Newton matrix on the free rows `factored` (indices into the free rows).
    pub(crate) fn new(
        problem: &ContactProblem,
        system: &NewtonSystem,
        factored: &[usize],
        (outcome, exact_first): (&mut ContactOutcome, bool),
    ) -> Self {
        let factored = factor_rows(problem, system, factored, (outcome, exact_first));
        let mut row = vec![None; problem.m()];
        for (a, &p) in factored.rows.iter().enumerate() {
            row[p] = Some(a);
        }
        KeptFactor {
            fingerprint: problem.fingerprint(),
            columns: KeptColumns::new(factored.rows.len()),
            factored,
            row,
        }
    }

    /// The order of the factor, |ℱ|.
    fn n(&self) -> usize {
        self.factored.rows.len()
    }

    /// How many columns A₀⁻¹ e_k it keeps.
    #[cfg(test)]
    pub(crate) fn kept_columns(&self) -> usize {
        self.columns.len()
    }

    /// Whether it was formed with this problem's operator.
    pub fn serves(&self, problem: &ContactProblem) -> bool {
        self.fingerprint == problem.fingerprint()
    }
}

/// The direction by CG with the kept factor, refactored where it no longer serves.
pub struct Kept<'a> {
    pub factor: &'a mut Option<KeptFactor>,
    pub settings: &'a ContactSettings,
}

impl DirectionSolver for Kept<'_> {
    fn direction(
        &mut self,
        problem: &ContactProblem,
        system: &NewtonSystem,
        outcome: &mut ContactOutcome,
    ) -> Option<Direction> {
        let on = self.settings.strategies;
        let nf = system.free.len();
        if nf <= self.settings.dense_limit || !on.kept_factor {
            return None;
        }
        let exact = system.exact_diagonal();
        let reused = (self.factor.as_mut())
            .filter(|k| k.serves(problem))
            .and_then(|k| preconditioned(problem, k, system, &on));
        if let Some((direction, _)) = reused {
            outcome.iterative += 1;
            return Some(direction);
        }
        outcome.factorisations += 1;
        // the rows a law holds stiffly are left out (Jacobi preconditions them): the factor's
        // direction is then CG's on it
        let mut factored: Vec<usize> = (0..nf)
            .filter(|&i| !on.jacobi_rows || !stiff(problem, system, &exact, i, TUNING.stiff))
            .collect();
        if factored.is_empty() {
            factored = (0..nf).collect();
        }
        let convexified = outcome.convexified;
        // (the old factor goes first: the two are never alive together)
        *self.factor = None;
        let mut fresh = KeptFactor::new(problem, system, &factored, (outcome, true));
        // where the exact Newton matrix on the factored rows is not positive definite, neither is
        // the one on all free rows (it holds it as a principal submatrix)
        let indefinite = outcome.convexified > convexified;
        let mut solved = None;
        if factored.len() < nf {
            solved = preconditioned(problem, &mut fresh, system, &on).map(|(d, _)| d);
            if solved.is_none() {
                // CG met a direction of non-positive curvature or did not converge: the dense
                // direction on every free row
                drop(fresh);
                outcome.factorisations += 1;
                let all: Vec<usize> = (0..nf).collect();
                fresh = KeptFactor::new(problem, system, &all, (outcome, !indefinite));
            }
        }
        let direction = solved.unwrap_or_else(|| Direction {
            x: fresh.factored.factor.solve(&system.rhs()),
        });
        *self.factor = Some(fresh);
        Some(direction)
    }
}

/// Whether free row i's law curvature is `share` times its stiffness Q_pp or more (a pair: both
/// of its block's curvatures beside both rows' stiffness), so that Jacobi's 1/(Q_pp + e_p)
/// preconditions it well and the kept factor can leave it out (docs/method.md §9.2).
pub(crate) fn stiff(problem: &ContactProblem, system: &NewtonSystem, curvature: &[f64], i: usize, share: f64) -> bool {
    let (free, hessian) = (system.free, system.hessian);
    let p = free[i];
    match hessian.partner.get(i).copied().flatten() {
        None => curvature[i] > share * problem.c(p),
        Some(j) => {
            let (a, b, _) = hessian.pair[i];
            a.min(b) > share * problem.c(p).max(problem.c(free[j]))
        }
    }
}

/// The Newton system (Q_ℐℐ + diag(curvature) + the pairs' coupling) x = G_ℐ, its curvature the
/// laws' diagonal with the proximal shift, by CG preconditioned with the kept factor brought to
/// the present system (this file's doc), to the relative residual
/// `system.forcing` within [`TUNING`]`.cg_iterations` + |ℐ|/`cg_rows_per_iteration`
/// iterations. Returns the direction and the iterations; None where the factor does not serve
/// (the caller refactors).
pub fn preconditioned(
    problem: &ContactProblem,
    kept: &mut KeptFactor,
    system: &NewtonSystem,
    on: &Strategies,
) -> Option<(Direction, usize)> {
    let curvature = &system.exact_diagonal()[..];
    let (free, hessian) = (system.free, system.hessian);
    let nf = free.len();
    // a free row outside the factor that no law holds stiffly: the factor does not serve
    let outside_soft = (0..nf).any(|i| {
        kept.row[free[i]].is_none() && (!on.jacobi_rows || !stiff(problem, system, curvature, i, TUNING.stiff / 10.0))
    });
    if outside_soft {
        return None;
    }
    // the kept rows that left the free set: pinned at 0 by the update (an infinite Δ)
    let mut now_free = vec![false; kept.n()];
    for &p in free {
        if let Some(k) = kept.row[p] {
            now_free[k] = true;
        }
    }
    let pinned: Vec<usize> = (0..kept.n()).filter(|&k| !now_free[k]).collect();
    let moved = |i: usize| {
        let Some(k) = kept.row[free[i]] else {
            return false;
        };
        let limit = TUNING.moved * (problem.c(free[i]) + kept.factored.diagonal[k].abs());
        (curvature[i] - kept.factored.diagonal[k]).abs() > limit
            || hessian.partner[i].is_some() && (hessian.coupling[i] - kept.factored.coupling[k]).abs() > limit
    };
    let mut in_u: Vec<bool> = (0..nf).map(moved).collect();
    for i in 0..nf {
        if let Some(j) = hessian.partner[i].filter(|&j| in_u[i] && kept.row[free[j]].is_some()) {
            in_u[j] = true;
        }
    }
    let u: Vec<usize> = (0..nf).filter(|&i| in_u[i]).collect();
    let update = match u.is_empty() && pinned.is_empty() {
        true => None,
        false if !on.low_rank_update => return None,
        false => Some(low_rank_update(kept, system, curvature, (&u, &pinned))?),
    };
    iterate(problem, kept, system, curvature, update.as_ref())
}

/// The low-rank update on the free rows `u` and the factor's rows `pinned` (no longer free;
/// Δ = ∞): the columns of Z = A₀⁻¹ U not kept yet (one blocked solve), Δ and the capacitance
/// matrix. None past |ℱ|/[`TUNING`]`.new_columns` new columns, |ℱ|/`update_rows` rows, or where
/// the kept columns would pass |ℱ|/`update_rows` (a quarter of the factor's size; a
/// refactorisation starts them afresh).
fn low_rank_update(
    kept: &mut KeptFactor,
    system: &NewtonSystem,
    curvature: &[f64],
    (u, pinned): (&[usize], &[usize]),
) -> Option<LowRankUpdate> {
    let (free, hessian) = (system.free, system.hessian);
    let n = kept.n();
    let rows: Vec<usize> = (u.iter().map(|&i| kept.row[free[i]].expect("𝒰 is in the factor")))
        .chain(pinned.iter().copied())
        .collect();
    let fresh = kept.columns.missing(&rows);
    let (new, size) = (TUNING.new_columns, TUNING.update_rows);
    if new * fresh.len() > n || size * rows.len() > n || size * (kept.columns.len() + fresh.len()) > n {
        return None;
    }
    if !fresh.is_empty() {
        kept.columns.add(&kept.factored.factor, &fresh);
    }
    // Δ: per row of 𝒰 its diagonal change and, for a pair, its partner's place in 𝒰 and the
    // change of their coupling
    let place: std::collections::HashMap<usize, usize> = u.iter().enumerate().map(|(a, &i)| (i, a)).collect();
    let delta: Vec<DeltaRow> = (u.iter().zip(&rows))
        .map(|(&i, &k)| DeltaRow {
            diagonal: curvature[i] - kept.factored.diagonal[k],
            pair: (hessian.partner[i].and_then(|j| place.get(&j)))
                .map(|&a| (a, hessian.coupling[i] - kept.factored.coupling[k])),
        })
        .chain(pinned.iter().map(|_| DeltaRow {
            diagonal: f64::INFINITY,
            pair: None,
        }))
        .collect();
    Some(LowRankUpdate::new(&kept.columns, rows, delta))
}

/// CG with the kept factor, updated, as the preconditioner.
fn iterate(
    problem: &ContactProblem,
    kept: &KeptFactor,
    system: &NewtonSystem,
    curvature: &[f64],
    update: Option<&LowRankUpdate>,
) -> Option<(Direction, usize)> {
    let (free, hessian, forcing) = (system.free, system.hessian, system.forcing);
    let (m, nf) = (problem.m(), free.len());
    let iterations = TUNING.cg_iterations + nf / TUNING.cg_rows_per_iteration;
    let (mut full, mut product) = (vec![0.0; m], vec![0.0; m]);
    let mut apply = |x: &[f64], y: &mut [f64]| {
        full.fill(0.0);
        for (i, &p) in free.iter().enumerate() {
            full[p] = x[i];
        }
        problem.operator.apply_q(&full, &mut product);
        for (i, &p) in free.iter().enumerate() {
            y[i] = product[p] + curvature[i] * x[i];
            if let Some(j) = hessian.partner[i] {
                y[i] += hessian.coupling[i] * x[j];
            }
        }
    };
    let mut kept_rhs = vec![0.0; kept.n()];
    let mut precondition = |r: &[f64], z: &mut [f64]| {
        kept_rhs.fill(0.0);
        for (i, &p) in free.iter().enumerate() {
            if let Some(k) = kept.row[p] {
                kept_rhs[k] = r[i];
            }
        }
        // (one column on the run's threads: a preconditioner's rounding only changes CG's path)
        kept.factored.factor.solve_columns_in_place(&mut kept_rhs, 1);
        if let Some(update) = update {
            update.correct(&kept.columns, &mut kept_rhs);
        }
        for (i, &p) in free.iter().enumerate() {
            z[i] = match kept.row[p] {
                None => r[i] / (problem.c(p) + curvature[i].max(0.0)),
                Some(k) => kept_rhs[k],
            };
        }
    };
    let b = system.rhs();
    let norm_b = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut x = vec![0.0; nf];
    if norm_b == 0.0 {
        return Some((Direction { x }, 0));
    }
    let mut r = b;
    let mut z = vec![0.0; nf];
    precondition(&r, &mut z);
    let mut dir = z.clone();
    let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
    let mut ad = vec![0.0; nf];
    for k in 0..iterations {
        apply(&dir, &mut ad);
        let curvature_along: f64 = dir.iter().zip(&ad).map(|(a, b)| a * b).sum();
        // (rz ≤ 0: the updated preconditioner is not positive definite)
        if curvature_along <= 0.0 || rz <= 0.0 {
            return None;
        }
        let alpha = rz / curvature_along;
        for i in 0..nf {
            x[i] += alpha * dir[i];
            r[i] -= alpha * ad[i];
        }
        if r.iter().map(|v| v * v).sum::<f64>().sqrt() <= forcing * norm_b {
            return Some((Direction { x }, k + 1));
        }
        precondition(&r, &mut z);
        let next: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let beta = next / rz;
        rz = next;
        for i in 0..nf {
            dir[i] = z[i] + beta * dir[i];
        }
    }
    None
}
