//! The body's materials from the scene and the mesh (docs/method.md §8.5): `[material]`'s
//! constants for the cells no `[[materials]]` entry claims, each entry's for its group's cells;
//! each material's memory checked against the time step, and its volumetric rule chosen by its
//! own K/G.

use super::error::{group_error, SolveError};
use crate::fem::assembly::Volumetric;
use crate::fem::materials::{BodyMaterial, Materials};
use crate::material::PlaneModel;
use crate::mesh::Mesh;
use crate::scene::{self, Constants, Scene};

/// From this K/G on (ν ≥ 0.495) a material is nearly incompressible for hvi's elements, which
/// lock (the plain P1/Q1 cells; [`Volumetric::Mean`] is chosen from here on by
/// `formulation = "auto"`): measured on 2D Hertz (a block on a rigid cylinder,
/// docs/troubleshooting.md), the contact half-width and peak pressure are within 1.5 % at
/// ν = 0.49 (K/G = 50), off by up to 7.8 % at 0.499 (K/G = 500) and by up to 40 % at 0.4999.
pub const LOCKING_BULK_TO_SHEAR: f64 = 100.0;

/// The materials of `scene` on `mesh` for the 2D model `plane` (None: 3D).
pub fn build<const D: usize>(
    scene: &Scene,
    mesh: &Mesh<D>,
    plane: Option<PlaneModel>,
) -> Result<Materials, SolveError> {
    let constants = scene.constants();
    let several = constants.len() > 1;
    let mut list = Vec::with_capacity(constants.len());
    for c in &constants {
        list.push(material(scene, mesh, c, plane, several)?);
    }
    if scene.materials.is_empty() {
        return Ok(Materials::one(list.pop().expect("[material]"), &mesh.cells));
    }
    // (one entry alone must still claim every cell)
    let mut of = of_cell(scene, mesh, &constants)?;
    // [material]'s constants where the entries claim every cell: not a material of the body (its
    // memory would cost a product per step for nothing)
    if scene.has_unnamed_material() && !of.contains(&0) {
        list.remove(0);
        of.iter_mut().for_each(|m| *m -= 1);
    }
    Ok(Materials::new(list, of, &mesh.cells))
}

/// One material: its constants, its memory (checked against the time step), its formulation.
fn material<const D: usize>(
    scene: &Scene,
    mesh: &Mesh<D>,
    c: &Constants,
    plane: Option<PlaneModel>,
    several: bool,
) -> Result<BodyMaterial, SolveError> {
    // the scene's checks have run these too (with D from material.plane), naming the file
    let scene_error = |e: scene::MaterialError| SolveError::Setup(format!("the scene's {e}"));
    let (elasticity, memory) = c.model(plane).map_err(scene_error)?;
    if let Some(m) = &memory {
        let stepping = scene
            .time
            .stepping(&scene.origin)
            .map_err(|e| SolveError::Setup(e.to_string()))?;
        scene
            .check_time_step(m, elasticity.tensor(), D, &stepping)
            .map_err(|e| scene_error(e.of(c, several)))?;
    }
    let name = match c.group {
        Some(g) => mesh
            .group(g, D as u8)
            .map_err(group_error(&scene.origin, &c.key("group")))?
            .label(),
        None => "[material]".to_string(),
    };
    let mut material = BodyMaterial {
        name,
        elasticity,
        memory,
        volumetric: Volumetric::Pointwise,
    };
    // mean dilatation where the material is nearly incompressible, or as the scene forces
    let nearly_incompressible = material
        .bulk_to_shear()
        .is_some_and(|(at_once, long_term)| at_once.max(long_term.unwrap_or(0.0)) >= LOCKING_BULK_TO_SHEAR);
    material.volumetric = match c.formulation {
        scene::Formulation::Auto if nearly_incompressible => Volumetric::Mean,
        scene::Formulation::MeanDilatation if elasticity.plane == Some(PlaneModel::Stress) => {
            return Err(SolveError::Setup(format!(
                "{}: `{}` = \"mean_dilatation\": plane stress has no volumetric constraint to relieve (it does not \
                 lock); use plane = \"strain\", or leave `formulation` out",
                scene.origin,
                c.key("formulation")
            )))
        }
        scene::Formulation::MeanDilatation => Volumetric::Mean,
        _ => Volumetric::Pointwise,
    };
    Ok(material)
}

/// Each cell's material: the `[[materials]]` entry whose group holds it, else `[material]`'s
/// (index 0) when it has constants. A cell in two entries' groups, or in none without
/// `[material]` constants, is refused, naming the groups.
fn of_cell<const D: usize>(scene: &Scene, mesh: &Mesh<D>, constants: &[Constants]) -> Result<Vec<u32>, SolveError> {
    const UNSET: u32 = u32::MAX;
    let mut of = vec![UNSET; mesh.cells.len()];
    for c in constants.iter().filter(|c| c.group.is_some()) {
        let key = c.key("group");
        let group = mesh
            .group(c.group.expect("an entry's group"), D as u8)
            .map_err(group_error(&scene.origin, &key))?;
        for &cell in &group.cells {
            if of[cell] != UNSET {
                let other = &constants[of[cell] as usize];
                return Err(SolveError::Setup(format!(
                    "{}: `{key}` = {} and `{}` = {} share cell {} (gmsh element {}): each cell has one material; \
                     give the two physical groups no common elements",
                    scene.origin,
                    group.label(),
                    other.key("group"),
                    other.group.map_or(String::new(), |g| g.to_string()),
                    cell,
                    mesh.cell_tags.get(cell).copied().unwrap_or(0)
                )));
            }
            of[cell] = c.index as u32;
        }
    }
    let unnamed = scene.has_unnamed_material();
    let Some(first) = of.iter().position(|&m| m == UNSET) else {
        return Ok(of);
    };
    if unnamed {
        of.iter_mut().filter(|m| **m == UNSET).for_each(|m| *m = 0);
        return Ok(of);
    }
    let count = of.iter().filter(|&&m| m == UNSET).count();
    let groups: Vec<String> = mesh
        .groups
        .iter()
        .filter(|g| g.dim as usize == D && g.cells.contains(&first))
        .map(|g| g.label())
        .collect();
    let which = match groups.is_empty() {
        true => "in no physical group".to_string(),
        false => format!("in group {}", groups.join(", ")),
    };
    Err(SolveError::Setup(format!(
        "{}: {count} cells of {} have no material — the first, cell {first} (gmsh element {}), is {which} — and \
         [material] gives no constants of its own: add a [[materials]] entry with group = that group, or give \
         [material] youngs_modulus and poisson_ratio (the material of every cell no entry claims)",
        scene.origin,
        mesh.path.display(),
        mesh.cell_tags.get(first).copied().unwrap_or(0)
    )))
}
