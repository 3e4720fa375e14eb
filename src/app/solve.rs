//! `hvi solve`: read the mesh and the scene, run, write the series.

use super::options::SolveOptions;
use super::sink::{FileSink, MemorySink};
use super::summary::Summary;
use crate::mesh::{self, AnyMesh, GroupSelector, Mesh};
use crate::output;
use crate::scene::Scene;
use crate::solver::{timeloop, RunStats, Simulation, SolveError};
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Reads a mesh file, or builds the paper's rectangle (0,2)×(0,1) for a spec `rect:NXxNY`
/// (quadrilaterals) or `rect:NXxNY:tri` (triangles) when no such file exists.
pub fn read_mesh(path: &Path) -> Result<AnyMesh, SolveError> {
    let text = path.to_string_lossy();
    if let (Some(spec), false) = (text.strip_prefix("box:"), path.exists()) {
        let (dims, shape) = match spec.split_once(':') {
            Some((d, "tet")) => (d, mesh::structured::SolidShape::Tet),
            Some((d, "prism")) => (d, mesh::structured::SolidShape::Prism),
            Some((d, "pyramid")) => (d, mesh::structured::SolidShape::Pyramid),
            Some((d, "hex")) | Some((d, "")) => (d, mesh::structured::SolidShape::Hex),
            None => (spec, mesh::structured::SolidShape::Hex),
            Some((_, other)) => {
                return Err(SolveError::Setup(format!(
                    "mesh spec {text}: unknown cell shape `{other}` (use hex, tet, prism or pyramid)"
                )))
            }
        };
        let parsed: Option<Vec<usize>> = dims.split('x').map(|v| v.parse::<usize>().ok()).collect();
        return match parsed.as_deref() {
            Some(&[nx, ny, nz])
                if nx > 0 && ny > 0 && nz > 0 && nx.saturating_mul(ny).saturating_mul(nz) <= 20_000_000 =>
            {
                // cubic cells: the slab (0,2)×(0,1)×(0, nz/ny) for nx = 2 ny
                let h = 1.0 / ny as f64;
                Ok(AnyMesh::Three(mesh::structured::block(
                    [nx as f64 * h, 1.0, nz as f64 * h],
                    [nx, ny, nz],
                    shape,
                )))
            }
            _ => Err(SolveError::Setup(format!(
                "mesh spec {text}: expected box:NXxNYxNZ[:tet|:prism|:pyramid] with counts ≥ 1, e.g. box:64x32x8 (cubic cells of size 1/NY: the slab (0, NX/NY)×(0,1)×(0, NZ/NY))"
            ))),
        };
    }
    if let (Some(spec), false) = (text.strip_prefix("rect:"), path.exists()) {
        let (dims, shape) = match spec.split_once(':') {
            Some((d, "tri")) => (d, mesh::structured::CellShape::Tri),
            Some((d, "quad")) | Some((d, "")) => (d, mesh::structured::CellShape::Quad),
            None => (spec, mesh::structured::CellShape::Quad),
            Some((_, other)) => {
                return Err(SolveError::Setup(format!(
                    "mesh spec {text}: unknown cell shape `{other}` (use quad or tri)"
                )))
            }
        };
        let parsed = dims
            .split_once('x')
            .and_then(|(a, b)| Some((a.parse::<usize>().ok()?, b.parse::<usize>().ok()?)));
        return match parsed {
            Some((nx, ny)) if nx > 0 && ny > 0 && nx.saturating_mul(ny) <= 50_000_000 => {
                Ok(AnyMesh::Two(mesh::structured::rectangle(2.0, 1.0, nx, ny, shape)))
            }
            _ => Err(SolveError::Setup(format!(
                "mesh spec {text}: expected rect:NXxNY[:tri] with NX, NY ≥ 1, e.g. rect:256x128 (the paper's domain (0,2)×(0,1), cells 2/NX × 1/NY)"
            ))),
        };
    }
    Ok(mesh::read_msh(path)?)
}

/// Reads mesh and scene, runs, writes the series, `gamma3.csv`, `scene.toml` and `summary.json`.
pub fn solve(opts: &SolveOptions, stop: Option<&AtomicBool>) -> Result<RunStats, SolveError> {
    let scene = Scene::load(opts.scene.as_deref(), &opts.overrides)?;
    let t0 = Instant::now();
    let mesh = read_mesh(&opts.mesh)?;
    let mesh_seconds = t0.elapsed().as_secs_f64();
    match mesh {
        AnyMesh::Two(m) => solve_dim(opts, &scene, m, mesh_seconds, stop),
        AnyMesh::Three(m) => solve_dim(opts, &scene, m, mesh_seconds, stop),
    }
}

/// [`solve`] on a mesh of dimension D.
fn solve_dim<const D: usize>(
    opts: &SolveOptions,
    scene: &Scene,
    mesh: Mesh<D>,
    mesh_seconds: f64,
    stop: Option<&AtomicBool>,
) -> Result<RunStats, SolveError> {
    let mesh_warnings = super::warnings::mesh_warnings(&mesh, scene, opts.accept_mesh_defects)?;
    let sim = Simulation::new(scene, mesh)?;
    // what `hvi check` would warn about, said before the run (and kept in summary.json)
    let warnings = super::warnings::warnings(mesh_warnings, scene, &sim);
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let manifest = output::RunManifest::start(&opts.out, opts.overwrite)?;
    let contact_groups: Vec<GroupSelector> = (0..scene.contact.len()).map(|i| scene.contact_group(i)).collect();
    let mut sink = FileSink::create(
        &opts.out,
        manifest,
        &sim,
        &scene.output.fields,
        &contact_groups,
        scene.output.compression_level(),
        opts.progress,
    )?
    .with_active_scalar(scene.output.active_scalar_name());
    sink.manifest.add("scene.toml")?;
    sink.manifest.add("summary.json")?;
    arm_failure_summary(opts, &warnings);
    let result = output::write_atomic(&opts.out.join("scene.toml"), scene.to_toml_string().as_bytes())
        .map_err(SolveError::from)
        .and_then(|()| timeloop::run(&sim, &mut sink, stop));
    sink.finish();
    crate::alloc::arm(None);
    let mut summary = Summary::new(opts, warnings, sink.steps_done, sink.last_written, None);
    let mut stats = match result {
        Ok(stats) => stats,
        Err(e) => {
            summary.stopped_by(&e);
            // The run's own error is the one to report; a summary that cannot be written adds
            // nothing to it.
            let _ = output::write_json_atomic(&opts.out.join("summary.json"), &summary);
            return Err(e);
        }
    };
    stats.phases.mesh = mesh_seconds;
    stats.phases.stress = sink.stress_seconds;
    stats.peak_memory_bytes = crate::solver::stats::peak_memory_bytes();
    stats.phases.total += mesh_seconds;
    summary.stats = Some(&stats);
    output::write_json_atomic(&opts.out.join("summary.json"), &summary)?;
    Ok(stats)
}

/// Arms the summary.json an allocation failure leaves (src/alloc.rs): this run's summary with
/// the failure as its status and the progress as of the failure.
pub(crate) fn arm_failure_summary(opts: &SolveOptions, warnings: &[String]) {
    let mut template = Summary::new(
        opts,
        warnings.to_vec(),
        crate::alloc::STEPS_MARK,
        Some(crate::alloc::LAST_MARK),
        None,
    );
    template.status = crate::alloc::STATUS_MARK.into();
    if let Ok(text) = serde_json::to_string_pretty(&template) {
        crate::alloc::arm(crate::alloc::FailureReport::from_template(
            &opts.out.join("summary.json"),
            &format!("{text}\n"),
        ));
    }
}

/// Solves in memory (no files): for tests, studies and examples.
pub fn solve_in_memory<const D: usize>(
    scene: &Scene,
    mesh: Mesh<D>,
) -> Result<(Simulation<D>, RunStats, MemorySink), SolveError> {
    let sim = Simulation::new(scene, mesh)?;
    let mut sink = MemorySink::default();
    let stats = timeloop::run(&sim, &mut sink, None)?;
    Ok((sim, stats, sink))
}
