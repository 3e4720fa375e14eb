//! Small dense linear algebra for the contact solve (docs/method.md §4, §9.2, §9.7): the Cholesky
//! factor of a symmetric positive definite matrix, in storage kept from one factorisation to the
//! next, and the row-major product by Q. faer does the work; the rest of hvi sees slices.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::{MatMut, MatRef, Par};

/// From this order on a dense factorisation or inverse runs on the run's threads (below it the
/// threads' start-up costs more than they save).
const PARALLEL_FROM: usize = 512;

fn par(n: usize) -> Par {
    if n >= PARALLEL_FROM {
        Par::rayon(0)
    } else {
        Par::Seq
    }
}

/// The dense Cholesky factor L Lᵀ of a symmetric positive definite n × n matrix, L in the lower
/// triangle of a column-major slice that can be handed back ([`FactorBuffer`]) and reused.
#[derive(Debug)]
pub struct DenseCholesky {
    n: usize,
    values: Vec<f64>,
}

impl DenseCholesky {
    /// Factors the matrix with entries `a(i, j)` (its lower triangle is read); None if it is not
    /// (numerically) positive definite.
    pub fn new(n: usize, a: impl Fn(usize, usize) -> f64) -> Option<Self> {
        FactorBuffer::default().factor(n, |column_major| {
            for (j, column) in column_major.chunks_exact_mut(n.max(1)).enumerate() {
                for (i, v) in column.iter_mut().enumerate().skip(j) {
                    *v = a(i, j);
                }
            }
        })
    }

    /// The order n.
    pub fn n(&self) -> usize {
        self.n
    }

    fn l(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.values, self.n, self.n)
    }

    /// A⁻¹ b.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut x = b.to_vec();
        self.solve_in_place(&mut x);
        x
    }

    /// x ← A⁻¹ x.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        self.solve_block(x, 1, Par::Seq);
    }

    /// X ← A⁻¹ X for the n × k column-major X: k right-hand sides at once, so each sweep reads
    /// L once for all of them (blocked, on the run's threads from order 512).
    pub fn solve_columns_in_place(&self, x: &mut [f64], k: usize) {
        self.solve_block(x, k, par(self.n));
    }

    fn solve_block(&self, x: &mut [f64], k: usize, par: Par) {
        use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
        let mut rhs = MatMut::from_column_major_slice_mut(x, self.n, k);
        solve_lower_triangular_in_place(self.l(), rhs.as_mut(), par);
        solve_upper_triangular_in_place(self.l().transpose(), rhs, par);
    }

    /// The factor rounded to single precision, for a preconditioner ([`SingleCholesky`]).
    pub fn single(&self) -> SingleCholesky {
        SingleCholesky {
            n: self.n,
            values: self.values.iter().map(|&v| v as f32).collect(),
        }
    }

    /// A⁻¹, row-major: L⁻ᵀ L⁻¹ by faer's triangular inverse and product, its lower triangle
    /// mirrored (exactly symmetric).
    pub fn symmetric_inverse(&self) -> Vec<f64> {
        use faer::linalg::cholesky::llt::inverse::{inverse, inverse_scratch};
        let n = self.n;
        let mut inv = vec![0.0; n * n];
        let mut scratch = MemBuffer::new(inverse_scratch::<f64>(n, par(n)));
        inverse(
            MatMut::from_column_major_slice_mut(&mut inv, n, n),
            self.l(),
            par(n),
            MemStack::new(&mut scratch),
        );
        // column-major lower triangle = row-major upper triangle: mirror it down
        for p in 0..n {
            for q in 0..p {
                inv[p * n + q] = inv[q * n + p];
            }
        }
        inv
    }
}

/// A [`DenseCholesky`] factor rounded to single precision: its sweeps read half the bytes of
/// the double one, which bounds their time (a one-column sweep reads the whole triangle for two
/// flops per entry). For a preconditioner only — a solve is as accurate as the factor's
/// condition allows at 6·10⁻⁸ rounding, so an iteration (CG, §9.2) it preconditions gains that
/// per step and takes its residuals and products in double precision (docs/method.md §9.2).
#[derive(Debug)]
pub struct SingleCholesky {
    n: usize,
    values: Vec<f32>,
}

impl SingleCholesky {
    /// X ← A⁻¹ X for the n × k column-major X (in double precision; the sweeps in single),
    /// blocked and on the run's threads from order 512 as [`DenseCholesky::solve_columns_in_place`].
    pub fn solve_columns_in_place(&self, x: &mut [f64], k: usize) {
        use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
        let mut single: Vec<f32> = x.iter().map(|&v| v as f32).collect();
        let l = MatRef::from_column_major_slice(&self.values, self.n, self.n);
        let mut rhs = MatMut::from_column_major_slice_mut(&mut single, self.n, k);
        solve_lower_triangular_in_place(l, rhs.as_mut(), par(self.n));
        solve_upper_triangular_in_place(l.transpose(), rhs, par(self.n));
        x.iter_mut().zip(&single).for_each(|(a, &b)| *a = f64::from(b));
    }

    /// Appends to `out` the columns A⁻¹ e_k for the unit vectors of `rows`, n × |rows|
    /// column-major (in double precision; the sweeps in single), in place of a copy. L y = e_k
    /// is zero above k, so the forward sweep of a block of columns starts at its first row: the
    /// columns are taken in the order of their rows, in blocks of [`UNIT_BLOCK`] (a kept
    /// factor's new columns Z = A₀⁻¹ U, docs/method.md §9.2, mostly on the tangential rows, the
    /// last two thirds).
    pub fn solve_unit_columns(&self, rows: &[usize], out: &mut Vec<f64>) {
        use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
        let (n, c) = (self.n, rows.len());
        let mut order: Vec<usize> = (0..c).collect();
        order.sort_by_key(|&a| rows[a]);
        let mut single = vec![0.0f32; n * c];
        for (b, &a) in order.iter().enumerate() {
            single[b * n + rows[a]] = 1.0;
        }
        let l = MatRef::from_column_major_slice(&self.values, n, n);
        for (block, columns) in order.chunks(UNIT_BLOCK).enumerate() {
            let (first, width) = (rows[columns[0]], columns.len());
            let rhs = MatMut::from_column_major_slice_mut(&mut single, n, c);
            let rhs = rhs.submatrix_mut(first, block * UNIT_BLOCK, n - first, width);
            solve_lower_triangular_in_place(l.submatrix(first, first, n - first, n - first), rhs, par(n));
        }
        let rhs = MatMut::from_column_major_slice_mut(&mut single, n, c);
        solve_upper_triangular_in_place(l.transpose(), rhs, par(n));
        let start = out.len();
        out.resize(start + n * c, 0.0);
        let x = &mut out[start..];
        for (b, &a) in order.iter().enumerate() {
            let column = &single[b * n..(b + 1) * n];
            x[a * n..(a + 1) * n]
                .iter_mut()
                .zip(column)
                .for_each(|(x, &v)| *x = f64::from(v));
        }
    }
}

/// Columns per block of [`SingleCholesky::solve_unit_columns`]' forward sweeps (narrower blocks
/// read the triangle more often than they save: 187 columns on rows 800–2 480 of n = 2 480,
/// 21–26 ms in blocks of 32, 18 ms in blocks of 128 or one, 24–25 ms by the full solve).
const UNIT_BLOCK: usize = 128;

/// An n × n matrix (row-major) rounded to single precision, for the products of an iteration that
/// a preconditioner leads (CG on the kept factor, docs/method.md §9.2): half the bytes of the
/// double matrix, which bound a product's time; the sums are formed in double precision, so a
/// product's error is the entries' rounding, 6·10⁻⁸ Σ_j |a_ij x_j| per row.
#[derive(Debug)]
pub struct SingleMatrix {
    n: usize,
    values: Vec<f32>,
}

impl SingleMatrix {
    /// The matrix with entries `a(i, j)`, rounded.
    pub fn new(n: usize, a: impl Fn(usize, usize) -> f64) -> Self {
        let values = (0..n * n).map(|k| a(k / n, k % n) as f32).collect();
        SingleMatrix { n, values }
    }

    /// The matrix with rows `row(i)` (each of length n), rounded: a conversion of contiguous
    /// rows, without a call per entry.
    pub fn from_rows<'a>(n: usize, row: impl Fn(usize) -> &'a [f64]) -> Self {
        let mut values = Vec::with_capacity(n * n);
        for i in 0..n {
            values.extend(row(i)[..n].iter().map(|&v| v as f32));
        }
        SingleMatrix { n, values }
    }

    /// y = A x (rows on the run's threads from order 512).
    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        let n = self.n;
        let rows = |first: usize, part: &mut [f64]| {
            for (k, yi) in part.iter_mut().enumerate() {
                let row = &self.values[(first + k) * n..(first + k + 1) * n];
                *yi = dot_single(row, x);
            }
        };
        if n >= PARALLEL_FROM {
            y.par_chunks_mut(64)
                .enumerate()
                .for_each(|(c, part)| rows(64 * c, part));
        } else {
            rows(0, y);
        }
    }
}

/// Σ_j a_j x_j for single-precision a, in double precision: eight running sums, so the compiler
/// can keep them in vector registers (widened with AVX2 where the processor has it).
fn dot_single(a: &[f32], x: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 was detected
        return unsafe { dot_single_avx2(a, x) };
    }
    dot_single_generic(a, x)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn dot_single_avx2(a: &[f32], x: &[f64]) -> f64 {
    dot_single_generic(a, x)
}

#[inline(always)]
fn dot_single_generic(a: &[f32], x: &[f64]) -> f64 {
    let mut sums = [0.0f64; 8];
    let (a8, x8) = (a.chunks_exact(8), x[..a.len()].chunks_exact(8));
    let (a_rest, x_rest) = (a8.remainder(), x8.remainder());
    for (a, x) in a8.zip(x8) {
        for k in 0..8 {
            sums[k] += f64::from(a[k]) * x[k];
        }
    }
    let tail: f64 = a_rest.iter().zip(x_rest).map(|(a, x)| f64::from(*a) * x).sum();
    sums.iter().sum::<f64>() + tail
}

/// The LU factors (partial pivoting) of a small general k × k matrix (the capacitance matrix of
/// a low-rank update, docs/method.md §9.2).
pub struct DenseLu(faer::linalg::solvers::PartialPivLu<f64>);

impl DenseLu {
    /// Factors the matrix with entries `a(i, j)`.
    pub fn new(k: usize, a: impl Fn(usize, usize) -> f64) -> Self {
        DenseLu(faer::Mat::from_fn(k, k, a).partial_piv_lu())
    }

    /// Factors the k × k matrix whose column j is `column(j)` written into a slice of k zeros
    /// (built a column at a time into faer's storage, without a call per entry).
    pub fn from_columns(k: usize, mut column: impl FnMut(usize, &mut [f64])) -> Self {
        let mut a = faer::Mat::<f64>::zeros(k, k);
        for j in 0..k {
            column(
                j,
                a.col_mut(j)
                    .try_as_col_major_mut()
                    .expect("a Mat's columns are contiguous")
                    .as_slice_mut(),
            );
        }
        DenseLu(a.partial_piv_lu())
    }

    /// x ← A⁻¹ x.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        self.solve_columns_in_place(x, 1);
    }

    /// X ← A⁻¹ X for the k × c column-major X (c right-hand sides at once).
    pub fn solve_columns_in_place(&self, x: &mut [f64], c: usize) {
        use faer::linalg::solvers::Solve;
        let k = x.len() / c.max(1);
        self.0.solve_in_place(MatMut::from_column_major_slice_mut(x, k, c));
    }
}

/// Aᵀ X (k × c, column-major) for the column-major n × k A and n × c X (faer's product, on the
/// run's threads from order 512).
pub fn transpose_product(a: &[f64], x: &[f64], (n, k, c): (usize, usize, usize)) -> Vec<f64> {
    let mut out = vec![0.0; k * c];
    faer::linalg::matmul::matmul(
        MatMut::from_column_major_slice_mut(&mut out, k, c),
        faer::Accum::Replace,
        MatRef::from_column_major_slice(a, n, k).transpose(),
        MatRef::from_column_major_slice(x, n, c),
        1.0,
        par(n),
    );
    out
}

/// Y ← Y − Z T for the column-major n × k Y, n × u Z and u × k T (faer's product, on the run's
/// threads from order 512).
pub fn subtract_product(y: &mut [f64], z: &[f64], t: &[f64], (n, u, k): (usize, usize, usize)) {
    faer::linalg::matmul::matmul(
        MatMut::from_column_major_slice_mut(y, n, k),
        faer::Accum::Add,
        MatRef::from_column_major_slice(z, n, u),
        MatRef::from_column_major_slice(t, u, k),
        -1.0,
        par(n),
    );
}

/// Storage for dense Cholesky factors, kept from one factorisation to the next: the contact
/// solve factors a new matrix of about the same order at every Newton iteration, and a fresh
/// allocation each time (n² numbers, tens to hundreds of MB) costs page faults on this kind of
/// machine worth a third of the 3D friction solve's time and, at 4 096 free nodes, half of a
/// factorisation's (docs/method.md §4.6, §9.7). A cache: a clone starts empty.
#[derive(Debug, Default)]
pub struct FactorBuffer {
    values: Vec<f64>,
}

impl Clone for FactorBuffer {
    fn clone(&self) -> Self {
        FactorBuffer::default()
    }
}

impl FactorBuffer {
    /// Factors, in the kept storage (taken out of the buffer), the symmetric n × n matrix whose
    /// lower triangle `fill` writes into a zeroed column-major slice (column j at j n..(j + 1) n);
    /// None if it is not (numerically) positive definite, the storage then kept.
    pub fn factor(&mut self, n: usize, fill: impl FnOnce(&mut [f64])) -> Option<DenseCholesky> {
        use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
        let mut values = std::mem::take(&mut self.values);
        values.clear();
        values.resize(n * n, 0.0);
        fill(&mut values);
        let mut scratch = MemBuffer::new(cholesky_in_place_scratch::<f64>(n, par(n), Default::default()));
        let factored = cholesky_in_place(
            MatMut::from_column_major_slice_mut(&mut values, n, n),
            Default::default(),
            par(n),
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .is_ok();
        match factored {
            true => Some(DenseCholesky { n, values }),
            false => {
                self.values = values;
                None
            }
        }
    }

    /// Gives a factor's storage back for the next [`Self::factor`] (the larger of the two kept).
    pub fn recycle(&mut self, factor: DenseCholesky) {
        if factor.values.capacity() > self.values.capacity() {
            self.values = factor.values;
        }
    }
}

/// A ← ½(A + Aᵀ) for a row-major n × n matrix: exact symmetry against the round-off of a
/// product that should be symmetric (W = GᵀG, C Z, Q after an update).
pub fn symmetrise_row_major(a: &mut [f64], n: usize) {
    for p in 0..n {
        for q in 0..p {
            let v = 0.5 * (a[p * n + q] + a[q * n + p]);
            a[p * n + q] = v;
            a[q * n + p] = v;
        }
    }
}

/// y = A x for a row-major n × n matrix `a`: faer's SIMD product, on two threads from n = 512
/// (the contact solve's products by Q were its largest cost at m in the thousands).
pub fn matvec_row_major(a: &[f64], n: usize, x: &[f64], y: &mut [f64]) {
    let a = faer::MatRef::from_row_major_slice(a, n, n);
    let par = if n >= 512 { faer::Par::rayon(0) } else { faer::Par::Seq };
    faer::linalg::matmul::matmul(
        faer::ColMut::from_slice_mut(y),
        faer::Accum::Replace,
        a,
        faer::ColRef::from_slice(x),
        1.0,
        par,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric positive definite test matrix: a smooth kernel plus a diagonal shift.
    fn entry(i: usize, j: usize) -> f64 {
        (-(i as f64 - j as f64).abs() / 7.0).exp() + if i == j { 0.5 } else { 0.0 }
    }

    fn residual(n: usize, x: &[f64], b: &[f64]) -> f64 {
        (0..n)
            .map(|i| ((0..n).map(|j| entry(i, j) * x[j]).sum::<f64>() - b[i]).abs())
            .fold(0.0, f64::max)
    }

    /// Storage handed back and reused (holding a larger factor's numbers, and kept through a
    /// matrix that is not positive definite) factors as fresh storage does: the fill adds into
    /// zeros, and the solve meets A x = b to round-off.
    #[test]
    fn a_factor_in_kept_storage_is_a_fresh_one() {
        let fill = |n: usize| {
            move |matrix: &mut [f64]| {
                for (j, column) in matrix.chunks_exact_mut(n).enumerate() {
                    for (i, v) in column.iter_mut().enumerate().skip(j) {
                        *v += entry(i, j);
                    }
                }
            }
        };
        let mut buffer = FactorBuffer::default();
        let large = buffer.factor(60, fill(60)).unwrap();
        buffer.recycle(large);
        assert!(buffer.factor(3, |m| m[0] = -1.0).is_none());
        assert!(
            buffer.values.capacity() >= 3600,
            "the storage was kept through the failure"
        );
        let n = 45;
        let kept = buffer.factor(n, fill(n)).unwrap();
        let fresh = DenseCholesky::new(n, entry).unwrap();
        for (a, b) in kept.values.iter().zip(&fresh.values) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        assert!(residual(n, &kept.solve(&b), &b) < 1e-13);
    }

    /// The inverse, on one thread and (from 512 on) on the run's threads: A A⁻¹ = I to
    /// round-off, and exactly symmetric.
    #[test]
    fn the_symmetric_inverse_inverts() {
        for n in [50, 600] {
            let inverse = DenseCholesky::new(n, entry).unwrap().symmetric_inverse();
            for p in (0..n).step_by(37) {
                let row = &inverse[p * n..(p + 1) * n];
                let e: Vec<f64> = (0..n).map(|i| if i == p { 1.0 } else { 0.0 }).collect();
                assert!(residual(n, row, &e) < 1e-12, "n = {n}, row {p}");
                for (q, v) in row.iter().enumerate() {
                    assert_eq!(v.to_bits(), inverse[q * n + p].to_bits());
                }
            }
        }
    }

    /// The single-precision factor solves as a preconditioner must: on one column and on three
    /// (blocked, from 512 on the run's threads) its solution is the double one to the rounding
    /// of single precision times the matrix's condition (κ ≈ 30 here: 10⁻⁵), and not to double
    /// precision (it is the single-precision factor that solves).
    #[test]
    fn the_single_precision_factor_solves_to_its_rounding() {
        for n in [40, 600] {
            let double = DenseCholesky::new(n, entry).unwrap();
            let single = double.single();
            let b: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.37).sin()).collect();
            for k in [1, 3] {
                let mut x = b[..n * k].to_vec();
                single.solve_columns_in_place(&mut x, k);
                let mut exact = b[..n * k].to_vec();
                double.solve_columns_in_place(&mut exact, k);
                let size = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let error = x.iter().zip(&exact).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                assert!(error < 1e-5 * size, "n = {n}, k = {k}: {error:e} of {size:e}");
                assert!(error > 1e-12 * size, "n = {n}, k = {k}: solved in double precision");
            }
        }
    }

    /// The unit columns' solve (forward sweeps started at each block's first row, columns in
    /// any order, repeated rows, more columns than a block) gives A⁻¹ e_k as the full solve of
    /// the unit vectors does, to single precision's rounding, each column in its place.
    #[test]
    fn the_unit_columns_are_the_inverse_columns() {
        let n = 300;
        let double = DenseCholesky::new(n, entry).unwrap();
        let single = double.single();
        let rows: Vec<usize> = (0..200).map(|a| (a * 137 + 11) % n).chain([5, 299, 0, 5]).collect();
        let mut out = vec![7.0; 3];
        single.solve_unit_columns(&rows, &mut out);
        assert_eq!(out[..3], [7.0; 3], "appended after what was there");
        let x = &out[3..];
        let c = rows.len();
        let mut exact = vec![0.0; n * c];
        for (a, &k) in rows.iter().enumerate() {
            exact[a * n + k] = 1.0;
        }
        double.solve_columns_in_place(&mut exact, c);
        let size = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let error = x.iter().zip(&exact).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(error < 1e-5 * size, "{error:e} of {size:e}");
    }

    /// The single-precision product is the double one to the entries' rounding: within
    /// 6·10⁻⁸ Σ_j |a_ij x_j| per row (the sums in double precision), on one thread and on the
    /// run's threads, with a length that is not a multiple of the eight running sums.
    #[test]
    fn the_single_precision_product_is_the_double_one_to_the_rounding_of_its_entries() {
        for n in [45, 601] {
            let a = SingleMatrix::new(n, entry);
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.61).sin()).collect();
            let mut y = vec![0.0; n];
            a.apply(&x, &mut y);
            for (i, yi) in y.iter().enumerate() {
                let exact: f64 = (0..n).map(|j| entry(i, j) * x[j]).sum();
                let bound: f64 = (0..n).map(|j| (entry(i, j) * x[j]).abs()).sum();
                assert!((yi - exact).abs() <= 6e-8 * bound, "n = {n}, row {i}");
            }
        }
    }
}
