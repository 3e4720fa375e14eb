//! Checks of a scene: every key known (with the nearest valid key suggested), every value in
//! range, every expression compiling and finite at a probe point.
//!
//! Over 600 lines because it is one pass: every value of every section, with a message that names
//! the key, the value and the fix.

use super::error::{invalid, SceneError};
use super::types::{
    BoundSpec, Constants, ContactDirection, ContactLawSpec, LawKind, MemoryKernelSpec, MemorySpec, ObstacleSpec, Scene,
    TensorSpec, BOUND_VARIABLES,
};
use crate::expr::Expr;
use toml::Value;

/// The keys allowed in a table, given its path and contents.
fn allowed_keys(path: &str, table: &toml::Table) -> Option<Vec<&'static str>> {
    let kind = table.get("kind").and_then(|v| v.as_str());
    // a `[[materials]]` entry's relaxation modulus and memory are those of `[material]`
    let path = match path.strip_prefix("materials.") {
        Some(rest) if rest.starts_with("relaxation_modulus") => format!("material.{rest}"),
        Some(rest) => rest.to_string(),
        None => path.to_string(),
    };
    Some(match path.as_str() {
        "" => vec![
            "groups",
            "material",
            "materials",
            "memory",
            "time",
            "dirichlet",
            "force_control",
            "traction",
            "body_force",
            "contact",
            "solver",
            "output",
        ],
        "groups" => vec!["clamped", "contact"],
        "material" => vec![
            "plane",
            "youngs_modulus",
            "poisson_ratio",
            "relaxation_modulus",
            "formulation",
        ],
        "materials" => vec![
            "group",
            "youngs_modulus",
            "poisson_ratio",
            "relaxation_modulus",
            "formulation",
            "memory",
        ],
        "material.relaxation_modulus" => vec!["bulk", "shear", "youngs", "poisson_ratio"],
        "material.relaxation_modulus.bulk"
        | "material.relaxation_modulus.shear"
        | "material.relaxation_modulus.youngs" => vec!["long_term", "terms"],
        "material.relaxation_modulus.bulk.terms"
        | "material.relaxation_modulus.shear.terms"
        | "material.relaxation_modulus.youngs.terms" => {
            vec!["modulus", "relaxation_time"]
        }
        "memory" => match kind {
            Some("polynomial") => vec!["kind", "coefficients", "tensor"],
            Some("exponential") => vec!["kind", "terms", "tensor"],
            Some("expression") => vec!["kind", "expression", "tensor"],
            _ => vec!["kind", "coefficients", "terms", "expression", "tensor"],
        },
        "memory.terms" => vec!["coefficient", "relaxation_time"],
        "memory.tensor" => vec!["bulk", "shear"],
        "time" => vec![
            "final_time",
            "steps",
            "first_step",
            "steps_per_decade",
            "growth",
            "times",
            "tolerance",
            "min_step",
            "max_step",
            "quadrature",
        ],
        "traction" => vec!["group", "value", "pressure"],
        "dirichlet" => vec!["group", "components", "value"],
        "force_control" => vec!["group", "component", "force"],
        "body_force" => vec!["value"],
        "contact" => vec![
            "group",
            "bound",
            "law",
            "obstacle",
            "direction",
            "friction",
            "bilateral",
            "target",
            "tied",
        ],
        "contact.friction" => match kind {
            Some("tresca") => vec!["kind", "bound", "regularisation"],
            Some("coulomb") => vec!["kind", "coefficient", "regularisation"],
            Some("potential") => vec!["kind", "law"],
            _ => vec!["kind", "bound", "coefficient", "regularisation", "law"],
        },
        "contact.obstacle" => match kind {
            Some("plane") => vec!["kind", "point", "normal", "motion"],
            Some("circle") | Some("sphere") => vec!["kind", "centre", "radius", "motion"],
            Some("sdf") => vec!["kind", "sdf", "motion"],
            _ => vec!["kind", "point", "normal", "centre", "radius", "sdf", "motion"],
        },
        "contact.law" | "contact.friction.law" => {
            let mut keys = vec!["kind", "one_sided", "regularisation", "scale"];
            keys.extend(match kind {
                Some("paper") => vec!["a", "b", "alpha"],
                Some("power") => vec!["exponent"],
                Some("piecewise_linear") => vec!["table"],
                Some("tabulated") => vec!["file"],
                _ => vec!["a", "b", "alpha", "exponent", "table", "file"],
            });
            keys
        }
        "solver" => vec![
            "tolerance",
            "max_iterations",
            "condensation",
            "dense_newton_limit",
            "without",
        ],
        "output" => vec!["every", "times", "fields", "compress", "active_scalar"],
        _ => return None,
    })
}

/// Levenshtein distance (for "did you mean").
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1];
        for (j, cb) in b.iter().enumerate() {
            cur.push((prev[j] + usize::from(ca != *cb)).min(prev[j + 1] + 1).min(cur[j] + 1));
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Rejects unknown keys anywhere in the tree, naming the nearest valid one.
pub fn check_keys(value: &Value, origin: &str) -> Result<(), SceneError> {
    walk(value, "", "", origin)?;
    // `[[contact]]` sections name their groups; `groups.contact` belongs to the one-table form.
    let sections = value.get("contact").and_then(|c| c.as_array());
    let shorthand = value.get("groups").and_then(|g| g.get("contact"));
    if let (Some(sections), Some(group)) = (sections, shorthand) {
        return Err(invalid(
            origin,
            "groups.contact",
            group,
            &format!(
                "the scene has {} [[contact]] section(s), each naming its own `group`; groups.contact belongs to the \
                 one-group [contact] table: remove groups.contact, or write one [contact] table",
                sections.len()
            ),
        ));
    }
    if let Some(sections) = sections {
        for (i, s) in sections.iter().enumerate() {
            if s.get("group").is_none() {
                return Err(invalid(
                    origin,
                    &format!("contact[{i}].group"),
                    "(missing)",
                    "each [[contact]] section names its group, e.g. group = \"Gamma3\"",
                ));
            }
        }
    }
    if let (Some(group), Some(inner)) = (shorthand, value.get("contact").and_then(|c| c.get("group"))) {
        return Err(invalid(
            origin,
            "contact.group",
            inner,
            &format!("groups.contact = {group} names the contact group too: give it in one place only"),
        ));
    }
    Ok(())
}

/// `shown`: how messages name the table (`contact[1]` for the second `[[contact]]` section);
/// `path`: the dotted path that selects its valid keys.
fn walk(value: &Value, path: &str, shown: &str, origin: &str) -> Result<(), SceneError> {
    match value {
        Value::Table(table) => {
            if let Some(allowed) = allowed_keys(path, table) {
                for (key, v) in table {
                    if !allowed.contains(&key.as_str()) {
                        let best = allowed.iter().min_by_key(|k| distance(key, k)).copied();
                        let suggestion = match best {
                            _ if key == "motion" && allowed.contains(&"obstacle") => {
                                " (`motion` belongs inside the obstacle's table: obstacle = { kind = \"plane\", …, \
                                 motion = [\"0\", \"-0.1*t\"] })"
                                    .to_string()
                            }
                            Some(b) if distance(key, b) <= (key.len() / 3).max(2) => format!(" (did you mean `{b}`?)"),
                            _ => String::new(),
                        };
                        return Err(SceneError::UnknownKey {
                            origin: origin.into(),
                            section: if path.is_empty() {
                                "the top level".into()
                            } else if shown.contains('[') {
                                shown.to_string()
                            } else {
                                format!("[{shown}]")
                            },
                            key: key.clone(),
                            suggestion,
                            allowed: allowed.join(", "),
                        });
                    }
                    let child = if path.is_empty() {
                        key.clone()
                    } else {
                        format!("{path}.{key}")
                    };
                    let shown_child = if shown.is_empty() {
                        key.clone()
                    } else {
                        format!("{shown}.{key}")
                    };
                    walk(v, &child, &shown_child, origin)?;
                }
            }
            Ok(())
        }
        Value::Array(items) if items.len() > 1 || items.iter().all(Value::is_table) => items
            .iter()
            .enumerate()
            .try_for_each(|(i, v)| walk(v, path, &format!("{shown}[{i}]"), origin)),
        Value::Array(items) => items.iter().try_for_each(|v| walk(v, path, shown, origin)),
        _ => Ok(()),
    }
}

/// Range checks of every value; expressions compile and are finite at a probe point.
pub fn check_values(scene: &Scene, origin: &str) -> Result<(), SceneError> {
    for c in scene.constants() {
        check_material(&c, origin)?;
    }
    let stepping = super::time::check(scene, origin)?;
    for c in scene.constants() {
        for (i, spec) in c.memory.iter().enumerate() {
            check_memory(spec, origin, &c.memory_key(i))?;
        }
        check_memory_model(scene, &c, origin, &stepping)?;
    }
    for (i, dc) in scene.dirichlet.iter().enumerate() {
        if dc.components.is_empty() {
            return Err(invalid(
                origin,
                &format!("dirichlet[{i}].components"),
                "[]",
                "list the prescribed components, e.g. components = [\"z\"] or [\"x\", \"y\"]",
            ));
        }
        for (k, c) in dc.components.iter().enumerate() {
            if !matches!(c.as_str(), "x" | "y" | "z") || dc.components[..k].contains(c) {
                return Err(invalid(
                    origin,
                    &format!("dirichlet[{i}].components"),
                    format!("{:?}", dc.components),
                    "components are \"x\", \"y\" and \"z\", each at most once",
                ));
            }
        }
        if let Some(values) = &dc.value {
            if values.len() != dc.components.len() {
                return Err(invalid(
                    origin,
                    &format!("dirichlet[{i}].value"),
                    format!("{values:?}"),
                    &format!(
                        "give one expression per listed component ({} of them), or omit value for zero",
                        dc.components.len()
                    ),
                ));
            }
            for (c, v) in values.iter().enumerate() {
                compile_load(
                    origin,
                    &format!("dirichlet[{i}].value[{c}]"),
                    v,
                    &super::BODY_FORCE_VARIABLES,
                    &[0.0; 4],
                )?;
            }
        }
    }
    for (i, fc) in scene.force_control.iter().enumerate() {
        if !matches!(fc.component.as_str(), "x" | "y" | "z") {
            return Err(invalid(
                origin,
                &format!("force_control[{i}].component"),
                format!("{:?}", fc.component),
                "the axis the group moves along: \"x\", \"y\" or \"z\"",
            ));
        }
        compile_load(origin, &format!("force_control[{i}].force"), &fc.force, &["t"], &[0.0])?;
    }
    for (i, tr) in scene.traction.iter().enumerate() {
        match (&tr.pressure, tr.value.is_empty()) {
            (Some(p), true) => {
                compile_load(
                    origin,
                    &format!("traction[{i}].pressure"),
                    p,
                    &super::TRACTION_VARIABLES,
                    &[0.0; 7],
                )?;
                continue;
            }
            (Some(p), false) => {
                return Err(invalid(
                    origin,
                    &format!("traction[{i}].pressure"),
                    format!("\"{p}\" beside value = {:?}", tr.value),
                    "a [[traction]] section gives either value (the traction's components) or pressure (the traction −p·ν), not both",
                ))
            }
            (None, true) => {
                return Err(invalid(
                    origin,
                    &format!("traction[{i}].value"),
                    "(absent)",
                    "give value = [\"fx\", \"fy\"] (3D: three) or pressure = \"p\" (the traction −p·ν, ν the outward normal)",
                ))
            }
            (None, false) => {}
        }
        check_components(origin, &format!("traction[{i}].value"), &tr.value)?;
        for c in 0..tr.value.len() {
            compile_load(
                origin,
                &format!("traction[{i}].value[{c}]"),
                &tr.value[c],
                &super::TRACTION_VARIABLES,
                &[0.0; 7],
            )?;
        }
    }
    if let Some(f) = &scene.body_force {
        check_components(origin, "body_force.value", &f.value)?;
        for c in 0..f.value.len() {
            compile_load(
                origin,
                &format!("body_force.value[{c}]"),
                &f.value[c],
                &super::BODY_FORCE_VARIABLES,
                &[0.0; 4],
            )?;
        }
    }
    let many = scene.contact.len() > 1 || scene.contact.iter().any(|c| c.group.is_some());
    for (i, c) in scene.contact.iter().enumerate() {
        let at = scene.contact_key(i);
        if let Some(f) = &c.friction {
            check_friction(f, origin, &at)?;
        }
        if c.tied && c.target.is_none() {
            return Err(invalid(
                origin,
                &format!("{at}.tied"),
                true,
                "tied contact glues the group to another body's surface: give that surface as `target`",
            ));
        }
        if c.bilateral && (c.bound.is_some() || c.law.is_some()) {
            return Err(invalid(
                origin,
                &format!("{at}.bilateral"),
                true,
                "bilateral contact holds u_ν = 0 on the group: remove its law and its bound, or remove bilateral",
            ));
        }
        if many && !c.is_posed() {
            // a section naming a group and nothing else would be left out without a word
            return Err(invalid(
                origin,
                &format!("{at}.group"),
                c.group.as_ref().map_or("(none)".to_string(), |g| g.to_string()),
                "this contact section has no bound, law or obstacle, so it would impose nothing: give it a `bound`, a \
                 [contact.law], an `obstacle` (docs/method.md §14.1) or `bilateral = true` (§17.4), or remove the \
                 section",
            ));
        }
        match &c.bound {
            Some(BoundSpec::Number(g)) if !(g.is_finite() && *g >= 0.0) => {
                return Err(invalid(
                    origin,
                    &format!("{at}.bound"),
                    g,
                    "the bound g must be ≥ 0 (omit it for no bound), or an expression g(x, y, z) ≥ 0 in quotes such as \"0.2 + 0.02*sin(6*PI*x)\"",
                ));
            }
            // compiled here, evaluated (and checked ≥ 0) at the contact nodes by the solver's
            // set-up: a probe point need not lie where g is defined
            Some(BoundSpec::Expression(e)) => {
                Expr::parse(e, &BOUND_VARIABLES).map_err(|message| SceneError::Expression {
                    origin: origin.into(),
                    key: format!("{at}.bound"),
                    expression: e.clone(),
                    message,
                })?;
            }
            _ => {}
        }
        if let Some(law) = &c.law {
            check_law(law, origin, &at)?;
        }
        if let Some(o) = &c.obstacle {
            check_obstacle(o, origin, &format!("{at}.obstacle"))?;
        }
        if let Some(t) = &c.target {
            // contact with another deformable body (docs/method.md §18): what is there so far
            let refuse = |what: &str, why: &str| invalid(origin, &format!("{at}.{what}"), t, why);
            if c.obstacle.is_some() || c.bound.is_some() || c.direction.is_some() {
                return Err(refuse(
                    "target",
                    "contact with another body (target) takes the gap to the target surface as its bound; an \
                     obstacle, a bound or a direction beside it are not supported (docs/method.md §18): remove them",
                ));
            }
            if c.tied && (c.law.is_some() || c.friction.is_some() || c.bilateral) {
                return Err(invalid(
                    origin,
                    &format!("{at}.tied"),
                    true,
                    "tied contact glues the group to the target in every direction: remove its law, friction and \
                     bilateral, or remove tied",
                ));
            }
            if c.group.is_none() {
                return Err(refuse(
                    "group",
                    "a target needs the slave surface as `group` in a [[contact]] section",
                ));
            }
        }
        if c.direction == Some(ContactDirection::Obstacle) && c.obstacle.is_none() {
            return Err(invalid(
                origin,
                &format!("{at}.direction"),
                "\"obstacle\"",
                "direction = \"obstacle\" needs an obstacle; without one the constraint acts along the body's normal \
                 (direction = \"body\")",
            ));
        }
    }
    if !(scene.solver.tolerance > 0.0 && scene.solver.tolerance < 1.0) {
        return Err(invalid(
            origin,
            "solver.tolerance",
            scene.solver.tolerance,
            "the relative tolerance must lie in (0, 1), e.g. 1e-10",
        ));
    }
    if scene.solver.max_iterations == 0 {
        return Err(invalid(
            origin,
            "solver.max_iterations",
            0,
            "allow at least one iteration",
        ));
    }
    for (i, name) in scene.solver.without.iter().enumerate() {
        if !crate::contact::Strategies::default().switch_off(name) {
            return Err(invalid(
                origin,
                &format!("solver.without[{i}]"),
                format!("\"{name}\""),
                &format!(
                    "name one of the contact solve's strategies (docs/ablation.md): {}",
                    crate::contact::Strategies::NAMES.join(", ")
                ),
            ));
        }
    }
    match &scene.output.compress {
        None | Some(toml::Value::Boolean(_)) => {}
        Some(toml::Value::Integer(l)) if (0..=9).contains(l) => {}
        Some(v) => {
            return Err(invalid(
                origin,
                "output.compress",
                v,
                "give true, false or a zlib level from 0 (none) to 9 (smallest); 1 is fastest, true means 1",
            ))
        }
    }
    if let Some(name) = &scene.output.active_scalar {
        let valid = scene.output.scalar_names();
        if !valid.iter().any(|v| v == name) {
            let fix = if valid.is_empty() {
                "output.fields writes no point field of the body to colour by: add \"von_mises\" to output.fields"
                    .to_string()
            } else {
                format!(
                    "give one of the point fields output.fields writes: {}",
                    valid.iter().map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", ")
                )
            };
            return Err(invalid(origin, "output.active_scalar", format!("\"{name}\""), &fix));
        }
    }
    Ok(())
}

/// A material (`[material]` or a `[[materials]]` entry): either Young's modulus and Poisson's
/// ratio, or a relaxation modulus (then no memory sections: the relaxation modulus is the memory,
/// docs/method.md §15.2).
fn check_material(m: &Constants, origin: &str) -> Result<(), SceneError> {
    if let Some(r) = m.relaxation_modulus {
        for (key, given) in [("youngs_modulus", m.youngs_modulus), ("poisson_ratio", m.poisson_ratio)] {
            if let Some(v) = given {
                return Err(invalid(
                    origin,
                    &m.key(key),
                    v,
                    &format!(
                        "{} is given too, and sets A = G(0): give either youngs_modulus and poisson_ratio, or \
                         relaxation_modulus; remove {} or the relaxation modulus",
                        m.key("relaxation_modulus"),
                        m.key(key)
                    ),
                ));
            }
        }
        if !m.memory.is_empty() {
            return Err(invalid(
                origin,
                &m.memory_key(0),
                format!("({} section(s))", m.memory.len()),
                &format!(
                    "{} is given too, and is the material's memory (B = G′): give either the memory sections or the \
                     relaxation modulus, not both",
                    m.key("relaxation_modulus")
                ),
            ));
        }
        let given = match (&r.bulk, &r.shear, &r.youngs, r.poisson_ratio) {
            (Some(b), Some(s), None, None) => vec![("bulk", b), ("shear", s)],
            (None, None, Some(e), Some(nu)) => {
                if !(nu > -1.0 && nu < 0.5) {
                    return Err(invalid(
                        origin,
                        &m.key("relaxation_modulus.poisson_ratio"),
                        nu,
                        "Poisson's ratio must lie in (−1, 0.5)",
                    ));
                }
                vec![("youngs", e)]
            }
            _ => {
                let keys = super::time::given_keys(&[
                    ("bulk", r.bulk.is_some()),
                    ("shear", r.shear.is_some()),
                    ("youngs", r.youngs.is_some()),
                    ("poisson_ratio", r.poisson_ratio.is_some()),
                ]);
                let with = if keys.is_empty() {
                    "nothing".to_string()
                } else {
                    keys.join(", ")
                };
                return Err(invalid(
                    origin,
                    &m.key("relaxation_modulus"),
                    format!("(with {with})"),
                    "give the bulk and shear relaxation moduli, relaxation_modulus = { bulk = { long_term = κ∞, \
                     terms = [...] }, shear = { ... } }, or Young's relaxation modulus with a constant Poisson's \
                     ratio, relaxation_modulus = { youngs = { long_term = E∞, terms = [...] }, poisson_ratio = ν } \
                     (docs/scenes.md)",
                ));
            }
        };
        for (part, p) in given {
            let at = m.key(&format!("relaxation_modulus.{part}"));
            if !(p.long_term.is_finite() && p.long_term >= 0.0) {
                return Err(invalid(
                    origin,
                    &format!("{at}.long_term"),
                    p.long_term,
                    "the long-term modulus must be finite and ≥ 0",
                ));
            }
            for (i, t) in p.terms.iter().enumerate() {
                if !(t.modulus.is_finite() && t.modulus > 0.0) {
                    return Err(invalid(
                        origin,
                        &format!("{at}.terms[{i}].modulus"),
                        t.modulus,
                        "a Prony term's modulus must be positive and finite (a relaxation modulus decreases; drop \
                         a zero term)",
                    ));
                }
                if !(t.relaxation_time.is_finite() && t.relaxation_time > 0.0) {
                    return Err(invalid(
                        origin,
                        &format!("{at}.terms[{i}].relaxation_time"),
                        t.relaxation_time,
                        "relaxation times must be positive and finite",
                    ));
                }
            }
            if p.long_term == 0.0 && p.terms.is_empty() {
                return Err(invalid(
                    origin,
                    &format!("{at}.long_term"),
                    0,
                    &format!(
                        "the {part} modulus would be zero at every time (no terms and no long-term value): the \
                         instantaneous modulus {part}(0) must be positive"
                    ),
                ));
            }
        }
        let value = |p: &super::PronySeriesSpec| p.long_term + p.terms.iter().map(|t| t.modulus).sum::<f64>();
        let (bulk, shear) = r.bulk_and_shear().expect("a complete form, checked above");
        let (k0, g0) = (value(&bulk), value(&shear));
        let e0 = 9.0 * k0 * g0 / (3.0 * k0 + g0);
        if !(k0.is_finite() && g0.is_finite() && e0.is_finite() && e0 > 0.0) {
            return Err(invalid(
                origin,
                &m.key("relaxation_modulus"),
                format!("κ(0) = {k0:e}, G(0) = {g0:e}"),
                "the instantaneous moduli κ(0) = long_term + Σ modulus and G(0) (and E(0) = 9κG/(3κ + G)) must be \
                 positive and finite",
            ));
        }
        return Ok(());
    }
    let (Some(e), Some(nu)) = (m.youngs_modulus, m.poisson_ratio) else {
        let missing = if m.youngs_modulus.is_none() {
            m.key("youngs_modulus")
        } else {
            m.key("poisson_ratio")
        };
        return Err(invalid(
            origin,
            &missing,
            "(missing)",
            "give youngs_modulus and poisson_ratio (e.g. youngs_modulus = 1.0, poisson_ratio = 0.3), or a \
             relaxation_modulus = { bulk = { long_term = κ∞, terms = [...] }, shear = { ... } }",
        ));
    };
    if !(e.is_finite() && e > 0.0) {
        return Err(invalid(
            origin,
            &m.key("youngs_modulus"),
            e,
            "Young's modulus must be positive and finite",
        ));
    }
    if !(nu > -1.0 && nu < 0.5) {
        return Err(invalid(
            origin,
            &m.key("poisson_ratio"),
            nu,
            "Poisson's ratio must lie in (−1, 0.5)",
        ));
    }
    Ok(())
}

/// The material as constitutive data (docs/method.md §15): in plane stress a tensor with its own
/// moduli only when ∝ A (a relaxation modulus only when bulk and shear relax proportionally), and
/// a time step within the bound a relaxing memory sets. The dimension is the scene's: 2 with
/// `material.plane` (a 2D mesh requires it), 3 without.
fn check_memory_model(
    scene: &Scene,
    c: &Constants,
    origin: &str,
    stepping: &crate::time::Stepping,
) -> Result<(), SceneError> {
    use crate::material::PlaneModel;
    let plane = scene.material.plane.map(|p| match p {
        super::Plane::Stress => PlaneModel::Stress,
        super::Plane::Strain => PlaneModel::Strain,
        super::Plane::Axisymmetric => PlaneModel::Axisymmetric,
    });
    let bad = |e: super::MaterialError| invalid(origin, &e.key, e.value, &e.fix);
    let (elasticity, memory) = c.model(plane).map_err(bad)?;
    if let Some(m) = memory {
        let dim = if plane.is_some() { 2 } else { 3 };
        scene
            .check_time_step(&m, elasticity.tensor(), dim, stepping)
            .map_err(|e| bad(e.of(c, !scene.materials.is_empty())))?;
    }
    Ok(())
}

/// One memory term: its kernel's values and its tensor.
fn check_memory(spec: &MemorySpec, origin: &str, at: &str) -> Result<(), SceneError> {
    match &spec.kernel {
        MemoryKernelSpec::Polynomial { coefficients }
            if coefficients.is_empty() || coefficients.iter().any(|c| !c.is_finite()) =>
        {
            return Err(invalid(
                origin,
                &format!("{at}.coefficients"),
                format!("{coefficients:?}"),
                "give at least one finite coefficient c0, c1, … of b(s) = Σ c_j s^j",
            ));
        }
        MemoryKernelSpec::Polynomial { coefficients } if coefficients.len() > 64 => {
            return Err(invalid(
                origin,
                &format!("{at}.coefficients"),
                format!("({} coefficients)", coefficients.len()),
                "a polynomial kernel of degree above 63 is surely a mistake (each degree holds a history vector); \
                 give at most 64 coefficients, or kind = \"expression\"",
            ));
        }
        MemoryKernelSpec::Exponential { terms } => {
            if terms.is_empty() {
                return Err(invalid(
                    origin,
                    &format!("{at}.terms"),
                    "[]",
                    "give at least one { coefficient, relaxation_time }",
                ));
            }
            for (i, term) in terms.iter().enumerate() {
                if !(term.relaxation_time.is_finite() && term.relaxation_time > 0.0) {
                    return Err(invalid(
                        origin,
                        &format!("{at}.terms[{i}].relaxation_time"),
                        term.relaxation_time,
                        "relaxation times must be positive",
                    ));
                }
                if !term.coefficient.is_finite() {
                    return Err(invalid(
                        origin,
                        &format!("{at}.terms[{i}].coefficient"),
                        term.coefficient,
                        "coefficients must be finite (negative for a relaxing material, docs/scenes.md \"Viscoelastic memory\")",
                    ));
                }
            }
        }
        MemoryKernelSpec::Expression { expression } => {
            compile(
                origin,
                &format!("{at}.expression"),
                expression,
                &super::KERNEL_VARIABLES,
                &[0.0],
            )?;
        }
        MemoryKernelSpec::Polynomial { .. } => {}
    }
    if let Some(TensorSpec::Moduli { bulk, shear }) = spec.tensor {
        if !(bulk.is_finite() && shear.is_finite()) || (bulk == 0.0 && shear == 0.0) {
            return Err(invalid(
                origin,
                &format!("{at}.tensor"),
                format!("{{ bulk = {bulk}, shear = {shear} }}"),
                "the tensor's bulk and shear moduli must be finite and not both zero (B = (κ − 2G/3, G))",
            ));
        }
    }
    Ok(())
}

/// A vector load has 2 or 3 components (the mesh decides which is right).
fn check_components(origin: &str, key: &str, value: &[String]) -> Result<(), SceneError> {
    if matches!(value.len(), 2 | 3) {
        Ok(())
    } else {
        Err(invalid(
            origin,
            key,
            format!("{value:?}"),
            "give one expression per component: [\"fx\", \"fy\"] in 2D, [\"fx\", \"fy\", \"fz\"] in 3D",
        ))
    }
}

/// A point or a vector of 2 or 3 finite numbers.
fn check_vector(origin: &str, key: &str, v: &[f64]) -> Result<(), SceneError> {
    if matches!(v.len(), 2 | 3) && v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(invalid(
            origin,
            key,
            format!("{v:?}"),
            "give 2 finite numbers in 2D, 3 in 3D, e.g. [0.0, -0.1]",
        ))
    }
}

fn check_obstacle(o: &ObstacleSpec, origin: &str, at: &str) -> Result<(), SceneError> {
    match o {
        ObstacleSpec::Plane { point, normal, .. } => {
            check_vector(origin, &format!("{at}.point"), point)?;
            check_vector(origin, &format!("{at}.normal"), normal)?;
            if normal.iter().map(|x| x * x).sum::<f64>() == 0.0 || normal.len() != point.len() {
                return Err(invalid(
                    origin,
                    &format!("{at}.normal"),
                    format!("{normal:?}"),
                    "the plane's normal points out of the obstacle, toward the body: a non-zero vector with as many \
                     components as the point",
                ));
            }
        }
        ObstacleSpec::Circle { centre, radius, .. } => {
            check_vector(origin, &format!("{at}.centre"), centre)?;
            if !(radius.is_finite() && *radius > 0.0) {
                return Err(invalid(
                    origin,
                    &format!("{at}.radius"),
                    radius,
                    "the radius must be positive and finite",
                ));
            }
        }
        ObstacleSpec::Sdf { sdf, .. } => {
            compile(origin, &format!("{at}.sdf"), sdf, &["x", "y", "z"], &[0.1, 0.2, 0.3])?;
        }
    }
    if let Some(m) = o.motion() {
        if !matches!(m.len(), 2 | 3) {
            return Err(invalid(
                origin,
                &format!("{at}.motion"),
                format!("{m:?}"),
                "give the obstacle's rigid displacement as one expression of t per component (2 in 2D, 3 in 3D), \
                 e.g. motion = [\"0\", \"-0.01*t\"]",
            ));
        }
        for (c, e) in m.iter().enumerate() {
            compile(origin, &format!("{at}.motion[{c}]"), e, &["t"], &[0.0])?;
        }
    }
    Ok(())
}

fn check_law(law: &ContactLawSpec, origin: &str, at: &str) -> Result<(), SceneError> {
    if !(law.regularisation.is_finite() && law.regularisation > 0.0) {
        return Err(invalid(
            origin,
            &format!("{at}.law.regularisation"),
            law.regularisation,
            "ε = 0 is not supported: the Clarke subdifferential is set-valued at u_ν = 0; use a small ε such as 1e-8",
        ));
    }
    let scale = match &law.kind {
        LawKind::Paper { scale, a, b, alpha } => {
            if !(alpha.is_finite() && *alpha > 0.0) {
                return Err(invalid(origin, &format!("{at}.law.alpha"), alpha, "α must be positive"));
            }
            for (k, v) in [("a", a), ("b", b)] {
                if !(v.is_finite() && *v >= 0.0) {
                    return Err(invalid(origin, &format!("{at}.law.{k}"), v, "a and b must be ≥ 0"));
                }
            }
            scale
        }
        LawKind::Power { scale, exponent } => {
            if !(exponent.is_finite() && *exponent >= 1.0) {
                return Err(invalid(
                    origin,
                    &format!("{at}.law.exponent"),
                    exponent,
                    "the exponent p of S (u_ν)₊^p must be ≥ 1",
                ));
            }
            scale
        }
        LawKind::PiecewiseLinear { scale, table } => {
            let points: Vec<(f64, f64)> = table.iter().map(|p| (p[0], p[1])).collect();
            crate::contact::PiecewiseLinear::new(&points)
                .map_err(|e| invalid(origin, &format!("{at}.law.table"), format!("{table:?}"), &e))?;
            scale
        }
        LawKind::Tabulated { scale, .. } => scale,
    };
    if !(scale.is_finite() && *scale >= 0.0) {
        return Err(invalid(
            origin,
            &format!("{at}.law.scale"),
            scale,
            "the scale S must be ≥ 0",
        ));
    }
    Ok(())
}

fn compile(origin: &str, key: &str, source: &str, vars: &[&str], probe: &[f64]) -> Result<Expr, SceneError> {
    compile_with(origin, key, source, vars, probe, false)
}

/// [`compile`] for a load or prescribed value: an expression of position is not probed here
/// but on its group (`positional`).
fn compile_load(origin: &str, key: &str, source: &str, vars: &[&str], probe: &[f64]) -> Result<Expr, SceneError> {
    compile_with(origin, key, source, vars, probe, true)
}

fn compile_with(
    origin: &str,
    key: &str,
    source: &str,
    vars: &[&str],
    probe: &[f64],
    positional: bool,
) -> Result<Expr, SceneError> {
    let err = |message: String| SceneError::Expression {
        origin: origin.into(),
        key: key.into(),
        expression: source.into(),
        message,
    };
    let e = Expr::parse(source, vars).map_err(err)?;
    // A load depending on position is evaluated on its own group's points before the run
    // (Simulation::check_data, docs/method.md §16.3): a probe at the origin would refuse `p/x`
    // on a body in 1 ≤ x ≤ 3. A constant (or time-only) one is probed here.
    if positional && ["x", "y", "z", "nx", "ny", "nz"].iter().any(|v| e.depends_on(v)) {
        return Ok(e);
    }
    let v = e.eval(probe);
    if !v.is_finite() {
        return Err(err(format!(
            "evaluates to {v} at {} = {probe:?}; check divisions and logarithms",
            vars.join(", ")
        )));
    }
    Ok(e)
}

/// A friction table's values (docs/method.md §17): a finite coefficient μ ≥ 0 or a Tresca bound
/// expression of (x, y, z, t), and a positive regularisation.
fn check_friction(f: &super::FrictionSpec, origin: &str, at: &str) -> Result<(), SceneError> {
    let eps = f.regularisation();
    if !(eps.is_finite() && eps > 0.0) {
        return Err(invalid(
            origin,
            &format!("{at}.friction.regularisation"),
            eps,
            "the width ε of the smoothed |Δu_τ| must be positive (default 1e-8)",
        ));
    }
    match f {
        super::FrictionSpec::Coulomb {
            coefficient: super::FrictionCoefficient::Value(mu),
            ..
        } => {
            if !(mu.is_finite() && *mu >= 0.0) {
                return Err(invalid(
                    origin,
                    &format!("{at}.friction.coefficient"),
                    mu,
                    "the friction coefficient μ must be finite and ≥ 0 (or an expression of the accumulated slip s)",
                ));
            }
        }
        super::FrictionSpec::Coulomb {
            coefficient: super::FrictionCoefficient::Expression(e),
            ..
        } => {
            compile_load(origin, &format!("{at}.friction.coefficient"), e, &["s"], &[0.0])?;
        }
        super::FrictionSpec::Potential { law } => {
            if law.one_sided {
                return Err(invalid(
                    origin,
                    &format!("{at}.friction.law.one_sided"),
                    true,
                    "a friction potential acts on |u_τ| in both directions: leave one_sided out",
                ));
            }
            check_law(law, origin, &format!("{at}.friction"))?;
        }
        super::FrictionSpec::Tresca { bound, .. } => {
            compile_load(
                origin,
                &format!("{at}.friction.bound"),
                bound,
                &super::BODY_FORCE_VARIABLES,
                &[0.0; 4],
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn distance_counts_edits() {
        assert_eq!(super::distance("youngs_modulos", "youngs_modulus"), 1);
        assert_eq!(super::distance("", "abc"), 3);
    }
}
