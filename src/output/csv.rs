//! A line-oriented CSV table appended one block of rows at a time.
//!
//! Each [`CsvTable::append`] validates the whole block, formats it into one buffer and hands
//! it to the OS in one `write_all` (the file is unbuffered, so there is nothing left to flush):
//! an interrupted run loses at most the block being written, and a rejected block writes
//! nothing. Numbers are written with [`format_number`](super::format_number): shortest
//! round-trip, so reading them back gives the same `f64` bits.
//!
//! Lines are formatted by the `csv` crate: a cell is quoted (RFC 4180, `"` doubled) only when
//! it holds a comma, a quote or a line break, such as a group named `Gamma, 3`; lines end in
//! `\n`. A table without such cells is byte for byte what joining the cells with commas gives.

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

/// `records` as CSV text in memory (quoted only where necessary, `\n` line ends), for one
/// `write_all` to `path`.
fn format_block<R, C>(path: &Path, records: impl IntoIterator<Item = R>) -> Result<Vec<u8>, OutputError>
where
    R: IntoIterator<Item = C>,
    C: AsRef<[u8]>,
{
    let fail = |e: csv::Error| OutputError::write(path, std::io::Error::other(e));
    let mut writer = csv::WriterBuilder::new()
        .quote_style(csv::QuoteStyle::Necessary)
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    for record in records {
        writer.write_record(record).map_err(fail)?;
    }
    writer
        .into_inner()
        .map_err(|e| OutputError::write(path, e.into_error()))
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
        let line = format_block(path, [header])?;
        let mut file = File::create(path).map_err(|e| OutputError::write(path, e))?;
        file.write_all(&line).map_err(|e| OutputError::write(path, e))?;
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
        let block = format_block(&self.path, rows)?;
        self.file
            .write_all(&block)
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

#[cfg(test)]
mod tests {
    use super::CsvTable;

    /// Cells are quoted only when they must be: plain tables are what joining with commas gives.
    #[test]
    fn quotes_only_cells_that_need_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let mut table = CsvTable::create(&path, &["time", "group", "force"]).unwrap();
        table.append(&[vec![0.5, 3.0, -1e-7]]).unwrap();
        let cells = |g: &str| vec!["1".to_string(), g.to_string(), "2".to_string()];
        table
            .append_text(&[cells("Gamma3"), cells("Gamma, 3"), cells("say \"hi\""), cells("a\nb")])
            .unwrap();
        assert_eq!(table.rows(), 5);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            "time,group,force\n0.5,3,-1e-7\n1,Gamma3,2\n1,\"Gamma, 3\",2\n1,\"say \"\"hi\"\"\",2\n1,\"a\nb\",2\n"
        );
        let header = CsvTable::create(&dir.path().join("h.csv"), &["a,b", "c"]).unwrap();
        assert_eq!(std::fs::read_to_string(header.path()).unwrap(), "\"a,b\",c\n");
    }
}
