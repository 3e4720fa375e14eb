//! The application layer behind the `hvi` commands: reading inputs, running, and the sinks
//! that turn steps into files (VTK series, Γ₃ CSV, summary) or keep them in memory (tests).

use crate::contact::active_set::{ContactOutcome, ContactState};
use crate::fem::stress::{cell_measures, cell_stresses, nodal_stresses, CellStresses, MemoryField};
use crate::mesh::{self, AnyMesh, GroupSelector, Mesh};
use crate::output::{self, ContactBoundary, CsvTable, Field, Frame, SeriesWriter, SurfaceFrame};
use crate::scene::{OutputField, Scene};
use crate::solver::stats::timed;
use crate::solver::{timeloop, FrameSink, Plan, RunStats, Simulation, SolveError, StepView};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// One step kept in memory by [`MemorySink`].
#[derive(Clone, Debug)]
pub struct StoredStep {
    pub step: usize,
    pub time: f64,
    /// u_n over all unknowns (D per node).
    pub displacement: Vec<f64>,
    pub memory_displacement: Option<Vec<f64>>,
    pub contact: Option<ContactState>,
    pub outcome: Option<ContactOutcome>,
}

/// Keeps every output step in memory (for tests and studies).
#[derive(Default)]
pub struct MemorySink {
    pub steps: Vec<StoredStep>,
}

impl<const D: usize> FrameSink<D> for MemorySink {
    fn write_frame(&mut self, _sim: &Simulation<D>, view: &StepView) -> Result<(), SolveError> {
        self.steps.push(StoredStep {
            step: view.step,
            time: view.time,
            displacement: view.displacement.to_vec(),
            memory_displacement: view.memory_displacement.map(|m| m.to_vec()),
            contact: view.contact.cloned(),
            outcome: view.outcome,
        });
        Ok(())
    }
}

/// Each memory channel's tensor and nodal memory displacement (docs/method.md §15).
fn memory_fields<const D: usize>(sim: &Simulation<D>, memory: Option<&[f64]>) -> Vec<MemoryField<D>> {
    match (&sim.memory, memory) {
        (Some(m), Some(values)) => m
            .channels()
            .iter()
            .zip(values.chunks_exact(sim.dofs.n()))
            .map(|(c, v)| (c.tensor, sim.dofs.to_nodal(v)))
            .collect(),
        _ => Vec::new(),
    }
}

/// The contact dataset of a run: its points and facets, and its series (`contact.pvd`).
struct ContactSeries<const D: usize> {
    boundary: ContactBoundary<D>,
    series: SeriesWriter,
}

/// Writes the VTK series (the body's `solution.pvd`, Γ₃'s `contact.pvd`), `gamma3.csv`, and
/// shows progress.
pub struct FileSink<const D: usize = 2> {
    /// Every file this run writes, listed before it is created (`.hvi-run`).
    pub manifest: output::RunManifest,
    /// Steps computed so far, and the last step written.
    pub steps_done: usize,
    pub last_written: Option<usize>,
    /// The body's series (None when another writer writes the body: the PETSc run's pieces).
    series: Option<SeriesWriter>,
    contact: Option<ContactSeries<D>>,
    /// The physical tag of each cell's group (-1 for a cell in none).
    cell_groups: Vec<i32>,
    /// Areas or volumes of the cells, for the nodal stresses.
    cell_measures: Vec<f64>,
    gamma3: Option<CsvTable>,
    reactions: Option<CsvTable>,
    contact_forces: Option<CsvTable>,
    fields: Vec<OutputField>,
    /// The body's active scalars (`output.active_scalar`; None: the first 1-component field).
    active_scalar: Option<String>,
    progress: Option<indicatif::ProgressBar>,
    pub stress_seconds: f64,
}

impl<const D: usize> FileSink<D> {
    /// Prepares the output directory (checked writable before any solving). `contact_groups`
    /// are the groups of Γ₃ (their facets make the contact dataset); `compression` the zlib
    /// level of the `.vtu`/`.vtp` files (0: none).
    pub fn create(
        dir: &Path,
        manifest: output::RunManifest,
        sim: &Simulation<D>,
        fields: &[OutputField],
        contact_groups: &[GroupSelector],
        compression: u32,
        progress: bool,
    ) -> Result<Self, SolveError> {
        let series = SeriesWriter::create(dir, "solution")?.with_compression(compression);
        Self::create_with(
            dir,
            manifest,
            Some(series),
            sim,
            fields,
            contact_groups,
            compression,
            progress,
        )
    }

    /// As [`FileSink::create`] but without the body's series, which another writer writes:
    /// the Γ₃ tables and dataset, the reactions and the contact forces only.
    pub fn create_without_body(
        dir: &Path,
        manifest: output::RunManifest,
        sim: &Simulation<D>,
        fields: &[OutputField],
        contact_groups: &[GroupSelector],
        compression: u32,
        progress: bool,
    ) -> Result<Self, SolveError> {
        Self::create_with(dir, manifest, None, sim, fields, contact_groups, compression, progress)
    }

    #[allow(clippy::too_many_arguments)]
    fn create_with(
        dir: &Path,
        mut manifest: output::RunManifest,
        series: Option<SeriesWriter>,
        sim: &Simulation<D>,
        fields: &[OutputField],
        contact_groups: &[GroupSelector],
        compression: u32,
        progress: bool,
    ) -> Result<Self, SolveError> {
        if let Some(series) = &series {
            for name in series.index_names() {
                manifest.add(&name)?;
            }
        }
        let contact = match &sim.contact {
            Some(_) if fields.contains(&OutputField::Contact) => {
                let mut parts = Vec::new();
                for g in contact_groups {
                    let tag = sim.mesh.group(g, (D - 1) as u8)?.tag;
                    parts.push((tag, sim.mesh.boundary(g)?));
                }
                let parts: Vec<(i32, &crate::mesh::BoundaryPart<D>)> = parts.iter().map(|(t, p)| (*t, p)).collect();
                let series = SeriesWriter::create_surface(dir, "contact")?.with_compression(compression);
                for name in series.index_names() {
                    manifest.add(&name)?;
                }
                Some(ContactSeries {
                    boundary: ContactBoundary::new(&sim.mesh.points, &parts),
                    series,
                })
            }
            _ => None,
        };
        let cell_groups = if series.is_some() {
            cell_groups(&sim.mesh)
        } else {
            Vec::new()
        };
        let cell_measures = if series.is_some() && wants_stress(fields) {
            cell_measures(&sim.mesh.cells, &sim.mesh.points)
        } else {
            Vec::new()
        };
        let gamma3 = match &sim.contact {
            Some(_) if fields.contains(&OutputField::Contact) => {
                let mut columns = vec!["time", "x", "y", "z"];
                columns.truncate(1 + D);
                columns.extend(["u_nu", "force", "pressure", "status", "group"]);
                manifest.add("gamma3.csv")?;
                Some(CsvTable::create(&dir.join("gamma3.csv"), &columns)?)
            }
            _ => None,
        };
        let reactions = if sim.dirichlet.reaction_groups.is_empty() {
            None
        } else {
            manifest.add("reactions.csv")?;
            Some(CsvTable::create(
                &dir.join("reactions.csv"),
                &["time", "group", "component", "force"],
            )?)
        };
        let contact_forces = match &sim.contact {
            Some(_) => Some({
                manifest.add("contact_forces.csv")?;
                CsvTable::create(
                    &dir.join("contact_forces.csv"),
                    &["time", "group", "component", "force"],
                )?
            }),
            None => None,
        };
        let progress = progress.then(|| {
            let bar = indicatif::ProgressBar::new(sim.time.steps as u64 + 1);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{spinner} step {pos}/{len} [{bar:30}] {elapsed_precise} eta {eta} {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> "),
            );
            bar
        });
        Ok(FileSink {
            manifest,
            steps_done: 0,
            last_written: None,
            series,
            contact,
            cell_groups,
            cell_measures,
            gamma3,
            reactions,
            contact_forces,
            fields: fields.to_vec(),
            active_scalar: None,
            progress,
            stress_seconds: 0.0,
        })
    }

    /// Marks the point field `name` (and the cell field of that name, if any) as the active
    /// scalars of the body's frames (`output.active_scalar`, docs/method.md §12.3).
    pub fn with_active_scalar(mut self, name: Option<&str>) -> Self {
        self.active_scalar = name.map(str::to_string);
        self
    }

    /// Clears the progress bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.progress {
            bar.finish_and_clear();
        }
    }
}

impl<const D: usize> FrameSink<D> for FileSink<D> {
    fn step_done(&mut self, _sim: &Simulation<D>, view: &StepView) {
        self.steps_done = view.step + 1;
        if let Some(bar) = &self.progress {
            bar.set_position(view.step as u64 + 1);
            if let Some(o) = view.outcome {
                bar.set_message(format!("{} Newton it., {} on bound", o.iterations, o.active));
            }
        }
    }

    fn write_frame(&mut self, sim: &Simulation<D>, view: &StepView) -> Result<(), SolveError> {
        let mesh = &sim.mesh;
        let nodal = sim.dofs.to_nodal(view.displacement);
        if let Some(series) = &mut self.series {
            let displacement = displacement_3(&nodal);
            let stresses = wants_stress(&self.fields).then(|| {
                timed(&mut self.stress_seconds, || {
                    let memory = memory_fields(sim, view.memory_displacement);
                    let cell = cell_stresses(&mesh.cells, &mesh.points, &sim.elasticity, &nodal, Some(&memory));
                    let node = nodal_stresses(&mesh.cells, &self.cell_measures, &cell.tensor, mesh.points.len());
                    (cell, node)
                })
            });
            let (mut point_fields, mut cell_fields) =
                body_fields(&self.fields, &displacement, stresses.as_ref(), &self.cell_groups);
            mark_active(&mut point_fields, &mut cell_fields, self.active_scalar.as_deref());
            let frame = Frame {
                step: view.step,
                time: view.time,
                points: &mesh.points,
                cells: &mesh.cells,
                point_fields,
                cell_fields,
            };
            self.manifest.add(&series.frame_name(view.step))?;
            series.write_frame(&frame)?;
            self.last_written = Some(view.step);
        }
        if let (Some(c), Some(state)) = (&sim.contact, view.contact) {
            let mut normal = vec![0.0; c.nodes.len()];
            c.nodes.normal_displacements(view.displacement, &mut normal);
            let mut rows = Vec::with_capacity(c.nodes.len());
            for (k, &p) in c.nodes.nodes.iter().enumerate() {
                let pressure = state.force[k] / c.nodes.weights[k];
                let mut row = vec![view.time];
                row.extend_from_slice(&mesh.points[p]);
                // the row's group by its physical tag (a number, like every other column): a run with
                // several contact groups splits by it (docs/method.md §14.6)
                let tag = c.group_tags[c.row_group[k]];
                row.extend([
                    normal[k],
                    state.force[k],
                    pressure,
                    f64::from(state.status[k].code()),
                    f64::from(tag),
                ]);
                rows.push(row);
            }
            if let Some(csv) = &mut self.gamma3 {
                csv.append(&rows)?;
            }
            if let Some(cs) = &mut self.contact {
                self.manifest.add(&cs.series.frame_name(view.step))?;
                write_contact_frame(cs, c, state, &normal, &nodal, view)?;
            }
        }
        if let (Some(csv), Some(values)) = (&mut self.reactions, view.reactions) {
            let rows: Vec<Vec<String>> = sim
                .dirichlet
                .reaction_groups
                .iter()
                .zip(values)
                .map(|(g, f)| {
                    vec![
                        output::format_number(view.time),
                        g.group.clone(),
                        ["x", "y", "z"][g.component].to_string(),
                        output::format_number(*f),
                    ]
                })
                .collect();
            csv.append_text(&rows)?;
        }
        if let (Some(csv), Some(values), Some(c)) = (&mut self.contact_forces, view.contact_forces, &sim.contact) {
            let mut rows = Vec::new();
            for (group, f) in c.groups.iter().zip(values.chunks(D)) {
                for (k, v) in f.iter().enumerate() {
                    rows.push(vec![
                        output::format_number(view.time),
                        group.clone(),
                        ["x", "y", "z"][k].to_string(),
                        output::format_number(*v),
                    ]);
                }
            }
            csv.append_text(&rows)?;
        }
        Ok(())
    }
}

/// True if `fields` ask for the stress or von Mises (which need the cell stresses).
pub(crate) fn wants_stress(fields: &[OutputField]) -> bool {
    fields.contains(&OutputField::Stress) || fields.contains(&OutputField::VonMises)
}

/// Nodal displacements as 3-vectors (z = 0 in 2D), for ParaView's Warp By Vector.
pub(crate) fn displacement_3<const D: usize>(nodal: &[[f64; D]]) -> Vec<f64> {
    nodal
        .iter()
        .flat_map(|u| [u[0], u[1], u.get(2).copied().unwrap_or(0.0)])
        .collect()
}

/// The point and cell fields of a frame of the body (docs/method.md §12), as `fields` ask:
/// `stresses` are the (cell, recovered nodal) stresses. The first scalar of each list is the
/// active one, which ParaView colours by: von Mises.
pub(crate) fn body_fields<'a>(
    fields: &[OutputField],
    displacement: &'a [f64],
    stresses: Option<&'a (CellStresses, CellStresses)>,
    cell_groups: &'a [i32],
) -> (Vec<Field<'a>>, Vec<Field<'a>>) {
    let mut point_fields = Vec::new();
    let mut cell_fields = Vec::new();
    if let Some((cell, node)) = stresses {
        if fields.contains(&OutputField::VonMises) {
            point_fields.push(Field::f64("von_mises", 1, &node.von_mises));
            cell_fields.push(Field::f64("von_mises", 1, &cell.von_mises));
        }
        if fields.contains(&OutputField::Stress) {
            point_fields.push(Field::f64("stress", 9, &node.tensor));
            cell_fields.push(Field::f64("stress", 9, &cell.tensor));
        }
    }
    if fields.contains(&OutputField::Displacement) {
        point_fields.insert(0, Field::f64("displacement", 3, displacement));
    }
    cell_fields.push(Field::i32("group", 1, cell_groups));
    (point_fields, cell_fields)
}

/// Marks the point field `name` and the cell field of that name, if any, as the active scalars
/// (`output.active_scalar`, docs/method.md §12.3); None leaves the writer's default (the first
/// 1-component field: von Mises).
pub(crate) fn mark_active<'a>(point_fields: &mut [Field<'a>], cell_fields: &mut [Field<'a>], name: Option<&str>) {
    if let Some(name) = name {
        for f in point_fields.iter_mut().chain(cell_fields.iter_mut()) {
            f.active = f.name == name;
        }
    }
}

/// The physical tag of each cell's group (-1 for a cell in none): the last group of dimension
/// D listing it.
pub(crate) fn cell_groups<const D: usize>(mesh: &Mesh<D>) -> Vec<i32> {
    let mut cell_groups = vec![-1; mesh.cells.len()];
    for g in mesh.groups.iter().filter(|g| g.dim as usize == D).rev() {
        for &c in &g.cells {
            cell_groups[c] = g.tag;
        }
    }
    cell_groups
}

/// Writes one frame of the contact dataset (docs/method.md §12): u_ν, gap, force, pressure and
/// status at every Γ₃ node, the nodal normal, and the group ids. A Γ₃ node that is no contact
/// unknown (its normal displacement is prescribed) has its u_ν = ν·u, force and pressure 0 and
/// status −1.
fn write_contact_frame<const D: usize>(
    cs: &mut ContactSeries<D>,
    c: &crate::solver::ContactSetup<D>,
    state: &ContactState,
    normal: &[f64],
    nodal: &[[f64; D]],
    view: &StepView,
) -> Result<(), SolveError> {
    let b = &cs.boundary;
    let n = b.nodes.len();
    let mut u_nu: Vec<f64> = (0..n)
        .map(|i| (0..D).map(|d| b.normals[3 * i + d] * nodal[b.nodes[i]][d]).sum())
        .collect();
    let (mut force, mut pressure, mut status) = (vec![0.0; n], vec![0.0; n], vec![-1i32; n]);
    let mut gap = c.bound.as_ref().map(|_| vec![0.0; n]);
    let mut bound_at = vec![f64::NAN; n];
    for (k, &p) in c.nodes.nodes.iter().enumerate() {
        if let Some(i) = b.local(p) {
            u_nu[i] = normal[k];
            force[i] = state.force[k];
            pressure[i] = state.force[k] / c.nodes.weights[k];
            status[i] = state.status[k].code();
            if let Some(g) = &c.bound {
                bound_at[i] = g[k];
            }
        }
    }
    if let Some(gap) = &mut gap {
        for i in 0..n {
            // g − u_ν; NaN at a node that is no contact unknown (its normal is prescribed)
            gap[i] = bound_at[i] - u_nu[i];
        }
    }
    let displacement: Vec<f64> = b
        .nodes
        .iter()
        .flat_map(|&p| std::array::from_fn::<f64, 3, _>(|d| if d < D { nodal[p][d] } else { 0.0 }))
        .collect();
    let mut point_fields = vec![Field::f64("u_nu", 1, &u_nu)];
    if let Some(gap) = &gap {
        point_fields.push(Field::f64("gap", 1, gap));
    }
    point_fields.extend([
        Field::f64("force", 1, &force),
        Field::f64("pressure", 1, &pressure),
        Field::i32("status", 1, &status),
        Field::f64("displacement", 3, &displacement),
        Field::f64("normal", 3, &b.normals),
        Field::i32("group", 1, &b.node_groups),
    ]);
    let frame = SurfaceFrame {
        step: view.step,
        time: view.time,
        points: &b.points,
        facets: &b.facets,
        point_fields,
        cell_fields: vec![Field::i32("group", 1, &b.facet_groups)],
    };
    cs.series.write_surface_frame(&frame)?;
    Ok(())
}

/// What `summary.json` holds: written when a run completes and also when it stops early
/// (interrupted, or an error after the output directory was prepared), then without the run's
/// statistics.
#[derive(Serialize)]
pub struct Summary<'a> {
    pub hvi_version: &'static str,
    pub mesh: String,
    pub scene: String,
    pub output: String,
    /// "completed", "interrupted", or "failed: <the error>".
    pub status: String,
    /// Steps computed (of `time.steps + 1`, step 0 included), and the last step written.
    pub steps_done: usize,
    pub last_step_written: Option<usize>,
    #[serde(flatten)]
    pub stats: Option<&'a RunStats>,
}

impl<'a> Summary<'a> {
    /// The summary of a run of `opts` that has computed `steps_done` steps and written up to
    /// `last_step_written`; `status` "completed" until the caller says otherwise.
    pub fn new(
        opts: &SolveOptions,
        steps_done: usize,
        last_step_written: Option<usize>,
        stats: Option<&'a RunStats>,
    ) -> Self {
        Summary {
            hvi_version: env!("CARGO_PKG_VERSION"),
            mesh: opts.mesh.display().to_string(),
            scene: opts
                .scene
                .as_ref()
                .map_or("<embedded default: examples/paper.toml>".into(), |p| {
                    p.display().to_string()
                }),
            output: opts.out.display().to_string(),
            status: "completed".into(),
            steps_done,
            last_step_written,
            stats,
        }
    }
}

/// Reads a mesh file, or builds the paper's rectangle (0,2)×(0,1) for a spec `rect:NXxNY`
/// (quadrilaterals) or `rect:NXxNY:tri` (triangles) when no such file exists.
pub fn read_mesh(path: &Path) -> Result<AnyMesh, SolveError> {
    let text = path.to_string_lossy();
    if let (Some(spec), false) = (text.strip_prefix("box:"), path.exists()) {
        let (dims, shape) = match spec.split_once(':') {
            Some((d, "tet")) => (d, mesh::structured::SolidShape::Tet),
            Some((d, "hex")) | Some((d, "")) => (d, mesh::structured::SolidShape::Hex),
            None => (spec, mesh::structured::SolidShape::Hex),
            Some((_, other)) => {
                return Err(SolveError::Setup(format!(
                    "mesh spec {text}: unknown cell shape `{other}` (use hex or tet)"
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
                "mesh spec {text}: expected box:NXxNYxNZ[:tet] with counts ≥ 1, e.g. box:64x32x8 (cubic cells of size 1/NY: the slab (0, NX/NY)×(0,1)×(0, NZ/NY))"
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

/// Options of `hvi solve`.
pub struct SolveOptions {
    pub mesh: PathBuf,
    pub scene: Option<PathBuf>,
    pub out: PathBuf,
    pub overrides: Vec<String>,
    pub progress: bool,
    /// Replace an earlier run in `out` (remove exactly the files its manifest lists) instead
    /// of refusing to write there.
    pub overwrite: bool,
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
    let sim = Simulation::new(scene, mesh)?;
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
    let result = output::write_atomic(&opts.out.join("scene.toml"), scene.to_toml_string().as_bytes())
        .map_err(SolveError::from)
        .and_then(|()| timeloop::run(&sim, &mut sink, stop));
    sink.finish();
    let mut summary = Summary::new(opts, sink.steps_done, sink.last_written, None);
    let mut stats = match result {
        Ok(stats) => stats,
        Err(e) => {
            summary.status = match &e {
                SolveError::Interrupted { .. } => "interrupted".into(),
                e => format!("failed: {e}"),
            };
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

/// The report of `hvi check`.
pub fn check(mesh_path: &Path, scene_path: Option<&Path>, overrides: &[String]) -> Result<String, SolveError> {
    let scene = Scene::load(scene_path, overrides)?;
    match read_mesh(mesh_path)? {
        AnyMesh::Two(m) => check_dim(mesh_path, scene_path, &scene, m),
        AnyMesh::Three(m) => check_dim(mesh_path, scene_path, &scene, m),
    }
}

/// [`check`] on a mesh of dimension D.
fn check_dim<const D: usize>(
    mesh_path: &Path,
    scene_path: Option<&Path>,
    scene: &Scene,
    mesh: Mesh<D>,
) -> Result<String, SolveError> {
    use std::fmt::Write;
    let mut out = check_mesh_report(mesh_path, &mesh);
    let sim = Simulation::new(scene, mesh)?;
    out.push_str(&check_scene_report(scene_path, &sim));
    // The factor: symbolic analysis only (cheap), so its size is known before solving.
    let [k_a] =
        crate::fem::assemble_stiffness(&sim.mesh.cells, &sim.mesh.points, &sim.dofs, &[sim.elasticity.tensor()]);
    let analysis =
        crate::linalg::Factor::analyse_with_last(&k_a.with_identity_rows(&sim.dofs), &sim.unknowns_ordered_last())
            .map_err(|e| SolveError::Setup(e.to_string()))?;
    let factor_bytes = 8 * analysis.factor_entries() as u64;
    let _ = writeln!(
        out,
        "factor: {} ordering, nnz(L) = {} ({:.1} MiB per factor, at most 2 factors)",
        analysis.ordering(),
        analysis.factor_entries(),
        factor_bytes as f64 / 1048576.0
    );
    if let Some(available) = available_memory_bytes() {
        if 2 * factor_bytes > available {
            return Err(SolveError::Setup(format!(
                "{}: the factor needs {:.1} GiB ({} entries, twice with memory) but {:.1} GiB are available; use a \
                 coarser mesh (fewer unknowns) or a machine with more memory",
                mesh_path.display(),
                2.0 * factor_bytes as f64 / 1073741824.0,
                analysis.factor_entries(),
                available as f64 / 1073741824.0
            )));
        }
    }
    if let Some(c) = &sim.contact {
        // rows per group (a corner node counts once per wall, docs/method.md §14.3)
        let per_group: Vec<String> = c
            .groups
            .iter()
            .enumerate()
            .map(|(i, g)| format!("\"{g}\" ({})", c.row_group.iter().filter(|&&r| r == i).count()))
            .collect();
        let _ = writeln!(out, "contact: {} rows on {}", c.nodes.len(), per_group.join(", "));
        if !c.laws.is_empty() {
            let ratio = smallness_ratio(&sim)?;
            let _ = writeln!(
                out,
                "  smallness condition (discrete, energy norm of A): α_j·c² = {:.3} ({})",
                ratio,
                if ratio < 1.0 && softening_memory(&sim) {
                    "holds with A; but b(0) < 0 makes the step matrix K softer than K_A, so the step energy is convex \
                     only if it also holds with K: see `smallness` in the run's summary.json (docs/method.md §15.3)"
                } else if ratio < 1.0 {
                    "holds: every step's energy is convex"
                } else {
                    "FAILS: the step energy is non-convex; the globalised solver handles it, but uniqueness is not guaranteed"
                }
            );
        }
    }
    let warnings = crate::solver::advice::warnings(scene, &sim);
    for w in &warnings {
        let _ = writeln!(out, "warning: {w}");
    }
    Ok(out)
}

/// The mesh part of `hvi check`'s report: counts, cell sizes, physical groups.
pub(crate) fn check_mesh_report<const D: usize>(mesh_path: &Path, mesh: &Mesh<D>) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(out, "mesh {}", mesh_path.display());
    let count = |name: &str| mesh.cells.iter().filter(|c| c.name() == name).count();
    let kinds: Vec<String> = if D == 2 {
        vec![
            format!("{} triangles", count("triangle")),
            format!("{} quadrilaterals", count("quadrangle")),
        ]
    } else {
        vec![
            format!("{} tetrahedra", count("tetrahedron")),
            format!("{} hexahedra", count("hexahedron")),
        ]
    };
    let _ = writeln!(
        out,
        "  {D}D: {} nodes, {} cells ({})",
        mesh.points.len(),
        mesh.cells.len(),
        kinds.join(", ")
    );
    let (hmin, hmax) = mesh.cell_size();
    let _ = writeln!(out, "  cell size h: {hmin:.4e} … {hmax:.4e}");
    let _ = writeln!(out, "  physical groups:");
    for g in &mesh.groups {
        let _ = writeln!(
            out,
            "    dim {} tag {:>3} {:<14} {} facets, {} cells",
            g.dim,
            g.tag,
            g.name.as_deref().unwrap_or("(no name)"),
            g.facets.len(),
            g.cells.len()
        );
    }
    out
}

/// The scene part of `hvi check`'s report: unknowns, time steps and the plan.
pub(crate) fn check_scene_report<const D: usize>(scene_path: Option<&Path>, sim: &Simulation<D>) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "scene {}",
        scene_path.map_or("<embedded default: examples/paper.toml>".to_string(), |p| p
            .display()
            .to_string())
    );
    let _ = writeln!(
        out,
        "  unknowns: {} free ({} prescribed components kept as identity rows)",
        sim.dofs.n_free(),
        sim.dofs.n_prescribed()
    );
    let _ = writeln!(
        out,
        "  time: T = {}, {} steps of k = {:.4e}",
        sim.time.final_time,
        sim.time.steps,
        sim.time.step()
    );
    let _ = writeln!(out, "plan:");
    let _ = write!(out, "{}", Plan::new(sim));
    out
}

/// True when the memory's share of the step matrix, Σ_j (k/2) b_j(0) T_j, has a negative
/// eigenvalue (b(0) < 0, a relaxing material): K is then softer than K_A in some strain.
fn softening_memory<const D: usize>(sim: &Simulation<D>) -> bool {
    sim.memory.as_ref().is_some_and(|m| {
        let s = m.step_share(sim.time.step());
        s.mu < 0.0 || 2.0 * s.mu + D as f64 * s.lambda < 0.0
    })
}

/// MemAvailable of /proc/meminfo (Linux), in bytes.
fn available_memory_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// α_j λ_max(D^{1/2} C K_A⁻¹ Cᵀ D^{1/2}) (see
/// [`crate::contact::DenseNormalStiffness::trace_constant`]).
pub fn smallness_ratio<const D: usize>(sim: &Simulation<D>) -> Result<f64, SolveError> {
    let c = sim
        .contact
        .as_ref()
        .ok_or_else(|| SolveError::Setup("no contact".into()))?;
    let [k_a] =
        crate::fem::assemble_stiffness(&sim.mesh.cells, &sim.mesh.points, &sim.dofs, &[sim.elasticity.tensor()]);
    let k_a = k_a.with_identity_rows(&sim.dofs);
    let counters = crate::linalg::Counters::default();
    let symbolic = crate::linalg::Factor::analyse(&k_a).map_err(|e| SolveError::Setup(e.to_string()))?;
    let factor = crate::linalg::Factor::new(&symbolic, &k_a, &counters).map_err(|e| SolveError::Singular {
        mesh: sim.mesh.path.display().to_string(),
        detail: e.to_string(),
    })?;
    let op = crate::contact::SplitSweeps::new(&c.nodes, std::sync::Arc::new(factor), &counters)
        .map_err(SolveError::Setup)?;
    use crate::contact::Condensation;
    Ok(op
        .stiffness()
        .trace_constant(&c.laws.monotonicity_weights(c.nodes.len())))
}

/// The one-screen summary printed at the end of `hvi solve`.
pub fn report(stats: &RunStats, out: &Path) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let p = &stats.phases;
    let _ = writeln!(
        s,
        "hvi: {} steps of k = {:.4e} to T = {} on {} nodes / {} cells ({} unknowns, {} contact nodes)",
        stats.steps, stats.time_step, stats.final_time, stats.nodes, stats.cells, stats.unknowns, stats.contact_nodes
    );
    let _ = writeln!(s, "  effects: {}", stats.effects.join(", "));
    if !stats.newton_iterations.is_empty() {
        let total: usize = stats.newton_iterations.iter().sum();
        let max = stats.newton_iterations.iter().max().copied().unwrap_or(0);
        let active = stats.contact.last().map_or(0, |o| o.active);
        let _ = writeln!(s, "  contact: {total} Newton iterations in all (max {max} per step), {active} nodes on the bound at T, max residual {:.2e}", stats.max_contact_residual);
    }
    if let Some(h) = &stats.history_algorithm {
        let _ = writeln!(
            s,
            "  memory: {h}, {:.1} MiB held",
            stats.history_bytes as f64 / 1048576.0
        );
    }
    let _ = writeln!(
        s,
        "  work: {} factorisation(s), {} sparse solves, {} sparse forward sweeps; peak memory {}",
        stats.factorisations,
        stats.solves,
        stats.sparse_forward_sweeps,
        stats
            .peak_memory_bytes
            .map_or("unknown".into(), |b| format!("{:.0} MiB", b as f64 / 1048576.0))
    );
    let _ = writeln!(
        s,
        "  time [s]: mesh {:.3}, assembly {:.3}, factorisation {:.3}, condensation {:.3}, steps {:.3} (history {:.3}, solves {:.3}, contact {:.3}), output {:.3}; total {:.3}",
        p.mesh, p.assembly, p.factorisation, p.condensation,
        p.loads + p.history + p.forward_sweep + p.contact + p.backward_sweep, p.history, p.forward_sweep + p.backward_sweep, p.contact, p.output, p.total
    );
    let _ = write!(
        s,
        "  wrote {} frames to {} (solution.pvd, contact.pvd, gamma3.csv, summary.json)",
        stats.frames_written,
        out.display()
    );
    s
}
