//! A frame in pieces (docs/method.md §13.3): each process writes its piece of the body,
//! `<basename>_<step:05>_<rank>.vtu` (an ordinary `.vtu` of its cells and their nodes), and one
//! process then the `.pvtu` that lists the pieces, `<basename>_<step:05>.pvtu`, and the
//! `.pvd`/`.pvtu.series` over the `.pvtu` files; and reading a `.pvtu` back whole.
//!
//! Every piece carries the point array [`NODE_IDS`] (each point's mesh node) and the cell array
//! [`CELL_IDS`] (each cell's mesh cell), so that the whole frame can be put back together: a
//! node on the border of two pieces is a point of both, with the same values.
//!
//! Atomic as a serial series: each piece and each `.pvtu` is written to a temporary name and
//! renamed, and the `.pvtu` and the index only after every piece of its frame is in place, so a
//! run that stops leaves every frame the index lists whole.

use super::raw::{open_section, start_array, vtk_type};
use super::{read_vtu_arrays, write_vtu, VtuContents};
use crate::output::atomic::write_atomic;
use crate::output::pvd::{write_index, xml_escape};
use crate::output::xml::parse_tags;
use crate::output::{Field, Frame, OutputError, SeriesWriter};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The point array of a piece holding each point's mesh node number.
pub const NODE_IDS: &str = "node";

/// The cell array of a piece holding each cell's mesh cell number.
pub const CELL_IDS: &str = "cell";

impl SeriesWriter {
    /// As [`SeriesWriter::create`], for a series of frames in pieces: `.pvtu` frames listing
    /// `.vtu` pieces, indexed by `<basename>.pvd` and `<basename>.pvtu.series`.
    pub fn create_parallel(dir: &Path, basename: &str) -> Result<Self, OutputError> {
        Self::create_with(dir, basename, "pvtu")
    }

    /// The file name of piece `rank` of step `step`: `<basename>_<step:05>_<rank>.vtu`.
    pub fn piece_name(&self, step: usize, rank: usize) -> String {
        format!("{}_{step:05}_{rank}.vtu", self.basename)
    }

    /// Writes `frame` as piece `rank` of its step (validated, atomically; listed in no index
    /// until [`SeriesWriter::write_parallel_frame`]). Returns the piece's path.
    pub fn write_piece<const D: usize>(&mut self, frame: &Frame<D>, rank: usize) -> Result<PathBuf, OutputError> {
        let path = self.dir.join(self.piece_name(frame.step, rank));
        if self.extension != "pvtu" {
            return Err(OutputError::InvalidArgument {
                path,
                detail: "pieces belong to a series made by SeriesWriter::create_parallel".into(),
            });
        }
        write_vtu(&path, &frame.view(), self.compression_level, &mut self.buffer)?;
        Ok(path)
    }

    /// Writes the `.pvtu` of `frame`'s step listing the pieces 0..`pieces` (whose arrays are
    /// those of `frame`, any one of them), then rewrites the index files to list it (both
    /// atomically). Call once every piece is written. Returns the `.pvtu` path.
    pub fn write_parallel_frame<const D: usize>(
        &mut self,
        frame: &Frame<D>,
        pieces: usize,
    ) -> Result<PathBuf, OutputError> {
        let path = self.dir.join(self.frame_name(frame.step));
        if self.extension != "pvtu" || !frame.time.is_finite() {
            return Err(OutputError::invalid_frame(
                &path,
                format!(
                    "a .pvtu frame needs a series made by SeriesWriter::create_parallel and a finite time (step {} at t = {})",
                    frame.step, frame.time
                ),
            ));
        }
        let names: Vec<String> = (0..pieces).map(|r| self.piece_name(frame.step, r)).collect();
        write_atomic(
            &path,
            pvtu_text(&frame.point_fields, &frame.cell_fields, &names).as_bytes(),
        )?;
        let mut frames = self.frames.clone();
        match frames.iter_mut().find(|(_, p)| *p == path) {
            Some(entry) => entry.0 = frame.time,
            None => frames.push((frame.time, path.clone())),
        }
        write_index(&self.pvd, &self.series, &frames)?;
        self.frames = frames;
        Ok(path)
    }
}

/// Declares the arrays of one section (`PPointData`/`PCellData`), with the active scalars,
/// vectors and tensors as a piece's `PointData`/`CellData` marks them (the same code, raw.rs).
fn declare(text: &mut String, tag: &str, fields: &[Field]) {
    open_section(text, "    ", tag, fields);
    for f in fields {
        text.push_str("      ");
        start_array(text, "PDataArray", vtk_type(&f.values), f.name, f.components);
        text.push_str("/>\n");
    }
    let _ = writeln!(text, "    </{tag}>");
}

/// The text of a `.pvtu` listing `pieces` (file names in the same directory) with the arrays of
/// `point_fields` and `cell_fields`.
fn pvtu_text(point_fields: &[Field], cell_fields: &[Field], pieces: &[String]) -> String {
    let mut text = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n",
    );
    declare(&mut text, "PPointData", point_fields);
    declare(&mut text, "PCellData", cell_fields);
    text.push_str("    <PPoints>\n      <PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n    </PPoints>\n");
    for p in pieces {
        let _ = writeln!(text, "    <Piece Source=\"{}\"/>", xml_escape(p));
    }
    text.push_str("  </PUnstructuredGrid>\n</VTKFile>\n");
    text
}

/// The pieces a `.pvtu` lists, as paths (relative names resolved against its directory).
pub fn pvtu_pieces(path: &Path) -> Result<Vec<PathBuf>, OutputError> {
    let bytes = std::fs::read(path).map_err(|e| OutputError::read(path, e))?;
    let (tags, _) = parse_tags(&bytes, None).map_err(|e| OutputError::format(path, e))?;
    if !tags.iter().any(|t| t.name == "PUnstructuredGrid" && !t.closing) {
        return Err(OutputError::format(path, "not a .pvtu (no <PUnstructuredGrid>)"));
    }
    let dir = crate::output::atomic::parent_dir(path);
    let pieces: Vec<PathBuf> = tags
        .iter()
        .filter(|t| t.name == "Piece" && !t.closing)
        .map(|t| {
            t.attr("Source")
                .map(|s| dir.join(s))
                .ok_or_else(|| OutputError::format(path, "a <Piece> without Source"))
        })
        .collect::<Result<_, _>>()?;
    if pieces.is_empty() {
        return Err(OutputError::format(path, "the .pvtu lists no pieces"));
    }
    Ok(pieces)
}

/// Reads a `.pvtu` written by hvi and puts its pieces back together: the points in mesh node
/// order, the cells in mesh cell order, every point and cell array over the whole mesh (without
/// the [`NODE_IDS`]/[`CELL_IDS`] arrays that placed them), the field data of the pieces. An
/// error names the file when a piece is missing, truncated or foreign, when the pieces do not
/// cover every node and cell, or when two pieces disagree at a node they share.
pub fn read_pvtu_arrays(path: &Path) -> Result<VtuContents, OutputError> {
    let pieces = pvtu_pieces(path)?;
    let mut read = Vec::with_capacity(pieces.len());
    for p in &pieces {
        read.push((p.clone(), read_vtu_arrays(p)?));
    }
    let ids = |p: &Path, values: Option<&(usize, Vec<f64>)>, name: &str| -> Result<Vec<usize>, OutputError> {
        match values {
            Some((1, v)) => Ok(v.iter().map(|&x| x as usize).collect()),
            _ => Err(OutputError::format(
                p,
                format!("a piece of hvi has the one-component array `{name}`; this one has not"),
            )),
        }
    };
    let mut per_piece = Vec::new();
    let (mut n_points, mut n_cells) = (0, 0);
    for (p, c) in &read {
        let nodes = ids(p, c.point_data.get(NODE_IDS), NODE_IDS)?;
        let cells = ids(p, c.cell_data.get(CELL_IDS), CELL_IDS)?;
        n_points = n_points.max(nodes.iter().map(|&n| n + 1).max().unwrap_or(0));
        n_cells = n_cells.max(cells.iter().map(|&n| n + 1).max().unwrap_or(0));
        per_piece.push((nodes, cells));
    }
    let first = &read[0].1;
    let mut whole = VtuContents {
        points: vec![[f64::NAN; 3]; n_points],
        cell_types: vec![0; n_cells],
        connectivity: vec![Vec::new(); n_cells],
        point_data: BTreeMap::new(),
        cell_data: BTreeMap::new(),
        field_data: first.field_data.clone(),
    };
    let (mut point_seen, mut cell_seen) = (vec![false; n_points], vec![false; n_cells]);
    for ((p, c), (nodes, cells)) in read.iter().zip(&per_piece) {
        if c.field_data != first.field_data {
            return Err(OutputError::format(
                p,
                "its field data (TimeValue, step) differ from the first piece's",
            ));
        }
        let names = |m: &BTreeMap<String, (usize, Vec<f64>)>| m.keys().cloned().collect::<Vec<_>>();
        if names(&c.point_data) != names(&first.point_data) || names(&c.cell_data) != names(&first.cell_data) {
            return Err(OutputError::format(p, "its arrays differ from the first piece's"));
        }
        for (i, &n) in nodes.iter().enumerate() {
            let disagree = point_seen[n] && whole.points[n] != c.points[i];
            if disagree {
                return Err(OutputError::format(
                    p,
                    format!(
                        "node {n} is at {:?} here but at {:?} in another piece",
                        c.points[i], whole.points[n]
                    ),
                ));
            }
            whole.points[n] = c.points[i];
        }
        for (i, &e) in cells.iter().enumerate() {
            if cell_seen[e] {
                return Err(OutputError::format(p, format!("cell {e} is in two pieces")));
            }
            cell_seen[e] = true;
            whole.cell_types[e] = c.cell_types[i];
            whole.connectivity[e] = c.connectivity[i].iter().map(|&k| nodes[k]).collect();
        }
        for (name, (components, values)) in &c.point_data {
            let k = *components;
            let target = whole
                .point_data
                .entry(name.clone())
                .or_insert_with(|| (k, vec![f64::NAN; k * n_points]));
            for (i, &n) in nodes.iter().enumerate() {
                let (new, old) = (&values[k * i..k * i + k], &mut target.1[k * n..k * n + k]);
                if point_seen[n] && new.iter().zip(old.iter()).any(|(a, b)| a.to_bits() != b.to_bits()) {
                    return Err(OutputError::format(
                        p,
                        format!("`{name}` at node {n} is {new:?} here but {old:?} in another piece"),
                    ));
                }
                old.copy_from_slice(new);
            }
        }
        for (name, (components, values)) in &c.cell_data {
            let k = *components;
            let target = whole
                .cell_data
                .entry(name.clone())
                .or_insert_with(|| (k, vec![f64::NAN; k * n_cells]));
            for (i, &e) in cells.iter().enumerate() {
                target.1[k * e..k * e + k].copy_from_slice(&values[k * i..k * i + k]);
            }
        }
        for &n in nodes {
            point_seen[n] = true;
        }
    }
    if let Some(n) = point_seen.iter().position(|s| !s) {
        return Err(OutputError::format(path, format!("no piece holds node {n}")));
    }
    if let Some(e) = cell_seen.iter().position(|s| !s) {
        return Err(OutputError::format(path, format!("no piece holds cell {e}")));
    }
    whole.point_data.remove(NODE_IDS);
    whole.cell_data.remove(CELL_IDS);
    Ok(whole)
}

#[cfg(test)]
mod tests {
    use super::super::Parts;
    use super::*;
    use crate::mesh::Cell;

    /// Two pieces of the two-cell frame of the other tests, written and read back whole: the
    /// same points, cells and arrays as the frame written in one piece.
    #[test]
    fn pieces_read_back_as_the_whole_frame() {
        let dir = tempfile::tempdir().unwrap();
        let p = Parts::new();
        let mut whole = SeriesWriter::create(dir.path(), "one").unwrap();
        let cell_ids = [0, 1];
        let frame = Frame {
            step: 3,
            time: 0.5,
            points: &p.points,
            cells: &p.cells,
            point_fields: vec![Field::f64("u", 3, &p.u), Field::i32("status", 1, &p.status)],
            cell_fields: vec![Field::f64("stress", 9, &p.stress)],
        };
        let single = whole.write_frame(&frame).unwrap();
        let mut series = SeriesWriter::create_parallel(dir.path(), "solution").unwrap();
        // piece 0: the quad (nodes 0 1 2 3); piece 1: the triangle (nodes 1 4 2)
        let pieces: [(&[usize], Cell, usize); 2] = [(&[0, 1, 2, 3], p.cells[0], 0), (&[1, 2, 4], p.cells[1], 1)];
        for (rank, (nodes, cell, e)) in pieces.iter().enumerate() {
            let local = |n: usize| nodes.iter().position(|&m| m == n).unwrap();
            let points: Vec<[f64; 2]> = nodes.iter().map(|&n| p.points[n]).collect();
            let cells = [cell.renumbered(local)];
            let u: Vec<f64> = nodes.iter().flat_map(|&n| p.u[3 * n..3 * n + 3].to_vec()).collect();
            let status: Vec<i32> = nodes.iter().map(|&n| p.status[n]).collect();
            let ids: Vec<i32> = nodes.iter().map(|&n| n as i32).collect();
            let cell_id = [cell_ids[*e]];
            let frame = Frame {
                step: 3,
                time: 0.5,
                points: &points,
                cells: &cells,
                point_fields: vec![
                    Field::f64("u", 3, &u),
                    Field::i32("status", 1, &status),
                    Field::i32(NODE_IDS, 1, &ids),
                ],
                cell_fields: vec![
                    Field::f64("stress", 9, &p.stress[9 * e..9 * e + 9]),
                    Field::i32(CELL_IDS, 1, &cell_id),
                ],
            };
            series.write_piece(&frame, rank).unwrap();
            if rank == 1 {
                series.write_parallel_frame(&frame, 2).unwrap();
            }
        }
        let pvtu = dir.path().join("solution_00003.pvtu");
        assert_eq!(
            pvtu_pieces(&pvtu).unwrap(),
            vec![
                dir.path().join("solution_00003_0.vtu"),
                dir.path().join("solution_00003_1.vtu")
            ]
        );
        assert_eq!(read_pvtu_arrays(&pvtu).unwrap(), read_vtu_arrays(&single).unwrap());
        let pvd = std::fs::read_to_string(dir.path().join("solution.pvd")).unwrap();
        assert!(pvd.contains("file=\"solution_00003.pvtu\""), "{pvd}");
        // A piece that goes missing makes the frame unreadable, naming the piece.
        std::fs::remove_file(dir.path().join("solution_00003_1.vtu")).unwrap();
        let e = read_pvtu_arrays(&pvtu).unwrap_err().to_string();
        assert!(e.contains("solution_00003_1.vtu"), "{e}");
    }
}
