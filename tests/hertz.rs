//! Hertz contact against the closed forms (docs/method.md §10.3): a rigid cylinder (2D, plane
//! strain) and a rigid sphere (3D) pressed into a block by a prescribed displacement,
//! frictionless. The rigid body is the bound g = R − sqrt(R² − r²) of u_ν ≤ g on the block's
//! flat top (the gap to the cylinder or sphere along the top's normal); meshes and scenes are
//! the gallery's (examples/gallery/hertz_2d, hertz_3d).

mod common;

use hvi::app::solve_in_memory;
use hvi::mesh::{read_mesh, Mesh};
use hvi::scene::Scene;
use std::path::{Path, PathBuf};

fn gallery(entry: &str, file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/gallery")
        .join(entry)
        .join(file)
}

fn scene(entry: &str) -> Scene {
    Scene::load(Some(&gallery(entry, &format!("{entry}.toml"))), &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// What a run gives: the total force P on the contact group (the symmetry part's contact force
/// scaled to the whole body), the reaction on the pushed group (same scaling), and per contact
/// node on the obstacle its distance r from the axis and its pressure λ_p / w_p.
struct Contact {
    force: f64,
    reaction: f64,
    /// The first rigid parameter's displacement (a force-controlled base's δ), NaN without one.
    motion: f64,
    pressures: Vec<(f64, f64)>,
}

fn run<const D: usize>(entry: &str, mesh: &str, symmetry_factor: f64) -> Contact {
    run_scene::<D>(&scene(entry), entry, mesh, symmetry_factor)
}

fn run_scene<const D: usize>(scene: &Scene, entry: &str, mesh: &str, symmetry_factor: f64) -> Contact {
    let mesh = read_mesh::<D>(&gallery(entry, mesh)).unwrap_or_else(|e| panic!("{e}"));
    run_mesh(scene, mesh, symmetry_factor)
}

fn run_mesh<const D: usize>(scene: &Scene, mesh: Mesh<D>, symmetry_factor: f64) -> Contact {
    let (sim, stats, sink) = solve_in_memory(scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let last = sink.steps.last().unwrap();
    let state = last.contact.as_ref().unwrap();
    let pressures = common::bound_pressures(&sim, &sink);
    let axis = ["x", "y", "z"][D - 1];
    Contact {
        force: symmetry_factor * state.force.iter().sum::<f64>(),
        reaction: symmetry_factor * common::reaction(&stats, "Base", axis, last.time),
        motion: last.motion.first().copied().unwrap_or(f64::NAN),
        pressures,
    }
}

/// The relative errors of a run's a and p₀ (fitted) against Hertz of dimension `dim`, after
/// checking that the pushed base's reaction balances the contact force to 1e-9.
fn balanced_errors(label: &str, c: &Contact, dim: usize, e_star: f64) -> (f64, f64) {
    assert!(
        (c.reaction - c.force).abs() <= 1e-9 * c.force,
        "{label}: reaction {} against the contact force {}",
        c.reaction,
        c.force
    );
    common::hertz_errors(c.force, &c.pressures, dim, e_star)
}

/// Plane strain, E = 1, ν = 0.3, R = 1: a² = 4PR/(πE*), p₀ = 2P/(πa), with P the force per unit
/// length. Three meshes, element size on the contact a/8, a/16, a/33 (hf = 0.005, 0.0025,
/// 0.00125; a ≈ 0.041).
///
/// Tolerances: 1 % on a and p₀ (the issue's). The block is 2 × 2 = 49a × 49a, so the
/// half-plane formula's error from the finite body is far below that (the measured a is within
/// 0.1 % on the finest mesh); what remains is the discretisation, and the error in a must shrink
/// from mesh to mesh. The reaction of the pushed base equals the contact force to 1e-9
/// (equilibrium of the body: both are the same linear functional of one solution).
#[test]
fn hertz_2d_cylinder_half_width_and_peak_pressure_within_one_percent() {
    let e_star = 1.0 / (1.0 - 0.3f64 * 0.3);
    let mut errors = Vec::new();
    eprintln!("| mesh | nodes in contact | P | a (fit) | a (Hertz) | error | p₀ (fit) | p₀ (Hertz) | error |");
    for mesh in ["hertz_2d_h1.msh", "hertz_2d_h2.msh", "hertz_2d_h3.msh"] {
        // the half model carries half of the force per unit length
        let c = run::<2>("hertz_2d", mesh, 2.0);
        assert!(
            (c.reaction - c.force).abs() <= 1e-9 * c.force,
            "{mesh}: reaction {} against the contact force {}",
            c.reaction,
            c.force
        );
        let p = c.force;
        let (a_hertz, p0_hertz) = common::hertz(2, p, e_star);
        let (a, p0) = common::hertz_fit(&c.pressures);
        let (ea, ep) = (a / a_hertz - 1.0, p0 / p0_hertz - 1.0);
        eprintln!(
            "| {mesh} | {} | {p:.5e} | {a:.5} | {a_hertz:.5} | {:+.2} % | {p0:.5} | {p0_hertz:.5} | {:+.2} % |",
            c.pressures.len(),
            100.0 * ea,
            100.0 * ep
        );
        assert!(c.pressures.len() >= 8, "{mesh}: a is resolved by too few nodes");
        assert!(ea.abs() < 0.01, "{mesh}: a = {a} against Hertz {a_hertz}");
        assert!(ep.abs() < 0.01, "{mesh}: p₀ = {p0} against Hertz {p0_hertz}");
        errors.push(ea.abs());
    }
    assert!(
        errors.windows(2).all(|w| w[1] < w[0]),
        "the error in a does not shrink with h: {errors:?}"
    );
}

/// The same 2D Hertz problem posed with the rigid obstacle instead of the bound expression:
/// `obstacle = { kind = "circle", centre = [0, 1], radius = 1 }` on the finest mesh.
/// * `direction = "body"`: the gap along the top's normal (0, 1) to the circle is exactly
///   1 − sqrt(1 − x²), the bound expression, so the runs agree to rounding (1e-9 relative in
///   P, a and p₀: the same problem assembled through two paths).
/// * `direction = "obstacle"` (the default with an obstacle): the constraint acts along the
///   circle's normal, tilted by x/R from the vertical, so u·n picks up the tangential surface
///   displacement, (x/R) u_x, beside the gap x²/(2R): a relative change O(u_x/a), which Hertz's
///   theory neglects. Measured on this mesh: P +0.32 %, a +0.62 %, p₀ −0.35 % against the bound
///   version, and a +0.39 %, p₀ −0.35 % against Hertz with its own P. Asked: 1 % for both.
#[test]
fn hertz_2d_with_the_circle_obstacle_agrees_with_the_bound() {
    let text = std::fs::read_to_string(gallery("hertz_2d", "hertz_2d.toml")).unwrap();
    let bound_line = "bound = \"1 - sqrt(1 - x^2)\"";
    assert!(text.contains(bound_line));
    let with = |direction: &str| {
        let t = text.replace(
            bound_line,
            &format!(
                "obstacle = {{ kind = \"circle\", centre = [0.0, 1.0], radius = 1.0 }}\ndirection = \"{direction}\""
            ),
        );
        Scene::from_toml_str(&t, "hertz_2d with a circle").unwrap_or_else(|e| panic!("{e}"))
    };
    let mesh = "hertz_2d_h3.msh";
    let bound = run::<2>("hertz_2d", mesh, 2.0);
    let (a_b, p0_b) = common::hertz_fit(&bound.pressures);
    let e_star = 1.0 / (1.0 - 0.3f64 * 0.3);
    for (direction, tol) in [("body", 1e-9), ("obstacle", 1e-2)] {
        let c = run_scene::<2>(&with(direction), "hertz_2d", mesh, 2.0);
        let (a, p0) = common::hertz_fit(&c.pressures);
        let (a_hertz, p0_hertz) = common::hertz(2, c.force, e_star);
        eprintln!(
            "circle, direction {direction}: P = {:.6e} (bound {:.6e}), a = {a:.5} (bound {a_b:.5}, Hertz {a_hertz:.5}), p₀ = {p0:.5} (bound {p0_b:.5}, Hertz {p0_hertz:.5})",
            c.force, bound.force
        );
        assert!((c.force / bound.force - 1.0).abs() <= tol, "{direction}: P");
        assert!((a / a_b - 1.0).abs() <= tol, "{direction}: a = {a} against {a_b}");
        assert!((p0 / p0_b - 1.0).abs() <= tol, "{direction}: p₀ = {p0} against {p0_b}");
        assert!(
            (a / a_hertz - 1.0).abs() < 0.01 && (p0 / p0_hertz - 1.0).abs() < 0.01,
            "{direction}: Hertz"
        );
    }
}

/// E = 1, ν = 0.3, R = 1: a³ = 3PR/(4E*), p₀ = 3P/(2πa²), with P the total force. One mesh of
/// tetrahedra (examples/gallery/hertz_3d/hertz_3d.msh, element size a/14 on the contact patch).
///
/// Tolerances: 3 % on a and 5 % on p₀ (the issue's). On this mesh a is found within 0.4 % and
/// p₀ within 1.5 % (P1 tetrahedra overestimate the peak: the nodal pressure at the centre is
/// the least accurate, with the fewest nodes near it); the block is 15a on each side, so the
/// half-space formula's own error is well below both. The reaction of the pushed base equals
/// the contact force to 1e-9.
#[test]
fn hertz_3d_sphere_contact_radius_within_3_percent_and_peak_pressure_within_5() {
    let e_star = 1.0 / (1.0 - 0.3f64 * 0.3);
    // the quarter model carries a quarter of the force
    let c = run::<3>("hertz_3d", "hertz_3d.msh", 4.0);
    assert!(
        (c.reaction - c.force).abs() <= 1e-9 * c.force,
        "reaction {} against the contact force {}",
        c.reaction,
        c.force
    );
    let p = c.force;
    let (a_hertz, p0_hertz) = common::hertz(3, p, e_star);
    let (a, p0) = common::hertz_fit(&c.pressures);
    let (ea, ep) = (a / a_hertz - 1.0, p0 / p0_hertz - 1.0);
    eprintln!(
        "3D: {} nodes in contact, P = {p:.5e}, a = {a:.5} (Hertz {a_hertz:.5}, {:+.2} %), p₀ = {p0:.5} (Hertz {p0_hertz:.5}, {:+.2} %)",
        c.pressures.len(),
        100.0 * ea,
        100.0 * ep
    );
    assert!(c.pressures.len() >= 30, "a is resolved by too few nodes");
    assert!(ea.abs() < 0.03, "a = {a} against Hertz {a_hertz}");
    assert!(ep.abs() < 0.05, "p₀ = {p0} against Hertz {p0_hertz}");
}

/// The gallery's Hertz scene with its base pushed by the force `force` (half or quarter model's
/// share) through a `[[force_control]]` section instead of the prescribed δ = `delta`·t.
fn force_controlled(entry: &str, axis: &str, delta: &str, force: f64) -> Scene {
    let t = force_controlled_text(entry, axis, delta, force);
    Scene::from_toml_str(&t, &format!("{entry} under force control")).unwrap_or_else(|e| panic!("{e}"))
}

/// The text of [`force_controlled`]'s scene.
fn force_controlled_text(entry: &str, axis: &str, delta: &str, force: f64) -> String {
    let text = std::fs::read_to_string(gallery(entry, &format!("{entry}.toml"))).unwrap();
    let section = format!("group = \"Base\"\ncomponents = [\"{axis}\"]\nvalue = [\"{delta}*t\"]");
    assert!(text.contains(&section), "{entry}: the base section moved");
    let start = text.find(&section).unwrap();
    let header = text[..start].rfind("[[dirichlet]]").unwrap();
    format!(
        "{}[[force_control]]\ngroup = \"Base\"\ncomponent = \"{axis}\"\nforce = \"{force:e}*t\"{}",
        &text[..header],
        &text[start + section.len()..]
    )
}

/// Force control (docs/method.md §7.7): the 2D and 3D Hertz blocks pressed by a given force P
/// (the one the displacement-controlled runs find) through their base, which nothing else holds
/// along the axis: the base's reaction is P to 1e-10, a and p₀ are Hertz's to the gallery's
/// tolerances (1 % in 2D; 3 % and 5 % in 3D), and the base moves by the displacement control's
/// δ (to 1e-8: the same discrete problem solved the other way round, where only the contact
/// solve's tolerance 1e-10 and the conditioning of S separate them).
#[test]
fn hertz_under_force_control_matches_hertz_and_the_displacement_control() {
    let e_star = 1.0 / (1.0 - 0.3f64 * 0.3);
    // (entry, mesh, symmetry factor, axis, δ)
    for (entry, mesh, factor, axis, delta) in [
        ("hertz_2d", "hertz_2d_h3.msh", 2.0, "y", 0.004),
        ("hertz_3d", "hertz_3d.msh", 4.0, "z", 0.01),
    ] {
        let displaced = run_scene_any(&scene(entry), entry, mesh, factor);
        let share = displaced.force / factor;
        let forced_scene = force_controlled(entry, axis, &delta.to_string(), share);
        let forced = run_scene_any(&forced_scene, entry, mesh, factor);
        assert!(
            (forced.reaction - displaced.force).abs() <= 1e-10 * displaced.force,
            "{entry}: the base's reaction {} against P = {}",
            forced.reaction,
            displaced.force
        );
        assert!(
            (forced.force - displaced.force).abs() <= 1e-9 * displaced.force,
            "{entry}: the contact force {} against P = {}",
            forced.force,
            displaced.force
        );
        assert!(
            (forced.motion - delta).abs() <= 1e-8 * delta,
            "{entry}: δ = {} against the displacement control's {delta}",
            forced.motion
        );
        let p = forced.force;
        let (a, p0) = common::hertz_fit(&forced.pressures);
        let (dim, tol_a, tol_p) = if entry == "hertz_2d" {
            (2, 0.01, 0.01)
        } else {
            (3, 0.03, 0.05)
        };
        let (a_hertz, p0_hertz) = common::hertz(dim, p, e_star);
        eprintln!(
            "{entry} under force control: P = {p:.6e}, δ = {:.10e}, a = {a:.5} (Hertz {a_hertz:.5}), p₀ = {p0:.5} (Hertz {p0_hertz:.5})",
            forced.motion
        );
        assert!(
            (a / a_hertz - 1.0).abs() < tol_a,
            "{entry}: a = {a} against Hertz {a_hertz}"
        );
        assert!(
            (p0 / p0_hertz - 1.0).abs() < tol_p,
            "{entry}: p₀ = {p0} against Hertz {p0_hertz}"
        );
    }
}

/// [`run_scene`] in the dimension of the entry.
fn run_scene_any(scene: &Scene, entry: &str, mesh: &str, factor: f64) -> Contact {
    if entry.ends_with("3d") {
        run_scene::<3>(scene, entry, mesh, factor)
    } else {
        run_scene::<2>(scene, entry, mesh, factor)
    }
}

/// 2D Hertz at ν = 0.4999 (K/G = 5 000) on quadrilaterals (hertz_2d_q3.msh: the gallery's .geo
/// recombined and subdivided, element size a/33 on the contact): with mean dilatation (chosen by
/// `material.formulation = "auto"` at this K/G) a and p₀ within 2 % of Hertz; the plain Q1 element
/// on the same mesh locks (measured −28 % / +40 % on another mesh, issue 43): the test shows both.
#[test]
fn hertz_2d_nearly_incompressible_on_quadrilaterals_with_mean_dilatation() {
    nearly_incompressible_hertz_2d("hertz_2d_q3.msh");
}

/// The same on triangles (hertz_2d_h3.msh, the gallery's P1 mesh, element size a/40 on the
/// contact): the patch-mean dilatation (docs/method.md §8.4) against the locking plain P1.
#[test]
fn hertz_2d_nearly_incompressible_on_triangles_with_patch_dilatation() {
    nearly_incompressible_hertz_2d("hertz_2d_h3.msh");
}

/// 3D Hertz at ν = 0.4999 on the gallery's tetrahedra (a/14 on the contact): the patch-mean
/// dilatation (docs/method.md §8.4) holds a and p₀ within the 2 % (measured −0.52 %,
/// +1.29 %; the node patches hvi had before: −0.77 %, +2.8 %), where the plain P1 tetrahedron
/// locks (a +550 %).
#[test]
fn hertz_3d_nearly_incompressible_on_tetrahedra_with_patch_dilatation() {
    nearly_incompressible("3D tetrahedra", "hertz_3d", &[], 3, |scene| {
        run_scene::<3>(scene, "hertz_3d", "hertz_3d.msh", 4.0)
    });
}

/// a and p₀ of 2D Hertz at ν = 0.4999 on `mesh`: within 2 % with `formulation = "auto"`, more
/// than 5 % off with the plain element.
fn nearly_incompressible_hertz_2d(mesh: &str) {
    nearly_incompressible(mesh, "hertz_2d", &[], 2, |scene| {
        run_scene::<2>(scene, "hertz_2d", mesh, 2.0)
    });
}

/// The errors of a and p₀ (Hertz of dimension `dim`) at ν = 0.4999 on the gallery `entry`'s
/// scene with the overrides `extra`, run by `run` with `formulation = "auto"` and with the plain
/// element (`"standard"`), in that order; `label` names the case in the output.
fn auto_and_standard(
    label: &str,
    entry: &str,
    extra: &[&str],
    dim: usize,
    run: impl Fn(&Scene) -> Contact,
) -> [(f64, f64); 2] {
    let nu = 0.4999f64;
    let e_star = 1.0 / (1.0 - nu * nu);
    ["auto", "standard"].map(|formulation| {
        let mut overrides: Vec<String> = extra.iter().map(|e| e.to_string()).collect();
        overrides.push(format!("material.poisson_ratio={nu}"));
        overrides.push(format!("material.formulation=\"{formulation}\""));
        let scene = Scene::load(Some(&gallery(entry, &format!("{entry}.toml"))), &overrides).unwrap();
        let c = run(&scene);
        let (ea, ep) = common::hertz_errors(c.force, &c.pressures, dim, e_star);
        eprintln!(
            "{label} ν = 0.4999 {formulation}: {} nodes in contact, a {:+.2} %, p₀ {:+.2} %",
            c.pressures.len(),
            100.0 * ea,
            100.0 * ep
        );
        (ea, ep)
    })
}

/// Hertz at ν = 0.4999 (K/G = 5 000) on the gallery `entry`'s scene with the overrides `extra`,
/// run by `run` with `formulation = "auto"` and with the plain element (`"standard"`): a and p₀
/// (Hertz of dimension `dim`) within 2 % with the first, more than 5 % off with the second
/// (it locks). `label` names the case in the output and the messages.
fn nearly_incompressible(label: &str, entry: &str, extra: &[&str], dim: usize, run: impl Fn(&Scene) -> Contact) {
    let results = auto_and_standard(label, entry, extra, dim, run);
    let (ea, ep) = results[0];
    assert!(
        ea.abs() < 0.02 && ep.abs() < 0.02,
        "{label}: the locking-free element: a {ea:+.4}, p₀ {ep:+.4}"
    );
    let (sa, sp) = results[1];
    assert!(
        sa.abs().max(sp.abs()) > 0.05,
        "{label}: the plain element locks: a {sa:+.4}, p₀ {sp:+.4}"
    );
}

/// The sphere as a body of revolution (docs/method.md §8.6): the 2D gallery's meridian half
/// (0, 2) × (−2, 0) with `material.plane = "axisymmetric"`, x = r, the same gap
/// 1 − sqrt(1 − r²) (now a sphere's), the axis x = 0 where u_r = 0: a and p₀ of 3D Hertz,
/// a³ = 3PR/(4E*), p₀ = 3P/(2πa²), within 1 % on quadrilaterals of a/50, on triangles of a/60 and
/// on gmsh's 6-node triangles of a/12 and a/25 (§19; measured a +0.05 %, p₀ +0.03 and +0.04 %),
/// the total force P off the revolved contact weights; the base's reaction is that force to 1e-9.
#[test]
fn hertz_sphere_as_a_body_of_revolution_within_one_percent() {
    let e_star = 1.0 / (1.0 - 0.3f64 * 0.3);
    let scene = Scene::load(
        Some(&gallery("hertz_2d", "hertz_2d.toml")),
        &["material.plane=\"axisymmetric\"".to_string()],
    )
    .unwrap();
    let second = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/second_order");
    for path in [
        gallery("hertz_2d", "hertz_2d_q3.msh"),
        gallery("hertz_2d", "hertz_2d_h3.msh"),
        second.join("hertz_2d_p2_a8.msh"),
        second.join("hertz_2d_p2_a16.msh"),
    ] {
        let mesh = path.file_name().unwrap().to_string_lossy().to_string();
        let c = run_mesh::<2>(&scene, read_mesh::<2>(&path).unwrap_or_else(|e| panic!("{e}")), 1.0);
        let (ea, ep) = balanced_errors(&mesh, &c, 3, e_star);
        eprintln!(
            "axisymmetric {mesh}: {} nodes, P = {:.5e}, a {:+.2} %, p₀ {:+.2} %",
            c.pressures.len(),
            c.force,
            100.0 * ea,
            100.0 * ep
        );
        assert!(ea.abs() < 0.01 && ep.abs() < 0.01, "{mesh}: a {ea:+.4}, p₀ {ep:+.4}");
    }
}

/// 3D Hertz at ν = 0.4999 on hexahedra: the graded structured quarter above (h = 0.16/12 =
/// 0.0133 ≈ a/7.6 on the patch, cells growing by 1.3 beyond it; 15 625 nodes) with mean
/// dilatation (B-bar per cell, chosen by `formulation = "auto"`, docs/method.md §8.4): a and p₀
/// within 2 % of Hertz (the bound; measured −0.11 %, −0.28 %); the plain trilinear
/// hexahedron on the same mesh locks (measured −22 %, +76 %; asserted more than 5 % off).
#[test]
fn hertz_3d_nearly_incompressible_on_hexahedra_with_mean_dilatation() {
    nearly_incompressible("3D hexahedra", "hertz_3d", &[], 3, |scene| {
        let c = run_mesh::<3>(scene, common::hertz_3d_hexahedra(12, 1.3), 4.0);
        // to rounding: K's entries carry λ ≈ 5 000 μ, and the sums of K u lose about as many
        // digits (measured 1.3e-9 on the plain element, 1e-10 and below elsewhere)
        assert!(
            (c.reaction - c.force).abs() <= 1e-8 * c.force,
            "reaction {} against the contact force {}",
            c.reaction,
            c.force
        );
        c
    });
}

/// The sphere as a body of revolution against hvi's own 3D run of the same case: the rigid sphere
/// (R = 1) on an elastic block (E = 1, ν = 0.3) pressed by the same total force P, the one the 3D
/// quarter on hexahedra (the graded mesh above with h = 0.01 ≈ a/7 on the patch, δ = 0.005, so
/// that a ≈ 0.07 stays inside the meridian mesh's contact group r < 0.1) carries; the
/// axisymmetric meridian (hertz_2d_q3.msh, a/35, force control) then gives a and p₀ within 1 % of
/// the 3D run's (the bound; the two bodies differ only far from the contact: a 1.5 cube's
/// quarter and a cylinder of radius and height 2, which moves δ but not a(P) to this order), and
/// each within 1 % of Hertz.
#[test]
fn the_sphere_as_a_body_of_revolution_matches_the_3d_run() {
    let e_star = 1.0 / (1.0 - 0.3f64 * 0.3);
    let text = std::fs::read_to_string(gallery("hertz_3d", "hertz_3d.toml")).unwrap();
    assert!(
        text.contains("value = [\"0.01*t\"]"),
        "hertz_3d.toml: the base's δ moved"
    );
    let half_push = text.replace("value = [\"0.01*t\"]", "value = [\"0.005*t\"]");
    let solid_scene = Scene::from_toml_str(&half_push, "hertz_3d with δ = 0.005").unwrap();
    let solid = run_mesh::<3>(&solid_scene, common::hertz_3d_hexahedra(16, 1.3), 4.0);
    let p = solid.force;
    let text =
        force_controlled_text("hertz_2d", "y", "0.004", p).replace("plane = \"strain\"", "plane = \"axisymmetric\"");
    let axisymmetric = Scene::from_toml_str(&text, "hertz_2d as a body of revolution").unwrap();
    let revolved = run_scene::<2>(&axisymmetric, "hertz_2d", "hertz_2d_q3.msh", 1.0);
    assert!(
        (revolved.reaction - p).abs() <= 1e-9 * p,
        "the meridian's base carries {} against P = {p}",
        revolved.reaction
    );
    let (a_hertz, p0_hertz) = common::hertz(3, p, e_star);
    let (a3, p3) = common::hertz_fit(&solid.pressures);
    let (a2, p2) = common::hertz_fit(&revolved.pressures);
    eprintln!(
        "P = {p:.5e}: 3D hexahedra a = {a3:.5} ({:+.2} % of Hertz), p₀ = {p3:.5} ({:+.2} %); \
         axisymmetric a = {a2:.5} ({:+.2} %), p₀ = {p2:.5} ({:+.2} %); axisymmetric/3D a {:+.2} %, p₀ {:+.2} %",
        100.0 * (a3 / a_hertz - 1.0),
        100.0 * (p3 / p0_hertz - 1.0),
        100.0 * (a2 / a_hertz - 1.0),
        100.0 * (p2 / p0_hertz - 1.0),
        100.0 * (a2 / a3 - 1.0),
        100.0 * (p2 / p3 - 1.0)
    );
    for (what, v) in [
        ("3D a against Hertz", a3 / a_hertz),
        ("3D p₀ against Hertz", p3 / p0_hertz),
        ("axisymmetric a against Hertz", a2 / a_hertz),
        ("axisymmetric p₀ against Hertz", p2 / p0_hertz),
        ("axisymmetric a against 3D", a2 / a3),
        ("axisymmetric p₀ against 3D", p2 / p3),
    ] {
        assert!((v - 1.0).abs() < 0.01, "{what}: {:+.3} %", 100.0 * (v - 1.0));
    }
}

/// The sphere as a body of revolution at ν = 0.4999 (K/G = 5 000) on the meridian's
/// quadrilaterals (a/50) and triangles (a/60): mean dilatation with the hoop strain, per cell and
/// over patches of cells (docs/method.md §8.4, §8.6), keeps a and p₀ within 2 % of Hertz (the issue's
/// bound); the plain Q1 and P1 lock (more than 5 % off).
#[test]
fn the_nearly_incompressible_sphere_as_a_body_of_revolution() {
    for mesh in ["hertz_2d_q3.msh", "hertz_2d_h3.msh"] {
        nearly_incompressible_sphere_as_a_body_of_revolution(mesh);
    }
}

fn nearly_incompressible_sphere_as_a_body_of_revolution(mesh: &str) {
    let label = format!("axisymmetric {mesh}");
    nearly_incompressible(&label, "hertz_2d", &["material.plane=\"axisymmetric\""], 3, |scene| {
        run_scene::<2>(scene, "hertz_2d", mesh, 1.0)
    });
}

/// 3D Hertz on second-order cells (docs/method.md §19.3): gmsh's 10-node tetrahedra of the
/// gallery's geometry (meshes/second_order/hertz_3d_tet10_a{7,10}.msh: element size a/7 and a/10
/// on the contact) and the graded hexahedra above with h = 0.16/f on the patch (f = 6, 8, 10: a/3.8,
/// a/5.1, a/6.3) raised to 27 and 20 nodes; the reaction equal to the contact force on each.
///
/// Asserted: a and p₀ within the 1 % of Hertz on every mesh, and the 20-node meshes' a
/// falling from a/5.1 to a/6.3. Measured with the rows' dual functions (§19.3): 10-node a/7
/// +0.02 %, +0.03 %, a/10 +0.00 %, +0.09 %; 27-node a/3.8 −0.19 %, +0.57 %, a/5.1 +0.11 %,
/// +0.34 %; 20-node a/5.1 +0.60 %, −0.30 %, a/6.3 +0.31 %, −0.19 % (a/3.8, not run here: +1.95 %,
/// −1.04 %). With the split functions before them a did not converge on the hexahedra (27-node
/// +0.96 %, +2.70 %; 20-node, rows at the corners, +13 %, +9.0 %, +1.14 %): the rows at the
/// edge of the zone swung by 10–20 % of p₀. With the bound taken at the row's node instead of its
/// weighted gap the tetrahedra's pressures scattered and a/10 was +3.7 % off.
#[test]
fn hertz_3d_on_second_order_cells() {
    let e_star = 1.0 / (1.0 - 0.3f64 * 0.3);
    let scene = scene("hertz_3d");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/second_order");
    let tet10 =
        |s: &str| read_mesh::<3>(&dir.join(format!("hertz_3d_tet10_{s}.msh"))).unwrap_or_else(|e| panic!("{e}"));
    let hexahedra =
        |fine: usize, complete: bool| hvi::mesh::structured::elevate(&common::hertz_3d_hexahedra(fine, 1.3), complete);
    let cases = [
        ("tet10 a/7", tet10("a7")),
        ("tet10 a/10", tet10("a10")),
        ("hex27 a/3.8", hexahedra(6, true)),
        ("hex27 a/5.1", hexahedra(8, true)),
        ("hex20 a/5.1", hexahedra(8, false)),
        ("hex20 a/6.3", hexahedra(10, false)),
    ];
    let mut hex20 = Vec::new();
    for (label, mesh) in cases {
        let unknowns = 3 * mesh.points.len();
        let c = run_mesh::<3>(&scene, mesh, 4.0);
        let (ea, ep) = balanced_errors(label, &c, 3, e_star);
        eprintln!(
            "{label}: {unknowns} unknowns, {} rows on the sphere, a {:+.2} %, p₀ {:+.2} %",
            c.pressures.len(),
            100.0 * ea,
            100.0 * ep
        );
        assert!(c.pressures.len() >= 30, "{label}: a is resolved by too few rows");
        assert!(ea.abs() < 0.01 && ep.abs() < 0.01, "{label}: a {ea:+e}, p₀ {ep:+e}");
        if label.starts_with("hex20") {
            hex20.push(ea.abs());
        }
    }
    assert!(
        hex20[1] < hex20[0],
        "20-node hexahedra: a's error {hex20:?} does not fall"
    );
}

/// Hertz at ν = 0.4999 on second-order cells (docs/method.md §19.3): `formulation = "auto"` takes
/// each cell's own mean dilatation (P2–P0, Q2–P0), the plain quadratic element is left to itself.
/// Measured (a, p₀ against Hertz): 6-node triangles a/8 auto +0.17 %, −0.27 % against plain
/// +3.8 %, +4.5 %; 10-node tetrahedra a/7 +0.17 %, +0.15 % against +0.69 %, +3.5 %; 27-node
/// hexahedra a/3.8 +1.3 %, −3.6 % against +5.7 %, −14 %. Quadratic cells lock far less than
/// linear ones (tests above: +76 % and +395 % on p₀).
/// Asserted: within the 1 % on the simplices; where the plain element locks (the
/// 6-node triangles, the 27-node hexahedra) the largest error with the mean dilatation is below a
/// third of the plain element's.
#[test]
fn nearly_incompressible_hertz_on_second_order_cells() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/second_order");
    // (label, dimension, bound on the mean dilatation's error, whether the plain element locks, run)
    type Case<'a> = (
        &'static str,
        usize,
        Option<f64>,
        bool,
        Box<dyn Fn(&Scene) -> Contact + 'a>,
    );
    let cases: [Case; 3] = [
        (
            "6-node triangles a/8",
            2,
            Some(0.01),
            true,
            Box::new(|scene: &Scene| {
                run_mesh::<2>(scene, read_mesh::<2>(&dir.join("hertz_2d_p2_a8.msh")).unwrap(), 2.0)
            }),
        ),
        (
            "10-node tetrahedra a/7",
            3,
            Some(0.01),
            false,
            Box::new(|scene: &Scene| {
                run_mesh::<3>(scene, read_mesh::<3>(&dir.join("hertz_3d_tet10_a7.msh")).unwrap(), 4.0)
            }),
        ),
        (
            "27-node hexahedra a/3.8",
            3,
            None,
            true,
            Box::new(|scene: &Scene| {
                run_mesh::<3>(
                    scene,
                    hvi::mesh::structured::elevate(&common::hertz_3d_hexahedra(6, 1.3), true),
                    4.0,
                )
            }),
        ),
    ];
    for (label, dim, bound, locks, run) in cases {
        let entry = if dim == 2 { "hertz_2d" } else { "hertz_3d" };
        let [mean, plain] = auto_and_standard(label, entry, &[], dim, run).map(|(ea, ep)| ea.abs().max(ep.abs()));
        assert!(
            !locks || mean < plain / 3.0,
            "{label}: mean dilatation {mean:.4} against the plain element's {plain:.4}"
        );
        if let Some(bound) = bound {
            assert!(mean < bound, "{label}: mean dilatation off by {mean:.4}");
        }
    }
}
