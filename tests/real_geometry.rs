//! Issue 20, what a gmsh user's own parts hit first: messages that say what is wrong with the
//! mesh or the scene and name the scene key a group came from, and the cells gmsh makes beyond
//! tetrahedra and hexahedra (prisms, pyramids).

mod common;

use std::path::Path;
use std::process::Command;

fn hvi_fails(args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_hvi")).args(args).output().unwrap();
    assert!(!o.status.success(), "hvi {args:?} succeeded");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn assert_contains(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "expected {p:?} in:\n{msg}");
    }
}

/// An MSH 2.2 file with the given nodes (x, y, z) and elements (type, physical tag, nodes).
fn msh22(names: &[(u8, i32, &str)], nodes: &[[f64; 3]], elements: &[(i32, i32, Vec<usize>)]) -> String {
    let mut s = format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n{}\n",
        names.len()
    );
    for (d, t, n) in names {
        s += &format!("{d} {t} \"{n}\"\n");
    }
    s += &format!("$EndPhysicalNames\n$Nodes\n{}\n", nodes.len());
    for (i, p) in nodes.iter().enumerate() {
        s += &format!("{} {} {} {}\n", i + 1, p[0], p[1], p[2]);
    }
    s += &format!("$EndNodes\n$Elements\n{}\n", elements.len());
    for (i, (ty, tag, n)) in elements.iter().enumerate() {
        let n: Vec<String> = n.iter().map(|v| v.to_string()).collect();
        s += &format!("{} {ty} 2 {tag} {tag} {}\n", i + 1, n.join(" "));
    }
    s + "$EndElements\n"
}

/// A second-order pyramid and a volume mesh saved without its Physical Volume each get their own
/// message (both used to be told "mesh the volume (gmsh -3)"); a linear pyramid is read (prisms
/// and pyramids are computed on now, tests/three_d.rs and below), and a 10-node tetrahedron too
/// (second-order cells, docs/method.md §19).
#[test]
fn volume_meshes_hvi_cannot_use_say_why() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: String| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
    ];
    // a pyramid (the apex above the square base)
    let pyramid_nodes = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 0.5, 1.0],
    ];
    let pyramid = write(
        "pyramid.msh",
        msh22(&[(3, 5, "Omega")], &pyramid_nodes, &[(7, 5, vec![1, 2, 3, 4, 5])]),
    );
    let m = hvi::mesh::read_mesh::<3>(Path::new(&pyramid)).unwrap_or_else(|e| panic!("{e}"));
    assert!(matches!(m.cells[..], [hvi::mesh::Cell::Pyr5(_)]), "{:?}", m.cells);
    assert!((m.measure() - 1.0 / 3.0).abs() < 1e-15, "volume {}", m.measure());
    // the 13-node second-order pyramid (gmsh type 19): the corners, then the middles of the
    // edges 0–1, 0–3, 0–4, 1–2, 1–4, 2–3, 2–4, 3–4
    let mut pyr13 = pyramid_nodes.to_vec();
    for (a, b) in [(0, 1), (0, 3), (0, 4), (1, 2), (1, 4), (2, 3), (2, 4), (3, 4)] {
        let (p, q): ([f64; 3], [f64; 3]) = (pyramid_nodes[a], pyramid_nodes[b]);
        pyr13.push(std::array::from_fn(|k| 0.5 * (p[k] + q[k])));
    }
    let second = write(
        "pyr13.msh",
        msh22(&[(3, 5, "Omega")], &pyr13, &[(19, 5, (1..=13).collect())]),
    );
    let msg = hvi_fails(&["check", &second, "--scene", "examples/slab.toml"]);
    assert_contains(&msg, &["pyr13.msh", "13-node second-order pyramid", "-order 1"]);
    assert!(!msg.contains("gmsh -3)"), "{msg}");

    let mut tet10 = corners[..4].to_vec();
    for (a, b) in [(0, 1), (1, 2), (2, 0), (0, 3), (2, 3), (1, 3)] {
        let (p, q): ([f64; 3], [f64; 3]) = (corners[a], corners[b]);
        tet10.push(std::array::from_fn(|k| 0.5 * (p[k] + q[k])));
    }
    let second = write(
        "tet10.msh",
        msh22(&[(3, 5, "Omega")], &tet10, &[(11, 5, (1..=10).collect())]),
    );
    let m = hvi::mesh::read_mesh::<3>(Path::new(&second)).unwrap_or_else(|e| panic!("{e}"));
    assert!(matches!(m.cells[..], [hvi::mesh::Cell::Tet10(_)]), "{:?}", m.cells);
    assert!((m.measure() - 1.0 / 6.0).abs() < 1e-15, "volume {}", m.measure());

    // the surfaces of a tetrahedron in physical groups, its volume in none: gmsh saves only them
    let surfaces = write(
        "surfaces.msh",
        msh22(
            &[(2, 1, "Gamma1"), (2, 3, "Gamma3")],
            &corners[..4],
            &[(2, 1, vec![1, 3, 2]), (2, 3, vec![1, 2, 4]), (2, 3, vec![2, 3, 4])],
        ),
    );
    let msg = hvi_fails(&["check", &surfaces, "--scene", "examples/slab.toml"]);
    assert_contains(&msg, &["no volume elements", "Physical Volume", "Mesh.SaveAll"]);
}

/// The embedded default scene (the paper's 2D example) on a 3D mesh: the message says so and
/// points at a 3D scene, instead of "remove material.plane" from a scene the user never wrote.
#[test]
fn the_embedded_scene_on_a_3d_mesh_points_at_a_3d_scene() {
    let msg = hvi_fails(&["check", "meshes/block_q1_h8.msh"]);
    assert_contains(
        &msg,
        &[
            "3D mesh",
            "embedded default is the paper's 2D example",
            "--scene examples/slab.toml",
        ],
    );
}

/// A misnamed group names the scene key it came from (and the embedded scene as the scene),
/// suggests the nearest group name, and says that a tag works too.
#[test]
fn a_misnamed_group_names_the_key_and_the_nearest_group() {
    let mesh = Path::new("meshes/rect_q1_h8.msh").to_str().unwrap();
    let msg = hvi_fails(&["check", mesh, "--set", "groups.contact=gamma3"]);
    assert_contains(
        &msg,
        &[
            "embedded default scene",
            "`groups.contact`",
            "no physical group \"gamma3\"",
            "did you mean \"Gamma3\"",
            "tag number works too",
        ],
    );
    let msg = hvi_fails(&["check", mesh, "--set", "traction.0.group=Gama2_top"]);
    assert_contains(&msg, &["`traction[0].group`", "did you mean \"Gamma2_top\""]);
    let msg = hvi_fails(&["check", mesh, "--set", "groups.clamped=Gamma9"]);
    assert_contains(&msg, &["`groups.clamped`", "did you mean \"Gamma1\""]);
}

/// A contact group that is also the clamped group has no contact unknowns: `hvi check` (and
/// `hvi solve`) say so instead of running a contact problem on 0 nodes without a word.
#[test]
fn a_contact_group_that_is_clamped_is_warned_about() {
    let o = Command::new(env!("CARGO_BIN_EXE_hvi"))
        .args(["check", "meshes/rect_q1_h8.msh", "--set", "groups.contact=Gamma1"])
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{report}");
    assert_contains(
        &report,
        &[
            "warning: contact group `Gamma1` has no contact unknowns",
            "clamped group",
        ],
    );
}

/// A study with `mesh_files` runs only on those files: an n without its file (here the
/// reference) is refused naming it, instead of running on a generated rectangle beside the
/// user's geometry.
#[test]
fn a_study_with_mesh_files_needs_a_file_for_every_n() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(root.join("examples/paper.toml"), dir.path().join("paper.toml")).unwrap();
    for n in [8, 16] {
        std::fs::copy(
            root.join(format!("meshes/rect_q1_h{n}.msh")),
            dir.path().join(format!("m{n}.msh")),
        )
        .unwrap();
    }
    let study = dir.path().join("study.toml");
    std::fs::write(
        &study,
        "scene = \"paper.toml\"\nreference = { n = 32, steps = 8 }\nmesh_files = { \"8\" = \"m8.msh\", \"16\" = \"m16.msh\" }\n\
         [[h_paths]]\nsteps = 8\nn = [8, 16]\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let e = hvi::study::execute::run_file_with(&study, &out, &[], &hvi::study::Targets::default())
        .map(|_| ())
        .unwrap_err();
    assert_contains(
        &e,
        &[
            "the reference runs n = 32",
            "mesh_files has no mesh for it",
            "n = 8, 16",
            "32 = ",
        ],
    );
}

/// A traction written with `floor(y)` on the face y = 1 of a hexahedral slab acts on the whole
/// face: the quadrature points of a facet in a plane y = 1 have y = 1 exactly (Σ N_a y_a missed
/// it by a rounding at some points, where the load silently vanished).
#[test]
fn a_load_selected_by_a_coordinate_acts_on_its_whole_face() {
    use hvi::mesh::structured::{block, SolidShape};
    let scene = |value: &str| {
        hvi::scene::Scene::from_toml_str(
            &format!(
                "[material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n\
                 [groups]\nclamped = \"Gamma1\"\n[[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"0\", \"{value}\", \"0\"]\n"
            ),
            "<test>",
        )
        .unwrap()
    };
    let mesh = block([2.0, 1.0, 0.25], [32, 16, 4], SolidShape::Hex);
    let load = |value: &str| {
        let sim = hvi::solver::Simulation::new(&scene(value), mesh.clone()).unwrap();
        let mut f = vec![0.0; sim.dofs.n()];
        sim.loads.assemble(0.0, &sim.dofs, &mut f).unwrap();
        f
    };
    let (by_floor, by_one) = (load("floor(y)"), load("1"));
    let total = |f: &[f64]| f.iter().sum::<f64>();
    assert!(
        (total(&by_one) - 0.5).abs() < 1e-12,
        "the face's area is 2 × 0.25: {}",
        total(&by_one)
    );
    assert_eq!(by_floor, by_one);
}

/// A load depending on position is checked on its own group, not at the origin: `1/x` on a body
/// in 1 ≤ x ≤ 3 is accepted (it was refused, "evaluates to inf at [0, 0, 0]"), and `log(x - 2.5)`
/// there is refused naming the point of the group where it is NaN.
#[test]
fn loads_are_checked_on_their_groups_not_at_the_origin() {
    use hvi::mesh::structured::{rectangle, CellShape};
    let mut mesh = rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
    mesh.points.iter_mut().for_each(|p| p[0] += 1.0);
    let scene = |value: &str| {
        hvi::scene::Scene::from_toml_str(
            &format!(
                "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\n\
                 steps = 2\n[groups]\nclamped = \"Gamma1\"\n[[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"0\", \"{value}\"]\n"
            ),
            "<test>",
        )
    };
    let sim = hvi::solver::Simulation::new(&scene("-0.01/x").unwrap(), mesh.clone()).unwrap();
    sim.check_data().unwrap();
    let sim = hvi::solver::Simulation::new(&scene("log(x - 2.5)").unwrap(), mesh).unwrap();
    let e = sim.check_data().unwrap_err().to_string();
    assert_contains(&e, &["traction[0].value[1]", "is NaN at (x, y) = ("]);
}

/// A component prescribed by two groups (the corner of a clamped side and a roller side) counts
/// in both groups' rows (each the whole force on its group) and once more, negatively, in the
/// overlap row `Gamma1 & Gamma3`, so all rows and the loads add up to zero along each direction
/// (there was no overlap row before, and the sum missed the corner's reaction).
#[test]
fn reactions_of_overlapping_groups_add_up() {
    use hvi::mesh::structured::{rectangle, CellShape};
    let s = hvi::scene::Scene::from_toml_str(
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 2\n\
         [groups]\nclamped = \"Gamma1\"\n[[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n\
         [[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"0.01\", \"-0.02*x\"]\n",
        "<test>",
    )
    .unwrap();
    let mesh = rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
    let (sim, stats, _) = hvi::app::solve_in_memory(&s, mesh).unwrap();
    let mut load = vec![0.0; sim.dofs.n()];
    sim.loads.assemble(1.0, &sim.dofs, &mut load).unwrap();
    for (k, comp) in ["x", "y"].iter().enumerate() {
        let applied: f64 = (0..sim.mesh.points.len()).map(|p| load[sim.dofs.index(p, k)]).sum();
        let reactions: f64 = stats
            .reactions
            .iter()
            .filter(|r| r.time == 1.0 && r.component == *comp)
            .map(|r| r.force)
            .sum();
        assert!(applied.abs() > 1e-3);
        if *comp == "y" {
            assert!(
                stats.reactions.iter().any(|r| r.group == "Gamma1 & Gamma3"),
                "no overlap row"
            );
        }
        assert!(
            (reactions + applied).abs() < 1e-12 * applied.abs().max(1.0),
            "{comp}: reactions {reactions:e} + loads {applied:e}"
        );
    }
}

/// A missing `[time]` says so (it pointed at line 1, column 1), and `motion` written beside an
/// obstacle instead of inside it names the section `contact[1]` (it said `[contact]`) and where
/// `motion` belongs.
#[test]
fn scene_messages_name_the_missing_section_and_the_numbered_contact_section() {
    let base =
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[groups]\nclamped = \"Gamma1\"\n";
    let e = hvi::scene::Scene::from_toml_str(base, "s.toml")
        .unwrap_err()
        .to_string();
    assert_contains(&e, &["s.toml", "`time`", "add a [time] section"]);
    assert!(!e.contains("line 1"), "{e}");
    let motion = format!(
        "{base}[time]\nfinal_time = 1.0\nsteps = 2\n[[contact]]\ngroup = \"Gamma3\"\nbound = 0.1\n[[contact]]\n\
         group = \"Gamma2_top\"\nobstacle = {{ kind = \"plane\", point = [0.0, 1.1], normal = [0.0, -1.0] }}\nmotion = [\"0\", \"-t\"]\n"
    );
    let e = hvi::scene::Scene::from_toml_str(&motion, "s.toml")
        .unwrap_err()
        .to_string();
    assert_contains(
        &e,
        &["unknown key `motion` in contact[1]", "belongs inside the obstacle"],
    );
}

/// A convergence study on a curved domain with gmsh meshes that are not nested
/// (examples/gallery/ring/ring_study.toml: the quarter ring, n = 4, 8, 16 against n = 32). The
/// fine meshes' arc nodes lie outside the coarse meshes' chords by O(h²); they are evaluated by
/// extension (the study stopped with "lies outside the mesh" before), study.md says how far the
/// farthest was, that distance falls like h², and the H¹ error converges at the order the theory
/// gives for Q1 (1; L² 2).
#[test]
fn a_study_on_curved_non_nested_meshes_converges_at_the_theoretical_order() {
    let out = tempfile::tempdir().unwrap();
    let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/ring/ring_study.toml");
    hvi::study::execute::run_file(&study, out.path(), &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut reader = csv::Reader::from_path(out.path().join("study.csv")).unwrap();
    let rows: Vec<(f64, f64, f64)> = reader
        .records()
        .map(|r| {
            let r = r.unwrap();
            (r[1].parse().unwrap(), r[6].parse().unwrap(), r[7].parse().unwrap())
        })
        .collect();
    assert_eq!(rows.len(), 3);
    for w in rows.windows(2) {
        let ratio = w[0].0 / w[1].0;
        let h1 = (w[0].1 / w[1].1).ln() / ratio.ln();
        let l2 = (w[0].2 / w[1].2).ln() / ratio.ln();
        // (the last pair is biased by the reference, h_ref = h/2: ≤ 1.3)
        assert!(
            (0.9..1.3).contains(&h1),
            "H¹ order {h1} between h = {} and {}",
            w[0].0,
            w[1].0
        );
        assert!((1.8..2.5).contains(&l2), "L² order {l2}");
    }
    let md = std::fs::read_to_string(out.path().join("study.md")).unwrap();
    let farthest: Vec<(f64, f64)> = md
        .lines()
        .filter(|l| l.contains("reference nodes outside its mesh"))
        .map(|l| {
            let by = l.split("the farthest by ").nth(1).unwrap();
            let (d, rest) = by.split_once(" (allowed ").unwrap();
            (d.parse().unwrap(), rest.trim_end_matches(')').parse().unwrap())
        })
        .collect();
    assert_eq!(farthest.len(), 3, "{md}");
    for (d, allowed) in &farthest {
        assert!(d <= allowed && *d > 0.0);
    }
    for w in farthest.windows(2) {
        let ratio = w[0].0 / w[1].0;
        assert!((3.0..5.0).contains(&ratio), "the gap falls like h²: ratio {ratio}");
    }
}

/// A point farther outside than the coarse boundary's sagitta bound is refused, saying the
/// meshes are not of the same geometry; a polygonal domain has no such allowance.
#[test]
fn points_beyond_the_sagitta_bound_are_refused() {
    use hvi::mesh::structured::{rectangle, CellShape};
    use hvi::study::{boundary_sagitta, Locator};
    let rect = rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
    assert_eq!(boundary_sagitta(&rect), 0.0);
    let ring = hvi::mesh::read_mesh::<2>(Path::new("meshes/ring_q1_n4.msh")).unwrap();
    let allowed = boundary_sagitta(&ring);
    assert!(allowed > 0.0 && allowed < 0.05, "{allowed}");
    let locator = Locator::new(&ring);
    // just outside the outer arc at 45°, within the bound; and well outside
    let at = |r: f64| [r * std::f64::consts::FRAC_1_SQRT_2, r * std::f64::consts::FRAC_1_SQRT_2];
    let (_, e) = locator.transfer_extending(&[at(2.0)], allowed).unwrap();
    assert!(e.points <= 1 && e.farthest <= allowed);
    let err = locator.transfer_extending(&[at(2.2)], allowed).map(|_| ()).unwrap_err();
    assert_contains(&err, &["lies outside the mesh", "not of the same geometry"]);
}

/// A run on the mixed prism–tetrahedron mesh (meshes/prism.geo: an extruded triangulation under
/// tetrahedra) with contact on its triangulated bottom writes a series ParaView reads as wedges:
/// VTK type 13 with the base triangle's normal pointing away from the other triangle (VTK's
/// convention; gmsh's prism has it the other way round).
#[test]
fn a_prism_mesh_runs_with_contact_and_writes_vtk_wedges() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("prism.toml");
    std::fs::write(
        &scene,
        "[material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 2\n\
         [groups]\nclamped = \"Gamma1\"\n[[traction]]\ngroup = \"Gamma2\"\npressure = \"0.01*t*(z > 0.49)\"\n\
         [[contact]]\ngroup = \"Gamma3\"\nbound = 0.001\n[contact.law]\nkind = \"power\"\nscale = 0.1\nexponent = 1.0\n",
    )
    .unwrap();
    let out = dir.path().join("run");
    let o = Command::new(env!("CARGO_BIN_EXE_hvi"))
        .args(["solve", "meshes/prism_tet.msh", "--scene", scene.to_str().unwrap()])
        .args(["--out", out.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frame = hvi::output::read_vtu_arrays(&out.join("solution_00002.vtu")).unwrap();
    let wedges: Vec<&Vec<usize>> = frame
        .cell_types
        .iter()
        .zip(&frame.connectivity)
        .filter(|(t, _)| **t == 13)
        .map(|(_, c)| c)
        .collect();
    assert_eq!(wedges.len(), 84);
    for c in wedges {
        let p = |k: usize| frame.points[c[k]];
        let d = |a: [f64; 3], b: [f64; 3]| [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let (u, v) = (d(p(0), p(1)), d(p(0), p(2)));
        let normal = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let up = d(p(0), p(3));
        assert!(normal.iter().zip(&up).map(|(a, b)| a * b).sum::<f64>() < 0.0, "{c:?}");
    }
    // the contact surface is the bottom's triangles
    let contact = hvi::output::read_vtu_arrays(&out.join("contact_00002.vtp")).unwrap();
    assert!(!contact.connectivity.is_empty() && contact.connectivity.iter().all(|c| c.len() == 3));
}

// ---------------------------------------------------------------------------------------------
// Pyramids (gmsh type 7, docs/method.md §8.1)
// ---------------------------------------------------------------------------------------------

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(u: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

fn dot(u: [f64; 3], v: [f64; 3]) -> f64 {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

/// Lamé's λ, μ of E = 1, ν = 0.3 and the stress λ tr(ε) I + 2μ ε of ε = sym A.
fn stress_of(a: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let (e, nu) = (1.0, 0.3);
    let (l, m) = (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)));
    let tr = a[0][0] + a[1][1] + a[2][2];
    std::array::from_fn(|i| std::array::from_fn(|j| m * (a[i][j] + a[j][i]) + if i == j { l * tr } else { 0.0 }))
}

/// The linear patch test on gmsh's hexahedron–pyramid–tetrahedron mesh (meshes/pyramid.geo: the
/// pyramids gmsh puts on the interface quadrangles) with its interior nodes moved by up to 0.2 h,
/// which bends the pyramids' bases out of plane and moves their apexes: their maps are not
/// affine and the rational term of their basis is at work (docs/method.md §8.1). u = A x with a
/// non-symmetric A is reproduced at every node (a) prescribed on the whole boundary and (b)
/// prescribed on Γ₁ only, with the traction σν of the constant stress σ(A) on Γ₂ and Γ₃
/// (quadrangles of hexahedra, triangles of tetrahedra). The collapsed 8-point rule integrates
/// ∫ ∇N_a exactly on any pyramid, so both hold to the solver's round-off: asserted 1e-10 of
/// max |A x| (the bound; measured about 1e-14 and 1e-13).
#[test]
fn pyramids_pass_the_patch_test_on_the_distorted_hex_pyramid_tet_mesh() {
    let mut m = hvi::mesh::read_mesh::<3>(Path::new("meshes/pyramid_hex_tet.msh")).unwrap_or_else(|e| panic!("{e}"));
    let count = |m: &hvi::mesh::Mesh<3>, name: &str| m.cells.iter().filter(|c| c.name() == name).count();
    let kinds = [count(&m, "pyramid"), count(&m, "hexahedron"), count(&m, "tetrahedron")];
    assert!(
        kinds[0] >= 24 && kinds[1] > 0 && kinds[2] > 0,
        "pyramids, hexahedra, tetrahedra: {kinds:?}"
    );
    assert!(m.defects().is_empty(), "{:?}", m.defects());
    common::distort_off_groups(&mut m, 0.2);
    // the largest distance of a base's fourth corner from the plane of its first three, relative
    // to the base's diagonal
    let bend = m
        .cells
        .iter()
        .filter_map(|c| match c {
            hvi::mesh::Cell::Pyr5(n) => Some(n),
            _ => None,
        })
        .map(|n| {
            let p = |k: usize| m.points[n[k]];
            let normal = cross(sub(p(1), p(0)), sub(p(2), p(0)));
            let diagonal = dot(sub(p(2), p(0)), sub(p(2), p(0))).sqrt();
            dot(normal, sub(p(3), p(0))).abs() / dot(normal, normal).sqrt() / diagonal
        })
        .fold(0.0, f64::max);
    assert!(bend > 0.02, "the distortion left the pyramids' bases planar ({bend:e})");
    // and every cell is still positively oriented at its quadrature points
    for c in &m.cells {
        for q in hvi::mesh::element::stiffness_rule(c) {
            let det = hvi::mesh::element::shape_at(c, &m.points, q.xi).det_j;
            assert!(det > 0.0, "the distortion inverted {c:?}");
        }
    }

    let a = [[0.01, 0.02, -0.005], [0.003, -0.01, 0.004], [0.002, 0.006, 0.008]];
    let s = stress_of(a);
    let linear = |x: &[f64; 3]| -> [f64; 3] { std::array::from_fn(|i| (0..3).map(|j| a[i][j] * x[j]).sum()) };
    let scale = m.points.iter().flat_map(linear).fold(0.0f64, |v, c| v.max(c.abs()));
    let value: Vec<String> = (0..3)
        .map(|i| format!("{:e}*x + {:e}*y + {:e}*z", a[i][0], a[i][1], a[i][2]))
        .collect();
    let traction: Vec<String> = (0..3)
        .map(|i| format!("{:e}*nx + {:e}*ny + {:e}*nz", s[i][0], s[i][1], s[i][2]))
        .collect();
    let prescribe = |g: &str| {
        format!(
            "[[dirichlet]]\ngroup = \"{g}\"\ncomponents = [\"x\", \"y\", \"z\"]\nvalue = [\"{}\", \"{}\", \"{}\"]\n",
            value[0], value[1], value[2]
        )
    };
    let load = |g: &str| {
        format!(
            "[[traction]]\ngroup = \"{g}\"\nvalue = [\"{}\", \"{}\", \"{}\"]\n",
            traction[0], traction[1], traction[2]
        )
    };
    let head = "[material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n";
    for (case, toml) in [
        (
            "prescribed",
            format!(
                "{head}{}{}{}",
                prescribe("Gamma1"),
                prescribe("Gamma2"),
                prescribe("Gamma3")
            ),
        ),
        (
            "loaded",
            format!("{head}{}{}{}", prescribe("Gamma1"), load("Gamma2"), load("Gamma3")),
        ),
    ] {
        let (sim, _, sink) = hvi::app::solve_in_memory(&common::scene(&toml), m.clone()).unwrap();
        assert!(sim.dofs.n_free() > 0, "{case}: interior nodes to test");
        let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
        let err = common::nodal_error(&sim.mesh.points, &u, linear) / scale;
        eprintln!(
            "pyramid_hex_tet.msh, distorted (bases bent by {bend:.3}), {case}: patch test error {err:e} of max |A x|"
        );
        assert!(err <= 1e-10, "{case}: patch test error {err:e} of max |A x|");
    }
}

/// `hvi check` and `hvi solve` on the mixed mesh with the gallery's scene
/// (examples/gallery/pyramid/pyramid.toml: clamped, pressed on its top, in contact on its
/// triangulated bottom): the run finishes, and its frames hold the pyramids as VTK pyramids
/// (type 14), base first with its right-hand normal towards the apex (VTK's convention and
/// gmsh's), beside the hexahedra (12) and tetrahedra (10), as many of each as `hvi check` counts.
#[test]
fn a_pyramid_mesh_runs_with_contact_and_writes_vtk_pyramids() {
    let (mesh, scene) = ("meshes/pyramid_hex_tet.msh", "examples/gallery/pyramid/pyramid.toml");
    let report = String::from_utf8_lossy(&common::hvi_ok(&["check", mesh, "--scene", scene]).stdout).into_owned();
    let counted = |kind: &str| -> usize {
        let at = report
            .find(&format!(" {kind}"))
            .unwrap_or_else(|| panic!("no {kind} in:\n{report}"));
        report[..at]
            .rsplit(|c: char| !c.is_ascii_digit())
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let (pyramids, hexahedra, tetrahedra) = (counted("pyramids"), counted("hexahedra"), counted("tetrahedra"));
    assert!(pyramids > 0 && hexahedra > 0 && tetrahedra > 0, "{report}");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = Command::new(env!("CARGO_BIN_EXE_hvi"))
        .args([
            "solve",
            mesh,
            "--scene",
            scene,
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frame = hvi::output::read_vtu_arrays(&out.join("solution_00008.vtu")).unwrap();
    let of_type = |t: u8| frame.cell_types.iter().filter(|&&c| c == t).count();
    assert_eq!(
        (of_type(14), of_type(12), of_type(10)),
        (pyramids, hexahedra, tetrahedra)
    );
    for (_, c) in frame
        .cell_types
        .iter()
        .zip(&frame.connectivity)
        .filter(|(t, _)| **t == 14)
    {
        let p = |k: usize| frame.points[c[k]];
        // the base's normal (the cross product of its diagonals) towards the apex
        let normal = cross(sub(p(2), p(0)), sub(p(3), p(1)));
        let centre: [f64; 3] = std::array::from_fn(|d| (0..4).map(|k| p(k)[d]).sum::<f64>() / 4.0);
        assert!(dot(normal, sub(p(4), centre)) > 0.0, "{c:?}");
    }
    // the body moved: down under the pressure, and finitely
    let (_, u) = &frame.point_data["displacement"];
    assert!(u.iter().all(|v| v.is_finite()) && u.chunks(3).any(|d| d[2] < 0.0));
    let contact = hvi::output::read_vtu_arrays(&out.join("contact_00008.vtp")).unwrap();
    assert!(!contact.connectivity.is_empty() && contact.connectivity.iter().all(|c| c.len() == 3));
}

/// The unit cube as three pyramids with their apex at the origin and their bases on x = 1,
/// y = 1 and z = 1: its boundary is the three bases and six of the pyramids' triangles (two on
/// each of x = 0, y = 0, z = 0). A pressure p on the group "Pressed" (the triangles on x = 0 and
/// y = 0 and the base on z = 1, one group of both kinds of face) with rollers on x = 1, y = 1
/// (bases) and z = 0 (triangles) is a uniform compression σ = −p I: u = −p (1 − 2ν)/E (x − 1,
/// y − 1, z), reproduced to round-off (1e-12 of its size), with the reactions of the rollers
/// −p, −p and +p (1e-12 p). The group's nodal weights add up to its area 3 with its facets
/// turned outward, and at the origin (on triangles of x = 0 and y = 0 only) the weight is 1/3 +
/// 1/3 and the normal (−1, −1, 0)/√2.
#[test]
fn loads_reactions_and_normals_on_pyramid_faces() {
    let nodes = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1.0],
    ];
    let (pressed, x1, y1, z0) = (7, 11, 12, 13);
    let text = msh22(
        &[
            (2, pressed, "Pressed"),
            (2, x1, "X1"),
            (2, y1, "Y1"),
            (2, z0, "Z0"),
            (3, 5, "Omega"),
        ],
        &nodes,
        &[
            (7, 5, vec![2, 6, 7, 3, 1]),
            (7, 5, vec![4, 3, 7, 8, 1]),
            (7, 5, vec![5, 8, 7, 6, 1]),
            (3, x1, vec![2, 3, 7, 6]),
            (3, y1, vec![3, 4, 8, 7]),
            (3, pressed, vec![5, 6, 7, 8]),
            (2, pressed, vec![1, 4, 8]),
            (2, pressed, vec![1, 5, 8]),
            (2, pressed, vec![1, 2, 6]),
            (2, pressed, vec![1, 5, 6]),
            (2, z0, vec![1, 2, 3]),
            (2, z0, vec![1, 3, 4]),
        ],
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("three_pyramids.msh");
    std::fs::write(&path, text).unwrap();
    let m = hvi::mesh::read_mesh::<3>(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!((m.measure() - 1.0).abs() < 1e-15 && m.defects().is_empty());

    let part = m
        .boundary(&hvi::mesh::GroupSelector::from("Pressed"))
        .unwrap_or_else(|e| panic!("{e}"));
    let total: f64 = part.weights.iter().sum();
    assert!((total - 3.0).abs() < 1e-14, "weights add up to {total}");
    for f in &part.facets {
        let p = |k: usize| m.points[f[k]];
        let normal = cross(sub(p(1), p(0)), sub(p(2), p(0)));
        let centre: [f64; 3] =
            std::array::from_fn(|d| f.nodes().iter().map(|&q| m.points[q][d]).sum::<f64>() / f.len() as f64);
        assert!(dot(normal, sub(centre, [0.5; 3])) > 0.0, "facet {f:?} turned inward");
    }
    let origin = part.local(0).expect("the origin is on the group");
    let r = std::f64::consts::FRAC_1_SQRT_2;
    assert!(
        (part.weights[origin] - 2.0 / 3.0).abs() < 1e-15,
        "{}",
        part.weights[origin]
    );
    let n = part.normals[origin];
    assert!(
        (n[0] + r).abs() < 1e-15 && (n[1] + r).abs() < 1e-15 && n[2].abs() < 1e-15,
        "{n:?}"
    );

    let (e, nu, p) = (1.0, 0.3, 0.01);
    let toml = format!(
        "[material]\nyoungs_modulus = {e}\npoisson_ratio = {nu}\n[time]\nfinal_time = 1.0\nsteps = 1\n\
         [[dirichlet]]\ngroup = \"X1\"\ncomponents = [\"x\"]\n[[dirichlet]]\ngroup = \"Y1\"\ncomponents = [\"y\"]\n\
         [[dirichlet]]\ngroup = \"Z0\"\ncomponents = [\"z\"]\n[[traction]]\ngroup = \"Pressed\"\npressure = \"{p}\"\n"
    );
    let (sim, stats, sink) = hvi::app::solve_in_memory(&common::scene(&toml), m).unwrap();
    let u = sim.dofs.to_nodal(&sink.steps.last().unwrap().displacement);
    let c = -p * (1.0 - 2.0 * nu) / e;
    let err = common::nodal_error(&sim.mesh.points, &u, |x| [c * (x[0] - 1.0), c * (x[1] - 1.0), c * x[2]]);
    assert!(err <= 1e-12 * c.abs(), "field error {err:e} of {c:e}");
    for (group, component, want) in [("X1", "x", -p), ("Y1", "y", -p), ("Z0", "z", p)] {
        let r = common::reaction(&stats, group, component, 1.0);
        assert!(
            (r - want).abs() <= 1e-12 * p,
            "{group} {component} reaction {r} (want {want})"
        );
    }
}

/// The local stiffness of a pyramid with a warped base and a tilted apex
/// (hvi::fem::assembly::local_stiffness with its collapsed 8-point rule) applied to the nodal
/// values of a linear field u = A x gives the nodal forces ∮ N_a σ ν ds of its constant stress
/// (the base's bilinear face by 2 × 2 Gauss, exact for its bicubic integrand; the flat triangles
/// by their vertex rule), and uᵀ K u = V σ : ε with V = (1/3) ∮ x · ν ds: the stiffness of a
/// linear field is integrated exactly. Round-off: 1e-14 of the largest force. (Any rule
/// symmetric in the collapsed (u, v) and exact for (1 − w)² does that much, even one point; the
/// 8 points also make K singular on the rigid motions only: 6 eigenvalues below 1e-12 of the
/// largest, the other 9 above 1e-3 of it, where one point would leave 3 hourglass modes.)
#[test]
fn a_pyramid_stiffness_is_exact_on_linear_fields() {
    use hvi::mesh::quadrature::QUAD_GAUSS_2X2;
    use hvi::mesh::topology::facet_map;
    use hvi::mesh::Cell;
    let pts = [
        [0.0, 0.0, 0.05],
        [1.2, 0.1, 0.0],
        [1.0, 0.9, -0.1],
        [-0.1, 1.1, 0.02],
        [0.7, 0.3, 0.8],
    ];
    let cell = Cell::Pyr5([0, 1, 2, 3, 4]);
    // ∮ N_a ν ds per node, face by face as the cell turns them outward
    let mut nv = [[0.0; 3]; 5];
    for f in cell.facets() {
        if f.len() == 3 {
            let area = cross(sub(pts[f[1]], pts[f[0]]), sub(pts[f[2]], pts[f[0]]));
            for &q in f.nodes() {
                (0..3).for_each(|d| nv[q][d] += area[d] / 6.0);
            }
        } else {
            for g in &QUAD_GAUSS_2X2 {
                let (value, area, _) = facet_map(&pts, &f, g.xi);
                for (k, &q) in f.nodes().iter().enumerate() {
                    (0..3).for_each(|d| nv[q][d] += g.weight * value[k] * area[d]);
                }
            }
        }
    }
    let volume: f64 = (0..5).map(|a| dot(pts[a], nv[a])).sum::<f64>() / 3.0;
    let a = [[0.01, 0.02, -0.005], [0.003, -0.01, 0.004], [0.002, 0.006, 0.008]];
    let s = stress_of(a);
    let (e, nu) = (1.0, 0.3);
    let c = hvi::material::Isotropic {
        lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        mu: e / (2.0 * (1.0 + nu)),
    };
    let mut k = vec![0.0; 15 * 15];
    hvi::fem::assembly::local_stiffness(
        &cell,
        &pts,
        &[c],
        hvi::fem::assembly::Volumetric::Pointwise,
        false,
        &mut [&mut k[..]],
    );
    let u: Vec<f64> = pts
        .iter()
        .flat_map(|x| (0..3).map(move |i| (0..3).map(|j| a[i][j] * x[j]).sum::<f64>()))
        .collect();
    let f: Vec<f64> = (0..15)
        .map(|r| (0..15).map(|col| k[r * 15 + col] * u[col]).sum())
        .collect();
    let largest = f.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for node in 0..5 {
        for i in 0..3 {
            let want: f64 = (0..3).map(|j| s[i][j] * nv[node][j]).sum();
            let got = f[3 * node + i];
            assert!(
                (got - want).abs() <= 1e-14 * largest,
                "node {node}, component {i}: {got} vs {want}"
            );
        }
    }
    let energy: f64 = (0..15).map(|r| u[r] * f[r]).sum();
    let sym = |i: usize, j: usize| 0.5 * (a[i][j] + a[j][i]);
    let exact = volume
        * (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| s[i][j] * sym(i, j))
            .sum::<f64>();
    assert!(
        (energy - exact).abs() <= 1e-14 * exact,
        "uᵀKu = {energy}, V σ:ε = {exact}"
    );
    let mut eigen: Vec<f64> = nalgebra::DMatrix::from_row_slice(15, 15, &k)
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .collect();
    eigen.sort_by(f64::total_cmp);
    let top = eigen[14];
    assert!(
        eigen[..6].iter().all(|v| v.abs() <= 1e-12 * top) && eigen[6] >= 1e-3 * top,
        "eigenvalues {eigen:?}"
    );
}

/// study.md gives every path its table under its heading (the headings of a study without
/// published numbers stood empty) and says which order is which.
#[test]
fn every_path_of_a_study_has_its_table_and_its_fitted_order() {
    let out = tempfile::tempdir().unwrap();
    let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/gallery/ring/ring_study.toml");
    hvi::study::execute::run_file(&study, out.path(), &[]).unwrap_or_else(|e| panic!("{e}"));
    let md = std::fs::read_to_string(out.path().join("study.md")).unwrap();
    let section = md
        .split("## h refined at k = T/4")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .unwrap_or_else(|| panic!("{md}"));
    assert_contains(
        section,
        &[
            "| 1/4 |",
            "| 1/8 |",
            "| 1/16 |",
            "observed between neighbouring runs",
            "order 1.",
        ],
    );
}

/// `--target` whose recommendation has the reference's own h says plainly that the target
/// cannot be verified against this reference (its spatial error is 0 by construction there).
#[test]
fn a_target_on_the_reference_mesh_says_it_cannot_be_verified() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("small.toml");
    std::fs::write(
        &study,
        format!(
            "scene = \"{}\"\nreference = {{ n = 32, steps = 32 }}\n[[h_paths]]\nsteps = 32\nn = [4, 8, 16]\n\
             [[k_paths]]\nn = 32\nsteps = [2, 4, 8]\n",
            concat!(env!("CARGO_MANIFEST_DIR"), "/examples/paper.toml")
        ),
    )
    .unwrap();
    let targets = hvi::study::Targets {
        errors: vec![1e-3],
        verify: false,
    };
    let out = dir.path().join("out");
    hvi::study::execute::run_file_with(&study, &out, &[], &targets).unwrap_or_else(|e| panic!("{e}"));
    let md = std::fs::read_to_string(out.join("study.md")).unwrap();
    assert_contains(
        &md,
        &[
            "Recommended: **h = 1/32",
            "the target cannot be verified against it",
            "finer reference",
        ],
    );
}
