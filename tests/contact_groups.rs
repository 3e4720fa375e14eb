//! Several contact groups (docs/method.md §14): a node shared by two groups with different
//! obstacles and directions (the corner rule of §14.3), an obstacle moving with a prescribed
//! motion against the analytic force of a uniaxially compressed block, a node meeting more walls
//! than it has components, and the effective scene of a run with `[[contact]]` sections.

mod common;

use common::{rectangle_with_sides, scene};
use hvi::app::solve_in_memory;
use hvi::contact::NodeStatus;
use hvi::mesh::structured::CellShape;

/// The unit square pushed by its top, u = (0.03 t, −0.03 t) prescribed there, into a corner: the
/// floor is a plane 0.01 below the bottom ("Gamma3", direction = the plane's normal, the
/// default), the wall a rigid disc of radius 1 whose leftmost point is 0.01 right of the corner
/// (1, 0) ("Right", direction = "body": along the side's normal (1, 0), gap 1.01 − √(1 − y²)
/// at height y). The corner node (1, 0) is in both groups. §14.3: their directions are 90° apart,
/// so the node gets one row per wall, and it ends on both, penetrating neither; had the rows been
/// merged into one along the bisector, the node could slide into either wall.
#[test]
fn a_node_of_two_groups_meets_both_walls() {
    let text = "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 4\n\
        [[dirichlet]]\ngroup = \"Gamma2_top\"\ncomponents = [\"x\", \"y\"]\nvalue = [\"0.03*t\", \"-0.03*t\"]\n\
        [[contact]]\ngroup = \"Gamma3\"\nobstacle = { kind = \"plane\", point = [0.0, -0.01], normal = [0.0, 1.0] }\n\
        [[contact]]\ngroup = \"Right\"\nobstacle = { kind = \"circle\", centre = [2.01, 0.0], radius = 1.0 }\ndirection = \"body\"\n";
    let mesh = rectangle_with_sides(1.0, 1.0, 8, 8, CellShape::Quad);
    let (sim, stats, sink) = solve_in_memory(&scene(text), mesh).unwrap();
    let c = sim.contact.as_ref().unwrap();
    let corner = sim.mesh.points.iter().position(|x| *x == [1.0, 0.0]).unwrap();
    let rows: Vec<usize> = (0..c.nodes.len()).filter(|&k| c.nodes.nodes[k] == corner).collect();
    assert_eq!(rows.len(), 2, "the corner carries one row per wall");
    let floor = rows
        .iter()
        .copied()
        .find(|&k| c.row_group[k] == 0)
        .expect("a floor row");
    let wall = rows.iter().copied().find(|&k| c.row_group[k] == 1).expect("a wall row");
    assert_eq!(c.nodes.normals[floor], [0.0, -1.0]);
    assert_eq!(c.nodes.normals[wall], [1.0, 0.0]);
    let gap = c.gap.as_ref().unwrap();
    // each row's own gap, from the geometry
    for (k, g) in gap.iter().enumerate() {
        let x = sim.mesh.points[c.nodes.nodes[k]];
        let expected = if c.row_group[k] == 0 {
            0.01
        } else {
            1.01 - (1.0 - x[1] * x[1]).sqrt()
        };
        // (the ray is intersected to 1e-13 of the body's size, docs/method.md §14.2)
        assert!((g - expected).abs() < 1e-12, "row {k} at {x:?}: gap {g}");
    }
    let mut worst = 0.0f64;
    for s in &sink.steps {
        let state = s.contact.as_ref().unwrap();
        let u = sim.dofs.to_nodal(&s.displacement);
        for k in 0..c.nodes.len() {
            let ud: f64 = (0..2).map(|i| c.nodes.normals[k][i] * u[c.nodes.nodes[k]][i]).sum();
            worst = worst.max(ud - gap[k]);
            // rigid walls (no law): no force off the wall, none pulling on it
            if state.status[k] == NodeStatus::OnBound {
                assert!(state.force[k] >= 0.0, "t = {}: row {k} pulls", s.time);
            } else {
                assert!(
                    state.force[k].abs() < 1e-14,
                    "t = {}: row {k} off its wall carries {}",
                    s.time,
                    state.force[k]
                );
            }
        }
        if s.time == 1.0 {
            // pushed 0.03 into both: the corner rests on both walls
            assert_eq!(state.status[floor], NodeStatus::OnBound);
            assert_eq!(state.status[wall], NodeStatus::OnBound);
            assert!(
                (u[corner][0] - 0.01).abs() < 1e-12 && (u[corner][1] + 0.01).abs() < 1e-12,
                "{:?}",
                u[corner]
            );
            assert!(state.force[floor] > 0.0 && state.force[wall] > 0.0);
        }
    }
    // no row passes its wall (the solver's tolerance 1e-10 of the displacement scale 0.03)
    println!("corner: worst d·u − gap over the rows and steps {worst:.1e}");
    assert!(worst < 3e-12, "a row passes its wall by {worst:e}");
    // each group's total: the floor pushes up only, the disc (acting along (1, 0)) left only
    let total = |g: &str, comp: &str| {
        stats
            .contact_forces
            .iter()
            .find(|r| r.time == 1.0 && r.group == g && r.component == comp)
            .unwrap()
            .force
    };
    assert!(total("Gamma3", "y") > 0.0 && total("Gamma3", "x") == 0.0);
    assert!(total("Right", "x") < 0.0 && total("Right", "y") == 0.0);
}

/// A node meeting three walls in 2D (the corner (1, 0) of the floor, the wall and a third group
/// on the bottom whose obstacle acts along (−1, 1)/√2, more than 45° from both) is refused with a
/// message naming the node and the fix, before anything is solved.
#[test]
fn more_walls_than_components_is_an_error_naming_the_node() {
    let text = "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n\
        [[dirichlet]]\ngroup = \"Gamma2_top\"\ncomponents = [\"x\", \"y\"]\n\
        [[contact]]\ngroup = \"Gamma3\"\nobstacle = { kind = \"plane\", point = [0.0, -0.01], normal = [0.0, 1.0] }\n\
        [[contact]]\ngroup = \"Right\"\nobstacle = { kind = \"plane\", point = [1.01, 0.0], normal = [-1.0, 0.0] }\n\
        [[contact]]\ngroup = \"Gamma3\"\nobstacle = { kind = \"plane\", point = [-2.0, 0.0], normal = [1.0, -1.0] }\n";
    let mesh = rectangle_with_sides(1.0, 1.0, 4, 4, CellShape::Quad);
    let err = match solve_in_memory(&scene(text), mesh) {
        Ok(_) => panic!("three walls at a 2D node were accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("[1.0, 0.0]") && err.contains("3 walls") && err.contains("at most 2"),
        "{err}"
    );
}

/// `motion`: a rigid plane 0.01 above the top of the unit square moves down by 0.02 t (frictionless,
/// rigid: no law). The square stands on rollers (u_y = 0 on the bottom, u_x = 0 on the left), so once
/// the plane has closed the gap (t > 1/2) it is compressed uniaxially by δ(t) = 0.02 t − 0.01:
/// σ_yy = −E/(1 − ν²) δ / H (plane strain with σ_xx = 0), and the plane's total force on the body
/// is (0, −E/(1 − ν²) δ L/H) — exactly, since that displacement is linear, in the Q1 space. Before,
/// nothing touches and the body does not move. At every step, in both directions (the plane's
/// normal and the body's coincide here, and §14.2's gap(t) = gap₀ + n·a/(n·d) is exact for a plane).
#[test]
fn a_moving_plane_compresses_a_block_by_its_prescribed_motion() {
    let (e, nu) = (1.0, 0.3);
    let mut worst = 0.0f64;
    for direction in ["obstacle", "body"] {
        let text = format!(
            "[material]\nplane = \"strain\"\nyoungs_modulus = {e}\npoisson_ratio = {nu}\n[time]\nfinal_time = 1.0\nsteps = 10\n\
             [[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n[[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\"]\n\
             [[contact]]\ngroup = \"Gamma2_top\"\ndirection = \"{direction}\"\n\
             obstacle = {{ kind = \"plane\", point = [0.0, 1.01], normal = [0.0, -1.0], motion = [\"0\", \"-0.02*t\"] }}\n"
        );
        let mesh = rectangle_with_sides(1.0, 1.0, 4, 4, CellShape::Quad);
        let (sim, stats, sink) = solve_in_memory(&scene(&text), mesh).unwrap();
        let c = sim.contact.as_ref().unwrap();
        assert!(c.motion.is_some());
        assert_eq!(sink.steps.len(), 11);
        for s in &sink.steps {
            let delta = (0.02 * s.time - 0.01).max(0.0);
            let expected = -e / (1.0 - nu * nu) * delta;
            let force: Vec<f64> = ["x", "y"]
                .iter()
                .map(|comp| {
                    stats
                        .contact_forces
                        .iter()
                        .find(|r| r.time == s.time && r.group == "Gamma2_top" && r.component == *comp)
                        .unwrap()
                        .force
                })
                .collect();
            // round-off of the solve (the exact solution is in the space): 1e-10 of the final force
            let tol = 1e-10 * e / (1.0 - nu * nu) * 0.01;
            worst = worst.max((force[1] - expected).abs().max(force[0].abs()) / (e / (1.0 - nu * nu) * 0.01));
            assert!(
                force[0].abs() < tol,
                "{direction}, t = {}: x force {}",
                s.time,
                force[0]
            );
            assert!(
                (force[1] - expected).abs() < tol,
                "{direction}, t = {}: contact force {} against {expected}",
                s.time,
                force[1]
            );
            // the top follows the plane once it touches, and nothing moves before
            let u = sim.dofs.to_nodal(&s.displacement);
            for &p in &c.nodes.nodes {
                assert!(
                    (u[p][1] + delta).abs() < 1e-12,
                    "{direction}, t = {}: u_y = {}",
                    s.time,
                    u[p][1]
                );
            }
            if delta == 0.0 {
                assert!(u.iter().all(|v| v[0].abs() < 1e-14 && v[1].abs() < 1e-14));
            }
        }
    }
    println!("moving plane: the contact force differs from E* δ L/H by {worst:.1e} of the final force");
}

/// The effective scene of a run with `[[contact]]` sections (written as the run's scene.toml, read
/// back by `hvi plot` and by a user rerunning it) reads back to the same scene: it must not carry
/// `groups.contact`, which `[[contact]]` sections refuse.
#[test]
fn a_scene_with_contact_groups_round_trips() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/two_zones/two_zones.toml");
    let s = hvi::scene::Scene::load(Some(&path), &[]).unwrap();
    assert_eq!(s.contact.len(), 2);
    let text = s.to_toml_string();
    assert!(!text.contains("contact = \"Gamma3\""), "{text}");
    let again = hvi::scene::Scene::from_toml_str(&text, "round trip").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again.to_toml_string(), text);
    // the one-table form keeps a group that is not the default
    let one = hvi::scene::Scene::load(None, &["groups.contact = \"Floor\"".into()]).unwrap();
    let again = hvi::scene::Scene::from_toml_str(&one.to_toml_string(), "round trip").unwrap();
    assert_eq!(again.contact_group(0), hvi::mesh::GroupSelector::Name("Floor".into()));
}

/// The rectangle (0, 2) × (0, 1) on rollers (u_x = 0 at x = 0, u_y = 0 at y = 0) with its top in
/// contact with a rigid plane `depth` below the top (normal (0, −1), toward the body), no load.
fn interference(depth: f64) -> String {
    format!(
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n\
         [[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n[[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\"]\n\
         [[contact]]\ngroup = \"Gamma2_top\"\nobstacle = {{ kind = \"plane\", point = [0.0, {}], normal = [0.0, -1.0] }}\n",
        1.0 - depth
    )
}

/// An interference fit: the plane starts 0.01 inside the top, and nothing is loaded. The plane
/// pushes the top out at t = 0: uniaxial compression by δ = 0.01, force E/(1 − ν²) δ L/H on the
/// body (L = 2, H = 1), exactly in the Q1 space. Before the contact solve's force scale counted
/// the interference, an unloaded step had the scale 0 and never converged (it reported a residual
/// of 1e291 "after 100 iterations"); `hvi check` says the nodes start inside the obstacle.
#[test]
fn an_interference_fit_is_pushed_out_with_the_analytic_force() {
    let (e, nu, depth) = (1.0, 0.3, 0.01);
    let mesh = hvi::mesh::structured::rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
    let (sim, stats, sink) = solve_in_memory(&scene(&interference(depth)), mesh).unwrap();
    let expected = -e / (1.0 - nu * nu) * depth * 2.0;
    for s in &sink.steps {
        let force = stats
            .contact_forces
            .iter()
            .find(|r| r.time == s.time && r.component == "y")
            .unwrap()
            .force;
        // the exact solution is in the space: round-off of the solve (1e-10 relative)
        assert!(
            (force - expected).abs() < 1e-10 * expected.abs(),
            "t = {}: {force} against {expected}",
            s.time
        );
        let u = sim.dofs.to_nodal(&s.displacement);
        for &p in &sim.contact.as_ref().unwrap().nodes.nodes {
            assert!((u[p][1] + depth).abs() < 1e-12, "u_y = {}", u[p][1]);
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fit.toml");
    std::fs::write(&path, interference(depth)).unwrap();
    let report = hvi::app::check(std::path::Path::new("rect:8x4"), Some(&path), &[], false).unwrap();
    assert!(
        report.contains("warning: 9 node(s) of contact group `Gamma2_top` start inside its obstacle"),
        "{report}"
    );
    // touching, not inside: no such warning
    std::fs::write(&path, interference(0.0)).unwrap();
    let report = hvi::app::check(std::path::Path::new("rect:8x4"), Some(&path), &[], false).unwrap();
    assert!(!report.contains("inside its obstacle"), "{report}");
}

/// Bad values of contact keys that only show when the scene meets the mesh or the clock name
/// the key, the value and what is valid.
#[test]
fn bad_contact_values_name_their_key() {
    let base = "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 2\n";
    let mesh = || hvi::mesh::structured::rectangle(2.0, 1.0, 4, 2, CellShape::Quad);
    let fails = |text: String| -> String {
        match hvi::scene::Scene::from_toml_str(&text, "bad.toml") {
            Err(e) => e.to_string(),
            Ok(s) => match solve_in_memory(&s, mesh()) {
                Err(e) => e.to_string(),
                Ok(_) => panic!("accepted:\n{text}"),
            },
        }
    };
    // a motion that is not finite at a step time: the key, the expression and the value
    let e = fails(format!(
        "{base}[[contact]]\ngroup = \"Gamma3\"\nobstacle = {{ kind = \"plane\", point = [0.0, -0.1], normal = [0.0, 1.0], motion = [\"0\", \"1/(t - 0.5)\"] }}\n"
    ));
    assert!(
        e.contains("contact[0].obstacle.motion[1] = \"1/(t - 0.5)\" is inf") && e.contains("t = 0.5"),
        "{e}"
    );
    // an sdf without a gradient: the key and the expression
    let e = fails(format!(
        "{base}[[contact]]\ngroup = \"Gamma3\"\nobstacle = {{ kind = \"sdf\", sdf = \"1\" }}\n"
    ));
    assert!(
        e.contains("contact[0].obstacle.sdf = \"1\"") && e.contains("gradient vanishes"),
        "{e}"
    );
    // a section with a group and nothing else would have been dropped silently
    let e = fails(format!("{base}[[contact]]\ngroup = \"Gamma3\"\n"));
    assert!(
        e.contains("contact[0].group") && e.contains("no bound, law or obstacle"),
        "{e}"
    );
    // a group that is neither a name nor an integer tag, or a tag out of range
    let e = fails(format!("{base}[[contact]]\ngroup = 3.5\nbound = 0.1\n"));
    assert!(
        e.contains("3.5") && e.contains("its name in quotes") && e.contains("integer tag"),
        "{e}"
    );
    let e = fails(format!("{base}[[contact]]\ngroup = 99999999999\nbound = 0.1\n"));
    assert!(e.contains("99999999999 is out of range"), "{e}");
    // a plane's normal whose square overflows is still a direction: [1e300, 1e300] is (1, 1)/√2
    let ok = format!(
        "{base}[groups]\nclamped = \"Gamma1\"\n[[contact]]\ngroup = \"Gamma3\"\nobstacle = {{ kind = \"plane\", point = [0.0, -1.0], normal = [1e300, 1e300] }}\n"
    );
    let (sim, _, _) = solve_in_memory(&scene(&ok), mesh()).unwrap();
    let c = sim.contact.unwrap();
    let s = std::f64::consts::FRAC_1_SQRT_2;
    assert!(c
        .nodes
        .normals
        .iter()
        .all(|d| (d[0] + s).abs() < 1e-15 && (d[1] + s).abs() < 1e-15));
}
