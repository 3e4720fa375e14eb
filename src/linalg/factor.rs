//! The cached sparse Cholesky factor K = Pᵀ L Lᵀ P of a symmetric positive definite matrix
//! (METHOD.md §3): symbolic analysis with AMD ordering once, numeric factorisation once per
//! distinct matrix, and counted solves against it, whole or as separate forward and backward
//! sweeps.
//!
//! faer's high-level `Llt` solves only whole systems; the split sweeps and the sparse
//! forward sweep of [`super::ForwardColumns`] need the supernodal factor itself, so this
//! module drives faer's mid-level API (`factorize_symbolic_cholesky`,
//! `factorize_numeric_llt`, `SupernodalLltRef::{l_solve, l_transpose_solve}`), forcing the
//! supernodal structure so that one code path serves every size.

use crate::fem::SymmetricMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::{Par, Side};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// Why a factorisation failed.
#[derive(Debug, thiserror::Error)]
pub enum FactorError {
    #[error("the stiffness matrix is not positive definite (pivot failed in the Cholesky factorisation); usually the body is not held: check that the clamped group has nodes and that they stop rigid motions")]
    NotPositiveDefinite,
    #[error("sparse Cholesky failed: {0}")]
    Other(String),
}

/// How many numeric factorisations and solves a run performed (exposed in `summary.json`
/// and used by tests to check that effects a scene does not name cost nothing).
#[derive(Debug, Default)]
pub struct Counters {
    pub factorisations: AtomicUsize,
    /// Whole solves: one forward and one backward sweep over the factor.
    pub solves: AtomicUsize,
    /// Sparse forward sweeps (one per column of a [`super::ForwardColumns`]).
    pub sparse_forward_sweeps: AtomicUsize,
}

impl Counters {
    pub fn factorisations(&self) -> usize {
        self.factorisations.load(Ordering::Relaxed)
    }
    pub fn solves(&self) -> usize {
        self.solves.load(Ordering::Relaxed)
    }
    pub fn sparse_forward_sweeps(&self) -> usize {
        self.sparse_forward_sweeps.load(Ordering::Relaxed)
    }
}

/// Parallelism for factorisation and solves. On 2 cores `Seq` measured faster (STACK.md).
pub fn set_parallelism(threads: usize) {
    faer::set_global_parallelism(if threads <= 1 { Par::Seq } else { Par::rayon(threads) });
}

/// The symbolic analysis of a sparsity pattern: the fill-reducing permutation P and the
/// supernodal structure of L, plus the supernodal elimination tree used by sparse sweeps.
#[derive(Clone)]
pub struct Analysis {
    inner: Arc<SymbolicCholesky<usize>>,
    supernodes: Arc<Supernodes>,
}

/// The supernodal structure of L as the sweeps use it: per supernode its columns
/// `start..start + width`, its off-diagonal row pattern, where its dense column-major block
/// ((width + pattern) × width) sits in the factor's values, and its parent in the supernodal
/// elimination tree (`usize::MAX` at a root); per column of L its supernode.
pub(super) struct Supernodes {
    pub start: Vec<usize>,
    pub width: Vec<usize>,
    pub pattern_start: Vec<usize>,
    pub pattern_len: Vec<usize>,
    pub value_start: Vec<usize>,
    pub row_idx: Vec<usize>,
    pub parent: Vec<usize>,
    pub supernode_of: Vec<usize>,
    /// The tallest block (width + pattern), the size of a sweep's local vector.
    pub max_rows: usize,
}

impl Supernodes {
    pub fn len(&self) -> usize {
        self.start.len()
    }

    pub fn pattern(&self, s: usize) -> &[usize] {
        &self.row_idx[self.pattern_start[s]..self.pattern_start[s] + self.pattern_len[s]]
    }
}

impl Analysis {
    /// (number of supernodes, widths histogram by powers of two, entries in each class).
    pub fn supernode_statistics(&self) -> (usize, Vec<(usize, usize, usize)>) {
        let sn = &self.supernodes;
        let mut classes: Vec<(usize, usize, usize)> = Vec::new();
        for s in 0..sn.len() {
            let c = sn.width[s].next_power_of_two();
            let entries = sn.width[s] * (sn.width[s] + sn.pattern_len[s]);
            match classes.iter_mut().find(|e| e.0 == c) {
                Some(e) => {
                    e.1 += 1;
                    e.2 += entries;
                }
                None => classes.push((c, 1, entries)),
            }
        }
        classes.sort();
        (sn.len(), classes)
    }

    /// Number of stored entries of L.
    pub fn factor_nonzeros(&self) -> usize {
        self.inner.len_val()
    }
}

/// A right-hand side after the forward sweep, y = L⁻¹ P r: what the backward sweep takes and
/// what [`super::ForwardColumns`] acts on. Its entries are in the factor's (permuted) order.
pub struct Forward {
    pub(super) values: Vec<f64>,
}

impl Forward {
    /// The entries, in the factor's order.
    pub fn as_slice(&self) -> &[f64] {
        &self.values
    }
}

/// A cached Cholesky factor K = Pᵀ L Lᵀ P.
pub struct Factor {
    analysis: Analysis,
    values: Vec<f64>,
    n: usize,
}

impl Factor {
    /// Symbolic analysis of the pattern of `matrix` (reusable for every matrix on it).
    pub fn analyse(matrix: &SymmetricMatrix) -> Result<Analysis, FactorError> {
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let inner = factorize_symbolic_cholesky(matrix.pattern.symbolic(), Side::Lower, SymmetricOrdering::Amd, params)
            .map_err(|e| FactorError::Other(format!("{e:?}")))?;
        let supernodes = match inner.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => supernode_table(s),
            SymbolicCholeskyRaw::Simplicial(_) => {
                return Err(FactorError::Other("faer chose a simplicial factor".into()));
            }
        };
        Ok(Analysis {
            inner: Arc::new(inner),
            supernodes: Arc::new(supernodes),
        })
    }

    /// Numeric factorisation of `matrix` with a symbolic analysis of its pattern.
    pub fn new(analysis: &Analysis, matrix: &SymmetricMatrix, counters: &Counters) -> Result<Self, FactorError> {
        counters.factorisations.fetch_add(1, Ordering::Relaxed);
        let symbolic = &analysis.inner;
        let mut values = Vec::new();
        values
            .try_reserve_exact(symbolic.len_val())
            .map_err(|_| FactorError::Other(format!("out of memory for {} factor entries", symbolic.len_val())))?;
        values.resize(symbolic.len_val(), 0.0);
        let par = faer::get_global_parallelism();
        let mut buffer = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
            .map_err(|e| FactorError::Other(format!("workspace: {e:?}")))?;
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut values,
                matrix.as_faer(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .map_err(|_: LltError| FactorError::NotPositiveDefinite)?;
        Ok(Factor {
            analysis: analysis.clone(),
            values,
            n: matrix.n(),
        })
    }

    /// Order of the factored matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    pub(super) fn analysis(&self) -> &Analysis {
        &self.analysis
    }

    /// P: entry i of a permuted vector is entry `permutation().0[i]` of the original, and
    /// original entry j sits at `permutation().1[j]`.
    fn permutation(&self) -> (&[usize], &[usize]) {
        self.analysis
            .inner
            .perm()
            .expect("AMD ordering gives a permutation")
            .arrays()
    }

    /// The factor's position of original unknown `i` (the inverse permutation).
    pub(super) fn position(&self, i: usize) -> usize {
        self.permutation().1[i]
    }

    /// x ← K⁻¹ x (one solve).
    pub fn solve_in_place(&self, x: &mut [f64], counters: &Counters) {
        let y = self.forward(x);
        self.backward(y, x, counters);
    }

    /// The forward sweep y = L⁻¹ P r (half a solve; counted with its backward sweep).
    pub fn forward(&self, rhs: &[f64]) -> Forward {
        let (fwd, _) = self.permutation();
        let mut y: Vec<f64> = fwd.iter().map(|&i| rhs[i]).collect();
        let mut local = vec![0.0; self.analysis.supernodes.max_rows];
        if has_avx2() {
            // SAFETY: AVX2 was detected at run time.
            unsafe { self.forward_sweep_avx2(&mut y, &mut local) }
        } else {
            self.forward_sweep(&mut y, &mut local)
        }
        Forward { values: y }
    }

    /// The backward sweep x = Pᵀ L⁻ᵀ y, completing one solve: K⁻¹ r = backward(forward(r)).
    pub fn backward(&self, mut y: Forward, x: &mut [f64], counters: &Counters) {
        counters.solves.fetch_add(1, Ordering::Relaxed);
        let mut local = vec![0.0; self.analysis.supernodes.max_rows];
        if has_avx2() {
            // SAFETY: AVX2 was detected at run time.
            unsafe { self.backward_sweep_avx2(&mut y.values, &mut local) }
        } else {
            self.backward_sweep(&mut y.values, &mut local)
        }
        let (_, inv) = self.permutation();
        for (xi, &p) in x.iter_mut().zip(inv) {
            *xi = y.values[p];
        }
    }

    /// All supernodes in increasing order (the forward sweep in the factor's order).
    #[inline(always)]
    fn forward_sweep(&self, y: &mut [f64], local: &mut [f64]) {
        for s in 0..self.analysis.supernodes.len() {
            self.forward_supernode(s, y, local);
        }
    }

    /// All supernodes in decreasing order (the backward sweep in the factor's order).
    #[inline(always)]
    fn backward_sweep(&self, y: &mut [f64], local: &mut [f64]) {
        for s in (0..self.analysis.supernodes.len()).rev() {
            self.backward_supernode(s, y, local);
        }
    }

    /// [`Self::forward_sweep`] generated for AVX2 (the loops are `#[inline(always)]`, so they
    /// are compiled inside this function with 256-bit vectors).
    #[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
    unsafe fn forward_sweep_avx2(&self, y: &mut [f64], local: &mut [f64]) {
        self.forward_sweep(y, local)
    }

    /// [`Self::backward_sweep`] generated for AVX2.
    #[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
    unsafe fn backward_sweep_avx2(&self, y: &mut [f64], local: &mut [f64]) {
        self.backward_sweep(y, local)
    }

    /// The dense column-major block of supernode s and its shape (rows, width).
    #[inline(always)]
    fn block(&self, s: usize) -> (&[f64], usize, usize) {
        let sn = &self.analysis.supernodes;
        let (width, rows) = (sn.width[s], sn.width[s] + sn.pattern_len[s]);
        (
            &self.values[sn.value_start[s]..sn.value_start[s] + rows * width],
            rows,
            width,
        )
    }

    /// One supernode of the forward sweep, column by column so that L is read once:
    /// x_s ← L_ss⁻¹ x_s, then x_pattern ← x_pattern − L_ps x_s (accumulated in `local`).
    #[inline(always)]
    pub(super) fn forward_supernode(&self, s: usize, x: &mut [f64], local: &mut [f64]) {
        let sn = &self.analysis.supernodes;
        let (block, rows, width) = self.block(s);
        let start = sn.start[s];
        let t = &mut local[..rows];
        t[..width].copy_from_slice(&x[start..start + width]);
        t[width..].fill(0.0);
        for j in 0..width {
            let column = &block[j * rows..(j + 1) * rows];
            let v = t[j] / column[j];
            t[j] = v;
            if v != 0.0 {
                for (a, l) in t[j + 1..].iter_mut().zip(&column[j + 1..]) {
                    *a -= l * v;
                }
            }
        }
        x[start..start + width].copy_from_slice(&t[..width]);
        for (&row, a) in sn.pattern(s).iter().zip(&t[width..]) {
            x[row] += a;
        }
    }

    /// One supernode of the backward sweep: x_s ← L_ssᵀ⁻¹ (x_s − L_psᵀ x_pattern), one dot
    /// product per column.
    #[inline(always)]
    fn backward_supernode(&self, s: usize, x: &mut [f64], local: &mut [f64]) {
        let sn = &self.analysis.supernodes;
        let (block, rows, width) = self.block(s);
        let start = sn.start[s];
        let t = &mut local[..rows];
        t[..width].copy_from_slice(&x[start..start + width]);
        for (a, &row) in t[width..].iter_mut().zip(sn.pattern(s)) {
            *a = x[row];
        }
        // From the last column back, each column from its last row up: L is read as one
        // descending stream across supernodes, which the hardware prefetcher follows.
        for j in (0..width).rev() {
            let column = &block[j * rows..(j + 1) * rows];
            t[j] = (t[j] - dot_descending(&column[j + 1..], &t[j + 1..])) / column[j];
        }
        x[start..start + width].copy_from_slice(&t[..width]);
    }
}

/// Whether the processor has AVX2 (detected once, then cached by the standard library).
fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Dot product with four partial sums (vectorises; the order of summation is fixed).
#[inline(always)]
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f64 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| x * y).sum();
    let mut acc = [0.0; 8];
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
    ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7])) + tail
}

/// Dot product taken from the last entries to the first (addresses descending).
#[inline(always)]
fn dot_descending(a: &[f64], b: &[f64]) -> f64 {
    let (ca, cb) = (a.rchunks_exact(8), b.rchunks_exact(8));
    let tail: f64 = ca.remainder().iter().zip(cb.remainder()).map(|(x, y)| x * y).sum();
    let mut acc = [0.0; 8];
    for (x, y) in ca.zip(cb) {
        for k in (0..8).rev() {
            acc[k] += x[k] * y[k];
        }
    }
    ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7])) + tail
}

/// The supernode table; the parent of a supernode is the supernode holding the first row of its
/// off-diagonal pattern (every such row belongs to an ancestor).
fn supernode_table(symbolic: &SymbolicSupernodalCholesky<usize>) -> Supernodes {
    let ns = symbolic.n_supernodes();
    let (begin, end) = (symbolic.supernode_begin(), symbolic.supernode_end());
    let mut supernode_of = vec![0; symbolic.nrows()];
    for s in 0..ns {
        supernode_of[begin[s]..end[s]].fill(s);
    }
    let mut table = Supernodes {
        start: begin[..ns].to_vec(),
        width: (0..ns).map(|s| end[s] - begin[s]).collect(),
        pattern_start: symbolic.col_ptr_for_row_idx()[..ns].to_vec(),
        pattern_len: (0..ns).map(|s| symbolic.supernode(s).pattern().len()).collect(),
        value_start: symbolic.col_ptr_for_val()[..ns].to_vec(),
        row_idx: symbolic.row_idx().to_vec(),
        parent: Vec::with_capacity(ns),
        supernode_of,
        max_rows: 0,
    };
    for s in 0..ns {
        let parent = table
            .pattern(s)
            .iter()
            .min()
            .map_or(usize::MAX, |&row| table.supernode_of[row]);
        table.parent.push(parent);
        table.max_rows = table.max_rows.max(table.width[s] + table.pattern_len[s]);
    }
    table
}

impl Analysis {
    pub(super) fn supernodes(&self) -> &Supernodes {
        &self.supernodes
    }
}
