//! The convergence-study machinery (docs/method.md §6): interpolation between meshes (exact for
//! linear fields on any meshes, exact for nested meshes), observed orders against an exact
//! solution and against a fine reference run, and a reduced version of the paper's study.

mod common;

use common::{distort_interior, manufactured_exact, manufactured_scene, rectangle_with_sides};

use hvi::fem::norms::errors;
use hvi::mesh::element::shape_at;
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::Mesh;
use hvi::scene::Scene;
use hvi::study::{
    self, interpolate_nodal, plot, report, seminorm_errors, Keep, Locator, Refinement, RunOptions, Study, StudyPlan,
    TimeLevel,
};

// ---- scenes (begin) ----
/// The embedded default scene (the paper's example) with N steps.
fn paper_scene(steps: usize) -> Scene {
    let mut scene = Scene::load(None, &[format!("time.steps={steps}")]).unwrap_or_else(|e| panic!("{e}"));
    scene.time.steps = Some(steps);
    scene
}

// ---- scenes (end) ----

fn linear(x: [f64; 2]) -> [f64; 2] {
    [0.3 + 1.7 * x[0] - 0.4 * x[1], -0.2 + 0.5 * x[0] + 2.1 * x[1]]
}

fn max_diff(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    assert_eq!(a.len(), b.len(), "fields of different lengths");
    assert!(!a.is_empty(), "empty fields: nothing compared");
    a.iter()
        .zip(b)
        .map(|(u, v)| (u[0] - v[0]).abs().max((u[1] - v[1]).abs()))
        .fold(0.0, f64::max)
}

/// A deterministic, non-polynomial nodal field.
fn rough_field(mesh: &Mesh<2>) -> Vec<[f64; 2]> {
    mesh.points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            [
                (3.0 * p[0]).sin() + 0.1 * (k as f64).cos(),
                p[0] * p[1] - 0.05 * (k as f64 * 0.7).sin(),
            ]
        })
        .collect()
}

#[test]
fn interpolation_is_exact_for_linear_fields_between_non_nested_meshes() {
    // distorted P1 (10 × 5 squares, 100 triangles) and distorted Q1 (13 × 7) on (0, 2) × (0, 1)
    let mut p1 = rectangle(2.0, 1.0, 10, 5, CellShape::Tri);
    distort_interior(&mut p1, 2.0, 1.0, 0.2, 0.5);
    let mut q1 = rectangle(2.0, 1.0, 13, 7, CellShape::Quad);
    distort_interior(&mut q1, 2.0, 1.0, 1.0 / 7.0, 0.5);
    for (from, to) in [(&p1, &q1), (&q1, &p1)] {
        let u: Vec<[f64; 2]> = from.points.iter().map(|&x| linear(x)).collect();
        let carried = interpolate_nodal(from, &u, &to.points).unwrap();
        let exact: Vec<[f64; 2]> = to.points.iter().map(|&x| linear(x)).collect();
        assert!(
            max_diff(&carried, &exact) < 1e-12,
            "nodal error {:e}",
            max_diff(&carried, &exact)
        );
        let e = seminorm_errors(to, &exact, &carried);
        assert!(e.h1_seminorm < 1e-11 && e.l2 < 1e-12, "{e:?}");
        // and at arbitrary interior points
        let pts: Vec<[f64; 2]> = (0..200)
            .map(|i| [2.0 * ((i as f64 * 0.618_034) % 1.0), (i as f64 * 0.414_214) % 1.0])
            .collect();
        let at = interpolate_nodal(from, &u, &pts).unwrap();
        let want: Vec<[f64; 2]> = pts.iter().map(|&x| linear(x)).collect();
        assert!(max_diff(&at, &want) < 1e-12);
    }
}

#[test]
fn points_outside_the_mesh_are_errors_naming_the_point_and_the_boundary_is_inside() {
    let mesh = rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
    let u = vec![[1.0, 2.0]; mesh.points.len()];
    let err = interpolate_nodal(&mesh, &u, &[[1.0, 0.5], [2.5, 0.25]]).unwrap_err();
    assert!(err.contains("2.5") && err.contains("outside"), "{err}");
    let err = interpolate_nodal(&mesh, &u, &[[1.0, -1e-6]]).unwrap_err();
    assert!(err.contains("outside"), "{err}");
    // corners, edges and points outside by less than 1e-10 × diameter are inside
    let ok = interpolate_nodal(
        &mesh,
        &u,
        &[
            [0.0, 0.0],
            [2.0, 1.0],
            [1.0, 0.0],
            [2.0 + 1e-12, 0.5],
            [0.3, 1.0 + 1e-12],
        ],
    )
    .unwrap();
    assert!(max_diff(&ok, &[[1.0, 2.0]; 5]) < 1e-14);
    let locator = Locator::new(&mesh);
    let (cell, xi) = locator.locate([0.3, 0.2]).unwrap();
    let s = shape_at(&mesh.cells[cell], &mesh.points, [xi[0], xi[1], 0.0]);
    assert!((s.x[0] - 0.3).abs() < 1e-14 && (s.x[1] - 0.2).abs() < 1e-14);
}

#[test]
fn nested_meshes_carry_exactly_both_ways() {
    for quad in [true, false] {
        let shape = || {
            if quad {
                CellShape::Quad
            } else {
                CellShape::Tri
            }
        };
        let coarse = rectangle(2.0, 1.0, 8, 4, shape());
        let fine = rectangle(2.0, 1.0, 32, 16, shape());
        let u = rough_field(&coarse);
        let carried = interpolate_nodal(&coarse, &u, &fine.points).unwrap();
        let back = interpolate_nodal(&fine, &carried, &coarse.points).unwrap();
        assert!(max_diff(&back, &u) < 1e-13, "there and back: {:e}", max_diff(&back, &u));
        // the carried field is the coarse function: its H¹ and L² distance to a direct
        // evaluation of the coarse field (value and gradient at each quadrature point) is 0
        let locator = Locator::new(&coarse);
        let direct = |x: [f64; 2]| {
            let (c, xi) = locator.locate(x).unwrap();
            let cell = &coarse.cells[c];
            let s = shape_at(cell, &coarse.points, [xi[0], xi[1], 0.0]);
            let (mut v, mut g) = ([0.0; 2], [[0.0; 2]; 2]);
            for a in 0..s.n {
                let ua = u[cell.nodes()[a]];
                for r in 0..2 {
                    v[r] += s.value[a] * ua[r];
                    g[r][0] += s.grad[a][0] * ua[r];
                    g[r][1] += s.grad[a][1] * ua[r];
                }
            }
            (v, g)
        };
        let e = errors(&fine.cells, &fine.points, &carried, direct);
        assert!(e.h1_seminorm < 1e-12 && e.l2 < 1e-13, "{e:?}");
    }
}

#[test]
fn nested_transfer_of_a_solution_is_exact() {
    // a coarse solution of the paper's problem, carried to a nested fine mesh and back
    let options = RunOptions {
        label: "coarse".into(),
        h: None,
        keep: Keep::All,
    };
    let coarse = study::run_with(rectangle(2.0, 1.0, 8, 4, CellShape::Quad), &paper_scene(4), &options).unwrap();
    let fine = rectangle(2.0, 1.0, 32, 16, CellShape::Quad);
    let carried = interpolate_nodal(&coarse.mesh, &coarse.final_displacement, &fine.points).unwrap();
    let back = interpolate_nodal(&fine, &carried, &coarse.mesh.points).unwrap();
    assert!(max_diff(&back, &coarse.final_displacement) < 1e-14);
    assert_eq!(coarse.displacement_at.len(), 5, "Keep::All keeps every step");
    assert!((coarse.displacement_at.last().unwrap().0 - 1.0).abs() < 1e-12);
    // a study of a run against itself has zero error
    let mut s = Study::against_run(
        study::run_with(rectangle(2.0, 1.0, 8, 4, CellShape::Quad), &paper_scene(4), &options).unwrap(),
    );
    let i = s.add_run(&coarse).unwrap();
    assert!(s.runs[i].errors.at_final.h1_seminorm < 1e-14 && s.runs[i].errors.h1_max_over_time < 1e-14);
    assert_eq!(s.runs[i].errors.times_compared, 5);
}

/// Against the exact solution, the study reports H¹ order 1 and L² order 2 (±0.1), per
/// neighbour at the finest pair and by least squares; against a fine reference run the
/// H¹ order is ≈ 1 too.
#[test]
fn study_reports_theoretical_orders_for_a_manufactured_solution() {
    let scene = manufactured_scene();
    let mut exact = Study::against_exact(Box::new(|_t, x| manufactured_exact(x)));
    let mut records = Vec::new();
    for n in [4, 8, 16, 32] {
        let options = RunOptions {
            label: format!("h=1/{n}"),
            h: Some(1.0 / n as f64),
            keep: Keep::All,
        };
        records.push(
            study::run_with(
                rectangle_with_sides(2.0, 1.0, 2 * n, n, CellShape::Quad),
                &scene,
                &options,
            )
            .unwrap(),
        );
    }
    let idx: Vec<usize> = records.iter().map(|r| exact.add_run(r).unwrap()).collect();
    exact.add_path("h", Refinement::H, idx).unwrap();
    let rows = exact.rows();
    eprintln!("against the exact solution:\n{}", report::markdown(&rows));
    let last = rows.last().unwrap();
    let (p1, p2) = (last.order.unwrap(), last.l2_order.unwrap());
    assert!((p1 - 1.0).abs() <= 0.1, "H¹ order {p1}");
    assert!((p2 - 2.0).abs() <= 0.1, "L² order {p2}");
    let fitted = exact.fitted_order(&exact.paths[0]).unwrap();
    assert!((fitted - 1.0).abs() <= 0.1, "fitted H¹ order {fitted}");
    // max over the two output times (t = 0, 1: the loads do not depend on t) equals the error at T
    assert!(
        (last.errors.h1_max_over_time - last.errors.at_final.h1_seminorm).abs() <= 1e-12 * last.errors.h1_max_over_time
    );

    // the same runs against a reference run at h = 1/128
    let options = RunOptions {
        label: "reference".into(),
        h: Some(1.0 / 128.0),
        keep: Keep::All,
    };
    let reference = study::run_with(
        rectangle_with_sides(2.0, 1.0, 256, 128, CellShape::Quad),
        &scene,
        &options,
    )
    .unwrap();
    let mut against_run = Study::against_run(reference);
    let idx: Vec<usize> = records[..3].iter().map(|r| against_run.add_run(r).unwrap()).collect();
    against_run.add_path("h", Refinement::H, idx).unwrap();
    let rows = against_run.rows();
    eprintln!("against a reference run at h = 1/128:\n{}", report::markdown(&rows));
    for r in &rows[1..] {
        let p = r.order.unwrap();
        assert!((p - 1.0).abs() <= 0.1, "H¹ order against the reference run {p}");
    }
    // the reported errors differ from the exact ones by about the reference's own error
    let (e_ref, e_exact) = (
        rows[2].errors.at_final.h1_seminorm,
        exact.runs[2].errors.at_final.h1_seminorm,
    );
    assert!(
        (e_ref / e_exact - 1.0).abs() < 0.1,
        "against the reference {e_ref:e}, against the exact solution {e_exact:e}"
    );
}

/// The paper's study, reduced: h = 1/8, 1/16, 1/32 at k = 1/16; k = 1/4, 1/8, 1/16 at
/// h = 1/64; reference h = k = 1/64. Orders ≥ 0.8 in h and ≥ 1.7 in k; reports and plots.
///
/// As in the paper's Table 2, the k-path runs on the reference mesh: at h = 1/32 the spatial
/// error against the h = 1/64 reference (3.3e-3 in H¹) exceeds the time error from k = 1/8 on,
/// and the observed order in k collapses (0.75, then 0.08).
#[test]
fn reduced_paper_study_shows_first_order_in_h_and_second_order_in_k() {
    let plan = StudyPlan {
        reference: (64, TimeLevel::Steps(64)),
        h_paths: vec![(16, vec![8, 16, 32])],
        k_paths: vec![(64, [4, 8, 16].map(TimeLevel::Steps).to_vec())],
        keep: Keep::MultiplesOf(1.0 / 16.0),
    };
    let mut seen = 0;
    let s = study::run_plan(
        &plan,
        &|n| rectangle(2.0, 1.0, 2 * n, n, CellShape::Quad),
        &|level| paper_scene(level.steps().expect("uniform steps")),
        &mut |_, _| seen += 1,
    )
    .unwrap();
    assert_eq!(seen, 7, "the reference and six runs");
    assert_eq!(s.runs.len(), 6);
    let rows = s.rows();
    eprintln!("{}", report::markdown(&rows));
    assert_eq!(rows.len(), 6);
    for r in &rows {
        if let Some(p) = r.order {
            match r.refine {
                Refinement::H => assert!(
                    p >= 0.8,
                    "order in h {p} at h = {}\n{}",
                    r.summary.h,
                    report::markdown(&rows)
                ),
                Refinement::K => assert!(
                    p >= 1.7,
                    "order in k {p} at k = {}\n{}",
                    r.summary.k,
                    report::markdown(&rows)
                ),
            }
        }
        assert!(r.errors.h1_max_over_time >= r.errors.at_final.h1_seminorm);
        assert!(r.errors.times_compared >= 5, "t = 0, 1/4, 1/2, 3/4, 1 at least");
    }
    // the reference kept t = j/16
    assert_eq!(s.reference_run().unwrap().displacement_at.len(), 17);

    let csv = report::csv(&rows);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 7);
    assert_eq!(lines[0], report::CSV_COLUMNS.join(","));
    assert!(lines.iter().all(|l| l.split(',').count() == 18), "{csv}");
    let md = report::markdown(&rows);
    assert!(
        md.contains("| h (k=1/16) | 1/8 | 1/16 |") && md.contains("k (h=1/64)"),
        "{md}"
    );

    let dir = tempfile::tempdir().unwrap();
    plot::plot_error_vs_h(&dir.path().join("h.svg"), &rows).unwrap();
    plot::plot_error_vs_k(&dir.path().join("k.svg"), &rows).unwrap();
    plot::plot_work_precision(&dir.path().join("w.svg"), &rows).unwrap();
    let reference = s.reference_run().unwrap();
    let series: Vec<(f64, Vec<(f64, f64)>)> = reference
        .displacement_at
        .iter()
        .step_by(4)
        .map(|(t, u)| {
            (
                *t,
                reference
                    .mesh
                    .points
                    .iter()
                    .zip(u)
                    .filter(|(p, _)| p[1] == 0.0)
                    .map(|(p, u)| (p[0], -u[1]))
                    .collect(),
            )
        })
        .collect();
    plot::plot_gamma3(&dir.path().join("g.svg"), "u_ν along the bottom", &series).unwrap();
    let values: Vec<f64> = (0..reference.mesh.cells.len()).map(|c| c as f64).collect();
    hvi::plot::render_deformed(
        &dir.path().join("d.png"),
        None,
        &hvi::plot::DeformedPicture {
            title: "reference".into(),
            field: "cell index".into(),
            mesh: &reference.mesh,
            displacement: &reference.final_displacement,
            cell_values: &values,
            scale: 1.0,
            scale_text: "true scale".into(),
            foundation: None,
            obstacles: vec![],
        },
    )
    .unwrap();
    for f in ["h.svg", "k.svg", "w.svg", "g.svg"] {
        let text = std::fs::read_to_string(dir.path().join(f)).unwrap();
        assert!(text.starts_with("<svg") && text.contains("<polyline"), "{f}");
    }
    let png = std::fs::read(dir.path().join("d.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

/// Runs a study file written from `text` (the scene: examples/paper.toml) into a tempdir;
/// returns the output and the directory.
fn study_from_text(text: &str) -> (study::execute::StudyOutput, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "scene = \"{}\"\n{text}",
        concat!(env!("CARGO_MANIFEST_DIR"), "/examples/paper.toml")
    );
    let spec: study::spec::StudySpec = toml::from_str(&text).unwrap();
    let written = study::execute::run_spec(&spec, dir.path(), &dir.path().join("out"), &[], "test").unwrap();
    (written, dir)
}

/// The CSV rows (after the header) of a study, as (path, h, k, h1_error, order).
fn csv_rows(dir: &std::path::Path) -> Vec<(String, f64, f64, f64, Option<f64>)> {
    let csv = std::fs::read_to_string(dir.join("study.csv")).unwrap();
    csv.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let num = |i: usize| c[i].parse::<f64>().unwrap();
            (c[0].to_string(), num(1), num(2), num(6), c[9].parse().ok())
        })
        .collect()
}

/// A study with only an h path writes its tables and the plots it can draw (error against h,
/// work–precision, Γ₃), and no error-against-k plot (there is no k line to draw); its rows
/// are the h path's, with first-order convergence (the reduced study above shows ≥ 0.8 at
/// these sizes).
#[test]
fn an_h_only_study_writes_its_tables() {
    let (written, dir) =
        study_from_text("reference = { n = 32, steps = 16 }\n[[h_paths]]\nsteps = 16\nn = [4, 8, 16]\n");
    let out = dir.path().join("out");
    assert_eq!(
        written.files,
        [
            "study.md",
            "study.csv",
            "gamma3.svg",
            "error_vs_h.svg",
            "work_precision.svg"
        ]
    );
    for f in &written.files {
        assert!(out.join(f).metadata().unwrap().len() > 0, "{f}");
    }
    assert!(!out.join("error_vs_k.svg").exists());
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 3);
    for (i, (path, h, k, e, order)) in rows.iter().enumerate() {
        assert!(path.starts_with("h (k=1/16)"), "{path}");
        assert!((h - 1.0 / [4.0, 8.0, 16.0][i]).abs() < 1e-12 && (k - 1.0 / 16.0).abs() < 1e-12);
        assert!(*e > 0.0);
        if i > 0 {
            assert!(order.unwrap() >= 0.8, "order in h {order:?}");
        }
    }
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert!(
        md.contains("## h refined at k = T/16") && !md.contains("## k refined"),
        "{md}"
    );
}

/// A study with only a k path writes its tables, error against k and work–precision, no
/// error-against-h plot; second order in k (≥ 1.7 as in the reduced study).
#[test]
fn a_k_only_study_writes_its_tables() {
    let (written, dir) = study_from_text("reference = { n = 16, steps = 32 }\n[[k_paths]]\nn = 16\nsteps = [4, 8]\n");
    let out = dir.path().join("out");
    assert_eq!(
        written.files,
        [
            "study.md",
            "study.csv",
            "gamma3.svg",
            "error_vs_k.svg",
            "work_precision.svg"
        ]
    );
    assert!(!out.join("error_vs_h.svg").exists());
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 2);
    assert!(rows
        .iter()
        .all(|r| r.0 == "k (h=1/16)" && (r.1 - 1.0 / 16.0).abs() < 1e-12));
    assert!(rows[1].4.unwrap() >= 1.7, "order in k {:?}", rows[1].4);
}

// ---- steps that grow with time (docs/studies.md, "Refining steps that grow with time") ----

/// The creeping block of examples/creep_study_scene.toml: Young's relaxation modulus
/// E(t) = 1 + 2 e^{−t/0.01} + e^{−t} with ν = 0.3 (one channel, one factorisation), clamped on the
/// left, a constant downward traction on the top from t = 0, T = 10: its creep's retardation
/// times are 0.02 and 2, so a run from a first step of 1e-4 spans five decades.
const CREEP_SCENE: &str = include_str!("../examples/creep_study_scene.toml");

/// Runs the study `text` on [`CREEP_SCENE`] with the fast term's modulus `fast` instead of 2
/// (written beside it as creep_study_scene.toml, which `text` names or is given): the output, or
/// the study's error.
fn creep_study(
    fast: f64,
    text: &str,
    targets: &study::Targets,
) -> Result<(study::execute::StudyOutput, tempfile::TempDir), String> {
    let dir = tempfile::tempdir().unwrap();
    let scene = CREEP_SCENE.replace("modulus = 2.0,", &format!("modulus = {fast:?},"));
    assert!(scene.contains(&format!("modulus = {fast:?}, relaxation_time = 0.01")));
    std::fs::write(dir.path().join("creep_study_scene.toml"), scene).unwrap();
    let text = if text.contains("scene = ") {
        text.to_string()
    } else {
        format!("scene = \"creep_study_scene.toml\"\n{text}")
    };
    let spec: study::spec::StudySpec = toml::from_str(&text).map_err(|e| e.to_string())?;
    let out = dir.path().join("out");
    let written = study::execute::run_spec_with(&spec, dir.path(), &out, &[], "creep_study.toml", targets)?;
    Ok((written, dir))
}

/// The least-squares order of the H¹ errors at T against the parameters.
fn fitted(rows: &[(String, f64, f64, f64, Option<f64>)]) -> f64 {
    let (k, e): (Vec<f64>, Vec<f64>) = rows.iter().map(|r| (r.2, r.3)).unzip();
    hvi::fem::norms::fitted_order(&k, &e)
}

/// examples/creep_study.toml: steps growing 10, 20 and 40 a decade from 1e-4 against 160 a
/// decade; the order in the relative step r = 10^{1/s} − 1 is close to 2, the rule's order
/// (docs/method.md §6, §20). Its tolerance path's errors fall too.
///
/// Measured (n = 8, T = 10): H¹ errors at T 1.61e-3, 4.19e-4, 1.17e-4, orders 1.79 and 1.77,
/// fitted 1.78. Two things keep it below 2: the fast term (τ = 0.01, 60 to 260 times shorter than
/// the steps near T) sees the displacement's linear interpolant only by its last increment, a
/// backward difference of error O(τ k) — with its modulus 0.2 instead of 2 the fitted order is
/// 1.84 (checked here), with 20 it is 1.45 —, and each level's steps are cut differently to land
/// on the decades and on T (neighbouring s differ by up to ±0.2 in the observed order). Hence the
/// band 1.6 … 2.2 on the fitted order, and the weak-fast-term variant at least as close to 2.
#[test]
fn steps_per_decade_on_prony_memory_show_second_order_in_the_relative_step() {
    let text = include_str!("../examples/creep_study.toml");
    let mut orders = Vec::new();
    for fast in [2.0, 0.2] {
        let (written, dir) = creep_study(fast, text, &study::Targets::default()).unwrap();
        let out = dir.path().join("out");
        let md = std::fs::read_to_string(out.join("study.md")).unwrap();
        eprintln!("fast term's modulus {fast}:\n{}", written.report);
        assert_eq!(
            written.files,
            [
                "study.md",
                "study.csv",
                "gamma3.svg",
                "error_vs_k.svg",
                "work_precision.svg"
            ]
        );
        let all = csv_rows(&out);
        assert_eq!(all.len(), 6);
        let (rows, tolerances) = all.split_at(3);
        assert!(
            tolerances.iter().all(|r| r.0 == "k by tolerance (h=1/8)")
                && tolerances.windows(2).all(|w| w[1].3 < w[0].3),
            "{tolerances:?}"
        );
        for (r, s) in rows.iter().zip([10.0f64, 20.0, 40.0]) {
            assert_eq!(r.0, "k per decade (h=1/8)");
            // the parameter is the relative step, not a step size
            assert!((r.2 - (10f64.powf(1.0 / s) - 1.0)).abs() < 1e-12, "{r:?}");
            assert!(md.contains(&format!("| 1/8 | {s}/decade |")), "{md}");
        }
        assert!(rows.windows(2).all(|w| w[1].3 < w[0].3), "{rows:?}");
        let order = fitted(rows);
        // the report's sentence names the parameter and gives the same fitted order
        assert!(
            md.contains("The parameter is r = 10^(1/s) − 1") && md.contains(&format!("has order {order:.3}")),
            "{md}"
        );
        // the compared times are levels of every run: one a decade after the first step, and T
        assert!(md.contains("compares t = 0.001, 0.01, 0.1, 1, 10 "), "{md}");
        eprintln!(
            "fast modulus {fast}: errors {:?}, observed orders {:?}, fitted {order:.3}",
            rows.iter().map(|r| r.3).collect::<Vec<_>>(),
            rows.iter().map(|r| r.4).collect::<Vec<_>>()
        );
        assert!(
            (1.6..=2.2).contains(&order),
            "fitted order {order} in the relative step\n{md}"
        );
        for o in rows.iter().filter_map(|r| r.4) {
            assert!(o >= 1.5, "observed order {o}\n{md}");
        }
        orders.push(order);
    }
    assert!(
        orders[1] >= orders[0] - 0.02,
        "{orders:?}: a weaker fast term is no closer to 2"
    );
}

/// Automatic steps to tolerances 1e-2, 1e-3, 1e-4 (no first_step: the automatic steps' own,
/// a tenth of the shortest relaxation time) against tolerance 1e-6: the error falls with the
/// tolerance and the steps grow. Measured: H¹ errors at T 3.76e-3, 1.13e-3, 2.61e-4 in 20, 31,
/// 65 steps, fitted order 0.58 in the tolerance (a local error O(k³) per step held at tol gives
/// about tol^{2/3} at T).
#[test]
fn a_tolerance_path_s_errors_fall_with_the_tolerance() {
    let text = "reference = { n = 8, tolerance = 1e-6 }\n[[k_paths]]\nn = 8\ntolerance = [1e-2, 1e-3, 1e-4]\n";
    let (written, dir) = creep_study(2.0, text, &study::Targets::default()).unwrap();
    let out = dir.path().join("out");
    eprintln!("{}", written.report);
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    let rows = csv_rows(&out);
    assert_eq!(rows.len(), 3);
    assert!(rows.iter().all(|r| r.0 == "k by tolerance (h=1/8)"), "{rows:?}");
    assert_eq!(rows.iter().map(|r| r.2).collect::<Vec<_>>(), [1e-2, 1e-3, 1e-4]);
    assert!(
        rows.windows(2).all(|w| w[1].3 < 0.6 * w[0].3),
        "the error does not fall with the tolerance: {rows:?}"
    );
    let steps: Vec<usize> = std::fs::read_to_string(out.join("study.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(5).unwrap().parse().unwrap())
        .collect();
    assert!(steps.windows(2).all(|w| w[1] > w[0]), "steps {steps:?}");
    let order = fitted(&rows);
    eprintln!(
        "errors {:?} in {steps:?} steps, fitted order {order:.3} in the tolerance",
        rows.iter().map(|r| r.3).collect::<Vec<_>>()
    );
    assert!(
        (0.4..=1.0).contains(&order),
        "fitted order {order} in the tolerance\n{md}"
    );
    assert!(
        md.contains("| 1/8 | tol 1e-3 |") && md.contains("The parameter is tol,") && md.contains("log(tol₁/tol₂)"),
        "{md}"
    );
    // no first_step: the decades start after the automatic first step, 0.1 × 0.01
    assert!(md.contains("compares t = 0.01, 0.1, 1, 10 "), "{md}");
}

/// Bad time levels in a study file are refused before any run, naming the file, the key, the
/// value and the fix.
#[test]
fn bad_time_levels_are_refused_with_the_key_the_value_and_the_fix() {
    let none = study::Targets::default();
    let k = "reference = { n = 8, steps = 64 }\n[[k_paths]]\nn = 8\nsteps = [4]\n[[k_paths]]\nn = 8\n";
    let cases: [(String, &[&str]); 11] = [
        (
            format!("{k}steps = [4, 8]\ntolerance = [1e-3]\n"),
            &[
                "`k_paths[1].tolerance`",
                "(with k_paths[1].steps)",
                "one way of stepping",
            ],
        ),
        (
            k.to_string(),
            &[
                "`k_paths[1]`",
                "(no steps, steps_per_decade or tolerance)",
                "exactly one",
            ],
        ),
        (
            format!("{k}steps_per_decade = [5, 10]\n"),
            &["`k_paths[1].steps_per_decade` = [5, 10]", "add `first_step = …`"],
        ),
        (
            "reference = { n = 8, steps_per_decade = 40 }\n".into(),
            &["`reference.steps_per_decade` = 40", "first_step"],
        ),
        (
            format!("first_step = 1e-4\n{k}steps_per_decade = [5, -10]\n"),
            &[
                "`k_paths[1].steps_per_decade[1]` = -10",
                "positive, finite number of steps per decade",
            ],
        ),
        (
            format!("first_step = 1e-4\n{k}steps_per_decade = [5, inf]\n"),
            &["`k_paths[1].steps_per_decade[1]` = inf", "positive, finite"],
        ),
        (
            format!("{k}tolerance = [1e-3, 0.0]\n"),
            &["`k_paths[1].tolerance[1]` = 0", "a number in (0, 1)"],
        ),
        (
            format!("{k}tolerance = [nan]\n"),
            &["`k_paths[1].tolerance[0]` = NaN", "a number in (0, 1)"],
        ),
        (
            format!("{k}steps = [0, 4]\n").replace("[[k_paths]]\nn = 8\nsteps = [4]\n", ""),
            &["`k_paths[0].steps[0]` = 0", "at least one step"],
        ),
        (
            format!("first_step = 10.0\n{k}steps_per_decade = [5]\n"),
            &["`first_step` = 10", "shorter than the scene's time.final_time = 10"],
        ),
        (
            format!("first_step = -1e-3\n{k}tolerance = [1e-3]\n"),
            &["`first_step` = -0.001", "positive, finite"],
        ),
    ];
    for (text, wanted) in cases {
        let err = creep_study(2.0, &text, &none).map(|_| ()).unwrap_err();
        assert!(err.starts_with("creep_study.toml: "), "{err}");
        for w in wanted {
            assert!(err.contains(w), "{text}\nwanted `{w}` in: {err}");
        }
    }
    // --target plans uniform steps only: a non-uniform k path is refused by name
    let targets = study::Targets {
        errors: vec![1e-3],
        verify: false,
    };
    let err = creep_study(
        2.0,
        &format!("first_step = 1e-4\n{k}steps_per_decade = [5, 10]\n[[h_paths]]\nsteps = 64\nn = [2, 4]\n"),
        &targets,
    )
    .map(|_| ())
    .unwrap_err();
    assert!(
        err.contains("--target: k_paths[1] steps by steps_per_decade (5/decade)") && err.contains("uniform steps only"),
        "{err}"
    );
}

// ---- the target planner (docs/method.md, "Planning a run for a target error") ----

use hvi::study::target::{self, Candidate, CostModel, CostSample, ErrorModel, ErrorSample};

/// A manufactured study: the runs of an h path at k = k_r and a k path at h = h_r (the paper's
/// design) plus one run off both paths, with errors from the model with known constants.
fn synthetic_samples(truth: &ErrorModel) -> Vec<ErrorSample> {
    let mut hk: Vec<(f64, f64)> = [8.0, 16.0, 32.0, 64.0].iter().map(|n| (1.0 / n, 1.0 / 256.0)).collect();
    hk.extend([4.0, 8.0, 12.0, 16.0].iter().map(|s| (1.0 / 256.0, 1.0 / s)));
    hk.push((1.0 / 16.0, 1.0 / 8.0));
    hk.iter()
        .map(|&(h, k)| ErrorSample {
            h,
            k,
            error: truth.predict(h, k),
        })
        .collect()
}

/// The paper's rectangle with square Q1 cells: 2(2n + 1)(n + 1) nodal unknowns less the
/// clamped side's 2(n + 1).
fn unknowns(n: usize) -> f64 {
    (4 * n * (n + 1)) as f64
}

/// The planner recovers the constants and orders of a manufactured error model, against an
/// exact solution (h_r = k_r = 0: e = C_h h^p + C_k k^q) and against a reference run, and
/// the cost model's; its recommendation meets the target and is the cheapest candidate that
/// does under the true models.
#[test]
fn the_target_planner_recovers_a_manufactured_model_and_meets_the_target() {
    for (h_ref, k_ref) in [(0.0, 0.0), (1.0 / 256.0, 1.0 / 256.0)] {
        // orders off the search grids (steps 0.01 and 0.0005), so that recovery is not luck
        let truth = ErrorModel {
            c_h: 0.1234,
            p: 1.1234,
            c_k: 0.0876,
            q: 1.9567,
            h_ref,
            k_ref,
            rms_relative_residual: 0.0,
            samples: 0,
        };
        let fitted = ErrorModel::fit(&synthetic_samples(&truth), h_ref, k_ref).unwrap();
        // the fine grid's half step is 2.5e-4; over h in [1/64, 1/8] a change δ of p moves h^p by
        // a factor within e^{±δ ln 64} ≈ 1 ± 1e-3, which C_h absorbs: 1 % on the constants is safe
        assert!(
            (fitted.p - truth.p).abs() <= 5e-4,
            "p = {} (true {})",
            fitted.p,
            truth.p
        );
        assert!(
            (fitted.q - truth.q).abs() <= 5e-4,
            "q = {} (true {})",
            fitted.q,
            truth.q
        );
        assert!((fitted.c_h / truth.c_h - 1.0).abs() <= 0.01, "C_h = {}", fitted.c_h);
        assert!((fitted.c_k / truth.c_k - 1.0).abs() <= 0.01, "C_k = {}", fitted.c_k);
        assert!(fitted.rms_relative_residual <= 2e-3, "{}", fitted.rms_relative_residual);

        // cost: setup 2e-6·N^1.2 s, steps 3e-8·N^1.25 s each, at the runs' sizes
        let true_cost = CostModel {
            c_setup: 2e-6,
            b: 1.2,
            c_step: 3e-8,
            a: 1.25,
        };
        let cost_samples: Vec<CostSample> = [(8, 256), (16, 256), (32, 256), (64, 256), (256, 4), (256, 16)]
            .iter()
            .map(|&(n, steps)| {
                let (nu, s) = (unknowns(n), steps as f64);
                CostSample {
                    unknowns: nu,
                    steps: s,
                    setup_seconds: true_cost.c_setup * nu.powf(true_cost.b),
                    steps_seconds: true_cost.c_step * nu.powf(true_cost.a) * s,
                }
            })
            .collect();
        let cost = CostModel::fit(&cost_samples).unwrap();
        // noise-free power laws: recovered to round-off
        assert!((cost.b - 1.2).abs() < 1e-9 && (cost.a - 1.25).abs() < 1e-9, "{cost:?}");
        assert!((cost.c_setup / 2e-6 - 1.0).abs() < 1e-7 && (cost.c_step / 3e-8 - 1.0).abs() < 1e-7);

        let candidates: Vec<Candidate> = (8..=256)
            .flat_map(|n| {
                (4..=256).map(move |steps| Candidate {
                    n,
                    steps,
                    h: 1.0 / n as f64,
                    k: 1.0 / steps as f64,
                    unknowns: unknowns(n),
                })
            })
            .collect();
        for target_error in [3e-3, 1e-3, 3e-4] {
            let plan = target::plan(&fitted, &cost, candidates.iter().copied(), target_error).unwrap();
            let true_error = truth.predict(plan.run.h, plan.run.k);
            // the fitted model is within 1 % of the truth, so the truth at the plan is ≤ 1.01 E
            assert!(
                true_error <= 1.01 * target_error,
                "E = {target_error:e}: {plan:?} has true error {true_error:e}"
            );
            // the cheapest candidate meeting E under the true models costs at most 1 % less
            let best = target::plan(&truth, &true_cost, candidates.iter().copied(), target_error).unwrap();
            assert!(
                true_cost.predict(plan.run.unknowns, plan.run.steps as f64) <= 1.01 * best.wall,
                "E = {target_error:e}: planned {plan:?}, best {best:?}"
            );
            // and every candidate strictly cheaper than the plan misses E under the fitted model
            assert!(candidates
                .iter()
                .filter(|c| cost.predict(c.unknowns, c.steps as f64) < plan.wall)
                .all(|c| fitted.predict(c.h, c.k) > target_error));
        }
    }
}
