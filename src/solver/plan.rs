//! The plan of a run: which effects are in force and what each costs. `hvi check` prints it
//! and `summary.json` records the effect names, so "not in the scene" is visibly "not built".

use super::setup::Simulation;
use std::fmt;

/// One effect of a scene and its cost.
#[derive(Clone, Debug)]
pub struct Effect {
    pub name: &'static str,
    pub detail: String,
    pub cost: String,
}

/// The effects a simulation will compute.
#[derive(Clone, Debug)]
pub struct Plan {
    pub effects: Vec<Effect>,
    pub factorisations: Factorisations,
    pub solves_per_step: usize,
}

/// How many step matrices a run factorises (docs/method.md §20.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Factorisations {
    /// Every step matrix is a multiple of K_A: one factorisation, whatever the steps.
    Proportional,
    /// A fixed grid: its distinct step matrices after step 0, the factorisations the run makes
    /// of them, and whether step 0 may need K_A's own (a loaded step 0 with memory).
    Counted {
        distinct: usize,
        built: usize,
        step_zero: bool,
    },
    /// Automatic steps: one per distinct size met (held on the ladder k₁ 2^j).
    PerSize,
}

/// The materials: the 2D model, and per material E, ν and the formulation (its name first when
/// there are several).
fn elasticity_detail<const D: usize>(sim: &Simulation<D>) -> String {
    let model = match sim.materials.plane() {
        Some(crate::material::PlaneModel::Stress) => "2D, plane stress",
        Some(crate::material::PlaneModel::Strain) => "2D, plane strain",
        Some(crate::material::PlaneModel::Axisymmetric) => "2D, axisymmetric (x = r, y = z)",
        None => "3D",
    };
    let several = sim.materials.list().len() > 1;
    let counts = sim.materials.cell_counts(sim.mesh.cells.len());
    let parts: Vec<String> = sim
        .materials
        .list()
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let mine: Vec<&crate::mesh::Cell> = (0..sim.mesh.cells.len())
                .filter(|&c| sim.materials.id_of_cell(c).index() == i)
                .map(|c| &sim.mesh.cells[c])
                .collect();
            let by_cell = mine.iter().filter(|c| m.volumetric.cell_mean(c)).count();
            let by_node = mine.len() - by_cell;
            format!(
                "{}E = {}, ν = {}{}{}",
                if several {
                    format!("{} ({} cells): ", m.name, counts[i])
                } else {
                    String::new()
                },
                m.elasticity.youngs_modulus,
                m.elasticity.poisson_ratio,
                if m.memory.as_ref().is_some_and(|m| m.is_from_relaxation_modulus()) {
                    " (instantaneous: A = G(0) of the relaxation modulus)"
                } else {
                    ""
                },
                match m.volumetric {
                    crate::fem::assembly::Volumetric::Mean => format!(
                        "; mean dilatation (docs/method.md §8.4): per cell (B-bar) on {by_cell}, over patches of \
                         cells on {by_node} triangles or tetrahedra (each patch joins the matrix as one cell)",
                    ),
                    crate::fem::assembly::Volumetric::Pointwise => String::new(),
                }
            )
        })
        .collect();
    format!("{model}, {}", parts.join("; "))
}

impl Plan {
    /// The plan of `sim`.
    pub fn new<const D: usize>(sim: &Simulation<D>) -> Self {
        let n = sim.dofs.n_free();
        let mut effects = vec![Effect {
            name: "elasticity",
            detail: elasticity_detail(sim),
            cost: format!("K_A assembled once ({n} unknowns), factorised once"),
        }];
        if sim.dirichlet.is_nonzero() {
            effects.push(Effect {
                name: "dirichlet",
                detail: format!(
                    "{} prescribed components in {} (group, component) pairs, {}",
                    sim.dirichlet.len(),
                    sim.dirichlet.reaction_groups.len(),
                    if sim.dirichlet.is_time_dependent() {
                        "values depend on t"
                    } else {
                        "non-zero values, constant in time"
                    }
                ),
                cost: "identity rows in K; the prescribed part moves to the right-hand side (lifting) every step"
                    .into(),
            });
        }
        let forced: Vec<&str> = sim
            .dirichlet
            .rigid
            .iter()
            .filter(|p| p.group.is_some())
            .map(|p| p.name.as_str())
            .collect();
        if !forced.is_empty() || !sim.dirichlet.held_by_contact.is_empty() {
            let k = sim.dirichlet.rigid.len();
            let mut parts = Vec::new();
            if !forced.is_empty() {
                parts.push(format!("force control of {}", forced.join(", ")));
            }
            if !sim.dirichlet.held_by_contact.is_empty() {
                parts.push(format!(
                    "held by the contact alone: {} ({} pinned component(s) whose reaction the step makes zero)",
                    sim.dirichlet.held_by_contact.join(", "),
                    k - forced.len()
                ));
            }
            effects.push(Effect {
                name: "rigid",
                detail: parts.join("; "),
                cost: format!(
                    "{k} stored response(s) (one solve each, once per factor) and a {k} × {k} system; the motions \
                     join each step's contact solve (docs/method.md §7.7)"
                ),
            });
        }
        let mut solves_per_step = 1;
        if let Some(memory) = sim.materials.memory() {
            // the accumulated atoms of all kernels: one vector per distinct relaxation time and
            // per monomial degree, every step's displacement for a general kernel (§5, §15)
            let mut taus: Vec<f64> = Vec::new();
            let (mut degree, mut direct) = (0, false);
            for t in memory.terms() {
                match &t.kernel {
                    crate::material::RelaxationKernel::Polynomial { coefficients } => {
                        degree = degree.max(coefficients.len())
                    }
                    crate::material::RelaxationKernel::Exponentials { terms } => {
                        for (_, tau) in terms {
                            if !taus.contains(tau) {
                                taus.push(*tau);
                            }
                        }
                    }
                    crate::material::RelaxationKernel::General { .. } => direct = true,
                }
            }
            let levels = sim.time.steps().map_or(0, |n| n + 1);
            let vectors = taus.len() + degree + 1 + if direct { levels } else { 0 };
            let rule = |q: crate::material::Quadrature| match q {
                crate::material::Quadrature::Exact => " (exact for u linear over each step)",
                crate::material::Quadrature::Trapezoid => " (trapezoid)",
            };
            let exponential = format!("recursive exponential sums{}", rule(sim.rules.exponential));
            let polynomial = format!("recursive polynomial moments{}", rule(sim.rules.polynomial));
            let algo: Vec<&str> = [
                (!taus.is_empty()).then_some(exponential.as_str()),
                (degree > 0).then_some(polynomial.as_str()),
                direct.then_some("direct sum (trapezoid; every step's displacement kept)"),
            ]
            .into_iter()
            .flatten()
            .collect();
            let algo = algo.join(" + ");
            let j = memory.channels().len();
            let d = sim.materials.plane().map_or(3, |_| 2);
            let several = sim.materials.list().len() > 1;
            let mut described = Vec::new();
            for m in sim.materials.list() {
                let Some(own) = &m.memory else { continue };
                let trapezoid = sim.rules == crate::material::Rules::TRAPEZOID;
                let bound = match own.largest_stable_step(m.elasticity.tensor(), d).filter(|_| trapezoid) {
                    Some(k_max) => format!(
                        "; b(0) < 0: K positive definite for k < {k_max:.4e} (here k ≤ {:.4e})",
                        sim.time.largest_step()
                    ),
                    None => String::new(),
                };
                let name = if several {
                    format!("{}: ", m.name)
                } else {
                    String::new()
                };
                described.push(format!("{name}{}{bound}", own.describe()));
            }
            effects.push(Effect {
                name: "memory",
                detail: described.join("; "),
                cost: format!(
                    "{j} K_B matri{} assembled once; history by {algo}: {vectors} vectors of {n} unknowns ({:.1} MiB), {j} K_B product(s) per step",
                    if j == 1 { "x" } else { "ces" },
                    (vectors * n * 8) as f64 / 1048576.0
                ),
            });
        }
        if !sim.loads.is_empty() {
            effects.push(Effect {
                name: "loads",
                detail: if sim.loads.is_time_dependent() {
                    "time-dependent".into()
                } else {
                    "constant in time".into()
                },
                cost: if sim.loads.is_time_dependent() {
                    "load vector re-evaluated every step".into()
                } else {
                    "load vector assembled once".into()
                },
            });
        }
        if let Some(c) = &sim.contact {
            let m = c.nodes.len();
            let mut parts = Vec::new();
            let bilateral = c.bilateral.as_ref().map_or(0, |b| b.iter().filter(|&&v| v).count());
            if bilateral > 0 {
                parts.push(format!(
                    "bilateral u_ν = 0 on {bilateral} nodes (a normal force of either sign, docs/method.md §17.4)"
                ));
            }
            if let Some(g) = c.bound.as_ref().filter(|_| bilateral < m) {
                let (lo, hi) = g
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
                if lo == hi || g.is_empty() {
                    parts.push(format!("bound u_ν ≤ g (g = {})", g.first().copied().unwrap_or(0.0)));
                } else {
                    parts.push(format!("bound u_ν ≤ g (g from {lo} to {hi} at the nodes)"));
                }
            }
            for l in c.laws.used() {
                parts.push(format!(
                    "{} compliance law, S = {}, {}, ε = {:e}",
                    match l.symmetry {
                        crate::contact::Symmetry::Odd => "odd",
                        crate::contact::Symmetry::OneSided => "one-sided",
                    },
                    l.scale,
                    l.profile.describe(),
                    l.epsilon
                ));
            }
            effects.push(Effect {
                name: "contact",
                detail: format!(
                    "{} on {m} nodes ({} Γ₃ node(s) also clamped, set aside)",
                    parts.join(" + "),
                    c.nodes.clamped_nodes.len()
                ),
                cost: match sim.condensation {
                    crate::scene::CondensationKind::SplitSweeps if sim.trailing_block() => format!(
                        "condensation off the factor's trailing block: its {m} contact unknowns ordered last, Q = T⁻ᵀ L_cc L_ccᵀ T⁻¹ once{} ({:.1} MiB dense); per step one dense active-set solve of size {m} and two triangular solves with L_cc between the forward and backward sweeps of the step's one solve",
                        if sim.forms_w_off_trailing_block() { " and W = T L_cc⁻ᵀ L_cc⁻¹ Tᵀ" } else { "" },
                        ((2 + usize::from(sim.forms_w_off_trailing_block())) * m * m * 8) as f64 / 1048576.0
                    ),
                    crate::scene::CondensationKind::SplitSweeps => format!(
                        "condensation by split sweeps: G = L⁻¹ P Cᵀ ({m} sparse forward sweeps{}) and W = Gᵀ G once, {:.1} MiB dense; per step one dense active-set solve of size {m} between the forward and backward sweeps of the step's one solve",
                        if m >= crate::linalg::BLOCKED_FROM_COLUMNS { ", blocked" } else { "" },
                        (2 * m * m * 8) as f64 / 1048576.0
                    ),
                    crate::scene::CondensationKind::StoredResponses => format!(
                        "condensation by stored responses: Z = K⁻¹ Cᵀ ({m} solves, {:.1} MiB) and W = C Z once; per step one whole solve, a dense active-set solve of size {m} and u = u_free − Z λ",
                        (n * m * 8) as f64 / 1048576.0
                    ),
                    crate::scene::CondensationKind::RecoverySolve => format!(
                        "condensation by a recovery solve: Z = K⁻¹ Cᵀ ({m} solves, {:.1} MiB while W = C Z is formed); per step a free solve, a dense active-set solve of size {m} and a recovery solve",
                        (n * m * 8) as f64 / 1048576.0
                    ),
                },
            });
        }
        if let Some(f) = sim.contact.as_ref().and_then(|c| c.friction.as_ref()) {
            let (coulomb, tresca, potential) = f.laws.iter().fold((0, 0, 0), |(c, t, p), l| match l {
                crate::contact::friction::FrictionLaw::Coulomb(_) => (c + 1, t, p),
                crate::contact::friction::FrictionLaw::Tresca(_) => (c, t + 1, p),
                crate::contact::friction::FrictionLaw::Potential => (c, t, p + 1),
            });
            let all = f.rows.len();
            effects.push(Effect {
                name: "friction",
                detail: format!(
                    "{} tangential rows: {coulomb} Coulomb, {tresca} Tresca (on the slip increment of each step), \
                     {potential} friction potential (on the total tangential displacement)",
                    f.normal_row.len()
                ),
                cost: format!(
                    "the condensed contact problem grows to {all} rows (normal + tangential; {:.1} MiB dense), still \
                     one solve per step{}",
                    (2 * all * all * 8) as f64 / 1048576.0,
                    if coulomb > 0 {
                        "; Coulomb's bound μλ_ν by a fixed point of warm-started contact solves"
                    } else {
                        ""
                    }
                ),
            });
        }
        let memory = sim.materials.memory();
        let factorisations = match (sim.proportional_memory(), sim.time.grid()) {
            (Some(_), _) => Factorisations::Proportional,
            (None, Some(grid)) => {
                let future: Vec<(usize, Vec<f64>)> = grid
                    .size_runs()
                    .into_iter()
                    .map(|(n, k)| (n, memory.map_or(Vec::new(), |m| m.step_coefficients(k, sim.rules))))
                    .collect();
                let (distinct, built) = super::operators::Operators::count(false, &future);
                Factorisations::Counted {
                    distinct,
                    built,
                    step_zero: memory.is_some(),
                }
            }
            (None, None) if memory.is_none() => Factorisations::Counted {
                distinct: 1,
                built: 1,
                step_zero: false,
            },
            (None, None) => Factorisations::PerSize,
        };
        if sim.is_static() {
            solves_per_step = 0;
        }
        Plan {
            effects,
            factorisations,
            solves_per_step,
        }
    }

    /// The names of the effects in force.
    pub fn effect_names(&self) -> Vec<String> {
        self.effects.iter().map(|e| e.name.to_string()).collect()
    }
}

/// The note on step 0's own factorisation.
fn step_zero_note(with: bool) -> &'static str {
    if with {
        ", and a second of K_A alone if step 0 has a load (docs/method.md §3)"
    } else {
        ""
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for e in &self.effects {
            writeln!(f, "  {:<11} {}", e.name, e.detail)?;
            writeln!(f, "  {:<11} cost: {}", "", e.cost)?;
        }
        if self.solves_per_step == 0 {
            writeln!(
                f,
                "  no memory, constant loads and no moving obstacle: one solve at t = 0, the same state written for \
                 every output step"
            )?;
        } else {
            writeln!(
                f,
                "  per step: {} sparse solve(s) with the cached factor",
                self.solves_per_step
            )?;
        }
        let step_zero = "; and one of K_A alone if step 0 has a load (docs/method.md §3)";
        match self.factorisations {
            Factorisations::Proportional => writeln!(
                f,
                "  factorisations: 1 — the memory is proportional to A, so every step matrix is a multiple of K_A \
                 whatever the steps (docs/method.md §20.3)"
            ),
            Factorisations::Counted {
                distinct: 1,
                built: 1,
                step_zero,
            } => writeln!(f, "  factorisations: 1{}", if step_zero { step_zero_note(step_zero) } else { "" }),
            Factorisations::Counted {
                distinct,
                built,
                step_zero: zero,
            } => writeln!(
                f,
                "  factorisations: {built}, of {distinct} distinct step matrices (one per step size, at most {} held at \
                 once: docs/method.md §20.3){}",
                super::operators::CAPACITY,
                if zero { step_zero } else { "" }
            ),
            Factorisations::PerSize => writeln!(
                f,
                "  factorisations: one per distinct step size the automatic steps meet (sizes k₁·2^j, about 3.3 a \
                 decade; at most {} held at once, docs/method.md §20.3)",
                super::operators::CAPACITY
            ),
        }
    }
}
