//! The numeric supernodal Cholesky factorisation, left-looking, on the subtrees of the
//! elimination tree in parallel (docs/method.md §9.5).
//!
//! Supernode s gathers its columns of P K Pᵀ, subtracts the updates of the supernodes below it
//! whose pattern reaches its columns (its descendants), then factors its diagonal block and
//! solves for the rows below. A supernode reads only its descendants, which lie in its own
//! subtree: the pieces of the sweeps' [`Schedule`] (disjoint subtrees, each a contiguous range
//! of supernodes and of values) are factored on separate threads with sequential dense
//! kernels, then the supernodes above them in order with the dense kernels on all threads.
//! faer's supernodal kernel (the same method) runs the supernodes one after another and
//! parallelises only inside each dense operation, which on this machine's two cores gained
//! nothing (box 80 × 40 × 10: 3.1 s on one core, 3.0–3.5 s on two).

use super::schedule::Schedule;
use super::supernodes::Supernodes;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltError};
use faer::linalg::matmul::matmul;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::ops::Range;

/// The lower triangle of P K Pᵀ in compressed columns (rows unsorted; entries above the
/// diagonal, if any, are skipped).
pub(super) struct Lower<'a> {
    pub col_ptr: &'a [usize],
    pub row_idx: &'a [usize],
    pub values: &'a [f64],
}

/// For each supernode, the supernodes below it whose pattern holds one of its columns, in
/// compressed rows (ascending).
pub(super) struct Updates {
    ptr: Vec<usize>,
    from: Vec<usize>,
}

impl Updates {
    pub fn new(sn: &Supernodes) -> Self {
        let ns = sn.len();
        // each d updates the distinct supernodes of its pattern's rows (ascending, grouped)
        let targets = |d: usize| {
            let mut last = usize::MAX;
            sn.pattern(d).iter().filter_map(move |&row| {
                let s = sn.supernode_of[row];
                (s != last).then(|| {
                    last = s;
                    s
                })
            })
        };
        let mut ptr = vec![0usize; ns + 1];
        for d in 0..ns {
            for s in targets(d) {
                ptr[s + 1] += 1;
            }
        }
        for s in 0..ns {
            ptr[s + 1] += ptr[s];
        }
        let mut next = ptr.clone();
        let mut from = vec![0usize; ptr[ns]];
        for d in 0..ns {
            for s in targets(d) {
                from[next[s]] = d;
                next[s] += 1;
            }
        }
        Updates { ptr, from }
    }

    fn of(&self, s: usize) -> &[usize] {
        &self.from[self.ptr[s]..self.ptr[s + 1]]
    }
}

/// A non-positive pivot (the matrix is not positive definite).
#[derive(Debug)]
pub(super) struct NotPositiveDefinite;

/// Per-thread workspace: the map from a row of L to its row in the current supernode's block,
/// the dense product of one update, the row map of that update, and the dense kernels' stack.
struct Work {
    local: Vec<usize>,
    product: Vec<f64>,
    rows: Vec<usize>,
    stack: MemBuffer,
}

impl Work {
    fn new(n: usize, max_width: usize, par: Par) -> Self {
        Work {
            local: vec![usize::MAX; n],
            product: Vec::new(),
            rows: Vec::new(),
            stack: MemBuffer::new(cholesky_in_place_scratch::<f64>(max_width, par, Default::default())),
        }
    }
}

/// Factors P K Pᵀ = L Lᵀ into `values` (faer's supernodal layout, zeroed by the caller).
/// With a schedule and threads, in three phases:
/// 1. the pieces (disjoint subtrees) on the threads, each supernode whole, kernels sequential;
/// 2. the supernodes above them (the top), on the threads: each gathers its columns of the
///    matrix and the updates of its descendants in the pieces, which are final;
/// 3. the top in order: the updates of its descendants in the top, and its factorisation, with
///    the dense kernels on all threads (these are the separators' large blocks).
///
/// Without, every supernode in order (phase 3 with all descendants).
pub(super) fn factorize(
    sn: &Supernodes,
    updates: &Updates,
    schedule: Option<&Schedule>,
    lower: &Lower,
    values: &mut [f64],
    par: Par,
) -> Result<(), NotPositiveDefinite> {
    let n = sn.supernode_of.len();
    let max_width = sn.width.iter().copied().max().unwrap_or(0);
    let Some(schedule) = schedule.filter(|_| par.degree() > 1) else {
        let mut work = Work::new(n, max_width, par);
        return in_order(
            sn,
            updates,
            Some(lower),
            0..sn.len(),
            |_| true,
            (values, 0),
            &mut work,
            par,
        );
    };
    let top = schedule.top();
    let mut in_top = vec![false; sn.len()];
    top.iter().for_each(|&s| in_top[s] = true);
    // 1. the pieces: a piece's values are consecutive, and its supernodes read only each other
    let mut pieces = Vec::new();
    let mut tail: &mut [f64] = values;
    let mut taken = 0;
    for piece in schedule.piece_supernodes() {
        let (base, end) = (
            sn.value_start[piece.start],
            sn.value_start[piece.end - 1] + sn.entries(piece.end - 1),
        );
        let (_, after) = std::mem::take(&mut tail).split_at_mut(base - taken);
        let (mine, after) = after.split_at_mut(end - base);
        pieces.push((piece, (mine, base)));
        tail = after;
        taken = end;
    }
    pieces.into_par_iter().try_for_each_init(
        || Work::new(n, max_width, Par::Seq),
        |work, (piece, values)| in_order(sn, updates, Some(lower), piece, |_| true, values, work, Par::Seq),
    )?;
    // each supernode's block, apart
    let mut blocks: Vec<&mut [f64]> = Vec::with_capacity(sn.len());
    let mut tail: &mut [f64] = values;
    for s in 0..sn.len() {
        let (block, rest) = std::mem::take(&mut tail).split_at_mut(sn.entries(s));
        blocks.push(block);
        tail = rest;
    }
    // 2. the top gathers the pieces' updates, in slices of its supernodes' columns on the
    //    threads (an update writes only the columns of the rows it is made of)
    type Blocks<'v> = Vec<(usize, &'v mut [f64])>;
    let (finished, gathering): (Blocks, Blocks) = blocks.into_iter().enumerate().partition(|(s, _)| !in_top[*s]);
    let mut finished_of: Vec<&[f64]> = vec![&[]; sn.len()];
    for (s, block) in finished {
        finished_of[s] = block;
    }
    let mut slices: Vec<(usize, Range<usize>, &mut [f64])> = Vec::new();
    for (s, block) in gathering {
        let (rows, width) = (sn.rows(s), sn.width[s]);
        let step = GATHER_COLUMNS.min(width).max(1);
        for (k, columns) in block.chunks_mut(step * rows).enumerate() {
            let first = k * step;
            slices.push((s, first..first + columns.len() / rows, columns));
        }
    }
    slices.into_par_iter().for_each_init(
        || Work::new(n, max_width, Par::Seq),
        |work, (s, columns, block)| {
            work.enter(sn, s);
            assemble(sn, lower, s, (&mut *block, columns.clone()), work);
            for &d in updates.of(s).iter().filter(|&&d| !in_top[d]) {
                update(sn, s, (&mut *block, columns.clone()), d, finished_of[d], work, Par::Seq);
            }
            work.leave(sn, s);
        },
    );
    drop(finished_of);
    // 3. the top in order
    let mut work = Work::new(n, max_width, par);
    in_order(
        sn,
        updates,
        None,
        top.iter().copied(),
        |d| in_top[d],
        (values, 0),
        &mut work,
        par,
    )
}

/// The supernodes `supernodes` in order, each: its columns of `lower` (if given, else gathered
/// already), the updates of its descendants d with `from(d)`, its factorisation. `values` holds
/// the factor's values from value `base` on (a piece's, or all of them), the supernodes' blocks
/// and their descendants' among them.
#[allow(clippy::too_many_arguments)]
fn in_order(
    sn: &Supernodes,
    updates: &Updates,
    lower: Option<&Lower>,
    supernodes: impl Iterator<Item = usize>,
    from: impl Fn(usize) -> bool,
    (values, base): (&mut [f64], usize),
    work: &mut Work,
    par: Par,
) -> Result<(), NotPositiveDefinite> {
    for s in supernodes {
        let (head, tail) = values.split_at_mut(sn.value_start[s] - base);
        let block = &mut tail[..sn.entries(s)];
        work.enter(sn, s);
        if let Some(lower) = lower {
            assemble(sn, lower, s, (block, 0..sn.width[s]), work);
        }
        for &d in updates.of(s).iter().filter(|&&d| from(d)) {
            let columns = (&mut *block, 0..sn.width[s]);
            update(sn, s, columns, d, &head[sn.value_start[d] - base..], work, par);
        }
        work.leave(sn, s);
        factor(sn, s, block, work, par)?;
    }
    Ok(())
}

impl Work {
    /// Maps the pattern of s to its rows in the block of s.
    fn enter(&mut self, sn: &Supernodes, s: usize) {
        for (i, &row) in sn.pattern(s).iter().enumerate() {
            self.local[row] = sn.width[s] + i;
        }
    }

    fn leave(&mut self, sn: &Supernodes, s: usize) {
        for &row in sn.pattern(s) {
            self.local[row] = usize::MAX;
        }
    }
}

/// Adds the matrix's columns `columns` (local to s) of supernode s to `block`, which holds
/// those columns of its block (the pattern entered in `work`).
fn assemble(sn: &Supernodes, lower: &Lower, s: usize, (block, columns): (&mut [f64], Range<usize>), work: &Work) {
    let (start, end, rows) = (sn.start[s], sn.start[s] + sn.width[s], sn.rows(s));
    for j in start + columns.start..start + columns.end {
        let column = &mut block[(j - start - columns.start) * rows..(j - start - columns.start + 1) * rows];
        for k in lower.col_ptr[j]..lower.col_ptr[j + 1] {
            let i = lower.row_idx[k];
            if i < j {
                continue;
            }
            let at = if i < end { i - start } else { work.local[i] };
            column[at] += lower.values[k];
        }
    }
}

/// Subtracts descendant d's update from the columns `columns` (local to s) of the block of s,
/// whose first column is s's column `columns.start` (`block` holds those columns only):
/// L_s −= L_d[rows ≥ column] L_d[rows of those columns]ᵀ, `d_block` starting at d's values
/// (the pattern of s entered in `work`).
///
/// The columns go in slices of at most [`UPDATE_COLUMNS`], so that the dense product of a
/// separator's update stays a few MiB (whole, it was tens of MiB per thread).
#[allow(clippy::too_many_arguments)]
fn update(
    sn: &Supernodes,
    s: usize,
    (block, columns): (&mut [f64], Range<usize>),
    d: usize,
    d_block: &[f64],
    work: &mut Work,
    par: Par,
) {
    let rows = sn.rows(s);
    let one = OneUpdate { sn, s, d, d_block, par };
    let mut first = columns.start;
    for slice in block.chunks_mut(UPDATE_COLUMNS * rows) {
        let last = first + slice.len() / rows;
        one.apply(slice, first..last, work);
        first = last;
    }
}

/// Descendant d's update of supernode s, applied a slice of s's columns at a time.
struct OneUpdate<'a> {
    sn: &'a Supernodes,
    s: usize,
    d: usize,
    d_block: &'a [f64],
    par: Par,
}

impl OneUpdate<'_> {
    /// [`update`] on the columns `columns` of s, held by `block`.
    fn apply(&self, block: &mut [f64], columns: Range<usize>, work: &mut Work) {
        let OneUpdate { sn, s, d, d_block, par } = *self;
        let (start, rows) = (sn.start[s], sn.rows(s));
        let d_pattern = sn.pattern(d);
        // d's rows from the first of these columns on, and how many of them are these columns
        let first = d_pattern.partition_point(|&r| r < start + columns.start);
        let mid = d_pattern[first..].partition_point(|&r| r < start + columns.end);
        if mid == 0 {
            return;
        }
        let (d_width, d_rows) = (sn.width[d], sn.rows(d));
        let below = d_pattern.len() - first;
        let d_block = &d_block[..d_rows * d_width];
        work.rows.clear();
        let local = &work.local;
        let end = start + sn.width[s];
        work.rows.extend(
            d_pattern[first..]
                .iter()
                .map(|&r| if r < end { r - start } else { local[r] }),
        );
        let column_of = |j: usize| (work.rows[j] - columns.start) * rows;
        if below * mid * d_width <= SMALL_UPDATE {
            // a few numbers: straight loops beat a dense product's set-up
            let at = |k: usize, i: usize| d_block[k * d_rows + d_width + first + i];
            for j in 0..mid {
                let column = column_of(j);
                for i in j..below {
                    let sum: f64 = (0..d_width).map(|k| at(k, i) * at(k, j)).sum();
                    block[column + work.rows[i]] -= sum;
                }
            }
            return;
        }
        let d_below = MatRef::from_column_major_slice_with_stride(&d_block[d_width + first..], below, d_width, d_rows);
        let d_mid = d_below.subrows(0, mid);
        if work.product.len() < below * mid {
            work.product.resize(below * mid, 0.0);
        }
        let product = &mut work.product[..below * mid];
        let par = if below * mid * d_width > PARALLEL_UPDATE {
            par
        } else {
            Par::Seq
        };
        matmul(
            MatMut::from_column_major_slice_mut(product, below, mid),
            Accum::Replace,
            d_below,
            d_mid.transpose(),
            1.0,
            par,
        );
        // scattered by runs of rows that are adjacent in both blocks (a node's D rows, a
        // supernode's columns): slices the compiler vectorises
        for j in 0..mid {
            let column = &mut block[column_of(j)..column_of(j) + rows];
            let product = &product[j * below..(j + 1) * below];
            let mut i = j;
            while i < below {
                let (from, to) = (i, work.rows[i]);
                i += 1;
                while i < below && work.rows[i] == to + (i - from) {
                    i += 1;
                }
                column[to..to + (i - from)]
                    .iter_mut()
                    .zip(&product[from..i])
                    .for_each(|(c, p)| *c -= p);
            }
        }
    }
}

/// Factors the diagonal block of s and solves for the rows below it.
fn factor(sn: &Supernodes, s: usize, block: &mut [f64], work: &mut Work, par: Par) -> Result<(), NotPositiveDefinite> {
    let (rows, width) = (sn.rows(s), sn.width[s]);
    let l = MatMut::from_column_major_slice_mut(block, rows, width);
    let (mut diagonal, below) = l.split_at_row_mut(width);
    cholesky_in_place(
        diagonal.rb_mut(),
        Default::default(),
        par,
        MemStack::new(&mut work.stack),
        Default::default(),
    )
    .map_err(|_: LltError| NotPositiveDefinite)?;
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(diagonal.rb(), below.transpose_mut(), par);
    Ok(())
}

/// Columns of s one dense product of an update covers at most.
const UPDATE_COLUMNS: usize = 256;
/// Columns of a top supernode gathered by one task in phase 2.
const GATHER_COLUMNS: usize = 64;
/// Updates of more than this many multiply-adds run their product on all threads (above the
/// pieces; faer's own threshold for its supernodal updates).
const PARALLEL_UPDATE: usize = 32 * 32 * 32;
/// Updates of at most this many multiply-adds are summed in plain loops.
const SMALL_UPDATE: usize = 512;
