//! Shared helpers of the integration tests.
#![allow(dead_code)]

use hvi::mesh::structured::{block, rectangle, CellShape, SolidShape};
use hvi::mesh::{Cell, Facet, Mesh, PhysicalGroup};
use hvi::scene::Scene;
use std::process::{Command, Output};

// the asphalt's data, the creep compliance of a Prony series and the creep cube (shared with
// benches/time_scales.rs)
#[path = "support/creep.rs"]
mod creep;
#[allow(unused_imports)] // (each test crate uses its share of common.rs)
pub use creep::{creep_cube, sub_group, uniaxial_scene, Compliance, ASPHALT, ASPHALT_E_INF, ASPHALT_NU};

/// Runs the hvi binary with `args` and asserts it succeeded (the message shows its stderr).
pub fn hvi_ok(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_hvi")).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "hvi {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// `hvi solve` through files, as a user runs it: the mesh and the scene (paths from the
/// repository's root), the series into `out` (panics with the error).
pub fn solve_files(mesh: &str, scene: Option<&str>, out: &std::path::Path) -> hvi::solver::RunStats {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let opts = hvi::app::SolveOptions {
        mesh: root.join(mesh),
        scene: scene.map(|s| root.join(s)),
        out: out.to_path_buf(),
        overrides: vec![],
        progress: false,
        overwrite: false,
        accept_mesh_defects: false,
    };
    hvi::app::solve(&opts, None).unwrap_or_else(|e| panic!("{e}"))
}

/// A scene from TOML text (panics with the error, which names the key).
pub fn scene(toml: &str) -> Scene {
    Scene::from_toml_str(toml, "<test scene>").unwrap_or_else(|e| panic!("{e}"))
}

/// The rectangle (0, lx) × (0, ly) with nx × ny cells and its groups (Gamma1 left, Gamma2
/// right+top, Gamma3 bottom, Gamma2_top top) plus a "Right" group for the right side.
pub fn rectangle_with_sides(lx: f64, ly: f64, nx: usize, ny: usize, shape: CellShape) -> Mesh<2> {
    let mut mesh = rectangle(lx, ly, nx, ny, shape);
    let right: Vec<Facet> = mesh
        .groups
        .iter()
        .find(|g| g.name.as_deref() == Some("Gamma2"))
        .expect("Gamma2")
        .facets
        .iter()
        .copied()
        .filter(|f| f.nodes().iter().all(|&p| (mesh.points[p][0] - lx).abs() < 1e-12))
        .collect();
    mesh.groups.push(PhysicalGroup {
        dim: 1,
        tag: 90,
        name: Some("Right".into()),
        facets: right,
        cells: vec![],
        nodes: vec![],
    });
    mesh
}

/// Moves interior nodes by a smooth, deterministic perturbation of amplitude `amp`·h.
pub fn distort_interior(mesh: &mut Mesh<2>, lx: f64, ly: f64, h: f64, amp: f64) {
    for (k, p) in mesh.points.iter_mut().enumerate() {
        let on_boundary =
            p[0].abs() < 1e-12 || p[1].abs() < 1e-12 || (p[0] - lx).abs() < 1e-12 || (p[1] - ly).abs() < 1e-12;
        if !on_boundary {
            let s = (k as f64 * 12.9898).sin() * 43758.5453;
            let t = (k as f64 * 78.233).sin() * 12345.678;
            p[0] += amp * h * (s - s.floor() - 0.5);
            p[1] += amp * h * (t - t.floor() - 0.5);
        }
    }
}

/// The manufactured problem u = (sin x cos y, x² sin y): plane stress E = 1, ν = 0.3, clamped
/// at x = 0, the tractions of its stress on the other sides ("Right", "Gamma2_top", "Gamma3")
/// and the body force −div σ, one step.
pub fn manufactured_scene() -> Scene {
    let nu: f64 = 0.3;
    let c = 1.0 / (1.0 - nu * nu);
    let g = c * (1.0 - nu) / 2.0;
    let s11 = format!("{c:e}*(cos(x)*cos(y) + {nu:e}*x^2*cos(y))");
    let s22 = format!("{c:e}*({nu:e}*cos(x)*cos(y) + x^2*cos(y))");
    let s12 = format!("{g:e}*(-sin(x)*sin(y) + 2*x*sin(y))");
    let f1 = format!("-({c:e}*(-sin(x)*cos(y) + 2*{nu:e}*x*cos(y)) + {g:e}*(-sin(x)*cos(y) + 2*x*cos(y)))");
    let f2 = format!("-({g:e}*(-cos(x)*sin(y) + 2*sin(y)) + {c:e}*(-{nu:e}*cos(x)*sin(y) - x^2*sin(y)))");
    scene(&format!(
        "[material]\nplane = \"stress\"\nyoungs_modulus = 1.0\npoisson_ratio = {nu}\n[time]\nfinal_time = 1.0\nsteps = 1\n\
         [[traction]]\ngroup = \"Right\"\nvalue = [\"{s11}\", \"{s12}\"]\n[[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"{s12}\", \"{s22}\"]\n\
         [[traction]]\ngroup = \"Gamma3\"\nvalue = [\"-({s12})\", \"-({s22})\"]\n[body_force]\nvalue = [\"{f1}\", \"{f2}\"]\n"
    ))
}

/// u = (sin x cos y, x² sin y) and its gradient [[∂u₁/∂x, ∂u₁/∂y], [∂u₂/∂x, ∂u₂/∂y]].
pub fn manufactured_exact(x: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
    let (sx, cx, sy, cy) = (x[0].sin(), x[0].cos(), x[1].sin(), x[1].cos());
    (
        [sx * cy, x[0] * x[0] * sy],
        [[cx * cy, -sx * sy], [2.0 * x[0] * sy, x[0] * x[0] * cy]],
    )
}

/// The reaction force of (group, component) at time t in a run's statistics.
pub fn reaction(stats: &hvi::solver::RunStats, group: &str, component: &str, t: f64) -> f64 {
    stats
        .reactions
        .iter()
        .find(|r| r.group == group && r.component == component && (r.time - t).abs() < 1e-12)
        .unwrap_or_else(|| panic!("no reaction {group} {component} at t = {t}"))
        .force
}

/// max over the nodes of max_c |u_c − exact(x)_c|.
pub fn nodal_error<const D: usize>(points: &[[f64; D]], u: &[[f64; D]], exact: impl Fn(&[f64; D]) -> [f64; D]) -> f64 {
    points
        .iter()
        .zip(u)
        .map(|(x, u)| {
            let e = exact(x);
            (0..D).map(|c| (u[c] - e[c]).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

/// Per output step of two runs: (step, max |u_a − u_b| / max over all steps of |u_a|).
pub fn step_differences(a: &hvi::app::MemorySink, b: &hvi::app::MemorySink) -> Vec<(usize, f64)> {
    let max_u = a
        .steps
        .iter()
        .flat_map(|s| s.displacement.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(max_u > 0.0, "the runs compared have zero displacement");
    assert_eq!(a.steps.len(), b.steps.len());
    a.steps
        .iter()
        .zip(&b.steps)
        .map(|(x, y)| {
            let d = x
                .displacement
                .iter()
                .zip(&y.displacement)
                .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
            (x.step, d / max_u)
        })
        .collect()
}

/// MSH 2.2 text of a mesh with its groups: dim-0 groups as points (type 15), dim-1 groups as
/// lines, each cell in the first dim-2 group that holds it (else the first dim-2 group, else tag 5), all named in
/// `$PhysicalNames`.
pub fn msh22(mesh: &Mesh<2>) -> String {
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n");
    s += &format!("{}\n", mesh.groups.len());
    for g in &mesh.groups {
        s += &format!("{} {} \"{}\"\n", g.dim, g.tag, g.name.clone().unwrap_or_default());
    }
    s += &format!("$EndPhysicalNames\n$Nodes\n{}\n", mesh.points.len());
    for (i, p) in mesh.points.iter().enumerate() {
        s += &format!("{} {:?} {:?} 0\n", i + 1, p[0], p[1]);
    }
    let mut el = Vec::new();
    for g in &mesh.groups {
        for n in &g.nodes {
            el.push(format!("15 2 {} {} {}", g.tag, g.tag, n + 1));
        }
        for f in &g.facets {
            el.push(format!("1 2 {} {} {} {}", g.tag, g.tag, f[0] + 1, f[1] + 1));
        }
    }
    for (k, c) in mesh.cells.iter().enumerate() {
        let omega = mesh
            .groups
            .iter()
            .find(|g| g.dim == 2 && g.cells.contains(&k))
            .or_else(|| mesh.groups.iter().find(|g| g.dim == 2))
            .map_or(5, |g| g.tag);
        el.push(match c {
            Cell::Tri3(n) => format!("2 2 {omega} {omega} {} {} {}", n[0] + 1, n[1] + 1, n[2] + 1),
            Cell::Quad4(n) => format!(
                "3 2 {omega} {omega} {} {} {} {}",
                n[0] + 1,
                n[1] + 1,
                n[2] + 1,
                n[3] + 1
            ),
            other => panic!("a 2D test mesh has no {other:?}"),
        });
    }
    s += &format!("$EndNodes\n$Elements\n{}\n", el.len());
    for (i, e) in el.iter().enumerate() {
        s += &format!("{} {e}\n", i + 1);
    }
    s + "$EndElements\n"
}

/// Moves the interior nodes (on no boundary group) of a mesh pseudo-randomly by up to `amount`
/// of the cell size.
pub fn distort_off_groups<const D: usize>(m: &mut Mesh<D>, amount: f64) {
    let mut boundary = vec![false; m.points.len()];
    for g in m.groups.iter().filter(|g| (g.dim as usize) < D) {
        for f in &g.facets {
            for &p in f.nodes() {
                boundary[p] = true;
            }
        }
    }
    let h = m.cell_size().0;
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    for (p, x) in m.points.iter_mut().enumerate() {
        if !boundary[p] {
            for v in x.iter_mut() {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                *v += amount * h * ((seed % 2001) as f64 / 1000.0 - 1.0);
            }
        }
    }
}

/// Two bodies in one mesh: a block (0, 2) × (0, 1) of `lower` cells (nx, ny, shape) and one
/// (0, 2) × (lift, lift + 1) of `upper` cells, sharing no nodes (touching at lift = 1): groups
/// LowerBottom, LowerLeft, LowerTop, UpperBottom, UpperLeft, UpperTop and the bodies Lower and
/// Upper (`hvi::mesh::structured::stack`).
pub fn stacked(lower: (usize, usize, CellShape), upper: (usize, usize, CellShape), lift: f64) -> Mesh<2> {
    hvi::mesh::structured::stack(
        rectangle(2.0, 1.0, lower.0, lower.1, lower.2),
        rectangle(2.0, 1.0, upper.0, upper.1, upper.2),
        lift,
    )
}

/// Least squares of p² = p₀² (1 − r²/a²) over (r, p) of the nodes in contact: a straight line
/// in r² whose intercept is p₀² and whose root is a² (Hertz in 2D and 3D); returns (a, p₀).
/// Every node in contact contributes, so a is located to a fraction of the node spacing, unlike
/// the last node in contact (which only brackets a within one element) or an interpolated edge
/// of the active set (which depends on the nodal pressure of the two nodes around the edge, the
/// least accurate ones: the pressure is ∝ sqrt(a − r) there).
pub fn hertz_fit(pressures: &[(f64, f64)]) -> (f64, f64) {
    let n = pressures.len() as f64;
    let xs: Vec<f64> = pressures.iter().map(|(r, _)| r * r).collect();
    let ys: Vec<f64> = pressures.iter().map(|(_, p)| p * p).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    let slope = sxy / sxx; // −p₀²/a²
    let intercept = my - slope * mx; // p₀²
    ((intercept / -slope).sqrt(), intercept.sqrt())
}

/// The relative errors of a run's a and p₀ (the fit of its rows' `pressures`) against Hertz of
/// dimension `dim` for its total force P: (a/a_Hertz − 1, p₀/p₀_Hertz − 1).
pub fn hertz_errors(force: f64, pressures: &[(f64, f64)], dim: usize, e_star: f64) -> (f64, f64) {
    let (a_hertz, p0_hertz) = hertz(dim, force, e_star);
    let (a, p0) = hertz_fit(pressures);
    (a / a_hertz - 1.0, p0 / p0_hertz - 1.0)
}

/// (r, pressure λ_p / w_p) of every contact row on its bound at the last step, r the distance of
/// its node from the axis through the origin along the last coordinate (Hertz's r).
pub fn bound_pressures<const D: usize>(
    sim: &hvi::solver::Simulation<D>,
    sink: &hvi::app::MemorySink,
) -> Vec<(f64, f64)> {
    let c = sim.contact.as_ref().unwrap();
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let mut pressures = Vec::new();
    for (k, &p) in c.nodes.nodes.iter().enumerate() {
        if state.status[k] == hvi::contact::NodeStatus::OnBound {
            let x = sim.mesh.points[p];
            let r = x[..D - 1].iter().map(|v| v * v).sum::<f64>().sqrt();
            pressures.push((r, state.force[k] / c.nodes.weights[k]));
        }
    }
    pressures
}

/// Hertz for a rigid cylinder (2D, plane strain, P per unit length) or sphere (3D, total force
/// P) of radius 1 on a half-space of E* = E/(1 − ν²): the contact half-width or radius a and the
/// peak pressure p₀. 2D: a² = 4P/(πE*), p₀ = 2P/(πa); 3D: a³ = 3P/(4E*), p₀ = 3P/(2πa²).
pub fn hertz(dim: usize, p: f64, e_star: f64) -> (f64, f64) {
    use std::f64::consts::PI;
    if dim == 2 {
        let a = (4.0 * p / (PI * e_star)).sqrt();
        (a, 2.0 * p / (PI * a))
    } else {
        let a = (3.0 * p / (4.0 * e_star)).cbrt();
        (a, 3.0 * p / (2.0 * PI * a * a))
    }
}

/// The gallery's 3D Hertz quarter (hertz_3d.toml: 1.5 × 1.5 × 1.5, δ = 0.01, groups Gamma3,
/// SymX, SymY, Base) as a graded structured hexahedral mesh: along each axis `fine` cells of
/// h = 0.16/fine over the contact patch (0, 0.16), then cells growing by `ratio` to 1.5. Built
/// from [`block`] by a monotone map of each axis and the rotation (x, y, z) → (x, z, −y), which
/// takes block's y = 0 face to the top z = 0 and keeps every hexahedron's orientation.
pub fn hertz_3d_hexahedra(fine: usize, ratio: f64) -> Mesh<3> {
    let (patch, side) = (0.16, 1.5);
    let mut axis = vec![0.0];
    let h = patch / fine as f64;
    let mut step = h;
    while *axis.last().unwrap() < side - 1e-12 {
        let last = *axis.last().unwrap();
        if last >= patch - 1e-12 {
            step *= ratio;
        }
        axis.push((last + step).min(side));
    }
    // the last cell is cut at the side; fold it into its neighbour if it is a sliver
    if axis.len() > 2 && axis[axis.len() - 1] - axis[axis.len() - 2] < 0.5 * step {
        let n = axis.len();
        axis.remove(n - 2);
    }
    let n = axis.len() - 1;
    let mut mesh = block([1.0; 3], [n; 3], SolidShape::Hex);
    let at = |s: f64| axis[(s * n as f64).round() as usize];
    for x in &mut mesh.points {
        *x = [at(x[0]), at(x[2]), -at(x[1])];
    }
    let points = mesh.points.clone();
    let face = |name: &str, tag: i32, on: &dyn Fn(&[f64; 3]) -> bool| PhysicalGroup {
        dim: 2,
        tag,
        name: Some(name.to_string()),
        facets: mesh
            .groups
            .iter()
            .filter(|g| g.dim == 2)
            .flat_map(|g| g.facets.iter())
            .filter(|f| f.nodes().iter().all(|&p| on(&points[p])))
            .fold(Vec::new(), |mut v, f| {
                if !v.iter().any(|g: &hvi::mesh::Facet| g.nodes() == f.nodes()) {
                    v.push(*f);
                }
                v
            }),
        cells: Vec::new(),
        nodes: Vec::new(),
    };
    let e = 1e-12;
    let groups = vec![
        face("Gamma3", 3, &|x| {
            x[2].abs() < e && x[0] <= patch + e && x[1] <= patch + e
        }),
        face("SymX", 4, &|x| x[0].abs() < e),
        face("SymY", 5, &|x| x[1].abs() < e),
        face("Base", 6, &|x| (x[2] + side).abs() < e),
    ];
    let body = mesh.groups.iter().find(|g| g.dim == 3).unwrap().clone();
    mesh.groups = groups.into_iter().chain([body]).collect();
    mesh
}
