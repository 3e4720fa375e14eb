//! The gallery of README's "Problems you can pose": each entry run as README says, with a check
//! of what it shows. (The Hertz entries, examples/gallery/hertz_2d and hertz_3d, are run and
//! checked against the closed forms by tests/hertz.rs.)

mod common;

use hvi::app::solve_in_memory;
use hvi::mesh::read_mesh;
use hvi::scene::Scene;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn run_files(mesh: &str, scene: Option<&str>, out: &Path) -> hvi::solver::RunStats {
    common::solve_files(mesh, scene, out)
}

/// The paper's example on a mesh with only the paper's groups (Gamma1, Gamma2, Gamma3, Omega):
/// `hvi solve meshes/rect_q1_h16_plain.msh` runs with the embedded scene and gives the same
/// solution as the mesh with the extra group Gamma2_top (same nodes, same cells): the load on
/// Gamma2 is written with the facet normal, so no extra group is needed. Agreement to 1e-12
/// relative: the two runs assemble the same numbers, up to the order of summation.
#[test]
fn paper_on_a_gamma1_2_3_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let stats = run_files("meshes/rect_q1_h16_plain.msh", None, &dir.path().join("paper"));
    assert!(dir.path().join("paper/solution.pvd").exists());
    let scene = Scene::load(None, &[]).unwrap();
    let plain = read_mesh::<2>(&root().join("meshes/rect_q1_h16_plain.msh")).unwrap();
    let full = read_mesh::<2>(&root().join("meshes/rect_q1_h16.msh")).unwrap();
    assert_eq!(plain.points, full.points);
    let (_, _, a) = solve_in_memory(&scene, plain).unwrap();
    let (_, full_stats, b) = solve_in_memory(&scene, full).unwrap();
    let (ua, ub) = (
        &a.steps.last().unwrap().displacement,
        &b.steps.last().unwrap().displacement,
    );
    let scale = ub.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = ua.iter().zip(ub).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(scale > 0.0 && diff <= 1e-12 * scale, "max difference {diff} of {scale}");
    assert_eq!(
        stats.contact.last().unwrap().active,
        full_stats.contact.last().unwrap().active
    );
}

/// A layer of varying thickness: examples/gallery/layer/layer.toml on meshes/rect_q1_h32.msh.
/// The nodes on the bound at T have u_ν = g(x_p) to the solver's tolerance (1e-10 relative, so
/// 1e-9 g), there are some, and they lie in the valleys of g (sin 6πx < 0), where g is convex.
#[test]
fn layer_of_varying_thickness() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = "meshes/rect_q1_h32.msh";
    let scene_file = "examples/gallery/layer/layer.toml";
    run_files(mesh, Some(scene_file), &dir.path().join("layer"));
    let scene = Scene::load(Some(&root().join(scene_file)), &[]).unwrap();
    let (sim, _, sink) = solve_in_memory(&scene, read_mesh::<2>(&root().join(mesh)).unwrap()).unwrap();
    let c = sim.contact.as_ref().unwrap();
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let mut on_bound = 0;
    for (k, &p) in c.nodes.nodes.iter().enumerate() {
        let x = sim.mesh.points[p][0];
        let g = 0.2 + 0.02 * (6.0 * std::f64::consts::PI * x).sin();
        let r = state.normal_displacement[k];
        assert!(r <= g * (1.0 + 1e-9), "node at x = {x}: u_ν = {r} > g = {g}");
        if state.status[k] == hvi::contact::NodeStatus::OnBound {
            on_bound += 1;
            assert!(
                (r - g).abs() <= 1e-9 * g,
                "node at x = {x}: u_ν = {r} on the bound g = {g}"
            );
            assert!(
                (6.0 * std::f64::consts::PI * x).sin() < 0.0,
                "node on the bound at x = {x} off a valley"
            );
        }
    }
    assert!(on_bound >= 5, "only {on_bound} nodes on the bound");
}

/// The 2D Hertz entry through files, as README's command runs it: the scene's groups exist in
/// the mesh and some nodes end on the obstacle.
#[test]
fn hertz_entries_run_as_readme_says() {
    let dir = tempfile::tempdir().unwrap();
    // (the 3D entry reads its scene the same way in tests/hertz.rs; not run twice)
    let (mesh, scene) = (
        "examples/gallery/hertz_2d/hertz_2d_h1.msh",
        "examples/gallery/hertz_2d/hertz_2d.toml",
    );
    let out: PathBuf = dir.path().join("hertz_2d");
    let stats = run_files(mesh, Some(scene), &out);
    assert!(
        stats.contact.last().unwrap().active > 0,
        "{mesh}: no node on the obstacle"
    );
    assert!(out.join("solution.pvd").exists());
}

/// A pressure-loaded body: examples/gallery/ring/ring.toml on meshes/ring_q1_n16.msh, run through
/// files as README says. The displacement at T is the Lamé solution to the mesh's accuracy (the
/// nodal error on this mesh is 1.0e-3 of u_r(a), tests/pressure.rs; 2e-3 allows for nothing but
/// a wrong load or normal), and the frames are written.
#[test]
fn pressure_loaded_ring() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, scene_file) = ("meshes/ring_q1_n16.msh", "examples/gallery/ring/ring.toml");
    run_files(mesh, Some(scene_file), &dir.path().join("ring"));
    assert!(dir.path().join("ring/solution.pvd").exists());
    let scene = Scene::load(Some(&root().join(scene_file)), &[]).unwrap();
    let (sim, _, sink) = solve_in_memory(&scene, read_mesh::<2>(&root().join(mesh)).unwrap()).unwrap();
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let (e, nu, p, a, b) = (1.0, 0.3, 0.01, 1.0, 2.0);
    let ur = |r: f64| p * a * a / (e * (b * b - a * a)) * ((1.0 + nu) * (1.0 - 2.0 * nu) * r + (1.0 + nu) * b * b / r);
    let mut worst = 0.0f64;
    for (x, v) in sim.mesh.points.iter().zip(&u) {
        let r = (x[0] * x[0] + x[1] * x[1]).sqrt();
        let exact = [ur(r) * x[0] / r, ur(r) * x[1] / r];
        worst = worst.max((v[0] - exact[0]).abs().max((v[1] - exact[1]).abs()));
    }
    assert!(worst < 2e-3 * ur(a), "nodal error {worst:e} of u_r(a) = {:e}", ur(a));
}

/// A CSV file's header and rows of cells (numbers or text), addressed by column name.
struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Csv {
    fn read(path: &Path) -> Csv {
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut lines = text
            .lines()
            .map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>());
        let header = lines.next().expect("a header");
        let rows: Vec<Vec<String>> = lines.collect();
        assert!(
            rows.iter().all(|r| r.len() == header.len()),
            "{}: ragged rows",
            path.display()
        );
        Csv { header, rows }
    }
    fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }
    fn num(&self, row: &[String], name: &str) -> f64 {
        row[self.col(name)].parse().expect("a number")
    }
}

/// Two contact zones: examples/gallery/two_zones (an arched beam clamped at x = 0 under a rising
/// pressure, its left foot on the paper's layer with a bound, its right foot at a gap over a
/// coated rigid roller), run through files as README says. From the files alone, at every output
/// step:
/// * gamma3.csv's `group` column splits the rows into the two groups (by their physical tags),
///   24 rows on the left foot (its node at the clamp carries no contact unknown) and 61 on the right;
/// * each group's law holds at each of its rows, with the law, bound and gap written out here from
///   two_zones.toml (the gap to the roller |x − c| − R, not hvi's): off the bound the pressure is
///   the regularised j_ε'(u_ν − gap) of docs/method.md §4.2 (the paper's odd law on the left, a
///   one-sided linear law on the right), on the bound u_ν = gap + g and the pressure is at least
///   j'(g); no row passes its bound;
/// * each group's total in contact_forces.csv is the sum of its rows' forces −λ d (d = (0, −1) on
///   the flat foot, minus the roller's normal at the closest point on the right);
/// * reactions + contact forces + the applied pressure (0, −4 p(t)) = 0 (global equilibrium).
#[test]
fn two_contact_zones() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("two_zones");
    let mesh_file = "examples/gallery/two_zones/two_zones.msh";
    run_files(mesh_file, Some("examples/gallery/two_zones/two_zones.toml"), &out);
    let mesh = read_mesh::<2>(&root().join(mesh_file)).unwrap();
    let tag = |name: &str| mesh.group(&hvi::mesh::GroupSelector::Name(name.into()), 1).unwrap().tag;
    let (left, right) = (f64::from(tag("LeftFoot")), f64::from(tag("RightFoot")));
    let (g3, totals, reactions) = (
        Csv::read(&out.join("gamma3.csv")),
        Csv::read(&out.join("contact_forces.csv")),
        Csv::read(&out.join("reactions.csv")),
    );
    // two_zones.toml
    let eps = 1e-8;
    let pressure = |t: f64| 0.001 * t;
    let (s_left, a, b, alpha, g_left) = (0.1, 0.04, 0.02, 100.0, 0.002);
    let (centre, radius, s_right, g_right) = ([3.4, -0.52], 0.5, 1.0, 0.008);
    // (j_ε', j_ε'') of docs/method.md §4.2: j_ε'(r) = S μ(ρ_ε(r)) ρ_ε'(r)
    let odd = |r: f64| {
        let q = (r * r + eps * eps).sqrt();
        let (rho, d, dd) = (q - eps, r / q, eps * eps / (q * q * q));
        let e = (a - b) * (-alpha * rho).exp();
        (s_left * (e + b) * d, s_left * (-alpha * e * d * d + (e + b) * dd))
    };
    let one_sided = |r: f64| {
        let q = (r * r + eps * eps).sqrt();
        let (rho, d, dd) = ((r + q - eps) / 2.0, (1.0 + r / q) / 2.0, eps * eps / (2.0 * q * q * q));
        (s_right * rho * d, s_right * (d * d + rho * dd))
    };
    let mut times: Vec<f64> = g3.rows.iter().map(|r| g3.num(r, "time")).collect();
    times.dedup();
    assert_eq!(times.len(), 17);
    let (mut worst_law, mut worst_total, mut worst_balance) = (0.0f64, 0.0f64, 0.0f64);
    let mut seen = [[false; 3]; 2];
    for &t in &times {
        let rows: Vec<&Vec<String>> = g3.rows.iter().filter(|r| g3.num(r, "time") == t).collect();
        let mut sum = [[0.0f64; 2]; 2];
        let mut count = [0; 2];
        // the law's scale: the pressure over the foot at T is ~ p(T)·4 / 1.2 ≈ 3e-3 … 2e-2
        let scale = 1e-2;
        for r in &rows {
            let (x, y) = (g3.num(r, "x"), g3.num(r, "y"));
            let (un, force, p) = (g3.num(r, "u_nu"), g3.num(r, "force"), g3.num(r, "pressure"));
            let status = g3.num(r, "status") as usize;
            let group = g3.num(r, "group");
            assert_eq!(y, 0.0);
            let (k, gap, layer, law, normal) = if group == left {
                assert!(x <= 1.2 + 1e-12, "a left-foot row at x = {x}");
                (0, 0.0, g_left, &odd as &dyn Fn(f64) -> (f64, f64), [0.0, 1.0])
            } else {
                assert_eq!(group, right, "row at x = {x}");
                assert!(x >= 2.8 - 1e-12, "a right-foot row at x = {x}");
                let (dx, dy) = (x - centre[0], y - centre[1]);
                let len = (dx * dx + dy * dy).sqrt();
                (
                    1,
                    len - radius,
                    g_right,
                    &one_sided as &dyn Fn(f64) -> (f64, f64),
                    [dx / len, dy / len],
                )
            };
            count[k] += 1;
            seen[k][status] = true;
            for c in 0..2 {
                sum[k][c] += force * normal[c];
            }
            // the bound: never passed; on it to the solver's tolerance (1e-10 relative, so 1e-9 of g)
            assert!(
                un <= gap + layer + 1e-9 * layer,
                "t = {t}, x = {x}: u_ν = {un} past {}",
                gap + layer
            );
            if status == 2 {
                assert!(
                    (un - gap - layer).abs() <= 1e-9 * layer,
                    "t = {t}, x = {x}: on the bound at {un}"
                );
                assert!(
                    p >= law(layer).0 - 1e-9 * scale,
                    "t = {t}, x = {x}: pressure {p} < j'(g)"
                );
            } else {
                assert_eq!(
                    status == 1,
                    un > gap,
                    "t = {t}, x = {x}: status {status}, u_ν − gap = {}",
                    un - gap
                );
                // the contact solve stops at a relative residual of 1e-10: the pressure is the law's
                // to 1e-10 of its scale, and u_ν to 1e-10 of the displacement scale (0.03), which
                // moves j_ε' by j_ε'' times that (large within ~ε of r = 0 on the left foot)
                let (j1, j2) = law(un - gap);
                let tolerance = 1e-10 * scale + j2.abs() * 1e-10 * 0.03;
                worst_law = worst_law.max((p - j1).abs() / tolerance);
            }
        }
        assert_eq!(count, [24, 61], "t = {t}: rows per group");
        for (k, name) in ["LeftFoot", "RightFoot"].iter().enumerate() {
            for (c, comp) in ["x", "y"].iter().enumerate() {
                let row = totals
                    .rows
                    .iter()
                    .find(|r| {
                        totals.num(r, "time") == t
                            && r[totals.col("group")] == *name
                            && r[totals.col("component")] == *comp
                    })
                    .unwrap_or_else(|| panic!("no total of {name} {comp} at t = {t}"));
                worst_total = worst_total.max((totals.num(row, "force") - sum[k][c]).abs() / (4.0 * pressure(1.0)));
            }
        }
        for (c, comp) in ["x", "y"].iter().enumerate() {
            let of = |csv: &Csv| -> f64 {
                csv.rows
                    .iter()
                    .filter(|r| csv.num(r, "time") == t && r[csv.col("component")] == *comp)
                    .map(|r| csv.num(r, "force"))
                    .sum()
            };
            let applied = if c == 1 { -4.0 * pressure(t) } else { 0.0 };
            worst_balance = worst_balance.max((of(&reactions) + of(&totals) + applied).abs() / (4.0 * pressure(1.0)));
        }
        if t == 1.0 {
            // both groups carry a real share of the load (0.004)
            assert!(sum[0][1] > 1e-3 && sum[1][1] > 1e-3, "t = 1: {sum:?}");
        }
    }
    println!("two zones: law {worst_law:.1e} of its tolerance, totals {worst_total:.1e}, balance {worst_balance:.1e} (relative)");
    // the law (measured 0.1 of its tolerance above); the totals are sums of the same printed
    // forces (round-off, measured 1e-16); equilibrium as tests/equilibrium.rs (measured 5e-14)
    assert!(
        worst_law < 1.0,
        "a group's law is off by {worst_law:e} of its tolerance"
    );
    assert!(
        worst_total < 1e-12,
        "contact_forces.csv and gamma3.csv differ by {worst_total:e}"
    );
    assert!(worst_balance < 1e-10, "out of equilibrium by {worst_balance:e}");
    // every branch was met: separated (the left foot only at t = 0: it is pressed everywhere
    // after), in the layer, and on the bound (the left foot's end near x = 1.2, the roller's top)
    assert_eq!(seen, [[true; 3]; 2], "statuses met (left, right): {seen:?}");
}

/// The paper's example with Coulomb friction (examples/gallery/paper_coulomb, README "Friction
/// with the memory term"): run as README says, `hvi plot` draws gamma3_zones, and at every
/// output time each node that slips carries |λ_τ| = μ λ_ν (to 1e-6 relative: the smoothing
/// ε²/(2Δ²) of slips above 1e-6 and the solve's 1e-10 of the force scale) while each that sticks
/// carries less; both zones exist at T, and the stick zone moves over time (the memory term
/// changes the stresses under the growing load).
#[test]
fn paper_example_with_coulomb_friction() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("paper_coulomb");
    run_files(
        "meshes/rect_q1_h32.msh",
        Some("examples/gallery/paper_coulomb/paper_coulomb.toml"),
        &out,
    );
    let pictures = hvi::plot::plot_run(&out, &hvi::plot::PlotOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert!(pictures.iter().any(|p| p.ends_with("gamma3_zones.png")), "{pictures:?}");
    let text = std::fs::read_to_string(out.join("gamma3.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let (time, force, tau, slip, status) = (
        col("time"),
        col("force"),
        col("force_tau"),
        col("slip"),
        col("friction_status"),
    );
    let mut zones: Vec<(f64, Vec<i32>)> = Vec::new();
    let scale = 1e-3;
    for line in lines {
        let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        if zones.last().is_none_or(|z| z.0 != v[time]) {
            zones.push((v[time], Vec::new()));
        }
        let code = v[status] as i32;
        zones.last_mut().unwrap().1.push(code);
        match code {
            2 if v[slip].abs() > 1e-6 => assert!(
                (v[tau].abs() - 0.3 * v[force]).abs() <= 1e-6 * (0.3 * v[force]) + 1e-10 * scale,
                "t = {}: a slipping node carries {:e} against μλ_ν = {:e}",
                v[time],
                v[tau],
                0.3 * v[force]
            ),
            1 => assert!(
                v[tau].abs() < 0.3 * v[force],
                "t = {}: a sticking node at its bound",
                v[time]
            ),
            _ => {}
        }
    }
    let last = &zones.last().unwrap().1;
    assert!(last.contains(&1) && last.contains(&2), "both zones at T: {last:?}");
    let sticking: Vec<usize> = zones
        .iter()
        .map(|(_, z)| z.iter().filter(|&&c| c == 1).count())
        .collect();
    assert!(
        sticking.iter().any(|&n| n != sticking[sticking.len() / 2]),
        "the stick zone does not change: {sticking:?}"
    );
}
