//! hvi's sparse Cholesky (faer, with hvi's choice of ordering) against SuiteSparse CHOLMOD on the
//! step matrix K = K_A + (k/2) b(0) K_B of the 3D slab (examples/slab.toml on the Q1 box
//! 2 × 1 × 0.25 with 2n × n × n/4 cells), the same matrix (one MatrixMarket file) in the same run,
//! interleaved (the floor: nnz(L) within 1.2× of CHOLMOD's best ordering and a numeric
//! factorisation no slower than CHOLMOD's).
//!
//! `cargo bench --bench factor_vs_cholmod_3d` — needs python3 with scikit-sparse
//! (`pip install "scikit-sparse<0.5"`, Debian's libsuitesparse-dev); without it, prints hvi's
//! numbers and says what is missing. CHOLMOD runs in one child process
//! (benches/cholmod_server.py) that analyses once per ordering and refactorises on request.
//!
//! Settings (environment):
//! - `HVI_BENCH_N` = sizes n (default `32,40`: 52 800 and 101 680 free unknowns);
//! - `HVI_BENCH_MESH` = gmsh files (comma-separated) instead of the slab, with the scene
//!   `HVI_BENCH_SCENE` (e.g. the graded tetrahedral blocks of benches/graded/README.md);
//! - `HVI_BENCH_REPEATS` = numeric factorisations per row, medians reported (default 5);
//! - `HVI_BENCH_THREADS` = threads for both sides (default 1, hvi's default `threads`; CHOLMOD's
//!   BLAS gets `OPENBLAS_NUM_THREADS` / `OMP_NUM_THREADS`);
//! - `HVI_CHOLMOD_BLAS=system` keeps the BLAS the dynamic linker picks for libcholmod; by default
//!   the child prefers Debian's OpenBLAS (`/usr/lib/x86_64-linux-gnu/openblas-pthread`, put first
//!   on `LD_LIBRARY_PATH`) when it is installed, since CHOLMOD's supernodal kernels are BLAS calls
//!   and the reference BLAS would make CHOLMOD several times slower than it is;
//! - `HVI_PYTHON` = the interpreter (default `python3`); `HVI_KEEP_MTX=1` keeps the files.
//!
//! nnz(L) is counted three ways, and only like with like is compared:
//! - "lower": the supernodes' lower trapezoids, relaxation zeros included — CHOLMOD's `L().nnz`
//!   (scikit-sparse converts the supernodal factor to simplicial form keeping every stored
//!   entry); for hvi, counted from the same supernodal structure as hvi's;
//! - "storage": Σ rows × columns over supernodes (the diagonal blocks in full) — faer's `len_val`,
//!   i.e. hvi's `Analysis::factor_entries()`, and CHOLMOD's `L->xsize` (recovered from `L()`'s
//!   pattern, an upper bound);
//! - "exact": the structural nnz(L) of the permutation, no relaxation (faer's simplicial analysis
//!   of the permutation each side used) — what compares the orderings alone.
//!
//! The solver's factor orders the contact rows' unknowns last; the rows `CHOLMOD metis_last` and
//! `CHOLMOD nesdis_last` hold CHOLMOD to the same constraint the way the peer
//! (benches/numpy_reference_3d.py) does — its ordering of K without those unknowns, them appended
//! — and the last line compares the solver's factor with the better of them (issue 22).
//!
//! Both sides see the pattern hvi analyses: the couplings of a prescribed component's identity
//! row (stored zeros) are left out (`Structure`), as src/linalg/factor.rs does.
//!
//! hvi's `Analysis` does not expose its permutation or supernodes, so the bench recomputes hvi's
//! node orderings the way `src/linalg/factor.rs` does (AMD and METIS NodeND on the node graph,
//! expanded to the unknowns) and checks that faer's analysis of them has exactly
//! `factor_entries()` entries. Diagnostic rows (not hvi's code path) time faer's numeric
//! factorisation on CHOLMOD's best permutation and on hvi's ND permutation postordered like
//! CHOLMOD's (children by increasing column count), to tell ordering from kernels.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::Side;
use hvi::fem::assembly::assemble_stiffness;
use hvi::fem::SymmetricMatrix;
use hvi::linalg::{decoupled_unknowns, Analysis, Counters, Factor, NodeOrdering};
use hvi::material::IDENTITY_TENSOR;
use hvi::mesh::structured::{block, SolidShape};
use hvi::scene::Scene;
use hvi::solver::Simulation;
use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::time::Instant;

const NONE: usize = usize::MAX;
const OPENBLAS_DIR: &str = "/usr/lib/x86_64-linux-gnu/openblas-pthread";
const CHOLMOD_ORDERINGS: [&str; 4] = ["default", "amd", "metis", "nesdis"];
/// The peer's orderings (benches/numpy_reference_3d.py): CHOLMOD's METIS or NESDIS on K without
/// the unknowns the solver orders last, those appended — what the solver's factor is held to.
const CHOLMOD_LAST: [&str; 2] = ["metis_last", "nesdis_last"];

fn constrained(name: &str) -> bool {
    name.ends_with("_last")
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// A permutation of the unknowns: entry i of the permuted order is original unknown fwd[i].
struct Perm {
    fwd: Vec<usize>,
    inv: Vec<usize>,
}

impl Perm {
    fn from_fwd(fwd: Vec<usize>) -> Result<Perm, String> {
        let mut inv = vec![NONE; fwd.len()];
        for (i, &p) in fwd.iter().enumerate() {
            if p >= fwd.len() || inv[p] != NONE {
                return Err(format!("not a permutation (entry {i} = {p})"));
            }
            inv[p] = i;
        }
        Ok(Perm { fwd, inv })
    }

    fn as_faer(&self) -> PermRef<'_, usize> {
        PermRef::new_checked(&self.fwd, &self.inv, self.fwd.len())
    }
}

/// faer's symbolic Cholesky of the matrix under `perm`, supernodal (hvi's parameters) or simplicial.
/// The matrix's pattern as hvi's analysis sees it (src/linalg/factor.rs): the unknowns
/// [`decoupled_unknowns`] finds (prescribed components' identity rows, whose couplings are
/// stored zeros) have their couplings left out. Counting the factor on the stored
/// pattern instead made the bench's copy of hvi's orderings (which put those unknowns first)
/// fill 20× more than hvi's factor. CHOLMOD is given the same pattern.
struct Structure {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    decoupled: Vec<bool>,
}

impl Structure {
    fn of(matrix: &SymmetricMatrix) -> Self {
        let sym = matrix.pattern.symbolic();
        let (cp, ri) = (sym.col_ptr(), sym.row_idx());
        let n = matrix.n();
        let decoupled = decoupled_unknowns(matrix);
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::with_capacity(ri.len()), Vec::new());
        for j in 0..n {
            for (&i, &v) in ri[cp[j]..cp[j + 1]].iter().zip(&matrix.values[cp[j]..cp[j + 1]]) {
                if i == j || !(decoupled[i] || decoupled[j]) {
                    row_idx.push(i);
                    values.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        Structure {
            n,
            col_ptr,
            row_idx,
            values,
            decoupled,
        }
    }

    fn symbolic(&self) -> faer::sparse::SymbolicSparseColMatRef<'_, usize> {
        faer::sparse::SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }

    /// The matrix on this pattern (both triangles), for faer's numeric factorisation.
    fn matrix(&self) -> faer::sparse::SparseColMatRef<'_, usize, f64> {
        faer::sparse::SparseColMatRef::new(self.symbolic(), &self.values)
    }
}

fn symbolic(structure: &Structure, perm: &Perm, supernodal: bool) -> SymbolicCholesky<usize> {
    let params = CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: if supernodal {
            SupernodalThreshold::FORCE_SUPERNODAL
        } else {
            SupernodalThreshold::FORCE_SIMPLICIAL
        },
        ..Default::default()
    };
    factorize_symbolic_cholesky(
        structure.symbolic(),
        Side::Lower,
        SymmetricOrdering::Custom(perm.as_faer()),
        params,
    )
    .expect("faer symbolic analysis")
}

/// The three counts of nnz(L) (see the module notes) and the number of supernodes.
#[derive(Clone, Copy, Default)]
struct Counts {
    lower: usize,
    storage: usize,
    exact: usize,
    supernodes: usize,
}

/// faer's counts under `perm`, with the exact column counts (permuted order).
fn faer_counts(structure: &Structure, perm: &Perm) -> (Counts, Vec<usize>) {
    let simplicial = symbolic(structure, perm, false);
    let col_counts: Vec<usize> = match simplicial.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr().windows(2).map(|w| w[1] - w[0]).collect(),
        SymbolicCholeskyRaw::Supernodal(_) => unreachable!("forced simplicial"),
    };
    let supernodal = symbolic(structure, perm, true);
    let SymbolicCholeskyRaw::Supernodal(sn) = supernodal.raw() else {
        unreachable!("forced supernodal")
    };
    let mut lower = 0;
    for s in 0..sn.n_supernodes() {
        let ncols = sn.supernode_end()[s] - sn.supernode_begin()[s];
        let below = sn.supernode(s).pattern().len();
        lower += ncols * (ncols + 1) / 2 + below * ncols;
    }
    let counts = Counts {
        lower,
        storage: supernodal.len_val(),
        exact: simplicial.len_val(),
        supernodes: sn.n_supernodes(),
    };
    (counts, col_counts)
}

/// The elimination tree of the matrix under `perm` (parent in permuted order, NONE for roots).
fn etree(structure: &Structure, perm: &Perm) -> Vec<usize> {
    let sym = structure.symbolic();
    let (cp, ri) = (sym.col_ptr(), sym.row_idx());
    let n = perm.fwd.len();
    let (mut parent, mut ancestor) = (vec![NONE; n], vec![NONE; n]);
    for k in 0..n {
        let old = perm.fwd[k];
        for &row in &ri[cp[old]..cp[old + 1]] {
            let mut i = perm.inv[row];
            while i < k {
                let next = ancestor[i];
                ancestor[i] = k;
                if next == NONE {
                    parent[i] = k;
                    break;
                }
                i = next;
            }
        }
    }
    parent
}

/// `perm` followed by a postorder of its elimination tree with each node's children in increasing
/// column count (the heaviest child next to its parent), as cholmod_analyze postorders.
fn postordered(structure: &Structure, perm: &Perm, col_counts: &[usize]) -> Perm {
    let n = perm.fwd.len();
    let parent = etree(structure, perm);
    let mut by_weight: Vec<usize> = (0..n).collect();
    by_weight.sort_by_key(|&j| std::cmp::Reverse(col_counts[j]));
    let (mut head, mut next) = (vec![NONE; n + 1], vec![NONE; n]);
    for &j in &by_weight {
        let p = if parent[j] == NONE { n } else { parent[j] };
        next[j] = head[p];
        head[p] = j;
    }
    let mut post = Vec::with_capacity(n);
    let mut stack = vec![n];
    while let Some(&top) = stack.last() {
        let child = head[top];
        if child == NONE {
            stack.pop();
            if top != n {
                post.push(top);
            }
        } else {
            head[top] = next[child];
            stack.push(child);
        }
    }
    Perm::from_fwd(post.iter().map(|&k| perm.fwd[k]).collect()).unwrap()
}

/// One numeric factorisation with faer's mid-level API, as `Factor::new` does it (values
/// allocated and zeroed, workspace allocated, supernodal LLᵀ): seconds.
fn faer_numeric(symbolic: &SymbolicCholesky<usize>, structure: &Structure) -> f64 {
    let t = Instant::now();
    let mut values = Vec::new();
    values.resize(symbolic.len_val(), 0.0f64);
    let par = faer::get_global_parallelism();
    let mut buffer = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
    symbolic
        .factorize_numeric_llt::<f64>(
            &mut values,
            structure.matrix(),
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut buffer),
            Default::default(),
        )
        .expect("positive definite");
    let seconds = t.elapsed().as_secs_f64();
    std::hint::black_box(&values);
    seconds
}

/// The lower triangle of the matrix as MatrixMarket (shortest round-trip decimals: exact).
fn write_matrix_market(matrix: &SymmetricMatrix, structure: &Structure, path: &Path) -> std::io::Result<usize> {
    let sym = matrix.pattern.symbolic();
    let (cp, ri) = (sym.col_ptr(), sym.row_idx());
    let kept = |i: usize, j: usize| i >= j && (i == j || !(structure.decoupled[i] || structure.decoupled[j]));
    let entries = (0..matrix.n())
        .map(|j| ri[cp[j]..cp[j + 1]].iter().filter(|&&i| kept(i, j)).count())
        .sum();
    let mut file = BufWriter::new(std::fs::File::create(path)?);
    writeln!(
        file,
        "%%MatrixMarket matrix coordinate real symmetric\n{} {} {entries}",
        matrix.n(),
        matrix.n()
    )?;
    for j in 0..matrix.n() {
        for (&i, v) in ri[cp[j]..cp[j + 1]].iter().zip(&matrix.values[cp[j]..cp[j + 1]]) {
            if kept(i, j) {
                writeln!(file, "{} {} {v:e}", i + 1, j + 1)?;
            }
        }
    }
    file.flush()?;
    Ok(entries)
}

/// The CHOLMOD child process (benches/cholmod_server.py).
struct Cholmod {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    stderr: Option<std::thread::JoinHandle<String>>,
}

impl Cholmod {
    fn start(
        mtx: &Path,
        dir: &Path,
        threads: usize,
        names: &[&str],
        last: Option<&Path>,
    ) -> Result<(Cholmod, serde_json::Value), String> {
        let script = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/cholmod_server.py");
        let python = std::env::var("HVI_PYTHON").unwrap_or_else(|_| "python3".into());
        let mut cmd = Command::new(&python);
        cmd.arg(script)
            .arg(mtx)
            .arg(dir)
            .arg(names.join(","))
            .args(last)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        for var in ["OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"] {
            cmd.env(var, threads.to_string());
        }
        let system_blas = std::env::var("HVI_CHOLMOD_BLAS").is_ok_and(|v| v == "system");
        if !system_blas && Path::new(OPENBLAS_DIR).join("libblas.so.3").exists() {
            let old = std::env::var("LD_LIBRARY_PATH").unwrap_or_default();
            cmd.env(
                "LD_LIBRARY_PATH",
                if old.is_empty() {
                    OPENBLAS_DIR.to_string()
                } else {
                    format!("{OPENBLAS_DIR}:{old}")
                },
            );
        }
        let mut child = cmd.spawn().map_err(|e| format!("{python} not runnable ({e})"))?;
        let stdin = child.stdin.take().unwrap();
        let stdout = BufReader::new(child.stdout.take().unwrap());
        let mut err = child.stderr.take().unwrap();
        let stderr = std::thread::spawn(move || {
            let mut s = String::new();
            let _ = err.read_to_string(&mut s);
            s
        });
        let mut server = Cholmod {
            child,
            stdin,
            stdout,
            stderr: Some(stderr),
        };
        let ready = server.read()?;
        Ok((server, ready))
    }

    fn read(&mut self) -> Result<serde_json::Value, String> {
        let mut line = String::new();
        match self.stdout.read_line(&mut line) {
            Ok(n) if n > 0 => serde_json::from_str(line.trim()).map_err(|e| format!("bad reply {line:?}: {e}")),
            _ => {
                let _ = self.child.wait();
                let err = self
                    .stderr
                    .take()
                    .map(|h| h.join().unwrap_or_default())
                    .unwrap_or_default();
                Err(err.lines().last().unwrap_or("the CHOLMOD child exited").to_string())
            }
        }
    }

    fn request(&mut self, command: &str) -> Result<serde_json::Value, String> {
        writeln!(self.stdin, "{command}").map_err(|e| e.to_string())?;
        self.stdin.flush().map_err(|e| e.to_string())?;
        self.read()
    }
}

/// How a row's numeric factorisation is run.
enum Method {
    Hvi(Analysis),
    Faer(Box<SymbolicCholesky<usize>>),
    Cholmod(&'static str),
}

struct Row {
    label: String,
    method: Method,
    counts: Option<Counts>,
    symbolic: f64,
    numeric: Vec<f64>,
    error: Option<f64>,
    diagnostic: bool,
}

fn row(label: impl Into<String>, method: Method, counts: Option<Counts>, symbolic: f64, diagnostic: bool) -> Row {
    Row {
        label: label.into(),
        method,
        counts,
        symbolic,
        numeric: Vec::new(),
        error: None,
        diagnostic,
    }
}

/// What the child reported of its BLAS: OpenBLAS's configuration and threads, else the libraries.
fn blas_summary(blas: &serde_json::Value) -> String {
    match blas["openblas_config"].as_str() {
        Some(config) => format!(
            "{config}, core {}, {} thread(s)",
            blas["openblas_core"].as_str().unwrap_or("?"),
            blas["openblas_threads"]
        ),
        None => blas["libraries"]
            .as_array()
            .map(|l| l.iter().filter_map(|v| v.as_str()).collect::<Vec<_>>().join(", "))
            .unwrap_or_else(|| "unknown".into()),
    }
}

fn millions(v: usize) -> String {
    format!("{:.2} M", v as f64 / 1e6)
}

/// A case of the bench: a label, the simulation and its step matrix with identity rows.
struct Case {
    label: String,
    sim: Simulation<3>,
    matrix: SymmetricMatrix,
}

/// K = K_A + (k/2) b(0) K_B with identity rows (K_A alone without memory), as the time loop
/// factors it (one memory channel on I, as examples/slab.toml; a scene with other memory is
/// refused by the bench).
fn step_matrix(sim: &Simulation<3>) -> SymmetricMatrix {
    let (cells, points) = (&sim.mesh.cells, &sim.mesh.points);
    match sim.materials.memory() {
        None => {
            let [k_a] = assemble_stiffness(cells, points, &sim.dofs, &[sim.materials.list()[0].elasticity.tensor()]);
            k_a.with_identity_rows(&sim.dofs)
        }
        Some(m) => {
            let [k_a, k_b] = assemble_stiffness(
                cells,
                points,
                &sim.dofs,
                &[sim.materials.list()[0].elasticity.tensor(), IDENTITY_TENSOR],
            );
            let b0 = m.kernel_value(0, 0.0);
            k_a.plus_scaled(0.5 * sim.time.first_step() * b0, &k_b)
                .with_identity_rows(&sim.dofs)
        }
    }
}

/// The cases: `HVI_BENCH_MESH` (gmsh files, comma-separated) with the scene `HVI_BENCH_SCENE`,
/// else the slab boxes of `HVI_BENCH_N`.
fn cases() -> Vec<Box<dyn FnOnce() -> Case>> {
    if let Ok(meshes) = std::env::var("HVI_BENCH_MESH") {
        let scene_path = std::env::var("HVI_BENCH_SCENE").expect("HVI_BENCH_MESH needs HVI_BENCH_SCENE");
        return meshes
            .split(',')
            .map(|m| {
                let (m, scene_path) = (PathBuf::from(m.trim()), PathBuf::from(&scene_path));
                Box::new(move || {
                    let scene = Scene::load(Some(&scene_path), &[]).expect("the scene");
                    let mesh = hvi::mesh::read_mesh::<3>(&m).expect("a 3D gmsh mesh");
                    let sim = Simulation::new(&scene, mesh).expect("the scene on the mesh");
                    let matrix = step_matrix(&sim);
                    let tets = sim.mesh.cells.len();
                    Case {
                        label: format!(
                            "{}: {tets} cells, {} contact nodes",
                            m.display(),
                            sim.contact.as_ref().map_or(0, |c| c.nodes.len())
                        ),
                        sim,
                        matrix,
                    }
                }) as Box<dyn FnOnce() -> Case>
            })
            .collect();
    }
    let slab = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/slab.toml"));
    let sizes: Vec<usize> = std::env::var("HVI_BENCH_N")
        .unwrap_or_else(|_| "32,40".into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    sizes
        .into_iter()
        .map(|n| {
            Box::new(move || {
                let scene = Scene::load(Some(slab), &[]).expect("examples/slab.toml");
                let mesh = block([2.0, 1.0, 0.25], [2 * n, n, (n / 4).max(1)], SolidShape::Hex);
                let sim = Simulation::new(&scene, mesh).expect("slab scene on the box");
                let matrix = step_matrix(&sim);
                Case {
                    label: format!("n = {n}: Q1 box {}x{}x{}", 2 * n, n, (n / 4).max(1)),
                    sim,
                    matrix,
                }
            }) as Box<dyn FnOnce() -> Case>
        })
        .collect()
}

fn main() {
    let repeats: usize = env_or("HVI_BENCH_REPEATS", 5).max(1);
    let threads: usize = env_or("HVI_BENCH_THREADS", 1).max(1);
    hvi::linalg::set_parallelism(threads);
    println!("factor_vs_cholmod_3d: {threads} thread(s) each side, medians of {repeats}, interleaved");
    for (case_number, case) in cases().into_iter().enumerate() {
        let bench_start = Instant::now();
        let Case { label, sim, matrix } = case();
        println!(
            "\n{label}: {} unknowns ({} free, {} identity rows), {} stored entries (both triangles)",
            matrix.n(),
            sim.dofs.n_free(),
            matrix.n() - sim.dofs.n_free(),
            matrix.values.len()
        );
        let structure = Structure::of(&matrix);
        let counters = Counters::default();
        let rhs: Vec<f64> = {
            let mut y = vec![0.0; matrix.n()];
            matrix.matvec(&vec![1.0; matrix.n()], &mut y);
            y
        };

        // hvi: its own choice, and each ordering forced
        let t = Instant::now();
        let auto = Factor::analyse(&matrix).expect("analysis");
        let auto_symbolic = t.elapsed().as_secs_f64();
        let mut rows = Vec::new();
        let mut nd_perm = None;
        for (ordering, label) in [
            (NodeOrdering::Amd, "hvi AMD (node graph)"),
            (NodeOrdering::NestedDissection, "hvi ND (METIS, node graph)"),
        ] {
            let t = Instant::now();
            let analysis = Factor::analyse_with(&matrix, ordering).expect("analysis");
            let seconds = t.elapsed().as_secs_f64();
            let perm = Perm::from_fwd(analysis.permutation().0.to_vec()).unwrap();
            let (counts, col_counts) = faer_counts(&structure, &perm);
            if counts.storage != analysis.factor_entries() {
                println!(
                    "  warning: the bench's copy of {label} gives {} entries, hvi {}: its lower/exact counts are not hvi's",
                    counts.storage,
                    analysis.factor_entries()
                );
            }
            if ordering == NodeOrdering::NestedDissection {
                nd_perm = Some((col_counts, perm.fwd.clone()));
            }
            rows.push(row(label, Method::Hvi(analysis), Some(counts), seconds, false));
        }
        let auto_row = rows
            .iter()
            .position(|r| matches!(&r.method, Method::Hvi(a) if a.ordering() == auto.ordering()))
            .expect("hvi's choice is one of its orderings");
        drop(auto);

        // the solver's factor: the same choice with the contact normals' unknowns ordered last
        // (Simulation::unknowns_ordered_last, Factor::analyse_with_last, as the time loop does)
        let last = sim.unknowns_ordered_last();
        let solver_row = (!last.is_empty()).then(|| {
            let t = Instant::now();
            let analysis = Factor::analyse_with_last(&matrix, &last).expect("analysis");
            let seconds = t.elapsed().as_secs_f64();
            let counts = Some(faer_counts(&structure, &Perm::from_fwd(analysis.permutation().0.to_vec()).unwrap()).0)
                .filter(|c| c.storage == analysis.factor_entries());
            if counts.is_none() {
                println!("  warning: the bench's copy of the solver's ordering does not give hvi's factor");
            }
            let kind = if analysis.ordering().starts_with("AMD") {
                "AMD"
            } else {
                "ND"
            };
            let label = format!("hvi {kind}, {} contact unknowns last", last.len());
            rows.push(row(label, Method::Hvi(analysis), counts, seconds, false));
            rows.len() - 1
        });

        // diagnostic: hvi's ND permutation postordered like CHOLMOD's
        if let Some((col_counts, fwd)) = nd_perm {
            let perm = Perm::from_fwd(fwd).unwrap();
            let perm = &perm;
            let col_counts = &col_counts;
            let t = Instant::now();
            let post = postordered(&structure, perm, col_counts);
            let sym = symbolic(&structure, &post, true);
            let seconds = t.elapsed().as_secs_f64();
            let (counts, _) = faer_counts(&structure, &post);
            rows.push(row(
                "faer, hvi ND postordered",
                Method::Faer(Box::new(sym)),
                Some(counts),
                seconds,
                true,
            ));
        }

        // the same matrix for CHOLMOD
        let dir = std::env::temp_dir().join(format!("hvi_factor3d_{}_{case_number}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let mtx: PathBuf = dir.join("K.mtx");
        let entries = write_matrix_market(&matrix, &structure, &mtx).expect("writing the MatrixMarket file");
        // the unknowns the solver orders last, for the constrained rows
        let last_path = (!last.is_empty()).then(|| {
            let path = dir.join("last.bin");
            let bytes: Vec<u8> = last.iter().flat_map(|&i| (i as i64).to_le_bytes()).collect();
            std::fs::write(&path, bytes).expect("writing the contact unknowns");
            path
        });
        let names: Vec<&'static str> = match last_path {
            Some(_) => CHOLMOD_ORDERINGS.iter().chain(&CHOLMOD_LAST).copied().collect(),
            None => CHOLMOD_ORDERINGS.to_vec(),
        };
        let mut cholmod = match Cholmod::start(&mtx, &dir, threads, &names, last_path.as_deref()) {
            Ok((server, ready)) => {
                println!(
                    "  CHOLMOD: {} unknowns, {} entries read (file: {entries} lower); BLAS: {}",
                    ready["n"],
                    ready["nnz"],
                    blas_summary(&ready["blas"])
                );
                let mut cholmod_perms = Vec::new();
                for &name in &names {
                    let info = &ready["orderings"][name];
                    let bytes = std::fs::read(info["perm"].as_str().unwrap()).expect("permutation file");
                    let fwd: Vec<usize> = bytes
                        .chunks_exact(8)
                        .map(|c| i64::from_le_bytes(c.try_into().unwrap()) as usize)
                        .collect();
                    let perm = Perm::from_fwd(fwd).expect("CHOLMOD's P()");
                    let (counts, _) = faer_counts(&structure, &perm);
                    // CHOLMOD's own lower/storage/supernodes come with "finish"; keep faer's exact count
                    let own = Counts {
                        exact: counts.exact,
                        ..Default::default()
                    };
                    rows.push(row(
                        format!("CHOLMOD {name}"),
                        Method::Cholmod(name),
                        Some(own),
                        info["symbolic"].as_f64().unwrap(),
                        false,
                    ));
                    cholmod_perms.push((name, perm, counts));
                }
                let same: Vec<&str> = CHOLMOD_ORDERINGS[1..]
                    .iter()
                    .zip(&cholmod_perms[1..CHOLMOD_ORDERINGS.len()])
                    .filter(|(_, (_, p, _))| p.fwd == cholmod_perms[0].1.fwd)
                    .map(|(name, _)| *name)
                    .collect();
                println!(
                    "  CHOLMOD default = {}",
                    if same.is_empty() {
                        "none of the others".into()
                    } else {
                        same.join(", ")
                    }
                );
                // diagnostic: faer's supernodes and kernels on CHOLMOD's best permutation (exact count)
                let (name, perm, counts) = cholmod_perms
                    .iter()
                    .filter(|(name, _, _)| !constrained(name))
                    .min_by_key(|(_, _, c)| c.exact)
                    .unwrap();
                let t = Instant::now();
                let sym = symbolic(&structure, perm, true);
                let seconds = t.elapsed().as_secs_f64();
                rows.push(row(
                    format!("faer, CHOLMOD {name} permutation"),
                    Method::Faer(Box::new(sym)),
                    Some(*counts),
                    seconds,
                    true,
                ));
                Some(server)
            }
            Err(e) => {
                println!("  CHOLMOD not measured: {e}");
                None
            }
        };

        // interleaved numeric factorisations, the starting row rotated each round
        let timed_start = Instant::now();
        for rep in 0..repeats {
            let count = rows.len();
            for k in 0..count {
                let r = &mut rows[(k + rep) % count];
                let seconds = match &r.method {
                    Method::Hvi(analysis) => {
                        let t = Instant::now();
                        let f = Factor::new(analysis, &matrix, &counters).expect("factorisation");
                        let seconds = t.elapsed().as_secs_f64();
                        if r.error.is_none() {
                            let mut x = rhs.clone();
                            f.solve_in_place(&mut x, &counters);
                            r.error = Some(x.iter().fold(0.0, |a, v| a.max((v - 1.0).abs())));
                        }
                        seconds
                    }
                    Method::Faer(sym) => faer_numeric(sym, &structure),
                    Method::Cholmod(name) => {
                        let Some(server) = cholmod.as_mut() else { continue };
                        match server.request(&format!("factor {name}")) {
                            Ok(v) => v["numeric"].as_f64().unwrap_or(f64::NAN),
                            Err(e) => {
                                println!("  CHOLMOD failed: {e}");
                                cholmod = None;
                                continue;
                            }
                        }
                    }
                };
                r.numeric.push(seconds);
            }
        }
        let timed_seconds = timed_start.elapsed().as_secs_f64();
        if let Some(mut server) = cholmod.take() {
            match server.request("finish") {
                Ok(v) => {
                    for r in rows.iter_mut() {
                        if let Method::Cholmod(name) = r.method {
                            let c = &v[name];
                            let counts = r.counts.get_or_insert_with(Counts::default);
                            counts.lower = c["nnz_L"].as_u64().unwrap_or(0) as usize;
                            counts.storage = c["storage"].as_u64().unwrap_or(0) as usize;
                            counts.supernodes = c["supernodes"].as_u64().unwrap_or(0) as usize;
                            r.error = c["max_abs_error"].as_f64();
                        }
                    }
                }
                Err(e) => println!("  CHOLMOD finish failed: {e}"),
            }
            let _ = server.child.wait();
        }
        if std::env::var_os("HVI_KEEP_MTX").is_none() {
            let _ = std::fs::remove_dir_all(&dir);
        } else {
            println!("  kept {}", dir.display());
        }

        // the table
        let cholmod_rows: Vec<&Row> = rows
            .iter()
            .filter(|r| matches!(r.method, Method::Cholmod(name) if !constrained(name)) && r.numeric.len() == repeats)
            .collect();
        let best_last = rows
            .iter()
            .filter(|r| matches!(r.method, Method::Cholmod(name) if constrained(name)))
            .filter_map(|r| r.counts.map(|c| c.lower))
            .filter(|&v| v > 0)
            .min();
        let best_lower = cholmod_rows
            .iter()
            .filter_map(|r| r.counts.map(|c| c.lower))
            .filter(|&v| v > 0)
            .min();
        let best_exact = cholmod_rows.iter().filter_map(|r| r.counts.map(|c| c.exact)).min();
        let best_time = cholmod_rows
            .iter()
            .map(|r| median(r.numeric.clone()))
            .min_by(|a, b| a.total_cmp(b));
        println!(
            "\n  {:<36} {:>10} {:>10} {:>10} {:>8} {:>8} {:>9} {:>7} {:>8} {:>8} {:>8}",
            "ordering",
            "lower",
            "storage",
            "exact",
            "supern.",
            "symb. s",
            "numeric s",
            "min s",
            "lower/b",
            "exact/b",
            "time/b"
        );
        let ratio = |a: usize, b: Option<usize>| b.map_or("-".into(), |b| format!("{:.3}", a as f64 / b as f64));
        for (i, r) in rows.iter().enumerate() {
            if r.diagnostic && !rows[..i].iter().any(|q| q.diagnostic) {
                println!("  diagnostics (bench-only, faer numeric on other permutations):");
            }
            let c = r.counts.unwrap_or_default();
            let t = if r.numeric.is_empty() {
                f64::NAN
            } else {
                median(r.numeric.clone())
            };
            let chosen = if i == auto_row { " *" } else { "" };
            println!(
                "  {:<36} {:>10} {:>10} {:>10} {:>8} {:>8.3} {:>9.3} {:>7.3} {:>8} {:>8} {:>8}",
                format!("{}{chosen}", r.label),
                millions(c.lower),
                format!(
                    "{}{}",
                    millions(c.storage),
                    if matches!(r.method, Method::Cholmod(_)) {
                        "≤"
                    } else {
                        ""
                    }
                ),
                millions(c.exact),
                c.supernodes,
                r.symbolic,
                t,
                r.numeric.iter().copied().fold(f64::NAN, f64::min),
                ratio(c.lower, best_lower),
                ratio(c.exact, best_exact),
                best_time.map_or("-".into(), |b| format!("{:.3}", t / b)),
            );
        }
        println!(
            "  * = Factor::analyse's choice (symbolic {auto_symbolic:.3} s, both orderings tried). /b = over CHOLMOD's best \
             unconstrained ordering by that column (lower: L().nnz; exact: structural; time: fastest median); numeric s = \
             median, min s = fastest. NAME_last: CHOLMOD's NAME on K without the solver's last unknowns, those appended \
             (the peer's factor)."
        );
        let errors: Vec<String> = rows
            .iter()
            .filter_map(|r| r.error.map(|e| format!("{} {e:.1e}", r.label)))
            .collect();
        println!("  max |x - 1| of one solve: {}", errors.join(", "));
        if let (Some(bl), Some(bt)) = (best_lower, best_time) {
            for (what, i) in [("Factor::analyse", Some(auto_row)), ("the solver's factor", solver_row)] {
                let Some(h) = i.map(|i| &rows[i]) else { continue };
                let (hl, ht) = (
                    h.counts.map_or(f64::NAN, |c| c.lower as f64 / bl as f64),
                    median(h.numeric.clone()) / bt,
                );
                println!(
                    "  floor (nnz(L) ≤ 1.2× CHOLMOD best, numeric ≤ CHOLMOD's), {what}: nnz {hl:.3} {}, time {ht:.3} {}",
                    if hl <= 1.2 { "met" } else { "NOT met" },
                    if ht <= 1.0 { "met" } else { "NOT met" }
                );
            }
        }
        if let (Some(bl), Some(h)) = (best_last, solver_row.map(|i| &rows[i])) {
            let hl = h.counts.map_or(f64::NAN, |c| c.lower as f64 / bl as f64);
            println!(
                "  issue 22 (nnz(L) ≤ CHOLMOD's with the same unknowns last), the solver's factor: {} against {}, {hl:.3} {}",
                millions(h.counts.map_or(0, |c| c.lower)),
                millions(bl),
                if hl <= 1.0 { "met" } else { "NOT met" }
            );
        }
        println!(
            "  (this size: {:.0} s in all, {timed_seconds:.0} s in the interleaved factorisations)",
            bench_start.elapsed().as_secs_f64()
        );
    }
}
