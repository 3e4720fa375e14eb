//! The degree-of-freedom map: D displacement components per node, unknown D·node + c for
//! component c of `node` (docs/method.md §7). Every component stays in the linear system; a
//! prescribed component (Dirichlet) is flagged here and its row and column of the step matrix
//! are replaced by the identity, so the matrices keep their D × D node blocks whatever is
//! prescribed.

/// Maps (node, component) to its unknown and knows which components are prescribed.
#[derive(Clone, Debug)]
pub struct DofMap<const D: usize> {
    prescribed: Vec<bool>,
    n_prescribed: usize,
}

impl<const D: usize> DofMap<D> {
    /// Every component of `n_nodes` nodes, those of `clamped` nodes prescribed (all components).
    pub fn new(n_nodes: usize, clamped: &[usize]) -> Self {
        let mut map = DofMap {
            prescribed: vec![false; D * n_nodes],
            n_prescribed: 0,
        };
        for &p in clamped {
            for c in 0..D {
                map.prescribe(p, c);
            }
        }
        map
    }

    /// Marks component `c` of `node` as prescribed.
    pub fn prescribe(&mut self, node: usize, c: usize) {
        let d = D * node + c;
        if !self.prescribed[d] {
            self.prescribed[d] = true;
            self.n_prescribed += 1;
        }
    }

    /// The unknown of component `c` of `node`, if it is free.
    #[inline]
    pub fn get(&self, node: usize, c: usize) -> Option<usize> {
        let d = D * node + c;
        (!self.prescribed[d]).then_some(d)
    }

    /// The unknown of component `c` of `node` (free or prescribed).
    #[inline]
    pub fn index(&self, node: usize, c: usize) -> usize {
        D * node + c
    }

    /// True if unknown `d` is prescribed.
    #[inline]
    pub fn is_prescribed(&self, d: usize) -> bool {
        self.prescribed[d]
    }

    /// The prescribed flags of all unknowns.
    pub fn prescribed(&self) -> &[bool] {
        &self.prescribed
    }

    /// Number of unknowns of the linear system (D per node, prescribed ones included).
    pub fn n(&self) -> usize {
        self.prescribed.len()
    }

    /// Number of free unknowns (what the user's problem has).
    pub fn n_free(&self) -> usize {
        self.prescribed.len() - self.n_prescribed
    }

    /// Number of prescribed components.
    pub fn n_prescribed(&self) -> usize {
        self.n_prescribed
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.prescribed.len() / D
    }

    /// The unknowns as nodal displacements.
    pub fn to_nodal(&self, u: &[f64]) -> Vec<[f64; D]> {
        u.chunks_exact(D)
            .map(|c| {
                let mut v = [0.0; D];
                v.copy_from_slice(c);
                v
            })
            .collect()
    }

    /// Nodal values as the vector of unknowns.
    pub fn from_nodal(&self, nodal: &[[f64; D]]) -> Vec<f64> {
        nodal.iter().flatten().copied().collect()
    }
}

impl<const D: usize> crate::linalg::sparse::Prescribed for DofMap<D> {
    fn is_prescribed(&self, i: usize) -> bool {
        self.prescribed[i]
    }
}
