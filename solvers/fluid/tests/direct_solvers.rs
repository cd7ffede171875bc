//! The direct Poisson and Helmholtz solvers recover a discrete manufactured
//! solution to round-off: a field `x` with the right end conditions is
//! chosen, `r = (a I + b L) x` is formed with the same stencil the flow
//! solver uses, and the solver must return `x` (up to its mean when the
//! system is singular). Tolerance: 1e-10 relative in the maximum norm.
//!
//! Velocity components tangential to a wall along the last axis are closed
//! by the quadratic ghost (`Dq`, `u_ghost = (8 u_wall − 6 u_1 + u_2)/3`),
//! those tangential to a wall along a transformed axis by the linear one
//! (`Dc`): `r` is formed with the ghosts these closures set, so the solver
//! must build the same closure into its rows.
//!
//! Every non-periodic case also runs on a grid stretched along the last
//! axis, where each row of the line has its own weights and the quadratic
//! ghost its own Lagrange weights: the solver must recover those systems to
//! the same tolerance.

use grainflow_core::Dimension;
use grainflow_fluid::boundary::{fill_ghosts, EndCondition, EndKind, FieldEnds};
use grainflow_fluid::grid::{clustered_faces, Clustering};
use grainflow_fluid::operators::add_laplacian;
use grainflow_fluid::{DirectSolver, FluidError, Grid, Location, TransformBackend};

const TOLERANCE: f64 = 1e-10;

fn ends(kinds: [[EndKind; 2]; 3]) -> FieldEnds {
    kinds.map(|pair| pair.map(|kind| EndCondition { kind, value: 0.0 }))
}

fn location_of(kinds: &[[EndKind; 2]; 3]) -> Location {
    (0..3)
        .find(|&axis| kinds[axis][0] == EndKind::DirichletFace)
        .map_or(Location::Centre, Location::Face)
}

/// A deterministic, rough field (every mode present).
fn pseudo_random(seed: usize) -> f64 {
    let x = ((seed as u64)
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407)
        >> 33) as f64;
    x / (1u64 << 31) as f64 - 0.5
}

/// Relative max-norm error of the solver on grid `grid` with ends `kinds`
/// for `(identity I + laplacian L)`.
fn recovery_error(grid: &Grid, kinds: [[EndKind; 2]; 3], identity: f64, laplacian: f64) -> f64 {
    let ends = ends(kinds);
    let location = location_of(&kinds);
    let mut solver = DirectSolver::new(grid, &ends).unwrap();
    let block = *solver.unknowns();
    let mut exact = grid.zeros();
    grid.for_each(&block, |index, _| exact[index] = pseudo_random(index));
    let singular = identity == 0.0
        && kinds[..grid.dim()]
            .iter()
            .flatten()
            .all(|k| matches!(k, EndKind::Periodic | EndKind::Neumann));
    fill_ghosts(grid, &mut exact, location, &ends);
    let mut field = grid.zeros();
    grid.for_each(&block, |index, _| field[index] = identity * exact[index]);
    add_laplacian(grid, &exact, location, &block, laplacian, &mut field);
    solver.solve(grid, &mut field, identity, laplacian);
    if singular {
        // Determined up to a constant: compare both with zero mean.
        for values in [&mut exact, &mut field] {
            let mut count = 0.0;
            let mut sum = 0.0;
            grid.for_each(&block, |index, _| {
                sum += values[index];
                count += 1.0;
            });
            grid.for_each(&block, |index, _| values[index] -= sum / count);
        }
    }
    let mut error: f64 = 0.0;
    let mut scale: f64 = 0.0;
    grid.for_each(&block, |index, _| {
        error = error.max((field[index] - exact[index]).abs());
        scale = scale.max(exact[index].abs());
    });
    error / scale
}

/// The same grid with the last axis clustered towards both ends
/// (widths varying by a factor of about 4).
fn stretched(grid: &Grid) -> Grid {
    let axis = grid.line_axis();
    let faces = clustered_faces(
        Clustering::BothEnds,
        1.8,
        grid.cells[axis],
        grid.lower[axis],
        grid.upper[axis],
    );
    Grid::stretched(grid.dimension, grid.cells, grid.lower, grid.upper, &faces).unwrap()
}

/// The grid itself, and stretched along its last axis if `kinds` has no
/// periodic end there.
fn grids(grid: &Grid, kinds: &[[EndKind; 2]; 3]) -> Vec<Grid> {
    let mut grids = vec![grid.clone()];
    if kinds[grid.line_axis()][0] != EndKind::Periodic {
        grids.push(stretched(grid));
    }
    grids
}

/// Asserts the recovery on `grid` and its stretched twin.
fn assert_recovered(grid: &Grid, kinds: [[EndKind; 2]; 3], identity: f64, laplacian: f64) {
    for grid in grids(grid, &kinds) {
        let error = recovery_error(&grid, kinds, identity, laplacian);
        let label = if grid.is_uniform(grid.line_axis()) {
            "uniform"
        } else {
            "stretched"
        };
        println!(
            "{}D {label} {kinds:?}, ({identity} I + {laplacian} L): relative error {error:.2e}",
            grid.dim()
        );
        assert!(error <= TOLERANCE, "{label} {kinds:?}: {error}");
    }
}

use EndKind::{
    DirichletCell as Dc, DirichletCellQuadratic as Dq, DirichletFace as Df, Neumann as N,
    Periodic as P,
};

#[test]
fn poisson_2d_periodic_and_neumann() {
    let grid = Grid::new(Dimension::Two, [16, 12, 1], [0.0; 3], [2.0, 1.0, 1.0]);
    for kinds in [
        [[P, P], [P, P], [P, P]],
        [[P, P], [N, N], [P, P]],
        [[N, N], [P, P], [P, P]],
        [[N, N], [N, N], [P, P]],
    ] {
        assert_recovered(&grid, kinds, 0.0, 1.0);
    }
}

#[test]
fn poisson_3d_periodic_and_neumann() {
    let grid = Grid::new(Dimension::Three, [8, 10, 12], [0.0; 3], [1.0, 2.0, 3.0]);
    for kinds in [
        [[P, P], [P, P], [P, P]],
        [[P, P], [P, P], [N, N]],
        [[N, N], [P, P], [N, N]],
        [[N, N], [N, N], [P, P]],
        [[N, N], [N, N], [N, N]],
    ] {
        assert_recovered(&grid, kinds, 0.0, 1.0);
    }
}

/// The end conditions of the flow's velocity components (the Helmholtz
/// equation of the viscous step): walls along the last axis (quadratic
/// ghost for tangential components), along transformed axes (linear
/// ghost), or both.
#[test]
fn helmholtz_with_velocity_end_conditions() {
    let grid_2d = Grid::new(Dimension::Two, [16, 12, 1], [0.0; 3], [2.0, 1.0, 1.0]);
    let grid_3d = Grid::new(Dimension::Three, [8, 10, 12], [0.0; 3], [1.0, 2.0, 3.0]);
    let c = 0.05;
    for (grid, kinds) in [
        (&grid_2d, [[P, P], [Dq, Dq], [P, P]]),
        (&grid_2d, [[P, P], [Df, Df], [P, P]]),
        (&grid_2d, [[Dc, Dc], [Dq, N], [P, P]]),
        (&grid_2d, [[Df, Df], [P, P], [P, P]]),
        (&grid_2d, [[Df, Df], [Dq, Dq], [P, P]]),
        (&grid_3d, [[P, P], [P, P], [Dq, N]]),
        (&grid_3d, [[Dc, Dc], [N, N], [Df, Df]]),
        (&grid_3d, [[Df, Df], [P, P], [Dq, Dq]]),
        (&grid_3d, [[P, P], [Dc, Dc], [N, Dq]]),
        (&grid_3d, [[N, N], [Dc, Dc], [P, P]]),
    ] {
        assert_recovered(grid, kinds, 1.0, -c);
    }
}

/// The linear ghost is still solved along the last axis, alone or facing
/// a quadratic one.
#[test]
fn helmholtz_with_the_linear_closure_along_the_last_axis() {
    let grid = Grid::new(Dimension::Three, [8, 10, 12], [0.0; 3], [1.0, 2.0, 3.0]);
    for kinds in [[[P, P], [N, N], [Dc, Dc]], [[P, P], [P, P], [Dc, Dq]]] {
        assert_recovered(&grid, kinds, 1.0, -0.05);
    }
}

/// The transforms diagonalise the second difference with the linear
/// ghost only: a quadratic ghost on a transformed axis is refused.
#[test]
fn the_quadratic_closure_on_a_transformed_axis_is_refused() {
    let grid = Grid::new(Dimension::Three, [8, 10, 12], [0.0; 3], [1.0, 2.0, 3.0]);
    for kinds in [[[Dq, Dq], [P, P], [N, N]], [[P, P], [Dc, Dq], [N, N]]] {
        let result = DirectSolver::new(&grid, &ends(kinds));
        assert!(
            matches!(result, Err(FluidError::Boundary(_))),
            "{kinds:?} accepted"
        );
    }
}

/// A Poisson problem that is not singular (a Dirichlet end) needs no
/// mean fixing and is recovered exactly too.
#[test]
fn poisson_with_dirichlet_ends() {
    let grid = Grid::new(Dimension::Three, [8, 6, 10], [0.0; 3], [1.0, 1.0, 1.0]);
    for kinds in [
        [[P, P], [Dc, Dc], [N, N]],
        [[N, N], [P, P], [Dc, N]],
        [[P, P], [N, N], [Dq, Dq]],
        [[N, N], [P, P], [N, Dq]],
    ] {
        assert_recovered(&grid, kinds, 0.0, 1.0);
    }
}

/// The smallest lines: two cells along the tridiagonal axis (one unknown
/// between prescribed faces, a singular pair of Neumann cells, and two
/// cells whose quadratic wall ghosts each read the cell next to the other
/// end), three along a periodic one.
#[test]
fn two_cells_along_the_last_axis() {
    let grid = Grid::new(Dimension::Two, [6, 2, 1], [0.0; 3], [1.0, 0.5, 1.0]);
    for (kinds, identity, laplacian) in [
        ([[P, P], [N, N], [P, P]], 0.0, 1.0),
        ([[N, N], [N, N], [P, P]], 0.0, 1.0),
        ([[P, P], [Df, Df], [P, P]], 1.0, -0.1),
        ([[P, P], [Dc, N], [P, P]], 1.0, -0.1),
        ([[P, P], [Dq, Dq], [P, P]], 1.0, -0.1),
        ([[P, P], [Dq, Dq], [P, P]], 0.0, 1.0),
        ([[N, N], [N, Dq], [P, P]], 1.0, -0.1),
    ] {
        assert_recovered(&grid, kinds, identity, laplacian);
    }
    let grid = Grid::new(Dimension::Three, [4, 5, 3], [0.0; 3], [1.0, 1.0, 0.75]);
    for (identity, laplacian) in [(0.0, 1.0), (1.0, -0.1)] {
        let error = recovery_error(&grid, [[P, P], [N, N], [P, P]], identity, laplacian);
        println!("three periodic cells, identity {identity}: relative error {error:.2e}");
        assert!(error <= TOLERANCE, "{error}");
    }
}

/// Wall-normal faces along transformed axes with line lengths (29, 39)
/// where the sine transform's work array must be cleared between lines.
#[test]
fn helmholtz_on_longer_lines() {
    for cells in [[30, 30, 4], [40, 4, 12]] {
        let grid = Grid::new(Dimension::Three, cells, [0.0; 3], [1.0, 1.0, 1.5]);
        for kinds in [[[Df, Df], [N, N], [N, N]], [[N, N], [Df, Df], [P, P]]] {
            let error = recovery_error(&grid, kinds, 1.0, -0.05);
            println!("helmholtz {cells:?} {kinds:?}: relative error {error:.2e}");
            assert!(error <= TOLERANCE, "{cells:?} {kinds:?}: {error}");
        }
    }
}

/// FFTW (cargo feature `fftw`) and the pure-Rust transforms solve the same
/// systems to round-off: every transform kind, 2D and 3D, uniform and
/// stretched. Without the feature, asking for FFTW is refused.
#[test]
fn fftw_and_rust_transforms_agree() {
    let grid = Grid::new(Dimension::Three, [12, 10, 9], [0.0; 3], [1.0, 2.0, 3.0]);
    let cases = [
        [[P, P], [N, N], [Dq, Dq]],
        [[Df, Df], [Dc, Dc], [N, N]],
        [[N, N], [P, P], [Df, Df]],
    ];
    for kinds in cases {
        if !TransformBackend::Fftw.is_available() {
            let refused = DirectSolver::with_backend(&grid, &ends(kinds), TransformBackend::Fftw);
            assert!(matches!(refused, Err(FluidError::Unsupported(_))));
            continue;
        }
        for grid in grids(&grid, &kinds) {
            let mut solutions = Vec::new();
            for backend in [TransformBackend::Rust, TransformBackend::Fftw] {
                let mut solver = DirectSolver::with_backend(&grid, &ends(kinds), backend).unwrap();
                let block = *solver.unknowns();
                let mut field = grid.zeros();
                grid.for_each(&block, |index, _| field[index] = pseudo_random(index));
                solver.solve(&grid, &mut field, 1.0, -0.05);
                solutions.push(field);
            }
            let difference = solutions[0]
                .iter()
                .zip(&solutions[1])
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let scale = solutions[0].iter().map(|a| a.abs()).fold(0.0, f64::max);
            println!(
                "{kinds:?}: FFTW against rustfft/rustdct {:.2e}",
                difference / scale
            );
            assert!(difference <= 1e-12 * scale, "{kinds:?}: {difference:e}");
        }
    }
}
