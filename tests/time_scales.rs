//! Real materials' time scales (docs/method.md §20): a published Prony series of 12 terms over 14
//! decades, integrated exactly for a displacement linear over each step, on steps that grow
//! with time, with one factorisation for the run.
//!
//! The material: the relaxation modulus of an asphalt concrete, Gibson, Schwartz, Schapery &
//! Witczak, *Transportation Research Record* 1860 (2003) 3–15, as transcribed in the public data
//! file `relaxation-modulus/Gibson2003.csv` of github.com/rubensocj/viscomodule (E_i in MPa, ρ_i
//! in s; E∞ = 412.8 MPa from the same repository; the transcription is not checked against the
//! paper here), with a constant Poisson's ratio ν = 0.35: bulk and shear relax alike.
//!
//! Every closed form is computed here from the series: the creep compliance D of a relaxation
//! function f(t) = f∞ + Σ f_i e^{−t/ρ_i} inverts its Carson transform F(s) = f∞ + Σ f_i s/(s + 1/ρ_i),
//! whose roots s_j < 0 interlace the poles −1/ρ_i:  D(t) = 1/f∞ + Σ_j e^{s_j t} / (s_j F′(s_j)).

mod common;

use common::{creep_cube, scene, uniaxial_scene, Compliance, ASPHALT, ASPHALT_E_INF, ASPHALT_NU};
use hvi::app::solve_in_memory;
use hvi::mesh::structured::{block, SolidShape};

const E_INF: f64 = ASPHALT_E_INF;
const NU: f64 = ASPHALT_NU;
/// The creep test's uniaxial stress [MPa].
const SIGMA0: f64 = 0.1;

/// The relaxation modulus of `terms` (E_i, ρ_i) with constant ν as a scene's material: κ and G
/// in proportion to E.
fn proportional_material(plane: Option<&str>, e_inf: f64, terms: &[(f64, f64)]) -> String {
    let (kb, kg) = (1.0 / (3.0 * (1.0 - 2.0 * NU)), 1.0 / (2.0 * (1.0 + NU)));
    let series = |factor: f64| {
        let t: Vec<String> = terms
            .iter()
            .map(|(e, rho)| format!("{{ modulus = {:e}, relaxation_time = {rho:e} }}", e * factor))
            .collect();
        format!("{{ long_term = {:e}, terms = [{}] }}", e_inf * factor, t.join(", "))
    };
    format!(
        "[material]\n{}relaxation_modulus = {{ bulk = {}, shear = {} }}\n",
        plane.map_or(String::new(), |p| format!("plane = \"{p}\"\n")),
        series(kb),
        series(kg)
    )
}

/// (t_n, ε_xx(t_n)) of every step written: u_x at x = 1.
fn strains(sim: &hvi::solver::Simulation<3>, sink: &hvi::app::MemorySink) -> Vec<(f64, f64)> {
    let corner = sim
        .mesh
        .points
        .iter()
        .position(|p| (p[0] - 1.0).abs() < 1e-12)
        .expect("a node at x = 1");
    sink.steps
        .iter()
        .map(|s| (s.time, sim.dofs.to_nodal(&s.displacement)[corner][0]))
        .collect()
}

/// The compliance inverts the modulus: D(0) = 1/E(0), D(∞) = 1/E∞, and E * dD = 1 (checked by the
/// trapezoid on a fine log grid, to the grid's accuracy).
#[test]
fn the_creep_compliance_inverts_the_relaxation_modulus() {
    let d = Compliance::of(E_INF, &ASPHALT);
    let e0 = E_INF + ASPHALT.iter().map(|(e, _)| e).sum::<f64>();
    assert!((d.at(0.0) * e0 - 1.0).abs() < 1e-12, "D(0) E(0) = {}", d.at(0.0) * e0);
    assert!((d.at(1e12) * E_INF - 1.0).abs() < 1e-12);
    assert!(e0 / E_INF > 69.0 && e0 / E_INF < 71.0, "E(0)/E∞ = {}", e0 / E_INF);
    // E(t) D(0) + ∫₀ᵗ E(t − s) D′(s) ds = 1 at t = 1 s, by the trapezoid on points spread in log s
    // near s = 0 and in log (t − s) near s = t (where E varies on the scale of τ_min), 10⁵ each
    let modulus = |t: f64| E_INF + ASPHALT.iter().map(|(e, rho)| e * (-t / rho).exp()).sum::<f64>();
    let t = 1.0;
    let n = 100_000;
    let spread = |i: usize| 1e-14 * (0.5 / 1e-14f64).powf(i as f64 / n as f64);
    let mut s: Vec<f64> = std::iter::once(0.0)
        .chain((0..=n).map(spread))
        .chain((0..n).rev().map(|i| t - spread(i)))
        .chain(std::iter::once(t))
        .collect();
    s.dedup();
    let integral: f64 = s
        .windows(2)
        .map(|w| 0.5 * (modulus(t - w[0]) + modulus(t - w[1])) * (d.at(w[1]) - d.at(w[0])))
        .sum();
    let total = modulus(t) * d.at(0.0) + integral;
    assert!((total - 1.0).abs() < 1e-6, "E * dD = {total}");
}

/// Creep of the asphalt under a constant uniaxial stress from 10⁻⁶ τ_min (the first step) to
/// 10 τ_max = 1.5·10⁸ s, 21 decades, on steps growing 19 a decade (382 steps): ε_xx = σ₀ D(t)
/// within 10⁻³ at every step; one factorisation for the run (every step matrix a multiple of K_A,
/// docs/method.md §20.3). On the paper's trapezoid and uniform steps the run was refused (its
/// step bound needs more than 10⁸ steps).
#[test]
fn asphalt_creeps_as_its_compliance_on_growing_steps() {
    let d = Compliance::of(E_INF, &ASPHALT);
    let text = uniaxial_scene(
        &proportional_material(None, E_INF, &ASPHALT),
        "final_time = 1.5e8\nfirst_step = 1.5e-13\nsteps_per_decade = 19",
        &format!("{SIGMA0:e}"),
    );
    let (sim, stats, sink) = solve_in_memory(&scene(&text), creep_cube()).unwrap();
    let series = strains(&sim, &sink);
    assert!(series.len() <= 401, "{} steps", series.len() - 1);
    assert_eq!(stats.factorisations, 1, "one factorisation for the run");
    let mut worst = (0.0f64, 0.0);
    for &(t, e) in &series {
        let error = e / (SIGMA0 * d.at(t)) - 1.0;
        if error.abs() > worst.0.abs() {
            worst = (error, t);
        }
    }
    let (first, last) = (series[1], *series.last().unwrap());
    eprintln!(
        "asphalt creep: {} steps, {} factorisation(s); ε(t₁ = {:e}) = {:.6e}, ε(T) = {:.6e} (σ₀ D: {:.6e}, {:.6e}); \
         worst {:+.2e} at t = {:e}",
        series.len() - 1,
        stats.factorisations,
        first.0,
        first.1,
        last.1,
        SIGMA0 * d.at(first.0),
        SIGMA0 * d.at(last.0),
        worst.0,
        worst.1
    );
    assert!(last.1 > 60.0 * series[0].1, "it creeps 70-fold");
    assert!(
        worst.0.abs() < 1e-3,
        "off σ₀ D(t) by {:+.3e} at t = {:e}",
        worst.0,
        worst.1
    );
    // the uniform trapezoid refuses it, saying why
    let uniform = uniaxial_scene(
        &proportional_material(None, E_INF, &ASPHALT),
        "final_time = 1.5e8\nsteps = 1000\nquadrature = \"trapezoid\"",
        &format!("{SIGMA0:e}"),
    );
    let err = hvi::scene::Scene::from_toml_str(&uniform, "asphalt.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("10⁸ time steps") && err.contains("quadrature = \"exact\""),
        "{err}"
    );
}

/// A held uniaxial strain ε₀ (every face prescribed, u = (ε₀ x, 0, 0)): the reaction on x = 0 is
/// −(κ(t) + 4G(t)/3) ε₀ to round-off at every step, on growing steps and on steps listed at
/// random, one channel or two (bulk and shear relaxing at their own times).
#[test]
fn a_held_strain_relaxes_exactly_on_any_steps() {
    let eps0 = 1e-3;
    let (kb, kg) = (1.0 / (3.0 * (1.0 - 2.0 * NU)), 1.0 / (2.0 * (1.0 + NU)));
    let proportional = proportional_material(None, E_INF, &ASPHALT);
    let own_times = "[material]\nrelaxation_modulus = { bulk = { long_term = 2.0, terms = [{ modulus = 3.0, \
                     relaxation_time = 0.05 }] }, shear = { long_term = 0.1, terms = [{ modulus = 0.5, relaxation_time \
                     = 1e-3 }, { modulus = 0.4, relaxation_time = 2.0 }] } }\n"
        .to_string();
    let modulus = |t: f64, own: bool| {
        if own {
            let k = 2.0 + 3.0 * (-t / 0.05).exp();
            let g = 0.1 + 0.5 * (-t / 1e-3).exp() + 0.4 * (-t / 2.0).exp();
            k + 4.0 * g / 3.0
        } else {
            let e = E_INF + ASPHALT.iter().map(|(e, rho)| e * (-t / rho).exp()).sum::<f64>();
            e * (kb + 4.0 * kg / 3.0)
        }
    };
    let listed = "final_time = 1e3\ntimes = [1e-7, 3e-7, 2e-5, 1e-3, 0.5, 0.51, 7.0, 300.0]";
    for (own, material) in [(false, &proportional), (true, &own_times)] {
        for time in ["final_time = 1e8\nfirst_step = 1e-9\nsteps_per_decade = 3", listed] {
            let mut text = format!("{material}[time]\n{time}\n");
            for g in ["Gamma1", "Gamma2", "Gamma3", "Sides"] {
                text += &format!(
                    "[[dirichlet]]\ngroup = \"{g}\"\ncomponents = [\"x\", \"y\", \"z\"]\nvalue = [\"{eps0:e}*x\", \"0\", \"0\"]\n"
                );
            }
            let (_, stats, _) = solve_in_memory(&scene(&text), block([1.0; 3], [2, 2, 2], SolidShape::Hex)).unwrap();
            let mut worst = 0.0f64;
            let mut count = 0;
            for r in stats
                .reactions
                .iter()
                .filter(|r| r.group == "Gamma1" && r.component == "x")
            {
                let want = -modulus(r.time, own) * eps0;
                worst = worst.max((r.force / want - 1.0).abs());
                count += 1;
            }
            eprintln!(
                "held strain (two channels: {own}), {}: {count} steps, worst {worst:.1e}",
                time.replace('\n', "; ")
            );
            assert!(count >= 9, "{count} steps");
            assert!(
                worst < 1e-12,
                "a held strain is off the relaxation modulus by {worst:e}"
            );
        }
    }
}

/// Bulk and shear creeping at their own times (two channels): under a uniaxial stress
/// ε_xx = σ₀ (D_κ/9 + D_G/3), D_κ and D_G the compliances of κ(t) and G(t); within 10⁻³ at every
/// step on steps growing 25 a decade from 10⁻⁷ s to 10⁴ s (20 a decade: 9.3e-4). The step matrix is no multiple of one
/// matrix: its sizes are held on the ladder k₁ 2^j, and the run factorises about 3.3 matrices a
/// decade, each once (docs/method.md §20.3).
#[test]
fn bulk_and_shear_creep_at_their_own_times() {
    let bulk = (2.0e3, vec![(3.0e3, 1e-5), (1.0e3, 0.1)]);
    let shear = (20.0, vec![(600.0, 1e-6), (300.0, 1e-3), (80.0, 1.0), (30.0, 100.0)]);
    let series = |(long, terms): &(f64, Vec<(f64, f64)>)| {
        let t: Vec<String> = terms
            .iter()
            .map(|(m, rho)| format!("{{ modulus = {m:e}, relaxation_time = {rho:e} }}"))
            .collect();
        format!("{{ long_term = {long:e}, terms = [{}] }}", t.join(", "))
    };
    let material = format!(
        "[material]\nrelaxation_modulus = {{ bulk = {}, shear = {} }}\n",
        series(&bulk),
        series(&shear)
    );
    let text = uniaxial_scene(
        &material,
        "final_time = 1e4\nfirst_step = 1e-7\nsteps_per_decade = 25",
        &format!("{SIGMA0:e}"),
    );
    let (sim, stats, sink) = solve_in_memory(&scene(&text), creep_cube()).unwrap();
    assert_eq!(sim.materials.memory().unwrap().channels().len(), 2);
    let (dk, dg) = (Compliance::of(bulk.0, &bulk.1), Compliance::of(shear.0, &shear.1));
    let exact = |t: f64| SIGMA0 * (dk.at(t) / 9.0 + dg.at(t) / 3.0);
    let mut worst = (0.0f64, 0.0);
    let run = strains(&sim, &sink);
    for &(t, e) in &run {
        let error = e / exact(t) - 1.0;
        if error.abs() > worst.0.abs() {
            worst = (error, t);
        }
    }
    eprintln!(
        "two channels: {} steps, {} distinct sizes, {} step matrices, {} factorisations; worst {:+.2e} at t = {:e}",
        run.len() - 1,
        stats.distinct_steps,
        stats.step_matrices,
        stats.factorisations,
        worst.0,
        worst.1
    );
    assert!(
        worst.0.abs() < 1e-3,
        "off the closed form by {:+.3e} at t = {:e}",
        worst.0,
        worst.1
    );
    // 11 decades: about 3.3 sizes a decade, the last step cut to land, and K_A of step 0
    assert!(stats.factorisations <= 40, "{} factorisations", stats.factorisations);
    assert_eq!(stats.factorisations, stats.step_matrices, "each step matrix once");
}

/// ε_xx of the asphalt cube under σ(t) = σ₀ for t < t₁, 0 until t₂, σ₀ after (unloaded and
/// reloaded), by superposition: σ₀ (D(t) − H(t − t₁) D(t − t₁) + H(t − t₂) D(t − t₂)).
fn unloaded_and_reloaded(d: &Compliance, t: f64, t1: f64, t2: f64) -> f64 {
    let h = |s: f64| if s >= 0.0 { d.at(s) } else { 0.0 };
    SIGMA0 * (d.at(t) - h(t - t1) + h(t - t2))
}

/// A load history with jumps, on automatic steps (docs/method.md §20.4): the asphalt cube pulled
/// by σ₀, unloaded at t₁ = 10 s and pulled again at t₂ = 10³ s, to T = 10⁶ s. The steps find the
/// jumps alone (steps rejected there, and cut to below the relaxation times the jump excites),
/// and every accepted step is within 2·10⁻³ of the largest strain of the closed form (measured
/// 9.7e-4 in 532 steps, 35 rejected). Steps growing geometrically from the same first step, more
/// of them, are not (3.9e-2 in 936): their steps across the jumps are as long as the times then.
#[test]
fn automatic_steps_follow_a_load_that_jumps() {
    let d = Compliance::of(E_INF, &ASPHALT);
    let (t1, t2) = (10.0, 1e3);
    let stress = format!("{SIGMA0:e}*(t < {t1:e} || t >= {t2:e})");
    let material = proportional_material(None, E_INF, &ASPHALT);
    let largest = SIGMA0 * d.at(1e6);
    let worst = |time: &str| {
        let text = uniaxial_scene(&material, time, &stress);
        let (sim, stats, sink) = solve_in_memory(&scene(&text), creep_cube()).unwrap();
        let run = strains(&sim, &sink);
        let worst = run
            .iter()
            .map(|&(t, e)| ((e - unloaded_and_reloaded(&d, t, t1, t2)).abs() / largest, t))
            .fold((0.0f64, 0.0), |w, x| if x.0 > w.0 { x } else { w });
        (worst, run.len() - 1, stats)
    };
    let ((error, at), steps, stats) = worst("final_time = 1e6\ntolerance = 1e-4");
    eprintln!(
        "jumps, automatic steps: {steps} steps ({} rejected), {} factorisation(s); worst {error:.2e} of the largest \
         strain at t = {at:e}",
        stats.rejected_steps, stats.factorisations
    );
    assert!(stats.rejected_steps > 0, "the jumps cut the steps");
    assert_eq!(stats.factorisations, 1);
    assert!(error < 2e-3, "automatic steps: {error:e} at t = {at:e}");
    let growth = 10f64.powf(1.0 / (2.0 * steps as f64 / 14.0));
    let geometric = format!("final_time = 1e6\nfirst_step = 1.5e-8\ngrowth = {growth}");
    let ((error, at), steps_geometric, _) = worst(&geometric);
    eprintln!("jumps, geometric steps: {steps_geometric} steps; worst {error:.2e} at t = {at:e}");
    assert!(steps_geometric > steps, "{steps_geometric} against {steps}");
    assert!(error > 2e-3, "geometric steps miss the jumps: {error:e}");
}

/// Automatic steps that cannot meet the tolerance above the smallest step stop with a message that
/// names the time, the size needed, `time.min_step` and what to do (docs/method.md §20.4): the
/// jump of the test above with steps no shorter than a second.
#[test]
fn automatic_steps_below_their_smallest_are_an_error() {
    let text = uniaxial_scene(
        &proportional_material(None, E_INF, &ASPHALT),
        "final_time = 1e3\ntolerance = 1e-4\nfirst_step = 1.0\nmin_step = 1.0",
        &format!("{SIGMA0:e}*(t < 10.5)"),
    );
    let e = solve_in_memory(&scene(&text), creep_cube())
        .err()
        .expect("refused")
        .to_string();
    for part in [
        "automatic steps would need a step of",
        "time.min_step = 1.000e0",
        "time.tolerance",
        "output.times",
    ] {
        assert!(e.contains(part), "`{part}` missing from: {e}");
    }
}
