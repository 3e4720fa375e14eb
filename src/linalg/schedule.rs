//! The triangular sweeps, sequential or on several threads.
//!
//! A sweep is bound by how fast L streams from memory, and one core does not saturate the
//! memory bus here (two sweeps in two processes run at the speed of one alone). The
//! parallel sweeps split the supernodal elimination tree into disjoint subtrees ("pieces")
//! and the supernodes above them ("top"):
//!
//! * forward: the pieces in parallel, each writing its own columns and accumulating its
//!   updates of top rows in a private vector; the private vectors are added in; then the top
//!   supernodes in order;
//! * backward: the top supernodes first; then the pieces in parallel, each reading the (now
//!   final) top rows from a shared copy and writing its own columns.
//!
//! The top supernodes are few and large (a fifth of L at n = 40): those of at least
//! [`SPLIT_MIN_ENTRIES`] entries run on two threads inside, by panels of columns, with the
//! same bits as on one (docs/method.md §9.8).
//!
//! Faer numbers supernodes in a postorder, so a subtree is a contiguous range of supernodes
//! and of columns: the pieces are disjoint slices of the vector, and safe Rust can hand each
//! to its own thread.

use super::supernodes::{backward_block, backward_block_split, forward_block, forward_block_split, Supernodes};
use rayon::prelude::*;
use std::ops::Range;

/// Below this many stored entries in L a sweep takes well under a millisecond and threads
/// cost more than they save.
const PARALLEL_MIN_ENTRIES: usize = 400_000;
/// Split until no piece holds more than this share of the work (work stealing evens out
/// the rest).
const PIECES: usize = 12;
/// Stop splitting when the top holds this share of the work.
const MAX_TOP_SHARE: f64 = 0.2;
/// Top supernodes of at least this many stored entries (2 MB) are swept on two threads
/// inside (supernodes.rs, `forward_block_split`): below it a panel's work nears the cost of
/// handing half of it to the other thread.
const SPLIT_MIN_ENTRIES: usize = 262_144;

/// A subtree of the supernodal elimination tree: supernodes `supernodes` (inclusive range
/// in postorder) owning the columns `columns`.
#[derive(Clone, Debug)]
struct Piece {
    supernodes: Range<usize>,
    columns: Range<usize>,
    entries: usize,
}

/// The split of the tree for parallel sweeps.
pub(super) struct Schedule {
    /// Ordered by their columns.
    pieces: Vec<Piece>,
    /// The supernodes above the pieces, ascending.
    top: Vec<usize>,
    /// The columns of the top supernodes, ascending.
    top_rows: Vec<usize>,
    /// For every column: its index in `top_rows`, or `u32::MAX` below the top.
    top_slot: Vec<u32>,
}

impl Schedule {
    /// Splits the tree, or `None` when L is too small to gain from threads or the tree does
    /// not split into at least two pieces.
    pub fn new(sn: &Supernodes) -> Option<Schedule> {
        let ns = sn.len();
        let mut subtree_entries = vec![0usize; ns];
        let mut subtree_first: Vec<usize> = (0..ns).collect();
        let mut subtree_count = vec![1usize; ns];
        let mut children = vec![Vec::new(); ns];
        let mut roots = Vec::new();
        for s in 0..ns {
            subtree_entries[s] += sn.entries(s);
            match sn.parent[s] {
                usize::MAX => roots.push(s),
                p => {
                    debug_assert!(p > s, "postorder: a parent comes after its children");
                    subtree_entries[p] += subtree_entries[s];
                    subtree_first[p] = subtree_first[p].min(subtree_first[s]);
                    subtree_count[p] += subtree_count[s];
                    children[p].push(s);
                }
            }
        }
        let total: usize = roots.iter().map(|&r| subtree_entries[r]).sum();
        if total < PARALLEL_MIN_ENTRIES {
            return None;
        }
        let mut frontier = roots;
        let mut top = Vec::new();
        let mut top_entries = 0;
        loop {
            let (k, &largest) = frontier.iter().enumerate().max_by_key(|(_, &s)| subtree_entries[s])?;
            if subtree_entries[largest] * PIECES <= total || top_entries as f64 > MAX_TOP_SHARE * total as f64 {
                break;
            }
            frontier.swap_remove(k);
            top.push(largest);
            top_entries += sn.entries(largest);
            frontier.extend(&children[largest]);
        }
        if frontier.len() < 2 {
            return None;
        }
        let mut pieces = Vec::with_capacity(frontier.len());
        for &root in &frontier {
            let first = subtree_first[root];
            if subtree_count[root] != root - first + 1 {
                return None; // not a postorder: keep the sequential sweeps
            }
            pieces.push(Piece {
                supernodes: first..root + 1,
                columns: sn.start[first]..sn.start[root] + sn.width[root],
                entries: subtree_entries[root],
            });
        }
        pieces.sort_by_key(|p| p.columns.start);
        // Adjacent small pieces that are whole trees of the forest (e.g. the thousands of 1 × 1
        // roots of decoupled prescribed components, factor.rs) become one: each piece costs a
        // task and a private vector over the top rows, and a whole tree updates no top row, so
        // merging them changes no arithmetic.
        let whole_tree = |p: &Piece| sn.parent[p.supernodes.end - 1] == usize::MAX;
        let mut merged: Vec<Piece> = Vec::with_capacity(pieces.len());
        for p in pieces {
            match merged.last_mut() {
                Some(q)
                    if whole_tree(q)
                        && whole_tree(&p)
                        && q.columns.end == p.columns.start
                        && q.supernodes.end == p.supernodes.start
                        && (q.entries + p.entries) * PIECES <= total =>
                {
                    q.columns.end = p.columns.end;
                    q.supernodes.end = p.supernodes.end;
                    q.entries += p.entries;
                }
                _ => merged.push(p),
            }
        }
        let pieces = merged;
        if pieces.len() < 2 {
            return None;
        }
        top.sort_unstable();
        let n = sn.supernode_of.len();
        let mut top_slot = vec![u32::MAX; n];
        let mut top_rows = Vec::new();
        for &s in &top {
            for (c, slot) in top_slot.iter_mut().enumerate().skip(sn.start[s]).take(sn.width[s]) {
                *slot = top_rows.len() as u32;
                top_rows.push(c);
            }
        }
        Some(Schedule {
            pieces,
            top,
            top_rows,
            top_slot,
        })
    }

    /// The pieces' slices of x, in the pieces' order.
    fn split<'x>(&self, mut x: &'x mut [f64]) -> Vec<(&Piece, &'x mut [f64])> {
        let mut offset = 0;
        let mut out = Vec::with_capacity(self.pieces.len());
        for piece in &self.pieces {
            let rest = std::mem::take(&mut x);
            let (_, rest) = rest.split_at_mut(piece.columns.start - offset);
            let (mine, rest) = rest.split_at_mut(piece.columns.len());
            out.push((piece, mine));
            x = rest;
            offset = piece.columns.end;
        }
        out
    }

    /// The pieces' supernodes (each a subtree: a contiguous range in postorder).
    pub fn piece_supernodes(&self) -> impl Iterator<Item = Range<usize>> + '_ {
        self.pieces.iter().map(|p| p.supernodes.clone())
    }

    /// The supernodes above the pieces, ascending.
    pub fn top(&self) -> &[usize] {
        &self.top
    }

    /// How many subtrees the sweeps run in parallel.
    #[cfg(test)]
    pub fn pieces(&self) -> usize {
        self.pieces.len()
    }

    /// The forward sweep y ← L⁻¹ y on the pieces in parallel, then the top.
    pub fn forward(&self, sn: &Supernodes, values: &[f64], y: &mut [f64]) {
        let n_top = self.top_rows.len();
        let mut work = self.split(y);
        work.sort_by_key(|(p, _)| std::cmp::Reverse(p.entries)); // largest first
        let updates: Vec<Vec<f64>> = work
            .into_par_iter()
            .map_init(
                || vec![0.0; sn.max_rows],
                |local, (piece, x)| {
                    let mut top = vec![0.0; n_top];
                    let (c0, c1) = (piece.columns.start, piece.columns.end);
                    for s in piece.supernodes.clone() {
                        let (width, start) = (sn.width[s], sn.start[s] - c0);
                        let t = &mut local[..sn.rows(s)];
                        t[..width].copy_from_slice(&x[start..start + width]);
                        t[width..].fill(0.0);
                        forward_block(sn.block(values, s), width, t);
                        x[start..start + width].copy_from_slice(&t[..width]);
                        for (&row, a) in sn.pattern(s).iter().zip(&t[width..]) {
                            if row < c1 {
                                x[row - c0] += a;
                            } else {
                                top[self.top_slot[row] as usize] += a;
                            }
                        }
                    }
                    top
                },
            )
            .collect();
        for update in &updates {
            for (&row, a) in self.top_rows.iter().zip(update) {
                y[row] += a;
            }
        }
        let mut local = vec![0.0; sn.max_rows];
        for &s in &self.top {
            forward_supernode_with(
                sn,
                values,
                s,
                y,
                &mut local,
                top_kernel(sn, s, forward_block, forward_block_split),
            );
        }
    }

    /// The backward sweep y ← L⁻ᵀ y: the top, then the pieces in parallel.
    pub fn backward(&self, sn: &Supernodes, values: &[f64], y: &mut [f64]) {
        let mut local = vec![0.0; sn.max_rows];
        for &s in self.top.iter().rev() {
            backward_supernode_with(
                sn,
                values,
                s,
                y,
                &mut local,
                top_kernel(sn, s, backward_block, backward_block_split),
            );
        }
        let shared: Vec<f64> = self.top_rows.iter().map(|&r| y[r]).collect();
        let mut work = self.split(y);
        work.sort_by_key(|(p, _)| std::cmp::Reverse(p.entries));
        work.into_par_iter().for_each_init(
            || vec![0.0; sn.max_rows],
            |local, (piece, x)| {
                let (c0, c1) = (piece.columns.start, piece.columns.end);
                for s in piece.supernodes.clone().rev() {
                    let (width, start) = (sn.width[s], sn.start[s] - c0);
                    let t = &mut local[..sn.rows(s)];
                    t[..width].copy_from_slice(&x[start..start + width]);
                    for (a, &row) in t[width..].iter_mut().zip(sn.pattern(s)) {
                        *a = if row < c1 {
                            x[row - c0]
                        } else {
                            shared[self.top_slot[row] as usize]
                        };
                    }
                    backward_block(sn.block(values, s), width, t);
                    x[start..start + width].copy_from_slice(&t[..width]);
                }
            },
        );
    }
}

/// A dense kernel of the sweeps (supernodes.rs).
type Kernel = fn(&[f64], usize, &mut [f64]);

/// The kernel for top supernode s: split between the threads from [`SPLIT_MIN_ENTRIES`] on.
fn top_kernel(sn: &Supernodes, s: usize, one: Kernel, split: Kernel) -> Kernel {
    if sn.entries(s) >= SPLIT_MIN_ENTRIES {
        split
    } else {
        one
    }
}

/// One supernode of the forward sweep on the whole vector.
#[inline]
pub(super) fn forward_supernode(sn: &Supernodes, values: &[f64], s: usize, x: &mut [f64], local: &mut [f64]) {
    forward_supernode_with(sn, values, s, x, local, forward_block)
}

/// [`forward_supernode`] with a given kernel.
#[inline]
fn forward_supernode_with(sn: &Supernodes, values: &[f64], s: usize, x: &mut [f64], local: &mut [f64], kernel: Kernel) {
    let (width, start) = (sn.width[s], sn.start[s]);
    let t = &mut local[..sn.rows(s)];
    t[..width].copy_from_slice(&x[start..start + width]);
    t[width..].fill(0.0);
    kernel(sn.block(values, s), width, t);
    x[start..start + width].copy_from_slice(&t[..width]);
    for (&row, a) in sn.pattern(s).iter().zip(&t[width..]) {
        x[row] += a;
    }
}

/// One supernode of the backward sweep on the whole vector.
#[inline]
pub(super) fn backward_supernode(sn: &Supernodes, values: &[f64], s: usize, x: &mut [f64], local: &mut [f64]) {
    backward_supernode_with(sn, values, s, x, local, backward_block)
}

/// [`backward_supernode`] with a given kernel.
#[inline]
fn backward_supernode_with(
    sn: &Supernodes,
    values: &[f64],
    s: usize,
    x: &mut [f64],
    local: &mut [f64],
    kernel: Kernel,
) {
    let (width, start) = (sn.width[s], sn.start[s]);
    let t = &mut local[..sn.rows(s)];
    t[..width].copy_from_slice(&x[start..start + width]);
    for (a, &row) in t[width..].iter_mut().zip(sn.pattern(s)) {
        *a = x[row];
    }
    kernel(sn.block(values, s), width, t);
    x[start..start + width].copy_from_slice(&t[..width]);
}

/// The whole forward sweep on one thread.
pub(super) fn forward_sequential(sn: &Supernodes, values: &[f64], y: &mut [f64]) {
    let mut local = vec![0.0; sn.max_rows];
    for s in 0..sn.len() {
        forward_supernode(sn, values, s, y, &mut local);
    }
}

/// The whole backward sweep on one thread.
pub(super) fn backward_sequential(sn: &Supernodes, values: &[f64], y: &mut [f64]) {
    let mut local = vec![0.0; sn.max_rows];
    for s in (0..sn.len()).rev() {
        backward_supernode(sn, values, s, y, &mut local);
    }
}
