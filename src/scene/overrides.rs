//! `--set key.path=value` overrides, applied to the TOML tree before deserialising.

use super::error::SceneError;
use toml::Value;

/// Applies one `key.path=value` override to `root`. The value is read as a TOML value
/// (`64`, `1e-6`, `true`, `[1, 0]`, `"text"`) and otherwise taken as a string; missing tables
/// are created; a numeric segment indexes an array (`traction.0.group=Gamma2`), and so does the
/// bracket form the error messages name keys with (`traction[0].value[1]`, `materials[1].group`).
pub fn apply(root: &mut Value, text: &str) -> Result<(), SceneError> {
    let fail = |reason: &str| SceneError::Override {
        text: text.into(),
        reason: reason.into(),
    };
    let (key, raw) = text.split_once('=').ok_or_else(|| fail("no `=`"))?;
    let key = key.trim().replace('[', ".").replace(']', "");
    let key = key.as_str();
    if key.is_empty() || key.split('.').any(|s| s.trim().is_empty()) {
        return Err(fail("empty key segment"));
    }
    let raw = raw.trim();
    let value = match format!("v = {raw}").parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").unwrap_or(Value::String(raw.into())),
        Err(_) => Value::String(raw.into()),
    };
    let segments: Vec<&str> = key.split('.').map(str::trim).collect();
    let mut node = root;
    for (i, seg) in segments.iter().enumerate() {
        let last = i + 1 == segments.len();
        node = match node {
            Value::Table(t) => {
                if last {
                    t.insert(seg.to_string(), value);
                    return Ok(());
                }
                t.entry(seg.to_string())
                    .or_insert_with(|| Value::Table(toml::Table::new()))
            }
            Value::Array(a) => {
                let idx: usize = seg
                    .parse()
                    .map_err(|_| fail(&format!("`{seg}` is not an index into an array")))?;
                let len = a.len();
                let slot = a
                    .get_mut(idx)
                    .ok_or_else(|| fail(&format!("index {idx} is out of range (the array has {len} entries)")))?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                slot
            }
            _ => return Err(fail(&format!("`{}` is not a table", segments[..i].join(".")))),
        };
    }
    Ok(())
}
