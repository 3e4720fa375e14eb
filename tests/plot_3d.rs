//! `hvi plot` on a 3D run: maps of u_ν and the contact pressure over Γ₃ (gamma3_map.png and
//! .svg), and a 2D run still gives deformed.png and gamma3.svg; the tiles the map draws.

mod common;

use hvi::plot::surface::{node_tiles, project_surface};
use std::path::Path;
fn root(name: &str) -> String {
    format!("{}/{name}", env!("CARGO_MANIFEST_DIR"))
}

use common::hvi_ok as run;

/// Width and height of a PNG file, after checking its signature and IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let png = std::fs::read(path).unwrap();
    assert!(png.len() > 1000, "{}: {} bytes", path.display(), png.len());
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&png[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&png[16..20]), be(&png[20..24]))
}

#[test]
fn a_3d_run_gives_maps_over_gamma3() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slab");
    let out_s = out.to_str().unwrap();
    run(&[
        "solve",
        &root("meshes/slab_q1_h8_z1.msh"),
        "--scene",
        &root("examples/slab.toml"),
        "--set",
        "time.steps=4",
        "--out",
        out_s,
        "--quiet",
    ]);
    let plot = run(&["plot", out_s]);
    let stdout = String::from_utf8_lossy(&plot.stdout);
    let png = out.join("gamma3_map.png");
    let svg = out.join("gamma3_map.svg");
    for f in [&png, &svg] {
        assert!(stdout.contains(&format!("wrote {}", f.display())), "{stdout}");
    }
    assert!(!out.join("deformed.png").exists(), "a 3D run has no 2D picture");

    // the slab's Γ₃ (y = 0) is a strip 2 × 1/8 in x and z: the two maps stacked, each 850 px wide
    let (w, h) = png_size(&png);
    assert!((900..=1400).contains(&w) && (300..=1000).contains(&h), "{w} × {h}");

    // the SVG has the same picture with text: one tile per Γ₃ node in each of the two maps
    let csv = std::fs::read_to_string(out.join("gamma3.csv")).unwrap();
    assert!(csv.starts_with("time,x,y,z,u_nu,force,pressure,status"));
    let last_rows = csv.lines().filter(|l| l.starts_with("1,")).count();
    assert!(last_rows > 0);
    let svg = std::fs::read_to_string(&svg).unwrap();
    assert!(svg.contains("<svg"));
    // the surface's own faces (16 Q1 faces of the 16 × 1 strip), each drawn as 4 × 4 pieces with
    // the colour interpolated, in each of the two maps
    assert_eq!(svg.matches("<polygon").count(), 2 * 16 * 16);
    let status = csv
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "status")
        .unwrap();
    let on_bound = csv
        .lines()
        .filter(|l| l.starts_with("1,") && l.split(',').nth(status) == Some("2"))
        .count();
    for text in [
        "Normal displacement u_ν on Γ₃ at t = 1",
        "Contact pressure on Γ₃ at t = 1",
        "u_ν at t = 1",
        "min ",
        "max 0.2", // u_ν reaches the bound g = 0.2
        // (the surface's 34 nodes: the 2 whose normal is clamped are not rows of gamma3.csv)
        &format!("nodes on the bound, {on_bound} of {}", last_rows + 2),
        ">\nx\n<",
        ">\nz\n<",
    ] {
        assert!(svg.contains(text), "no {text:?} in the SVG");
    }
}

#[test]
fn a_2d_run_still_gives_the_deformed_mesh_and_the_gamma3_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rect");
    let out_s = out.to_str().unwrap();
    run(&[
        "solve",
        &root("meshes/rect_q1_h8.msh"),
        "--set",
        "time.steps=4",
        "--out",
        out_s,
        "--quiet",
    ]);
    let plot = run(&["plot", out_s]);
    let stdout = String::from_utf8_lossy(&plot.stdout);
    for f in ["deformed.png", "deformed.svg", "gamma3.png", "gamma3.svg"] {
        assert!(stdout.contains(&format!("wrote {}", out.join(f).display())), "{stdout}");
    }
    assert!(!stdout.contains("gamma3_map"), "{stdout}");
    assert!(!out.join("gamma3_map.png").exists());
    let (w, h) = png_size(&out.join("deformed.png"));
    assert_eq!(w, 1200);
    assert!((500..=900).contains(&h), "{h}");
    assert!(std::fs::read_to_string(out.join("gamma3.svg"))
        .unwrap()
        .contains("<svg"));
}

#[test]
fn a_flat_face_is_drawn_in_its_plane() {
    // the face y = 0.3 of a box: x and z have the spread, y none
    let pts: Vec<[f64; 3]> = (0..4)
        .flat_map(|i| (0..3).map(move |k| [i as f64 * 0.5, 0.3, k as f64 * 0.25]))
        .collect();
    let (axes, flat) = project_surface(&pts);
    assert_eq!(axes, [0, 2]);
    assert_eq!(flat[5], [pts[5][0], pts[5][2]]);
    // z = 0: x and y
    let base: Vec<[f64; 3]> = pts.iter().map(|p| [p[0], p[2], 0.0]).collect();
    assert_eq!(project_surface(&base).0, [0, 1]);
}

fn area(poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        / 2.0
}

#[test]
fn tiles_of_a_grid_are_the_squares_of_its_spacing() {
    let h = 0.125;
    let pts: Vec<[f64; 2]> = (0..9)
        .flat_map(|i| (0..3).map(move |j| [1.0 + i as f64 * h, j as f64 * h]))
        .collect();
    let tiles = node_tiles(&pts);
    assert_eq!(tiles.len(), pts.len(), "one tile per node");
    for (p, t) in pts.iter().zip(&tiles) {
        assert!((area(t) - h * h).abs() < 1e-12, "{p:?}: {t:?}");
        for q in t {
            assert!((q[0] - p[0]).abs() <= h / 2.0 + 1e-12 && (q[1] - p[1]).abs() <= h / 2.0 + 1e-12);
        }
    }

    // scattered nodes: the tiles do not overlap (their areas add up to at most the box's)
    let mut s = 12345u64;
    let mut rnd = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let pts: Vec<[f64; 2]> = (0..200).map(|_| [rnd(), 0.5 * rnd()]).collect();
    let tiles = node_tiles(&pts);
    assert!(tiles.iter().all(|t| t.len() >= 3 && area(t) > 0.0));
    let inside = |t: &[[f64; 2]], q: [f64; 2]| {
        (0..t.len()).all(|i| {
            let (a, b) = (t[i], t[(i + 1) % t.len()]);
            (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]) > 1e-12
        })
    };
    let mut covered = 0;
    for _ in 0..2000 {
        let q = [rnd(), 0.5 * rnd()];
        let n = tiles.iter().filter(|t| inside(t, q)).count();
        assert!(n <= 1, "{q:?} in {n} tiles");
        // and it is in the tile of its nearest node
        if n == 1 {
            let d = |p: &[f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
            let near = (0..pts.len())
                .min_by(|&a, &b| d(&pts[a]).total_cmp(&d(&pts[b])))
                .unwrap();
            assert!(inside(&tiles[near], q));
            covered += 1;
        }
    }
    assert!(covered > 1900, "{covered} of 2000 covered");
}

/// A 3D run with friction (docs/method.md §17.5): the map gets a third panel, the stick and
/// slip zones at the last time, each piece in its node's zone colour, with their legend.
#[test]
fn a_3d_run_with_friction_maps_its_stick_and_slip_zones() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("slab_coulomb.toml");
    let text = std::fs::read_to_string(root("examples/slab.toml")).unwrap();
    assert!(text.contains("[contact]\n"));
    std::fs::write(
        &scene,
        text.replace(
            "[contact]\n",
            "[contact]\nfriction = { kind = \"coulomb\", coefficient = 0.3 }\n",
        ),
    )
    .unwrap();
    let out = dir.path().join("slab");
    let out_s = out.to_str().unwrap();
    run(&[
        "solve",
        &root("meshes/slab_q1_h8_z1.msh"),
        "--scene",
        scene.to_str().unwrap(),
        "--set",
        "time.steps=4",
        "--out",
        out_s,
        "--quiet",
    ]);
    run(&["plot", out_s]);
    let csv = std::fs::read_to_string(out.join("gamma3.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let status = header
        .iter()
        .position(|c| *c == "friction_status")
        .expect("friction columns");
    assert!(
        header.contains(&"slip_x") && header.contains(&"force_tau_z"),
        "{header:?}"
    );
    let codes: Vec<&str> = csv
        .lines()
        .filter(|l| l.starts_with("1,"))
        .map(|l| l.split(',').nth(status).unwrap())
        .collect();
    assert!(
        codes.iter().any(|c| *c == "1" || *c == "2"),
        "no node sticks or slips: {codes:?}"
    );
    let svg = std::fs::read_to_string(out.join("gamma3_map.svg")).unwrap();
    // three maps of the strip's 16 faces, each face as 4 × 4 pieces
    assert_eq!(svg.matches("<polygon").count(), 3 * 16 * 16);
    for text in [
        "Stick and slip on Γ₃ at t = 1",
        "friction status",
        ">\nstick\n<",
        ">\nslip\n<",
        ">\nseparated\n<",
    ] {
        assert!(svg.contains(text), "no {text:?} in the SVG");
    }
}
