//! Global assembly of the stiffness matrices K_A (elasticity A) and K_B (memory tensor B₀)
//! (METHOD.md §3). Local matrices are computed in parallel with rayon; the scatter into the
//! shared pattern is a sequential pass over precomputed positions.

use super::dofs::DofMap;
use super::element::{shape_at, stiffness_rule, MAX_NODES};
use super::pattern::{Pattern, SymmetricMatrix};
use crate::material::VoigtMatrix;
use crate::mesh::Cell;
use rayon::prelude::*;
use std::sync::Arc;

const MAX_LOCAL: usize = 2 * MAX_NODES;

/// A local stiffness matrix, row-major over the cell's 2·n_nodes dofs.
pub type LocalMatrix = [[f64; MAX_LOCAL]; MAX_LOCAL];

/// Local stiffness ∫_cell Bᵀ D B dx for each Voigt matrix in `ds` (computed together: they
/// share the strain-displacement matrices B).
pub fn local_stiffness<const M: usize>(cell: &Cell, points: &[[f64; 2]], ds: &[VoigtMatrix; M]) -> [LocalMatrix; M] {
    let mut k = [[[0.0; MAX_LOCAL]; MAX_LOCAL]; M];
    for q in stiffness_rule(cell) {
        let s = shape_at(cell, points, q.xi);
        let w = q.weight * s.det_j;
        // Columns of B for dof (a, c): the Voigt strain of the unit displacement N_a e_c.
        let mut b = [[0.0; 3]; MAX_LOCAL];
        for a in 0..s.n {
            let [gx, gy] = s.grad[a];
            b[2 * a] = [gx, 0.0, gy];
            b[2 * a + 1] = [0.0, gy, gx];
        }
        let nl = 2 * s.n;
        for (d, km) in ds.iter().zip(k.iter_mut()) {
            for j in 0..nl {
                let db = super::super::material::elasticity::apply(d, &b[j]);
                for i in 0..=j {
                    km[i][j] += w * (b[i][0] * db[0] + b[i][1] * db[1] + b[i][2] * db[2]);
                }
            }
        }
    }
    // Bᵀ D B is symmetric (D is): the lower triangle mirrors the upper one.
    let nl = 2 * cell.nodes().len();
    for km in k.iter_mut() {
        #[allow(clippy::needless_range_loop)] // reads row j while writing column j
        for j in 0..nl {
            for i in j + 1..nl {
                km[i][j] = km[j][i];
            }
        }
    }
    k
}

/// K_A and K_B on one pattern.
pub struct StiffnessPair {
    pub elastic: SymmetricMatrix,
    pub memory: SymmetricMatrix,
}

/// Assembles the stiffness matrices of the Voigt matrices `ds` on a pattern built here.
pub fn assemble_stiffness<const M: usize>(
    cells: &[Cell],
    points: &[[f64; 2]],
    dofs: &DofMap,
    ds: &[VoigtMatrix; M],
) -> [SymmetricMatrix; M] {
    let pattern = Arc::new(Pattern::new(cells, dofs));
    assemble_on(&pattern, cells, points, ds)
}

/// Assembles on an existing pattern (re-assembly reuses the scatter map).
pub fn assemble_on<const M: usize>(
    pattern: &Arc<Pattern>,
    cells: &[Cell],
    points: &[[f64; 2]],
    ds: &[VoigtMatrix; M],
) -> [SymmetricMatrix; M] {
    let locals: Vec<[LocalMatrix; M]> = cells.par_iter().map(|c| local_stiffness(c, points, ds)).collect();
    let mut out: [SymmetricMatrix; M] = std::array::from_fn(|_| SymmetricMatrix::zeros(pattern.clone()));
    for (e, (cell, km)) in cells.iter().zip(&locals).enumerate() {
        let nl = 2 * cell.nodes().len();
        let pos = pattern.cell_scatter(e);
        for (m, mat) in out.iter_mut().enumerate() {
            for i in 0..nl {
                for j in 0..nl {
                    let p = pos[i * nl + j];
                    if p != usize::MAX {
                        mat.values[p] += km[m][i][j];
                    }
                }
            }
        }
    }
    out
}

/// Stiffness matrices on the paper's rectangle (0,2)×(0,1) with Γ₁ clamped, for unit tests
/// of the linear algebra: `nx × ny` cells of `shape`, one matrix per Voigt matrix.
#[cfg(test)]
pub(crate) fn rectangle_stiffness<const M: usize>(
    nx: usize,
    ny: usize,
    shape: crate::mesh::structured::CellShape,
    ds: &[VoigtMatrix; M],
) -> [SymmetricMatrix; M] {
    let mesh = crate::mesh::structured::rectangle(2.0, 1.0, nx, ny, shape);
    let clamped = mesh
        .group_nodes(&crate::mesh::GroupSelector::Name("Gamma1".into()))
        .expect("the rectangle has Gamma1");
    let dofs = DofMap::new(mesh.points.len(), &clamped);
    assemble_stiffness(&mesh.cells, &mesh.points, &dofs, ds)
}

/// max |a − b| / max |b| (for tests comparing two computations of one vector).
#[cfg(test)]
pub(crate) fn relative_difference(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}
