//! The serde types of a scene file (TOML). Unknown keys are caught before deserialising by
//! [`super::validate::check_keys`], which also suggests the nearest valid key.
//!
//! Over 600 lines because it is one schema: every section of a scene with its documented defaults,
//! in one place so that the scene table of docs/scenes.md can be checked against it.

use crate::mesh::GroupSelector;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// A whole scene: the physics to simulate. An absent optional section is an absent effect.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// How messages name the scene: its file, or [`super::DEFAULT_SCENE_ORIGIN`] (not a key).
    #[serde(skip)]
    pub origin: String,
    #[serde(default)]
    pub groups: Groups,
    pub material: Material,
    /// `[[materials]]`: the materials of physical groups of the body, each with its own constants
    /// and memory (docs/method.md §8.5); the cells of no such group have `[material]`'s.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<MaterialPart>,
    /// `[memory]` (one term) or `[[memory]]` sections (B(s) = Σ_m b_m(s) B_m, docs/method.md §15)
    /// of `[material]`'s constants.
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "memory_sections",
        serialize_with = "write_memory_sections"
    )]
    pub memory: Vec<MemorySpec>,
    pub time: TimeSpec,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dirichlet: Vec<DirichletSpec>,
    /// `[[force_control]]` sections: a group moved rigidly along one axis by the displacement
    /// that makes its total reaction a given force (docs/method.md §7.7).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub force_control: Vec<ForceControlSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub traction: Vec<TractionSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body_force: Option<BodyForceSpec>,
    /// `[contact]` (one group: `groups.contact`) or `[[contact]]` sections, each with its
    /// `group` (docs/method.md §14).
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "contact_sections",
        serialize_with = "write_contact_sections"
    )]
    pub contact: Vec<ContactSpec>,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default)]
    pub output: OutputSpec,
}

/// Which physical groups play Γ₁ and Γ₃.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Groups {
    /// Γ₁, every component zero. Absent: "Gamma1" — unless the scene has `[[dirichlet]]`
    /// sections, which then say everything that is prescribed ([`Scene::clamped_group`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clamped: Option<GroupSelector>,
    /// Not written when it is the default: a scene with `[[contact]]` sections (which leave it at
    /// the default) must read back, and those refuse `groups.contact`.
    #[serde(default = "default_contact", skip_serializing_if = "is_default_contact")]
    pub contact: GroupSelector,
}

fn default_contact() -> GroupSelector {
    GroupSelector::Name("Gamma3".into())
}

fn is_default_contact(g: &GroupSelector) -> bool {
    *g == default_contact()
}

impl Default for Groups {
    fn default() -> Self {
        Groups {
            clamped: None,
            contact: default_contact(),
        }
    }
}

impl Scene {
    /// The group of contact section `i`: its `group`, or `groups.contact` for the `[contact]` table.
    pub fn contact_group(&self, i: usize) -> GroupSelector {
        self.contact[i]
            .group
            .clone()
            .unwrap_or_else(|| self.groups.contact.clone())
    }

    /// How messages name contact section `i`: `contact` for the one table, else `contact[i]`.
    pub fn contact_key(&self, i: usize) -> String {
        if self.contact.len() > 1 || self.contact.iter().any(|c| c.group.is_some()) {
            format!("contact[{i}]")
        } else {
            "contact".into()
        }
    }

    /// The group clamped in every component: `groups.clamped`, or "Gamma1" when the scene says
    /// neither that nor any `[[dirichlet]]` section.
    pub fn clamped_group(&self) -> Option<GroupSelector> {
        match &self.groups.clamped {
            Some(g) => Some(g.clone()),
            None if self.dirichlet.is_empty() && self.force_control.is_empty() => {
                Some(GroupSelector::Name("Gamma1".into()))
            }
            None => None,
        }
    }
}

/// Prescribed displacement components on a group (docs/method.md §7).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirichletSpec {
    pub group: GroupSelector,
    /// Which components: any of "x", "y", "z".
    pub components: Vec<String>,
    /// One expression of (x, y, z, t) per listed component; absent: all zero.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<Vec<String>>,
}

/// A group moved rigidly along one axis by an unknown δ(t) such that the total force the group
/// exerts on the body along that axis is `force` (docs/method.md §7.7).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceControlSpec {
    pub group: GroupSelector,
    /// "x", "y" or "z".
    pub component: String,
    /// P(t), an expression of t: the total force on the body through the group along the axis
    /// (what its row of reactions.csv then reads).
    pub force: String,
}

/// Plane stress or plane strain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Plane {
    Stress,
    Strain,
    /// A body of revolution about the y axis: x = r ≥ 0, y = z (docs/method.md §8.6).
    Axisymmetric,
}

/// Isotropic linear elasticity A: Young's modulus and Poisson's ratio, or a relaxation modulus
/// (which gives A = G(0) and the memory term, docs/method.md §15.2).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// The 2D model (required for a 2D mesh, an error for a 3D one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plane: Option<Plane>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson_ratio: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relaxation_modulus: Option<RelaxationModulusSpec>,
    /// How the volumetric strain enters (docs/method.md §8.4): automatic by K/G, or forced.
    #[serde(default, skip_serializing_if = "is_auto")]
    pub formulation: Formulation,
}

/// `[[materials]]`: the material of the cells of one physical group of the body (a surface in
/// 2D, a volume in 3D), with its own constants, formulation and memory (docs/method.md §8.5).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialPart {
    pub group: GroupSelector,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson_ratio: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relaxation_modulus: Option<RelaxationModulusSpec>,
    /// Absent: `material.formulation`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formulation: Option<Formulation>,
    /// Its memory terms, as `[[memory]]` (`[materials.memory]` or `[[materials.memory]]`).
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "memory_sections",
        serialize_with = "write_memory_sections"
    )]
    pub memory: Vec<MemorySpec>,
}

/// One material's constants as the scene gives them: `[material]` with the `[memory]` sections,
/// or a `[[materials]]` entry — what the checks and the set-up read, whichever it is.
#[derive(Clone, Copy, Debug)]
pub struct Constants<'a> {
    /// Its index in [`Scene::constants`].
    pub index: usize,
    /// The `[[materials]]` entry's group; None for `[material]`.
    pub group: Option<&'a GroupSelector>,
    pub youngs_modulus: Option<f64>,
    pub poisson_ratio: Option<f64>,
    pub relaxation_modulus: Option<&'a RelaxationModulusSpec>,
    pub formulation: Formulation,
    pub memory: &'a [MemorySpec],
    /// Its place in `[[materials]]`; None for `[material]`.
    part: Option<usize>,
}

impl Constants<'_> {
    /// How messages name one of its keys: `material.youngs_modulus` or
    /// `materials[1].youngs_modulus`.
    pub fn key(&self, key: &str) -> String {
        match self.part {
            None => format!("material.{key}"),
            Some(i) => format!("materials[{i}].{key}"),
        }
    }

    /// The key of the whole table: `material` or `materials[1]`.
    pub fn table(&self) -> String {
        match self.part {
            None => "material".into(),
            Some(i) => format!("materials[{i}]"),
        }
    }

    /// How messages name its memory section `i`: `memory` / `memory[i]` for `[material]`'s,
    /// `materials[1].memory` / `materials[1].memory[i]` for an entry's.
    pub fn memory_key(&self, i: usize) -> String {
        let prefix = match self.part {
            None => String::new(),
            Some(p) => format!("materials[{p}]."),
        };
        if self.memory.len() > 1 {
            format!("{prefix}memory[{i}]")
        } else {
            format!("{prefix}memory")
        }
    }
}

/// The element formulation's volumetric part (docs/method.md §8.4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Formulation {
    /// Mean dilatation where the material is nearly incompressible (K/G ≥ 100 at t = 0 or once
    /// relaxed, plane strain and 3D), the plain element elsewhere.
    #[default]
    Auto,
    /// The plain displacement element everywhere.
    Standard,
    /// Mean dilatation (B-bar) on quadrilaterals, hexahedra, prisms and pyramids.
    MeanDilatation,
}

fn is_auto(f: &Formulation) -> bool {
    *f == Formulation::Auto
}

/// Bulk and shear relaxation moduli κ(t), G(t), each a Prony series; or Young's relaxation
/// modulus E(t) with a constant Poisson's ratio (bulk and shear then relax alike: κ = E/(3(1 − 2ν)),
/// G = E/(2(1 + ν)), docs/method.md §15.2). Checked by `validate::check_material`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RelaxationModulusSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bulk: Option<PronySeriesSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear: Option<PronySeriesSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs: Option<PronySeriesSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson_ratio: Option<f64>,
}

impl RelaxationModulusSpec {
    /// κ(t) and G(t): as given, or from E(t) and ν (each term's moduli by the same factors, so that
    /// they are proportional to the bit). None when neither form is complete.
    pub fn bulk_and_shear(&self) -> Option<(PronySeriesSpec, PronySeriesSpec)> {
        match (&self.bulk, &self.shear, &self.youngs, self.poisson_ratio) {
            (Some(b), Some(s), None, None) => Some((b.clone(), s.clone())),
            (None, None, Some(e), Some(nu)) => {
                let scaled = |factor: f64| PronySeriesSpec {
                    long_term: factor * e.long_term,
                    terms: e
                        .terms
                        .iter()
                        .map(|t| ModulusTermSpec {
                            modulus: factor * t.modulus,
                            relaxation_time: t.relaxation_time,
                        })
                        .collect(),
                };
                Some((scaled(1.0 / (3.0 * (1.0 - 2.0 * nu))), scaled(1.0 / (2.0 * (1.0 + nu)))))
            }
            _ => None,
        }
    }
}

/// f(t) = f∞ + Σ_m f_m e^{−t/τ_m}.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PronySeriesSpec {
    /// f∞ ≥ 0.
    pub long_term: f64,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub terms: Vec<ModulusTermSpec>,
}

/// One term f_m e^{−t/τ_m} of a relaxation modulus.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModulusTermSpec {
    pub modulus: f64,
    pub relaxation_time: f64,
}

/// One term b(s) B of the memory: a scalar kernel and its tensor (default: the identity).
#[derive(Clone, Debug)]
pub struct MemorySpec {
    pub kernel: MemoryKernelSpec,
    pub tensor: Option<TensorSpec>,
}

/// The keys of a memory section as written (read without `serde(flatten)`, so that an error in
/// `kind` or a value points at its own line).
#[derive(Serialize, Deserialize)]
struct RawMemorySpec {
    kind: KernelKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    coefficients: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    terms: Option<Vec<PronyTerm>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    expression: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tensor: Option<TensorSpec>,
}

#[derive(Clone, Copy, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum KernelKind {
    Polynomial,
    Exponential,
    Expression,
}

impl<'de> Deserialize<'de> for MemorySpec {
    fn deserialize<De: serde::Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        use serde::de::Error;
        let raw = RawMemorySpec::deserialize(d)?;
        let kernel = match raw.kind {
            KernelKind::Polynomial => MemoryKernelSpec::Polynomial {
                coefficients: raw
                    .coefficients
                    .ok_or_else(|| De::Error::missing_field("coefficients"))?,
            },
            KernelKind::Exponential => MemoryKernelSpec::Exponential {
                terms: raw.terms.ok_or_else(|| De::Error::missing_field("terms"))?,
            },
            KernelKind::Expression => MemoryKernelSpec::Expression {
                expression: raw.expression.ok_or_else(|| De::Error::missing_field("expression"))?,
            },
        };
        Ok(MemorySpec {
            kernel,
            tensor: raw.tensor,
        })
    }
}

impl Serialize for MemorySpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut raw = RawMemorySpec {
            kind: KernelKind::Polynomial,
            coefficients: None,
            terms: None,
            expression: None,
            tensor: self.tensor,
        };
        match &self.kernel {
            MemoryKernelSpec::Polynomial { coefficients } => raw.coefficients = Some(coefficients.clone()),
            MemoryKernelSpec::Exponential { terms } => {
                raw.kind = KernelKind::Exponential;
                raw.terms = Some(terms.clone());
            }
            MemoryKernelSpec::Expression { expression } => {
                raw.kind = KernelKind::Expression;
                raw.expression = Some(expression.clone());
            }
        }
        raw.serialize(s)
    }
}

impl From<MemoryKernelSpec> for MemorySpec {
    /// The kernel on the identity (the paper's B(s) = b(s) I).
    fn from(kernel: MemoryKernelSpec) -> Self {
        MemorySpec { kernel, tensor: None }
    }
}

/// The scalar relaxation kernel b(s) of one memory term.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum MemoryKernelSpec {
    /// b(s) = Σ c_j s^j.
    Polynomial { coefficients: Vec<f64> },
    /// b(s) = Σ c_m e^{−s/τ_m}.
    Exponential { terms: Vec<PronyTerm> },
    /// Any b(s).
    Expression { expression: String },
}

/// One term c e^{−s/τ} of a Prony series.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PronyTerm {
    pub coefficient: f64,
    pub relaxation_time: f64,
}

/// The tensor B of a memory term: `"identity"` (the paper), `"elasticity"` (B = A), or
/// `{ bulk = κ, shear = G }` (λ = κ − 2G/3, μ = G).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TensorSpec {
    Identity,
    Elasticity,
    Moduli { bulk: f64, shear: f64 },
}

impl Serialize for TensorSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        match self {
            TensorSpec::Identity => s.serialize_str("identity"),
            TensorSpec::Elasticity => s.serialize_str("elasticity"),
            TensorSpec::Moduli { bulk, shear } => {
                let mut m = s.serialize_map(Some(2))?;
                m.serialize_entry("bulk", bulk)?;
                m.serialize_entry("shear", shear)?;
                m.end()
            }
        }
    }
}

impl<'de> Deserialize<'de> for TensorSpec {
    fn deserialize<De: serde::Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Moduli {
            bulk: f64,
            shear: f64,
        }
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = TensorSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "memory.tensor: \"identity\" (the paper), \"elasticity\" (B = A) or { bulk = κ, shear = G }",
                )
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<TensorSpec, E> {
                match v {
                    "identity" => Ok(TensorSpec::Identity),
                    "elasticity" => Ok(TensorSpec::Elasticity),
                    _ => Err(E::custom(format!(
                        "memory.tensor = \"{v}\": give \"identity\" (the paper), \"elasticity\" (B = A) or \
                         {{ bulk = κ, shear = G }}"
                    ))),
                }
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<TensorSpec, A::Error> {
                let m = Moduli::deserialize(serde::de::value::MapAccessDeserializer::new(map))?;
                Ok(TensorSpec::Moduli {
                    bulk: m.bulk,
                    shear: m.shear,
                })
            }
        }
        d.deserialize_any(Visitor)
    }
}

fn memory_sections<'de, De: serde::Deserializer<'de>>(d: De) -> Result<Vec<MemorySpec>, De::Error> {
    struct Sections;
    impl<'de> serde::de::Visitor<'de> for Sections {
        type Value = Vec<MemorySpec>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a [memory] table or [[memory]] sections")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
            Ok(vec![MemorySpec::deserialize(
                serde::de::value::MapAccessDeserializer::new(map),
            )?])
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
            Vec::<MemorySpec>::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))
        }
    }
    d.deserialize_any(Sections)
}

fn write_memory_sections<S: serde::Serializer>(specs: &[MemorySpec], s: S) -> Result<S::Ok, S::Error> {
    match specs {
        [one] => one.serialize(s),
        _ => specs.serialize(s),
    }
}

impl Scene {
    /// How messages name memory section `i` of `[material]`: `memory` for one, else `memory[i]`.
    pub fn memory_key(&self, i: usize) -> String {
        self.material_constants().memory_key(i)
    }

    /// `[material]`'s constants with the `[memory]` sections.
    pub fn material_constants(&self) -> Constants<'_> {
        let m = &self.material;
        Constants {
            index: 0,
            group: None,
            youngs_modulus: m.youngs_modulus,
            poisson_ratio: m.poisson_ratio,
            relaxation_modulus: m.relaxation_modulus.as_ref(),
            formulation: m.formulation,
            memory: &self.memory,
            part: None,
        }
    }

    /// Whether `[material]` gives constants of its own (the material of the cells no
    /// `[[materials]]` entry claims): always without `[[materials]]`, else when it has any.
    pub fn has_unnamed_material(&self) -> bool {
        let m = &self.material;
        self.materials.is_empty()
            || m.youngs_modulus.is_some()
            || m.poisson_ratio.is_some()
            || m.relaxation_modulus.is_some()
            || !self.memory.is_empty()
    }

    /// Every material's constants: `[material]`'s first when it has its own
    /// ([`Self::has_unnamed_material`]), then the `[[materials]]` entries in order.
    pub fn constants(&self) -> Vec<Constants<'_>> {
        let unnamed = self.has_unnamed_material().then(|| self.material_constants());
        let parts = self.materials.iter().enumerate().map(|(i, p)| Constants {
            index: 0,
            group: Some(&p.group),
            youngs_modulus: p.youngs_modulus,
            poisson_ratio: p.poisson_ratio,
            relaxation_modulus: p.relaxation_modulus.as_ref(),
            formulation: p.formulation.unwrap_or(self.material.formulation),
            memory: &p.memory,
            part: Some(i),
        });
        unnamed
            .into_iter()
            .chain(parts)
            .enumerate()
            .map(|(index, c)| Constants { index, ..c })
            .collect()
    }
}

/// The time levels on [0, T] (docs/method.md §20, docs/scenes.md "Time steps"): exactly one way
/// of stepping — `steps` (uniform), `first_step` with `steps_per_decade` or `growth`
/// (geometric), `times` (listed) or `tolerance` (automatic, with `first_step`, `min_step`,
/// `max_step` optional); checked by src/scene/time.rs.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    pub final_time: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_step: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps_per_decade: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub times: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_step: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_step: Option<f64>,
    /// The memory integral's rule over a step (docs/method.md §20.2); absent: exact for Prony
    /// terms and relaxation moduli, the paper's trapezoid for polynomial kernels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadrature: Option<QuadratureSpec>,
}

/// `time.quadrature`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QuadratureSpec {
    Trapezoid,
    Exact,
}

/// A traction density on a boundary group: either its components (`value`) or a pressure p,
/// the traction −p ν with ν the facet's outward unit normal (docs/method.md §11.2). Exactly one.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TractionSpec {
    pub group: GroupSelector,
    /// One expression per component (2 in 2D, 3 in 3D); empty when `pressure` is given.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub value: Vec<String>,
    /// p(x, y, z, t, nx, ny, nz): positive pushes into the body.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure: Option<String>,
}

/// A body force density.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyForceSpec {
    /// One expression per component (2 in 2D, 3 in 3D).
    pub value: Vec<String>,
}

/// Contact on a group: the bound u_ν ≤ g and/or a normal-compliance law, against the layer of
/// the paper or a rigid obstacle (docs/method.md §14).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// The contact group: required in `[[contact]]`; in the `[contact]` table `groups.contact`
    /// (default "Gamma3") names it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<GroupSelector>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bound: Option<BoundSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law: Option<ContactLawSpec>,
    /// A rigid obstacle: the surface the body first touches (its initial gap is computed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obstacle: Option<ObstacleSpec>,
    /// The direction of u_ν: the obstacle's normal (default with an obstacle) or the body's
    /// nodal normal (the paper; the only one without an obstacle).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<ContactDirection>,
    /// A tangential law beside the normal one (docs/method.md §17); absent: frictionless.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<FrictionSpec>,
    /// Bilateral contact: u_ν = 0 on the group (the body slides along the surface and cannot
    /// leave it), the normal condition of the non-monotone friction examples (docs/method.md
    /// §17.4); no law and no bound beside it.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub bilateral: bool,
    /// The master surface of contact with another deformable body (docs/method.md §18): the
    /// group is the slave surface, paired once with this one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<GroupSelector>,
    /// Tied contact with the target: the slave surface glued to the master as it lies, the
    /// relative displacement zero in every direction (docs/method.md §18.3).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub tied: bool,
}

impl ContactSpec {
    /// True if the section poses contact: a law, a bound, an obstacle, a target or bilateral
    /// contact.
    pub fn is_posed(&self) -> bool {
        self.bound.is_some() || self.law.is_some() || self.obstacle.is_some() || self.bilateral || self.target.is_some()
    }
}

/// The friction law of a contact group, acting on the slip increment of a step
/// (docs/method.md §17).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum FrictionSpec {
    /// |σ_τ| ≤ F_b with F_b an expression of (x, y, z, t): stick below it, slip against the slip
    /// increment at it.
    Tresca {
        bound: String,
        #[serde(default = "default_friction_regularisation")]
        regularisation: f64,
    },
    /// F_b = μ |σ_ν|, with σ_ν the node's normal contact pressure of the same step (implicit);
    /// μ a number or an expression of the node's accumulated slip `s` (slip-dependent friction).
    Coulomb {
        coefficient: FrictionCoefficient,
        #[serde(default = "default_friction_regularisation")]
        regularisation: f64,
    },
    /// The hemivariational case: −σ_τ ∈ ∂j_τ(u_τ) with j_τ(ξ) = S ∫₀^{|ξ|} μ(r) dr on the total
    /// tangential displacement, μ any of the normal laws' profiles (non-monotone ones included).
    Potential { law: ContactLawSpec },
}

/// A Coulomb coefficient: a number, or an expression of the accumulated slip `s`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(untagged)]
pub enum FrictionCoefficient {
    Value(f64),
    Expression(String),
}

fn default_friction_regularisation() -> f64 {
    1e-8
}

impl FrictionSpec {
    /// ε of the smoothed |Δu_τ|.
    pub fn regularisation(&self) -> f64 {
        match self {
            FrictionSpec::Tresca { regularisation, .. } | FrictionSpec::Coulomb { regularisation, .. } => {
                *regularisation
            }
            FrictionSpec::Potential { law } => law.regularisation,
        }
    }
}

/// The direction in which a contact constraint and its law act.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactDirection {
    /// The body's nodal normal ν_p (the paper).
    Body,
    /// The obstacle's normal at the point closest to the node.
    Obstacle,
}

/// A rigid obstacle; `normal`/the sign of `sdf` point out of the obstacle, toward the body.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ObstacleSpec {
    /// The half-space {(x − point)·normal < 0}.
    Plane {
        point: Vec<f64>,
        normal: Vec<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        motion: Option<Vec<String>>,
    },
    /// A rigid disc (2D) or ball (3D); the body is outside it.
    #[serde(alias = "sphere")]
    Circle {
        centre: Vec<f64>,
        radius: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        motion: Option<Vec<String>>,
    },
    /// {φ(x, y, z) < 0}: φ > 0 where the body is, its zero level set the obstacle's surface.
    Sdf {
        sdf: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        motion: Option<Vec<String>>,
    },
}

impl ObstacleSpec {
    /// The rigid displacement a(t) of the obstacle, one expression of t per component.
    pub fn motion(&self) -> Option<&[String]> {
        match self {
            ObstacleSpec::Plane { motion, .. }
            | ObstacleSpec::Circle { motion, .. }
            | ObstacleSpec::Sdf { motion, .. } => motion.as_deref(),
        }
    }
}

fn contact_sections<'de, De: serde::Deserializer<'de>>(d: De) -> Result<Vec<ContactSpec>, De::Error> {
    struct Sections;
    impl<'de> serde::de::Visitor<'de> for Sections {
        type Value = Vec<ContactSpec>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a [contact] table or [[contact]] sections")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
            Ok(vec![ContactSpec::deserialize(
                serde::de::value::MapAccessDeserializer::new(map),
            )?])
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
            Vec::<ContactSpec>::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))
        }
    }
    d.deserialize_any(Sections)
}

fn write_contact_sections<S: serde::Serializer>(specs: &[ContactSpec], s: S) -> Result<S::Ok, S::Error> {
    match specs {
        [one] if one.group.is_none() => one.serialize(s),
        _ => specs.serialize(s),
    }
}

/// The variables of a bound expression g(x, y, z): the reference position of the contact node
/// (z = 0 in 2D).
pub const BOUND_VARIABLES: [&str; 3] = ["x", "y", "z"];

/// The bound g of u_ν ≤ g (the paper's layer thickness, docs/method.md §10): one number for all
/// of Γ₃, or an expression g(x, y, z) ≥ 0 evaluated at each contact node (the constraint is
/// imposed at the nodes: the paper's external approximation).
#[derive(Clone, Debug, PartialEq)]
pub enum BoundSpec {
    Number(f64),
    Expression(String),
}

impl From<f64> for BoundSpec {
    fn from(g: f64) -> Self {
        BoundSpec::Number(g)
    }
}

impl Serialize for BoundSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            BoundSpec::Number(g) => s.serialize_f64(*g),
            BoundSpec::Expression(e) => s.serialize_str(e),
        }
    }
}

impl<'de> Deserialize<'de> for BoundSpec {
    fn deserialize<De: serde::Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = BoundSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "contact.bound: a number g ≥ 0 (bound = 0.2) or an expression of x, y, z in quotes \
                     (bound = \"0.2 + 0.02*sin(6*PI*x)\")",
                )
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<BoundSpec, E> {
                Ok(BoundSpec::Number(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<BoundSpec, E> {
                Ok(BoundSpec::Number(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<BoundSpec, E> {
                Ok(BoundSpec::Number(v as f64))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<BoundSpec, E> {
                Ok(BoundSpec::Expression(v.to_string()))
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// A normal-compliance law j_ν = S ∫ μ and its regularisation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ContactLawSpec {
    #[serde(flatten)]
    pub kind: LawKind,
    #[serde(default)]
    pub one_sided: bool,
    #[serde(default = "default_regularisation")]
    pub regularisation: f64,
}

fn default_regularisation() -> f64 {
    1e-8
}

/// The menu of laws.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LawKind {
    /// μ(s) = (a − b) e^{−αs} + b (docs/example.md (5.3)).
    Paper { scale: f64, a: f64, b: f64, alpha: f64 },
    /// μ(s) = s^p: p_ν = S (u_ν)₊^p.
    Power { scale: f64, exponent: f64 },
    /// μ piecewise linear through `table = [[s0, μ0], [s1, μ1], …]`, s0 = 0.
    PiecewiseLinear { scale: f64, table: Vec<[f64; 2]> },
    /// As piecewise_linear, the table read from a CSV file of `s,mu` rows (relative to the scene).
    Tabulated { scale: f64, file: PathBuf },
}

/// Contact solver settings.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// How a step is condensed onto the contact normals (docs/method.md §9).
    #[serde(default)]
    pub condensation: CondensationKind,
    /// Free contact nodes above which the Newton matrix's factorisation is kept and reused as the
    /// preconditioner of conjugate gradients (docs/method.md §9.2).
    #[serde(default = "default_dense_newton_limit")]
    pub dense_newton_limit: usize,
    /// Strategies of the contact solve switched off, by name: for measuring what each is worth
    /// (docs/ablation.md); empty for the default solver.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub without: Vec<String>,
}

fn default_dense_newton_limit() -> usize {
    // measured at m = 4 096 (docs/method.md §9.2): a soft layer whose surface stays free, contact
    // solves 16.2 s → 3.05 s; the paper law with a bound, where the kept factor does not serve,
    // 2.47 s either way; the slab 96x48x12 (m = 1 248) unchanged
    1000
}

/// The implementations of the contact condensation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CondensationKind {
    /// The faer factor's forward and backward sweeps around the contact solve (one solve).
    #[default]
    SplitSweeps,
    /// Stored responses Z = K⁻¹Cᵀ and a whole solve per step.
    StoredResponses,
    /// Z = K⁻¹Cᵀ only while W = C Z is formed; per step a free and a recovery solve (nothing of
    /// size n·m is held: the memory-light path, which the PETSc backend takes by itself when Z
    /// does not fit its budget, docs/method.md §13).
    RecoverySolve,
}

fn default_tolerance() -> f64 {
    1e-10
}
fn default_max_iterations() -> usize {
    100
}

impl Default for SolverSpec {
    fn default() -> Self {
        SolverSpec {
            tolerance: default_tolerance(),
            max_iterations: default_max_iterations(),
            condensation: CondensationKind::default(),
            dense_newton_limit: default_dense_newton_limit(),
            without: Vec::new(),
        }
    }
}

/// A field that can be written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputField {
    Displacement,
    Stress,
    VonMises,
    Contact,
}

/// Which steps and fields are written.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Every n-th step is written (and the last); absent: every step, or with `times` none but
    /// those.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every: Option<usize>,
    /// Times at which frames are written: levels of the run (a step is split, or an automatic
    /// step lands, to reach them; docs/method.md §20.1).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub times: Vec<f64>,
    #[serde(default = "default_fields")]
    pub fields: Vec<OutputField>,
    /// zlib compression of the `.vtu`/`.vtp` files: `false` (default), `true` (level
    /// [`DEFAULT_COMPRESS_LEVEL`]) or a level 0–9; checked by `validate::check_values`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compress: Option<toml::Value>,
    /// The body's active scalars, what ParaView and `hvi plot` colour by: one of the point
    /// fields written ([`OutputSpec::scalar_names`]); `von_mises` when absent (docs/method.md §12.3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub active_scalar: Option<String>,
}

/// The zlib level of `output.compress = true` (measured in docs/outputs.md, "Compression").
pub const DEFAULT_COMPRESS_LEVEL: u32 = 1;

impl OutputSpec {
    /// The point fields of the body that `output.fields` writes, by name: the values
    /// `output.active_scalar` may take.
    pub fn scalar_names(&self) -> Vec<&'static str> {
        [
            (OutputField::VonMises, "von_mises"),
            (OutputField::Displacement, "displacement"),
            (OutputField::Stress, "stress"),
        ]
        .iter()
        .filter(|(f, _)| self.fields.contains(f))
        .map(|(_, n)| *n)
        .collect()
    }

    /// The name of the body's active scalars: `output.active_scalar`, else `von_mises` when it is
    /// written, else None (the writer's default: the first 1-component field).
    pub fn active_scalar_name(&self) -> Option<&str> {
        match &self.active_scalar {
            Some(n) => Some(n.as_str()),
            None => self.fields.contains(&OutputField::VonMises).then_some("von_mises"),
        }
    }

    /// The zlib level `output.compress` asks for (0: uncompressed); a value that
    /// `validate::check_values` rejects counts as 0.
    pub fn compression_level(&self) -> u32 {
        match &self.compress {
            Some(toml::Value::Boolean(true)) => DEFAULT_COMPRESS_LEVEL,
            Some(toml::Value::Integer(l)) if (0..=9).contains(l) => *l as u32,
            _ => 0,
        }
    }
}

fn default_fields() -> Vec<OutputField> {
    vec![
        OutputField::Displacement,
        OutputField::Stress,
        OutputField::VonMises,
        OutputField::Contact,
    ]
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            every: None,
            times: Vec::new(),
            fields: default_fields(),
            compress: None,
            active_scalar: None,
        }
    }
}
