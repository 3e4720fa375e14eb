//! The body's materials (docs/method.md §8.5): each cell's material, each material's elasticity
//! A, memory and volumetric rule; and the memories of all of them as the time loop runs them —
//! one list of channels, each owned by one material, whose K_j is assembled over that material's
//! cells only (zero tensor elsewhere). With one material everything is as it was: no per-cell
//! index, its memory as it is.

use super::assembly::{assemble_by_cell, CellTensors, Volumetric};
use super::dofs::DofMap;
use super::patch_dilatation::CellPatches;
use crate::linalg::sparse::SymmetricMatrix;
use crate::material::{Elasticity, Isotropic, Memory, PlaneModel};
use crate::mesh::Cell;

/// One material of the body.
#[derive(Clone, Debug)]
pub struct BodyMaterial {
    /// How messages and `hvi check` name it: its group's label (`Seal (tag 2)`), or `[material]`.
    pub name: String,
    pub elasticity: Elasticity,
    pub memory: Option<Memory>,
    pub volumetric: Volumetric,
}

impl BodyMaterial {
    /// K/G at t = 0 and once relaxed (the long-term tensor A + Σ_j T_j ∫₀^∞ b_j, for Prony
    /// kernels; infinite for a shear modulus that relaxes to zero); None in plane stress, which
    /// has no volumetric constraint (docs/method.md §8.4).
    pub fn bulk_to_shear(&self) -> Option<(f64, Option<f64>)> {
        if self.elasticity.plane == Some(PlaneModel::Stress) {
            return None;
        }
        let long_term = self
            .memory
            .as_ref()
            .and_then(|m| m.long_term_share(None, crate::material::Rules::TRAPEZOID))
            .map(|s| {
                let a = self.elasticity.tensor();
                let (lambda, mu) = (a.lambda + s.lambda, a.mu + s.mu);
                if mu > 0.0 {
                    (lambda + 2.0 * mu / 3.0) / mu
                } else {
                    f64::INFINITY
                }
            });
        Some((self.elasticity.bulk_to_shear(), long_term))
    }
}

/// A material's place in [`Materials::list`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MaterialId(pub u32);

impl MaterialId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The materials of a body and which cell has which.
#[derive(Clone, Debug)]
pub struct Materials {
    list: Vec<BodyMaterial>,
    /// Each cell's material; None with one material.
    of_cell: Option<Vec<u32>>,
    /// Every material's memory as one (docs/method.md §8.5).
    memory: Option<Memory>,
    /// The material of each channel of `memory`.
    owner: Vec<MaterialId>,
    /// The patches of the simplices whose bulk part is averaged there (docs/method.md §8.4).
    patches: CellPatches,
}

impl Materials {
    /// A body of one material on `cells`.
    pub fn one(material: BodyMaterial, cells: &[Cell]) -> Self {
        Self::new(vec![material], Vec::new(), cells)
    }

    /// Materials `list` on `cells`, with `of_cell[c]` the index of cell c's (ignored with one
    /// material).
    pub fn new(list: Vec<BodyMaterial>, of_cell: Vec<u32>, cells: &[Cell]) -> Self {
        let with_memory: Vec<(usize, &Memory)> = list
            .iter()
            .enumerate()
            .filter_map(|(i, m)| m.memory.as_ref().map(|mem| (i, mem)))
            .collect();
        let (memory, owner) = if with_memory.is_empty() {
            (None, Vec::new())
        } else {
            let parts: Vec<&Memory> = with_memory.iter().map(|(_, m)| *m).collect();
            let (memory, part) = Memory::combined(&parts);
            let owner = part.iter().map(|&p| MaterialId(with_memory[p].0 as u32)).collect();
            (Some(memory), owner)
        };
        let of_cell = (list.len() > 1).then_some(of_cell);
        let axisymmetric = list
            .first()
            .is_some_and(|m| m.elasticity.plane == Some(PlaneModel::Axisymmetric));
        let patches = CellPatches::new(cells, of_cell.as_deref(), axisymmetric, |m, cell| {
            list[m as usize].volumetric.patch_mean(cell)
        });
        Materials {
            list,
            of_cell,
            memory,
            owner,
            patches,
        }
    }

    /// The materials, in the order of [`MaterialId`].
    pub fn list(&self) -> &[BodyMaterial] {
        &self.list
    }

    /// Cell `c`'s material.
    pub fn id_of_cell(&self, c: usize) -> MaterialId {
        MaterialId(self.of_cell.as_ref().map_or(0, |of| of[c]))
    }

    /// Cell `c`'s material.
    pub fn of_cell(&self, c: usize) -> &BodyMaterial {
        &self.list[self.id_of_cell(c).index()]
    }

    /// How many cells each material has, of `n_cells` in all.
    pub fn cell_counts(&self, n_cells: usize) -> Vec<usize> {
        let mut counts = vec![0; self.list.len()];
        match &self.of_cell {
            Some(of) => of.iter().for_each(|&m| counts[m as usize] += 1),
            None => counts[0] = n_cells,
        }
        counts
    }

    /// The patches of the averaged simplices (empty: none).
    pub fn patches(&self) -> &CellPatches {
        &self.patches
    }

    /// The memory of all materials, as the time loop runs it; None when no material has any.
    pub fn memory(&self) -> Option<&Memory> {
        self.memory.as_ref()
    }

    /// The material memory channel `j` belongs to.
    pub fn channel_owner(&self, j: usize) -> MaterialId {
        self.owner[j]
    }

    /// The 2D model (the same for every material).
    pub fn plane(&self) -> Option<PlaneModel> {
        self.list[0].elasticity.plane
    }

    /// Whether some material's cell takes the volumetric strain as its mean (docs/method.md §8.4).
    pub fn projects(&self, c: usize, cell: &Cell) -> bool {
        self.of_cell(c).volumetric.projects(cell)
    }

    /// The material whose bulk modulus is largest against its shear modulus (K/G): the one a
    /// singular matrix is put down to.
    pub fn most_incompressible(&self) -> &BodyMaterial {
        self.list
            .iter()
            .max_by(|a, b| a.elasticity.bulk_to_shear().total_cmp(&b.elasticity.bulk_to_shear()))
            .expect("a body has a material")
    }

    /// The smallest coercivity constant m_A over the materials (docs/method.md §1).
    pub fn coercivity(&self, dim: usize) -> f64 {
        self.list
            .iter()
            .map(|m| m.elasticity.coercivity(dim))
            .fold(f64::INFINITY, f64::min)
    }

    /// Per material, the tensors of the matrices asked for: A (`elastic`) and the channels'
    /// T_j (`channels`), each zero on the materials a channel does not belong to.
    pub fn tensors(&self, elastic: bool, channels: bool) -> Vec<Vec<Isotropic>> {
        const ZERO: Isotropic = Isotropic { lambda: 0.0, mu: 0.0 };
        (0..self.list.len())
            .map(|i| {
                let a = elastic.then(|| self.list[i].elasticity.tensor());
                let t = self.memory.iter().filter(|_| channels).flat_map(|m| {
                    m.channels()
                        .iter()
                        .zip(&self.owner)
                        .map(move |(c, o)| if o.index() == i { c.tensor } else { ZERO })
                });
                a.into_iter().chain(t).collect()
            })
            .collect()
    }

    /// K_A (`elastic`) and every channel's K_j (`channels`), in one assembly pass, in that order.
    pub fn assemble<const D: usize>(
        &self,
        cells: &[Cell],
        points: &[[f64; D]],
        dofs: &DofMap<D>,
        elastic: bool,
        channels: bool,
    ) -> Vec<SymmetricMatrix> {
        let tensors = self.tensors(elastic, channels);
        let volumetric: Vec<Volumetric> = self.list.iter().map(|m| m.volumetric).collect();
        let by_cell = CellTensors {
            tensors: &tensors,
            volumetric: &volumetric,
            of_cell: self.of_cell.as_deref(),
            patches: Some(&self.patches).filter(|p| !p.is_empty()),
            axisymmetric: self.plane() == Some(PlaneModel::Axisymmetric),
        };
        assemble_by_cell(cells, points, dofs, &by_cell)
    }

    /// K_A alone.
    pub fn assemble_elastic<const D: usize>(
        &self,
        cells: &[Cell],
        points: &[[f64; D]],
        dofs: &DofMap<D>,
    ) -> SymmetricMatrix {
        let mut k = self.assemble(cells, points, dofs, true, false);
        k.pop().expect("K_A")
    }
}
