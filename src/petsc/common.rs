//! What `hvi solve` and `hvi check` share under `--backend petsc` (docs/method.md §13): the
//! solver choice, collective agreement, reading the inputs on every rank, the simulation and
//! its partition, each rank's share.

use crate::app::{self};
use crate::mesh::{AnyMesh, Mesh};
use crate::petsc::Partition;
use crate::scene::Scene;
use crate::solver::{Simulation, SolveError};
use hvi_petsc::mpi::collective::SystemOperation;
use hvi_petsc::mpi::topology::SimpleCommunicator;
use hvi_petsc::mpi::traits::*;
use hvi_petsc::Petsc;
use serde::Serialize;

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
pub(super) fn agree(world: &SimpleCommunicator, local: Result<(), String>) -> Result<(), String> {
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
pub(super) fn fingerprint<const D: usize>(mesh: &Mesh<D>) -> [u64; 3] {
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
pub(super) fn read_everywhere(
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
pub(super) fn unsupported<const D: usize>(
    scene_path: Option<&std::path::Path>,
    sim: &Simulation<D>,
) -> Result<(), String> {
    let origin = scene_path.map_or(crate::scene::DEFAULT_SCENE_ORIGIN.into(), |p| p.display().to_string());
    if let Some(p) = sim.dirichlet.rigid.first() {
        return Err(format!(
            "{origin}: {} needs the rigid parameters of docs/method.md §7.7 (force control, or a body only its \
             contact holds: {}), which the PETSc backend does not support yet; run this scene without --backend \
             petsc, or hold the body with prescribed components",
            p.name,
            if sim.dirichlet.held_by_contact.is_empty() {
                "none here".to_string()
            } else {
                sim.dirichlet.held_by_contact.join(", ")
            }
        ));
    }
    if !sim.materials.patches().is_empty() {
        return Err(format!(
            "{origin}: the nearly incompressible material's triangles or tetrahedra take their volumetric strain \
             as the mean over a patch of cells (docs/method.md §8.4), which couples the patches across the ranks' \
             parts and the PETSc backend does not assemble: run this scene without --backend petsc, mesh the body \
             with quadrilaterals or hexahedra (mean dilatation per cell runs on PETSc), or set \
             material.formulation = \"standard\" (the element then locks)"
        ));
    }
    if let crate::time::Schedule::Automatic(_) = sim.time {
        return Err(format!(
            "{origin}: time.tolerance asks for automatic steps (docs/method.md §20.4), whose error estimate the \
             PETSc backend does not distribute yet: run this scene without --backend petsc, or give the steps — \
             time.first_step with time.steps_per_decade (steps growing with time, which run on PETSc), time.times \
             or time.steps"
        ));
    }
    match sim.materials.memory() {
        Some(m) if m.channels().len() > 1 => Err(format!(
            "{origin}: the memory has {} channels (tensors that are not proportional — own bulk and shear moduli \
                 that are not A's ratio — make two, docs/method.md §15.1; each material with memory has its own, \
                 §8.5), which the PETSc backend does not support (it runs memory of one channel only): run this \
                 scene without --backend petsc, or give memory terms whose tensors are proportional (e.g. all \
                 \"identity\" or all \"elasticity\", or bulk and shear relaxing proportionally) to one material",
            m.channels().len()
        )),
        _ => Ok(()),
    }
}

/// The scene on the mesh on every rank, the partition rank 0 computes, and the warnings of
/// `hvi check` (collective). `scene_path` names the scene in a refusal ([`unsupported`]); a mesh
/// with severe defects is refused unless `accept_mesh_defects`.
pub(super) fn simulation_and_partition<const D: usize>(
    world: &SimpleCommunicator,
    scene_path: Option<&std::path::Path>,
    scene: &Scene,
    mesh: Mesh<D>,
    accept_mesh_defects: bool,
) -> Result<(Simulation<D>, Partition, Vec<String>), SolveError> {
    let (rank, ranks) = (world.rank() as usize, world.size() as usize);
    let collective = |r: Result<(), String>| agree(world, r).map_err(SolveError::Setup);
    let mesh_warnings = crate::app::warnings::mesh_warnings(&mesh, scene, accept_mesh_defects);
    collective(mesh_warnings.as_ref().map(|_| ()).map_err(|e| e.to_string()))?;
    let mesh_warnings = mesh_warnings?;
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
    let warnings = crate::app::warnings::warnings(mesh_warnings, scene, &sim);
    Ok((sim, partition, warnings))
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
    pub(super) fn all<const D: usize>(sim: &Simulation<D>, partition: &Partition) -> Vec<RankShare> {
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

/// Gathers one number of every rank onto every rank (collective).
pub(super) fn all_gather(world: &SimpleCommunicator, mine: f64) -> Vec<f64> {
    let mut all = vec![0.0; world.size() as usize];
    world.all_gather_into(&mine, &mut all[..]);
    all
}

/// Starts MPI and PETSc for one command; a panic on any rank then ends all of them.
pub(super) fn start() -> Result<Petsc, String> {
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
