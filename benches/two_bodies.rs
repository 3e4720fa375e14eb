//! Issue 44's cost floor: "at equal m, a two-body step costs at most 1.5× a one-body step against
//! a rigid foundation" (docs/method.md §18.5). One mesh, two stacked blocks (0, 2) × (0, 1) and
//! (0, 2) × (1, 2): the lower of 2N × N/2 quadrilaterals, the upper of (2N − 1) × N/2 triangles'
//! squares (non-matching along the interface), a Prony memory term on both, the upper top pushed
//! down over `STEPS` steps; and in 3D the same with hexahedra below and tetrahedra above. Two variants with the same unknowns and the same m = 2N contact rows:
//!
//! * **pair**: the upper bottom (slave) against the lower top (master), mortar rows;
//! * **foundation**: the upper bottom against a rigid plane at y = 1 (`bound = "0"`), the lower
//!   block clamped at its bottom and pressed on its top by a pressure of the contact's size (the
//!   same factorisation size, no master terms; unloaded, its zero right-hand sides would make the
//!   sweeps skip half the work and the comparison unfair).
//!
//! Run interleaved `HVI_BENCH_REPS` times (default 5); printed are the medians of the whole run,
//! of its contact phase, and the time of the pairing with its mortar integrals alone.
//!
//! `cargo bench --bench two_bodies`

use hvi::app::MemorySink;
use hvi::contact::{mortar, pairing::SurfacePair};
use hvi::mesh::structured::{block, rectangle, stack, CellShape, SolidShape};
use hvi::mesh::{GroupSelector, Mesh};
use hvi::scene::Scene;
use hvi::solver::timeloop::run;
use hvi::solver::Simulation;
use std::time::Instant;

const N: usize = 128;
const M: usize = 16;
const STEPS: usize = 32;

fn mesh() -> Mesh<2> {
    stack(
        rectangle(2.0, 1.0, 2 * N, N / 2, CellShape::Quad),
        rectangle(2.0, 1.0, 2 * N - 1, N / 2, CellShape::Tri),
        1.0,
    )
}

/// The 3D stack: (0, 2) × (0, 1) × (0, 1) boxes, hexahedra 2M × M/2 × M below, tetrahedra
/// (2M − 1) × M/2 × (M − 1) above.
fn mesh_3d() -> Mesh<3> {
    stack(
        block([2.0, 1.0, 1.0], [2 * M, M / 2, M], SolidShape::Hex),
        block([2.0, 1.0, 1.0], [2 * M - 1, M / 2, M - 1], SolidShape::Tet),
        1.0,
    )
}

fn scene(pair: bool, dim: usize) -> Scene {
    let contact = if pair {
        "[[contact]]\ngroup = \"UpperBottom\"\ntarget = \"LowerTop\"\n"
    } else {
        "[[contact]]\ngroup = \"UpperBottom\"\nbound = \"0\"\n\
         [[traction]]\ngroup = \"LowerTop\"\npressure = \"0.005*t\"\n"
    };
    let (plane, sides, clamped) = if dim == 2 {
        ("plane = \"strain\"\n", "", "[\"x\", \"y\"]")
    } else {
        (
            "",
            "[[dirichlet]]\ngroup = \"UpperSides\"\ncomponents = [\"z\"]\n",
            "[\"x\", \"y\", \"z\"]",
        )
    };
    let text = format!(
        "[material]\n{plane}youngs_modulus = 1.0\npoisson_ratio = 0.3\n\
         [memory]\nkind = \"exponential\"\nterms = [{{ coefficient = -0.5, relaxation_time = 0.5 }}]\n\
         [time]\nfinal_time = 1.0\nsteps = {STEPS}\n\
         [[dirichlet]]\ngroup = \"LowerBottom\"\ncomponents = {clamped}\n\
         [[dirichlet]]\ngroup = \"UpperLeft\"\ncomponents = [\"x\"]\n{sides}\
         [[dirichlet]]\ngroup = \"UpperTop\"\ncomponents = [\"y\"]\nvalue = [\"-0.01*t*(1 + 0.5*x)\"]\n\
         {contact}[output]\nevery = {STEPS}\nfields = [\"displacement\", \"contact\"]\n"
    );
    Scene::from_toml_str(&text, "<bench scene>").unwrap_or_else(|e| panic!("{e}"))
}

/// (whole run in seconds, contact phase in seconds, contact rows).
fn whole_run(pair: bool, dim: usize) -> (f64, f64, usize) {
    let scene = scene(pair, dim);
    let start = Instant::now();
    let stats = if dim == 2 {
        let sim = Simulation::new(&scene, mesh()).expect("simulation");
        run(&sim, &mut MemorySink::default(), None).expect("run")
    } else {
        let sim = Simulation::new(&scene, mesh_3d()).expect("simulation");
        run(&sim, &mut MemorySink::default(), None).expect("run")
    };
    if std::env::var_os("HVI_BENCH_PHASES").is_some() {
        eprintln!(
            "{dim}D pair {pair}: {:?}; solves {}, sparse forward sweeps {}, factor entries {}, condensation {:?}, ordering {:?}",
            stats.phases, stats.solves, stats.sparse_forward_sweeps, stats.factor_entries, stats.condensation, stats.ordering
        );
    }
    (start.elapsed().as_secs_f64(), stats.phases.contact, stats.contact_nodes)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The pairing of UpperBottom with LowerTop and its mortar integrals, in seconds.
fn pairing<const D: usize>(m: &Mesh<D>) -> f64 {
    let start = Instant::now();
    let slave = m.boundary(&GroupSelector::Name("UpperBottom".into())).unwrap();
    let master = m.boundary(&GroupSelector::Name("LowerTop".into())).unwrap();
    let pair = SurfacePair::new(&m.points, slave, master).unwrap();
    let rows = mortar::rows(&m.points, &pair, false);
    assert!(rows.iter().all(|r| r.is_some()));
    start.elapsed().as_secs_f64()
}

fn main() {
    let reps: usize = std::env::var("HVI_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    for dim in [2, 3] {
        whole_run(true, dim); // warm-up (page cache, allocator)
        let (mut wall, mut contact) = ([Vec::new(), Vec::new()], [Vec::new(), Vec::new()]);
        let mut rows = [0, 0];
        let mut pairings = Vec::new();
        for _ in 0..reps {
            for (i, pair) in [true, false].into_iter().enumerate() {
                let (w, c, r) = whole_run(pair, dim);
                wall[i].push(w);
                contact[i].push(c);
                rows[i] = r;
            }
            pairings.push(if dim == 2 {
                pairing(&mesh())
            } else {
                pairing(&mesh_3d())
            });
        }
        let unknowns = if dim == 2 {
            2 * mesh().points.len()
        } else {
            3 * mesh_3d().points.len()
        };
        let (w0, w1) = (median(wall[0].clone()), median(wall[1].clone()));
        let (c0, c1) = (median(contact[0].clone()), median(contact[1].clone()));
        println!(
            "\ntwo bodies in {dim}D, {unknowns} unknowns, m = {} / {} contact rows, {STEPS} steps, {reps} interleaved \
             repetitions, medians:\n  \
             pair:       whole run {w0:.3} s, contact phase {:.1} ms\n  \
             foundation: whole run {w1:.3} s, contact phase {:.1} ms\n  \
             ratio pair / foundation: whole run {:.3}, contact phase {:.3}\n  \
             pairing and mortar integrals: {:.2} ms",
            rows[0],
            rows[1],
            c0 * 1e3,
            c1 * 1e3,
            w0 / w1,
            c0 / c1,
            median(pairings) * 1e3
        );
    }
}
