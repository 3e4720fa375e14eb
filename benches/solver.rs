//! Benchmarks of the phases of a run on the paper's example (Q1, square cells h × h):
//! assembly, symbolic and numeric factorisation, one solve with the cached factor (a forward
//! and a backward sweep, on two threads when rayon has them), the contact condensation
//! (G = L⁻¹PCᵀ and W = GᵀG), one full time step (memory load, forward sweep, contact solve,
//! backward sweep, history update), and whole runs at h = k = 1/64 and 1/128. Issue 3's floor:
//! one time step ≤ 3× one solve.
//!
//! `cargo bench --bench solver` (criterion; medians in target/criterion). Set
//! `HVI_BENCH_FULL=1` to include the h = k = 1/128 whole run.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use hvi::app::MemorySink;
use hvi::fem::assembly::assemble_stiffness;
use hvi::linalg::{Counters, Factor};
use hvi::material::IDENTITY_TENSOR;
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::scene::Scene;
use hvi::solver::timeloop::{run, Stepper};
use hvi::solver::Simulation;
use std::time::Duration;

fn paper(n: usize, steps: usize) -> Simulation<2> {
    // only the last frame is kept (output.every = steps)
    let scene =
        Scene::load(None, &[format!("time.steps={steps}"), format!("output.every={steps}")]).expect("embedded scene");
    Simulation::new(&scene, rectangle(2.0, 1.0, 2 * n, n, CellShape::Quad)).expect("paper example")
}

fn phases(c: &mut Criterion) {
    // as in a run (Simulation::threads = 1: sequential measured faster on 2 cores)
    hvi::linalg::set_parallelism(1);
    for n in [64, 128] {
        let sim = paper(n, n);
        let d = sim.materials.list()[0].elasticity.tensor();
        let mut g = c.benchmark_group(format!("h=1/{n}"));
        g.sample_size(20).measurement_time(Duration::from_secs(4));
        g.bench_function("assembly K_A+K_B", |b| {
            b.iter(|| assemble_stiffness(&sim.mesh.cells, &sim.mesh.points, &sim.dofs, &[d, IDENTITY_TENSOR]))
        });
        let [k] = assemble_stiffness(&sim.mesh.cells, &sim.mesh.points, &sim.dofs, &[d]);
        let k = k.with_identity_rows(&sim.dofs);
        let counters = Counters::default();
        g.bench_function("symbolic factorisation", |b| b.iter(|| Factor::analyse(&k).unwrap()));
        let symbolic = Factor::analyse(&k).unwrap();
        g.bench_function("numeric factorisation", |b| {
            b.iter(|| Factor::new(&symbolic, &k, &counters).unwrap())
        });
        let factor = std::sync::Arc::new(Factor::new(&symbolic, &k, &counters).unwrap());
        let rhs: Vec<f64> = (0..k.n()).map(|i| (i as f64).sin()).collect();
        g.bench_function("one solve", |b| {
            b.iter_batched_ref(
                || rhs.clone(),
                |x| factor.solve_in_place(x, &counters),
                BatchSize::SmallInput,
            )
        });
        let nodes = &sim.contact.as_ref().unwrap().nodes;
        g.sample_size(10);
        g.bench_function("contact condensation", |b| {
            b.iter(|| hvi::contact::SplitSweeps::new(nodes, factor.clone(), &counters).unwrap())
        });
        // one full step (history, free solve, contact, recover) in the middle of the run
        g.bench_function("one time step", |b| {
            b.iter_batched_ref(
                || {
                    let mut s = Stepper::prepare(&sim).unwrap();
                    for _ in 0..n / 2 {
                        s.advance_next().unwrap();
                    }
                    s
                },
                |s| {
                    s.advance_next().unwrap();
                },
                BatchSize::LargeInput,
            )
        });
        g.finish();
    }
}

fn whole_runs(c: &mut Criterion) {
    let mut sizes = vec![64];
    if std::env::var_os("HVI_BENCH_FULL").is_some() {
        sizes.push(128);
    }
    let mut g = c.benchmark_group("whole run");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    for n in sizes {
        let sim = paper(n, n);
        g.bench_function(format!("h=k=1/{n}"), |b| {
            b.iter(|| {
                let mut sink = MemorySink::default();
                run(&sim, &mut sink, None).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, phases, whole_runs);
criterion_main!(benches);
