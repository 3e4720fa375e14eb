//! Scene files: the shipped example is the embedded default, every commented alternative of
//! it is a valid scene, unknown keys and bad values are rejected with the key and the fix,
//! and `--set` overrides work (mutated scene text: tests/bad_input.rs, `mutated_scenes_never_panic`).

use hvi::scene::{LawKind, MemoryKernelSpec, Scene, DEFAULT_SCENE_TOML};
use std::path::Path;

fn paper_path() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/paper.toml"))
}

fn err(text: &str) -> String {
    Scene::from_toml_str(text, "t.toml")
        .map(|_| ())
        .unwrap_err()
        .to_string()
}

fn with(overrides: &[&str]) -> Result<Scene, String> {
    Scene::load(None, &overrides.iter().map(|s| s.to_string()).collect::<Vec<_>>()).map_err(|e| e.to_string())
}

#[test]
fn paper_toml_is_the_embedded_default_and_reads_as_the_paper() {
    assert_eq!(std::fs::read_to_string(paper_path()).unwrap(), DEFAULT_SCENE_TOML);
    let s = Scene::load(Some(paper_path()), &[]).unwrap();
    assert_eq!(
        (s.material.youngs_modulus, s.material.poisson_ratio),
        (Some(1.0), Some(0.3))
    );
    assert!(matches!(&s.memory[..], [m] if m.tensor.is_none()
        && matches!(&m.kernel, MemoryKernelSpec::Polynomial { coefficients } if coefficients == &[0.25, 1.0, 1.0])));
    let c = s.contact.first().unwrap();
    assert_eq!(c.bound, Some(0.2.into()));
    let law = c.law.as_ref().unwrap();
    assert!(
        matches!(law.kind, LawKind::Paper { scale, a, b, alpha } if (scale, a, b, alpha) == (0.1, 0.04, 0.02, 100.0))
    );
    assert!(!law.one_sided);
    assert_eq!(s.time.final_time, 1.0);
}

/// Every commented line `# key = value` of paper.toml, uncommented in place of the active line
/// with the same key in the same section (or added), gives a valid scene.
#[test]
fn every_commented_alternative_parses() {
    let lines: Vec<&str> = DEFAULT_SCENE_TOML.lines().collect();
    let mut tried = 0;
    for (i, line) in lines.iter().enumerate() {
        let Some(alt) = line.strip_prefix("# ") else { continue };
        let Some((key, _)) = alt.split_once(" = ") else {
            continue;
        };
        let key = key.trim();
        if key.is_empty() || !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            continue; // prose
        }
        let mut edited: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        // replace the nearest active line above with the same key, else insert
        match (0..i)
            .rev()
            .find(|&j| lines[j].split_once(" = ").is_some_and(|(k, _)| k.trim() == key) && !lines[j].starts_with('#'))
        {
            Some(j) => {
                edited[j] = alt.to_string();
                edited[i] = String::new();
            }
            None => edited[i] = alt.to_string(),
        }
        let text = edited.join("\n");
        Scene::from_toml_str(&text, "alternative").unwrap_or_else(|e| panic!("alternative `{alt}`: {e}"));
        tried += 1;
    }
    assert!(tried >= 5, "only {tried} alternatives found");
    // the commented [body_force] section, switched on
    let text = DEFAULT_SCENE_TOML.replace(
        "# [body_force]\n# value = [\"0\", \"0\"]",
        "[body_force]\nvalue = [\"0\", \"0\"]",
    );
    assert!(Scene::from_toml_str(&text, "body force").unwrap().body_force.is_some());
}

#[test]
fn unknown_keys_are_rejected_at_every_level_with_the_nearest_key() {
    for (from, to, key, hint) in [
        ("youngs_modulus", "youngs_modulos", "youngs_modulos", "youngs_modulus"),
        ("[time]", "[tiem]", "tiem", "time"),
        ("final_time", "finaltime", "finaltime", "final_time"),
        ("coefficients", "coeficients", "coeficients", "coefficients"),
        ("alpha = 100.0", "alhpa = 100.0", "alhpa", "alpha"),
        ("every = 1", "evry = 1", "evry", "every"),
        ("bound = 0.2", "bund = 0.2", "bund", "bound"),
        ("max_iterations", "max_iteration", "max_iteration", "max_iterations"),
    ] {
        let e = err(&DEFAULT_SCENE_TOML.replacen(from, to, 1));
        assert!(
            e.contains(key) && e.contains(hint) && e.contains("t.toml"),
            "{from} → {to}: {e}"
        );
    }
    // a key of another law kind is unknown for this kind
    let e = err(&DEFAULT_SCENE_TOML.replace("alpha = 100.0", "alpha = 100.0\nexponent = 2.0"));
    assert!(e.contains("exponent"), "{e}");
}

#[test]
fn wrong_types_and_bad_values_name_the_key() {
    for (over, key) in [
        ("material.youngs_modulus=\"stiff\"", "youngs_modulus"),
        ("material.youngs_modulus=0", "material.youngs_modulus"),
        ("material.youngs_modulus=-1", "material.youngs_modulus"),
        ("material.poisson_ratio=0.5", "material.poisson_ratio"),
        ("material.poisson_ratio=-1", "material.poisson_ratio"),
        ("material.plane=membrane", "plane"),
        ("time.final_time=0", "time.final_time"),
        ("time.steps=0", "time.steps"),
        ("time.steps=-3", "steps"),
        ("contact.bound=-0.1", "contact.bound"),
        ("contact.bound=true", "contact.bound: a number g ≥ 0"),
        ("contact.bound=[0.2]", "contact.bound: a number g ≥ 0"),
        ("contact.bound=\"0.2 + w\"", "contact.bound"),
        ("contact.bound=0.2 + sin(", "contact.bound"),
        ("contact.law.regularisation=0", "contact.law.regularisation"),
        ("contact.law.alpha=0", "contact.law.alpha"),
        ("contact.law.a=-1", "contact.law.a"),
        ("solver.tolerance=2", "solver.tolerance"),
        ("output.every=0", "output.every"),
        ("output.compress=10", "output.compress"),
        ("output.compress=-1", "output.compress"),
        ("output.compress=\"zlib\"", "output.compress"),
        ("output.compress=0.5", "output.compress"),
        ("traction.0.value=[\"0\", \"sin(\"]", "traction[0].value[1]"),
        ("traction.0.value=[\"0\", \"log(-5)\"]", "traction[0].value[1]"),
        ("traction.0.value=[\"q\", \"0\"]", "traction[0].value[0]"),
        ("traction.0.value=[\"-x^2\", \"0\"]", "traction[0].value[0]"),
        ("memory.coefficients=[]", "memory.coefficients"),
    ] {
        let e = with(&[over]).map(|_| ()).unwrap_err();
        assert!(e.contains(key), "--set {over}: {e}");
    }
    assert!(with(&["contact.law.regularisation=0"])
        .unwrap_err()
        .contains("ε = 0 is not supported"));
}

#[test]
fn overrides_set_values_and_create_sections() {
    let s = with(&[
        "time.steps=64",
        "material.plane=strain",
        "contact.law.one_sided=true",
        "traction.0.group=Gamma2",
    ])
    .unwrap();
    assert_eq!(s.time.steps, Some(64));
    assert_eq!(s.material.plane, Some(hvi::scene::Plane::Strain));
    assert!(s.contact.first().unwrap().law.as_ref().unwrap().one_sided);
    // a section the scene does not have
    let elastic = "[material]\nplane = \"stress\"\nyoungs_modulus = 1.0\npoisson_ratio = 0.3\n[time]\nfinal_time = 1.0\nsteps = 2\n";
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("e.toml");
    std::fs::write(&path, elastic).unwrap();
    let s = Scene::load(Some(&path), &["contact.bound=0.3".into()]).unwrap();
    assert_eq!(s.contact[0].bound, Some(0.3.into()));
    // the bracket form of the error messages' keys indexes arrays too
    let s = with(&["traction[0].value[1]=\"-2\"", "traction[0].group=Gamma2_top"]).unwrap();
    assert_eq!(s.traction[0].group, "Gamma2_top".into());
    assert_eq!(s.traction[0].value[1], "-2");
    for bad in [
        "time.steps",
        "=3",
        "time..steps=3",
        "traction.7.group=G",
        "traction[7].group=G",
    ] {
        assert!(with(&[bad]).unwrap_err().contains("--set"), "{bad}");
    }
}

#[test]
fn a_bound_is_a_number_or_an_expression_and_round_trips() {
    use hvi::scene::BoundSpec;
    let s = with(&["contact.bound=0.2 + 0.02*sin(6*PI*x)"]).unwrap();
    let want = Some(BoundSpec::Expression("0.2 + 0.02*sin(6*PI*x)".into()));
    assert_eq!(s.contact.first().unwrap().bound, want);
    let again = Scene::from_toml_str(&s.to_toml_string(), "round trip").unwrap();
    assert_eq!(again.contact[0].bound, want);
    // an integer is a number
    assert_eq!(with(&["contact.bound=1"]).unwrap().contact[0].bound, Some(1.0.into()));
}

#[test]
fn the_effective_scene_round_trips() {
    let s = with(&["time.steps=7"]).unwrap();
    let again = Scene::from_toml_str(&s.to_toml_string(), "round trip").unwrap();
    assert_eq!(again.to_toml_string(), s.to_toml_string());
    assert_eq!(again.time.steps, Some(7));
}
