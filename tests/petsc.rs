//! The PETSc backend over MPI (docs/method.md §13) against the serial faer backend: the same
//! binary launched by `mpirun -np 1` and `-np 2` as a subprocess, every run bounded by a
//! timeout. Needs the `petsc` feature (and PETSc, Open MPI installed): `cargo test --release
//! --features petsc --test petsc`.
#![cfg(feature = "petsc")]

use std::path::Path;
use std::process::{Command, Output};

const HVI: &str = env!("CARGO_BIN_EXE_hvi");

/// Seconds any one launch may take (the runs here take a few seconds; a hang fails the test
/// instead of stalling CI).
const TIMEOUT: &str = "120";

/// The one `error:` line of a failed run's stderr (every rank holds the error, rank 0 prints it)
/// and the whole stderr, for messages.
fn the_one_error(out: &Output) -> (String, String) {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "one error, from rank 0:\n{err}");
    (errors[0].to_string(), err)
}

/// A session directory of Open MPI's own for one launch. The tests run in parallel, and launches
/// that share the default one (/tmp/ompi.<host>.<uid>) race: one that ends removes it while
/// another creates its `pid.N` below it, and that launch dies in `orte_init` ("A call to mkdir
/// was unable to create the desired directory"), as CI saw once.
fn session_dir() -> tempfile::TempDir {
    tempfile::tempdir().expect("a session directory for mpirun")
}

/// `mpirun -np <np> hvi <args>` as root on an oversubscribed machine, ranks yielding the CPU
/// while they wait (2 ranks share 2 cores with everything else here), under a timeout.
fn mpirun(np: usize, args: &[&str], env: &[(&str, &str)]) -> Output {
    let np = np.to_string();
    let session = session_dir();
    let mut cmd = Command::new("timeout");
    cmd.args(["-k", "10", TIMEOUT, "mpirun", "--allow-run-as-root", "--oversubscribe"])
        .args(["--mca", "mpi_yield_when_idle", "1", "-np", &np, HVI])
        .args(args)
        .env("OMPI_MCA_orte_tmpdir_base", session.path())
        .env_remove("PETSC_OPTIONS");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().expect("mpirun (install openmpi-bin)");
    assert_ne!(
        out.status.code(),
        Some(124),
        "mpirun -np {np} timed out: the ranks hang"
    );
    out
}

fn serial(args: &[&str]) -> Output {
    Command::new(HVI).args(args).output().expect("hvi")
}

fn assert_ok(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what} failed:\nstdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// gamma3.csv of a run: per row (time, u_ν, force), in the file's order (step by step, the
/// contact nodes in the same order in every run).
fn gamma3(dir: &Path) -> Vec<[f64; 3]> {
    let text = std::fs::read_to_string(dir.join("gamma3.csv")).expect("gamma3.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    };
    let (t, u, f) = (col("time"), col("u_nu"), col("force"));
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().expect("a number")).collect();
            [v[t], v[u], v[f]]
        })
        .collect()
}

/// The largest difference of u_ν and of the force between two runs, each relative to the
/// serial run's largest magnitude, over every contact node and every step.
fn difference(serial: &[[f64; 3]], other: &[[f64; 3]]) -> (f64, f64) {
    assert_eq!(
        serial.len(),
        other.len(),
        "the runs have different steps or contact nodes"
    );
    assert!(!serial.is_empty(), "no contact row: nothing compared");
    let scale = |k: usize| serial.iter().fold(0.0f64, |a, r| a.max(r[k].abs()));
    let (su, sf) = (scale(1), scale(2));
    assert!(
        su > 0.0 && sf > 0.0,
        "a test without contact displacement or force proves nothing"
    );
    let mut d = (0.0f64, 0.0f64);
    for (a, b) in serial.iter().zip(other) {
        assert_eq!(a[0], b[0], "times differ");
        d.0 = d.0.max((a[1] - b[1]).abs() / su);
        d.1 = d.1.max((a[2] - b[2]).abs() / sf);
    }
    d
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json is JSON")
}

/// The files a `.pvd` lists, in order.
fn pvd_files(pvd: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(pvd).expect(".pvd");
    text.split("file=\"")
        .skip(1)
        .map(|r| r.split('"').next().unwrap().to_string())
        .collect()
}

/// Runs `mesh` (+ scene) serially and on 1 and 2 ranks with `solver`; returns the largest
/// relative differences to the serial run.
fn compare(mesh: &str, scene: Option<&str>, solver: &str) -> Vec<(usize, (f64, f64))> {
    compare_with(mesh, scene, solver, &[])
        .into_iter()
        .map(|(np, d, _)| (np, d))
        .collect()
}

/// [`compare`] with `--set` overrides on the PETSc runs; also returns each run's condensation.
fn compare_with(mesh: &str, scene: Option<&str>, solver: &str, set: &[&str]) -> Vec<(usize, (f64, f64), String)> {
    let tmp = tempfile::tempdir().unwrap();
    let mut base = vec!["solve", mesh, "--quiet"];
    if let Some(s) = scene {
        base.extend(["--scene", s]);
    }
    let dir = |name: &str| tmp.path().join(name).display().to_string();
    let s = dir("serial");
    let mut args = base.clone();
    args.extend(["--out", &s]);
    assert_ok(&serial(&args), "the serial run");
    let reference = gamma3(Path::new(&s));
    [1, 2]
        .into_iter()
        .map(|np| {
            let out_dir = dir(&format!("np{np}"));
            let mut args = base.clone();
            args.extend(["--out", &out_dir, "--backend", "petsc", "--solver", solver]);
            for s in set {
                args.extend(["--set", s]);
            }
            let out = mpirun(np, &args, &[]);
            assert_ok(&out, &format!("mpirun -np {np} ({solver})"));
            let summary = summary(Path::new(&out_dir));
            assert_eq!(summary["ranks"], np, "{summary}");
            assert_eq!(summary["per_rank"].as_array().unwrap().len(), np, "{summary}");
            let d = difference(&reference, &gamma3(Path::new(&out_dir)));
            eprintln!("{mesh} {solver} np {np}: u_ν {:.2e}, force {:.2e} relative", d.0, d.1);
            let condensation = summary["condensation"].as_str().unwrap_or_default().to_string();
            (np, d, condensation)
        })
        .collect()
}

/// MUMPS is a direct factor: the runs differ from faer's only by round-off, amplified by the
/// condition of K (≈ 10³ at h = 1/8) and of the contact solve, far below 1e-10 relative.
#[test]
fn paper_example_2d_mumps_matches_faer_on_1_and_2_ranks() {
    for (np, (du, df)) in compare("meshes/rect_q1_h8.msh", None, "mumps") {
        assert!(
            du <= 1e-10 && df <= 1e-10,
            "np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
        );
    }
}

/// Friction (docs/method.md §17) under PETSc: the Cattaneo–Mindlin scene (Coulomb, partial slip)
/// on 1 and 2 ranks gives the serial Γ₃ to 1e-10 (the tangential rows are condensed with the
/// normal ones by the same stored responses, and rank 0 runs the same contact solve).
#[test]
fn friction_matches_faer_on_1_and_2_ranks() {
    for (np, (du, df)) in compare(
        "examples/gallery/cattaneo_2d/cattaneo_2d.msh",
        Some("examples/gallery/cattaneo_2d/cattaneo_2d.toml"),
        "mumps",
    ) {
        assert!(
            du <= 1e-10 && df <= 1e-10,
            "np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
        );
    }
}

/// Two deformable bodies (docs/method.md §18) under PETSc: the gallery's steel punch pressed into
/// a relaxing pad and slid with Coulomb friction, on 1 and 2 ranks, gives the serial Γ₃ to 1e-10.
/// A pair's rows hold the slave's and the master's unknowns, which the partition may put on
/// different ranks: each rank sets its own entries of the columns of Cᵀ and its share of W and of
/// C u is summed over the ranks, as for any row.
#[test]
fn two_bodies_match_faer_on_1_and_2_ranks() {
    for (np, (du, df)) in compare(
        "examples/gallery/two_bodies/two_bodies.msh",
        Some("examples/gallery/two_bodies/two_bodies.toml"),
        "mumps",
    ) {
        assert!(
            du <= 1e-10 && df <= 1e-10,
            "np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
        );
    }
}

/// Second-order cells under PETSc (docs/method.md §19): the paper's example on gmsh's 9-node
/// quadrangles and the gallery's Hertz on 6-node triangles and on 10-node tetrahedra — contact
/// rows over their faces' nodes with the weighted gap (§19.3) — and the gallery's punch on its
/// pad (two bodies, memory, Coulomb friction; §18.6) on 6-node triangles and 9-node quadrangles,
/// on 1 and 2 ranks give the serial Γ₃ to 1e-10.
#[test]
fn second_order_meshes_match_faer_on_1_and_2_ranks() {
    for (mesh, scene) in [
        ("meshes/second_order/rect_q9_h16.msh", None),
        (
            "meshes/second_order/hertz_2d_p2_a8.msh",
            Some("examples/gallery/hertz_2d/hertz_2d.toml"),
        ),
        (
            "meshes/second_order/hertz_3d_tet10_a7.msh",
            Some("examples/gallery/hertz_3d/hertz_3d.toml"),
        ),
        (
            "meshes/two_bodies/gallery_o2.msh",
            Some("examples/gallery/two_bodies/two_bodies.toml"),
        ),
    ] {
        for (np, (du, df)) in compare(mesh, scene, "mumps") {
            assert!(
                du <= 1e-10 && df <= 1e-10,
                "{mesh}, np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
            );
        }
    }
}

/// 3D friction (docs/method.md §17.3) under PETSc: a hexahedral block (meshes/block_q1_h8.msh)
/// pressed and dragged diagonally over a rigid paraboloid (so that u_ν varies: on a plane every
/// node sits at u_ν = 0 and a relative difference is round-off over round-off) with Coulomb
/// friction — two tangential rows per base node, paired in the contact solve — on 1 and 2 ranks
/// gives the serial Γ₃ to 1e-10.
#[test]
fn friction_3d_matches_faer_on_1_and_2_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("dragged.toml");
    std::fs::write(
        &scene,
        "[material]\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 4\n\
         [[dirichlet]]\ngroup = \"Gamma1\"\ncomponents = [\"x\", \"y\", \"z\"]\nvalue = [\"0.01*t\", \"0.006*t\", \"-0.002\"]\n\
         [contact]\nbound = \"0.01*((x - 0.5)^2 + (y - 0.5)^2)\"\nfriction = { kind = \"coulomb\", coefficient = 0.3 }\n[solver]\ntolerance = 1e-12\n",
    )
    .unwrap();
    for (np, (du, df)) in compare("meshes/block_q1_h8.msh", Some(scene.to_str().unwrap()), "mumps") {
        assert!(
            du <= 1e-10 && df <= 1e-10,
            "np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
        );
    }
}

#[test]
fn slab_3d_mumps_matches_faer_on_1_and_2_ranks() {
    for (np, (du, df)) in compare("meshes/slab_q1_h8_z1.msh", Some("examples/slab.toml"), "mumps") {
        assert!(
            du <= 1e-10 && df <= 1e-10,
            "np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
        );
    }
}

/// The two recoveries of docs/method.md §13 (u = u_free − Zλ from the stored responses, one
/// solve per step; or a second solve) forced in turn, on 1 and 2 ranks of the 3D slab: both give
/// the serial steps, and the summary names the one that ran.
#[test]
fn both_recoveries_match_faer_on_1_and_2_ranks() {
    for (kind, name) in [
        ("stored_responses", "stored responses"),
        ("recovery_solve", "a free and a recovery solve"),
    ] {
        let set = format!("solver.condensation=\"{kind}\"");
        for (np, (du, df), ran) in
            compare_with("meshes/slab_q1_h8_z1.msh", Some("examples/slab.toml"), "mumps", &[&set])
        {
            assert!(ran.contains(name), "{kind} np {np}: the summary says {ran:?}");
            assert!(
                du <= 1e-10 && df <= 1e-10,
                "{kind} np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
            );
        }
    }
}

/// CG + GAMG stops at the relative residual 1e-10 (hvi::petsc::GAMG_RTOL): the error of a
/// solve is then at most κ(K)·1e-10 relative, κ ≤ 10⁴ on these h = 1/8 meshes, so 1e-6 is what
/// the solver tolerance allows (measured: ≤ 1.7e-9; a wrong operator or partition is off by
/// O(1)).
#[test]
fn gamg_matches_faer_to_the_solver_tolerance() {
    for (mesh, scene) in [
        ("meshes/rect_q1_h8.msh", None),
        ("meshes/slab_q1_h8_z1.msh", Some("examples/slab.toml")),
    ] {
        for (np, (du, df)) in compare(mesh, scene, "gamg") {
            assert!(
                du <= 1e-5 && df <= 1e-5,
                "{mesh} np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
            );
        }
    }
}

/// Rank 1 runs in a directory whose mesh.msh is broken (as when a node holds a stale copy):
/// both ranks stop, rank 0 prints the one error naming rank 1 and the file's problem.
#[test]
fn a_rank_that_reads_a_bad_mesh_stops_every_rank() {
    let tmp = tempfile::tempdir().unwrap();
    let (good, bad) = (tmp.path().join("good"), tmp.path().join("bad"));
    std::fs::create_dir_all(&good).unwrap();
    std::fs::create_dir_all(&bad).unwrap();
    let text = std::fs::read_to_string("meshes/rect_q1_h8.msh").unwrap();
    std::fs::write(good.join("mesh.msh"), &text).unwrap();
    std::fs::write(bad.join("mesh.msh"), &text[..text.len() / 2]).unwrap();
    let out_dir = tmp.path().join("out").display().to_string();
    let args = ["solve", "mesh.msh", "--quiet", "--backend", "petsc", "--out", &out_dir];
    let session = session_dir();
    let mut cmd = Command::new("timeout");
    cmd.env("OMPI_MCA_orte_tmpdir_base", session.path());
    cmd.args(["-k", "10", TIMEOUT, "mpirun", "--allow-run-as-root", "--oversubscribe"])
        .args(["--mca", "mpi_yield_when_idle", "1"])
        .args(["-np", "1", "-wdir", &good.display().to_string(), HVI])
        .args(args)
        .arg(":")
        .args(["-np", "1", "-wdir", &bad.display().to_string(), HVI])
        .args(args);
    let out = cmd.output().expect("mpirun");
    assert_ne!(out.status.code(), Some(124), "the ranks hang");
    assert!(!out.status.success());
    let (error, err) = the_one_error(&out);
    assert!(error.contains("rank 1 of 2") && error.contains("mesh.msh"), "{err}");
    assert!(!Path::new(&out_dir).join("summary.json").exists(), "nothing was solved");
}

/// A solver that fails inside the time loop (here CG + GAMG allowed one iteration through
/// PETSc's own options) fails on every rank at once: one clear error, no hang.
#[test]
fn a_failing_solver_stops_every_rank_with_one_error() {
    let tmp = tempfile::tempdir().unwrap();
    let out_dir = tmp.path().join("out").display().to_string();
    let args = [
        "solve",
        "meshes/rect_q1_h8.msh",
        "--quiet",
        "--backend",
        "petsc",
        "--solver",
        "gamg",
        "--out",
        &out_dir,
    ];
    let out = mpirun(2, &args, &[("PETSC_OPTIONS", "-hvi_ksp_max_it 1")]);
    assert!(!out.status.success());
    let (error, err) = the_one_error(&out);
    assert!(
        error.contains("CG + GAMG") && error.contains("iteration limit"),
        "{err}"
    );
}

/// Without MPI the serial binary refuses --solver alone (it names the PETSc solver).
#[test]
fn solver_needs_the_petsc_backend() {
    let out = serial(&[
        "solve",
        "meshes/rect_q1_h8.msh",
        "--solver",
        "gamg",
        "--out",
        "/nonexistent",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--backend petsc"));
}

/// The largest difference between two arrays relative to the first one's largest magnitude
/// (0 when both are zero).
fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let d = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    if scale == 0.0 {
        d
    } else {
        d / scale
    }
}

/// Every frame of the serial run against the same frame of a run in pieces: the same points
/// and cells exactly, every point and cell array to `tolerance` relative to the array's largest
/// magnitude in the frame; returns the largest difference seen.
fn compare_series(serial: &Path, pieces: &Path, tolerance: f64) -> f64 {
    let frames = pvd_files(&serial.join("solution.pvd"));
    let parallel = pvd_files(&pieces.join("solution.pvd"));
    assert_eq!(frames.len(), parallel.len(), "the runs list different frames");
    assert!(frames.len() > 1);
    let mut worst = 0.0f64;
    for (s, p) in frames.iter().zip(&parallel) {
        assert_eq!(p, &s.replace(".vtu", ".pvtu"), "frame names");
        let a = hvi::output::read_vtu_arrays(&serial.join(s)).unwrap();
        let b = hvi::output::read_pvtu_arrays(&pieces.join(p)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(a.points, b.points, "{p}: points");
        assert_eq!(a.connectivity, b.connectivity, "{p}: cells");
        assert_eq!(a.cell_types, b.cell_types, "{p}: cell types");
        assert_eq!(a.field_data, b.field_data, "{p}: TimeValue and step");
        for (kind, x, y) in [
            ("point", &a.point_data, &b.point_data),
            ("cell", &a.cell_data, &b.cell_data),
        ] {
            let names =
                |m: &std::collections::BTreeMap<String, (usize, Vec<f64>)>| m.keys().cloned().collect::<Vec<_>>();
            assert_eq!(names(x), names(y), "{p}: {kind} arrays");
            for (name, (k, values)) in x {
                let (l, other) = &y[name];
                assert_eq!(k, l, "{p}: components of {name}");
                let d = relative_difference(values, other);
                assert!(d <= tolerance, "{p}: {kind} array {name} off by {d:.2e} relative");
                worst = worst.max(d);
            }
        }
    }
    worst
}

/// The body of a run in pieces reads back whole (every `.pvtu` the `.pvd` lists, through hvi's
/// reader, which also checks that the pieces agree at the nodes they share) and equals the
/// serial run's output: every point and cell array of every frame, 3D with memory, loads and
/// contact, on 1 and 2 ranks. MUMPS is a direct factor: the displacements agree to round-off
/// (≤ 2e-13 measured on gamma3.csv), and the stresses are linear in them, so 1e-10 relative
/// leaves three orders of margin and still catches any wrong piece, node or ghost value (off by
/// O(1)). Measured: see the printed differences.
#[test]
fn pieces_read_back_whole_and_equal_the_serial_output() {
    let tmp = tempfile::tempdir().unwrap();
    for (mesh, scene) in [
        ("meshes/slab_q1_h8_z1.msh", Some("examples/slab.toml")),
        ("meshes/rect_q1_h8.msh", None),
    ] {
        let mut base = vec!["solve", mesh, "--quiet"];
        if let Some(s) = scene {
            base.extend(["--scene", s]);
        }
        let name = Path::new(mesh).file_stem().unwrap().to_str().unwrap();
        let serial_dir = tmp.path().join(format!("{name}-serial"));
        let s = serial_dir.display().to_string();
        let mut args = base.clone();
        args.extend(["--out", &s]);
        assert_ok(&serial(&args), "the serial run");
        for np in [1, 2] {
            let dir = tmp.path().join(format!("{name}-np{np}"));
            let d = dir.display().to_string();
            let mut args = base.clone();
            args.extend(["--out", &d, "--backend", "petsc"]);
            assert_ok(&mpirun(np, &args, &[]), &format!("mpirun -np {np}"));
            let worst = compare_series(&serial_dir, &dir, 1e-10);
            eprintln!("{mesh} np {np}: every array of every frame within {worst:.2e} relative");
            // pieces: one per rank and frame, and the manifest lists every file of the run
            let frames = pvd_files(&dir.join("solution.pvd"));
            for f in &frames {
                let pieces = hvi::output::pvtu_pieces(&dir.join(f)).unwrap();
                assert_eq!(pieces.len(), np, "{f}");
            }
            let listed: std::collections::BTreeSet<String> =
                hvi::output::read_manifest(&dir.join(hvi::output::MANIFEST_NAME))
                    .unwrap()
                    .into_iter()
                    .collect();
            let present: std::collections::BTreeSet<String> = std::fs::read_dir(&dir)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .filter(|n| n != hvi::output::MANIFEST_NAME)
                .collect();
            assert!(
                present.is_subset(&listed),
                "unlisted: {:?}",
                present.difference(&listed)
            );
            // the rest of the run: as in serial (gamma3.csv, the contact dataset, the tables)
            for file in ["gamma3.csv", "contact.pvd", "scene.toml"] {
                assert!(dir.join(file).exists(), "{file}");
            }
            let c = hvi::output::read_vtu_arrays(&dir.join("contact_00008.vtp")).unwrap();
            let c0 = hvi::output::read_vtu_arrays(&serial_dir.join("contact_00008.vtp")).unwrap();
            for (name, (_, v)) in &c0.point_data {
                let d = relative_difference(v, &c.point_data[name].1);
                assert!(d <= 1e-10, "contact_00008.vtp: {name} off by {d:.2e}");
            }
        }
    }
}

/// --overwrite removes exactly the files of the earlier run, its pieces included, whatever the
/// number of ranks of either run; a file of the user's stays.
#[test]
fn overwrite_removes_every_piece_and_nothing_else() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let d = dir.display().to_string();
    let args = [
        "solve",
        "meshes/rect_q1_h8.msh",
        "--quiet",
        "--backend",
        "petsc",
        "--out",
        &d,
    ];
    assert_ok(&mpirun(2, &args, &[]), "mpirun -np 2");
    assert!(dir.join("solution_00010_1.vtu").exists());
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    // again without --overwrite: refused, nothing touched
    let again = mpirun(1, &args, &[]);
    assert!(!again.status.success());
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("--overwrite"), "{err}");
    assert!(dir.join("solution_00010_1.vtu").exists());
    // on 1 rank with --overwrite: no piece of rank 1 survives, notes.txt does
    let mut args = args.to_vec();
    args.push("--overwrite");
    assert_ok(&mpirun(1, &args, &[]), "mpirun -np 1 --overwrite");
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.ends_with("_1.vtu")), "{names:?}");
    assert!(names.contains(&"notes.txt".to_string()));
    // and a serial run over it removes the pieces of rank 0 and the .pvtu files too
    let s = ["solve", "meshes/rect_q1_h8.msh", "--quiet", "--out", &d, "--overwrite"];
    assert_ok(&serial(&s), "the serial --overwrite");
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.ends_with(".pvtu") || n.ends_with("_0.vtu")),
        "{names:?}"
    );
    assert!(names.contains(&"notes.txt".to_string()));
}

/// A piece that cannot be written (a directory stands where rank 1's piece of step 3 goes)
/// stops every rank with one error naming the file; every frame before it stays whole and
/// listed, and summary.json says how far the run got.
#[test]
fn a_piece_that_fails_leaves_every_earlier_frame_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    std::fs::create_dir_all(dir.join("solution_00003_1.vtu")).unwrap();
    let d = dir.display().to_string();
    let args = [
        "solve",
        "meshes/rect_q1_h8.msh",
        "--quiet",
        "--backend",
        "petsc",
        "--out",
        &d,
    ];
    let out = mpirun(2, &args, &[]);
    assert!(!out.status.success());
    let (error, err) = the_one_error(&out);
    assert!(
        error.contains("rank 1 of 2") && error.contains("solution_00003_1.vtu"),
        "{err}"
    );
    let frames = pvd_files(&dir.join("solution.pvd"));
    assert_eq!(
        frames,
        ["solution_00000.pvtu", "solution_00001.pvtu", "solution_00002.pvtu"]
    );
    for f in &frames {
        hvi::output::read_pvtu_arrays(&dir.join(f)).unwrap_or_else(|e| panic!("{e}"));
    }
    assert!(!dir.join("solution_00003.pvtu").exists());
    let s = summary(&dir);
    assert!(s["status"].as_str().unwrap().starts_with("failed: rank 1 of 2"), "{s}");
    assert_eq!(s["steps_done"], 4, "{s}");
    assert_eq!(s["last_step_written"], 2, "{s}");
}

/// A run that stops early (the contact solve allowed one Newton iteration at a tolerance it
/// cannot meet) writes summary.json from rank 0 as in serial: the status, the steps done, the
/// last step written — the same numbers as the serial run's.
#[test]
fn an_early_stop_writes_the_summary_as_in_serial() {
    let tmp = tempfile::tempdir().unwrap();
    let run = |dir: &Path, petsc: bool| {
        let d = dir.display().to_string();
        let mut args = vec!["solve", "meshes/rect_q1_h8.msh", "--quiet", "--out", &d];
        args.extend(["--set", "solver.max_iterations=1", "--set", "solver.tolerance=1e-15"]);
        let out = if petsc {
            args.extend(["--backend", "petsc"]);
            mpirun(2, &args, &[])
        } else {
            serial(&args)
        };
        assert!(!out.status.success());
        summary(dir)
    };
    let s = run(&tmp.path().join("serial"), false);
    let p = run(&tmp.path().join("mpi"), true);
    assert!(
        p["status"]
            .as_str()
            .unwrap()
            .starts_with("failed: contact solve failed at step"),
        "{p}"
    );
    assert_eq!(p["steps_done"], s["steps_done"], "{p}");
    assert_eq!(p["last_step_written"], s["last_step_written"], "{p}");
    assert_eq!(p["ranks"], 2);
}

/// `hvi check --backend petsc` on 2 ranks prints one row per rank whose cells, unknowns and
/// contact nodes add up to the mesh's, and a positive predicted memory per rank.
#[test]
fn check_prints_the_partition_and_the_memory_per_rank() {
    let out = mpirun(
        2,
        &[
            "check",
            "meshes/slab_q1_h8_z1.msh",
            "--scene",
            "examples/slab.toml",
            "--backend",
            "petsc",
        ],
        &[],
    );
    assert_ok(&out, "hvi check --backend petsc");
    let text = String::from_utf8_lossy(&out.stdout);
    let serial_text = String::from_utf8_lossy(
        &serial(&["check", "meshes/slab_q1_h8_z1.msh", "--scene", "examples/slab.toml"]).stdout,
    )
    .into_owned();
    let number = |t: &str, prefix: &str| -> usize {
        let line = t
            .lines()
            .find(|l| l.trim_start().starts_with(prefix))
            .unwrap_or_else(|| panic!("{prefix}:\n{t}"));
        line.split_whitespace().find_map(|w| w.parse().ok()).unwrap()
    };
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("rank "))
        .skip(1)
        .take_while(|l| l.trim_start().chars().next().is_some_and(|c| c.is_ascii_digit()))
        .map(|l| {
            l.split(|c: char| c.is_whitespace() || c == '|')
                .filter_map(|w| w.parse().ok())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 2, "{text}");
    let sum = |k: usize| rows.iter().map(|r| r[k]).sum::<f64>() as usize;
    let mesh_cells: usize = text
        .lines()
        .find(|l| l.contains("nodes,") && l.contains("cells"))
        .and_then(|l| l.split_whitespace().nth(3)?.parse().ok())
        .unwrap();
    assert_eq!(sum(2), mesh_cells, "{text}");
    assert_eq!(sum(3), number(&serial_text, "unknowns:"), "{text}");
    assert_eq!(sum(4), number(&serial_text, "contact:"), "{text}");
    for r in &rows {
        let total = *r.last().unwrap();
        assert!(total > 10.0, "a predicted total of {total} MiB per rank:\n{text}");
    }
    assert!(text.contains("INFOG(16)"), "{text}");
}

/// output.active_scalar marks the same array in every piece and in the `.pvtu` as in a serial
/// frame (ParaView colours the frame by it).
#[test]
fn the_active_scalar_is_marked_in_the_pieces_and_the_pvtu() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("run").display().to_string();
    let args = [
        "solve",
        "meshes/rect_q1_h8.msh",
        "--quiet",
        "--backend",
        "petsc",
        "--out",
        &d,
        "--set",
        "output.active_scalar=displacement",
    ];
    assert_ok(&mpirun(2, &args, &[]), "mpirun -np 2");
    let read = |name: &str| std::fs::read_to_string(tmp.path().join("run").join(name)).unwrap();
    assert!(read("solution_00004.pvtu").contains("<PPointData Scalars=\"displacement\""));
    for piece in ["solution_00004_0.vtu", "solution_00004_1.vtu"] {
        let text = String::from_utf8_lossy(&std::fs::read(tmp.path().join("run").join(piece)).unwrap()).into_owned();
        assert!(text.contains("<PointData Scalars=\"displacement\""), "{piece}");
    }
}

/// Memory of two channels (own bulk and shear moduli not in A's ratio, docs/method.md §15.1) is
/// not run by the PETSc backend (it assembles one K_B): `hvi solve` and `hvi check` with
/// `--backend petsc` both refuse the scene before anything is assembled or written, with one
/// error that names the scene file, what is not supported and the fix; the same scene runs
/// serially.
#[test]
fn memory_of_two_channels_is_refused_by_solve_and_check() {
    let tmp = tempfile::tempdir().unwrap();
    let slab = std::fs::read_to_string("examples/slab.toml").unwrap();
    assert!(slab.contains("[memory]"), "examples/slab.toml has a [memory] section");
    // the slab's B(s) = (0.5 + s)² I, plus a term on a tensor with its own moduli: not ∝ I
    let text = slab.replace("[memory]", "[[memory]]")
        + "\n[[memory]]\nkind = \"polynomial\"\ncoefficients = [0.1]\ntensor = { bulk = 2.0, shear = 0.1 }\n";
    let scene = tmp.path().join("two_channels.toml");
    std::fs::write(&scene, text).unwrap();
    let scene_arg = scene.display().to_string();
    let mesh = "meshes/slab_q1_h8_z1.msh";
    let serial_dir = tmp.path().join("serial").display().to_string();
    assert_ok(
        &serial(&["solve", mesh, "--scene", &scene_arg, "--quiet", "--out", &serial_dir]),
        "the serial run of the two-channel scene",
    );
    let out_dir = tmp.path().join("mpi");
    let d = out_dir.display().to_string();
    for args in [
        vec!["check", mesh, "--scene", &scene_arg, "--backend", "petsc"],
        vec![
            "solve",
            mesh,
            "--scene",
            &scene_arg,
            "--quiet",
            "--backend",
            "petsc",
            "--out",
            &d,
        ],
    ] {
        let out = mpirun(2, &args, &[]);
        assert!(!out.status.success(), "{} accepted two channels", args[0]);
        let (error, err) = the_one_error(&out);
        for part in [
            scene_arg.as_str(),
            "2 channels",
            "PETSc backend does not support",
            "without --backend petsc",
            "proportional",
        ] {
            assert!(
                error.contains(part),
                "`{part}` missing from {}'s error:\n{err}",
                args[0]
            );
        }
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            !stdout.contains("predicted memory"),
            "check predicted memory anyway:\n{stdout}"
        );
    }
    // refused before the output was prepared: nothing written
    let written = std::fs::read_dir(&out_dir).map_or(0, |d| d.count());
    assert_eq!(written, 0, "the refused run wrote into {d}");
}

/// Ctrl-C on `mpirun` (which sends SIGTERM to every rank, then SIGKILL after a grace time):
/// the ranks stop together after the step they agree on, rank 0 writes the interrupted summary,
/// the series stays valid (issue 23; PETSc's own signal handler used to abort the ranks with no
/// message and no summary).
#[test]
fn ctrl_c_on_mpirun_stops_every_rank_with_the_interrupted_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let session = session_dir();
    let mut child = Command::new("mpirun")
        .env("OMPI_MCA_orte_tmpdir_base", session.path())
        .args([
            "--allow-run-as-root",
            "--oversubscribe",
            "--mca",
            "mpi_yield_when_idle",
            "1",
        ])
        .args(["--mca", "odls_base_sigkill_timeout", "30", "-np", "2", HVI])
        .args(["solve", "meshes/rect_q1_h8.msh", "--quiet", "--backend", "petsc"])
        .args(["--out", out.to_str().unwrap()])
        .args(["--set", "time.steps=5000000", "--set", "output.every=100"])
        .env_remove("PETSC_OPTIONS")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("mpirun");
    let listed = |p: &Path| std::fs::read_to_string(p).map_or(0, |t| t.matches("file=\"").count());
    let t0 = std::time::Instant::now();
    while listed(&out.join("solution.pvd")) < 2 {
        assert!(t0.elapsed().as_secs() < 120, "no frames written");
        if let Some(s) = child.try_wait().unwrap() {
            panic!("mpirun ended early: {s}");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    assert!(Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap()
        .success());
    let t1 = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t1.elapsed().as_secs() > 60 {
            let _ = child.kill();
            panic!("the ranks did not stop within 60 s of Ctrl-C");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    // (each rank exits with 130; mpirun, having forwarded a signal, reports 1 itself)
    assert!(!status.success(), "{stderr}");
    assert!(stderr.contains("run interrupted"), "{stderr}");
    assert_eq!(summary(&out)["status"], "interrupted", "{stderr}");
    let pvtu = pvd_files(&out.join("solution.pvd"));
    assert!(pvtu.len() >= 2);
    for f in &pvtu {
        assert!(out.join(f).exists(), "{f} listed but missing");
    }
}

/// Force control and bodies held by their contact (docs/method.md §7.7) are not run by the PETSc
/// backend yet: `hvi solve --backend petsc` refuses the gallery's force-controlled Hertz scene
/// with one error naming the parameter and the fix, before writing anything.
#[test]
fn force_control_is_refused_by_the_petsc_backend() {
    refused_on_two_ranks(
        &[
            "solve",
            "examples/gallery/hertz_2d/hertz_2d_h1.msh",
            "--scene",
            "examples/gallery/hertz_2d/hertz_2d_force.toml",
        ],
        &[
            "force_control[0] (group Base, y)",
            "PETSc backend does not support",
            "without --backend petsc",
        ],
    );
}

/// `args` (a solve without its output and backend) on 2 PETSc ranks is refused with one error
/// holding every one of `parts`, before anything is written.
fn refused_on_two_ranks(args: &[&str], parts: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("mpi").display().to_string();
    let mut all = args.to_vec();
    all.extend(["--quiet", "--backend", "petsc", "--out", &d]);
    let out = mpirun(2, &all, &[]);
    assert!(!out.status.success(), "the PETSc backend accepted {}", args.join(" "));
    let (error, err) = the_one_error(&out);
    for part in parts {
        assert!(error.contains(part), "`{part}` missing from the error:\n{err}");
    }
    assert!(!tmp.path().join("mpi").join("summary.json").exists());
}

/// Several materials (docs/method.md §8.5) under PETSc: the paper's scene on the two halves, its
/// material with its memory on the left, a stiffer elastic one on the right
/// (`[[materials]]`), gives the serial Γ₃ on 1 and 2 ranks to 1e-10 (each rank assembles its
/// cells with their material).
#[test]
fn two_materials_match_faer_on_1_and_2_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let paper = std::fs::read_to_string("examples/paper.toml").unwrap();
    let scene = dir.path().join("two_materials.toml");
    std::fs::write(
        &scene,
        format!("{paper}\n[[materials]]\ngroup = \"Right\"\nyoungs_modulus = 3.0\npoisson_ratio = 0.3\n"),
    )
    .unwrap();
    for (np, (du, df)) in compare("meshes/rect_halves_q1_h4.msh", scene.to_str(), "mumps") {
        assert!(
            du <= 1e-10 && df <= 1e-10,
            "np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
        );
    }
}

/// A body of revolution (docs/method.md §8.6) under PETSc: Hertz's sphere on the 2D gallery's
/// meridian mesh with `material.plane = "axisymmetric"` gives the serial Γ₃ on 1 and 2 ranks to
/// 1e-10 (each rank's cells carry the hoop strain and 2πr; the loads and contact weights are the
/// serial ones).
#[test]
fn axisymmetric_hertz_matches_faer_on_1_and_2_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("examples/gallery/hertz_2d/hertz_2d.toml").unwrap();
    let scene = dir.path().join("sphere.toml");
    std::fs::write(&scene, text.replace("plane = \"strain\"", "plane = \"axisymmetric\"")).unwrap();
    for (np, (du, df)) in compare("examples/gallery/hertz_2d/hertz_2d_h2.msh", scene.to_str(), "mumps") {
        assert!(
            du <= 1e-10 && df <= 1e-10,
            "np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
        );
    }
}

/// Steps that grow with time (docs/method.md §20) under PETSc: the relaxation gallery, whose
/// memory is proportional to A (one factorisation, rescaled per step size, §20.3), and the
/// paper's example, whose memory on the identity takes a step matrix per size (a PETSc
/// factorisation each), on steps growing 5 a decade from 10⁻³, give the serial Γ₃ on 1 and 2
/// ranks to 1e-10; automatic steps are refused by name before anything runs.
#[test]
fn growing_steps_match_faer_and_automatic_steps_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let growing = |path: &str, name: &str| -> String {
        let text = std::fs::read_to_string(path).unwrap();
        let start = text.find("[time]").unwrap();
        let end = start + text[start..].find("\n\n").unwrap_or(text.len() - start);
        let final_time = text[start..end]
            .lines()
            .find(|l| l.starts_with("final_time"))
            .unwrap()
            .to_string();
        let scene = format!(
            "{}[time]\n{final_time}\nfirst_step = 1e-3\nsteps_per_decade = 5\n{}",
            &text[..start],
            &text[end..]
        );
        let file = tmp.path().join(name);
        std::fs::write(&file, scene).unwrap();
        file.display().to_string()
    };
    let relaxation = growing("examples/gallery/relaxation/relaxation.toml", "relaxation.toml");
    let paper = growing("examples/paper.toml", "paper.toml");
    for (mesh, scene) in [
        ("examples/gallery/relaxation/relaxation.msh", &relaxation),
        ("meshes/rect_q1_h8.msh", &paper),
    ] {
        for (np, (du, df)) in compare(mesh, Some(scene), "mumps") {
            assert!(
                du <= 1e-10 && df <= 1e-10,
                "{scene}, np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
            );
        }
    }
    refused_on_two_ranks(
        &["solve", "meshes/rect_q1_h8.msh", "--set", "time.tolerance=1e-3"],
        &["time.tolerance", "automatic steps", "steps_per_decade"],
    );
}
