//! Helpers shared by the integration tests: run a case file of `cases/`
//! with overrides into a temporary directory and read its summary.

#![allow(dead_code)]

use grainflow::case::Case;
use grainflow::simulation;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

pub fn case_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(name)
}

pub fn load(name: &str, overrides: &[&str]) -> Case {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Case::load(&case_path(name), &overrides).expect("case loads")
}

/// Runs a case (with `--set` style overrides) and returns the summary and
/// the output directory (kept alive by the returned guard).
pub fn run(name: &str, overrides: &[&str]) -> (Value, tempfile::TempDir) {
    let case = load(name, overrides);
    let dir = tempfile::tempdir().expect("temporary directory");
    let summary = simulation::run(&case, dir.path(), false).expect("run succeeds");
    (summary.json, dir)
}

pub fn metric(summary: &Value, name: &str) -> f64 {
    summary["metrics"][name]
        .as_f64()
        .unwrap_or_else(|| panic!("metric {name} missing in {summary}"))
}

pub fn relative_error(value: f64, reference: f64) -> f64 {
    ((value - reference) / reference).abs()
}

/// `grainflow run` of a case of `cases/` with `--set` overrides into a
/// fresh directory: (exit code, stderr, whether the directory was written).
pub fn run_cli(case: &str, overrides: &[&str]) -> (Option<i32>, String, bool) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut command = Command::new(env!("CARGO_BIN_EXE_grainflow"));
    command.args([
        "run",
        case_path(case).to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    for assignment in overrides {
        command.args(["--set", assignment]);
    }
    let result = command.output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr).into_owned();
    (result.status.code(), stderr, out.exists())
}

/// The numbers of the last row of a CSV file written by a run.
pub fn last_row(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    text.lines()
        .last()
        .expect("a row")
        .split(',')
        .map(|v| v.parse().expect("a number"))
        .collect()
}
