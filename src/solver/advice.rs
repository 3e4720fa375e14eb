//! Warnings of `hvi check`: set-ups that are valid but probably not what the user meant
//! (docs/method.md §14.5). Each is a sentence naming the group and what to do instead.

use super::materials::LOCKING_BULK_TO_SHEAR;
use super::setup::Simulation;
use crate::fem::materials::BodyMaterial;
use crate::scene::{BoundSpec, Scene};

/// The angle (degrees) between two nodal normals of one contact group above which its Γ₃
/// counts as curved: a constant bound then follows the curve instead of a flat foundation.
const CURVED_DEGREES: f64 = 10.0;

/// The warnings for a scene on its simulation (empty: nothing looks unintended).
pub fn warnings<const D: usize>(scene: &Scene, sim: &Simulation<D>) -> Vec<String> {
    let mut out = Vec::new();
    let several = sim.materials.list().len() > 1;
    for (i, material) in sim.materials.list().iter().enumerate() {
        let which = if several {
            format!("the material of {}", material.name)
        } else {
            "the material".to_string()
        };
        out.extend(unresolved_relaxation(scene, sim, material, &which));
        let cells: Vec<&crate::mesh::Cell> = (0..sim.mesh.cells.len())
            .filter(|&c| sim.materials.id_of_cell(c).index() == i)
            .map(|c| &sim.mesh.cells[c])
            .collect();
        out.extend(locking(material, &cells, &which));
    }
    // a traction on a group whose displacement is prescribed does work only on the reaction
    let prescribed: Vec<(String, String)> = scene
        .clamped_group()
        .map(|g| (g.to_string(), "every component (groups.clamped)".to_string()))
        .into_iter()
        .chain(scene.dirichlet.iter().map(|d| {
            (
                d.group.to_string(),
                format!("components {} ([[dirichlet]])", d.components.join(", ")),
            )
        }))
        .collect();
    for t in &scene.traction {
        let name = t.group.to_string();
        for (g, what) in prescribed.iter().filter(|(g, _)| *g == name) {
            out.push(format!(
                "a traction acts on group {g}, whose {what} is prescribed: the load there only changes the \
                 reaction; put the load on a group that is free in its direction, or drop it"
            ));
        }
    }
    let Some(c) = &sim.contact else {
        return out;
    };
    let diameter = body_diameter(&sim.mesh.points);
    // two sections on one group: their rows are merged per wall (§14.3), so the laws add up and
    // the stricter bound wins; meant for one group meeting two obstacles, a slip if repeated
    for (j, tag) in c.group_tags.iter().enumerate() {
        if let Some(i) = c.group_tags[..j].iter().position(|t| t == tag) {
            out.push(format!(
                "[[contact]] sections {i} and {j} both name group `{}`: at every node their walls are merged \
                 where they lie within 45° (the stricter bound wins and both laws act, each with the node's full \
                 weight, so a repeated section doubles the law's force) and kept apart where they do not \
                 (docs/method.md §14.3); unless the group really meets two obstacles, give it one section",
                c.groups[j]
            ));
        }
    }
    for (i, spec) in scene.contact.iter().enumerate() {
        let group = c.groups.get(i).cloned().unwrap_or_else(|| format!("#{i}"));
        let rows: Vec<usize> = (0..c.row_group.len()).filter(|&p| c.row_group[p] == i).collect();
        // (two sections on one group share its rows, kept under the first: §14.3)
        let same_group = |j: usize| c.group_tags.get(j) == c.group_tags.get(i);
        if rows.is_empty() && !c.row_group.iter().any(|&j| same_group(j)) {
            out.push(format!(
                "contact group `{group}` has no contact unknowns: every node of it has its normal component \
                 prescribed (it is the clamped group, or a [[dirichlet]] group's), so it can never touch; name the \
                 group that touches in `groups.contact` (or `contact[{i}].group`)"
            ));
            continue;
        }
        // a constant bound along each node's own normal on a curved Γ₃: the foundation is then a
        // copy of Γ₃ shifted by g, not a flat obstacle
        if spec.obstacle.is_none() && matches!(spec.bound, Some(BoundSpec::Number(_))) {
            let cos = CURVED_DEGREES.to_radians().cos();
            let curved = rows.iter().any(|&p| {
                rows.iter().any(|&q| {
                    let (a, b) = (c.nodes.normals[p], c.nodes.normals[q]);
                    (0..D).map(|k| a[k] * b[k]).sum::<f64>() < cos
                })
            });
            if curved {
                out.push(format!(
                    "contact group `{group}` is curved (its normals differ by more than {CURVED_DEGREES}°) and has a \
                     constant bound but no obstacle: each node may move g along its own normal, so the foundation \
                     is Γ₃ shifted by g, not a flat surface; for a rigid body use `obstacle = {{ kind = \"plane\", \
                     … }}` (docs/method.md §14)"
                ));
            }
        }
        let never: Vec<usize> = c
            .never_touching
            .iter()
            .filter(|&&(_, g)| g == i)
            .map(|&(n, _)| n)
            .collect();
        if let Some(&n) = never.first() {
            out.push(match &spec.target {
                Some(target) => format!(
                    "{} node(s) of contact group `{group}` project onto no facet of its target `{target}` (e.g. the \
                     node at {:?}) and have no contact row; if they can touch the other body, extend the target \
                     surface to lie under them (docs/method.md §18)",
                    never.len(),
                    sim.mesh.points[n]
                ),
                None => format!(
                    "{} node(s) of contact group `{group}` never meet its obstacle along their normal (e.g. the node \
                     at {:?}) and are left out of the contact problem; check the obstacle's position and `direction`",
                    never.len(),
                    sim.mesh.points[n]
                ),
            });
        }
        if let Some(gap) = &c.gap {
            let far: Vec<usize> = rows
                .iter()
                .copied()
                .filter(|&p| gap[p].is_finite() && gap[p] > diameter)
                .collect();
            // a node that starts inside its obstacle is pushed out at t = 0: an interference fit
            // if meant, a misplaced obstacle (or a normal pointing the wrong way) if not
            let inside: Vec<usize> = rows.iter().copied().filter(|&p| gap[p] < -1e-9 * diameter).collect();
            if let Some(&deepest) = inside.iter().min_by(|&&p, &&q| gap[p].total_cmp(&gap[q])) {
                out.push(format!(
                    "{} node(s) of contact group `{group}` start inside its obstacle (deepest: the node at {:?}, \
                     {:.3e} inside): at t = 0 the body is pushed out of it, an interference fit; if that is not \
                     meant, check the obstacle's position and that its normal (or φ > 0) points toward the body",
                    inside.len(),
                    sim.mesh.points[c.nodes.nodes[deepest]],
                    -gap[deepest]
                ));
            }
            if let Some(&p) = far.first() {
                out.push(format!(
                    "{} node(s) of contact group `{group}` start farther from the obstacle than the body's size \
                     ({diameter:.3e}; e.g. the node at {:?}, gap {:.3e}): they can hardly ever touch; check the \
                     obstacle's position and units",
                    far.len(),
                    sim.mesh.points[c.nodes.nodes[p]],
                    gap[p]
                ));
            }
        }
    }
    // a slave surface finer than its target: more multipliers than the target's displacements
    // carry, and the pressure may oscillate (docs/method.md §18.2)
    for (name, s) in &c.pairs {
        if s.slave_size < FINER_SLAVE * s.master_size {
            out.push(format!(
                "pair {name}: the slave surface's facets ({:.3e}) are finer than the target's ({:.3e}) where they \
                 meet: a multiplier per slave node is then more than the target's displacements can carry, and the \
                 contact pressure may oscillate; make the coarser surface the slave (swap group and target), or \
                 refine the target (docs/method.md §18.2)",
                s.slave_size, s.master_size
            ));
        }
    }
    out
}

/// A pair warns when its slave facets are smaller than this share of its master facets: the
/// gallery's punch (examples/gallery/two_bodies) as the slave, at 0.0067 on the pad's 0.01, had
/// neighbouring pressures 73 % of the peak apart, at 0.015 on 0.01 5.5 %.
pub const FINER_SLAVE: f64 = 0.75;

/// The diagonal of the points' bounding box.
fn body_diameter<const D: usize>(points: &[[f64; D]]) -> f64 {
    (0..D)
        .map(|k| {
            let (lo, hi) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            });
            (hi - lo).powi(2)
        })
        .sum::<f64>()
        .sqrt()
}

/// A relaxation the time step does not resolve with the trapezoid: the scheme's long-term moduli,
/// which set the creep's end value, are off (docs/method.md §15.3; not positive at all is
/// refused). The exact rule sums them exactly: nothing to say.
fn unresolved_relaxation<const D: usize>(
    scene: &Scene,
    sim: &Simulation<D>,
    material: &BodyMaterial,
    which: &str,
) -> Option<String> {
    let m = material.memory.as_ref()?;
    let (a, k) = (material.elasticity.tensor(), sim.time.largest_step());
    let off = m
        .long_term_error(a, D, k, sim.rules)
        .filter(|&off| off > crate::material::LONG_TERM_TOLERANCE)?;
    let needed = m
        .largest_accurate_step(a, D, crate::material::LONG_TERM_TOLERANCE, k, sim.rules)
        .map_or(String::new(), |k1| match scene.time.steps {
            Some(_) => format!(
                "; time.steps ≥ {} bring them within 1 %",
                (scene.time.final_time / k1).ceil()
            ),
            None => format!("; steps below {k1:e} bring them within 1 %"),
        });
    Some(format!(
        "the time step k = {k:e} does not resolve the relaxation of {which} with time.quadrature = \"trapezoid\": the \
         scheme's long-term moduli are {:.1} % off the material's (the trapezoid rule over-integrates each relaxation \
         term by about (k/τ)²/12 of its strength, which a small long-term modulus feels most), and a creep under a \
         constant load ends at the displacement those moduli give{needed}; time.quadrature = \"exact\" sums them \
         exactly on any steps (docs/method.md §15.3, §20.2)",
        100.0 * off
    ))
}

/// A nearly incompressible material (at once, or as its shear relaxes) on `cells`, its cells:
/// those that do not project their volumetric strain lock (docs/method.md §8.4).
fn locking(material: &BodyMaterial, cells: &[&crate::mesh::Cell], which: &str) -> Option<String> {
    let (at_once, long_term) = material.bulk_to_shear()?;
    let (ratio, when, nu) = match long_term {
        Some(l) if l > at_once => (
            l,
            " once relaxed (κ∞/G∞)",
            format!("{:.6}", (3.0 * l - 2.0) / (6.0 * l + 2.0)),
        ),
        _ => (at_once, "", format!("{}", material.elasticity.poisson_ratio)),
    };
    // the plain element locks wherever the bulk part is taken pointwise
    let locked = cells.iter().filter(|c| !material.volumetric.projects(c)).count();
    let what = "hvi's plain P1/Q1 elements";
    (ratio >= LOCKING_BULK_TO_SHEAR && locked > 0).then(|| {
        format!(
            "{which} is nearly incompressible{when}: K/G = {ratio:.3e} (ν = {nu}); {what} lock there and come out \
             too stiff (2D Hertz: up to 7.8 % off in a and p₀ at ν = 0.499, up to 40 % at 0.4999; \
             docs/troubleshooting.md); leave `formulation` at \"auto\" or set \"mean_dilatation\" (per cell on \
             quadrilaterals and hexahedra, over patches of cells on triangles and tetrahedra, docs/method.md §8.4)"
        )
    })
}
