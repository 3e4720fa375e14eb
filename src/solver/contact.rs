//! The contact of a scene on a mesh (docs/method.md §14): every `[[contact]]` group (or the one
//! `[contact]` table) with its law, bound and obstacle, turned into one set of contact rows for
//! one active-set solve.

use super::error::SolveError;
use super::pairs::{paired_rows, tied_rows};
use crate::contact::friction::{Coefficient, Friction, FrictionLaw};
use crate::contact::pairing::{PairSummary, PairingError, SurfacePair};
use crate::contact::rows::{self, GroupRows};
use crate::contact::ContactState;
use crate::contact::{
    ComplianceProfile, ContactLaw, ContactNodes, ContactSettings, LawTerm, NodalLaws, Obstacle, PiecewiseLinear,
    Symmetry,
};
use crate::fem::DofMap;
use crate::mesh::Mesh;
use crate::scene::{self, ContactDirection, Expr, ObstacleSpec, Scene};

/// The laws' origins o_p and the bounds g_p of a step, per row.
pub type MovedGaps = (Vec<f64>, Vec<f64>);

/// The rigid motions a(t) of the moving obstacles and how each row's gap follows them.
#[derive(Clone, Debug)]
pub struct ObstacleMotion<const D: usize> {
    /// One expression of t per component, per moving obstacle.
    pub motions: Vec<Vec<Expr>>,
    /// The scene key of each motion (`contact[i].obstacle.motion`), for messages.
    pub keys: Vec<String>,
    /// Per row: (motion, ∂gap/∂a).
    pub rows: Vec<Option<(usize, [f64; D])>>,
}

/// Contact: the rows of all groups, their laws and bounds, and the solver settings.
#[derive(Clone, Debug)]
pub struct ContactSetup<const D: usize> {
    pub nodes: ContactNodes<D>,
    /// The laws of the rows, each term with its group's nodal weight (empty: no law).
    pub laws: NodalLaws,
    /// g_p per row at t = 0 (gap₀ + layer; ∞ where a row has none), or `None` if no row has one.
    pub bound: Option<Vec<f64>>,
    /// gap₀ per row: where the laws start (`None` without an obstacle).
    pub gap: Option<Vec<f64>>,
    /// The layer between first contact and the rigid bound per row (∞: none).
    pub layer: Vec<f64>,
    /// Moving obstacles (`None`: none moves, and no step pays for it).
    pub motion: Option<ObstacleMotion<D>>,
    /// The contact groups' names (or tags), in scene order.
    pub groups: Vec<String>,
    /// The physical tag of each group (the `group` column of gamma3.csv and the contact dataset).
    pub group_tags: Vec<i32>,
    /// The group of each row (the stricter wall's where groups meet, docs/method.md §14.3).
    pub row_group: Vec<usize>,
    /// Γ₃ nodes whose normal never meets their obstacle (dropped): (node, group).
    pub never_touching: Vec<(usize, usize)>,
    pub settings: ContactSettings,
    /// The tangential rows of the groups with friction (docs/method.md §17); None: frictionless.
    pub friction: Option<Friction<D>>,
    /// Per normal row, whether its group is bilateral (u_ν = g_p, held from both sides,
    /// docs/method.md §17.4); None when no group is.
    pub bilateral: Option<Vec<bool>>,
    /// The groups in contact with another body (`target`, docs/method.md §18), whose rows hold
    /// the master nodes' unknowns too: per pair, how messages name it and its pairing's numbers.
    pub pairs: Vec<(String, PairSummary)>,
    /// The target surfaces, as (group index, target name): their bodies receive the opposite of
    /// their group's contact force, written beside it (docs/method.md §18.4).
    pub targets: Vec<(usize, String)>,
    /// Per normal row, the master nodes' coefficients c_i of a row of contact between two bodies
    /// (empty for the others); a tangential row has its normal row's.
    pub master_terms: Vec<Vec<(usize, f64)>>,
}

impl<const D: usize> ContactSetup<D> {
    /// The rows the condensation holds: the normal rows, and with friction the tangential rows
    /// after them (docs/method.md §17).
    pub fn condensed_rows(&self) -> &ContactNodes<D> {
        self.friction.as_ref().map_or(&self.nodes, |f| &f.rows)
    }

    /// The law when every row has the same one (None without a law or with several).
    pub fn law(&self) -> Option<&ContactLaw> {
        self.laws.single()
    }

    /// The laws' origins o_p and the bounds g_p at time t (the initial ones when nothing moves).
    pub fn gaps_at(&self, t: f64) -> Result<Option<MovedGaps>, String> {
        let Some(motion) = &self.motion else {
            return Ok(None);
        };
        let a: Vec<[f64; D]> = motion
            .motions
            .iter()
            .map(|m| std::array::from_fn(|k| m[k].eval(&[t])))
            .collect();
        for (i, v) in a.iter().enumerate() {
            if let Some(k) = (0..D).find(|&k| !v[k].is_finite()) {
                return Err(format!(
                    "{}[{k}] = \"{}\" is {} (the obstacle's rigid displacement must be finite for 0 ≤ t ≤ T)",
                    motion.keys[i],
                    motion.motions[i][k].source(),
                    v[k]
                ));
            }
        }
        let gap0 = self.gap.as_deref().unwrap_or(&[]);
        let offset: Vec<f64> = (0..self.nodes.len())
            .map(|p| gap0[p] + motion.rows[p].map_or(0.0, |(i, c)| (0..D).map(|k| c[k] * a[i][k]).sum::<f64>()))
            .collect();
        let bound = offset.iter().zip(&self.layer).map(|(o, l)| o + l).collect();
        Ok(Some((offset, bound)))
    }

    /// The total contact force on the body exerted by each group, Σ_p −λ_p d_p (the force of
    /// a row where groups meet split by their laws' shares, the rest to the stricter wall's
    /// group), then on the body of each target; `offset` are the laws' origins of the step.
    pub fn group_forces(&self, state: &ContactState, offset: Option<&[f64]>) -> Vec<[f64; D]> {
        let mut out = vec![[0.0; D]; self.groups.len()];
        for p in 0..self.nodes.len() {
            let d = self.nodes.normals[p];
            let mut rest = state.force[p];
            let o = offset.or(self.gap.as_deref()).map_or(0.0, |o| o[p]);
            for t in self.laws.terms(p) {
                if t.group != self.row_group[p] {
                    let f = t.weight * self.laws.laws[t.law].derivative(state.normal_displacement[p] - o);
                    rest -= f;
                    for k in 0..D {
                        out[t.group][k] -= f * d[k];
                    }
                }
            }
            for k in 0..D {
                out[self.row_group[p]][k] -= rest * d[k];
            }
        }
        // the friction forces of the tangential rows (docs/method.md §17)
        if let Some(f) = &self.friction {
            let m = self.nodes.len();
            for (k, &p) in f.normal_row.iter().enumerate() {
                let tau = f.rows.normals[m + k];
                for c in 0..D {
                    out[self.row_group[p]][c] -= state.force[m + k] * tau[c];
                }
            }
        }
        // the target's body: Σ_r λ_r d_r Σ_i c_ri over its pair's rows, a tangential row with its
        // normal row's coefficients (docs/method.md §18.4)
        if !self.targets.is_empty() {
            let rows = self.condensed_rows();
            let m = self.nodes.len();
            let mut on_master = vec![[0.0; D]; self.groups.len()];
            for r in 0..rows.len() {
                let p = match &self.friction {
                    Some(f) if r >= m => f.normal_row[r - m],
                    _ => r,
                };
                let share: f64 = self.master_terms[p].iter().map(|t| t.1).sum();
                for c in 0..D {
                    on_master[self.row_group[p]][c] += state.force[r] * rows.normals[r][c] * share;
                }
            }
            out.extend(self.targets.iter().map(|&(g, _)| on_master[g]));
        }
        out
    }

    /// The names of [`ContactSetup::group_forces`]' entries: the groups, then the targets.
    pub fn force_names(&self) -> Vec<String> {
        self.groups
            .iter()
            .cloned()
            .chain(self.targets.iter().map(|(_, name)| name.clone()))
            .collect()
    }
}

/// A row's coefficients over other nodes: (node, c).
type Terms = Vec<(usize, f64)>;

/// Rows of second-order faces (docs/method.md §19.3): row k takes the coefficients of normal
/// row `normal(k)` over its faces' nodes (none: a row of its own node).
fn spread_rows<const D: usize>(
    rows: &mut ContactNodes<D>,
    spread: &[Terms],
    normal: impl Fn(usize) -> usize,
    dofs: &DofMap<D>,
) {
    for k in 0..rows.len() {
        let terms = &spread[normal(k)];
        if !terms.is_empty() {
            rows.spread(k, terms, dofs);
        }
    }
}

fn law_of(l: &scene::ContactLawSpec, key: &str) -> Result<ContactLaw, SolveError> {
    let (scale, profile) = match &l.kind {
        scene::LawKind::Paper { scale, a, b, alpha } => (
            *scale,
            ComplianceProfile::Paper {
                a: *a,
                b: *b,
                alpha: *alpha,
            },
        ),
        scene::LawKind::Power { scale, exponent } => (*scale, ComplianceProfile::Power { exponent: *exponent }),
        scene::LawKind::PiecewiseLinear { scale, table } => {
            let points: Vec<(f64, f64)> = table.iter().map(|p| (p[0], p[1])).collect();
            let table =
                PiecewiseLinear::new(&points).map_err(|e| SolveError::Setup(format!("{key}.law.table: {e}")))?;
            (*scale, ComplianceProfile::PiecewiseLinear { table })
        }
        scene::LawKind::Tabulated { .. } => {
            return Err(SolveError::Setup("a tabulated law must be read by Scene::load".into()))
        }
    };
    Ok(ContactLaw {
        scale,
        profile,
        symmetry: if l.one_sided { Symmetry::OneSided } else { Symmetry::Odd },
        epsilon: l.regularisation,
    })
}

fn vector<const D: usize>(v: &[f64], key: &str, origin: &str) -> Result<[f64; D], SolveError> {
    v.try_into().map_err(|_| {
        SolveError::Setup(format!(
            "{origin}: {key} = {v:?} has {} components but the mesh is {D}D: give {D}",
            v.len()
        ))
    })
}

/// The obstacle of a `[[contact]]` section (also drawn by `hvi plot`, src/plot/mod.rs).
pub(crate) fn obstacle_of<const D: usize>(
    o: &ObstacleSpec,
    key: &str,
    origin: &str,
    length: f64,
) -> Result<Obstacle<D>, SolveError> {
    Ok(match o {
        ObstacleSpec::Plane { point, normal, .. } => {
            let n: [f64; D] = vector(normal, &format!("{key}.normal"), origin)?;
            // scaled by its largest entry first: |n|² of [1e300, 1e300] would overflow
            let big = n.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            let n = n.map(|x| x / big);
            let len = n.iter().map(|x| x * x).sum::<f64>().sqrt();
            Obstacle::Plane {
                point: vector(point, &format!("{key}.point"), origin)?,
                normal: n.map(|x| x / len),
            }
        }
        ObstacleSpec::Circle { centre, radius, .. } => Obstacle::Ball {
            centre: vector(centre, &format!("{key}.centre"), origin)?,
            radius: *radius,
        },
        ObstacleSpec::Sdf { sdf, .. } => Obstacle::Level {
            phi: Box::new(
                Expr::parse(sdf, &["x", "y", "z"])
                    .map_err(|e| SolveError::Setup(format!("{key}.sdf = \"{sdf}\": {e}")))?,
            ),
            // central differences: error O(step²) ≈ 1e-12 of the body's size
            step: 1e-6 * length,
        },
    })
}

/// True if some contact section has a law, a bound or an obstacle (else there is no contact).
pub fn is_posed(scene: &Scene) -> bool {
    scene.contact.iter().any(|c| c.is_posed())
}

/// The contact of `scene` on `mesh` (None when no section has a law or a bound or an obstacle).
pub fn build<const D: usize>(
    scene: &Scene,
    mesh: &Mesh<D>,
    dofs: &DofMap<D>,
    origin: &str,
) -> Result<Option<ContactSetup<D>>, SolveError> {
    let used: Vec<usize> = (0..scene.contact.len())
        .filter(|&i| scene.contact[i].is_posed())
        .collect();
    if used.is_empty() {
        return Ok(None);
    }
    let length = {
        let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
        for x in &mesh.points {
            for k in 0..D {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        (0..D)
            .map(|k| (hi[k] - lo[k]).powi(2))
            .sum::<f64>()
            .sqrt()
            .max(f64::MIN_POSITIVE)
    };
    let mut laws = Vec::new();
    let mut motions = Vec::new();
    let mut motion_keys = Vec::new();
    let mut parts = Vec::new();
    let mut group_tags = Vec::new();
    let mut obstacles = Vec::new();
    let mut specs = Vec::new();
    // per used section: its pairing with its target surface (docs/method.md §18)
    let mut pairs: Vec<Option<SurfacePair<D>>> = Vec::new();
    let revolved = scene.material.plane == Some(crate::scene::Plane::Axisymmetric);
    for &i in &used {
        let c = &scene.contact[i];
        let key = scene.contact_key(i);
        let group_key = if c.group.is_some() {
            format!("{key}.group")
        } else {
            "groups.contact".to_string()
        };
        let keyed = super::error::group_error(&scene.origin, &group_key);
        let mut part = mesh.boundary(&scene.contact_group(i)).map_err(&keyed)?;
        // a body of revolution: the weights of the swept surface (docs/method.md §8.6)
        if revolved {
            part.revolve(&mesh.points);
        }
        pairs.push(match &c.target {
            Some(target) => {
                let mut master = mesh
                    .boundary(target)
                    .map_err(super::error::group_error(&scene.origin, &format!("{key}.target")))?;
                if revolved {
                    master.revolve(&mesh.points);
                }
                let names = format!(
                    "{key}: the surfaces {} (group) and {} (target)",
                    part.label, master.label
                );
                Some(SurfacePair::new(&mesh.points, part.clone(), master).map_err(|e| {
                    SolveError::Setup(format!(
                        "{origin}: {names} {}",
                        match e {
                            PairingError::NoOverlap => "do not overlap: no node of the group projects onto the \
                                                       target; check the groups (docs/method.md §18)"
                                .to_string(),
                            PairingError::SameWay { facing_away, paired } => format!(
                                "face the same way ({facing_away} of {paired} paired nodes): the group and the target \
                                 must be the two sides of the contact, facing each other"
                            ),
                        }
                    ))
                })?)
            }
            None => None,
        });
        parts.push(part);
        group_tags.push(mesh.group(&scene.contact_group(i), (D - 1) as u8).map_err(&keyed)?.tag);
        obstacles.push(match &c.obstacle {
            Some(o) => Some(obstacle_of::<D>(o, &format!("{key}.obstacle"), origin, length)?),
            None => None,
        });
        let law = match &c.law {
            Some(l) => {
                let given = law_of(l, &key)?;
                let one_sided = ContactLaw {
                    symmetry: Symmetry::OneSided,
                    ..given.clone()
                };
                laws.push(given.clone());
                if given.symmetry != Symmetry::OneSided {
                    laws.push(one_sided);
                }
                Some((
                    laws.len() - if given.symmetry == Symmetry::OneSided { 1 } else { 2 },
                    laws.len() - 1,
                ))
            }
            None => None,
        };
        let motion = match c.obstacle.as_ref().and_then(|o| o.motion()) {
            Some(m) => {
                if m.len() != D {
                    return Err(SolveError::Setup(format!(
                        "{origin}: {key}.obstacle.motion has {} components but the mesh is {D}D: give {D} expressions of t",
                        m.len()
                    )));
                }
                let exprs = m
                    .iter()
                    .enumerate()
                    .map(|(k, e)| {
                        Expr::parse(e, &["t"])
                            .map_err(|err| SolveError::Setup(format!("{key}.obstacle.motion[{k}] = \"{e}\": {err}")))
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                motions.push(exprs);
                motion_keys.push(format!("{key}.obstacle.motion"));
                Some(motions.len() - 1)
            }
            None => None,
        };
        specs.push((law, motion));
    }
    let mut inputs = Vec::new();
    for (k, &i) in used.iter().enumerate() {
        let c = &scene.contact[i];
        let n = parts[k].nodes.len();
        // the layer: the bound if given; a rigid obstacle (no law) is its own bound
        let layer = match (&c.bound, &c.obstacle, &c.law) {
            (Some(g), _, _) => super::bound::nodal_bound(
                g,
                &parts[k].nodes,
                &mesh.points,
                origin,
                &format!("{}.bound", scene.contact_key(i)),
            )?,
            (None, Some(_), None) => vec![0.0; n],
            // a target without a law is rigid contact: u_ν ≤ g₀
            (None, None, None) if c.target.is_some() => vec![0.0; n],
            // bilateral: u_ν = o_p exactly (docs/method.md §17.4)
            _ if c.bilateral => vec![0.0; n],
            _ => vec![f64::INFINITY; n],
        };
        let key = match &c.obstacle {
            Some(ObstacleSpec::Sdf { sdf, .. }) => format!("{}.obstacle.sdf = \"{sdf}\"", scene.contact_key(i)),
            _ => format!("{}.obstacle", scene.contact_key(i)),
        };
        inputs.push(GroupRows {
            key,
            part: &parts[k],
            obstacle: obstacles[k].as_ref(),
            along_obstacle: c.obstacle.is_some() && c.direction != Some(ContactDirection::Body),
            law: specs[k].0,
            layer,
            motion: specs[k].1,
        });
    }
    let mut rows =
        rows::build(&inputs, &mesh.points, length).map_err(|e| SolveError::Setup(format!("{origin}: {e}")))?;
    // rows of contact with another body: along −n of the master surface, their gap g₀ and the
    // master nodes' terms; a slave node off the target has no row (docs/method.md §18)
    let mut master_terms = paired_rows(&mut rows, &pairs, &mesh.points, revolved);
    let tied: Vec<bool> = used.iter().map(|&i| scene.contact[i].tied).collect();
    tied_rows(&mut rows, &mut master_terms, &tied);
    let (mut nodes, kept) = ContactNodes::from_rows(&rows.nodes, &rows.weights, &rows.directions, dofs);
    let master_terms: Vec<Vec<(usize, f64)>> = kept.iter().map(|&r| master_terms[r].clone()).collect();
    let spread: Vec<Terms> = kept.iter().map(|&r| rows.spread[r].clone()).collect();
    // the slave side first: a spread row replaces its node's terms (docs/method.md §18.6)
    spread_rows(&mut nodes, &spread, |k| k, dofs);
    for (k, terms) in master_terms.iter().enumerate() {
        nodes.add_master_terms(k, terms, dofs);
    }
    let pick = |v: &[f64]| -> Vec<f64> { kept.iter().map(|&k| v[k]).collect() };
    let gap = pick(&rows.gap);
    let layer = pick(&rows.layer);
    let any_obstacle = obstacles.iter().any(|o| o.is_some()) || pairs.iter().any(|p| p.is_some());
    let bound: Vec<f64> = gap.iter().zip(&layer).map(|(g, l)| g + l).collect();
    let terms: Vec<_> = kept.iter().map(|&k| rows.terms[k].clone()).collect();
    let row_group: Vec<usize> = kept.iter().map(|&k| rows.group[k]).collect();
    let laws = NodalLaws::new(laws, &terms);
    let friction = friction_rows(
        scene,
        &used,
        (&nodes, &laws, &row_group),
        (&master_terms, &spread),
        dofs,
        origin,
    )?;
    let bilateral: Vec<bool> = row_group
        .iter()
        .map(|&g| scene.contact[used[g]].bilateral || tied[g])
        .collect();
    Ok(Some(ContactSetup {
        pairs: used
            .iter()
            .zip(&pairs)
            .filter_map(|(&i, p)| {
                p.as_ref().map(|p| {
                    let c = &scene.contact[i];
                    let name = format!(
                        "{}: {} against {}",
                        scene.contact_key(i),
                        c.group.as_ref().map_or(String::new(), |g| g.to_string()),
                        c.target.as_ref().map_or(String::new(), |g| g.to_string())
                    );
                    (name, p.summary())
                })
            })
            .collect(),
        bilateral: bilateral.contains(&true).then_some(bilateral),
        targets: used
            .iter()
            .enumerate()
            .filter_map(|(g, &i)| scene.contact[i].target.as_ref().map(|t| (g, t.label())))
            .collect(),
        master_terms,
        laws,
        bound: bound.iter().any(|g| g.is_finite()).then_some(bound),
        gap: any_obstacle.then_some(gap),
        layer,
        motion: (!motions.is_empty()).then(|| ObstacleMotion {
            motions,
            keys: motion_keys,
            rows: kept.iter().map(|&k| rows.motion[k]).collect(),
        }),
        groups: used.iter().map(|&i| scene.contact_group(i).label()).collect(),
        group_tags,
        row_group,
        never_touching: rows.never_touching,
        friction,
        nodes,
        settings: ContactSettings {
            tolerance: scene.solver.tolerance,
            max_iterations: scene.solver.max_iterations,
            dense_limit: scene.solver.dense_newton_limit,
            strategies: {
                let mut on = crate::contact::Strategies::default();
                for name in &scene.solver.without {
                    on.switch_off(name);
                }
                on
            },
            // the contact solve's report to standard error (docs/troubleshooting.md): read here,
            // once, and handed to the solver as a sink
            trace: std::env::var_os("HVI_TRACE_CONTACT").is_some(),
        },
    }))
}

/// The tangential rows of the contact groups that have a `friction` table (None when none has):
/// in 2D one per normal row, along τ = (−ν_y, ν_x); a row whose tangential direction is
/// prescribed cannot slip and is left out (docs/method.md §17).
fn friction_rows<const D: usize>(
    scene: &Scene,
    used: &[usize],
    (nodes, normal_laws, row_group): (&ContactNodes<D>, &NodalLaws, &[usize]),
    (master_terms, spread): (&[Terms], &[Terms]),
    dofs: &DofMap<D>,
    origin: &str,
) -> Result<Option<Friction<D>>, SolveError> {
    let specs: Vec<Option<&scene::FrictionSpec>> = used.iter().map(|&i| scene.contact[i].friction.as_ref()).collect();
    if specs.iter().all(|f| f.is_none()) {
        return Ok(None);
    }
    let mut laws_of_group = Vec::with_capacity(specs.len());
    for (g, spec) in specs.iter().enumerate() {
        laws_of_group.push(match spec {
            None => None,
            Some(scene::FrictionSpec::Coulomb {
                coefficient,
                regularisation,
            }) => {
                let mu = match coefficient {
                    scene::FrictionCoefficient::Value(v) => Coefficient::Constant(*v),
                    scene::FrictionCoefficient::Expression(text) => {
                        let key = format!("{}.friction.coefficient", scene.contact_key(used[g]));
                        Coefficient::OfSlip(
                            Expr::parse(text, &["s"])
                                .map_err(|e| SolveError::Setup(format!("{origin}: {key} = \"{text}\": {e}")))?,
                        )
                    }
                };
                Some((
                    FrictionLaw::Coulomb(mu),
                    ContactLaw::smoothed_magnitude(*regularisation),
                ))
            }
            Some(scene::FrictionSpec::Potential { law }) => {
                let key = format!("{}.friction", scene.contact_key(used[g]));
                let law = ContactLaw {
                    symmetry: Symmetry::Odd,
                    ..law_of(law, &key)?
                };
                Some((FrictionLaw::Potential, law))
            }
            Some(scene::FrictionSpec::Tresca { bound, regularisation }) => {
                let key = format!("{}.friction.bound", scene.contact_key(used[g]));
                let e = Expr::parse(bound, &scene::BODY_FORCE_VARIABLES)
                    .map_err(|e| SolveError::Setup(format!("{origin}: {key} = \"{bound}\": {e}")))?;
                Some((FrictionLaw::Tresca(e), ContactLaw::smoothed_magnitude(*regularisation)))
            }
        });
    }
    let m = nodes.len();
    // the candidate tangential rows: (normal row, tangent), D − 1 per normal row with friction
    let with: Vec<(usize, [f64; D])> = (0..m)
        .filter(|&p| laws_of_group[row_group[p]].is_some())
        .flat_map(|p| {
            Friction::<D>::tangents(nodes.normals[p])
                .into_iter()
                .map(move |t| (p, t))
        })
        .collect();
    let all_nodes: Vec<usize> = nodes
        .nodes
        .iter()
        .copied()
        .chain(with.iter().map(|&(p, _)| nodes.nodes[p]))
        .collect();
    let weights: Vec<f64> = nodes
        .weights
        .iter()
        .copied()
        .chain(with.iter().map(|&(p, _)| nodes.weights[p]))
        .collect();
    let directions: Vec<[f64; D]> = nodes
        .normals
        .iter()
        .copied()
        .chain(with.iter().map(|&(_, t)| t))
        .collect();
    let (mut rows, kept) = ContactNodes::from_rows(&all_nodes, &weights, &directions, dofs);
    // the rows of contact with another body: the master nodes' share of each direction
    let normal_row = |r: usize| if r < m { r } else { with[r - m].0 };
    spread_rows(&mut rows, spread, |k| normal_row(kept[k]), dofs);
    for (k, &r) in kept.iter().enumerate() {
        rows.add_master_terms(k, &master_terms[normal_row(r)], dofs);
    }
    if kept[..m.min(kept.len())] != (0..m).collect::<Vec<_>>()[..] {
        return Err(SolveError::Setup(format!(
            "{origin}: the contact rows changed when their tangential rows were added (a bug: please report it)"
        )));
    }
    let tangential: Vec<usize> = kept[m..].iter().map(|&k| with[k - m].0).collect();
    // 3D: the two kept tangential rows of a normal row form a pair (docs/method.md §17.3)
    let pairs = (D == 3).then(|| {
        let mut pairs = vec![None; m + tangential.len()];
        for k in 1..tangential.len() {
            if tangential[k] == tangential[k - 1] {
                (pairs[m + k - 1], pairs[m + k]) = (Some(m + k), Some(m + k - 1));
            }
        }
        pairs
    });
    // one law per group with friction, after the normal rows' laws
    let mut all_laws = normal_laws.laws.clone();
    let law_index: Vec<Option<usize>> = laws_of_group
        .iter()
        .map(|l| {
            l.as_ref().map(|(_, law)| {
                all_laws.push(law.clone());
                all_laws.len() - 1
            })
        })
        .collect();
    let mut terms: Vec<Vec<LawTerm>> = (0..m).map(|p| normal_laws.terms(p).to_vec()).collect();
    let mut laws = Vec::with_capacity(tangential.len());
    for &p in &tangential {
        let group = row_group[p];
        let (kind, _) = laws_of_group[group].as_ref().expect("a row with friction");
        terms.push(vec![LawTerm {
            law: law_index[group].expect("a row with friction"),
            // a potential's law carries its own scale; the others' weight is set every step
            weight: if matches!(kind, FrictionLaw::Potential) {
                nodes.weights[p]
            } else {
                0.0
            },
            group,
        }]);
        laws.push(kind.clone());
    }
    Ok(Some(Friction {
        rows,
        normal_row: tangential,
        pairs,
        laws,
        laws_of_rows: NodalLaws::new(all_laws, &terms),
    }))
}
