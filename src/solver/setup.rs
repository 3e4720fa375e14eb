//! The discrete problem of a scene on a mesh of dimension D, holding only the effects the scene
//! names: no `[memory]` (or relaxation modulus) → no kernel, no `[contact]` → no contact nodes, no load → no load terms,
//! no non-zero prescribed value → no lifting.

use super::dirichlet::Dirichlet;
use super::error::SolveError;
use crate::fem::loads::Loads;
use crate::fem::materials::Materials;
use crate::fem::DofMap;
use crate::material::PlaneModel;
use crate::mesh::{GroupSelector, Mesh};
use crate::scene::{self, Expr, Scene};

/// The most unknowns of two-body contact rows ordered last in 3D ([`Simulation::unknowns_ordered_last`]):
/// their trailing block is dense, 1 500² / 2 entries (9 MB) at most; a whole graded face of 1 656
/// nodes ordered last tripled the factor (docs/method.md §9.9), so larger pairs keep METIS's order.
pub const PAIR_LAST_UNKNOWNS: usize = 1500;

pub use crate::time::{Schedule, TimeGrid};

pub use super::contact::ContactSetup;

/// Everything a run needs, built once from scene + mesh.
pub struct Simulation<const D: usize> {
    pub mesh: Mesh<D>,
    pub dofs: DofMap<D>,
    /// The prescribed components and their values (docs/method.md §7).
    pub dirichlet: Dirichlet<D>,
    /// The materials, each cell's, and their memories as one (docs/method.md §8.5, §15).
    pub materials: Materials,
    pub loads: Loads<D>,
    pub contact: Option<ContactSetup<D>>,
    /// The time levels: a fixed grid, or automatic steps (docs/method.md §20).
    pub time: Schedule,
    /// The memory's rule over a step per kind of kernel (`time.quadrature`, docs/method.md §20.2).
    pub rules: crate::material::Rules,
    /// `output.every` (None: every step, or only `output.times` when they are given).
    pub output_every: Option<usize>,
    pub threads: usize,
    /// How a step is condensed onto the contact normals.
    pub condensation: scene::CondensationKind,
}

fn exprs<const D: usize>(
    value: &[String],
    variables: &[&str],
    origin: &str,
    key: &str,
) -> Result<[Expr; D], SolveError> {
    if value.len() != D {
        return Err(SolveError::Setup(format!(
            "{origin}: {key} has {} components but the mesh is {D}D: give {D} expressions ({})",
            value.len(),
            ["x", "y", "z"][..D].join(", ")
        )));
    }
    let parse = |i: usize| {
        Expr::parse(&value[i], variables)
            .map_err(|e| SolveError::Setup(format!("{origin}: {key}[{i}] = \"{}\": {e}", value[i])))
    };
    let mut out = Vec::with_capacity(D);
    for i in 0..D {
        out.push(parse(i)?);
    }
    Ok(out.try_into().unwrap_or_else(|_| unreachable!("D expressions")))
}

/// The nodes on the axis r = x = 0 of a body of revolution (None: not one): u_r = 0 there
/// (docs/method.md §8.6). A node at r < 0 is refused: the meridian section lies in x ≥ 0.
fn axis_nodes<const D: usize>(scene: &Scene, mesh: &Mesh<D>) -> Result<Option<Vec<usize>>, SolveError> {
    if D != 2 || scene.material.plane != Some(scene::Plane::Axisymmetric) {
        return Ok(None);
    }
    let size = mesh
        .points
        .iter()
        .map(|p| p[0].abs().max(p[1].abs()))
        .fold(0.0, f64::max);
    let tolerance = 1e-12 * size.max(f64::MIN_POSITIVE);
    if let Some(p) = mesh.points.iter().position(|p| p[0] < -tolerance) {
        return Err(SolveError::Setup(format!(
            "{}: material.plane = \"axisymmetric\" takes x as the radius r ≥ 0, but node {p} is at {}: mesh the \
             meridian section on the side x ≥ 0 of the axis x = 0",
            mesh.path.display(),
            crate::mesh::fmt_point(mesh.points[p])
        )));
    }
    Ok(Some(
        (0..mesh.points.len())
            .filter(|&p| mesh.points[p][0] <= tolerance)
            .collect(),
    ))
}

/// The 2D model of the scene on a mesh of dimension D (None: 3D).
fn plane_model<const D: usize>(scene: &Scene, origin: &str) -> Result<Option<PlaneModel>, SolveError> {
    Ok(match (D, scene.material.plane) {
        (2, Some(p)) => Some(match p {
            scene::Plane::Stress => PlaneModel::Stress,
            scene::Plane::Strain => PlaneModel::Strain,
            scene::Plane::Axisymmetric => PlaneModel::Axisymmetric,
        }),
        (2, None) => {
            return Err(SolveError::Setup(format!(
                "{origin} is a 2D mesh: say which 2D model in the scene, material.plane = \"stress\", \"strain\" or \"axisymmetric\""
            )))
        }
        (_, Some(_)) if scene.origin == scene::DEFAULT_SCENE_ORIGIN => {
            return Err(SolveError::Setup(format!(
                "{origin} is a 3D mesh, but no scene was given and the embedded default is the paper's 2D example \
                 (examples/paper.toml, plane strain); a 3D body needs a scene of its own: --scene \
                 examples/slab.toml (the paper's example on a slab) or one of yours (docs/scenes.md)"
            )))
        }
        (_, Some(_)) => {
            return Err(SolveError::Setup(format!(
                "{origin} is a 3D mesh, but the scene {} sets material.plane: plane stress and plane strain are 2D \
                 models; remove material.plane for a 3D body",
                scene.origin
            )))
        }
        (_, None) => None,
    })
}

/// c when the run's one memory channel's tensor is c A of its one material: every step matrix is
/// then (1 + c β) K_A (docs/method.md §20.3).
fn proportional_memory(materials: &crate::fem::materials::Materials) -> Option<f64> {
    match (materials.list(), materials.memory()) {
        ([one], Some(m)) => m.proportional_to_elasticity(one.elasticity.tensor()),
        _ => None,
    }
}

impl<const D: usize> Simulation<D> {
    /// Whether the state of step 0 stands for every step (one solve for the run): no memory and
    /// nothing that changes in time — loads, prescribed values, forces, a moving obstacle
    /// (docs/method.md §14.2). The plan and the time loop both ask here.
    pub fn is_static(&self) -> bool {
        self.materials.memory().is_none()
            && !self.loads.is_time_dependent()
            && !self.dirichlet.is_time_dependent()
            && self.contact.as_ref().is_none_or(|c| c.motion.is_none())
            && !self
                .dirichlet
                .rigid
                .iter()
                .any(|p| p.force.as_ref().is_some_and(|e| e.depends_on("t")))
    }

    /// Builds the discrete problem of `scene` on `mesh`.
    pub fn new(scene: &Scene, mesh: Mesh<D>) -> Result<Self, SolveError> {
        let origin = mesh.path.display().to_string();
        let clamped: Option<GroupSelector> = scene.clamped_group();
        let times = scene
            .time
            .stepping(&scene.origin)
            .map_err(|e| SolveError::Setup(e.to_string()))?
            .sample_times(scene.time.final_time);
        // the nodes of the contact groups and their targets: the contact may hold what the
        // prescribed components leave free (docs/method.md §7.7, §18), the body on either side of
        // a pair; a group that is not there is reported by the contact
        let contact_nodes: Option<Vec<usize>> = super::contact::is_posed(scene).then(|| {
            (0..scene.contact.len())
                .flat_map(|i| std::iter::once(scene.contact_group(i)).chain(scene.contact[i].target.clone()))
                .filter_map(|g| mesh.boundary(&g).ok())
                .flat_map(|part| part.nodes)
                .collect()
        });
        let axis = axis_nodes(scene, &mesh)?;
        let (dofs, dirichlet) = Dirichlet::new(
            &mesh,
            (clamped.as_ref(), &scene.dirichlet, &scene.force_control),
            contact_nodes.as_deref().filter(|n| !n.is_empty()),
            axis.as_deref(),
            &times,
            &scene.origin,
        )?;
        let plane = plane_model::<D>(scene, &origin)?;
        let materials = super::materials::build(scene, &mesh, plane)?;
        let time = super::schedule::build(scene, &materials, proportional_memory(&materials).is_some())?;
        let axisymmetric = plane == Some(PlaneModel::Axisymmetric);
        let mut loads = if axisymmetric {
            Loads::axisymmetric()
        } else {
            Loads::new()
        };
        for (i, t) in scene.traction.iter().enumerate() {
            let part = mesh.boundary(&t.group).map_err(super::error::group_error(
                &scene.origin,
                &format!("traction[{i}].group"),
            ))?;
            if let Some(p) = &t.pressure {
                let key = format!("traction[{i}].pressure");
                let p = Expr::parse(p, &scene::TRACTION_VARIABLES)
                    .map_err(|e| SolveError::Setup(format!("{origin}: {key} = \"{p}\": {e}")))?;
                loads.add_pressure(&part, &mesh.points, p, &key);
                continue;
            }
            let key = format!("traction[{i}].value");
            loads.add_traction(
                &part,
                &mesh.points,
                exprs(&t.value, &scene::TRACTION_VARIABLES, &origin, &key)?,
                &key,
            );
        }
        if let Some(f) = &scene.body_force {
            loads.add_body_force(
                &mesh.cells,
                &mesh.points,
                exprs(&f.value, &scene::BODY_FORCE_VARIABLES, &origin, "body_force.value")?,
                "body_force.value",
            );
        }
        let contact = super::contact::build(scene, &mesh, &dofs, &origin)?;
        Ok(Simulation {
            mesh,
            dofs,
            dirichlet,
            materials,
            loads,
            contact,
            time,
            rules: scene.time.rules(),
            output_every: scene.output.every,
            threads: 1,
            condensation: scene.solver.condensation,
        })
    }

    /// The unknowns the factor orders last: those of the contact normals where Q is read off the
    /// factor's trailing block ([`Self::trailing_block`], docs/method.md §9.1, §9.4), else none.
    /// Only the unknowns a row uses (non-zero coefficient): a row lists every free component of
    /// its node, and ordering the zero ones last too cost 13–17 % more fill (box n = 32:
    /// 30.05 M → 26.54 M entries below the diagonal; n = 40: 91.1 M → 77.8 M stored).
    /// Until 2026-12-06 also up to 2 000 contact nodes with the sweeps of G: on a graded
    /// tetrahedral block with its whole face in contact (benches/graded, 1 656 nodes on a
    /// sphere) that tripled the factor (57.4 M entries against 18.3 M, CHOLMOD's METIS 18.7 M)
    /// and the run took 4.5 s against 1.6 s with the sweeps blocked on the unconstrained
    /// factor (docs/method.md §9.9).
    ///
    /// Also, in 3D, the unknowns of rows of contact between two bodies (docs/method.md §18.5),
    /// up to [`PAIR_LAST_UNKNOWNS`]: both surfaces' normal components last keep the columns of
    /// G = L⁻¹PCᵀ within the trailing block, where otherwise each slave and master unknown's
    /// path to the root ran through a different body's tree (benches/two_bodies.rs, 3D, m = 512,
    /// 850 unknowns last: condensation 137 → 28 ms, the sweeps of 32 steps 0.51 → 0.35 s, the
    /// whole run 1.29 → 1.11 s, the factor 9.6 M → 10.8 M entries).
    pub fn unknowns_ordered_last(&self) -> Vec<usize> {
        match &self.contact {
            Some(c) if self.trailing_block() => c.condensed_rows().unknowns(),
            Some(c) if D == 3 && !c.targets.is_empty() => {
                let unknowns = c.condensed_rows().unknowns();
                if unknowns.len() <= PAIR_LAST_UNKNOWNS {
                    unknowns
                } else {
                    Vec::new()
                }
            }
            _ => Vec::new(),
        }
    }

    /// Whether the condensation reads Q off the factor's trailing block (docs/method.md §9.4): in
    /// 3D, by split sweeps, with each contact node's rows using as many unknowns as there are
    /// rows (a face normal to an axis; with friction, any frame). The one place this is decided:
    /// the ordering, the condensation, the memory prediction and the plan follow it.
    pub fn trailing_block(&self) -> bool {
        D == 3
            && self.condensation == scene::CondensationKind::SplitSweeps
            && self
                .contact
                .as_ref()
                .is_some_and(|c| !c.nodes.is_empty() && c.condensed_rows().trailing_block_applies())
    }

    /// Whether the trailing-block condensation forms W beside Q (docs/method.md §9.4, §9.7):
    /// with friction, whose first round without normal forces solves on the normal rows with
    /// (W_νν)⁻¹ (docs/method.md §17.2); without it a product by W is two triangular solves with L_cc.
    pub fn forms_w_off_trailing_block(&self) -> bool {
        self.contact.as_ref().is_some_and(|c| c.friction.is_some())
    }

    /// c when every step matrix is (1 + c β) K_A: one memory channel ∝ A of the one material
    /// (docs/method.md §20.3).
    pub fn proportional_memory(&self) -> Option<f64> {
        proportional_memory(&self.materials)
    }

    /// True if level n of a fixed grid is written: every `output.every`-th (every one without
    /// `output.every` and `output.times`), each output time, and always t = 0 and the last.
    pub fn is_output_step(&self, n: usize) -> bool {
        let Some(grid) = self.time.grid() else {
            return false;
        };
        let every = self
            .output_every
            .or((!grid.has_marks()).then_some(1))
            .is_some_and(|e| n.is_multiple_of(e));
        n == 0 || every || grid.is_marked(n) || n == grid.steps()
    }

    /// The loads and prescribed values evaluated on their groups before anything is factorised
    /// (docs/method.md §16.3): at t_0 when nothing depends on t, else at t_0, t_1, t_N and evenly
    /// spaced steps between (at most 16 in all), so that a NaN or an infinity in the data stops
    /// the run at once with the key, the point and the time. One at a time not evaluated here
    /// stops the run at that step (the time loop evaluates them every step).
    pub fn check_data(&self) -> Result<(), SolveError> {
        let varies = self.loads.is_time_dependent() || self.dirichlet.is_time_dependent();
        let at = if varies {
            self.time.sample()
        } else {
            vec![(Some(0), 0.0)]
        };
        let mut load = vec![0.0; self.dofs.n()];
        let mut prescribed = vec![0.0; self.dofs.n()];
        for (n, t) in at {
            let failed = |detail| SolveError::NonFiniteLoad {
                step: n,
                time: t,
                detail,
            };
            if !self.loads.is_empty() {
                self.loads.assemble(t, &self.dofs, &mut load).map_err(failed)?;
            }
            self.dirichlet.values(t, &mut prescribed).map_err(failed)?;
        }
        Ok(())
    }
}
