//! Prescribed displacement components (docs/method.md §7): `groups.clamped` (every component
//! zero) and `[[dirichlet]]` sections (chosen components, values g(x, y, z, t)). Decided here,
//! once: which unknowns are prescribed, their values at a time t, the groups whose reactions are
//! reported, and whether the prescribed components stop every rigid motion of the body.

use super::error::SolveError;
use crate::fem::DofMap;
use crate::mesh::{GroupSelector, Mesh};
use crate::scene::{DirichletSpec, Expr, ForceControlSpec, BODY_FORCE_VARIABLES};
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

/// A rigid parameter a_i of the step (docs/method.md §7.7): its unknowns are prescribed in the
/// factor and all move by a_i, which the step solves for so that their total reaction is P_i(t).
/// A force-controlled group's component is one; a single component pinned where the contact
/// alone holds a rigid motion of the body (a semi-coercive body) is another, with P = 0.
#[derive(Clone, Debug)]
pub struct RigidParameter {
    /// How messages and outputs name it: `force_control[0] (group Base, y)`, or the motion a
    /// pin stands for.
    pub name: String,
    /// The unknowns it moves.
    pub unknowns: Vec<usize>,
    /// P_i(t), an expression of t (None: 0).
    pub force: Option<Expr>,
    /// The force-controlled (group, component), None for a pin.
    pub group: Option<(String, usize)>,
}

impl RigidParameter {
    /// P_i(t).
    pub fn force_at(&self, t: f64) -> f64 {
        self.force.as_ref().map_or(0.0, |e| e.eval(&[t]))
    }
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
    /// The rigid parameters: force-controlled groups, then the pins of the rigid motions only
    /// the contact holds (docs/method.md §7.7). Their unknowns are among `entries`, with value 0.
    pub rigid: Vec<RigidParameter>,
    /// The rigid motions that only the contact holds (empty: the prescribed components hold
    /// every one), by name.
    pub held_by_contact: Vec<String>,
    /// A body of revolution: its only rigid motion is the translation along the axis (y).
    axisymmetric: bool,
}

const COMPONENTS: [&str; 3] = ["x", "y", "z"];

impl<const D: usize> Dirichlet<D> {
    /// The degree-of-freedom map and the prescribed values of `clamped` (every component zero)
    /// and the `[[dirichlet]]` sections on `mesh`. A component prescribed twice is compared by
    /// value at the shared node at `times` (the text may differ: "0.0" and "0", "0.01*x" and "0"
    /// at x = 0): different values are an error naming both. The `force_control` groups'
    /// components are prescribed too, each group's by one rigid parameter. A rigid motion that
    /// the prescribed components leave free is an error, unless the body has contact nodes
    /// (`contact_nodes`): then the contact is to hold it and one component per free motion is
    /// pinned as a rigid parameter (docs/method.md §7.7). Every group must be on the boundary of
    /// the body ([`Mesh::boundary_group_nodes`]).
    pub fn new(
        mesh: &Mesh<D>,
        (clamped, sections, force_control): (Option<&GroupSelector>, &[DirichletSpec], &[ForceControlSpec]),
        contact_nodes: Option<&[usize]>,
        axis: Option<&[usize]>,
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
            rigid: Vec::new(),
            held_by_contact: Vec::new(),
            axisymmetric: axis.is_some(),
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
            out.add_entry(dofs, mesh, d, expr);
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
                    group: sel.label(),
                    component: c,
                    unknowns,
                    weight: 1.0,
                });
            }
        }
        // a body of revolution: u_r = 0 on the axis r = 0 (docs/method.md §8.6)
        for &p in axis.unwrap_or_default() {
            prescribe(&mut dofs, &mut out, p, 0, "the axis r = 0 (axisymmetric)", "0", None)?;
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
                    group: section.group.label(),
                    component: c,
                    unknowns,
                    weight: 1.0,
                });
            }
        }
        for (i, fc) in force_control.iter().enumerate() {
            let key = format!("force_control[{i}].group");
            let nodes = mesh
                .boundary_group_nodes(&fc.group)
                .map_err(super::error::group_error(scene_origin, &key))?;
            let c = COMPONENTS[..D].iter().position(|n| *n == fc.component).ok_or_else(|| {
                SolveError::Setup(format!(
                    "{origin}: force_control[{i}].component = \"{}\", but the mesh is {D}D (components {})",
                    fc.component,
                    COMPONENTS[..D].join(", ")
                ))
            })?;
            if nodes.is_empty() {
                return Err(SolveError::Setup(format!(
                    "{origin}: force_control[{i}].group = {} has no nodes",
                    fc.group
                )));
            }
            let force = Expr::parse(&fc.force, &["t"]).map_err(|e| {
                SolveError::Setup(format!("{origin}: force_control[{i}].force = \"{}\": {e}", fc.force))
            })?;
            let mut unknowns = Vec::with_capacity(nodes.len());
            for &p in &nodes {
                if let Some((other, _, _)) = set_by.get(&dofs.index(p, c)) {
                    return Err(SolveError::Setup(format!(
                        "{origin}: component {} of the node at {} is prescribed by {other} and moved by force_control[{i}] \
                         (group {}): a force-controlled component cannot be prescribed too; take the node out of one group \
                         or drop the component from the [[dirichlet]] section",
                        COMPONENTS[c],
                        crate::mesh::fmt_point(mesh.points[p]),
                        fc.group
                    )));
                }
                let d = dofs.index(p, c);
                set_by.insert(d, (format!("force_control[{i}]"), "δ(t)".into(), None));
                out.add_entry(&mut dofs, mesh, d, None);
                unknowns.push(d);
            }
            out.reaction_groups.push(ReactionGroup {
                group: fc.group.label(),
                component: c,
                unknowns: unknowns.clone(),
                weight: 1.0,
            });
            out.rigid.push(RigidParameter {
                name: format!("force_control[{i}] (group {}, {})", fc.group.label(), COMPONENTS[c]),
                unknowns,
                force: Some(force),
                group: Some((fc.group.label(), c)),
            });
        }
        out.add_overlap_rows();
        // each body (a connected piece of the mesh) is held on its own: by its prescribed
        // components, or by its contact with one of its motions pinned (docs/method.md §7.6–7.7)
        let bodies = mesh.bodies();
        let several = bodies.len() > 1;
        for (b, nodes) in bodies.iter().enumerate() {
            let body = several.then_some((b, bodies.len(), nodes.as_slice()));
            let free = out.free_rigid_motions(mesh, &dofs, body);
            if free.modes.is_empty() {
                continue;
            }
            let in_body: Option<Vec<usize>> = contact_nodes.map(|c| {
                c.iter()
                    .copied()
                    .filter(|p| !several || nodes.binary_search(p).is_ok())
                    .collect()
            });
            match in_body.filter(|c| !c.is_empty()) {
                Some(contact) => out.pin(mesh, &mut dofs, free, &contact, body.map(|b| b.2)),
                None => return Err(free.error(mesh, out.entries.len(), body)),
            }
        }
        Ok((dofs, out))
    }

    /// Prescribes unknown d (node d / D, component d % D) with the value of expression `expr`
    /// (None: zero).
    fn add_entry(&mut self, dofs: &mut DofMap<D>, mesh: &Mesh<D>, d: usize, expr: Option<usize>) {
        dofs.prescribe(d / D, d % D);
        self.entries.push((d, expr));
        self.at.push(mesh.points[d / D]);
    }

    /// One pinned component per rigid motion only the contact holds (docs/method.md §7.7): the
    /// free unknowns off the contact nodes that best determine those motions, chosen greedily
    /// (each time the one whose values of the motions are largest after removing what the
    /// pins so far fix: a pivoted Gram–Schmidt over the unknowns).
    /// Of a mesh of several bodies, only the unknowns of `body`'s nodes are candidates.
    fn pin(
        &mut self,
        mesh: &Mesh<D>,
        dofs: &mut DofMap<D>,
        free: FreeMotions<D>,
        contact: &[usize],
        body: Option<&[usize]>,
    ) {
        let k = free.modes.len();
        let on_contact: std::collections::HashSet<usize> = contact.iter().copied().collect();
        let in_body = |d: usize| body.is_none_or(|nodes| nodes.binary_search(&(d / D)).is_ok());
        // (unknown, the motions' values there)
        let candidates_where = |keep: &dyn Fn(usize) -> bool| -> Vec<(usize, Vec<f64>)> {
            (0..dofs.n())
                .filter(|&d| !dofs.is_prescribed(d) && in_body(d) && keep(d))
                .map(|d| {
                    let row = free.row(mesh, d);
                    let values = free
                        .modes
                        .iter()
                        .map(|m| m.iter().zip(&row).map(|(a, b)| a * b).sum())
                        .collect();
                    (d, values)
                })
                .collect()
        };
        let mut candidates = candidates_where(&|d| !on_contact.contains(&(d / D)));
        if candidates.len() < k {
            // every free unknown is on a contact node: pin there
            candidates = candidates_where(&|_| true);
        }
        for _ in 0..k.min(candidates.len()) {
            let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
            let Some(best) =
                (0..candidates.len()).max_by(|&a, &b| norm(&candidates[a].1).total_cmp(&norm(&candidates[b].1)))
            else {
                break;
            };
            let (d, v) = candidates.swap_remove(best);
            let len = norm(&v).sqrt();
            if len == 0.0 {
                break;
            }
            let unit: Vec<f64> = v.iter().map(|x| x / len).collect();
            for (_, w) in &mut candidates {
                let dot: f64 = w.iter().zip(&unit).map(|(a, b)| a * b).sum();
                w.iter_mut().zip(&unit).for_each(|(a, b)| *a -= dot * b);
            }
            self.add_entry(dofs, mesh, d, None);
            self.rigid.push(RigidParameter {
                name: format!(
                    "a pin of {} at the node at {} ({})",
                    free.names.join(", "),
                    crate::mesh::fmt_point(mesh.points[d / D]),
                    COMPONENTS[d % D]
                ),
                unknowns: vec![d],
                force: None,
                group: None,
            });
        }
        self.held_by_contact.extend(free.names);
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
    /// that no prescribed component stops (docs/method.md §7.6); of a mesh of several bodies,
    /// of body (index, count, its nodes), named by it.
    fn free_rigid_motions(
        &self,
        mesh: &Mesh<D>,
        dofs: &DofMap<D>,
        body: Option<(usize, usize, &[usize])>,
    ) -> FreeMotions<D> {
        let all: Vec<usize>;
        let nodes: &[usize] = match body {
            Some((_, _, nodes)) => nodes,
            None => {
                all = (0..mesh.points.len()).collect();
                &all
            }
        };
        let n = nodes.len().max(1) as f64;
        let mut centre = [0.0; D];
        for &p in nodes {
            for k in 0..D {
                centre[k] += mesh.points[p][k] / n;
            }
        }
        let extent = nodes
            .iter()
            .map(|&p| {
                (0..D)
                    .map(|k| (mesh.points[p][k] - centre[k]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(f64::MIN_POSITIVE, f64::max);
        let mut free = FreeMotions {
            centre,
            extent,
            modes: Vec::new(),
            names: Vec::new(),
            body: body.map(|(b, count, _)| (b, count)),
        };
        // the prescribed unknowns of the body's nodes
        let prescribed: Vec<usize> = nodes
            .iter()
            .flat_map(|&p| (0..D).map(move |c| p * D + c))
            .filter(|&d| dofs.is_prescribed(d))
            .collect();
        if self.axisymmetric {
            // a radial displacement strains the hoops: only the translation along the axis is free
            // unless some component y is prescribed (docs/method.md §8.6)
            if !prescribed.iter().any(|&d| d % D == 1) {
                free.modes = vec![vec![0.0, 1.0, 0.0]];
                free.names = vec![free.named("translation in y (along the axis of revolution)")];
            }
            return free;
        }
        let modes = if D == 2 { 3 } else { 6 };
        let mut gram = nalgebra::DMatrix::<f64>::zeros(modes, modes);
        for &d in &prescribed {
            let row = free.row(mesh, d);
            for i in 0..modes {
                for j in 0..modes {
                    gram[(i, j)] += row[i] * row[j];
                }
            }
        }
        let eigen = gram.symmetric_eigen();
        let largest = eigen.eigenvalues.iter().fold(0.0f64, |a, &b| a.max(b));
        free.modes = (0..modes)
            .filter(|&i| eigen.eigenvalues[i] <= 1e-10 * largest.max(1.0))
            .map(|i| eigen.eigenvectors.column(i).iter().copied().collect())
            .collect();
        if free.modes.is_empty() {
            return free;
        }
        // Translations along an axis no prescribed component acts on are free; what is free
        // beyond them are rotations.
        free.names = (0..D)
            .filter(|&c| !prescribed.iter().any(|&d| d % D == c))
            .map(|c| free.named(&format!("translation in {}", COMPONENTS[c])))
            .collect();
        let rotations = free.modes.len().saturating_sub(free.names.len());
        if rotations > 0 {
            let name = if D == 2 {
                "the rotation in the plane (the prescribed components act at a single point)".to_string()
            } else {
                format!(
                    "{rotations} rotation{} (the prescribed components act at too few points or along one line)",
                    if rotations == 1 { "" } else { "s" }
                )
            };
            free.names.push(free.named(&name));
        }
        free
    }
}

/// The rigid motions no prescribed component stops: an orthonormal basis of their coefficients
/// over the D translations and D(D−1)/2 rotations about `centre` (lengths scaled by `extent`).
struct FreeMotions<const D: usize> {
    centre: [f64; D],
    extent: f64,
    modes: Vec<Vec<f64>>,
    names: Vec<String>,
    /// Of a mesh of several bodies: (this body's index, how many).
    body: Option<(usize, usize)>,
}

impl<const D: usize> FreeMotions<D> {
    /// A motion's name, with its body's in a mesh of several.
    fn named(&self, motion: &str) -> String {
        match self.body {
            Some((b, _)) => format!("{motion} of body {}", b + 1),
            None => motion.to_string(),
        }
    }

    /// The value at unknown d (node d / D, component d % D) of each rigid mode: translations
    /// e_k, then rotations (2D: about z; 3D: about x, y, z).
    fn row(&self, mesh: &Mesh<D>, d: usize) -> Vec<f64> {
        let (node, c) = (d / D, d % D);
        let x: Vec<f64> = (0..D)
            .map(|k| (mesh.points[node][k] - self.centre[k]) / self.extent)
            .collect();
        let mut row = vec![0.0; if D == 2 { 3 } else { 6 }];
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
        row
    }

    /// The error of a body nothing holds against these motions; of a mesh of several bodies,
    /// naming which (`body`: its index, count and nodes).
    fn error(&self, mesh: &Mesh<D>, prescribed: usize, body: Option<(usize, usize, &[usize])>) -> SolveError {
        let which = match body {
            Some((b, count, nodes)) => format!(
                "the mesh has {count} bodies (pieces connected through their nodes), and body {} ({} nodes, the \
                 first at {}) is not held against rigid motions",
                b + 1,
                nodes.len(),
                crate::mesh::fmt_point(mesh.points[nodes[0]])
            ),
            None => "the body is not held against rigid motions".to_string(),
        };
        SolveError::Singular {
            mesh: mesh.path.display().to_string(),
            detail: format!(
                "{which}: {} {} free ({prescribed} components prescribed); clamp a group (groups.clamped), prescribe \
                 more components with [[dirichlet]] sections, or give the body a contact group that holds it \
                 (docs/method.md §7.7)",
                self.names.join(", "),
                if self.modes.len() == 1 { "is" } else { "are" },
            ),
        }
    }
}
