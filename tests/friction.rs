//! Friction (docs/method.md §17): Tresca and Coulomb on the slip increment of each step, in the
//! one condensed contact solve of the step.

mod common;

use common::{rectangle_with_sides, scene};
use hvi::app::solve_in_memory;
use hvi::mesh::read_mesh;
use hvi::mesh::structured::CellShape;
use hvi::scene::Scene;

const MU: f64 = 0.3;
/// The top's horizontal displacement per step once pressed: 1e-3, so that the smoothing of |Δu_τ|
/// (ε = 1e-8) changes a sliding node's friction force by ε²/(2Δ²) = 5e-11 of it.
const STEPS: usize = 10;
const SLIDE: f64 = 0.01;

/// A block (0, 1) × (0, 0.5) on a rigid plane (Gamma3: u_ν ≤ 0), its top (Gamma2_top) pressed
/// down by 0.002 from step 0 on and moved sideways by 0.01 t.
fn dragged(friction: &str) -> String {
    format!(
        r#"
[material]
plane = "strain"
youngs_modulus = 1.0
poisson_ratio = 0.3

[time]
final_time = 1.0
steps = {STEPS}

[[dirichlet]]
group = "Gamma2_top"
components = ["x", "y"]
value = ["{SLIDE}*t", "-0.002"]

[contact]
bound = "0"
friction = {friction}

[solver]
tolerance = 1e-13
"#
    )
}

/// The dragged block under Coulomb (μ = 0.3) and Tresca friction: once the whole base slides,
/// the total friction force is μ times the total normal force (Coulomb) or F_b times the base's
/// length (Tresca, which acts at every node in contact or not), to 1e-10, it opposes the slip,
/// and every base node slips by the top's increment (the state only translates).
#[test]
fn a_dragged_block_slides_with_the_friction_force_of_its_law() {
    let f_b = 0.0005;
    let coulomb = format!("{{ kind = \"coulomb\", coefficient = {MU} }}");
    for (name, text) in [
        ("coulomb", dragged(&coulomb)),
        (
            "tresca",
            dragged(&format!("{{ kind = \"tresca\", bound = \"{f_b}\" }}")),
        ),
        // every Newton system by the kept factor (docs/method.md §9.2), so that Coulomb's rounds
        // take the coupled law's Newton steps (§17.2)
        (
            "coulomb, kept factor",
            dragged(&coulomb).replace("tolerance = 1e-13", "tolerance = 1e-13\ndense_newton_limit = 0"),
        ),
    ] {
        let mesh = rectangle_with_sides(1.0, 0.5, 16, 8, CellShape::Quad);
        let (sim, _, sink) = solve_in_memory(&scene(&text), mesh).unwrap_or_else(|e| panic!("{e}"));
        let c = sim.contact.as_ref().unwrap();
        let f = c.friction.as_ref().expect("friction rows");
        let m = c.nodes.len();
        assert_eq!(f.normal_row.len(), m, "{name}: one tangential row per base node");
        let length: f64 = c.nodes.weights.iter().sum();
        // the last two steps: fully sliding
        for pair in sink.steps[sink.steps.len() - 2..].windows(1) {
            let step = &pair[0];
            let state = step.contact.as_ref().unwrap();
            let normal: f64 = state.force[..m].iter().sum();
            let tangential: f64 = state.force[m..].iter().sum();
            let expected = if name.starts_with("coulomb") {
                MU * normal
            } else {
                f_b * length
            };
            assert!(normal > 0.0, "{name}: the block is pressed");
            assert!(
                (tangential - expected).abs() <= 1e-10 * expected,
                "{name} t = {}: friction {tangential:e} against {expected:e}",
                step.time
            );
        }
        // the slip increment of the last step at every base node (τ = (1, 0) on the base)
        let (a, b) = (&sink.steps[STEPS - 1], &sink.steps[STEPS]);
        let increment = SLIDE / STEPS as f64;
        for (k, &p) in c.nodes.nodes.iter().enumerate() {
            let slip = b.displacement[2 * p] - a.displacement[2 * p];
            assert!(
                (slip - increment).abs() <= 1e-9 * increment,
                "{name}: base node {k} slipped {slip:e}, the top {increment:e}"
            );
        }
    }
}

/// μ = 0 and F_b = 0 give the frictionless run's numbers on the 2D Hertz block (bound), to
/// 1e-14 of the largest displacement: the tangential rows enlarge the condensed problem, so the
/// arithmetic differs at round-off only (measured 1.7e-15).
#[test]
fn zero_friction_is_the_frictionless_run() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let hertz = std::fs::read_to_string(root.join("examples/gallery/hertz_2d/hertz_2d.toml")).unwrap();
    let with = |text: &str, friction: &str| -> Scene {
        let t = text.replace("[contact]", &format!("[contact]\nfriction = {friction}"));
        Scene::from_toml_str(&t, "zero friction").unwrap_or_else(|e| panic!("{e}"))
    };
    let mesh = || read_mesh::<2>(&root.join("examples/gallery/hertz_2d/hertz_2d_h1.msh")).unwrap();
    let plain = Scene::from_toml_str(&hertz, "hertz").unwrap();
    let (_, _, reference) = solve_in_memory(&plain, mesh()).unwrap();
    for friction in [
        "{ kind = \"coulomb\", coefficient = 0.0 }",
        "{ kind = \"tresca\", bound = \"0\" }",
    ] {
        let (_, _, run) = solve_in_memory(&with(&hertz, friction), mesh()).unwrap_or_else(|e| panic!("{e}"));
        let (u, v) = (
            &reference.steps.last().unwrap().displacement,
            &run.steps.last().unwrap().displacement,
        );
        let scale = u.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let diff = u.iter().zip(v).fold(0.0f64, |a, (x, y)| a.max((x - y).abs())) / scale;
        eprintln!("Hertz 2D, {friction}: max |Δu| / max |u| = {diff:.1e}");
        assert!(diff <= 1e-14, "{friction}: {diff:e}");
    }
}

/// Cattaneo–Mindlin partial slip (2D, plane strain; examples/gallery/cattaneo_2d): the block
/// pressed by P onto the rigid cylinder, then its base moved sideways so that Q ≈ μP/2.
/// Mindlin: a stick zone of half-length c = a sqrt(1 − Q/(μP)), a the Hertz half-width. The
/// theory neglects the normal–tangential coupling of an elastic body on a rigid one (Dundurs
/// β = (1 − 2ν)/(2(1 − ν)) = 0.091 at ν = 0.45): during the pressing the surface is drawn inward
/// against friction, and the tractions this locks in shift the stick zone sideways under the
/// shear (measured: by 0.19 a). Its length is what Mindlin predicts: the half-length, located to
/// ±h/2 at each end between the outermost sticking and the innermost slipping node (h = a/34),
/// within 3 % of Mindlin's c (the issue's tolerance; measured −0.4 %). At ν = 0.49 (β = 0.02) the
/// shift is smaller but P1 triangles lock and c is off by 7 %: ν = 0.45 is the compromise.
#[test]
fn cattaneo_mindlin_stick_zone_in_2d() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/cattaneo_2d");
    let scene = Scene::load(Some(&root.join("cattaneo_2d.toml")), &[]).unwrap_or_else(|e| panic!("{e}"));
    let mesh = read_mesh::<2>(&root.join("cattaneo_2d.msh")).unwrap_or_else(|e| panic!("{e}"));
    let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let c = sim.contact.as_ref().unwrap();
    let f = c.friction.as_ref().unwrap();
    let m = c.nodes.len();
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let p: f64 = state.force[..m].iter().sum();
    let q: f64 = state.force[m..].iter().sum();
    // per node in contact: x, and whether it sticks (|λ_τ| below μ λ_ν by more than the solve's
    // tolerance and the smoothing: 1e-6 relative)
    let mut nodes: Vec<(f64, bool)> = Vec::new();
    for (k, &row) in f.normal_row.iter().enumerate() {
        let normal = state.force[row];
        if normal > 1e-12 * p {
            let x = sim.mesh.points[c.nodes.nodes[row]][0];
            nodes.push((x, state.force[m + k].abs() < MU * normal * (1.0 - 1e-6)));
        }
    }
    nodes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let h = nodes.windows(2).map(|w| w[1].0 - w[0].0).fold(0.0f64, f64::max);
    let a = 0.5 * (nodes.last().unwrap().0 - nodes[0].0) + 0.5 * h;
    let ratio = q.abs() / (MU * p);
    let c_mindlin = a * (1.0 - ratio).sqrt();
    // the stick zone's edges: midway between the last sticking and the first slipping node
    let stick: Vec<usize> = (0..nodes.len()).filter(|&i| nodes[i].1).collect();
    assert!(
        !stick.is_empty() && stick.len() < nodes.len(),
        "partial slip expected: {nodes:?}"
    );
    let (lo, hi) = (stick[0], *stick.last().unwrap());
    assert!(stick.len() == hi - lo + 1, "one stick zone in the middle: {nodes:?}");
    let left = -0.5 * (nodes[lo].0 + nodes[lo - 1].0);
    let right = 0.5 * (nodes[hi].0 + nodes[hi + 1].0);
    let half = 0.5 * (left + right);
    let shift = 0.5 * (right - left);
    eprintln!(
        "Cattaneo–Mindlin 2D: P = {p:.5e}, Q/(μP) = {ratio:.4}, a = {a:.5}, stick zone from {:.5} to {right:.5}: half-length {half:.5} (Mindlin {c_mindlin:.5}, {:+.2} %), shifted by {:.3} a; h = {h:.2e}",
        -left,
        100.0 * (half / c_mindlin - 1.0),
        shift / a
    );
    assert!((0.3..0.7).contains(&ratio), "Q/(μP) = {ratio}: not a partial-slip load");
    assert!(
        (half / c_mindlin - 1.0).abs() < 0.03,
        "the stick zone's half-length {half} against Mindlin's {c_mindlin}"
    );
    // the coupling's shift stays a fraction of the zone (it would be 0 at β = 0)
    assert!(shift.abs() < 0.5 * half, "the stick zone is shifted by {shift}");
}

/// Cattaneo–Mindlin partial slip in 3D (examples/gallery/cattaneo_3d): the half block (symmetry
/// plane y = 0, tetrahedra of size a/17 on the contact) pressed by P onto the rigid sphere R = 1,
/// then its base moved along x so that Q ≈ 0.57 μP, Coulomb μ = 0.6, ν = 0.45. Mindlin: a stick
/// disk of radius c = a (1 − Q/(μP))^{1/3} inside the Hertz contact of radius a, and in it the
/// tangential traction μp − (μp₀/a) √(c² − r²). Both radii are measured by moments of nodal
/// forces, which the elements integrate consistently (counting sticking nodes' areas was
/// ±1 % noisy from mesh to mesh): p = p₀√(1 − r²/a²) gives a² = (5/2) Σλ_ν r²/Σλ_ν, and the stick
/// deficit D = μλ_ν − |λ_τ| (zero where the node slips), (μp₀/a)√(c² − r²) in the disk, gives
/// c² = (5/2) ΣD r²/ΣD about its centroid (the coupling Mindlin neglects shifts the disk along x:
/// measured 0.07 a). c/a within 5 % of Mindlin's (the issue's tolerance; measured −2.3 %, and
/// −3.1 %, −2.0 % on meshes of a/13 and a/23: it converges). μ = 0.6 rather than 2D's 0.3: the
/// coupling (Dundurs β = 0.09) makes the contact's edge slip inward already while pressing, by
/// an amount set by β/μ (after pressing the deficit's disk is 0.955 a at μ = 0.6, 0.91 a at 0.3,
/// where c/a came out −4.6 %), and Mindlin starts from a contact that sticks everywhere.
#[test]
fn cattaneo_mindlin_stick_zone_in_3d() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/cattaneo_3d");
    let scene = Scene::load(Some(&root.join("cattaneo_3d.toml")), &[]).unwrap_or_else(|e| panic!("{e}"));
    let mesh = read_mesh::<3>(&root.join("cattaneo_3d.msh")).unwrap_or_else(|e| panic!("{e}"));
    let (sim, _, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let mu = 0.6;
    let c = sim.contact.as_ref().unwrap();
    let f = c.friction.as_ref().unwrap();
    let m = c.nodes.len();
    let rows = f.rows_of(m);
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let (mut p, mut q) = (0.0, 0.0);
    let (mut normal, mut deficit) = ([0.0; 3], [0.0; 3]);
    let mut sticking = 0;
    for (row, pair) in rows.iter().enumerate() {
        let x = sim.mesh.points[c.nodes.nodes[row]];
        let lambda = state.force[row];
        let mut tangential = [0.0; 3];
        for &k in pair {
            for (d, t) in tangential.iter_mut().enumerate() {
                *t += state.force[m + k] * f.rows.normals[m + k][d];
            }
        }
        p += lambda;
        q += tangential[0];
        let gap = (mu * lambda - tangential[0].hypot(tangential[1])).max(0.0);
        sticking += usize::from(state.friction.status[pair[0]] == 1);
        let r2 = x[0] * x[0] + x[1] * x[1];
        normal = [normal[0] + lambda, normal[1] + lambda * r2, 0.0];
        deficit = [deficit[0] + gap, deficit[1] + gap * x[0], deficit[2] + gap * r2];
    }
    let a = (2.5 * normal[1] / normal[0]).sqrt();
    // about the deficit's centroid x₀ (on y = 0): Σ D |x − x₀|² = Σ D r² − x₀² Σ D
    let x0 = deficit[1] / deficit[0];
    let stick = (2.5 * (deficit[2] / deficit[0] - x0 * x0)).sqrt();
    let ratio = q.abs() / (mu * p);
    let mindlin = (1.0 - ratio).cbrt();
    let e_star = 1.0 / (1.0 - 0.45f64 * 0.45);
    let a_hertz = (3.0 * 2.0 * p / (4.0 * e_star)).cbrt();
    eprintln!(
        "Cattaneo–Mindlin 3D: P = {:.5e} (the whole), Q/(μP) = {ratio:.4}, a = {a:.5} (Hertz {a_hertz:.5}), {sticking} nodes stick, c = {stick:.5}: c/a = {:.4} (Mindlin {mindlin:.4}, {:+.2} %), centre shifted by {:.3} a",
        2.0 * p,
        stick / a,
        100.0 * (stick / a / mindlin - 1.0),
        x0 / a
    );
    assert!((0.3..0.7).contains(&ratio), "Q/(μP) = {ratio}: not a partial-slip load");
    assert!(
        sticking > 50 && sticking < m,
        "partial slip expected: {sticking} of {m} stick"
    );
    assert!((a / a_hertz - 1.0).abs() < 0.03, "a = {a} against Hertz {a_hertz}");
    assert!(
        (stick / a / mindlin - 1.0).abs() < 0.05,
        "c/a = {} against Mindlin's {mindlin}",
        stick / a
    );
    assert!(x0.abs() < 0.25 * stick, "the stick disk is shifted by {x0}");
}

/// Slip-dependent Coulomb friction (slip weakening μ(s) = 0.2 + 0.1 e^{−s/0.005}, s the node's
/// accumulated slip including the step's own increment: implicit): at every step each base row
/// that slips by more than 1e-4 carries |λ_τ| = μ(s) λ_ν to 1e-8 (below that the smoothing of
/// |Δu_τ| with ε = 1e-8 is felt: ε²/(2Δ²) = 5e-9 at Δ = 1e-4; the fixed point's and the solve's
/// tolerances are 1e-13), and once the whole base slides the total friction is Σ μ(s_k) λ_ν,k
/// (the rows began to slip at different steps, so their s differ by what each slipped before)
/// while every s grows by the step's slip, which exceeds the top's increment (weakening releases
/// elastic shear).
#[test]
fn slip_weakening_friction_follows_mu_of_the_accumulated_slip() {
    let mu = |s: f64| 0.2 + 0.1 * (-s / 0.005).exp();
    let text = dragged("{ kind = \"coulomb\", coefficient = \"0.2 + 0.1*exp(-s/0.005)\" }");
    let mesh = rectangle_with_sides(1.0, 0.5, 16, 8, CellShape::Quad);
    let (sim, _, sink) = solve_in_memory(&scene(&text), mesh).unwrap_or_else(|e| panic!("{e}"));
    let c = sim.contact.as_ref().unwrap();
    let f = c.friction.as_ref().unwrap();
    let m = c.nodes.len();
    let mut slipping_steps = 0;
    for step in &sink.steps[1..] {
        let state = step.contact.as_ref().unwrap();
        let rows = &state.friction;
        let mut all_slip = true;
        for (k, &p) in f.normal_row.iter().enumerate() {
            if rows.slip[k].abs() >= 1e-4 {
                assert_eq!(
                    rows.status[k], 2,
                    "t = {}: row {k} slips but is not marked so",
                    step.time
                );
                let expected = mu(rows.accumulated[k]) * state.force[p];
                assert!(
                    (state.force[m + k].abs() - expected).abs() <= 1e-8 * expected,
                    "t = {}: row {k} carries {:e}, μ(s) λ_ν = {expected:e}",
                    step.time,
                    state.force[m + k]
                );
            } else {
                all_slip = false;
            }
        }
        if all_slip {
            slipping_steps += 1;
            // the rows began to slip at different steps, so each has its own s
            let expected: f64 = f
                .normal_row
                .iter()
                .enumerate()
                .map(|(k, &p)| mu(rows.accumulated[k]) * state.force[p])
                .sum();
            let tangential: f64 = state.force[m..].iter().sum();
            assert!(
                (tangential - expected).abs() <= 1e-8 * tangential,
                "t = {}: friction {tangential:e} against Σ μ(s) λ_ν = {expected:e}",
                step.time
            );
        }
    }
    assert!(
        slipping_steps >= 3,
        "the base slides fully for only {slipping_steps} steps"
    );
    let last = &sink.steps[STEPS].contact.as_ref().unwrap().friction;
    let before = &sink.steps[STEPS - 1].contact.as_ref().unwrap().friction;
    // s grows by the step's |Δu_τ|, which exceeds the top's increment: the weakening friction
    // releases some of the base's elastic shear every step
    for k in 0..f.normal_row.len() {
        let grown = last.accumulated[k] - before.accumulated[k];
        assert!(
            (grown - last.slip[k].abs()).abs() <= 1e-15,
            "row {k}: s grew by {grown:e}"
        );
        assert!(
            last.slip[k] > SLIDE / STEPS as f64,
            "row {k}: slip {:e} under weakening",
            last.slip[k]
        );
    }
}

/// The command line on the Cattaneo–Mindlin scene: `hvi check` shows the friction plan,
/// gamma3.csv has the friction columns with stick (1) and slip (2) rows at T, and the contact
/// dataset carries the friction fields.
#[test]
fn friction_outputs_from_the_command_line() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/cattaneo_2d");
    let (mesh, scene_file) = (root.join("cattaneo_2d.msh"), root.join("cattaneo_2d.toml"));
    let check = common::hvi_ok(&["check", mesh.to_str().unwrap(), "--scene", scene_file.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(text.contains("friction") && text.contains("Coulomb"), "{text}");
    let out = tempfile::tempdir().unwrap();
    common::hvi_ok(&[
        "solve",
        mesh.to_str().unwrap(),
        "--scene",
        scene_file.to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
    ]);
    let csv = std::fs::read_to_string(out.path().join("gamma3.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("{name}: {header:?}"))
    };
    let (status, time) = (column("friction_status"), column("time"));
    for name in ["u_tau", "slip", "force_tau", "friction_bound", "accumulated_slip"] {
        column(name);
    }
    let last: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|r| r[time] == "1")
        .collect();
    assert!(last.iter().any(|r| r[status] == "1"), "no stick row at T");
    assert!(last.iter().any(|r| r[status] == "2"), "no slip row at T");
    // (the appended data are binary: the field names are in the XML head)
    let vtp = String::from_utf8_lossy(&std::fs::read(out.path().join("contact_00002.vtp")).unwrap()).into_owned();
    for field in [
        "\"slip\"",
        "\"friction_force\"",
        "\"friction_status\"",
        "\"accumulated_slip\"",
    ] {
        assert!(vtp.contains(field), "{field} missing from the contact dataset");
    }
    // hvi plot marks the stick and slip zones in gamma3's pressure panel
    common::hvi_ok(&["plot", out.path().to_str().unwrap()]);
    let svg = std::fs::read_to_string(out.path().join("gamma3.svg")).unwrap();
    let lines: Vec<&str> = svg.lines().map(str::trim).collect();
    assert!(
        lines.contains(&"stick") && lines.contains(&"slip"),
        "no zone legend in gamma3.svg"
    );
}

/// The hemivariational case (docs/method.md §17.1): a non-monotone friction potential on the total
/// tangential displacement, the paper's profile μ(s) = (a − b)e^{−αs} + b (softening from a = 1 to
/// b = 0.5), scale S = 1e-3. At every step each base row displaced tangentially by more than
/// 1e-4 carries |λ_τ| = w_p S μ(ρ_ε) ρ_ε' (the regularised law) to 1e-8, with the sign of u_τ
/// (λ_τ > 0 pushes the body back along −τ); the softening makes the step energy non-convex, which the convexified
/// Newton directions of §4.4 handle.
#[test]
fn a_non_monotone_friction_potential_gives_its_law_at_every_node() {
    let law = "{ kind = \"potential\", law = { kind = \"paper\", scale = 1e-3, a = 1.0, b = 0.5, alpha = 100.0 } }";
    let mesh = rectangle_with_sides(1.0, 0.5, 16, 8, CellShape::Quad);
    let (sim, _, sink) = solve_in_memory(&scene(&dragged(law)), mesh).unwrap_or_else(|e| panic!("{e}"));
    let c = sim.contact.as_ref().unwrap();
    let f = c.friction.as_ref().unwrap();
    let m = c.nodes.len();
    let mu = |s: f64| 0.5 * (-100.0 * s).exp() + 0.5;
    let mut checked = 0;
    for step in &sink.steps {
        let state = step.contact.as_ref().unwrap();
        for (k, &p) in f.normal_row.iter().enumerate() {
            let u = state.normal_displacement[m + k];
            if u.abs() >= 1e-4 {
                // the regularised law j_ε' = S μ(ρ_ε(u)) ρ_ε'(u), ρ_ε = √(u² + ε²) − ε (ε = 1e-8):
                // against S μ(|u|) it differs by μ'·ε ≈ 5e-7 relative here
                let root = (u * u + 1e-16).sqrt();
                let expected = c.nodes.weights[p] * 1e-3 * mu(root - 1e-8) * u.abs() / root;
                let got = state.force[m + k];
                assert!(
                    (got - expected * u.signum()).abs() <= 1e-8 * expected,
                    "t = {}: row {k} at u_τ = {u:e} carries {got:e}, the law {expected:e}",
                    step.time
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 3 * m, "only {checked} rows were displaced enough to check");
    // the slip written out is the step's increment of u_τ (the law acts on u_τ itself), and the
    // accumulated slip grows by its size
    for pair in sink.steps.windows(2) {
        let (a, b) = (pair[0].contact.as_ref().unwrap(), pair[1].contact.as_ref().unwrap());
        for k in 0..f.normal_row.len() {
            let increment = b.normal_displacement[m + k] - a.normal_displacement[m + k];
            assert!(
                (b.friction.slip[k] - increment).abs() <= 1e-15,
                "t = {}: row {k} slip {:e}, u_τ moved {increment:e}",
                pair[1].time,
                b.friction.slip[k]
            );
            let before = a.friction.accumulated.get(k).copied().unwrap_or(0.0);
            assert!((b.friction.accumulated[k] - before - increment.abs()).abs() <= 1e-15);
        }
    }
}

/// The forces add up with friction (docs/method.md §14.4, §17.5): on the Cattaneo–Mindlin scene
/// (no load) the base's reactions and the contact group's total force — its tangential part
/// included — cancel in both components at every step, to 1e-10 of the normal force.
#[test]
fn reactions_and_contact_forces_balance_with_friction() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/cattaneo_2d");
    let scene = Scene::load(Some(&root.join("cattaneo_2d.toml")), &[]).unwrap_or_else(|e| panic!("{e}"));
    let mesh = read_mesh::<2>(&root.join("cattaneo_2d.msh")).unwrap_or_else(|e| panic!("{e}"));
    let (_, stats, _) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let last = stats.reactions.last().unwrap().time;
    let normal = common::reaction(&stats, "Base", "y", last).abs();
    assert!(normal > 0.0);
    for r in &stats.reactions {
        let contact = stats
            .contact_forces
            .iter()
            .find(|c| c.time == r.time && c.component == r.component)
            .unwrap();
        assert!(
            (r.force + contact.force).abs() <= 1e-10 * normal,
            "t = {}, {}: reaction {:e} + contact {:e}",
            r.time,
            r.component,
            r.force,
            contact.force
        );
    }
    // the shear step carries a tangential force of about μP/2
    let shear = common::reaction(&stats, "Base", "x", last).abs();
    assert!(shear > 0.1 * MU * normal, "shear {shear:e}");
}

/// Friction with force control (docs/method.md §7.7 with §17): the Cattaneo–Mindlin block pressed
/// by the force P that the displacement-controlled run finds at T (its base's y-reaction), its x
/// still prescribed. The base's reaction is P to 1e-10 at T, and the base moves by the
/// displacement control's 0.004 there (to 1e-6: the two runs solve the same problem at T, but
/// the Coulomb history of the pressing step differs because P is applied at t = 1/2 already;
/// measured 4e-8).
#[test]
fn friction_under_force_control_matches_the_displacement_control() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/cattaneo_2d");
    let text = std::fs::read_to_string(root.join("cattaneo_2d.toml")).unwrap();
    let mesh = || read_mesh::<2>(&root.join("cattaneo_2d.msh")).unwrap_or_else(|e| panic!("{e}"));
    let displaced = Scene::from_toml_str(&text, "cattaneo").unwrap();
    let (_, stats, _) = solve_in_memory(&displaced, mesh()).unwrap_or_else(|e| panic!("{e}"));
    let p = common::reaction(&stats, "Base", "y", 1.0);
    let section = "components = [\"x\", \"y\"]\nvalue = [\"0.001*max(2*t - 1, 0)\", \"0.004*min(2*t, 1)\"]";
    assert!(text.contains(section), "the gallery scene's base section moved");
    let forced = text.replace(
        section,
        &format!(
            "components = [\"x\"]\nvalue = [\"0.001*max(2*t - 1, 0)\"]\n\n[[force_control]]\ngroup = \"Base\"\ncomponent = \"y\"\nforce = \"{p:e}*min(2*t, 1)\""
        ),
    );
    let forced = Scene::from_toml_str(&forced, "cattaneo under force control").unwrap_or_else(|e| panic!("{e}"));
    let (_, stats, sink) = solve_in_memory(&forced, mesh()).unwrap_or_else(|e| panic!("{e}"));
    let r = common::reaction(&stats, "Base", "y", 1.0);
    assert!((r - p).abs() <= 1e-10 * p, "reaction {r:e} against P = {p:e}");
    let delta = sink.steps.last().unwrap().motion[0];
    assert!((delta / 0.004 - 1.0).abs() <= 1e-6, "δ = {delta:e}");
}

/// Friction with a long memory (the issue's "with the memory term"): the dragged block of a
/// viscoelastic material (one Prony term), Coulomb μ = 0.3. The memory changes the stresses from
/// step to step (the normal force relaxes under the fixed compression), and once the whole base
/// slides the friction force is still μ times the normal force of the same step, to 1e-10.
#[test]
fn coulomb_friction_with_memory_follows_the_relaxing_normal_force() {
    let text = dragged(&format!("{{ kind = \"coulomb\", coefficient = {MU} }}"))
        + "\n[memory]\nkind = \"exponential\"\nterms = [{ coefficient = -0.3, relaxation_time = 0.5 }]\n";
    let mesh = rectangle_with_sides(1.0, 0.5, 16, 8, CellShape::Quad);
    let (sim, _, sink) = solve_in_memory(&scene(&text), mesh).unwrap_or_else(|e| panic!("{e}"));
    let c = sim.contact.as_ref().unwrap();
    let m = c.nodes.len();
    let normals: Vec<f64> = sink
        .steps
        .iter()
        .map(|s| s.contact.as_ref().unwrap().force[..m].iter().sum())
        .collect();
    // the memory relaxes the normal force of the held compression
    assert!(
        (normals[STEPS] - normals[1]).abs() > 1e-3 * normals[1],
        "the normal force does not relax: {normals:?}"
    );
    for step in &sink.steps[STEPS - 1..] {
        let state = step.contact.as_ref().unwrap();
        assert!(
            state.friction.status.iter().all(|&s| s == 2),
            "t = {}: not fully sliding",
            step.time
        );
        let normal: f64 = state.force[..m].iter().sum();
        let tangential: f64 = state.force[m..].iter().sum();
        assert!(
            (tangential - MU * normal).abs() <= 1e-10 * MU * normal,
            "t = {}: friction {tangential:e} against μ × {normal:e}",
            step.time
        );
    }
}

/// The 3D dragged block (docs/method.md §17.3): the box (0, 1) × (0, 0.5) × (0, 1) of hexahedra
/// on a rigid plane y = 0, its top pressed down by 0.002 and moved by (0.01, 0, 0.006) t — a
/// direction along neither fixed tangent (e_x, e_z) of the base.
/// * At every step and base node the friction force is the vector law's: where the node slips,
///   F ρ/√(ρ² + ε²) times the unit slip vector (ρ its length, F the node's bound force: μ λ_ν or
///   w_p F_b), to 1e-10 of the largest F; where it sticks, shorter than F. Two independent scalar
///   laws on the two tangents would give (±F, ±F), √2 too long off the axes.
/// * The whole base slides from t = 0.3 on, and at T the total friction force is μ × the normal
///   force (Coulomb) or F_b × the base's area (Tresca) along the drag to 1e-4, and every base node
///   slips by the top's increment to 1e-3. Not to round-off as in 2D: in 3D the nodes' slip
///   directions differ at the onset of sliding and relax towards the drag's direction by a
///   factor of about 0.7 per step (measured deviation 3e-5 at T), the translation being reached
///   only in the limit.
///
/// (Tolerance 1e-13, as in 2D. Before the rows were solved for their slip increment this stalled
/// at 1.4e-13: a sticking row's smoothed law is as stiff as F/ε ≈ 10³ here, and the rounding of
/// its total displacement, 2.7e-20 at |u_τ| ≈ 1.7e-4, made forces of 3e-13 of the scale.)
#[test]
fn a_dragged_block_slides_along_its_slip_vector_in_3d() {
    use hvi::mesh::structured::{block, SolidShape};
    let f_b = 0.0005;
    let drag: [f64; 3] = [0.01, 0.0, 0.006];
    let epsilon = 1e-8;
    for (name, friction) in [
        ("coulomb", format!("{{ kind = \"coulomb\", coefficient = {MU} }}")),
        ("tresca", format!("{{ kind = \"tresca\", bound = \"{f_b}\" }}")),
    ] {
        let text = format!(
            r#"
[material]
youngs_modulus = 1.0
poisson_ratio = 0.3

[time]
final_time = 1.0
steps = {STEPS}

[[dirichlet]]
group = "Gamma2_top"
components = ["x", "y", "z"]
value = ["{}*t", "-0.002", "{}*t"]

[contact]
group = "Gamma3"
bound = "0"
friction = {friction}

[solver]
tolerance = 1e-13
"#,
            drag[0], drag[2]
        );
        let mesh = block([1.0, 0.5, 1.0], [6, 3, 6], SolidShape::Hex);
        let (sim, _, sink) = solve_in_memory(&scene(&text), mesh).unwrap_or_else(|e| panic!("{e}"));
        let c = sim.contact.as_ref().unwrap();
        let f = c.friction.as_ref().expect("friction rows");
        let m = c.nodes.len();
        assert_eq!(f.normal_row.len(), 2 * m, "{name}: two tangential rows per base node");
        let rows = f.rows_of(m);
        let area: f64 = c.nodes.weights.iter().sum();
        let norm = (drag[0] * drag[0] + drag[2] * drag[2]).sqrt();
        for step in &sink.steps[1..] {
            let state = step.contact.as_ref().unwrap();
            let largest = state.friction.bound.iter().fold(0.0f64, |a, b| a.max(*b));
            let mut sliding = 0;
            for (p, pair) in rows.iter().enumerate() {
                let [a, b] = [pair[0], pair[1]];
                let (force, slip) = (
                    [state.force[m + a], state.force[m + b]],
                    [state.friction.slip[a], state.friction.slip[b]],
                );
                let (bound, rho) = (state.friction.bound[a], slip[0].hypot(slip[1]));
                match state.friction.status[a] {
                    2 => {
                        sliding += 1;
                        let along = bound / rho.hypot(epsilon);
                        for d in 0..2 {
                            assert!(
                                (force[d] - along * slip[d]).abs() <= 1e-10 * largest,
                                "{name} t = {}, node {p}: force {force:?}, slip {slip:?}, bound {bound:e}",
                                step.time
                            );
                        }
                    }
                    1 => assert!(force[0].hypot(force[1]) < bound, "{name}: a sticking node at its bound"),
                    s => panic!("{name}: base node {p} has status {s}"),
                }
            }
            assert!(
                step.time < 0.25 || sliding == m,
                "{name} t = {}: {sliding} of {m} slide",
                step.time
            );
        }
        let state = sink.steps[STEPS].contact.as_ref().unwrap();
        let normal: f64 = state.force[..m].iter().sum();
        let mut total = [0.0; 3];
        for k in 0..f.normal_row.len() {
            for (d, t) in total.iter_mut().enumerate() {
                *t += state.force[m + k] * f.rows.normals[m + k][d];
            }
        }
        let expected = if name == "coulomb" { MU * normal } else { f_b * area };
        for d in 0..3 {
            let along = expected * drag[d] / norm;
            assert!(
                (total[d] - along).abs() <= 1e-4 * expected,
                "{name}, component {d}: friction {:e} against {along:e}",
                total[d]
            );
        }
        let (a, b) = (&sink.steps[STEPS - 1], &sink.steps[STEPS]);
        let mut worst = 0.0f64;
        for &p in &c.nodes.nodes {
            for d in [0, 2] {
                let increment = drag[d] / STEPS as f64;
                let slip = b.displacement[3 * p + d] - a.displacement[3 * p + d];
                worst = worst.max((slip - increment).abs() / (norm / STEPS as f64));
            }
        }
        eprintln!("{name}: the base's slip at T differs from the top's increment by {worst:.1e} of it");
        assert!(worst <= 1e-3, "{name}: {worst:e}");
    }
}

/// A block on a bilateral support (docs/method.md §17.4): the base of (0, 1) × (0, 0.5) cannot
/// leave y = 0 nor press into it, its top pulled up by 0.001 and dragged along x by 0.01 t.
fn bilateral(friction: &str, steps: usize) -> String {
    format!(
        r#"
[material]
plane = "strain"
youngs_modulus = 1.0
poisson_ratio = 0.3

[time]
final_time = 1.0
steps = {steps}

[[dirichlet]]
group = "Gamma2_top"
components = ["x", "y"]
value = ["0.01*t", "0.001"]

[contact]
bilateral = true
friction = {friction}

[solver]
tolerance = 1e-13
"#
    )
}

/// Bilateral contact with a non-monotone friction potential, the hemivariational case of the
/// literature (docs/method.md §17.4). The base holds u_ν = 0 at every row (to 1e-15 of the top's
/// drag) while the pulled top makes the normal forces tensile (λ_ν < 0, which a one-sided
/// contact cannot carry), and at every row and step the tangential force lies in the Clarke
/// subdifferential w_p S ∂j_τ(u_τ) of the unregularised law — at the paper's softening profile
/// μ(ρ) = 0.5 e^{−100ρ} + 0.5 — widened by what the smoothing ρ_ε = √(u² + ε²) − ε changes:
/// w_p S (|μ'| ε + μ ε²/(2u²)) ≤ w_p S (50 ε + ε²/u²), ε = 1e-8, plus the solve's 1e-13.
/// With a monotone μ (piecewise linear from 0.5 up to 1) the potential is convex and the problem
/// at T has one solution, whatever the path: one step and eight steps to T agree to 1e-9, where
/// the non-monotone law's two paths need not.
#[test]
fn bilateral_contact_with_a_non_monotone_friction_potential() {
    use hvi::contact::ContactLaw;
    let paper = "{ kind = \"potential\", law = { kind = \"paper\", scale = 1e-3, a = 1.0, b = 0.5, alpha = 100.0 } }";
    let mesh = || rectangle_with_sides(1.0, 0.5, 16, 8, CellShape::Quad);
    let (sim, _, sink) = solve_in_memory(&scene(&bilateral(paper, 8)), mesh()).unwrap_or_else(|e| panic!("{e}"));
    let c = sim.contact.as_ref().unwrap();
    let f = c.friction.as_ref().unwrap();
    let m = c.nodes.len();
    let rows = &f.laws_of_rows;
    let law: &ContactLaw = &rows.laws[rows.terms(m)[0].law];
    let (mut checked, mut tensile) = (0, 0);
    for step in &sink.steps[1..] {
        let state = step.contact.as_ref().unwrap();
        for p in 0..m {
            assert!(
                state.normal_displacement[p].abs() <= 1e-15 * 0.01,
                "t = {}: u_ν = {:e} on the bilateral base",
                step.time,
                state.normal_displacement[p]
            );
            tensile += usize::from(state.force[p] < 0.0);
        }
        for (k, &p) in f.normal_row.iter().enumerate() {
            let (u, got) = (state.normal_displacement[m + k], state.force[m + k]);
            let w = c.nodes.weights[p];
            let (lo, hi) = law.clarke_interval(u);
            let slack = w * 1e-3 * (50.0 * 1e-8 + if u == 0.0 { 0.0 } else { (1e-8 / u).powi(2).min(1.0) }) + 1e-13;
            assert!(
                got >= w * lo - slack && got <= w * hi + slack,
                "t = {}: row {k} at u_τ = {u:e} carries {got:e}, outside w S ∂j = [{:e}, {:e}]",
                step.time,
                w * lo,
                w * hi
            );
            checked += 1;
        }
    }
    assert!(tensile > 0, "the pulled top should make some normal forces tensile");
    assert!(checked >= 8 * m);
    // monotone μ: the convex problem's one solution, by two paths
    let convex = "{ kind = \"potential\", law = { kind = \"piecewise_linear\", scale = 1e-3, table = [[0.0, 0.5], [0.002, 1.0], [1.0, 1.0]] } }";
    let last = |steps: usize| {
        let (_, _, sink) = solve_in_memory(&scene(&bilateral(convex, steps)), mesh()).unwrap_or_else(|e| panic!("{e}"));
        sink.steps.last().unwrap().displacement.clone()
    };
    let (one, eight) = (last(1), last(8));
    let scale = one.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let diff = one.iter().zip(&eight).fold(0.0f64, |a, (x, y)| a.max((x - y).abs())) / scale;
    eprintln!("bilateral, monotone μ: one step against eight, max |Δu| / max |u| = {diff:.1e}");
    assert!(diff <= 1e-9, "{diff:e}");
}

/// Bilateral contact holds u_ν = 0: a law or a bound beside it is refused by key and fix.
#[test]
fn bilateral_contact_with_a_law_or_a_bound_is_refused_by_name() {
    for extra in [
        "bound = \"0.1\"",
        "law = { kind = \"power\", scale = 1.0, exponent = 1.0 }",
    ] {
        let text = bilateral("{ kind = \"coulomb\", coefficient = 0.3 }", 2)
            .replace("[contact]", &format!("[contact]\n{extra}"));
        let message = Scene::from_toml_str(&text, "t.toml")
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("contact.bilateral") && message.contains("remove its law and its bound"),
            "{extra}: {message}"
        );
    }
}

/// Convergence in h with Tresca friction (docs/method.md §17.6): the smooth
/// u = k ((1 + x/2)(1 + y)², x² y), k = 0.01, on (0, 1) × (0, 0.5), plane stress E = 1, ν = 0.3,
/// held by its values on x = 0, the tractions of its stress on the right and the top, the body
/// force −div σ, and on the base y = 0 bilateral contact (u_y = 0 there) with Tresca's bound
/// F_b = σ_xy(x, 0) = 2Gk(1 + x/2). The base slips forward (u_x(x, 0) = k(1 + x/2) > 0) in the one
/// step, so friction's traction −F_b is the exact solution's: u is the solution of the Tresca
/// problem, and the elements must approach it at order 1 in the energy (H¹) norm and 2 in L²
/// (fitted on h = 1/8 … 1/64, ±0.1, as the frictionless manufactured test). Every base row
/// slips: the test reaches the law's slip branch, not a Neumann condition in disguise.
#[test]
fn tresca_friction_converges_at_order_one_in_the_energy_norm() {
    use hvi::fem::norms::{errors, fitted_order};
    let (nu, k): (f64, f64) = (0.3, 0.01);
    let c = 1.0 / (1.0 - nu * nu);
    let g = 1.0 / (2.0 * (1.0 + nu));
    let s11 = format!("t*{c:e}*({k:e}/2*(1 + y)^2 + {nu:e}*{k:e}*x^2)");
    let s22 = format!("t*{c:e}*({nu:e}*{k:e}/2*(1 + y)^2 + {k:e}*x^2)");
    let s12 = format!("t*{g:e}*(2*{k:e}*(1 + x/2)*(1 + y) + 2*{k:e}*x*y)");
    let f1 = format!("-t*(2*{c:e}*{nu:e}*{k:e}*x + {g:e}*(2*{k:e}*(1 + x/2) + 2*{k:e}*x))");
    let f2 = format!("-t*({g:e}*({k:e}*(1 + y) + 2*{k:e}*y) + {c:e}*{nu:e}*{k:e}*(1 + y))");
    let text = format!(
        r#"
[material]
plane = "stress"
youngs_modulus = 1.0
poisson_ratio = {nu}

[time]
final_time = 1.0
steps = 1

[[dirichlet]]
group = "Gamma1"
components = ["x", "y"]
value = ["t*{k:e}*(1 + y)^2", "0"]

[[traction]]
group = "Right"
value = ["{s11}", "{s12}"]

[[traction]]
group = "Gamma2_top"
value = ["{s12}", "{s22}"]

[body_force]
value = ["{f1}", "{f2}"]

[contact]
bilateral = true
friction = {{ kind = "tresca", bound = "t*{g:e}*2*{k:e}*(1 + x/2)" }}

[solver]
tolerance = 1e-12
"#
    );
    let exact = |x: [f64; 2]| -> ([f64; 2], [[f64; 2]; 2]) {
        let (a, b) = (x[0], x[1]);
        (
            [k * (1.0 + a / 2.0) * (1.0 + b).powi(2), k * a * a * b],
            [
                [k / 2.0 * (1.0 + b).powi(2), 2.0 * k * (1.0 + a / 2.0) * (1.0 + b)],
                [2.0 * k * a * b, k * a * a],
            ],
        )
    };
    for shape in [CellShape::Quad, CellShape::Tri] {
        let (mut hs, mut h1, mut l2) = (vec![], vec![], vec![]);
        for n in [8, 16, 32, 64] {
            let mesh = rectangle_with_sides(1.0, 0.5, n, n / 2, shape);
            let (sim, _, sink) = solve_in_memory(&scene(&text), mesh).unwrap_or_else(|e| panic!("{e}"));
            let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
            assert!(
                !state.friction.status.is_empty() && state.friction.status.iter().all(|&s| s == 2),
                "{shape:?} n = {n}: every base row should slip: {:?}",
                state.friction.status
            );
            let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
            let e = errors(&sim.mesh.cells, &sim.mesh.points, &u, exact);
            hs.push(1.0 / n as f64);
            h1.push(e.h1_seminorm);
            l2.push(e.l2);
        }
        let (p1, p2) = (fitted_order(&hs, &h1), fitted_order(&hs, &l2));
        eprintln!("Tresca, {shape:?}: H¹ order {p1:.3}, L² order {p2:.3} (H¹ errors {h1:?})");
        assert!((p1 - 1.0).abs() <= 0.1, "{shape:?}: H¹ order {p1} (errors {h1:?})");
        assert!((p2 - 2.0).abs() <= 0.1, "{shape:?}: L² order {p2} (errors {l2:?})");
    }
}

/// 3D friction with a long memory (examples/gallery/cattaneo_3d/cattaneo_3d_memory.toml): the
/// Cattaneo–Mindlin block made viscoelastic (B(s) = −e^{−s/0.3} A), pressed, sheared, then held.
/// After the shear the contact's edge slips; in the hold the memory relaxes the tractions: the
/// normal force falls at every step, no node slips any more (a held body relaxing below the
/// Coulomb bound), and the tangential force that friction locked in stays above half of μ times
/// the normal force (frictionless, it would be zero) while it relaxes. At every step the base's
/// and the symmetry plane's reactions and the contact forces balance to 1e-10 of P.
#[test]
fn friction_with_memory_in_3d_locks_the_shear_in_while_the_body_relaxes() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/cattaneo_3d");
    let scene = Scene::load(Some(&root.join("cattaneo_3d_memory.toml")), &[]).unwrap_or_else(|e| panic!("{e}"));
    let mesh = read_mesh::<3>(&root.join("cattaneo_3d_coarse.msh")).unwrap_or_else(|e| panic!("{e}"));
    let (sim, stats, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let mu = 0.6;
    let c = sim.contact.as_ref().unwrap();
    let f = c.friction.as_ref().unwrap();
    let m = c.nodes.len();
    let totals: Vec<(f64, f64)> = sink
        .steps
        .iter()
        .map(|s| {
            let state = s.contact.as_ref().unwrap();
            let p: f64 = state.force[..m].iter().sum();
            let q: f64 = (0..f.normal_row.len())
                .map(|k| state.force[m + k] * f.rows.normals[m + k][0])
                .sum();
            (p, q)
        })
        .collect();
    let sheared = sink.steps[2].contact.as_ref().unwrap();
    assert!(sheared.friction.status.contains(&2), "the shear step slips at the edge");
    for n in 3..sink.steps.len() {
        let state = sink.steps[n].contact.as_ref().unwrap();
        let (p, q) = totals[n];
        assert!(
            p < totals[n - 1].0,
            "step {n}: the normal force does not relax: {totals:?}"
        );
        assert!(
            !state.friction.status.contains(&2),
            "step {n}: a node slips in the hold"
        );
        assert!(
            q > 0.5 * mu * p && q < mu * p,
            "step {n}: Q = {q:e} against μP = {:e}",
            mu * p
        );
    }
    let p0 = totals[2].0;
    for r in &stats.reactions {
        let contact: f64 = stats
            .contact_forces
            .iter()
            .filter(|c| c.time == r.time && c.component == r.component)
            .map(|c| c.force)
            .sum();
        let reactions: f64 = stats
            .reactions
            .iter()
            .filter(|s| s.time == r.time && s.component == r.component)
            .map(|s| s.force)
            .sum();
        assert!(
            (reactions + contact).abs() <= 1e-10 * p0,
            "t = {}, {}: reactions {reactions:e} + contact {contact:e}",
            r.time,
            r.component
        );
    }
    eprintln!("3D Cattaneo–Mindlin with memory, (P, Q) per step: {totals:?}");
}

/// A semi-coercive body held by its friction (docs/method.md §7.7, §17.7): the block's top is
/// pressed down by a prescribed u_y and nothing prescribes x, so the translation in x is a free
/// rigid motion (pinned by a rigid parameter) that only Coulomb friction on the base can hold.
/// A sideways load on the left side below μ × the normal force is held: the base's friction
/// force balances it to 1e-10 at every step (the first guess of such a body's Coulomb fixed
/// point is full stick: with no normal force yet, friction of bound 0 would hold nothing). Ten
/// times the load exceeds μP: the run stops with the message that names the motion and friction.
#[test]
fn friction_holds_a_semi_coercive_body_up_to_its_bound() {
    let text = |load: f64| {
        format!(
            r#"
[material]
plane = "strain"
youngs_modulus = 1.0
poisson_ratio = 0.3

[time]
final_time = 1.0
steps = 2

[[dirichlet]]
group = "Gamma2_top"
components = ["y"]
value = ["-0.002*t"]

[[traction]]
group = "Gamma1"
value = ["{load}*t", "0"]

[contact]
bound = "0"
friction = {{ kind = "coulomb", coefficient = {MU} }}

[solver]
tolerance = 1e-12
"#
        )
    };
    let mesh = || rectangle_with_sides(2.0, 1.0, 16, 8, CellShape::Quad);
    let load = 0.0003;
    let (sim, stats, _) = solve_in_memory(&scene(&text(load)), mesh()).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !sim.dirichlet.held_by_contact.is_empty(),
        "x should be held by the contact only"
    );
    for t in [0.5, 1.0] {
        let force = |component: &str| {
            stats
                .contact_forces
                .iter()
                .find(|c| c.time == t && c.component == component)
                .unwrap()
                .force
        };
        let (fx, fy) = (force("x"), force("y"));
        assert!(
            (fx + load * t).abs() <= 1e-10 * fy,
            "t = {t}: friction {fx:e} against the load {:e}",
            load * t
        );
        assert!(fx.abs() < MU * fy, "t = {t}: held below μP");
    }
    let err = solve_in_memory(&scene(&text(10.0 * load)), mesh())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("translation in x") && err.contains("friction holds at most"),
        "{err}"
    );
}
