//! The degree-of-freedom map: two displacement components per node, with the clamped
//! nodes of Γ₁ eliminated (u = 0 there), numbered node by node.

/// Sentinel for a constrained (eliminated) degree of freedom.
pub const CONSTRAINED: usize = usize::MAX;

/// Maps (node, component) to a free unknown, or [`CONSTRAINED`].
#[derive(Clone, Debug)]
pub struct DofMap {
    /// `dof[2 * node + c]` for component c ∈ {0, 1}.
    dof: Vec<usize>,
    n_free: usize,
}

impl DofMap {
    /// Numbers every component of every node not in `clamped` (sorted or not).
    pub fn new(n_nodes: usize, clamped: &[usize]) -> Self {
        let mut is_clamped = vec![false; n_nodes];
        for &p in clamped {
            is_clamped[p] = true;
        }
        let mut dof = vec![CONSTRAINED; 2 * n_nodes];
        let mut next = 0;
        for (p, &c) in is_clamped.iter().enumerate() {
            if !c {
                dof[2 * p] = next;
                dof[2 * p + 1] = next + 1;
                next += 2;
            }
        }
        DofMap { dof, n_free: next }
    }

    /// The unknown of component `c` of `node`, if free.
    #[inline]
    pub fn get(&self, node: usize, c: usize) -> Option<usize> {
        let d = self.dof[2 * node + c];
        (d != CONSTRAINED).then_some(d)
    }

    /// Raw index (possibly [`CONSTRAINED`]).
    #[inline]
    pub fn raw(&self, node: usize, c: usize) -> usize {
        self.dof[2 * node + c]
    }

    /// Number of free unknowns.
    pub fn n_free(&self) -> usize {
        self.n_free
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.dof.len() / 2
    }

    /// Expands a vector of free unknowns to nodal displacements (zero on Γ₁).
    pub fn to_nodal(&self, u: &[f64]) -> Vec<[f64; 2]> {
        (0..self.n_nodes())
            .map(|p| {
                let c = |k| self.get(p, k).map_or(0.0, |d| u[d]);
                [c(0), c(1)]
            })
            .collect()
    }

    /// Restricts nodal values to the free unknowns.
    pub fn from_nodal(&self, nodal: &[[f64; 2]]) -> Vec<f64> {
        let mut u = vec![0.0; self.n_free];
        for (p, v) in nodal.iter().enumerate() {
            for (c, vc) in v.iter().enumerate() {
                if let Some(d) = self.get(p, c) {
                    u[d] = *vc;
                }
            }
        }
        u
    }
}
