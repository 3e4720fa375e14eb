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
                for c in 0..2 {
                    worst = worst.max((step.displacement[2 * p + c] - e[c]).abs());
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
