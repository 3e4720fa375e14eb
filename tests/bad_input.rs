//! Bad input (issue 4): every error names the file, the place (line, section, group or key)
//! and the fix; nothing panics, hangs or allocates more than the input warrants; a failed or
//! interrupted run leaves only whole frames and a `.pvd` that lists exactly them.
//!
//! `tests/mesh_read.rs` and `tests/scene_input.rs` test the readers directly; this file goes
//! end to end, through `hvi::app::solve` and the `hvi` binary, and adds the cases they miss.

mod common;
use common::msh22;

use hvi::app::{solve, solve_in_memory, SolveOptions};
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::{parse_mesh, Cell, Mesh, PhysicalGroup};
use hvi::scene::{Scene, DEFAULT_SCENE_TOML};
use hvi::solver::{Simulation, SolveError};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes")
}

fn mesh_text(name: &str) -> String {
    std::fs::read_to_string(meshes().join(name)).unwrap()
}

fn mesh_bytes(name: &str) -> Vec<u8> {
    std::fs::read(meshes().join(name)).unwrap()
}

fn assert_contains(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "message lacks {p:?}:\n{msg}");
    }
}

fn hvi() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hvi"))
}

/// Runs the binary; returns (exit code, stderr).
fn run_cli(args: &[&str]) -> (i32, String) {
    let out: Output = hvi().args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The paper's domain with 4 × 2 cells (15 nodes, Gamma1 = left, Gamma3 = bottom, …).
fn small() -> Mesh<2> {
    rectangle(2.0, 1.0, 4, 2, CellShape::Quad)
}

/// A temporary directory holding a mesh file, for `hvi::app::solve`.
struct Case {
    dir: tempfile::TempDir,
    mesh: PathBuf,
}

impl Case {
    fn new(file_name: &str, contents: &[u8]) -> Case {
        let dir = tempfile::tempdir().unwrap();
        let mesh = dir.path().join(file_name);
        std::fs::write(&mesh, contents).unwrap();
        Case { dir, mesh }
    }

    fn out(&self) -> PathBuf {
        self.dir.path().join("out")
    }

    /// Solves with the embedded paper scene and `overrides`; the error (an `Ok` is a failure
    /// of the test) and whether the output directory was created.
    fn error(&self, overrides: &[&str]) -> (SolveError, bool) {
        let opts = SolveOptions {
            mesh: self.mesh.clone(),
            scene: None,
            out: self.out(),
            overrides: overrides.iter().map(|s| s.to_string()).collect(),
            progress: false,
            // each case replaces the run of the one before
            overwrite: true,
            accept_mesh_defects: false,
        };
        match solve(&opts, None) {
            Ok(_) => panic!("{}: expected an error", self.mesh.display()),
            Err(e) => (e, self.out().exists()),
        }
    }

    /// The message of [`Case::error`], checked to name the mesh file and to come before any
    /// output was written.
    fn message(&self, overrides: &[&str]) -> String {
        let (e, out) = self.error(overrides);
        let msg = e.to_string();
        assert!(
            msg.contains(&self.mesh.display().to_string()),
            "the message does not name the file: {msg}"
        );
        assert!(
            !out,
            "{msg}: the output directory was created before the input was checked"
        );
        msg
    }

    /// The same through the binary: exit code 1, `error: ` and the message on stderr.
    fn cli_message(&self, overrides: &[&str]) -> String {
        let out = self.out();
        let mut args = vec![
            "solve",
            self.mesh.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ];
        for o in overrides {
            args.push("--set");
            args.push(o);
        }
        let (code, stderr) = run_cli(&args);
        assert_eq!(code, 1, "{stderr}");
        assert!(
            stderr.starts_with("error: ") && !stderr.contains("panicked"),
            "{stderr}"
        );
        assert!(stderr.contains(&self.mesh.display().to_string()), "{stderr}");
        stderr
    }
}

// ---------------------------------------------------------------------------------------------
// .msh files

#[test]
fn truncated_meshes_fail_cleanly_end_to_end() {
    for (file, name) in [
        ("rect_q1_h8.msh", "cut.msh"),
        ("rect_q1_h16_v22.msh", "cut22.msh"),
        ("rect_q1_h16_bin.msh", "cut_bin.msh"),
    ] {
        let b = mesh_bytes(file);
        for k in 1..24 {
            let at = b.len() * k / 24;
            let case = Case::new(name, &b[..at]);
            let msg = case.message(&["time.steps=2"]);
            // past the header, every cut is reported with its place and as a truncation
            // (or as the malformed token it leaves behind)
            if at > 200 && !file.contains("bin") {
                assert!(
                    msg.contains("line ") && (msg.contains("truncated") || msg.contains("expected")),
                    "{file} cut at {at}: {msg}"
                );
            }
            if at > 200 && file.contains("bin") {
                assert!(
                    msg.contains('$') || msg.contains("byte") || msg.contains("truncated"),
                    "{file} cut at {at}: {msg}"
                );
            }
        }
    }
    // in the middle of $Elements, through the binary
    let t = mesh_text("rect_q1_h8.msh");
    let case = Case::new("cut.msh", &t.as_bytes()[..t.find("$EndElements").unwrap() - 300]);
    let msg = case.cli_message(&[]);
    assert_contains(
        &msg,
        &["line 342 ($Elements)", "no $EndElements", "truncated", "re-export"],
    );
}

#[test]
fn wrong_counts_name_the_line_and_what_is_wrong() {
    let t = mesh_text("rect_q1_h8.msh");
    let v = mesh_text("rect_q1_h16_v22.msh");
    for (name, text, parts) in [
        // MSH 4.1: total number of nodes in the $Nodes header, too small and too large
        (
            "nodes_less.msh",
            t.replacen("\n9 153 1 153\n", "\n9 152 1 153\n", 1),
            vec!["line 130 ($Nodes)", "more than the 152 nodes the section header says"],
        ),
        (
            "nodes_more.msh",
            t.replacen("\n9 153 1 153\n", "\n9 154 1 153\n", 1),
            vec!["line 25 ($Nodes)", "header says 154 nodes but its blocks hold 153"],
        ),
        // the size of one node block
        (
            "block.msh",
            t.replacen("\n1 1 0 15\n", "\n1 1 0 16\n", 1),
            vec!["line 54 ($Nodes)", "expected a node tag"],
        ),
        // the size of one element block
        (
            "elements_block.msh",
            t.replacen("\n1 1 1 16\n", "\n1 1 1 17\n", 1),
            vec!["line 518", "invalid element definition", "re-export it from gmsh"],
        ),
        // $PhysicalNames
        (
            "names_more.msh",
            t.replacen("$PhysicalNames\n5\n", "$PhysicalNames\n7\n", 1),
            vec!["line 11 ($PhysicalNames)", "after 5 names, but the section says 7"],
        ),
        (
            "names_less.msh",
            t.replacen("$PhysicalNames\n5\n", "$PhysicalNames\n3\n", 1),
            vec!["line 9 ($PhysicalNames)", "expected $EndPhysicalNames after 3 names"],
        ),
        // MSH 2.2
        (
            "v22_nodes_less.msh",
            v.replacen("$Nodes\n561\n", "$Nodes\n560\n", 1),
            vec![
                "line 574 ($Nodes)",
                "after 560 nodes",
                "the count in the section header is wrong",
            ],
        ),
        (
            "v22_nodes_more.msh",
            v.replacen("$Nodes\n561\n", "$Nodes\n562\n", 1),
            vec!["line 575 ($Nodes)", "node 562 of 562", "$EndNodes"],
        ),
        (
            "v22_elements_less.msh",
            v.replacen("$Elements\n640\n", "$Elements\n639\n", 1),
            vec![
                "line 1217 ($Elements)",
                "after 639 elements",
                "the count in the section header is wrong",
            ],
        ),
        (
            "v22_elements_more.msh",
            v.replacen("$Elements\n640\n", "$Elements\n641\n", 1),
            vec!["line 1218 ($Elements)", "element 641 of 641", "truncated"],
        ),
    ] {
        let case = Case::new(name, text.as_bytes());
        assert_contains(&case.message(&[]), &parts);
    }
}

/// MSH 4.1 `$Elements` header `numEntityBlocks numElements minTag maxTag`: a wrong total
/// `numElements` (175 or 177 for 176) is not noticed, while every other count (the `$Nodes`
/// total, node and element block sizes, `$PhysicalNames`, both MSH 2.2 sections) is.
#[test]
fn msh41_element_total_is_checked() {
    let t = mesh_text("rect_q1_h8.msh");
    for wrong in ["175", "177"] {
        let case = Case::new(
            "elements_total.msh",
            t.replacen("\n5 176 1 176\n", &format!("\n5 {wrong} 1 176\n"), 1)
                .as_bytes(),
        );
        assert_contains(&case.message(&[]), &["line 343 ($Elements)", wrong, "176"]);
    }
}

#[test]
fn a_header_claiming_1e12_nodes_is_rejected_at_once() {
    let huge = "1000000000000";
    let t = mesh_text("rect_q1_h8.msh");
    let v = mesh_text("rect_q1_h16_v22.msh");
    let mut b = mesh_bytes("rect_q1_h16_bin.msh");
    let at = b.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7 + 8;
    b[at..at + 8].copy_from_slice(&1_000_000_000_000u64.to_le_bytes());
    for (name, bytes, parts) in [
        (
            "huge41.msh",
            t.replacen("\n9 153 1 153\n", &format!("\n9 {huge} 1 {huge}\n"), 1)
                .into_bytes(),
            vec!["line 25 ($Nodes)", "truncated or its header is corrupt", "re-export"],
        ),
        (
            "huge22.msh",
            v.replacen("$Nodes\n561\n", &format!("$Nodes\n{huge}\n"), 1)
                .into_bytes(),
            vec!["line 13 ($Nodes)", "truncated or its header is corrupt"],
        ),
        ("huge_bin.msh", b, vec!["byte", "corrupt"]),
    ] {
        let case = Case::new(name, &bytes);
        let t0 = Instant::now();
        let msg = case.message(&[]);
        // no allocation in proportion to the count: the answer comes at once
        assert!(t0.elapsed() < Duration::from_secs(1), "{:?}", t0.elapsed());
        assert_contains(&msg, &parts);
        assert_contains(&msg, &[huge]);
    }
    let case = Case::new(
        "huge41.msh",
        t.replacen("\n9 153 1 153\n", &format!("\n9 {huge} 1 {huge}\n"), 1)
            .as_bytes(),
    );
    assert_contains(&case.cli_message(&[]), &[huge, "nodes"]);
}

#[test]
fn unknown_and_unsupported_element_types() {
    let base = msh22(&small());
    // element 1 is the first line of Gamma1: make it type 99 (unknown) or 8 (second order)
    let unknown = base.replacen("\n1 1 2 1 1 ", "\n1 99 2 1 1 ", 1);
    let case = Case::new("type99.msh", unknown.as_bytes());
    assert_contains(
        &case.message(&[]),
        &[
            "line 32 (element 1)",
            "type 99",
            "an element type hvi does not know",
            "physical group tag 1",
            "gmsh -2 -order 1",
        ],
    );
    // a second-order line on first-order cells: the orders must match
    let quadratic = base.replacen("\n1 1 2 1 1 11 6\n", "\n1 8 2 1 1 11 6 3\n", 1);
    assert_ne!(quadratic, base);
    let case = Case::new("type8.msh", quadratic.as_bytes());
    assert_contains(
        &case.cli_message(&[]),
        &[
            "element 1",
            "type 8",
            "3-node second-order line",
            "\"Gamma1\" (tag 1)",
            "-order 1",
        ],
    );
}

#[test]
fn non_finite_coordinates() {
    let base = msh22(&small());
    assert!(base.contains("\n7 0.5 0.5 0\n"));
    for bad in ["nan", "NaN", "inf", "-inf", "1e999"] {
        let case = Case::new(
            "nan.msh",
            base.replacen("\n7 0.5 0.5 0\n", &format!("\n7 {bad} 0.5 0\n"), 1)
                .as_bytes(),
        );
        assert_contains(
            &case.message(&[]),
            &["line 20 (node 7)", "non-finite coordinate", "re-export"],
        );
    }
    let t = mesh_text("rect_q1_h8.msh").replacen("\n2 0 0\n", "\n2 NaN 0\n", 1);
    let case = Case::new("nan41.msh", t.as_bytes());
    assert_contains(&case.cli_message(&[]), &["node 2", "non-finite"]);
}

#[test]
fn element_refers_to_a_missing_node() {
    let base = msh22(&small());
    // the first quadrangle: element 17 "3 2 5 5 1 2 7 6"
    let case = Case::new("missing.msh", base.replacen(" 1 2 7 6\n", " 1 2 77 6\n", 1).as_bytes());
    assert_contains(
        &case.message(&[]),
        &[
            "line 48 (element 17)",
            "refers to node 77, which is not in $Nodes",
            "re-export",
        ],
    );
}

#[test]
fn duplicate_node_tags() {
    let base = msh22(&small());
    let case = Case::new(
        "dup.msh",
        base.replacen("$Nodes\n15\n", "$Nodes\n16\n3 5 5 0\n", 1).as_bytes(),
    );
    assert_contains(
        &case.message(&[]),
        &[
            "line 17 (node 3)",
            "node tag 3 is defined twice (also at line 14 (node 3))",
            "-renumber",
        ],
    );
}

#[test]
fn inverted_element() {
    let mut m = small();
    if let Cell::Quad4(n) = &mut m.cells[3] {
        n.swap(1, 3);
    }
    let case = Case::new("inverted.msh", msh22(&m).as_bytes());
    assert_contains(
        &case.message(&[]),
        &[
            "line 51 (element 20)",
            "element 20 is inverted",
            "1 of 8 cells",
            "Reverse Surface",
        ],
    );
    // a triangle too: a P1 mesh with one triangle listed clockwise
    let mut m = rectangle(2.0, 1.0, 4, 2, CellShape::Tri);
    if let Cell::Tri3(n) = &mut m.cells[5] {
        n.swap(1, 2);
    }
    let case = Case::new("inverted_tri.msh", msh22(&m).as_bytes());
    assert_contains(&case.cli_message(&[]), &["is inverted", "1 of 16 cells"]);
}

#[test]
fn missing_or_misnamed_groups_list_the_existing_ones() {
    let case = Case::new("groups.msh", msh22(&small()).as_bytes());
    let existing = [
        "dim 1 tag 1 \"Gamma1\"",
        "dim 1 tag 2 \"Gamma2\"",
        "dim 1 tag 3 \"Gamma3\"",
        "dim 1 tag 4 \"Gamma2_top\"",
        "dim 2 tag 5 \"Omega\"",
    ];
    for (set, wanted) in [
        ("groups.contact=Bottom", "\"Bottom\""),
        ("groups.contact=gamma3", "\"gamma3\""),
        ("groups.clamped=7", "tag 7"),
        ("traction.0.group=Top", "\"Top\""),
    ] {
        let msg = case.message(&[set]);
        assert_contains(
            &msg,
            &[
                &format!("there is no physical group {wanted} of dimension 1"),
                "the mesh has these groups",
            ],
        );
        assert_contains(&msg, &existing);
    }
    assert_contains(
        &case.cli_message(&["groups.contact=Bottom"]),
        &["\"Bottom\"", "dim 1 tag 3 \"Gamma3\""],
    );

    // A mesh whose groups have no names: they are listed by tag.
    let unnamed = msh22(&small());
    let (a, b) = (unnamed.find("$PhysicalNames").unwrap(), unnamed.find("$Nodes").unwrap());
    let unnamed = format!("{}{}", &unnamed[..a], &unnamed[b..]);
    let case = Case::new("unnamed.msh", unnamed.as_bytes());
    assert_contains(
        &case.message(&[]),
        &["no physical group \"Gamma1\"", "dim 1 tag 1, dim 1 tag 2, dim 1 tag 3"],
    );
    // … so the scene can use the tags.
    let ok = Case::new("unnamed.msh", unnamed.as_bytes());
    let opts = SolveOptions {
        mesh: ok.mesh.clone(),
        scene: None,
        out: ok.out(),
        overrides: [
            "groups.clamped=1",
            "groups.contact=3",
            "traction.0.group=4",
            "time.steps=2",
        ]
        .map(String::from)
        .to_vec(),
        progress: false,
        overwrite: false,
        accept_mesh_defects: false,
    };
    solve(&opts, None).unwrap_or_else(|e| panic!("{e}"));

    // A mesh with no physical groups at all: the message says how to define them.
    let bare = unnamed
        .replace("1 2 1 1 ", "1 2 0 0 ")
        .replace("1 2 2 2 ", "1 2 0 0 ")
        .replace("1 2 3 3 ", "1 2 0 0 ")
        .replace("1 2 4 4 ", "1 2 0 0 ")
        .replace("3 2 5 5 ", "3 2 0 0 ");
    let case = Case::new("bare.msh", bare.as_bytes());
    assert_contains(
        &case.message(&[]),
        &["no physical groups at all", "Physical Curve(\"Gamma3\", 3)"],
    );
}

#[test]
fn gamma3_that_is_not_a_boundary() {
    // Gamma3 = the vertical grid line x = 0.5 inside the body
    let mut m = small();
    m.groups[2].facets = vec![[1, 6].into(), [6, 11].into()];
    let case = Case::new("inner.msh", msh22(&m).as_bytes());
    assert_contains(
        &case.message(&[]),
        &[
            "Gamma3 (tag 3) is not on the boundary of the body",
            "(0.5, 0.0)–(0.5, 0.5)",
            "shared by two cells",
            "Physical Curve",
        ],
    );
    // a diagonal of a cell: not an edge of the mesh at all
    let mut m = small();
    m.groups[2].facets = vec![[0, 6].into()];
    let case = Case::new("diagonal.msh", msh22(&m).as_bytes());
    assert_contains(
        &case.cli_message(&[]),
        &["Gamma3 (tag 3) is not on the boundary", "not an edge of any cell"],
    );
}

#[test]
fn no_clamped_part_is_reported_before_factorising() {
    // Gamma1 is named in $PhysicalNames but has no line elements.
    let mut m = small();
    m.groups[0].facets.clear();
    let text = msh22(&m);
    let case = Case::new("free.msh", text.as_bytes());
    let (e, out) = case.error(&[]);
    assert!(matches!(e, SolveError::NoClampedNodes { .. }), "{e:?}");
    assert!(!out);
    let msg = e.to_string();
    assert_contains(
        &msg,
        &[
            &case.mesh.display().to_string(),
            "the clamped group \"Gamma1\" has no nodes",
            "singular",
            "tag the clamped boundary (Γ₁) in the mesh or set `groups.clamped`",
        ],
    );
    assert_contains(&case.cli_message(&[]), &["\"Gamma1\" has no nodes"]);
    // Simulation::new says so itself: no matrix is assembled or factorised before.
    let mesh = parse_mesh::<2>(Path::new("free.msh"), text.as_bytes()).unwrap();
    let scene = Scene::load(None, &[]).unwrap();
    assert!(matches!(
        Simulation::new(&scene, mesh),
        Err(SolveError::NoClampedNodes { .. })
    ));
}

/// A body held at one point only can still rotate about it: K is singular. Without contact
/// the Cholesky factorisation notices and says so; with the paper's memory and contact it does
/// not, and the run stops later with a contact failure that blames the time step.
#[test]
fn a_body_clamped_at_one_point() {
    let mut m = small();
    m.groups.push(PhysicalGroup {
        dim: 0,
        tag: 9,
        name: Some("Corner".into()),
        facets: vec![],
        cells: vec![],
        nodes: vec![0],
    });
    let text = "[groups]\nclamped = \"Corner\"\n[material]\nplane = \"stress\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n[[traction]]\ngroup = \"Gamma2_top\"\nvalue = [\"0\", \"-0.1*x\"]\n";
    let scene = Scene::from_toml_str(text, "corner.toml").unwrap();
    let mesh = parse_mesh::<2>(Path::new("corner.msh"), msh22(&m).as_bytes()).unwrap();
    let e = solve_in_memory(&scene, mesh).err().expect("a singular problem");
    // The rigid-motion check names the free rotation before anything is factorised (before it
    // existed, round-off decided whether the pivot failed or the probe solve caught it).
    let text = e.to_string();
    assert!(text.contains("rotation in the plane"), "{text}");
    assert_contains(&text, &["corner.msh", "the body is not held", "clamp"]);
}

/// The same body with the paper's contact (and memory): the rotation about the corner is held by
/// the contact layer along Γ₃, so it is a semi-coercive body (docs/method.md §7.7), solved with
/// the rotation pinned and the pin's reaction made zero inside the contact solve. (Before issue
/// 20 it was refused: once by a contact failure that blamed the time step, then by the probe.)
#[test]
fn a_body_clamped_at_one_point_with_memory_and_contact_is_held_by_the_contact() {
    let mut m = small();
    m.groups.push(PhysicalGroup {
        dim: 0,
        tag: 9,
        name: Some("Corner".into()),
        facets: vec![],
        cells: vec![],
        nodes: vec![0],
    });
    let overrides = ["groups.clamped=Corner".to_string(), "time.steps=2".to_string()];
    let scene = Scene::load(None, &overrides).unwrap_or_else(|e| panic!("{e}"));
    let mesh = parse_mesh::<2>(Path::new("corner.msh"), msh22(&m).as_bytes()).unwrap();
    let (sim, stats, sink) = solve_in_memory(&scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        sim.dirichlet.held_by_contact.len(),
        1,
        "{:?}",
        sim.dirichlet.held_by_contact
    );
    assert!(sim.dirichlet.held_by_contact[0].contains("rotation in the plane"));
    assert!(stats.effects.iter().any(|e| e == "rigid"), "{:?}", stats.effects);
    assert!(stats.max_contact_residual <= 1e-10, "{}", stats.max_contact_residual);
    assert_eq!(sink.steps.len(), 3);
}

#[test]
fn unsupported_msh_versions() {
    let base = msh22(&small());
    for (version, parts) in [
        (
            "3.0 0 8",
            vec!["MSH version 3.0 is not supported", "gmsh -format msh41"],
        ),
        ("4.0 0 8", vec!["MSH version 4.0 is not supported", "msh41"]),
        ("4 0 8", vec!["4.0", "msh41"]),
        ("5.0 0 8", vec!["MSH version 5.0 is not supported"]),
        ("2.2 1 8", vec!["binary MSH 2.2 is not supported", "-format msh41"]),
    ] {
        let case = Case::new("version.msh", base.replacen("2.2 0 8", version, 1).as_bytes());
        assert_contains(&case.message(&[]), &parts);
    }
    let case = Case::new("v1.msh", b"$NOD\n1\n1 0 0 0\n$ENDNOD\n");
    assert_contains(&case.cli_message(&[]), &["MSH 1 file", "-format msh41"]);
    let case = Case::new("not_a_mesh.msh", b"solid cube\nfacet normal 0 0 1\n");
    assert_contains(&case.cli_message(&[]), &["not a gmsh MSH file", "$MeshFormat"]);
}

// ---------------------------------------------------------------------------------------------
// Scenes

/// The error of the paper's scene text with `from` replaced by `to`, read from a file (so the
/// origin is its path), and the same through `hvi check --scene`.
fn scene_error(from: &str, to: &str) -> (String, String) {
    assert!(DEFAULT_SCENE_TOML.contains(from), "{from}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("my_scene.toml");
    std::fs::write(&path, DEFAULT_SCENE_TOML.replacen(from, to, 1)).unwrap();
    let msg = match Scene::load(Some(&path), &[]) {
        Ok(_) => panic!("{to}: expected an error"),
        Err(e) => e.to_string(),
    };
    assert!(
        msg.contains(&path.display().to_string()),
        "the message does not name the file: {msg}"
    );
    let (code, stderr) = run_cli(&[
        "check",
        meshes().join("rect_q1_h8.msh").to_str().unwrap(),
        "--scene",
        path.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains(&msg),
        "the binary prints another message:\n{stderr}\nvs\n{msg}"
    );
    (msg, path.display().to_string())
}

/// The error of the embedded scene with `--set` overrides.
fn override_error(sets: &[&str]) -> String {
    match Scene::load(None, &sets.iter().map(|s| s.to_string()).collect::<Vec<_>>()) {
        Ok(_) => panic!("{sets:?}: expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn unknown_keys_name_the_nearest_valid_key() {
    for (from, to, parts) in [
        (
            "youngs_modulus = 1.0",
            "youngs_modulos = 1.0",
            vec![
                "unknown key `youngs_modulos` in [material]",
                "did you mean `youngs_modulus`?",
                "valid keys there: plane, youngs_modulus, poisson_ratio",
            ],
        ),
        (
            "[solver]",
            "[solvers]",
            vec!["unknown key `solvers` in the top level", "did you mean `solver`?"],
        ),
        (
            "final_time = 1.0",
            "final_tme = 1.0",
            vec!["unknown key `final_tme` in [time]", "did you mean `final_time`?"],
        ),
        (
            "alpha = 100.0",
            "alpha = 100.0\nexponent = 2.0",
            vec![
                "unknown key `exponent` in [contact.law]",
                "valid keys there: kind, one_sided, regularisation, scale, a, b, alpha",
            ],
        ),
        (
            "regularisation = 1e-8",
            "regularization = 1e-8",
            vec![
                "unknown key `regularization` in [contact.law]",
                "did you mean `regularisation`?",
            ],
        ),
        (
            "group = \"Gamma2\"",
            "groop = \"Gamma2\"",
            vec!["unknown key `groop` in traction[0]", "did you mean `group`?"],
        ),
    ] {
        let (msg, _) = scene_error(from, to);
        assert_contains(&msg, &parts);
    }
    let msg = override_error(&["material.poisson=0.2"]);
    assert_contains(
        &msg,
        &[
            "embedded default scene",
            "unknown key `poisson` in [material]",
            "poisson_ratio",
        ],
    );
}

#[test]
fn wrong_types_name_the_line_and_the_key() {
    for (from, to, parts) in [
        (
            "steps = 32",
            "steps = \"ten\"",
            vec![
                "line 29",
                "`time.steps`",
                "steps = \"ten\"",
                "invalid type: string \"ten\", expected usize",
            ],
        ),
        (
            "steps = 32",
            "steps = -3",
            vec!["line 29", "`time.steps`", "steps = -3", "expected usize"],
        ),
        (
            "steps = 32",
            "steps = 3.5",
            vec!["line 29", "`time.steps`", "expected usize"],
        ),
        (
            "youngs_modulus = 1.0",
            "youngs_modulus = \"1\"",
            vec![
                "line 18",
                "`material.youngs_modulus`",
                "youngs_modulus = \"1\"",
                "expected f64",
            ],
        ),
        (
            "plane = \"stress\"",
            "plane = \"stres\"",
            vec![
                "line 17",
                "`material.plane`",
                "unknown variant `stres`, expected one of `stress`, `strain`, `axisymmetric`",
            ],
        ),
        (
            "kind = \"polynomial\"",
            "kind = \"polynomal\"",
            vec![
                "line 22",
                "`memory.kind`",
                "expected one of `polynomial`, `exponential`, `expression`",
            ],
        ),
        (
            "bound = 0.2",
            "bound = true",
            vec![
                "line 44",
                "`contact.bound`",
                "bound = true",
                "expected contact.bound: a number g ≥ 0 (bound = 0.2) or an expression of x, y, z in quotes",
            ],
        ),
        (
            "bound = 0.2",
            "bound = [0.2]",
            vec![
                "line 44",
                "`contact.bound`",
                "bound = [0.2]",
                "contact.bound: a number g ≥ 0",
            ],
        ),
        (
            "\"von_mises\",",
            "\"speed\",",
            vec![
                "line 62",
                "`output.fields[2]`",
                "unknown variant `speed`",
                "`von_mises`",
            ],
        ),
        (
            "value = [\"0\", \"-0.1*(1 - exp(-2*t))*x*ny\"]",
            "value = [0, 1]",
            vec![
                "line 35",
                "`traction[0].value[0]`",
                "value = [0, 1]",
                "expected a string",
            ],
        ),
        ("steps = 32", "steps = = 32", vec!["TOML syntax error", "line 29"]),
    ] {
        let (msg, _) = scene_error(from, to);
        assert_contains(&msg, &parts);
    }
    let msg = override_error(&["time.steps=ten"]);
    assert_contains(&msg, &["--set time.steps=ten", "steps = \"ten\"", "expected usize"]);
}

#[test]
fn values_out_of_range_name_the_key_and_the_fix() {
    for (from, to, parts) in [
        (
            "youngs_modulus = 1.0",
            "youngs_modulus = 0.0",
            vec!["`material.youngs_modulus` = 0", "must be positive and finite"],
        ),
        (
            "youngs_modulus = 1.0",
            "youngs_modulus = -2.0",
            vec!["`material.youngs_modulus` = -2", "must be positive"],
        ),
        (
            "youngs_modulus = 1.0",
            "youngs_modulus = nan",
            vec!["`material.youngs_modulus` = NaN"],
        ),
        (
            "poisson_ratio = 0.3",
            "poisson_ratio = 0.5",
            vec!["`material.poisson_ratio` = 0.5", "must lie in (−1, 0.5)"],
        ),
        (
            "poisson_ratio = 0.3",
            "poisson_ratio = -1.0",
            vec!["`material.poisson_ratio` = -1", "(−1, 0.5)"],
        ),
        (
            "poisson_ratio = 0.3",
            "poisson_ratio = 0.7",
            vec!["`material.poisson_ratio` = 0.7"],
        ),
        (
            "final_time = 1.0",
            "final_time = 0.0",
            vec!["`time.final_time` = 0", "must be positive"],
        ),
        ("final_time = 1.0", "final_time = -1.0", vec!["`time.final_time` = -1"]),
        ("final_time = 1.0", "final_time = inf", vec!["`time.final_time` = inf"]),
        (
            "steps = 32",
            "steps = 0",
            vec!["`time.steps` = 0", "at least one time step"],
        ),
        (
            "bound = 0.2",
            "bound = -0.1",
            vec!["`contact.bound` = -0.1", "must be ≥ 0 (omit it for no bound)"],
        ),
        (
            "regularisation = 1e-8",
            "regularisation = 0.0",
            vec!["`contact.law.regularisation` = 0", "ε = 0 is not supported"],
        ),
        (
            "max_iterations = 100",
            "max_iterations = 0",
            vec!["`solver.max_iterations` = 0", "at least one iteration"],
        ),
    ] {
        let (msg, _) = scene_error(from, to);
        assert_contains(&msg, &parts);
    }
    assert_contains(&override_error(&["contact.bound=-1"]), &["`contact.bound` = -1"]);
}

#[test]
fn bad_expressions_name_the_key() {
    let traction = "value = [\"0\", \"-0.1*(1 - exp(-2*t))*x*ny\"]";
    for (expr, parts) in [
        (
            "-0.1*(1 - exp(-2*t)*x",
            vec!["column 22", "expected `)` to close the `(` of column 6"],
        ),
        ("2*/x", vec!["column 3", "expected a number, a variable"]),
        (
            "y > 0.99 ? 1 : 0",
            vec!["column 10", "`?` is not part of the language", "a if c else b"],
        ),
        ("1 if y > 0.99", vec!["column 14", "`if` needs an `else`"]),
        (
            "-0.1*(1 - exp(-2*t))*w",
            vec!["unknown variable `w`", "`x`, `y`, `z`, `t`, `nx`, `ny`, `nz`"],
        ),
        ("log(-5)", vec!["evaluates to NaN", "check divisions and logarithms"]),
        ("sqrt(-1)", vec!["evaluates to NaN"]),
        ("1/0", vec!["evaluates to inf"]),
        (
            "-x^2",
            vec!["column 1", "minus sign in front of a power is ambiguous", "-(x^2)"],
        ),
        ("", vec!["the expression is empty"]),
    ] {
        let (msg, _) = scene_error(traction, &format!("value = [\"0\", \"{expr}\"]"));
        assert_contains(&msg, &[&format!("`traction[0].value[1]` = \"{expr}\"")]);
        assert_contains(&msg, &parts);
    }
    let (msg, _) = scene_error(
        "kind = \"polynomial\"\ncoefficients = [0.25, 1.0, 1.0]",
        "kind = \"expression\"\nexpression = \"log(s-1)\"",
    );
    assert_contains(&msg, &["`memory.expression` = \"log(s-1)\"", "evaluates to NaN at s"]);
    // a bound expression: compiled when the scene is read (its values are checked at the nodes)
    for (expr, parts) in [
        ("0.2 + 0.02*sin(6*PI*w)", vec!["unknown variable `w`", "`x`, `y`, `z`"]),
        (
            "0.2 + (x",
            vec!["column 9", "expected `)` to close the `(` of column 7"],
        ),
        ("-x^2 + 1", vec!["column 1", "ambiguous"]),
        ("", vec!["the expression is empty"]),
    ] {
        let (msg, _) = scene_error("bound = 0.2", &format!("bound = \"{expr}\""));
        assert_contains(&msg, &[&format!("`contact.bound` = \"{expr}\"")]);
        assert_contains(&msg, &parts);
    }
    let msg = override_error(&["body_force.value=[\"0\", \"-x^2\"]"]);
    assert_contains(&msg, &["`body_force.value[1]` = \"-x^2\"", "ambiguous"]);
}

/// An expression that is finite at the probe point (0, 0, 0) but not on the body: the load is
/// NaN, and the run stops at step 0 with an error naming the key, the point and the time (no
/// panic, no hang, no frame).
#[test]
fn expression_that_is_nan_on_the_body_stops_the_run() {
    let case = Case::new("rect.msh", mesh_text("rect_q1_h8.msh").as_bytes());
    for (set, key) in [
        (
            "traction.0.value=[\"0\", \"log(1-x)\"]",
            "traction[0].value[1] = \"log(1-x)\"",
        ),
        (
            "body_force.value=[\"0\", \"sqrt(0.5-y)\"]",
            "body_force.value[1] = \"sqrt(0.5-y)\"",
        ),
    ] {
        let t0 = Instant::now();
        let (e, _) = case.error(&[set, "time.steps=4"]);
        assert!(t0.elapsed() < Duration::from_secs(5));
        assert!(matches!(e, SolveError::NonFiniteLoad { step: Some(0), .. }), "{e:?}");
        assert_contains(
            &e.to_string(),
            &["step 0", key, "is NaN at (x, y) = (", "make the expression finite"],
        );
        let files: Vec<String> = std::fs::read_dir(case.out())
            .unwrap()
            .map(|f| f.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(
            files
                .iter()
                .all(|f| !f.ends_with(".vtu") && !hvi::output::is_temporary_name(f)),
            "{files:?}"
        );
    }
}

/// A bound expression that is negative (or NaN) at a contact node: the run does not start, and
/// the message names the mesh, the key, the expression and the node's coordinates.
#[test]
fn a_bound_negative_at_a_node_names_the_node() {
    let case = Case::new("rect.msh", mesh_text("rect_q1_h8.msh").as_bytes());
    // Γ₃ is the bottom side y = 0, x ∈ [0, 2]: x − 1.5 < 0 first at the node (0, 0) or beyond
    for (set, parts) in [
        (
            "contact.bound=x - 1.5",
            vec![
                "contact.bound = \"x - 1.5\"",
                "at the contact node",
                "(x, y) = (",
                ", 0)",
                "≥ 0",
            ],
        ),
        ("contact.bound=sqrt(1 - x)", vec!["g = NaN", "(x, y) = (", "≥ 0"]),
    ] {
        let msg = case.message(&[set]);
        assert_contains(&msg, &parts);
        let cli = case.cli_message(&[set]);
        assert_contains(&cli, &parts);
    }
}

// ---------------------------------------------------------------------------------------------
// Output

/// The `file="…"` entries of a `.pvd`, in order.
fn pvd_files(pvd: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(pvd).unwrap();
    assert!(text.trim_end().ends_with("</VTKFile>"), "{text}");
    text.split("file=\"")
        .skip(1)
        .map(|s| s[..s.find('"').unwrap()].to_string())
        .collect()
}

/// The directory's `.vtu` files (sorted) and checks: no temporaries, every listed frame reads.
fn frames_on_disk(dir: &Path) -> Vec<String> {
    let mut vtu = Vec::new();
    for f in std::fs::read_dir(dir).unwrap() {
        let name = f.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            !hvi::output::is_temporary_name(&name) && !name.contains(".tmp."),
            "temporary file left: {name}"
        );
        if name.ends_with(".vtu") {
            vtu.push(name);
        }
    }
    vtu.sort();
    vtu
}

#[test]
fn unwritable_out_is_reported_before_solving() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a_file");
    std::fs::write(&file, "not a directory").unwrap();
    let out = file.join("run");
    let opts = SolveOptions {
        mesh: meshes().join("rect_q1_h8.msh"),
        scene: None,
        out: out.clone(),
        // a run that would take minutes: the error must come before it
        overrides: vec!["time.steps=10000000".into()],
        progress: false,
        overwrite: false,
        accept_mesh_defects: false,
    };
    let t0 = Instant::now();
    let e = solve(&opts, None).expect_err("an error");
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    assert_contains(
        &e.to_string(),
        &[
            &format!("cannot write to {}", out.display()),
            "a component of the path is a file, not a directory",
            "choose another --out directory",
        ],
    );
    let (code, stderr) = run_cli(&[
        "solve",
        meshes().join("rect_q1_h8.msh").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--set",
        "time.steps=10000000",
    ]);
    assert_eq!(code, 1);
    assert_contains(&stderr, &[&out.display().to_string(), "choose another --out directory"]);
    // nothing was written anywhere
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|f| f.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("a_file")]);
}

/// A contact solve that fails at a later step n (an iteration cap of 5 and a load ∝ t³: steps
/// 0 … 3 need at most 5 iterations, step 4 needs 18) leaves frames 0 … n − 1, a `.pvd` and a
/// `.vtu.series` listing exactly them, a `gamma3.csv` with their rows, no summary and no
/// temporary files.
#[test]
fn failure_at_step_n_leaves_frames_before_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let sets = [
        "solver.max_iterations=5",
        "time.steps=16",
        "traction.0.value=[\"0\", \"-0.2*t^3*x*ny\"]",
    ];
    let opts = SolveOptions {
        mesh: meshes().join("rect_q1_h8.msh"),
        scene: None,
        out: out.clone(),
        overrides: sets.map(String::from).to_vec(),
        progress: false,
        overwrite: false,
        accept_mesh_defects: false,
    };
    let e = solve(&opts, None).expect_err("the contact solve should fail");
    let SolveError::ContactFailed { step, iterations, .. } = e else {
        panic!("{e:?}")
    };
    assert!(step >= 2 && iterations == 5, "{e}");
    assert_contains(
        &e.to_string(),
        &[
            &format!("step {step}"),
            "no convergence in 5 iterations",
            "Try:",
            "solver.max_iterations",
        ],
    );
    let expected: Vec<String> = (0..step).map(|n| format!("solution_{n:05}.vtu")).collect();
    assert_eq!(frames_on_disk(&out), expected);
    assert_eq!(pvd_files(&out.join("solution.pvd")), expected);
    let series = std::fs::read_to_string(out.join("solution.vtu.series")).unwrap();
    let series: serde_json::Value = serde_json::from_str(&series).unwrap();
    let listed: Vec<&str> = series["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    assert_eq!(listed, expected);
    for f in &expected {
        hvi::output::read_vtu_arrays(&out.join(f)).unwrap_or_else(|e| panic!("{e}"));
    }
    let csv = std::fs::read_to_string(out.join("gamma3.csv")).unwrap();
    let times: std::collections::BTreeSet<String> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().to_string())
        .collect();
    assert_eq!(times.len(), step);
    // the summary of the stopped run says why and how far it got
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        summary["status"]
            .as_str()
            .unwrap()
            .starts_with("failed: contact solve failed"),
        "{summary}"
    );
    assert_eq!(summary["steps_done"], step);

    // the binary: exit code 1, the same message
    let out2 = dir.path().join("run2");
    let mut args: Vec<String> = vec![
        "solve".into(),
        meshes().join("rect_q1_h8.msh").to_str().unwrap().to_string(),
        "--out".into(),
        out2.to_str().unwrap().to_string(),
        "--quiet".into(),
    ];
    for s in sets {
        args.push("--set".into());
        args.push(s.into());
    }
    let (code, stderr) = run_cli(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 1);
    assert_contains(&stderr, &[&format!("contact solve failed at step {step}")]);
    assert_eq!(pvd_files(&out2.join("solution.pvd")), expected);
    assert_eq!(frames_on_disk(&out2), expected);
}

/// SIGINT stops a run between steps: exit code 130, and the frames on disk are exactly those
/// the `.pvd` lists.
#[test]
fn sigint_leaves_a_valid_series() {
    stop_with_signal("INT");
}

/// SIGTERM (what `timeout` and a batch scheduler send) and SIGHUP (a closed terminal) stop a run
/// as SIGINT does (issue 23): between steps, with the interrupted summary and no temporary left.
#[test]
fn sigterm_and_sighup_stop_like_sigint() {
    stop_with_signal("TERM");
    stop_with_signal("HUP");
}

/// Starts a long run, sends `signal` once two frames are listed, and checks the stop: exit code
/// 130, the series valid, summary.json's status "interrupted", no temporary file.
fn stop_with_signal(signal: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut child = hvi()
        .args([
            "solve",
            meshes().join("rect_q1_h8.msh").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .args(["--set", "time.steps=50000000", "--set", "output.every=20000"])
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    // wait until two frames are listed
    while pvd_count(&out) < 2 {
        assert!(t0.elapsed() < Duration::from_secs(60), "no frames written");
        if let Some(status) = child.try_wait().unwrap() {
            panic!("hvi stopped early: {status}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args([&format!("-{signal}"), &pid])
        .status()
        .unwrap()
        .success());
    let t1 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t1.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("hvi did not stop within 30 s of SIG{signal}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(130), "SIG{signal}: {stderr}");
    assert_contains(&stderr, &["interrupted", "valid"]);
    let on_disk = frames_on_disk(&out);
    assert!(on_disk.len() >= 2);
    assert_eq!(pvd_files(&out.join("solution.pvd")), on_disk);
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary.json written");
    assert_contains(&summary, &["\"status\": \"interrupted\""]);
    let temporaries: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| hvi::output::is_temporary_name(n))
        .collect();
    assert!(temporaries.is_empty(), "SIG{signal} left {temporaries:?}");
}

fn pvd_count(out: &Path) -> usize {
    std::fs::read_to_string(out.join("solution.pvd")).map_or(0, |t| t.matches("file=\"").count())
}

// ---------------------------------------------------------------------------------------------
// Mutated input never panics

/// One edit of a byte string.
#[derive(Clone, Debug)]
enum Edit {
    Set(usize, u8),
    Delete(usize, usize),
    Insert(usize, Vec<u8>),
    DuplicateLine(usize),
    Truncate(usize),
}

fn apply(bytes: &mut Vec<u8>, edit: &Edit) {
    let n = bytes.len().max(1);
    match edit {
        Edit::Set(i, b) => {
            if !bytes.is_empty() {
                let i = i % n;
                bytes[i] = *b;
            }
        }
        Edit::Delete(i, len) => {
            let i = i % n;
            let end = (i + len).min(bytes.len());
            if i < end {
                bytes.drain(i..end);
            }
        }
        Edit::Insert(i, b) => {
            let i = (i % n).min(bytes.len());
            bytes.splice(i..i, b.iter().copied());
        }
        Edit::DuplicateLine(i) => {
            let i = (i % n).min(bytes.len());
            let start = bytes[..i].iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
            let end = bytes[i..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(bytes.len(), |p| i + p + 1);
            let line = bytes[start..end].to_vec();
            bytes.splice(start..start, line);
        }
        Edit::Truncate(i) => {
            let i = i % n;
            bytes.truncate(i);
        }
    }
}

/// Tokens that make interesting nonsense in an MSH or TOML file.
const TOKENS: &[&str] = &[
    "0",
    "-1",
    "1000000000000",
    "18446744073709551616",
    "nan",
    "inf",
    "1e999",
    "$EndNodes",
    "$Elements",
    "$EndElements",
    "$Nodes",
    "$PhysicalNames",
    "\"",
    "\n",
    " ",
    "[",
    "]",
    "=",
    "-x^2",
    "log(",
    "2^3^4",
    "{}",
    "[[traction]]",
    "kind = \"power\"",
    "bound = \"x - 1\"",
    "pressure = \"1\"",
    "value = [\"0\", \"0\"]",
    " if ",
    " else ",
    "&&",
    "<=",
    "!",
    "min(1, ",
    "[[contact]]",
    "group = \"Gamma2\"",
    "direction = \"body\"",
    "obstacle = { kind = \"sphere\" }",
    "kind = \"circle\"",
    "radius = -1",
    "normal = [0.0, 0.0]",
    "motion = [\"t\"]",
    "sdf = \"1\"",
    "radius = 1e-300",
    "group = 3.5",
    "group = 99999999999",
    "normal = [1e300, 1e300]",
    "[[memory]]",
    "tensor = \"elasticity\"",
    "tensor = { bulk = 1.0, shear = 0.0 }",
    "plane = \"stress\"",
    "relaxation_modulus = { bulk = { long_term = 1.0 }, shear = { long_term = 0.0 } }",
    "modulus = -1",
    "long_term = 0",
    "#",
    "é",
    "\r\n",
];

fn edit_strategy() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Set(i, b)),
        2 => (any::<usize>(), 1usize..64).prop_map(|(i, l)| Edit::Delete(i, l)),
        3 => (any::<usize>(), 0..TOKENS.len()).prop_map(|(i, t)| Edit::Insert(i, TOKENS[t].as_bytes().to_vec())),
        1 => any::<usize>().prop_map(Edit::DuplicateLine),
        1 => any::<usize>().prop_map(Edit::Truncate),
    ]
}

/// The digit-changing edit most likely to give a valid-looking but wrong count or tag.
fn digit_strategy() -> impl Strategy<Value = Edit> {
    (any::<usize>(), 0u8..10).prop_map(|(i, d)| Edit::Set(i, b'0' + d))
}

fn msh_bases() -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("rect_q1_h8.msh", mesh_bytes("rect_q1_h8.msh")),
        ("rect_q1_h16_bin.msh", mesh_bytes("rect_q1_h16_bin.msh")),
        ("rect_q1_h16_v22.msh", mesh_bytes("rect_q1_h16_v22.msh")),
        ("rect_mixed_h4.msh", mesh_bytes("rect_mixed_h4.msh")),
        ("small_v22.msh", msh22(&small()).into_bytes()),
    ]
}

fn scene_bases() -> Vec<String> {
    let law = DEFAULT_SCENE_TOML.find("[contact.law]").unwrap();
    let solver = DEFAULT_SCENE_TOML.find("[solver]").unwrap();
    let memory = DEFAULT_SCENE_TOML.find("[memory]").unwrap();
    let time = DEFAULT_SCENE_TOML.find("[time]").unwrap();
    vec![
        DEFAULT_SCENE_TOML.to_string(),
        format!(
            "{}[contact.law]\nkind = \"piecewise_linear\"\nscale = 0.1\ntable = [[0.0, 0.04], [0.02, 0.01], [0.05, 0.05]]\none_sided = true\n{}",
            &DEFAULT_SCENE_TOML[..law],
            &DEFAULT_SCENE_TOML[solver..]
        ),
        format!(
            "{}[memory]\nkind = \"exponential\"\nterms = [{{ coefficient = 1.0, relaxation_time = 0.1 }}]\n{}",
            &DEFAULT_SCENE_TOML[..memory],
            &DEFAULT_SCENE_TOML[time..]
        ),
        "[material]\nplane = \"strain\"\nyoungs_modulus = 2e11\npoisson_ratio = 0.25\n[time]\nfinal_time = 2.0\nsteps = 4\n[body_force]\nvalue = [\"0\", \"-(x^2)*exp(-t)\"]\n[contact]\nbound = 0.0\n[output]\ncompress = 3\nactive_scalar = \"displacement\"\n".to_string(),
        DEFAULT_SCENE_TOML.replacen("bound = 0.2", "bound = \"0.2 + 0.02*sin(6*PI*x) + 0.01*sqrt(1.5 - y)\"", 1),
        // a pressure with a conditional, comparisons and logic (README "Expression language")
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 2\n\
         [[traction]]\ngroup = \"Gamma2\"\npressure = \"0.1*t if x > 1.5 && !(y < 0.5) || nx == 1 else min(1, max(x, 0.5))*ny\"\n\
         [[traction]]\ngroup = \"Gamma3\"\nvalue = [\"(y <= 0.5) * 2\", \"0\"]\n".to_string(),
        // two contact groups with rigid obstacles (plane, circle, signed distance), both
        // directions, a moving obstacle and a layer over an obstacle (docs/method.md §14)
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 2\n\
         [groups]\nclamped = \"Gamma1\"\n\
         [[contact]]\ngroup = \"Gamma3\"\nobstacle = { kind = \"plane\", point = [0.0, -0.01], normal = [0.0, 1.0] }\n\
         [[contact]]\ngroup = \"Gamma2\"\ndirection = \"body\"\nbound = 0.1\n\
         obstacle = { kind = \"circle\", centre = [2.5, 0.5], radius = 0.4, motion = [\"-0.1*t\", \"0\"] }\n\
         [contact.law]\nkind = \"power\"\nscale = 1.0\nexponent = 1.0\n".to_string(),
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 2\n\
         [contact]\ndirection = \"obstacle\"\nobstacle = { kind = \"sdf\", sdf = \"y + 0.02 - 0.1*(x - 1)^2\" }\n".to_string(),
        // an interference fit (a plane 0.01 into the bottom), a group by its tag, a moving signed
        // distance with a law and a layer, and a ball (docs/method.md §14.6–14.7)
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 2\n\
         [[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\", \"y\"]\n\
         [[contact]]\ngroup = 3\nobstacle = { kind = \"plane\", point = [0.0, 0.01], normal = [0.0, 1.0] }\n\
         [[contact]]\ngroup = \"Gamma2_top\"\nbound = 0.01\n\
         obstacle = { kind = \"sdf\", sdf = \"1.05 - y\", motion = [\"0\", \"-0.1*t\"] }\n\
         [contact.law]\nkind = \"power\"\nscale = 2.0\nexponent = 1.5\n\
         [[contact]]\ngroup = \"Gamma2\"\nobstacle = { kind = \"circle\", centre = [3.0, 0.5], radius = 0.9 }\n".to_string(),
        // a relaxation modulus (docs/method.md §15.2): bulk and shear Prony series, two channels
        format!(
            "[material]\nplane = \"strain\"\n\
             relaxation_modulus = {{ bulk = {{ long_term = 1.0, terms = [{{ modulus = 0.5, relaxation_time = 0.3 }}] }}, \
             shear = {{ long_term = 0.2, terms = [{{ modulus = 0.4, relaxation_time = 0.2 }}, {{ modulus = 0.1, relaxation_time = 2.0 }}] }} }}\n{}",
            &DEFAULT_SCENE_TOML[time..]
        ),
        // memory terms with their own tensors (docs/method.md §15.1)
        format!(
            "{}[[memory]]\nkind = \"exponential\"\nterms = [{{ coefficient = -1.0, relaxation_time = 0.5 }}]\ntensor = {{ bulk = 1.0, shear = 0.3 }}\n\
             [[memory]]\nkind = \"polynomial\"\ncoefficients = [0.25, 1.0]\ntensor = \"elasticity\"\n\
             [[memory]]\nkind = \"expression\"\nexpression = \"0.1/(1 + s)\"\ntensor = \"identity\"\n{}",
            DEFAULT_SCENE_TOML[..memory].replacen("plane = \"stress\"", "plane = \"strain\"", 1),
            &DEFAULT_SCENE_TOML[time..]
        ),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Mutated MSH files (ASCII 4.1, binary 4.1, 2.2, mixed cells): an error or a mesh, never a
    /// panic; a mesh that reads has finite points and cells that refer to them.
    #[test]
    fn mutated_msh_files_never_panic(
        base in 0usize..5,
        edits in proptest::collection::vec(prop_oneof![3 => edit_strategy(), 2 => digit_strategy()], 1..8),
    ) {
        let bases = msh_bases();
        let (name, mut bytes) = bases[base].clone();
        for e in &edits {
            apply(&mut bytes, e);
        }
        match parse_mesh::<2>(Path::new(name), &bytes) {
            Ok(mesh) => {
                prop_assert!(mesh.points.iter().all(|p| p[0].is_finite() && p[1].is_finite()));
                prop_assert!(mesh.cells.iter().all(|c| c.nodes().iter().all(|&p| p < mesh.points.len())));
                // asking for the groups never panics either
                for g in ["Gamma1", "Gamma3", "Gamma2_top"] {
                    let _ = mesh.boundary(&g.into());
                    let _ = mesh.group_nodes(&g.into());
                }
            }
            Err(e) => prop_assert!(e.to_string().contains(name)),
        }
    }
}

/// Every unmutated base of the scene fuzz is a valid scene that builds a simulation on the
/// small mesh, so the mutations start from the sections they are meant to exercise.
#[test]
fn the_fuzzed_scene_bases_are_valid() {
    for (i, text) in scene_bases().iter().enumerate() {
        let scene = Scene::from_toml_str(text, "base.toml").unwrap_or_else(|e| panic!("base {i}: {e}"));
        if let Err(e) = Simulation::new(&scene, small()) {
            panic!("base {i}: {e}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, failure_persistence: None, ..ProptestConfig::default() })]

    /// Mutated scene text: an error naming the origin, or a valid scene that a simulation can
    /// be built from on a small mesh (without solving), never a panic.
    #[test]
    fn mutated_scenes_never_panic(
        base in 0usize..11,
        edits in proptest::collection::vec(edit_strategy(), 1..6),
    ) {
        let bases = scene_bases();
        let mut bytes = bases[base].clone().into_bytes();
        for e in &edits {
            apply(&mut bytes, e);
        }
        let text = String::from_utf8_lossy(&bytes);
        match Scene::from_toml_str(&text, "mutated.toml") {
            Ok(scene) => {
                prop_assert!(scene.material.youngs_modulus.is_none_or(|e| e > 0.0) && scene.time.steps.is_some_and(|n| n > 0));
                let _ = Simulation::new(&scene, small());
            }
            Err(e) => prop_assert!(e.to_string().contains("mutated.toml"), "{}", e),
        }
    }
}

/// A well-held body whose material is incompressible to ten digits (ν = 1 − 10⁻¹⁰, K/G = 5·10⁹)
/// makes K ill-conditioned by the material, not by the supports: the refusal names the material
/// and its K/G before the supports (it blamed the supports alone before).
#[test]
fn an_incompressible_material_is_named_when_the_matrix_is_singular() {
    let scene = Scene::load(
        None,
        &[
            "material.plane=\"strain\"".to_string(),
            "material.poisson_ratio=0.4999999999".to_string(),
        ],
    )
    .unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/rect_q1_h32.msh");
    let mesh = hvi::mesh::read_mesh::<2>(&path).unwrap();
    let e = solve_in_memory(&scene, mesh)
        .err()
        .expect("a matrix singular to the probe");
    let text = e.to_string();
    assert_contains(
        &text,
        &[
            "rect_q1_h32.msh",
            "nearly incompressible",
            "K/G = 5.000e9",
            "ν = 0.4999999999",
        ],
    );
    let material = text.find("nearly incompressible").unwrap();
    let supports = text.find("not held").unwrap();
    assert!(material < supports, "{text}");
}
