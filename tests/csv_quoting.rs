//! CSV output and input through the `csv` crate: a gmsh group whose name holds a comma (legal
//! in gmsh) is quoted in `contact_forces.csv` and `reactions.csv`, so each row still has the
//! header's four fields (checked with the `csv` crate and, when python3 is installed, with
//! Python's `csv` module); and a row of `gamma3.csv` that does not parse is an error naming the
//! file and the line, from the reader and from `hvi plot`, never a row silently skipped.

mod common;

use hvi::mesh::structured::{rectangle, CellShape};
use hvi::plot::read_gamma3;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root(path: &str) -> String {
    format!("{}/{path}", env!("CARGO_MANIFEST_DIR"))
}

/// The header and the records of a CSV file, each record checked to have the header's length.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut reader = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let header: Vec<String> = reader.headers().unwrap().iter().map(str::to_string).collect();
    let rows: Vec<Vec<String>> = reader
        .records()
        .map(|r| {
            let r = r.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert_eq!(r.len(), header.len(), "{}: {r:?} under {header:?}", path.display());
            r.iter().map(str::to_string).collect()
        })
        .collect();
    (header, rows)
}

/// rect_q1_h8.msh with Γ₁ named `Gamma, 1` and Γ₃ named `Gamma, 3`, solved for two steps with
/// the paper's scene naming them; the output directory.
fn run_with_comma_names(dir: &Path) -> PathBuf {
    let mesh_text = std::fs::read_to_string(root("meshes/rect_q1_h8.msh")).unwrap();
    assert!(mesh_text.contains("1 1 \"Gamma1\"\n") && mesh_text.contains("1 3 \"Gamma3\"\n"));
    let mesh_text = mesh_text
        .replace("1 1 \"Gamma1\"\n", "1 1 \"Gamma, 1\"\n")
        .replace("1 3 \"Gamma3\"\n", "1 3 \"Gamma, 3\"\n");
    let mesh = dir.join("commas.msh");
    std::fs::write(&mesh, mesh_text).unwrap();
    let scene_text = hvi::scene::DEFAULT_SCENE_TOML;
    assert!(scene_text.contains("clamped = \"Gamma1\"") && scene_text.contains("contact = \"Gamma3\""));
    let scene_text = scene_text
        .replace("clamped = \"Gamma1\"", "clamped = \"Gamma, 1\"")
        .replace("contact = \"Gamma3\"", "contact = \"Gamma, 3\"");
    let scene = dir.join("commas.toml");
    std::fs::write(&scene, scene_text).unwrap();
    let out = dir.join("run");
    common::hvi_ok(&[
        "solve",
        mesh.to_str().unwrap(),
        "--scene",
        scene.to_str().unwrap(),
        "--set",
        "time.steps=2",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    out
}

/// Python's csv module: every row has the header's length; prints the distinct `group` values.
const PYTHON_CHECK: &str = r#"
import csv, sys
with open(sys.argv[1], newline="") as f:
    rows = list(csv.reader(f))
header, body = rows[0], rows[1:]
assert body, "no rows"
for i, r in enumerate(body, start=2):
    assert len(r) == len(header), f"line {i}: {r} under {header}"
print("|".join(sorted({r[header.index("group")] for r in body})))
"#;

#[test]
fn group_names_with_commas_are_quoted_in_the_force_tables() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_with_comma_names(dir.path());
    for (file, group) in [("contact_forces.csv", "Gamma, 3"), ("reactions.csv", "Gamma, 1")] {
        let path = out.join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains(&format!(",\"{group}\",")),
            "{file}: the name is not quoted:\n{text}"
        );
        let (header, rows) = read_csv(&path);
        assert_eq!(header, ["time", "group", "component", "force"], "{file}");
        // three times (t = 0, 0.5, 1), two components each
        assert_eq!(rows.len(), 3 * 2, "{file}: {rows:?}");
        for r in &rows {
            assert_eq!(r[1], group, "{file}: {r:?}");
            assert!(
                r[0].parse::<f64>().is_ok() && r[3].parse::<f64>().is_ok(),
                "{file}: {r:?}"
            );
            assert!(r[2] == "x" || r[2] == "y", "{file}: {r:?}");
        }
        let Some(python) = find_python() else {
            eprintln!("SKIPPED: {file}: the check with Python's csv module (python3 not found)");
            continue;
        };
        let check = Command::new(python)
            .args(["-c", PYTHON_CHECK])
            .arg(&path)
            .output()
            .unwrap();
        assert!(
            check.status.success(),
            "{file}: Python's csv module: {}",
            String::from_utf8_lossy(&check.stderr)
        );
        assert_eq!(String::from_utf8_lossy(&check.stdout).trim_end(), group, "{file}");
    }
    // gamma3.csv is all numbers (the group as its tag) and reads back row by row, too
    let (header, rows) = read_csv(&out.join("gamma3.csv"));
    assert_eq!(header.last().map(String::as_str), Some("group"));
    assert!(!rows.is_empty());
    assert!(rows.iter().all(|r| r.last().map(String::as_str) == Some("3")));
}

fn find_python() -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join("python3"))
        .find(|p| p.is_file())
}

const GAMMA3: &str = "time,x,y,u_nu,force,pressure,status,group\n\
                      0,0,0,0,0,0,0,3\n\
                      0,0.5,0,0,0,0,0,3\n";

#[test]
fn a_gamma3_row_that_does_not_parse_names_the_file_and_the_line() {
    let mesh = rectangle(2.0, 1.0, 4, 2, CellShape::Quad);
    assert!(read_gamma3(GAMMA3, &mesh).is_ok());
    let cases = [
        // a field missing, one too many, a cell that is not a number, a quote left open
        (format!("{GAMMA3}1,0,0,0.1,0.2\n"), "gamma3.csv line 4: 5 fields"),
        (
            format!("{GAMMA3}1,0,0,0.1,0.2,0.3,1,3,7\n"),
            "gamma3.csv line 4: 9 fields",
        ),
        (
            GAMMA3.replace("0,0.5,0,0", "0,0.5,zero,0"),
            "gamma3.csv line 3: `zero` in column `y` is not a number",
        ),
        (format!("{GAMMA3}1,\"0,0,0,0,0,0,3\n"), "gamma3.csv line 4"),
    ];
    for (text, want) in cases {
        match read_gamma3(&text, &mesh) {
            Ok(_) => panic!("accepted:\n{text}"),
            Err(e) => assert!(e.contains(want), "{e}\n(wanted `{want}`)"),
        }
    }
}

/// `hvi plot` of a 2D and of a 3D run whose gamma3.csv has a broken row: an error naming the
/// file and the line, not a picture drawn without it.
#[test]
fn hvi_plot_reports_a_broken_gamma3_row() {
    let dir = tempfile::tempdir().unwrap();
    let runs = [
        ("2d", vec!["rect:8x4".to_string()]),
        (
            "3d",
            vec![
                root("meshes/slab_q1_h8_z1.msh"),
                "--scene".into(),
                root("examples/slab.toml"),
            ],
        ),
    ];
    for (name, input) in runs {
        let out = dir.path().join(name);
        let mut args = vec!["solve".to_string()];
        args.extend(input);
        args.extend(["--set", "time.steps=2", "--quiet", "--out"].map(str::to_string));
        args.push(out.to_str().unwrap().to_string());
        common::hvi_ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let path = out.join("gamma3.csv");
        let text = std::fs::read_to_string(&path).unwrap();
        let mut lines: Vec<&str> = text.lines().collect();
        assert!(lines.len() > 4, "{name}: {text}");
        let broken = lines[3].replacen(',', ",x", 1);
        lines[3] = &broken;
        std::fs::write(&path, lines.join("\n") + "\n").unwrap();
        let plot = Command::new(env!("CARGO_BIN_EXE_hvi"))
            .args(["plot", out.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&plot.stderr);
        assert!(!plot.status.success(), "{name}: hvi plot drew a broken table");
        assert!(
            stderr.contains("gamma3.csv line 4: `x") && stderr.contains("is not a number"),
            "{name}: {stderr}"
        );
    }
}
