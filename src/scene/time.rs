//! `[time]` and `output.times` (docs/method.md §20, docs/scenes.md "Time steps"): which way of
//! stepping the scene asks for, its values in range, and the memory's quadrature.

use super::error::{invalid, SceneError};
use super::types::{QuadratureSpec, Scene, TimeSpec};
use crate::material::{Quadrature, Rules};
use crate::time::Stepping;

/// More levels than this is surely a typo (a fixed grid holds its levels; automatic steps stop
/// there too).
pub const MOST_STEPS: usize = 100_000_000;

/// The keys of `pairs` (key, given) that are given, in order: what a message about keys that
/// exclude each other names.
pub(super) fn given_keys<'a>(pairs: &[(&'a str, bool)]) -> Vec<&'a str> {
    pairs.iter().filter(|(_, g)| *g).map(|(k, _)| *k).collect()
}

/// A positive, finite value of `time.<key>`.
fn positive(origin: &str, key: &str, v: Option<f64>) -> Result<Option<f64>, SceneError> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(invalid(
            origin,
            &format!("time.{key}"),
            x,
            "give a positive, finite value",
        )),
        _ => Ok(v),
    }
}

impl TimeSpec {
    /// The quadrature rules `time.quadrature` asks for (docs/method.md §20.2).
    pub fn rules(&self) -> Rules {
        Rules::asked(self.quadrature.map(|q| match q {
            QuadratureSpec::Trapezoid => Quadrature::Trapezoid,
            QuadratureSpec::Exact => Quadrature::Exact,
        }))
    }

    /// The way of stepping the keys ask for: exactly one of `steps`, `first_step` with
    /// `steps_per_decade` or `growth`, `times`, `tolerance`; each value in range.
    pub fn stepping(&self, origin: &str) -> Result<Stepping, SceneError> {
        let t = self.final_time;
        if !(t.is_finite() && t > 0.0) {
            return Err(invalid(origin, "time.final_time", t, "the final time must be positive"));
        }
        let given = given_keys(&[
            ("steps", self.steps.is_some()),
            ("first_step", self.first_step.is_some() && self.tolerance.is_none()),
            ("times", self.times.is_some()),
            ("tolerance", self.tolerance.is_some()),
        ]);
        let ways = "steps = N (uniform), first_step = k₁ with steps_per_decade = s or growth = g (steps growing \
                    with time), times = [t₁, t₂, …] (listed), or tolerance = e (automatic steps)";
        if given.len() != 1 {
            let (key, value) = match given.first() {
                Some(k) => (
                    format!("time.{k}"),
                    format!("(with time.{})", given[1..].join(", time.")),
                ),
                None => ("time".into(), "(no steps)".into()),
            };
            return Err(invalid(
                origin,
                &key,
                value,
                &format!("say how to step in exactly one way: {ways} (docs/scenes.md, \"Time steps\")"),
            ));
        }
        let only_with = |key: &str, set: bool, with: &str| {
            if set {
                Err(invalid(
                    origin,
                    &format!("time.{key}"),
                    "(given)",
                    &format!("time.{key} belongs to {with}; remove it, or step that way ({ways})"),
                ))
            } else {
                Ok(())
            }
        };
        let geometric = self.first_step.is_some() && self.tolerance.is_none();
        only_with(
            "steps_per_decade",
            self.steps_per_decade.is_some() && !geometric,
            "steps growing from time.first_step",
        )?;
        only_with(
            "growth",
            self.growth.is_some() && !geometric,
            "steps growing from time.first_step",
        )?;
        only_with(
            "min_step",
            self.min_step.is_some() && self.tolerance.is_none(),
            "automatic steps (time.tolerance)",
        )?;
        only_with(
            "max_step",
            self.max_step.is_some() && self.tolerance.is_none(),
            "automatic steps (time.tolerance)",
        )?;
        let first = positive(origin, "first_step", self.first_step)?;
        if let Some(k) = first.filter(|&k| k >= t) {
            return Err(invalid(
                origin,
                "time.first_step",
                k,
                &format!("the first step must be shorter than time.final_time = {t}"),
            ));
        }
        if let Some(n) = self.steps {
            if n == 0 {
                return Err(invalid(origin, "time.steps", 0, "at least one time step is needed"));
            }
            if n > MOST_STEPS {
                return Err(invalid(origin, "time.steps", n, "more than 10⁸ steps is surely a typo"));
            }
            return Ok(Stepping::Uniform { steps: n });
        }
        if let Some(times) = &self.times {
            if times.is_empty() || times.len() > MOST_STEPS {
                return Err(invalid(
                    origin,
                    "time.times",
                    format!("({} times)", times.len()),
                    "list the time levels after 0, increasing, up to time.final_time",
                ));
            }
            let mut last = 0.0;
            for (i, &v) in times.iter().enumerate() {
                if !(v.is_finite() && v >= 0.0 && (v > last || (i == 0 && v == 0.0)) && v <= t * (1.0 + 1e-12)) {
                    return Err(invalid(
                        origin,
                        &format!("time.times[{i}]"),
                        v,
                        &format!("the times must increase from 0 up to time.final_time = {t}"),
                    ));
                }
                last = v;
            }
            return Ok(Stepping::Listed { times: times.clone() });
        }
        if let Some(tolerance) = self.tolerance {
            if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < 1.0) {
                return Err(invalid(
                    origin,
                    "time.tolerance",
                    tolerance,
                    "give the local error allowed per step, relative to the largest displacement: a number in \
                     (0, 1), e.g. 1e-3",
                ));
            }
            let (min, max) = (
                positive(origin, "min_step", self.min_step)?,
                positive(origin, "max_step", self.max_step)?,
            );
            if let (Some(lo), Some(hi)) = (min.or(first), max) {
                if lo > hi {
                    return Err(invalid(
                        origin,
                        "time.max_step",
                        hi,
                        &format!("the largest step is below the smallest ({lo})"),
                    ));
                }
            }
            return Ok(Stepping::Automatic {
                tolerance,
                first,
                min,
                max,
            });
        }
        let first = first.expect("geometric: first_step given");
        let growth = match (self.steps_per_decade, self.growth) {
            (Some(s), None) if s.is_finite() && s >= 0.1 => 10f64.powf(1.0 / s),
            (None, Some(g)) if (1.0..=100.0).contains(&g) => g,
            (Some(s), None) => {
                return Err(invalid(
                    origin,
                    "time.steps_per_decade",
                    s,
                    "give the number of steps per decade of time, at least 0.1 (e.g. 10: each step 26 % longer)",
                ))
            }
            (None, Some(g)) => {
                return Err(invalid(
                    origin,
                    "time.growth",
                    g,
                    "give the factor each step grows by, from 1 (uniform) to 100, e.g. 1.2",
                ))
            }
            (Some(_), Some(_)) => {
                return Err(invalid(
                    origin,
                    "time.growth",
                    "(with time.steps_per_decade)",
                    "give the growth once: time.steps_per_decade or time.growth",
                ))
            }
            (None, None) => {
                return Err(invalid(
                    origin,
                    "time.first_step",
                    first,
                    "steps growing from time.first_step need time.steps_per_decade (e.g. 10) or time.growth (e.g. \
                     1.2); for automatic steps give time.tolerance",
                ))
            }
        };
        Ok(Stepping::Geometric { first, growth })
    }
}

/// The keys of each way of stepping (docs/scenes.md "Time steps").
const UNIFORM: &[&str] = &["steps"];
const GEOMETRIC: &[&str] = &["first_step", "steps_per_decade", "growth"];
const LISTED: &[&str] = &["times"];
const AUTOMATIC: &[&str] = &["tolerance", "first_step", "min_step", "max_step"];

/// `--set` of a way of stepping replaces the scene file's (`--set time.tolerance=1e-3` on a scene
/// with `steps = 32` asks for automatic steps instead, not for both): the file's keys of the other
/// ways that no `--set` gives are dropped from the tree before it is read.
pub(super) fn replace_stepping(tree: &mut toml::Value, overrides: &[String]) {
    let set: Vec<String> = overrides
        .iter()
        .filter_map(|o| o.split_once('=').map(|(k, _)| k.trim().to_string()))
        .filter_map(|k| k.strip_prefix("time.").map(str::to_string))
        .collect();
    let has = |k: &str| set.iter().any(|s| s == k);
    let file_has = |tree: &toml::Value, k: &str| tree.get("time").and_then(|t| t.get(k)).is_some();
    let mode: &[&str] = if has("tolerance") || has("min_step") || has("max_step") {
        AUTOMATIC
    } else if has("steps") {
        UNIFORM
    } else if has("times") {
        LISTED
    } else if has("steps_per_decade") || has("growth") {
        GEOMETRIC
    } else if has("first_step") && file_has(tree, "tolerance") {
        AUTOMATIC
    } else if has("first_step") {
        GEOMETRIC
    } else {
        return;
    };
    if let Some(time) = tree.get_mut("time").and_then(|t| t.as_table_mut()) {
        for key in UNIFORM.iter().chain(GEOMETRIC).chain(LISTED).chain(AUTOMATIC) {
            if !mode.contains(key) && !has(key) {
                time.remove(*key);
            }
        }
    }
}

/// `[time]`, `time.quadrature` against the memory, and `output.times`.
pub fn check(scene: &Scene, origin: &str) -> Result<Stepping, SceneError> {
    let stepping = scene.time.stepping(origin)?;
    if scene.time.quadrature == Some(QuadratureSpec::Exact) {
        for c in scene.constants() {
            for (i, m) in c.memory.iter().enumerate() {
                if let super::types::MemoryKernelSpec::Expression { expression } = &m.kernel {
                    return Err(invalid(
                        origin,
                        "time.quadrature",
                        "\"exact\"",
                        &format!(
                            "{} = \"{expression}\" is an expression kernel, which has no exact rule (its history is \
                             the trapezoid's direct sum, docs/method.md §5); use \"trapezoid\", or write the kernel \
                             as a Prony series (kind = \"exponential\")",
                            c.memory_key(i)
                        ),
                    ));
                }
            }
        }
    }
    let t = scene.time.final_time;
    for (i, &v) in scene.output.times.iter().enumerate() {
        if !(v.is_finite() && v >= 0.0 && v <= t * (1.0 + 1e-12)) {
            return Err(invalid(
                origin,
                &format!("output.times[{i}]"),
                v,
                &format!("an output time lies in [0, time.final_time = {t}]"),
            ));
        }
    }
    if scene.output.every == Some(0) {
        return Err(invalid(origin, "output.every", 0, "write every n-th step with n ≥ 1"));
    }
    Ok(stepping)
}
