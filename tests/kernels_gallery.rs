//! The gallery entry examples/gallery/relaxation (README "Problems you can pose"): a viscoelastic
//! pad given by its relaxation moduli, held pressed against a rigid cylinder. Run through files
//! as README says, then checked against the closed form of a held indentation with proportional
//! relaxation (docs/method.md §15).

use hvi::app::solve_in_memory;
use hvi::mesh::read_mesh;
use hvi::scene::Scene;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

const MESH: &str = "examples/gallery/relaxation/relaxation.msh";
const SCENE: &str = "examples/gallery/relaxation/relaxation.toml";

/// The scene's relaxation function φ(t) = 1 − Σ_m g_m (1 − e^{−t/τ_m}) (κ and G both ∝ φ).
const TERMS: [(f64, f64); 2] = [(0.4, 0.1), (0.3, 1.0)];

fn phi(t: f64) -> f64 {
    1.0 - TERMS.iter().map(|(g, tau)| g * (1.0 - (-t / tau).exp())).sum::<f64>()
}

/// What the scheme computes for φ(t_n): 1 + k Σ'_{i=0..n} φ′(t_n − t_i), and for one exponential
/// k Σ'_{i=0..n} e^{−ik/τ} = (k/2) coth(k/(2τ)) · τ (1 − e^{−t_n/τ}) exactly (a geometric sum), so
/// φ_n = 1 − Σ_m g_m c_m (1 − e^{−t_n/τ_m}) with c_m = (k/2τ_m) coth(k/2τ_m) = 1 + (k/τ_m)²/12 + O(k⁴).
fn discrete_phi(t: f64, k: f64) -> f64 {
    1.0 - TERMS
        .iter()
        .map(|(g, tau)| {
            let x = k / (2.0 * tau);
            g * (x / x.tanh()) * (1.0 - (-t / tau).exp())
        })
        .sum::<f64>()
}

/// Held indentation and proportional relaxation (Lee & Radok): with u_n = u_0 at every step the
/// memory term is K_A u_0 (φ_n − 1) (one channel ∝ A), so λ_n = φ_n λ_0 satisfies the step's
/// contact conditions on the same contact set (complementarity is invariant under a positive
/// factor), and the step problem is convex, so that is THE discrete solution: the displacement
/// stays that of t = 0 and the contact force is P(0) φ_n. Checked: u to 1e-12, the contact set
/// constant, and P_n/P_0 = φ_n to 1e-10 (the contact solve's tolerance is 1e-10 of the force
/// scale), where φ_n is
/// * with the exact rule (the default for a relaxation modulus), φ(t_n) itself: a held strain is
///   integrated exactly on any steps (docs/method.md §20.2);
/// * with `time.quadrature = "trapezoid"`, the trapezoid's value, whose difference to φ(t_n) is
///   the trapezoidal one, order 2 in k.
#[test]
fn held_indentation_relaxes_the_force_as_the_modulus() {
    // through files, as README's command runs it
    let dir = tempfile::tempdir().unwrap();
    let out: PathBuf = dir.path().join("relaxation");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_hvi"))
        .args(["solve", MESH, "--scene", SCENE, "--out"])
        .arg(&out)
        .current_dir(root())
        .output()
        .unwrap();
    assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
    for f in ["solution.pvd", "contact.pvd", "contact_forces.csv", "summary.json"] {
        assert!(out.join(f).exists(), "{f}");
    }
    let exact = held_force_ratios(&[]);
    let worst = exact.iter().fold(0.0f64, |m, (t, r)| m.max((r - phi(*t)).abs()));
    eprintln!("relaxation gallery, exact rule: max |P/P(0) − φ(t)| = {worst:.2e}");
    assert!(worst <= 1e-10, "the exact rule is off φ(t) by {worst:e}");

    let trapezoid = held_force_ratios(&["time.quadrature=\"trapezoid\"".to_string()]);
    let scene = Scene::load(Some(&root().join(SCENE)), &[]).unwrap();
    let k = scene.time.final_time / scene.time.steps.unwrap() as f64;
    let (mut worst_scheme, mut worst_closed) = (0.0f64, 0.0f64);
    for (t, ratio) in &trapezoid {
        let scheme = discrete_phi(*t, k);
        worst_scheme = worst_scheme.max((ratio - scheme).abs());
        worst_closed = worst_closed.max((ratio - phi(*t)).abs());
        assert!(
            (ratio - scheme).abs() <= 1e-10,
            "t = {t}: P/P(0) = {ratio:.15}, the trapezoid's φ_n = {scheme:.15}"
        );
    }
    // the closed-form error is the trapezoidal one: Σ g_m (c_m − 1) at most ≈ Σ g_m (k/τ_m)²/12
    let lead: f64 = TERMS.iter().map(|(g, tau)| g * (k / tau).powi(2) / 12.0).sum();
    eprintln!(
        "relaxation gallery, trapezoid: k = {k}; max |P/P(0) − φ_n| = {worst_scheme:.2e}, max |P/P(0) − φ(t)| = \
         {worst_closed:.3e} (leading trapezoidal term {lead:.3e})"
    );
    assert!(
        worst_closed <= 1.01 * lead && worst_closed >= 0.9 * lead,
        "{worst_closed} vs {lead}"
    );
}

/// (t_n, P_n/P_0) of the gallery scene with `overrides`, checking that the deformation and the
/// contact set stay those of t = 0.
fn held_force_ratios(overrides: &[String]) -> Vec<(f64, f64)> {
    let scene = Scene::load(Some(&root().join(SCENE)), overrides).unwrap();
    let (sim, stats, sink) = solve_in_memory(&scene, read_mesh::<2>(&root().join(MESH)).unwrap()).unwrap();
    let memory = sim.materials.memory().expect("a relaxation modulus is a memory");
    assert!(memory.is_from_relaxation_modulus());
    assert_eq!(memory.channels().len(), 1, "bulk and shear relax proportionally");
    let a = sim.materials.list()[0].elasticity.tensor();
    assert!(
        (a.mu - 1.2).abs() < 1e-12 && (a.lambda + 2.0 * a.mu / 3.0 - 2.0).abs() < 1e-12,
        "A = (κ₀, G₀)"
    );
    let force = |t: f64| {
        stats
            .contact_forces
            .iter()
            .find(|r| r.group == "Gamma3" && r.component == "y" && (r.time - t).abs() < 1e-12)
            .unwrap_or_else(|| panic!("no contact force at t = {t}"))
            .force
    };
    let p0 = force(0.0);
    assert!(p0 < 0.0, "the cylinder pushes the pad down");
    let u0 = &sink.steps[0].displacement;
    let scale = u0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let active0 = stats.contact[0].active;
    assert!(active0 > 5, "only {active0} nodes in contact");
    sink.steps
        .iter()
        .map(|s| {
            let du = s
                .displacement
                .iter()
                .zip(u0)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(du <= 1e-12 * scale, "step {}: the deformation moved by {du:e}", s.step);
            assert_eq!(
                stats.contact[s.step].active, active0,
                "step {}: the contact set changed",
                s.step
            );
            (s.time, force(s.time) / p0)
        })
        .collect()
}
