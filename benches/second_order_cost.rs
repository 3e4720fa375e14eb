//! What second-order cells cost per unknown in 3D (docs/method.md §19.5): the slab scene
//! (examples/slab.toml, elastic part K_A with its memory term as the time loop factors it) on
//! the box 2 × 1 × 0.25, linear cells of 4m × 2m × 2⌈m/4⌉ against second-order cells of
//! 2m × m × ⌈m/4⌉ raised by `mesh::structured::elevate` — the same nodes, so the same unknowns.
//! Per mesh: the entries of K and of the factor (hvi's `Analysis::factor_entries`), the assembly of
//! K_A and K_B, their sum with the prescribed rows made identity rows (the step matrix), symbolic
//! analysis and numeric factorisation; medians of `HVI_BENCH_REPEATS` (default 5) runs, the kinds
//! interleaved within each repeat. Sizes: `HVI_BENCH_M` (default `12,16`).
//!
//! `cargo bench --bench second_order_cost`

use hvi::fem::assembly::assemble_stiffness;
use hvi::linalg::{Counters, Factor};
use hvi::material::IDENTITY_TENSOR;
use hvi::mesh::structured::{block, elevate, SolidShape};
use hvi::scene::Scene;
use hvi::solver::Simulation;
use std::path::Path;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// ([assembly of K_A and K_B s, their sum with the identity rows s, analysis s, factorisation s],
/// [entries of K, factor entries])
fn one(sim: &Simulation<3>) -> ([f64; 4], [usize; 2]) {
    let t = Instant::now();
    let tensors = [sim.materials.list()[0].elasticity.tensor(), IDENTITY_TENSOR];
    let [k_a, k_b] = assemble_stiffness(&sim.mesh.cells, &sim.mesh.points, &sim.dofs, &tensors);
    let assembly = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let b0 = sim.materials.memory().map_or(0.0, |m| m.kernel_value(0, 0.0));
    let matrix = k_a
        .plus_scaled(0.5 * sim.time.first_step() * b0, &k_b)
        .with_identity_rows(&sim.dofs);
    let sum = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let analysis = Factor::analyse(&matrix).expect("analysis");
    let symbolic = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let factor = Factor::new(&analysis, &matrix, &Counters::default()).expect("factorisation");
    let numeric = t.elapsed().as_secs_f64();
    drop(factor);
    (
        [assembly, sum, symbolic, numeric],
        [k_a.pattern.nnz(), analysis.factor_entries()],
    )
}

fn main() {
    let repeats: usize = std::env::var("HVI_BENCH_REPEATS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let sizes: Vec<usize> = std::env::var("HVI_BENCH_M")
        .unwrap_or_else(|_| "12,16".into())
        .split(',')
        .map(|s| s.trim().parse().expect("HVI_BENCH_M: sizes m, comma-separated"))
        .collect();
    let slab = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/slab.toml");
    let scene = Scene::load(Some(&slab), &[]).expect("examples/slab.toml");
    println!("second_order_cost: medians of {repeats}, interleaved; times in s");
    println!("| m | cells | unknowns | entries of K | factor entries | assembly | sum | analysis | factorisation |");
    println!("|---|---|--:|--:|--:|--:|--:|--:|--:|");
    for m in sizes {
        let z = m.div_ceil(4);
        let mut sims = Vec::new();
        for (label, shape) in [("hex", SolidShape::Hex), ("tet", SolidShape::Tet)] {
            let linear = block([2.0, 1.0, 0.25], [4 * m, 2 * m, 2 * z], shape);
            let coarse = block([2.0, 1.0, 0.25], [2 * m, m, z], shape);
            let quadratic = elevate(&coarse, true);
            assert_eq!(linear.points.len(), quadratic.points.len(), "the same nodes");
            let second = if label == "hex" { "hex27" } else { "tet10" };
            let first = if label == "hex" { "hex8" } else { "tet4" };
            sims.push((first, Simulation::new(&scene, linear).expect("slab on the box")));
            sims.push((second, Simulation::new(&scene, quadratic).expect("slab on the box")));
        }
        let mut times: Vec<[Vec<f64>; 4]> = vec![Default::default(); sims.len()];
        let mut entries = vec![[0; 2]; sims.len()];
        for _ in 0..repeats {
            for (k, (_, sim)) in sims.iter().enumerate() {
                let (t, e) = one(sim);
                for (list, t) in times[k].iter_mut().zip(t) {
                    list.push(t);
                }
                entries[k] = e;
            }
        }
        for (k, (label, sim)) in sims.iter().enumerate() {
            let [a, sum, s, f] = times[k].clone().map(median);
            println!(
                "| {m} | {label} ({}) | {} | {} | {} | {a:.3} | {sum:.3} | {s:.3} | {f:.3} |",
                sim.mesh.cells.len(),
                3 * sim.mesh.points.len(),
                entries[k][0],
                entries[k][1]
            );
        }
    }
}
