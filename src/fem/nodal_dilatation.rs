//! The nodal-averaged volumetric strain of triangles and tetrahedra (docs/method.md §8.4; Bonet &
//! Burton 1998, Dohrmann et al. 2000): a simplex has one constant divergence per cell, so the cell
//! mean changes nothing; the bulk energy is taken instead on the patch of the simplices of one
//! material around each node a,
//!
//! ```text
//!   ½ K Θ_a² / V_a,   Θ_a(u) = Σ_{e∋a} (|e|/(D+1)) div_e u,   V_a = Σ_{e∋a} |e|/(D+1),
//! ```
//!
//! so a node holds one volumetric constraint instead of each of its ~2D cells. The stiffness adds
//! (K/V_a) g_a g_aᵀ with g_a = ∂Θ_a/∂u over the patch's nodes, which couples the nodes of a patch
//! with each other: the matrix's pattern gains each patch as a "cell" (the node's second ring).
//! It stays symmetric positive definite, and a constant strain keeps the continuum's energy
//! (Σ_a V_a = |Ω|). On a body of revolution (docs/method.md §8.6) the same with the weight N_a
//! and the measure 2πr under the integral, and the hoop strain in the divergence:
//! Θ_a = ∫ N_a (div u + u_r/r) 2πr dA, V_a = ∫ N_a 2πr dA (three points per triangle: exact).
//! Written by hand: no crate assembles it.

use crate::linalg::sparse::Pattern;
use crate::material::Isotropic;
use crate::mesh::element::{shape_at, stiffness_rule, ShapeAt};
use crate::mesh::quadrature::TRI_3POINT;
use crate::mesh::Cell;
use rayon::prelude::*;

/// The patches: per (material, node) of the averaged simplices, the cells around the node.
#[derive(Clone, Debug, Default)]
pub struct NodalPatches {
    /// (material, centre node) of each patch.
    centre: Vec<(u32, usize)>,
    /// Patch p's cells are `cells[ptr[p]..ptr[p + 1]]`.
    ptr: Vec<usize>,
    cells: Vec<usize>,
    /// A body of revolution (x = r).
    axisymmetric: bool,
}

/// The points of ∫_cell N_a (…) over a simplex of patch centre `a`: (the weight times N_a, the
/// shapes there). In the plane one point, |e|/(D+1) with the constant gradients; on a body of
/// revolution the triangle's three points with 2πr (the integrands N_a ∂N_b r and N_a N_b are
/// quadratic: exact).
fn weighted_points<const D: usize>(
    cell: &Cell,
    points: &[[f64; D]],
    a: usize,
    axisymmetric: bool,
) -> Vec<(f64, ShapeAt<D>)> {
    if axisymmetric {
        let k = cell
            .nodes()
            .iter()
            .position(|&b| b == a)
            .expect("a patch's cells hold its centre");
        TRI_3POINT
            .iter()
            .map(|q| {
                let s = shape_at(cell, points, q.xi);
                (q.weight * s.det_j * 2.0 * std::f64::consts::PI * s.x[0] * s.value[k], s)
            })
            .collect()
    } else {
        let rule = stiffness_rule(cell);
        let s = shape_at(cell, points, rule[0].xi);
        let measure: f64 = rule.iter().map(|q| q.weight).sum::<f64>() * s.det_j;
        vec![(measure / (D as f64 + 1.0), s)]
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

impl NodalPatches {
    /// The patches of the simplices `averaged` says (by their material, `of_cell`; None: 0), of
    /// a body of revolution (x = r) if `axisymmetric`.
    pub fn new(
        cells: &[Cell],
        of_cell: Option<&[u32]>,
        axisymmetric: bool,
        averaged: impl Fn(u32, &Cell) -> bool,
    ) -> Self {
        let mut pairs: Vec<((u32, usize), usize)> = Vec::new();
        for (c, cell) in cells.iter().enumerate() {
            let m = of_cell.map_or(0, |of| of[c]);
            if averaged(m, cell) {
                pairs.extend(cell.nodes().iter().map(|&a| ((m, a), c)));
            }
        }
        pairs.sort_unstable();
        let mut patches = NodalPatches {
            centre: Vec::new(),
            ptr: vec![0],
            cells: Vec::with_capacity(pairs.len()),
            axisymmetric,
        };
        for (i, &(key, c)) in pairs.iter().enumerate() {
            if i > 0 && pairs[i - 1].0 != key {
                patches.ptr.push(patches.cells.len());
            }
            if i == 0 || pairs[i - 1].0 != key {
                patches.centre.push(key);
            }
            patches.cells.push(c);
        }
        if !pairs.is_empty() {
            patches.ptr.push(patches.cells.len());
        }
        patches
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.centre.is_empty()
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.centre.len()
    }

    fn cells_of(&self, p: usize) -> &[usize] {
        &self.cells[self.ptr[p]..self.ptr[p + 1]]
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

    /// V_a and g_a = ∂Θ_a/∂u over `nodes` (D per node) of patch p.
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
            for (share, s) in weighted_points(cell, points, self.centre[p].1, self.axisymmetric) {
                volume += share;
                for (k, &b) in cell.nodes().iter().enumerate() {
                    let at = nodes.binary_search(&b).expect("a patch holds its cells' nodes");
                    for i in 0..D {
                        g[D * at + i] += share * divergence(&s, k, i, self.axisymmetric);
                    }
                }
            }
        }
        (volume, g)
    }

    /// Adds Σ_p (K_j/V_a) g_a g_aᵀ to each matrix j of `out` (values on `pattern`, which holds
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
                let material = self.centre[p].0 as usize;
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

    /// θ_a = Θ_a(u)/V_a of every patch, for the nodal displacement `u`.
    pub fn dilatation<const D: usize>(&self, cells: &[Cell], points: &[[f64; D]], u: &[[f64; D]]) -> Vec<f64> {
        (0..self.len())
            .into_par_iter()
            .map(|p| {
                let (mut theta, mut volume) = (0.0, 0.0);
                for &c in self.cells_of(p) {
                    let cell = &cells[c];
                    for (share, s) in weighted_points(cell, points, self.centre[p].1, self.axisymmetric) {
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
                        theta += share * div;
                        volume += share;
                    }
                }
                theta / volume
            })
            .collect()
    }

    /// The patch of (material, node), if it is averaged.
    pub fn find(&self, material: u32, node: usize) -> Option<usize> {
        self.centre.binary_search(&(material, node)).ok()
    }

    /// The node lists of the patches, as cells of the matrix's pattern.
    pub fn node_lists(&self, cells: &[Cell]) -> Vec<Vec<usize>> {
        (0..self.len()).map(|p| self.nodes(p, cells)).collect()
    }
}
