//! Bodies held by their contact (docs/method.md §7.7): force control (a group moved rigidly by
//! the δ(t) that makes its reaction P(t)) and semi-coercive bodies (rigid motions the prescribed
//! components leave free, held by the contact and the load alone).

mod common;

use common::{reaction, rectangle_with_sides, scene};
use hvi::app::solve_in_memory;
use hvi::mesh::structured::CellShape;

const P: f64 = 0.01;
const S: f64 = 2.0;
const EPS: f64 = 1e-8;
const LX: f64 = 2.0;

/// The block (0, 2) × (0, 1) on a Winkler foundation along its base (Gamma3: one-sided linear
/// compliance, S = 2), a roller on its left side (u_x = 0 on Gamma1), nothing else holding it
/// vertically: `load` is the TOML that presses it down.
fn floating(load: &str) -> String {
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
group = "Gamma1"
components = ["x"]

[contact]
law = {{ kind = "power", scale = {S}, exponent = 1.0, one_sided = true, regularisation = {EPS:e} }}

{load}
"#
    )
}

/// The exact penetration of the foundation under the pressure p t: S ρ_ε(r) = p t with the
/// one-sided smoothing ρ_ε(r) = (r + √(r² + ε²) − ε)/2 (docs/method.md §4.2), inverted:
/// r = 2c(c + ε)/(2c + ε), c = p t / S.
fn penetration(t: f64) -> f64 {
    let c = P * t / S;
    2.0 * c * (c + EPS) / (2.0 * c + EPS)
}

/// The uniform state of a block pressed by p on a frictionless Winkler foundation with a roller
/// on x = 0: σ_yy = −p, σ_xx = 0, plane strain, so u_x = ν(1 + ν) p x / E and
/// u_y = −r − (1 − ν²) p y / E. P1/Q1 reproduce it exactly, and the nodal forces of a uniform
/// penetration are the exact pressure times the nodal weights: only round-off remains.
fn exact(x: [f64; 2], t: f64) -> [f64; 2] {
    let (e, nu, p) = (1.0, 0.3, P * t);
    [
        nu * (1.0 + nu) * p * x[0] / e,
        -penetration(t) - (1.0 - nu * nu) * p * x[1] / e,
    ]
}

/// The floating block pressed by a pressure on its top: solved with the vertical translation
/// held by the contact alone; the foundation's total force balances the load to 1e-10, the
/// displacement is the exact uniform state, and the same block with its top moved by a force
/// control of the same total force, or by the displacement that run found, gives the same
/// solution.
#[test]
fn a_floating_block_pressed_onto_a_foundation_balances_its_load_and_matches_displacement_control() {
    for shape in [CellShape::Quad, CellShape::Tri] {
        let mesh = || rectangle_with_sides(LX, 1.0, 8, 4, shape);
        let pressed = scene(&floating(&format!(
            "[[traction]]\ngroup = \"Gamma2_top\"\npressure = \"{P}*t\""
        )));
        let (sim, stats, sink) = solve_in_memory(&pressed, mesh()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(sim.dirichlet.held_by_contact, vec!["translation in y".to_string()]);
        assert!(stats.effects.iter().any(|e| e == "rigid"), "{:?}", stats.effects);
        for step in &sink.steps {
            let t = step.time;
            let contact = step.contact.as_ref().unwrap();
            let total: f64 = contact.force.iter().sum();
            assert!(
                (total - P * t * LX).abs() <= 1e-10 * P * LX,
                "{shape:?} t = {t}: foundation {total} against the load {}",
                P * t * LX
            );
            let mut worst = 0.0f64;
            for (p, x) in sim.mesh.points.iter().enumerate() {
                let e = exact(*x, t);
                for (c, v) in e.iter().enumerate() {
                    worst = worst.max((step.displacement[2 * p + c] - v).abs());
                }
            }
            // |u| ~ 1e-2: round-off of the solves and of S⁺ is ~1e-15 of it
            assert!(
                worst <= 1e-12,
                "{shape:?} t = {t}: off the exact uniform state by {worst:e}"
            );
        }

        // force control of the top: the same total force through a rigidly moving top
        let forced = scene(&floating(&format!(
            "[[force_control]]\ngroup = \"Gamma2_top\"\ncomponent = \"y\"\nforce = \"-{P}*{LX}*t\""
        )));
        let (_, forced_stats, forced_sink) = solve_in_memory(&forced, mesh()).unwrap_or_else(|e| panic!("{e}"));
        // and the displacement control that the force control found
        let delta = forced_sink.steps.last().unwrap().motion[0];
        let t_end = forced_sink.steps.last().unwrap().time;
        assert!(
            (delta - exact([0.0, 1.0], t_end)[1]).abs() <= 1e-12,
            "δ = {delta} against the exact top displacement {}",
            exact([0.0, 1.0], t_end)[1]
        );
        let displaced = scene(&floating(&format!(
            "[[dirichlet]]\ngroup = \"Gamma2_top\"\ncomponents = [\"y\"]\nvalue = [\"{delta:e}*t\"]"
        )));
        let (_, displaced_stats, displaced_sink) =
            solve_in_memory(&displaced, mesh()).unwrap_or_else(|e| panic!("{e}"));
        let (a, b, c) = (
            sink.steps.last().unwrap(),
            forced_sink.steps.last().unwrap(),
            displaced_sink.steps.last().unwrap(),
        );
        for k in 0..a.displacement.len() {
            assert!(
                (a.displacement[k] - b.displacement[k]).abs() <= 1e-12,
                "{shape:?}: force control differs"
            );
            assert!(
                (b.displacement[k] - c.displacement[k]).abs() <= 1e-12,
                "{shape:?}: displacement control differs"
            );
        }
        // the force-controlled group's reaction is its force; the displacement control's the same
        let r_forced = reaction(&forced_stats, "Gamma2_top", "y", t_end);
        let r_displaced = reaction(&displaced_stats, "Gamma2_top", "y", t_end);
        assert!(
            (r_forced + P * LX * t_end).abs() <= 1e-10 * P * LX,
            "force control reaction {r_forced}"
        );
        // δ is exact (within 1e-12 of 0.03), the reaction of the displacement control within the
        // stiffness times that
        assert!(
            (r_displaced + P * LX * t_end).abs() <= 1e-8 * P * LX,
            "displacement control reaction {r_displaced}"
        );
    }
}

/// The same block with nothing holding it along x (no roller; the top force-controlled in y):
/// frictionless contact takes no tangential force, so a load along x is refused naming the
/// motion; without one, the free translation is pinned and the run balances.
#[test]
fn a_load_along_a_motion_nothing_holds_is_refused_naming_it() {
    let text = |extra: &str| {
        floating(&format!(
            "[[force_control]]\ngroup = \"Gamma2_top\"\ncomponent = \"y\"\nforce = \"-{P}*{LX}*t\"\n{extra}"
        ))
        .replace("[[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\"]\n", "")
    };
    let mesh = || rectangle_with_sides(LX, 1.0, 8, 4, CellShape::Quad);
    // no load along x: the translation in x is pinned, the vertical balance holds
    let (sim, _, sink) = solve_in_memory(&scene(&text("")), mesh()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sim.dirichlet.held_by_contact, vec!["translation in x".to_string()]);
    let last = sink.steps.last().unwrap();
    let total: f64 = last.contact.as_ref().unwrap().force.iter().sum();
    assert!((total - P * LX).abs() <= 1e-10 * P * LX, "foundation {total}");
    // a shear load on the right side: nothing can balance it
    let pushed = text("[[traction]]\ngroup = \"Right\"\nvalue = [\"0.001*t\", \"0\"]");
    let e = solve_in_memory(&scene(&pushed), mesh())
        .err()
        .expect("a load along a free motion must be refused");
    let message = e.to_string();
    assert!(
        message.contains("nothing holds") && message.contains("x"),
        "the message names the motion: {message}"
    );
}

/// The block pulled off its one-sided foundation (a negative pressure): no contact force can
/// hold it, and the run stops with a message saying so, not with the advice for a stiff law.
#[test]
fn a_body_pulled_off_its_support_is_refused_naming_the_motion() {
    let pulled = scene(&floating(&format!(
        "[[traction]]\ngroup = \"Gamma2_top\"\npressure = \"-{P}*t\""
    )));
    let e = solve_in_memory(&pulled, rectangle_with_sides(LX, 1.0, 8, 4, CellShape::Quad))
        .err()
        .expect("a body pulled off its support has no equilibrium");
    let message = e.to_string();
    assert!(
        message.contains("cannot balance") && message.contains("translation in y"),
        "{message}"
    );
}

/// The floating block in 3D (hexahedra and tetrahedra): rollers on x = 0 (u_x) and on both
/// z-faces (u_z), the base on the Winkler foundation, the top pressed by p. The vertical
/// translation is held by the contact alone; the exact state is the plane-strain one of the 2D
/// test with u_z = 0, which P1 and Q1 reproduce to round-off.
#[test]
fn a_floating_3d_block_on_symmetry_planes_is_held_by_its_foundation() {
    use hvi::mesh::structured::{block, SolidShape};
    let text = floating(&format!(
        "[[dirichlet]]\ngroup = \"Sides\"\ncomponents = [\"z\"]\n\n[[traction]]\ngroup = \"Gamma2_top\"\npressure = \"{P}*t\""
    ))
    .replace("plane = \"strain\"\n", "");
    for shape in [SolidShape::Hex, SolidShape::Tet] {
        let (sim, _, sink) =
            solve_in_memory(&scene(&text), block([LX, 1.0, 0.5], [4, 2, 2], shape)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(sim.dirichlet.held_by_contact, vec!["translation in y".to_string()]);
        let last = sink.steps.last().unwrap();
        let t = last.time;
        let total: f64 = last.contact.as_ref().unwrap().force.iter().sum();
        let load = P * t * LX * 0.5;
        assert!(
            (total - load).abs() <= 1e-10 * load,
            "{shape:?}: foundation {total} against {load}"
        );
        let mut worst = 0.0f64;
        for (p, x) in sim.mesh.points.iter().enumerate() {
            let e = exact([x[0], x[1]], t);
            for (c, v) in [e[0], e[1], 0.0].into_iter().enumerate() {
                worst = worst.max((last.displacement[3 * p + c] - v).abs());
            }
        }
        assert!(worst <= 1e-12, "{shape:?}: off the exact uniform state by {worst:e}");
    }
}

/// Force control with a long memory (docs/method.md §7.7 with §3): the step matrix K and step
/// 0's K_A each get their own responses. At every step the force-controlled top's reaction —
/// computed from K_A u_n + K_B m_n, not from the a-equation — is P(t_n) to 1e-10, and the
/// foundation carries the same total (equilibrium), while δ(t) creeps (the memory relaxes the
/// body: δ must change between steps under a constant force).
#[test]
fn force_control_with_memory_balances_every_step() {
    let text = floating(&format!(
        "[[force_control]]\ngroup = \"Gamma2_top\"\ncomponent = \"y\"\nforce = \"-{P}*{LX}\"\n\n\
         [memory]\nkind = \"exponential\"\nterms = [{{ coefficient = -0.3, relaxation_time = 0.5 }}]"
    ))
    .replace("steps = 2", "steps = 8");
    let (_, stats, sink) = solve_in_memory(&scene(&text), rectangle_with_sides(LX, 1.0, 8, 4, CellShape::Quad))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sink.steps.len(), 9);
    let mut deltas = Vec::new();
    for step in &sink.steps {
        let r = reaction(&stats, "Gamma2_top", "y", step.time);
        assert!((r + P * LX).abs() <= 1e-10 * P * LX, "t = {}: reaction {r}", step.time);
        let total: f64 = step.contact.as_ref().unwrap().force.iter().sum();
        assert!(
            (total - P * LX).abs() <= 1e-10 * P * LX,
            "t = {}: foundation {total}",
            step.time
        );
        deltas.push(step.motion[0]);
    }
    assert!(
        deltas.windows(2).skip(1).all(|w| (w[1] - w[0]).abs() > 1e-8),
        "δ does not creep under the memory: {deltas:?}"
    );
}

/// The gallery's force-controlled Hertz scene through the command line: `hvi check` shows the
/// rigid parameter in its plan, `hvi solve` writes force_control.csv whose force is the scene's
/// P(t) and whose displacement is the δ that moves the base (positive: towards the cylinder),
/// and reactions.csv's base row equals that force.
#[test]
fn the_force_controlled_gallery_scene_runs_from_the_command_line() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mesh = root.join("examples/gallery/hertz_2d/hertz_2d_h3.msh");
    let scene_file = root.join("examples/gallery/hertz_2d/hertz_2d_force.toml");
    let out = tempfile::tempdir().unwrap();
    let check = common::hvi_ok(&["check", mesh.to_str().unwrap(), "--scene", scene_file.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(
        text.contains("force control of force_control[0] (group Base, y)"),
        "{text}"
    );
    common::hvi_ok(&[
        "solve",
        mesh.to_str().unwrap(),
        "--scene",
        scene_file.to_str().unwrap(),
        "--out",
        out.path().to_str().unwrap(),
    ]);
    let csv = std::fs::read_to_string(out.path().join("force_control.csv")).unwrap();
    let last: Vec<&str> = csv.lines().last().unwrap().split(',').collect();
    assert_eq!(&last[1..3], ["Base", "y"], "{csv}");
    let (force, delta): (f64, f64) = (last[3].parse().unwrap(), last[4].parse().unwrap());
    assert!((force - 7.2656e-4).abs() <= 1e-15, "{csv}");
    // P is δ = 0.004's force rounded to 5 digits: δ within that
    assert!((delta / 0.004 - 1.0).abs() < 1e-4, "δ = {delta}");
    let reactions = std::fs::read_to_string(out.path().join("reactions.csv")).unwrap();
    let base = reactions
        .lines()
        .rfind(|l| l.contains(",Base,y,"))
        .unwrap_or_else(|| panic!("{reactions}"));
    let r: f64 = base.rsplit(',').next().unwrap().parse().unwrap();
    assert!((r - force).abs() <= 1e-10 * force, "reaction {r} against {force}");
}
