//! G = L⁻¹ P Bᵀ for a sparse B with few rows (B = C, the contact normals; docs/method.md §4,
//! "the fast path"), stored column by column in supernode segments.
//!
//! A column of Bᵀ has one or two nonzeros. Its forward sweep L⁻¹ P b is nonzero only on the
//! supernodes of the path(s) from its entries to the root of the supernodal elimination tree,
//! so it is computed by a sparse sweep over those supernodes alone, and stored as one
//! segment per supernode. A few hundred paths of a 2D factor hold well under a tenth of the
//! factor's entries, so Gᵀ y and y − G λ are cheap next to a sweep over L.

use super::factor::{Analysis, Counters, Factor, Forward};
use super::supernodes::dot;
use rayon::prelude::*;
use std::sync::atomic::Ordering;

/// One supernode's slice of a column of G: rows `start..start + len` of the factor's order.
#[derive(Clone, Copy, Debug)]
struct Segment {
    supernode: usize,
    start: usize,
    len: usize,
    /// Offset of the segment's values in [`ForwardColumns::values`].
    offset: usize,
}

/// The columns of G = L⁻¹ P Bᵀ.
pub struct ForwardColumns {
    /// Column c has segments `segments[column_start[c]..column_start[c + 1]]`, in increasing
    /// supernode order.
    column_start: Vec<usize>,
    segments: Vec<Segment>,
    values: Vec<f64>,
}

impl ForwardColumns {
    /// The forward sweeps of the columns of Bᵀ; `rows[c]` lists the (unknown, coefficient)
    /// pairs of row c of B. Counted as one sparse sweep per row. From
    /// [`BLOCKED_FROM_COLUMNS`] rows on, the columns go through the tree together, in blocks of
    /// [`block_columns`] ([`blocked_sweeps`]: dense triangular solves and products on each
    /// supernode, docs/method.md §9.9); below, one sparse sweep each.
    pub fn new(factor: &Factor, rows: &[Vec<(usize, f64)>], counters: &Counters) -> Self {
        counters.sparse_forward_sweeps.fetch_add(rows.len(), Ordering::Relaxed);
        // a zero coefficient would start its column's path at its unknown for nothing
        let rows: Vec<Vec<(usize, f64)>> = rows
            .iter()
            .map(|r| r.iter().copied().filter(|&(_, c)| c != 0.0).collect())
            .collect();
        let rows = &rows[..];
        let n = factor.n();
        let n_supernodes = factor.analysis().supernodes().len();
        let columns: Vec<(Vec<Segment>, Vec<f64>)> = if rows.len() >= BLOCKED_FROM_COLUMNS {
            rows.par_chunks(block_columns(rows.len()))
                .flat_map_iter(|chunk| blocked_sweeps(factor, chunk))
                .collect()
        } else {
            rows.par_iter()
                .map_init(
                    || (vec![0.0; n], vec![false; n_supernodes]),
                    |(work, marked), row| sparse_forward_sweep(factor, row, work, marked),
                )
                .collect()
        };
        Self::from_columns(columns)
    }

    /// The columns' segments and values, in column order, concatenated.
    fn from_columns(columns: impl IntoIterator<Item = (Vec<Segment>, Vec<f64>)>) -> Self {
        let mut out = ForwardColumns {
            column_start: vec![0],
            segments: Vec::new(),
            values: Vec::new(),
        };
        for (segments, values) in columns {
            let base = out.values.len();
            out.segments.extend(segments.into_iter().map(|s| Segment {
                offset: s.offset + base,
                ..s
            }));
            out.values.extend(values);
            out.column_start.push(out.segments.len());
        }
        out
    }

    /// Number of columns (rows of B).
    pub fn len(&self) -> usize {
        self.column_start.len() - 1
    }

    /// True if there are no columns.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn column(&self, c: usize) -> &[Segment] {
        &self.segments[self.column_start[c]..self.column_start[c + 1]]
    }

    fn segment_values(&self, s: &Segment) -> &[f64] {
        &self.values[s.offset..s.offset + s.len]
    }

    /// out = Gᵀ y. With y = L⁻¹ P r this is B K⁻¹ r.
    pub fn transpose_apply(&self, y: &Forward, out: &mut [f64]) {
        for (c, o) in out.iter_mut().enumerate() {
            *o = self
                .column(c)
                .iter()
                .map(|s| dot(self.segment_values(s), &y.values[s.start..s.start + s.len]))
                .sum();
        }
    }

    /// y ← y − G λ. With y = L⁻¹ P r the backward sweep of the result is K⁻¹ (r − Bᵀ λ).
    pub fn subtract_apply(&self, lambda: &[f64], y: &mut Forward) {
        for (c, &l) in lambda.iter().enumerate() {
            if l == 0.0 {
                continue;
            }
            for s in self.column(c) {
                let target = &mut y.values[s.start..s.start + s.len];
                for (t, g) in target.iter_mut().zip(self.segment_values(s)) {
                    *t -= l * g;
                }
            }
        }
    }

    /// Gᵀ G (row-major, symmetric) = B K⁻¹ Bᵀ, supernode by supernode: the segments of the
    /// k columns whose paths pass through a supernode of width w form a dense w × k block G_s,
    /// and W = Σ_s G_sᵀ G_s, each term one matrix product (faer) scattered into W. Two threads
    /// take alternate supernodes into their own W, summed at the end. From
    /// [`BLOCKED_FROM_COLUMNS`] columns on, only the products' lower triangles are formed (half
    /// the work: the graded block at 10⁵ unknowns, m = 3 594, 2.2 s → 1.4 s) and W's upper
    /// triangle is copied from its lower one; below, the whole products, averaged with their
    /// transposes (the bits the 2D runs have always had).
    pub fn gram(&self) -> Vec<f64> {
        use faer::linalg::matmul::triangular::{matmul, BlockStructure};
        let m = self.len();
        let lower_only = m >= BLOCKED_FROM_COLUMNS;
        let structure = match lower_only {
            true => BlockStructure::TriangularLower,
            false => BlockStructure::Rectangular,
        };
        let n_supernodes = self.segments.iter().map(|s| s.supernode + 1).max().unwrap_or(0);
        // (column, segment) pairs on each supernode, columns ascending
        let mut on: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n_supernodes];
        for c in 0..m {
            for k in self.column_start[c]..self.column_start[c + 1] {
                on[self.segments[k].supernode].push((c, k));
            }
        }
        let threads = rayon::current_num_threads().clamp(1, 2);
        let parts: Vec<Vec<f64>> = (0..threads)
            .into_par_iter()
            .map(|t| {
                let mut w = vec![0.0; m * m];
                // G_s and G_sᵀG_s in storage kept from supernode to supernode (the trailing
                // supernodes' blocks are tens of MB: fresh ones cost page faults)
                let (mut g, mut block) = (Vec::new(), Vec::new());
                for list in on.iter().skip(t).step_by(threads) {
                    if list.is_empty() {
                        continue;
                    }
                    // Segments on one supernode end together; a trimmed one starts later, its
                    // rows above its start being zeros of G.
                    let top = list.iter().map(|&(_, k)| self.segments[k].start).min().unwrap_or(0);
                    let end = self.segments[list[0].1].start + self.segments[list[0].1].len;
                    let (rows, k) = (end - top, list.len());
                    g.clear();
                    g.resize(rows * k, 0.0);
                    for (c, &(_, s)) in list.iter().enumerate() {
                        let segment = &self.segments[s];
                        let skip = segment.start - top;
                        g[c * rows + skip..(c + 1) * rows].copy_from_slice(self.segment_values(segment));
                    }
                    block.clear();
                    block.resize(k * k, 0.0);
                    let g = faer::MatRef::from_column_major_slice(&g, rows, k);
                    matmul(
                        faer::MatMut::from_column_major_slice_mut(&mut block, k, k),
                        structure,
                        faer::Accum::Replace,
                        g.transpose(),
                        BlockStructure::Rectangular,
                        g,
                        BlockStructure::Rectangular,
                        1.0,
                        faer::get_global_parallelism(),
                    );
                    for (a, &(ca, _)) in list.iter().enumerate() {
                        let row = &mut w[ca * m..(ca + 1) * m];
                        let upto = if lower_only { a + 1 } else { k };
                        for (b, &(cb, _)) in list[..upto].iter().enumerate() {
                            row[cb] += block[b * k + a];
                        }
                    }
                }
                w
            })
            .collect();
        let mut w = vec![0.0; m * m];
        for part in &parts {
            for (x, y) in w.iter_mut().zip(part) {
                *x += y;
            }
        }
        // exact symmetry
        match lower_only {
            true => super::dense::mirror_lower_row_major(&mut w, m),
            false => super::dense::symmetrise_row_major(&mut w, m),
        }
        w
    }
}

/// The row from which a column's segments are kept. L⁻¹ P b is zero above b's first non-zero
/// row: with unknowns ordered last (docs/method.md §9.1) the columns of G start deep inside the
/// wide trailing supernode, so the segments are trimmed to that row (box 96x48x12: 6.8 M values
/// → 2.2 M); otherwise they are kept whole (0), which leaves every product of the 2D runs as it
/// was.
fn first_row(analysis: &Analysis, row: &[(usize, f64)]) -> usize {
    match analysis.ordered_last() > 0 {
        true => {
            let position = analysis.permutation().1;
            row.iter().map(|&(i, _)| position[i]).min().unwrap_or(0)
        }
        false => 0,
    }
}

/// The number of values [`ForwardColumns::new`] will store for `rows` on `analysis`: each
/// column's supernode path, trimmed as the sweep trims it. For predicting a run's memory before
/// the numeric factorisation (docs/method.md §16.1).
pub fn forward_columns_entries(analysis: &Analysis, rows: &[Vec<(usize, f64)>]) -> usize {
    let supernodes = analysis.supernodes();
    let position = analysis.permutation().1;
    let mut marked = vec![usize::MAX; supernodes.len()];
    let mut total = 0;
    for (c, row) in rows.iter().enumerate() {
        let first = first_row(analysis, row);
        for &(i, _) in row {
            let mut s = supernodes.supernode_of[position[i]];
            while s != usize::MAX && marked[s] != c {
                marked[s] = c;
                let end = supernodes.start[s] + supernodes.width[s];
                total += end - supernodes.start[s].max(first).min(end);
                s = supernodes.parent[s];
            }
        }
    }
    total
}

/// L⁻¹ P b for a sparse b, visiting only the supernodes on the paths from b's entries to the
/// root (in increasing order, so every supernode is finished before its ancestors use it).
/// `work` (length n, zero) and `marked` (one flag per supernode, false) are returned clean.
fn sparse_forward_sweep(
    factor: &Factor,
    entries: &[(usize, f64)],
    work: &mut [f64],
    marked: &mut [bool],
) -> (Vec<Segment>, Vec<f64>) {
    let supernodes = factor.analysis().supernodes();
    let mut path = Vec::new();
    for &(i, c) in entries {
        let row = factor.position(i);
        work[row] += c;
        let mut s = supernodes.supernode_of[row];
        while s != usize::MAX && !marked[s] {
            marked[s] = true;
            path.push(s);
            s = supernodes.parent[s];
        }
    }
    path.sort_unstable();
    let first = first_row(factor.analysis(), entries);
    let mut local = vec![0.0; supernodes.max_rows];
    let mut segments = Vec::with_capacity(path.len());
    let mut values = Vec::new();
    for &s in &path {
        factor.forward_supernode(s, work, &mut local);
        let end = supernodes.start[s] + supernodes.width[s];
        let start = supernodes.start[s].max(first);
        let len = end - start;
        segments.push(Segment {
            supernode: s,
            start,
            len,
            offset: values.len(),
        });
        values.extend_from_slice(&work[start..start + len]);
    }
    for &s in &path {
        work[supernodes.start[s]..supernodes.start[s] + supernodes.width[s]].fill(0.0);
        marked[s] = false;
    }
    (segments, values)
}

/// From how many columns [`ForwardColumns::new`] sweeps them together ([`blocked_sweeps`]) and
/// [`ForwardColumns::gram`] forms only lower triangles (docs/method.md §9.9). The blocks win at
/// every size measured (two threads, medians of 5: the graded block of benches/graded, 1 656
/// columns on a factor of 18.3 M entries, 0.98 s by single sweeps, 0.24 s by blocks; the 2D
/// paper at h = 1/128, 16 to 256 columns, 2.3–2.8× faster), but below 128 columns they save
/// under a millisecond (rect_q1_h32's 64: 0.3 ms either way) and would change the bits of the 2D
/// paper run, so the single sweeps stay there.
pub const BLOCKED_FROM_COLUMNS: usize = 128;
/// At most this many columns per block of [`blocked_sweeps`].
pub const MAX_BLOCK_COLUMNS: usize = 512;

/// Columns per block of [`blocked_sweeps`] for m columns: at least four blocks per thread (the
/// blocks' costs differ with where their nodes sit in the tree) and at most
/// [`MAX_BLOCK_COLUMNS`] columns each. Measured on two threads (benches/graded, blocked sweeps
/// alone): m = 1 656, blocks of 207 0.24 s, 256 0.25 s, 512 0.37–0.40 s; m = 3 594, 64 3.9 s,
/// 128 3.0 s, 256 2.4 s, 450 1.8–1.9 s, 512 2.0 s, 1 024 2.9 s, 1 797 2.4 s (larger blocks
/// fall out of cache in the scatter into the ancestors).
fn block_columns(m: usize) -> usize {
    let threads = rayon::current_num_threads().max(1);
    let blocks = (4 * threads).max(m.div_ceil(MAX_BLOCK_COLUMNS));
    m.div_ceil(blocks).max(1)
}

/// L⁻¹ P bᵢ for the columns `rows` together (a supernodal forward sweep with many sparse
/// right-hand sides): on each supernode s, in increasing order, the columns whose paths pass
/// through it form a dense block X_s (the rows of s from the first that any of them reaches);
/// X_s ← L_ss⁻¹ X_s (one triangular solve) and the rows below, L_ps X_s (one product), are
/// subtracted from the blocks of the ancestors that hold them. The same numbers as one sweep per
/// column, in matrix–matrix operations. Returns each column's segments and values (a segment
/// per supernode on its path, trimmed as the single sweep trims it).
fn blocked_sweeps(factor: &Factor, rows: &[Vec<(usize, f64)>]) -> Vec<(Vec<Segment>, Vec<f64>)> {
    use faer::reborrow::{Reborrow, ReborrowMut};
    use faer::{Accum, MatMut, MatRef, Par};
    let sn = factor.analysis().supernodes();
    let ns = sn.len();
    // each column's first row and the supernodes it reaches
    let first: Vec<usize> = rows.iter().map(|row| first_row(factor.analysis(), row)).collect();
    let mut active: Vec<Vec<usize>> = vec![Vec::new(); ns];
    let mut reached: Vec<Option<usize>> = vec![None; ns];
    for (c, row) in rows.iter().enumerate() {
        for &(i, _) in row {
            // up the path to the root (a root's parent is usize::MAX), until a reached supernode
            let mut s = sn.supernode_of[factor.position(i)];
            while s != usize::MAX && reached[s] != Some(c) {
                reached[s] = Some(c);
                active[s].push(c);
                s = sn.parent[s];
            }
        }
    }
    // X_s: rows top[s]..end of s, one column per active column, column-major, at offset[s]
    let mut top = vec![0; ns];
    let mut offset = vec![0; ns + 1];
    for s in 0..ns {
        let end = sn.start[s] + sn.width[s];
        top[s] = active[s]
            .iter()
            .map(|&c| sn.start[s].max(first[c]))
            .min()
            .unwrap_or(end);
        offset[s + 1] = offset[s] + (end - top[s]) * active[s].len();
    }
    let mut x = vec![0.0; offset[ns]];
    for (c, row) in rows.iter().enumerate() {
        for &(i, coefficient) in row {
            let r = factor.position(i);
            let s = sn.supernode_of[r];
            let h = sn.start[s] + sn.width[s] - top[s];
            let j = active[s]
                .binary_search(&c)
                .expect("a column is active on its own supernode");
            x[offset[s] + j * h + r - top[s]] += coefficient;
        }
    }
    let values = factor.values();
    let mut product = Vec::new();
    let mut map = Vec::new();
    for s in 0..ns {
        let k = active[s].len();
        if k == 0 {
            continue;
        }
        let (width, rows_s, below) = (sn.width[s], sn.rows(s), sn.pattern_len[s]);
        let skip = top[s] - sn.start[s];
        let h = width - skip;
        let block = sn.block(values, s);
        let (head, tail) = x.split_at_mut(offset[s + 1]);
        let mut xs = MatMut::from_column_major_slice_mut(&mut head[offset[s]..], h, k);
        let diagonal = MatRef::from_column_major_slice_with_stride(&block[skip * rows_s + skip..], h, h, rows_s);
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(diagonal, xs.rb_mut(), Par::Seq);
        if below == 0 {
            continue;
        }
        // the rows below: P = L_ps X_s, subtracted from the ancestors' blocks
        product.clear();
        product.resize(below * k, 0.0);
        let lower = MatRef::from_column_major_slice_with_stride(&block[skip * rows_s + width..], below, h, rows_s);
        faer::linalg::matmul::matmul(
            MatMut::from_column_major_slice_mut(&mut product, below, k),
            Accum::Replace,
            lower,
            xs.rb(),
            1.0,
            Par::Seq,
        );
        let pattern = sn.pattern(s);
        let mut p = 0;
        while p < below {
            // the run of pattern rows in one ancestor t
            let t = sn.supernode_of[pattern[p]];
            let end_t = sn.start[t] + sn.width[t];
            let q = p + pattern[p..].partition_point(|&r| r < end_t);
            // the columns of s among t's (every column reaching s reaches t)
            map.clear();
            let mut from = 0;
            for &c in &active[s] {
                from += active[t][from..].partition_point(|&d| d < c);
                map.push(from);
            }
            let h_t = end_t - top[t];
            let base = offset[t] - offset[s + 1];
            for (j, &jt) in map.iter().enumerate() {
                let target = &mut tail[base + jt * h_t..base + (jt + 1) * h_t];
                for (&r, v) in pattern[p..q].iter().zip(&product[j * below + p..j * below + q]) {
                    target[r - top[t]] -= v;
                }
            }
            p = q;
        }
    }
    // each column's segments, in increasing supernode order
    let mut columns: Vec<(Vec<Segment>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); rows.len()];
    for s in 0..ns {
        let end = sn.start[s] + sn.width[s];
        let h = end - top[s];
        for (j, &c) in active[s].iter().enumerate() {
            let start = sn.start[s].max(first[c]);
            let (segments, values) = &mut columns[c];
            let from = offset[s] + j * h + start - top[s];
            segments.push(Segment {
                supernode: s,
                start,
                len: end - start,
                offset: values.len(),
            });
            values.extend_from_slice(&x[from..from + end - start]);
        }
    }
    columns
}

#[cfg(test)]
mod tests {
    //! G = L⁻¹ P Cᵀ against whole solves: Gᵀ (L⁻¹ P r) = C K⁻¹ r, Gᵀ G = C K⁻¹ Cᵀ, and
    //! backward(forward(r) − G λ) = K⁻¹ (r − Cᵀ λ), for rows with one and two entries
    //! anywhere in the mesh, on matrices of P1 and Q1 patterns.
    use super::super::sparse::test_matrices::{grid_stiffness, relative_difference as rel};
    use super::*;
    use proptest::prelude::*;

    fn solve(factor: &Factor, r: &[f64]) -> Vec<f64> {
        let mut x = r.to_vec();
        factor.solve_in_place(&mut x, &Counters::default());
        x
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn forward_columns_agree_with_whole_solves(
            quad in any::<bool>(),
            picks in proptest::collection::vec((0usize..10_000, 0usize..10_000, -1.0f64..1.0, -1.0f64..1.0, any::<bool>()), 1..12),
            seed in 0u64..1000,
        ) {
            let k = grid_stiffness(12, 7, quad);
            let n = k.n();
            let counters = Counters::default();
            let factor = Factor::new(&Factor::analyse(&k).unwrap(), &k, &counters).unwrap();
            let rows: Vec<Vec<(usize, f64)>> = picks
                .iter()
                .map(|&(i, j, a, b, two)| {
                    let (i, j) = (i % n, j % n);
                    if two && i != j { vec![(i, a + 1.5), (j, b)] } else { vec![(i, a + 1.5)] }
                })
                .collect();
            let g = ForwardColumns::new(&factor, &rows, &counters);
            prop_assert_eq!(counters.sparse_forward_sweeps(), rows.len());
            let apply_c = |x: &[f64]| -> Vec<f64> { rows.iter().map(|r| r.iter().map(|(d, c)| c * x[*d]).sum()).collect() };
            // W = C K⁻¹ Cᵀ column by column with whole solves.
            let m = rows.len();
            let gram = g.gram();
            for q in 0..m {
                let mut e = vec![0.0; n];
                for (d, c) in &rows[q] { e[*d] += c; }
                let column = apply_c(&solve(&factor, &e));
                let ours: Vec<f64> = (0..m).map(|p| gram[p * m + q]).collect();
                prop_assert!(rel(&ours, &column) < 1e-12, "W column {q}: {:.1e}", rel(&ours, &column));
            }
            // A right-hand side and forces.
            let r: Vec<f64> = (0..n).map(|i| ((i as f64 + seed as f64) * 0.754_877_666).fract() - 0.5).collect();
            let lambda: Vec<f64> = (0..m).map(|p| if p % 3 == 1 { 0.0 } else { (p as f64 * 0.618).fract() - 0.3 }).collect();
            let mut y = factor.forward(&r);
            let mut d = vec![0.0; m];
            g.transpose_apply(&y, &mut d);
            let expected_d = apply_c(&solve(&factor, &r));
            prop_assert!(rel(&d, &expected_d) < 1e-12, "C K⁻¹ r: {:.1e}", rel(&d, &expected_d));
            g.subtract_apply(&lambda, &mut y);
            let mut u = vec![0.0; n];
            factor.backward(y, &mut u, &counters);
            let mut shifted = r.clone();
            for (row, l) in rows.iter().zip(&lambda) {
                for (i, c) in row { shifted[*i] -= c * l; }
            }
            let expected_u = solve(&factor, &shifted);
            prop_assert!(rel(&u, &expected_u) < 1e-12, "K⁻¹(r − Cᵀλ): {:.1e}", rel(&u, &expected_u));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]
        /// The blocked sweeps give the single sweeps' columns (to rounding: the sums run in
        /// another order), in chunks and whole, on factors with and without the rows' unknowns
        /// ordered last (where both trim the columns above their first row); W = Gᵀ G on either
        /// side of BLOCKED_FROM_COLUMNS is C K⁻¹ Cᵀ.
        #[test]
        fn blocked_sweeps_agree_with_single_sweeps(
            quad in any::<bool>(),
            last in any::<bool>(),
            picks in proptest::collection::vec((0usize..10_000, 0usize..10_000, -1.0f64..1.0, any::<bool>()), 1..200),
        ) {
            let k = grid_stiffness(14, 9, quad);
            let n = k.n();
            let rows: Vec<Vec<(usize, f64)>> = picks
                .iter()
                .map(|&(i, j, a, two)| {
                    let (i, j) = (i % n, j % n);
                    if two && i != j { vec![(i, a + 1.5), (j, 0.5 - a)] } else { vec![(i, a + 1.5)] }
                })
                .collect();
            let mut unknowns: Vec<usize> = rows.iter().flatten().map(|&(i, _)| i).collect();
            unknowns.sort_unstable();
            unknowns.dedup();
            let analysis = if last { Factor::analyse_with_last(&k, &unknowns).unwrap() } else { Factor::analyse(&k).unwrap() };
            let factor = Factor::new(&analysis, &k, &Counters::default()).unwrap();
            let (mut work, mut marked) = (vec![0.0; n], vec![false; analysis.supernodes().len()]);
            let single = ForwardColumns::from_columns(rows.iter().map(|row| sparse_forward_sweep(&factor, row, &mut work, &mut marked)));
            for chunk in [7, rows.len()] {
                let blocked = ForwardColumns::from_columns(rows.chunks(chunk).flat_map(|c| blocked_sweeps(&factor, c)));
                prop_assert_eq!(&blocked.column_start, &single.column_start);
                for (a, b) in blocked.segments.iter().zip(&single.segments) {
                    prop_assert_eq!((a.supernode, a.start, a.len), (b.supernode, b.start, b.len));
                    let (va, vb) = (blocked.segment_values(a), single.segment_values(b));
                    let scale = vb.iter().fold(1.0f64, |m, v| m.max(v.abs()));
                    for (x, y) in va.iter().zip(vb) {
                        prop_assert!((x - y).abs() <= 1e-13 * scale, "{x} against {y}");
                    }
                }
            }
            // W = Gᵀ G (from BLOCKED_FROM_COLUMNS on, formed by lower triangles): symmetric,
            // and its columns C K⁻¹ cᵢ by whole solves
            let m = rows.len();
            let w = ForwardColumns::new(&factor, &rows, &Counters::default()).gram();
            for q in [0, m / 2, m - 1] {
                let mut e = vec![0.0; n];
                for (d, c) in &rows[q] { e[*d] += c; }
                let mut x = e.clone();
                factor.solve_in_place(&mut x, &Counters::default());
                let column: Vec<f64> = rows.iter().map(|r| r.iter().map(|(d, c)| c * x[*d]).sum()).collect();
                let ours: Vec<f64> = (0..m).map(|p| w[p * m + q]).collect();
                let transposed: Vec<f64> = (0..m).map(|p| w[q * m + p]).collect();
                prop_assert_eq!(&ours, &transposed);
                prop_assert!(rel(&ours, &column) < 1e-12, "W column {q}: {:.1e}", rel(&ours, &column));
            }
        }
    }
}
