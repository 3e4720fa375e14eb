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
/// t_pattern ← t_pattern − L_ps t_s. Supernodes of at least a panel's width go by panels
/// ([`forward_panels`], four columns per pass over the rows below a panel), narrower ones
/// column by column; the two give the same bits.
pub(super) fn forward_block(block: &[f64], width: usize, t: &mut [f64]) {
    if width >= PANEL_COLUMNS {
        forward_panels(block, width, t, false)
    } else {
        forward_by_columns(block, width, t)
    }
}

/// The forward kernel column by column.
fn forward_by_columns(block: &[f64], width: usize, t: &mut [f64]) {
    if has_avx2() {
        // SAFETY: AVX2 was detected at run time.
        unsafe { forward_block_avx2(block, width, t) }
    } else {
        forward_block_generic(block, width, t)
    }
}

/// Backward kernel on a local vector t: t_s ← L_ssᵀ⁻¹ (t_s − L_psᵀ t_pattern), from the last
/// column back and each column from its last row up, so that L is read as one descending
/// stream across supernodes, which the hardware prefetcher follows. Supernodes of at least a
/// panel's width go by panels ([`backward_panels`]), with the same bits.
pub(super) fn backward_block(block: &[f64], width: usize, t: &mut [f64]) {
    if width >= PANEL_COLUMNS {
        backward_panels(block, width, t, false)
    } else {
        backward_by_columns(block, width, t)
    }
}

/// The backward kernel column by column.
fn backward_by_columns(block: &[f64], width: usize, t: &mut [f64]) {
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

/// The backward kernel with the dot products' lanes taken by `accumulate` (the processor's
/// choice is made once per block, in [`backward_block`]).
#[inline(always)]
fn backward_block_with(block: &[f64], width: usize, t: &mut [f64], accumulate: impl Fn(&[f64], &[f64], &mut [f64; 8])) {
    let rows = t.len();
    for j in (0..width).rev() {
        let column = &block[j * rows..(j + 1) * rows];
        t[j] = (t[j] - dot_descending(&column[j + 1..], &t[j + 1..], &accumulate)) / column[j];
    }
}

#[inline(always)]
fn backward_block_generic(block: &[f64], width: usize, t: &mut [f64]) {
    backward_block_with(block, width, t, accumulate_descending_generic)
}

#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn forward_block_avx2(block: &[f64], width: usize, t: &mut [f64]) {
    forward_block_generic(block, width, t)
}

#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn backward_block_avx2(block: &[f64], width: usize, t: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: this function runs only where AVX2 was detected
    backward_block_with(block, width, t, |a, b, acc| unsafe {
        accumulate_descending_avx2(a, b, acc)
    });
    #[cfg(not(target_arch = "x86_64"))]
    backward_block_generic(block, width, t)
}

/// Columns per panel of the panel kernels: a panel's own triangle is swept column by column,
/// the rows below it four columns per pass (on two threads in the split kernels). Measured on
/// the slab n = 40 factor: panels from 40 or 64 columns on, one solve 74.5 -> 71.5 ms (medians
/// of six alternating runs); on blocks of 16-32 columns they gain nothing (docs/method.md §9.8).
const PANEL_COLUMNS: usize = 64;
/// Under this many rows below a block, the two-thread kernels stay on one thread for it.
const SPLIT_MIN_ROWS: usize = 256;

/// [`forward_block`] on two threads, for the large supernodes at the top of the tree that
/// the parallel sweeps otherwise run on one (docs/method.md §9.8): in panels of
/// [`PANEL_COLUMNS`] columns, the panel's triangle on this thread, then the rows below it in
/// two halves, one per thread. Every entry of t receives the same updates in the same order
/// as in [`forward_by_columns`]: the same bits.
pub(super) fn forward_block_split(block: &[f64], width: usize, t: &mut [f64]) {
    forward_panels(block, width, t, true)
}

/// The forward kernel by panels, the rows below a panel on two threads or on this one.
pub(super) fn forward_panels(block: &[f64], width: usize, t: &mut [f64], threads: bool) {
    let avx2 = has_avx2();
    let rows = t.len();
    let mut j0 = 0;
    while j0 < width {
        let j1 = (j0 + PANEL_COLUMNS).min(width);
        let (head, below) = t.split_at_mut(j1);
        for j in j0..j1 {
            let column = &block[j * rows..(j + 1) * rows];
            let v = head[j] / column[j];
            head[j] = v;
            if v != 0.0 {
                for (a, l) in head[j + 1..].iter_mut().zip(&column[j + 1..j1]) {
                    *a -= l * v;
                }
            }
        }
        let v = &head[j0..];
        let update = |first: usize, part: &mut [f64]| subtract_columns(block, rows, j0, v, first, part, avx2);
        if threads && below.len() >= SPLIT_MIN_ROWS {
            let half = below.len() / 2;
            let (a, b) = below.split_at_mut(half);
            rayon::join(|| update(j1, a), || update(j1 + half, b));
        } else {
            update(j1, below);
        }
        j0 = j1;
    }
}

/// [`backward_block`] on two threads: in panels of [`PANEL_COLUMNS`] columns from the last,
/// each column's dot product over the rows already final (from a row whose distance to the
/// block's end is a multiple of eight) taken on two threads, half the columns each, into the
/// lanes the column kernel uses for them; then the panel's columns in order on this thread,
/// continuing those lanes over the remaining rows. The chunks of eight, the lanes and the
/// order of every sum are [`backward_by_columns`]'s: the same bits.
pub(super) fn backward_block_split(block: &[f64], width: usize, t: &mut [f64]) {
    backward_panels(block, width, t, true)
}

/// The backward kernel by panels, the final rows' dot products on two threads or on this one.
pub(super) fn backward_panels(block: &[f64], width: usize, t: &mut [f64], threads: bool) {
    let avx2 = has_avx2();
    let rows = t.len();
    let mut lanes = [[0.0f64; 8]; PANEL_COLUMNS];
    let mut j1 = width;
    while j1 > 0 {
        let j0 = j1.saturating_sub(PANEL_COLUMNS);
        // rows e.. are final and rows - e is a multiple of eight: whole chunks of every column
        let e = rows - (rows - j1) / 8 * 8;
        let lanes = &mut lanes[..j1 - j0];
        lanes.fill([0.0; 8]);
        {
            let done = &t[e..];
            let column = |j: usize| &block[j * rows + e..(j + 1) * rows];
            let partial = |first: usize, lanes: &mut [[f64; 8]]| {
                let mut chunks = lanes.chunks_exact_mut(4);
                let mut j = first;
                for four in &mut chunks {
                    accumulate4(
                        [column(j), column(j + 1), column(j + 2), column(j + 3)],
                        done,
                        four,
                        avx2,
                    );
                    j += 4;
                }
                for acc in chunks.into_remainder() {
                    accumulate(column(j), done, acc, avx2);
                    j += 1;
                }
            };
            if threads && rows - e >= SPLIT_MIN_ROWS {
                let half = lanes.len() / 2;
                let (a, b) = lanes.split_at_mut(half);
                rayon::join(|| partial(j0, a), || partial(j0 + half, b));
            } else {
                partial(j0, lanes);
            }
        }
        for j in (j0..j1).rev() {
            let column = &block[j * rows..(j + 1) * rows];
            let dot = dot_descending_from(lanes[j - j0], &column[j + 1..e], &t[j + 1..e], |a, b, acc| {
                accumulate(a, b, acc, avx2)
            });
            t[j] = (t[j] - dot) / column[j];
        }
        j1 = j0;
    }
}

/// part ← part − Σ_k L[first.., j0 + k] v_k, k ascending (rows `first..` of the block).
fn subtract_columns(block: &[f64], rows: usize, j0: usize, v: &[f64], first: usize, part: &mut [f64], avx2: bool) {
    if avx2 {
        // SAFETY: AVX2 was detected at run time.
        unsafe { subtract_columns_avx2(block, rows, j0, v, first, part) }
    } else {
        subtract_columns_generic(block, rows, j0, v, first, part)
    }
}

#[inline(always)]
fn subtract_columns_generic(block: &[f64], rows: usize, j0: usize, v: &[f64], first: usize, part: &mut [f64]) {
    let n = part.len();
    let column = |k: usize| &block[(j0 + k) * rows + first..][..n];
    let mut k = 0;
    // four columns at a time where all four are non-zero: each entry still takes the four
    // updates in column order, one multiply and one subtraction each
    while k + 4 <= v.len() {
        let w = &v[k..k + 4];
        if w.iter().all(|&x| x != 0.0) {
            let (c0, c1, c2, c3) = (column(k), column(k + 1), column(k + 2), column(k + 3));
            for i in 0..n {
                let mut a = part[i];
                a -= c0[i] * w[0];
                a -= c1[i] * w[1];
                a -= c2[i] * w[2];
                a -= c3[i] * w[3];
                part[i] = a;
            }
        } else {
            for (q, &x) in w.iter().enumerate() {
                if x != 0.0 {
                    for (a, l) in part.iter_mut().zip(column(k + q)) {
                        *a -= l * x;
                    }
                }
            }
        }
        k += 4;
    }
    for (q, &x) in v[k..].iter().enumerate() {
        if x != 0.0 {
            for (a, l) in part.iter_mut().zip(column(k + q)) {
                *a -= l * x;
            }
        }
    }
}

#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn subtract_columns_avx2(block: &[f64], rows: usize, j0: usize, v: &[f64], first: usize, part: &mut [f64]) {
    subtract_columns_generic(block, rows, j0, v, first, part)
}

/// [`accumulate`] for four columns against one b (read once for the four): lane for lane
/// each column's sums.
fn accumulate4(a: [&[f64]; 4], b: &[f64], acc: &mut [[f64; 8]], avx2: bool) {
    #[cfg(target_arch = "x86_64")]
    if avx2 {
        // SAFETY: AVX2 was detected at run time.
        return unsafe { accumulate4_avx2(a, b, acc) };
    }
    for (a, acc) in a.iter().zip(acc) {
        accumulate(a, b, acc, avx2);
    }
}

/// [`accumulate_descending_avx2`] for four columns of equal length against one b.
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn accumulate4_avx2(a: [&[f64]; 4], b: &[f64], acc: &mut [[f64; 8]]) {
    use std::arch::x86_64::{__m256d, _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_storeu_pd};
    let n = b.len();
    assert!(acc.len() == 4 && a.iter().all(|c| c.len() == n));
    let r = n % 8;
    // SAFETY: every acc holds eight values; base + 8 <= n, within every slice
    unsafe {
        let mut lanes: [[__m256d; 2]; 4] = std::array::from_fn(|k| {
            [
                _mm256_loadu_pd(acc[k].as_ptr()),
                _mm256_loadu_pd(acc[k].as_ptr().add(4)),
            ]
        });
        let pb = b.as_ptr();
        let mut base = n;
        while base >= r + 8 {
            base -= 8;
            let (lo, hi) = (_mm256_loadu_pd(pb.add(base)), _mm256_loadu_pd(pb.add(base + 4)));
            for k in 0..4 {
                let pa = a[k].as_ptr();
                lanes[k][0] = _mm256_add_pd(lanes[k][0], _mm256_mul_pd(_mm256_loadu_pd(pa.add(base)), lo));
                lanes[k][1] = _mm256_add_pd(lanes[k][1], _mm256_mul_pd(_mm256_loadu_pd(pa.add(base + 4)), hi));
            }
        }
        for k in 0..4 {
            _mm256_storeu_pd(acc[k].as_mut_ptr(), lanes[k][0]);
            _mm256_storeu_pd(acc[k].as_mut_ptr().add(4), lanes[k][1]);
        }
    }
}

/// The chunks of eight of a and b from the end into `acc`, on the processor's lanes.
fn accumulate(a: &[f64], b: &[f64], acc: &mut [f64; 8], avx2: bool) {
    #[cfg(target_arch = "x86_64")]
    if avx2 {
        // SAFETY: AVX2 was detected at run time.
        return unsafe { accumulate_descending_avx2(a, b, acc) };
    }
    let _ = avx2;
    accumulate_descending_generic(a, b, acc)
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

/// Dot product taken from the last entries to the first (addresses descending), in eight
/// lanes: the chunks of eight from the end, then the first `len % 8` entries, then the lanes
/// summed pairwise.
#[inline(always)]
fn dot_descending(a: &[f64], b: &[f64], accumulate: impl Fn(&[f64], &[f64], &mut [f64; 8])) -> f64 {
    dot_descending_from([0.0; 8], a, b, accumulate)
}

/// [`dot_descending`] continuing lanes `acc` that already hold the chunks after a and b (the
/// panel kernels take a column's final rows first, in the same lanes).
#[inline(always)]
fn dot_descending_from(
    mut acc: [f64; 8],
    a: &[f64],
    b: &[f64],
    accumulate: impl Fn(&[f64], &[f64], &mut [f64; 8]),
) -> f64 {
    let r = a.len() % 8;
    accumulate(a, b, &mut acc);
    let tail: f64 = a[..r].iter().zip(&b[..r]).map(|(x, y)| x * y).sum();
    ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7])) + tail
}

/// The chunks of eight of a and b from the end into the lanes `acc` (the first `len % 8`
/// entries are left); lane k takes entry k of each chunk, as a separate multiply and add.
#[inline(always)]
fn accumulate_descending_generic(a: &[f64], b: &[f64], acc: &mut [f64; 8]) {
    debug_assert_eq!(a.len(), b.len());
    for (x, y) in a.rchunks_exact(8).zip(b.rchunks_exact(8)) {
        for k in 0..8 {
            acc[k] += x[k] * y[k];
        }
    }
}

/// [`accumulate_descending_generic`] with AVX2 loads and arithmetic, lane for lane the same sums: LLVM
/// compiled the scalar form to 128-bit shuffles, which made the backward sweep 40 % slower than
/// the forward one on the same entries (docs/method.md §9.6).
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn accumulate_descending_avx2(a: &[f64], b: &[f64], acc: &mut [f64; 8]) {
    use std::arch::x86_64::{_mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_storeu_pd};
    let n = a.len().min(b.len());
    let r = n % 8;
    let (pa, pb, pacc) = (a.as_ptr(), b.as_ptr(), acc.as_mut_ptr());
    // SAFETY: acc holds eight values; base + 8 <= n, within both slices
    unsafe {
        let (mut lo, mut hi) = (_mm256_loadu_pd(pacc), _mm256_loadu_pd(pacc.add(4)));
        let mut base = n;
        while base >= r + 8 {
            base -= 8;
            lo = _mm256_add_pd(
                lo,
                _mm256_mul_pd(_mm256_loadu_pd(pa.add(base)), _mm256_loadu_pd(pb.add(base))),
            );
            hi = _mm256_add_pd(
                hi,
                _mm256_mul_pd(_mm256_loadu_pd(pa.add(base + 4)), _mm256_loadu_pd(pb.add(base + 4))),
            );
        }
        _mm256_storeu_pd(pacc, lo);
        _mm256_storeu_pd(pacc.add(4), hi);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The panel kernels, on one thread and on two, are the column-by-column kernels to the
    /// bit, on blocks around the panel's width, with no rows below the diagonal block and with
    /// many (so that both the split and the one-thread paths of every panel run).
    #[test]
    fn panel_kernels_are_the_column_kernels_to_the_bit() {
        type Kernel = fn(&[f64], usize, &mut [f64]);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let value = |i: usize, s: f64| (i as f64 * 0.7548776662 + s).fract() - 0.5;
        let one_thread_forward: Kernel = |b, w, t| forward_panels(b, w, t, false);
        let one_thread_backward: Kernel = |b, w, t| backward_panels(b, w, t, false);
        for width in [1, 7, 63, 64, 65, 130, 300] {
            for pattern in [0, 5, 257, 700] {
                let rows = width + pattern;
                let block: Vec<f64> = (0..rows * width)
                    .map(|k| match (k % rows, k / rows) {
                        (i, j) if i == j => 1.0 + value(k, 0.3).abs(),
                        (i, j) if i < j => f64::NAN, // above the diagonal: never read
                        _ => 2.0 * value(k, 0.1) / rows as f64,
                    })
                    .collect();
                let rhs: Vec<f64> = (0..rows)
                    .map(|i| value(i, 0.6) * 10f64.powi((i % 5) as i32 - 2))
                    .collect();
                for (reference, panels) in [
                    (
                        forward_by_columns as Kernel,
                        [forward_block as Kernel, one_thread_forward, forward_block_split],
                    ),
                    (
                        backward_by_columns,
                        [backward_block as Kernel, one_thread_backward, backward_block_split],
                    ),
                ] {
                    let mut a = rhs.clone();
                    reference(&block, width, &mut a);
                    assert!(a.iter().all(|v| v.is_finite()), "width {width}, pattern {pattern}");
                    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                    for (k, kernel) in panels.into_iter().enumerate() {
                        let mut b = rhs.clone();
                        pool.install(|| kernel(&block, width, &mut b));
                        assert_eq!(bits(&a), bits(&b), "kernel {k}, width {width}, pattern {pattern}");
                    }
                }
            }
        }
    }

    /// The AVX2 lanes are the scalar lanes to the bit, at every length around the chunk size
    /// (values of mixed sign and magnitude, so that a different order of the sums would show).
    #[test]
    fn descending_lanes_with_avx2_are_the_scalar_ones() {
        if !has_avx2() {
            eprintln!("skipped: the processor has no AVX2");
            return;
        }
        let value = |i: usize, s: f64| ((i as f64 * 0.7548776662 + s).fract() - 0.5) * 10f64.powi((i % 7) as i32 - 3);
        for n in 0..=41 {
            let a: Vec<f64> = (0..n).map(|i| value(i, 0.1)).collect();
            let b: Vec<f64> = (0..n).map(|i| value(i, 0.6)).collect();
            let (mut scalar, mut vector) = ([0.25; 8], [0.25; 8]);
            accumulate_descending_generic(&a, &b, &mut scalar);
            // SAFETY: AVX2 was detected above.
            unsafe { accumulate_descending_avx2(&a, &b, &mut vector) };
            assert_eq!(scalar.map(f64::to_bits), vector.map(f64::to_bits), "length {n}");
        }
    }
}
