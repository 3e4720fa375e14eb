//! Cell stresses for output: σ = Aε(u_n) + Σ_j T_j ε(m_n^j) at the cell centroid, where
//! m_n^j = h_n^j + (k/2) b_j(0) u_n is the memory displacement of memory channel j with tensor
//! T_j (docs/method.md §3, §15), and the von Mises equivalent stress, in any dimension. With mean
//! dilatation (docs/method.md §8.4) the bulk part is the cell's: σ = K θ̄ I + 2μ dev ε, i.e. σ(ε)
//! plus K (θ̄ − tr ε) on the diagonal (out of plane too), θ̄ the cell's mean of tr ε.

use super::materials::Materials;
use crate::material::{Isotropic, PlaneModel};
use crate::mesh::element::{reference_centroid, shape_at, stiffness_rule, strain};
use crate::mesh::Cell;
use rayon::prelude::*;

/// A memory channel's tensor T_j and its nodal memory displacement m^j.
pub type MemoryField<const D: usize> = (Isotropic, Vec<[f64; D]>);

/// Per-cell stress tensors (9 components, row-major 3×3, for ParaView) and von Mises values.
pub struct CellStresses {
    pub tensor: Vec<f64>,
    pub von_mises: Vec<f64>,
}

/// The von Mises stress of a symmetric 3×3 tensor.
pub fn von_mises(s: &[[f64; 3]; 3]) -> f64 {
    let d = (s[0][0] - s[1][1]).powi(2) + (s[1][1] - s[2][2]).powi(2) + (s[2][2] - s[0][0]).powi(2);
    let shear = s[0][1].powi(2) + s[1][2].powi(2) + s[0][2].powi(2);
    (0.5 * d + 3.0 * shear).sqrt()
}

/// Evaluates the stress of every cell at its centroid with its material's constants: cell c is
/// the mesh's cell `of_mesh[c]` (None: `cells` are the mesh's cells);
/// `memory` holds each memory channel's tensor T_j and nodal memory displacement m^j, in the
/// order of the materials' channels (None or empty without memory), each acting on its own
/// material's cells. In 2D the out-of-plane stress σ₃₃ of plane strain is included,
/// λ_A tr ε(u) + Σ_j λ_j tr ε(m^j) (zero in plane stress).
pub fn cell_stresses<const D: usize>(
    cells: &[Cell],
    points: &[[f64; D]],
    materials: &Materials,
    of_mesh: Option<&[usize]>,
    u: &[[f64; D]],
    memory: Option<&[MemoryField<D>]>,
) -> CellStresses {
    let memory = memory.unwrap_or_default();
    // the dilatations of the averaged simplices' patches (docs/method.md §8.4): of u and of each
    // memory field (a simplex's bulk part is its patch's)
    let patches = materials.patches();
    let nodal: Vec<Vec<f64>> = if patches.is_empty() {
        Vec::new()
    } else {
        assert!(of_mesh.is_none(), "averaged simplices' stresses need the mesh's cells");
        std::iter::once(u)
            .chain(memory.iter().map(|(_, m)| &m[..]))
            .map(|field| patches.dilatation(cells, points, field))
            .collect()
    };
    let per_cell: Vec<([f64; 9], f64)> = cells
        .par_iter()
        .enumerate()
        .map(|(c, cell)| {
            let c = of_mesh.map_or(c, |of| of[c]);
            let id = materials.id_of_cell(c);
            let material = materials.of_cell(c);
            let elasticity = &material.elasticity;
            let volumetric = material.volumetric;
            let plane_strain = D == 2 && elasticity.plane == Some(PlaneModel::Strain);
            let axisymmetric = D == 2 && elasticity.plane == Some(PlaneModel::Axisymmetric);
            let a = elasticity.tensor();
            let own = memory
                .iter()
                .enumerate()
                .filter(|(j, _)| materials.channel_owner(*j) == id)
                .map(|(j, f)| (j + 1, f));
            let s = shape_at(cell, points, reference_centroid(cell));
            let local = |field: &[[f64; D]]| -> Vec<[f64; D]> { cell.nodes().iter().map(|&p| field[p]).collect() };
            // the hoop strain u_r/r of a body of revolution (zero otherwise)
            let hoop = |field: &[[f64; D]]| -> f64 {
                if !axisymmetric {
                    return 0.0;
                }
                cell.nodes()
                    .iter()
                    .enumerate()
                    .map(|(k, &p)| s.value[k] * field[p][0])
                    .sum::<f64>()
                    / s.x[0]
            };
            let e = strain(&s, &local(u));
            let mut sig = a.apply(&e);
            let trace: f64 = (0..D).map(|i| e[i][i]).sum();
            let mut full = [[0.0; 3]; 3];
            let mut out_of_plane = 0.0;
            // λ ε_θθ on the in-plane diagonal; returns σ_θθ = λ tr ε + 2μ ε_θθ
            let add_hoop = |t: &Isotropic, sig: &mut [[f64; D]; D], trace: f64, eh: f64| -> f64 {
                if !axisymmetric {
                    return 0.0;
                }
                for (i, row) in sig.iter_mut().enumerate() {
                    row[i] += t.lambda * eh;
                }
                t.lambda * (trace + eh) + 2.0 * t.mu * eh
            };
            out_of_plane += add_hoop(&a, &mut sig, trace, hoop(u));
            // mean dilatation: K (θ̄ − tr ε) on the diagonal, for A and each memory tensor; θ̄
            // the cell's mean, or on a simplex its patch's
            let project = volumetric.projects(cell);
            let mut bulk_shift = 0.0;
            let mut shift = |t: &Isotropic, field: usize, e: &[[f64; D]; D]| {
                if !project {
                    return;
                }
                let mean = if let Some(patch) = patches.of_cell(c).filter(|_| volumetric.patch_mean(cell)) {
                    nodal[field][patch.index()]
                } else {
                    let values = if field == 0 { u } else { &memory[field - 1].1[..] };
                    mean_trace(cell, points, &local(values), axisymmetric)
                };
                let values = if field == 0 { u } else { &memory[field - 1].1[..] };
                let trace = (0..D).map(|i| e[i][i]).sum::<f64>() + hoop(values);
                bulk_shift += (t.lambda + 2.0 * t.mu / 3.0) * (mean - trace);
            };
            shift(&a, 0, &e);
            for (field, (t, m)) in own {
                let em = strain(&s, &local(m));
                shift(t, field, &em);
                let mut sm = t.apply(&em);
                out_of_plane += add_hoop(t, &mut sm, (0..D).map(|i| em[i][i]).sum(), hoop(m));
                for i in 0..D {
                    for j in 0..D {
                        sig[i][j] += sm[i][j];
                    }
                }
                if plane_strain && t.lambda != 0.0 {
                    out_of_plane += t.lambda * (0..D).map(|i| em[i][i]).sum::<f64>();
                }
            }
            for (i, row) in sig.iter_mut().enumerate() {
                row[i] += bulk_shift;
            }
            if D == 2 && project {
                out_of_plane += bulk_shift;
            }
            for i in 0..D {
                for j in 0..D {
                    full[i][j] = sig[i][j];
                }
            }
            if D == 2 {
                full[2][2] = elasticity.out_of_plane_stress(trace) + out_of_plane;
            }
            let vm = von_mises(&full);
            let flat: [f64; 9] = std::array::from_fn(|k| full[k / 3][k % 3]);
            (flat, vm)
        })
        .collect();
    CellStresses {
        tensor: per_cell.iter().flat_map(|(t, _)| t.iter().copied()).collect(),
        von_mises: per_cell.iter().map(|(_, v)| *v).collect(),
    }
}

/// The cell's mean of tr ε(u) for its nodal values `u`, over its stiffness rule (of a body of
/// revolution: with the hoop strain u_r/r, over the measure 2πr).
fn mean_trace<const D: usize>(cell: &Cell, points: &[[f64; D]], u: &[[f64; D]], axisymmetric: bool) -> f64 {
    let (mut integral, mut measure) = (0.0, 0.0);
    for q in stiffness_rule(cell) {
        let s = shape_at(cell, points, q.xi);
        let e = strain(&s, u);
        let (w, hoop) = if axisymmetric {
            let ur: f64 = (0..cell.nodes().len()).map(|k| s.value[k] * u[k][0]).sum();
            (q.weight * s.det_j * s.x[0], ur / s.x[0])
        } else {
            (q.weight * s.det_j, 0.0)
        };
        integral += w * ((0..D).map(|i| e[i][i]).sum::<f64>() + hoop);
        measure += w;
    }
    integral / measure
}

/// Nodal (recovered) stresses: at each node the volume-weighted mean of the stress tensors of
/// the cells around it, σ_p = Σ_c |c| σ_c / Σ_c |c| (docs/method.md §12), and the von Mises
/// stress of that mean tensor. `tensor` is [`CellStresses::tensor`]; `measures` the cells'
/// areas or volumes ([`cell_measures`]). A node of no cell gets 0.
pub fn nodal_stresses(cells: &[Cell], measures: &[f64], tensor: &[f64], n_points: usize) -> CellStresses {
    let (sum, weight) = nodal_stress_sums(cells, measures, tensor, n_points);
    nodal_stresses_from_sums(sum, &weight)
}

/// The sums of [`nodal_stresses`] before the division: Σ_c |c| σ_c (9 per node) and Σ_c |c|
/// over the given cells (a mesh partition adds its parts' sums before dividing).
pub fn nodal_stress_sums(cells: &[Cell], measures: &[f64], tensor: &[f64], n_points: usize) -> (Vec<f64>, Vec<f64>) {
    let mut sum = vec![0.0; 9 * n_points];
    let mut weight = vec![0.0; n_points];
    for ((cell, &m), s) in cells.iter().zip(measures).zip(tensor.chunks_exact(9)) {
        for &p in cell.nodes() {
            weight[p] += m;
            for (a, b) in sum[9 * p..9 * p + 9].iter_mut().zip(s) {
                *a += m * b;
            }
        }
    }
    (sum, weight)
}

/// [`nodal_stresses`] from the sums of [`nodal_stress_sums`].
pub fn nodal_stresses_from_sums(mut sum: Vec<f64>, weight: &[f64]) -> CellStresses {
    let n_points = weight.len();
    let mut von = vec![0.0; n_points];
    for (p, (s, w)) in sum.chunks_exact_mut(9).zip(weight).enumerate() {
        if *w > 0.0 {
            s.iter_mut().for_each(|x| *x /= w);
        }
        von[p] = von_mises(&std::array::from_fn(|i| std::array::from_fn(|j| s[3 * i + j])));
    }
    CellStresses {
        tensor: sum,
        von_mises: von,
    }
}

/// The area (2D) or volume (3D) of every cell, by the stiffness quadrature.
pub fn cell_measures<const D: usize>(cells: &[Cell], points: &[[f64; D]]) -> Vec<f64> {
    cells
        .iter()
        .map(|c| {
            crate::mesh::element::stiffness_rule(c)
                .iter()
                .map(|q| q.weight * shape_at(c, points, q.xi).det_j)
                .sum()
        })
        .collect()
}
