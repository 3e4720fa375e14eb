//! Cell stresses for output: σ = Aε(u_n) + B₀ ε(m_n) at the cell centroid, where
//! m_n = k Σ'_{i≤n} b(t_n − t_i) u_i is the memory displacement (METHOD.md §2), and the
//! von Mises equivalent stress.

use super::element::{reference_centroid, shape_at, strain};
use crate::material::elasticity::apply;
use crate::material::{Elasticity, IDENTITY_TENSOR};
use crate::mesh::Cell;
use rayon::prelude::*;

/// Per-cell stress tensors (9 components, row-major 3×3, for ParaView) and von Mises values.
pub struct CellStresses {
    pub tensor: Vec<f64>,
    pub von_mises: Vec<f64>,
}

/// Evaluates the stress of every cell at its centroid.
pub fn cell_stresses(
    cells: &[Cell],
    points: &[[f64; 2]],
    elasticity: &Elasticity,
    u: &[[f64; 2]],
    memory: Option<&[[f64; 2]]>,
) -> CellStresses {
    let d = elasticity.voigt();
    let per_cell: Vec<([f64; 9], f64)> = cells
        .par_iter()
        .map(|cell| {
            let s = shape_at(cell, points, reference_centroid(cell));
            let local = |field: &[[f64; 2]]| -> Vec<[f64; 2]> { cell.nodes().iter().map(|&p| field[p]).collect() };
            let e = strain(&s, &local(u));
            let mut sig = apply(&d, &e);
            let szz = elasticity.out_of_plane_stress(&e);
            if let Some(m) = memory {
                let em = strain(&s, &local(m));
                let sm = apply(&IDENTITY_TENSOR, &em);
                for k in 0..3 {
                    sig[k] += sm[k];
                }
            }
            let [sxx, syy, sxy] = sig;
            let vm = (0.5 * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2)) + 3.0 * sxy * sxy).sqrt();
            ([sxx, sxy, 0.0, sxy, syy, 0.0, 0.0, 0.0, szz], vm)
        })
        .collect();
    CellStresses {
        tensor: per_cell.iter().flat_map(|(t, _)| t.iter().copied()).collect(),
        von_mises: per_cell.iter().map(|(_, v)| *v).collect(),
    }
}
