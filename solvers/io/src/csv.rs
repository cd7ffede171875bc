//! A CSV file with a fixed header, one row per call, flushed each row so a
//! run that stops keeps every row written so far.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

pub struct CsvSeries {
    writer: BufWriter<File>,
    columns: usize,
}

impl CsvSeries {
    pub fn create(path: &Path, header: &[&str]) -> std::io::Result<Self> {
        let mut writer = BufWriter::new(File::create(path)?);
        writeln!(writer, "{}", header.join(","))?;
        writer.flush()?;
        Ok(CsvSeries {
            writer,
            columns: header.len(),
        })
    }

    /// [`CsvSeries::create`] on the rank that writes the shared files
    /// (`root`); None elsewhere.
    pub fn create_on(root: bool, path: &Path, header: &[&str]) -> std::io::Result<Option<Self>> {
        root.then(|| Self::create(path, header)).transpose()
    }

    /// Writes one row of numbers (17 significant digits, round-trip exact).
    pub fn row(&mut self, values: &[f64]) -> std::io::Result<()> {
        debug_assert_eq!(values.len(), self.columns);
        let line: Vec<String> = values.iter().map(|v| format_number(*v)).collect();
        writeln!(self.writer, "{}", line.join(","))?;
        self.writer.flush()
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
