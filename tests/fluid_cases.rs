//! The fluid-only cases of `cases/` run through the whole program: exact
//! decaying vortices (second order in space and time), divergence after
//! projection, steady channel flows, the start-up of a Couette flow on a
//! stretched grid, and the refusals of bad fluid tables.

mod common;

use common::{last_row, load, metric, run, run_cli};
use grainflow::case::Case;
use grainflow::simulation;
use grainflow_fluid::CFL_LIMIT;

/// Relative L2 error of the Taylor–Green vortex (carried by a stream) at
/// t = 1 s on n² cells with Δt ∝ Δx (CFL 0.36 at n = 64).
fn taylor_green_error(n: usize) -> f64 {
    let cells = format!("fluid.cells=[{n}, {n}]");
    let dt = format!("time.dt={}", 0.01 * 64.0 / n as f64);
    let (summary, _dir) = run(
        "taylor_green_2d.toml",
        &[&cells, &dt, "output.fields=false"],
    );
    assert!(metric(&summary, "max_divergence") <= 1e-12, "{summary}");
    metric(&summary, "l2_error")
}

#[test]
fn taylor_green_2d_converges_at_second_order_in_space_and_time() {
    let errors: Vec<f64> = [16, 32, 64].map(taylor_green_error).to_vec();
    let orders: Vec<f64> = errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    eprintln!("Taylor–Green 2D: errors {errors:?}, observed orders {orders:?}");
    assert!(orders.iter().all(|&p| p >= 1.9), "orders {orders:?}");
    // The 64² case of cases/ itself: the error of a second-order scheme at
    // this resolution (measured 9.46e-4).
    assert!(errors[2] < 2e-3, "{errors:?}");
}

#[test]
fn beltrami_3d_converges_at_second_order_and_stays_divergence_free() {
    let errors: Vec<f64> = [8, 16]
        .map(|n| {
            let cells = format!("fluid.cells=[{n}, {n}, {n}]");
            let dt = format!("time.dt={}", 0.02 * 32.0 / n as f64);
            let (summary, _dir) = run(
                "taylor_green_3d.toml",
                &[&cells, &dt, "time.end=0.32", "output.fields=false"],
            );
            assert!(metric(&summary, "max_divergence") <= 1e-12, "{summary}");
            metric(&summary, "l2_error")
        })
        .to_vec();
    let order = (errors[0] / errors[1]).log2();
    eprintln!("Beltrami 3D: errors {errors:?}, observed order {order:.3}");
    assert!(order >= 1.9, "{errors:?}");
}

#[test]
fn couette_flow_reaches_the_exact_line() {
    let (summary, _dir) = run("channel_couette.toml", &["output.fields=false"]);
    let error = metric(&summary, "profile_error");
    eprintln!("Couette: profile error {error:.3e}");
    assert!(error <= 1e-10, "{summary}");
}

/// The steady discrete Poiseuille flow is the exact parabola
/// u = K y (H − y): the interior stencil is exact for a parabola, and so is
/// the no-slip closure along the wall-normal axis (the quadratic ghost
/// u_ghost = (8 u_wall − 6 u_1 + u_2)/3). The metric is the largest
/// |u − u_exact| over the largest |u_exact|.
#[test]
fn poiseuille_flow_reaches_the_exact_parabola() {
    for cells in [16, 32] {
        let set = format!("fluid.cells=[4, {cells}]");
        let (summary, _dir) = run("channel_poiseuille.toml", &[&set, "output.fields=false"]);
        let error = metric(&summary, "profile_error");
        eprintln!("Poiseuille {cells} cells: profile error {error:.3e}");
        assert!(error <= 1e-10, "{cells} cells: {summary}");
    }
}

/// The start-up of Couette flow (a wall set sliding under water at rest)
/// on 32 cells clustered at the sliding wall, against the exact sine
/// series at t = 1 s, when the layer is a tenth of the gap: the error of a
/// second-order scheme at this resolution (measured 4.08e-4, bound 5e-4),
/// 3.0 times smaller than on uniform cells (bound: at least 2.5 times).
/// The fields go to RectilinearGrid files with the stretched coordinates.
#[test]
fn couette_start_up_is_resolved_by_cells_clustered_at_the_wall() {
    let (summary, dir) = run("couette_startup.toml", &[]);
    let clustered = metric(&summary, "profile_error");
    assert!(metric(&summary, "max_divergence") <= 1e-12, "{summary}");
    let (summary, _dir) = run(
        "couette_startup.toml",
        &["fluid.stretching.factor=1e-6", "output.fields=false"],
    );
    let uniform = metric(&summary, "profile_error");
    eprintln!(
        "Couette start-up: profile error {clustered:.3e} clustered, {uniform:.3e} uniform, gain {:.2}",
        uniform / clustered
    );
    assert!(clustered <= 5e-4, "{clustered:e}");
    assert!(uniform / clustered >= 2.5, "{uniform:e} / {clustered:e}");
    let index = std::fs::read_to_string(dir.path().join("fields.pvd")).unwrap();
    assert!(index.contains("fields/fields_000000.vtr"), "{index}");
    let bytes = std::fs::read(dir.path().join("fields/fields_000004.vtr")).unwrap();
    let frame = grainflow_io::read_vtk(&bytes).unwrap();
    assert!(frame
        .xml
        .contains(r#"<RectilinearGrid WholeExtent="0 4 0 32 0 1">"#));
    assert_eq!(frame.arrays.len(), 3 + 3, "3 coordinates, 3 fields");
}

/// Flow through porous walls (blowing below, suction above, the upper wall
/// sliding): the steady asymptotic suction profile on 32 cells clustered at
/// the suction wall (measured 2.95e-4, bound 4e-4), 2.9 times more
/// accurate than on uniform cells (bound: at least 2.5 times); the
/// wall-normal velocity stays V, so the projection keeps the divergence at
/// round-off.
#[test]
fn the_suction_profile_through_porous_walls() {
    let (summary, _dir) = run("channel_suction.toml", &["output.fields=false"]);
    let clustered = metric(&summary, "profile_error");
    assert!(metric(&summary, "max_divergence") <= 1e-12, "{summary}");
    let (summary, _dir) = run(
        "channel_suction.toml",
        &["fluid.stretching.factor=1e-6", "output.fields=false"],
    );
    let uniform = metric(&summary, "profile_error");
    eprintln!(
        "suction profile: error {clustered:.3e} clustered, {uniform:.3e} uniform, gain {:.2}",
        uniform / clustered
    );
    assert!(clustered <= 4e-4, "{clustered:e}");
    assert!(uniform / clustered >= 2.5, "{uniform:e} / {clustered:e}");
    // As much must leave as enters.
    let (code, stderr, written) = run_cli(
        "channel_suction.toml",
        &["fluid.boundary.y_upper_velocity=[0.01, 1.0e-3]"],
    );
    assert_ne!(code, Some(0));
    assert!(
        stderr.contains("fluid.boundary.y_upper_velocity"),
        "{stderr}"
    );
    assert!(!written);
}

/// An inflow through the floor and an open outflow at the top
/// (`cases/channel_outflow.toml`) against the steady profile with
/// u'(H) = 0: second order (orders ≥ 1.9 over 16, 32, 64 cells; measured
/// errors 2.81e-3, 7.20e-4, 1.82e-4), the divergence at round-off. Without
/// the inflow the profile is the half parabola, which the outflow's mirror
/// ghost represents exactly (measured 1.2e-13; bound 1e-10). An outflow on
/// a lower face is refused.
#[test]
fn an_open_outflow_passes_the_profile_on() {
    let errors: Vec<f64> = [16, 32, 64]
        .iter()
        .map(|n| {
            let cells = format!("fluid.cells=[4, {n}]");
            let (summary, _dir) = run("channel_outflow.toml", &[&cells, "output.fields=false"]);
            assert!(metric(&summary, "max_divergence") <= 1e-12, "{summary}");
            metric(&summary, "profile_error")
        })
        .collect();
    let orders: Vec<f64> = errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    eprintln!("inflow and outflow: errors {errors:?}, orders {orders:?}");
    assert!(orders.iter().all(|&p| p >= 1.9), "{orders:?}");
    let (summary, _dir) = run(
        "channel_outflow.toml",
        &[
            "fluid.boundary.y_lower_velocity=[0.0, 0.0]",
            "fluid.initial={kind=\"rest\"}",
            "output.fields=false",
            "time.end=1500.0",
        ],
    );
    let error = metric(&summary, "profile_error");
    eprintln!("outflow without inflow: profile error {error:.3e}");
    assert!(error <= 1e-10, "{summary}");
    let (code, stderr, written) = run_cli(
        "channel_outflow.toml",
        &["fluid.boundary.y=[\"outflow\", \"no_slip\"]"],
    );
    assert_ne!(code, Some(0));
    assert!(stderr.contains("fluid.boundary.y"), "{stderr}");
    assert!(!written);
}

/// A stretched axis must have walls, a scene with grains keeps uniform
/// cells, and the stretching table takes one of its two forms with values
/// that make a grid.
#[test]
fn bad_stretching_tables_are_refused_with_the_key_and_nothing_is_written() {
    for (case, overrides, key) in [
        (
            "couette_startup.toml",
            vec!["fluid.stretching.cluster=\"middle\""],
            "fluid.stretching.cluster",
        ),
        (
            "couette_startup.toml",
            vec!["fluid.stretching.factor=0.0"],
            "fluid.stretching.factor",
        ),
        (
            "couette_startup.toml",
            vec!["fluid.stretching.factor=20.0"],
            "fluid.stretching.factor",
        ),
        (
            "couette_startup.toml",
            vec!["fluid.stretching={faces=[0.0, 0.005, 0.01]}"],
            "fluid.stretching.faces",
        ),
        (
            "couette_startup.toml",
            vec!["fluid.stretching={cluster=\"lower_wall\", factor=2.0, faces=[0.0, 0.01]}"],
            "fluid.stretching",
        ),
        (
            "channel_poiseuille.toml",
            vec![
                "fluid.stretching={cluster=\"both_walls\", factor=2.0}",
                "domain.periodic=[true, true]",
                "fluid.boundary.y=[\"periodic\", \"periodic\"]",
            ],
            "fluid.stretching",
        ),
        (
            "falling_sphere.toml",
            vec!["fluid.stretching={cluster=\"both_walls\", factor=1.0}"],
            "fluid.stretching",
        ),
    ] {
        let (code, stderr, written) = run_cli(case, &overrides);
        assert_ne!(code, Some(0), "{overrides:?}");
        assert!(stderr.contains(key), "{overrides:?}: {stderr}");
        assert!(!written, "{overrides:?}: output written");
    }
}

#[test]
fn bad_fluid_tables_are_refused_with_the_key_and_nothing_is_written() {
    for (assignment, key) in [
        ("fluid.boundary.y=[\"no_slip\"]", "fluid.boundary.y"),
        (
            "fluid.boundary.y=[\"sticky\", \"no_slip\"]",
            "fluid.boundary.y",
        ),
        (
            "fluid.boundary.y=[\"no_slip\", \"moving\"]",
            "fluid.boundary.y_upper_velocity",
        ),
        ("fluid.cells=[4]", "fluid.cells"),
        ("fluid.viscosity=-1", "fluid.viscosity"),
        ("time.cfl=2.0", "time.cfl"),
        ("domain.periodic=[true, true]", "fluid.boundary.y"),
        ("time.dt=10.0", "CFL"),
        ("fluid.transforms=\"fft\"", "fluid.transforms"),
        (
            if cfg!(feature = "fftw") {
                "fluid.transforms=\"fast\""
            } else {
                "fluid.transforms=\"fftw\""
            },
            "fluid.transforms",
        ),
    ] {
        let mut overrides = vec![assignment];
        if assignment.starts_with("time.dt") {
            // A flow to convect: the refused step is the CFL one.
            overrides.push("fluid.initial={kind=\"uniform\", velocity=[1.0, 0.0]}");
        }
        let (code, stderr, written) = run_cli("channel_poiseuille.toml", &overrides);
        assert_ne!(code, Some(0), "{assignment}");
        assert!(stderr.contains(key), "{assignment}: {stderr}");
        assert!(!written, "{assignment}: output written");
    }
}

#[test]
fn a_fluid_run_writes_the_output_contract() {
    let dir = tempfile::tempdir().unwrap();
    let case = load(
        "taylor_green_2d.toml",
        &["fluid.cells=[16, 16]", "time.end=0.1"],
    );
    simulation::run(&case, dir.path(), false).unwrap();
    for file in [
        "case.toml",
        "log.txt",
        "series.csv",
        "tracked.csv",
        "fields.pvd",
        "summary.json",
    ] {
        assert!(dir.path().join(file).exists(), "{file}");
    }
    let frames = std::fs::read_dir(dir.path().join("fields"))
        .unwrap()
        .count();
    assert_eq!(frames, 2, "t = 0 and the end");
    let series = std::fs::read_to_string(dir.path().join("series.csv")).unwrap();
    assert!(series.starts_with("t,dt,step,kinetic_energy,max_cfl,max_divergence"));
    // The kinetic energy decays as exp(−4 ν k² t) around the stream's share.
    let last = last_row(&dir.path().join("series.csv"));
    let area = (2.0 * std::f64::consts::PI).powi(2);
    let stream = 0.5 * (1.0 + 0.25) * area;
    let vortex = 0.25 * area * (-4.0 * 0.01 * 0.1f64).exp();
    assert!(
        ((last[3] - stream - vortex) / vortex).abs() < 0.02,
        "{last:?}"
    );
}

/// An explicit viscous term: a time step beyond its limit (ν Δt Σ 4/h² =
/// 12.5 here, limit 8.61) is refused before anything is written; within it
/// the channel still reaches the exact parabola.
#[test]
fn an_explicit_viscous_step_is_refused_beyond_its_limit() {
    let (code, stderr, written) = run_cli(
        "channel_poiseuille.toml",
        &["fluid.viscous=\"explicit\"", "time.dt=3e-3"],
    );
    assert_ne!(code, Some(0));
    assert!(stderr.contains("viscous number"), "{stderr}");
    assert!(!written);
    let (summary, _dir) = run(
        "channel_poiseuille.toml",
        &["fluid.viscous=\"explicit\"", "output.fields=false"],
    );
    assert!(metric(&summary, "profile_error") <= 1e-10, "{summary}");
}

/// A channel driven at constant flow rate (bulk velocity 0.5 m/s held
/// along x) instead of a pressure gradient: the steady profile is the
/// parabola whose mean over the cells is 0.5 m/s, to 1e-10, and the
/// pressure gradient that holds it is μ u'' = −12 μ U_b / (H² + h²/2),
/// to 1e-10 relative; with either viscous scheme.
#[test]
fn a_channel_at_constant_flow_rate_reaches_the_parabola_and_its_pressure_gradient() {
    for viscous in ["crank_nicolson", "explicit"] {
        let scheme = format!("fluid.viscous=\"{viscous}\"");
        let (summary, _dir) = run(
            "channel_poiseuille.toml",
            &[
                "fluid.pressure_gradient=[0.0, 0.0]",
                "fluid.bulk_velocity={x = 0.5}",
                &scheme,
                "output.fields=false",
            ],
        );
        assert!(metric(&summary, "profile_error") <= 1e-10, "{summary}");
        // μ = 1 Pa s, H = 1 m, h = 1/32 m.
        let expected = -12.0 * 0.5 / (1.0 + 1.0 / (2.0 * 32.0 * 32.0));
        let held = metric(&summary, "pressure_gradient_x");
        assert!(
            ((held - expected) / expected).abs() <= 1e-10,
            "{held} vs {expected}"
        );
    }
}

/// A lid sliding at 1 m/s over a cavity of 16 × 16 cells at rest, the step
/// adapted to CFL 0.8 (the case of a reported defect: the step was taken
/// from the fluid at rest alone, so the first one spanned the whole run,
/// reached CFL 3.7e4 and was reported "ok").
const LID_FROM_REST: &str = r#"
[domain]
dimension = 2
lower = [0.0, 0.0]
upper = [1.0, 1.0]

[fluid]
cells = [16, 16]
density = 1.0
viscosity = 0.01

[fluid.boundary]
x = ["no_slip", "no_slip"]
y = ["no_slip", "moving"]
y_upper_velocity = [1.0, 0.0]

[time]
end = 0.1
cfl = 0.8

[output]
interval = 0.01
"#;

#[test]
fn an_adapted_step_from_rest_keeps_the_cfl_number_a_sliding_lid_sets() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lid.toml");
    std::fs::write(&path, LID_FROM_REST).unwrap();
    let case = Case::load(&path, &[]).unwrap();
    let out = dir.path().join("out");
    let summary = simulation::run(&case, &out, false).unwrap().json;
    assert_eq!(summary["status"], "ok");
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    let rows: Vec<Vec<f64>> = series
        .lines()
        .skip(1)
        .map(|line| line.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // t, dt, step, kinetic_energy, max_cfl, ...: every step within CFL 0.8
    // at the lid's speed (h = 1/16), so at least 0.1 / (0.8/16) = 2 steps.
    for row in &rows {
        assert!(row[1] <= 0.8 / 16.0 * (1.0 + 1e-12), "dt {}", row[1]);
        assert!(row[4] <= 0.8, "CFL {}", row[4]);
        // The fluid never outruns its lid: ½ ∫|u|² ≤ ½ U² on the unit square.
        assert!(row[3] <= 0.5, "kinetic energy {}", row[3]);
    }
    assert!(summary["steps"].as_u64().unwrap() >= 2);
}

#[test]
fn a_step_that_ends_past_the_rk3_limit_is_a_failure_in_either_mode() {
    let fixed = load("channel_poiseuille.toml", &[]);
    let mut adapted = fixed.clone();
    (adapted.time.dt, adapted.time.cfl) = (None, Some(0.5));
    for case in [&fixed, &adapted] {
        assert!(simulation::fluid::cfl_overrun(CFL_LIMIT, 1e-3, case).is_none());
        for beyond in [1.0001 * CFL_LIMIT, 3.7e4, f64::NAN] {
            let why = simulation::fluid::cfl_overrun(beyond, 1e-3, case).expect("a failure");
            let advice = if case.time.cfl.is_some() {
                "lower time.cfl"
            } else {
                "reduce time.dt"
            };
            assert!(why.contains(advice), "{why}");
        }
    }
}
