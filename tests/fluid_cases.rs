//! The fluid-only cases of `cases/` run through the whole program: exact
//! decaying vortices (second order in space and time), divergence after
//! projection, steady channel flows, and the refusals of bad fluid tables.

mod common;

use common::{load, metric, run, run_cli};
use grainflow::simulation;

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
    let last: Vec<f64> = series
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
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
