//! Rigid parameters in a step (docs/method.md §7.7): force-controlled groups and the pins of a
//! body held only by its contact. Each parameter a_i moves its unknowns (prescribed in the
//! factor, value 0) by a_i; the step finds the a that makes every parameter's total reaction
//! its force P_i(t), inside the contact solve, with the factor of K̃ and one stored response per
//! parameter:
//!
//! ```text
//!   v_i = K̃⁻¹ (lifting of e_i)                        once per factor (one solve each)
//!   K_a = [e_iᵀ K v_j],  D_a = C V,  S = D_aᵀ Q D_a + K_a  once per factor
//!   Q ← Q̂ = Q − Q D_a S⁺ D_aᵀ Q                        (a eliminated from the contact problem)
//!   per step: p̂ = P(t) − R⁰ (the reactions with a = 0, λ = 0, by dot products)
//!             q = Q̂ d + Q D_a S⁺ p̂  → contact solve → λ, r
//!             a = S⁺ ((Q D_a)ᵀ (r − d) + p̂),   u = K̃⁻¹(rhs − Cᵀλ) + V a
//! ```
//!
//! S⁺ is the inverse of S on the motions the contact or the stiffness holds; a load along a
//! motion nothing holds is an error naming it.

use super::columns::PrescribedColumns;
use super::error::SolveError;
use crate::contact::{Condensation, ContactNodes, NormalStiffness};
use crate::fem::DofMap;
use crate::linalg::dense::symmetrise_row_major;
use crate::linalg::{Counters, LinearSolver};

/// What a step operator keeps for its rigid parameters.
pub(super) struct RigidResponses {
    /// Each parameter's columns in `columns`.
    ranges: Vec<std::ops::Range<usize>>,
    /// v_i over all unknowns (1 at the parameter's unknowns, 0 at the other prescribed ones).
    v: Vec<Vec<f64>>,
    /// The unmodified step matrix's columns at every parameter's unknowns, parameter after
    /// parameter.
    columns: PrescribedColumns,
    /// S⁺, row-major k × k.
    s_plus: Vec<f64>,
    /// The motions nothing holds (unit vectors in a) and the name of each.
    unheld: Vec<(Vec<f64>, String)>,
    /// Q D_a, one column of m numbers per parameter (with contact).
    q_d: Vec<Vec<f64>>,
    /// a of the last step.
    values: Vec<f64>,
}

impl RigidResponses {
    /// The responses v_i with `solver` (K̃'s factor), K_a from `columns` (the unmodified
    /// matrix's columns at the parameters' unknowns), and with contact D_a, S and Q̂ written
    /// into the condensation's Q.
    pub(super) fn new<const D: usize>(
        parameters: &[super::dirichlet::RigidParameter],
        dofs: &DofMap<D>,
        columns: PrescribedColumns,
        solver: &dyn LinearSolver,
        condensed: Option<(&ContactNodes<D>, &mut Box<dyn Condensation>)>,
        counters: &Counters,
    ) -> Self {
        let k = parameters.len();
        let n = solver.n();
        // the columns hold the parameters' unknowns one parameter after the other
        let ranges: Vec<std::ops::Range<usize>> = parameters
            .iter()
            .scan(0, |start, p| {
                let range = *start..*start + p.unknowns.len();
                *start = range.end;
                Some(range)
            })
            .collect();
        // (K x)_d at every parameter's unknowns, summed per parameter
        let per_parameter = |x: &[f64]| -> Vec<f64> {
            let mut at = vec![0.0; columns.len()];
            columns.add_product(x, &mut at);
            ranges.iter().map(|r| at[r.clone()].iter().sum()).collect()
        };
        let mut v = Vec::with_capacity(k);
        let mut reference = Vec::with_capacity(k);
        for (i, p) in parameters.iter().enumerate() {
            let u = &p.unknowns;
            let mut e = vec![0.0; n];
            u.iter().for_each(|&d| e[d] = 1.0);
            reference.push(per_parameter(&e)[i].abs());
            // the lifting of e_i: rhs_f = −K_fP e_i, rhs_P = e_i
            let mut rhs = vec![0.0; n];
            columns.lift_unit(ranges[i].clone(), dofs, &mut rhs);
            u.iter().for_each(|&d| rhs[d] = 1.0);
            let mut x = vec![0.0; n];
            solver.solve(&rhs, &mut x, counters);
            v.push(x);
        }
        let mut s = vec![0.0; k * k];
        for (j, vj) in v.iter().enumerate() {
            for (i, kij) in per_parameter(vj).into_iter().enumerate() {
                s[i * k + j] = kij;
            }
        }
        let mut q_d = Vec::new();
        let mut condensed = condensed;
        if let Some((nodes, op)) = &mut condensed {
            let m = nodes.len();
            let d_a: Vec<Vec<f64>> = v
                .iter()
                .map(|vi| {
                    let mut col = vec![0.0; m];
                    nodes.normal_displacements(vi, &mut col);
                    col
                })
                .collect();
            q_d = d_a
                .iter()
                .map(|col| {
                    let mut y = vec![0.0; m];
                    op.stiffness().apply_q(col, &mut y);
                    y
                })
                .collect();
            for i in 0..k {
                for j in 0..k {
                    s[i * k + j] += d_a[i].iter().zip(&q_d[j]).map(|(a, b)| a * b).sum::<f64>();
                }
            }
        }
        // S symmetrised; its eigenvalues against the parameters' own stiffness tell what is held
        symmetrise_row_major(&mut s, k);
        let eigen = nalgebra::DMatrix::from_row_slice(k, k, &s).symmetric_eigen();
        let scale = reference.iter().fold(f64::MIN_POSITIVE, |a, &b| a.max(b));
        let mut s_plus = vec![0.0; k * k];
        let mut unheld = Vec::new();
        for (l, &value) in eigen.eigenvalues.iter().enumerate() {
            let u: Vec<f64> = eigen.eigenvectors.column(l).iter().copied().collect();
            if value > 1e-10 * scale {
                for i in 0..k {
                    for j in 0..k {
                        s_plus[i * k + j] += u[i] * u[j] / value;
                    }
                }
            } else {
                let main = (0..k).max_by(|&a, &b| u[a].abs().total_cmp(&u[b].abs())).unwrap_or(0);
                unheld.push((u, parameters[main].name.clone()));
            }
        }
        // Q̂ = Q − Q D_a S⁺ (Q D_a)ᵀ in the condensation (a eliminated, docs/method.md §7.7)
        if let Some((nodes, op)) = condensed {
            let m = nodes.len();
            op.stiffness_mut().q_inverts_w = false;
            let q = &mut op.stiffness_mut().q;
            // Y = Q D_a S⁺ (m × k), then Q −= Y (Q D_a)ᵀ
            let y: Vec<Vec<f64>> = (0..k)
                .map(|j| {
                    (0..m)
                        .map(|p| (0..k).map(|l| q_d[l][p] * s_plus[l * k + j]).sum())
                        .collect()
                })
                .collect();
            for p in 0..m {
                for r in 0..m {
                    q[p * m + r] -= (0..k).map(|j| y[j][p] * q_d[j][r]).sum::<f64>();
                }
            }
            symmetrise_row_major(q, m);
        }
        RigidResponses {
            ranges,
            v,
            columns,
            s_plus,
            unheld,
            q_d,
            values: vec![0.0; k],
        }
    }

    /// The step matrix is now `ratio` times the one the responses were made with (docs/method.md
    /// §20.3): v_i stay (the lifting of e_i scales with K), K_a, Q D_a and S scale with it.
    pub(super) fn rescale(&mut self, ratio: f64) {
        self.columns.scale(ratio);
        self.s_plus.iter_mut().for_each(|v| *v /= ratio);
        for col in &mut self.q_d {
            col.iter_mut().for_each(|v| *v *= ratio);
        }
    }

    /// k.
    fn k(&self) -> usize {
        self.v.len()
    }

    /// p̂ = P(t) − R⁰ with R⁰_i = −v_i·rhs + Σ_{d ∈ i} (K g)_d − f̃_i, the reactions with a = 0
    /// and no contact force: `rhs` lifted, `g` the prescribed values (None: 0), `loads` the
    /// unlifted f̃ summed over each parameter's unknowns (the time loop's `rigid_loads`). A load
    /// along a motion nothing holds is an error.
    pub(super) fn balance(
        &self,
        forces: &[f64],
        rhs: &[f64],
        g: Option<&[f64]>,
        loads: &[f64],
    ) -> Result<Vec<f64>, String> {
        let k = self.k();
        let mut kg = vec![0.0; self.columns.len()];
        if let Some(g) = g {
            self.columns.add_product(g, &mut kg);
        }
        let p: Vec<f64> = (0..k)
            .map(|i| {
                let r0 = -self.v[i].iter().zip(rhs).map(|(a, b)| a * b).sum::<f64>()
                    + kg[self.ranges[i].clone()].iter().sum::<f64>()
                    - loads[i];
                forces[i] - r0
            })
            .collect();
        let size = p.iter().chain(forces).chain(loads).fold(0.0f64, |a, b| a.max(b.abs()));
        for (u, name) in &self.unheld {
            let along: f64 = u.iter().zip(&p).map(|(a, b)| a * b).sum();
            if along.abs() > 1e-9 * size.max(f64::MIN_POSITIVE) {
                return Err(format!(
                    "the load pushes the body along a motion nothing holds ({name}: {along:.3e} unbalanced): the contact \
                     cannot take a force along it (frictionless contact takes none tangentially) and no component along \
                     it is prescribed; prescribe one ([[dirichlet]]), or change the load"
                ));
            }
        }
        Ok(p)
    }

    /// q = Q̂ d + Q D_a S⁺ p̂, the free contact force of the step with a eliminated, from
    /// `q_hat_d` = Q̂ d.
    pub(super) fn contact_load(&self, p: &[f64], q_hat_d: &mut [f64]) {
        let sp = self.times_s_plus(p);
        for (j, col) in self.q_d.iter().enumerate() {
            q_hat_d.iter_mut().zip(col).for_each(|(q, c)| *q += c * sp[j]);
        }
    }

    /// a = S⁺ ((Q D_a)ᵀ (r − d) + p̂) with contact, S⁺ p̂ without (`moved` = r − d or empty).
    pub(super) fn solve_values(&mut self, p: &[f64], moved: &[f64]) {
        let b: Vec<f64> = (0..self.k())
            .map(|i| {
                p[i] + if moved.is_empty() {
                    0.0
                } else {
                    self.q_d[i].iter().zip(moved).map(|(a, b)| a * b).sum::<f64>()
                }
            })
            .collect();
        self.values = self.times_s_plus(&b);
    }

    /// a of the last step.
    pub(super) fn values(&self) -> &[f64] {
        &self.values
    }

    /// u += V a.
    pub(super) fn add_motion(&self, u: &mut [f64]) {
        for (vi, &a) in self.v.iter().zip(&self.values) {
            if a != 0.0 {
                u.iter_mut().zip(vi).for_each(|(x, v)| *x += a * v);
            }
        }
    }

    fn times_s_plus(&self, x: &[f64]) -> Vec<f64> {
        let k = self.k();
        (0..k)
            .map(|i| (0..k).map(|j| self.s_plus[i * k + j] * x[j]).sum())
            .collect()
    }
}

/// The error of a step whose load a rigid parameter cannot balance.
pub(super) fn unbalanced(step: usize, time: f64, detail: String) -> SolveError {
    SolveError::Unbalanced { step, time, detail }
}
