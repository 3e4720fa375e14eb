//! The files of a PETSc run (docs/method.md §13.3): every rank writes its piece of each frame of
//! the body (its cells and their nodes, `solution_NNNNN_R.vtu`); rank 0 the `.pvtu` listing the
//! pieces, `solution.pvd`, and everything else a serial run writes (gamma3.csv, the contact
//! dataset, reactions.csv, contact_forces.csv, scene.toml, summary.json), through the serial
//! [`FileSink`] without its body series.
//!
//! A frame is written in three agreed phases, so that a failure anywhere leaves every earlier
//! frame whole on every rank: rank 0 lists the frame's files in the run's manifest (before any
//! of them exists); every rank writes its piece; rank 0 writes the `.pvtu` and then the index and
//! the tables. Nothing lists a frame before all of its pieces are in place.

use super::common::agree;
use super::partition::Partition;
use crate::app::sink::{body_fields, cell_groups, cell_materials, displacement_3, mark_active, wants_stress, FileSink};
use crate::fem::stress::{cell_measures, cell_stresses, nodal_stress_sums, nodal_stresses_from_sums};
use crate::mesh::{Cell, GroupSelector};
use crate::output::{Field, Frame, SeriesWriter, CELL_IDS, NODE_IDS};
use crate::scene::OutputField;
use crate::solver::stats::timed;
use crate::solver::{FrameSink, Simulation, SolveError, StepView};
use hvi_petsc::mpi::topology::SimpleCommunicator;
use hvi_petsc::{Int, Petsc, Scatter, Vector};
use std::path::Path;

/// Values per node of the nodal-stress sums: Σ|c|σ_c (9) and Σ|c| (1).
const SUMS: usize = 10;

/// This rank's piece of the body: its cells and the nodes they use (and the nodes it owns that
/// are in no cell), numbered in the piece.
struct Piece<const D: usize> {
    /// Mesh nodes of the piece's points, ascending.
    nodes: Vec<usize>,
    points: Vec<[f64; D]>,
    cells: Vec<Cell>,
    node_ids: Vec<i32>,
    cell_ids: Vec<i32>,
    /// The mesh's index of each cell (for its material).
    mesh_cells: Vec<usize>,
    cell_groups: Vec<i32>,
    /// Each cell's material index, with several materials.
    cell_materials: Vec<i32>,
    measures: Vec<f64>,
}

impl<const D: usize> Piece<D> {
    fn new(sim: &Simulation<D>, partition: &Partition, rank: usize, with_stress: bool) -> Result<Self, String> {
        let mesh = &sim.mesh;
        // (the same verdict on every rank)
        for (what, n) in [(NODE_IDS, mesh.points.len()), (CELL_IDS, mesh.cells.len())] {
            if i32::try_from(n).is_err() {
                return Err(format!(
                    "{}: {n} mesh {what}s do not fit the Int32 array `{what}` of the output's pieces",
                    mesh.path.display()
                ));
            }
        }
        let own = partition.cells_owned_by(rank);
        let mut used = vec![false; mesh.points.len()];
        let mut in_cell = vec![false; mesh.points.len()];
        for (e, c) in mesh.cells.iter().enumerate() {
            for &p in c.nodes() {
                in_cell[p] = true;
                if partition.cell_owner[e] == rank {
                    used[p] = true;
                }
            }
        }
        // a node of no cell is written by its owner, so that every node is in some piece
        for (p, u) in used.iter_mut().enumerate() {
            *u |= !in_cell[p] && partition.owner[p] == rank;
        }
        let nodes: Vec<usize> = (0..used.len()).filter(|&p| used[p]).collect();
        let mut number = vec![usize::MAX; mesh.points.len()];
        for (k, &p) in nodes.iter().enumerate() {
            number[p] = k;
        }
        let groups = cell_groups(mesh);
        let cells: Vec<Cell> = own.iter().map(|&e| mesh.cells[e].renumbered(|p| number[p])).collect();
        let points: Vec<[f64; D]> = nodes.iter().map(|&p| mesh.points[p]).collect();
        Ok(Piece {
            // (checked above to fit)
            node_ids: nodes.iter().map(|&p| p as i32).collect(),
            cell_ids: own.iter().map(|&e| e as i32).collect(),
            cell_groups: own.iter().map(|&e| groups[e]).collect(),
            cell_materials: {
                let all = cell_materials(sim);
                own.iter().filter(|_| !all.is_empty()).map(|&e| all[e]).collect()
            },
            mesh_cells: own.clone(),
            measures: if with_stress {
                cell_measures(&cells, &points)
            } else {
                Vec::new()
            },
            nodes,
            points,
            cells,
        })
    }
}

/// The scatters that bring a piece the values at its nodes from their owners (and rank 0 the
/// displacement of the contact boundary).
struct Exchange {
    /// This rank's unknowns (a step vector) as a PETSc vector.
    owned: Vector,
    /// The D components of each piece node.
    to_piece: Scatter,
    /// The nodal-stress sums of this rank's nodes.
    sums: Vector,
    sums_to_piece: Scatter,
    /// Rank 0: the D components of `boundary_nodes`; elsewhere nothing.
    boundary: Scatter,
    boundary_nodes: Vec<usize>,
}

/// The body's pieces on every rank, and rank 0's tables.
pub(super) struct PieceSink<'a, const D: usize> {
    world: &'a SimpleCommunicator,
    rank: usize,
    ranks: usize,
    /// Rank 0's: Γ₃ tables and dataset, reactions, contact forces, the manifest, progress.
    pub tables: Option<FileSink<D>>,
    series: SeriesWriter,
    piece: Piece<D>,
    exchange: Exchange,
    fields: Vec<OutputField>,
    /// `output.active_scalar` (None: von Mises, the first scalar).
    active_scalar: Option<String>,
    pub stress_seconds: f64,
}

impl<'a, const D: usize> PieceSink<'a, D> {
    /// Every rank: checks `dir` writable (rank 0 has created it and started the manifest,
    /// `tables` is its sink) and prepares its piece, agreed on by all; then the scatters
    /// (collective).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        petsc: &'a Petsc,
        dir: &Path,
        sim: &Simulation<D>,
        partition: &Partition,
        fields: &[OutputField],
        contact_groups: &[GroupSelector],
        compression: u32,
        tables: Option<FileSink<D>>,
    ) -> Result<Self, SolveError> {
        let (rank, ranks) = (petsc.rank(), petsc.size());
        let local = || -> Result<_, SolveError> {
            let series = SeriesWriter::create_parallel(dir, "solution")?.with_compression(compression);
            let piece = Piece::new(sim, partition, rank, wants_stress(fields)).map_err(SolveError::Setup)?;
            // Rank 0's tables need the displacement on Γ₃ only: the nodes of the contact
            // groups and of the contact rows, the target nodes of two-body rows included
            // (their u_ν and target points, docs/method.md §18.4).
            let mut boundary_nodes = Vec::new();
            if let (0, Some(c)) = (rank, &sim.contact) {
                boundary_nodes.extend_from_slice(&c.nodes.nodes);
                boundary_nodes.extend_from_slice(&c.nodes.clamped_nodes);
                boundary_nodes.extend(c.master_terms.iter().flatten().map(|&(q, _)| q));
                for g in contact_groups {
                    boundary_nodes.extend_from_slice(&sim.mesh.boundary(g)?.nodes);
                }
                boundary_nodes.sort_unstable();
                boundary_nodes.dedup();
            }
            Ok((series, piece, boundary_nodes))
        };
        let local = local();
        agree(petsc.world(), local.as_ref().map(|_| ()).map_err(|e| e.to_string())).map_err(SolveError::Setup)?;
        let (series, piece, boundary_nodes) = local?;
        let exchange = Self::exchange(petsc, partition, &piece, boundary_nodes);
        agree(petsc.world(), exchange.as_ref().map(|_| ()).map_err(|e| e.to_string())).map_err(|e| {
            SolveError::Setup(format!(
                "the PETSc backend could not prepare the output's scatters: {e}"
            ))
        })?;
        Ok(PieceSink {
            world: petsc.world(),
            rank,
            ranks,
            tables,
            series,
            piece,
            exchange: exchange.map_err(|e| SolveError::Setup(e.to_string()))?,
            fields: fields.to_vec(),
            active_scalar: None,
            stress_seconds: 0.0,
        })
    }

    /// Marks the body's active scalars as a serial run does (`output.active_scalar`,
    /// docs/method.md §12.3).
    pub fn with_active_scalar(mut self, name: Option<&str>) -> Self {
        self.active_scalar = name.map(str::to_string);
        self
    }

    fn exchange(
        petsc: &Petsc,
        partition: &Partition,
        piece: &Piece<D>,
        boundary_nodes: Vec<usize>,
    ) -> Result<Exchange, hvi_petsc::Error> {
        let rank = petsc.rank();
        let own = partition.nodes_of(rank);
        let owned = Vector::mpi(petsc, D * own)?;
        let rows = |nodes: &[usize], per: usize| -> Vec<Int> {
            nodes
                .iter()
                .flat_map(|&p| (0..per).map(move |c| (per * partition.position[p] + c) as Int))
                .collect()
        };
        let to_piece = Scatter::new(&owned, &rows(&piece.nodes, D))?;
        let sums = Vector::mpi(petsc, SUMS * own)?;
        let sums_to_piece = Scatter::new(&sums, &rows(&piece.nodes, SUMS))?;
        let boundary = Scatter::new(&owned, &rows(&boundary_nodes, D))?;
        Ok(Exchange {
            owned,
            to_piece,
            sums,
            sums_to_piece,
            boundary,
            boundary_nodes,
        })
    }

    /// The values of the frame at the piece's nodes, and on rank 0 the displacement over all
    /// unknowns that its tables read (correct on Γ₃, zero elsewhere); collective.
    #[allow(clippy::type_complexity)]
    fn gather(
        &mut self,
        sim: &Simulation<D>,
        view: &StepView,
    ) -> Result<
        (
            Vec<[f64; D]>,
            Option<Vec<crate::fem::stress::MemoryField<D>>>,
            Option<Vec<f64>>,
        ),
        hvi_petsc::Error,
    > {
        let x = &mut self.exchange;
        let np = self.piece.nodes.len();
        let mut flat = vec![0.0; D * np];
        x.owned.set_local(view.displacement)?;
        x.to_piece.gather(&x.owned, &mut flat)?;
        let nodal = sim.dofs.to_nodal(&flat);
        let mut at_boundary = vec![0.0; D * x.boundary_nodes.len()];
        x.boundary.gather(&x.owned, &mut at_boundary)?;
        let whole = (self.rank == 0).then(|| {
            let mut u = vec![0.0; sim.dofs.n()];
            for (k, &p) in x.boundary_nodes.iter().enumerate() {
                u[D * p..D * p + D].copy_from_slice(&at_boundary[D * k..D * k + D]);
            }
            u
        });
        // one memory channel with a backend (docs/method.md §15.1): its tensor and m_n
        let memory = match (view.memory_displacement, sim.materials.memory()) {
            (Some(m), Some(memory)) => {
                x.owned.set_local(m)?;
                x.to_piece.gather(&x.owned, &mut flat)?;
                Some(vec![(memory.channels()[0].tensor, sim.dofs.to_nodal(&flat))])
            }
            _ => None,
        };
        Ok((nodal, memory, whole))
    }

    /// The cell stresses of the piece and the recovered nodal stresses at its nodes, the sums
    /// over the cells around each node added up over the pieces first (collective).
    fn stresses(
        &mut self,
        sim: &Simulation<D>,
        nodal: &[[f64; D]],
        memory: Option<&[crate::fem::stress::MemoryField<D>]>,
    ) -> Result<(crate::fem::stress::CellStresses, crate::fem::stress::CellStresses), hvi_petsc::Error> {
        let p = &self.piece;
        let cell = cell_stresses(&p.cells, &p.points, &sim.materials, Some(&p.mesh_cells), nodal, memory);
        let (sum, weight) = nodal_stress_sums(&p.cells, &p.measures, &cell.tensor, p.nodes.len());
        let mut packed = vec![0.0; SUMS * p.nodes.len()];
        for (k, chunk) in packed.chunks_exact_mut(SUMS).enumerate() {
            chunk[..9].copy_from_slice(&sum[9 * k..9 * k + 9]);
            chunk[9] = weight[k];
        }
        let x = &mut self.exchange;
        x.sums.with_local_mut(|a| a.fill(0.0))?;
        x.sums_to_piece.add_back(&packed, &mut x.sums)?;
        x.sums_to_piece.gather(&x.sums, &mut packed)?;
        let mut sum = vec![0.0; 9 * p.nodes.len()];
        let mut weight = vec![0.0; p.nodes.len()];
        for (k, chunk) in packed.chunks_exact(SUMS).enumerate() {
            sum[9 * k..9 * k + 9].copy_from_slice(&chunk[..9]);
            weight[k] = chunk[9];
        }
        Ok((cell, nodal_stresses_from_sums(sum, &weight)))
    }
}

impl<const D: usize> FrameSink<D> for PieceSink<'_, D> {
    fn step_done(&mut self, sim: &Simulation<D>, view: &StepView) {
        if let Some(t) = self.tables.as_mut() {
            t.step_done(sim, view);
        }
    }

    fn write_frame(&mut self, sim: &Simulation<D>, view: &StepView) -> Result<(), SolveError> {
        let step = view.step;
        // 1. Rank 0 lists the frame's files before any of them exists.
        let listed = match self.tables.as_mut() {
            Some(t) => (0..self.ranks)
                .map(|r| self.series.piece_name(step, r))
                .chain([self.series.frame_name(step)])
                .try_for_each(|name| t.manifest.add(&name))
                .map_err(|e| e.to_string()),
            None => Ok(()),
        };
        // 2. The values at the piece's nodes (collective, whatever happened above).
        // (A rank whose gather failed goes on with zeros, so that every rank makes the same
        // collective calls; the agreement below then stops all of them.)
        let gathered = self.gather(sim, view).map_err(|e| e.to_string());
        let (nodal, memory, whole) = match &gathered {
            Ok(values) => values.clone(),
            Err(_) => (vec![[0.0; D]; self.piece.nodes.len()], None, None),
        };
        let stresses = wants_stress(&self.fields).then(|| {
            let mut seconds = 0.0;
            let s = timed(&mut seconds, || self.stresses(sim, &nodal, memory.as_deref()));
            self.stress_seconds += seconds;
            s.map_err(|e| e.to_string())
        });
        let ready = listed.and(gathered.map(|_| ())).and(match &stresses {
            Some(Err(e)) => Err(e.clone()),
            _ => Ok(()),
        });
        agree(self.world, ready).map_err(SolveError::Setup)?;
        let stresses = stresses.and_then(Result::ok);
        // 3. Every rank writes its piece.
        let p = &self.piece;
        let displacement = displacement_3(&nodal);
        let (mut point_fields, mut cell_fields) = body_fields(
            &self.fields,
            &displacement,
            stresses.as_ref(),
            &p.cell_groups,
            &p.cell_materials,
        );
        mark_active(&mut point_fields, &mut cell_fields, self.active_scalar.as_deref());
        point_fields.push(Field::i32(NODE_IDS, 1, &p.node_ids));
        cell_fields.push(Field::i32(CELL_IDS, 1, &p.cell_ids));
        let frame = Frame {
            step,
            time: view.time,
            points: &p.points,
            cells: &p.cells,
            point_fields,
            cell_fields,
        };
        let written = self.series.write_piece(&frame, self.rank).map(|_| ());
        agree(self.world, written.map_err(|e| e.to_string())).map_err(SolveError::Setup)?;
        // 4. Rank 0: the .pvtu and the index, then the tables.
        let finished = match (self.tables.as_mut(), whole) {
            (Some(t), Some(u)) => self
                .series
                .write_parallel_frame(&frame, self.ranks)
                .map_err(SolveError::from)
                .and_then(|_| {
                    let tables = StepView {
                        step,
                        time: view.time,
                        output: view.output,
                        displacement: &u,
                        memory_displacement: None,
                        contact: view.contact,
                        outcome: view.outcome,
                        reactions: view.reactions,
                        contact_forces: view.contact_forces,
                        motion: view.motion,
                    };
                    t.write_frame(sim, &tables)
                })
                .map(|()| t.last_written = Some(step)),
            _ => Ok(()),
        };
        let verdict = agree(self.world, finished.as_ref().map(|_| ()).map_err(|e| e.to_string()));
        finished?;
        verdict.map_err(SolveError::Setup)
    }
}
