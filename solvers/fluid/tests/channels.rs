//! Flows between walls with known answers: plane Poiseuille flow driven by
//! a mean pressure gradient, Couette flow under a sliding wall, an open
//! channel (no slip below, free slip above) and a shear mode decaying
//! between two free-slip walls.
//!
//! On the tangential velocity, half a cell off the wall, a no-slip wall is
//! imposed by the ghost `u_ghost = −u_first` (linear interpolation to zero
//! at the wall). Central differences are exact for a line, so Couette flow
//! is reproduced to round-off. For a parabola the interior stencil is exact
//! but the linear ghost is not: the discrete steady profile is the exact
//! parabola shifted by `K h² / 4` (with `u = K y (L − y)`, obtained by
//! requiring the ghost relation of the shifted parabola), which is the
//! answer checked to 1e-10, and which is the exact parabola to second order.

mod common;

use std::f64::consts::PI;

use common::{advance, max_velocity_error, order, scientific};
use grainflow_core::{Communicator, Dimension};
use grainflow_fluid::{Boundaries, BoundaryCondition, FlowSolver, Grid};

const ROUND_OFF: f64 = 1e-10;
const VISCOSITY: f64 = 1.0;

/// Runs to a steady state: the slowest mode of the walls decays as
/// `e^{−ν (π/2)² t}` at worst (one free-slip wall), below 1e-13 by t = 15.
fn run_to_steady_state(solver: &mut FlowSolver, velocity_scale: f64) {
    advance(solver, 0.05, 300, velocity_scale);
}

fn solver_with(grid: Grid, boundaries: Boundaries) -> FlowSolver {
    FlowSolver::new(grid, boundaries, VISCOSITY, Communicator::serial()).unwrap()
}

/// Plane Poiseuille flow between no-slip walls at y = 0 and 1 driven by
/// `∂⟨p⟩/∂x / ρ = −2ν`: `u = y (1 − y)`.
#[test]
fn poiseuille_2d_between_no_slip_walls() {
    let cells = 32;
    let grid = Grid::new(Dimension::Two, [4, cells, 1], [0.0; 3], [1.0, 1.0, 1.0]);
    let h = grid.spacing[1];
    let boundaries =
        Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
    let mut solver = solver_with(grid, boundaries);
    solver.mean_pressure_gradient = [-2.0 * VISCOSITY, 0.0, 0.0];
    run_to_steady_state(&mut solver, 0.25);
    let parabola = |y: f64| y * (1.0 - y);
    let discrete_error = max_velocity_error(&solver, |c, x| {
        if c == 0 {
            parabola(x[1]) + h * h / 4.0
        } else {
            0.0
        }
    });
    let analytic_error =
        max_velocity_error(&solver, |c, x| if c == 0 { parabola(x[1]) } else { 0.0 });
    println!(
        "Poiseuille 2D: relative error to the discrete solution {:.3e}, to the parabola {:.3e} (h² = {:.3e})",
        discrete_error / 0.25,
        analytic_error / 0.25,
        h * h
    );
    assert!(discrete_error / 0.25 <= ROUND_OFF);
    assert!((analytic_error / 0.25 - h * h).abs() <= ROUND_OFF);
}

/// Poiseuille flow along z between no-slip walls normal to x (3D): the
/// walls are now on an axis solved by a sine transform.
#[test]
fn poiseuille_3d_between_no_slip_walls_across_a_transformed_axis() {
    let grid = Grid::new(Dimension::Three, [24, 3, 4], [0.0; 3], [1.0, 0.5, 0.5]);
    let h = grid.spacing[0];
    let boundaries =
        Boundaries::periodic().with(0, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
    let mut solver = solver_with(grid, boundaries);
    solver.mean_pressure_gradient = [0.0, 0.0, -2.0 * VISCOSITY];
    run_to_steady_state(&mut solver, 0.25);
    let error = max_velocity_error(&solver, |c, x| {
        if c == 2 {
            x[0] * (1.0 - x[0]) + h * h / 4.0
        } else {
            0.0
        }
    });
    println!(
        "Poiseuille 3D: relative error to the discrete solution {:.3e}",
        error / 0.25
    );
    assert!(error / 0.25 <= ROUND_OFF);
}

/// Couette flow: wall at rest at y = 0, wall sliding at U = 1.5 at y = 2,
/// `u = U y / 2`, reproduced to round-off.
#[test]
fn couette_2d_under_a_moving_wall() {
    let speed = 1.5;
    let grid = Grid::new(Dimension::Two, [4, 16, 1], [0.0; 3], [1.0, 2.0, 1.0]);
    let boundaries = Boundaries::periodic().with(
        1,
        BoundaryCondition::NoSlip,
        BoundaryCondition::MovingWall([speed, 0.0, 0.0]),
    );
    let mut solver = solver_with(grid, boundaries);
    // Diffusion time L²/ν = 4: run to t = 60.
    advance(&mut solver, 0.2, 300, speed);
    let error = max_velocity_error(
        &solver,
        |c, x| if c == 0 { speed * x[1] / 2.0 } else { 0.0 },
    );
    println!("Couette 2D: relative error {:.3e}", error / speed);
    assert!(error / speed <= ROUND_OFF);
}

/// Couette flow in 3D between walls normal to y (a transformed axis), the
/// upper one sliding along z and the lower one along x: `w = W y`,
/// `u = U (1 − y)`.
#[test]
fn couette_3d_with_walls_sliding_in_different_directions() {
    let grid = Grid::new(Dimension::Three, [3, 16, 4], [0.0; 3], [0.5, 1.0, 0.5]);
    let boundaries = Boundaries::periodic().with(
        1,
        BoundaryCondition::MovingWall([0.5, 0.0, 0.0]),
        BoundaryCondition::MovingWall([0.0, 0.0, 1.0]),
    );
    let mut solver = solver_with(grid, boundaries);
    run_to_steady_state(&mut solver, 1.0);
    let error = max_velocity_error(&solver, |c, x| match c {
        0 => 0.5 * (1.0 - x[1]),
        1 => 0.0,
        _ => x[1],
    });
    println!("Couette 3D: relative error {error:.3e}");
    assert!(error <= ROUND_OFF);
}

/// Open channel: no slip at y = 0, free slip at y = 1, driven by
/// `∂⟨p⟩/∂x / ρ = −2ν`: `u = y (2 − y)`, zero shear at the free-slip wall.
/// The free-slip ghost (mirror) is exact for a parabola symmetric about
/// the wall, so only the no-slip shift `h²/4` remains.
#[test]
fn open_channel_with_a_free_slip_surface() {
    let grid = Grid::new(Dimension::Two, [4, 32, 1], [0.0; 3], [1.0, 1.0, 1.0]);
    let h = grid.spacing[1];
    let boundaries =
        Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::FreeSlip);
    let mut solver = solver_with(grid, boundaries);
    solver.mean_pressure_gradient = [-2.0 * VISCOSITY, 0.0, 0.0];
    run_to_steady_state(&mut solver, 1.0);
    let error = max_velocity_error(&solver, |c, x| {
        if c == 0 {
            x[1] * (2.0 - x[1]) + h * h / 4.0
        } else {
            0.0
        }
    });
    println!("open channel: relative error to the discrete solution {error:.3e}");
    assert!(error <= ROUND_OFF);
}

/// A shear mode `v = cos(π x) e^{−ν π² t}` between free-slip walls at
/// x = 0 and 1 (zero shear, no penetration) decays like the continuous
/// mode to second order in space.
#[test]
fn shear_mode_between_free_slip_walls_decays_at_second_order() {
    let viscosity = 0.1;
    let end = 1.0;
    let exact = |c: usize, x: [f64; 3], t: f64| {
        if c == 1 {
            (PI * x[0]).cos() * (-viscosity * PI * PI * t).exp()
        } else {
            0.0
        }
    };
    let errors: Vec<f64> = [16, 32, 64]
        .iter()
        .map(|&cells| {
            let grid = Grid::new(Dimension::Two, [cells, 4, 1], [0.0; 3], [1.0, 0.25, 1.0]);
            let boundaries = Boundaries::periodic().with(
                0,
                BoundaryCondition::FreeSlip,
                BoundaryCondition::FreeSlip,
            );
            let mut solver =
                FlowSolver::new(grid, boundaries, viscosity, Communicator::serial()).unwrap();
            solver.set_velocity(|c, x| exact(c, x, 0.0));
            advance(&mut solver, end / 500.0, 500, 1.0);
            max_velocity_error(&solver, |c, x| exact(c, x, end))
        })
        .collect();
    let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
    println!(
        "free-slip shear mode: errors {}, orders {orders:.3?}",
        scientific(&errors)
    );
    assert!(orders.iter().all(|&p| p >= 1.9), "orders {orders:?}");
}

/// A shear mode `u = sin(π y)` between no-slip walls at y = 0 and 1 is an
/// exact eigenvector of the discrete Laplacian with the ghost condition,
/// with eigenvalue `λ_h = −(2 − 2 cos π h) / h²`: the semi-discrete
/// solution `sin(π y) e^{ν λ_h t}` has no space error, so the distance to
/// it is the time error alone, second order (Crank–Nicolson over the
/// three sub-steps); and `λ_h` is `−π²` to second order in `h`.
#[test]
fn shear_mode_between_no_slip_walls_is_second_order_in_time() {
    let viscosity = 0.5;
    let end = 0.5;
    let cells = 32;
    let run = |steps: usize| -> f64 {
        let grid = Grid::new(Dimension::Two, [4, cells, 1], [0.0; 3], [0.25, 1.0, 1.0]);
        let h = grid.spacing[1];
        let rate = -(2.0 - 2.0 * (PI * h).cos()) / (h * h);
        let boundaries =
            Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
        let mut solver =
            FlowSolver::new(grid, boundaries, viscosity, Communicator::serial()).unwrap();
        solver.set_velocity(|c, x| if c == 0 { (PI * x[1]).sin() } else { 0.0 });
        advance(&mut solver, end / steps as f64, steps, 1.0);
        let decay = (viscosity * rate * end).exp();
        max_velocity_error(&solver, |c, x| {
            if c == 0 {
                (PI * x[1]).sin() * decay
            } else {
                0.0
            }
        })
    };
    let errors: Vec<f64> = [5, 10, 20, 40].iter().map(|&steps| run(steps)).collect();
    let orders: Vec<f64> = errors
        .windows(2)
        .map(|pair| order(pair[0], pair[1]))
        .collect();
    println!(
        "no-slip shear mode, time: errors {}, orders {orders:.3?}",
        scientific(&errors)
    );
    assert!(orders.iter().all(|&p| p >= 1.9), "orders {orders:?}");
}

/// Gravity normal to the walls of a closed box is balanced by a
/// hydrostatic pressure, `∇p/ρ = g`: the fluid stays at rest and the
/// pressure is hydrostatic, both to round-off (the Helmholtz solve bends
/// the predicted velocity near the walls; the `− ν α Δt/2 L φ` pressure
/// term undoes exactly that).
/// Along the last axis (2D, walls normal to y) and across a transformed
/// axis (3D, walls normal to x).
#[test]
fn hydrostatic_balance_under_gravity_normal_to_walls() {
    let gravity = 9.81;
    for (grid, axis) in [
        (
            Grid::new(Dimension::Two, [8, 16, 1], [0.0; 3], [1.0, 2.0, 1.0]),
            1,
        ),
        (
            Grid::new(Dimension::Three, [16, 4, 6], [0.0; 3], [2.0, 0.5, 0.75]),
            0,
        ),
    ] {
        let h = grid.spacing[axis];
        let dim = grid.dim();
        let boundaries =
            Boundaries::periodic().with(axis, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
        let mut solver = FlowSolver::new(grid, boundaries, 1e-3, Communicator::serial()).unwrap();
        solver.body_force[axis] = -gravity;
        let dt = 0.01;
        for _ in 0..20 {
            solver.step(dt).unwrap();
        }
        let speed = max_velocity_error(&solver, |_, _| 0.0);
        // The pressure gradient between neighbouring cells along the axis.
        let grid = &solver.grid;
        let stride = grid.stride(axis);
        let mut block = grid.cell_block();
        block.end[axis] -= 1;
        let mut gradient_error: f64 = 0.0;
        grid.for_each(&block, |index, _| {
            let gradient = (solver.pressure[index + stride] - solver.pressure[index]) / h;
            gradient_error = gradient_error.max((gradient + gravity).abs());
        });
        println!(
            "hydrostatic {dim}D: max |u| / (g dt) {:.2e}, max |dp/dx − g| / g {:.2e}",
            speed / (gravity * dt),
            gradient_error / gravity
        );
        assert!(speed / (gravity * dt) <= 1e-12, "{speed}");
        assert!(gradient_error / gravity <= 1e-12, "{gradient_error}");
    }
}
