//! Errors of reading a scene. Every message names the origin (file), the key path and the fix.

/// What is wrong with a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read scene file {origin}: {message}")]
    Io { origin: String, message: String },
    #[error("{origin}: TOML syntax error: {message}")]
    Syntax { origin: String, message: String },
    #[error("{origin}: unknown key `{key}` in {section}{suggestion}; valid keys there: {allowed}")]
    UnknownKey {
        origin: String,
        section: String,
        key: String,
        suggestion: String,
        allowed: String,
    },
    #[error("{origin}: `{key}`: {message}")]
    Type {
        origin: String,
        key: String,
        message: String,
    },
    #[error("{origin}: `{key}` = {value}: {fix}")]
    Invalid {
        origin: String,
        key: String,
        value: String,
        fix: String,
    },
    #[error("{origin}: `{key}` = \"{expression}\": {message}")]
    Expression {
        origin: String,
        key: String,
        expression: String,
        message: String,
    },
    #[error("--set {text}: {reason} (expected KEY=VALUE, e.g. --set time.steps=64)")]
    Override { text: String, reason: String },
}

/// The error of a value out of range: the scene (`origin`), the key, the value and the fix.
pub(super) fn invalid(origin: &str, key: &str, value: impl std::fmt::Display, fix: &str) -> SceneError {
    SceneError::Invalid {
        origin: origin.into(),
        key: key.into(),
        value: value.to_string(),
        fix: fix.into(),
    }
}
