//! The two index files ParaView reads for a time series: the `.pvd` collection (XML) and the
//! `.vtu.series` file (JSON), written here; both list file
//! names relative to their own directory, in the order written, with each frame's real time.
//! [`read_pvd`] reads a `.pvd` back (its markup by quick-xml, [`super::xml`]).

use super::atomic::{write_atomic, write_json_atomic};
use super::xml::parse_tags;
use super::{format_number, OutputError};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Escapes the five XML special characters for use in an attribute value.
pub(crate) fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map_or_else(|| p.to_string_lossy(), |n| n.to_string_lossy())
        .into_owned()
}

/// The text of a `.pvd` collection listing `frames` (time, path) in order.
pub fn pvd_text(frames: &[(f64, PathBuf)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, p) in frames {
        let _ = writeln!(
            s,
            "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
            format_number(*t),
            xml_escape(&file_name(p))
        );
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    s
}

/// The frames a `.pvd` collection lists: (time, file name as written, escapes undone), in
/// order. A missing file, markup that is not well-formed, a file that is not a `Collection`, or
/// a `<DataSet>` without a `file` or a numeric `timestep` is an error naming the file.
pub fn read_pvd(path: &Path) -> Result<Vec<(f64, String)>, OutputError> {
    let bytes = std::fs::read(path).map_err(|e| OutputError::read(path, e))?;
    let fail = |detail: String| OutputError::format(path, detail);
    let (tags, _) = parse_tags(&bytes, None).map_err(fail)?;
    let root = tags.iter().find(|t| t.name == "VTKFile" && !t.closing);
    if root.and_then(|t| t.attr("type")) != Some("Collection") {
        return Err(fail("its root is not a <VTKFile type=\"Collection\">".into()));
    }
    tags.iter()
        .filter(|t| t.name == "DataSet" && !t.closing)
        .map(|t| {
            let file = t.attr("file").ok_or_else(|| fail("a <DataSet> without file".into()))?;
            let time = t.attr("timestep").unwrap_or("(none)");
            let time = time.trim().parse::<f64>().map_err(|_| {
                fail(format!(
                    "the <DataSet> of {file:?} has the timestep {time:?}, not a number"
                ))
            })?;
            Ok((time, file.to_string()))
        })
        .collect()
}

#[derive(Serialize)]
struct SeriesEntry {
    name: String,
    time: f64,
}

#[derive(Serialize)]
struct Series {
    #[serde(rename = "file-series-version")]
    version: &'static str,
    files: Vec<SeriesEntry>,
}

/// Rewrites `pvd` and `series` (atomically, each) to list `frames`.
pub(crate) fn write_index(pvd: &Path, series: &Path, frames: &[(f64, PathBuf)]) -> Result<(), OutputError> {
    write_atomic(pvd, pvd_text(frames).as_bytes())?;
    let value = Series {
        version: "1.0",
        files: frames
            .iter()
            .map(|(t, p)| SeriesEntry {
                name: file_name(p),
                time: *t,
            })
            .collect(),
    };
    write_json_atomic(series, &value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pvd_lists_frames_with_escaped_names() {
        let text = pvd_text(&[(0.0, "d/a_00000.vtu".into()), (0.25, "d/a&b_00001.vtu".into())]);
        assert!(text.contains("<DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"a_00000.vtu\"/>"));
        assert!(text.contains("timestep=\"0.25\" group=\"\" part=\"0\" file=\"a&amp;b_00001.vtu\""));
    }
}
