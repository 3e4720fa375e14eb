//! Work–precision of Hertz on linear and second-order meshes (docs/method.md §19.3, README's
//! "Second-order meshes"): per mesh the unknowns, the rows in contact, the errors of a and p₀
//! against the closed form (the fit of tests/common.rs `hertz_fit`) and the time of the whole
//! run a user pays — `Simulation::new` (contact rows, assembly, factorisation, condensation) and
//! the time loop (one elastic step) into memory, no output. Medians of `HVI_BENCH_REPEATS`
//! (default 3) runs, the meshes interleaved within each repeat. `HVI_BENCH_DIM` = 2 or 3 runs one
//! dimension only.
//!
//! Meshes: 2D, the gallery's linear triangles (examples/gallery/hertz_2d, a/8, a/16, a/33) and
//! gmsh's 6-node triangles of the same geometry (meshes/second_order/hertz_2d_p2_a{4,8,16});
//! 3D, the gallery's linear tetrahedra (a/14), gmsh's 10-node tetrahedra (a/7, a/10) and the
//! graded hexahedra of tests/common.rs `hertz_3d_hexahedra` (h = 0.16/f on the contact patch,
//! a ≈ 0.102) with 8 and 27 nodes.
//!
//! `cargo bench --bench hertz_work_precision`

#[path = "../tests/common.rs"]
mod common;

use hvi::app::solve_in_memory;
use hvi::mesh::structured::elevate;
use hvi::mesh::{read_mesh, Mesh};
use hvi::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

enum AnyMesh {
    Two(Mesh<2>),
    Three(Mesh<3>),
}

struct Case {
    label: String,
    scene: &'static str,
    mesh: AnyMesh,
}

/// (seconds, unknowns, rows in contact, error of a, error of p₀)
fn one<const D: usize>(scene: &Scene, mesh: Mesh<D>, symmetry: f64) -> (f64, usize, usize, f64, f64) {
    let unknowns = D * mesh.points.len();
    let t = Instant::now();
    let (sim, _, sink) = solve_in_memory(scene, mesh).unwrap_or_else(|e| panic!("{e}"));
    let seconds = t.elapsed().as_secs_f64();
    let state = sink.steps.last().unwrap().contact.as_ref().unwrap();
    let force = symmetry * state.force.iter().sum::<f64>();
    let pressures = common::bound_pressures(&sim, &sink);
    let (ea, ep) = common::hertz_errors(force, &pressures, D, 1.0 / (1.0 - 0.3f64 * 0.3));
    (seconds, unknowns, pressures.len(), ea, ep)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let repeats: usize = std::env::var("HVI_BENCH_REPEATS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let dims: Vec<usize> = match std::env::var("HVI_BENCH_DIM").as_deref() {
        Ok("2") => vec![2],
        Ok("3") => vec![3],
        _ => vec![2, 3],
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let gallery = |entry: &str, file: &str| -> PathBuf { root.join("examples/gallery").join(entry).join(file) };
    let second = |file: &str| -> PathBuf { root.join("meshes/second_order").join(file) };
    let read2 = |p: PathBuf| AnyMesh::Two(read_mesh::<2>(&p).unwrap_or_else(|e| panic!("{e}")));
    let read3 = |p: PathBuf| AnyMesh::Three(read_mesh::<3>(&p).unwrap_or_else(|e| panic!("{e}")));
    let case = |label: &str, scene, mesh| Case {
        label: label.into(),
        scene,
        mesh,
    };
    let mut cases = Vec::new();
    if dims.contains(&2) {
        for (label, file) in [("a/8", "h1"), ("a/16", "h2"), ("a/33", "h3")] {
            let path = gallery("hertz_2d", &format!("hertz_2d_{file}.msh"));
            cases.push(case(&format!("2D 3-node triangles {label}"), "hertz_2d", read2(path)));
        }
        for size in ["a4", "a8", "a16"] {
            let path = second(&format!("hertz_2d_p2_{size}.msh"));
            let label = format!("2D 6-node triangles a/{}", &size[1..]);
            cases.push(case(&label, "hertz_2d", read2(path)));
        }
    }
    if dims.contains(&3) {
        let path = gallery("hertz_3d", "hertz_3d.msh");
        cases.push(case("3D 4-node tetrahedra a/14", "hertz_3d", read3(path)));
        for size in ["a7", "a10"] {
            let path = second(&format!("hertz_3d_tet10_{size}.msh"));
            let label = format!("3D 10-node tetrahedra a/{}", &size[1..]);
            cases.push(case(&label, "hertz_3d", read3(path)));
        }
        // h = 0.16/f on the patch, a ≈ 0.102: a/h = 0.64 f
        let a_over = |f: usize| format!("{:.1}", 0.102 / (0.16 / f as f64));
        for f in [6, 8, 12] {
            let mesh = AnyMesh::Three(common::hertz_3d_hexahedra(f, 1.3));
            cases.push(case(&format!("3D 8-node hexahedra a/{}", a_over(f)), "hertz_3d", mesh));
        }
        for f in [4, 6] {
            let mesh = AnyMesh::Three(elevate(&common::hertz_3d_hexahedra(f, 1.3), true));
            cases.push(case(&format!("3D 27-node hexahedra a/{}", a_over(f)), "hertz_3d", mesh));
        }
    }
    let scene = |entry: &str| {
        Scene::load(Some(&gallery(entry, &format!("{entry}.toml"))), &[]).unwrap_or_else(|e| panic!("{e}"))
    };
    let scenes = [("hertz_2d", scene("hertz_2d")), ("hertz_3d", scene("hertz_3d"))];
    let scene_of = |name: &str| &scenes.iter().find(|(n, _)| *n == name).unwrap().1;
    let mut times = vec![Vec::new(); cases.len()];
    let mut results = vec![(0, 0, 0.0, 0.0); cases.len()];
    for _ in 0..repeats {
        for (k, c) in cases.iter().enumerate() {
            let scene = scene_of(c.scene);
            // the 2D half model carries half the force per unit length, the 3D quarter a quarter
            let (t, n, rows, ea, ep) = match &c.mesh {
                AnyMesh::Two(m) => one(scene, m.clone(), 2.0),
                AnyMesh::Three(m) => one(scene, m.clone(), 4.0),
            };
            times[k].push(t);
            results[k] = (n, rows, ea, ep);
        }
    }
    println!("hertz_work_precision: medians of {repeats} whole runs, interleaved");
    println!("| mesh | unknowns | rows in contact | a | p₀ | run (s) |");
    println!("|---|--:|--:|--:|--:|--:|");
    for (c, (t, (n, rows, ea, ep))) in cases.iter().zip(times.into_iter().zip(results)) {
        println!(
            "| {} | {n} | {rows} | {:+.2} % | {:+.2} % | {:.3} |",
            c.label,
            100.0 * ea,
            100.0 * ep,
            median(t)
        );
    }
}
