//! The contact boundary Γ₃ as a dataset of its own (docs/method.md §12): its nodes (and only
//! those) as points, its facets as cells, indexed into those points, with the group each facet
//! and each node belongs to. Several contact groups go into one dataset; the group id (the
//! physical tag) tells them apart.

use crate::mesh::{BoundaryPart, Facet};

/// The points and facets of the contact dataset, built once per run.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactBoundary<const D: usize> {
    /// Mesh node index of each point, ascending and unique.
    pub nodes: Vec<usize>,
    /// The coordinates of the nodes.
    pub points: Vec<[f64; D]>,
    /// The facets, their node indices local (into `points`).
    pub facets: Vec<Facet>,
    /// The physical tag of each facet's group.
    pub facet_groups: Vec<i32>,
    /// The physical tag of each point's group (the first group, in the order given, that has
    /// the node).
    pub node_groups: Vec<i32>,
    /// The unit outward nodal normal of each point, as 3 components (z = 0 in 2D), from its
    /// group's facets.
    pub normals: Vec<f64>,
}

impl<const D: usize> ContactBoundary<D> {
    /// The dataset of the parts (physical tag, part), over the mesh's `points`.
    pub fn new(points: &[[f64; D]], parts: &[(i32, &BoundaryPart<D>)]) -> Self {
        let mut nodes: Vec<usize> = parts.iter().flat_map(|(_, p)| p.nodes.iter().copied()).collect();
        nodes.sort_unstable();
        nodes.dedup();
        let local = |p: usize| nodes.binary_search(&p).expect("a node of the parts");
        let mut node_groups = vec![0; nodes.len()];
        let mut normals = vec![0.0; 3 * nodes.len()];
        let mut seen = vec![false; nodes.len()];
        let mut facets = Vec::new();
        let mut facet_groups = Vec::new();
        for (tag, part) in parts {
            for (k, &p) in part.nodes.iter().enumerate() {
                let i = local(p);
                if !seen[i] {
                    seen[i] = true;
                    node_groups[i] = *tag;
                    normals[3 * i..3 * i + D].copy_from_slice(&part.normals[k]);
                }
            }
            for f in &part.facets {
                let l: Vec<usize> = f.nodes().iter().map(|&p| local(p)).collect();
                facets.push(Facet::with_corners(&l, f.corners().len()));
                facet_groups.push(*tag);
            }
        }
        ContactBoundary {
            points: nodes.iter().map(|&p| points[p]).collect(),
            nodes,
            facets,
            facet_groups,
            node_groups,
            normals,
        }
    }

    /// The point of mesh node `p`, if it is on the boundary.
    pub fn local(&self, p: usize) -> Option<usize> {
        self.nodes.binary_search(&p).ok()
    }
}
