//! The output module's files, read back: `.vtu` arrays bit for bit, the `.pvd` and
//! `.vtu.series` indexes, CSV tables, and what is left on disk after failures.

use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::Cell;
use hvi::output::{
    is_temporary_name, read_vtu_arrays, write_atomic, write_json_atomic, CsvTable, Field, FieldValues, Frame,
    OutputError, SeriesWriter,
};
use std::collections::BTreeSet;
use std::path::Path;

/// A unit square split into a quad and a triangle hanging off its right side.
const POINTS: [[f64; 2]; 5] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.5]];
const CELLS: [Cell; 2] = [Cell::Quad4([0, 1, 2, 3]), Cell::Tri3([1, 4, 2])];

/// Values that expose any loss of precision or sign.
fn awkward(k: usize, salt: f64) -> f64 {
    const V: [f64; 8] = [
        0.1 + 0.2,
        -0.0,
        1e-300,
        -2.5e17,
        1.0 / 3.0,
        f64::MIN_POSITIVE,
        7.0,
        -1e-7,
    ];
    V[k % V.len()] * (1.0 + salt)
}

struct FrameData {
    displacement: Vec<f64>,
    pair: Vec<f64>,
    status: Vec<i32>,
    stress: Vec<f64>,
    von_mises: Vec<f64>,
    region: Vec<i32>,
}

impl FrameData {
    fn new(salt: f64) -> Self {
        let n = POINTS.len();
        let c = CELLS.len();
        FrameData {
            displacement: (0..3 * n)
                .map(|k| if k % 3 == 2 { 0.0 } else { awkward(k, salt) })
                .collect(),
            pair: (0..2 * n).map(|k| awkward(k + 3, salt)).collect(),
            status: vec![-1, 0, 2, i32::MIN, i32::MAX],
            stress: (0..9 * c).map(|k| awkward(k + 1, salt)).collect(),
            von_mises: (0..c).map(|k| awkward(k + 5, salt)).collect(),
            region: vec![7, -3],
        }
    }

    fn frame(&self, step: usize, time: f64) -> Frame<'_, 2> {
        Frame {
            step,
            time,
            points: &POINTS,
            cells: &CELLS,
            point_fields: vec![
                Field {
                    name: "displacement",
                    components: 3,
                    values: FieldValues::F64(&self.displacement),
                    active: false,
                },
                Field::f64("pair", 2, &self.pair),
                Field {
                    name: "contact_status",
                    components: 1,
                    values: FieldValues::I32(&self.status),
                    active: false,
                },
            ],
            cell_fields: vec![
                Field::f64("stress", 9, &self.stress),
                Field::f64("von_mises", 1, &self.von_mises),
                Field::i32("region", 1, &self.region),
            ],
        }
    }
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Compares every array of the `.vtu` at `path` with `frame`, bit for bit.
fn assert_vtu_matches(path: &Path, frame: &Frame<2>) {
    let vtu = read_vtu_arrays(path).unwrap_or_else(|e| panic!("{e}"));
    let expected_points: Vec<[f64; 3]> = frame.points.iter().map(|p| [p[0], p[1], 0.0]).collect();
    assert_eq!(vtu.points, expected_points);
    let expected_types: Vec<u8> = frame.cells.iter().map(Cell::vtk_type).collect();
    assert_eq!(vtu.cell_types, expected_types);
    let expected_conn: Vec<Vec<usize>> = frame.cells.iter().map(|c| c.nodes().to_vec()).collect();
    assert_eq!(vtu.connectivity, expected_conn);
    for (fields, data, what) in [
        (&frame.point_fields, &vtu.point_data, "point"),
        (&frame.cell_fields, &vtu.cell_data, "cell"),
    ] {
        let names: BTreeSet<&str> = data.keys().map(String::as_str).collect();
        let expected: BTreeSet<&str> = fields.iter().map(|f| f.name).collect();
        assert_eq!(names, expected, "{what} arrays of {}", path.display());
        for f in fields {
            let (components, values) = &data[f.name];
            assert_eq!(*components, f.components, "{what} field {}", f.name);
            let want: Vec<f64> = match f.values {
                FieldValues::F64(v) => v.to_vec(),
                FieldValues::I32(v) => v.iter().map(|&i| i as f64).collect(),
            };
            assert_eq!(bits(values), bits(&want), "{what} field {}", f.name);
        }
    }
}

/// The (timestep, file) attributes of the `<DataSet>` entries of a `.pvd`, in order, with a
/// tiny XML scan (the file must be a `Collection`).
fn pvd_entries(path: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.trim_start().starts_with("<?xml"), "{text}");
    assert!(text.contains("<VTKFile type=\"Collection\""), "{text}");
    assert!(
        text.contains("<Collection>") && text.contains("</Collection>") && text.contains("</VTKFile>"),
        "{text}"
    );
    let attr = |element: &str, name: &str| -> String {
        let key = format!(" {name}=\"");
        let start = element.find(&key).unwrap_or_else(|| panic!("no {name} in {element}")) + key.len();
        let len = element[start..].find('"').unwrap();
        element[start..start + len].to_string()
    };
    text.match_indices("<DataSet")
        .map(|(i, _)| {
            let end = i + text[i..].find("/>").expect("DataSet is not self-closing");
            let element = &text[i..end];
            (attr(element, "timestep"), attr(element, "file"))
        })
        .collect()
}

/// The (name, time) entries of a `.vtu.series`.
fn series_entries(path: &Path) -> Vec<(String, f64)> {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    assert_eq!(json["file-series-version"], "1.0");
    json["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| (f["name"].as_str().unwrap().to_string(), f["time"].as_f64().unwrap()))
        .collect()
}

fn dir_names(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

fn assert_no_temporaries(dir: &Path) {
    let temps: Vec<String> = dir_names(dir)
        .into_iter()
        .filter(|n| is_temporary_name(n) || n.contains(".tmp"))
        .collect();
    assert!(temps.is_empty(), "temporary files left: {temps:?}");
}

#[test]
fn two_frame_series_reads_back_exactly() {
    for level in [0, 1, 9] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("nested/run");
        let mut writer = SeriesWriter::create(&dir, "sol").unwrap().with_compression(level);
        assert!(dir.is_dir());
        assert_eq!(writer.dir(), dir);
        assert!(dir_names(&dir).is_empty(), "create leaves nothing behind");

        let (d0, d1) = (FrameData::new(0.0), FrameData::new(0.5));
        let t1 = 0.1 + 0.2; // a time that only survives in full precision
        let f0 = d0.frame(0, 0.0);
        let f1 = d1.frame(3, t1);
        let p0 = writer.write_frame(&f0).unwrap();
        let p1 = writer.write_frame(&f1).unwrap();
        assert_eq!(p0, dir.join("sol_00000.vtu"));
        assert_eq!(p1, dir.join("sol_00003.vtu"));
        assert_eq!(writer.frames(), &[(0.0, p0.clone()), (t1, p1.clone())]);

        assert_vtu_matches(&p0, &f0);
        assert_vtu_matches(&p1, &f1);

        let pvd = pvd_entries(&dir.join("sol.pvd"));
        assert_eq!(pvd.len(), 2);
        assert_eq!(pvd[0], ("0".to_string(), "sol_00000.vtu".to_string()));
        assert_eq!(pvd[1].1, "sol_00003.vtu");
        assert_eq!(pvd[1].0.parse::<f64>().unwrap().to_bits(), t1.to_bits());

        let series = series_entries(&dir.join("sol.vtu.series"));
        assert_eq!(
            series,
            vec![("sol_00000.vtu".to_string(), 0.0), ("sol_00003.vtu".to_string(), t1)]
        );

        let expected: BTreeSet<String> = ["sol.pvd", "sol.vtu.series", "sol_00000.vtu", "sol_00003.vtu"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(dir_names(&dir), expected, "level {level}");
    }
}

#[test]
fn rewriting_a_step_replaces_its_entry() {
    let tmp = tempfile::tempdir().unwrap();
    let mut writer = SeriesWriter::create(tmp.path(), "sol").unwrap();
    let (d0, d1) = (FrameData::new(0.0), FrameData::new(1.0));
    writer.write_frame(&d0.frame(0, 0.0)).unwrap();
    writer.write_frame(&d0.frame(1, 0.5)).unwrap();
    let again = d1.frame(1, 0.75);
    writer.write_frame(&again).unwrap();
    assert_eq!(writer.frames().len(), 2);
    let pvd = pvd_entries(&tmp.path().join("sol.pvd"));
    assert_eq!(
        pvd,
        vec![
            ("0".into(), "sol_00000.vtu".into()),
            ("0.75".into(), "sol_00001.vtu".into())
        ]
    );
    assert_vtu_matches(&tmp.path().join("sol_00001.vtu"), &again);
}

#[test]
fn csv_has_header_and_full_precision_rows() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("gamma3.csv");
    let mut csv = CsvTable::create(&path, &["time", "x", "status"]).unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        "time,x,status\n",
        "header written at creation"
    );
    let rows = vec![
        vec![0.0, 0.1 + 0.2, -1.0],
        vec![0.25, 1e-300, 2.0],
        vec![0.5, -2.5e17, f64::MIN_POSITIVE],
    ];
    csv.append(&rows[..2]).unwrap();
    csv.append(&rows[2..]).unwrap();
    csv.append(&[]).unwrap();

    // a row of the wrong length is an error and writes nothing of its block
    let err = csv.append(&[vec![1.0, 2.0, 3.0], vec![1.0, 2.0]]).unwrap_err();
    assert!(
        matches!(
            err,
            OutputError::CsvRow {
                row: 1,
                got: 2,
                expected: 3,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("gamma3.csv"), "{err}");
    assert_eq!(csv.rows(), 3);

    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time,x,status"));
    let read: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(read.len(), rows.len());
    for (r, w) in read.iter().zip(&rows) {
        assert_eq!(bits(r), bits(w));
    }
    assert!(text.ends_with('\n'));
}

#[test]
fn unwritable_directory_is_reported_by_create() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("plain.txt");
    std::fs::write(&file, "not a directory").unwrap();

    for dir in [file.join("out"), file.clone()] {
        let err = SeriesWriter::create(&dir, "sol").unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, OutputError::Directory { .. }), "{msg}");
        assert!(msg.contains(&dir.display().to_string()), "names the directory: {msg}");
        assert!(msg.contains("choose another --out directory"), "names the fix: {msg}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "not a directory");

    // A read-only directory (not testable as root, who may write anyway).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let ro = tmp.path().join("ro");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        if std::fs::write(ro.join("x"), "").is_err() {
            let msg = SeriesWriter::create(&ro, "sol").unwrap_err().to_string();
            assert!(msg.contains("permission denied") && msg.contains("ro"), "{msg}");
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

#[test]
fn bad_frames_are_errors_and_write_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let mut writer = SeriesWriter::create(tmp.path(), "sol").unwrap();
    let d = FrameData::new(0.0);
    let short = vec![0.0; 3 * POINTS.len() - 1];

    let mut f = d.frame(0, 0.0);
    f.point_fields[0] = Field::f64("displacement", 3, &short);
    let err = writer.write_frame(&f).unwrap_err();
    assert!(
        matches!(
            err,
            OutputError::FieldLength {
                expected: 15,
                got: 14,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("displacement"), "{err}");

    let mut f = d.frame(0, 0.0);
    f.cell_fields[1] = Field::i32("von_mises", 1, &d.status);
    assert!(matches!(
        writer.write_frame(&f).unwrap_err(),
        OutputError::FieldLength { .. }
    ));

    let bad_cells = [Cell::Tri3([0, 1, 5])];
    let mut f = d.frame(0, 0.0);
    f.cells = &bad_cells;
    f.cell_fields.clear();
    assert!(matches!(
        writer.write_frame(&f).unwrap_err(),
        OutputError::InvalidFrame { .. }
    ));

    let f = d.frame(0, f64::NAN);
    assert!(matches!(
        writer.write_frame(&f).unwrap_err(),
        OutputError::InvalidFrame { .. }
    ));

    let mut f = d.frame(0, 0.0);
    f.point_fields.push(Field::f64("pair", 2, &d.pair));
    assert!(matches!(
        writer.write_frame(&f).unwrap_err(),
        OutputError::InvalidFrame { .. }
    ));

    assert!(writer.frames().is_empty());
    assert!(dir_names(tmp.path()).is_empty(), "{:?}", dir_names(tmp.path()));
}

#[test]
fn failures_leave_a_consistent_index_and_no_temporaries() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let d = FrameData::new(0.0);
    let short = [1.0];
    {
        let mut writer = SeriesWriter::create(dir, "sol").unwrap();
        writer.write_frame(&d.frame(0, 0.0)).unwrap();
        writer.write_frame(&d.frame(1, 0.5)).unwrap();

        // a bogus frame
        let mut bogus = d.frame(2, 1.0);
        bogus.cell_fields.push(Field::f64("short", 1, &short));
        assert!(writer.write_frame(&bogus).is_err());

        // an I/O failure in the middle of a write: the target name is taken by a directory,
        // so the rename of the finished temporary file fails
        std::fs::create_dir(dir.join("sol_00002.vtu")).unwrap();
        let err = writer.write_frame(&d.frame(2, 1.0)).unwrap_err();
        assert!(matches!(err, OutputError::Write { .. }), "{err}");
        assert!(err.to_string().contains("sol_00002.vtu"), "{err}");
        assert_eq!(writer.frames().len(), 2);
        assert_no_temporaries(dir);
    } // the writer is dropped, as when a run dies after frame 1

    let expect = vec![
        ("0".to_string(), "sol_00000.vtu".to_string()),
        ("0.5".to_string(), "sol_00001.vtu".to_string()),
    ];
    assert_eq!(pvd_entries(&dir.join("sol.pvd")), expect);
    assert_eq!(series_entries(&dir.join("sol.vtu.series")).len(), 2);

    // a new run in the same directory whose first frame is bogus leaves the index alone
    let mut writer = SeriesWriter::create(dir, "sol").unwrap();
    let mut bogus = d.frame(0, 0.0);
    bogus.point_fields.push(Field::f64("short", 1, &short));
    assert!(writer.write_frame(&bogus).is_err());
    drop(writer);
    assert_eq!(pvd_entries(&dir.join("sol.pvd")), expect);
    for (_, file) in &expect {
        assert_vtu_matches(&dir.join(file), &d.frame(0, 0.0));
    }
    assert_no_temporaries(dir);
}

#[test]
fn atomic_writes_replace_whole_files() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("scene.toml");
    write_atomic(&path, b"a = 1\n").unwrap();
    write_atomic(&path, b"a = 2\n").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"a = 2\n");

    #[derive(serde::Serialize)]
    struct Summary {
        steps: usize,
        residual: f64,
    }
    let json = tmp.path().join("summary.json");
    write_json_atomic(
        &json,
        &Summary {
            steps: 4,
            residual: 0.1 + 0.2,
        },
    )
    .unwrap();
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["steps"], 4);
    assert_eq!(v["residual"].as_f64().unwrap(), 0.1 + 0.2);
    assert!(
        std::fs::read_to_string(&json).unwrap().contains("\n  \"steps\""),
        "pretty-printed"
    );

    let err = write_atomic(&tmp.path().join("missing/x.txt"), b"").unwrap_err();
    assert!(err.to_string().contains("missing/x.txt"), "{err}");
    assert_no_temporaries(tmp.path());
}

#[test]
fn read_vtu_arrays_reports_missing_and_foreign_files() {
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("none.vtu");
    let err = read_vtu_arrays(&missing).unwrap_err();
    assert!(
        matches!(err, OutputError::Read { .. }) && err.to_string().contains("none.vtu"),
        "{err}"
    );
    let junk = tmp.path().join("junk.vtu");
    std::fs::write(&junk, "<VTKFile type=\"PolyData\"></VTKFile>").unwrap();
    assert!(read_vtu_arrays(&junk).is_err());
}

/// Fields of every kind hvi writes (Float64 with 1, 2, 3 and 9 components, Int32) on a mesh,
/// with values that expose any loss of bits (signed zeros, subnormals, NaN, infinities).
struct MeshFields {
    displacement: Vec<f64>,
    pair: Vec<f64>,
    status: Vec<i32>,
    stress: Vec<f64>,
    von_mises: Vec<f64>,
    region: Vec<i32>,
}

impl MeshFields {
    fn new(n_points: usize, n_cells: usize) -> Self {
        let special = |k: usize| match k % 11 {
            3 => f64::NAN,
            7 => f64::NEG_INFINITY,
            9 => 5e-324,
            _ => awkward(k, 0.25),
        };
        MeshFields {
            displacement: (0..3 * n_points)
                .map(|k| if k % 3 == 2 { 0.0 } else { special(k) })
                .collect(),
            pair: (0..2 * n_points).map(|k| special(k + 1)).collect(),
            status: (0..n_points)
                .map(|k| [-1, 0, 1, 2, i32::MIN, i32::MAX][k % 6])
                .collect(),
            stress: (0..9 * n_cells).map(|k| special(k + 2)).collect(),
            von_mises: (0..n_cells).map(|k| special(k + 5)).collect(),
            region: (0..n_cells).map(|k| k as i32 - 3).collect(),
        }
    }

    fn frame<'a>(&'a self, mesh: &'a hvi::mesh::Mesh<2>, step: usize) -> Frame<'a, 2> {
        Frame {
            step,
            time: 0.25 * step as f64,
            points: &mesh.points,
            cells: &mesh.cells,
            point_fields: vec![
                Field::f64("displacement", 3, &self.displacement),
                // a name that needs XML escaping
                Field::f64("a&b \"q\" <x>'", 2, &self.pair),
                Field::i32("contact_status", 1, &self.status),
            ],
            cell_fields: vec![
                Field::f64("stress", 9, &self.stress),
                Field::f64("von_mises", 1, &self.von_mises),
                Field::i32("region", 1, &self.region),
            ],
        }
    }
}

#[test]
fn p1_and_q1_frames_read_back_bit_identically() {
    for (shape, vtk_type) in [(CellShape::Tri, 5u8), (CellShape::Quad, 9u8)] {
        let mesh = rectangle(2.0, 1.0, 7, 5, shape);
        let data = MeshFields::new(mesh.points.len(), mesh.cells.len());
        let tmp = tempfile::tempdir().unwrap();
        let mut writer = SeriesWriter::create(tmp.path(), "sol").unwrap();
        // the second frame reuses the writer's buffer; a smaller frame after a larger one too
        let small = rectangle(1.0, 1.0, 2, 1, shape);
        let small_data = MeshFields::new(small.points.len(), small.cells.len());
        for (step, (m, d)) in [(&mesh, &data), (&mesh, &data), (&small, &small_data)]
            .into_iter()
            .enumerate()
        {
            let frame = d.frame(m, step);
            let path = writer.write_frame(&frame).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            let header = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]);
            assert!(header.contains("<AppendedData encoding=\"raw\">"), "{header}");
            assert!(!header.contains("format=\"binary\""), "{header}");
            assert_vtu_matches(&path, &frame);
            let vtu = read_vtu_arrays(&path).unwrap();
            assert!(vtu.cell_types.iter().all(|&t| t == vtk_type));
            assert_eq!(vtu.point_data.len(), 3);
            assert_eq!(vtu.cell_data.len(), 3);
        }
        assert_no_temporaries(tmp.path());
    }
}

#[test]
fn truncated_frames_are_errors_not_panics() {
    let mesh = rectangle(1.0, 1.0, 3, 2, CellShape::Quad);
    let data = MeshFields::new(mesh.points.len(), mesh.cells.len());
    let tmp = tempfile::tempdir().unwrap();
    let mut writer = SeriesWriter::create(tmp.path(), "sol").unwrap();
    let path = writer.write_frame(&data.frame(&mesh, 0)).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let marker = b"<AppendedData encoding=\"raw\">";
    let tag = bytes.windows(marker.len()).position(|w| w == marker).unwrap();
    let start = tag + bytes[tag..].iter().position(|&b| b == b'_').unwrap() + 1;
    let end = bytes.len() - "\n  </AppendedData>\n</VTKFile>\n".len();
    let cut = tmp.path().join("cut.vtu");

    // cut in the middle of the appended data
    std::fs::write(&cut, &bytes[..(start + end) / 2]).unwrap();
    let err = read_vtu_arrays(&cut).unwrap_err();
    assert!(matches!(err, OutputError::Format { .. }), "{err}");
    let msg = err.to_string();
    assert!(msg.contains("truncated") && msg.contains("cut.vtu"), "{msg}");

    // any cut at all (only the final newline may go)
    for len in 0..bytes.len() - 1 {
        std::fs::write(&cut, &bytes[..len]).unwrap();
        match std::panic::catch_unwind(|| read_vtu_arrays(&cut)) {
            Ok(Err(_)) => {}
            Ok(Ok(_)) => panic!("a file cut to {len} of {} bytes was read as complete", bytes.len()),
            Err(_) => panic!("a file cut to {len} of {} bytes made the reader panic", bytes.len()),
        }
    }
    std::fs::write(&cut, &bytes[..bytes.len() - 1]).unwrap();
    assert_vtu_matches(&cut, &data.frame(&mesh, 0));

    // a byte count that does not match the header is an error too
    let mut bad = bytes.clone();
    bad[start] ^= 0x08;
    std::fs::write(&cut, &bad).unwrap();
    assert!(read_vtu_arrays(&cut).is_err());
}
