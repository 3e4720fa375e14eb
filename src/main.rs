//! `hvi`: the command line. A thin clap layer over the library (`hvi::app`).

use clap::{Parser, Subcommand};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set by Ctrl-C: the run stops after the current step, leaving every written frame and a
/// valid `.pvd`.
static STOP: AtomicBool = AtomicBool::new(false);

#[derive(Parser)]
#[command(
    name = "hvi",
    version,
    about = "Quasistatic contact of viscoelastic bodies with long memory (history-dependent hemivariational inequalities)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// An allocation failure ends a run with a message and its summary, never an abort
/// (src/alloc.rs).
#[global_allocator]
static GLOBAL: hvi::alloc::Guarded = hvi::alloc::Guarded;

#[derive(Subcommand)]
enum Command {
    /// Solve a scene on a gmsh mesh and write a ParaView time series.
    Solve {
        /// The mesh (.msh, MSH 4.1 ASCII/binary or 2.2 ASCII) with physical groups, or
        /// `rect:NXxNY[:tri]` for the paper's rectangle built in (e.g. rect:256x128).
        mesh: PathBuf,
        /// Scene file (TOML); default: the paper's example (examples/paper.toml, embedded).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Output directory.
        #[arg(long, default_value = "hvi-out")]
        out: PathBuf,
        /// Override a scene key, e.g. --set time.steps=64 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// The linear algebra: faer (one machine), or petsc (PETSc over MPI, launched with
        /// mpirun; needs a build with `--features petsc`, docs/cluster.md).
        #[arg(long, value_enum, default_value_t = BackendArg::Faer)]
        backend: BackendArg,
        /// With --backend petsc: mumps (a Cholesky factor, the default) or gamg (CG + GAMG).
        #[arg(long, value_enum)]
        solver: Option<SolverArg>,
        /// Replace an earlier run in --out: remove exactly the files it wrote (listed in its
        /// manifest .hvi-run) first. Without it, an --out holding a run is refused.
        #[arg(long)]
        overwrite: bool,
        /// Run on a mesh that is not one conforming body (a crack, non-matching faces,
        /// overlapping cells), which is refused otherwise; its defects become warnings.
        #[arg(long)]
        accept_mesh_defects: bool,
    },
    /// Run a convergence study described by a study file (see examples/paper_study.toml).
    Study {
        /// The study file (TOML).
        study: PathBuf,
        /// Output directory for study.md, study.csv and the plots.
        #[arg(long, default_value = "hvi-study")]
        out: PathBuf,
        /// Override a scene key for every run (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
        /// After the study, recommend the cheapest (h, k) whose predicted H¹ error at T is at
        /// most E, from error and cost models fitted to the study's runs (repeatable).
        #[arg(long = "target", value_name = "E")]
        targets: Vec<f64>,
        /// Run each recommendation and print its measured error and time beside the prediction.
        #[arg(long)]
        verify: bool,
    },
    /// Draw a run (PNG and SVG each): 2D, the last frame deformed and coloured by von Mises
    /// (deformed.*) and u_ν and the contact pressure along Γ₃ against arc length (gamma3.*);
    /// 3D, colour maps of u_ν and the pressure over Γ₃ at the last time (gamma3_map.*).
    Plot {
        /// An output directory of `hvi solve`.
        run: PathBuf,
        /// Displacement magnification; default: true scale if the largest displacement is at
        /// least 5 % of the body's diagonal, else a round factor drawing it as 2–5 %.
        #[arg(long)]
        scale: Option<f64>,
        /// Times of the Γ₃ plot, comma-separated (the nearest output times are drawn); default:
        /// the paper's Fig. 2 times t = j/8 for the paper's scene, else up to six evenly spaced
        /// output times.
        #[arg(long, value_delimiter = ',', value_name = "T1,T2,…")]
        times: Option<Vec<f64>>,
    },
    /// Validate a mesh and a scene and print what would be computed.
    Check {
        mesh: PathBuf,
        #[arg(long)]
        scene: Option<PathBuf>,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        overrides: Vec<String>,
        /// petsc (under mpirun): also the partition over the ranks and the memory each rank
        /// will need (docs/cluster.md).
        #[arg(long, value_enum, default_value_t = BackendArg::Faer)]
        backend: BackendArg,
        /// With --backend petsc: the solver whose memory to predict (mumps, the default, or gamg).
        #[arg(long, value_enum)]
        solver: Option<SolverArg>,
        /// Report a mesh that is not one conforming body with warnings instead of an error.
        #[arg(long)]
        accept_mesh_defects: bool,
    },
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum BackendArg {
    Faer,
    Petsc,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum SolverArg {
    Mumps,
    Gamg,
}

/// `error: <message>` on stderr in one write: under mpirun, whose own messages share the
/// stream, an `eprintln!` that writes the prefix and the message separately can be split by
/// them (tests/petsc.rs saw "error: ----" followed by mpirun's banner).
fn report_error(e: &dyn std::fmt::Display) {
    use std::io::Write;
    let line = format!("error: {e}\n");
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
}

#[cfg(feature = "petsc")]
fn petsc_solver(solver: Option<SolverArg>) -> hvi::petsc::SolverChoice {
    match solver {
        Some(SolverArg::Gamg) => hvi::petsc::SolverChoice::Gamg,
        _ => hvi::petsc::SolverChoice::Mumps,
    }
}

/// The exit of a PETSc command on one rank: rank 0 prints the outcome (every rank holds the
/// same error), `print` on success; a start-up failure is printed by every rank (there is no
/// agreed rank 0 then).
#[cfg(feature = "petsc")]
fn petsc_exit<T>(
    started: Result<(usize, Result<T, hvi::solver::SolveError>), String>,
    print: impl FnOnce(T),
) -> ExitCode {
    let (rank, result) = match started {
        Ok(run) => run,
        Err(e) => {
            report_error(&e);
            return ExitCode::FAILURE;
        }
    };
    match result {
        Ok(value) => {
            if rank == 0 {
                print(value);
            }
            ExitCode::SUCCESS
        }
        Err(e @ hvi::solver::SolveError::Interrupted { .. }) => {
            if rank == 0 {
                eprintln!("hvi: {e}");
            }
            ExitCode::from(130)
        }
        Err(e) => {
            if rank == 0 {
                report_error(&e);
            }
            ExitCode::FAILURE
        }
    }
}

/// `hvi solve --backend petsc`: every rank runs; rank 0 prints the report or the error.
#[cfg(feature = "petsc")]
fn solve_petsc(opts: &hvi::app::SolveOptions, solver: Option<SolverArg>) -> ExitCode {
    // (the signal handlers are installed once PETSc has started: src/petsc/run.rs)
    let run = hvi::petsc::solve(opts, petsc_solver(solver), Some(&STOP)).map(|r| (r.rank, r.result));
    petsc_exit(run, |stats| println!("{}", hvi::app::report(&stats, &opts.out)))
}

/// `hvi check --backend petsc`: every rank checks its part; rank 0 prints the report.
#[cfg(feature = "petsc")]
fn check_petsc(
    mesh: &std::path::Path,
    scene: Option<&std::path::Path>,
    overrides: &[String],
    solver: Option<SolverArg>,
    accept_mesh_defects: bool,
) -> ExitCode {
    let run = hvi::petsc::check(mesh, scene, overrides, petsc_solver(solver), accept_mesh_defects)
        .map(|r| (r.rank, r.result));
    petsc_exit(run, |report| print!("{report}"))
}

#[cfg(not(feature = "petsc"))]
const NO_PETSC: &str = "error: --backend petsc: this hvi was built without the PETSc backend; build it with `cargo build --release --features petsc` (needs PETSc ≥ 3.18 and MPI, see docs/cluster.md) and launch it with mpirun";

#[cfg(not(feature = "petsc"))]
fn solve_petsc(_opts: &hvi::app::SolveOptions, _solver: Option<SolverArg>) -> ExitCode {
    eprintln!("{NO_PETSC}");
    ExitCode::FAILURE
}

#[cfg(not(feature = "petsc"))]
fn check_petsc(
    _mesh: &std::path::Path,
    _scene: Option<&std::path::Path>,
    _overrides: &[String],
    _solver: Option<SolverArg>,
    _accept_mesh_defects: bool,
) -> ExitCode {
    eprintln!("{NO_PETSC}");
    ExitCode::FAILURE
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Solve {
            mesh,
            scene,
            out,
            overrides,
            quiet,
            backend,
            solver,
            overwrite,
            accept_mesh_defects,
        } => {
            let opts = hvi::app::SolveOptions {
                mesh,
                scene,
                out: out.clone(),
                overrides,
                progress: !quiet && std::io::stderr().is_terminal(),
                overwrite,
                accept_mesh_defects,
            };
            if backend == BackendArg::Petsc {
                return solve_petsc(&opts, solver);
            }
            if solver.is_some() {
                report_error(&"--solver chooses the PETSc solver: use it with --backend petsc");
                return ExitCode::FAILURE;
            }
            let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::Relaxed));
            match hvi::app::solve(&opts, Some(&STOP)) {
                Ok(stats) => {
                    println!("{}", hvi::app::report(&stats, &out));
                    ExitCode::SUCCESS
                }
                Err(e @ hvi::solver::SolveError::Interrupted { .. }) => {
                    eprintln!("hvi: {e}");
                    ExitCode::from(130)
                }
                Err(e) => {
                    report_error(&e);
                    ExitCode::FAILURE
                }
            }
        }
        Command::Study {
            study,
            out,
            overrides,
            targets,
            verify,
        } => {
            let targets = hvi::study::Targets {
                errors: targets,
                verify,
            };
            match hvi::study::execute::run_file_with(&study, &out, &overrides, &targets) {
                Ok(written) => {
                    println!("{}", written.report);
                    println!("wrote {} to {}", written.files.join(", "), out.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    report_error(&e);
                    ExitCode::FAILURE
                }
            }
        }
        Command::Plot { run, scale, times } => {
            match hvi::plot::plot_run(&run, &hvi::plot::PlotOptions { scale, times }) {
                Ok(files) => {
                    for f in files {
                        println!("wrote {}", f.display());
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    report_error(&e);
                    ExitCode::FAILURE
                }
            }
        }
        Command::Check {
            mesh,
            scene,
            overrides,
            backend,
            solver,
            accept_mesh_defects,
        } => {
            if backend == BackendArg::Petsc {
                return check_petsc(&mesh, scene.as_deref(), &overrides, solver, accept_mesh_defects);
            }
            if solver.is_some() {
                report_error(&"--solver chooses the PETSc solver: use it with --backend petsc");
                return ExitCode::FAILURE;
            }
            match hvi::app::check(&mesh, scene.as_deref(), &overrides, accept_mesh_defects) {
                Ok(report) => {
                    print!("{report}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    report_error(&e);
                    ExitCode::FAILURE
                }
            }
        }
    }
}
