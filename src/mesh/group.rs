//! How a scene names a physical group: by its `$PhysicalNames` name or by its integer tag.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A physical group selector as written in a scene: `"Gamma3"` or `3`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum GroupSelector {
    /// By integer physical tag.
    Tag(i32),
    /// By name (as in gmsh's `$PhysicalNames`).
    Name(String),
}

impl fmt::Display for GroupSelector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GroupSelector::Tag(t) => write!(f, "tag {t}"),
            GroupSelector::Name(n) => write!(f, "\"{n}\""),
        }
    }
}

impl From<&str> for GroupSelector {
    fn from(s: &str) -> Self {
        GroupSelector::Name(s.to_string())
    }
}
