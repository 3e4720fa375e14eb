//! `hvi solve --backend petsc` (docs/method.md §13): every rank runs the time loop on its share
//! with the PETSc backend and writes its pieces; rank 0 the tables and the summary.

use super::backend::method_name;
use super::backend::PetscBackend;
use super::common::{agree, all_gather, read_everywhere, simulation_and_partition, start, RankShare, SolverChoice};
use super::files::PieceSink;
use crate::app::{FileSink, SolveOptions, Summary};
use crate::mesh::{AnyMesh, GroupSelector, Mesh};
use crate::output;
use crate::scene::Scene;
use crate::solver::timeloop;
use crate::solver::{RunStats, SolveError};
use hvi_petsc::Petsc;
use serde::Serialize;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Per rank in summary.json: its share, its peak memory and MUMPS's factor memory there.
#[derive(Serialize)]
struct RankSummary {
    #[serde(flatten)]
    share: RankShare,
    /// VmHWM of the rank's process.
    peak_memory_bytes: Option<u64>,
    /// MUMPS's INFO(16): MB allocated for the factorisation on this rank (the last factor).
    mumps_factor_mb: Option<i64>,
    /// PETSc's K_A and K_B held for the products (MatGetInfo).
    product_matrix_bytes: f64,
}

/// What `summary.json` holds for a PETSc run.
#[derive(Serialize)]
struct MpiSummary<'a> {
    #[serde(flatten)]
    summary: Summary<'a>,
    backend: &'static str,
    ranks: usize,
    petsc_solver: &'static str,
    per_rank: Vec<RankSummary>,
}

/// The outcome of `hvi solve --backend petsc` on one rank.
pub struct MpiRun {
    pub rank: usize,
    pub ranks: usize,
    pub result: Result<RunStats, SolveError>,
}

/// `hvi solve --backend petsc`: initialises MPI and PETSc, runs the scene on every rank, and
/// finalises. Only rank 0 should print the result (every rank holds the same error). `stop`
/// (set on SIGINT, SIGTERM or SIGHUP of any rank, handlers installed here) ends the run after the
/// step every rank agrees on, with rank 0's interrupted summary.
pub fn solve(opts: &SolveOptions, choice: SolverChoice, stop: Option<&'static AtomicBool>) -> Result<MpiRun, String> {
    let petsc = start()?;
    // After PETSc's start, whose signal handler would otherwise take SIGTERM (what mpirun sends
    // every rank on Ctrl-C) and abort the ranks: SIGINT, SIGTERM and SIGHUP set `stop`, and the
    // ranks stop together after the step they agree on (docs/method.md §13).
    if let Some(stop) = stop {
        let _ = ctrlc::set_handler(move || stop.store(true, std::sync::atomic::Ordering::Relaxed));
    }
    let (rank, ranks) = (petsc.rank(), petsc.size());
    let result = run(&petsc, opts, choice, stop);
    Ok(MpiRun { rank, ranks, result })
}

fn run(
    petsc: &Petsc,
    opts: &SolveOptions,
    choice: SolverChoice,
    stop: Option<&AtomicBool>,
) -> Result<RunStats, SolveError> {
    let t0 = Instant::now();
    let (scene, mesh) = read_everywhere(petsc.world(), &opts.mesh, opts.scene.as_deref(), &opts.overrides)?;
    let mesh_seconds = t0.elapsed().as_secs_f64();
    match mesh {
        AnyMesh::Two(m) => run_dim(petsc, opts, &scene, m, mesh_seconds, choice, stop),
        AnyMesh::Three(m) => run_dim(petsc, opts, &scene, m, mesh_seconds, choice, stop),
    }
}

fn run_dim<const D: usize>(
    petsc: &Petsc,
    opts: &SolveOptions,
    scene: &Scene,
    mesh: Mesh<D>,
    mesh_seconds: f64,
    choice: SolverChoice,
    stop: Option<&AtomicBool>,
) -> Result<RunStats, SolveError> {
    let world = petsc.world();
    let (rank, ranks) = (petsc.rank(), petsc.size());
    let collective = |r: Result<(), String>| agree(world, r).map_err(SolveError::Setup);
    let (sim, partition, warnings) =
        simulation_and_partition(world, opts.scene.as_deref(), scene, mesh, opts.accept_mesh_defects)?;
    if rank == 0 {
        for w in &warnings {
            eprintln!("warning: {w}");
        }
    }
    let shares = RankShare::all(&sim, &partition);
    let mut backend = PetscBackend::new(petsc, &sim, partition, choice);
    collective(backend.prepare_products(&sim).map_err(|e| e.to_string()))?;
    // Rank 0 prepares the output directory (checked writable before any solving) and its
    // tables; then every rank its pieces.
    let contact_groups: Vec<GroupSelector> = (0..scene.contact.len()).map(|i| scene.contact_group(i)).collect();
    let mut tables = None;
    let prepared = if rank == 0 {
        output::RunManifest::start(&opts.out, opts.overwrite)
            .map_err(SolveError::from)
            .and_then(|manifest| {
                FileSink::create_without_body(
                    &opts.out,
                    manifest,
                    &sim,
                    &scene.output.fields,
                    &contact_groups,
                    scene.output.compression_level(),
                    opts.progress,
                )
            })
            .and_then(|mut s| {
                for name in ["solution.pvd", "solution.pvtu.series", "scene.toml", "summary.json"] {
                    s.manifest.add(name)?;
                }
                output::write_atomic(&opts.out.join("scene.toml"), scene.to_toml_string().as_bytes())?;
                tables = Some(s);
                Ok(())
            })
            .map_err(|e| e.to_string())
    } else {
        Ok(())
    };
    collective(prepared)?;
    if rank == 0 {
        crate::app::solve::arm_failure_summary(opts, &warnings);
    }
    let sink = PieceSink::new(
        petsc,
        &opts.out,
        &sim,
        backend.partition(),
        &scene.output.fields,
        &contact_groups,
        scene.output.compression_level(),
        tables,
    );
    let mut sink = sink?.with_active_scalar(scene.output.active_scalar_name());
    let result = timeloop::run_with(&sim, &mut sink, stop, Box::new(&mut backend));
    if let Some(t) = &sink.tables {
        t.finish();
    }
    // A solve that failed in PETSc left NaN behind: report PETSc's reason instead.
    let result = match (result, backend.failure()) {
        (Err(SolveError::NonFinite { .. }), Some(f)) | (Err(SolveError::ContactFailed { .. }), Some(f)) => {
            Err(SolveError::Singular {
                mesh: sim.mesh.path.display().to_string(),
                detail: f,
            })
        }
        (r, _) => r,
    };
    // Every rank ends the loop at the same step; agree all the same.
    let local = match &result {
        Ok(_) => Ok(()),
        Err(e) => Err(e.to_string()),
    };
    let result = match (collective(local), result) {
        (Err(e), Ok(_)) => Err(e),
        (_, r) => r,
    };
    // The record of every rank, for summary.json.
    let memory = all_gather(
        world,
        crate::solver::stats::peak_memory_bytes().map_or(-1.0, |b| b as f64),
    );
    let mumps = all_gather(world, backend.mumps_memory().map_or(-1.0, |m| m.this_rank_mb as f64));
    let products = all_gather(world, backend.product_bytes());
    let per_rank = (0..ranks)
        .map(|r| RankSummary {
            share: shares[r],
            peak_memory_bytes: (memory[r] >= 0.0).then_some(memory[r] as u64),
            mumps_factor_mb: (mumps[r] >= 0.0).then_some(mumps[r] as i64),
            product_matrix_bytes: products[r],
        })
        .collect();
    let mut stats = match result {
        Ok(stats) => stats,
        Err(e) => {
            if let Some(t) = &sink.tables {
                let mut summary = Summary::new(opts, warnings, t.steps_done, t.last_written, None);
                summary.stopped_by(&e);
                let summary = MpiSummary {
                    summary,
                    backend: "petsc",
                    ranks,
                    petsc_solver: method_name(backend.method()),
                    per_rank,
                };
                // The run's own error is the one to report (as in serial).
                let _ = output::write_json_atomic(&opts.out.join("summary.json"), &summary);
            }
            return Err(e);
        }
    };
    stats.phases.mesh = mesh_seconds;
    stats.phases.total += mesh_seconds;
    stats.phases.stress = sink.stress_seconds;
    stats.peak_memory_bytes = crate::solver::stats::peak_memory_bytes();
    let written = match &sink.tables {
        Some(t) => {
            let summary = MpiSummary {
                summary: Summary::new(opts, warnings, t.steps_done, t.last_written, Some(&stats)),
                backend: "petsc",
                ranks,
                petsc_solver: method_name(backend.method()),
                per_rank,
            };
            output::write_json_atomic(&opts.out.join("summary.json"), &summary).map_err(|e| e.to_string())
        }
        None => Ok(()),
    };
    collective(written)?;
    Ok(stats)
}
