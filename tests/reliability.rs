//! Issue 23: nothing lost, nothing silently wrong. Two runs into one output folder, groups that
//! are not faces of the mesh, broken meshes, non-finite results, values compared by value.

mod common;
use common::{msh22, scene};

use hvi::mesh::structured::{block, rectangle, CellShape, SolidShape};
use hvi::mesh::{Cell, Facet, Mesh, PhysicalGroup};
use hvi::solver::{Simulation, SolveError};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes")
}

fn hvi() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hvi"))
}

/// `hvi solve MESH --out OUT --quiet`, to add arguments to.
fn hvi_solve(mesh: &Path, out: &Path) -> Command {
    let mut c = hvi();
    c.args([
        "solve",
        mesh.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    c
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn assert_contains(msg: &str, parts: &[&str]) {
    for p in parts {
        assert!(msg.contains(p), "expected {p:?} in:\n{msg}");
    }
}

/// The `file="…"` entries and times of a `.pvd`.
fn pvd_entries(pvd: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(pvd).unwrap();
    text.lines()
        .filter(|l| l.contains("<DataSet"))
        .map(|l| {
            let attr = |name: &str| {
                let s = &l[l.find(&format!("{name}=\"")).unwrap() + name.len() + 2..];
                s[..s.find('"').unwrap()].to_string()
            };
            (attr("timestep").parse().unwrap(), attr("file"))
        })
        .collect()
}

/// Every frame the `.pvd` lists holds the time the `.pvd` gives it (the frames are one run's).
fn assert_series_consistent(out: &Path) {
    let entries = pvd_entries(&out.join("solution.pvd"));
    assert!(!entries.is_empty());
    for (t, file) in entries {
        let contents = hvi::output::read_vtu_arrays(&out.join(&file)).unwrap();
        let time = contents.field_data["TimeValue"].1[0];
        assert_eq!(time, t, "{file} holds t = {time} but solution.pvd says {t}");
    }
}

// ---------------------------------------------------------------------------------------------
// One run per output folder

/// A run into a folder whose lock another process holds is refused, naming that process, and
/// writes nothing; once the holder is gone the folder is free.
#[test]
fn a_held_output_folder_is_refused_naming_the_holder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    std::fs::create_dir_all(&out).unwrap();
    let lock = hvi::output::RunLock::acquire(&out).unwrap();
    let mesh = meshes().join("rect_q1_h8.msh");
    let run = |extra: &[&str]| hvi_solve(&mesh, &out).args(extra).output().unwrap();
    for extra in [&[][..], &["--overwrite"][..]] {
        let o = run(extra);
        assert!(!o.status.success(), "{}", text(&o));
        assert_contains(
            &text(&o),
            &[&format!("process {}", std::process::id()), "choose another --out"],
        );
        let files: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(files.is_empty(), "{extra:?} wrote {files:?}");
    }
    drop(lock);
    let o = run(&[]);
    assert!(o.status.success(), "{}", text(&o));
    assert_series_consistent(&out);
}

/// Two runs started together into one folder (both released at once): exactly one succeeds,
/// the other is refused, and the folder holds one run's consistent files; and `--overwrite`
/// while a run is still writing is refused, naming the running process.
#[test]
fn two_runs_into_one_folder_never_mix() {
    let mesh = meshes().join("rect_q1_h8.msh");
    for trial in 0..4 {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        let go = dir.path().join("go");
        // each child waits for the file `go` (a barrier both are released from together)
        let spawn = |steps: &str| {
            Command::new("sh")
                .arg("-c")
                .arg(format!(
                    "while [ ! -e '{}' ]; do sleep 0.005; done; exec '{}' solve '{}' --out '{}' --quiet --set time.steps={steps} --set output.every=1",
                    go.display(),
                    env!("CARGO_BIN_EXE_hvi"),
                    mesh.display(),
                    out.display()
                ))
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (spawn("40"), spawn("64"));
        std::thread::sleep(Duration::from_millis(50));
        std::fs::write(&go, "").unwrap();
        let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
        let ok = [a.status.success(), b.status.success()];
        assert_eq!(
            ok.iter().filter(|&&s| s).count(),
            1,
            "trial {trial}: exactly one run may succeed:\n{}\n{}",
            text(&a),
            text(&b)
        );
        let loser = if ok[0] { &b } else { &a };
        let msg = text(loser);
        assert!(
            msg.contains("is writing into it") || msg.contains("holds an earlier hvi run"),
            "trial {trial}: {msg}"
        );
        assert_series_consistent(&out);
        let steps = if ok[0] { 40 } else { 64 };
        assert_eq!(pvd_entries(&out.join("solution.pvd")).len(), steps + 1);
    }

    // --overwrite into a folder a run is still writing
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut first = hvi_solve(&mesh, &out)
        .args(["--set", "time.steps=50000000", "--set", "output.every=20000"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !out.join("solution.pvd").exists() {
        assert!(t0.elapsed() < Duration::from_secs(60), "the first run wrote nothing");
        std::thread::sleep(Duration::from_millis(20));
    }
    let second = hvi_solve(&mesh, &out).arg("--overwrite").output().unwrap();
    let still_running = first.try_wait().unwrap().is_none();
    let _ = first.kill();
    let _ = first.wait();
    assert!(still_running);
    assert!(!second.status.success(), "{}", text(&second));
    assert_contains(
        &text(&second),
        &[&format!("process {}", first.id()), "is writing into it"],
    );
}

// ---------------------------------------------------------------------------------------------
// Every group the scene prescribes displacements on is on the boundary

fn group(dim: u8, tag: i32, name: &str, facets: Vec<Facet>, nodes: Vec<usize>) -> PhysicalGroup {
    PhysicalGroup {
        dim,
        tag,
        name: Some(name.into()),
        facets,
        cells: Vec::new(),
        nodes,
    }
}

fn node_at<const D: usize>(m: &Mesh<D>, x: [f64; D]) -> usize {
    m.points.iter().position(|p| p == &x).unwrap()
}

const FIXED_LEFT: &str = r#"
[material]
plane = "strain"
youngs_modulus = 1.0
poisson_ratio = 0.3
[time]
final_time = 1.0
steps = 1
[groups]
clamped = "Gamma1"
[[traction]]
group = "Gamma2_top"
value = ["0", "-0.01"]
"#;

/// A clamped group or a `[[dirichlet]]` group whose edge is not an edge of any cell, lies inside
/// the body, or whose point is inside, is refused naming the group and the place (it used to
/// clamp nodes elsewhere without a word).
#[test]
fn prescribed_groups_must_be_on_the_boundary() {
    let base = rectangle(2.0, 1.0, 4, 2, CellShape::Quad);
    let (a, b, c) = (
        node_at(&base, [0.0, 0.0]),
        node_at(&base, [0.5, 0.5]),
        node_at(&base, [1.0, 0.5]),
    );
    let bottom_left = node_at(&base, [0.5, 0.0]);
    let cases: Vec<(PhysicalGroup, &str)> = vec![
        // a diagonal of a cell: not an edge of any cell
        (
            group(1, 7, "Bad", vec![Facet::from([a, b])], vec![]),
            "is not an edge of any cell",
        ),
        // an edge inside the body, shared by two cells
        (
            group(1, 7, "Bad", vec![Facet::from([b, c])], vec![]),
            "shared by 2 cells",
        ),
        // a point inside the body
        (group(0, 7, "Bad", vec![], vec![b]), "is not a node of the boundary"),
    ];
    for (bad, expected) in cases {
        for how in ["clamped", "dirichlet"] {
            let mut m = base.clone();
            m.groups.push(bad.clone());
            let mut toml = FIXED_LEFT.to_string();
            if how == "clamped" {
                toml = toml.replace("clamped = \"Gamma1\"", "clamped = \"Bad\"");
            } else {
                toml.push_str("[[dirichlet]]\ngroup = \"Bad\"\ncomponents = [\"x\"]\nvalue = [\"0.01\"]\n");
            }
            let e = Simulation::new(&scene(&toml), m).map(|_| ()).unwrap_err();
            let msg = e.to_string();
            assert!(matches!(e, SolveError::Group { .. }), "{how}: {e:?}");
            for part in ["Bad (tag 7)", "not on the boundary", expected] {
                assert!(msg.contains(part), "{how}: expected {part:?} in {msg}");
            }
        }
    }
    // the same groups on the boundary are accepted: a boundary edge, a corner point
    let mut m = base.clone();
    m.groups
        .push(group(1, 7, "Edge", vec![Facet::from([a, bottom_left])], vec![]));
    m.groups.push(group(0, 8, "Corner", vec![], vec![a]));
    let toml = format!(
        "{FIXED_LEFT}[[dirichlet]]\ngroup = \"Edge\"\ncomponents = [\"y\"]\n[[dirichlet]]\ngroup = \"Corner\"\ncomponents = [\"x\"]\n"
    );
    Simulation::new(&scene(&toml), m)
        .map(|_| ())
        .unwrap_or_else(|e| panic!("{e}"));

    // 3D: a face inside the block, an edge through it, a point inside
    let base = block([2.0, 1.0, 1.0], [2, 2, 2], SolidShape::Hex);
    let mid = |x: [f64; 3]| node_at(&base, x);
    let inner_face = Facet::from([
        mid([1.0, 0.0, 0.0]),
        mid([1.0, 0.5, 0.0]),
        mid([1.0, 0.5, 0.5]),
        mid([1.0, 0.0, 0.5]),
    ]);
    let cases: Vec<(PhysicalGroup, &str)> = vec![
        (group(2, 7, "Bad", vec![inner_face], vec![]), "shared by 2 cells"),
        (
            group(
                1,
                7,
                "Bad",
                vec![Facet::from([mid([0.0, 0.0, 0.0]), mid([1.0, 0.5, 0.5])])],
                vec![],
            ),
            "is not an edge of a boundary face",
        ),
        (
            group(0, 7, "Bad", vec![], vec![mid([1.0, 0.5, 0.5])]),
            "is not a node of the boundary",
        ),
    ];
    for (bad, expected) in cases {
        let mut m = base.clone();
        m.groups.push(bad);
        let toml = FIXED_LEFT.replace("clamped = \"Gamma1\"", "clamped = \"Bad\"");
        let msg = Simulation::new(&scene(&toml), m).map(|_| ()).unwrap_err().to_string();
        assert!(msg.contains(expected), "expected {expected:?} in {msg}");
    }
}

// ---------------------------------------------------------------------------------------------
// Meshes that are not one conforming body

fn write_mesh(dir: &Path, name: &str, m: &Mesh<2>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, msh22(m)).unwrap();
    p
}

/// The paper's rectangle with the node (1, 0.5) duplicated for the cells right of x = 1: a crack.
fn cracked() -> Mesh<2> {
    let mut m = rectangle(2.0, 1.0, 8, 4, CellShape::Quad);
    let mid = node_at(&m, [1.0, 0.5]);
    m.points.push([1.0, 0.5]);
    let dup = m.points.len() - 1;
    let points = m.points.clone();
    for c in &mut m.cells {
        if let Cell::Quad4(n) = c {
            if n.iter().all(|&p| points[p][0] >= 1.0) {
                n.iter_mut().filter(|p| **p == mid).for_each(|p| *p = dup);
            }
        }
    }
    m
}

/// `hvi solve` and `hvi check` refuse a cracked mesh, naming the place and the flag; with
/// `--accept-mesh-defects` the run goes on and says why in a warning (also in summary.json).
#[test]
fn a_cracked_mesh_is_refused_unless_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_mesh(dir.path(), "cracked.msh", &cracked());
    let out = dir.path().join("run");
    let o = hvi_solve(&mesh, &out).output().unwrap();
    assert!(!o.status.success());
    assert_contains(
        &text(&o),
        &[
            "cracked.msh",
            "not one conforming body",
            "coincide",
            "(1.0, 0.5)",
            "--accept-mesh-defects",
        ],
    );
    assert!(!out.join("solution.pvd").exists());
    let o = hvi().args(["check", mesh.to_str().unwrap()]).output().unwrap();
    assert!(!o.status.success());
    assert_contains(&text(&o), &["coincide"]);
    let o = hvi_solve(&mesh, &out).arg("--accept-mesh-defects").output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert_contains(&String::from_utf8_lossy(&o.stderr), &["warning:", "coincide"]);
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert_contains(&summary, &["\"warnings\"", "coincide"]);
}

/// A body that starts inside its obstacle: `hvi solve` says so before running, as `hvi check`
/// does (it used to push the body out without a word).
#[test]
fn solve_prints_the_warnings_of_check() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("inside.toml");
    // the rectangle on rollers, its top 0.01 into a rigid plane (tests/contact_groups.rs)
    std::fs::write(
        &scene_path,
        "[material]\nplane = \"strain\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 1\n\
         [[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"y\"]\n[[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\"]\n\
         [[contact]]\ngroup = \"Gamma2_top\"\nobstacle = { kind = \"plane\", point = [0.0, 0.99], normal = [0.0, -1.0] }\n",
    )
    .unwrap();
    let mesh = meshes().join("rect_q1_h8.msh");
    let check = hvi()
        .args(["check", mesh.to_str().unwrap(), "--scene", scene_path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(check.status.success(), "{}", text(&check));
    let warning = String::from_utf8_lossy(&check.stdout)
        .lines()
        .find(|l| l.starts_with("warning:") && l.contains("start inside its obstacle"))
        .unwrap_or_else(|| panic!("check did not warn: {}", text(&check)))
        .to_string();
    let out = dir.path().join("run");
    let o = hvi()
        .args(["solve", mesh.to_str().unwrap(), "--scene", scene_path.to_str().unwrap()])
        .args(["--out", out.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains(&warning), "{}", text(&o));
}

// ---------------------------------------------------------------------------------------------
// Non-finite results and data

/// A load of 1e300 overflows the stress: the run fails (it used to exit 0 with `inf` in the
/// frames), naming the step and what overflowed.
#[test]
fn a_result_that_overflows_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mesh = meshes().join("rect_q1_h8.msh");
    let o = hvi_solve(&mesh, &out)
        .args(["--set", "traction.0.value=[\"0\", \"-1e300\"]", "--set", "time.steps=2"])
        .output()
        .unwrap();
    assert!(!o.status.success(), "{}", text(&o));
    assert_contains(&text(&o), &["non-finite", "overflow double precision", "moderate"]);
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert_contains(&summary, &["\"status\": \"failed: step"]);
}

/// A traction that is NaN on part of its group, from t = 0.5 on: `hvi check` refuses it, and
/// `hvi solve` stops before factorising (no frame written), naming the key, the point and t.
#[test]
fn a_load_nan_on_part_of_its_group_is_found_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = meshes().join("rect_q1_h8.msh");
    let set = "traction.0.value=[\"0\", \"sqrt(x - 1) if t > 0.5 else 0\"]";
    let o = hvi()
        .args(["check", mesh.to_str().unwrap(), "--set", set, "--set", "time.steps=40"])
        .output()
        .unwrap();
    assert!(!o.status.success(), "{}", text(&o));
    assert_contains(&text(&o), &["traction[0].value[1]", "is NaN at (x, y) = (", "t = 0."]);
    let out = dir.path().join("run");
    let o = hvi_solve(&mesh, &out)
        .args(["--set", set, "--set", "time.steps=40"])
        .output()
        .unwrap();
    assert!(!o.status.success(), "{}", text(&o));
    assert_contains(&text(&o), &["traction[0].value[1]", "is NaN"]);
    let frames = std::fs::read_dir(&out)
        .map(|d| {
            d.filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "vtu"))
                .count()
        })
        .unwrap_or(0);
    assert_eq!(frames, 0, "frames were written before the NaN was found");
}

/// `[[dirichlet]]` sections that give shared nodes the same value in different words ("0.0" and
/// "0", "0.01*x" and "0" at x = 0) are no conflict; different values are, naming both.
#[test]
fn dirichlet_values_are_compared_by_value() {
    let m = rectangle(2.0, 1.0, 4, 2, CellShape::Quad);
    let base = FIXED_LEFT.replace("clamped = \"Gamma1\"", "");
    let two = |a: &str, b: &str| {
        format!(
            "{base}[[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\", \"y\"]\nvalue = [\"{a}\", \"0\"]\n\
             [[dirichlet]]\ngroup = \"Gamma3\"\ncomponents = [\"x\"]\nvalue = [\"{b}\"]\n"
        )
    };
    for (a, b) in [("0.0", "0"), ("0.01*x", "0"), ("t*x", "0*t")] {
        Simulation::new(&scene(&two(a, b)), m.clone()).unwrap_or_else(|e| panic!("{a} vs {b}: {e}"));
    }
    let msg = Simulation::new(&scene(&two("0.01", "0")), m.clone())
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_contains(
        &msg,
        &["prescribed by dirichlet[0]", "\"0.01\"", "dirichlet[1]", "(0.0, 0.0)"],
    );
    let msg = Simulation::new(&scene(&two("0.01*t", "0")), m)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert_contains(&msg, &["\"0.01*t\"", "t = "]);
}

// ---------------------------------------------------------------------------------------------
// Memory

/// `hvi` under an address-space cap (`ulimit -v`, setrlimit in the test's child): the command,
/// its exit status, and everything it printed. glibc reserves 64 MiB of address space for each
/// thread's malloc arena — counted by `ulimit -v`, never used — and on a loaded machine rayon's
/// workers open theirs at different moments, so the first allocation to fail moved between runs
/// (measured: 2 of 6 concurrent runs failed before the prediction, and with 2 arenas the test
/// still failed once in 4); one arena keeps the reservations fixed (6 of 6 reached it).
fn capped(kib: u64, args: &[&str], env: &[(&str, &str)]) -> (Option<i32>, String) {
    let quoted: Vec<String> = args.iter().map(|a| format!("'{a}'")).collect();
    let mut cmd = Command::new("sh");
    cmd.env("MALLOC_ARENA_MAX", "1");
    cmd.arg("-c").arg(format!(
        "ulimit -v {kib} && exec '{}' {}",
        env!("CARGO_BIN_EXE_hvi"),
        quoted.join(" ")
    ));
    for (k, v) in env {
        cmd.env(k, v);
    }
    let o = cmd.output().unwrap();
    (o.status.code(), text(&o))
}

/// Under a memory cap a run whose predicted peak does not fit is refused before the
/// factorisation, naming the prediction, the limit and the remedies; `hvi check` says the same;
/// and when the refusal is overridden the allocation that fails ends the run with a message and
/// summary.json, never a panic (exit code 101) or an abort (134).
#[test]
fn a_run_that_does_not_fit_ends_with_a_message_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let slab = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/slab.toml");
    let solve = [
        "solve",
        "box:64x32x8",
        "--scene",
        slab.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    // the run's predicted peak is ≈ 480 MiB (README "When the solver struggles")
    let (code, msg) = capped(350_000, &solve, &[]);
    assert_eq!(code, Some(1), "{msg}");
    assert_contains(
        &msg,
        &[
            "out of memory",
            "the run needs about",
            "factor",
            "ulimit -v is",
            "coarser mesh",
            "--backend petsc",
        ],
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert_contains(&summary, &["\"status\": \"failed: out of memory"]);

    let (code, msg) = capped(
        350_000,
        &["check", "box:64x32x8", "--scene", slab.to_str().unwrap()],
        &[],
    );
    assert_eq!(code, Some(1), "{msg}");
    assert_contains(&msg, &["out of memory"]);
    assert!(!msg.contains("panicked"), "{msg}");

    // the refusal overridden: at two caps the failure comes at different places (assembly,
    // factorisation), each ends cleanly
    for cap in [150_000, 350_000] {
        std::fs::remove_dir_all(&out).unwrap();
        let (code, msg) = capped(cap, &solve, &[("HVI_IGNORE_MEMORY_ESTIMATE", "1")]);
        assert_eq!(code, Some(1), "cap {cap} KiB: {msg}");
        assert_contains(&msg, &["error:", "out of memory"]);
        assert!(
            !msg.contains("panicked") && !msg.contains("memory allocation of"),
            "{msg}"
        );
        let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
        assert_contains(&summary, &["\"status\": \"failed:", "out of memory"]);
        let left: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }
}

/// The predicted peak (summary.json's `predicted_peak_bytes`, what `hvi check` prints and a run
/// is refused by) is within 30 % of the measured peak (VmHWM) on a 2D and a 3D run with
/// contact and memory (README "When the solver struggles" lists the larger cases).
#[test]
fn the_predicted_peak_is_within_30_percent_of_the_measured_one() {
    let dir = tempfile::tempdir().unwrap();
    let slab = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/slab.toml");
    for (mesh, extra) in [
        ("rect:256x128", vec!["--set", "time.steps=16"]),
        (
            "box:48x24x6",
            vec!["--scene", slab.to_str().unwrap(), "--set", "time.steps=8"],
        ),
    ] {
        let out = dir.path().join(mesh.replace(':', "_"));
        let o = hvi()
            .args(["solve", mesh, "--quiet", "--out", out.to_str().unwrap()])
            .args(&extra)
            .args(["--set", "output.every=1000"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
        let (Some(peak), Some(predicted)) = (
            summary["peak_memory_bytes"].as_f64(),
            summary["predicted_peak_bytes"].as_f64(),
        ) else {
            panic!("{mesh}: no peak in {summary}");
        };
        let ratio = predicted / peak;
        assert!(
            (0.7..1.3).contains(&ratio),
            "{mesh}: predicted {predicted} against {peak} measured ({ratio:.2})"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// A residual that stalls at round-off

/// An ill-conditioned condensed operator (W = 10⁻⁹ I + 𝟙𝟙ᵀ/m, the compliance of a body that is
/// almost rigid in all but one mode, like a thin plate): with a tolerance below its round-off the
/// solve fails having stalled near it, and the advice names a tolerance (not smaller steps or
/// more regularisation, which cannot lower a round-off floor) at which the same solve converges.
#[test]
fn a_stalled_contact_solve_names_the_tolerance_that_converges() {
    use hvi::contact::trace::Silent;
    use hvi::contact::{
        ActiveSetSolver, ContactProblem, ContactSettings, ContactState, DenseNormalStiffness, NodalLaws, SolverCache,
    };
    let m = 60;
    let w: Vec<f64> = (0..m * m)
        .map(|k| 1.0 / m as f64 + if k / m == k % m { 1e-9 } else { 0.0 })
        .collect();
    let op = DenseNormalStiffness::from_w(w, m).unwrap();
    let laws = NodalLaws::default();
    // the free solution d crosses the bound on part of the surface
    let d: Vec<f64> = (0..m).map(|p| 0.3 * (p as f64 / m as f64 * 6.0).sin()).collect();
    let bound = vec![0.1; m];
    let solve = |tolerance: f64| {
        let problem = ContactProblem {
            bound: Some(&bound),
            ..ContactProblem::new(&op, &laws)
        };
        let solver = ActiveSetSolver {
            settings: ContactSettings {
                tolerance,
                max_iterations: 100,
                dense_limit: 1000,
                ..ContactSettings::default()
            },
            trace: &Silent,
        };
        solver.solve(&problem, &d, &mut ContactState::new(m), &mut SolverCache::default())
    };
    let failure = solve(1e-18).expect_err("a tolerance below round-off cannot be met");
    let advice = hvi::solver::error::contact_failure_advice(failure.smallest_residual, 1e-18);
    assert!(
        advice.contains("stalled"),
        "smallest {:e}: {advice}",
        failure.smallest_residual
    );
    let suggested: f64 = advice
        .split("solver.tolerance = ")
        .nth(1)
        .and_then(|s| s.split('`').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{advice}"));
    assert!(
        suggested > failure.smallest_residual && suggested <= 20.0 * failure.smallest_residual,
        "{advice}"
    );
    solve(suggested).unwrap_or_else(|f| panic!("the suggested {suggested:e} fails too: {}", f.reason));
}
