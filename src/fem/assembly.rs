//! Global assembly of the stiffness matrices K_A (elasticity A) and K_B (memory tensor B₀)
//! (docs/method.md §3, §8), written once for any dimension D. Local matrices are computed in
//! parallel with rayon, each with its positions in the shared pattern; the scatter is a
//! sequential pass in cell order.

use super::dofs::DofMap;
use crate::linalg::sparse::{Pattern, SymmetricMatrix};
use crate::material::Isotropic;
use crate::mesh::element::{shape_at, stiffness_rule};
use crate::mesh::Cell;
use rayon::prelude::*;
use std::sync::Arc;

/// Local stiffness ∫_cell ε(v) : C ε(u) dx for each isotropic tensor C = (λ, μ) in `cs`: for
/// dofs (a, i) and (b, j),
///
/// ```text
///   K[(a,i),(b,j)] = ∫ λ ∂ᵢN_a ∂ⱼN_b + μ (δᵢⱼ ∇N_a·∇N_b + ∂ⱼN_a ∂ᵢN_b) dx
/// ```
///
/// (computed together: they share the shape gradients), written row-major into `out[m]`
/// (each nl × nl, nl = D · nodes of the cell, zeroed here).
pub fn local_stiffness<const D: usize, const M: usize>(
    cell: &Cell,
    points: &[[f64; D]],
    cs: &[Isotropic; M],
    out: &mut [&mut [f64]; M],
) {
    let n = cell.nodes().len();
    let nl = D * n;
    for km in out.iter_mut() {
        km[..nl * nl].fill(0.0);
    }
    for q in stiffness_rule(cell) {
        let s = shape_at(cell, points, q.xi);
        let w = q.weight * s.det_j;
        for a in 0..n {
            let ga = s.grad[a];
            for b in a..n {
                let gb = s.grad[b];
                let dot: f64 = (0..D).map(|r| ga[r] * gb[r]).sum();
                for (c, km) in cs.iter().zip(out.iter_mut()) {
                    for i in 0..D {
                        let row = (D * a + i) * nl + D * b;
                        for j in 0..D {
                            let mut v = c.lambda * ga[i] * gb[j] + c.mu * ga[j] * gb[i];
                            if i == j {
                                v += c.mu * dot;
                            }
                            km[row + j] += w * v;
                        }
                    }
                }
            }
        }
    }
    // Symmetric: the node blocks below the diagonal mirror those above it.
    for km in out.iter_mut() {
        for i in 0..nl {
            for j in 0..(i / D) * D {
                km[i * nl + j] = km[j * nl + i];
            }
        }
    }
}

/// K_A and K_B on one pattern.
pub struct StiffnessPair {
    pub elastic: SymmetricMatrix,
    pub memory: SymmetricMatrix,
}

/// Assembles the stiffness matrices of the tensors `cs` on a pattern built here, over every
/// unknown of `dofs` (prescribed ones included: docs/method.md §7).
pub fn assemble_stiffness<const D: usize, const M: usize>(
    cells: &[Cell],
    points: &[[f64; D]],
    dofs: &DofMap<D>,
    cs: &[Isotropic; M],
) -> [SymmetricMatrix; M] {
    let pattern = Arc::new(Pattern::new(cells, dofs.n_nodes(), D));
    assemble_values(&pattern, cells, points, cs).map(|values| SymmetricMatrix {
        pattern: pattern.clone(),
        values,
    })
}

/// The values of the stiffness matrices on `pattern`. Cells are done in chunks, each chunk's
/// local matrices and their positions computed in parallel into two buffers kept across
/// chunks, so that what is held at once stays bounded; the sums then go in cell by cell.
fn assemble_values<const D: usize, const M: usize>(
    pattern: &Pattern,
    cells: &[Cell],
    points: &[[f64; D]],
    cs: &[Isotropic; M],
) -> [Vec<f64>; M] {
    let mut out: [Vec<f64>; M] = std::array::from_fn(|_| vec![0.0; pattern.nnz()]);
    let nl_max = D * cells.iter().map(|c| c.nodes().len()).max().unwrap_or(0);
    let stride = nl_max * nl_max;
    const CHUNK: usize = 4096;
    let chunk_len = CHUNK.min(cells.len());
    let mut buffer = vec![0.0; chunk_len * M * stride];
    let mut positions = vec![0usize; chunk_len * stride];
    for cell_chunk in cells.chunks(CHUNK) {
        buffer
            .par_chunks_mut(M * stride)
            .zip(positions.par_chunks_mut(stride))
            .zip(cell_chunk.par_iter())
            .for_each(|((local, at), cell)| {
                let mut parts = local.chunks_mut(stride);
                let mut views: [&mut [f64]; M] = std::array::from_fn(|_| parts.next().expect("M parts"));
                local_stiffness(cell, points, cs, &mut views);
                pattern.cell_positions(cell.nodes(), at);
            });
        for ((cell, local), at) in cell_chunk
            .iter()
            .zip(buffer.chunks(M * stride))
            .zip(positions.chunks(stride))
        {
            let nl = D * cell.nodes().len();
            for (m, mat) in out.iter_mut().enumerate() {
                let km = &local[m * stride..m * stride + nl * nl];
                for (p, v) in at[..nl * nl].iter().zip(km) {
                    mat[*p] += v;
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
    cs: &[Isotropic; M],
) -> [SymmetricMatrix; M] {
    let mesh = crate::mesh::structured::rectangle(2.0, 1.0, nx, ny, shape);
    let clamped = mesh
        .group_nodes(&crate::mesh::GroupSelector::Name("Gamma1".into()))
        .expect("the rectangle has Gamma1");
    let dofs = DofMap::<2>::new(mesh.points.len(), &clamped);
    let mats = assemble_stiffness(&mesh.cells, &mesh.points, &dofs, cs);
    mats.map(|m| m.with_identity_rows(&dofs))
}
