//! Studies in 3D (docs/method.md §6): point location and nodal interpolation on tetrahedra and
//! hexahedra, and a study on the generated slab, which with u_z = 0 on its z faces is the 2D
//! plane-strain study: every error is the 2D one times √0.25 (the depth; the fields do not
//! vary in z).

use hvi::mesh::structured::{block, SolidShape};
use hvi::mesh::Mesh;
use hvi::study::{self, interpolate_nodal};
use std::path::Path;

fn rough_field(mesh: &Mesh<3>) -> Vec<[f64; 3]> {
    mesh.points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            [
                (3.0 * p[0]).sin() + 0.1 * (k as f64).cos(),
                p[0] * p[1] - 0.05 * (k as f64 * 0.7).sin(),
                p[2] * p[0] + 0.02 * (k as f64 * 1.3).cos(),
            ]
        })
        .collect()
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len(), "fields of different lengths");
    assert!(!a.is_empty(), "empty fields: nothing compared");
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |d| (x[d] - y[d]).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn nested_solid_meshes_carry_exactly_both_ways_and_linear_fields_on_any_meshes() {
    // (pyramids: the coarse boxes' centres are the centres of the fine middle boxes, so the
    // coarse nodes are fine nodes)
    for kind in [SolidShape::Hex, SolidShape::Tet, SolidShape::Pyramid] {
        let coarse = block([2.0, 1.0, 0.5], [4, 2, 1], kind);
        let fine = block([2.0, 1.0, 0.5], [12, 6, 3], kind);
        let u = rough_field(&coarse);
        // a coarse field carried to the nested fine mesh and back is itself
        let carried = interpolate_nodal(&coarse, &u, &fine.points).unwrap();
        let back = interpolate_nodal(&fine, &carried, &coarse.points).unwrap();
        assert!(max_diff(&back, &u) < 1e-13, "{kind:?}: {:e}", max_diff(&back, &u));
        // a linear field is carried exactly between non-nested meshes
        let other = block([2.0, 1.0, 0.5], [7, 5, 3], kind);
        let linear = |p: &[f64; 3]| [1.0 + p[0] - 2.0 * p[2], 0.5 * p[1] + p[2], p[0] + p[1] + p[2]];
        let u: Vec<[f64; 3]> = other.points.iter().map(linear).collect();
        let at = interpolate_nodal(&other, &u, &fine.points).unwrap();
        let exact: Vec<[f64; 3]> = fine.points.iter().map(linear).collect();
        assert!(max_diff(&at, &exact) < 1e-13, "{kind:?}: {:e}", max_diff(&at, &exact));
        // a point outside is an error naming it
        let err = interpolate_nodal(&other, &u, &[[1.0, 0.5, 0.6]]).unwrap_err();
        assert!(err.contains("outside"), "{err}");
    }
}

#[test]
fn a_study_on_the_slab_is_the_plane_strain_study_times_the_root_of_its_depth() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let run = |text: String, sub: &str| {
        let spec: study::spec::StudySpec = toml::from_str(&text).unwrap();
        let out = dir.path().join(sub);
        let written = study::execute::run_spec(&spec, &root.join("examples"), &out, &[], sub).unwrap();
        assert!(written.files.contains(&"study.csv".to_string()), "{:?}", written.files);
        let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| {
            header
                .iter()
                .position(|h| *h == name)
                .unwrap_or_else(|| panic!("{name}: {header:?}"))
        };
        let (h1, l2) = (col("h1_error"), col("l2_error"));
        lines
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                (f[h1].parse::<f64>().unwrap(), f[l2].parse::<f64>().unwrap())
            })
            .collect::<Vec<_>>()
    };
    let paths = "reference = { n = 16, steps = 16 }\n[[h_paths]]\nsteps = 16\nn = [4, 8]\n\
                 [[k_paths]]\nn = 16\nsteps = [4, 8]\n";
    let solid = run(format!("scene = \"slab.toml\"\nshape = \"hex\"\n{paths}"), "slab");
    let plane = run(
        format!("scene = \"paper.toml\"\nset = [\"material.plane=\\\"strain\\\"\"]\n{paths}"),
        "plane",
    );
    assert_eq!(solid.len(), 4);
    assert_eq!(solid.len(), plane.len());
    // both are solved to the contact tolerance 1e-10; the errors are differences of O(1e-2)
    // solutions, so they agree to about 1e-8 relative
    for (s, p) in solid.iter().zip(&plane) {
        for (a, b) in [(s.0, p.0), (s.1, p.1)] {
            assert!((a - 0.5 * b).abs() <= 1e-6 * b, "3D {a:e} against 2D {b:e} × 0.5");
        }
    }
}
