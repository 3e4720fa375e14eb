//! The schedule of a run from its scene and materials (docs/method.md §20.1, §20.4): the stepping
//! `[time]` asks for, the output times as levels, steps on the ladder k₁ 2^j where each size
//! costs a factorisation, and the automatic steps' defaults.

use super::error::SolveError;
use crate::fem::materials::Materials;
use crate::scene::Scene;
use crate::time::{Automatic, Growth, Schedule, Stepping, TimeGrid};

/// The first automatic step, as a fraction of the shortest relaxation time (or of T without
/// one): the memory's fastest term is resolved from the start, and a first step too small costs
/// only the few steps that double it (docs/method.md §20.4).
pub const FIRST_STEP_OF_SHORTEST_TIME: f64 = 0.1;
/// The smallest automatic step, as a fraction of the first: a load that jumps needs steps below
/// the shortest relaxation time to be followed within the tolerance (docs/method.md §20.4).
pub const SMALLEST_OF_FIRST: f64 = 1e-4;

/// The automatic steps' first step when `[time]` gives none: a tenth of the shortest relaxation
/// time of the Prony terms, at most a tenth of T (docs/method.md §20.4). Also the lower end of a
/// study's compared times (src/study).
pub fn default_first_step(final_time: f64, shortest_relaxation_time: Option<f64>) -> f64 {
    (FIRST_STEP_OF_SHORTEST_TIME * shortest_relaxation_time.unwrap_or(final_time)).min(0.1 * final_time)
}

/// The schedule of `scene` for `materials`; `proportional` when every step matrix is a multiple
/// of one (then sizes need not repeat).
pub fn build(scene: &Scene, materials: &Materials, proportional: bool) -> Result<Schedule, SolveError> {
    let origin = &scene.origin;
    let stepping = scene
        .time
        .stepping(origin)
        .map_err(|e| SolveError::Setup(e.to_string()))?;
    let t = scene.time.final_time;
    let outputs = &scene.output.times;
    let grid_error = |key: &str| {
        let key = key.to_string();
        move |e: crate::time::grid::GridError| SolveError::Setup(format!("{origin}: `{key}`: {}", e.0))
    };
    let growth = if proportional { Growth::Smooth } else { Growth::Ladder };
    Ok(match stepping {
        Stepping::Uniform { steps } => Schedule::Fixed(
            TimeGrid::uniform(t, steps)
                .with_outputs(outputs)
                .map_err(grid_error("output.times"))?,
        ),
        Stepping::Listed { times } => Schedule::Fixed(
            TimeGrid::listed(t, &times)
                .map_err(grid_error("time.times"))?
                .with_outputs(outputs)
                .map_err(grid_error("output.times"))?,
        ),
        Stepping::Geometric { first, growth: g } => Schedule::Fixed(
            TimeGrid::geometric(t, first, g, growth, outputs, crate::scene::MOST_STEPS)
                .map_err(grid_error("time.first_step"))?,
        ),
        Stepping::Automatic {
            tolerance,
            first,
            min,
            max,
        } => {
            let shortest = materials.memory().and_then(|m| m.shortest_relaxation_time());
            let first_step = first.unwrap_or(default_first_step(t, shortest));
            let mut stops: Vec<f64> = outputs.iter().copied().filter(|&s| s > 0.0 && s < t).collect();
            stops.sort_by(f64::total_cmp);
            stops.dedup();
            Schedule::Automatic(Automatic {
                final_time: t,
                tolerance,
                first_step,
                min_step: min.unwrap_or(SMALLEST_OF_FIRST * first_step).min(first_step),
                max_step: max.unwrap_or(t),
                stops,
                ladder: !proportional,
            })
        }
    })
}
