//! The sinks that turn a run's steps into files (the VTK series, Γ₃'s CSV and series, the
//! reactions) or keep them in memory (tests and studies); docs/method.md §12.
//!
//! About 600 lines because it is one idea, a step as the files a user opens: every output of a
//! frame is written here, so that a field added to the series is added once.

use crate::contact::{ContactOutcome, ContactState};
use crate::fem::stress::{cell_measures, cell_stresses, nodal_stresses, CellStresses, MemoryField};
use crate::mesh::{GroupSelector, Mesh};
use crate::output::{self, ContactBoundary, CsvTable, Field, Frame, SeriesWriter, SurfaceFrame};
use crate::scene::OutputField;
use crate::solver::stats::timed;
use crate::solver::{FrameSink, Simulation, SolveError, StepView};
use std::path::Path;

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
    /// The rigid parameters' displacements (force-controlled groups, then pins; docs/method.md
    /// §7.7).
    pub motion: Vec<f64>,
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
            motion: view.motion.to_vec(),
        });
        Ok(())
    }
}

/// Each memory channel's tensor and nodal memory displacement (docs/method.md §15), from a
/// step's memory displacements (`StoredStep::memory_displacement`): what the cell stresses take.
pub fn memory_fields<const D: usize>(sim: &Simulation<D>, memory: Option<&[f64]>) -> Vec<MemoryField<D>> {
    match (sim.materials.memory(), memory) {
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
pub struct FileSink<const D: usize> {
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
    /// Each cell's material index, with several materials (the `material` cell array).
    cell_materials: Vec<i32>,
    /// Areas or volumes of the cells, for the nodal stresses.
    cell_measures: Vec<f64>,
    gamma3: Option<CsvTable>,
    reactions: Option<CsvTable>,
    /// force_control.csv: each force-controlled group's force and displacement δ (docs/method.md
    /// §7.7).
    force_control: Option<CsvTable>,
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
        let (cell_groups, cell_materials) = if series.is_some() {
            (cell_groups(&sim.mesh), cell_materials(sim))
        } else {
            (Vec::new(), Vec::new())
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
                if sim.contact.as_ref().is_some_and(|c| c.friction.is_some()) {
                    // docs/method.md §17: along τ = (−ν_y, ν_x) in 2D, vectors in 3D
                    columns.extend(if D == 2 {
                        &FRICTION_COLUMNS[..]
                    } else {
                        &FRICTION_COLUMNS_3D[..]
                    });
                }
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
        let force_control = if sim.dirichlet.rigid.iter().any(|p| p.group.is_some()) {
            manifest.add("force_control.csv")?;
            Some(CsvTable::create(
                &dir.join("force_control.csv"),
                &["time", "group", "component", "force", "displacement"],
            )?)
        } else {
            None
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
            // automatic steps: a spinner with the step and its time (their number is not known)
            let Some(steps) = sim.time.steps() else {
                let spinner = indicatif::ProgressBar::new_spinner();
                spinner.set_style(
                    indicatif::ProgressStyle::with_template("{spinner} step {pos} {elapsed_precise} {msg}")
                        .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
                );
                return spinner;
            };
            let bar = indicatif::ProgressBar::new(steps as u64 + 1);
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
            cell_materials,
            cell_measures,
            gamma3,
            reactions,
            force_control,
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
        crate::alloc::record_progress(self.steps_done, self.last_written);
        if let Some(bar) = &self.progress {
            bar.set_position(view.step as u64 + 1);
            let contact = view.outcome.map_or(String::new(), |o| {
                format!(", {} Newton it., {} on bound", o.iterations, o.active)
            });
            bar.set_message(format!("t = {:.4e}{contact}", view.time));
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
                    let cell = cell_stresses(&mesh.cells, &mesh.points, &sim.materials, None, &nodal, Some(&memory));
                    let node = nodal_stresses(&mesh.cells, &self.cell_measures, &cell.tensor, mesh.points.len());
                    (cell, node)
                })
            });
            if let Some((cell, node)) = &stresses {
                // von Mises squares the stress: the first to overflow
                if !cell.von_mises.iter().chain(&node.von_mises).all(|v| v.is_finite()) {
                    return Err(SolveError::NonFinite {
                        step: view.step,
                        time: view.time,
                        what: "stress".into(),
                    });
                }
            }
            let (mut point_fields, mut cell_fields) = body_fields(
                &self.fields,
                &displacement,
                stresses.as_ref(),
                &self.cell_groups,
                &self.cell_materials,
            );
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
            let tangential = c.friction.as_ref().map_or(Vec::new(), |f| f.rows_of(c.nodes.len()));
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
                if let Some(f) = &c.friction {
                    row.extend(friction_columns(f, &tangential[k], state));
                }
                rows.push(row);
            }
            if let Some(csv) = &mut self.gamma3 {
                csv.append(&rows)?;
            }
            if let Some(cs) = &mut self.contact {
                self.manifest.add(&cs.series.frame_name(view.step))?;
                write_contact_frame(cs, (c, &sim.mesh.points), state, &normal, &nodal, view)?;
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
        if let Some(csv) = &mut self.force_control {
            let rows: Vec<Vec<String>> = sim
                .dirichlet
                .rigid
                .iter()
                .zip(view.motion)
                .filter_map(|(p, &delta)| {
                    let (group, c) = p.group.as_ref()?;
                    Some(vec![
                        output::format_number(view.time),
                        group.clone(),
                        ["x", "y", "z"][*c].to_string(),
                        output::format_number(p.force_at(view.time)),
                        output::format_number(delta),
                    ])
                })
                .collect();
            csv.append_text(&rows)?;
        }
        if let (Some(csv), Some(values), Some(c)) = (&mut self.contact_forces, view.contact_forces, &sim.contact) {
            let mut rows = Vec::new();
            for (group, f) in c.force_names().iter().zip(values.chunks(D)) {
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
    cell_materials: &'a [i32],
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
    if !cell_materials.is_empty() {
        cell_fields.push(Field::i32("material", 1, cell_materials));
    }
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

/// Each cell's material (its index in `hvi check`'s list, docs/method.md §8.5); empty with one
/// material (no `material` array is written).
pub(crate) fn cell_materials<const D: usize>(sim: &Simulation<D>) -> Vec<i32> {
    if sim.materials.list().len() < 2 {
        return Vec::new();
    }
    (0..sim.mesh.cells.len())
        .map(|c| sim.materials.id_of_cell(c).index() as i32)
        .collect()
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
/// status −1. With contact between two bodies, `target_point` is the displaced point of the
/// target each row is measured against, Σ c_i (x_i + u_i) (NaN off the pairs, docs/method.md §18.4).
fn write_contact_frame<const D: usize>(
    cs: &mut ContactSeries<D>,
    (c, points): (&crate::solver::ContactSetup<D>, &[[f64; D]]),
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
    // friction (docs/method.md §17): the slip increment and the friction force on the body as
    // vectors along each row's tangent, the bound force, the accumulated slip and the status
    let friction_fields = c.friction.as_ref().map(|f| {
        let m = c.nodes.len();
        let (mut slip, mut force_tau) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
        let (mut bound, mut accumulated, mut fstatus) = (vec![f64::NAN; n], vec![f64::NAN; n], vec![-1i32; n]);
        for (k, &p) in f.normal_row.iter().enumerate() {
            let (Some(i), true) = (b.local(c.nodes.nodes[p]), state.friction.slip.len() > k) else {
                continue;
            };
            let tau = f.rows.normals[m + k];
            for d in 0..D {
                // (in 3D the node's two rows add up to the vectors)
                slip[3 * i + d] += state.friction.slip[k] * tau[d];
                force_tau[3 * i + d] -= state.force[m + k] * tau[d];
            }
            bound[i] = state.friction.bound[k];
            accumulated[i] = state.friction.accumulated[k];
            fstatus[i] = state.friction.status[k];
        }
        (slip, force_tau, bound, accumulated, fstatus)
    });
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
    if let Some((slip, force_tau, bound, accumulated, fstatus)) = &friction_fields {
        point_fields.extend([
            Field::f64("slip", 3, slip),
            Field::f64("friction_force", 3, force_tau),
            Field::f64("friction_bound", 1, bound),
            Field::f64("accumulated_slip", 1, accumulated),
            Field::i32("friction_status", 1, fstatus),
        ]);
    }
    let target_point = (!c.targets.is_empty()).then(|| {
        let mut at = vec![f64::NAN; 3 * n];
        for (k, &p) in c.nodes.nodes.iter().enumerate() {
            let (Some(i), false) = (b.local(p), c.master_terms[k].is_empty()) else {
                continue;
            };
            for d in 0..3 {
                at[3 * i + d] = if d < D {
                    c.master_terms[k]
                        .iter()
                        .map(|&(q, w)| w * (points[q][d] + nodal[q][d]))
                        .sum()
                } else {
                    0.0
                };
            }
        }
        at
    });
    if let Some(at) = &target_point {
        point_fields.push(Field::f64("target_point", 3, at));
    }
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

/// gamma3.csv's friction columns (docs/method.md §17): 2D, along τ.
const FRICTION_COLUMNS: [&str; 6] = [
    "u_tau",
    "slip",
    "force_tau",
    "friction_bound",
    "accumulated_slip",
    "friction_status",
];

/// gamma3.csv's friction columns in 3D: the tangential displacement, slip increment and friction
/// force as vectors (docs/method.md §17.5).
const FRICTION_COLUMNS_3D: [&str; 12] = [
    "u_tau_x",
    "u_tau_y",
    "u_tau_z",
    "slip_x",
    "slip_y",
    "slip_z",
    "force_tau_x",
    "force_tau_y",
    "force_tau_z",
    "friction_bound",
    "accumulated_slip",
    "friction_status",
];

/// The friction columns of a normal row with tangential rows `tangential` (NaN and status −1
/// where it has none: its group has no friction, or its tangential directions are prescribed).
/// In 3D the vectors are Σ_k value_k τ_k over the row's tangential rows.
fn friction_columns<const D: usize>(
    f: &crate::contact::friction::Friction<D>,
    tangential: &[usize],
    state: &ContactState,
) -> Vec<f64> {
    let m = f.rows.len() - f.normal_row.len();
    let Some(&first) = tangential.first().filter(|&&t| state.friction.slip.len() > t) else {
        let width = if D == 2 {
            FRICTION_COLUMNS.len()
        } else {
            FRICTION_COLUMNS_3D.len()
        };
        let mut row = vec![f64::NAN; width];
        row[width - 1] = -1.0;
        return row;
    };
    let values: [&dyn Fn(usize) -> f64; 3] = [
        &|t| state.normal_displacement[m + t],
        &|t| state.friction.slip[t],
        &|t| state.force[m + t],
    ];
    let mut row = Vec::with_capacity(12);
    for value in values {
        if D == 2 {
            row.push(value(first));
        } else {
            let mut v = [0.0; 3];
            for &t in tangential {
                for (d, vd) in v.iter_mut().enumerate().take(D) {
                    *vd += value(t) * f.rows.normals[m + t][d];
                }
            }
            row.extend(v);
        }
    }
    row.extend([
        state.friction.bound[first],
        state.friction.accumulated[first],
        f64::from(state.friction.status[first]),
    ]);
    row
}
