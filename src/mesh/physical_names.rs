//! The `$PhysicalNames` section (the same in MSH 2.2 and 4.1, and ASCII even in binary files):
//!
//! ```text
//! $PhysicalNames
//! 2
//! 1 3 "Gamma3"
//! 2 5 "Omega"
//! $EndPhysicalNames
//! ```

use super::{trim, Lines, MeshError};
use std::collections::HashMap;
use std::path::Path;

/// One line of `$PhysicalNames`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PhysicalName {
    pub dim: u8,
    pub tag: i32,
    pub name: String,
}

/// Finds the first line `$PhysicalNames` at or after `body` and parses the section. No such
/// section: no names.
pub(crate) fn parse(path: &Path, bytes: &[u8], body: usize) -> Result<Vec<PhysicalName>, MeshError> {
    let Some(start) = find_section(bytes, body, b"$PhysicalNames") else {
        return Ok(Vec::new());
    };
    let syntax = |line: usize, detail: String| MeshError::Syntax {
        path: path.to_path_buf(),
        place: format!("line {line} ($PhysicalNames)"),
        detail,
    };
    let mut lines = Lines::new(bytes, start);
    let _ = lines.next_line(); // $PhysicalNames
    let Some((n_line, l)) = lines.next_nonblank() else {
        return Err(syntax(
            lines.line,
            "the file ends inside $PhysicalNames: it is truncated".into(),
        ));
    };
    let count: usize = std::str::from_utf8(trim(l))
        .ok()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| {
            syntax(
                n_line,
                format!(
                    "expected the number of names, found \"{}\"",
                    String::from_utf8_lossy(trim(l))
                ),
            )
        })?;
    // Each name line takes at least 6 bytes ("1 1 a" and a line break).
    if count.saturating_mul(6) > lines.remaining() {
        return Err(syntax(
            n_line,
            format!(
                "the section says {count} names, more than the rest of the file can hold: it is truncated or corrupt"
            ),
        ));
    }
    let mut names: Vec<PhysicalName> = Vec::with_capacity(count);
    let mut seen: HashMap<(u8, i32), usize> = HashMap::with_capacity(count);
    for k in 0..count {
        let Some((line, l)) = lines.next_line() else {
            return Err(syntax(
                lines.line,
                format!("the file ends after {k} of {count} physical names: it is truncated"),
            ));
        };
        let text = String::from_utf8_lossy(trim(l)).into_owned();
        if text.starts_with('$') {
            return Err(syntax(
                line,
                format!("found {text} after {k} names, but the section says {count}"),
            ));
        }
        let bad = || syntax(line, format!("expected `dim tag \"name\"`, found \"{text}\""));
        let (first, rest) = text.split_once(char::is_whitespace).ok_or_else(bad)?;
        let (second, rest) = rest.trim_start().split_once(char::is_whitespace).ok_or_else(bad)?;
        let dim: u8 = first.parse().ok().filter(|&d| d <= 3).ok_or_else(bad)?;
        let tag: i32 = second.parse().ok().ok_or_else(bad)?;
        let rest = rest.trim();
        let name = rest
            .strip_prefix('"')
            .and_then(|r| r.strip_suffix('"'))
            .unwrap_or(rest)
            .to_string();
        if name.is_empty() {
            return Err(bad());
        }
        if let Some(&p) = seen.get(&(dim, tag)) {
            return Err(syntax(
                line,
                format!(
                    "physical group (dim {dim}, tag {tag}) is named twice (\"{}\" and \"{name}\")",
                    names[p].name
                ),
            ));
        }
        seen.insert((dim, tag), names.len());
        names.push(PhysicalName { dim, tag, name });
    }
    match lines.next_nonblank() {
        Some((_, l)) if trim(l) == b"$EndPhysicalNames" => Ok(names),
        Some((line, l)) => Err(syntax(
            line,
            format!(
                "expected $EndPhysicalNames after {count} names, found \"{}\"",
                String::from_utf8_lossy(trim(l))
            ),
        )),
        None => Err(syntax(
            lines.line,
            "the file ends inside $PhysicalNames (no $EndPhysicalNames): it is truncated".into(),
        )),
    }
}

/// Offset of the first line at or after `from` that is exactly `name` (and a line break).
pub(crate) fn find_section(bytes: &[u8], from: usize, name: &[u8]) -> Option<usize> {
    let mut i = from;
    while i + name.len() <= bytes.len() {
        let hit = bytes[i..].windows(name.len()).position(|w| w == name)? + i;
        let at_line_start = hit == 0 || bytes[hit - 1] == b'\n';
        let after = &bytes[hit + name.len()..];
        let at_line_end = after.is_empty() || after[0] == b'\n' || after.starts_with(b"\r\n");
        if at_line_start && at_line_end {
            return Some(hit);
        }
        i = hit + 1;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(text: &str) -> Result<Vec<PhysicalName>, MeshError> {
        parse(Path::new("t.msh"), text.as_bytes(), 0)
    }

    #[test]
    fn quoted_unquoted_spaces_and_crlf() {
        let n = names("$PhysicalNames\r\n3\r\n1  3   \"Gamma 3\"\r\n2\t5 Omega\r\n0 -2 \"p\"\r\n$EndPhysicalNames\r\n")
            .unwrap();
        let got: Vec<(u8, i32, &str)> = n.iter().map(|p| (p.dim, p.tag, p.name.as_str())).collect();
        assert_eq!(got, vec![(1, 3, "Gamma 3"), (2, 5, "Omega"), (0, -2, "p")]);
        assert!(names("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n").unwrap().is_empty());
    }

    #[test]
    fn errors() {
        let e = names("$PhysicalNames\n2\n1 3 \"a\"\n1 3 \"b\"\n$EndPhysicalNames\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("named twice") && e.contains("line 4"), "{e}");
        let e = names("$PhysicalNames\n1000000000000\n1 3 \"a\"\n$EndPhysicalNames\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("1000000000000") && e.contains("truncated"), "{e}");
        let e = names("$PhysicalNames\n2\n1 3 \"a\"\n$EndPhysicalNames\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("after 1 names"), "{e}");
        let e = names("$PhysicalNames\n1\nx 3 \"a\"\n$EndPhysicalNames\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3") && e.contains("dim tag"), "{e}");
        assert!(names("$PhysicalNames\n1\n1 3 \"a\"\n")
            .unwrap_err()
            .to_string()
            .contains("truncated"));
    }
}
