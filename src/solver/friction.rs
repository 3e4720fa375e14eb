//! The contact solve of a step with friction (docs/method.md §17). The condensation holds the
//! normal rows and, after them, one tangential row per normal row of a group with friction
//! (2D: along τ = (−ν_y, ν_x)). On a tangential row the law acts on the slip increment
//! Δu_τ = u_τ − u_τ(t_{n−1}) of the step:
//!
//! ```text
//!   j_τ(u_τ) = F · ρ_ε(u_τ − u_τ(t_{n−1})),   ρ_ε the smoothed |·| of docs/method.md §4.2,
//! ```
//!
//! F the row's bound force: w_p F_b(x_p, t_n) (Tresca) or μ λ_ν,p (Coulomb, λ_ν,p the normal
//! force of the same step). That is the odd law with a constant profile μ ≡ 1, scale F and the
//! origin u_τ(t_{n−1}): the tangential rows join the same globalised active-set solve as the
//! normal ones, in one condensed problem of size m + m_τ, still after the step's one forward
//! sweep. Tresca is a potential (one solve); Coulomb's F depends on the solution and is found by
//! a fixed point F ← μ λ_ν, each round warm-started from the last.

use super::contact::{ContactSetup, Friction, FrictionLaw};
use super::setup::Simulation;
use crate::contact::active_set::{
    ActiveSetSolver, ContactFailure, ContactOutcome, ContactSettings, ContactState, FrictionRows, FrictionStatus,
    StepTrend,
};
use crate::contact::condensed::DenseNormalStiffness;
use crate::contact::NormalStiffness;
use crate::linalg::dense::matvec_row_major;

/// Rounds of the Coulomb fixed point before the step fails.
const COULOMB_ROUNDS: usize = 50;

/// The condensed operator, the normal rows' law origins and bounds of the step, and whether Q
/// may be singular (rigid parameters).
pub(super) struct NormalRows<'a> {
    pub operator: &'a dyn NormalStiffness,
    pub offset: Option<&'a [f64]>,
    pub bound: Option<&'a [f64]>,
    pub singular: bool,
}

/// Solves the step's contact problem with friction for the free contact forces `q` over all
/// rows, warm-started from `state` (whose tangential displacements are the previous step's).
pub(super) fn solve<const D: usize>(
    sim: &Simulation<D>,
    setup: &ContactSetup<D>,
    friction: &Friction<D>,
    normal: NormalRows,
    step: usize,
    q: &[f64],
    state: &mut ContactState,
) -> Result<ContactOutcome, ContactFailure> {
    let m = setup.nodes.len();
    let all = friction.rows.len();
    // The rows of Tresca and Coulomb are solved for their slip increment r − u_τ(t_{n−1}), not
    // for u_τ: E(r) with r = s + shift is ½ sᵀQs − (q − Q shift)ᵀs + Σ w j(s) up to a constant.
    // Their laws then act at s = 0 exactly, and a sticking row's stiffness F/ε multiplies the
    // rounding of s (the step's slip) instead of that of u_τ (all the slip so far, which can be
    // ten thousand times larger and made the residual stall at 1e-10, docs/method.md §17.2).
    let shift: Vec<f64> = (0..all)
        .map(|r| match r.checked_sub(m).map(|k| &friction.laws[k]) {
            Some(FrictionLaw::Tresca(_) | FrictionLaw::Coulomb(_)) => state.normal_displacement[r],
            _ => 0.0,
        })
        .collect();
    let mut shifted = vec![0.0; all];
    normal.operator.apply_q(&shift, &mut shifted);
    shifted.iter_mut().zip(q).for_each(|(s, q)| *s = q - *s);
    state
        .normal_displacement
        .iter_mut()
        .zip(&shift)
        .for_each(|(r, s)| *r -= s);
    // The load-following predictor: where this step's load moves on as the last step's did (the
    // projection `along` of its change of q on the last step's), the normal rows start at their
    // last displacement plus `along` times its last change, and Coulomb's bound forces likewise
    // (in solve_increment); a load that turns (the Cattaneo–Mindlin block's shear step after its
    // pressing step) gives along ≈ 0, the plain warm start (docs/method.md §17.2).
    let trend = &state.friction.trend;
    let change: Vec<f64> = if trend.load.len() == all {
        q.iter().zip(&trend.load).map(|(a, b)| a - b).collect()
    } else {
        Vec::new()
    };
    let along = match setup.settings.strategies.load_predictor {
        true => load_following(&change, &trend.load_change),
        false => 0.0,
    };
    let start = state.normal_displacement[..m].to_vec();
    if trend.normal_change.len() == m {
        for (r, d) in state.normal_displacement.iter_mut().zip(&trend.normal_change) {
            *r += along * d;
        }
    }
    let solved = solve_increment(sim, setup, friction, normal, (step, along), &shifted, state);
    if solved.is_ok() {
        let trend = &mut state.friction.trend;
        trend.normal_change = (state.normal_displacement.iter().zip(&start))
            .map(|(a, b)| a - b)
            .collect();
        trend.load_change = change;
        trend.load = q.to_vec();
    }
    state
        .normal_displacement
        .iter_mut()
        .zip(&shift)
        .for_each(|(r, s)| *r += s);
    solved
}

/// [`solve`] in the frame of the slip increments: Tresca's and Coulomb's tangential rows hold
/// r − u_τ(t_{n−1}) (their origin 0), the other rows their displacements.
fn solve_increment<const D: usize>(
    sim: &Simulation<D>,
    setup: &ContactSetup<D>,
    friction: &Friction<D>,
    normal: NormalRows,
    (step, along): (usize, f64),
    q: &[f64],
    state: &mut ContactState,
) -> Result<ContactOutcome, ContactFailure> {
    let t = sim.time.time(step);
    let on = setup.settings.strategies;
    let m = setup.nodes.len();
    let all = friction.rows.len();
    // origins: the normal rows' gaps; 0 on the tangential rows (Tresca and Coulomb: their slip
    // increment; a potential: the total tangential displacement)
    let offset: Vec<f64> = (0..all)
        .map(|r| {
            if r < m {
                normal.offset.map_or(0.0, |o| o[r])
            } else {
                0.0
            }
        })
        .collect();
    let bound: Option<Vec<f64>> = normal
        .bound
        .map(|g| (0..all).map(|r| if r < m { g[r] } else { f64::INFINITY }).collect());
    // bilateral normal rows (docs/method.md §17.4), over all rows
    let fixed: Option<Vec<bool>> = setup
        .bilateral
        .as_ref()
        .map(|b| (0..all).map(|r| r < m && b[r]).collect());
    // the normal force that presses row p: λ_ν, or |λ_ν| where the contact is bilateral
    let pressing = |state: &ContactState, p: usize| match &setup.bilateral {
        Some(b) if b[p] => state.force[p].abs(),
        _ => state.force[p].max(0.0),
    };
    // the laws of all rows, built once; the bound forces of Tresca and Coulomb set below
    let mut laws = friction.laws_of_rows.clone();
    // the slip accumulated before this step, and the tangential rows' values at its start (0 for
    // Tresca and Coulomb in this frame, u_τ(t_{n−1}) for a potential): the step's slip is
    // measured from them
    let k_rows = friction.normal_row.len();
    let before = state.normal_displacement[m..].to_vec();
    // The predictor: Tresca's and Coulomb's rows start at their last step's slip increment
    // instead of at their kink (0). Under a steady load the step slips about as much as the
    // last, so the slipping rows start near their slip curvature F/|Δu_τ| of the last step's end,
    // where the kept factor of the Newton matrix was made, instead of at the kink's F/ε: fewer
    // refactorisations at a step's first directions (docs/method.md §17.2).
    if state.friction.slip.len() == k_rows && on.slip_predictor {
        for (k, law) in friction.laws.iter().enumerate() {
            if matches!(law, FrictionLaw::Tresca(_) | FrictionLaw::Coulomb(_)) {
                state.normal_displacement[m + k] += state.friction.slip[k];
            }
        }
    }
    let accumulated: Vec<f64> = if state.friction.accumulated.len() == k_rows {
        state.friction.accumulated.clone()
    } else {
        vec![0.0; k_rows]
    };
    // the bound force of each tangential row, given the state (Coulomb: its normal force and,
    // for μ(s), its accumulated slip with this step's increment)
    let bound_forces = |state: &ContactState| -> Result<Vec<f64>, String> {
        let slip = |k: usize| state.normal_displacement[m + k] - before[k];
        (0..k_rows)
            .map(|k| {
                let p = friction.normal_row[k];
                let x = sim.mesh.points[setup.nodes.nodes[p]];
                let (value, what) = match &friction.laws[k] {
                    // w_p S μ(|u_τ|): the law's strength where the row is
                    FrictionLaw::Potential => {
                        let rows = &friction.laws_of_rows;
                        let law = &rows.laws[rows.terms(m + k)[0].law];
                        let u = friction.length(k, |k| state.normal_displacement[m + k]);
                        (law.scale * law.profile.slope(u), "the friction law's μ")
                    }
                    FrictionLaw::Coulomb(mu) => {
                        let s = accumulated[k] + friction.length(k, slip);
                        (mu.at(s), "the friction coefficient")
                    }
                    FrictionLaw::Tresca(e) => {
                        let mut vars = [0.0; 4];
                        vars[..D].copy_from_slice(&x);
                        vars[3] = t;
                        (e.eval(&vars), "the Tresca bound")
                    }
                };
                if !(value.is_finite() && value >= 0.0) {
                    return Err(format!(
                        "{what} is {value} at {}, t = {t}: it must be finite and ≥ 0",
                        crate::mesh::fmt_point(x)
                    ));
                }
                Ok(match &friction.laws[k] {
                    FrictionLaw::Coulomb(_) => value * pressing(state, p),
                    FrictionLaw::Tresca(_) | FrictionLaw::Potential => setup.nodes.weights[p] * value,
                })
            })
            .collect()
    };
    let failure = |reason: String, outcome: ContactOutcome| ContactFailure {
        outcome,
        reason,
        smallest_residual: f64::INFINITY,
    };
    // Coulomb's first round uses the previous step's normal forces (the warm start), moved on by
    // the load-following predictor (see `solve`)
    let is_coulomb: Vec<bool> = friction
        .laws
        .iter()
        .map(|l| matches!(l, FrictionLaw::Coulomb(_)))
        .collect();
    let mut forces = bound_forces(state).map_err(|reason| failure(reason, ContactOutcome::default()))?;
    if state.friction.trend.bound_change.len() == k_rows {
        for (k, change) in state.friction.trend.bound_change.iter().enumerate() {
            if is_coulomb[k] {
                forces[k] = (forces[k] + along * change).max(0.0);
            }
        }
    }
    let coulomb = is_coulomb.contains(&true);
    let mut total = ContactOutcome::default();
    // A body that only its contact holds (rigid parameters, docs/method.md §7.7) and no normal
    // force yet: friction of bound 0 would hold nothing and a tangential load would have no
    // equilibrium. The first guess is then full stick — the tangential rows held at their
    // origin like bilateral rows — whose normal forces give the first bound forces.
    if coulomb && normal.singular && forces.iter().all(|&f| f == 0.0) {
        let stick_bound: Vec<f64> = (0..all)
            .map(|r| {
                if r < m {
                    bound.as_ref().map_or(f64::INFINITY, |g| g[r])
                } else {
                    0.0
                }
            })
            .collect();
        let stick: Vec<bool> = (0..all)
            .map(|r| r >= m || fixed.as_ref().is_some_and(|f| f[r]))
            .collect();
        let predictor = ActiveSetSolver {
            operator: normal.operator,
            laws: &laws,
            offset: Some(&offset),
            bound: Some(&stick_bound),
            settings: setup.settings,
            singular: normal.singular,
            pairs: None,
            fixed: Some(&stick),
            branch_from: usize::MAX,
        };
        let outcome = predictor.solve_forces(q, state)?;
        total.add_work(&outcome);
        forces = bound_forces(state).map_err(|reason| failure(reason, total))?;
    }
    // Coulomb's rounds are solved inexactly while the bound forces still move: to 10⁻² of their
    // last change (at most 10⁻³, the first round), and at the solver's tolerance once they
    // settle, which the last round always is (docs/method.md §17.2)
    let tolerance = setup.settings.tolerance;
    let inexact = coulomb && on.inexact_rounds;
    let mut round_tolerance = if inexact { tolerance.max(1e-3) } else { tolerance };
    let mut mixing = Anderson::new(is_coulomb.clone());
    // Coulomb's first round with no normal force yet (a step's first contact) is the frictionless
    // problem: solved on the normal rows alone (see `unloaded_round`), the rounds go on from it
    let mut first = 0;
    let unloaded = coulomb && on.unloaded_round && forces.iter().all(|&f| f == 0.0);
    if unloaded && is_coulomb.iter().all(|&c| c) && !normal.singular {
        let settings = ContactSettings {
            tolerance: round_tolerance,
            ..setup.settings
        };
        if let Some(outcome) = unloaded_round(setup, &normal, (&offset, bound.as_deref()), settings, q, state)? {
            total.add_work(&outcome);
            let next = bound_forces(state).map_err(|reason| failure(reason, total))?;
            let (change, scale) = bound_change(state, m, &forces, &next);
            if inexact {
                round_tolerance = moving_tolerance(tolerance, change, scale);
            }
            forces = next;
            first = 1;
        }
    }
    for round in first..COULOMB_ROUNDS {
        // (a potential's "bound" is an output only: its term keeps the weight w_p)
        for (k, law) in friction.laws.iter().enumerate() {
            if !matches!(law, FrictionLaw::Potential) {
                laws.set_weight(m + k, forces[k]);
            }
        }
        let solver = ActiveSetSolver {
            operator: normal.operator,
            laws: &laws,
            offset: Some(&offset),
            bound: bound.as_deref(),
            settings: ContactSettings {
                tolerance: round_tolerance,
                ..setup.settings
            },
            singular: normal.singular,
            pairs: friction.pairs.as_deref(),
            fixed: fixed.as_deref(),
            // Coulomb's rows only: on the Cattaneo–Mindlin block Tresca took 29 → 34 directions
            // with it (docs/method.md §17.2)
            branch_from: if coulomb { m } else { usize::MAX },
        };
        let outcome = solver.solve_forces(q, state).map_err(|mut f| {
            f.outcome.iterations += total.iterations;
            f
        })?;
        total.add_work(&outcome);
        total.residual = outcome.residual;
        total.active = outcome.active;
        let next = bound_forces(state).map_err(|reason| failure(reason, total))?;
        // the fixed point F = μ(s) λ_ν has settled when the bound forces stop moving
        let (change, scale) = bound_change(state, m, &forces, &next);
        let settled = change <= tolerance * scale;
        if !coulomb || (settled && (round_tolerance == tolerance || outcome.residual <= tolerance)) {
            let pressed: Vec<f64> = friction.normal_row.iter().map(|&p| pressing(state, p)).collect();
            record(state, friction, (&before, &pressed), &accumulated, &forces);
            return Ok(total);
        }
        round_tolerance = if settled || !inexact {
            tolerance
        } else {
            moving_tolerance(tolerance, change, scale)
        };
        // the bound forces' next guess: from a Newton step on the coupled law where it serves
        // (docs/method.md §17.2), otherwise the fixed point's (mixed)
        // (not after the first round: from the predicted bound forces the stick/slip pattern
        // still moves, and the step cost more directions than it saved, 264 against 256 on the
        // slab)
        let stepped = (round > 0 && on.coupled_step)
            .then(|| {
                let coupling: Vec<(usize, usize, f64, f64)> = (0..k_rows)
                    .filter(|&k| is_coulomb[k] && forces[k] > 0.0)
                    .filter_map(|k| {
                        let p = friction.normal_row[k];
                        let pressed = pressing(state, p);
                        (pressed > 0.0).then(|| (m + k, p, forces[k], next[k] / pressed))
                    })
                    .collect();
                // a step wherever the coupled residual is above the solve's tolerance, not the
                // round's: the next round then starts converged instead of one or two rounds
                // of a direction each (docs/method.md §17.2)
                let full = ActiveSetSolver {
                    settings: ContactSettings {
                        tolerance,
                        ..setup.settings
                    },
                    ..solver
                };
                full.coupled_step(q, state, &coupling)
            })
            .flatten();
        match stepped {
            Some(iterations) => {
                if iterations > 0 {
                    total.iterations += 1;
                    total.iterative += 1;
                }
                forces = bound_forces(state).map_err(|reason| failure(reason, total))?;
                mixing.restart();
            }
            None if on.anderson => forces = mixing.next(&forces, next),
            None => forces = next,
        }
    }
    Err(failure(
        format!(
            "the Coulomb fixed point F_b = μ λ_ν did not settle in {COULOMB_ROUNDS} rounds (the normal forces still \
             change with the friction forces: a large μ against a compliant body)"
        ),
        total,
    ))
}

/// The largest change of the bound forces from `forces` to `next`, and the scale it is measured
/// against: the largest normal force of the state (m normal rows).
fn bound_change(state: &ContactState, m: usize, forces: &[f64], next: &[f64]) -> (f64, f64) {
    let scale = state.force[..m].iter().fold(f64::MIN_POSITIVE, |a, b| a.max(b.abs()));
    let change = next.iter().zip(forces).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    (change, scale)
}

/// A round's tolerance while the bound forces still move: 10⁻² of their last change relative to
/// the scale, at most 10⁻³, never below the solve's (docs/method.md §17.2).
fn moving_tolerance(tolerance: f64, change: f64, scale: f64) -> f64 {
    tolerance.max((1e-2 * change / scale).min(1e-3))
}

/// Coulomb's first round where every bound force is 0 (no normal force yet, docs/method.md §17.2):
/// no tangential row holds a force, so the round is the frictionless problem of the normal rows,
/// whose stiffness is the Schur complement S = (W_νν)⁻¹ of Q on them and whose free forces are
/// S d_ν, d = W q. Solved there (m rows, where the full round factors m + m_τ), the tangential rows
/// follow as r_τ = d_τ − W_τν λ_ν; the state is then the full round's solution. None (the full
/// round runs) where W is not at hand or not positive definite on the normal rows.
fn unloaded_round<const D: usize>(
    setup: &ContactSetup<D>,
    normal: &NormalRows,
    (offset, bound): (&[f64], Option<&[f64]>),
    settings: ContactSettings,
    q: &[f64],
    state: &mut ContactState,
) -> Result<Option<ContactOutcome>, ContactFailure> {
    let (m, all) = (setup.nodes.len(), normal.operator.m());
    let Some(w) = normal.operator.w() else {
        return Ok(None);
    };
    let normal_block: Vec<f64> = (0..m).flat_map(|p| w[p * all..p * all + m].iter().copied()).collect();
    let Ok(reduced) = DenseNormalStiffness::from_w(normal_block, m) else {
        return Ok(None);
    };
    let mut d = vec![0.0; all];
    matvec_row_major(w, all, q, &mut d);
    let mut free_forces = vec![0.0; m];
    reduced.apply_q(&d[..m], &mut free_forces);
    let mut rows = ContactState::new(m);
    rows.normal_displacement
        .copy_from_slice(&state.normal_displacement[..m]);
    let solver = ActiveSetSolver {
        operator: &reduced,
        laws: &setup.laws,
        offset: Some(&offset[..m]),
        bound: bound.map(|g| &g[..m]),
        settings,
        singular: false,
        pairs: None,
        fixed: setup.bilateral.as_deref(),
        branch_from: usize::MAX,
    };
    let outcome = solver.solve_forces(&free_forces, &mut rows)?;
    // λ_τ = 0 and r = d − W λ
    let mut lambda = vec![0.0; all];
    lambda[..m].copy_from_slice(&rows.force);
    let mut moved = vec![0.0; all];
    matvec_row_major(w, all, &lambda, &mut moved);
    state.normal_displacement[..m].copy_from_slice(&rows.normal_displacement);
    for p in m..all {
        state.normal_displacement[p] = d[p] - moved[p];
    }
    state.force.copy_from_slice(&lambda);
    state.balanced_at = None;
    Ok(Some(outcome))
}

/// The projection of this step's change of the free contact forces on the last step's,
/// clamped to [0, 2]: 1 for a load that moves on as it did, 0 for one that turns or reverses,
/// or where either change is unknown or zero (the load-following predictor of [`solve`]).
fn load_following(change: &[f64], last: &[f64]) -> f64 {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let norm = dot(last, last);
    if change.len() != last.len() || norm == 0.0 {
        return 0.0;
    }
    (dot(change, last) / norm).clamp(0.0, 2.0)
}

/// Rounds of the Coulomb fixed point that [`Anderson`] combines.
const ANDERSON_DEPTH: usize = 3;

/// Anderson mixing of Coulomb's fixed point F ← Φ(F) = μ(s) λ_ν(F) (docs/method.md §17.2). The
/// next round's bound forces combine the last rounds' outputs Φ(F_j) with the weights whose
/// residuals Φ(F_j) − F_j combine to the least length; on a linear Φ that is GMRES on I − Φ',
/// where the plain fixed point gains only Φ's contraction per round. Only Coulomb's rows are
/// mixed (Tresca's bound is fixed, a potential's an output); a round whose residual grew starts
/// the history afresh (the plain round).
struct Anderson {
    coulomb: Vec<bool>,
    /// the last rounds' residuals Φ(F_j) − F_j (0 off Coulomb's rows) and outputs Φ(F_j),
    /// oldest first
    rounds: Vec<(Vec<f64>, Vec<f64>)>,
}

impl Anderson {
    fn new(coulomb: Vec<bool>) -> Self {
        Anderson {
            coulomb,
            rounds: Vec::new(),
        }
    }

    /// Forgets the rounds so far (the bound forces moved by other means than a round).
    fn restart(&mut self) {
        self.rounds.clear();
    }

    /// The next round's bound forces, given this round's F and Φ(F).
    fn next(&mut self, input: &[f64], output: Vec<f64>) -> Vec<f64> {
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        // the residual Φ(F) − F on Coulomb's rows (0 elsewhere)
        let f: Vec<f64> = (input.iter().zip(&output).zip(&self.coulomb))
            .map(|((x, g), &c)| if c { g - x } else { 0.0 })
            .collect();
        if self.rounds.last().is_some_and(|(last, _)| norm(&f) > norm(last)) {
            self.rounds.clear();
        }
        self.rounds.push((f, output));
        if self.rounds.len() > ANDERSON_DEPTH + 1 {
            self.rounds.remove(0);
        }
        let k = self.rounds.len() - 1;
        let (f, newest) = &self.rounds[k];
        if k == 0 {
            return newest.clone();
        }
        // γ = argmin |f_k − Σ_j γ_j (f_{j+1} − f_j)|, by an SVD that drops directions below 10⁻¹²
        // of |f_k| (rounds whose residuals are nearly parallel)
        let n = f.len();
        let differences = nalgebra::DMatrix::from_fn(n, k, |i, j| self.rounds[j + 1].0[i] - self.rounds[j].0[i]);
        let target = nalgebra::DVector::from_column_slice(f);
        let Ok(gamma) = differences.svd(true, true).solve(&target, 1e-12 * norm(f)) else {
            return newest.clone();
        };
        (0..n)
            .map(|i| {
                if !self.coulomb[i] {
                    return newest[i];
                }
                let mut v = newest[i];
                for j in 0..k {
                    v -= gamma[j] * (self.rounds[j + 1].1[i] - self.rounds[j].1[i]);
                }
                v.max(0.0)
            })
            .collect()
    }
}

/// The tangential rows' slip (their change from `before`, their values at the step's start),
/// accumulated slip, bound force and status after the step (docs/method.md §17): separated
/// where the normal row presses with no force (λ_ν, |λ_ν| where bilateral, below 10⁻¹² of the
/// largest), else stick where |λ_τ| < F (1 − 10⁻⁶), slip at F; |·| the length of the pair's
/// vector in 3D, whose two rows get the same accumulated slip and status.
fn record<const D: usize>(
    state: &mut ContactState,
    friction: &Friction<D>,
    (before, pressed): (&[f64], &[f64]),
    accumulated: &[f64],
    forces: &[f64],
) {
    let k_rows = forces.len();
    let m = friction.rows.len() - k_rows;
    // a normal force below 1e-12 of the largest is round-off of a node off the bound
    let largest = pressed.iter().fold(0.0f64, |a, &v| a.max(v));
    let slip: Vec<f64> = (0..k_rows)
        .map(|k| state.normal_displacement[m + k] - before[k])
        .collect();
    let mut rows = FrictionRows {
        slip: slip.clone(),
        accumulated: Vec::with_capacity(k_rows),
        bound: forces.to_vec(),
        trend: StepTrend {
            bound_change: if state.friction.bound.len() == k_rows {
                forces.iter().zip(&state.friction.bound).map(|(a, b)| a - b).collect()
            } else {
                vec![0.0; k_rows]
            },
            ..std::mem::take(&mut state.friction.trend)
        },
        status: Vec::with_capacity(k_rows),
    };
    for k in 0..k_rows {
        rows.accumulated.push(accumulated[k] + friction.length(k, |k| slip[k]));
        let force = friction.length(k, |k| state.force[m + k]);
        rows.status.push(if pressed[k] <= 1e-12 * largest {
            FrictionStatus::Separated
        } else if force < forces[k] * (1.0 - 1e-6) {
            FrictionStatus::Stick
        } else {
            FrictionStatus::Slip
        } as i32);
    }
    state.friction = rows;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear contraction Φ(F) = A F + b on n rows (A symmetric, eigenvalues spread over
    /// [0.05, `largest`]) and its fixed point: the Coulomb map's linearisation.
    fn linear_map(n: usize, largest: f64) -> (impl Fn(&[f64]) -> Vec<f64>, Vec<f64>) {
        // A = V diag(θ) Vᵀ with V the orthonormal sine basis
        let v = |i: usize, j: usize| {
            (2.0 / (n as f64 + 1.0)).sqrt()
                * (((i + 1) * (j + 1)) as f64 * std::f64::consts::PI / (n as f64 + 1.0)).sin()
        };
        let theta: Vec<f64> = (0..n)
            .map(|j| 0.05 + (largest - 0.05) * j as f64 / (n - 1) as f64)
            .collect();
        let a: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|k| (0..n).map(|j| v(i, j) * theta[j] * v(k, j)).sum())
                    .collect()
            })
            .collect();
        let b: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * i as f64).collect();
        // the fixed point (I − A)⁻¹ b = V diag(1/(1 − θ)) Vᵀ b
        let vb: Vec<f64> = (0..n).map(|j| (0..n).map(|i| v(i, j) * b[i]).sum()).collect();
        let fixed: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| v(i, j) * vb[j] / (1.0 - theta[j])).sum())
            .collect();
        let map = move |f: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| b[i] + (0..n).map(|k| a[i][k] * f[k]).sum::<f64>())
                .collect()
        };
        (map, fixed)
    }

    /// Rounds until max |F − F*| ≤ 10⁻¹⁰ max |F*|, mixed or plain, and the error then.
    fn rounds(n: usize, largest: f64, mixed: bool) -> (usize, f64) {
        let (map, fixed) = linear_map(n, largest);
        let scale = fixed.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let mut mixing = Anderson::new(vec![true; n]);
        let mut f = vec![0.0; n];
        for round in 1..=5000 {
            let next = map(&f);
            f = if mixed { mixing.next(&f, next) } else { next };
            let error = f.iter().zip(&fixed).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            if error <= 1e-10 * scale {
                return (round, error / scale);
            }
        }
        (usize::MAX, f64::INFINITY)
    }

    #[test]
    fn anderson_mixing_reaches_the_fixed_point_in_fewer_rounds() {
        // the plain fixed point gains the contraction per round: log(1e-10)/log(θ) rounds
        for (largest, plain_at_least) in [(0.9, 150), (0.99, 1500)] {
            let (plain, _) = rounds(40, largest, false);
            let (mixed, error) = rounds(40, largest, true);
            assert!(
                (plain_at_least..usize::MAX).contains(&plain),
                "plain {plain} rounds at θ = {largest}"
            );
            assert!(error <= 1e-10, "mixed error {error:e}");
            assert!(
                3 * mixed <= plain,
                "θ ≤ {largest}: {mixed} mixed rounds against {plain} plain"
            );
        }
    }

    #[test]
    fn anderson_mixing_leaves_other_rows_and_keeps_forces_non_negative() {
        // rows 1 and 3 are not Coulomb's: they take Φ's output as it is (row 3 a potential's
        // output, negative where its μ falls)
        let mut mixing = Anderson::new(vec![true, false, true, false]);
        let phi = |f: &[f64]| vec![0.5 * f[0] + 1.0, 7.0, (0.5 * f[2] - 1.0).max(0.0), f[3] - 1.0];
        let mut f = vec![0.0, 0.0, 3.0, 0.0];
        for _ in 0..6 {
            let next = phi(&f);
            let expected = next.clone();
            f = mixing.next(&f, next);
            assert_eq!((f[1], f[3]), (expected[1], expected[3]));
            assert!(f[0] >= 0.0 && f[2] >= 0.0, "{f:?}");
        }
        // the Coulomb rows reach their fixed points 2 and 0 (Φ ≥ 0, as μ λ_ν)
        assert!((f[0] - 2.0).abs() <= 1e-12 && f[2].abs() <= 1e-12, "{f:?}");
    }

    #[test]
    fn the_predictor_follows_a_load_that_moves_on_and_not_one_that_turns() {
        let last = [0.0, -2.0, 0.0, 1.0];
        assert_eq!(load_following(&[0.0, -1.8, 0.0, 0.9], &last), 0.9);
        // a shear step after a pressing step: the change is across the last one
        assert_eq!(load_following(&[3.0, 0.0, -1.0, 0.0], &last), 0.0);
        // reversed, unknown or zero
        assert_eq!(load_following(&[0.0, 2.0, 0.0, -1.0], &last), 0.0);
        assert_eq!(load_following(&[], &last), 0.0);
        assert_eq!(load_following(&[1.0, 0.0, 0.0, 0.0], &[0.0; 4]), 0.0);
        // at most twice the last change
        assert_eq!(load_following(&[0.0, -20.0, 0.0, 10.0], &last), 2.0);
    }
}
