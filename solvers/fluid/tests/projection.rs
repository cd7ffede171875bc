//! The projection leaves a velocity whose discrete divergence is
//! round-off, whatever the walls: after every projection
//! `max |D u| h / U ≤ 1e-12`.

mod common;

use common::advance;
use grainflow_core::{Communicator, Dimension};
use grainflow_fluid::{Boundaries, BoundaryCondition, FlowSolver, Grid};

/// A rough velocity field with every mode present, of magnitude ≤ 1.
fn rough(component: usize, position: [f64; 3]) -> f64 {
    let [x, y, z] = position;
    let phase = 12.9898 * x + 78.233 * y + 37.719 * z + 3.1 * component as f64;
    (phase.sin() * 43758.5453).fract()
}

fn check(grid: Grid, boundaries: Boundaries) {
    let spacing = grid.spacing[..grid.dim()]
        .iter()
        .cloned()
        .fold(f64::INFINITY, f64::min);
    let mut solver = FlowSolver::new(grid, boundaries, 0.01, Communicator::serial()).unwrap();
    solver.set_velocity(rough);
    let before = solver.max_divergence() * spacing;
    solver.remove_divergence();
    let after = solver.max_divergence() * spacing;
    println!("projection of a rough field: max |div u| h / U from {before:.2e} to {after:.2e}");
    assert!(
        before > 0.1,
        "the rough field should not be divergence free"
    );
    assert!(after <= 1e-12, "{after:e}");
    assert!(
        solver.pressure.iter().all(|&p| p == 0.0),
        "removing the divergence leaves the pressure alone"
    );
    // And after every stage of ten steps at a convective CFL about 0.5.
    advance(&mut solver, 0.1 * spacing, 10, 1.0);
}

#[test]
fn projection_with_walls_in_2d() {
    let grid = Grid::new(Dimension::Two, [24, 20, 1], [0.0; 3], [1.2, 1.0, 1.0]);
    let boundaries = Boundaries::periodic()
        .with(0, BoundaryCondition::FreeSlip, BoundaryCondition::FreeSlip)
        .with(
            1,
            BoundaryCondition::NoSlip,
            BoundaryCondition::MovingWall([1.0, 0.0, 0.0]),
        );
    check(grid, boundaries);
}

#[test]
fn projection_with_walls_in_3d() {
    let grid = Grid::new(Dimension::Three, [12, 10, 8], [0.0; 3], [1.2, 1.0, 0.8]);
    let boundaries = Boundaries::periodic()
        .with(0, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip)
        .with(2, BoundaryCondition::NoSlip, BoundaryCondition::FreeSlip);
    check(grid, boundaries);
}

#[test]
fn projection_periodic_3d() {
    let grid = Grid::new(Dimension::Three, [8, 12, 10], [0.0; 3], [1.0, 1.5, 1.25]);
    check(grid, Boundaries::periodic());
}
