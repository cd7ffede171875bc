//! Where the time step stops being stable, and the step's diagnostics.
//!
//! Convection is explicit (RK3) with central differences: a perturbation
//! carried by a uniform stream is amplified per step by
//! `|1 + z + z²/2 + z³/6|`, `z = i CFL sin(k h)`, which exceeds 1 only
//! beyond CFL √3. The tests run just below and above that limit, and check
//! that the solver refuses a step above it. The viscous term is implicit
//! (Crank–Nicolson) by default: its step is checked stable at any
//! diffusion number, walls included; the explicit viscous step is checked
//! against its amplification factor on both sides of its limit.

mod common;

use approx::assert_relative_eq;

use grainflow_core::{Communicator, Dimension};
use grainflow_fluid::{
    Boundaries, BoundaryCondition, FlowSolver, FluidError, Grid, ViscousScheme, CFL_LIMIT,
    EXPLICIT_VISCOUS_LIMIT,
};

/// A rough field with every mode present, of magnitude ≤ 1.
fn rough(component: usize, position: [f64; 3]) -> f64 {
    let [x, y, z] = position;
    let phase = 12.9898 * x + 78.233 * y + 37.719 * z + 3.1 * component as f64;
    (phase.sin() * 43758.5453).fract()
}

/// A unit stream along x with a divergence-free perturbation of 1e-6,
/// inviscid, doubly periodic.
fn perturbed_stream() -> FlowSolver {
    let grid = Grid::new(Dimension::Two, [32, 8, 1], [0.0; 3], [1.0, 0.25, 1.0]);
    let mut solver =
        FlowSolver::new(grid, Boundaries::periodic(), 0.0, Communicator::serial()).unwrap();
    solver.set_velocity(|c, x| if c == 0 { 1.0 } else { 0.0 } + 1e-6 * rough(c, x));
    solver.remove_divergence();
    solver
}

/// `Σ (u − U)² + v²` over the faces.
fn perturbation_energy(solver: &FlowSolver) -> f64 {
    let mut sum = 0.0;
    for component in 0..2 {
        let stream = if component == 0 { 1.0 } else { 0.0 };
        solver
            .grid
            .for_each(solver.velocity_unknowns(component), |index, _| {
                let perturbation = solver.velocity[component][index] - stream;
                sum += perturbation * perturbation;
            });
    }
    sum
}

/// Growth of the perturbation energy over `steps` steps at `cfl`.
fn growth(cfl: f64, steps: usize) -> f64 {
    let mut solver = perturbed_stream();
    solver.cfl_limit = f64::INFINITY;
    let dt = solver.time_step_for_cfl(cfl);
    let before = perturbation_energy(&solver);
    for _ in 0..steps {
        solver.step(dt).unwrap();
    }
    perturbation_energy(&solver) / before
}

#[test]
fn convection_is_stable_up_to_cfl_root_three() {
    let below = growth(0.98 * CFL_LIMIT, 200);
    let above = growth(1.1 * CFL_LIMIT, 100);
    println!("perturbation energy growth: CFL 0.98 √3 over 200 steps {below:.3e}, CFL 1.1 √3 over 100 steps {above:.3e}");
    assert!(below <= 1.0, "{below}");
    // At 1.1 √3 the worst mode (k h = π/2) gains a factor 1.23 in energy
    // a step; it starts with a small share of the perturbation.
    assert!(above >= 1e6, "{above}");
}

/// An inviscid Taylor–Green vortex, `u = sin x cos y`, `v = −cos x sin y`
/// on a doubly periodic `2π` square of 32², with a rough perturbation of
/// 1e-6. `|u| + |v| ≤ 1` everywhere while `max|u| + max|v| = 2`: the fast
/// flow along x and along y is in different places.
fn perturbed_vortex() -> FlowSolver {
    let side = std::f64::consts::TAU;
    let grid = Grid::new(Dimension::Two, [32, 32, 1], [0.0; 3], [side, side, 1.0]);
    let mut solver =
        FlowSolver::new(grid, Boundaries::periodic(), 0.0, Communicator::serial()).unwrap();
    solver.set_velocity(|c, [x, y, _]| {
        let vortex = if c == 0 {
            x.sin() * y.cos()
        } else {
            -x.cos() * y.sin()
        };
        vortex + 1e-6 * rough(c, [x, y, 0.0])
    });
    solver.remove_divergence();
    solver
}

/// Kinetic energy of the vortex after `steps` steps at the pointwise CFL
/// number `cfl`, over its initial energy.
fn vortex_energy_growth(cfl: f64, steps: usize) -> f64 {
    let mut solver = perturbed_vortex();
    solver.cfl_limit = f64::INFINITY;
    let dt = solver.time_step_for_cfl(cfl);
    let before = solver.kinetic_energy();
    for _ in 0..steps {
        solver.step(dt).unwrap();
    }
    solver.kinetic_energy() / before
}

#[test]
fn the_cfl_number_is_taken_cell_by_cell_and_holds_where_the_streams_are_apart() {
    let solver = perturbed_vortex();
    let h = std::f64::consts::TAU / 32.0;
    // Cell by cell |u| + |v| ≤ 1; the larger of each cell's two faces
    // adds at most the change over half a cell, sin(h/2) ≈ 0.1.
    let rate = solver.max_cfl(1.0) * h;
    println!("pointwise max (|u| + |v|) = {rate:.4}");
    assert!((1.0..=1.0 + (0.5 * h).sin()).contains(&rate), "{rate}");
    // Stable just below √3 in that number, where the sum of each
    // component's largest speed would read about 2 √3, and broken above.
    let largest = |c: usize| {
        let mut largest: f64 = 0.0;
        solver
            .grid
            .for_each(solver.velocity_unknowns(c), |index, _| {
                largest = largest.max(solver.velocity[c][index].abs())
            });
        largest
    };
    let summed = (largest(0) + largest(1)) / h * solver.time_step_for_cfl(0.95 * CFL_LIMIT);
    println!(
        "at pointwise 0.95 √3 the summed number is {:.3} √3",
        summed / CFL_LIMIT
    );
    assert!(summed > 1.7 * CFL_LIMIT, "{summed}");
    let below = vortex_energy_growth(0.95 * CFL_LIMIT, 400);
    let above = vortex_energy_growth(1.3 * CFL_LIMIT, 300);
    println!(
        "vortex energy: after 400 steps at CFL 0.95 √3 {below:.6}, after 300 at 1.3 √3 {above:.3e}"
    );
    // Central differences conserve energy; RK3 below its limit only
    // removes some. Above it the perturbation grows until the run
    // overflows (NaN counts as broken).
    assert!(below <= 1.0, "{below}");
    assert!(above.is_nan() || above >= 10.0, "{above}");
}

#[test]
fn a_step_beyond_the_limit_is_refused() {
    let mut solver = perturbed_stream();
    let dt = solver.time_step_for_cfl(1.01 * CFL_LIMIT);
    let before = solver.velocity.clone();
    match solver.step(dt) {
        Err(FluidError::Unstable { cfl, limit }) => {
            assert!((cfl - 1.01 * CFL_LIMIT).abs() < 1e-12);
            assert_eq!(limit, CFL_LIMIT);
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    assert_eq!(solver.velocity, before);
    assert_eq!(solver.time, 0.0);
    assert!(solver.step(0.99 * dt).is_ok());
}

/// A uniform stream is an exact steady solution: it stays, and the
/// diagnostics take their exact values.
#[test]
fn a_uniform_stream_is_kept_and_measured_exactly() {
    let grid = Grid::new(Dimension::Three, [6, 5, 4], [0.0; 3], [1.2, 1.0, 0.8]);
    let stream = [1.0, -2.0, 0.5];
    let mut solver =
        FlowSolver::new(grid, Boundaries::periodic(), 0.3, Communicator::serial()).unwrap();
    solver.set_velocity(|c, _| stream[c]);
    let dt = solver.time_step_for_cfl(1.0);
    assert_relative_eq!(dt, 1.0 / 17.5, max_relative = 1e-14);
    for _ in 0..3 {
        let report = solver.step(dt).unwrap();
        let energy = 0.5 * (1.0 + 4.0 + 0.25) * 0.96;
        assert_relative_eq!(report.kinetic_energy, energy, max_relative = 1e-14);
        assert_relative_eq!(report.max_cfl, 1.0, max_relative = 1e-14);
        assert!(report.max_divergence <= 1e-13, "{report:?}");
    }
    let error = common::max_velocity_error(&solver, |c, _| stream[c]);
    assert!(error <= 1e-14, "{error}");
}

/// Relative change of kinetic energy of a rough inviscid flow over the
/// time of ten steps at CFL 0.4, taken at CFL `cfl`.
fn inviscid_energy_change(boundaries: Boundaries, cfl: f64) -> f64 {
    let grid = Grid::new(Dimension::Three, [12, 10, 8], [0.0; 3], [1.2, 1.0, 0.8]);
    let mut solver = FlowSolver::new(grid, boundaries, 0.0, Communicator::serial()).unwrap();
    solver.set_velocity(rough);
    solver.remove_divergence();
    let dt = solver.time_step_for_cfl(cfl);
    let steps = (0.4 / cfl).round() as usize * 10;
    let before = solver.kinetic_energy();
    for _ in 0..steps {
        solver.step(dt).unwrap();
    }
    (solver.kinetic_energy() - before) / before
}

/// Convection in divergence form on the staggered grid moves kinetic
/// energy between modes but creates or destroys none when the velocity is
/// discretely divergence free, walls included (no flux crosses them): an
/// inviscid flow loses energy only through the time integration, at third
/// order in Δt for RK3. A wrong index in a flux would show as an O(1)
/// change.
#[test]
fn inviscid_convection_conserves_energy_up_to_the_time_error() {
    for (name, boundaries) in [
        ("periodic", Boundaries::periodic()),
        (
            "walls",
            Boundaries::periodic()
                .with(0, BoundaryCondition::FreeSlip, BoundaryCondition::FreeSlip)
                .with(2, BoundaryCondition::NoSlip, BoundaryCondition::FreeSlip),
        ),
    ] {
        let coarse = inviscid_energy_change(boundaries.clone(), 0.4);
        let fine = inviscid_energy_change(boundaries, 0.2);
        let observed = (coarse / fine).log2();
        println!("inviscid energy change ({name}): CFL 0.4 {coarse:.3e}, CFL 0.2 {fine:.3e}, order {observed:.2}");
        assert!(coarse < 0.0 && fine < 0.0, "RK3 can only dissipate");
        assert!(fine.abs() <= 1e-5, "{fine}");
        assert!(observed >= 2.8, "order {observed}");
    }
}

#[test]
fn a_negative_or_undefined_viscosity_is_refused() {
    for viscosity in [-1e-6, f64::NAN, f64::INFINITY] {
        let grid = Grid::new(Dimension::Two, [4, 4, 1], [0.0; 3], [1.0; 3]);
        let result = FlowSolver::new(
            grid,
            Boundaries::periodic(),
            viscosity,
            Communicator::serial(),
        );
        assert!(
            matches!(result, Err(FluidError::Parameter(_))),
            "{viscosity}"
        );
    }
}

/// Largest ratio of the kinetic energy after a step to the energy before
/// it, and the energy at the end relative to the start, of a rough flow
/// of amplitude 1e-8 (convection negligible, CFL below 1e-3) between
/// no-slip walls, stepped `steps` times at diffusion number
/// `ν Δt / h² = diffusion_number`.
fn viscous_energy_history(diffusion_number: f64, steps: usize) -> (f64, f64) {
    let grid = Grid::new(Dimension::Three, [12, 10, 16], [0.0; 3], [1.2, 1.0, 1.6]);
    let h = grid.spacing[2];
    let boundaries = Boundaries::periodic()
        .with(0, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip)
        .with(2, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
    let mut solver = FlowSolver::new(grid, boundaries, 1.0, Communicator::serial()).unwrap();
    solver.set_velocity(|c, x| 1e-8 * rough(c, x));
    solver.remove_divergence();
    let dt = diffusion_number * h * h;
    let initial = solver.kinetic_energy();
    let mut previous = initial;
    let mut largest_growth: f64 = 0.0;
    for _ in 0..steps {
        let energy = solver.step(dt).unwrap().kinetic_energy;
        largest_growth = largest_growth.max(energy / previous);
        previous = energy;
    }
    (largest_growth, previous / initial)
}

/// Crank–Nicolson keeps the viscous step stable at any diffusion number
/// with the quadratic wall ghost along the last axis (z here, the linear
/// one along x): the line operator it gives is not symmetric but has real
/// negative eigenvalues. The kinetic energy of a rough flow between walls
/// falls at every step, from diffusion numbers 0.1 to 1e5 (where the
/// stiffest modes are barely damped, |amplification| → 1).
#[test]
fn the_viscous_step_is_stable_at_any_diffusion_number_between_walls() {
    for diffusion_number in [0.1, 10.0, 1e3, 1e5] {
        let (growth, last) = viscous_energy_history(diffusion_number, 50);
        println!(
            "diffusion number {diffusion_number:.0e}: largest energy ratio over a step {growth:.6}, \
             after 50 steps {last:.3e}"
        );
        assert!(growth < 1.0, "energy grew by {growth} in a step");
        assert!(last < 1.0, "{last}");
    }
}

/// The explicit viscous step: the most damped divergence-free mode of a
/// periodic square, the checkerboard of stream function (−1)^{i+j} (u and
/// v alternate in x and y, so the Laplacian gives −8/h² exactly), is
/// multiplied per step by G(z) = Π_k (1 + α_k z), z = −ν Δt 8/h². Returns
/// the ratio of its energy after to before `steps` steps.
fn explicit_viscous_growth(viscous_number: f64, steps: usize) -> f64 {
    let n = 16;
    let h = 1.0 / n as f64;
    let grid = Grid::new(Dimension::Two, [n, n, 1], [0.0; 3], [1.0, 1.0, 1.0]);
    let viscosity = 1e-2;
    let mut solver = FlowSolver::new(
        grid,
        Boundaries::periodic(),
        viscosity,
        Communicator::serial(),
    )
    .unwrap();
    solver.viscous_scheme = ViscousScheme::Explicit;
    solver.viscous_limit = f64::INFINITY;
    // Amplitude 1e-8: convection, of order ε², stays far below round-off.
    solver.set_velocity(|component, x| {
        let (i, j) = ((x[0] / h).floor() as i64, (x[1] / h).floor() as i64);
        let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
        1e-8 * if component == 0 { sign } else { -sign }
    });
    let before = solver.kinetic_energy();
    let dt = viscous_number / (viscosity * 8.0 / (h * h));
    for _ in 0..steps {
        solver.step(dt).unwrap();
    }
    solver.kinetic_energy() / before
}

#[test]
fn the_explicit_viscous_step_breaks_where_its_amplification_leaves_the_unit_disc() {
    let amplification = |z: f64| (1.0 + 8.0 / 15.0 * z) * (1.0 + 2.0 / 15.0 * z) * (1.0 + z / 3.0);
    // The limit is the root of G(z) = −1.
    assert_relative_eq!(
        amplification(-EXPLICIT_VISCOUS_LIMIT),
        -1.0,
        epsilon = 1e-12
    );
    for fraction in [0.5, 0.9, 0.98, 1.02, 1.1] {
        let number = fraction * EXPLICIT_VISCOUS_LIMIT;
        let measured = explicit_viscous_growth(number, 20);
        let predicted = amplification(-number).powi(40);
        eprintln!(
            "explicit viscous number {fraction} of the limit: energy ratio {measured:.4e} after 20 steps (G^40 = {predicted:.4e})"
        );
        assert_relative_eq!(measured, predicted, max_relative = 1e-6);
        assert_eq!(measured > 1.0, fraction > 1.0);
    }
    // At the solver's own limit the step is refused instead.
    let grid = Grid::new(Dimension::Two, [8, 8, 1], [0.0; 3], [1.0; 3]);
    let mut solver =
        FlowSolver::new(grid, Boundaries::periodic(), 1.0, Communicator::serial()).unwrap();
    solver.viscous_scheme = ViscousScheme::Explicit;
    let dt = 1.01 * EXPLICIT_VISCOUS_LIMIT / solver.viscous_number(1.0);
    assert!(matches!(
        solver.step(dt),
        Err(FluidError::ViscousUnstable { .. })
    ));
    assert!(solver.step(0.99 * dt / 1.01).is_ok());
}

/// A 2D cavity of 16 × 16 cells on the unit square, at rest, closed by
/// walls at rest but for a lid sliding at `lid` m/s along x.
fn cavity(lid: f64) -> FlowSolver {
    let grid = Grid::new(Dimension::Two, [16, 16, 1], [0.0; 3], [1.0, 1.0, 1.0]);
    let boundaries = Boundaries::periodic()
        .with(0, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip)
        .with(
            1,
            BoundaryCondition::NoSlip,
            BoundaryCondition::MovingWall([lid, 0.0, 0.0]),
        );
    FlowSolver::new(grid, boundaries, 1e-2, Communicator::serial()).unwrap()
}

#[test]
fn the_adapted_step_from_rest_sees_the_sliding_lid() {
    // At rest the velocity alone would allow any step: the lid sets the
    // pace, CFL = U Δt / h with h = 1/16.
    let mut solver = cavity(1.0);
    assert_eq!(solver.max_cfl(1.0), 0.0);
    let dt = solver.time_step_for_cfl(0.8);
    assert_relative_eq!(dt, 0.8 / 16.0, max_relative = 1e-14);
    assert_relative_eq!(solver.cfl_bound(dt), 0.8, max_relative = 1e-14);
    // The fluid never outruns its lid: the step ends below the target.
    let report = solver.step(dt).unwrap();
    assert!(
        report.max_cfl <= 0.8,
        "CFL after the step {}",
        report.max_cfl
    );
    // A lid at rest leaves the cavity at rest and the step unbounded.
    assert_eq!(cavity(0.0).time_step_for_cfl(0.8), f64::INFINITY);
}

#[test]
fn the_adapted_step_from_rest_sees_a_body_force_only_where_pressure_cannot_balance_it() {
    let grid = Grid::new(Dimension::Two, [16, 16, 1], [0.0; 3], [1.0, 1.0, 1.0]);
    let channel =
        Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
    let mut solver = FlowSolver::new(grid, channel, 1e-2, Communicator::serial()).unwrap();
    // Along the periodic x a force f moves the fluid by f Δt within the
    // step: f Δt² / h = CFL. Across the walls it is a hydrostatic pressure.
    solver.body_force = [2.0, -9.81, 0.0];
    let dt = solver.time_step_for_cfl(0.5);
    assert_relative_eq!(dt, (0.5 / 16.0 / 2.0_f64).sqrt(), max_relative = 1e-14);
    solver.step(dt).unwrap();
    // From rest the channel's core gains f Δt (the implicit viscous solve
    // reaches it from the walls at 1e-8); the wall layer less.
    let reached = solver.max_cfl(dt);
    assert!(reached <= 0.5, "CFL after the step {reached}");
    assert_relative_eq!(reached, 0.5, max_relative = 1e-6);
    // A pressure gradient along x counts with the force.
    solver.mean_pressure_gradient = [2.0, 0.0, 0.0];
    assert_eq!(solver.unbalanced_acceleration(), [0.0; 3]);
    // A held bulk velocity sets its speed instead.
    solver.bulk_velocity = [Some(-0.25), None, None];
    assert_eq!(solver.boundary_speeds(), [0.25, 0.0, 0.0]);
    assert_eq!(solver.unbalanced_acceleration(), [0.0; 3]);
}
