//! Errors of setting up and running a simulation.

use crate::mesh::MeshError;
use crate::scene::SceneError;

/// What can stop a run, each with what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A group the scene names, at `key`, is missing from the mesh or not where it must be.
    #[error("{origin}: `{key}`: {source}")]
    Group {
        origin: String,
        key: String,
        #[source]
        source: Box<MeshError>,
    },
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A [`FrameSink`](super::FrameSink) could not take a frame (the output layer's errors
    /// convert into this; the solver does not know them).
    #[error("{0}")]
    Sink(Box<dyn std::error::Error + Send + Sync>),
    #[error("{mesh}: the clamped group {group} has no nodes, so the body can move freely and the problem is singular; tag the clamped boundary (Γ₁) in the mesh or set `groups.clamped` in the scene")]
    NoClampedNodes { mesh: String, group: String },
    #[error("{mesh}: {detail}")]
    Singular { mesh: String, detail: String },
    /// A load that the force-controlled groups and the contact cannot balance (docs/method.md
    /// §7.7).
    #[error("step {step} (t = {time}): {detail}")]
    Unbalanced { step: usize, time: f64, detail: String },
    /// The contact solve of a step did not converge; `advice` is [`contact_failure_advice`]'s.
    #[error("contact solve failed at step {step} (t = {time}): {reason}; residual {residual:.3e} after {iterations} iterations (tolerance {tolerance:.1e}). {advice}")]
    ContactFailed {
        step: usize,
        time: f64,
        iterations: usize,
        residual: f64,
        tolerance: f64,
        reason: String,
        advice: String,
    },
    /// A load that is not finite at a step (None: a time automatic steps may meet, checked
    /// before the run).
    #[error("{} (t = {time}): the load {detail}", step.map_or("before the run".to_string(), |n| format!("step {n}")))]
    NonFiniteLoad {
        step: Option<usize>,
        time: f64,
        detail: String,
    },
    /// A result that is not finite: the data overflow double precision (a load of 1e300), or
    /// something not finite got past the checks.
    #[error("step {step} (t = {time}) produced a non-finite {what}: the results overflow double precision or the data are not finite; check the load expressions and material data of the scene (work in units in which loads and moduli are moderate numbers)")]
    NonFinite { step: usize, time: f64, what: String },
    /// Automatic steps that cannot meet the tolerance above the smallest step (docs/method.md §20.4).
    #[error("at t = {time} automatic steps would need a step of {size:.3e} to meet time.tolerance, below the smallest step time.min_step = {smallest:.3e}: the displacement changes faster there than the memory can follow at this tolerance (a load that jumps, contact that snaps); allow smaller steps (time.min_step), loosen time.tolerance, or put a time level where the load jumps (output.times)")]
    StepTooSmall { time: f64, size: f64, smallest: f64 },
    #[error("run interrupted; {}", match last_written { Some(n) => format!("the frames up to step {n} and the .pvd listing them are valid"), None => "no frame was written".to_string() })]
    Interrupted { last_written: Option<usize> },
    /// The predicted peak does not fit the memory this process may use (docs/method.md §16.1).
    #[error("out of memory: {0}")]
    OutOfMemory(String),
    #[error("{0}")]
    Setup(String),
}

/// What to do when a contact solve fails having reached at best the relative residual
/// `smallest` (docs/method.md §16.4). Far from converged: smaller steps, more regularisation or
/// iterations. Within reach but above `tolerance` by no more than round-off can explain (below
/// 10⁻⁶): the residual has stalled at the round-off of the condensed operator's scale (a thin
/// plate, very different stiffnesses), which none of those lower: name the tolerance where the
/// solve converges, the stall level rounded up to a power of ten.
pub fn contact_failure_advice(smallest: f64, tolerance: f64) -> String {
    if smallest.is_finite() && smallest > tolerance && smallest < 1e-6 {
        let suggested = 10f64.powf((2.0 * smallest).log10().ceil());
        format!(
            "The residual stalled at {smallest:.1e}, the round-off level of the condensed contact operator for this \
             body (an ill-conditioned one: a thin plate, or parts of very different stiffness); smaller steps or \
             more regularisation do not lower it. Set `solver.tolerance = {suggested:.0e}` (`--set \
             solver.tolerance={suggested:.0e}`)"
        )
    } else {
        "Try: a smaller time step (`--set time.steps=...`), a larger `contact.law.regularisation`, or more \
         `solver.max_iterations`"
            .to_string()
    }
}

/// A mesh error about the group the scene names at `key` (of the scene `origin`), as a
/// [`SolveError::Group`] that says where the name came from; other errors unchanged.
pub fn group_error(origin: &str, key: &str) -> impl Fn(MeshError) -> SolveError {
    let (origin, key) = (origin.to_string(), key.to_string());
    move |e| match e {
        MeshError::GroupNotFound { .. } | MeshError::NotBoundary { .. } => SolveError::Group {
            origin: origin.clone(),
            key: key.clone(),
            source: Box::new(e),
        },
        e => SolveError::Mesh(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stall_near_the_tolerance_names_a_tolerance_above_it() {
        let advice = contact_failure_advice(1.7e-9, 1e-10);
        assert!(advice.contains("solver.tolerance = 1e-8"), "{advice}");
        let advice = contact_failure_advice(1e-9, 1e-10);
        assert!(advice.contains("solver.tolerance = 1e-8"), "{advice}");
        // far from converged: the usual remedies
        assert!(contact_failure_advice(0.7, 1e-10).contains("smaller time step"));
        assert!(contact_failure_advice(f64::NAN, 1e-10).contains("smaller time step"));
    }
}
