//! A run's ParaView series read back: every frame carries the time its `.pvd` lists, the
//! contact dataset holds exactly Γ₃'s nodes and facets, the group ids are the mesh's, the
//! nodal stresses are the recovered ones, and ParaView's first view colours by von Mises.

use hvi::app::{solve, SolveOptions};
use hvi::fem::stress::{cell_measures, cell_stresses, nodal_stresses};
use hvi::material::Elasticity;
use hvi::mesh::{read_msh, AnyMesh, GroupSelector, Mesh};
use hvi::output::read_vtu_arrays;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Solves `mesh` (with `scene`, or the paper's default) for `steps` steps into `out`.
fn run(mesh: &str, scene: Option<&str>, steps: usize, out: &Path) {
    let opts = SolveOptions {
        mesh: root(mesh),
        scene: scene.map(root),
        out: out.to_path_buf(),
        overrides: vec![format!("time.steps={steps}")],
        progress: false,
        overwrite: false,
        accept_mesh_defects: false,
    };
    solve(&opts, None).unwrap_or_else(|e| panic!("{e}"));
}

/// The (time, file) entries of a `.pvd`.
fn pvd_entries(path: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .filter(|l| l.contains("<DataSet"))
        .map(|l| {
            let attr = |key: &str| {
                let start = l.find(&format!("{key}=\"")).unwrap() + key.len() + 2;
                l[start..].split('"').next().unwrap().to_string()
            };
            (attr("timestep").parse().unwrap(), attr("file"))
        })
        .collect()
}

/// Every frame of both series carries as FieldData the time and step its `.pvd` lists.
fn assert_times_match(out: &Path, steps: usize) {
    for pvd in ["solution.pvd", "contact.pvd"] {
        let entries = pvd_entries(&out.join(pvd));
        assert_eq!(entries.len(), steps + 1, "{pvd}");
        for (n, (t, file)) in entries.iter().enumerate() {
            let f = read_vtu_arrays(&out.join(file)).unwrap();
            // exact: both are the same f64, written in shortest round-trip form and as bits
            assert_eq!(f.field_data["TimeValue"], (1, vec![*t]), "{file}");
            assert_eq!(f.field_data["step"], (1, vec![n as f64]), "{file}");
        }
    }
}

/// The contact dataset's points are exactly Γ₃'s nodes, its cells exactly Γ₃'s facets, and the
/// group ids on the body's cells and the contact facets are the mesh's physical tags.
fn assert_datasets_match_mesh<const D: usize>(mesh: &Mesh<D>, out: &Path, last: usize) {
    let gamma3 = mesh.boundary(&GroupSelector::Name("Gamma3".into())).unwrap();
    let tag = mesh
        .group(&GroupSelector::Name("Gamma3".into()), (D - 1) as u8)
        .unwrap()
        .tag;
    let vtp = read_vtu_arrays(&out.join(format!("contact_{last:05}.vtp"))).unwrap();
    let xyz = |p: &[f64; D]| std::array::from_fn::<f64, 3, _>(|i| p.get(i).copied().unwrap_or(0.0));
    let expected: Vec<[f64; 3]> = gamma3.nodes.iter().map(|&p| xyz(&mesh.points[p])).collect();
    assert_eq!(vtp.points, expected);
    // the facets as sets of mesh nodes (the dataset indexes its own points)
    let as_mesh = |c: &[usize]| -> BTreeSet<usize> { c.iter().map(|&i| gamma3.nodes[i]).collect() };
    let got: BTreeSet<BTreeSet<usize>> = vtp.connectivity.iter().map(|c| as_mesh(c)).collect();
    let want: BTreeSet<BTreeSet<usize>> = gamma3
        .facets
        .iter()
        .map(|f| f.nodes().iter().copied().collect())
        .collect();
    assert_eq!(got, want);
    assert_eq!(vtp.connectivity.len(), gamma3.facets.len());
    let line_or_polygon = if D == 2 { 3.0 } else { 7.0 };
    assert!(vtp.cell_types.iter().all(|&t| f64::from(t) == line_or_polygon));
    assert!(vtp.cell_data["group"].1.iter().all(|&g| g == f64::from(tag)));
    assert!(vtp.point_data["group"].1.iter().all(|&g| g == f64::from(tag)));
    // the nodal normals are the part's, as 3-vectors
    let normals: Vec<f64> = gamma3.normals.iter().flat_map(xyz).collect();
    assert_eq!(vtp.point_data["normal"], (3, normals));

    let vtu = read_vtu_arrays(&out.join(format!("solution_{last:05}.vtu"))).unwrap();
    let mut groups = vec![-1.0; mesh.cells.len()];
    for g in mesh.groups.iter().filter(|g| g.dim as usize == D) {
        for &c in &g.cells {
            if groups[c] == -1.0 {
                groups[c] = f64::from(g.tag);
            }
        }
    }
    assert!(
        groups.iter().all(|&g| g >= 0.0),
        "every cell of the shipped mesh is in a group"
    );
    assert_eq!(vtu.cell_data["group"], (1, groups));
    // the body no longer carries the contact arrays (0 on interior nodes)
    for name in ["u_nu", "contact_force", "contact_pressure", "contact_status"] {
        assert!(!vtu.point_data.contains_key(name), "{name}");
    }
}

/// The header of a written file up to its appended data.
fn header(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap();
    let end = bytes.windows(13).position(|w| w == b"<AppendedData").unwrap();
    String::from_utf8(bytes[..end].to_vec()).unwrap()
}

#[test]
fn series_2d_reads_back_with_times_contact_dataset_and_groups() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    run("meshes/rect_q1_h8.msh", None, 4, &out);
    assert_times_match(&out, 4);
    let AnyMesh::Two(mesh) = read_msh(&root("meshes/rect_q1_h8.msh")).unwrap() else {
        panic!("a 2D mesh")
    };
    assert_datasets_match_mesh(&mesh, &out, 4);

    // the contact dataset agrees with gamma3.csv at T (the same nodes where both have them)
    let vtp = read_vtu_arrays(&out.join("contact_00004.vtp")).unwrap();
    let csv = std::fs::read_to_string(out.join("gamma3.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .filter(|r: &Vec<f64>| r[0] == 1.0)
        .collect();
    assert!(!rows.is_empty());
    for r in &rows {
        let i = vtp.points.iter().position(|p| p[0] == r[1] && p[1] == r[2]).unwrap();
        assert_eq!(vtp.point_data["u_nu"].1[i], r[3]);
        assert_eq!(vtp.point_data["force"].1[i], r[4]);
        assert_eq!(vtp.point_data["pressure"].1[i], r[5]);
        assert_eq!(vtp.point_data["status"].1[i], r[6]);
        // gap = g − u_ν with the paper's bound g = 0.2
        assert_eq!(vtp.point_data["gap"].1[i], 0.2 - r[3]);
    }

    // ParaView's first view: von Mises (point data) is the active scalar, displacement the
    // active vector, and the arrays name their components
    let h = header(&out.join("solution_00004.vtu"));
    assert!(
        h.contains("<PointData Scalars=\"von_mises\" Vectors=\"displacement\" Tensors=\"stress\">"),
        "{h}"
    );
    assert!(h.contains("<CellData Scalars=\"von_mises\" Tensors=\"stress\">"), "{h}");
    assert!(h.contains("Name=\"stress\" NumberOfComponents=\"9\" ComponentName0=\"xx\" ComponentName1=\"xy\""));
    assert!(h.contains("Name=\"displacement\" NumberOfComponents=\"3\" ComponentName0=\"x\""));
}

#[test]
fn series_3d_contact_dataset_is_gamma3_faces() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("slab");
    run("meshes/slab_q1_h8_z1.msh", Some("examples/slab.toml"), 2, &out);
    assert_times_match(&out, 2);
    let AnyMesh::Three(mesh) = read_msh(&root("meshes/slab_q1_h8_z1.msh")).unwrap() else {
        panic!("a 3D mesh")
    };
    assert_datasets_match_mesh(&mesh, &out, 2);
}

/// The recovered nodal stress of a displacement with constant strain is that constant stress at
/// every node (each cell has it, and a weighted mean of equal tensors is the tensor); its von
/// Mises value is the tensor's. On a non-uniform field every nodal value lies between the
/// smallest and largest value of its cells (a convex combination).
#[test]
fn nodal_stress_is_the_volume_weighted_mean() {
    let mesh = hvi::mesh::structured::rectangle(2.0, 1.0, 6, 4, hvi::mesh::structured::CellShape::Tri);
    let e = Elasticity {
        youngs_modulus: 3.0,
        poisson_ratio: 0.3,
        plane: Some(hvi::material::PlaneModel::Strain),
    };
    let materials = hvi::fem::materials::Materials::one(
        hvi::fem::materials::BodyMaterial {
            name: "[material]".into(),
            elasticity: e,
            memory: None,
            volumetric: hvi::fem::assembly::Volumetric::Pointwise,
        },
        &mesh.cells,
    );
    let linear: Vec<[f64; 2]> = mesh
        .points
        .iter()
        .map(|p| [0.1 * p[0] + 0.3 * p[1], -0.2 * p[0] + 0.05 * p[1]])
        .collect();
    let cell = cell_stresses(&mesh.cells, &mesh.points, &materials, None, &linear, None);
    let m = cell_measures(&mesh.cells, &mesh.points);
    // the measures add up to the rectangle's area
    assert!((m.iter().sum::<f64>() - 2.0).abs() < 1e-12);
    let node = nodal_stresses(&mesh.cells, &m, &cell.tensor, mesh.points.len());
    for p in 0..mesh.points.len() {
        for k in 0..9 {
            // round-off of a weighted mean of equal values: a few ulps of |σ| ~ 1
            assert!((node.tensor[9 * p + k] - cell.tensor[k]).abs() < 1e-12);
        }
        assert!((node.von_mises[p] - cell.von_mises[0]).abs() < 1e-12);
    }
    let wavy: Vec<[f64; 2]> = mesh
        .points
        .iter()
        .map(|p| [(3.0 * p[0]).sin() * p[1], p[0] * p[0]])
        .collect();
    let cell = cell_stresses(&mesh.cells, &mesh.points, &materials, None, &wavy, None);
    let node = nodal_stresses(&mesh.cells, &m, &cell.tensor, mesh.points.len());
    for p in 0..mesh.points.len() {
        let around: Vec<usize> = (0..mesh.cells.len())
            .filter(|&c| mesh.cells[c].nodes().contains(&p))
            .collect();
        for k in 0..9 {
            let (lo, hi) = around.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &c| {
                (lo.min(cell.tensor[9 * c + k]), hi.max(cell.tensor[9 * c + k]))
            });
            let v = node.tensor[9 * p + k];
            assert!(
                v >= lo - 1e-12 && v <= hi + 1e-12,
                "node {p} component {k}: {v} outside [{lo}, {hi}]"
            );
        }
    }
}

fn opts(out: &Path, steps: usize, extra: &[&str], overwrite: bool) -> SolveOptions {
    let mut overrides = vec![format!("time.steps={steps}")];
    overrides.extend(extra.iter().map(|s| s.to_string()));
    SolveOptions {
        mesh: root("meshes/rect_q1_h8.msh"),
        scene: None,
        out: out.to_path_buf(),
        overrides,
        progress: false,
        overwrite,
        accept_mesh_defects: false,
    }
}

fn names(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// A 40-step run, then a 4-step run into the same directory: refused without --overwrite (and
/// nothing touched); with it, the directory holds exactly the new run's files (4 + 1 frames of
/// each series, no stale frame of the first run) and the user's own file.
#[test]
fn reruns_are_refused_or_replace_exactly_the_earlier_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    solve(&opts(&out, 40, &[], false), None).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("solution_00099.vtu"), "a user's file with an hvi-like name").unwrap();
    let first = names(&out);
    assert!(first.contains("solution_00040.vtu") && first.contains("contact_00040.vtp"));

    let e = solve(&opts(&out, 4, &[], false), None).unwrap_err().to_string();
    assert!(e.contains(out.to_str().unwrap()) && e.contains("--overwrite"), "{e}");
    assert_eq!(names(&out), first, "a refused run touches nothing");

    solve(&opts(&out, 4, &[], true), None).unwrap();
    let mut want: BTreeSet<String> = (0..=4)
        .flat_map(|n| [format!("solution_{n:05}.vtu"), format!("contact_{n:05}.vtp")])
        .collect();
    for f in [
        "solution.pvd",
        "solution.vtu.series",
        "contact.pvd",
        "contact.vtp.series",
        "gamma3.csv",
        "reactions.csv",
        "contact_forces.csv",
        "scene.toml",
        "summary.json",
        ".hvi-run",
        "notes.txt",
        "solution_00099.vtu",
    ] {
        want.insert(f.to_string());
    }
    assert_eq!(names(&out), want);
    assert_eq!(std::fs::read_to_string(out.join("notes.txt")).unwrap(), "mine");
    // the manifest lists exactly the run's files (all but the user's two)
    let listed: BTreeSet<String> = hvi::output::read_manifest(&out.join(".hvi-run"))
        .unwrap()
        .into_iter()
        .collect();
    let mut run_files = want.clone();
    for f in [".hvi-run", "notes.txt", "solution_00099.vtu"] {
        run_files.remove(f);
    }
    assert_eq!(listed, run_files);
    assert_eq!(pvd_entries(&out.join("solution.pvd")).len(), 5);
    assert_eq!(summary(&out)["status"], "completed");
}

/// A run whose contact solve fails (one Newton iteration at a tolerance it cannot meet) still
/// writes summary.json, with the failure, the steps done, and the frames before it listed.
#[test]
fn a_failed_run_writes_its_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let e = solve(
        &opts(&out, 8, &["solver.max_iterations=1", "solver.tolerance=1e-15"], false),
        None,
    )
    .unwrap_err();
    assert!(matches!(e, hvi::solver::SolveError::ContactFailed { .. }), "{e}");
    let s = summary(&out);
    let status = s["status"].as_str().unwrap();
    assert!(status.starts_with("failed: contact solve failed at step"), "{status}");
    let failed_at = match e {
        hvi::solver::SolveError::ContactFailed { step, .. } => step,
        _ => unreachable!(),
    };
    // steps before the failing one were computed and written (every step is an output step)
    assert_eq!(s["steps_done"], failed_at);
    assert_eq!(pvd_entries(&out.join("solution.pvd")).len(), failed_at);
    if failed_at > 0 {
        assert_eq!(s["last_step_written"], failed_at - 1);
    }
}

/// A run stopped by the stop flag (Ctrl-C) writes summary.json with status "interrupted".
#[test]
fn an_interrupted_run_writes_its_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let stop = std::sync::atomic::AtomicBool::new(true);
    let e = solve(&opts(&out, 4, &[], false), Some(&stop)).unwrap_err();
    assert!(matches!(e, hvi::solver::SolveError::Interrupted { .. }), "{e}");
    let s = summary(&out);
    assert_eq!(s["status"], "interrupted");
    assert_eq!(s["steps_done"], 0);
    assert!(s["last_step_written"].is_null());
}

/// `output.active_scalar` (docs/method.md §12.3) names the body's active scalars — what ParaView
/// (and `hvi plot`) colour by — among the point fields the run writes; any other value is an
/// error naming the key, the value and the valid names, before anything is written.
#[test]
fn the_active_scalar_is_the_scenes_choice_among_the_written_fields() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("u");
    solve(&opts(&out, 2, &["output.active_scalar=\"displacement\""], false), None).unwrap();
    let h = header(&out.join("solution_00002.vtu"));
    assert!(
        h.contains("<PointData Scalars=\"displacement\" Vectors=\"displacement\" Tensors=\"stress\">"),
        "{h}"
    );
    // no cell field of that name: the cells keep their first scalar
    assert!(h.contains("<CellData Scalars=\"von_mises\" Tensors=\"stress\">"), "{h}");
    let out = dir.path().join("s");
    solve(&opts(&out, 2, &["output.active_scalar=\"stress\""], false), None).unwrap();
    let h = header(&out.join("solution_00002.vtu"));
    assert!(
        h.contains("<PointData Scalars=\"stress\" Vectors=\"displacement\" Tensors=\"stress\">"),
        "{h}"
    );
    assert!(h.contains("<CellData Scalars=\"stress\" Tensors=\"stress\">"), "{h}");

    let bad = dir.path().join("bad");
    let e = solve(&opts(&bad, 2, &["output.active_scalar=\"u_nu\""], false), None)
        .unwrap_err()
        .to_string();
    for part in [
        "output.active_scalar",
        "\"u_nu\"",
        "\"von_mises\", \"displacement\", \"stress\"",
    ] {
        assert!(e.contains(part), "no {part:?} in: {e}");
    }
    // a field the run does not write is not offered
    let e = solve(
        &opts(
            &bad,
            2,
            &[
                "output.fields=[\"displacement\", \"von_mises\"]",
                "output.active_scalar=\"stress\"",
            ],
            false,
        ),
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("\"stress\"")
            && e.contains("\"von_mises\", \"displacement\"")
            && !e.contains("\"von_mises\", \"displacement\", \"stress\""),
        "{e}"
    );
    assert!(!bad.exists(), "the refused run created {}", bad.display());
}
