//! The time loop's backend on one machine (docs/method.md §3, §9): K_A and the memory channels'
//! K_j assembled once, the step matrix's symbolic analysis and one cached faer Cholesky factor,
//! the contact normals condensed by split sweeps (or stored responses).

use super::backend::{Backend, Stiffness};
use super::error::SolveError;
use super::operator::{system_matrix, StepOperator};
use super::reactions::Reactions;
use super::setup::Simulation;
use super::stats::{timed, RunStats};
use crate::fem::{NodeBlockMatrix, SymmetricMatrix};
use crate::linalg::{Analysis, Counters, Factor};

/// K_j as the time loop multiplies it: in node blocks (a third of the memory traffic) when
/// its pattern allows, else as assembled. Unmodified: the memory load includes the history of
/// prescribed displacements (docs/method.md §7).
enum MemoryStiffness<const D: usize> {
    NodeBlocks(NodeBlockMatrix<D>),
    Full(SymmetricMatrix),
}

impl<const D: usize> MemoryStiffness<D> {
    fn matvec(&self, x: &[f64], y: &mut [f64]) {
        match self {
            MemoryStiffness::NodeBlocks(m) => m.matvec(x, y),
            MemoryStiffness::Full(m) => m.matvec(x, y),
        }
    }
}

/// The serial backend: what it has assembled and analysed, once its first operator is built.
pub struct FaerBackend<const D: usize> {
    /// K_A, unmodified (the products, and the factor of K_A alone). Not kept beside a step
    /// matrix with memory: such a run needs K_A alone only at a loaded step 0, which assembles it
    /// again (docs/method.md §9.6).
    k_a: Option<SymmetricMatrix>,
    /// K_j of each memory channel, for the memory load K_j h_n of every step.
    k_b: Vec<MemoryStiffness<D>>,
    /// The symbolic analysis every factor of the run shares.
    symbolic: Option<Analysis>,
    /// The prescribed columns for the reactions, taken before the factorisation.
    reactions: Option<Reactions>,
}

impl<const D: usize> Default for FaerBackend<D> {
    fn default() -> Self {
        FaerBackend {
            k_a: None,
            k_b: Vec::new(),
            symbolic: None,
            reactions: None,
        }
    }
}

impl<const D: usize> FaerBackend<D> {
    /// Assembles K_A and the K_j, analyses and factors K = K_A + Σ_j c_j K_j (c = `memory`),
    /// and condenses the contact normals.
    fn first_operator(
        &mut self,
        sim: &Simulation<D>,
        memory: &[f64],
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<StepOperator, SolveError> {
        let (points, cells) = (&sim.mesh.points, &sim.mesh.cells);
        let channels = sim.materials.memory().map_or(0, |m| m.channels().len());
        if !memory.is_empty() && channels != memory.len() {
            return Err(SolveError::Setup(format!(
                "the step matrix names {} memory channels and the materials' memories have {channels}",
                memory.len()
            )));
        }
        // one assembly pass for K_A and every channel's K_j (docs/method.md §8.5, §15.1)
        let mut assembled = timed(&mut stats.phases.assembly, || {
            sim.materials.assemble(cells, points, &sim.dofs, true, true)
        });
        let k_b = assembled.split_off(1);
        let k_a = assembled.pop().expect("K_A");
        stats.matrix_nonzeros = k_a.values.len();
        // The pattern the factors have: identity rows, fully prescribed nodes decoupled. In 3D the
        // contact normals' unknowns go last (docs/method.md §4.5): G and W then live in the
        // factor's trailing block (measured: box 96x48x12, m = 1248, condensation 12.4 s before).
        let last = sim.unknowns_ordered_last();
        // K = K_A + Σ_j (k/2) b_j(0) K_j (unmodified: before the identity rows)
        let k_step = timed(&mut stats.phases.assembly, || {
            let mut sum: Option<SymmetricMatrix> = None;
            for (kb, c) in k_b.iter().zip(memory) {
                sum = Some(sum.as_ref().unwrap_or(&k_a).plus_scaled(*c, kb));
            }
            sum
        });
        let system = system_matrix(sim, k_step.as_ref().unwrap_or(&k_a));
        drop(k_step);
        // K_j's prescribed columns and its node blocks are taken before the factorisation, and
        // the assembled K_j dropped: it is not held next to the factor (docs/method.md §9.3).
        self.reactions = (!sim.dirichlet.reaction_groups.is_empty()).then(|| Reactions::from_columns(sim, &k_a, &k_b));
        self.k_b = k_b
            .into_iter()
            .map(|kb| match NodeBlockMatrix::new(&kb) {
                Some(blocks) => MemoryStiffness::NodeBlocks(blocks),
                None => MemoryStiffness::Full(kb),
            })
            .collect();
        let symbolic = timed(&mut stats.phases.factorisation, || {
            Factor::analyse_with_last(&system.matrix, &last)
        })
        .map_err(|e| SolveError::Setup(e.to_string()))?;
        stats.ordering = Some(symbolic.ordering().to_string());
        stats.factor_entries = symbolic.factor_entries();
        // the predicted peak against what the process may use, before the large allocations
        let estimate = super::memory::MemoryEstimate::new(sim, &symbolic, stats.matrix_nonzeros);
        stats.predicted_peak_bytes = Some(estimate.total());
        estimate
            .check_fits(sim.contact.as_ref().map_or(0, |c| c.condensed_rows().len()))
            .map_err(|e| SolveError::OutOfMemory(format!("{}: {e}", sim.mesh.path.display())))?;
        // with memory, K_A would sit beside the factor for nothing (a fifth of the n = 40 slab's
        // peak besides the factor): dropped before the factorisation
        self.k_a = memory.is_empty().then_some(k_a);
        let operator = StepOperator::factored(sim, &symbolic, system, counters, stats)?;
        self.symbolic = Some(symbolic);
        Ok(operator)
    }
}

impl<const D: usize> Backend<D> for FaerBackend<D> {
    fn operator(
        &mut self,
        sim: &Simulation<D>,
        memory: &[f64],
        counters: &Counters,
        stats: &mut RunStats,
    ) -> Result<StepOperator, SolveError> {
        match &self.symbolic {
            None => self.first_operator(sim, memory, counters, stats),
            Some(symbolic) if memory.is_empty() => {
                let assembled;
                let k_a = match &self.k_a {
                    Some(k_a) => k_a,
                    None => {
                        let k_a = timed(&mut stats.phases.assembly, || {
                            sim.materials
                                .assemble_elastic(&sim.mesh.cells, &sim.mesh.points, &sim.dofs)
                        });
                        assembled = k_a;
                        &assembled
                    }
                };
                StepOperator::factored(sim, symbolic, system_matrix(sim, k_a), counters, stats)
            }
            Some(symbolic) => {
                // another step size (docs/method.md §20.3): K_A and the K_j are assembled again
                // (they are not held beside the factors, §9.3) and summed with the new β
                let (points, cells) = (&sim.mesh.points, &sim.mesh.cells);
                let mut assembled = timed(&mut stats.phases.assembly, || {
                    sim.materials.assemble(cells, points, &sim.dofs, true, true)
                });
                let k_b = assembled.split_off(1);
                let k_a = assembled.pop().expect("K_A");
                let k_step = timed(&mut stats.phases.assembly, || {
                    let mut sum = k_a;
                    for (kb, c) in k_b.iter().zip(memory) {
                        sum = sum.plus_scaled(*c, kb);
                    }
                    sum
                });
                drop(k_b);
                StepOperator::factored(sim, symbolic, system_matrix(sim, &k_step), counters, stats)
            }
        }
    }

    fn reactions(&mut self, sim: &Simulation<D>) -> Reactions {
        self.reactions
            .take()
            .unwrap_or_else(|| Reactions::over_products(sim, None))
    }

    fn product(&self, _sim: &Simulation<D>, matrix: Stiffness, x: &[f64], y: &mut [f64]) {
        match (matrix, &self.k_a) {
            (Stiffness::Elastic, Some(k_a)) => k_a.matvec(x, y),
            (Stiffness::Memory(j), _) if j < self.k_b.len() => self.k_b[j].matvec(x, y),
            // nothing assembled to multiply by: NaN, which the loop's checks report
            _ => y.fill(f64::NAN),
        }
    }
}

/// What `hvi check` asks of the faer backend before a run, without running it: K_A assembled
/// once with identity rows at the prescribed unknowns, its symbolic analysis with the run's
/// ordering (the factor's size), and on request the discrete smallness number of docs/method.md
/// §1 through a factor of K_A on that analysis.
pub struct ElasticCheck {
    k_a: SymmetricMatrix,
    analysis: Analysis,
}

impl ElasticCheck {
    /// Assembles K_A and analyses its pattern as a run would.
    pub fn new<const D: usize>(sim: &Simulation<D>) -> Result<Self, SolveError> {
        let k_a = sim
            .materials
            .assemble_elastic(&sim.mesh.cells, &sim.mesh.points, &sim.dofs);
        let k_a = k_a.with_identity_rows(&sim.dofs);
        let analysis = Factor::analyse_with_last(&k_a, &sim.unknowns_ordered_last())
            .map_err(|e| SolveError::Setup(e.to_string()))?;
        Ok(ElasticCheck { k_a, analysis })
    }

    /// Stored entries of the assembled K_A (for the memory prediction).
    pub fn matrix_entries(&self) -> usize {
        self.k_a.values.len()
    }

    /// The symbolic analysis: the ordering and nnz(L).
    pub fn analysis(&self) -> &Analysis {
        &self.analysis
    }

    /// α_j λ_max(D^{1/2} C K_A⁻¹ Cᵀ D^{1/2}) over the contact rows (docs/method.md §1): below 1,
    /// every step's energy is convex. One factorisation of K_A.
    pub fn smallness_ratio<const D: usize>(&self, sim: &Simulation<D>) -> Result<f64, SolveError> {
        let c = sim
            .contact
            .as_ref()
            .ok_or_else(|| SolveError::Setup("no contact".into()))?;
        let counters = Counters::default();
        let factor =
            Factor::new(&self.analysis, &self.k_a, &counters).map_err(|e| super::operator::factor_failed(sim, e))?;
        let op =
            super::operator::condensation(sim, &std::sync::Arc::new(factor), &counters).map_err(SolveError::Setup)?;
        // (the tangential rows of friction, after the normal ones, have no normal law)
        let mut weights = c.laws.monotonicity_weights(c.nodes.len());
        weights.resize(c.condensed_rows().len(), 0.0);
        Ok(op.trace_constant(&weights))
    }
}
