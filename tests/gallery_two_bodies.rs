//! The two deformable bodies of docs/gallery.md ("Two deformable bodies: a steel punch on a relaxing
//! pad"): examples/gallery/two_bodies/two_bodies.toml on the committed two_bodies.msh. A steel punch
//! with a rounded nose (R = 1, elastic, E = 200) pressed by δ = 0.03 into a polymer pad bonded to a
//! rigid base (its shear relaxing sixfold, G(t) = 0.2 + 1.0 e^{−t}, its bulk modulus κ = 4 held),
//! held until t = 4 while the pad relaxes, then moved sideways by 0.04 (t − 4) with Coulomb
//! friction μ = 0.4 between them. Plane strain, one mesh, non-matching along the contact
//! (triangles of 0.015 on the nose, quadrilaterals of 0.01 on the pad's top); the nose is the
//! slave surface, the pad's top the target (docs/method.md §18).
//!
//! The pad's top is flat, so every row's direction is the master normal ±(0, 1) and its tangent
//! ±(1, 0): the y component of the contact force on the punch is the total normal force N and its
//! x component the total friction force T.

mod common;

use hvi::app::solve_in_memory;
use hvi::mesh::read_mesh;
use hvi::scene::Scene;
use std::path::Path;
use std::time::Instant;

const MESH: &str = "examples/gallery/two_bodies/two_bodies.msh";
const SCENE: &str = "examples/gallery/two_bodies/two_bodies.toml";
/// The contact pair: the slave surface (the punch's nose) and the target (the pad's top), and
/// the groups whose displacements are prescribed (the punch's top, the pad's bottom).
const SLAVE: &str = "PunchNose";
const TARGET: &str = "PadTop";
const PUNCH_TOP: &str = "PunchTop";
const PAD_BOTTOM: &str = "PadBottom";
/// two_bodies.toml: the friction coefficient, the end of the press, the start of the slide and
/// the time step.
const MU: f64 = 0.4;
const PRESSED: f64 = 0.2;
const SLIDE: f64 = 4.0;
const K_STEP: f64 = 0.1;
/// The pad's shear line of two_bodies.toml, which the elastic comparisons replace, and its
/// instantaneous and long-term shear moduli G(0) = G∞ + G₁ and G∞.
const SHEAR: &str = "shear = { long_term = 0.2, terms = [{ modulus = 1.0, relaxation_time = 1.0 }] }";
const G_0: f64 = 1.2;
const G_INF: f64 = 0.2;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// One row of contact_forces.csv or reactions.csv (or of RunStats' lists).
struct Row {
    time: f64,
    group: String,
    component: String,
    force: f64,
}

/// The rows of `time,group,component,force`.
fn read_forces(path: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time,group,component,force"), "{}", path.display());
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            Row {
                time: c[0].parse().unwrap(),
                group: c[1].trim_matches('"').to_string(),
                component: c[2].to_string(),
                force: c[3].parse().unwrap(),
            }
        })
        .collect()
}

fn rows_of(list: &[hvi::solver::Reaction]) -> Vec<Row> {
    list.iter()
        .map(|r| Row {
            time: r.time,
            group: r.group.clone(),
            component: r.component.to_string(),
            force: r.force,
        })
        .collect()
}

/// (t, force) of one group's component at every output time, in time order.
fn series(rows: &[Row], group: &str, component: &str) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| r.group == group && r.component == component)
        .map(|r| (r.time, r.force))
        .collect()
}

/// The rows of gamma3.csv (one per slave node and output time) by column name.
struct Gamma3 {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Gamma3 {
    fn read(path: &Path) -> Gamma3 {
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut lines = text.lines();
        let header: Vec<String> = lines.next().unwrap().split(',').map(str::to_string).collect();
        let rows = lines
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        Gamma3 { header, rows }
    }
    fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }
    /// The rows at output time t.
    fn at(&self, t: f64) -> Vec<&Vec<f64>> {
        let time = self.col("time");
        self.rows.iter().filter(|r| (r[time] - t).abs() < 1e-9).collect()
    }
}

/// The normal force on the punch at each output time, from the committed scene run in memory
/// with the pad's shear line replaced by `shear` (the scene's own with None).
fn normal_force(shear: Option<String>) -> Vec<(f64, f64)> {
    let mut text = std::fs::read_to_string(root().join(SCENE)).unwrap();
    if let Some(line) = shear {
        assert!(text.contains(SHEAR), "two_bodies.toml's shear line changed");
        text = text.replace(SHEAR, &line);
    }
    let scene = Scene::from_toml_str(&text, SCENE).unwrap_or_else(|e| panic!("{e}"));
    let mesh = read_mesh::<2>(&root().join(MESH)).unwrap_or_else(|e| panic!("{e}"));
    let (_, stats, _) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    series(&rows_of(&stats.contact_forces), SLAVE, "y")
}

/// The value of a series at time t.
fn at(series: &[(f64, f64)], t: f64) -> f64 {
    series
        .iter()
        .find(|(s, _)| (s - t).abs() < 1e-9)
        .unwrap_or_else(|| panic!("no output at t = {t}"))
        .1
}

/// The entry's commands as docs/gallery.md gives them — `hvi solve` on the committed files, then
/// `hvi plot` — and what its pictures show, checked from the files the run writes:
///
/// * the run: 1 495 nodes (the punch's 963 triangles, the pad's 883 quadrilaterals and 2
///   triangles), 42 slave nodes, 50 steps, 51 frames; `hvi plot` draws the deformed bodies, the
///   pressure along the nose and the stick/slip zones;
/// * **each body's balance**, at every step and in both components, against the step's normal
///   force N: the forces on the two sides of the pair (contact_forces.csv's rows PunchNose and
///   PadTop: the master's from the rows' mortar coefficients) are equal and opposite to 1e-12
///   (measured 7e-16); the punch's top holds the punch against the force on
///   the slave side and the pad's bottom the pad against the force on the target side, to 1e-10.
///   The reactions are the residuals of the step's equations, so only round-off of the bodies'
///   internal forces separates them: the steel's, of order E δ ≈ 6 against N ≈ 0.02 (measured
///   3.9e-12 for the punch, 3.0e-14 for the pad);
/// * **the normal force relaxes**: it rises over the press (t = 0.1, 0.2) and falls strictly at
///   every step of the hold (t = 0.2 … 4), the punch held still; during the hold friction only
///   locks: the friction force stays below μN and part of the contact sticks at every step;
/// * **sliding**: at the first step of the slide (t = 4.1) the contact is partly stuck and
///   |T| < μN; from t = 4.2 on every pressing row slips, T opposes the punch's motion (T < 0) and
///   |T| = μN to 1e-10 (measured ≤ 6.5e-12), each pressing row at its Coulomb bound
///   | |λ_τ| − μλ_ν | ≤ 1e-10 μ max λ_ν (measured ≤ 2.8e-11). What separates them: Coulomb's
///   fixed point stops once the bound forces move by at most the solver's tolerance 1e-12 of the
///   largest normal force, and the regularised law leaves a slipping row ε²/(2Δ²) below its bound
///   (ε = 1e-8, Δ ≈ 0.004 the slip of a step: 3e-12).
#[test]
fn two_bodies_run_as_the_gallery_says_and_balance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("two_bodies");
    let start = Instant::now();
    let stats = common::solve_files(MESH, Some(SCENE), &out);
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!(
        (stats.nodes, stats.contact_nodes, stats.steps, stats.frames_written),
        (1495, 42, 50, 51)
    );
    let options = hvi::plot::PlotOptions {
        scale: None,
        times: Some(vec![0.2, 1.0, 2.0, 4.0, 5.0]),
    };
    let pictures = hvi::plot::plot_run(&out, &options).unwrap_or_else(|e| panic!("{e}"));
    for name in ["deformed.png", "gamma3.png", "gamma3_zones.png"] {
        assert!(pictures.iter().any(|p| p.ends_with(name)), "{name}: {pictures:?}");
    }

    let contact = read_forces(&out.join("contact_forces.csv"));
    let reactions = read_forces(&out.join("reactions.csv"));
    let normal = series(&contact, SLAVE, "y");
    let friction = series(&contact, SLAVE, "x");
    assert_eq!(normal.len(), 51);
    assert!(normal[0].1 == 0.0 && friction[0].1 == 0.0, "no load at t = 0");

    // each body's balance
    let (mut sides, mut punch, mut pad) = (0.0f64, 0.0f64, 0.0f64);
    for c in ["x", "y"] {
        let slave = series(&contact, SLAVE, c);
        let target = series(&contact, TARGET, c);
        let top = series(&reactions, PUNCH_TOP, c);
        let bottom = series(&reactions, PAD_BOTTOM, c);
        assert_eq!((slave.len(), target.len(), top.len(), bottom.len()), (51, 51, 51, 51));
        for n in 1..normal.len() {
            let (t, scale) = normal[n];
            assert!([target[n].0, top[n].0, bottom[n].0].iter().all(|&s| s == t), "times");
            let errors = [
                (slave[n].1 + target[n].1).abs() / scale,
                (slave[n].1 + top[n].1).abs() / scale,
                (target[n].1 + bottom[n].1).abs() / scale,
            ];
            (sides, punch, pad) = (sides.max(errors[0]), punch.max(errors[1]), pad.max(errors[2]));
            assert!(
                errors[0] <= 1e-12 && errors[1] <= 1e-10 && errors[2] <= 1e-10,
                "t = {t}, {c}: slave side {:e}, target side {:e}, punch top {:e}, pad bottom {:e} (N = {scale:e})",
                slave[n].1,
                target[n].1,
                top[n].1,
                bottom[n].1
            );
        }
    }

    // the press, then the hold: the normal force relaxes, friction only locks
    let pressed = (PRESSED / K_STEP).round() as usize;
    let slide = (SLIDE / K_STEP).round() as usize;
    let forces: Vec<f64> = normal.iter().map(|n| n.1).collect();
    for n in 1..=slide {
        if n <= pressed {
            assert!(forces[n] > forces[n - 1], "pressing, step {n}: {forces:?}");
        } else {
            assert!(forces[n] < forces[n - 1], "held, step {n}: {forces:?}");
        }
    }
    let gamma3 = Gamma3::read(&out.join("gamma3.csv"));
    let (status, zone, force, tau) = (
        gamma3.col("status"),
        gamma3.col("friction_status"),
        gamma3.col("force"),
        gamma3.col("force_tau"),
    );
    // the rows pressing (on their bound, u_ν = g) and how many of them stick
    let pressing = |t: f64| -> (Vec<&Vec<f64>>, usize) {
        let rows: Vec<&Vec<f64>> = gamma3.at(t).into_iter().filter(|r| r[status] == 2.0).collect();
        let stuck = rows.iter().filter(|r| r[zone] == 1.0).count();
        (rows, stuck)
    };
    for n in 1..=slide {
        let (t, f) = friction[n];
        let (rows, stuck) = pressing(t);
        assert!(
            f.abs() < MU * forces[n] && stuck > 0,
            "t = {t}: friction {f:e} against μN = {:e}, {stuck} of {} rows stuck",
            MU * forces[n],
            rows.len()
        );
    }

    // the slide: partly stuck at its first step, then sliding at the Coulomb bound
    let (t, f) = friction[slide + 1];
    let (rows, stuck) = pressing(t);
    assert!(
        f.abs() < MU * forces[slide + 1] && stuck > 0 && stuck < rows.len(),
        "t = {t}: the first step of the slide sticks in part: friction {f:e}, {stuck} of {} rows stuck",
        rows.len()
    );
    let (mut total, mut per_row) = (0.0f64, 0.0f64);
    for n in slide + 2..friction.len() {
        let (t, f) = friction[n];
        let (rows, stuck) = pressing(t);
        assert!(
            stuck == 0 && rows.len() > 10,
            "t = {t}: {stuck} of {} rows stuck",
            rows.len()
        );
        assert!(
            f < 0.0,
            "t = {t}: the friction force {f:e} on the punch opposes its motion (+x)"
        );
        let off = (f.abs() - MU * forces[n]).abs() / (MU * forces[n]);
        total = total.max(off);
        assert!(
            off <= 1e-10,
            "t = {t}: friction {f:e} against μN = {:e}",
            MU * forces[n]
        );
        let largest = rows.iter().fold(0.0f64, |m, r| m.max(r[force]));
        for r in &rows {
            let row = (r[tau].abs() - MU * r[force]).abs() / (MU * largest);
            per_row = per_row.max(row);
            assert!(
                row <= 1e-10,
                "t = {t}: a row slips off its bound: λ_τ = {:e}, λ_ν = {:e}",
                r[tau],
                r[force]
            );
        }
    }
    let last = normal.len() - 1;
    eprintln!(
        "two bodies: run {seconds:.2} s; N({PRESSED}) = {:.6}, N({SLIDE}) = {:.6}, N(5) = {:.6}, T(5) = {:.6}; \
         balance: sides {sides:.1e}, punch {punch:.1e}, pad {pad:.1e} of N; sliding: |T|/(μN) − 1 up to {total:.1e}, \
         rows off their bound up to {per_row:.1e} of μ max λ_ν",
        forces[pressed], forces[slide], forces[last], friction[last].1
    );
}

/// The normal force at the end of the hold (t = 4) lies between the forces of the same scene with
/// the pad elastic at its instantaneous moduli (κ = 4, G(0) = 1.2: the force the pad would keep
/// without relaxing) and at its long-term ones (κ = 4, G∞ = 0.2: the force once fully relaxed).
/// The pad's relaxation modulus lies between them at every time, so must the force; measured
/// N(4) = 1.20 F∞ = 0.29 F₀ (the relaxation is not over at t = 4τ; the scheme's long-term shear
/// modulus, G(0) − G₁ (k/2τ) coth(k/2τ) = 0.19917, is 0.4 % below G∞, well inside that margin). Just after the press (t = 0.2 = τ/5) N is 0.95 F₀: the ramp
/// already relaxes the pad a little.
#[test]
fn held_force_lies_between_the_elastic_pads() {
    let elastic = |g: f64| normal_force(Some(format!("shear = {{ long_term = {g:.17e} }}")));
    let run = normal_force(None);
    let (f0, f_inf) = (elastic(G_0), elastic(G_INF));
    let (held, pressed) = (at(&run, SLIDE), at(&run, PRESSED));
    let (upper, lower) = (at(&f0, SLIDE), at(&f_inf, SLIDE));
    eprintln!(
        "two bodies: N({PRESSED}) = {pressed:.6} = {:.4} F₀, N({SLIDE}) = {held:.6} = {:.4} F∞ = {:.4} F₀; \
         elastic pads: F₀ = {upper:.6} (G(0) = {G_0}), F∞ = {lower:.6} (G∞ = {G_INF})",
        pressed / upper,
        held / lower,
        held / upper
    );
    assert!(
        lower < held && held < upper,
        "N({SLIDE}) = {held} outside ({lower}, {upper})"
    );
    assert!(pressed < upper, "N({PRESSED}) = {pressed} above the unrelaxed {upper}");
}
