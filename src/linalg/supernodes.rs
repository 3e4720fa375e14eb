//! The supernodal structure of L and the dense kernels of the triangular sweeps.
//!
//! A supernode s holds the columns `start..start + width` of L with one common row pattern
//! below its diagonal block; its values are a dense column-major block of
//! `rows = width + pattern` rows. A sweep works on a local copy `t` of the supernode's rows:
//! the callers gather into `t` and scatter out of it (so the same kernels serve the
//! sequential sweeps, the parallel ones and the sparse forward sweeps of
//! [`super::ForwardColumns`]).
//!
//! The kernels read L once per sweep, column by column, and are compiled twice: as is, and
//! for AVX2 where the processor has it (detected at run time).

use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;

/// Per supernode: its columns, its off-diagonal row pattern, where its block sits in the
/// factor's values, and its parent in the supernodal elimination tree (`usize::MAX` at a
/// root); per column of L: its supernode.
pub(super) struct Supernodes {
    pub start: Vec<usize>,
    pub width: Vec<usize>,
    pattern_start: Vec<usize>,
    pub pattern_len: Vec<usize>,
    pub value_start: Vec<usize>,
    row_idx: Vec<usize>,
    pub parent: Vec<usize>,
    pub supernode_of: Vec<usize>,
    /// The tallest block (width + pattern): the size of a sweep's local vector.
    pub max_rows: usize,
}

impl Supernodes {
    /// The table of faer's supernodal structure. The parent of a supernode is the supernode
    /// holding the first row of its pattern (every such row belongs to an ancestor).
    pub fn new(symbolic: &SymbolicSupernodalCholesky<usize>) -> Self {
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
            table.max_rows = table.max_rows.max(table.rows(s));
        }
        table
    }

    /// Number of supernodes.
    pub fn len(&self) -> usize {
        self.start.len()
    }

    /// Rows of the block of s (width + pattern).
    pub fn rows(&self, s: usize) -> usize {
        self.width[s] + self.pattern_len[s]
    }

    /// The rows of L below the diagonal block of s (ascending).
    pub fn pattern(&self, s: usize) -> &[usize] {
        &self.row_idx[self.pattern_start[s]..self.pattern_start[s] + self.pattern_len[s]]
    }

    /// The block of s in the factor's values.
    pub fn block<'v>(&self, values: &'v [f64], s: usize) -> &'v [f64] {
        &values[self.value_start[s]..self.value_start[s] + self.rows(s) * self.width[s]]
    }

    /// Stored entries of the block of s (what a sweep reads of it).
    pub fn entries(&self, s: usize) -> usize {
        self.rows(s) * self.width[s]
    }
}

/// Forward kernel on a local vector t (rows of the block): t_s ← L_ss⁻¹ t_s and
/// t_pattern ← t_pattern − L_ps t_s, column by column.
pub(super) fn forward_block(block: &[f64], width: usize, t: &mut [f64]) {
    if has_avx2() {
        // SAFETY: AVX2 was detected at run time.
        unsafe { forward_block_avx2(block, width, t) }
    } else {
        forward_block_generic(block, width, t)
    }
}

/// Backward kernel on a local vector t: t_s ← L_ssᵀ⁻¹ (t_s − L_psᵀ t_pattern), from the last
/// column back and each column from its last row up, so that L is read as one descending
/// stream across supernodes, which the hardware prefetcher follows.
pub(super) fn backward_block(block: &[f64], width: usize, t: &mut [f64]) {
    if has_avx2() {
        // SAFETY: AVX2 was detected at run time.
        unsafe { backward_block_avx2(block, width, t) }
    } else {
        backward_block_generic(block, width, t)
    }
}

#[inline(always)]
fn forward_block_generic(block: &[f64], width: usize, t: &mut [f64]) {
    let rows = t.len();
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
}

#[inline(always)]
fn backward_block_generic(block: &[f64], width: usize, t: &mut [f64]) {
    let rows = t.len();
    for j in (0..width).rev() {
        let column = &block[j * rows..(j + 1) * rows];
        t[j] = (t[j] - dot_descending(&column[j + 1..], &t[j + 1..])) / column[j];
    }
}

#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn forward_block_avx2(block: &[f64], width: usize, t: &mut [f64]) {
    forward_block_generic(block, width, t)
}

#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn backward_block_avx2(block: &[f64], width: usize, t: &mut [f64]) {
    backward_block_generic(block, width, t)
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

/// Dot product with eight partial sums (vectorises; the order of summation is fixed).
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
