//! `hvi plot` on 2D runs (docs of src/plot/mod.rs): PNG and SVG of the deformed mesh and of Γ₃, the
//! text drawn on them (colour bar, field, time, magnification), the default magnification, the
//! foundation, the Γ₃ plot against arc length (a vertical Γ₃ too) at chosen times.

mod common;

use hvi::mesh::structured::{rectangle, CellShape};
use hvi::output::{CsvTable, Field, Frame, SeriesWriter};
use hvi::plot::{arc_length, default_scale, plot_run, PlotOptions};
use std::process::{Command, Output};

fn hvi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hvi")).args(args).output().unwrap()
}

use common::hvi_ok as ok;

/// The paper's scene on rect:16x8 with 8 steps (t = j/8: the Fig. 2 times are output times);
/// Γ₃ starts at the first node off the clamped corner, x = h = 1/8.
#[test]
fn a_paper_run_gives_png_and_svg_with_colour_bar_time_scale_and_foundation() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("paper16");
    let o = out.to_str().unwrap();
    ok(&["solve", "rect:16x8", "--set", "time.steps=8", "--out", o, "--quiet"]);
    let plot = ok(&["plot", o]);
    let stdout = String::from_utf8_lossy(&plot.stdout);
    for f in ["deformed.png", "deformed.svg", "gamma3.png", "gamma3.svg"] {
        assert!(stdout.contains(&format!("wrote {}", out.join(f).display())), "{stdout}");
        assert!(out.join(f).metadata().unwrap().len() > 1000, "{f}");
    }
    for f in ["deformed.png", "gamma3.png"] {
        assert_eq!(&std::fs::read(out.join(f)).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
    }
    let deformed = std::fs::read_to_string(out.join("deformed.svg")).unwrap();
    // the paper's largest displacement (≈ 0.3) is more than 5 % of the diagonal √5: true scale
    for text in [
        "run paper16 (mesh rect:16x8): von Mises stress at t = 1",
        "von Mises stress (colours span",
        "displacement at true scale (largest |u| = 0.3",
        "red: the foundation u_ν = g",
    ] {
        assert!(deformed.contains(text), "no {text:?} in deformed.svg");
    }
    // the foundation: a polyline of the Γ₃ nodes moved by g = 0.2 along −y (the outward normal)
    assert!(deformed.contains("stroke=\"#962828\""), "no foundation line");
    let gamma3 = std::fs::read_to_string(out.join("gamma3.svg")).unwrap();
    for text in [
        "u_ν and pressure on Γ₃ (the paper&apos;s Fig. 2 times)",
        "normal displacement u_ν",
        "contact pressure",
        "arc length s along Γ₃ from (0.125, 0)",
        "bound g",
        "t = 0.125",
        "t = 0.875",
        "t = 1",
    ] {
        assert!(gamma3.contains(text), "no {text:?} in gamma3.svg");
    }
    // chosen times: only those are drawn
    ok(&["plot", o, "--times", "0.5,1"]);
    let gamma3 = std::fs::read_to_string(out.join("gamma3.svg")).unwrap();
    assert!(gamma3.contains("t = 0.5") && gamma3.contains("(chosen times)") && !gamma3.contains("t = 0.125"));
    // a magnification the user gives is said
    ok(&["plot", o, "--scale", "3"]);
    let deformed = std::fs::read_to_string(out.join("deformed.svg")).unwrap();
    assert!(
        deformed.contains("displacement magnified ×3 (largest |u| = 0.3"),
        "{deformed}"
    );
    let bad = hvi(&["plot", o, "--scale", "0"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--scale 0: the magnification must be a positive number"));
}

/// The default magnification draws the largest displacement as 2–5 % of the diagonal (a round
/// factor 1, 2 or 5 × 10^j), and is 1 when it is already visible.
#[test]
fn the_default_scale_makes_small_displacements_visible() {
    let diagonal = 5f64.sqrt();
    for max_u in [3e-7, 1e-6, 4.4e-5, 1e-4, 2.5e-3, 0.01, 0.1] {
        let s = default_scale(max_u, diagonal);
        let drawn = s * max_u / diagonal;
        if max_u >= 0.05 * diagonal {
            assert_eq!(s, 1.0);
        } else {
            assert!((0.02..=0.05 + 1e-12).contains(&drawn), "{max_u:e}: ×{s} draws {drawn}");
            let mantissa = s / 10f64.powf(s.log10().floor());
            assert!([1.0, 2.0, 5.0].iter().any(|m| (mantissa - m).abs() < 1e-9), "×{s}");
        }
    }
    assert_eq!(default_scale(0.3, diagonal), 1.0);
    assert_eq!(default_scale(0.0, diagonal), 1.0);
}

/// A vertical Γ₃ (the side x = 1 of a 1 × 4 strip): arc length runs from 0 to the side's
/// length 4 in y order, the normals are outward (+x); `hvi plot`'s Γ₃ figure of a run written
/// by hand with that Γ₃ spans it.
#[test]
fn a_vertical_gamma3_is_plotted_against_its_arc_length() {
    let mesh = rectangle(1.0, 4.0, 2, 8, CellShape::Quad);
    let side: Vec<usize> = (0..mesh.points.len()).filter(|&i| mesh.points[i][0] == 1.0).collect();
    assert_eq!(side.len(), 9);
    let (arc, order, normals) = arc_length(&mesh, &side);
    let max = arc.iter().copied().fold(0.0, f64::max);
    assert!((max - 4.0).abs() < 1e-12, "arc length spans {max}");
    for (k, &p) in side.iter().enumerate() {
        // arc length from the lowest end is y; the normal is +x
        assert!((arc[k] - mesh.points[p][1]).abs() < 1e-12);
        assert!(
            (normals[k][0] - 1.0).abs() < 1e-12 && normals[k][1].abs() < 1e-12,
            "{:?}",
            normals[k]
        );
    }
    assert!(order.windows(2).all(|w| arc[w[0]] < arc[w[1]]));

    // a run directory with that Γ₃: u = (0.01 y, 0), u_ν = 0.01 y, pressure y/4 at t = 0.5, 1
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("strip");
    let mut series = SeriesWriter::create(&run, "solution").unwrap();
    let mut csv = CsvTable::create(
        &run.join("gamma3.csv"),
        &["time", "x", "y", "u_nu", "force", "pressure", "status"],
    )
    .unwrap();
    for (step, t) in [(1usize, 0.5f64), (2, 1.0)] {
        let u: Vec<f64> = mesh.points.iter().flat_map(|p| [0.01 * t * p[1], 0.0, 0.0]).collect();
        series
            .write_frame(&Frame {
                step,
                time: t,
                points: &mesh.points,
                cells: &mesh.cells,
                point_fields: vec![Field::f64("displacement", 3, &u)],
                cell_fields: vec![],
            })
            .unwrap();
        let rows: Vec<Vec<f64>> = side
            .iter()
            .map(|&p| {
                let y = mesh.points[p][1];
                vec![t, 1.0, y, 0.01 * t * y, 0.0, t * y / 4.0, 0.0]
            })
            .collect();
        csv.append(&rows).unwrap();
    }
    drop(csv);
    let written = plot_run(&run, &PlotOptions::default()).unwrap();
    assert_eq!(written.len(), 4, "{written:?}");
    let svg = std::fs::read_to_string(run.join("gamma3.svg")).unwrap();
    // the axis starts at the lowest node and its ticks reach the length 4; both times drawn
    for text in [
        "arc length s along Γ₃ from (1, 0)",
        ">\n4\n<",
        "t = 0.5",
        "t = 1",
        "(evenly spaced output times)",
    ] {
        assert!(svg.contains(text), "no {text:?} in gamma3.svg");
    }
    // the strip moves by at most 0.04, 1 % of its diagonal √17: magnified ×5 (4.9 %), and said so
    let deformed = std::fs::read_to_string(run.join("deformed.svg")).unwrap();
    assert!(
        deformed.contains("displacement magnified ×5 (largest |u| = 0.04"),
        "{deformed}"
    );
    assert!(deformed.contains("|u| (no von_mises in the run)"));
}

/// The pictures of `hvi plot` are recorded in the run's manifest (docs/method.md §12.2): a rerun
/// with --overwrite removes them with the run's frames (no stale picture of the earlier run), a
/// file of the user's stays, and plotting twice lists each picture once.
#[test]
fn plot_pictures_are_in_the_manifest_and_a_rerun_removes_them() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = out.to_str().unwrap();
    ok(&["solve", "rect:8x4", "--set", "time.steps=4", "--out", o, "--quiet"]);
    ok(&["plot", o]);
    ok(&["plot", o]);
    let pictures = ["deformed.png", "deformed.svg", "gamma3.png", "gamma3.svg"];
    let listed = hvi::output::read_manifest(&out.join(hvi::output::MANIFEST_NAME)).unwrap();
    for p in pictures {
        assert_eq!(listed.iter().filter(|l| *l == p).count(), 1, "{p} in {listed:?}");
        assert!(out.join(p).is_file());
    }
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    ok(&[
        "solve",
        "rect:8x4",
        "--set",
        "time.steps=2",
        "--out",
        o,
        "--quiet",
        "--overwrite",
    ]);
    for p in pictures {
        assert!(!out.join(p).exists(), "{p} survived the rerun");
    }
    assert!(out.join("notes.txt").is_file());
    // the new run's manifest lists its own files and no picture until it is plotted again
    let listed = hvi::output::read_manifest(&out.join(hvi::output::MANIFEST_NAME)).unwrap();
    assert!(listed.iter().all(|l| !pictures.contains(&l.as_str())), "{listed:?}");
    ok(&["plot", o]);
    let listed = hvi::output::read_manifest(&out.join(hvi::output::MANIFEST_NAME)).unwrap();
    assert!(pictures.iter().all(|p| listed.iter().any(|l| l == p)), "{listed:?}");
    let mut on_disk: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != hvi::output::MANIFEST_NAME && n != "notes.txt")
        .collect();
    on_disk.sort();
    let mut expected = listed.clone();
    expected.sort();
    expected.dedup();
    assert_eq!(on_disk, expected, "the directory holds exactly the listed files");
}

/// `hvi plot` colours the body by the run's active scalar (`output.active_scalar`,
/// docs/method.md §12.3), as ParaView does.
#[test]
fn plot_colours_by_the_active_scalar() {
    let dir = tempfile::tempdir().unwrap();
    for (value, bar) in [
        ("displacement", "|u| (colours span"),
        ("stress", "|σ| (Frobenius norm of the stress) (colours span"),
        ("von_mises", "von Mises stress (colours span"),
    ] {
        let out = dir.path().join(value);
        let o = out.to_str().unwrap();
        let set = format!("output.active_scalar=\"{value}\"");
        ok(&[
            "solve",
            "rect:8x4",
            "--set",
            "time.steps=2",
            "--set",
            &set,
            "--out",
            o,
            "--quiet",
        ]);
        ok(&["plot", o]);
        let svg = std::fs::read_to_string(out.join("deformed.svg")).unwrap();
        assert!(svg.contains(bar), "{value}: no {bar:?} in deformed.svg");
    }
}

/// The obstacle outline (docs/method.md §12.4): marching squares put a circle's vertices within
/// h²/R of it (linear interpolation of φ = |x − c| − R along a grid edge of length h errs by at
/// most h²/(8R)) with the inward direction towards the centre, and its length within 1 % of 2πR
/// (a polygon inscribed to within h²/R in a circle of R = 1 with h = 0.02 is 0.02 % short).
#[test]
fn the_obstacle_outline_follows_a_circle_and_points_into_it() {
    use hvi::plot::level_set_segments;
    let (c, r) = ([0.3, -0.2], 1.0);
    let phi = |x: [f64; 2]| ((x[0] - c[0]).powi(2) + (x[1] - c[1]).powi(2)).sqrt() - r;
    let (n, lo, hi) = (150, [-1.2, -1.7], [1.8, 1.3]);
    let h = (hi[0] - lo[0]) / n as f64;
    let edges = level_set_segments(&phi, lo, hi, n, n);
    let mut length = 0.0;
    for e in &edges {
        for p in [e.a, e.b] {
            assert!(phi(p).abs() <= h * h / r, "{p:?} is {} off the circle", phi(p));
        }
        length += ((e.b[0] - e.a[0]).powi(2) + (e.b[1] - e.a[1]).powi(2)).sqrt();
        let m = [(e.a[0] + e.b[0]) / 2.0, (e.a[1] + e.b[1]) / 2.0];
        let to_centre = [c[0] - m[0], c[1] - m[1]];
        let d = (to_centre[0].powi(2) + to_centre[1].powi(2)).sqrt();
        assert!(
            (e.inward[0] * to_centre[0] + e.inward[1] * to_centre[1]) / d > 0.999,
            "{e:?}"
        );
    }
    let circumference = 2.0 * std::f64::consts::PI * r;
    assert!((length / circumference - 1.0).abs() < 0.01, "length {length}");
    // one closed curve, in order: each edge starts where the previous one ended (the grid has
    // vertices exactly on the circle, e.g. (0.02, −1.16) = c + (−0.28, −0.96): no edge of no length)
    let gap = |p: [f64; 2], q: [f64; 2]| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
    let breaks = edges.windows(2).filter(|w| gap(w[0].b, w[1].a) > 1e-9).count();
    assert_eq!(breaks, 0);
    assert!(gap(edges[edges.len() - 1].b, edges[0].a) <= 1e-9);
}

/// Magnified like the displacement: a plane 0.05 below a flat Γ₃ is drawn 10 × 0.05 below it
/// at scale 10 — exactly, since marching squares are exact for a plane and the closest point of
/// Γ₃ is straight above — so a node resting on the plane (u_y = −0.05, drawn at −0.5) is drawn on it.
#[test]
fn a_magnified_picture_moves_the_obstacle_with_the_gap() {
    use hvi::plot::{level_set_segments, magnify_from};
    let phi = |x: [f64; 2]| x[1] + 0.05;
    let mut edges = level_set_segments(&phi, [-0.2, -0.3], [1.2, 0.5], 70, 40);
    assert!(!edges.is_empty());
    let gamma3 = [[[0.0, 0.0], [0.5, 0.0]], [[0.5, 0.0], [1.0, 0.0]]];
    magnify_from(&mut edges, &gamma3, 10.0);
    let mut under = 0;
    for e in &edges {
        for p in [e.a, e.b] {
            if (0.0..=1.0).contains(&p[0]) {
                assert!((p[1] + 0.5).abs() < 1e-12, "{p:?}");
                under += 1;
            }
        }
        assert!((e.inward[1] + 1.0).abs() < 1e-9, "{e:?}");
    }
    assert!(under > 0);
}

/// A run against a rigid circle: `hvi plot` draws the obstacle (hatched, said in the legend).
#[test]
fn plot_draws_a_circular_obstacle() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("circle.toml");
    std::fs::write(
        &scene,
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 4\n\
         [[dirichlet]]\ngroup = \"Gamma2_top\"\ncomponents = [\"x\", \"y\"]\nvalue = [\"0\", \"-0.1*t\"]\n\
         [contact]\nobstacle = { kind = \"circle\", centre = [1.0, -2.02], radius = 2.0 }\n",
    )
    .unwrap();
    let out = dir.path().join("run");
    let o = out.to_str().unwrap();
    ok(&[
        "solve",
        "rect:16x8",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        o,
        "--quiet",
    ]);
    ok(&["plot", o]);
    let svg = std::fs::read_to_string(out.join("deformed.svg")).unwrap();
    assert!(svg.contains("black, hatched: the obstacle"), "no obstacle legend");
    assert!(svg.matches("stroke=\"#282828\"").count() > 20, "no obstacle outline");
}

/// A run on steps growing with time (docs/method.md §20) spans decades: `hvi plot` draws the
/// largest u_ν over time on a logarithmic time axis (a tick at each decade), and the Γ₃ plot's
/// default times spread in log t so that the early ones are drawn too; a uniform run keeps a
/// linear axis.
#[test]
fn a_run_over_decades_gets_a_log_time_axis() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("decades");
    let o = out.to_str().unwrap();
    ok(&[
        "solve",
        "rect:8x4",
        "--set",
        "time.first_step=1e-4",
        "--set",
        "time.steps_per_decade=5",
        "--out",
        o,
        "--quiet",
    ]);
    let plot = ok(&["plot", o]);
    assert!(String::from_utf8_lossy(&plot.stdout).contains("history.svg"));
    let history = std::fs::read_to_string(out.join("history.svg")).unwrap();
    for text in [
        "time t (logarithmic)",
        "1e−4",
        "1e−2",
        "1e0",
        "largest normal displacement u_ν on Γ₃",
    ] {
        assert!(history.contains(text), "no {text:?} in history.svg");
    }
    let gamma3 = std::fs::read_to_string(out.join("gamma3.svg")).unwrap();
    assert!(
        gamma3.contains("t = 1e−4") && gamma3.contains("t = 4.2e−3"),
        "early times in gamma3.svg"
    );
    let uniform = dir.path().join("uniform");
    let u = uniform.to_str().unwrap();
    ok(&["solve", "rect:8x4", "--set", "time.steps=8", "--out", u, "--quiet"]);
    ok(&["plot", u]);
    let history = std::fs::read_to_string(uniform.join("history.svg")).unwrap();
    assert!(history.contains("time t") && !history.contains("logarithmic"));
}
