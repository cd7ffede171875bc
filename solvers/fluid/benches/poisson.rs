//! The direct pressure solve against a generic one on the same discrete
//! system: the Poisson equation `L φ = r` of a projection (the staggered
//! grid's 7-point Laplacian, zero-gradient walls), solved by
//! [`DirectSolver`] and by the conjugate gradient method with a Jacobi
//! preconditioner (matrix-free, the same `L`, to a relative residual of
//! 1e-10 from a zero first guess), the generic iterative solver of
//! general-purpose codes. Grids: a triply periodic 64³ box and a channel
//! 128×64×64 (periodic x and y, walls normal to z). Prints the median over
//! repeats of the time per solve, the CG iterations, and the errors of
//! both against a manufactured solution.
//!
//! usage: cargo bench -p grainflow-fluid --bench poisson [--features fftw]

use std::time::Instant;

use grainflow_core::Dimension;
use grainflow_fluid::boundary::{fill_ghosts, EndKind, FieldEnds};
use grainflow_fluid::operators::add_laplacian;
use grainflow_fluid::{Boundaries, BoundaryCondition, DirectSolver, Grid, Location};

/// A deterministic field with every mode present.
fn pseudo_random(seed: usize) -> f64 {
    let x = ((seed as u64)
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407)
        >> 33) as f64;
    x / (1u64 << 31) as f64 - 0.5
}

/// `out = L x` on the cells (ghosts of `x` filled from `ends`).
fn apply(grid: &Grid, ends: &FieldEnds, x: &mut [f64], out: &mut [f64]) {
    fill_ghosts(grid, x, Location::Centre, ends);
    let cells = grid.cell_block();
    grid.for_each(&cells, |index, _| out[index] = 0.0);
    add_laplacian(grid, x, Location::Centre, &cells, 1.0, out);
}

/// `Σ a b` over the cells.
fn dot(grid: &Grid, a: &[f64], b: &[f64]) -> f64 {
    grid.par_sum(&grid.cell_block(), |index, _| a[index] * b[index])
}

/// Removes the mean over the cells (the null space of the singular system).
fn remove_mean(grid: &Grid, x: &mut [f64]) {
    let cells = grid.cell_block();
    let count = grid.cells.iter().product::<usize>() as f64;
    let mean = grid.par_sum(&cells, |index, _| x[index]) / count;
    grid.par_update(&cells, x, |_, value| value - mean);
}

/// Jacobi-preconditioned conjugate gradient for `−L x = −r` (symmetric
/// positive semi-definite on zero-mean fields); returns the iterations.
fn conjugate_gradient(grid: &Grid, ends: &FieldEnds, rhs: &[f64], x: &mut [f64]) -> usize {
    let cells = grid.cell_block();
    // The diagonal of −L: Σ_a 2/h_a², less 1/h_a² next to a wall along a
    // (its ghost mirrors the cell).
    let mut diagonal = grid.zeros();
    let walls = [0, 1, 2].map(|a| a < grid.dim() && ends[a][0].kind != EndKind::Periodic);
    grid.for_each(&cells, |index, point| {
        let mut sum = 0.0;
        for a in 0..grid.dim() {
            let h2 = grid.spacing[a] * grid.spacing[a];
            let at_wall = walls[a] && (point[a] == 1 || point[a] == grid.cells[a]);
            sum += if at_wall { 1.0 / h2 } else { 2.0 / h2 };
        }
        diagonal[index] = sum;
    });
    x.iter_mut().for_each(|v| *v = 0.0);
    let mut residual = grid.zeros();
    grid.for_each(&cells, |index, _| residual[index] = -rhs[index]);
    remove_mean(grid, &mut residual);
    let norm_rhs = dot(grid, &residual, &residual).sqrt();
    let mut preconditioned = grid.zeros();
    let mut direction = grid.zeros();
    let mut product = grid.zeros();
    grid.for_each(&cells, |index, _| {
        preconditioned[index] = residual[index] / diagonal[index];
        direction[index] = preconditioned[index];
    });
    let mut rho = dot(grid, &residual, &preconditioned);
    for iteration in 1..=10_000 {
        apply(grid, ends, &mut direction, &mut product);
        grid.par_update(&cells, &mut product, |_, value| -value);
        let alpha = rho / dot(grid, &direction, &product);
        grid.par_update(&cells, x, |index, value| value + alpha * direction[index]);
        grid.par_update(&cells, &mut residual, |index, value| {
            value - alpha * product[index]
        });
        if dot(grid, &residual, &residual).sqrt() <= 1e-10 * norm_rhs {
            remove_mean(grid, x);
            return iteration;
        }
        grid.par_update(&cells, &mut preconditioned, |index, _| {
            residual[index] / diagonal[index]
        });
        let rho_next = dot(grid, &residual, &preconditioned);
        let beta = rho_next / rho;
        rho = rho_next;
        grid.par_update(&cells, &mut direction, |index, value| {
            preconditioned[index] + beta * value
        });
    }
    panic!("conjugate gradient did not converge");
}

fn main() {
    let side = std::f64::consts::TAU;
    for (name, cells, boundaries) in [
        ("vortex_64", [64, 64, 64], Boundaries::periodic()),
        (
            "channel_128x64x64",
            [128, 64, 64],
            Boundaries::periodic().with(2, BoundaryCondition::NoSlip, BoundaryCondition::NoSlip),
        ),
    ] {
        let grid = Grid::new(
            Dimension::Three,
            cells,
            [0.0; 3],
            [side * cells[0] as f64 / 64.0, side, side],
        );
        let ends = boundaries.pressure_ends(&grid);
        let mut solver = DirectSolver::new(&grid, &ends).unwrap();
        // A manufactured zero-mean solution and its right-hand side.
        let mut exact = grid.zeros();
        grid.for_each(&grid.cell_block(), |index, _| {
            exact[index] = pseudo_random(index)
        });
        remove_mean(&grid, &mut exact);
        let mut rhs = grid.zeros();
        apply(&grid, &ends, &mut exact.clone(), &mut rhs);
        let error = |x: &[f64]| {
            let mut largest: f64 = 0.0;
            grid.for_each(&grid.cell_block(), |index, _| {
                largest = largest.max((x[index] - exact[index]).abs())
            });
            largest
        };
        let (mut direct_times, mut cg_times) = (Vec::new(), Vec::new());
        let (mut direct_error, mut cg_error, mut iterations) = (0.0, 0.0, 0);
        for _ in 0..5 {
            let mut field = rhs.clone();
            let started = Instant::now();
            solver.solve_poisson(&grid, &mut field);
            direct_times.push(started.elapsed().as_secs_f64());
            direct_error = error(&field);
            let mut x = grid.zeros();
            let started = Instant::now();
            iterations = conjugate_gradient(&grid, &ends, &rhs, &mut x);
            cg_times.push(started.elapsed().as_secs_f64());
            cg_error = error(&x);
        }
        direct_times.sort_by(f64::total_cmp);
        cg_times.sort_by(f64::total_cmp);
        let (direct, cg) = (direct_times[2], cg_times[2]);
        println!(
            "{name}: direct {:.2} ms (max error {direct_error:.1e}), Jacobi CG {:.1} ms \
             ({iterations} iterations, max error {cg_error:.1e}), CG / direct {:.1}",
            direct * 1e3,
            cg * 1e3,
            cg / direct
        );
    }
}
