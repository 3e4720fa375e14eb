//! How a scene names a physical group: by its `$PhysicalNames` name or by its integer tag.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A physical group selector as written in a scene: `"Gamma3"` or `3`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(untagged)]
pub enum GroupSelector {
    /// By integer physical tag.
    Tag(i32),
    /// By name (as in gmsh's `$PhysicalNames`).
    Name(String),
}

impl GroupSelector {
    /// The group as tables and output columns print it: its name bare, or its tag.
    pub fn label(&self) -> String {
        match self {
            GroupSelector::Name(n) => n.clone(),
            GroupSelector::Tag(t) => t.to_string(),
        }
    }
}

impl fmt::Display for GroupSelector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GroupSelector::Tag(t) => write!(f, "tag {t}"),
            GroupSelector::Name(n) => write!(f, "\"{n}\""),
        }
    }
}

/// By hand rather than `untagged`: serde's untagged message ("data did not match any variant")
/// says neither what was found nor what is valid.
impl<'de> Deserialize<'de> for GroupSelector {
    fn deserialize<De: serde::Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        struct Selector;
        impl serde::de::Visitor<'_> for Selector {
            type Value = GroupSelector;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a physical group: its name in quotes (e.g. \"Gamma3\") or its integer tag (e.g. 3)")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<GroupSelector, E> {
                Ok(GroupSelector::Name(v.to_string()))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<GroupSelector, E> {
                i32::try_from(v).map(GroupSelector::Tag).map_err(|_| {
                    E::custom(format!(
                        "the physical tag {v} is out of range: tags are integers from {} to {}",
                        i32::MIN,
                        i32::MAX
                    ))
                })
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<GroupSelector, E> {
                match i64::try_from(v) {
                    Ok(v) => self.visit_i64(v),
                    Err(_) => Err(E::custom(format!(
                        "the physical tag {v} is out of range: tags are integers from {} to {}",
                        i32::MIN,
                        i32::MAX
                    ))),
                }
            }
        }
        d.deserialize_any(Selector)
    }
}

impl From<&str> for GroupSelector {
    fn from(s: &str) -> Self {
        GroupSelector::Name(s.to_string())
    }
}
