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

/// `mpirun -np <np> hvi <args>` as root on an oversubscribed machine, ranks yielding the CPU
/// while they wait (2 ranks share 2 cores with everything else here), under a timeout.
fn mpirun(np: usize, args: &[&str], env: &[(&str, &str)]) -> Output {
    let np = np.to_string();
    let mut cmd = Command::new("timeout");
    cmd.args(["-k", "10", TIMEOUT, "mpirun", "--allow-run-as-root", "--oversubscribe"])
        .args(["--mca", "mpi_yield_when_idle", "1", "-np", &np, HVI])
        .args(args)
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

/// Runs `mesh` (+ scene) serially and on 1 and 2 ranks with `solver`; returns the largest
/// relative differences to the serial run.
fn compare(mesh: &str, scene: Option<&str>, solver: &str) -> Vec<(usize, (f64, f64))> {
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
            let out = mpirun(np, &args, &[]);
            assert_ok(&out, &format!("mpirun -np {np} ({solver})"));
            let summary = std::fs::read_to_string(Path::new(&out_dir).join("summary.json")).unwrap();
            assert!(summary.contains(&format!("\"ranks\": {np}")), "{summary}");
            let d = difference(&reference, &gamma3(Path::new(&out_dir)));
            eprintln!("{mesh} {solver} np {np}: u_ν {:.2e}, force {:.2e} relative", d.0, d.1);
            (np, d)
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

#[test]
fn slab_3d_mumps_matches_faer_on_1_and_2_ranks() {
    for (np, (du, df)) in compare("meshes/slab_q1_h8_z1.msh", Some("examples/slab.toml"), "mumps") {
        assert!(
            du <= 1e-10 && df <= 1e-10,
            "np {np}: u_ν off by {du:.2e}, force by {df:.2e}"
        );
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
    let mut cmd = Command::new("timeout");
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
    let err = String::from_utf8_lossy(&out.stderr);
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "one error, from rank 0:\n{err}");
    assert!(
        errors[0].contains("rank 1 of 2") && errors[0].contains("mesh.msh"),
        "{err}"
    );
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
    let err = String::from_utf8_lossy(&out.stderr);
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "one error, from rank 0:\n{err}");
    assert!(
        errors[0].contains("CG + GAMG") && errors[0].contains("iteration limit"),
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
