//! The factorisation of K = K_A + (k/2) b(0) K_B of the paper's example against SuiteSparse
//! CHOLMOD on the same matrix, in the same run (issue 3: the ratio must be ≤ 1).
//!
//! `cargo bench --bench factor_vs_cholmod` — needs python3 with scikit-sparse
//! (`pip install "scikit-sparse<0.5"`, Debian's libsuitesparse-dev); without it, prints faer's
//! times and says what is missing. Sizes: h = 1/128 and 1/256 (Q1, square cells).
//! `HVI_KEEP_MTX=1` keeps the MatrixMarket files (in the temp directory) for other tools.

use hvi::fem::assembly::assemble_stiffness;
use hvi::linalg::{Counters, Factor};
use hvi::material::IDENTITY_TENSOR;
use hvi::mesh::structured::{rectangle, CellShape};
use hvi::scene::Scene;
use hvi::solver::Simulation;
use std::io::Write;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn main() {
    hvi::linalg::set_parallelism(1);
    let repeats = 7;
    for n in [128usize, 256] {
        let scene = Scene::load(None, &[format!("time.steps={n}")]).expect("embedded scene");
        let sim = Simulation::new(&scene, rectangle(2.0, 1.0, 2 * n, n, CellShape::Quad)).expect("paper example");
        let [k_a, k_b] = assemble_stiffness(
            &sim.mesh.cells,
            &sim.mesh.points,
            &sim.dofs,
            &[sim.materials.list()[0].elasticity.tensor(), IDENTITY_TENSOR],
        );
        let k = 1.0 / n as f64;
        let matrix = k_a.plus_scaled(0.5 * k * 0.25, &k_b).with_identity_rows(&sim.dofs); // b(0) = 0.25 for (0.5 + s)²
        let counters = Counters::default();
        let (mut sym, mut num, mut sol) = (vec![], vec![], vec![]);
        let rhs: Vec<f64> = {
            let ones = vec![1.0; matrix.n()];
            let mut y = vec![0.0; matrix.n()];
            matrix.matvec(&ones, &mut y);
            y
        };
        let mut err = 0.0f64;
        for _ in 0..repeats {
            let t = Instant::now();
            let s = Factor::analyse(&matrix).unwrap();
            sym.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let f = Factor::new(&s, &matrix, &counters).unwrap();
            num.push(t.elapsed().as_secs_f64());
            let mut x = rhs.clone();
            let t = Instant::now();
            f.solve_in_place(&mut x, &counters);
            sol.push(t.elapsed().as_secs_f64());
            err = x.iter().fold(0.0, |a, v| a.max((v - 1.0).abs()));
        }
        let (fs, fnum, fsol) = (median(sym), median(num), median(sol));
        println!(
            "h = 1/{n}: {} unknowns, {} stored entries",
            matrix.n(),
            matrix.values.len()
        );
        println!("  faer    symbolic {fs:.4} s  numeric {fnum:.4} s  solve {fsol:.5} s  (max error {err:.1e})");

        // the same matrix, lower triangle, in MatrixMarket for CHOLMOD
        let path = std::env::temp_dir().join(format!("hvi_paper_K_{n}.mtx"));
        let sym_pattern = matrix.pattern.symbolic();
        let (cp, ri) = (sym_pattern.col_ptr(), sym_pattern.row_idx());
        let mut text = String::new();
        let mut entries = 0;
        for j in 0..matrix.n() {
            for (&i, v) in ri[cp[j]..cp[j + 1]].iter().zip(&matrix.values[cp[j]..cp[j + 1]]) {
                if i >= j {
                    entries += 1;
                    text.push_str(&format!("{} {} {v:e}\n", i + 1, j + 1));
                }
            }
        }
        let mut file = std::fs::File::create(&path).unwrap();
        writeln!(
            file,
            "%%MatrixMarket matrix coordinate real symmetric\n{} {} {entries}",
            matrix.n(),
            matrix.n()
        )
        .unwrap();
        file.write_all(text.as_bytes()).unwrap();
        drop(file);
        let script = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/cholmod_time.py");
        match std::process::Command::new("python3")
            .arg(script)
            .arg(&path)
            .arg(repeats.to_string())
            .output()
        {
            Ok(out) if out.status.success() => {
                let line = String::from_utf8_lossy(&out.stdout);
                let v: serde_json::Value = serde_json::from_str(line.trim()).unwrap();
                let (cs, cn, csol) = (
                    v["symbolic"].as_f64().unwrap(),
                    v["numeric"].as_f64().unwrap(),
                    v["solve"].as_f64().unwrap(),
                );
                println!(
                    "  CHOLMOD symbolic {cs:.4} s  numeric {cn:.4} s  solve {csol:.5} s  (nnz(L) {})",
                    v["nnz_factor"]
                );
                println!(
                    "  ratio faer / CHOLMOD: numeric {:.2}, symbolic + numeric {:.2}, solve {:.2}",
                    fnum / cn,
                    (fs + fnum) / (cs + cn),
                    fsol / csol
                );
            }
            Ok(out) => println!(
                "  CHOLMOD not measured: {}",
                String::from_utf8_lossy(&out.stderr).lines().last().unwrap_or("")
            ),
            Err(e) => println!("  CHOLMOD not measured: python3 not runnable ({e})"),
        }
        if std::env::var_os("HVI_KEEP_MTX").is_none() {
            let _ = std::fs::remove_file(&path);
        }
    }
}
