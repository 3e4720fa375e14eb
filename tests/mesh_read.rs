//! The mesh reader on the committed meshes (meshes/*.msh), the formats against each other, the
//! built-in rectangle mesher against gmsh, boundary normals on a curved boundary, and every
//! kind of bad input.

use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::{parse_mesh, read_mesh, Cell, GroupSelector, Mesh, MeshError};
use std::path::{Path, PathBuf};

fn meshes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes")
}

fn read(name: &str) -> Mesh<2> {
    let path = meshes_dir().join(name);
    read_mesh::<2>(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(meshes_dir().join(name)).unwrap()
}

fn text(name: &str) -> String {
    String::from_utf8(bytes(name)).unwrap()
}

fn sel(s: &str) -> GroupSelector {
    GroupSelector::from(s)
}

fn signed_area(m: &Mesh<2>, c: &Cell) -> f64 {
    let n = c.nodes();
    (0..n.len())
        .map(|i| {
            let (p, q) = (m.points[n[i]], m.points[n[(i + 1) % n.len()]]);
            0.5 * (p[0] * q[1] - q[0] * p[1])
        })
        .sum()
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Quad,
    Tri,
    /// Quadrangles on x < 1, triangles on x > 1.
    Mixed,
}

/// Every committed mesh: file, cells along x, cells along y, kind.
const MESHES: &[(&str, usize, usize, Kind)] = &[
    ("rect_q1_h8.msh", 16, 8, Kind::Quad),
    ("rect_q1_h16.msh", 32, 16, Kind::Quad),
    ("rect_q1_h32.msh", 64, 32, Kind::Quad),
    ("rect_q1_h64.msh", 128, 64, Kind::Quad),
    ("rect_p1_h16.msh", 32, 16, Kind::Tri),
    ("rect_q1_h16_bin.msh", 32, 16, Kind::Quad),
    ("rect_q1_h16_v22.msh", 32, 16, Kind::Quad),
    ("rect_q1_h16_wide.msh", 16, 16, Kind::Quad),
    ("rect_mixed_h4.msh", 8, 4, Kind::Mixed),
    ("rect_q1_h8_sparse.msh", 16, 8, Kind::Quad),
    // Only the paper's groups Gamma1, Gamma2, Gamma3 and Omega (`-setnumber plain 1`).
    ("rect_q1_h16_plain.msh", 32, 16, Kind::Quad),
    ("rect_p1_h8_plain.msh", 16, 8, Kind::Tri),
    // Two halves, each its own surface group Left 6 / Right 7 (`-setnumber halves 1`).
    ("rect_halves_q1_h4.msh", 8, 4, Kind::Quad),
    ("rect_halves_p1_h4.msh", 8, 4, Kind::Tri),
];

/// Every committed 3D mesh: file, nodes, cells, volume, (surface group, faces).
#[allow(clippy::type_complexity)]
const MESHES_3D: &[(&str, usize, usize, f64, &[(&str, usize)])] = &[
    (
        "slab_q1_h8_z1.msh",
        306,
        128,
        0.25,
        &[
            ("Gamma1", 8),
            ("Gamma2", 24),
            ("Gamma3", 16),
            ("Gamma2_top", 16),
            ("Sides", 256),
        ],
    ),
    (
        "slab_q1_h8_z3.msh",
        612,
        384,
        0.75,
        &[("Gamma1", 24), ("Gamma2", 72), ("Gamma3", 48), ("Sides", 256)],
    ),
    (
        "slab_q1_h16_z4.msh",
        2805,
        2048,
        0.5,
        &[("Gamma1", 64), ("Gamma3", 128), ("Sides", 1024)],
    ),
    (
        "slab_p1_h4.msh",
        135,
        384,
        1.0,
        &[("Gamma1", 16), ("Gamma3", 32), ("Sides", 128)],
    ),
    (
        "block_q1_h8.msh",
        405,
        256,
        0.5,
        &[("Gamma1", 64), ("Gamma2", 128), ("Gamma3", 64)],
    ),
    (
        "block_p1.msh",
        1309,
        5301,
        0.5,
        &[("Gamma1", 406), ("Gamma2", 868), ("Gamma3", 406)],
    ),
    (
        "prism_tet.msh",
        136,
        268,
        0.5,
        &[("Gamma1", 24), ("Gamma2", 114), ("Gamma3", 42)],
    ),
    (
        "pyramid_hex_tet.msh",
        269,
        554,
        0.5,
        &[("Gamma1", 38), ("Gamma2", 150), ("Gamma3", 90)],
    ),
    (
        "block_p1_bin.msh",
        91,
        222,
        0.5,
        &[("Gamma1", 42), ("Gamma2", 88), ("Gamma3", 42)],
    ),
    (
        "block_p1_v22.msh",
        91,
        222,
        0.5,
        &[("Gamma1", 42), ("Gamma2", 88), ("Gamma3", 42)],
    ),
    (
        "bracket_p1.msh",
        4972,
        19951,
        0.07637,
        &[("Gamma1", 552), ("Gamma2", 328), ("Gamma3", 1270), ("Sides", 4498)],
    ),
];

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// Checks a mesh of (0,2)×(0,1) with nx × ny grid cells and the groups of rectangle.geo.
fn check_rectangle(m: &Mesh<2>, nx: usize, ny: usize, kind: Kind) {
    let what = m.path.display().to_string();
    assert_eq!(m.points.len(), (nx + 1) * (ny + 1), "{what}: nodes");
    let tris = m.cells.iter().filter(|c| matches!(c, Cell::Tri3(_))).count();
    let quads = m.cells.len() - tris;
    let (want_tris, want_quads) = match kind {
        Kind::Quad => (0, nx * ny),
        Kind::Tri => (2 * nx * ny, 0),
        Kind::Mixed => (2 * (nx / 2) * ny, (nx / 2) * ny),
    };
    assert_eq!(
        (tris, quads),
        (want_tris, want_quads),
        "{what}: (triangles, quadrangles)"
    );
    assert_eq!(m.cell_tags.len(), m.cells.len());
    let mut area = 0.0;
    for c in &m.cells {
        let a = signed_area(m, c);
        assert!(a > 0.0, "{what}: cell {c:?} is not counter-clockwise");
        area += a;
    }
    assert!(close(area, 2.0, 1e-9), "{what}: area {area}");

    // A "_plain" mesh has only the groups the paper names.
    let plain = what.contains("_plain");
    let expect: Vec<(u8, i32, &str)> = [
        (1, 1, "Gamma1"),
        (1, 2, "Gamma2"),
        (1, 3, "Gamma3"),
        (1, 4, "Gamma2_top"),
        (2, 5, "Omega"),
    ]
    .into_iter()
    .filter(|g| !(plain && g.2 == "Gamma2_top"))
    .chain(
        [(1, 8, "Gamma2_right"), (2, 6, "Left"), (2, 7, "Right")]
            .into_iter()
            .filter(|_| what.contains("_halves")),
    )
    .collect::<Vec<_>>();
    // (the groups are sorted by dimension, then tag)
    let mut expect = expect;
    expect.sort_by_key(|g| (g.0, g.1));
    let got: Vec<(u8, i32, &str)> = m
        .groups
        .iter()
        .map(|g| (g.dim, g.tag, g.name.as_deref().unwrap_or("")))
        .collect();
    assert_eq!(got, expect, "{what}: groups");
    let facets = |name: &str| m.group(&sel(name), 1).unwrap().facets.len();
    assert_eq!(facets("Gamma1"), ny, "{what}");
    assert_eq!(facets("Gamma2"), ny + nx, "{what}");
    assert_eq!(facets("Gamma3"), nx, "{what}");
    if !plain {
        assert_eq!(facets("Gamma2_top"), nx, "{what}");
    }
    assert_eq!(
        m.group(&GroupSelector::Tag(5), 2).unwrap().cells.len(),
        m.cells.len(),
        "{what}"
    );
    for half in ["Left", "Right"].iter().filter(|_| what.contains("_halves")) {
        let cells = &m.group(&sel(half), 2).unwrap().cells;
        assert_eq!(2 * cells.len(), m.cells.len(), "{what}: {half}");
        let left = cells
            .iter()
            .all(|&c| m.cells[c].nodes().iter().all(|&p| m.points[p][0] <= 1.0 + 1e-12));
        assert_eq!(left, *half == "Left", "{what}: {half}");
    }
    assert_eq!(m.group_nodes(&sel("Gamma1")).unwrap().len(), ny + 1, "{what}");
    assert_eq!(m.group_nodes(&sel("Gamma2")).unwrap().len(), nx + ny + 1, "{what}");
    assert_eq!(m.group_nodes(&GroupSelector::Tag(3)).unwrap().len(), nx + 1, "{what}");

    // Γ₃: total weight 2, normals (0, −1), facets oriented with the body on the left.
    let g3 = m.boundary(&sel("Gamma3")).unwrap();
    assert_eq!(g3.label, "Gamma3 (tag 3)");
    assert_eq!(g3.nodes.len(), nx + 1);
    assert!(close(g3.weights.iter().sum::<f64>(), 2.0, 1e-12), "{what}: Γ₃ weight");
    assert!(close(g3.facet_lengths.iter().sum::<f64>(), 2.0, 1e-12));
    for (&p, n) in g3.nodes.iter().zip(&g3.normals) {
        assert!(close(m.points[p][1], 0.0, 1e-12));
        assert!(
            close(n[0], 0.0, 1e-12) && close(n[1], -1.0, 1e-12),
            "{what}: Γ₃ normal {n:?}"
        );
    }
    for f in &g3.facets {
        assert!(
            m.points[f[1]][0] > m.points[f[0]][0],
            "{what}: Γ₃ facet {f:?} not oriented"
        );
    }
    // Γ₁: normals (−1, 0), weight 1. Γ₂: weight 3, unit normals pointing out.
    let g1 = m.boundary(&GroupSelector::Tag(1)).unwrap();
    assert!(close(g1.weights.iter().sum::<f64>(), 1.0, 1e-12));
    assert!(g1
        .normals
        .iter()
        .all(|n| close(n[0], -1.0, 1e-12) && close(n[1], 0.0, 1e-12)));
    let g2 = m.boundary(&sel("Gamma2")).unwrap();
    assert!(close(g2.weights.iter().sum::<f64>(), 3.0, 1e-12));
    for (&p, n) in g2.nodes.iter().zip(&g2.normals) {
        let x = m.points[p];
        assert!(close(n[0].hypot(n[1]), 1.0, 1e-12));
        if close(x[0], 2.0, 1e-9) && close(x[1], 1.0, 1e-9) {
            assert!(n[0] > 0.0 && n[1] > 0.0, "{what}: corner normal {n:?}");
        } else if close(x[0], 2.0, 1e-9) {
            assert!(close(n[0], 1.0, 1e-12), "{what}: right normal {n:?}");
        } else {
            assert!(close(n[1], 1.0, 1e-12), "{what}: top normal {n:?} at {x:?}");
        }
    }
    assert!(
        plain
            || close(
                m.boundary(&sel("Gamma2_top")).unwrap().weights.iter().sum::<f64>(),
                2.0,
                1e-12
            )
    );

    let (dx, dy) = (2.0 / nx as f64, 1.0 / ny as f64);
    let (hmin, hmax) = m.cell_size();
    let (want_min, want_max) = match kind {
        Kind::Quad => (dx.max(dy), dx.max(dy)),
        Kind::Tri => (dx.hypot(dy), dx.hypot(dy)),
        Kind::Mixed => (dx.max(dy), dx.hypot(dy)),
    };
    assert!(
        close(hmin, want_min, 1e-9) && close(hmax, want_max, 1e-9),
        "{what}: h = ({hmin}, {hmax})"
    );
}

#[test]
fn every_committed_mesh_reads_with_the_expected_groups() {
    let mut files: Vec<String> = std::fs::read_dir(meshes_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| f.ends_with(".msh"))
        .collect();
    files.sort();
    for f in &files {
        assert!(
            MESHES.iter().any(|m| m.0 == f) || MESHES_3D.iter().any(|m| m.0 == f) || RINGS.iter().any(|m| m.0 == f),
            "meshes/{f} has no expectations in MESHES or MESHES_3D: add it"
        );
    }
    for &(file, nodes, cells, measure, groups) in MESHES_3D {
        let m = hvi::mesh::read_mesh::<3>(&meshes_dir().join(file)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((m.points.len(), m.cells.len()), (nodes, cells), "{file}: nodes, cells");
        let volume = m.measure();
        assert!((volume - measure).abs() <= 2e-3 * measure, "{file}: volume {volume}");
        for &(name, facets) in groups {
            let g = m.group(&sel(name), 2).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(g.facets.len(), facets, "{file}: {name}");
            let part = m.boundary(&sel(name)).unwrap_or_else(|e| panic!("{e}"));
            let total: f64 = part.weights.iter().sum();
            assert!((total - part.length()).abs() <= 1e-12 * total, "{file}: {name} weights");
        }
    }
    for &(file, nx, ny, kind) in MESHES {
        let m = read(file);
        assert_eq!(m.path, meshes_dir().join(file));
        check_rectangle(&m, nx, ny, kind);
    }
    // The quarter rings 1 <= r <= 2 of ring.geo: (n + 1)(2n + 1) nodes, 2n² quadrangles or 4n²
    // triangles, the area of the polygon through the boundary nodes, n (2n) facets per straight
    // (curved) side.
    for &(file, n, quads) in RINGS {
        let m = read(file);
        assert_eq!(m.points.len(), (n + 1) * (2 * n + 1), "{file}: nodes");
        assert_eq!(
            m.cells.len(),
            if quads { 2 * n * n } else { 4 * n * n },
            "{file}: cells"
        );
        let area = n as f64 * 3.0 * (std::f64::consts::PI / (4 * n) as f64).sin();
        assert!(
            (m.measure() - area).abs() <= 1e-12 * area,
            "{file}: area {}",
            m.measure()
        );
        for (name, facets) in [("Inner", 2 * n), ("Outer", 2 * n), ("SymX", n), ("SymY", n)] {
            let g = m.group(&sel(name), 1).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(g.facets.len(), facets, "{file}: {name}");
        }
    }
}

/// The quarter rings of ring.geo: file, cells across the wall, quadrangles?
const RINGS: &[(&str, usize, bool)] = &[
    ("ring_q1_n4.msh", 4, true),
    ("ring_q1_n8.msh", 8, true),
    ("ring_q1_n16.msh", 16, true),
    ("ring_q1_n32.msh", 32, true),
    ("ring_p1_n4.msh", 4, false),
    ("ring_p1_n8.msh", 8, false),
    ("ring_p1_n16.msh", 16, false),
];

#[test]
fn ascii_binary_and_v22_give_the_same_mesh() {
    let a = read("rect_q1_h16.msh");
    for other in ["rect_q1_h16_bin.msh", "rect_q1_h16_v22.msh"] {
        let b = read(other);
        assert_eq!(a.points.len(), b.points.len());
        for (p, q) in a.points.iter().zip(&b.points) {
            // ASCII prints 16 significant digits; binary is exact.
            assert!(
                close(p[0], q[0], 1e-14) && close(p[1], q[1], 1e-14),
                "{other}: {p:?} vs {q:?}"
            );
        }
        assert_eq!(a.cells, b.cells, "{other}");
        assert_eq!(a.groups, b.groups, "{other}");
    }
    assert_eq!(a.cell_tags, read("rect_q1_h16_bin.msh").cell_tags);
}

#[test]
fn sparse_node_tags_read_like_the_original() {
    let a = read("rect_q1_h8.msh");
    let b = read("rect_q1_h8_sparse.msh");
    assert_eq!(a.points, b.points);
    assert_eq!(a.cells, b.cells);
    assert_eq!(a.groups, b.groups);
    assert!(a.cell_tags.iter().zip(&b.cell_tags).all(|(x, y)| x + 1000 == *y));
}

#[test]
fn contiguous_permuted_node_tags_not_starting_at_1() {
    // rect_q1_h8_sparse.msh with tags 10t + 3 mapped to t + 100: one contiguous range
    // (101..=253) but listed in reverse within each block, which mshio alone gets wrong.
    let t = text("rect_q1_h8_sparse.msh");
    let map = |s: &str| ((s.parse::<u64>().unwrap() - 3) / 10 + 100).to_string();
    let mut out = Vec::new();
    let mut section = "";
    let mut lines = t.lines();
    while let Some(l) = lines.next() {
        let tokens: Vec<&str> = l.split_whitespace().collect();
        match l {
            "$Nodes" | "$Elements" => {
                section = l;
                out.push(l.to_string());
                let h: Vec<&str> = lines.next().unwrap().split_whitespace().collect();
                out.push(if l == "$Nodes" {
                    format!("{} {} 101 253", h[0], h[1])
                } else {
                    h.join(" ")
                });
            }
            _ if l.starts_with("$End") => {
                section = "";
                out.push(l.to_string());
            }
            _ if section == "$Nodes" && tokens.len() == 1 => out.push(map(tokens[0])),
            // Element lines (in this quadrangle mesh, block headers are the 4-number lines).
            _ if section == "$Elements" && tokens.len() != 4 => {
                let mut v = vec![tokens[0].to_string()];
                v.extend(tokens[1..].iter().map(|s| map(s)));
                out.push(v.join(" "));
            }
            _ => out.push(l.to_string()),
        }
    }
    let m = parse_mesh::<2>(Path::new("contiguous.msh"), (out.join("\n") + "\n").as_bytes()).unwrap();
    let a = read("rect_q1_h8.msh");
    assert_eq!(m.points, a.points);
    assert_eq!(m.cells, a.cells);
    assert_eq!(m.groups, a.groups);
}

#[test]
fn crlf_line_endings_read_the_same() {
    for file in ["rect_q1_h8.msh", "rect_q1_h16_v22.msh"] {
        let crlf = text(file).replace('\n', "\r\n");
        let m = parse_mesh::<2>(Path::new(file), crlf.as_bytes()).unwrap_or_else(|e| panic!("{e}"));
        let a = read(file);
        assert_eq!((m.points, m.cells, m.groups), (a.points, a.cells, a.groups));
    }
}

/// Points sorted by coordinates (rounded, so gmsh's 1e-12 noise does not reorder them).
fn sorted(points: impl Iterator<Item = [f64; 2]>) -> Vec<[f64; 2]> {
    let mut v: Vec<[f64; 2]> = points.collect();
    v.sort_by_key(|p| ((p[0] * 1e6).round() as i64, (p[1] * 1e6).round() as i64));
    v
}

fn centroids(m: &Mesh<2>) -> Vec<[f64; 2]> {
    sorted(m.cells.iter().map(|c| {
        let n = c.nodes();
        let k = n.len() as f64;
        [
            n.iter().map(|&p| m.points[p][0]).sum::<f64>() / k,
            n.iter().map(|&p| m.points[p][1]).sum::<f64>() / k,
        ]
    }))
}

#[test]
fn structured_rectangle_equals_the_gmsh_mesh() {
    for &(file, nx, ny, kind) in MESHES {
        let shape = match kind {
            Kind::Quad => CellShape::Quad,
            Kind::Tri => CellShape::Tri,
            Kind::Mixed => continue,
        };
        let r = rectangle(2.0, 1.0, nx, ny, shape);
        assert_eq!(r.path, PathBuf::from(format!("<rectangle {nx}x{ny}>")));
        check_rectangle(&r, nx, ny, kind);
        let mut r = r;
        if file.contains("_plain") {
            r.groups.retain(|g| g.name.as_deref() != Some("Gamma2_top"));
        }
        let mut g = read(file);
        // the structured rectangle has one body group (the halves' Left and Right are checked
        // by check_rectangle)
        g.groups.retain(|g| g.tag <= 5);
        let (pr, pg) = (sorted(r.points.iter().copied()), sorted(g.points.iter().copied()));
        assert_eq!(pr.len(), pg.len());
        for (p, q) in pr.iter().zip(&pg) {
            assert!(
                close(p[0], q[0], 1e-9) && close(p[1], q[1], 1e-9),
                "{file}: {p:?} vs {q:?}"
            );
        }
        // Same cells (also the same triangle diagonals), compared by centroid.
        assert_eq!(r.cells.len(), g.cells.len(), "{file}: cell count");
        assert!(!r.cells.is_empty());
        for (p, q) in centroids(&r).iter().zip(&centroids(&g)) {
            assert!(
                close(p[0], q[0], 1e-9) && close(p[1], q[1], 1e-9),
                "{file}: cell at {p:?} vs {q:?}"
            );
        }
        assert_eq!(r.groups.len(), g.groups.len(), "{file}: group count");
        assert!(!r.groups.is_empty());
        for (gr, gg) in r.groups.iter().zip(&g.groups) {
            assert_eq!((gr.dim, gr.tag, &gr.name), (gg.dim, gg.tag, &gg.name));
            assert_eq!(
                (gr.facets.len(), gr.cells.len(), gr.nodes.len()),
                (gg.facets.len(), gg.cells.len(), gg.nodes.len())
            );
        }
        assert_eq!(r.groups.len(), g.groups.len());
    }
}

/// A fan of triangles from the origin to a polygon on the unit quarter circle, its arc vertices
/// at angles (π/2) s(i/n) with the smooth, non-uniform s(t) = t + 0.1 sin(πt), as MSH 2.2.
fn quarter_disc_v22(n: usize) -> String {
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
    s += "$PhysicalNames\n2\n1 7 \"Arc\"\n2 8 \"Body\"\n$EndPhysicalNames\n";
    s += &format!("$Nodes\n{}\n1 0 0 0\n", n + 2);
    for i in 0..=n {
        let t = i as f64 / n as f64;
        let th = std::f64::consts::FRAC_PI_2 * (t + 0.1 * (std::f64::consts::PI * t).sin());
        s += &format!("{} {:.17e} {:.17e} 0\n", i + 2, th.cos(), th.sin());
    }
    s += &format!("$EndNodes\n$Elements\n{}\n", 2 * n);
    for i in 0..n {
        s += &format!("{} 1 2 7 1 {} {}\n", i + 1, i + 2, i + 3);
    }
    for i in 0..n {
        s += &format!("{} 2 2 8 1 1 {} {}\n", n + i + 1, i + 2, i + 3);
    }
    s + "$EndElements\n"
}

#[test]
fn nodal_normals_on_an_arc_are_radial_to_second_order() {
    let dir = tempfile::tempdir().unwrap();
    let mut errors = Vec::new();
    for n in [16, 32, 64] {
        let path = dir.path().join(format!("quarter_disc_{n}.msh"));
        std::fs::write(&path, quarter_disc_v22(n)).unwrap();
        let m = read_mesh::<2>(&path).unwrap_or_else(|e| panic!("{e}"));
        let arc = m.boundary(&sel("Arc")).unwrap();
        assert_eq!(arc.nodes.len(), n + 1);
        let perimeter: f64 = arc.facet_lengths.iter().sum();
        assert!(close(arc.weights.iter().sum::<f64>(), perimeter, 1e-12));
        assert!(close(perimeter, std::f64::consts::FRAC_PI_2, 2.0 / (n * n) as f64));
        let mut worst = 0.0_f64;
        for (&p, nu) in arc.nodes.iter().zip(&arc.normals) {
            let x = m.points[p];
            let r = x[0].hypot(x[1]);
            // The end points have one facet only; the interior ones are what O(h²) is about.
            if close(x[0], 0.0, 1e-12) || close(x[1], 0.0, 1e-12) {
                continue;
            }
            let angle = (nu[0] * x[1] / r - nu[1] * x[0] / r).abs().asin();
            assert!(nu[0] * x[0] + nu[1] * x[1] > 0.0, "normal points inwards");
            worst = worst.max(angle);
        }
        errors.push(worst);
    }
    // Halving h divides the angle error by about 4.
    for w in errors.windows(2) {
        assert!(w[1] < 0.3 * w[0], "normal errors {errors:?} are not O(h²)");
    }
    assert!(errors[0] < 0.01, "{errors:?}");
}

#[test]
fn mixed_mesh_has_both_cell_kinds_and_one_omega() {
    let m = read("rect_mixed_h4.msh");
    assert!(m.cells.iter().any(|c| matches!(c, Cell::Tri3(_))));
    assert!(m.cells.iter().any(|c| matches!(c, Cell::Quad4(_))));
    // Quadrangles on the left, triangles on the right.
    for c in &m.cells {
        let x = c.nodes().iter().map(|&p| m.points[p][0]).sum::<f64>() / c.nodes().len() as f64;
        assert_eq!(matches!(c, Cell::Quad4(_)), x < 1.0);
    }
}

// ---------------------------------------------------------------------------------------------
// Bad input: every error names the file, the place and the fix; nothing panics.

fn parse_err(name: &str, content: &[u8]) -> String {
    match parse_mesh::<2>(Path::new(name), content) {
        Ok(_) => panic!("{name}: expected an error"),
        Err(e) => {
            let s = e.to_string();
            assert!(s.contains(name), "message does not name the file: {s}");
            s
        }
    }
}

fn assert_contains(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message lacks \"{p}\": {msg}");
    }
}

#[test]
fn missing_group_lists_the_existing_ones() {
    let m = read("rect_q1_h8.msh");
    let e = m.group(&sel("Gamma9"), 1).unwrap_err();
    assert!(matches!(e, MeshError::GroupNotFound { .. }));
    let s = e.to_string();
    assert_contains(
        &s,
        &[
            "rect_q1_h8.msh",
            "\"Gamma9\"",
            "dim 1 tag 1 \"Gamma1\"",
            "dim 1 tag 3 \"Gamma3\"",
            "dim 1 tag 4 \"Gamma2_top\"",
            "dim 2 tag 5 \"Omega\"",
        ],
    );
    assert!(m.boundary(&GroupSelector::Tag(42)).is_err());
    assert!(m
        .group_nodes(&sel("nothing"))
        .unwrap_err()
        .to_string()
        .contains("Gamma2"));
    // Omega is a surface: not a boundary part.
    assert!(m.boundary(&sel("Omega")).is_err());
    // A name that is a number is tried as a tag.
    assert_eq!(m.group(&sel("3"), 1).unwrap().name.as_deref(), Some("Gamma3"));
}

#[test]
fn truncated_files_are_errors_never_panics() {
    for file in [
        "rect_q1_h8.msh",
        "rect_q1_h16_bin.msh",
        "rect_q1_h16_v22.msh",
        "rect_mixed_h4.msh",
    ] {
        let b = bytes(file);
        let step = (b.len() / 150).max(1);
        let mut cut = 0;
        while cut + 16 < b.len() {
            let s = parse_err(file, &b[..cut]);
            if cut > b.len() / 3 && !file.contains("bin") {
                assert!(
                    s.contains("truncated") || s.contains("line"),
                    "{file} cut at {cut}: {s}"
                );
            }
            cut += step;
        }
    }
    // A cut in the middle of $Nodes says so, with the line.
    let t = text("rect_q1_h8.msh");
    let mid = t.find("$EndNodes").unwrap() - 200;
    let s = parse_err("cut.msh", &t.as_bytes()[..mid]);
    assert_contains(&s, &["truncated", "line"]);
    let t = text("rect_q1_h16_v22.msh");
    let mid = t.find("$EndElements").unwrap() - 200;
    let s = parse_err("cut22.msh", &t.as_bytes()[..mid]);
    assert_contains(&s, &["truncated", "$Elements", "line"]);
}

#[test]
fn element_referring_to_a_missing_node() {
    let t = text("rect_q1_h8.msh");
    // The first quadrangle of rect_q1_h8.msh.
    let line = t.lines().position(|l| l.starts_with("2 1 3 ")).unwrap() + 2;
    let old = t.lines().nth(line - 1).unwrap().to_string();
    let mut parts: Vec<&str> = old.split_whitespace().collect();
    parts[2] = "99999";
    let t = t.replacen(&old, &parts.join(" "), 1);
    let s = parse_err("missing.msh", t.as_bytes());
    assert_contains(
        &s,
        &[
            "node 99999",
            &format!("line {line}"),
            &format!("element {}", parts[0]),
            "re-export",
        ],
    );

    let t = text("rect_q1_h16_v22.msh").replacen("\n1 1 2 3 1 1 5\n", "\n1 1 2 3 1 1 77777\n", 1);
    let s = parse_err("missing22.msh", t.as_bytes());
    assert_contains(&s, &["node 77777", "element 1"]);
}

#[test]
fn inverted_cell_is_reported_and_all_clockwise_is_flipped() {
    let t = text("rect_q1_h8.msh");
    let start = t.lines().position(|l| l.starts_with("2 1 3 ")).unwrap();
    let lines: Vec<&str> = t.lines().collect();
    let reverse = |l: &str| {
        let v: Vec<&str> = l.split_whitespace().collect();
        format!("{} {} {} {} {}", v[0], v[1], v[4], v[3], v[2])
    };
    // One quadrangle (the 5th) reversed: an error naming its element tag and line.
    let mut one: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    one[start + 5] = reverse(lines[start + 5]);
    let tag = lines[start + 5].split_whitespace().next().unwrap();
    let s = parse_err("inverted.msh", (one.join("\n") + "\n").as_bytes());
    assert_contains(
        &s,
        &[
            "inverted",
            &format!("element {tag}"),
            &format!("line {}", start + 6),
            "1 of 128 cells",
        ],
    );

    // All reversed (a surface with normal −z): flipped back, the same mesh as the original.
    let mut all: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    for l in all.iter_mut().skip(start + 1).take(128) {
        *l = reverse(l);
    }
    let flipped = parse_mesh::<2>(Path::new("cw.msh"), (all.join("\n") + "\n").as_bytes()).unwrap();
    let orig = read("rect_q1_h8.msh");
    assert_eq!(flipped.points, orig.points);
    assert_eq!(flipped.groups, orig.groups);
    assert_eq!(flipped.cells.len(), orig.cells.len());
    assert!(!orig.cells.is_empty());
    for (a, b) in flipped.cells.iter().zip(&orig.cells) {
        // The same cycle, reversed twice: [a, b, c, d] → [a, d, c, b] → [a, b, c, d].
        assert_eq!(a, b);
    }
}

#[test]
fn absurd_counts_in_headers_are_errors_not_aborts() {
    let t = text("rect_q1_h8.msh");
    let huge = "1000000000000";
    let s = parse_err(
        "huge.msh",
        t.replacen("\n9 153 1 153\n", &format!("\n9 {huge} 1 {huge}\n"), 1)
            .as_bytes(),
    );
    assert_contains(&s, &[huge, "nodes", "truncated or its header is corrupt", "line"]);
    let s = parse_err(
        "huge_block.msh",
        t.replacen("\n0 1 0 1\n", &format!("\n0 1 0 {huge}\n"), 1).as_bytes(),
    );
    assert_contains(&s, &[huge, "corrupt"]);
    let s = parse_err(
        "huge_blocks.msh",
        t.replacen("\n9 153 1 153\n", &format!("\n{huge} 153 1 153\n"), 1)
            .as_bytes(),
    );
    assert_contains(&s, &[huge, "node blocks"]);
    let s = parse_err(
        "huge_elements.msh",
        t.replacen("\n5 176 1 176\n", &format!("\n5 {huge} 1 {huge}\n"), 1)
            .as_bytes(),
    );
    assert_contains(&s, &[huge, "elements"]);
    let s = parse_err(
        "huge_entities.msh",
        t.replacen("\n4 4 1 0\n", &format!("\n4 {huge} 1 0\n"), 1).as_bytes(),
    );
    assert_contains(&s, &["entities"]);
    let s = parse_err("zero.msh", t.replacen("\n9 153 1 153\n", "\n9 0 1 153\n", 1).as_bytes());
    assert_contains(&s, &["no nodes"]);

    let t22 = text("rect_q1_h16_v22.msh");
    let s = parse_err(
        "huge22.msh",
        t22.replacen("$Nodes\n561\n", &format!("$Nodes\n{huge}\n"), 1)
            .as_bytes(),
    );
    assert_contains(&s, &[huge, "line 13"]);
    let s = parse_err(
        "huge22e.msh",
        t22.replacen("$Elements\n640\n", "$Elements\n18446744073709551615\n", 1)
            .as_bytes(),
    );
    assert_contains(&s, &["18446744073709551615"]);

    // Binary: the size_t number of nodes right after "$Nodes\n" (after the number of blocks).
    let mut b = bytes("rect_q1_h16_bin.msh");
    let at = b.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7 + 8;
    b[at..at + 8].copy_from_slice(&1_000_000_000_000u64.to_le_bytes());
    let s = parse_err("huge_bin.msh", &b);
    assert_contains(&s, &[huge, "byte"]);
    let mut b = bytes("rect_q1_h16_bin.msh");
    b[at - 8..at].copy_from_slice(&u64::MAX.to_le_bytes());
    parse_err("huge_bin2.msh", &b);
}

/// A small MSH 2.2 file: two unit squares side by side, (0,2)×(0,1), with the given extra
/// element lines (numbered from 3) and a physical "Omega" (tag 5).
fn two_squares_v22(extra_nodes: &str, extra: &[&str]) -> String {
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
    s += "$PhysicalNames\n3\n1 3 \"Gamma3\"\n0 7 \"Corner\"\n2 5 \"Omega\"\n$EndPhysicalNames\n";
    let nodes = "1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n".to_string() + extra_nodes;
    s += &format!("$Nodes\n{}\n{nodes}$EndNodes\n", nodes.lines().count());
    s += &format!("$Elements\n{}\n1 3 2 5 1 1 2 5 4\n2 3 2 5 1 2 3 6 5\n", 2 + extra.len());
    for (i, e) in extra.iter().enumerate() {
        s += &format!("{} {e}\n", i + 3);
    }
    s + "$EndElements\n"
}

#[test]
fn small_v22_file_groups_and_points() {
    let t = two_squares_v22("", &["1 2 3 1 1 2", "1 2 3 1 2 3", "15 2 7 1 6"]);
    let m = parse_mesh::<2>(Path::new("small.msh"), t.as_bytes()).unwrap();
    assert_eq!(m.cells, vec![Cell::Quad4([0, 1, 4, 3]), Cell::Quad4([1, 2, 5, 4])]);
    assert_eq!(m.cell_tags, vec![1, 2]);
    assert_eq!(m.group_nodes(&sel("Gamma3")).unwrap(), vec![0, 1, 2]);
    assert_eq!(m.group_nodes(&sel("Corner")).unwrap(), vec![5]);
    assert_eq!(m.group(&sel("Corner"), 0).unwrap().nodes, vec![5]);
    let b = m.boundary(&sel("Gamma3")).unwrap();
    assert_eq!(b.facets, vec![[0, 1], [1, 2]]);
    assert_eq!(b.weights, vec![0.5, 1.0, 0.5]);
}

#[test]
fn facet_inside_the_body_is_not_a_boundary() {
    // Gamma3 = the edge x = 1 between the two squares.
    let t = two_squares_v22("", &["1 2 3 1 2 5"]);
    let m = parse_mesh::<2>(Path::new("inner.msh"), t.as_bytes()).unwrap();
    let e = m.boundary(&sel("Gamma3")).unwrap_err();
    assert!(matches!(e, MeshError::NotBoundary { .. }));
    assert_contains(
        &e.to_string(),
        &[
            "inner.msh",
            "Gamma3 (tag 3) is not on the boundary of the body",
            "(1.0, 0.0)–(1.0, 1.0)",
            "shared by two cells",
        ],
    );
    // An edge that is no cell's edge (the diagonal of a square).
    let t = two_squares_v22("", &["1 2 3 1 1 5"]);
    let m = parse_mesh::<2>(Path::new("diag.msh"), t.as_bytes()).unwrap();
    assert_contains(
        &m.boundary(&sel("Gamma3")).unwrap_err().to_string(),
        &["not an edge of any cell"],
    );
}

#[test]
fn unsupported_element_types_name_type_group_and_fix() {
    // A 10-node third-order triangle (type 21) in Omega.
    let t = two_squares_v22("7 0.5 0.5 0\n", &["21 2 5 1 1 2 5 7 7 7 7 7 7 7"]);
    let s = parse_err("order3.msh", t.as_bytes());
    assert_contains(
        &s,
        &[
            "type 21",
            "10-node third-order triangle",
            "\"Omega\" (tag 5)",
            "gmsh -order 1 or -order 2",
            "line",
        ],
    );
    // A 3-node line (type 8) in Gamma3 of first-order cells: the orders must match.
    let t = two_squares_v22("7 0.5 0 0\n", &["8 2 3 1 1 2 7"]);
    let s = parse_err("line3.msh", t.as_bytes());
    assert_contains(
        &s,
        &["type 8", "3-node second-order line", "\"Gamma3\" (tag 3)", "-order 1"],
    );
    // A tetrahedron (type 4).
    let t = two_squares_v22("7 0.5 0.5 0\n", &["4 2 9 1 1 2 4 7"]);
    // (A tetrahedron makes the file a 3D mesh; this one is flat, so it is degenerate.)
    let s = match hvi::mesh::parse_msh(Path::new("tet.msh"), t.as_bytes()) {
        Ok(_) => panic!("a flat tetrahedron must be an error"),
        Err(e) => e.to_string(),
    };
    assert_contains(&s, &["tet.msh", "tetrahedron", "degenerate", "det J"]);
    // 9-node quadrangles in MSH 4.1, in a physical surface: read (docs/method.md §19).
    let t41 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 5 \"Omega\"\n$EndPhysicalNames\n\
        $Entities\n0 0 1 0\n1 0 0 0 1 1 0 1 5 0\n$EndEntities\n\
        $Nodes\n1 9 1 9\n2 1 0 9\n1\n2\n3\n4\n5\n6\n7\n8\n9\n\
        0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0 0\n1 0.5 0\n0.5 1 0\n0 0.5 0\n0.5 0.5 0\n$EndNodes\n\
        $Elements\n1 1 1 1\n2 1 10 1\n1 1 2 3 4 5 6 7 8 9\n$EndElements\n";
    let q9 = parse_mesh::<2>(Path::new("q9.msh"), t41.as_bytes()).unwrap();
    assert_eq!(q9.cells, vec![Cell::Quad9([0, 1, 2, 3, 4, 5, 6, 7, 8])]);
    // The same file with first-order content reads.
    let ok = t41
        .replace("2 1 10 1\n1 1 2 3 4 5 6 7 8 9", "2 1 3 1\n1 1 2 3 4")
        .replace(
            "1 9 1 9\n2 1 0 9\n1\n2\n3\n4\n5\n6\n7\n8\n9",
            "1 4 1 4\n2 1 0 4\n1\n2\n3\n4",
        )
        .replace("0.5 0 0\n1 0.5 0\n0.5 1 0\n0 0.5 0\n0.5 0.5 0\n", "");
    let m = parse_mesh::<2>(Path::new("q4.msh"), ok.as_bytes()).unwrap();
    assert_eq!(m.cells, vec![Cell::Quad4([0, 1, 2, 3])]);
    assert_eq!(m.groups[0].name.as_deref(), Some("Omega"));
}

#[test]
fn bad_nodes_and_versions() {
    // Duplicate node tag.
    let t = two_squares_v22("5 3 3 0\n", &[]);
    assert_contains(
        &parse_err("dup.msh", t.as_bytes()),
        &["node tag 5 is defined twice", "line 16", "line 18"],
    );
    // Non-finite coordinate, with the line.
    let t = two_squares_v22("", &[]).replace("\n3 2 0 0\n", "\n3 nan 0 0\n");
    assert_contains(
        &parse_err("nan.msh", t.as_bytes()),
        &["non-finite", "line 14", "node 3"],
    );
    let t = text("rect_q1_h8.msh").replacen("\n2 0 0\n", "\n2 1e999 0\n", 1);
    assert_contains(&parse_err("inf.msh", t.as_bytes()), &["non-finite", "node 2"]);
    // z not constant.
    let t = two_squares_v22("", &[]).replace("\n6 2 1 0\n", "\n6 2 1 0.5\n");
    assert_contains(&parse_err("z.msh", t.as_bytes()), &["z = 0.5", "plane"]);
    // A node in no cell.
    let t = two_squares_v22("7 5 5 0\n", &[]);
    assert_contains(&parse_err("orphan.msh", t.as_bytes()), &["node 7", "no 2D element"]);
    // No cells at all.
    let t = two_squares_v22("", &[])
        .replace("1 3 2 5 1 1 2 5 4", "1 1 2 3 1 1 2")
        .replace("2 3 2 5 1 2 3 6 5", "2 1 2 3 1 2 3");
    assert_contains(
        &parse_err("nocells.msh", t.as_bytes()),
        &["no 2D elements", "Physical Surface"],
    );

    let header = |v: &str| format!("$MeshFormat\n{v}\n$EndMeshFormat\n");
    assert_contains(
        &parse_err("v3.msh", header("3.0 0 8").as_bytes()),
        &["version 3.0", "msh41"],
    );
    assert_contains(&parse_err("v40.msh", header("4 0 8").as_bytes()), &["4.0", "msh41"]);
    assert_contains(
        &parse_err("v22b.msh", header("2.2 1 8").as_bytes()),
        &["binary", "-format msh41"],
    );
    assert_contains(&parse_err("garbage.msh", b"hello\n"), &["not a gmsh MSH file"]);
    assert_contains(&parse_err("empty.msh", b""), &["not a gmsh MSH file"]);
    assert_contains(
        &parse_err("size.msh", header("4.1 1 99999999999999999999999").as_bytes()),
        &["data size"],
    );
    assert_contains(
        &parse_err("size3.msh", b"$MeshFormat\n4.1 1 3\n\x01\0\0\0\n$EndMeshFormat\n"),
        &["data size 3"],
    );
    // A file that does not exist: the path is in the message.
    let e = read_mesh::<2>(Path::new("no/such/mesh.msh")).unwrap_err();
    assert!(matches!(e, MeshError::Io { .. }) && e.to_string().contains("no/such/mesh.msh"));
}
