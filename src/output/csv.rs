//! A line-oriented CSV table appended one block of rows at a time.
//!
//! Each [`CsvTable::append`] validates the whole block, formats it into one buffer and hands
//! it to the OS in one `write_all` (the file is unbuffered, so there is nothing left to flush):
//! an interrupted run loses at most the block being written, and a rejected block writes
//! nothing. Numbers are written with [`format_number`](super::format_number): shortest
//! round-trip, so reading them back gives the same `f64` bits.

use super::{format_number, OutputError};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A CSV file being written; see the module documentation.
#[derive(Debug)]
pub struct CsvTable {
    path: PathBuf,
    file: File,
    columns: usize,
    rows: usize,
}

/// Quotes a header cell if it contains a comma, a quote or a line break (RFC 4180).
fn quote(cell: &str) -> String {
    if cell.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", cell.replace('"', "\"\""))
    } else {
        cell.to_string()
    }
}

impl CsvTable {
    /// Creates (or truncates) `path` and writes the header line.
    pub fn create(path: &Path, header: &[&str]) -> Result<Self, OutputError> {
        if header.is_empty() {
            return Err(OutputError::InvalidArgument {
                path: path.to_path_buf(),
                detail: "a CSV table needs at least one column".into(),
            });
        }
        let mut file = File::create(path).map_err(|e| OutputError::write(path, e))?;
        let mut line = header.iter().map(|h| quote(h)).collect::<Vec<_>>().join(",");
        line.push('\n');
        file.write_all(line.as_bytes())
            .map_err(|e| OutputError::write(path, e))?;
        Ok(CsvTable {
            path: path.to_path_buf(),
            file,
            columns: header.len(),
            rows: 0,
        })
    }

    /// Appends `rows` as one block; an error if any row's length differs from the header's
    /// (then nothing is written).
    pub fn append(&mut self, rows: &[Vec<f64>]) -> Result<(), OutputError> {
        let text: Vec<Vec<String>> = rows
            .iter()
            .map(|r| r.iter().map(|&x| format_number(x)).collect())
            .collect();
        self.append_text(&text)
    }

    /// Appends rows of already formatted cells (text columns such as a group name), then flushes.
    pub fn append_text(&mut self, rows: &[Vec<String>]) -> Result<(), OutputError> {
        if let Some((row, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != self.columns) {
            return Err(OutputError::CsvRow {
                path: self.path.clone(),
                row,
                got: r.len(),
                expected: self.columns,
            });
        }
        if rows.is_empty() {
            return Ok(());
        }
        let mut block = String::with_capacity(rows.len() * self.columns * 24);
        for r in rows {
            for (i, x) in r.iter().enumerate() {
                if i > 0 {
                    block.push(',');
                }
                block.push_str(x);
            }
            block.push('\n');
        }
        self.file
            .write_all(block.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| OutputError::write(&self.path, e))?;
        self.rows += rows.len();
        Ok(())
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rows written so far (not counting the header).
    pub fn rows(&self) -> usize {
        self.rows
    }
}
