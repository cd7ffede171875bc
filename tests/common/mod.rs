//! Helpers shared by the integration tests: run a case file of `cases/`
//! with overrides into a temporary directory and read its summary.

#![allow(dead_code)]

use grainflow::case::Case;
use grainflow::simulation;
use serde_json::Value;
use std::path::{Path, PathBuf};

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
