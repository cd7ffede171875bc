//! Helpers shared by the flow tests.

// Each test file uses its own subset of the helpers.
#![allow(dead_code)]

use grainflow_fluid::{FlowSolver, Location};

/// Largest `|u_c − exact(c, x)|` over every velocity unknown.
pub fn max_velocity_error(solver: &FlowSolver, exact: impl Fn(usize, [f64; 3]) -> f64) -> f64 {
    let grid = &solver.grid;
    let mut error: f64 = 0.0;
    for component in 0..grid.dim() {
        let field = &solver.velocity[component];
        grid.for_each(solver.velocity_unknowns(component), |index, [i, j, k]| {
            let position = grid.position(Location::Face(component), i, j, k);
            error = error.max((field[index] - exact(component, position)).abs());
        });
    }
    error
}

/// Largest difference of the velocity unknowns of two solvers on the same grid.
pub fn max_velocity_difference(solver: &FlowSolver, reference: &FlowSolver) -> f64 {
    let grid = &solver.grid;
    let mut difference: f64 = 0.0;
    for component in 0..grid.dim() {
        grid.for_each(solver.velocity_unknowns(component), |index, _| {
            let gap = solver.velocity[component][index] - reference.velocity[component][index];
            difference = difference.max(gap.abs());
        });
    }
    difference
}

/// Observed order of convergence between two errors at a refinement ratio of 2.
pub fn order(coarse: f64, fine: f64) -> f64 {
    (coarse / fine).log2()
}

/// Advances `steps` steps of `dt`, asserting after each that the largest
/// divergence after any projection, made dimensionless with the finest
/// spacing and `velocity_scale`, is at most 1e-12.
pub fn advance(solver: &mut FlowSolver, dt: f64, steps: usize, velocity_scale: f64) -> f64 {
    let grid = &solver.grid;
    let spacing = (0..grid.dim())
        .map(|axis| grid.min_width(axis))
        .fold(f64::INFINITY, f64::min);
    let mut worst: f64 = 0.0;
    for _ in 0..steps {
        let report = solver.step(dt).unwrap();
        let divergence = report.max_divergence * spacing / velocity_scale;
        assert!(
            divergence <= 1e-12,
            "max |div u| h / U = {divergence:e} at t = {}",
            solver.time
        );
        assert!(report.kinetic_energy.is_finite());
        worst = worst.max(divergence);
    }
    println!("{steps} steps of {dt:.3e}: max |div u| h / U = {worst:.2e}");
    worst
}

/// Largest `|p − exact(x)|` over the cells, both taken with zero mean.
pub fn max_pressure_error(solver: &FlowSolver, exact: impl Fn([f64; 3]) -> f64) -> f64 {
    let grid = &solver.grid;
    let cells = grid.cell_block();
    let mut difference = Vec::new();
    grid.for_each(&cells, |index, [i, j, k]| {
        difference.push(solver.pressure[index] - exact(grid.position(Location::Centre, i, j, k)));
    });
    let mean = difference.iter().sum::<f64>() / difference.len() as f64;
    difference
        .iter()
        .map(|d| (d - mean).abs())
        .fold(0.0, f64::max)
}

/// Errors printed in scientific notation.
pub fn scientific(values: &[f64]) -> String {
    let parts: Vec<String> = values.iter().map(|v| format!("{v:.3e}")).collect();
    format!("[{}]", parts.join(", "))
}
