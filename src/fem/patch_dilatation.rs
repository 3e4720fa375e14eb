//! The patch-mean volumetric strain of triangles and tetrahedra (docs/method.md §8.4; the small-
//! strain form of de Souza Neto et al.'s F-bar-patch, 2005): a simplex has one constant divergence
//! per cell, so its own mean changes nothing; the mesh's simplices are instead partitioned into
//! disjoint patches of neighbouring cells, and the bulk energy is taken with each patch's mean
//!
//! ```text
//!   ½ K Θ_P² / V_P,   Θ_P(u) = Σ_{e∈P} ∫_e div u,   V_P = Σ_{e∈P} |e|,
//! ```
//!
//! one volumetric constraint per patch of ≥ [`MIN_PATCH_CELLS`] cells instead of one per cell. The
//! stiffness adds (K/V_P) g_P g_Pᵀ with g_P = ∂Θ_P/∂u over the patch's nodes: a patch joins the
//! matrix's pattern as one larger cell. It stays symmetric positive definite, a constant strain
//! keeps the continuum's energy (the patches tile the body), and the pressure −K Θ_P/V_P is one
//! value per patch. On a body of revolution (docs/method.md §8.6) the same over 2πr with the hoop
//! strain in the divergence: Θ_P = Σ ∫_e (div u + u_r/r) 2πr dA (three points per triangle, exact).
//! Written by hand: no crate assembles it.
//!
//! The patches: the star of a node (every cell around it) while all of the star's cells are still
//! free and there are at least [`MIN_PATCH_CELLS`] of them, nodes in ascending order; then, node by
//! node, the free cells around it if at least [`MIN_PATCH_CELLS`] are left; a cell still free
//! after that joins the smallest patch it shares a node with (rounds until none is left; a
//! material too small for any patch gets one per star). Deterministic for a mesh.

use crate::linalg::sparse::Pattern;
use crate::material::Isotropic;
use crate::mesh::element::{shape_at, stiffness_rule, ShapeAt};
use crate::mesh::quadrature::TRI_3POINT;
use crate::mesh::Cell;
use rayon::prelude::*;

/// The fewest cells a patch is made with (a leftover cell may join a patch later). Measured
/// (2026-12-06) at ν = 0.4999, the largest / RMS cell pressure error against Lamé's on the P1
/// quarter ring (16 cells across the wall, structured) and on an unstructured ring of 8 863
/// triangles, and 3D Hertz on the gallery's tetrahedra (a, p₀, nnz(L)):
///
/// | fewest | ring max / RMS | unstructured max / RMS | 3D Hertz a, p₀ | nnz(L) |
/// |---|---|---|---|---|
/// | node patches (before) | 1.53 / 0.74 | 0.35 / 0.043 | −0.77 %, +2.83 % | 42.9 M |
/// | 2 | 0.78 / 0.18 | 0.070 / 0.0045 | −0.62 %, +2.17 % | 21.5 M |
/// | 4 | 0.020 / 0.0042 | 0.021 / 0.0021 | −0.52 %, +1.29 % | 21.8 M |
/// | 8 | | | −0.45 %, +0.81 % | 25.2 M |
///
/// (the plain tetrahedra's nnz(L) is 14.0 M; the rows 2 and 8 took whole stars of any size
/// first). With 2 a patch of two triangles still carries the
/// pressure mode of the single triangles; from 4 on the structured ring's patches are its 2 × 2
/// squares of 8 triangles, Q1–P0's stable macro-element.
pub const MIN_PATCH_CELLS: usize = 4;

/// A patch: the index into [`CellPatches`]'s lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PatchId(u32);

impl PatchId {
    /// As an index.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The patches of the averaged simplices: each patch's material and cells, each cell's patch.
#[derive(Clone, Debug, Default)]
pub struct CellPatches {
    /// The material of each patch.
    material: Vec<u32>,
    /// Patch p's cells are `cells[ptr[p]..ptr[p + 1]]`.
    ptr: Vec<usize>,
    cells: Vec<usize>,
    /// Each mesh cell's patch (None: not averaged).
    of_cell: Vec<Option<PatchId>>,
    /// A body of revolution (x = r).
    axisymmetric: bool,
}

/// The points of ∫_cell (…) over a simplex: (weight, the shapes there). In the plane one point
/// (|e|, the constant gradients); on a body of revolution the triangle's three points with 2πr.
fn weighted_points<const D: usize>(cell: &Cell, points: &[[f64; D]], axisymmetric: bool) -> Vec<(f64, ShapeAt<D>)> {
    if axisymmetric {
        TRI_3POINT
            .iter()
            .map(|q| {
                let s = shape_at(cell, points, q.xi);
                (q.weight * s.det_j * 2.0 * std::f64::consts::PI * s.x[0], s)
            })
            .collect()
    } else {
        let rule = stiffness_rule(cell);
        let s = shape_at(cell, points, rule[0].xi);
        let measure: f64 = rule.iter().map(|q| q.weight).sum::<f64>() * s.det_j;
        vec![(measure, s)]
    }
}

/// The divergence of N_b e_i at a point: ∂ᵢN_b, plus N_b/r for i = r on a body of revolution.
fn divergence<const D: usize>(s: &ShapeAt<D>, b: usize, i: usize, axisymmetric: bool) -> f64 {
    let hoop = if axisymmetric && i == 0 {
        s.value[b] / s.x[0]
    } else {
        0.0
    };
    s.grad[b][i] + hoop
}

impl CellPatches {
    /// The patches of the simplices `averaged` says (by their material, `of_cell`; None: 0), of
    /// a body of revolution (x = r) if `axisymmetric`; a patch holds cells of one material.
    pub fn new(
        cells: &[Cell],
        of_cell: Option<&[u32]>,
        axisymmetric: bool,
        averaged: impl Fn(u32, &Cell) -> bool,
    ) -> Self {
        let material_of = |c: usize| of_cell.map_or(0, |of| of[c]);
        // the stars: per (material, node) its averaged cells
        let mut pairs: Vec<((u32, usize), usize)> = Vec::new();
        for (c, cell) in cells.iter().enumerate() {
            let m = material_of(c);
            if averaged(m, cell) {
                pairs.extend(cell.nodes().iter().map(|&a| ((m, a), c)));
            }
        }
        pairs.sort_unstable();
        let stars: Vec<&[((u32, usize), usize)]> = pairs.chunk_by(|x, y| x.0 == y.0).collect();
        let mut of: Vec<Option<PatchId>> = vec![None; cells.len()];
        let mut patches: Vec<(u32, Vec<usize>)> = Vec::new();
        for whole in [true, false] {
            for star in &stars {
                let free: Vec<usize> = star.iter().map(|&(_, c)| c).filter(|&c| of[c].is_none()).collect();
                if free.len() >= MIN_PATCH_CELLS && (!whole || free.len() == star.len()) {
                    let id = PatchId(patches.len() as u32);
                    free.iter().for_each(|&c| of[c] = Some(id));
                    patches.push((star[0].0 .0, free));
                }
            }
        }
        // the cells left join the smallest patch they share a node with (in the first star, by
        // the nodes' order, that has one); a cell with none around it waits for the next round
        loop {
            let mut joined = false;
            for star in &stars {
                for &(_, c) in star.iter() {
                    if of[c].is_some() {
                        continue;
                    }
                    let smallest = star
                        .iter()
                        .filter_map(|&(_, o)| of[o])
                        .min_by_key(|p| patches[p.index()].1.len());
                    if let Some(id) = smallest {
                        of[c] = Some(id);
                        patches[id.index()].1.push(c);
                        joined = true;
                    }
                }
            }
            if !joined {
                break;
            }
        }
        // what no patch reaches (a material with fewer cells than the fewest): a patch per star
        for star in &stars {
            let free: Vec<usize> = star.iter().map(|&(_, c)| c).filter(|&c| of[c].is_none()).collect();
            if !free.is_empty() {
                let id = PatchId(patches.len() as u32);
                free.iter().for_each(|&c| of[c] = Some(id));
                patches.push((star[0].0 .0, free));
            }
        }
        let mut out = CellPatches {
            material: Vec::with_capacity(patches.len()),
            ptr: vec![0],
            cells: Vec::new(),
            of_cell: of,
            axisymmetric,
        };
        for (m, cs) in patches {
            out.material.push(m);
            out.cells.extend(cs);
            out.ptr.push(out.cells.len());
        }
        out
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.material.is_empty()
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.material.len()
    }

    /// The cells of patch p.
    pub fn cells_of(&self, p: usize) -> &[usize] {
        &self.cells[self.ptr[p]..self.ptr[p + 1]]
    }

    /// Cell c's patch, if its bulk part is averaged.
    pub fn of_cell(&self, c: usize) -> Option<PatchId> {
        self.of_cell.get(c).copied().flatten()
    }

    /// The nodes of patch p, ascending.
    pub fn nodes(&self, p: usize, cells: &[Cell]) -> Vec<usize> {
        let mut nodes: Vec<usize> = self
            .cells_of(p)
            .iter()
            .flat_map(|&c| cells[c].nodes().to_vec())
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// V_P and g_P = ∂Θ_P/∂u over `nodes` (D per node) of patch p.
    fn gradient<const D: usize>(
        &self,
        p: usize,
        cells: &[Cell],
        points: &[[f64; D]],
        nodes: &[usize],
    ) -> (f64, Vec<f64>) {
        let mut g = vec![0.0; D * nodes.len()];
        let mut volume = 0.0;
        for &c in self.cells_of(p) {
            let cell = &cells[c];
            for (w, s) in weighted_points(cell, points, self.axisymmetric) {
                volume += w;
                for (k, &b) in cell.nodes().iter().enumerate() {
                    let at = nodes.binary_search(&b).expect("a patch holds its cells' nodes");
                    for i in 0..D {
                        g[D * at + i] += w * divergence(&s, k, i, self.axisymmetric);
                    }
                }
            }
        }
        (volume, g)
    }

    /// Adds Σ_P (K_j/V_P) g_P g_Pᵀ to each matrix j of `out` (values on `pattern`, which holds
    /// every patch as a cell), K_j the bulk modulus λ_j + 2μ_j/3 of tensor j of the patch's
    /// material (`tensors[material][j]`).
    pub fn add_stiffness<const D: usize>(
        &self,
        pattern: &Pattern,
        cells: &[Cell],
        points: &[[f64; D]],
        tensors: &[Vec<Isotropic>],
        out: &mut [Vec<f64>],
    ) {
        const CHUNK: usize = 4096;
        let patches: Vec<usize> = (0..self.len()).collect();
        for chunk in patches.chunks(CHUNK) {
            let local: Vec<(Vec<usize>, f64, Vec<f64>)> = chunk
                .par_iter()
                .map(|&p| {
                    let nodes = self.nodes(p, cells);
                    let (volume, g) = self.gradient(p, cells, points, &nodes);
                    let nl = D * nodes.len();
                    let mut at = vec![0; nl * nl];
                    pattern.cell_positions(&nodes, &mut at);
                    (at, volume, g)
                })
                .collect();
            for (&p, (at, volume, g)) in chunk.iter().zip(&local) {
                let material = self.material[p] as usize;
                let nl = g.len();
                for (j, values) in out.iter_mut().enumerate() {
                    let t = tensors[material][j];
                    let bulk = (t.lambda + 2.0 * t.mu / 3.0) / volume;
                    if bulk == 0.0 {
                        continue;
                    }
                    for r in 0..nl {
                        for s in 0..nl {
                            values[at[r * nl + s]] += bulk * g[r] * g[s];
                        }
                    }
                }
            }
        }
    }

    /// θ_P = Θ_P(u)/V_P of every patch, for the nodal displacement `u`.
    pub fn dilatation<const D: usize>(&self, cells: &[Cell], points: &[[f64; D]], u: &[[f64; D]]) -> Vec<f64> {
        (0..self.len())
            .into_par_iter()
            .map(|p| {
                let (mut theta, mut volume) = (0.0, 0.0);
                for &c in self.cells_of(p) {
                    let cell = &cells[c];
                    for (w, s) in weighted_points(cell, points, self.axisymmetric) {
                        let div: f64 = cell
                            .nodes()
                            .iter()
                            .enumerate()
                            .map(|(k, &b)| {
                                (0..D)
                                    .map(|i| divergence(&s, k, i, self.axisymmetric) * u[b][i])
                                    .sum::<f64>()
                            })
                            .sum();
                        theta += w * div;
                        volume += w;
                    }
                }
                theta / volume
            })
            .collect()
    }

    /// The node lists of the patches, as cells of the matrix's pattern.
    pub fn node_lists(&self, cells: &[Cell]) -> Vec<Vec<usize>> {
        (0..self.len()).map(|p| self.nodes(p, cells)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured::{block, rectangle, CellShape, SolidShape};

    /// Every averaged cell is in exactly one patch of its material, and a patch has at least
    /// MIN_PATCH_CELLS cells unless its material has fewer cells around it.
    #[test]
    fn the_patches_tile_the_averaged_cells() {
        let mesh = rectangle(2.0, 1.0, 9, 5, CellShape::Tri);
        let of: Vec<u32> = (0..mesh.cells.len()).map(|c| u32::from(c % 7 == 0)).collect();
        let patches = CellPatches::new(&mesh.cells, Some(&of), false, |_, _| true);
        let mut seen = vec![0; mesh.cells.len()];
        for p in 0..patches.len() {
            for &c in patches.cells_of(p) {
                seen[c] += 1;
                assert_eq!(of[c], patches.material[p], "a patch holds one material");
                assert_eq!(patches.of_cell(c), Some(PatchId(p as u32)));
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "every cell once: {seen:?}");
        let sizes: Vec<usize> = (0..patches.len()).map(|p| patches.cells_of(p).len()).collect();
        let material0 = (0..patches.len()).filter(|&p| patches.material[p] == 0);
        assert!(
            material0.clone().all(|p| sizes[p] >= MIN_PATCH_CELLS),
            "sizes {sizes:?}"
        );
        let tets = block([1.0, 1.0, 1.0], [4, 3, 3], SolidShape::Tet);
        let patches = CellPatches::new(&tets.cells, None, false, |_, _| true);
        let total: usize = (0..patches.len()).map(|p| patches.cells_of(p).len()).sum();
        assert_eq!(total, tets.cells.len());
        assert!((0..patches.len()).all(|p| patches.cells_of(p).len() >= MIN_PATCH_CELLS));
    }
}
