//! The reaction forces at the prescribed components (docs/method.md §7), serial and with a
//! backend that holds a share of the unknowns.

use super::backend::{Backend, Stiffness};
use super::setup::Simulation;
use super::step::PrescribedColumns;
use crate::contact::active_set::ContactState;
use crate::fem::SymmetricMatrix;

/// The reaction forces at the prescribed components (docs/method.md §7):
/// R = K_A u_n + K_B m_n − F_n + Cᵀ λ at each prescribed unknown.
pub(super) struct Reactions {
    /// K_A's and K_B's unmodified columns of the prescribed unknowns (serial; with a backend,
    /// its products).
    k_a: Option<PrescribedColumns>,
    /// One per memory channel (serial).
    k_b: Vec<PrescribedColumns>,
    /// Per reaction group: positions of its unknowns in the prescribed columns (serial), or in
    /// this process's vectors (only the unknowns it holds, with a backend).
    groups: Vec<Vec<usize>>,
    totals: Vec<f64>,
}

impl Reactions {
    pub(super) fn new<const D: usize>(sim: &Simulation<D>, k_a: &SymmetricMatrix, k_b: &[SymmetricMatrix]) -> Self {
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

    /// The reactions of the unknowns a backend holds (`unknowns`, its order).
    pub(super) fn held<const D: usize>(sim: &Simulation<D>, unknowns: &[usize]) -> Self {
        let position: std::collections::HashMap<usize, usize> =
            unknowns.iter().enumerate().map(|(k, &d)| (d, k)).collect();
        let groups = sim
            .dirichlet
            .reaction_groups
            .iter()
            .map(|g| g.unknowns.iter().filter_map(|d| position.get(d).copied()).collect())
            .collect();
        Reactions {
            k_a: None,
            k_b: Vec::new(),
            groups,
            totals: vec![0.0; sim.dirichlet.reaction_groups.len()],
        }
    }

    /// [`Reactions::compute`] with a backend: R over the unknowns this process holds, the
    /// group totals summed over all processes (collective).
    pub(super) fn compute_held<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        backend: &dyn Backend<D>,
        u: &[f64],
        memory: Option<&[f64]>,
        load: &[f64],
        contact: Option<&ContactState>,
    ) -> &[f64] {
        let unknowns = backend.unknowns();
        let mut r = vec![0.0; u.len()];
        backend.product(sim, Stiffness::Elastic, u, &mut r);
        if let Some(m) = memory {
            let mut y = vec![0.0; u.len()];
            backend.product(sim, Stiffness::Memory, m, &mut y);
            r.iter_mut().zip(&y).for_each(|(a, b)| *a += b);
        }
        // Cᵀλ at the prescribed unknowns: the prescribed parts of the contact rows.
        let mut force: std::collections::HashMap<usize, f64> = std::collections::HashMap::new();
        if let (Some(c), Some(state)) = (&sim.contact, contact) {
            for (l, fixed) in state.force.iter().zip(c.nodes.prescribed_rows()) {
                for &(d, coefficient) in fixed {
                    *force.entry(d).or_insert(0.0) += l * coefficient;
                }
            }
        }
        for (total, members) in self.totals.iter_mut().zip(&self.groups) {
            *total = members
                .iter()
                .map(|&k| r[k] + force.get(&unknowns[k]).copied().unwrap_or(0.0) - load[k])
                .sum();
        }
        backend.sum(&mut self.totals);
        &self.totals
    }

    pub(super) fn compute<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        u: &[f64],
        memory: Option<&[f64]>,
        load: &[f64],
        contact: Option<&ContactState>,
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
            c.nodes.add_forces(&state.force, &mut force);
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
