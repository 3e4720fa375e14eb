//! Errors of setting up and running a simulation.

use crate::mesh::MeshError;
use crate::scene::SceneError;

/// What can stop a run, each with what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error(transparent)]
    Mesh(#[from] MeshError),
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
    #[error("contact solve failed at step {step} (t = {time}): {reason}; residual {residual:.3e} after {iterations} iterations (tolerance {tolerance:.1e}). Try: a smaller time step (`--set time.steps=...`), a larger `contact.law.regularisation`, or more `solver.max_iterations`")]
    ContactFailed {
        step: usize,
        time: f64,
        iterations: usize,
        residual: f64,
        tolerance: f64,
        reason: String,
    },
    #[error("step {step} (t = {time}): the load {detail}")]
    NonFiniteLoad { step: usize, time: f64, detail: String },
    /// A result that is not finite: the data overflow double precision (a load of 1e300), or
    /// something not finite got past the checks.
    #[error("step {step} (t = {time}) produced a non-finite {what}: the results overflow double precision or the data are not finite; check the load expressions and material data of the scene (work in units in which loads and moduli are moderate numbers)")]
    NonFinite { step: usize, time: f64, what: String },
    #[error("run interrupted; {}", match last_written { Some(n) => format!("the frames up to step {n} and the .pvd listing them are valid"), None => "no frame was written".to_string() })]
    Interrupted { last_written: Option<usize> },
    /// The predicted peak does not fit the memory this process may use (docs/method.md §16.1).
    #[error("out of memory: {0}")]
    OutOfMemory(String),
    #[error("{0}")]
    Setup(String),
}
