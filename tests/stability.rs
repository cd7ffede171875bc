//! Where the explicit contact integration stops being accurate and where it
//! blows up, against Δt/t_c (the limits `check` and `run` enforce).

mod common;

use grainflow::stability::{ACCURATE_DT_OVER_TC, STABLE_DT_OVER_TC};
use grainflow::{scene, simulation, RunError};

/// Restitution of a head-on binary collision run at Δt = ratio · t_c,
/// stepping the system directly (past the limits the CLI enforces).
fn head_on_restitution(ratio: f64) -> f64 {
    let case = common::load(
        "binary_collision.toml",
        &[
            "particles.block[0].count=1",
            "particles.block[0].gap=1.0e-5",
        ],
    );
    let mut system = scene::build(&case).unwrap();
    let dt = ratio * 1.0e-5;
    let mut time = 0.0;
    while time < 3.0e-4 {
        system.step(dt);
        time += dt;
    }
    let p = &system.particles;
    let (a, b) = (system.index_of(0).unwrap(), system.index_of(1).unwrap());
    -(p.velocity[a].x - p.velocity[b].x) / 0.1
}

/// Whether a settled packing (the reduced 2D column before release, ~400
/// discs, several contacts each) stays bounded for 2000 steps at Δt = ratio · t_c.
fn packing_survives(settled: &grainflow_dem::DemSystem, ratio: f64) -> bool {
    let mut system = settled.clone();
    let dt = ratio * 1.0e-4;
    for _ in 0..2000 {
        let d = system.step(dt);
        if d.non_finite || d.max_overlap_ratio > 0.25 {
            return false;
        }
    }
    true
}

#[test]
fn restitution_is_accurate_up_to_the_accuracy_limit_and_not_far_beyond() {
    let e_n = 0.87;
    let mut rows = Vec::new();
    for ratio in [0.01, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4] {
        let e = head_on_restitution(ratio);
        rows.push((ratio, e, common::relative_error(e, e_n)));
    }
    for (ratio, e, err) in &rows {
        println!(
            "dt/t_c = {ratio:5.3}: e = {e:.5}, error {:.3} %",
            100.0 * err
        );
    }
    for &(ratio, _, err) in &rows {
        if ratio <= ACCURATE_DT_OVER_TC {
            assert!(
                err < 0.01,
                "dt/t_c = {ratio}: restitution error {err} above 1 %"
            );
        }
    }
    assert!(
        rows.iter().any(|&(ratio, _, err)| ratio <= 3.0 * ACCURATE_DT_OVER_TC && err > 0.01),
        "the accuracy limit {ACCURATE_DT_OVER_TC} is not sharp: errors stay below 1 % well beyond it"
    );
}

/// About 500 spheres settled on a floor, periodic in x and y.
fn settled_3d() -> grainflow_dem::DemSystem {
    let text = r#"
        [domain]
        dimension = 3
        lower = [0.0, 0.0, 0.0]
        upper = [0.066, 0.066, 0.2]
        periodic = [true, true, false]
        gravity = [0.0, 0.0, -9.81]
        [particles]
        density = 2500.0
        radius = 5.0e-3
        radius_spread = 0.1
        [[particles.block]]
        kind = "lattice"
        lower = [0.0, 0.0, 0.0]
        upper = [0.066, 0.066, 0.165]
        spacing = 0.011
        jitter = 0.5
        [contact]
        model = "soft"
        restitution = 0.5
        contact_time = 1.0e-4
        friction = 0.5
        [[walls]]
        point = [0.0, 0.0, 0.0]
        normal = [0.0, 0.0, 1.0]
        [time]
        end = 0.3
    "#;
    let case = grainflow::case::Case::from_text(text, "packing", &[]).unwrap();
    let mut system = scene::build(&case).unwrap();
    for _ in 0..(0.3 / 5.0e-6) as usize {
        system.step(5.0e-6);
    }
    system
}

fn settled(name: &str, overrides: &[&str], duration: f64) -> grainflow_dem::DemSystem {
    let case = common::load(name, overrides);
    let mut system = scene::build(&case).unwrap();
    for _ in 0..(duration / 5.0e-6) as usize {
        system.step(5.0e-6);
    }
    system
}

#[test]
fn a_dense_packing_blows_up_past_the_stability_limit() {
    // 2D discs (~400, before the gates open) and 3D spheres (a short silo).
    for settled in [settled("column_collapse_2d.toml", &[], 0.6), settled_3d()] {
        check_packing(&settled);
    }
}

fn check_packing(settled: &grainflow_dem::DemSystem) {
    println!(
        "{} particles, {} contacts",
        settled.particles.n_owned, settled.last.particle_contacts
    );
    let mut rows = Vec::new();
    for ratio in [0.1, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7] {
        rows.push((ratio, packing_survives(settled, ratio)));
    }
    for (ratio, ok) in &rows {
        println!(
            "dt/t_c = {ratio:4.2}: {}",
            if *ok { "stable" } else { "blows up" }
        );
    }
    for &(ratio, ok) in &rows {
        if ratio <= STABLE_DT_OVER_TC {
            assert!(
                ok,
                "dt/t_c = {ratio} is within the stability limit but blew up"
            );
        }
    }
    assert!(
        rows.iter()
            .any(|&(ratio, ok)| ratio <= 3.0 * STABLE_DT_OVER_TC && !ok),
        "no blow-up below 3x the stability limit: the limit is too strict"
    );
}

#[test]
fn run_refuses_a_step_past_the_stability_limit_and_writes_nothing() {
    let case = common::load(
        "binary_collision.toml",
        &[&format!(
            "time.dt_over_contact_time={}",
            1.2 * STABLE_DT_OVER_TC
        )],
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("refused");
    match simulation::run(&case, &out, false) {
        Err(RunError::Case(message)) => assert!(message.contains("stability limit"), "{message}"),
        other => panic!("expected a refusal, got {other:?}"),
    }
    assert!(
        !out.exists(),
        "a refused run must not create its output directory"
    );
}
