//! From a validated scene and a mesh to a solved time series: the [`Simulation`] holds the
//! discrete problem with only the effects the scene names, [`plan::Plan`] says what they cost,
//! and [`timeloop`] is the short driver of docs/method.md §3–4.

pub mod advice;
mod automatic;
pub mod backend;
pub mod bound;
mod columns;
pub mod contact;
pub mod dirichlet;
pub mod error;
pub mod faer;
pub mod materials;
pub mod memory;
pub mod operator;
mod operators;
mod pairs;
pub mod plan;
pub mod reactions;
pub mod rigid;
pub mod schedule;
pub mod setup;
pub mod stats;
pub mod step;
mod stepper;
pub mod timeloop;

pub use backend::{Backend, Stiffness};
pub use error::SolveError;
pub use operator::{singular, singularity_verdict, Singularity};
pub use plan::Plan;
pub use setup::{ContactSetup, Schedule, Simulation, TimeGrid};
pub use stats::{PhaseTimes, Reaction, RunStats};
pub use timeloop::Step;
pub use timeloop::{FrameSink, StepView};
