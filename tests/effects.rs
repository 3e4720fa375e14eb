//! Effects as optional scene sections (issue 5): every scene of `examples/scenes/` parses and
//! runs; switching an effect off equals setting it to its neutral value; the recursive history
//! equals the direct sum; an effect that is not in the scene costs nothing (asserted through the
//! counters of `RunStats`, not by timing); and the plan lists exactly the effects in force.
//!
//! The performance floors of the issue are measured by `cargo bench --bench history_scaling`.

use hvi::app::{solve_in_memory, MemorySink};
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::{read_mesh, Mesh};
use hvi::scene::{ContactLawSpec, ContactSpec, LawKind, MemoryKernelSpec, Scene};
use hvi::solver::{Plan, RunStats, Simulation};
use std::path::{Path, PathBuf};

/// Relative tolerance of the equivalence tests: max over all frames and unknowns of
/// |u − u_twin| divided by max |u| (round-off: the two runs do the same arithmetic up to adding
/// exact zeros and one extra solve against a contact force at round-off level).
const EQUIVALENCE_TOL: f64 = 1e-12;

/// Relative tolerance of "recursive history = direct sum" over N = 1000 steps (same norm).
const HISTORY_TOL: f64 = 1e-11;

/// Every scene of `examples/scenes/`, with the effects it must put in force.
const SCENES: &[(&str, Effects)] = &[
    ("elastic_only.toml", Effects::new(None, false, false, Loads::Constant)),
    (
        "elastic_time_dependent.toml",
        Effects::new(None, false, false, Loads::TimeDependent),
    ),
    (
        "memory_only.toml",
        Effects::new(Some("polynomial"), false, false, Loads::TimeDependent),
    ),
    (
        "memory_prony.toml",
        Effects::new(Some("exponential"), false, false, Loads::TimeDependent),
    ),
    (
        "memory_expression.toml",
        Effects::new(Some("direct sum"), false, false, Loads::TimeDependent),
    ),
    ("bound_only.toml", Effects::new(None, true, false, Loads::TimeDependent)),
    (
        "compliance_only.toml",
        Effects::new(None, false, true, Loads::TimeDependent),
    ),
    ("power_law.toml", Effects::new(None, false, true, Loads::TimeDependent)),
    (
        "piecewise_linear.toml",
        Effects::new(None, true, true, Loads::TimeDependent),
    ),
    ("tabulated.toml", Effects::new(None, true, true, Loads::TimeDependent)),
    ("body_force.toml", Effects::new(None, true, false, Loads::TimeDependent)),
    (
        "full.toml",
        Effects::new(Some("polynomial"), true, true, Loads::TimeDependent),
    ),
];

#[derive(Clone, Copy, Debug, PartialEq)]
enum Loads {
    Constant,
    TimeDependent,
}

/// The effects a scene names: the history algorithm (None = no memory), bound, law, loads.
#[derive(Clone, Copy, Debug)]
struct Effects {
    history: Option<&'static str>,
    bound: bool,
    law: bool,
    loads: Loads,
}

impl Effects {
    const fn new(history: Option<&'static str>, bound: bool, law: bool, loads: Loads) -> Self {
        Effects {
            history,
            bound,
            law,
            loads,
        }
    }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scene_path(name: &str) -> PathBuf {
    root().join("examples/scenes").join(name)
}

fn load(name: &str, overrides: &[String]) -> Scene {
    let path = scene_path(name);
    Scene::load(Some(&path), overrides).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn mesh(name: &str) -> Mesh<2> {
    let path = root().join("meshes").join(name);
    read_mesh::<2>(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A tiny mesh of the paper's domain (4 × 2 Q1 cells: 30 unknowns, 5 contact nodes).
fn tiny_mesh() -> Mesh<2> {
    rectangle(2.0, 1.0, 4, 2, CellShape::Quad)
}

fn steps(n: usize) -> Vec<String> {
    vec![format!("time.steps={n}")]
}

fn run(what: &str, scene: &Scene, mesh: Mesh<2>) -> (Simulation<2>, RunStats, MemorySink) {
    solve_in_memory(scene, mesh).unwrap_or_else(|e| panic!("{what}: {e}"))
}

/// max over frames of ‖u_a − u_b‖∞ / max over frames of ‖u_a‖∞ (frames must match).
fn relative_difference(a: &MemorySink, b: &MemorySink) -> f64 {
    assert_eq!(a.steps.len(), b.steps.len(), "different numbers of frames");
    assert!(!a.steps.is_empty(), "no frame: nothing compared");
    let mut diff = 0.0f64;
    let mut scale = 0.0f64;
    for (fa, fb) in a.steps.iter().zip(&b.steps) {
        assert_eq!(fa.step, fb.step);
        assert_eq!(fa.time, fb.time);
        assert_eq!(fa.displacement.len(), fb.displacement.len());
        for (x, y) in fa.displacement.iter().zip(&fb.displacement) {
            diff = diff.max((x - y).abs());
            scale = scale.max(x.abs());
        }
    }
    assert!(
        scale > 0.0,
        "the runs compared have zero displacement: the comparison would be vacuous"
    );
    diff / scale
}

/// max over frames of ‖λ_a − λ_b‖∞ (nodal contact forces; a run without contact counts as λ = 0),
/// relative to max over frames of ‖F_n‖∞ (the nodal load) — the force scale of the problem.
fn contact_force_difference(sim: &Simulation<2>, a: &MemorySink, b: &MemorySink) -> f64 {
    let mut load = vec![0.0; sim.dofs.n()];
    let mut scale = 0.0f64;
    let mut diff = 0.0f64;
    assert_eq!(a.steps.len(), b.steps.len(), "different numbers of frames");
    assert!(!a.steps.is_empty(), "no frame: nothing compared");
    for (fa, fb) in a.steps.iter().zip(&b.steps) {
        sim.loads.assemble(fa.time, &sim.dofs, &mut load).unwrap();
        scale = scale.max(load.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        let force = |f: &hvi::app::StoredStep| f.contact.as_ref().map(|c| c.force.clone());
        match (force(fa), force(fb)) {
            (Some(x), Some(y)) => {
                assert_eq!(x.len(), y.len(), "different contact nodes");
                x.iter().zip(&y).for_each(|(p, q)| diff = diff.max((p - q).abs()));
            }
            (Some(x), None) | (None, Some(x)) => x.iter().for_each(|p| diff = diff.max(p.abs())),
            (None, None) => {}
        }
    }
    diff / scale.max(f64::MIN_POSITIVE)
}

fn all_finite(sink: &MemorySink) -> bool {
    sink.steps.iter().all(|s| {
        s.displacement.iter().all(|v| v.is_finite())
            && s.memory_displacement.iter().flatten().all(|v| v.is_finite())
            && s.contact
                .iter()
                .all(|c| c.force.iter().chain(&c.normal_displacement).all(|v| v.is_finite()))
    })
}

// ---------------------------------------------------------------------------------------------
// Every scene parses and runs.

#[test]
fn scene_directory_holds_exactly_the_listed_scenes() {
    let mut found: Vec<String> = std::fs::read_dir(root().join("examples/scenes"))
        .expect("examples/scenes")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    found.sort();
    let mut listed: Vec<String> = SCENES.iter().map(|(n, _)| n.to_string()).collect();
    listed.sort();
    assert_eq!(
        found, listed,
        "every scene in examples/scenes must be listed (and so tested) here"
    );
}

#[test]
fn every_scene_parses_and_runs_with_finite_results() {
    for (name, _) in SCENES {
        let scene = load(name, &steps(4));
        assert_eq!(scene.time.steps, Some(4));
        let (sim, stats, sink) = run(name, &scene, mesh("rect_q1_h8.msh"));
        assert_eq!(sink.steps.len(), 5, "{name}: frames");
        assert_eq!(stats.frames_written, 5, "{name}: frames");
        assert!(all_finite(&sink), "{name}: non-finite values");
        let last = &sink.steps[4];
        assert_eq!(last.time, scene.time.final_time, "{name}: last frame at T");
        assert!(
            last.displacement.iter().any(|v| *v != 0.0),
            "{name}: the loaded body does not move"
        );
        if let Some(c) = &sim.contact {
            assert!(
                stats.max_contact_residual <= c.settings.tolerance,
                "{name}: contact residual {:e}",
                stats.max_contact_residual
            );
        }
    }
}

/// Each scene as shipped (its own number of steps) on the mesh its header names.
#[test]
fn every_scene_runs_as_shipped_on_the_documented_mesh() {
    for (name, _) in SCENES {
        let scene = load(name, &[]);
        let (_, stats, sink) = run(name, &scene, mesh("rect_q1_h16.msh"));
        assert_eq!(sink.steps.len(), scene.time.steps.unwrap() + 1, "{name}");
        assert!(all_finite(&sink), "{name}: non-finite values");
        assert!(stats.max_contact_residual <= scene.solver.tolerance, "{name}");
    }
}

/// `hvi solve meshes/rect_q1_h16.msh --scene examples/scenes/X.toml` works for every scene
/// (through the binary, so the tabulated law's CSV is found relative to the scene file).
#[test]
fn every_scene_runs_through_the_command_line() {
    let out = tempfile::tempdir().unwrap();
    for (name, _) in SCENES {
        let dir = out.path().join(name.trim_end_matches(".toml"));
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_hvi"))
            .current_dir(root())
            .args(["solve", "meshes/rect_q1_h16.msh", "--scene"])
            .arg(Path::new("examples/scenes").join(name))
            .arg("--out")
            .arg(&dir)
            .args(["--set", "time.steps=8"])
            .output()
            .expect("run hvi");
        assert!(
            status.status.success(),
            "hvi solve --scene examples/scenes/{name}: {}\n{}",
            status.status,
            String::from_utf8_lossy(&status.stderr)
        );
        assert!(
            dir.join("summary.json").is_file() && dir.join("solution.pvd").is_file(),
            "{name}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Equivalence: an effect switched off = the effect at its neutral value.

/// The neutral values: kernel b ≡ 0, bound g = 10⁶ (no node comes near), law scale S = 0.
const NEUTRAL_BOUND: f64 = 1e6;

fn neutral_kernel() -> MemoryKernelSpec {
    MemoryKernelSpec::Polynomial {
        coefficients: vec![0.0],
    }
}

/// The paper's law with S = 0.
fn neutral_law() -> ContactLawSpec {
    ContactLawSpec {
        kind: LawKind::Paper {
            scale: 0.0,
            a: 0.04,
            b: 0.02,
            alpha: 100.0,
        },
        one_sided: false,
        regularisation: 1e-8,
    }
}

fn law_with_zero_scale(law: &ContactLawSpec) -> ContactLawSpec {
    let mut law = law.clone();
    match &mut law.kind {
        LawKind::Paper { scale, .. }
        | LawKind::Power { scale, .. }
        | LawKind::PiecewiseLinear { scale, .. }
        | LawKind::Tabulated { scale, .. } => *scale = 0.0,
    }
    law
}

/// Which of the three switchable effects are off.
#[derive(Clone, Copy, Debug)]
struct Off {
    memory: bool,
    bound: bool,
    law: bool,
}

impl Off {
    fn all() -> impl Iterator<Item = Off> {
        (0..8).map(|b| Off {
            memory: b & 1 != 0,
            bound: b & 2 != 0,
            law: b & 4 != 0,
        })
    }
    fn name(&self) -> String {
        let mut on = vec![];
        if !self.memory {
            on.push("memory");
        }
        if !self.bound {
            on.push("bound");
        }
        if !self.law {
            on.push("law");
        }
        if on.is_empty() {
            "elastic only".into()
        } else {
            on.join(" + ")
        }
    }
}

/// `full` with the effects in `off` removed from the scene (absent sections).
fn switched_off(full: &Scene, off: Off) -> Scene {
    let mut s = full.clone();
    if off.memory {
        s.memory.clear();
    }
    let c = s.contact.first_mut().expect("full scene has contact");
    if off.bound {
        c.bound = None;
    }
    if off.law {
        c.law = None;
    }
    if off.bound && off.law {
        s.contact.clear();
    }
    s
}

/// `full` with the effects in `off` kept but set to their neutral values.
fn neutralised(full: &Scene, off: Off) -> Scene {
    let mut s = full.clone();
    if off.memory {
        s.memory = vec![neutral_kernel().into()];
    }
    let c = s.contact.first_mut().expect("full scene has contact");
    if off.bound {
        c.bound = Some(NEUTRAL_BOUND.into());
    }
    if off.law {
        c.law = Some(law_with_zero_scale(c.law.as_ref().expect("full scene has a law")));
    }
    s
}

/// Completes a scene with every absent effect at its neutral value (its "neutral twin").
fn with_neutral_effects(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    if s.memory.is_empty() {
        s.memory.push(neutral_kernel().into());
    }
    if s.contact.is_empty() {
        s.contact.push(ContactSpec::default());
    }
    let c = &mut s.contact[0];
    c.bound.get_or_insert(NEUTRAL_BOUND.into());
    c.law.get_or_insert_with(neutral_law);
    s
}

fn assert_equivalent(what: &str, off: &Scene, neutral: &Scene, mesh: &Mesh<2>) -> (f64, f64) {
    let (sim_off, stats_off, a) = run(&format!("{what} (switched off)"), off, mesh.clone());
    let (sim_neutral, stats_neutral, b) = run(&format!("{what} (neutral twin)"), neutral, mesh.clone());
    // the switched-off run really has fewer effects than its twin
    assert!(stats_off.effects.len() <= stats_neutral.effects.len(), "{what}");
    assert!(
        sim_off.materials.memory().is_none() || sim_neutral.materials.memory().is_some(),
        "{what}"
    );
    let du = relative_difference(&a, &b);
    let dl = contact_force_difference(&sim_neutral, &a, &b);
    println!("{what}: relative difference of u {du:.2e}, of contact forces {dl:.2e}");
    assert!(
        du <= EQUIVALENCE_TOL,
        "{what}: displacement differs from its neutral twin by {du:e} (relative) > {EQUIVALENCE_TOL:e}"
    );
    assert!(
        dl <= EQUIVALENCE_TOL,
        "{what}: contact force differs from its neutral twin by {dl:e} (relative to the load) > {EQUIVALENCE_TOL:e}"
    );
    (du, dl)
}

/// The paper scene with each subset of {memory, bound, law} switched off (absent) against the
/// paper scene with that subset at its neutral value (kernel [0.0], g = 10⁶, S = 0): all eight
/// combinations, including memory-only, bound-only, compliance-only and elastic-only.
#[test]
fn switching_an_effect_off_equals_its_neutral_value() {
    let full = load("full.toml", &steps(16));
    let mesh = mesh("rect_q1_h8.msh");
    for off in Off::all() {
        let a = switched_off(&full, off);
        let b = neutralised(&full, off);
        assert_equivalent(&format!("paper scene, {}", off.name()), &a, &b, &mesh);
    }
}

/// Every example scene against the same scene with all absent effects added at their neutral
/// values (this covers constant loads, where the effect-free run solves once and the twin
/// solves every step, and the other law kinds and the body force).
#[test]
fn every_example_scene_equals_its_neutral_twin() {
    let mesh = mesh("rect_q1_h8.msh");
    for (name, _) in SCENES {
        let scene = load(name, &steps(16));
        let twin = with_neutral_effects(&scene);
        if name == &"full.toml" {
            continue; // nothing is absent
        }
        assert_equivalent(name, &scene, &twin, &mesh);
    }
}

// ---------------------------------------------------------------------------------------------
// The recursive history equals the direct sum.

/// Full runs over N = 1000 steps on a tiny mesh: the paper kernel (0.5 + s)² as `polynomial`
/// (recursive moments) and as `expression` (direct sum), and a Prony series as `exponential`
/// (recursive accumulators) and as `expression`; without and with contact. The trapezoid for
/// all (an expression has no exact rule; the exact rule's recursions are tested against the
/// integrals they stand for in src/history/tests.rs).
#[test]
fn recursive_history_equals_direct_sum_over_1000_steps() {
    let n = 1000;
    let cases = [
        (
            MemoryKernelSpec::Polynomial {
                coefficients: vec![0.25, 1.0, 1.0],
            },
            "(0.5 + s)^2",
        ),
        (
            MemoryKernelSpec::Exponential {
                terms: vec![
                    hvi::scene::PronyTerm {
                        coefficient: 0.5,
                        relaxation_time: 0.1,
                    },
                    hvi::scene::PronyTerm {
                        coefficient: 0.25,
                        relaxation_time: 1.0,
                    },
                ],
            },
            "0.5*exp(-s/0.1) + 0.25*exp(-s/1.0)",
        ),
    ];
    for base in ["memory_only.toml", "full.toml"] {
        let mut scene = load(base, &steps(n));
        scene.time.quadrature = Some(hvi::scene::QuadratureSpec::Trapezoid);
        for (kernel, expression) in &cases {
            let mut recursive = scene.clone();
            recursive.memory = vec![kernel.clone().into()];
            let mut direct = scene.clone();
            direct.memory = vec![MemoryKernelSpec::Expression {
                expression: expression.to_string(),
            }
            .into()];
            let what = format!("{base} with b(s) = {expression}");
            let (_, sr, a) = run(&what, &recursive, tiny_mesh());
            let (_, sd, b) = run(&what, &direct, tiny_mesh());
            assert!(
                sr.history_algorithm.as_deref().unwrap().starts_with("recursive"),
                "{what}"
            );
            assert_eq!(sd.history_algorithm.as_deref(), Some("direct sum"), "{what}");
            assert_eq!(a.steps.len(), n + 1);
            let d = relative_difference(&a, &b);
            println!("{what}: recursive vs direct sum over N = {n}: relative difference {d:.2e}");
            assert!(
                d <= HISTORY_TOL,
                "{what}: recursive history differs from the direct sum by {d:e} > {HISTORY_TOL:e}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// What is not in the scene costs nothing (counters, not timing).

#[test]
fn elastic_only_allocates_no_history_factorises_once_and_solves_once() {
    for n in [10, 1000] {
        let scene = load("elastic_only.toml", &steps(n));
        let (sim, stats, sink) = run("elastic_only", &scene, mesh("rect_q1_h8.msh"));
        assert!(
            sim.materials.memory().is_none() && sim.contact.is_none(),
            "nothing but elasticity is built"
        );
        assert!(!sim.loads.is_time_dependent());
        assert_eq!(stats.history_bytes, 0, "no history");
        assert_eq!(stats.history_algorithm, None, "no history");
        assert_eq!(stats.factorisations, 1, "K_A factorised once");
        assert_eq!(stats.contact_solves, 0, "no contact solve");
        assert!(stats.contact.is_empty() && stats.newton_iterations.is_empty());
        assert_eq!(
            stats.solves, 1,
            "constant loads, no memory: one solve for all {n} steps"
        );
        assert_eq!(stats.frames_written, n + 1, "still one frame per step");
        assert_eq!(sink.steps.len(), n + 1);
        let first = &sink.steps[0].displacement;
        assert!(first.iter().any(|v| *v != 0.0));
        assert!(
            sink.steps.iter().all(|s| &s.displacement == first),
            "the same state at every step"
        );
        assert_eq!(sink.steps[n].time, scene.time.final_time);
    }
}

#[test]
fn elastic_time_dependent_solves_once_per_step_with_one_factor() {
    let n = 50;
    let scene = load("elastic_time_dependent.toml", &steps(n));
    let (_, stats, sink) = run("elastic_time_dependent", &scene, mesh("rect_q1_h8.msh"));
    assert_eq!(stats.history_bytes, 0);
    assert_eq!(stats.history_algorithm, None);
    assert_eq!(stats.factorisations, 1);
    assert_eq!(stats.contact_solves, 0);
    assert_eq!(stats.solves, n + 1, "one solve per step, steps 0..=N");
    assert_eq!(sink.steps.len(), n + 1);
}

/// Contact without memory: one factorisation, the condensation (m sparse forward sweeps once),
/// and per step one solve (a forward and a backward sweep) around one contact solve.
#[test]
fn contact_without_memory_costs_one_factorisation_and_one_solve_per_step() {
    let n = 20;
    for name in ["bound_only.toml", "compliance_only.toml"] {
        let scene = load(name, &steps(n));
        let (sim, stats, _) = run(name, &scene, mesh("rect_q1_h8.msh"));
        let m = sim.contact.as_ref().unwrap().nodes.len();
        assert_eq!(stats.history_bytes, 0, "{name}");
        assert_eq!(stats.history_algorithm, None, "{name}");
        assert_eq!(stats.factorisations, 1, "{name}");
        assert_eq!(stats.contact_solves, n + 1, "{name}");
        assert_eq!(stats.sparse_forward_sweeps, m, "{name}: condensation");
        assert_eq!(stats.solves, n + 1, "{name}: one solve per step");
    }
}

#[test]
fn separable_history_is_independent_of_n_and_the_direct_sum_grows() {
    let mesh = mesh("rect_q1_h8.msh");
    let bytes = |name: &str, n: usize| {
        let (sim, stats, _) = run(name, &load(name, &steps(n)), mesh.clone());
        assert_eq!(stats.contact_solves, 0, "{name}: memory only");
        (sim.dofs.n(), stats)
    };
    // one vector per kernel term, and the last step's displacement (the trapezoid's weight of
    // u_{n−1} needs k_n, the exact rule's carry needs u_{n−1}: docs/method.md §20.2)
    for (name, vectors, algorithm) in [
        ("memory_only.toml", 3 + 1, "recursive (polynomial moments)"),
        (
            "memory_prony.toml",
            2 + 1,
            "recursive (exponential accumulators, exact)",
        ),
    ] {
        let (n_dof, s10) = bytes(name, 10);
        let (_, s1000) = bytes(name, 1000);
        assert_eq!(s10.history_algorithm.as_deref(), Some(algorithm), "{name}");
        assert_eq!(
            s10.history_bytes,
            vectors * n_dof * 8,
            "{name}: one vector per kernel term and u_{{n−1}}"
        );
        assert_eq!(
            s1000.history_bytes, s10.history_bytes,
            "{name}: history memory independent of N"
        );
        // F_0 = 0 (the load has the factor 1 − e^{−2t}): u_0 = 0 without a solve or a factor of
        // K_A; then one factor of K = K_A + (k/2) b(0) K_B and one solve per step n = 1..=N.
        assert_eq!((s10.factorisations, s1000.factorisations), (1, 1), "{name}");
        assert_eq!((s10.solves, s1000.solves), (10, 1000), "{name}: one solve per step");
    }
    let (n_dof, s10) = bytes("memory_expression.toml", 10);
    let (_, s1000) = bytes("memory_expression.toml", 1000);
    assert_eq!(s10.history_algorithm.as_deref(), Some("direct sum"));
    assert_eq!(s10.history_bytes, (11 + 1) * n_dof * 8, "every u_n kept, and u_{{n−1}}");
    assert_eq!(
        s1000.history_bytes,
        (1001 + 1) * n_dof * 8,
        "every u_n kept, and u_{{n−1}}"
    );
}

/// The plan of every scene lists exactly the effects the scene names; `summary.json`'s
/// `effects` (RunStats) is the same list; absent sections build nothing.
#[test]
fn the_plan_lists_exactly_the_effects_in_force() {
    for (name, want) in SCENES {
        let scene = load(name, &steps(4));
        let sim = Simulation::new(&scene, mesh("rect_q1_h8.msh")).unwrap_or_else(|e| panic!("{name}: {e}"));
        let plan = Plan::new(&sim);
        let mut names = plan.effect_names();
        names.sort();
        let mut expected = vec!["elasticity", "loads"];
        if want.history.is_some() {
            expected.push("memory");
        }
        if want.bound || want.law {
            expected.push("contact");
        }
        expected.sort();
        assert_eq!(names, expected, "{name}: plan {plan}");
        assert_eq!(
            sim.materials.memory().is_some(),
            want.history.is_some(),
            "{name}: kernel built"
        );
        assert_eq!(sim.contact.is_some(), want.bound || want.law, "{name}: contact built");
        let detail = |effect: &str| {
            plan.effects
                .iter()
                .find(|e| e.name == effect)
                .map(|e| format!("{} {}", e.detail, e.cost))
                .unwrap_or_default()
        };
        if let Some(c) = &sim.contact {
            assert_eq!(c.bound.is_some(), want.bound, "{name}: bound");
            assert_eq!(c.law().is_some(), want.law, "{name}: law");
            assert_eq!(
                detail("contact").contains("bound"),
                want.bound,
                "{name}: {}",
                detail("contact")
            );
            assert_eq!(
                detail("contact").contains("compliance law"),
                want.law,
                "{name}: {}",
                detail("contact")
            );
        }
        if let Some(h) = want.history {
            assert!(detail("memory").contains(h), "{name}: {}", detail("memory"));
        }
        let constant = want.loads == Loads::Constant;
        assert_eq!(sim.loads.is_time_dependent(), !constant, "{name}");
        assert_eq!(
            detail("loads").contains("constant in time"),
            constant,
            "{name}: {}",
            detail("loads")
        );
        assert_eq!(plan.solves_per_step == 0, constant && want.history.is_none(), "{name}");
        // summary.json records the same effects, and the history it reports matches the plan
        let (_, stats, _) = run(name, &scene, sim.mesh.clone());
        assert_eq!(stats.effects, plan.effect_names(), "{name}");
        match want.history {
            None => assert_eq!(
                (stats.history_algorithm.as_deref(), stats.history_bytes),
                (None, 0),
                "{name}"
            ),
            Some(h) => assert!(stats.history_algorithm.as_deref().unwrap().contains(h), "{name}"),
        }
        if !(want.bound || want.law) {
            assert_eq!(stats.contact_solves, 0, "{name}");
        }
    }
}
