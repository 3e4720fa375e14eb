//! What accuracy costs in time for memory (issue 56, docs/method.md §20.5): the steps, the
//! factorisations and the run time each way of stepping needs to reach a relative error of 10⁻³
//! on two problems with the asphalt concrete of examples/gallery/asphalt (12 Prony terms, 14
//! decades):
//!
//! * **creep**: the unit cube under a constant uniaxial stress from 1.5·10⁻¹³ s (10⁻⁶ τ_min) to
//!   1.5·10⁸ s (10 τ_max), against the creep compliance at every step;
//! * **indentation**: the gallery's sphere from a microsecond to a year, against Lee & Radok (the
//!   elastic state under P E(0) D(t)) at its 15 frames, relative to the largest u_ν.
//!
//! Ways: the paper's trapezoid on uniform steps (refused: its step bound), the exact rule on
//! uniform steps, on steps growing s a decade, and automatic steps to a tolerance. For each the
//! cheapest level of a ladder that reaches 10⁻³ (or the finest tried, when none does), then its
//! run time as the median of `HVI_BENCH_REPS` (default 5) runs interleaved with the others'.
//!
//!     cargo bench --bench time_scales
//!
//! Prints a markdown table (the one in README and docs/method.md §20.5).

use hvi::app::solve_in_memory;
use hvi::scene::Scene;
use std::path::PathBuf;
use std::time::Instant;

#[path = "../tests/support/creep.rs"]
mod creep;
use creep::{creep_cube, uniaxial_scene, Compliance, ASPHALT};
const E_INF: f64 = creep::ASPHALT_E_INF;
const NU: f64 = creep::ASPHALT_NU;
const SIGMA0: f64 = 0.1;
const TARGET: f64 = 1e-3;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn material() -> String {
    let terms: Vec<String> = ASPHALT
        .iter()
        .map(|(e, rho)| format!("{{ modulus = {e:e}, relaxation_time = {rho:e} }}"))
        .collect();
    format!(
        "[material]\nrelaxation_modulus = {{ poisson_ratio = {NU}, youngs = {{ long_term = {E_INF:e}, terms = [{}] }} }}\n",
        terms.join(", ")
    )
}

/// A way of stepping and its levels, coarse to fine: the `[time]` keys of each.
struct Way {
    name: &'static str,
    levels: Vec<(String, String)>,
}

/// (error, steps, factorisations, seconds) of one run, or the refusal.
type Outcome = Result<(f64, usize, usize, f64), String>;

fn creep(time: &str, d: &Compliance) -> Outcome {
    let text = uniaxial_scene(
        &material(),
        &format!("final_time = 1.5e8\n{time}"),
        &format!("{SIGMA0:e}"),
    );
    let scene = Scene::from_toml_str(&text, "creep.toml").map_err(|e| e.to_string())?;
    let started = Instant::now();
    let (sim, stats, sink) = solve_in_memory(&scene, creep_cube()).map_err(|e| e.to_string())?;
    let seconds = started.elapsed().as_secs_f64();
    let corner = sim.mesh.points.iter().position(|p| (p[0] - 1.0).abs() < 1e-12).unwrap();
    let error = sink
        .steps
        .iter()
        .map(|s| (sim.dofs.to_nodal(&s.displacement)[corner][0] / (SIGMA0 * d.at(s.time)) - 1.0).abs())
        .fold(0.0, f64::max);
    Ok((error, stats.steps, stats.factorisations, seconds))
}

/// The gallery's indentation with `[time]` replaced; the error against Lee & Radok at its frames.
fn indentation(time: &str, d: &Compliance, references: &mut Vec<(f64, Vec<f64>)>) -> Outcome {
    let path = root().join("examples/gallery/asphalt/asphalt.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let start = text.find("[time]").unwrap();
    let end = start + text[start..].find("\n\n").unwrap();
    let text = format!(
        "{}[time]\nfinal_time = 31557600\n{time}{}",
        &text[..start],
        &text[end..]
    );
    let scene = Scene::from_toml_str(&text, "asphalt.toml").map_err(|e| e.to_string())?;
    let force: f64 = scene.force_control[0].force.parse().unwrap();
    let mesh = hvi::mesh::read_mesh::<2>(&root().join("examples/gallery/gel/gel.msh")).unwrap();
    let started = Instant::now();
    let (_, stats, sink) = solve_in_memory(&scene, mesh).map_err(|e| e.to_string())?;
    let seconds = started.elapsed().as_secs_f64();
    let e0 = E_INF + ASPHALT.iter().map(|(e, _)| e).sum::<f64>();
    let mut error = 0.0f64;
    for s in sink.steps.iter().filter(|s| s.time > 0.0) {
        let u = &s.contact.as_ref().unwrap().normal_displacement;
        let reference = match references.iter().find(|(t, _)| (t - s.time).abs() <= 1e-9 * s.time) {
            Some((_, r)) => r.clone(),
            None => {
                let elastic = Scene::from_toml_str(
                    &format!(
                        "[groups]\ncontact = \"Gamma3\"\n[material]\nplane = \"axisymmetric\"\nyoungs_modulus = {e0:e}\n\
                         poisson_ratio = {NU}\n[time]\nfinal_time = 1.0\nsteps = 1\n[[force_control]]\ngroup = \"Base\"\n\
                         component = \"y\"\nforce = \"{:e}\"\n[contact]\nbound = \"1 - sqrt(1 - x^2)\"\n",
                        force * e0 * d.at(s.time)
                    ),
                    "elastic.toml",
                )
                .unwrap();
                let mesh = hvi::mesh::read_mesh::<2>(&root().join("examples/gallery/gel/gel.msh")).unwrap();
                let (_, _, e) = solve_in_memory(&elastic, mesh).unwrap();
                let r = e
                    .steps
                    .last()
                    .unwrap()
                    .contact
                    .as_ref()
                    .unwrap()
                    .normal_displacement
                    .clone();
                references.push((s.time, r.clone()));
                r
            }
        };
        let largest = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        error = error.max(u.iter().zip(&reference).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / largest);
    }
    Ok((error, stats.steps, stats.factorisations, seconds))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let reps: usize = std::env::var("HVI_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let d = Compliance::asphalt();
    let trapezoid = "quadrature = \"trapezoid\"\n";
    let ways = |first: &str, uniform: &[usize]| -> Vec<Way> {
        vec![
            Way {
                name: "trapezoid, uniform steps",
                levels: vec![("N = 10⁶".into(), format!("steps = 1000000\n{trapezoid}"))],
            },
            Way {
                name: "exact, uniform steps",
                levels: uniform
                    .iter()
                    .map(|n| (format!("N = {n}"), format!("steps = {n}\n")))
                    .collect(),
            },
            Way {
                name: "exact, steps growing s a decade",
                levels: [5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 40.0]
                    .iter()
                    .map(|s| {
                        (
                            format!("s = {s}"),
                            format!("first_step = {first}\nsteps_per_decade = {s}\n"),
                        )
                    })
                    .collect(),
            },
            Way {
                name: "exact, automatic steps",
                levels: [1e-3, 3e-4, 1e-4, 3e-5, 1e-5]
                    .iter()
                    .map(|e| (format!("tolerance {e:e}"), format!("tolerance = {e:e}\n")))
                    .collect(),
            },
        ]
    };
    let mut references = Vec::new();
    // (the indentation's uniform runs take 3 ms a step: 10⁴ steps at most; its growing steps start
    // at τ_min/15, as its automatic ones do: from a microsecond the first frame is 1.3e-3 off
    // whatever s, the first step's [0, 1e-6] spanning the fastest relaxation)
    for (problem, first, uniform) in [
        ("creep", "1.5e-13", &[1_000usize, 10_000, 100_000][..]),
        ("indentation", "1e-8", &[10_000usize][..]),
    ] {
        println!("\n{problem}: the cheapest level within {TARGET:e} of each way (median of {reps} runs)\n");
        println!("| way | level | steps | factorisations | error | run [s] |");
        println!("|---|---|--:|--:|--:|--:|");
        let mut chosen: Vec<(&str, String, String)> = Vec::new();
        for way in ways(first, uniform) {
            let mut pick = None;
            for (label, time) in &way.levels {
                let outcome = match problem {
                    "creep" => creep(time, &d),
                    _ => indentation(time, &d, &mut references),
                };
                match outcome {
                    Err(e) => {
                        let short: String = e.chars().take(160).collect();
                        println!("| {} | {label} | refused: {short}… | | | |", way.name);
                        break;
                    }
                    Ok((error, ..)) => {
                        pick = Some((label.clone(), time.clone()));
                        if error <= TARGET {
                            break;
                        }
                    }
                }
            }
            if let Some((label, time)) = pick {
                chosen.push((way.name, label, time));
            }
        }
        // interleaved repetitions of the chosen levels
        let mut seconds: Vec<Vec<f64>> = vec![Vec::new(); chosen.len()];
        let mut last: Vec<(f64, usize, usize)> = vec![(0.0, 0, 0); chosen.len()];
        for _ in 0..reps {
            for (i, (_, _, time)) in chosen.iter().enumerate() {
                let (error, steps, factorisations, s) = match problem {
                    "creep" => creep(time, &d),
                    _ => indentation(time, &d, &mut references),
                }
                .unwrap();
                seconds[i].push(s);
                last[i] = (error, steps, factorisations);
            }
        }
        for (i, (name, label, _)) in chosen.iter().enumerate() {
            let (error, steps, factorisations) = last[i];
            println!(
                "| {name} | {label} | {steps} | {factorisations} | {error:.2e}{} | {:.3} |",
                if error > TARGET { " (not reached)" } else { "" },
                median(seconds[i].clone())
            );
        }
    }
}
