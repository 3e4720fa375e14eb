//! Issue 10's floor "several contact groups cost what their nodes cost, no more"
//! (docs/method.md §14.8): the paper's example at h = k = 1/128 (rect 256 × 128 Q1, m = 256
//! contact nodes, the last frame written) with its contact bottom Γ₃ given as one `[[contact]]`
//! group, and the same facets split into 2 and into 4 groups of equal length with the same law and
//! bound (the nodes where two groups meet become one row carrying both groups' law terms, §14.3).
//! The three variants are run interleaved, `HVI_BENCH_REPS` times each (default 5); printed are
//! the medians of the whole run (scene set-up with the contact rows, assembly, factorisation,
//! condensation, every step) and of its contact phase (the active-set solves), their ratios to one
//! group, and how far the final displacements differ (the same problem: round-off and the
//! solver's tolerance).
//!
//! `cargo bench --bench contact_groups`

use hvi::app::MemorySink;
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::mesh::{Facet, Mesh, PhysicalGroup};
use hvi::scene::Scene;
use hvi::solver::timeloop::run;
use hvi::solver::Simulation;
use std::time::Instant;

const N: usize = 128;

/// The paper's example (examples/paper.toml) with its contact on the groups `names`.
fn scene(names: &[String]) -> Scene {
    let mut text = format!(
        "[groups]\nclamped = \"Gamma1\"\n[material]\nplane = \"stress\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n\
         [memory]\nkind = \"polynomial\"\ncoefficients = [0.25, 1.0, 1.0]\n[time]\nfinal_time = 1.0\nsteps = {N}\n\
         [[traction]]\ngroup = \"Gamma2\"\nvalue = [\"0\", \"-0.1*(1 - exp(-2*t))*x*ny\"]\n\
         [output]\nevery = {N}\nfields = [\"displacement\", \"contact\"]\n"
    );
    for g in names {
        text.push_str(&format!(
            "[[contact]]\ngroup = \"{g}\"\nbound = 0.2\n[contact.law]\nkind = \"paper\"\nscale = 0.1\na = 0.04\nb = 0.02\nalpha = 100.0\n"
        ));
    }
    Scene::from_toml_str(&text, "<bench scene>").unwrap_or_else(|e| panic!("{e}"))
}

/// The rectangle (0, 2) × (0, 1) at h = 1/128 with Γ₃ also split into `parts` groups C0, C1, …
/// of equal length.
fn mesh(parts: usize) -> (Mesh<2>, Vec<String>) {
    let mut mesh = rectangle(2.0, 1.0, 2 * N, N, CellShape::Quad);
    if parts == 1 {
        return (mesh, vec!["Gamma3".into()]);
    }
    let bottom: Vec<Facet> = mesh
        .groups
        .iter()
        .find(|g| g.name.as_deref() == Some("Gamma3"))
        .expect("Gamma3")
        .facets
        .clone();
    let mut names = Vec::new();
    for i in 0..parts {
        let (lo, hi) = (2.0 * i as f64 / parts as f64, 2.0 * (i + 1) as f64 / parts as f64);
        let facets = bottom
            .iter()
            .copied()
            .filter(|f| {
                let mid = f.nodes().iter().map(|&p| mesh.points[p][0]).sum::<f64>() / f.nodes().len() as f64;
                lo < mid && mid < hi
            })
            .collect();
        let name = format!("C{i}");
        mesh.groups.push(PhysicalGroup {
            dim: 1,
            tag: 100 + i as i32,
            name: Some(name.clone()),
            facets,
            cells: vec![],
            nodes: vec![],
        });
        names.push(name);
    }
    (mesh, names)
}

/// (whole run in seconds, contact phase in seconds, final displacement).
fn whole_run(parts: usize) -> (f64, f64, Vec<f64>) {
    let (mesh, names) = mesh(parts);
    let scene = scene(&names);
    let start = Instant::now();
    let sim = Simulation::new(&scene, mesh).expect("simulation");
    let mut sink = MemorySink::default();
    let stats = run(&sim, &mut sink, None).expect("run");
    let seconds = start.elapsed().as_secs_f64();
    assert_eq!(stats.contact_nodes, 2 * N, "{parts} groups: the same rows");
    (
        seconds,
        stats.phases.contact,
        sink.steps.pop().expect("the last frame").displacement,
    )
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let reps: usize = std::env::var("HVI_BENCH_REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let variants = [1, 2, 4];
    let mut wall = vec![Vec::new(); 3];
    let mut contact = vec![Vec::new(); 3];
    let mut last: Vec<Vec<f64>> = vec![Vec::new(); 3];
    whole_run(1); // warm-up (page cache, allocator)
    for _ in 0..reps {
        for (i, &parts) in variants.iter().enumerate() {
            let (s, c, u) = whole_run(parts);
            wall[i].push(s);
            contact[i].push(c);
            last[i] = u;
        }
    }
    let scale = last[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    println!(
        "\ncontact groups, the paper's example at h = k = 1/{N} (m = {} contact nodes), {reps} interleaved repetitions, medians:",
        2 * N
    );
    let (w1, c1) = (median(wall[0].clone()), median(contact[0].clone()));
    for (i, &parts) in variants.iter().enumerate() {
        let (w, c) = (median(wall[i].clone()), median(contact[i].clone()));
        let diff = last[i]
            .iter()
            .zip(&last[0])
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / scale;
        println!(
            "  {parts} group(s): whole run {w:.3} s ({:.3}× one group; runs {:.3}–{:.3} s), contact phase {:.1} ms ({:.3}×), final u differs from one group's by {diff:.1e}",
            w / w1,
            wall[i].iter().copied().fold(f64::INFINITY, f64::min),
            wall[i].iter().copied().fold(0.0, f64::max),
            c * 1e3,
            c / c1,
        );
        assert!(diff < 1e-8, "{parts} groups solve a different problem: {diff:e}");
    }
}
