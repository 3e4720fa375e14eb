//! The rows of contact between two bodies (docs/method.md §18.2–18.3): the rows the contact
//! groups with a `target` get from their pairing — the mortar rows' directions, gaps and master
//! coefficients — and the tangential rows of tied pairs.

use crate::contact::friction::Friction;
use crate::contact::mortar::{self, MortarRow};
use crate::contact::pairing::SurfacePair;
use crate::contact::rows;

/// Turns the rows of the sections with a target into rows of contact between two bodies
/// (docs/method.md §18): direction −n (n the master's outward normal at the slave node's
/// projection), the mortar rows' weighted gap and master coefficients c_i (src/contact/mortar.rs),
/// or at the rim of the overlap the node-to-segment ones (g₀, N_i(ξ)); rows of slave nodes off
/// the target are removed (as never touching). Returns each remaining row's master coefficients.
pub(super) fn paired_rows<const D: usize>(
    rows: &mut rows::Rows<D>,
    pairs: &[Option<SurfacePair<D>>],
    points: &[[f64; D]],
    revolved: bool,
) -> Vec<Vec<(usize, f64)>> {
    let mortar: Vec<Option<Vec<Option<MortarRow>>>> = pairs
        .iter()
        .map(|p| p.as_ref().map(|p| mortar::rows(points, p, revolved)))
        .collect();
    let mut keep = vec![true; rows.nodes.len()];
    let mut terms = vec![Vec::new(); rows.nodes.len()];
    for r in 0..rows.nodes.len() {
        let (Some(pair), Some(mortar)) = (&pairs[rows.group[r]], &mortar[rows.group[r]]) else {
            continue;
        };
        let p = rows.nodes[r];
        let local = pair.slave.local(p);
        match local.and_then(|k| pair.projections[k].as_ref()) {
            Some(proj) => {
                rows.directions[r] = std::array::from_fn(|k| -proj.normal[k]);
                (rows.gap[r], terms[r]) = match local.and_then(|k| mortar[k].as_ref()) {
                    Some(row) => (row.gap, row.terms.clone()),
                    None => (proj.gap, proj.shape.clone()),
                };
            }
            None => {
                keep[r] = false;
                rows.never_touching.push((p, rows.group[r]));
            }
        }
    }
    retain(&mut rows.nodes, &keep);
    retain(&mut rows.weights, &keep);
    retain(&mut rows.directions, &keep);
    retain(&mut rows.group, &keep);
    retain(&mut rows.gap, &keep);
    retain(&mut rows.layer, &keep);
    retain(&mut rows.motion, &keep);
    retain(&mut rows.terms, &keep);
    retain(&mut rows.spread, &keep);
    retain(&mut terms, &keep);
    terms
}

/// The rows of tied pairs (docs/method.md §18.3): each normal row's gap set to zero (the slave
/// surface glued as it lies) and D − 1 rows along its tangents added, with the same master
/// coefficients; all of them are held bilaterally, so u_S = Σ c_i u_i in every direction.
pub(super) fn tied_rows<const D: usize>(
    rows: &mut rows::Rows<D>,
    master_terms: &mut Vec<Vec<(usize, f64)>>,
    tied: &[bool],
) {
    for r in 0..rows.nodes.len() {
        let g = rows.group[r];
        if !tied[g] {
            continue;
        }
        rows.gap[r] = 0.0;
        for t in Friction::<D>::tangents(rows.directions[r]) {
            rows.nodes.push(rows.nodes[r]);
            rows.weights.push(rows.weights[r]);
            rows.directions.push(t);
            rows.group.push(g);
            rows.gap.push(0.0);
            rows.layer.push(0.0);
            rows.motion.push(None);
            rows.terms.push(Vec::new());
            rows.spread.push(rows.spread[r].clone());
            master_terms.push(master_terms[r].clone());
        }
    }
}

/// Keeps the entries of `v` where `keep` is true.
fn retain<T>(v: &mut Vec<T>, keep: &[bool]) {
    let mut i = 0;
    v.retain(|_| {
        i += 1;
        keep[i - 1]
    });
}
