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
    /// Bytes in the file: what a checkpoint records, so that a resumed run
    /// appends after the rows of the state it resumes from.
    length: u64,
}

impl CsvSeries {
    pub fn create(path: &Path, header: &[&str]) -> std::io::Result<Self> {
        let mut file = File::create(path)?;
        let line = format!("{}\n", header.join(","));
        file.write_all(line.as_bytes())?;
        Ok(CsvSeries {
            file,
            columns: header.len(),
            length: line.len() as u64,
        })
    }

    /// Reopens a series to append after its first `length` bytes (the rows
    /// written up to a checkpoint); rows written after them by a run that
    /// was stopped are dropped.
    pub fn resume(path: &Path, header: &[&str], length: u64) -> std::io::Result<Self> {
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)?;
        let found = file.metadata()?.len();
        let mut first = String::new();
        std::io::BufRead::read_line(&mut std::io::BufReader::new(&file), &mut first)?;
        if found < length || first.trim_end() != header.join(",") {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "{} does not hold the {length} bytes the checkpoint recorded under the \
                     header {}",
                    path.display(),
                    header.join(",")
                ),
            ));
        }
        file.set_len(length)?;
        std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(length))?;
        Ok(CsvSeries {
            file,
            columns: header.len(),
            length,
        })
    }

    /// Bytes written so far.
    pub fn length(&self) -> u64 {
        self.length
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
        self.file.write_all(line.as_bytes())?;
        self.length += line.len() as u64;
        Ok(())
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
