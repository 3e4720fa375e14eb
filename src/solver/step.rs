//! One time step with a backend (docs/method.md §3–4, §7): the lifting of prescribed values,
//! the solve d = C K⁻¹ rhs, contact → λ, u_n = K⁻¹ (rhs − Cᵀ λ), and the reactions.

use super::backend::{Backend, Stiffness};
use super::error::SolveError;
use super::operator::{Lifting, StepOperator};
use super::reactions::{Reactions, StepState};
use super::setup::{ContactSetup, Simulation};
use super::stats::{timed, RunStats};
use crate::contact::{ActiveSetSolver, ContactOutcome, ContactProblem, ContactState, SolverCache};
use crate::contact::{Condensation, NormalStiffness, WithCompliance};
use crate::linalg::Counters;

/// What one solve of a step reads and writes.
pub(super) struct StepSolve<'a> {
    pub step: usize,
    /// t_n.
    pub time: f64,
    pub rhs: &'a [f64],
    /// The prescribed part of u_ν (None when it is zero).
    pub offset: Option<&'a [f64]>,
    /// f̃ summed over each rigid parameter's unknowns before the lifting (empty without them,
    /// docs/method.md §7.7).
    pub rigid_loads: &'a [f64],
    /// Receives a, the rigid parameters' motions (empty without them).
    pub motion: &'a mut [f64],
    /// Receives u_n.
    pub u: &'a mut [f64],
    /// The contact state, and the solver's caches beside it.
    pub state: Option<(&'a mut ContactState, &'a mut SolverCache)>,
}

/// Solves one step: d = C K⁻¹ rhs, contact → λ, u_n = K⁻¹ (rhs − Cᵀ λ) (docs/method.md
/// §3–4), with the rigid parameters' motions a found with λ and added (§7.7).
pub(super) fn solve<const D: usize>(
    operator: &mut StepOperator,
    sim: &Simulation<D>,
    backend: &dyn Backend<D>,
    StepSolve {
        step,
        time: t,
        rhs,
        offset,
        rigid_loads,
        motion,
        u,
        state,
    }: StepSolve,
    counters: &Counters,
    stats: &mut RunStats,
) -> Result<Option<ContactOutcome>, SolveError> {
    // K = s M with M factorised (docs/method.md §20.3): M u = rhs/s at the free rows, the
    // contact forces λ/s
    let scale = operator.scale;
    let scaled: Vec<f64>;
    let solved_rhs: &[f64] = if scale == 1.0 {
        rhs
    } else {
        let held = backend.held_unknowns();
        scaled = rhs
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                if sim.dofs.is_prescribed(held.map_or(k, |h| h[k])) {
                    v
                } else {
                    v / scale
                }
            })
            .collect();
        &scaled
    };
    // p̂ = P(t) − R⁰: what the rigid parameters must balance
    let balance = match &operator.rigid {
        Some(rigid) => {
            let forces: Vec<f64> = sim.dirichlet.rigid.iter().map(|p| p.force_at(t)).collect();
            Some(
                rigid
                    .balance(&forces, rhs, offset, rigid_loads)
                    .map_err(|detail| super::rigid::unbalanced(step, t, detail))?,
            )
        }
        None => None,
    };
    match (&sim.contact, operator.condensed.as_mut(), state) {
        (Some(setup), Some(op), Some((state, cache))) => {
            let mut d = vec![0.0; setup.condensed_rows().len()];
            timed(&mut stats.phases.forward_sweep, || {
                op.free_normal(solved_rhs, &mut d, counters)
            });
            if let Some(g) = offset {
                setup.condensed_rows().prescribed_offset(g, &mut d);
            }
            // (a backend may solve on one process and share the result)
            let outcome = timed(&mut stats.phases.contact, || {
                let local = if backend.solves_contact() {
                    // the free contact forces q = Q d (Q̂ d + Q D_a S⁺ p̂ with rigid parameters)
                    let mut q = vec![0.0; d.len()];
                    op.stiffness().apply_q(&d, &mut q);
                    if let (Some(rigid), Some(p)) = (&operator.rigid, &balance) {
                        rigid.contact_load(p, &mut q);
                    }
                    contact_solve(
                        sim,
                        setup,
                        op.as_ref(),
                        operator.rigid.is_some(),
                        (step, t),
                        &q,
                        (&mut *state, &mut *cache),
                    )
                } else {
                    Ok(ContactOutcome::default())
                };
                backend.share_contact(state, local)
            })?;
            stats.contact_solves += 1;
            if let (Some(rigid), Some(p)) = (&mut operator.rigid, &balance) {
                let moved: Vec<f64> = state.normal_displacement.iter().zip(&d).map(|(r, d)| r - d).collect();
                rigid.solve_values(p, &moved);
            }
            timed(&mut stats.phases.backward_sweep, || {
                if scale == 1.0 {
                    op.recover(&state.force, u, counters)
                } else {
                    let force: Vec<f64> = state.force.iter().map(|f| f / scale).collect();
                    op.recover(&force, u, counters)
                }
            });
            if let Some(rigid) = &operator.rigid {
                rigid.add_motion(u);
                motion.copy_from_slice(rigid.values());
            }
            Ok(Some(outcome))
        }
        _ => {
            timed(&mut stats.phases.backward_sweep, || {
                operator.solver.solve(solved_rhs, u, counters)
            });
            if let (Some(rigid), Some(p)) = (&mut operator.rigid, &balance) {
                rigid.solve_values(p, &[]);
                rigid.add_motion(u);
                motion.copy_from_slice(rigid.values());
            }
            Ok(None)
        }
    }
}

/// The group totals of R = K_A u_n + Σ_j K_j m_n^j − F_n + Cᵀ λ (collective with a
/// backend that holds a share of the unknowns).
pub(super) fn reactions<'a, const D: usize>(
    r: &'a mut Reactions,
    sim: &Simulation<D>,
    backend: &dyn Backend<D>,
    state: StepState,
) -> &'a [f64] {
    if r.k_a.is_some() {
        r.through_columns(sim, state);
    } else {
        reactions_through_products(r, sim, backend, state);
    }
    // an overlap row takes back what its groups count twice (docs/method.md §7.5)
    for (total, g) in r.totals.iter_mut().zip(&sim.dirichlet.reaction_groups) {
        *total *= g.weight;
    }
    &r.totals
}

/// R over the held unknowns through the backend's products.
fn reactions_through_products<const D: usize>(
    reactions: &mut Reactions,
    sim: &Simulation<D>,
    backend: &dyn Backend<D>,
    StepState {
        u,
        memory,
        load,
        contact,
    }: StepState,
) {
    let global = |k: usize| backend.held_unknowns().map_or(k, |held| held[k]);
    let mut r = vec![0.0; u.len()];
    backend.product(sim, Stiffness::Elastic, u, &mut r);
    if let Some(m) = memory {
        for (j, m) in m.chunks_exact(u.len()).enumerate() {
            let mut y = vec![0.0; u.len()];
            backend.product(sim, Stiffness::Memory(j), m, &mut y);
            r.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
        }
    }
    // Cᵀλ at the prescribed unknowns: the prescribed parts of the contact rows.
    let mut force: std::collections::HashMap<usize, f64> = std::collections::HashMap::new();
    if let (Some(c), Some(state)) = (&sim.contact, contact) {
        for (l, fixed) in state.force.iter().zip(c.condensed_rows().prescribed_rows()) {
            for &(d, coefficient) in fixed {
                *force.entry(d).or_insert(0.0) += l * coefficient;
            }
        }
    }
    for (total, members) in reactions.totals.iter_mut().zip(&reactions.groups) {
        *total = members
            .iter()
            .map(|&k| r[k] + force.get(&global(k)).copied().unwrap_or(0.0) - load[k])
            .sum();
    }
    backend.sum(&mut reactions.totals);
}

fn contact_solve<const D: usize>(
    sim: &Simulation<D>,
    setup: &ContactSetup<D>,
    op: &dyn Condensation,
    op_singular: bool,
    (step, t): (usize, f64),
    q: &[f64],
    (state, cache): (&mut ContactState, &mut SolverCache),
) -> Result<ContactOutcome, SolveError> {
    // a moving obstacle moves the laws' origins and the bounds (docs/method.md §14.2)
    let moved = setup.gaps_at(t).map_err(|detail| SolveError::NonFiniteLoad {
        step: Some(step),
        time: t,
        detail,
    })?;
    let (offset, bound) = match &moved {
        Some((o, g)) => (Some(&o[..]), Some(&g[..])),
        None => (setup.gap.as_deref(), setup.bound.as_deref()),
    };
    let solved = match &setup.friction {
        // with friction: the tangential rows join the solve (docs/method.md §17)
        Some(friction) => crate::contact::friction::solve(
            &crate::contact::friction::FrictionStep {
                friction,
                operator: op.stiffness(),
                offset,
                bound,
                singular: op_singular,
                bilateral: setup.bilateral.as_deref(),
                normal_laws: &setup.laws,
                weights: &setup.nodes.weights,
                nodes: &setup.nodes.nodes,
                points: &sim.mesh.points,
                time: t,
                settings: setup.settings,
            },
            q,
            state,
            cache,
        ),
        None => {
            let operator = WithCompliance(op);
            let problem = ContactProblem {
                offset,
                bound,
                singular: op_singular,
                fixed: setup.bilateral.as_deref(),
                ..ContactProblem::new(&operator, &setup.laws)
            };
            ActiveSetSolver {
                settings: setup.settings,
                trace: crate::contact::trace::sink(setup.settings.trace),
            }
            .solve_forces(&problem, q, state, cache)
        }
    };
    let failure = match solved {
        Ok(outcome) => return Ok(outcome),
        Err(f) => f,
    };
    // A body only its contact holds, every node separated when the solve gave up: the load
    // pulls it off its support, and no contact force can balance that (docs/method.md §7.7).
    let separated = (0..setup.nodes.len()).all(|p| state.normal_displacement[p] <= offset.map_or(0.0, |o| o[p]));
    // with friction the body may instead slide away: a tangential load above what friction
    // holds (docs/method.md §17.7)
    if op_singular && setup.friction.is_some() {
        let motions = sim.dirichlet.held_by_contact.join(", ");
        return Err(super::rigid::unbalanced(
            step,
            t,
            format!(
                "the contact cannot balance the load along {motions}: friction holds at most μ times the normal \
                 force (or the Tresca bound) against a sliding body, and the load exceeds it or pulls the body off \
                 its support; hold the motion with prescribed components, or reduce the tangential load"
            ),
        ));
    }
    if op_singular && separated {
        let mut motions: Vec<String> = sim.dirichlet.held_by_contact.clone();
        motions.extend(
            sim.dirichlet
                .rigid
                .iter()
                .filter(|p| p.group.is_some())
                .map(|p| p.name.clone()),
        );
        return Err(super::rigid::unbalanced(
            step,
            t,
            format!(
                "the contact cannot balance the load: it pulls the body off its support, every contact node \
                 separates, and nothing else holds {} (a one-sided law or a bound only pushes); hold it with \
                 prescribed components, or reverse the load",
                motions.join(", ")
            ),
        ));
    }
    Err(SolveError::ContactFailed {
        step,
        time: t,
        iterations: failure.outcome.iterations,
        residual: failure.outcome.residual,
        tolerance: setup.settings.tolerance,
        reason: failure.reason,
        advice: super::error::contact_failure_advice(failure.smallest_residual, setup.settings.tolerance),
    })
}

/// The prescribed components in a right-hand side (docs/method.md §7): rhs_f −= K_fp g at the
/// free rows, rhs_p = g_p at the prescribed ones (zero without non-zero values). `g` is over
/// all unknowns, `rhs` over the backend's held ones ([`Backend::held_unknowns`]).
pub(super) fn lift<const D: usize>(
    op: &StepOperator,
    sim: &Simulation<D>,
    g: Option<&[f64]>,
    rhs: &mut [f64],
    backend: &dyn Backend<D>,
) {
    let held = backend.held_unknowns();
    let global = |k: usize| held.map_or(k, |u| u[k]);
    // the columns of the matrix factorised: K's are `op.scale` times them (docs/method.md §20.3)
    match (g, &op.lifting) {
        (Some(g), Some(Lifting::Columns(columns))) if op.scale == 1.0 => columns.lift(g, &sim.dofs, rhs),
        (Some(g), Some(Lifting::Columns(columns))) => {
            let scaled: Vec<f64> = g.iter().map(|v| v * op.scale).collect();
            columns.lift(&scaled, &sim.dofs, rhs)
        }
        (Some(g), Some(Lifting::Products { memory })) => {
            // K g with g zero at the free unknowns is Σ_j K_ij g_j over the prescribed j.
            let g_held: Vec<f64> = (0..rhs.len()).map(|k| g[global(k)]).collect();
            let mut kg = vec![0.0; g_held.len()];
            backend.product(sim, Stiffness::Elastic, &g_held, &mut kg);
            for (j, c) in memory.iter().enumerate() {
                let mut y = vec![0.0; g_held.len()];
                backend.product(sim, Stiffness::Memory(j), &g_held, &mut y);
                kg.iter_mut().zip(&y).for_each(|(a, v)| *a += c * v);
            }
            for (k, (r, v)) in rhs.iter_mut().zip(&kg).enumerate() {
                if !sim.dofs.is_prescribed(global(k)) {
                    *r -= op.scale * v;
                }
            }
        }
        _ => {}
    }
    for (k, r) in rhs.iter_mut().enumerate() {
        let d = global(k);
        if sim.dofs.is_prescribed(d) {
            *r = g.map_or(0.0, |g| g[d]);
        }
    }
}
