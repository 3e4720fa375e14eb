//! The partition of a mesh over the ranks (docs/method.md §13): METIS's parts of the node
//! graph, each rank's nodes numbered contiguously, each cell owned by the lowest rank among its
//! nodes.

use crate::mesh::Mesh;

/// The partition of the mesh nodes over the ranks.
#[derive(Clone, Debug)]
pub struct Partition {
    pub ranks: usize,
    /// Owning rank of each mesh node.
    pub owner: Vec<usize>,
    /// PETSc node number of each mesh node (rank r's nodes are offsets[r]..offsets[r + 1]).
    pub position: Vec<usize>,
    pub offsets: Vec<usize>,
    /// Owning rank of each cell: the lowest owner among its nodes.
    pub cell_owner: Vec<usize>,
}

impl Partition {
    /// The partition of given node owners (ascending mesh number within a rank).
    pub fn from_owners<const D: usize>(mesh: &Mesh<D>, ranks: usize, owner: Vec<usize>) -> Self {
        let mut offsets = vec![0; ranks + 1];
        for &o in &owner {
            offsets[o + 1] += 1;
        }
        for r in 0..ranks {
            offsets[r + 1] += offsets[r];
        }
        let mut next = offsets.clone();
        let position = owner
            .iter()
            .map(|&o| {
                next[o] += 1;
                next[o] - 1
            })
            .collect();
        let cell_owner = mesh
            .cells
            .iter()
            .map(|c| c.nodes().iter().map(|&p| owner[p]).min().unwrap_or(0))
            .collect();
        Partition {
            ranks,
            owner,
            position,
            offsets,
            cell_owner,
        }
    }

    /// METIS's k-way partition of the node graph into `ranks` parts (everything on rank 0 for
    /// one rank).
    pub fn metis<const D: usize>(mesh: &Mesh<D>, ranks: usize) -> Result<Vec<usize>, String> {
        let n = mesh.points.len();
        if ranks <= 1 || n == 0 {
            return Ok(vec![0; n]);
        }
        use metis_sys::idx_t;
        let mut adjacency: Vec<Vec<usize>> = vec![Vec::new(); n];
        for cell in &mesh.cells {
            let nodes = cell.nodes();
            for &a in nodes {
                adjacency[a].extend(nodes.iter().copied().filter(|&b| b != a));
            }
        }
        let mut xadj: Vec<idx_t> = Vec::with_capacity(n + 1);
        let mut adjncy: Vec<idx_t> = Vec::new();
        xadj.push(0);
        for a in adjacency.iter_mut() {
            a.sort_unstable();
            a.dedup();
            adjncy.extend(a.iter().map(|&b| b as idx_t));
            xadj.push(adjncy.len() as idx_t);
        }
        let mut options = [0 as idx_t; metis_sys::METIS_NOPTIONS as usize];
        let (mut nvtxs, mut ncon, mut nparts, mut cut) = (n as idx_t, 1 as idx_t, ranks as idx_t, 0 as idx_t);
        let mut part = vec![0 as idx_t; n];
        let _metis = crate::linalg::metis_lock();
        // SAFETY: CSR arrays of the sizes METIS expects; null optional weights; no other METIS
        // call runs (the lock).
        let status = unsafe {
            metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
            metis_sys::METIS_PartGraphKway(
                &mut nvtxs,
                &mut ncon,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                &mut nparts,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                &mut cut,
                part.as_mut_ptr(),
            )
        };
        if status != metis_sys::rstatus_et_METIS_OK {
            return Err(format!(
                "METIS could not partition the {n} mesh nodes into {ranks} parts (status {status})"
            ));
        }
        Ok(part.into_iter().map(|p| p as usize).collect())
    }

    /// Nodes owned by `rank`.
    pub fn nodes_of(&self, rank: usize) -> usize {
        self.offsets[rank + 1] - self.offsets[rank]
    }
}

impl Partition {
    /// The mesh nodes `rank` owns, in their PETSc order (ascending mesh number).
    pub fn nodes_owned_by(&self, rank: usize) -> Vec<usize> {
        let mut nodes = vec![0; self.nodes_of(rank)];
        for (p, (&o, &q)) in self.owner.iter().zip(&self.position).enumerate() {
            if o == rank {
                nodes[q - self.offsets[rank]] = p;
            }
        }
        nodes
    }

    /// The cells `rank` owns (assembles and writes), ascending.
    pub fn cells_owned_by(&self, rank: usize) -> Vec<usize> {
        (0..self.cell_owner.len())
            .filter(|&e| self.cell_owner[e] == rank)
            .collect()
    }
}
