//! Flows between walls with known answers: plane Poiseuille flow driven by
//! a mean pressure gradient, Couette flow under a sliding wall, an open
//! channel (no slip below, free slip above), shear modes decaying between
//! free-slip and no-slip walls, and a closed box under gravity.
//!
//! On the tangential velocity, half a cell off the wall, a no-slip wall is
//! imposed by a ghost value. Along the last axis (y in 2D, z in 3D) the
//! ghost is the quadratic extrapolation `u_ghost = (8 u_wall − 6 u_1 +
//! u_2) / 3`, exact for parabolas; the three-point Laplacian is exact for
//! parabolas too, so the steady Poiseuille, open-channel and Couette
//! profiles are reproduced to round-off (checked to 1e-10). Along an axis
//! solved by a transform the ghost stays the linear `u_ghost = 2 u_wall −
//! u_1`: for a parabola `u = K y (L − y)` the steady discrete profile is
//! then the exact one shifted by `K h² / 4` (the shift that satisfies the
//! linear ghost relation), checked to 1e-10 too.

mod common;

use std::f64::consts::PI;

use common::{advance, max_velocity_error, order, scientific};
use grainflow_core::{Communicator, Dimension};
use grainflow_fluid::boundary::fill_ghosts;
use grainflow_fluid::operators::add_laplacian;
use grainflow_fluid::{Boundaries, BoundaryCondition, DirectSolver, FlowSolver, Grid, Location};

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
/// `∂⟨p⟩/∂x / ρ = −2ν`: `u = y (1 − y)`, reproduced to round-off on 32
/// cells across and on the smallest line, 2 cells, where each wall's ghost
/// reads the cell next to the other wall.
#[test]
fn poiseuille_2d_between_no_slip_walls() {
    for cells in [2, 32] {
        let grid = Grid::new(Dimension::Two, [4, cells, 1], [0.0; 3], [1.0, 1.0, 1.0]);
        let boundaries =
            Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
        let mut solver = solver_with(grid, boundaries);
        solver.mean_pressure_gradient = [-2.0 * VISCOSITY, 0.0, 0.0];
        run_to_steady_state(&mut solver, 0.25);
        let error = max_velocity_error(
            &solver,
            |c, x| if c == 0 { x[1] * (1.0 - x[1]) } else { 0.0 },
        );
        println!(
            "Poiseuille 2D, {cells} cells: relative error to the parabola {:.3e}",
            error / 0.25
        );
        assert!(error / 0.25 <= ROUND_OFF, "{cells} cells: {error:e}");
    }
}

/// Poiseuille flow in 3D between no-slip walls normal to z, the
/// tridiagonal axis, driven along x and y at once (`∂⟨p⟩/∂x / ρ = −2ν`,
/// `∂⟨p⟩/∂y / ρ = −ν`): `u = z (1 − z)`, `v = z (1 − z) / 2`, both
/// tangential components reproduced to round-off.
#[test]
fn poiseuille_3d_between_no_slip_walls_normal_to_the_last_axis() {
    let grid = Grid::new(Dimension::Three, [3, 4, 24], [0.0; 3], [0.5, 0.5, 1.0]);
    let boundaries =
        Boundaries::periodic().with(2, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
    let mut solver = solver_with(grid, boundaries);
    solver.mean_pressure_gradient = [-2.0 * VISCOSITY, -VISCOSITY, 0.0];
    run_to_steady_state(&mut solver, 0.25);
    let error = max_velocity_error(&solver, |c, x| {
        let parabola = x[2] * (1.0 - x[2]);
        match c {
            0 => parabola,
            1 => 0.5 * parabola,
            _ => 0.0,
        }
    });
    println!(
        "Poiseuille 3D, walls normal to z: relative error to the parabola {:.3e}",
        error / 0.25
    );
    assert!(error / 0.25 <= ROUND_OFF, "{error:e}");
}

/// Poiseuille flow along z between no-slip walls normal to x (3D): the
/// walls are on an axis solved by a sine transform, which keeps the linear
/// ghost, so the steady profile is the parabola shifted by `h²/4`, and its
/// gap to the exact parabola, relative to the largest velocity, is `h²`.
#[test]
fn poiseuille_3d_between_no_slip_walls_across_a_transformed_axis() {
    let grid = Grid::new(Dimension::Three, [24, 3, 4], [0.0; 3], [1.0, 0.5, 0.5]);
    let h = grid.spacing[0];
    let boundaries =
        Boundaries::periodic().with(0, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
    let mut solver = solver_with(grid, boundaries);
    solver.mean_pressure_gradient = [0.0, 0.0, -2.0 * VISCOSITY];
    run_to_steady_state(&mut solver, 0.25);
    let parabola = |x: f64| x * (1.0 - x);
    let discrete_error = max_velocity_error(&solver, |c, x| {
        if c == 2 {
            parabola(x[0]) + h * h / 4.0
        } else {
            0.0
        }
    });
    let analytic_error =
        max_velocity_error(&solver, |c, x| if c == 2 { parabola(x[0]) } else { 0.0 });
    println!(
        "Poiseuille 3D, walls normal to x: relative error to the shifted parabola {:.3e}, gap to the parabola {:.6e} (h² = {:.6e})",
        discrete_error / 0.25,
        analytic_error / 0.25,
        h * h
    );
    assert!(discrete_error / 0.25 <= ROUND_OFF, "{discrete_error:e}");
    assert!(
        (analytic_error / 0.25 - h * h).abs() <= ROUND_OFF,
        "{analytic_error:e}"
    );
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

/// Couette flow across x, an axis solved by a transform: a wall at rest
/// facing one sliding along y. Both prescribe the velocity (the same kind
/// of end), so they may face each other on any axis: `v = V x`, to
/// round-off.
#[test]
fn couette_2d_across_a_transformed_axis() {
    let speed = 1.5;
    let grid = Grid::new(Dimension::Two, [16, 4, 1], [0.0; 3], [2.0, 1.0, 1.0]);
    let boundaries = Boundaries::periodic().with(
        0,
        BoundaryCondition::NoSlip,
        BoundaryCondition::MovingWall([0.0, speed, 0.0]),
    );
    let mut solver = solver_with(grid, boundaries);
    advance(&mut solver, 0.2, 300, speed);
    let error = max_velocity_error(
        &solver,
        |c, x| if c == 1 { speed * x[0] / 2.0 } else { 0.0 },
    );
    println!("Couette 2D across x: relative error {:.3e}", error / speed);
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
/// the wall and the quadratic no-slip ghost for any parabola: the profile
/// is reproduced to round-off.
#[test]
fn open_channel_with_a_free_slip_surface() {
    let grid = Grid::new(Dimension::Two, [4, 32, 1], [0.0; 3], [1.0, 1.0, 1.0]);
    let boundaries =
        Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::FreeSlip);
    let mut solver = solver_with(grid, boundaries);
    solver.mean_pressure_gradient = [-2.0 * VISCOSITY, 0.0, 0.0];
    run_to_steady_state(&mut solver, 1.0);
    let error = max_velocity_error(
        &solver,
        |c, x| if c == 0 { x[1] * (2.0 - x[1]) } else { 0.0 },
    );
    println!("open channel: relative error to the parabola {error:.3e}");
    assert!(error <= ROUND_OFF, "{error:e}");
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

/// The slowest shear mode `u(y)` between no-slip walls at y = 0 and 1 of
/// the discrete viscous operator the flow solver uses (the three-point
/// Laplacian with the quadratic wall ghost), and its eigenvalue `λ_h`, by
/// inverse iteration with the direct solver from `sin(π y)`. The operator
/// is not symmetric, so the mode is not a sine; it is checked to be an
/// eigenvector of the explicit Laplacian to round-off. The mode is a field
/// of `grid` with its ghosts filled, scaled to a largest value of 1.
fn slowest_no_slip_shear_mode(grid: &Grid) -> (Vec<f64>, f64) {
    let boundaries =
        Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
    let ends = boundaries.velocity_ends(grid, 0);
    let mut solver = DirectSolver::new(grid, &ends).unwrap();
    let block = *solver.unknowns();
    let mut mode = grid.zeros();
    grid.for_each(&block, |index, [i, j, k]| {
        mode[index] = (PI * grid.position(Location::Face(0), i, j, k)[1]).sin();
    });
    let largest = |field: &[f64]| {
        let mut largest: f64 = 0.0;
        grid.for_each(&block, |index, _| largest = largest.max(field[index].abs()));
        largest
    };
    // The second mode decays about 4 times faster: 60 iterations gain a
    // factor 4⁶⁰ on it.
    for _ in 0..60 {
        solver.solve_poisson(grid, &mut mode);
        let scale = largest(&mode);
        grid.for_each(&block, |index, _| mode[index] /= -scale);
    }
    fill_ghosts(grid, &mut mode, Location::Face(0), &ends);
    let mut laplacian = grid.zeros();
    add_laplacian(grid, &mode, Location::Face(0), &block, 1.0, &mut laplacian);
    let (mut numerator, mut denominator) = (0.0, 0.0);
    grid.for_each(&block, |index, _| {
        numerator += mode[index] * laplacian[index];
        denominator += mode[index] * mode[index];
    });
    let eigenvalue = numerator / denominator;
    let mut residual: f64 = 0.0;
    grid.for_each(&block, |index, _| {
        residual = residual.max((laplacian[index] - eigenvalue * mode[index]).abs());
    });
    assert!(
        residual / eigenvalue.abs() <= 1e-12,
        "not an eigenvector: residual {residual:e}, eigenvalue {eigenvalue}"
    );
    (mode, eigenvalue)
}

/// The slowest shear mode `u_h(y)` between no-slip walls, with eigenvalue
/// `λ_h` of the discrete operator: the semi-discrete solution
/// `u_h(y) e^{ν λ_h t}` has no space error, so the distance to it is the
/// time error alone, second order (Crank–Nicolson over the three
/// sub-steps).
#[test]
fn shear_mode_between_no_slip_walls_is_second_order_in_time() {
    let viscosity = 0.5;
    let end = 0.5;
    let cells = 32;
    let grid = Grid::new(Dimension::Two, [4, cells, 1], [0.0; 3], [0.25, 1.0, 1.0]);
    let (mode, eigenvalue) = slowest_no_slip_shear_mode(&grid);
    let decay = (viscosity * eigenvalue * end).exp();
    let run = |steps: usize| -> f64 {
        let boundaries =
            Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
        let mut solver =
            FlowSolver::new(grid.clone(), boundaries, viscosity, Communicator::serial()).unwrap();
        solver.velocity[0].copy_from_slice(&mode);
        solver.fill_velocity_ghosts();
        advance(&mut solver, end / steps as f64, steps, 1.0);
        let mut error: f64 = 0.0;
        for component in 0..2 {
            let expected = |index: usize| {
                if component == 0 {
                    mode[index] * decay
                } else {
                    0.0
                }
            };
            let field = &solver.velocity[component];
            grid.for_each(solver.velocity_unknowns(component), |index, _| {
                error = error.max((field[index] - expected(index)).abs());
            });
        }
        error
    };
    let errors: Vec<f64> = [5, 10, 20, 40].iter().map(|&steps| run(steps)).collect();
    let orders: Vec<f64> = errors
        .windows(2)
        .map(|pair| order(pair[0], pair[1]))
        .collect();
    println!(
        "no-slip shear mode, time: λ_h = {eigenvalue:.12} (−π² = {:.12}), errors {}, orders {orders:.3?}",
        -PI * PI,
        scientific(&errors)
    );
    assert!(orders.iter().all(|&p| p >= 1.9), "orders {orders:?}");
}

/// The shear mode `u = sin(π y) e^{−ν π² t}` between no-slip walls at
/// y = 0 and 1 converges to the continuous one at second order in space,
/// and so does the eigenvalue `λ_h` of the discrete operator to `−π²`.
/// The interior stencil gives the leading error (`π⁴ h² / 12` on `λ_h`);
/// the quadratic ghost, third order at the wall, adds an `O(h³)` term of
/// the opposite sign, so the observed order approaches 2 from below
/// (about 1.85 between 16 and 32 cells): the orders are measured from 32
/// cells on. The time step is small enough for the time error (about 2e-8
/// at 1000 steps, from the time-order test) not to mask the space error.
#[test]
fn shear_mode_between_no_slip_walls_is_second_order_in_space() {
    let viscosity = 0.5;
    let end = 0.5;
    let exact = |c: usize, x: [f64; 3], t: f64| {
        if c == 0 {
            (PI * x[1]).sin() * (-viscosity * PI * PI * t).exp()
        } else {
            0.0
        }
    };
    let mut errors = Vec::new();
    let mut eigenvalue_errors = Vec::new();
    for cells in [32, 64, 128] {
        let grid = Grid::new(Dimension::Two, [4, cells, 1], [0.0; 3], [0.25, 1.0, 1.0]);
        eigenvalue_errors.push((slowest_no_slip_shear_mode(&grid).1 + PI * PI).abs());
        let boundaries =
            Boundaries::periodic().with(1, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
        let mut solver =
            FlowSolver::new(grid, boundaries, viscosity, Communicator::serial()).unwrap();
        solver.set_velocity(|c, x| exact(c, x, 0.0));
        advance(&mut solver, end / 1000.0, 1000, 1.0);
        errors.push(max_velocity_error(&solver, |c, x| exact(c, x, end)));
    }
    let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
    let eigenvalue_orders = [
        order(eigenvalue_errors[0], eigenvalue_errors[1]),
        order(eigenvalue_errors[1], eigenvalue_errors[2]),
    ];
    println!(
        "no-slip shear mode, space: errors {}, orders {orders:.3?}; |λ_h + π²| {}, orders {eigenvalue_orders:.3?}",
        scientific(&errors),
        scientific(&eigenvalue_errors)
    );
    assert!(orders.iter().all(|&p| p >= 1.9), "orders {orders:?}");
    assert!(
        eigenvalue_orders.iter().all(|&p| p >= 1.9),
        "orders {eigenvalue_orders:?}"
    );
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

/// Flow through porous walls, the asymptotic suction profile: fluid blown
/// in through the lower wall (at rest) at V and sucked out through the
/// upper one (sliding at U) at the same V; the wall-normal velocity is V
/// everywhere and `ν u'' = V u'` gives
/// `u = U (e^{V y/ν} − 1) / (e^{V H/ν} − 1)`, a layer of thickness ν/V at
/// the suction wall (here H/5). The steady profile converges at second
/// order; cells clustered at the suction wall (tanh, β = 2) make it 2.5 to
/// 3.3 times more accurate at the same count.
#[test]
fn suction_profile_through_porous_walls() {
    let (speed, through, viscosity) = (1.0, 1.0, 0.2);
    let exact = |c: usize, x: [f64; 3]| match c {
        0 => {
            speed * ((through * x[1] / viscosity).exp() - 1.0) / ((through / viscosity).exp() - 1.0)
        }
        _ => through,
    };
    let run = |cells: usize, clustered: bool| {
        let faces: Vec<f64> = if clustered {
            grainflow_fluid::clustered_faces(
                grainflow_fluid::Clustering::Upper,
                2.0,
                cells,
                0.0,
                1.0,
            )
        } else {
            (0..=cells).map(|i| i as f64 / cells as f64).collect()
        };
        let grid = Grid::stretched(
            Dimension::Two,
            [4, cells, 1],
            [0.0; 3],
            [0.25, 1.0, 1.0],
            &faces,
        )
        .unwrap();
        let boundaries = Boundaries::periodic().with(
            1,
            BoundaryCondition::MovingWall([0.0, through, 0.0]),
            BoundaryCondition::MovingWall([speed, through, 0.0]),
        );
        let mut solver =
            FlowSolver::new(grid, boundaries, viscosity, Communicator::serial()).unwrap();
        solver.set_velocity(|c, _| if c == 1 { through } else { 0.0 });
        // Small steps while the start's grid-scale modes decay, then to
        // t = 12: the slowest mode decays at ν π²/H² + V²/4ν = 3.2 /s
        // (below 1e-15 by then); CFL V Δt / w_min = 0.43 on the finest
        // clustered cells.
        advance(&mut solver, 2e-4, 100, speed);
        advance(&mut solver, 1e-3, 12_000, speed);
        max_velocity_error(&solver, exact) / speed
    };
    let uniform: Vec<f64> = [16, 32, 64].iter().map(|&n| run(n, false)).collect();
    let clustered: Vec<f64> = [16, 32, 64].iter().map(|&n| run(n, true)).collect();
    let orders = [order(uniform[0], uniform[1]), order(uniform[1], uniform[2])];
    let clustered_orders = [
        order(clustered[0], clustered[1]),
        order(clustered[1], clustered[2]),
    ];
    let gains: Vec<f64> = uniform.iter().zip(&clustered).map(|(u, c)| u / c).collect();
    println!(
        "suction profile: uniform errors {}, orders {orders:.3?}; clustered errors {}, orders {clustered_orders:.3?}; gains {gains:.2?}",
        scientific(&uniform),
        scientific(&clustered)
    );
    assert!(orders[1] >= 1.9, "orders {orders:?}");
    assert!(clustered_orders[1] >= 1.9, "orders {clustered_orders:?}");
    assert!(gains.iter().all(|&g| g >= 2.0), "gains {gains:?}");
}

/// Pressure-driven flow in a square duct, no-slip walls on y (a
/// transformed axis, linear wall ghost) and on z (the line axis, quadratic
/// ghost) at once: against the series solution of `ν ∇²u = ∂⟨p⟩/∂x / ρ`
/// on [0, a]², `u = (4 K a²/π³) Σ_{n odd} n⁻³ [1 − cosh(nπ(z − a/2)/a) /
/// cosh(nπ/2)] sin(nπ y/a)`, `K = −∂⟨p⟩/∂x / (ρ ν)`: second order.
#[test]
fn duct_flow_with_walls_on_two_axes() {
    let gradient = -1.0;
    let exact = |c: usize, x: [f64; 3]| {
        if c != 0 {
            return 0.0;
        }
        let k = -gradient / VISCOSITY;
        let mut sum = 0.0;
        for n in (1..200).step_by(2) {
            let n = n as f64;
            let ratio = (n * PI * (x[2] - 0.5)).cosh() / (n * PI / 2.0).cosh();
            sum += (1.0 - ratio) * (n * PI * x[1]).sin() / n.powi(3);
        }
        4.0 * k / PI.powi(3) * sum
    };
    let errors: Vec<f64> = [8, 16, 32]
        .iter()
        .map(|&cells| {
            let grid = Grid::new(
                Dimension::Three,
                [4, cells, cells],
                [0.0; 3],
                [0.5, 1.0, 1.0],
            );
            let boundaries = Boundaries::periodic()
                .with(1, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip)
                .with(2, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip);
            let mut solver = solver_with(grid, boundaries);
            solver.mean_pressure_gradient = [gradient, 0.0, 0.0];
            advance(&mut solver, 0.01, 300, 0.07);
            max_velocity_error(&solver, exact) / 0.0737
        })
        .collect();
    let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
    println!(
        "square duct: relative errors {}, orders {orders:.3?}",
        scientific(&errors)
    );
    assert!(orders[1] >= 1.9, "orders {orders:?}");
}

/// An inflow through the lower wall (at rest, blowing in at V) and an open
/// outflow at the top, under a streamwise pressure gradient: the fluid
/// leaves at V (the projection sets the flux out), and the steady profile
/// solves `u'' − (V/ν) u' = K` with `u(0) = 0` and `u'(H) = 0` (the outflow
/// passes the profile on): `u = (K/a²)(e^{a(y − H)} − e^{−aH}) − K y/a`,
/// `a = V/ν`. Second order; the outflow face's velocity is an unknown of
/// the solves.
#[test]
fn inflow_through_a_wall_and_an_open_outflow() {
    let (through, viscosity, gradient) = (1.0, 0.2, -1.0);
    let a = through / viscosity;
    let k = gradient / viscosity;
    let exact = move |c: usize, x: [f64; 3]| match c {
        0 => (k / (a * a)) * ((a * (x[1] - 1.0)).exp() - (-a).exp()) - k * x[1] / a,
        _ => through,
    };
    let scale = exact(0, [0.0, 1.0, 0.0]).abs();
    let errors: Vec<f64> = [16, 32, 64]
        .iter()
        .map(|&cells| {
            let grid = Grid::new(Dimension::Two, [4, cells, 1], [0.0; 3], [0.25, 1.0, 1.0]);
            let boundaries = Boundaries::periodic().with(
                1,
                BoundaryCondition::MovingWall([0.0, through, 0.0]),
                BoundaryCondition::Outflow,
            );
            let mut solver =
                FlowSolver::new(grid, boundaries, viscosity, Communicator::serial()).unwrap();
            solver.mean_pressure_gradient = [gradient, 0.0, 0.0];
            advance(&mut solver, 2e-4, 100, through);
            advance(&mut solver, 2e-3, 6000, through);
            // The flux out equals the flux in.
            let grid = &solver.grid;
            let outflow_face = grid.index(2, cells, 0);
            assert!(
                (solver.velocity[1][outflow_face] - through).abs() <= 1e-10,
                "outflow velocity {}",
                solver.velocity[1][outflow_face]
            );
            max_velocity_error(&solver, exact) / scale
        })
        .collect();
    let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
    println!(
        "inflow and outflow: relative errors {}, orders {orders:.3?}",
        scientific(&errors)
    );
    assert!(orders[1] >= 1.9, "orders {orders:?}");
}
