//! A grid stretched along its last axis (y in 2D, z in 3D), the wall-normal
//! axis of a channel or a bed: the tanh clustering, refusals of faces that
//! do not make a grid, second-order operators on smooth stretched faces,
//! an exact projection, flows between walls against their exact profiles,
//! and the gain of clustering cells where a boundary layer grows.
//!
//! Tolerances: 1e-12 for the projection's divergence (round-off), 1e-10
//! for profiles the discretisation reproduces exactly (linear Couette), an
//! observed order ≥ 1.9 for the rest (second-order scheme).

mod common;

use std::f64::consts::PI;

use common::{advance, max_velocity_error, order, scientific};
use grainflow_core::{Communicator, Dimension};
use grainflow_fluid::grid::Block;
use grainflow_fluid::operators::{
    add_laplacian, convective_tendency, divergence, subtract_gradient,
};
use grainflow_fluid::{
    clustered_faces, Boundaries, BoundaryCondition, Clustering, FlowSolver, FluidError, Grid,
    Location,
};

/// A 2D grid on [0, 1]² (periodic x) with y clustered by `factor`.
fn grid_2d(cells: [usize; 2], clustering: Clustering, factor: f64) -> Grid {
    let faces = clustered_faces(clustering, factor, cells[1], 0.0, 1.0);
    Grid::stretched(
        Dimension::Two,
        [cells[0], cells[1], 1],
        [0.0; 3],
        [1.0; 3],
        &faces,
    )
    .unwrap()
}

/// The tanh map clusters as its derivative says: the width of the first
/// cell at a clustered end is `L f'(0) / n` to first order in `1/n`, with
/// `f'(0) = 2β / sinh 2β` (both ends) and `β / tanh β · (1 − tanh² β)`,
/// i.e. `2β / sinh 2β` too (one end); the faces run from end to end and
/// increase; factor → 0 is uniform.
#[test]
fn tanh_clustering_puts_the_finest_cells_at_the_clustered_ends() {
    let (cells, beta, length): (usize, f64, f64) = (256, 2.0, 3.0);
    let slope = 2.0 * beta / (2.0 * beta).sinh();
    for clustering in [Clustering::BothEnds, Clustering::Lower, Clustering::Upper] {
        let faces = clustered_faces(clustering, beta, cells, 1.0, 1.0 + length);
        assert_eq!(faces[0], 1.0);
        assert_eq!(faces[cells], 1.0 + length);
        assert!(faces.windows(2).all(|pair| pair[1] > pair[0]));
        let first = faces[1] - faces[0];
        let last = faces[cells] - faces[cells - 1];
        let expected = length * slope / cells as f64;
        let clustered = match clustering {
            Clustering::BothEnds => vec![first, last],
            Clustering::Lower => vec![first],
            Clustering::Upper => vec![last],
        };
        for width in clustered {
            println!("{clustering:?}: end width {width:.6e}, L f'(0)/n = {expected:.6e}");
            assert!(
                (width / expected - 1.0).abs() <= 0.02,
                "{clustering:?}: {width}"
            );
        }
    }
    let nearly_uniform = clustered_faces(Clustering::Lower, 1e-6, 8, 0.0, 1.0);
    for (i, face) in nearly_uniform.iter().enumerate() {
        assert!((face - i as f64 / 8.0).abs() <= 1e-9);
    }
}

#[test]
fn faces_that_do_not_make_a_grid_are_refused() {
    let stretched =
        |faces: &[f64]| Grid::stretched(Dimension::Two, [4, 4, 1], [0.0; 3], [1.0; 3], faces);
    assert!(stretched(&[0.0, 0.1, 0.3, 0.6, 1.0]).is_ok());
    for faces in [
        vec![0.0, 0.1, 0.3, 1.0],
        vec![0.0, 0.1, 0.3, 0.6, 0.9],
        vec![0.1, 0.2, 0.3, 0.6, 1.0],
        vec![0.0, 0.3, 0.3, 0.6, 1.0],
        vec![0.0, 0.5, 0.3, 0.6, 1.0],
    ] {
        let result = stretched(&faces);
        assert!(
            matches!(result, Err(FluidError::Parameter(_))),
            "{faces:?} accepted"
        );
        println!("{faces:?}: {}", result.unwrap_err());
    }
    // A stretched axis has walls: periodic ends there are refused.
    let grid = grid_2d([4, 8], Clustering::BothEnds, 1.5);
    let result = FlowSolver::new(grid, Boundaries::periodic(), 1.0, Communicator::serial());
    assert!(matches!(result, Err(FluidError::Boundary(_))));
}

/// Every padded point of `field` at `location` set to `value(position)`,
/// ghosts included: the operators then see the exact function everywhere.
fn sampled(grid: &Grid, location: Location, value: impl Fn([f64; 3]) -> f64) -> Vec<f64> {
    let mut field = grid.zeros();
    let padded = grid.padded();
    let all = Block {
        start: [0; 3],
        end: padded,
    };
    grid.for_each(&all, |index, [i, j, k]| {
        field[index] = value(grid.position(location, i, j, k));
    });
    field
}

/// Largest `|field − exact|` over `block` at `location`.
fn max_error(
    grid: &Grid,
    field: &[f64],
    location: Location,
    block: &Block,
    exact: impl Fn([f64; 3]) -> f64,
) -> f64 {
    let mut error: f64 = 0.0;
    grid.for_each(block, |index, [i, j, k]| {
        let reference = exact(grid.position(location, i, j, k));
        error = error.max((field[index] - reference).abs());
    });
    error
}

/// Divergence, gradient, Laplacian (of a centre field and of a field on
/// the stretched faces) and both convective tendencies against the exact
/// derivatives of smooth fields, on y clustered at both ends (widths
/// varying fivefold) with 16, 32 and 64 cells: second order in the maximum
/// norm.
///
/// Two of them may be only first order in the cells next to a wall, as in any
/// cell-centred finite-volume scheme on a non-uniform grid: the Laplacian
/// of a centre field and the y flux of u take a difference of centre
/// values as the derivative at the face between them, which sits off the
/// face by a quarter of the change of width, `(w₂ − w₁)/4`. Inside, the
/// offsets of a cell's two faces nearly cancel; next to the wall the
/// wall's own flux has none (the ghost mirrors the first cell). A
/// truncation error one order lower on a layer one cell thick does not
/// lower the order of the solution: the flows below converge at second
/// order. Those wall cells are checked apart, for first order.
#[test]
fn operators_are_second_order_on_a_stretched_axis() {
    let k = 2.0 * PI;
    let u = move |x: [f64; 3]| (k * x[0]).sin() * (3.0 * x[1]).cos() + x[1] * x[1];
    let v = move |x: [f64; 3]| (k * x[0]).cos() * (2.0 * x[1]).sin() + 0.5;
    let p = move |x: [f64; 3]| (k * x[0]).cos() * x[1].exp();
    let du_dx = move |x: [f64; 3]| k * (k * x[0]).cos() * (3.0 * x[1]).cos();
    let du_dy = move |x: [f64; 3]| -3.0 * (k * x[0]).sin() * (3.0 * x[1]).sin() + 2.0 * x[1];
    let dv_dx = move |x: [f64; 3]| -k * (k * x[0]).sin() * (2.0 * x[1]).sin();
    let dv_dy = move |x: [f64; 3]| 2.0 * (k * x[0]).cos() * (2.0 * x[1]).cos();
    let d2v_dy2 = move |x: [f64; 3]| -4.0 * (k * x[0]).cos() * (2.0 * x[1]).sin();
    let names = [
        "divergence",
        "gradient (y)",
        "Laplacian at centres",
        "Laplacian on y faces",
        "convection of u",
        "convection of v",
        "Laplacian at centres, wall cells",
        "convection of u, wall cells",
    ];
    let first_order = 6;
    let mut errors = vec![Vec::new(); names.len()];
    for cells in [16, 32, 64] {
        let grid = grid_2d([cells, cells], Clustering::BothEnds, 1.5);
        let velocity = vec![
            sampled(&grid, Location::Face(0), u),
            sampled(&grid, Location::Face(1), v),
        ];
        let pressure = sampled(&grid, Location::Centre, p);
        let cells_block = grid.cell_block();
        // The y faces strictly inside the domain (the wall faces are given).
        let mut inner_y_faces = cells_block;
        inner_y_faces.end[1] -= 1;
        // Cells off the walls, and the first cell above the lower wall.
        let mut inner_cells = cells_block;
        inner_cells.start[1] += 1;
        inner_cells.end[1] -= 1;
        let mut wall_cells = cells_block;
        wall_cells.end[1] = wall_cells.start[1] + 1;

        let mut result = grid.zeros();
        divergence(&grid, &velocity, &mut result);
        errors[0].push(max_error(
            &grid,
            &result,
            Location::Centre,
            &cells_block,
            |x| du_dx(x) + dv_dy(x),
        ));

        // ∂p/∂y = p for this p.
        let mut gradient = grid.zeros();
        subtract_gradient(&grid, &pressure, 1, &inner_y_faces, -1.0, &mut gradient);
        errors[1].push(max_error(
            &grid,
            &gradient,
            Location::Face(1),
            &inner_y_faces,
            p,
        ));

        let mut laplacian = grid.zeros();
        add_laplacian(
            &grid,
            &pressure,
            Location::Centre,
            &cells_block,
            1.0,
            &mut laplacian,
        );
        let exact = |x: [f64; 3]| (1.0 - k * k) * p(x);
        errors[2].push(max_error(
            &grid,
            &laplacian,
            Location::Centre,
            &inner_cells,
            exact,
        ));
        errors[6].push(max_error(
            &grid,
            &laplacian,
            Location::Centre,
            &wall_cells,
            exact,
        ));

        let mut laplacian = grid.zeros();
        add_laplacian(
            &grid,
            &velocity[1],
            Location::Face(1),
            &inner_y_faces,
            1.0,
            &mut laplacian,
        );
        errors[3].push(max_error(
            &grid,
            &laplacian,
            Location::Face(1),
            &inner_y_faces,
            |x| -k * k * ((k * x[0]).cos() * (2.0 * x[1]).sin()) + d2v_dy2(x),
        ));

        // −∂(uu)/∂x − ∂(vu)/∂y at the x faces, −∂(uv)/∂x − ∂(vv)/∂y at the y faces.
        let mut tendency = grid.zeros();
        convective_tendency(&grid, &velocity, 0, &cells_block, &mut tendency);
        let exact = |x: [f64; 3]| -(2.0 * u(x) * du_dx(x) + dv_dy(x) * u(x) + v(x) * du_dy(x));
        errors[4].push(max_error(
            &grid,
            &tendency,
            Location::Face(0),
            &inner_cells,
            exact,
        ));
        errors[7].push(max_error(
            &grid,
            &tendency,
            Location::Face(0),
            &wall_cells,
            exact,
        ));
        let mut tendency = grid.zeros();
        convective_tendency(&grid, &velocity, 1, &inner_y_faces, &mut tendency);
        errors[5].push(max_error(
            &grid,
            &tendency,
            Location::Face(1),
            &inner_y_faces,
            |x| -(du_dx(x) * v(x) + u(x) * dv_dx(x) + 2.0 * v(x) * dv_dy(x)),
        ));
    }
    for (which, (name, errors)) in names.iter().zip(&errors).enumerate() {
        let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
        println!("{name}: errors {}, orders {orders:.3?}", scientific(errors));
        let expected = if which < first_order { 1.9 } else { 0.9 };
        assert!(orders[1] >= expected, "{name}: orders {orders:?}");
    }
}

/// A 3D velocity with walls on z (stretched towards the lower one) and x,
/// projected: `D u` vanishes to round-off, `max |D u| h_min / U ≤ 1e-12`,
/// since `D G` is the Laplacian the pressure solver inverts, row by row.
#[test]
fn projection_is_exact_on_a_stretched_grid() {
    let cells = [12, 10, 16];
    let faces = clustered_faces(Clustering::Lower, 2.5, cells[2], 0.0, 0.8);
    let grid = Grid::stretched(Dimension::Three, cells, [0.0; 3], [1.2, 1.0, 0.8], &faces).unwrap();
    let boundaries = Boundaries::periodic()
        .with(0, BoundaryCondition::FreeSlip, BoundaryCondition::FreeSlip)
        .with(
            2,
            BoundaryCondition::NoSlip,
            BoundaryCondition::MovingWall([0.3, 0.0, 0.0]),
        );
    let mut solver = FlowSolver::new(grid, boundaries, 1e-3, Communicator::serial()).unwrap();
    solver.set_velocity(|c, x| {
        let phase = 3.1 * x[0] + 1.7 * x[1] + 5.3 * x[2] + c as f64;
        phase.sin() + 0.4 * (7.0 * x[2]).cos()
    });
    let before = solver.max_divergence();
    solver.remove_divergence();
    let after = solver.max_divergence();
    let h = solver.grid.min_width(2);
    println!(
        "max |D u| h_min / U: {:.2e} before, {:.2e} after the projection",
        before * h,
        after * h
    );
    assert!(before * h > 1e-2);
    assert!(after * h <= 1e-12, "{after:e}");
    // And it stays so over steps.
    advance(&mut solver, 2e-3, 5, 1.0);
}

fn channel_2d(cells: usize, faces: &[f64], boundaries: Boundaries, viscosity: f64) -> FlowSolver {
    let grid = Grid::stretched(Dimension::Two, [4, cells, 1], [0.0; 3], [1.0; 3], faces).unwrap();
    FlowSolver::new(grid, boundaries, viscosity, Communicator::serial()).unwrap()
}

/// Couette flow (wall at rest below, sliding at U = 1.5 above) on faces
/// clustered at both walls: a line is exact for every operator and for
/// the quadratic wall ghost, so the profile is reproduced to round-off.
///
/// Crank–Nicolson damps a mode of `ν Δt λ ≫ 1` by a factor close to −1 per
/// stage, and the finest cells have the largest `λ`: the sudden start
/// excites them, so small steps come first (`ν Δt λ_max ≈ 90`), then large
/// ones for the slow modes.
#[test]
fn couette_is_exact_on_a_stretched_grid() {
    let speed = 1.5;
    let faces = clustered_faces(Clustering::BothEnds, 2.0, 16, 0.0, 1.0);
    let boundaries = Boundaries::periodic().with(
        1,
        BoundaryCondition::NoSlip,
        BoundaryCondition::MovingWall([speed, 0.0, 0.0]),
    );
    let mut solver = channel_2d(16, &faces, boundaries, 1.0);
    advance(&mut solver, 0.002, 200, speed);
    advance(&mut solver, 0.05, 300, speed);
    let error = max_velocity_error(&solver, |c, x| if c == 0 { speed * x[1] } else { 0.0 });
    println!(
        "Couette on a stretched grid: relative error {:.3e}",
        error / speed
    );
    assert!(error / speed <= 1e-10, "{error:e}");
}

/// Plane Poiseuille flow, `u = y (1 − y)` under `∂⟨p⟩/∂x / ρ = −2ν`, on
/// faces clustered at both walls: no longer exact (the centre Laplacian
/// of a parabola is exact only on a uniform grid), but second order.
#[test]
fn poiseuille_converges_at_second_order_on_a_stretched_grid() {
    let errors: Vec<f64> = [16, 32, 64]
        .iter()
        .map(|&cells| {
            let faces = clustered_faces(Clustering::BothEnds, 2.0, cells, 0.0, 1.0);
            let boundaries = Boundaries::periodic().with(
                1,
                BoundaryCondition::NoSlip,
                BoundaryCondition::NoSlip,
            );
            let mut solver = channel_2d(cells, &faces, boundaries, 1.0);
            solver.mean_pressure_gradient = [-2.0, 0.0, 0.0];
            advance(&mut solver, 0.05, 300, 0.25);
            max_velocity_error(
                &solver,
                |c, x| if c == 0 { x[1] * (1.0 - x[1]) } else { 0.0 },
            ) / 0.25
        })
        .collect();
    let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
    println!(
        "Poiseuille, stretched: relative errors {}, orders {orders:.3?}",
        scientific(&errors)
    );
    assert!(orders.iter().all(|&p| p >= 1.9), "orders {orders:?}");
}

/// The start-up of Couette flow: the lower wall set sliding at U at t = 0
/// under fluid at rest, the upper one at rest,
/// `u = U (1 − η) − (2U/π) Σ_n sin(nπη) e^{−n²π² ν t / H²} / n`, η = y/H.
/// At t = 0.01 H²/ν the layer is `√(νt) = H/10` thick: on faces clustered
/// at the lower wall the solution converges at second order, and it is
/// several times more accurate than on uniform faces of the same count.
#[test]
fn clustering_resolves_a_growing_boundary_layer() {
    let (speed, viscosity, end) = (1.0, 1.0, 0.01);
    let exact = |y: f64| {
        let mut sum = 0.0;
        for n in 1..=400 {
            let n = n as f64;
            sum += (n * PI * y).sin() * (-n * n * PI * PI * viscosity * end).exp() / n;
        }
        speed * (1.0 - y) - 2.0 * speed / PI * sum
    };
    let run = |cells: usize, faces: &[f64]| {
        let boundaries = Boundaries::periodic().with(
            1,
            BoundaryCondition::MovingWall([speed, 0.0, 0.0]),
            BoundaryCondition::NoSlip,
        );
        let mut solver = channel_2d(cells, faces, boundaries, viscosity);
        let steps = 400;
        advance(&mut solver, end / steps as f64, steps, speed);
        max_velocity_error(&solver, |c, x| if c == 0 { exact(x[1]) } else { 0.0 }) / speed
    };
    let sizes = [16, 32, 64];
    let clustered: Vec<f64> = sizes
        .iter()
        .map(|&n| run(n, &clustered_faces(Clustering::Lower, 2.0, n, 0.0, 1.0)))
        .collect();
    let uniform: Vec<f64> = sizes
        .iter()
        .map(|&n| run(n, &(0..=n).map(|i| i as f64 / n as f64).collect::<Vec<_>>()))
        .collect();
    let orders = [
        order(clustered[0], clustered[1]),
        order(clustered[1], clustered[2]),
    ];
    let gains: Vec<f64> = uniform.iter().zip(&clustered).map(|(u, c)| u / c).collect();
    println!(
        "start-up Couette at t = {end}: clustered errors {}, orders {orders:.3?}; uniform errors {}; gain {gains:.2?}",
        scientific(&clustered),
        scientific(&uniform)
    );
    assert!(orders[1] >= 1.9, "orders {orders:?}");
    assert!(gains.iter().all(|&g| g >= 2.0), "gains {gains:?}");
}
