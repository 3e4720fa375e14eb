//! The PETSc backend over MPI (docs/method.md §13), behind the cargo feature `petsc`.
//!
//! `mpirun -np P hvi solve mesh.msh --backend petsc [--solver mumps|gamg]` runs the serial time
//! loop ([`crate::solver::timeloop`]) on every rank with the step matrices solved by PETSc:
//!
//! * every rank reads the mesh and the scene; rank 0 partitions the nodes with METIS and
//!   broadcasts the partition ([`partition`]); the nodes of rank r are numbered contiguously, so
//!   rank r owns the rows of its nodes' unknowns, and each cell belongs to the lowest rank
//!   among its nodes;
//! * each rank assembles its own cells into one MPIAIJ matrix per distinct step matrix
//!   K = K_A + c K_B (identity rows at the prescribed unknowns, as in serial), which PETSc
//!   factorises once (MUMPS Cholesky) or gives a GAMG hierarchy once (CG + GAMG with the
//!   rigid-body modes as near null space), reused by every step ([`backend`]);
//! * the step vectors — loads, history, displacement — are held by each rank over its own
//!   unknowns only, and K_A and K_B (for the memory load, the lifting and the reactions) only as
//!   distributed matrices (docs/method.md §13.2);
//! * contact: W = C K⁻¹ Cᵀ from blocks of right-hand sides (`KSPMatSolve`), summed onto rank 0,
//!   which runs the active-set solve and broadcasts its forces λ; per step one free solve
//!   d = C K⁻¹ r and one recovery solve u = K⁻¹ (r − Cᵀ λ);
//! * every rank writes its piece of each frame, rank 0 the `.pvtu`, the index and the tables
//!   ([`files`], docs/method.md §13.3);
//! * `hvi check --backend petsc` prints the partition and the memory each rank will need
//!   ([`check`], docs/method.md §13.4).
//!
//! Failures: a rank that fails before the time loop (unreadable or different mesh, bad scene)
//! tells all ranks at one agreement point and every rank stops with that rank's message; PETSc
//! failures inside the loop are collective (the same converged reason on every rank), and the
//! time loop's decisions (a non-finite solution, a stop) are summed over the ranks; a panic
//! aborts all ranks through MPI_Abort. Nothing waits forever on a rank that has stopped.

mod backend;
mod check;
mod files;
mod partition;

pub use backend::{PetscBackend, GAMG_RTOL};
pub use check::check;
pub use partition::Partition;

use crate::app::{self, FileSink, SolveOptions, Summary};
use crate::mesh::{AnyMesh, GroupSelector, Mesh};
use crate::output;
use crate::scene::Scene;
use crate::solver::timeloop;
use crate::solver::{RunStats, Simulation, SolveError};
use backend::method_name;
use hvi_petsc::mpi::collective::SystemOperation;
use hvi_petsc::mpi::topology::SimpleCommunicator;
use hvi_petsc::mpi::traits::*;
use hvi_petsc::Petsc;
use serde::Serialize;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Which PETSc solver `--solver` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverChoice {
    /// MUMPS Cholesky: a direct factor, exact to round-off (the default).
    Mumps,
    /// CG preconditioned by GAMG to the relative residual [`GAMG_RTOL`].
    Gamg,
}

/// Every rank's outcome of a phase, agreed on by all (collective): Ok on every rank, or on
/// every rank the message of the lowest rank that failed.
fn agree(world: &SimpleCommunicator, local: Result<(), String>) -> Result<(), String> {
    let (rank, size) = (world.rank(), world.size());
    let mine = if local.is_err() { rank } else { size };
    let mut first = size;
    world.all_reduce_into(&mine, &mut first, SystemOperation::min());
    if first == size {
        return Ok(());
    }
    let mut message = match &local {
        Err(m) if rank == first => m.clone().into_bytes(),
        _ => Vec::new(),
    };
    let root = world.process_at_rank(first);
    let mut len = message.len() as u64;
    root.broadcast_into(&mut len);
    message.resize(len as usize, 0);
    root.broadcast_into(&mut message[..]);
    let text = String::from_utf8_lossy(&message).into_owned();
    Err(if size > 1 {
        format!("rank {first} of {size}: {text}")
    } else {
        text
    })
}

/// What identifies a mesh for the ranks' agreement that they all read the same one.
fn fingerprint<const D: usize>(mesh: &Mesh<D>) -> [u64; 3] {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for p in &mesh.points {
        for v in p {
            v.to_bits().hash(&mut h);
        }
    }
    for c in &mesh.cells {
        c.nodes().hash(&mut h);
    }
    [mesh.points.len() as u64, mesh.cells.len() as u64, h.finish()]
}

/// Every rank reads the scene and the mesh and checks that it holds the mesh rank 0 holds
/// (collective).
fn read_everywhere(
    world: &SimpleCommunicator,
    mesh_path: &std::path::Path,
    scene: Option<&std::path::Path>,
    overrides: &[String],
) -> Result<(Scene, AnyMesh), SolveError> {
    let collective = |r: Result<(), String>| agree(world, r).map_err(SolveError::Setup);
    let read = Scene::load(scene, overrides)
        .map_err(SolveError::from)
        .and_then(|scene| Ok((scene, app::read_mesh(mesh_path)?)));
    collective(read.as_ref().map(|_| ()).map_err(|e| e.to_string()))?;
    let (scene, mesh) = read?;
    let mut reference = match &mesh {
        AnyMesh::Two(m) => fingerprint(m),
        AnyMesh::Three(m) => fingerprint(m),
    };
    let mine = reference;
    world.process_at_rank(0).broadcast_into(&mut reference[..]);
    collective(if mine == reference {
        Ok(())
    } else {
        Err(format!(
            "{} reads differently here ({} nodes, {} cells) than on rank 0 ({} nodes, {} cells): every rank must read the same mesh file",
            mesh_path.display(),
            mine[0],
            mine[1],
            reference[0],
            reference[1]
        ))
    })?;
    Ok((scene, mesh))
}

/// What the PETSc backend does not run, refused before anything is assembled, naming the scene
/// file (`scene_path`, or the embedded default), what is not supported and the fix: memory of two
/// channels (docs/method.md §15.1: the backend assembles one K_B, from the one channel's tensor).
/// The time loop refuses it too ([`timeloop`]'s set-up with a backend); here `hvi check` says so.
fn unsupported<const D: usize>(scene_path: Option<&std::path::Path>, sim: &Simulation<D>) -> Result<(), String> {
    match &sim.memory {
        Some(m) if m.channels().len() > 1 => {
            let origin = scene_path.map_or(crate::scene::DEFAULT_SCENE_ORIGIN.into(), |p| p.display().to_string());
            Err(format!(
                "{origin}: the memory has two channels (its tensors are not proportional: own bulk and shear \
                 moduli that are not A's ratio, docs/method.md §15.1), which the PETSc backend does not support \
                 (it runs memory of one channel only): run this scene without --backend petsc, or give memory \
                 terms whose tensors are proportional (e.g. all \"identity\" or all \"elasticity\", or bulk and \
                 shear relaxing proportionally)"
            ))
        }
        _ => Ok(()),
    }
}

/// The scene on the mesh on every rank, and the partition rank 0 computes (collective).
/// `scene_path` names the scene in a refusal ([`unsupported`]).
fn simulation_and_partition<const D: usize>(
    world: &SimpleCommunicator,
    scene_path: Option<&std::path::Path>,
    scene: &Scene,
    mesh: Mesh<D>,
) -> Result<(Simulation<D>, Partition), SolveError> {
    let (rank, ranks) = (world.rank() as usize, world.size() as usize);
    let collective = |r: Result<(), String>| agree(world, r).map_err(SolveError::Setup);
    // (deterministic: the same verdict on every rank, but agreed on all the same so that no
    // rank goes on alone)
    let sim = Simulation::new(scene, mesh);
    collective(sim.as_ref().map(|_| ()).map_err(|e| e.to_string()))?;
    let sim = sim?;
    collective(unsupported(scene_path, &sim))?;
    let mut owner: Vec<u64> = vec![0; sim.mesh.points.len()];
    let parts = if rank == 0 {
        Partition::metis(&sim.mesh, ranks).map(|o| owner = o.into_iter().map(|v| v as u64).collect())
    } else {
        Ok(())
    };
    collective(parts)?;
    world.process_at_rank(0).broadcast_into(&mut owner[..]);
    let partition = Partition::from_owners(&sim.mesh, ranks, owner.into_iter().map(|v| v as usize).collect());
    Ok((sim, partition))
}

/// What one rank holds of the problem (summary.json's `per_rank`, `hvi check --backend petsc`).
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct RankShare {
    pub nodes: usize,
    pub cells: usize,
    /// Free unknowns among the rank's rows.
    pub unknowns: usize,
    pub contact_nodes: usize,
}

impl RankShare {
    /// The share of every rank.
    fn all<const D: usize>(sim: &Simulation<D>, partition: &Partition) -> Vec<RankShare> {
        let mut shares = vec![RankShare::default(); partition.ranks];
        for (p, &o) in partition.owner.iter().enumerate() {
            shares[o].nodes += 1;
            shares[o].unknowns += (0..D).filter(|&c| !sim.dofs.is_prescribed(D * p + c)).count();
        }
        for &o in &partition.cell_owner {
            shares[o].cells += 1;
        }
        if let Some(c) = &sim.contact {
            for &p in &c.nodes.nodes {
                shares[partition.owner[p]].contact_nodes += 1;
            }
        }
        shares
    }
}

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

/// Gathers one number of every rank onto every rank (collective).
fn all_gather(world: &SimpleCommunicator, mine: f64) -> Vec<f64> {
    let mut all = vec![0.0; world.size() as usize];
    world.all_gather_into(&mine, &mut all[..]);
    all
}

/// The outcome of `hvi solve --backend petsc` on one rank.
pub struct MpiRun {
    pub rank: usize,
    pub ranks: usize,
    pub result: Result<RunStats, SolveError>,
}

/// Starts MPI and PETSc for one command; a panic on any rank then ends all of them.
fn start() -> Result<Petsc, String> {
    let petsc = Petsc::init(&[]).map_err(|e| format!("could not start PETSc over MPI: {e}"))?;
    let (rank, ranks) = (petsc.rank(), petsc.size());
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        default_hook(info);
        eprintln!("hvi: rank {rank} of {ranks} stopped on an internal error; ending all ranks");
        SimpleCommunicator::world().abort(101);
    }));
    Ok(petsc)
}

/// `hvi solve --backend petsc`: initialises MPI and PETSc, runs the scene on every rank, and
/// finalises. Only rank 0 should print the result (every rank holds the same error). `stop`
/// (Ctrl-C on any rank) ends the run after the step every rank agrees on.
pub fn solve(opts: &SolveOptions, choice: SolverChoice, stop: Option<&AtomicBool>) -> Result<MpiRun, String> {
    let petsc = start()?;
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
    let (sim, partition) = simulation_and_partition(world, opts.scene.as_deref(), scene, mesh)?;
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
    let sink = files::PieceSink::new(
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
                let mut summary = Summary::new(opts, t.steps_done, t.last_written, None);
                summary.status = match &e {
                    SolveError::Interrupted { .. } => "interrupted".into(),
                    e => format!("failed: {e}"),
                };
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
                summary: Summary::new(opts, t.steps_done, t.last_written, Some(&stats)),
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
