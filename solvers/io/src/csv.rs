//! A CSV file with a fixed header, appended one row per call. Each row
//! (and the header) goes to the file in one `write` call of the whole line
//! with its newline, unbuffered, so a run that stops, a kill included,
//! keeps every row written so far and never leaves a partial row. (A crash
//! of the machine itself, which loses what the system had not yet put on
//! disk, can at worst leave a last partial line.)

use std::fs::File;
use std::io::Write;
use std::path::Path;

pub struct CsvSeries {
    file: File,
    columns: usize,
}

impl CsvSeries {
    pub fn create(path: &Path, header: &[&str]) -> std::io::Result<Self> {
        let mut file = File::create(path)?;
        file.write_all(format!("{}\n", header.join(",")).as_bytes())?;
        Ok(CsvSeries {
            file,
            columns: header.len(),
        })
    }

    /// [`CsvSeries::create`] on the rank that writes the shared files
    /// (`root`); None elsewhere.
    pub fn create_on(root: bool, path: &Path, header: &[&str]) -> std::io::Result<Option<Self>> {
        root.then(|| Self::create(path, header)).transpose()
    }

    /// Writes one row of numbers (17 significant digits, round-trip exact)
    /// in one write of the whole line.
    pub fn row(&mut self, values: &[f64]) -> std::io::Result<()> {
        debug_assert_eq!(values.len(), self.columns);
        let mut line = values
            .iter()
            .map(|v| format_number(*v))
            .collect::<Vec<_>>()
            .join(",");
        line.push('\n');
        self.file.write_all(line.as_bytes())
    }
}

/// Shortest representation that reads back to the same `f64`.
pub fn format_number(value: f64) -> String {
    if value.fract() == 0.0 && value.abs() < 1e15 {
        format!("{}", value as i64)
    } else {
        format!("{value:e}")
    }
}
