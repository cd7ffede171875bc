//! Stokes flow through a simple cubic array of fixed spheres: the drag in
//! translation, where `spin_down.rs` holds the torque in rotation.
//!
//! A body force `f` drives the fluid through a triply periodic box of side
//! `L = 4 D` holding one fixed sphere. At steady state the sphere takes the
//! whole body force on the box, `F = ρ f L³`, and the drag factor is
//! `K = F / (6π μ R U)`, `U` the superficial velocity (the mean of `u`
//! over the box, solid included). For the simple cubic array at solid
//! fraction `φ = (π/6)(D/L)³ = 0.00818`, Hasimoto's (1959) series as
//! extended by Sangani & Acrivos (1982),
//!
//! ```text
//! K = 1 / (1 − 1.7601 φ^{1/3} + φ − 1.5593 φ² + 3.9799 φ^{8/3} − …) = 1.5303,
//! ```
//!
//! within 1e-5 of Zick & Homsy's (1982) boundary-integral values at this
//! dilution. The Reynolds number `U D / ν` is about 0.003.
//!
//! The forced layer's strength per unit time sets the grain's apparent
//! size: eq. 7 moves a face by `α` per stage, whatever the stage's length,
//! so the longer the step against the viscous time of a cell `Δx²/ν`, the
//! more the fluid leaks through the layer between two forcings.

mod common;

use common::{PeriodicSphere, FLUID_DENSITY};
use grainflow_ibm::{CoupledSystem, Coupling, LayerForcing};

const DIAMETER: f64 = 0.01;
const KINEMATIC_VISCOSITY: f64 = 4e-3;
/// Hasimoto–Sangani–Acrivos at φ = (π/6)/64.
const ARRAY_DRAG_FACTOR: f64 = 1.5303;

/// A fixed sphere in the periodic box at D/Δx = `resolution`, the fluid
/// at rest, the layer forced by `layer`.
fn fixed_sphere(resolution: usize, layer: LayerForcing) -> CoupledSystem {
    let mut system = PeriodicSphere {
        diameter: DIAMETER,
        cells: 4 * resolution,
        viscosity: KINEMATIC_VISCOSITY,
        density: 2.0 * FLUID_DENSITY,
        drift: 0.0,
        spin: 0.0,
    }
    .build(Coupling::InnerFluidMomentum);
    let p = &mut system.dem.particles;
    p.inverse_mass[0] = 0.0;
    p.inverse_inertia[0] = 0.0;
    system.immersed.layer = layer;
    system
}

/// The mean of `u` over the box (the superficial velocity).
fn superficial_velocity(system: &CoupledSystem) -> f64 {
    let grid = &system.flow.grid;
    let faces = *system.flow.velocity_unknowns(0);
    let (mut sum, mut count) = (0.0, 0usize);
    for k in faces.start[2]..faces.end[2] {
        for j in faces.start[1]..faces.end[1] {
            for i in faces.start[0]..faces.end[0] {
                sum += system.flow.velocity[0][grid.index(i, j, k)];
                count += 1;
            }
        }
    }
    sum / count as f64
}

/// The drag factor `K` at D/Δx = `resolution` and the viscous number of a
/// cell `ν Δt / Δx²` = `viscous_number`, run until `U` changes by less
/// than 1e-6 of itself over a viscous time of the box `L²/ν`; and the
/// number of steps it took.
fn drag_factor(resolution: usize, viscous_number: f64, layer: LayerForcing) -> (f64, usize) {
    let cell = DIAMETER / resolution as f64;
    let dt = viscous_number * cell * cell / KINEMATIC_VISCOSITY;
    let side = 4.0 * DIAMETER;
    // U of about 1 mm/s.
    let body_force = 2.25 * KINEMATIC_VISCOSITY;
    let mut system = fixed_sphere(resolution, layer);
    system.flow.body_force = [body_force, 0.0, 0.0];
    let window = (0.1 * side * side / KINEMATIC_VISCOSITY / dt).ceil() as usize;
    let mut history = vec![0.0; window];
    let mut steps = 0;
    let velocity = loop {
        system.step(dt).unwrap();
        let velocity = superficial_velocity(&system);
        let then = history[steps % window];
        history[steps % window] = velocity;
        steps += 1;
        if steps > window && (velocity - then).abs() < 1e-7 * velocity {
            break velocity;
        }
        assert!(
            steps < 400 * window.max(10),
            "no steady state: U = {velocity}"
        );
    };
    let viscosity = KINEMATIC_VISCOSITY * FLUID_DENSITY;
    let force = FLUID_DENSITY * body_force * side.powi(3);
    let radius = 0.5 * DIAMETER;
    let k = force / (6.0 * std::f64::consts::PI * viscosity * radius * velocity);
    (k, steps)
}

/// At a step of 3.2 viscous times of a cell (`ν Δt/Δx² = 3.2`, D/Δx = 8)
/// the renewal forcing (`r Δt = 4`, four passes a stage) holds a steady
/// drag 7 % below the array's, where eq. 7 loses a quarter of it: the
/// layer leaks between two forcings in both, the renewal relaxing it
/// faster. Measured (`stokes_array_sweep`, K against 1.5303): renewal
/// −3.3, −4.4, −7.1, −12.0, −20.3 % and eq. 7 −2.8, −12.9, −23.7,
/// −35.8, −49.4 % at ν Δt/Δx² = 0.8, 1.6, 3.2, 6.4, 12.8. In one pass
/// the renewal at 3.2 held −5.6 % for 2,000 steps, then crept and blew up
/// by step 4,000: the passes are what keeps it steady.
#[test]
fn the_renewal_forcing_holds_a_steady_stokes_drag_at_a_long_step_where_eq_7_leaks() {
    let (renewal, _) = drag_factor(8, 3.2, LayerForcing::Renewal);
    let (eq_7, _) = drag_factor(8, 3.2, LayerForcing::EveryStage);
    let deficit = |k: f64| 1.0 - k / ARRAY_DRAG_FACTOR;
    println!(
        "K: renewal {renewal:.4} ({:+.2} %), eq. 7 {eq_7:.4} ({:+.2} %)",
        -100.0 * deficit(renewal),
        -100.0 * deficit(eq_7)
    );
    assert!(
        deficit(renewal) > 0.0 && deficit(renewal) < 0.08,
        "{renewal}"
    );
    assert!(
        deficit(eq_7) > 2.0 * deficit(renewal),
        "{eq_7} against {renewal}"
    );
}

/// The sweep behind `docs/validation.md` (run with `--ignored`): each
/// forcing at each `RESOLUTIONS` (default 8) and `NUMBERS` (viscous
/// numbers, default 0.2 to 12.8), one CSV row each.
#[test]
#[ignore]
fn stokes_array_sweep() {
    let list = |name: &str, default: &str| -> Vec<f64> {
        std::env::var(name)
            .unwrap_or(default.into())
            .split(',')
            .map(|v| v.parse().unwrap())
            .collect()
    };
    println!("forcing,resolution,viscous_number,drag_factor,against_array,steps");
    for resolution in list("RESOLUTIONS", "8") {
        for number in list("NUMBERS", "0.2,0.4,0.8,1.6,3.2,6.4,12.8") {
            for (name, layer) in [
                ("renewal", LayerForcing::Renewal),
                ("eq7", LayerForcing::EveryStage),
            ] {
                let (k, steps) = drag_factor(resolution as usize, number, layer);
                println!(
                    "{name},{resolution},{number},{k:.5},{:+.4},{steps}",
                    k / ARRAY_DRAG_FACTOR - 1.0
                );
            }
        }
    }
}
