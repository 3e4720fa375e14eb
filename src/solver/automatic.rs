//! Automatic steps (docs/method.md §20.4): each step proposed by the controller is solved, its
//! local error estimated, and accepted or taken back and tried again shorter.
//!
//! The estimate: the memory's local error δm_j of the step (src/history, `local_error`) as a
//! displacement, δu = K⁻¹ Σ_j K_j δm_j (one solve with the step's factor, contact left out: the
//! contact only holds the error back), measured against the largest displacement so far,
//! ρ = max|δu| / (tolerance · max|u|). A contact solve that fails is taken back too: a shorter
//! step starts it nearer its solution.

use super::backend::Stiffness;
use super::error::SolveError;
use super::stepper::{FrameSink, Step, Stepper, Written};
use crate::contact::ContactState;
use crate::history::History;
use crate::time::{Automatic, Controller};
use std::sync::atomic::AtomicBool;

/// ρ given to the controller for a step whose contact solve failed: shrink by the most it does.
const FAILED: f64 = 1e6;

/// What a step changes, kept to take it back.
struct Snapshot {
    history: Option<History>,
    contact: Option<ContactState>,
    trend: crate::contact::state::StepTrend,
    displacement: Vec<f64>,
    motion: Vec<f64>,
    memory_displacement: Option<Vec<f64>>,
    outcome: Option<crate::contact::ContactOutcome>,
    /// The lengths of the per-step statistics.
    iterations: usize,
    contacts: usize,
}

impl<const D: usize> Stepper<'_, D> {
    fn snapshot(&self) -> Snapshot {
        Snapshot {
            history: self.history.clone(),
            contact: self.contact.clone(),
            trend: self.contact_cache.trend.clone(),
            displacement: self.displacement.clone(),
            motion: self.motion.clone(),
            memory_displacement: self.memory_displacement.clone(),
            outcome: self.outcome,
            iterations: self.stats.newton_iterations.len(),
            contacts: self.stats.contact.len(),
        }
    }

    fn restore(&mut self, s: Snapshot) {
        self.history = s.history;
        self.contact = s.contact;
        self.contact_cache.trend = s.trend;
        // a kept Newton factor belongs to the step taken back
        self.contact_cache.kept = None;
        self.displacement = s.displacement;
        self.motion = s.motion;
        self.memory_displacement = s.memory_displacement;
        self.outcome = s.outcome;
        self.stats.newton_iterations.truncate(s.iterations);
        self.stats.contact.truncate(s.contacts);
    }

    /// max|δu| of the step just solved (docs/method.md §20.4); `older` is (u_{n−2}, k_{n−1}).
    fn local_error(&mut self, step: Step, older: Option<(&[f64], f64)>) -> Result<f64, SolveError> {
        let Some(history) = &self.history else {
            return Ok(0.0);
        };
        let sim = self.sim;
        let n = self.displacement.len();
        let mut force = vec![0.0; n];
        let (mut dm, mut kdm) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..history.channels() {
            history.local_error(j, &self.displacement, older, &mut dm);
            self.backend.product(sim, Stiffness::Memory(j), &dm, &mut kdm);
            force.iter_mut().zip(&kdm).for_each(|(f, v)| *f += v);
        }
        let held: Option<Vec<usize>> = self.backend.held_unknowns().map(<[usize]>::to_vec);
        let operator = self.operators.get(
            &self.beta,
            step.index,
            &mut *self.backend,
            sim,
            &self.counters,
            &mut self.stats,
        )?;
        for (k, f) in force.iter_mut().enumerate() {
            if sim.dofs.is_prescribed(held.as_ref().map_or(k, |h| h[k])) {
                *f = 0.0;
            } else {
                *f /= operator.scale;
            }
        }
        let mut du = vec![0.0; n];
        operator.solver.solve(&force, &mut du, &self.counters);
        let mut largest = [du.iter().fold(0.0f64, |a, v| a.max(v.abs()))];
        self.backend.sum(&mut largest);
        Ok(largest[0])
    }
}

/// The automatic steps of `spec` (after step 0), handing each accepted step to `sink`.
pub(super) fn run<const D: usize>(
    stepper: &mut Stepper<'_, D>,
    spec: &Automatic,
    sink: &mut dyn FrameSink<D>,
    stop: Option<&AtomicBool>,
    written: &mut Written,
) -> Result<(), SolveError> {
    let sim = stepper.sim;
    if stepper.backend.held_unknowns().is_some() {
        return Err(SolveError::Setup(format!(
            "{}: automatic steps (time.tolerance) run on one process: their error estimate is not distributed yet; \
             run serially, or give the steps (time.steps, or time.first_step with time.steps_per_decade, which \
             the PETSc backend takes)",
            sim.mesh.path.display()
        )));
    }
    let first = Step {
        index: 0,
        time: 0.0,
        size: 0.0,
        output: true,
    };
    let view = stepper.advance(first)?;
    written.step(sim, sink, &view)?;
    let mut largest = stepper.displacement.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut controller = Controller::new(spec.clone());
    let mut older: Option<(Vec<f64>, f64)> = None;
    let mut index = 1;
    while !controller.finished() {
        if written.stopped(&*stepper.backend, stop) {
            return Err(SolveError::Interrupted {
                last_written: written.last,
            });
        }
        let proposal = controller.propose();
        let every =
            sim.output_every.is_some_and(|e| index % e == 0) || (sim.output_every.is_none() && spec.stops.is_empty());
        let step = Step {
            index,
            time: proposal.time,
            size: proposal.size,
            output: proposal.stop || every,
        };
        let before = stepper.snapshot();
        let ratio = match stepper.solve(step) {
            Ok(()) => {
                let error = stepper.local_error(step, older.as_ref().map(|(u, k)| (&u[..], *k)))?;
                let scale = largest.max(stepper.displacement.iter().fold(0.0f64, |a, v| a.max(v.abs())));
                if scale > 0.0 {
                    error / (spec.tolerance * scale)
                } else {
                    0.0
                }
            }
            Err(SolveError::ContactFailed { .. }) if proposal.size > spec.min_step => FAILED,
            Err(e) => return Err(e),
        };
        stepper.stats.rejected_steps += usize::from(ratio > 1.0);
        if ratio > 1.0 {
            stepper.restore(before);
            controller
                .reject(&proposal, ratio)
                .map_err(|needed| SolveError::StepTooSmall {
                    time: proposal.time - proposal.size,
                    size: needed,
                    smallest: spec.min_step,
                })?;
            continue;
        }
        controller.accept(&proposal, ratio);
        largest = largest.max(stepper.displacement.iter().fold(0.0f64, |a, v| a.max(v.abs())));
        older = Some((before.displacement, proposal.size));
        let view = stepper.commit(step)?;
        written.step(sim, sink, &view)?;
        stepper.stats.steps = index;
        index += 1;
        if index > crate::scene::MOST_STEPS {
            return Err(SolveError::StepTooSmall {
                time: proposal.time,
                size: proposal.size,
                smallest: spec.min_step,
            });
        }
    }
    Ok(())
}
