//! The contact solve of a step with friction (docs/method.md §17). The condensation holds the
//! normal rows and, after them, one tangential row per normal row of a group with friction
//! (2D: along τ = (−ν_y, ν_x); 3D: two, a pair). On a tangential row the law acts on the slip
//! increment Δu_τ = u_τ − u_τ(t_{n−1}) of the step:
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
//! a fixed point F ← μ λ_ν, each round warm-started from the last and solved inexactly while
//! the bound forces still move.

use super::super::condensed::NormalStiffness;
use super::super::newton::ActiveSetSolver;
use super::super::nodal::NodalLaws;
use super::super::outcome::{ContactFailure, ContactOutcome};
use super::super::problem::ContactProblem;
use super::super::settings::{ContactSettings, TUNING};
use super::super::state::{ContactState, FrictionRows, FrictionStatus, SolverCache};
use super::super::trace;
use super::law::{Friction, FrictionLaw};
use super::unloaded;

/// The step's contact problem with friction: the condensed operator of all rows, the normal
/// rows' origins, bounds and weights, and where the rows are.
pub struct FrictionStep<'a, const D: usize> {
    pub friction: &'a Friction<D>,
    pub operator: &'a dyn NormalStiffness,
    /// The normal rows' law origins and bounds (m each), as the frictionless problem's.
    pub offset: Option<&'a [f64]>,
    pub bound: Option<&'a [f64]>,
    /// Whether Q may be singular along rigid motions (docs/method.md §7.7).
    pub singular: bool,
    /// Per normal row, whether it is bilateral (docs/method.md §17.4).
    pub bilateral: Option<&'a [bool]>,
    /// The normal rows' laws (the first m rows of `friction.laws_of_rows`, alone).
    pub normal_laws: &'a NodalLaws,
    /// The normal rows' nodal weights w_p and mesh nodes, and the mesh's points.
    pub weights: &'a [f64],
    pub nodes: &'a [usize],
    pub points: &'a [[f64; D]],
    /// t_n.
    pub time: f64,
    pub settings: ContactSettings,
}

/// Solves the step's contact problem with friction for the free contact forces `q` over all
/// rows, warm-started from `state` (whose tangential displacements are the previous step's).
pub fn solve<const D: usize>(
    step: &FrictionStep<D>,
    q: &[f64],
    state: &mut ContactState,
    cache: &mut SolverCache,
) -> Result<ContactOutcome, ContactFailure> {
    let (friction, m) = (step.friction, step.weights.len());
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
    step.operator.apply_q(&shift, &mut shifted);
    shifted.iter_mut().zip(q).for_each(|(s, q)| *s = q - *s);
    let r = &mut state.normal_displacement;
    r.iter_mut().zip(&shift).for_each(|(r, s)| *r -= s);
    // The load-following predictor: where this step's load moves on as the last step's did (the
    // projection `along` of its change of q on the last step's), the normal rows start at their
    // last displacement plus `along` times its last change, and Coulomb's bound forces likewise
    // (in solve_increment); a load that turns (the Cattaneo–Mindlin block's shear step after its
    // pressing step) gives along ≈ 0, the plain warm start (docs/method.md §17.2).
    let trend = &cache.trend;
    let change: Vec<f64> = match trend.load.len() == all {
        true => q.iter().zip(&trend.load).map(|(a, b)| a - b).collect(),
        false => Vec::new(),
    };
    let along = match step.settings.strategies.load_predictor {
        true => load_following(&change, &trend.load_change),
        false => 0.0,
    };
    let start = state.normal_displacement[..m].to_vec();
    if trend.normal_change.len() == m {
        for (r, d) in state.normal_displacement.iter_mut().zip(&trend.normal_change) {
            *r += along * d;
        }
    }
    let solved = solve_increment(step, along, &shifted, state, cache);
    if solved.is_ok() {
        let trend = &mut cache.trend;
        trend.normal_change = (state.normal_displacement.iter().zip(&start))
            .map(|(a, b)| a - b)
            .collect();
        trend.load_change = change;
        trend.load = q.to_vec();
    }
    let r = &mut state.normal_displacement;
    r.iter_mut().zip(&shift).for_each(|(r, s)| *r += s);
    solved
}

/// The projection of this step's change of the free contact forces on the last step's, clamped
/// to [0, 2]: 1 for a load that moves on as it did, 0 for one that turns or reverses, or where
/// either change is unknown or zero (the load-following predictor of [`solve`]).
fn load_following(change: &[f64], last: &[f64]) -> f64 {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let norm = dot(last, last);
    if change.len() != last.len() || norm == 0.0 {
        return 0.0;
    }
    (dot(change, last) / norm).clamp(0.0, 2.0)
}

/// [`solve`] in the frame of the slip increments: Tresca's and Coulomb's tangential rows hold
/// r − u_τ(t_{n−1}) (their origin 0), the other rows their displacements.
fn solve_increment<const D: usize>(
    step: &FrictionStep<D>,
    along: f64,
    q: &[f64],
    state: &mut ContactState,
    cache: &mut SolverCache,
) -> Result<ContactOutcome, ContactFailure> {
    let (friction, m) = (step.friction, step.weights.len());
    let on = step.settings.strategies;
    let all = friction.rows.len();
    // origins: the normal rows' gaps; 0 on the tangential rows (Tresca and Coulomb: their slip
    // increment; a potential: the total tangential displacement)
    let offset: Vec<f64> = (0..all)
        .map(|r| if r < m { step.offset.map_or(0.0, |o| o[r]) } else { 0.0 })
        .collect();
    let bound: Option<Vec<f64>> =
        (step.bound).map(|g| (0..all).map(|r| if r < m { g[r] } else { f64::INFINITY }).collect());
    // bilateral normal rows (docs/method.md §17.4), over all rows
    let fixed: Option<Vec<bool>> = step.bilateral.map(|b| (0..all).map(|r| r < m && b[r]).collect());
    // the laws of all rows, built once; the bound forces of Tresca and Coulomb set below
    let mut laws = friction.laws_of_rows.clone();
    // the tangential rows' values at the step's start (0 for Tresca and Coulomb in this frame,
    // u_τ(t_{n−1}) for a potential): the step's slip is measured from them
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
    let accumulated: Vec<f64> = match state.friction.accumulated.len() == k_rows {
        true => state.friction.accumulated.clone(),
        false => vec![0.0; k_rows],
    };
    let failure = |reason: String, outcome: ContactOutcome| ContactFailure {
        outcome,
        reason,
        smallest_residual: f64::INFINITY,
    };
    let forces_at = |state: &ContactState, total: ContactOutcome| {
        bound_forces(step, state, (&before, &accumulated)).map_err(|reason| failure(reason, total))
    };
    let is_coulomb: Vec<bool> = (friction.laws.iter())
        .map(|l| matches!(l, FrictionLaw::Coulomb(_)))
        .collect();
    let coulomb = is_coulomb.contains(&true);
    // Coulomb's first round uses the previous step's normal forces (the warm start)
    let mut forces = forces_at(state, ContactOutcome::default())?;
    if cache.trend.bound_change.len() == k_rows {
        for (k, change) in cache.trend.bound_change.iter().enumerate() {
            if is_coulomb[k] {
                forces[k] = (forces[k] + along * change).max(0.0);
            }
        }
    }
    let mut total = ContactOutcome::default();
    let solver = ActiveSetSolver {
        settings: step.settings,
        trace: trace::sink(step.settings.trace),
    };
    // A body that only its contact holds (rigid parameters, docs/method.md §7.7) and no normal
    // force yet: friction of bound 0 would hold nothing and a tangential load would have no
    // equilibrium. The first guess is then full stick — the tangential rows held at their
    // origin like bilateral rows — whose normal forces give the first bound forces.
    if coulomb && step.singular && forces.iter().all(|&f| f == 0.0) {
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
        let predictor = ContactProblem {
            offset: Some(&offset),
            bound: Some(&stick_bound),
            singular: step.singular,
            fixed: Some(&stick),
            ..ContactProblem::new(step.operator, &laws)
        };
        let outcome = solver.solve_forces(&predictor, q, state, cache)?;
        total.add_work(&outcome);
        forces = forces_at(state, total)?;
    }
    // Coulomb's rounds are solved inexactly while the bound forces still move: to 10⁻² of their
    // last change (at most 10⁻³, the first round), and at the solver's tolerance once they
    // settle, which the last round always is (docs/method.md §17.2)
    let tolerance = step.settings.tolerance;
    let inexact = coulomb && on.inexact_rounds;
    let mut round_tolerance = if inexact {
        tolerance.max(TUNING.first_round)
    } else {
        tolerance
    };
    // Coulomb's first round with no normal force yet (a step's first contact) is the frictionless
    // problem: solved on the normal rows alone (`unloaded.rs`), the rounds go on from it
    let mut first = 0;
    let unloaded = coulomb && on.unloaded_round && forces.iter().all(|&f| f == 0.0);
    if unloaded && is_coulomb.iter().all(|&c| c) && !step.singular {
        let round = ActiveSetSolver {
            settings: step.settings.with_tolerance(round_tolerance),
            ..solver
        };
        let rows = (step.operator, step.normal_laws, m);
        let solved = unloaded::solve(&round, rows, (&offset, bound.as_deref(), step.bilateral), q, state)?;
        if let Some(outcome) = solved {
            total.add_work(&outcome);
            let next = forces_at(state, total)?;
            let (change, scale) = bound_change(state, m, &forces, &next);
            if inexact {
                round_tolerance = moving_tolerance(tolerance, change, scale);
            }
            forces = next;
            first = 1;
        }
    }
    for _ in first..TUNING.coulomb_rounds {
        // (a potential's "bound" is an output only: its term keeps the weight w_p)
        for (k, law) in friction.laws.iter().enumerate() {
            if !matches!(law, FrictionLaw::Potential) {
                laws.set_weight(m + k, forces[k]);
            }
        }
        let problem = ContactProblem {
            offset: Some(&offset),
            bound: bound.as_deref(),
            singular: step.singular,
            pairs: friction.pairs.as_deref(),
            fixed: fixed.as_deref(),
            // Coulomb's rows only: on the Cattaneo–Mindlin block Tresca took 29 → 34 directions
            // with it (docs/method.md §17.2)
            branch_from: coulomb.then_some(m),
            ..ContactProblem::new(step.operator, &laws)
        };
        let round = ActiveSetSolver {
            settings: step.settings.with_tolerance(round_tolerance),
            ..solver
        };
        let outcome = round.solve_forces(&problem, q, state, cache).map_err(|mut f| {
            f.outcome.iterations += total.iterations;
            f
        })?;
        total.add_work(&outcome);
        total.residual = outcome.residual;
        total.active = outcome.active;
        let next = forces_at(state, total)?;
        // the fixed point F = μ(s) λ_ν has settled when the bound forces stop moving
        let (change, scale) = bound_change(state, m, &forces, &next);
        let settled = change <= tolerance * scale;
        if !coulomb || (settled && (round_tolerance == tolerance || outcome.residual <= tolerance)) {
            cache.trend.bound_change = match state.friction.bound.len() == k_rows {
                true => forces.iter().zip(&state.friction.bound).map(|(a, b)| a - b).collect(),
                false => vec![0.0; k_rows],
            };
            record(step, state, (&before, &accumulated), &forces);
            return Ok(total);
        }
        round_tolerance = match settled || !inexact {
            true => tolerance,
            false => moving_tolerance(tolerance, change, scale),
        };
        forces = next;
    }
    Err(failure(
        format!(
            "the Coulomb fixed point F_b = μ λ_ν did not settle in {} rounds (the normal forces still change with \
             the friction forces: a large μ against a compliant body)",
            TUNING.coulomb_rounds
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

/// A round's tolerance while the bound forces still move: a share of their last change relative
/// to the scale, at most the first round's, never below the solve's (docs/method.md §17.2).
fn moving_tolerance(tolerance: f64, change: f64, scale: f64) -> f64 {
    tolerance.max((TUNING.round_share * change / scale).min(TUNING.first_round))
}

/// The normal force that presses row p: λ_ν, or |λ_ν| where the contact is bilateral.
fn pressing<const D: usize>(step: &FrictionStep<D>, state: &ContactState, p: usize) -> f64 {
    match step.bilateral {
        Some(b) if b[p] => state.force[p].abs(),
        _ => state.force[p].max(0.0),
    }
}

/// The bound force of each tangential row given the state: Tresca's w_p F_b(x_p, t), Coulomb's
/// μ(s) times its normal force (s the accumulated slip with this step's increment from `before`),
/// a potential's w_p S μ(|u_τ|) (an output only).
fn bound_forces<const D: usize>(
    step: &FrictionStep<D>,
    state: &ContactState,
    (before, accumulated): (&[f64], &[f64]),
) -> Result<Vec<f64>, String> {
    let (friction, m) = (step.friction, step.weights.len());
    let slip = |k: usize| state.normal_displacement[m + k] - before[k];
    (0..friction.normal_row.len())
        .map(|k| {
            let p = friction.normal_row[k];
            let x = step.points[step.nodes[p]];
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
                    vars[3] = step.time;
                    (e.eval(&vars), "the Tresca bound")
                }
            };
            if !(value.is_finite() && value >= 0.0) {
                return Err(format!(
                    "{what} is {value} at {}, t = {}: it must be finite and ≥ 0",
                    crate::mesh::fmt_point(x),
                    step.time
                ));
            }
            Ok(match &friction.laws[k] {
                FrictionLaw::Coulomb(_) => value * pressing(step, state, p),
                FrictionLaw::Tresca(_) | FrictionLaw::Potential => step.weights[p] * value,
            })
        })
        .collect()
}

/// The tangential rows' slip (their change from `before`, their values at the step's start),
/// accumulated slip, bound force and status after the step (docs/method.md §17): separated
/// where the normal row presses with no force (λ_ν, |λ_ν| where bilateral, below 10⁻¹² of the
/// largest), else stick where |λ_τ| < F (1 − 10⁻⁶), slip at F; |·| the length of the pair's
/// vector in 3D, whose two rows get the same accumulated slip and status.
fn record<const D: usize>(
    step: &FrictionStep<D>,
    state: &mut ContactState,
    (before, accumulated): (&[f64], &[f64]),
    forces: &[f64],
) {
    let (friction, m) = (step.friction, step.weights.len());
    let k_rows = forces.len();
    let pressed: Vec<f64> = friction.normal_row.iter().map(|&p| pressing(step, state, p)).collect();
    // a normal force below 1e-12 of the largest is round-off of a node off the bound
    let largest = pressed.iter().fold(0.0f64, |a, &v| a.max(v));
    let slip: Vec<f64> = (0..k_rows)
        .map(|k| state.normal_displacement[m + k] - before[k])
        .collect();
    let mut rows = FrictionRows {
        slip: slip.clone(),
        accumulated: Vec::with_capacity(k_rows),
        bound: forces.to_vec(),
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

    /// The load-following factor is the projection of this step's load change on the last one:
    /// 0.9 for a load that moves on at 90 % of its pace, 0 for one that turns across or reverses,
    /// 0 where a change is unknown or zero, and at most 2.
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
