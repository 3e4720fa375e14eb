//! Boundary parts: a curve group (Γ₁, Γ₂, Γ₃) as oriented facets with outward normals and
//! nodal quadrature weights.

use super::{fmt_point, Mesh, MeshError, PhysicalGroup};
use std::collections::HashMap;

/// A dimension-1 physical group as a part of the boundary of the body.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryPart {
    /// How messages name it, e.g. `Gamma3 (tag 3)`.
    pub label: String,
    /// The group's facets (duplicates removed), each oriented so that the body lies on its
    /// left, i.e. as the counter-clockwise edge of its cell: the outward unit normal of
    /// `[a, b]` is `(dy, −dx)/len` with `(dx, dy) = x_b − x_a`.
    pub facets: Vec<[usize; 2]>,
    /// Length of each facet.
    pub facet_lengths: Vec<f64>,
    /// Sorted unique node indices on the part.
    pub nodes: Vec<usize>,
    /// Per node of `nodes`: half the length of every adjacent facet of this part (the
    /// trapezoidal / nodal quadrature weight; they sum to the length of the part).
    pub weights: Vec<f64>,
    /// Per node of `nodes`: the normalised, length-weighted mean of the outward unit normals of
    /// the adjacent facets of this part. On a smooth curve meshed with smoothly varying facet
    /// lengths this is the curve's normal to O(h²); at a corner of the part it bisects.
    pub normals: Vec<[f64; 2]>,
}

impl BoundaryPart {
    /// Position of node index `p` in [`BoundaryPart::nodes`], if it is on the part.
    pub fn local(&self, p: usize) -> Option<usize> {
        self.nodes.binary_search(&p).ok()
    }

    /// The total length of the part.
    pub fn length(&self) -> f64 {
        self.facet_lengths.iter().sum()
    }
}

pub(crate) fn boundary_part(mesh: &Mesh, group: &PhysicalGroup) -> Result<BoundaryPart, MeshError> {
    let label = group.label();
    let pts = &mesh.points;
    let not_boundary = |detail: String| MeshError::NotBoundary {
        path: mesh.path.clone(),
        group: label.clone(),
        detail,
    };
    let key = |[a, b]: [usize; 2]| if a < b { (a, b) } else { (b, a) };

    // The group's facets, each once, in the group's order.
    let mut slot: HashMap<(usize, usize), usize> = HashMap::with_capacity(group.facets.len());
    let mut facets: Vec<[usize; 2]> = Vec::with_capacity(group.facets.len());
    for &f in &group.facets {
        if f[0] == f[1] || f[0] >= pts.len() || f[1] >= pts.len() {
            return Err(not_boundary(format!(
                "facet {f:?} is degenerate or refers to a node that does not exist"
            )));
        }
        slot.entry(key(f)).or_insert_with(|| {
            facets.push(f);
            facets.len() - 1
        });
    }
    if facets.is_empty() {
        return Err(not_boundary(
            "the group has no line elements; give it the boundary curves in the .geo (Physical Curve) and mesh again"
                .into(),
        ));
    }

    // Orient each facet like the counter-clockwise edge of its (single) cell.
    let as_given = facets.clone();
    let mut count = vec![0u32; facets.len()];
    for cell in &mesh.cells {
        for e in cell.edges() {
            if let Some(&k) = slot.get(&key(e)) {
                count[k] += 1;
                facets[k] = e;
            }
        }
    }
    let show = |f: [usize; 2]| format!("facet {}–{}", fmt_point(pts[f[0]]), fmt_point(pts[f[1]]));
    for (k, &c) in count.iter().enumerate() {
        match c {
            1 => {}
            0 => {
                return Err(not_boundary(format!(
                    "{} is not an edge of any cell; the group must be made of edges of the mesh on its boundary",
                    show(as_given[k])
                )))
            }
            _ => {
                return Err(not_boundary(format!(
                    "{} is shared by {} cells, so it is inside the body; a boundary part must be on the outer boundary \
                     (check the Physical Curve of this group in the .geo)",
                    show(as_given[k]),
                    if c == 2 { "two".to_string() } else { c.to_string() }
                )))
            }
        }
    }

    let facet_lengths: Vec<f64> = facets
        .iter()
        .map(|&[a, b]| (pts[b][0] - pts[a][0]).hypot(pts[b][1] - pts[a][1]))
        .collect();
    let mut nodes: Vec<usize> = facets.iter().flatten().copied().collect();
    nodes.sort_unstable();
    nodes.dedup();
    let mut weights = vec![0.0; nodes.len()];
    let mut sums = vec![[0.0; 2]; nodes.len()];
    for (&[a, b], &len) in facets.iter().zip(&facet_lengths) {
        // (dy, −dx) is the outward normal times the length.
        let n = [pts[b][1] - pts[a][1], -(pts[b][0] - pts[a][0])];
        for p in [a, b] {
            let i = nodes.binary_search(&p).unwrap_or(0);
            weights[i] += 0.5 * len;
            sums[i][0] += n[0];
            sums[i][1] += n[1];
        }
    }
    let mut normals = Vec::with_capacity(nodes.len());
    for (i, s) in sums.iter().enumerate() {
        let norm = s[0].hypot(s[1]);
        if norm.is_nan() || norm <= 1e-12 * weights[i] {
            return Err(not_boundary(format!(
                "at node {} the outward normals of its facets cancel: the part folds back on itself",
                fmt_point(pts[nodes[i]])
            )));
        }
        normals.push([s[0] / norm, s[1] / norm]);
    }
    Ok(BoundaryPart {
        label,
        facets,
        facet_lengths,
        nodes,
        weights,
        normals,
    })
}
