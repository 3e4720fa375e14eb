//! Prescribed displacement components (docs/method.md §7): `groups.clamped` (every component
//! zero) and `[[dirichlet]]` sections (chosen components, values g(x, y, z, t)). Decided here,
//! once: which unknowns are prescribed, their values at a time t, the groups whose reactions are
//! reported, and whether the prescribed components stop every rigid motion of the body.

use super::error::SolveError;
use crate::fem::DofMap;
use crate::mesh::{GroupSelector, Mesh};
use crate::scene::{DirichletSpec, Expr, BODY_FORCE_VARIABLES};
use std::collections::HashMap;

/// The unknowns of one (group, component) whose reaction is reported.
#[derive(Clone, Debug)]
pub struct ReactionGroup {
    /// The group as the scene names it, e.g. `"Gamma1"`.
    pub group: String,
    /// 0, 1 or 2 (x, y, z).
    pub component: usize,
    pub unknowns: Vec<usize>,
    /// 1 for a group; −(k − 1) for the overlap row of k groups sharing these unknowns.
    pub weight: f64,
}

/// The prescribed components of a run and their values.
#[derive(Clone, Debug)]
pub struct Dirichlet<const D: usize> {
    /// Every prescribed unknown with the expression of its value (None: zero).
    entries: Vec<(usize, Option<usize>)>,
    exprs: Vec<Expr>,
    /// Node coordinates of each entry's node (for evaluating the expressions).
    at: Vec<[f64; D]>,
    /// The (group, component) pairs whose reactions are reported, in scene order.
    pub reaction_groups: Vec<ReactionGroup>,
}

const COMPONENTS: [&str; 3] = ["x", "y", "z"];

impl<const D: usize> Dirichlet<D> {
    /// The degree-of-freedom map and the prescribed values of `clamped` (every component zero)
    /// and the `[[dirichlet]]` sections on `mesh`. A component prescribed twice is compared by
    /// value at the shared node at `times` (the text may differ: "0.0" and "0", "0.01*x" and "0"
    /// at x = 0): different values are an error naming both; so is a body whose prescribed
    /// components leave a rigid motion free. Every group must be on the boundary of the body
    /// ([`Mesh::boundary_group_nodes`]).
    pub fn new(
        mesh: &Mesh<D>,
        clamped: Option<&GroupSelector>,
        sections: &[DirichletSpec],
        times: &[f64],
        scene_origin: &str,
    ) -> Result<(DofMap<D>, Self), SolveError> {
        let origin = mesh.path.display().to_string();
        let mut dofs = DofMap::new(mesh.points.len(), &[]);
        let mut out = Dirichlet {
            entries: Vec::new(),
            exprs: Vec::new(),
            at: Vec::new(),
            reaction_groups: Vec::new(),
        };
        // unknown → (who set it, the value's text, its expression)
        let mut set_by: HashMap<usize, (String, String, Option<usize>)> = HashMap::new();
        let mut prescribe = |dofs: &mut DofMap<D>,
                             out: &mut Dirichlet<D>,
                             node: usize,
                             c: usize,
                             who: &str,
                             text: &str,
                             expr: Option<usize>|
         -> Result<bool, SolveError> {
            let d = dofs.index(node, c);
            if let Some((other, t, first)) = set_by.get(&d) {
                let x = mesh.points[node];
                let value = |e: &Option<usize>, time: f64| {
                    e.map_or(0.0, |e| {
                        let mut vars = [0.0; 4];
                        vars[..D].copy_from_slice(&x);
                        vars[3] = time;
                        out.exprs[e].eval(&vars)
                    })
                };
                // (a NaN is no conflict here: Dirichlet::values names it)
                let differs = times.iter().find_map(|&time| {
                    let (a, b) = (value(first, time), value(&expr, time));
                    ((a - b).abs() > 1e-12 * a.abs().max(b.abs()).max(1.0)).then_some((time, a, b))
                });
                if let Some((time, a, b)) = differs {
                    return Err(SolveError::Setup(format!(
                        "{origin}: component {} of the node at {} is prescribed by {other} as \"{t}\" and by {who} \
                         as \"{text}\" ({a} against {b} at t = {time}); give the shared nodes one value (or leave the \
                         component out of one section)",
                        COMPONENTS[c],
                        crate::mesh::fmt_point(x)
                    )));
                }
                return Ok(false);
            }
            set_by.insert(d, (who.to_string(), text.to_string(), expr));
            dofs.prescribe(node, c);
            out.entries.push((d, expr));
            out.at.push(mesh.points[node]);
            Ok(true)
        };
        if let Some(sel) = clamped {
            let nodes = mesh
                .boundary_group_nodes(sel)
                .map_err(super::error::group_error(scene_origin, "groups.clamped"))?;
            if nodes.is_empty() {
                return Err(SolveError::NoClampedNodes {
                    mesh: origin,
                    group: sel.to_string(),
                });
            }
            for c in 0..D {
                let mut unknowns = Vec::with_capacity(nodes.len());
                for &p in &nodes {
                    prescribe(&mut dofs, &mut out, p, c, "groups.clamped", "0", None)?;
                    unknowns.push(dofs.index(p, c));
                }
                out.reaction_groups.push(ReactionGroup {
                    group: group_name(sel),
                    component: c,
                    unknowns,
                    weight: 1.0,
                });
            }
        }
        for (i, section) in sections.iter().enumerate() {
            let key = format!("dirichlet[{i}].group");
            let nodes = mesh
                .boundary_group_nodes(&section.group)
                .map_err(super::error::group_error(scene_origin, &key))?;
            if nodes.is_empty() {
                return Err(SolveError::Setup(format!(
                    "{origin}: dirichlet[{i}].group = {} has no nodes",
                    section.group
                )));
            }
            let who = format!("dirichlet[{i}] (group {})", section.group);
            for (k, name) in section.components.iter().enumerate() {
                let Some(c) = COMPONENTS[..D].iter().position(|n| n == name) else {
                    return Err(SolveError::Setup(format!(
                        "{origin}: dirichlet[{i}].components names \"{name}\", but the mesh is {D}D (components {})",
                        COMPONENTS[..D].join(", ")
                    )));
                };
                let text = section.value.as_ref().map_or("0", |v| v[k].as_str()).trim().to_string();
                let expr = if text == "0" {
                    None
                } else {
                    let e = Expr::parse(&text, &BODY_FORCE_VARIABLES).map_err(|e| {
                        SolveError::Setup(format!("{origin}: dirichlet[{i}].value[{k}] = \"{text}\": {e}"))
                    })?;
                    out.exprs.push(e);
                    Some(out.exprs.len() - 1)
                };
                let mut unknowns = Vec::with_capacity(nodes.len());
                for &p in &nodes {
                    prescribe(&mut dofs, &mut out, p, c, &who, &text, expr)?;
                    unknowns.push(dofs.index(p, c));
                }
                out.reaction_groups.push(ReactionGroup {
                    group: group_name(&section.group),
                    component: c,
                    unknowns,
                    weight: 1.0,
                });
            }
        }
        out.add_overlap_rows();
        out.check_rigid_motions(mesh, &dofs)?;
        Ok((dofs, out))
    }

    /// Each group's reaction is the whole force on that group, so a component in two groups (the
    /// corner of a clamped side and a roller side) counts in both; an overlap row per set of
    /// groups sharing components, `Gamma1 & Gamma3` with weight −(k − 1) for k groups, takes the
    /// surplus back, so that all rows together add up with the contact forces and the loads
    /// (docs/method.md §7.5).
    fn add_overlap_rows(&mut self) {
        let mut members: HashMap<usize, Vec<usize>> = HashMap::new();
        for (g, group) in self.reaction_groups.iter().enumerate() {
            for &d in &group.unknowns {
                let list = members.entry(d).or_default();
                if !list.iter().any(|&h| self.reaction_groups[h].group == group.group) {
                    list.push(g);
                }
            }
        }
        // (set of group names, component) → unknowns, in a stable order
        let mut overlaps: std::collections::BTreeMap<(Vec<String>, usize), Vec<usize>> = Default::default();
        for (d, list) in members {
            if list.len() > 1 {
                let names: Vec<String> = list.iter().map(|&g| self.reaction_groups[g].group.clone()).collect();
                let c = self.reaction_groups[list[0]].component;
                overlaps.entry((names, c)).or_default().push(d);
            }
        }
        for ((names, component), mut unknowns) in overlaps {
            unknowns.sort_unstable();
            self.reaction_groups.push(ReactionGroup {
                group: names.join(" & "),
                component,
                weight: -((names.len() - 1) as f64),
                unknowns,
            });
        }
    }

    /// True if some prescribed value is not identically zero (then the prescribed part moves
    /// to the right-hand side every step; else nothing is done for it).
    pub fn is_nonzero(&self) -> bool {
        !self.exprs.is_empty()
    }

    /// True if a prescribed value depends on t.
    pub fn is_time_dependent(&self) -> bool {
        self.exprs.iter().any(|e| e.depends_on("t"))
    }

    /// Number of prescribed unknowns.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True if nothing is prescribed.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The prescribed values at time t over all unknowns (zero at free ones), into `out`. A
    /// value that is not finite is an error naming the expression, the point and t.
    pub fn values(&self, t: f64, out: &mut [f64]) -> Result<(), String> {
        out.fill(0.0);
        for (&(d, e), x) in self.entries.iter().zip(&self.at) {
            if let Some(e) = e {
                let mut vars = [0.0; 4];
                vars[..D].copy_from_slice(x);
                vars[3] = t;
                let v = self.exprs[e].eval(&vars);
                if !v.is_finite() {
                    return Err(format!(
                        "prescribed displacement \"{}\" is {v} at {x:?}, t = {t}; make it finite on its group",
                        self.exprs[e].source()
                    ));
                }
                out[d] = v;
            }
        }
        Ok(())
    }

    /// The rigid motions of the body (D translations, D(D−1)/2 rotations about the centroid)
    /// that no prescribed component stops: an error naming them.
    fn check_rigid_motions(&self, mesh: &Mesh<D>, dofs: &DofMap<D>) -> Result<(), SolveError> {
        let n = mesh.points.len().max(1) as f64;
        let mut centre = [0.0; D];
        for p in &mesh.points {
            for k in 0..D {
                centre[k] += p[k] / n;
            }
        }
        let extent = mesh
            .points
            .iter()
            .map(|p| (0..D).map(|k| (p[k] - centre[k]).powi(2)).sum::<f64>().sqrt())
            .fold(f64::MIN_POSITIVE, f64::max);
        // Modes: translations e_k, then rotations (2D: about z; 3D: about x, y, z).
        let names: Vec<&str> = if D == 2 {
            vec!["translation in x", "translation in y", "rotation in the plane"]
        } else {
            vec![
                "translation in x",
                "translation in y",
                "translation in z",
                "rotation about x",
                "rotation about y",
                "rotation about z",
            ]
        };
        let modes = names.len();
        let mut gram = nalgebra::DMatrix::<f64>::zeros(modes, modes);
        let mut row = vec![0.0; modes];
        for d in (0..dofs.n()).filter(|&d| dofs.is_prescribed(d)) {
            let (node, c) = (d / D, d % D);
            let x: Vec<f64> = (0..D).map(|k| (mesh.points[node][k] - centre[k]) / extent).collect();
            row.fill(0.0);
            row[c] = 1.0;
            if D == 2 {
                // ω e_z × x = ω (−y, x)
                row[2] = if c == 0 { -x[1] } else { x[0] };
            } else {
                // ω e_a × x, component c
                for a in 0..3 {
                    let e = [(a == 0) as u8 as f64, (a == 1) as u8 as f64, (a == 2) as u8 as f64];
                    row[3 + a] = crate::mesh::vector::cross(e, [x[0], x[1], x[2]])[c];
                }
            }
            for i in 0..modes {
                for j in 0..modes {
                    gram[(i, j)] += row[i] * row[j];
                }
            }
        }
        let eigen = gram.symmetric_eigen();
        let largest = eigen.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
        let free_modes = eigen
            .eigenvalues
            .iter()
            .filter(|&&v| v <= 1e-10 * largest.max(1.0))
            .count();
        if free_modes == 0 {
            return Ok(());
        }
        // Translations along an axis no prescribed component acts on are free; what is free
        // beyond them are rotations.
        let mut free: Vec<String> = (0..D)
            .filter(|&c| !(0..dofs.n()).any(|d| d % D == c && dofs.is_prescribed(d)))
            .map(|c| names[c].to_string())
            .collect();
        let rotations = free_modes.saturating_sub(free.len());
        if rotations > 0 {
            free.push(if D == 2 {
                "the rotation in the plane (the prescribed components act at a single point)".to_string()
            } else {
                format!(
                    "{rotations} rotation{} (the prescribed components act at too few points or along one line)",
                    if rotations == 1 { "" } else { "s" }
                )
            });
        }
        Err(SolveError::Singular {
            mesh: mesh.path.display().to_string(),
            detail: format!(
                "the body is not held against rigid motions: {} {} free ({} components prescribed); clamp a group \
                 (groups.clamped) or prescribe more components with [[dirichlet]] sections",
                free.join(", "),
                if free_modes == 1 { "is" } else { "are" },
                self.entries.len()
            ),
        })
    }
}

fn group_name(sel: &GroupSelector) -> String {
    match sel {
        GroupSelector::Name(n) => n.clone(),
        GroupSelector::Tag(t) => t.to_string(),
    }
}
