//! Issue 23: nothing lost, nothing silently wrong. Two runs into one output folder, groups that
//! are not faces of the mesh, broken meshes, non-finite results, values compared by value.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn meshes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes")
}

fn hvi() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hvi"))
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
    let run = |extra: &[&str]| {
        hvi()
            .args([
                "solve",
                mesh.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--quiet",
            ])
            .args(extra)
            .output()
            .unwrap()
    };
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
        assert_eq!(files, vec![hvi::output::LOCK_NAME.to_string()], "{extra:?} wrote files");
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
    let mut first = hvi()
        .args([
            "solve",
            mesh.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
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
    let second = hvi()
        .args([
            "solve",
            mesh.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--overwrite",
        ])
        .output()
        .unwrap();
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
