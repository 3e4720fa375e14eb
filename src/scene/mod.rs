//! Scene files: the serde-typed TOML input, `--set` overrides, validation with messages that
//! name the file, the key and the fix, and the embedded default (the paper's example).

mod error;
mod material;
mod overrides;
mod time;
mod types;
mod validate;

pub use crate::expr::{
    Expr, BINARY_FUNCTIONS, BODY_FORCE_VARIABLES, CONSTANTS, FUNCTIONS, KERNEL_VARIABLES, TRACTION_VARIABLES,
};
pub use error::SceneError;
pub use material::MaterialError;
pub use time::MOST_STEPS;
pub use types::*;

use std::path::Path;

/// How messages name the embedded default scene (there is no file to name).
pub const DEFAULT_SCENE_ORIGIN: &str = "<embedded default scene (examples/paper.toml)>";

/// The embedded default scene: `examples/paper.toml`.
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../examples/paper.toml");

impl Scene {
    /// Parses and validates a scene from TOML text; `origin` names it in messages.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
        Self::from_text(text, origin, &[], None)
    }

    /// Loads `path` (or the embedded default), applies `--set` overrides in order, and validates.
    pub fn load(path: Option<&Path>, overrides: &[String]) -> Result<Scene, SceneError> {
        match path {
            Some(p) => {
                let origin = p.display().to_string();
                let text = std::fs::read_to_string(p).map_err(|e| SceneError::Io {
                    origin: origin.clone(),
                    message: e.to_string(),
                })?;
                Self::from_text(&text, &origin, overrides, p.parent())
            }
            None => Self::from_text(DEFAULT_SCENE_TOML, DEFAULT_SCENE_ORIGIN, overrides, None),
        }
    }

    fn from_text(text: &str, origin: &str, overrides: &[String], dir: Option<&Path>) -> Result<Scene, SceneError> {
        let mut tree: toml::Value =
            text.parse::<toml::Table>()
                .map(toml::Value::Table)
                .map_err(|e| SceneError::Syntax {
                    origin: origin.into(),
                    message: e.to_string(),
                })?;
        for o in overrides {
            overrides::apply(&mut tree, o)?;
        }
        time::replace_stepping(&mut tree, overrides);
        validate::check_keys(&tree, origin)?;
        // Deserialise from text, so that a type error shows the offending line with its key
        // (the original text when there are no overrides, keeping the file's line numbers).
        let effective = if overrides.is_empty() {
            text.to_string()
        } else {
            toml::to_string(&tree).map_err(|e| SceneError::Syntax {
                origin: origin.into(),
                message: e.to_string(),
            })?
        };
        // serde_path_to_error tracks the dotted key (`contact[1].law.scale`) that toml's own
        // error does not name; toml's message keeps the line, the column and the caret.
        let mut scene: Scene = serde_path_to_error::deserialize(toml::Deserializer::new(&effective)).map_err(|e| {
            let path = e.path().to_string();
            // a required section or key that is absent: say which, not "line 1, column 1"
            let inner = e.inner().to_string();
            // (at the top level only: toml points a nested one at its table's line)
            let top = path.is_empty() || path == ".";
            let missing = inner.split("missing field `").nth(1).and_then(|r| r.split('`').next());
            if let (true, Some(field)) = (top, missing) {
                let within = String::new();
                return SceneError::Invalid {
                    origin: origin.into(),
                    key: format!("{within}{field}"),
                    value: "(missing)".into(),
                    fix: match (within.as_str(), field) {
                        ("", "time") => "add a [time] section, e.g. [time] final_time = 1.0, steps = 32".into(),
                        ("", "material") => "add a [material] section, e.g. [material] youngs_modulus = 1.0, \
                                             poisson_ratio = 0.3 (and plane = \"strain\" in 2D)"
                            .into(),
                        _ => format!(
                            "it is required: add `{field} = …`{}",
                            if within.is_empty() {
                                String::new()
                            } else {
                                format!(" to [{path}]")
                            }
                        ),
                    },
                };
            }
            SceneError::Type {
                origin: if overrides.is_empty() {
                    origin.into()
                } else {
                    format!("{origin} (after --set {})", overrides.join(" --set "))
                },
                key: if path.is_empty() || path == "." {
                    "scene".into()
                } else {
                    path
                },
                message: e.into_inner().to_string(),
            }
        })?;
        scene.origin = origin.to_string();
        scene.read_tables(origin, dir)?;
        validate::check_values(&scene, origin)?;
        Ok(scene)
    }

    /// Reads a tabulated law's CSV (`s,mu` rows, `#` comments, an optional header) into a
    /// piecewise-linear table, relative to the scene's directory.
    fn read_tables(&mut self, origin: &str, dir: Option<&Path>) -> Result<(), SceneError> {
        let keys: Vec<String> = (0..self.contact.len()).map(|i| self.contact_key(i)).collect();
        for (c, at) in self.contact.iter_mut().zip(keys) {
            if let Some(law) = c.law.as_mut() {
                Self::read_table(law, origin, dir, &at)?;
            }
            if let Some(FrictionSpec::Potential { law }) = c.friction.as_mut() {
                Self::read_table(law, origin, dir, &format!("{at}.friction"))?;
            }
        }
        Ok(())
    }

    fn read_table(law: &mut ContactLawSpec, origin: &str, dir: Option<&Path>, at: &str) -> Result<(), SceneError> {
        let LawKind::Tabulated { scale, file } = &law.kind else {
            return Ok(());
        };
        let path = dir.map_or(file.clone(), |d| d.join(file));
        let bad = |message: String| SceneError::Invalid {
            origin: origin.into(),
            key: format!("{at}.law.file"),
            value: path.display().to_string(),
            fix: message,
        };
        let text = std::fs::read_to_string(&path).map_err(|e| bad(format!("cannot read the table: {e}")))?;
        let mut table = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') || line.chars().next().is_some_and(|c| c.is_alphabetic()) {
                continue;
            }
            let cols: Vec<f64> = line
                .split([',', ' ', '\t'])
                .filter(|s| !s.is_empty())
                .map(|s| s.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| bad(format!("line {}: {e}", i + 1)))?;
            if cols.len() != 2 {
                return Err(bad(format!("line {}: expected two columns s, mu", i + 1)));
            }
            table.push([cols[0], cols[1]]);
        }
        law.kind = LawKind::PiecewiseLinear { scale: *scale, table };
        Ok(())
    }

    /// The effective scene as TOML (written next to the output).
    pub fn to_toml_string(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# could not serialise the scene: {e}\n"))
    }
}
