//! The reaction forces at the prescribed components (docs/method.md §7), serial and with a
//! backend that holds a share of the unknowns.

use super::columns::PrescribedColumns;
use super::setup::Simulation;
use crate::contact::ContactState;
use crate::fem::SymmetricMatrix;

/// What the reactions of a step are computed from: u_n, the memory displacements m_n^j (None at
/// step 0 or without memory), F_n and the contact state, over the held unknowns.
#[derive(Clone, Copy)]
pub(super) struct StepState<'a> {
    pub u: &'a [f64],
    pub memory: Option<&'a [f64]>,
    pub load: &'a [f64],
    pub contact: Option<&'a ContactState>,
}

/// The reaction forces at the prescribed components (docs/method.md §7):
/// R = K_A u_n + K_B m_n − F_n + Cᵀ λ at each prescribed unknown.
pub struct Reactions {
    /// K_A's and K_B's unmodified columns of the prescribed unknowns (the faer backend's; None:
    /// through the backend's products).
    pub(super) k_a: Option<PrescribedColumns>,
    /// One per memory channel (serial).
    k_b: Vec<PrescribedColumns>,
    /// Per reaction group: positions of its unknowns in the prescribed columns (serial), or in
    /// this process's vectors (only the unknowns it holds, with a backend).
    pub(super) groups: Vec<Vec<usize>>,
    pub(super) totals: Vec<f64>,
}

impl Reactions {
    /// The reactions from the prescribed columns of the unmodified K_A and K_j (taken before
    /// the factorisation, so that K_j need not be held, docs/method.md §9.3).
    pub(super) fn from_columns<const D: usize>(
        sim: &Simulation<D>,
        k_a: &SymmetricMatrix,
        k_b: &[SymmetricMatrix],
    ) -> Self {
        let k_a = PrescribedColumns::new(k_a, &sim.dofs);
        let position: std::collections::HashMap<usize, usize> =
            k_a.columns.iter().enumerate().map(|(k, (j, _))| (*j, k)).collect();
        let groups = sim
            .dirichlet
            .reaction_groups
            .iter()
            .map(|g| g.unknowns.iter().map(|d| position[d]).collect())
            .collect();
        Reactions {
            k_b: k_b.iter().map(|m| PrescribedColumns::new(m, &sim.dofs)).collect(),
            groups,
            totals: vec![0.0; sim.dirichlet.reaction_groups.len()],
            k_a: Some(k_a),
        }
    }

    /// The reactions through a backend's products, over the unknowns it holds (`unknowns`, its
    /// order; None: all of them in hvi's order), the group totals summed over all processes.
    pub fn over_products<const D: usize>(sim: &Simulation<D>, unknowns: Option<&[usize]>) -> Self {
        let position: Option<std::collections::HashMap<usize, usize>> =
            unknowns.map(|list| list.iter().enumerate().map(|(k, &d)| (d, k)).collect());
        let groups = sim
            .dirichlet
            .reaction_groups
            .iter()
            .map(|g| {
                g.unknowns
                    .iter()
                    .filter_map(|d| position.as_ref().map_or(Some(*d), |p| p.get(d).copied()))
                    .collect()
            })
            .collect();
        Reactions {
            k_a: None,
            k_b: Vec::new(),
            groups,
            totals: vec![0.0; sim.dirichlet.reaction_groups.len()],
        }
    }

    /// R from the stored prescribed columns.
    pub(super) fn through_columns<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        StepState {
            u,
            memory,
            load,
            contact,
        }: StepState,
    ) -> &[f64] {
        let Some(k_a) = &self.k_a else {
            return &self.totals;
        };
        let mut r = vec![0.0; k_a.columns.len()];
        k_a.add_product(u, &mut r);
        if let Some(m) = memory {
            for (kb, m) in self.k_b.iter().zip(m.chunks_exact(u.len())) {
                kb.add_product(m, &mut r);
            }
        }
        let mut force = vec![0.0; u.len()];
        if let (Some(c), Some(state)) = (&sim.contact, contact) {
            c.condensed_rows().add_forces(&state.force, &mut force);
        }
        for (rk, (j, _)) in r.iter_mut().zip(&k_a.columns) {
            *rk += force[*j] - load[*j];
        }
        for (total, members) in self.totals.iter_mut().zip(&self.groups) {
            *total = members.iter().map(|&k| r[k]).sum();
        }
        &self.totals
    }
}
