//! Axisymmetric scenes from a case file (`domain.geometry =
//! "axisymmetric"`): the output contract of a run, and the refusals of
//! what (r, z) cannot hold, each naming its key, with nothing written.

mod common;

use common::{case_path, run_cli};
use std::process::Command;

#[test]
fn an_axisymmetric_run_keeps_the_output_contract_with_its_grains_on_the_axis() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let status = Command::new(env!("CARGO_BIN_EXE_grainflow"))
        .args([
            "run",
            case_path("bouncing_sphere_axisymmetric.toml")
                .to_str()
                .unwrap(),
        ])
        .args(["--out", out.to_str().unwrap()])
        .args(["--set", "time.end=0.02", "--set", "output.fields=true"])
        .status()
        .unwrap();
    assert!(status.success());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "ok");
    assert_eq!(summary["geometry"], "axisymmetric");
    assert_eq!(summary["cells"], 60 * 260);
    for file in [
        "series.csv",
        "flow_series.csv",
        "tracked.csv",
        "fields.pvd",
        "particles.pvd",
    ] {
        assert!(out.join(file).exists(), "{file} missing");
    }
    assert!(out.join("fields/fields_000000.vti").exists());
    // tracked.csv: t, id, x, y, z, ...: the grain stays on the axis and falls.
    let tracked = std::fs::read_to_string(out.join("tracked.csv")).unwrap();
    let rows: Vec<Vec<f64>> = tracked
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() > 10);
    assert!(
        rows.iter().all(|r| r[2] == 0.0 && r[3] == 0.0),
        "off the axis"
    );
    assert!(
        rows.last().unwrap()[4] < rows[0][4],
        "the grain did not fall"
    );
}

#[test]
fn what_r_z_cannot_hold_is_refused_naming_the_key_and_nothing_is_written() {
    let case = "falling_sphere_axisymmetric.toml";
    for (overrides, key) in [
        (
            vec!["particles.block[0].positions=[[0.001, 0.0, 0.3]]"],
            "off the axis",
        ),
        (vec!["domain.lower=[0.0, -0.2, 0.0]"], "domain.lower"),
        (vec!["fluid.cells=[255, 255, 800]"], "fluid.cells"),
        (vec!["fluid.cells=[256, 128, 800]"], "fluid.cells"),
        (vec!["domain.gravity=[1.0, 0.0, -9.81]"], "domain.gravity"),
        (vec!["output.format=\"hdf5\""], "output.format"),
        (
            vec!["fluid.boundary.x=[\"no_slip\", \"free_slip\"]"],
            "fluid.boundary.x",
        ),
        (
            vec!["fluid.boundary.z=[\"periodic\", \"free_slip\"]"],
            "fluid.boundary.z",
        ),
        (vec!["fluid.viscous=\"explicit\""], "fluid.viscous"),
        (vec!["fluid.stretching.core_cells=200"], "fluid.stretching"),
        (
            vec![
                "domain.dimension=2",
                "domain.lower=[-0.2, 0.0]",
                "domain.upper=[0.2, 0.4]",
                "domain.gravity=[0.0, -9.81]",
                "fluid.cells=[256, 800]",
                "particles.block[0].positions=[[0.0, 0.375]]",
            ],
            "domain.geometry",
        ),
        (vec!["analysis.kind=\"inclined_bed\""], "analysis.kind"),
        // The grain's immersed boundary must lie in the uniform core.
        (
            vec![
                "fluid.stretching.core_radius=0.004",
                "fluid.stretching.core_cells=8",
            ],
            "stretched",
        ),
    ] {
        let (code, stderr, written) = run_cli(case, &overrides);
        assert_eq!(code, Some(2), "{overrides:?}: {stderr}");
        assert!(stderr.contains(key), "{overrides:?}: {stderr}");
        assert!(!written, "{overrides:?}: output written");
    }
    // A Cartesian scene has no radial core.
    let (code, stderr, written) = run_cli(
        "falling_sphere.toml",
        &[
            "fluid.stretching.core_radius=0.01",
            "fluid.stretching.core_cells=4",
        ],
    );
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("fluid.stretching.core_radius"), "{stderr}");
    assert!(!written);
}

/// A step adapted to `time.cfl` that collapses (a flow running away, which
/// the adapted step would follow towards zero while the run stands still)
/// stops the run with a diagnosis; near the end a short last step does not.
#[test]
fn a_collapsed_adaptive_step_is_a_diagnosed_failure() {
    use grainflow::simulation::coupled::{collapsed_step, COLLAPSED_STEP};
    let overrides = vec!["time.cfl=1.0".to_string()];
    let case =
        grainflow::case::Case::load(&case_path("bouncing_sphere_axisymmetric.toml"), &overrides)
            .unwrap();
    let largest = case.time.dt.unwrap();
    let tiny = 0.5 * COLLAPSED_STEP * largest;
    let why = collapsed_step(tiny, &case, 0.1, 0.3).expect("a collapse");
    assert!(
        why.contains("time.cfl") && why.contains("running away"),
        "{why}"
    );
    assert!(collapsed_step(0.5 * largest, &case, 0.1, 0.3).is_none());
    assert!(collapsed_step(tiny, &case, 0.3 - 0.5 * tiny, 0.3).is_none());
}
