//! Hertz contact between two deformable bodies (issue 44; docs/method.md §18): two elastic
//! cylinders (2D, plane strain) and two elastic spheres (3D) of one mesh pressed together by a
//! given force, frictionless, through a `[[contact]]` section with a `target`. Each body is its own
//! physical group and `[[materials]]` entry; by symmetry each is a quarter disk or a quarter of a
//! hemisphere, cut through its centre. The lower body's base is held along the axis, the upper
//! body's top is pressed towards it by force control (docs/method.md §7.7), so F is the load
//! asked for, not one read off a solve. The slave surface is the lower body's patch around the
//! contact point, the master the upper body's (larger, so that every slave node near the contact
//! projects onto it). Meshes: meshes/two_bodies/ (cylinders.geo, spheres.geo; meshes/generate.sh),
//! first order and, for docs/method.md §18.6, gmsh's 6-node triangles and 10-node tetrahedra.

mod common;

use hvi::app::solve_in_memory;
use hvi::mesh::read_mesh;
use hvi::scene::Scene;
use std::f64::consts::PI;
use std::path::PathBuf;
use std::time::Instant;

fn mesh(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("meshes/two_bodies")
        .join(file)
}

/// What a run gives, scaled from the symmetry part to the whole bodies by `symmetry_factor`: the
/// resultant along the axis of the contact forces on the slave surface (Σ λ_p ν_p, ν_p the row's
/// direction, the master's normal turned around), the reactions of the lower body's base and of
/// the upper body's force-controlled top along the axis, and per slave node in contact its
/// distance r from the axis and its pressure λ_p / w_p; besides, the unknowns, the solve's
/// wall time and the slave nodes left without a row.
struct Contact {
    resultant: f64,
    base: f64,
    top: f64,
    pressures: Vec<(f64, f64)>,
    unknowns: usize,
    seconds: f64,
    /// Slave nodes that project onto no master facet (no row).
    unpaired: usize,
}

fn run<const D: usize>(scene: &str, file: &str, symmetry_factor: f64) -> Contact {
    let scene = Scene::from_toml_str(scene, file).unwrap_or_else(|e| panic!("{e}"));
    let mesh = read_mesh::<D>(&mesh(file)).unwrap_or_else(|e| panic!("{e}"));
    let start = Instant::now();
    let (sim, stats, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let seconds = start.elapsed().as_secs_f64();
    let c = sim.contact.as_ref().unwrap();
    let last = sink.steps.last().unwrap();
    let state = last.contact.as_ref().unwrap();
    let pressures = common::bound_pressures(&sim, &sink);
    let resultant: f64 = state
        .force
        .iter()
        .zip(&c.nodes.normals)
        .map(|(f, n)| f * n[D - 1])
        .sum();
    let axis = ["x", "y", "z"][D - 1];
    Contact {
        resultant: symmetry_factor * resultant,
        base: symmetry_factor * common::reaction(&stats, "LowerBase", axis, last.time),
        top: symmetry_factor * common::reaction(&stats, "UpperTop", axis, last.time),
        pressures,
        unknowns: sim.dofs.n(),
        seconds,
        unpaired: c.pairs[0].1.unpaired,
    }
}

/// Runs `scene` on `file` ([`run`]), asserts its balance under the total force `f`
/// ([`assert_balance`]) and fits Hertz's (a, p₀) to its pressures (`common::hertz_fit`), printed
/// beside Hertz's values: (the run, a, p₀, a's relative error, p₀'s).
fn against_hertz<const D: usize>(
    scene: &str,
    file: &str,
    symmetry_factor: f64,
    f: f64,
    (a_hertz, p0_hertz): (f64, f64),
) -> (Contact, f64, f64, f64, f64) {
    let c = run::<D>(scene, file, symmetry_factor);
    assert_balance(file, &c, f);
    let label = file;
    let (a, p0) = common::hertz_fit(&c.pressures);
    let (ea, ep) = (a / a_hertz - 1.0, p0 / p0_hertz - 1.0);
    eprintln!(
        "{label}: {} unknowns, solve {:.2} s, {} slave nodes in contact, F = {f:.6e}, \
         a = {a:.6} (Hertz {a_hertz:.6}, {:+.3} %), p₀ = {p0:.6e} (Hertz {p0_hertz:.6e}, {:+.3} %)",
        c.unknowns,
        c.seconds,
        c.pressures.len(),
        100.0 * ea,
        100.0 * ep
    );
    (c, a, p0, ea, ep)
}

/// The scene of the bodies "Lower" and "Upper" with their materials (E, ν), `model` the lines of
/// `[material]` (the 2D model), the symmetry groups (group, component), the lower base held along
/// `axis`, the upper top pressed towards it by `share` (the symmetry part's force), one elastic
/// step, frictionless contact of "LowerContact" (slave) with "UpperContact" (master).
fn scene(
    model: &str,
    lower: (f64, f64),
    upper: (f64, f64),
    symmetry: &[(&str, &str)],
    axis: &str,
    share: f64,
) -> String {
    let mut s = format!(
        "[material]\n{model}\
         [[materials]]\ngroup = \"Lower\"\nyoungs_modulus = {:e}\npoisson_ratio = {}\n\
         [[materials]]\ngroup = \"Upper\"\nyoungs_modulus = {:e}\npoisson_ratio = {}\n\
         [time]\nfinal_time = 1.0\nsteps = 1\n",
        lower.0, lower.1, upper.0, upper.1
    );
    for (group, component) in symmetry {
        s += &format!("[[dirichlet]]\ngroup = \"{group}\"\ncomponents = [\"{component}\"]\n");
    }
    s += &format!(
        "[[dirichlet]]\ngroup = \"LowerBase\"\ncomponents = [\"{axis}\"]\n\
         [[force_control]]\ngroup = \"UpperTop\"\ncomponent = \"{axis}\"\nforce = \"-{share:e}*t\"\n\
         [[contact]]\ngroup = \"LowerContact\"\ntarget = \"UpperContact\"\n"
    );
    s
}

/// Checks the balance of a run pressed by the total force `f`: the upper top's reaction is −f
/// (the force control), the lower base's f, and the slave surface's contact forces have the
/// resultant f along the axis, each to 1e-10 relative. The resultant, not Σ λ_p: each row acts
/// along the master's normal, tilted by up to a/R from the axis, so Σ λ_p exceeds f by the mean
/// of 1 − cos (measured 7e-5 on the cylinders, 5e-4 on the spheres).
fn assert_balance(what: &str, c: &Contact, f: f64) {
    for (name, value, want) in [
        ("the upper top's reaction", c.top, -f),
        ("the lower base's reaction", c.base, f),
        ("the contact forces' resultant", c.resultant, f),
    ] {
        assert!(
            (value - want).abs() <= 1e-10 * f,
            "{what}: {name} {value:.12e} against {want:.12e}"
        );
    }
}

/// Two cylinders in plane strain, the lower one (the slave) R1 = 1, E1 = 1, ν1 = 0.3, the upper
/// one (the master) R2 = 2, E2 = 2, ν2 = 0.25, touching along a line and pressed together by the
/// line load F per unit thickness: Hertz's a = sqrt(4FR/(πE*)), p₀ = 2F/(πa) with
/// 1/R = 1/R1 + 1/R2 (R = 2/3) and 1/E* = (1 − ν1²)/E1 + (1 − ν2²)/E2 (E* = 0.7253), F chosen so
/// that a = 0.05 (F = 2.136e-3; a/R1 = 0.05, a/R = 0.075). Frictionless, Hertz holds for the
/// dissimilar materials too (the Dundurs mismatch couples only shear tractions, which are absent).
/// The half model (meshes/two_bodies/cylinders_p1.msh): two quarter disks of P1 triangles of
/// a/25 (hf = 0.002) within 2a of the contact point, growing to 0.1 at distance 1; 7 642 nodes,
/// 15 284 unknowns (15 068 free), 52 contact rows, 26 slave nodes in contact; the solve takes
/// 0.1–0.2 s in release mode, the test under 0.5 s.
///
/// Tolerances: 2 % on a and 3 % on p₀ (the issue's). Measured with the mortar rows: a −0.11 %,
/// p₀ +0.01 %. With node-to-segment rows (before them): a −0.09 %, p₀ −0.00 %; on the
/// same geometry at a/12.5 +0.66 % and −0.14 %, at a/50 −0.06 % and +0.02 %, so the
/// discretisation's share is well inside, and what is left at a/25 is Hertz's own error from the
/// finite radii (the half-space assumption, of the order of (a/R)² = 0.56 %) and from cutting each cylinder
/// at its centre (which moves the approach, not a or p₀). Node to segment on these non-matching
/// curved meshes costs nothing visible here: with the slave and master swapped a −0.32 %,
/// p₀ +0.27 %. Force balance to 1e-10 ([`assert_balance`]).
#[test]
fn hertz_two_cylinders_in_plane_strain_half_width_within_2_percent_and_peak_pressure_within_3() {
    let (c, a, p0, ea, ep) = cylinders("cylinders_p1.msh");
    let a_hertz = a / (1.0 + ea);
    let p0_hertz = p0 / (1.0 + ep);
    assert!(c.pressures.len() >= 20, "a is resolved by too few slave nodes");
    assert!(ea.abs() < 0.02, "a = {a} against Hertz {a_hertz}");
    assert!(ep.abs() < 0.03, "p₀ = {p0} against Hertz {p0_hertz}");
}

/// The two cylinders' run on `file` (see the test above), its balance asserted: the run, a, p₀
/// and their relative errors.
fn cylinders(file: &str) -> (Contact, f64, f64, f64, f64) {
    let (r1, r2, e1, e2, nu1, nu2): (f64, f64, f64, f64, f64, f64) = (1.0, 2.0, 1.0, 2.0, 0.3, 0.25);
    let r = 1.0 / (1.0 / r1 + 1.0 / r2);
    let e_star = 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2);
    let a_hertz = 0.05;
    let f = PI * a_hertz * a_hertz * e_star / (4.0 * r);
    let p0_hertz = 2.0 * f / (PI * a_hertz);
    // the half model carries half of the line load
    let text = scene(
        "plane = \"strain\"\n",
        (e1, nu1),
        (e2, nu2),
        &[("Symmetry", "x")],
        "y",
        f / 2.0,
    );
    against_hertz::<2>(&text, file, 2.0, f, (a_hertz, p0_hertz))
}

/// Two equal spheres R1 = R2 = 2, E = 1.40625e7, ν = 0.25, pressed together by F = 1e4: Hertz's
/// 1/R = 1/R1 + 1/R2 (R = 1), 1/E* = 2(1 − ν²)/E (E* = 7.5e6), a³ = 3FR/(4E*) = 1e-3, so
/// a = 0.1 (a/R = 0.1, a/R1 = 0.05), and p₀ = 3F/(2πa²) = 4.775e5. The quarter model
/// (meshes/two_bodies/spheres_p1.msh): two quarters of hemispheres of tetrahedra of a/10
/// (hf = 0.01) within 1.5a of the contact point, growing linearly to 0.4 at distance 2; 7 035
/// nodes, 21 105 unknowns (18 971 free), 308 contact rows, 105 slave nodes in contact; the solve
/// takes 0.4–0.7 s in release mode, the test under 1 s. The slave nodes on the symmetry planes
/// project just beyond the rim of the master's facets there (the faceted sphere's normal tilts
/// off the plane): they are paired through the pairing's cone (src/contact/pairing.rs
/// `RIM_CONE`; without it 16 of the 324 had no row), and the test asserts every one has a row.
///
/// Tolerances: 5 % on a and 5 % on p₀ (the issue's). Measured with the mortar rows: a +0.12 %,
/// p₀ +0.76 %. With node-to-segment rows (before them): a +0.46 %, p₀ +0.61 %; on the
/// same geometry at a/6.7 +0.55 % and +1.49 %, at a/14 +0.14 % and +0.57 %: P1 tetrahedra
/// overestimate the peak (the centre's nodal pressure has the fewest nodes around it), and the
/// finite radii (Hertz's half-space assumption, of the order of (a/R)² = 1 %) for the rest.
/// With the slave and master swapped a +0.65 %, p₀ +0.24 %. Force balance to 1e-10
/// ([`assert_balance`]).
#[test]
fn hertz_two_spheres_contact_radius_and_peak_pressure_within_5_percent() {
    let (c, a, p0, ea, ep) = spheres("spheres_p1.msh");
    assert!(c.pressures.len() >= 30, "a is resolved by too few slave nodes");
    assert_eq!(c.unpaired, 0, "every slave node of the patch has a row");
    assert!(ea.abs() < 0.05, "a = {a} against Hertz {}", a / (1.0 + ea));
    assert!(ep.abs() < 0.05, "p₀ = {p0} against Hertz {}", p0 / (1.0 + ep));
}

/// The two spheres' run on `file` (see the test above), its balance asserted: the run, a, p₀ and
/// their relative errors.
fn spheres(file: &str) -> (Contact, f64, f64, f64, f64) {
    let (e, nu, f): (f64, f64, f64) = (1.40625e7, 0.25, 1e4);
    let (r1, r2): (f64, f64) = (2.0, 2.0);
    let r = 1.0 / (1.0 / r1 + 1.0 / r2);
    let e_star = e / (2.0 * (1.0 - nu * nu));
    let a_hertz = (3.0 * f * r / (4.0 * e_star)).cbrt();
    assert!((a_hertz - 0.1).abs() < 1e-12, "a = {a_hertz}");
    let p0_hertz = 3.0 * f / (2.0 * PI * a_hertz * a_hertz);
    // the quarter model carries a quarter of the force
    let text = scene("", (e, nu), (e, nu), &[("SymX", "x"), ("SymY", "y")], "z", f / 4.0);
    against_hertz::<3>(&text, file, 4.0, f, (a_hertz, p0_hertz))
}

/// The two cylinders on gmsh's 6-node triangles (docs/method.md §18.6: the mortar rows with
/// the positive multipliers of §19.3 on the slave's 3-node edges, the master's curved edges
/// projected onto): meshes/two_bodies/cylinders_p2_a8.msh and _a16.msh, the same geometry as
/// the linear mesh with hf = a/8 and a/16. a and p₀ within 1 % on both (the issue's), and a's
/// error falls at least twofold from a/8 to a/16 (first order at least). Measured: a/8 (15 914
/// unknowns, 17 slave nodes in contact) a +0.78 %, p₀ −0.12 %; a/16 (33 210, 33) a +0.16 %,
/// p₀ −0.02 %: 4.9× and 5× per halving. The linear mesh at a/25 (15 284 unknowns): −0.11 %,
/// +0.01 %.
#[test]
fn hertz_two_cylinders_on_6_node_triangles_within_1_percent_and_converging() {
    let (_, _, _, ea8, ep8) = cylinders("cylinders_p2_a8.msh");
    let (_, _, _, ea16, ep16) = cylinders("cylinders_p2_a16.msh");
    for (h, ea, ep) in [("a/8", ea8, ep8), ("a/16", ea16, ep16)] {
        assert!(ea.abs() < 0.01 && ep.abs() < 0.01, "{h}: a {ea:+.4}, p₀ {ep:+.4}");
    }
    assert!(
        ea8.abs() >= 2.0 * ea16.abs(),
        "a's error {ea8:+.5} at a/8, {ea16:+.5} at a/16"
    );
}

/// The two spheres on gmsh's 10-node tetrahedra (docs/method.md §18.6: the slave's 6-node
/// triangles with the transformed dual multipliers of §19.3, the master's curved 6-node
/// triangles clipped by their corners): meshes/two_bodies/spheres_tet10_a7.msh and _a10.msh
/// (hf = a/7, a/10). Every slave node of the patch pairs, a and p₀ within 1 % at a/10 (the
/// issue's) and a's error falls from a/7 to a/10 by at least the ratio of the sizes (first
/// order). Measured: a/7 (79 734 unknowns, 226 slave nodes in contact) a +0.33 %, p₀ −0.35 %;
/// a/10 (152 811, 413) a +0.15 %, p₀ −0.23 % (2.2× for a 1.43× finer mesh). With the split
/// multipliers (before): +1.40 % and +0.77 % in a. The linear tetrahedra at a/10 (21 105
/// unknowns): +0.12 %, +0.76 %.
#[test]
fn hertz_two_spheres_on_10_node_tetrahedra_within_1_percent_and_converging() {
    let (c7, _, _, ea7, _) = spheres("spheres_tet10_a7.msh");
    let (c10, _, _, ea10, ep10) = spheres("spheres_tet10_a10.msh");
    assert_eq!(
        (c7.unpaired, c10.unpaired),
        (0, 0),
        "every slave node of the patch has a row"
    );
    assert!(
        ea10.abs() < 0.01 && ep10.abs() < 0.01,
        "a/10: a {ea10:+.4}, p₀ {ep10:+.4}"
    );
    assert!(
        ea7.abs() >= 10.0 / 7.0 * ea10.abs(),
        "a's error {ea7:+.5} at a/7, {ea10:+.5} at a/10"
    );
}
