//! The cached sparse Cholesky factor K = Pᵀ L Lᵀ P of a symmetric positive definite matrix
//! (docs/method.md §3): symbolic analysis with AMD ordering once, numeric factorisation once per
//! distinct matrix, and counted solves against it, whole or as separate forward and backward
//! sweeps.
//!
//! faer's high-level `Llt` solves only whole systems; the split sweeps and the sparse
//! forward sweeps of [`super::ForwardColumns`] need the supernodal factor itself, so this
//! module drives faer's mid-level API (`factorize_symbolic_cholesky`, the supernodal numeric
//! kernel), forcing the supernodal structure so that one code path serves every size; 3D factors
//! on several threads are factored by `numeric.rs` on the subtrees of the elimination tree
//! (docs/method.md §9.5). The factor is swept with the kernels of `supernodes.rs` on the
//! schedule of `schedule.rs`.
//!
//! Over 600 lines because the analysis, the numeric factorisation and the counted sweeps share one
//! supernodal structure and its invariants (the permutation, the contact-last ordering, the
//! supernodes' ranges); what can stand apart is in `numeric.rs`, `supernodes.rs` and `schedule.rs`.

use super::schedule::{backward_sequential, forward_sequential, forward_supernode, Schedule};
use super::sparse::SymmetricMatrix;
use super::supernodes::Supernodes;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::{Par, Side};
use rayon::prelude::*;
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

/// Parallelism for factorisation and solves. On 2 cores `Seq` measured faster (measured with faer 0.24 on 2 cores).
pub fn set_parallelism(threads: usize) {
    faer::set_global_parallelism(if threads <= 1 { Par::Seq } else { Par::rayon(threads) });
}

/// The symbolic analysis of a sparsity pattern: the fill-reducing permutation P, the
/// supernodal structure of L with its elimination tree, and the tree's split for parallel
/// sweeps.
#[derive(Clone)]
pub struct Analysis {
    inner: Arc<SymbolicCholesky<usize>>,
    ordering: NodeOrdering,
    supernodes: Arc<Supernodes>,
    /// The split of the elimination tree for parallel sweeps (None: sequential only).
    pub(super) schedule: Option<Arc<Schedule>>,
    /// How many unknowns were ordered after all others ([`Factor::analyse_with_last`]).
    ordered_last: usize,
    /// The unknowns whose column had no non-zero coupling (the identity rows of prescribed
    /// components, docs/method.md §7.2): left out of the factor's pattern and ordered first
    /// (empty: none). A matrix factored on this analysis must have no coupling there either.
    decoupled: Arc<Vec<bool>>,
}

impl Analysis {
    /// Number of stored entries of the factor L (what a numeric factorisation allocates).
    pub fn factor_entries(&self) -> usize {
        self.inner.len_val()
    }

    /// The fill-reducing permutation P as (forward, inverse): entry i of a permuted vector is
    /// entry `forward[i]` of the original.
    pub fn permutation(&self) -> (&[usize], &[usize]) {
        self.inner.perm().expect("hvi always orders").arrays()
    }

    /// The ordering used (for the plan and summary.json).
    pub fn ordering(&self) -> &'static str {
        match self.ordering {
            NodeOrdering::Amd => "AMD on the node graph",
            NodeOrdering::NestedDissection => "nested dissection (METIS) on the node graph",
        }
    }

    pub(super) fn supernodes(&self) -> &Supernodes {
        &self.supernodes
    }

    /// How many unknowns were ordered after all others.
    pub(super) fn ordered_last(&self) -> usize {
        self.ordered_last
    }
}

/// A right-hand side after the forward sweep, y = L⁻¹ P r: what the backward sweep takes and
/// what [`super::ForwardColumns`] acts on. Its entries are in the factor's (permuted) order.
pub struct Forward {
    pub(super) values: Vec<f64>,
}

impl Forward {
    /// A vector of `n` zeros, to be filled by [`Factor::forward_into`].
    pub fn zeros(n: usize) -> Self {
        Forward { values: vec![0.0; n] }
    }
}

/// A cached Cholesky factor K = Pᵀ L Lᵀ P.
pub struct Factor {
    analysis: Analysis,
    values: Vec<f64>,
    n: usize,
}

/// 3D node count from which only nested dissection is analysed (docs/method.md §9.1).
const ND_ONLY_NODES: usize = 10_000;

impl Factor {
    /// Symbolic analysis of the pattern of `matrix` (reusable for every matrix on it), with the
    /// ordering chosen by the measured rule (docs/method.md §9): AMD on the node graph in 2D
    /// (nested dissection gives no less fill there), and in 3D whichever of AMD and nested
    /// dissection gives the smaller factor (nested dissection, from a few thousand nodes on),
    /// nested dissection alone from 10 000 nodes on.
    pub fn analyse(matrix: &SymmetricMatrix) -> Result<Analysis, FactorError> {
        Self::analyse_with_last(matrix, &[])
    }

    /// [`Self::analyse`] with the unknowns `last` ordered after all others (in the given order).
    /// With the contact normals' unknowns last (docs/method.md §4.5), a column of G = L⁻¹PCᵀ is
    /// non-zero only in the trailing block of the factor, so G and W = GᵀG cost O(m³) dense work
    /// instead of m sparse sweeps through the whole elimination tree.
    pub fn analyse_with_last(matrix: &SymmetricMatrix, last: &[usize]) -> Result<Analysis, FactorError> {
        // 3D from 10 000 nodes on: nested dissection alone. It gave the smaller factor on every
        // 3D mesh measured (box 96x48x12: 192 M entries against AMD's 333 M), and AMD's
        // analysis took 0.6 s of the 11.7 s factorisation there (docs/method.md §9.1).
        let choices: &[NodeOrdering] = match matrix.pattern.block {
            3 if matrix.n() / 3 >= ND_ONLY_NODES => &[NodeOrdering::NestedDissection],
            3 => &[NodeOrdering::Amd, NodeOrdering::NestedDissection],
            _ => &[NodeOrdering::Amd],
        };
        let decoupling = Decoupling::of(matrix);
        let mut best: Option<Analysis> = None;
        for &ordering in choices {
            let Ok(a) = Self::analyse_ordered(matrix, ordering, last, &decoupling) else {
                continue;
            };
            if best.as_ref().is_none_or(|b| a.factor_entries() < b.factor_entries()) {
                best = Some(a);
            }
        }
        match best {
            Some(a) => Ok(a),
            None => Self::analyse_ordered(matrix, NodeOrdering::Amd, last, &decoupling),
        }
    }

    /// Symbolic analysis with a given ordering of the node graph.
    pub fn analyse_with(matrix: &SymmetricMatrix, ordering: NodeOrdering) -> Result<Analysis, FactorError> {
        Self::analyse_ordered(matrix, ordering, &[], &Decoupling::of(matrix))
    }

    fn analyse_ordered(
        matrix: &SymmetricMatrix,
        ordering: NodeOrdering,
        last: &[usize],
        decoupling: &Decoupling,
    ) -> Result<Analysis, FactorError> {
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let first = decoupling.pattern.as_ref().map(|_| &decoupling.decoupled[..]);
        let node_order = match ordering {
            NodeOrdering::Amd => amd_ordering(&matrix.pattern),
            NodeOrdering::NestedDissection => Some(
                nested_dissection(&matrix.pattern, first, last)
                    .ok_or_else(|| FactorError::Other("METIS NodeND failed".into()))?,
            ),
        };
        // The identity rows of prescribed components couple with nothing but their zeros: out of
        // the factor's pattern and first in the order they cost no fill (docs/method.md §9.1);
        // only with hvi's own node order (faer's fallback AMD orders the whole pattern).
        let decoupling = decoupling
            .pattern
            .as_ref()
            .filter(|_| node_order.is_some())
            .map(|p| (decoupling, p));
        let node_order = match node_order {
            Some((fwd, _)) if !last.is_empty() || decoupling.is_some() => {
                Some(reorder(&fwd, decoupling.map(|(d, _)| &d.decoupled[..]), last))
            }
            order => order,
        };
        let pattern = match decoupling {
            Some((_, (col_ptr, row_idx))) => {
                faer::sparse::SymbolicSparseColMatRef::new_checked(matrix.n(), matrix.n(), col_ptr, None, row_idx)
            }
            None => matrix.pattern.symbolic(),
        };
        let ordering_used = ordering;
        let ordering = match &node_order {
            Some((fwd, inv)) => SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(fwd, inv, matrix.n())),
            None => SymmetricOrdering::Amd,
        };
        let inner = factorize_symbolic_cholesky(pattern, Side::Lower, ordering, params)
            .map_err(|e| FactorError::Other(format!("{e:?}")))?;
        let supernodes = match inner.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => Supernodes::new(s),
            SymbolicCholeskyRaw::Simplicial(_) => {
                return Err(FactorError::Other("faer chose a simplicial factor".into()));
            }
        };
        Ok(Analysis {
            inner: Arc::new(inner),
            ordering: ordering_used,
            schedule: Schedule::new(&supernodes).map(Arc::new),
            supernodes: Arc::new(supernodes),
            ordered_last: last.len(),
            decoupled: decoupling.map_or_else(Default::default, |(d, _)| d.decoupled.clone()),
        })
    }

    /// Numeric factorisation of `matrix` with a symbolic analysis of its pattern.
    pub fn new(analysis: &Analysis, matrix: &SymmetricMatrix, counters: &Counters) -> Result<Self, FactorError> {
        let lower = PermutedLower::new(analysis, matrix)?;
        Self::from_permuted(analysis, lower, matrix.pattern.block, counters)
    }

    /// [`Self::new`] taking the matrix, which is dropped before the numeric factorisation
    /// allocates the factor: only the lower triangle of P K Pᵀ is held with L (docs/method.md
    /// §9.3; box 96x48x12: 211 MiB less at the run's peak).
    pub fn new_consuming(
        analysis: &Analysis,
        matrix: SymmetricMatrix,
        counters: &Counters,
    ) -> Result<Self, FactorError> {
        let lower = PermutedLower::new(analysis, &matrix)?;
        let block = matrix.pattern.block;
        drop(matrix);
        Self::from_permuted(analysis, lower, block, counters)
    }

    /// The numeric factorisation of P K Pᵀ (its lower triangle): hvi's tree-parallel kernel
    /// (numeric.rs) or faer's supernodal kernel called directly, since faer's whole-matrix
    /// entry point would make a permuted copy of its own next to the caller's matrix.
    fn from_permuted(
        analysis: &Analysis,
        lower: PermutedLower,
        block: usize,
        counters: &Counters,
    ) -> Result<Self, FactorError> {
        counters.factorisations.fetch_add(1, Ordering::Relaxed);
        let symbolic = &analysis.inner;
        let SymbolicCholeskyRaw::Supernodal(supernodal) = symbolic.raw() else {
            return Err(FactorError::Other("faer chose a simplicial factor".into()));
        };
        let mut values = Vec::new();
        // (a failure is this message, not the allocator's end of the process: src/alloc.rs)
        crate::alloc::fallible(|| values.try_reserve_exact(symbolic.len_val()))
            .map_err(|_| FactorError::Other(format!("out of memory for {} factor entries", symbolic.len_val())))?;
        // 3D factors have large dense supernodes and an elimination tree that splits into
        // subtrees: with more than one thread, hvi's left-looking kernel factors the subtrees in
        // parallel (numeric.rs, docs/method.md §9.5). Elsewhere faer's supernodal kernel, the
        // same method supernode after supernode, which is faster on one thread and bit for bit
        // what 2D runs had before.
        let threads = rayon::current_num_threads();
        let schedule = analysis.schedule.as_deref().filter(|_| block == 3 && threads > 1);
        let len = symbolic.len_val();
        match schedule {
            Some(schedule) => {
                // the first touch of the values' pages (their zeroing) on the threads: on this
                // machine's virtual memory, page faults cost 2–3 s of the n = 48 slab's 1.3 GB
                // sequentially and ≈ 1 s on two threads (docs/method.md §9.5)
                values.spare_capacity_mut()[..len]
                    .par_chunks_mut(1 << 18)
                    .for_each(|chunk| chunk.iter_mut().for_each(|v| _ = v.write(0.0)));
                // SAFETY: the first `len` entries were just written
                unsafe { values.set_len(len) };
                let lower = super::numeric::Lower {
                    col_ptr: &lower.col_ptr,
                    row_idx: &lower.row_idx,
                    values: &lower.values,
                };
                let sn = &analysis.supernodes;
                let updates = super::numeric::Updates::new(sn);
                super::numeric::factorize(sn, &updates, Some(schedule), &lower, &mut values, Par::rayon(threads))
                    .map_err(|_| FactorError::NotPositiveDefinite)?;
            }
            None => {
                values.resize(len, 0.0);
                // (3D on several threads without a split tree: faer's kernels on the threads)
                let par = if block == 3 && threads > 1 {
                    Par::rayon(threads)
                } else {
                    faer::get_global_parallelism()
                };
                let mut buffer =
                    MemBuffer::try_new(supernodal::factorize_supernodal_numeric_llt_scratch::<usize, f64>(
                        supernodal,
                        par,
                        Default::default(),
                    ))
                    .map_err(|e| FactorError::Other(format!("workspace: {e:?}")))?;
                let n = symbolic.nrows();
                let a = faer::sparse::SparseColMatRef::new(
                    faer::sparse::SymbolicSparseColMatRef::new_unsorted_checked(
                        n,
                        n,
                        &lower.col_ptr,
                        None,
                        &lower.row_idx,
                    ),
                    &lower.values,
                );
                supernodal::factorize_supernodal_numeric_llt::<usize, f64>(
                    &mut values,
                    a,
                    Default::default(),
                    supernodal,
                    par,
                    MemStack::new(&mut buffer),
                    Default::default(),
                )
                .map_err(|_: LltError| FactorError::NotPositiveDefinite)?;
            }
        }
        let n = symbolic.nrows();
        Ok(Factor {
            analysis: analysis.clone(),
            values,
            n,
        })
    }

    /// Order of the factored matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// L's values in the supernodes' blocks.
    pub(super) fn values(&self) -> &[f64] {
        &self.values
    }

    pub(super) fn analysis(&self) -> &Analysis {
        &self.analysis
    }

    /// P: entry i of a permuted vector is entry `permutation().0[i]` of the original, and
    /// original entry j sits at `permutation().1[j]`.
    fn permutation(&self) -> (&[usize], &[usize]) {
        self.analysis.permutation()
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
        let mut y = Forward {
            values: vec![0.0; self.n],
        };
        self.forward_into(rhs, &mut y);
        y
    }

    /// [`Self::forward`] into an existing vector (no allocation in a time loop).
    pub fn forward_into(&self, rhs: &[f64], y: &mut Forward) {
        let (fwd, _) = self.permutation();
        y.values.clear();
        y.values.extend(fwd.iter().map(|&i| rhs[i]));
        let sn = &self.analysis.supernodes;
        match self.parallel_schedule() {
            Some(schedule) => schedule.forward(sn, &self.values, &mut y.values),
            None => forward_sequential(sn, &self.values, &mut y.values),
        }
    }

    /// The backward sweep x = Pᵀ L⁻ᵀ y, completing one solve: K⁻¹ r = backward(forward(r)).
    pub fn backward(&self, mut y: Forward, x: &mut [f64], counters: &Counters) {
        self.backward_from(&mut y, x, counters);
    }

    /// [`Self::backward`] leaving y (overwritten) for reuse.
    pub fn backward_from(&self, y: &mut Forward, x: &mut [f64], counters: &Counters) {
        counters.solves.fetch_add(1, Ordering::Relaxed);
        let sn = &self.analysis.supernodes;
        match self.parallel_schedule() {
            Some(schedule) => schedule.backward(sn, &self.values, &mut y.values),
            None => backward_sequential(sn, &self.values, &mut y.values),
        }
        let (_, inv) = self.permutation();
        for (xi, &p) in x.iter_mut().zip(inv) {
            *xi = y.values[p];
        }
    }

    /// The split for parallel sweeps, when there is one and more than one thread to run it.
    fn parallel_schedule(&self) -> Option<&Schedule> {
        self.analysis
            .schedule
            .as_deref()
            .filter(|_| rayon::current_num_threads() > 1)
    }

    /// One supernode of the forward sweep (for the sparse sweeps of `ForwardColumns`).
    pub(super) fn forward_supernode(&self, s: usize, x: &mut [f64], local: &mut [f64]) {
        forward_supernode(&self.analysis.supernodes, &self.values, s, x, local)
    }
}

/// The lower triangle of P K Pᵀ in compressed columns (rows unsorted), what the supernodal
/// numeric factorisation reads.
struct PermutedLower {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

impl PermutedLower {
    /// Entry (i, j), i ≥ j, of K (full symmetric storage) goes to (max(p, q), min(p, q)) with
    /// p, q the factor's positions of i and j: the entries faer's own permutation reads, to the
    /// bit (the lower triangle of K in the original order).
    fn new(analysis: &Analysis, matrix: &SymmetricMatrix) -> Result<Self, FactorError> {
        let n = matrix.n();
        let (_, inv) = analysis.permutation();
        if inv.len() != n {
            return Err(FactorError::Other(format!(
                "the symbolic analysis is of order {}, the matrix {n}",
                inv.len()
            )));
        }
        let sym = matrix.pattern.symbolic();
        let (cp, ri) = (sym.col_ptr(), sym.row_idx());
        let decoupled = &analysis.decoupled[..];
        // entries the analysis left out: the couplings of a decoupled unknown
        let out = |i: usize, j: usize| i != j && !decoupled.is_empty() && (decoupled[i] || decoupled[j]);
        let mut col_ptr = vec![0usize; n + 1];
        for j in 0..n {
            for (&i, &v) in ri[cp[j]..cp[j + 1]].iter().zip(&matrix.values[cp[j]..cp[j + 1]]) {
                if i >= j {
                    if out(i, j) {
                        if v != 0.0 {
                            return Err(FactorError::Other(format!(
                                "entry ({i}, {j}) = {v:e} couples an unknown the symbolic analysis found decoupled"
                            )));
                        }
                        continue;
                    }
                    col_ptr[inv[i].min(inv[j]) + 1] += 1;
                }
            }
        }
        for q in 0..n {
            col_ptr[q + 1] += col_ptr[q];
        }
        let nnz = col_ptr[n];
        let mut next = col_ptr[..n].to_vec();
        let (mut row_idx, mut values) = (vec![0usize; nnz], vec![0.0; nnz]);
        for j in 0..n {
            for k in cp[j]..cp[j + 1] {
                let i = ri[k];
                if i >= j && !out(i, j) {
                    let (p, q) = (inv[i], inv[j]);
                    let (row, col) = (p.max(q), p.min(q));
                    row_idx[next[col]] = row;
                    values[next[col]] = matrix.values[k];
                    next[col] += 1;
                }
            }
        }
        Ok(PermutedLower {
            col_ptr,
            row_idx,
            values,
        })
    }
}

/// A fill-reducing ordering of the node graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeOrdering {
    /// Approximate minimum degree (faer).
    Amd,
    /// Nested dissection (METIS_NodeND, vendored METIS 5).
    NestedDissection,
}

/// The unknowns whose column holds no non-zero off the diagonal (in a stiffness matrix: the
/// identity rows of prescribed components, docs/method.md §7.2) and the matrix's pattern without
/// their couplings; found once per matrix for every ordering tried.
struct Decoupling {
    decoupled: Arc<Vec<bool>>,
    /// (col_ptr, row_idx) of the pattern without the couplings; None if no unknown is decoupled.
    pattern: Option<(Vec<usize>, Vec<usize>)>,
}

impl Decoupling {
    fn of(matrix: &SymmetricMatrix) -> Self {
        let decoupled = decoupled_unknowns(matrix);
        let pattern = decoupled
            .iter()
            .any(|&b| b)
            .then(|| without_couplings(matrix, &decoupled));
        Decoupling {
            decoupled: Arc::new(decoupled),
            pattern,
        }
    }
}

/// The unknowns the factor decouples (docs/method.md §9.1): those whose column holds nothing
/// but zeros off the diagonal (a prescribed component's identity row). Their couplings are left
/// out of the factor's pattern and they are ordered first.
pub fn decoupled_unknowns(matrix: &SymmetricMatrix) -> Vec<bool> {
    let sym = matrix.pattern.symbolic();
    let (cp, ri) = (sym.col_ptr(), sym.row_idx());
    (0..matrix.n())
        .map(|j| (cp[j]..cp[j + 1]).all(|k| ri[k] == j || matrix.values[k] == 0.0))
        .collect()
}

/// The pattern of `matrix` (full storage) without the couplings of the `decoupled` unknowns
/// (their diagonal kept): (col_ptr, row_idx).
fn without_couplings(matrix: &SymmetricMatrix, decoupled: &[bool]) -> (Vec<usize>, Vec<usize>) {
    let sym = matrix.pattern.symbolic();
    let (cp, ri) = (sym.col_ptr(), sym.row_idx());
    let mut col_ptr = Vec::with_capacity(matrix.n() + 1);
    let mut row_idx = Vec::with_capacity(ri.len());
    col_ptr.push(0);
    for j in 0..matrix.n() {
        row_idx.extend(
            ri[cp[j]..cp[j + 1]]
                .iter()
                .copied()
                .filter(|&i| i == j || !(decoupled[i] || decoupled[j])),
        );
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}

/// The ordering `fwd` (new → old) with the `first` unknowns (if given) moved to the front and
/// the unknowns of `last` to the end, in their order.
fn reorder(fwd: &[usize], first: Option<&[bool]>, last: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut is_last = vec![false; fwd.len()];
    for &i in last {
        is_last[i] = true;
    }
    let is_first = |i: usize| first.is_some_and(|f| f[i]) && !is_last[i];
    let mut out: Vec<usize> = fwd.iter().copied().filter(|&i| is_first(i)).collect();
    out.extend(fwd.iter().copied().filter(|&i| !is_last[i] && !is_first(i)));
    out.extend_from_slice(last);
    let mut inv = vec![0; out.len()];
    for (k, &i) in out.iter().enumerate() {
        inv[i] = k;
    }
    (out, inv)
}

/// A node ordering (fwd: new → old node) expanded to the D unknowns of each node, kept together.
fn expand(fwd: &[usize], d: usize) -> (Vec<usize>, Vec<usize>) {
    let dof_fwd: Vec<usize> = fwd.iter().flat_map(|&k| (0..d).map(move |c| d * k + c)).collect();
    let mut dof_inv = vec![0; dof_fwd.len()];
    for (i, &p) in dof_fwd.iter().enumerate() {
        dof_inv[p] = i;
    }
    (dof_fwd, dof_inv)
}

/// Nested dissection of the node graph by METIS (written by hand only as the unsafe call: the
/// `metis` crate wraps partitioning but not NodeND), expanded to the unknowns.
///
/// Each node weighs what it puts into the ordered part of the factor (docs/method.md §9.1):
/// its unknowns that are neither decoupled (`first`) nor ordered `last`. Nodes that weigh
/// nothing (fully clamped) are left out of METIS's graph and put first; a contact node whose
/// normal goes last weighs D − 1, as in the graph of the unknowns CHOLMOD's METIS orders.
fn nested_dissection(
    pattern: &super::sparse::Pattern,
    first: Option<&[bool]>,
    last: &[usize],
) -> Option<(Vec<usize>, Vec<usize>)> {
    use metis_sys::idx_t;
    let d = pattern.block;
    let graph = pattern.node_graph();
    let mut weight = vec![d as idx_t; graph.len()];
    let mut lighten = |i: usize| weight[i / d] -= 1;
    if let Some(first) = first {
        first
            .iter()
            .enumerate()
            .filter(|(_, &f)| f)
            .for_each(|(i, _)| lighten(i));
    }
    last.iter()
        .filter(|&&i| !first.is_some_and(|f| f[i]))
        .for_each(|&i| lighten(i));
    // METIS's vertices: the nodes that weigh something, renumbered.
    let kept: Vec<usize> = (0..graph.len()).filter(|&k| weight[k] > 0).collect();
    let mut local = vec![idx_t::MAX; graph.len()];
    for (v, &k) in kept.iter().enumerate() {
        local[k] = v as idx_t;
    }
    let n = kept.len();
    if n == 0 || n > idx_t::MAX as usize || graph.nodes.len() > idx_t::MAX as usize {
        return None;
    }
    // METIS wants the adjacency without self loops.
    let mut xadj: Vec<idx_t> = Vec::with_capacity(n + 1);
    let mut adjncy: Vec<idx_t> = Vec::with_capacity(graph.nodes.len());
    let mut vwgt: Vec<idx_t> = kept.iter().map(|&k| weight[k]).collect();
    xadj.push(0);
    for &k in &kept {
        adjncy.extend(
            graph
                .coupled(k)
                .iter()
                .filter(|&&q| q != k && local[q] != idx_t::MAX)
                .map(|&q| local[q]),
        );
        xadj.push(adjncy.len() as idx_t);
    }
    let mut nvtxs = n as idx_t;
    let (mut perm, mut iperm) = (vec![0 as idx_t; n], vec![0 as idx_t; n]);
    let mut options = [0 as idx_t; metis_sys::METIS_NOPTIONS as usize];
    let _metis = super::metis_lock();
    // SAFETY: every array has the length METIS reads or writes: options METIS_NOPTIONS, xadj
    // n + 1, adjncy xadj[n], vwgt, perm and iperm n; no other METIS call runs (the lock).
    let status = unsafe {
        metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        metis_sys::METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            vwgt.as_mut_ptr(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return None;
    }
    // Row i of the permuted matrix is row perm[i] of the original: perm is faer's forward array.
    let fwd: Vec<usize> = (0..graph.len())
        .filter(|&k| weight[k] == 0)
        .chain(perm.iter().map(|&p| kept[p as usize]))
        .collect();
    Some(expand(&fwd, d))
}

/// AMD on the node graph of the pattern, expanded to the D unknowns of each node, kept
/// together: a graph D² times smaller to order, and supernodes that never split a node.
fn amd_ordering(pattern: &super::sparse::Pattern) -> Option<(Vec<usize>, Vec<usize>)> {
    let d = pattern.block;
    let n = pattern.n;
    let graph = pattern.node_graph();
    if graph.is_empty() {
        return None;
    }
    let n_nodes = graph.len();
    let nodes = faer::sparse::SymbolicSparseColMatRef::new_checked(n_nodes, n_nodes, &graph.ptr, None, &graph.nodes);
    let (mut fwd, mut inv) = (vec![0usize; n_nodes], vec![0usize; n_nodes]);
    let mut buffer = MemBuffer::try_new(faer::sparse::linalg::amd::order_scratch::<usize>(
        n_nodes,
        graph.nodes.len(),
    ))
    .ok()?;
    faer::sparse::linalg::amd::order(
        &mut fwd,
        &mut inv,
        nodes,
        Default::default(),
        MemStack::new(&mut buffer),
    )
    .ok()?;
    let _ = n;
    Some(expand(&fwd, d))
}

#[cfg(test)]
mod schedule_tests {
    //! The parallel sweeps of `schedule.rs` against the sequential ones on a factor large
    //! enough to be split.
    use super::super::sparse::test_matrices::{grid_stiffness, relative_difference};
    use super::*;

    #[test]
    fn parallel_sweeps_agree_with_sequential_sweeps() {
        for quads in [true, false] {
            let k = grid_stiffness(96, 48, quads);
            let analysis = Factor::analyse(&k).unwrap();
            let schedule = analysis.schedule.as_deref().expect("a factor this size is split");
            assert!(schedule.pieces() >= 2);
            let factor = Factor::new(&analysis, &k, &Counters::default()).unwrap();
            let (sn, values) = (analysis.supernodes(), factor.values());
            let r: Vec<f64> = (0..k.n())
                .map(|i| ((i as f64) * 0.618_033_988_7).fract() - 0.5)
                .collect();
            let (mut serial, mut parallel) = (r.clone(), r.clone());
            forward_sequential(sn, values, &mut serial);
            schedule.forward(sn, values, &mut parallel);
            // Only the order of the additions into top rows differs: round-off.
            let diff = relative_difference(&parallel, &serial);
            assert!(diff <= 1e-13, "forward: {diff:e}");
            backward_sequential(sn, values, &mut serial);
            schedule.backward(sn, values, &mut parallel);
            let diff = relative_difference(&parallel, &serial);
            assert!(diff <= 1e-12, "backward: {diff:e}");
            // and the solve is a solve: K x = r
            let mut x = r.clone();
            factor.solve_in_place(&mut x, &Counters::default());
            let mut kx = vec![0.0; k.n()];
            k.matvec(&x, &mut kx);
            let residual = kx.iter().zip(&r).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(residual < 1e-9, "residual {residual:e}");
        }
    }
}

#[cfg(test)]
mod numeric_tests {
    //! hvi's left-looking kernel (numeric.rs), sequential and on the tree's pieces, against
    //! faer's supernodal kernel on the same analysis.
    use super::super::numeric::{factorize, Lower, Updates};
    use super::super::sparse::test_matrices::{grid_stiffness, relative_difference};
    use super::*;

    fn ours(analysis: &Analysis, k: &SymmetricMatrix, schedule: Option<&Schedule>, par: Par) -> Result<Vec<f64>, ()> {
        let lower = PermutedLower::new(analysis, k).unwrap();
        let lower = Lower {
            col_ptr: &lower.col_ptr,
            row_idx: &lower.row_idx,
            values: &lower.values,
        };
        let sn = &analysis.supernodes;
        let mut values = vec![0.0; analysis.factor_entries()];
        factorize(sn, &Updates::new(sn), schedule, &lower, &mut values, par).map_err(|_| ())?;
        Ok(values)
    }

    #[test]
    fn the_tree_parallel_kernel_gives_faers_factor() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for quads in [true, false] {
            // 2D, so that Factor::new runs faer's kernel: the reference
            let k = grid_stiffness(96, 48, quads);
            let analysis = Factor::analyse(&k).unwrap();
            let schedule = analysis.schedule.as_deref().expect("a factor this size is split");
            let faer = Factor::new(&analysis, &k, &Counters::default()).unwrap();
            let sequential = ours(&analysis, &k, None, Par::Seq).unwrap();
            let parallel = pool
                .install(|| ours(&analysis, &k, Some(schedule), Par::rayon(2)))
                .unwrap();
            // the same products, summed in another order: round-off
            for (what, values) in [("sequential", &sequential), ("parallel", &parallel)] {
                let diff = relative_difference(values, faer.values());
                assert!(diff <= 1e-13, "{what} (quads {quads}): {diff:e}");
            }
        }
    }

    #[test]
    fn the_tree_parallel_kernel_refuses_a_matrix_that_is_not_positive_definite() {
        let mut k = grid_stiffness(96, 48, true);
        let analysis = Factor::analyse(&k).unwrap();
        let schedule = analysis.schedule.as_deref().unwrap();
        // a diagonal entry of a free unknown made negative, in a piece or in the top
        for i in [k.n() / 2 + 1, k.n() - 1] {
            assert!(!(i / 2).is_multiple_of(97), "a free unknown");
            let sym = k.pattern.symbolic();
            let at = (sym.col_ptr()[i]..sym.col_ptr()[i + 1])
                .find(|&p| sym.row_idx()[p] == i)
                .unwrap();
            let saved = k.values[at];
            k.values[at] = -1.0;
            let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
            assert!(pool
                .install(|| ours(&analysis, &k, Some(schedule), Par::rayon(2)))
                .is_err());
            assert!(ours(&analysis, &k, None, Par::Seq).is_err());
            k.values[at] = saved;
        }
    }
}
