//! Global assembly of the stiffness matrices K_A (elasticity A) and K_B (memory tensor B₀)
//! (docs/method.md §3, §8), written once for any dimension D. Local matrices are computed in
//! parallel with rayon, each with its positions in the shared pattern; the scatter is a
//! sequential pass in cell order.

use super::dofs::DofMap;
use super::patch_dilatation::CellPatches;
use crate::linalg::sparse::{Pattern, SymmetricMatrix};
use crate::material::Isotropic;
use crate::mesh::element::{shape_at, stiffness_rule};
use crate::mesh::Cell;
use rayon::prelude::*;
use std::sync::Arc;

/// How a cell's volumetric strain enters the stiffness (docs/method.md §8.4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Volumetric {
    /// tr ε(u) at every quadrature point: the plain displacement element.
    #[default]
    Pointwise,
    /// A mean dilatation, so that a nearly incompressible body does not lock: on quadrilaterals,
    /// hexahedra, prisms and pyramids the bulk part K tr ε(v) tr ε(u) is taken with the cell's
    /// mean θ̄ = (1/|c|) ∫_c div u (B-bar), on triangles and tetrahedra (one divergence per cell
    /// already) with the mean over a patch of neighbouring cells ([`super::patch_dilatation`]).
    Mean,
}

impl Volumetric {
    /// Whether `cell`'s bulk part is not taken pointwise (the cell keeps its deviatoric part).
    pub fn projects(self, _cell: &Cell) -> bool {
        self == Volumetric::Mean
    }

    /// Whether `cell`'s bulk part is the cell's mean dilatation (B-bar).
    pub fn cell_mean(self, cell: &Cell) -> bool {
        self == Volumetric::Mean && !is_linear_simplex(cell)
    }

    /// Whether `cell`'s bulk part is its patch's mean (a simplex).
    pub fn patch_mean(self, cell: &Cell) -> bool {
        self == Volumetric::Mean && is_linear_simplex(cell)
    }
}

/// A 3-node triangle or a 4-node tetrahedron: one divergence per cell, so its mean dilatation is
/// a patch's; a second-order simplex takes its own cell's mean (P2–P0, docs/method.md §19.2).
fn is_linear_simplex(cell: &Cell) -> bool {
    matches!(cell, Cell::Tri3(_) | Cell::Tet4(_))
}

/// Local stiffness ∫_cell ε(v) : C ε(u) dx for each isotropic tensor C = (λ, μ) in `cs`: for
/// dofs (a, i) and (b, j),
///
/// ```text
///   K[(a,i),(b,j)] = ∫ λ ∂ᵢN_a ∂ⱼN_b + μ (δᵢⱼ ∇N_a·∇N_b + ∂ⱼN_a ∂ᵢN_b) dx
/// ```
///
/// (computed together: they share the shape gradients), written row-major into `out[m]`
/// (each nl × nl, nl = D · nodes of the cell, zeroed here). With [`Volumetric::Mean`] on a
/// cell it projects, the bulk part K ∂ᵢN_a ∂ⱼN_b (K = λ + 2μ/3, the 3D bulk modulus: 3D and
/// plane strain) is replaced by K b̄_(a,i) b̄_(b,j) |c| with b̄ the cell's mean of ∂ᵢN_a.
/// `axisymmetric` (2D, x = r): the measure is 2πr dr dz and the strain has the hoop component
/// u_r/r, so the divergence of N_a e_i is ∂ᵢN_a + δᵢ₀ N_a/r and the hoop term adds
/// 2μ δᵢ₀ δⱼ₀ N_a N_b / r² (docs/method.md §8.6).
pub fn local_stiffness<const D: usize>(
    cell: &Cell,
    points: &[[f64; D]],
    cs: &[Isotropic],
    volumetric: Volumetric,
    axisymmetric: bool,
    out: &mut [&mut [f64]],
) {
    let n = cell.nodes().len();
    let nl = D * n;
    for km in out.iter_mut() {
        km[..nl * nl].fill(0.0);
    }
    let project = volumetric.cell_mean(cell);
    // the pointwise bulk part leaves λ as λ − K = −2μ/3 where the bulk part is a mean's
    let deviatoric = volumetric.projects(cell);
    let lambda_of = |c: &Isotropic| if deviatoric { -2.0 * c.mu / 3.0 } else { c.lambda };
    // ∫ ∂ᵢN_a (nl values) and |c|, for the cell's mean dilatation
    let mut mean = [0.0; 3 * 27];
    let mut measure = 0.0;
    // per node pair a ≤ b: Σ_q w ∂ᵢN_a ∂ⱼN_b (row-major 3 × 3); on the stack up to 8 nodes
    let pairs = n * (n + 1) / 2;
    let (mut small, mut large) = ([[0.0; 9]; 36], Vec::new());
    let grams: &mut [[f64; 9]] = if pairs <= small.len() {
        &mut small[..pairs]
    } else {
        large.resize(pairs, [0.0; 9]);
        &mut large
    };
    // a body of revolution's triangle: its hoop terms N_a N_b / r times r are quadratic, which
    // the 3-point rule integrates exactly (the centroid alone lost an order on the thick cylinder)
    let rule = match cell {
        Cell::Tri3(_) if axisymmetric => &crate::mesh::quadrature::TRI_3POINT[..],
        _ => stiffness_rule(cell),
    };
    for q in rule {
        let s = shape_at(cell, points, q.xi);
        let mut w = q.weight * s.det_j;
        // the hoop strain of N_a e_0 is N_a/r (axisymmetric)
        let inv_r = axisymmetric.then(|| 1.0 / s.x[0]);
        let hoop = |a: usize, i: usize| match inv_r {
            Some(inv_r) if i == 0 => s.value[a] * inv_r,
            _ => 0.0,
        };
        if axisymmetric {
            w *= 2.0 * std::f64::consts::PI * s.x[0];
        }
        if project {
            measure += w;
            for a in 0..n {
                for i in 0..D {
                    mean[D * a + i] += w * (s.grad[a][i] + hoop(a, i));
                }
            }
        }
        // the pairs' Σ_q w ∂ᵢN_a ∂ⱼN_b, shared by every tensor
        let mut pair = 0;
        for a in 0..n {
            let wa: [f64; D] = std::array::from_fn(|i| w * s.grad[a][i]);
            for b in a..n {
                let gb = s.grad[b];
                for i in 0..D {
                    for j in 0..D {
                        grams[pair][3 * i + j] += wa[i] * gb[j];
                    }
                }
                pair += 1;
            }
        }
        if axisymmetric {
            // the hoop terms, pointwise (2D only)
            for (c, km) in cs.iter().zip(out.iter_mut()) {
                let lambda = lambda_of(c);
                for a in 0..n {
                    for b in a..n {
                        let (ga, gb) = (s.grad[a], s.grad[b]);
                        for i in 0..D {
                            let row = (D * a + i) * nl + D * b;
                            for j in 0..D {
                                let (ha, hb) = (hoop(a, i), hoop(b, j));
                                km[row + j] +=
                                    w * (lambda * (ga[i] * hb + ha * gb[j] + ha * hb) + 2.0 * c.mu * ha * hb);
                            }
                        }
                    }
                }
            }
        }
    }
    // K[(a,i),(b,j)] = λ G_ij + μ (G_ji + δᵢⱼ tr G), G the pair's gram
    for (c, km) in cs.iter().zip(out.iter_mut()) {
        let lambda = lambda_of(c);
        let mut pair = 0;
        for a in 0..n {
            for b in a..n {
                let g = &grams[pair];
                let trace: f64 = (0..D).map(|r| g[4 * r]).sum();
                for i in 0..D {
                    let row = (D * a + i) * nl + D * b;
                    for j in 0..D {
                        let mut v = lambda * g[3 * i + j] + c.mu * g[3 * j + i];
                        if i == j {
                            v += c.mu * trace;
                        }
                        km[row + j] += v;
                    }
                }
                pair += 1;
            }
        }
    }
    if project {
        // K |c| b̄ b̄ᵀ = K (∫∂N)(∫∂N)ᵀ / |c|, upper node blocks (mirrored below)
        for (c, km) in cs.iter().zip(out.iter_mut()) {
            let bulk = (c.lambda + 2.0 * c.mu / 3.0) / measure;
            for a in 0..n {
                for b in a..n {
                    for i in 0..D {
                        let row = (D * a + i) * nl + D * b;
                        for j in 0..D {
                            km[row + j] += bulk * mean[D * a + i] * mean[D * b + j];
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

/// Assembles the stiffness matrices of the tensors `cs` on a pattern built here, over every
/// unknown of `dofs` (prescribed ones included: docs/method.md §7).
pub fn assemble_stiffness<const D: usize, const M: usize>(
    cells: &[Cell],
    points: &[[f64; D]],
    dofs: &DofMap<D>,
    cs: &[Isotropic; M],
) -> [SymmetricMatrix; M] {
    assemble_stiffness_with(cells, points, dofs, cs, Volumetric::Pointwise)
}

/// [`assemble_stiffness`] with the cells' volumetric strain taken as `volumetric` says.
pub fn assemble_stiffness_with<const D: usize, const M: usize>(
    cells: &[Cell],
    points: &[[f64; D]],
    dofs: &DofMap<D>,
    cs: &[Isotropic; M],
    volumetric: Volumetric,
) -> [SymmetricMatrix; M] {
    let patches = CellPatches::new(cells, None, false, |_, cell| volumetric.patch_mean(cell));
    let one = CellTensors {
        tensors: &[cs.to_vec()],
        volumetric: &[volumetric],
        of_cell: None,
        patches: Some(&patches).filter(|p| !p.is_empty()),
        axisymmetric: false,
    };
    let matrices = assemble_by_cell(cells, points, dofs, &one);
    matrices
        .try_into()
        .unwrap_or_else(|_| unreachable!("one matrix per tensor"))
}

/// What each cell's local stiffness is made of (docs/method.md §8.5): its material's tensor for
/// every matrix assembled and its volumetric rule.
pub struct CellTensors<'a> {
    /// Per material, one tensor per matrix (the same number for every material; a zero tensor
    /// leaves the material's cells out of that matrix).
    pub tensors: &'a [Vec<Isotropic>],
    /// Per material.
    pub volumetric: &'a [Volumetric],
    /// Each cell's material; None: every cell has material 0.
    pub of_cell: Option<&'a [u32]>,
    /// The patches of the simplices whose bulk part is averaged there.
    pub patches: Option<&'a CellPatches>,
    /// A body of revolution (x = r, docs/method.md §8.6).
    pub axisymmetric: bool,
}

/// Assembles one matrix per tensor of [`CellTensors`] on a pattern built here, over every
/// unknown of `dofs` (prescribed ones included: docs/method.md §7). With cell patches the
/// pattern holds each patch as a cell and their bulk parts are added (docs/method.md §8.4).
pub fn assemble_by_cell<const D: usize>(
    cells: &[Cell],
    points: &[[f64; D]],
    dofs: &DofMap<D>,
    materials: &CellTensors,
) -> Vec<SymmetricMatrix> {
    let pattern = Arc::new(match materials.patches {
        None => Pattern::new(cells, dofs.n_nodes(), D),
        Some(patches) => {
            let lists = patches.node_lists(cells);
            let all: Vec<&[usize]> = cells
                .iter()
                .map(|c| c.nodes())
                .chain(lists.iter().map(|l| &l[..]))
                .collect();
            Pattern::new(&all, dofs.n_nodes(), D)
        }
    });
    let mut values = assemble_values(&pattern, cells, points, materials);
    if let Some(patches) = materials.patches {
        patches.add_stiffness(&pattern, cells, points, materials.tensors, &mut values);
    }
    values
        .into_iter()
        .map(|values| SymmetricMatrix {
            pattern: pattern.clone(),
            values,
        })
        .collect()
}

/// The values of the stiffness matrices on `pattern`. Cells are done in chunks, each chunk's
/// local matrices and their positions computed in parallel into two buffers kept across
/// chunks, so that what is held at once stays bounded; the sums then go in cell by cell.
fn assemble_values<const D: usize>(
    pattern: &Pattern,
    cells: &[Cell],
    points: &[[f64; D]],
    materials: &CellTensors,
) -> Vec<Vec<f64>> {
    let m = materials.tensors.first().map_or(0, |t| t.len());
    let mut out: Vec<Vec<f64>> = (0..m).map(|_| vec![0.0; pattern.nnz()]).collect();
    if m == 0 || cells.is_empty() {
        return out;
    }
    let nl_max = D * cells.iter().map(|c| c.nodes().len()).max().unwrap_or(0);
    let stride = nl_max * nl_max;
    const CHUNK: usize = 4096;
    let chunk_len = CHUNK.min(cells.len());
    let mut buffer = vec![0.0; chunk_len * m * stride];
    let mut positions = vec![0usize; chunk_len * stride];
    for (chunk_index, cell_chunk) in cells.chunks(CHUNK).enumerate() {
        let first = chunk_index * CHUNK;
        buffer
            .par_chunks_mut(m * stride)
            .zip(positions.par_chunks_mut(stride))
            .zip(cell_chunk.par_iter().enumerate())
            .for_each(|((local, at), (i, cell))| {
                let material = materials.of_cell.map_or(0, |of| of[first + i] as usize);
                let mut views: Vec<&mut [f64]> = local.chunks_mut(stride).collect();
                local_stiffness(
                    cell,
                    points,
                    &materials.tensors[material],
                    materials.volumetric[material],
                    materials.axisymmetric,
                    &mut views,
                );
                pattern.cell_positions(cell.nodes(), at);
            });
        for ((cell, local), at) in cell_chunk
            .iter()
            .zip(buffer.chunks(m * stride))
            .zip(positions.chunks(stride))
        {
            let nl = D * cell.nodes().len();
            for (j, mat) in out.iter_mut().enumerate() {
                let km = &local[j * stride..j * stride + nl * nl];
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

#[cfg(test)]
mod tests {
    //! Mean dilatation on one distorted cell: a linear field u = G x (constant strain) has the
    //! energy |c| (K θ² + 2μ dev ε : dev ε) of the continuum, whatever K/G, and the rigid motions
    //! cost nothing; a field whose divergence varies over the cell costs only the bulk modulus of
    //! its mean divergence, which is what relieves locking.
    use super::*;

    fn energy<const D: usize>(cell: &Cell, points: &[[f64; D]], c: Isotropic, v: Volumetric, u: &[f64]) -> f64 {
        let nl = D * cell.nodes().len();
        let mut k = vec![0.0; nl * nl];
        local_stiffness(cell, points, &[c], v, false, &mut [&mut k[..]]);
        (0..nl)
            .map(|i| u[i] * (0..nl).map(|j| k[i * nl + j] * u[j]).sum::<f64>())
            .sum()
    }

    fn linear<const D: usize>(points: &[[f64; D]], g: [[f64; 3]; 3]) -> Vec<f64> {
        points
            .iter()
            .flat_map(|x| (0..D).map(move |i| (0..D).map(|j| g[i][j] * x[j]).sum::<f64>()))
            .collect()
    }

    /// |c| (K θ² + 2μ dev ε : dev ε) for ε = sym(G) (D × D; the 3D deviator, ε₃₃ = 0 in 2D).
    fn continuum<const D: usize>(g: [[f64; 3]; 3], c: Isotropic, measure: f64) -> f64 {
        let e = |i: usize, j: usize| if i < D && j < D { 0.5 * (g[i][j] + g[j][i]) } else { 0.0 };
        let theta: f64 = (0..D).map(|i| e(i, i)).sum();
        let dev: f64 = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| (e(i, j) - if i == j { theta / 3.0 } else { 0.0 }).powi(2))
            .sum();
        measure * ((c.lambda + 2.0 * c.mu / 3.0) * theta * theta + 2.0 * c.mu * dev)
    }

    #[test]
    fn mean_dilatation_keeps_constant_strains_and_rigid_motions() {
        let c = Isotropic {
            lambda: 4999.0 * 2.0 / 3.0,
            mu: 1.0,
        }; // ν ≈ 0.4999
        let g = [[0.3, -0.2, 0.1], [0.4, 0.1, -0.3], [0.2, 0.5, -0.1]];
        let quad = [[0.0, 0.0], [1.1, 0.1], [1.3, 0.9], [-0.1, 1.2]];
        let hex = [
            [0.0, 0.0, 0.0],
            [1.0, 0.1, 0.0],
            [1.2, 1.0, 0.1],
            [0.1, 0.9, -0.1],
            [0.1, 0.0, 1.0],
            [0.9, 0.2, 1.1],
            [1.1, 1.1, 0.9],
            [0.0, 1.0, 1.2],
        ];
        let quad_cell = Cell::Quad4([0, 1, 2, 3]);
        let hex_cell = Cell::Hex8([0, 1, 2, 3, 4, 5, 6, 7]);
        let area: f64 = stiffness_rule(&quad_cell)
            .iter()
            .map(|q| q.weight * shape_at(&quad_cell, &quad, q.xi).det_j)
            .sum();
        let volume: f64 = stiffness_rule(&hex_cell)
            .iter()
            .map(|q| q.weight * shape_at(&hex_cell, &hex, q.xi).det_j)
            .sum();
        for v in [Volumetric::Pointwise, Volumetric::Mean] {
            let e2 = energy(&quad_cell, &quad, c, v, &linear(&quad, g));
            let e3 = energy(&hex_cell, &hex, c, v, &linear(&hex, g));
            assert!(
                (e2 / continuum::<2>(g, c, area) - 1.0).abs() < 1e-11,
                "{v:?} quad: {e2}"
            );
            assert!(
                (e3 / continuum::<3>(g, c, volume) - 1.0).abs() < 1e-11,
                "{v:?} hex: {e3}"
            );
            // a rotation costs nothing
            let w = [[0.0, -0.3, 0.2], [0.3, 0.0, -0.1], [-0.2, 0.1, 0.0]];
            assert!(energy(&hex_cell, &hex, c, v, &linear(&hex, w)).abs() < 1e-9);
        }
        // u = (x y, 0) on the unit square: div u = y varies; its mean costs K, the rest only μ
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let u: Vec<f64> = square.iter().flat_map(|x| [x[0] * x[1], 0.0]).collect();
        let plain = energy(&quad_cell, &square, c, Volumetric::Pointwise, &u);
        let mean = energy(&quad_cell, &square, c, Volumetric::Mean, &u);
        let bulk = c.lambda + 2.0 * c.mu / 3.0;
        // ∫ θ² = 1/3 against θ̄² |c| = 1/4 (the μ part adds a few μ)
        assert!(
            plain >= bulk / 3.0,
            "the plain element pays K ∫ θ²: {plain} against K = {bulk}"
        );
        assert!(
            mean < bulk / 4.0 + 5.0 * c.mu,
            "mean dilatation pays K θ̄² |c| only: {mean} against K = {bulk}"
        );
    }

    /// The patch test of the cell patches' bulk part (docs/method.md §8.4): a constant strain
    /// keeps the continuum's energy |Ω| (K θ² + 2μ dev ε : dev ε) on a distorted mesh of
    /// triangles (the patches tile it), and the rigid motions cost nothing.
    #[test]
    fn a_constant_strain_keeps_the_continuum_energy() {
        use crate::mesh::structured::{rectangle, CellShape};
        let mut mesh = rectangle(2.0, 1.0, 6, 4, CellShape::Tri);
        for p in mesh.points.iter_mut() {
            let (x, y) = (p[0], p[1]);
            // interior nodes moved, the boundary kept straight
            if x > 0.0 && x < 2.0 && y > 0.0 && y < 1.0 {
                p[0] += 0.08 * (7.0 * y).sin();
                p[1] += 0.06 * (5.0 * x).cos();
            }
        }
        let dofs = DofMap::<2>::new(mesh.points.len(), &[]);
        let c = Isotropic {
            lambda: 4999.0 * 2.0 / 3.0,
            mu: 1.0,
        };
        let [k] = assemble_stiffness_with(&mesh.cells, &mesh.points, &dofs, &[c], Volumetric::Mean);
        let energy = |g: [[f64; 2]; 2]| {
            let u: Vec<f64> = mesh
                .points
                .iter()
                .flat_map(|x| (0..2).map(move |i| g[i][0] * x[0] + g[i][1] * x[1]))
                .collect();
            let mut ku = vec![0.0; u.len()];
            k.matvec(&u, &mut ku);
            u.iter().zip(&ku).map(|(a, b)| a * b).sum::<f64>()
        };
        let g = [[0.3, -0.2], [0.4, 0.1]];
        let e = |i: usize, j: usize| 0.5 * (g[i][j] + g[j][i]);
        let theta = e(0, 0) + e(1, 1);
        // the 3D deviator of the plane strain (ε₃₃ = 0)
        let dev = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| {
                let eij: f64 = if i < 2 && j < 2 { e(i, j) } else { 0.0 };
                (eij - if i == j { theta / 3.0 } else { 0.0 }).powi(2)
            })
            .sum::<f64>();
        let continuum = 2.0 * ((c.lambda + 2.0 * c.mu / 3.0) * theta * theta + 2.0 * c.mu * dev);
        assert!(
            (energy(g) / continuum - 1.0).abs() < 1e-11,
            "{} against {continuum}",
            energy(g)
        );
        assert!(
            energy([[0.0, -0.3], [0.3, 0.0]]).abs() < 1e-9,
            "a rotation costs nothing"
        );
    }
}
