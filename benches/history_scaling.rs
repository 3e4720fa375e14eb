//! The performance floors of issue 5, as ratios on the paper's example with the coarse mesh
//! `meshes/rect_q1_h16.msh` (h = 1/16), only the last frame kept (`output.every = N`):
//!
//! * with a separable kernel (the paper's polynomial (0.5 + s)²), a whole run at N = 4096 steps
//!   takes at most 2.2× the time at N = 2048, and the peak memory does not grow with N (VmHWM of
//!   a fresh process per run: this bench re-executes itself with `HVI_BENCH_CHILD=scene:N`);
//! * an elastic-only scene costs at least 5× less per time step than the full paper scene.
//!
//! `cargo bench --bench history_scaling` (criterion; medians in target/criterion), then the
//! ratios against the floors are printed (`HVI_BENCH_REPS` repetitions each, default 5).
//! The same measurement, without criterion, is the ignored test
//! `cargo test --release --test effects history_scaling_and_per_step_cost -- --ignored --nocapture`.

use criterion::{BenchmarkId, Criterion};
use hvi::app::MemorySink;
use hvi::scene::Scene;
use hvi::solver::timeloop::{run, Stepper};
use hvi::solver::Simulation;
use std::path::PathBuf;
use std::time::{Duration, Instant};

const CHILD_ENV: &str = "HVI_BENCH_CHILD";
const MESH: &str = "meshes/rect_q1_h16.msh";

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `examples/scenes/<name>` with N steps, writing only the last frame, on h = 1/16.
fn simulation(name: &str, n: usize) -> Simulation<2> {
    let scene = Scene::load(
        Some(&root().join("examples/scenes").join(name)),
        &[format!("time.steps={n}"), format!("output.every={n}")],
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    let mesh = hvi::mesh::read_mesh::<2>(&root().join(MESH)).unwrap_or_else(|e| panic!("{MESH}: {e}"));
    Simulation::new(&scene, mesh).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn whole_run(sim: &Simulation<2>) -> hvi::solver::RunStats {
    let mut sink = MemorySink::default();
    run(sim, &mut sink, None).expect("run")
}

/// Seconds per step of the time loop (after the one-off setup of `Stepper::prepare`).
fn seconds_per_step(sim: &Simulation<2>) -> f64 {
    let mut stepper = Stepper::prepare(sim).expect("prepare");
    let start = Instant::now();
    for _ in 0..=sim.time.steps().unwrap() {
        stepper.advance_next().expect("step");
    }
    start.elapsed().as_secs_f64() / (sim.time.steps().unwrap() + 1) as f64
}

fn vm_hwm_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .unwrap_or_default()
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}

/// Child mode: one whole run, then its wall time and peak memory on stdout.
fn child(spec: &str) {
    let (name, n) = spec.split_once(':').expect("HVI_BENCH_CHILD=scene.toml:steps");
    let sim = simulation(name, n.parse().expect("steps"));
    let start = Instant::now();
    let stats = whole_run(&sim);
    println!(
        "HVI_BENCH seconds={} vmhwm_kib={} history_bytes={}",
        start.elapsed().as_secs_f64(),
        vm_hwm_kib(),
        stats.history_bytes
    );
}

/// (seconds, peak KiB, history bytes) of a whole run in a fresh process.
fn child_run(name: &str, n: usize) -> (f64, f64, f64) {
    let out = std::process::Command::new(std::env::current_exe().expect("current exe"))
        .env(CHILD_ENV, format!("{name}:{n}"))
        .output()
        .expect("spawn the bench child");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "child {name}:{n}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = text
        .lines()
        .find(|l| l.starts_with("HVI_BENCH "))
        .expect("child result");
    let field = |key: &str| -> f64 {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(&format!("{key}=")))
            .and_then(|v| v.parse().ok())
            .expect("field")
    };
    (field("seconds"), field("vmhwm_kib"), field("history_bytes"))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Criterion: whole runs of the paper scene at N = 2048 and 4096.
fn history_scaling(c: &mut Criterion) {
    let mut g = c.benchmark_group("history_scaling/paper h=1/16");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    for n in [2048, 4096] {
        let sim = simulation("full.toml", n);
        g.bench_with_input(BenchmarkId::new("whole run", n), &sim, |b, sim| {
            b.iter(|| whole_run(sim))
        });
    }
    g.finish();
}

/// Criterion: one time step of the time loop (step 0 and the setup not timed), elastic only vs
/// the full paper scene.
fn per_step(c: &mut Criterion) {
    let n = 4096;
    let mut g = c.benchmark_group("per_step/h=1/16");
    g.sample_size(50).measurement_time(Duration::from_secs(4));
    for name in ["elastic_only.toml", "elastic_time_dependent.toml", "full.toml"] {
        let sim = simulation(name, n);
        g.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                let mut left = iters;
                while left > 0 {
                    let mut stepper = Stepper::prepare(&sim).expect("prepare");
                    stepper.advance_next().expect("step 0");
                    let chunk = left.min(n as u64);
                    let start = Instant::now();
                    for _ in 0..chunk {
                        stepper.advance_next().expect("step");
                    }
                    total += start.elapsed();
                    left -= chunk;
                }
                total
            })
        });
    }
    g.finish();
}

/// The ratios against the floors of the issue (medians of `HVI_BENCH_REPS` repetitions).
fn floors() {
    let reps: usize = std::env::var("HVI_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let (mut t, mut m) = ([vec![], vec![]], [vec![], vec![]]);
    let mut held = [0.0; 2];
    for _ in 0..reps {
        for (i, n) in [2048, 4096].into_iter().enumerate() {
            let (s, k, b) = child_run("full.toml", n);
            t[i].push(s);
            m[i].push(k);
            held[i] = b;
        }
    }
    let (t0, t1) = (median(t[0].clone()), median(t[1].clone()));
    let (m0, m1) = (median(m[0].clone()), median(m[1].clone()));
    println!("\nfloors (h = 1/16, paper scene, polynomial kernel, {reps} repetitions, medians):");
    println!(
        "  whole run: N = 2048 {t0:.4} s, N = 4096 {t1:.4} s: ratio {:.3} (floor ≤ 2.2) {}",
        t1 / t0,
        if t1 / t0 <= 2.2 { "ok" } else { "FAILS" }
    );
    // what a direct sum would add over the extra 2048 steps (n_dof from the 3 polynomial moments)
    let direct_growth = 2048.0 * held[0] / 3.0 / 1024.0;
    println!(
        "  peak memory (VmHWM): {m0:.0} KiB vs {m1:.0} KiB (+{:.0} KiB; a direct sum would add {direct_growth:.0} KiB); history held {held:?} bytes {}",
        m1 - m0,
        if held[0] == held[1] && m1 - m0 <= 0.1 * direct_growth { "ok" } else { "FAILS" }
    );
    let n = 2048;
    let mut per = [vec![], vec![], vec![]];
    let names = ["elastic_only.toml", "elastic_time_dependent.toml", "full.toml"];
    for _ in 0..reps {
        for (i, name) in names.iter().enumerate() {
            per[i].push(seconds_per_step(&simulation(name, n)));
        }
    }
    let full = median(per[2].clone());
    for i in 0..2 {
        let e = median(per[i].clone());
        println!(
            "  per step, N = {n}: {} {:.3} µs vs full.toml {:.3} µs: {:.1}× cheaper (floor ≥ 5) {}",
            names[i],
            e * 1e6,
            full * 1e6,
            full / e,
            if full / e >= 5.0 { "ok" } else { "FAILS" }
        );
    }
}

fn main() {
    if let Ok(spec) = std::env::var(CHILD_ENV) {
        child(&spec);
        return;
    }
    let mut c = Criterion::default().configure_from_args();
    history_scaling(&mut c);
    per_step(&mut c);
    c.final_summary();
    floors();
}
