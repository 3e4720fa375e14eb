//! Several materials in one body (docs/method.md §8.5): each cell has its group's material, each
//! material its own memory. Two halves of the rectangle side by side (meshes/rect_halves_*.msh:
//! Left x < 1, Right x > 1), compressed between the bottom and the top with the sides free:
//! the exact solution is piecewise linear — ε_yy = −δ in both halves, σ_xx = σ_xy = 0, so
//! ε_xx = −λ/(λ + 2μ) ε_yy in each — which P1 and Q1 hold exactly; with a relaxation modulus
//! relaxing bulk and shear alike on one half, the displacement stays and that half's stress
//! relaxes by the scheme's trapezoid sum of G′, the other half's not at all.

mod common;

use common::scene;
use hvi::app::{solve_in_memory, MemorySink};
use hvi::fem::stress::cell_stresses;
use hvi::mesh::{read_mesh, Mesh};
use hvi::solver::Simulation;
use std::path::Path;

fn halves(kind: &str) -> Mesh<2> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("meshes/rect_halves_{kind}_h4.msh"));
    read_mesh::<2>(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// δ: the top moves down by this.
const SQUEEZE: f64 = 0.01;

/// The halves squeezed by δ, plane strain; `materials` the scene's material sections.
fn squeezed(materials: &str, steps: usize) -> String {
    format!(
        r#"
[material]
plane = "strain"
{materials}

[time]
final_time = 1.0
steps = {steps}

[[dirichlet]]
group = "Gamma1"
components = ["x"]

[[dirichlet]]
group = "Gamma3"
components = ["y"]

[[dirichlet]]
group = "Gamma2_top"
components = ["y"]
value = ["-{SQUEEZE}"]
"#
    )
}

const LEFT: (f64, f64) = (1.0, 0.3);
const RIGHT: (f64, f64) = (20.0, 0.45);

fn two_elastic() -> String {
    squeezed(
        &format!(
            r#"
[[materials]]
group = "Left"
youngs_modulus = {}
poisson_ratio = {}

[[materials]]
group = "Right"
youngs_modulus = {}
poisson_ratio = {}
"#,
            LEFT.0, LEFT.1, RIGHT.0, RIGHT.1
        ),
        1,
    )
}

/// (λ, μ) of (E, ν).
fn lame((e, nu): (f64, f64)) -> (f64, f64) {
    (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)))
}

/// ε_xx of a half under ε_yy = −δ with σ_xx = 0 (plane strain), and its σ_yy.
fn uniaxial(material: (f64, f64)) -> (f64, f64) {
    let (l, m) = lame(material);
    let eyy = -SQUEEZE;
    let exx = -l / (l + 2.0 * m) * eyy;
    (exx, l * (exx + eyy) + 2.0 * m * eyy)
}

/// The exact displacement: u_y = −δ y, u_x piecewise linear with each half's ε_xx.
fn exact(x: &[f64; 2]) -> [f64; 2] {
    let (left, right) = (uniaxial(LEFT).0, uniaxial(RIGHT).0);
    let ux = if x[0] <= 1.0 {
        left * x[0]
    } else {
        left + right * (x[0] - 1.0)
    };
    [ux, -SQUEEZE * x[1]]
}

/// Each cell's stress at the last step, with the memory channels (the output's path).
fn stresses(sim: &Simulation<2>, sink: &MemorySink) -> Vec<f64> {
    let last = sink.steps.last().unwrap();
    let u = sim.dofs.to_nodal(&last.displacement);
    let memory = hvi::app::memory_fields(sim, last.memory_displacement.as_deref());
    cell_stresses(
        &sim.mesh.cells,
        &sim.mesh.points,
        &sim.materials,
        None,
        &u,
        Some(&memory),
    )
    .tensor
}

/// Whether cell `c` lies in the left half (by its first node... all of them: x ≤ 1).
fn in_left(mesh: &Mesh<2>, c: usize) -> bool {
    mesh.cells[c].nodes().iter().all(|&p| mesh.points[p][0] <= 1.0 + 1e-12)
}

#[test]
fn two_materials_side_by_side_hold_the_piecewise_linear_solution() {
    for kind in ["q1", "p1"] {
        let (sim, _, sink) = solve_in_memory(&scene(&two_elastic()), halves(kind)).unwrap();
        assert_eq!(sim.materials.list().len(), 2);
        let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
        let error = common::nodal_error(&sim.mesh.points, &u, exact);
        // a linear field on each half: exact up to the solve's round-off (|u| ~ 1e-2)
        assert!(error < 1e-12, "{kind}: nodal error {error:e}");
        let sigma = stresses(&sim, &sink);
        for c in 0..sim.mesh.cells.len() {
            let want = uniaxial(if in_left(&sim.mesh, c) { LEFT } else { RIGHT }).1;
            let s = &sigma[9 * c..9 * c + 9];
            assert!(
                (s[4] / want - 1.0).abs() < 1e-10,
                "{kind} cell {c}: σ_yy {} against {want}",
                s[4]
            );
            assert!(
                s[0].abs() < 1e-10 * want.abs() && s[1].abs() < 1e-10 * want.abs(),
                "{kind} cell {c}: σ_xx {}, σ_xy {}",
                s[0],
                s[1]
            );
        }
    }
}

/// One material over the whole body gives the same bits whether it is `[material]`'s or a
/// `[[materials]]` entry's covering every cell — and both halves as entries with equal constants
/// give the same solution.
#[test]
fn one_material_named_or_not_is_the_same_run() {
    let plain = squeezed("youngs_modulus = 3.0\npoisson_ratio = 0.3", 1);
    let named = squeezed(
        "[[materials]]\ngroup = \"Omega\"\nyoungs_modulus = 3.0\npoisson_ratio = 0.3",
        1,
    );
    let split = squeezed(
        "[[materials]]\ngroup = \"Left\"\nyoungs_modulus = 3.0\npoisson_ratio = 0.3\n\
         [[materials]]\ngroup = \"Right\"\nyoungs_modulus = 3.0\npoisson_ratio = 0.3",
        1,
    );
    let run = |text: &str| solve_in_memory(&scene(text), halves("q1")).unwrap();
    let (_, _, a) = run(&plain);
    let (_, _, b) = run(&named);
    let (_, _, c) = run(&split);
    let (ua, ub, uc) = (
        &a.steps[0].displacement,
        &b.steps[0].displacement,
        &c.steps[0].displacement,
    );
    assert_eq!(ua, ub, "one [[materials]] entry over every cell is [material]");
    let off = ua.iter().zip(uc).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    assert!(off < 1e-15, "two equal materials differ by {off:e}");
}

/// A relaxation modulus on the right half only (bulk and shear relaxing alike, so that ν stays
/// and the displacement with it): its σ_yy follows the continuum's relaxation A ε G(t)/G(0)
/// exactly, which the exact rule (the default for a relaxation modulus, docs/method.md §20.2)
/// integrates a held strain to on any steps; the left half stays elastic.
#[test]
fn a_relaxing_half_relaxes_and_the_elastic_half_does_not() {
    let (tau, share, steps): (f64, f64, usize) = (0.4, 0.6, 20);
    // κ(t) = κ₀ (1 − s + s e^{−t/τ}), G likewise: the right half's moduli at t = 0 are RIGHT's
    let (l, m) = lame(RIGHT);
    let (k0, g0) = (l + 2.0 * m / 3.0, m);
    let relaxing = format!(
        r#"
[[materials]]
group = "Left"
youngs_modulus = {}
poisson_ratio = {}

[[materials]]
group = "Right"
relaxation_modulus = {{ bulk = {{ long_term = {}, terms = [{{ modulus = {}, relaxation_time = {tau} }}] }}, shear = {{ long_term = {}, terms = [{{ modulus = {}, relaxation_time = {tau} }}] }} }}
"#,
        LEFT.0,
        LEFT.1,
        k0 * (1.0 - share),
        k0 * share,
        g0 * (1.0 - share),
        g0 * share,
    );
    let (sim, _, sink) = solve_in_memory(&scene(&squeezed(&relaxing, steps)), halves("q1")).unwrap();
    assert_eq!(sim.materials.memory().unwrap().channels().len(), 1);
    assert_eq!(sim.materials.channel_owner(0).index(), 1, "the right half's channel");
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let error = common::nodal_error(&sim.mesh.points, &u, exact);
    assert!(error < 1e-12, "the displacement stays: nodal error {error:e}");
    let continuum = 1.0 - share * (1.0 - (-1.0f64 / tau).exp());
    let sigma = stresses(&sim, &sink);
    for c in 0..sim.mesh.cells.len() {
        let left = in_left(&sim.mesh, c);
        let want = if left {
            uniaxial(LEFT).1
        } else {
            uniaxial(RIGHT).1 * continuum
        };
        let got = sigma[9 * c + 4];
        assert!(
            (got / want - 1.0).abs() < 1e-10,
            "cell {c} ({}): σ_yy {got} against {want}",
            if left { "elastic" } else { "relaxing" }
        );
    }
}

/// Every cell has exactly one material: a cell in two entries' groups, or in none when
/// `[material]` gives no constants, is refused naming the groups; a group that is not there is
/// refused naming the key.
#[test]
fn a_cell_with_two_materials_or_none_is_refused_by_name() {
    let run = |materials: &str| {
        solve_in_memory(&scene(&squeezed(materials, 1)), halves("q1"))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let twice = run(
        "[[materials]]\ngroup = \"Omega\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
                     [[materials]]\ngroup = \"Right\"\nyoungs_modulus = 2.0\npoisson_ratio = 0.3",
    );
    assert!(
        twice.contains("materials[1].group") && twice.contains("materials[0].group") && twice.contains("one material"),
        "{twice}"
    );
    let none = run("[[materials]]\ngroup = \"Left\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3");
    assert!(
        none.contains("have no material") && none.contains("Right") && none.contains("[[materials]]"),
        "{none}"
    );
    let missing = run("[[materials]]\ngroup = \"Rigth\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3");
    assert!(
        missing.contains("materials[0].group") && missing.contains("Right"),
        "{missing}"
    );
    // with [material]'s own constants the unclaimed cells take them
    let rest = format!(
        "youngs_modulus = {}\npoisson_ratio = {}\n[[materials]]\ngroup = \"Right\"\nyoungs_modulus = {}\n\
         poisson_ratio = {}",
        LEFT.0, LEFT.1, RIGHT.0, RIGHT.1
    );
    let (sim, _, sink) = solve_in_memory(&scene(&squeezed(&rest, 1)), halves("p1")).unwrap();
    let u = sim.dofs.to_nodal(&sink.steps[0].displacement);
    assert!(common::nodal_error(&sim.mesh.points, &u, exact) < 1e-12);
}

/// A relaxing material's time-step bound is its own: the same relaxation refused on one half
/// names that entry.
#[test]
fn the_time_step_bound_is_checked_per_material() {
    let relaxing = |long_term: f64| {
        format!(
            "[[materials]]\ngroup = \"Left\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
             [[materials]]\ngroup = \"Right\"\nrelaxation_modulus = {{ bulk = {{ long_term = 1.0, terms = [] }}, \
             shear = {{ long_term = {long_term}, terms = [{{ modulus = 1.0, relaxation_time = 0.01 }}] }} }}"
        )
    };
    // G(0)/G∞ = 100 at k = 100 τ: the trapezoid's long-term shear modulus is negative
    let trapezoid = |text: String| text.replace("[time]\n", "[time]\nquadrature = \"trapezoid\"\n");
    let err = hvi::scene::Scene::from_toml_str(&trapezoid(squeezed(&relaxing(0.01), 1)), "bad.toml")
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        err.contains("time.steps") && err.contains("materials[1]") && err.contains("Right"),
        "{err}"
    );
}

/// What the user sees: `hvi check` lists the materials with their groups and cell counts, and
/// the body series carries each cell's `material` beside its stress.
#[test]
fn check_lists_the_materials_and_the_series_carries_them() {
    let dir = std::env::temp_dir().join(format!("hvi_materials_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene_path = dir.join("halves.toml");
    std::fs::write(&scene_path, two_elastic()).unwrap();
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/rect_halves_q1_h4.msh");
    let (mesh, scene_arg) = (mesh.to_str().unwrap(), scene_path.to_str().unwrap());
    let check = common::hvi_ok(&["check", mesh, "--scene", scene_arg]);
    let report = String::from_utf8_lossy(&check.stdout);
    for line in ["Left (tag 6)", "Right (tag 7)"] {
        let listed = report
            .lines()
            .find(|l| l.contains(line))
            .unwrap_or_else(|| panic!("{report}"));
        assert!(listed.contains("16 cells"), "{listed}");
    }
    let out = dir.join("run");
    common::hvi_ok(&["solve", mesh, "--scene", scene_arg, "--out", out.to_str().unwrap()]);
    let vtu = hvi::output::read_vtu_arrays(&out.join("solution_00001.vtu")).unwrap();
    let (width, material) = &vtu.cell_data["material"];
    assert_eq!(*width, 1);
    let sigma = &vtu.cell_data["stress"].1;
    for (c, m) in material.iter().enumerate() {
        let want = uniaxial(if *m == 0.0 { LEFT } else { RIGHT }).1;
        assert!((sigma[9 * c + 4] / want - 1.0).abs() < 1e-9, "cell {c}: material {m}");
    }
    assert_eq!(material.iter().filter(|&&m| m == 1.0).count(), 16);
    std::fs::remove_dir_all(&dir).ok();
}

/// A relaxing layer bonded to an elastic one, in series: the left half (elastic, P-wave modulus
/// M_L = λ + 2μ) and the right half (relaxing alike in bulk and shear, M_R(t) = M₀ (1 − s +
/// s e^{−t/τ})) between x = 0 (held) and x = 2 (moved by δ at t = 0 and held), top and bottom on
/// rollers (u_y = 0, so each half is in uniaxial strain). The interface stress σ_xx is uniform
/// and is that of two springs in series with a standard linear solid: again a standard linear
/// solid, σ(t) = δ [M∞′ + (M₀′ − M∞′) e^{−t/τ′}], M′ = M_L M / (M_L + M),
/// τ′ = τ (M_L + M₀)/(M_L + M∞). The scheme's history follows it at order 2 in k.
#[test]
fn a_relaxing_layer_in_series_with_an_elastic_one_relaxes_as_two_springs_and_a_solid() {
    let (tau, share, delta) = (0.5, 0.7, 0.01);
    let (l, m) = lame(LEFT);
    let m_left = l + 2.0 * m;
    let (l, m) = lame(RIGHT);
    let (k0, g0) = (l + 2.0 * m / 3.0, m);
    let m0 = l + 2.0 * m;
    let m_inf = m0 * (1.0 - share);
    let series = |mm: f64| m_left * mm / (m_left + mm);
    let tau_series = tau * (m_left + m0) / (m_left + m_inf);
    let exact = |t: f64| delta * (series(m_inf) + (series(m0) - series(m_inf)) * (-t / tau_series).exp());
    let text = |steps: usize| {
        format!(
            r#"
[material]
plane = "strain"

[[materials]]
group = "Left"
youngs_modulus = {}
poisson_ratio = {}

[[materials]]
group = "Right"
relaxation_modulus = {{ bulk = {{ long_term = {}, terms = [{{ modulus = {}, relaxation_time = {tau} }}] }}, shear = {{ long_term = {}, terms = [{{ modulus = {}, relaxation_time = {tau} }}] }} }}

[time]
final_time = 2.0
steps = {steps}

[[dirichlet]]
group = "Gamma1"
components = ["x"]

[[dirichlet]]
group = "Gamma2_right"
components = ["x"]
value = ["{delta}"]

[[dirichlet]]
group = "Gamma3"
components = ["y"]

[[dirichlet]]
group = "Gamma2_top"
components = ["y"]
"#,
            LEFT.0,
            LEFT.1,
            k0 * (1.0 - share),
            k0 * share,
            g0 * (1.0 - share),
            g0 * share,
        )
    };
    let error = |steps: usize| {
        let (sim, _, sink) = solve_in_memory(&scene(&text(steps)), halves("q1")).unwrap();
        let mut worst: f64 = 0.0;
        for step in &sink.steps {
            let u = sim.dofs.to_nodal(&step.displacement);
            let memory = hvi::app::memory_fields(&sim, step.memory_displacement.as_deref());
            let sigma = cell_stresses(
                &sim.mesh.cells,
                &sim.mesh.points,
                &sim.materials,
                None,
                &u,
                Some(&memory),
            )
            .tensor;
            let first = sigma[0];
            for c in 0..sim.mesh.cells.len() {
                assert!(
                    (sigma[9 * c] / first - 1.0).abs() < 1e-9,
                    "step {}: σ_xx {} in cell {c} against {first} in cell 0 (series: one stress)",
                    step.step,
                    sigma[9 * c]
                );
            }
            worst = worst.max((first / exact(step.time) - 1.0).abs());
        }
        worst
    };
    let (coarse, fine) = (error(40), error(80));
    eprintln!("series relaxation: relative error {coarse:.3e} (k = 0.05), {fine:.3e} (k = 0.025)");
    // the trapezoid's relaxation error is of order (k/τ′)²/12 of the relaxed share: k/τ′ = 0.03
    // here (τ′ = 1.66), 7.6e-5 × 0.7 — measured 6.4e-5
    assert!(coarse < 2.0 * share * (0.05 / tau_series).powi(2) / 12.0, "{coarse:e}");
    let order = (coarse / fine).log2();
    assert!((order - 2.0).abs() < 0.2, "order {order} ({coarse:e}, {fine:e})");
}
