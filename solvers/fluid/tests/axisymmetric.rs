//! The (r, z) flow: its solvers against the discrete operators, the
//! projection, the pipe's Poiseuille profile and start-up against the
//! Bessel series, and the convective operator against a manufactured
//! field, each with its order of convergence.

mod common;

use std::f64::consts::PI;

use common::{order, scientific};
use grainflow_fluid::axisymmetric::operators::{
    add_axial_second_difference, convection, divergence, subtract_gradient,
};
use grainflow_fluid::axisymmetric::radial::{OuterClosure, RadialOperator};
use grainflow_fluid::axisymmetric::solver::RzDirectSolver;
use grainflow_fluid::axisymmetric::{
    core_and_growth_faces, AxialEnd, AxisymmetricFlow, OuterWall, RzField, RzGrid, RzWalls,
};
use grainflow_fluid::clustered_faces;
use grainflow_fluid::transform::AxisTransform;
use grainflow_fluid::{Clustering, FluidError};

/// A reproducible value in [−1, 1) for entry `n`.
fn noise(n: usize) -> f64 {
    let mut x = (n as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

fn stretched_grid(cells: [usize; 2], ends: [f64; 2]) -> RzGrid {
    let faces = clustered_faces(Clustering::Upper, 1.5, cells[0], 0.0, 1.0);
    RzGrid::from_radial_faces(&faces, cells[1], ends).unwrap()
}

fn walls(outer: OuterWall, end: AxialEnd) -> RzWalls {
    RzWalls::new(outer, [end, end]).unwrap()
}

/// `(a I + b L) x` for the field `kind`, explicit, on its unknowns.
fn apply(
    grid: &RzGrid,
    walls: &RzWalls,
    kind: RzField,
    radial: &RadialOperator,
    x: &mut [f64],
    a: f64,
    b: f64,
) -> Vec<f64> {
    match kind {
        RzField::Radial => walls.fill_radial_ghosts(grid, x),
        RzField::Axial => walls.fill_axial_ghosts(grid, x),
        RzField::Pressure => walls.fill_centre_ghosts(grid, x),
    }
    let rows = walls.z_unknowns(grid, kind);
    let radii = radial.first..radial.first + radial.len();
    let mut out = grid.zeros();
    for k in rows.clone() {
        for i in radii.clone() {
            out[grid.index(i, k)] = a * x[grid.index(i, k)];
        }
    }
    radial.apply_add(grid, x, 0.0, b, rows.clone(), &mut out);
    add_axial_second_difference(grid, x, b, radii, rows, &mut out);
    out
}

/// Solves `(a I + b L) x = (a I + b L) x_0` for a random `x_0` and returns
/// the largest `|x − x_0|` over the largest `|x_0|`.
fn solve_error(grid: &RzGrid, walls: &RzWalls, kind: RzField, a: f64, b: f64) -> f64 {
    let radial = match kind {
        RzField::Radial => RadialOperator::faces(grid),
        RzField::Axial => RadialOperator::centres(grid, OuterClosure::WallValue),
        RzField::Pressure => RadialOperator::centres(grid, OuterClosure::ZeroGradient),
    };
    let rows = walls.z_unknowns(grid, kind);
    let singular = kind == RzField::Pressure && a == 0.0;
    let mut exact = grid.zeros();
    let mut volume = 0.0;
    let mut mean = 0.0;
    for k in rows.clone() {
        for i in radial.first..radial.first + radial.len() {
            let value = noise(grid.index(i, k));
            exact[grid.index(i, k)] = value;
            mean += grid.ring(i) * value;
            volume += grid.ring(i);
        }
    }
    if singular {
        // The solve returns the solution of zero volume mean.
        for k in rows.clone() {
            for i in 1..=grid.cells[0] {
                exact[grid.index(i, k)] -= mean / volume;
            }
        }
    }
    let mut field = apply(grid, walls, kind, &radial, &mut exact.clone(), a, b);
    let transform = AxisTransform::new(walls.z_transform(kind), rows.len());
    let mut solver = RzDirectSolver::new(grid, radial, rows.clone(), transform, singular);
    solver.solve(grid, &mut field, a, b);
    let (mut error, mut size): (f64, f64) = (0.0, 0.0);
    for k in rows {
        for i in 1..=grid.cells[0] {
            let at = grid.index(i, k);
            error = error.max((field[at] - exact[at]).abs());
            size = size.max(exact[at].abs());
        }
    }
    error / size
}

#[test]
fn the_direct_solves_invert_the_discrete_operators_to_round_off() {
    let grids = [
        RzGrid::uniform([24, 20], 1.0, [0.0, 3.0]).unwrap(),
        stretched_grid([24, 20], [0.0, 3.0]),
        RzGrid::from_radial_faces(
            &core_and_growth_faces(0.3, 8, 1.0, 24).unwrap(),
            20,
            [0.0, 3.0],
        )
        .unwrap(),
    ];
    for grid in &grids {
        use AxialEnd::{FreeSlip, NoSlip, Periodic};
        for ends in [
            [Periodic; 2],
            [NoSlip; 2],
            [FreeSlip; 2],
            [NoSlip, FreeSlip],
            [FreeSlip, NoSlip],
        ] {
            let end = ends;
            let walls = RzWalls::new(OuterWall::NoSlip, ends).unwrap();
            for kind in [RzField::Radial, RzField::Axial, RzField::Pressure] {
                let helmholtz = solve_error(grid, &walls, kind, 1.0, -0.01);
                assert!(
                    helmholtz < 1e-12,
                    "{kind:?}, {end:?}: (I − cL) off by {helmholtz:.2e}"
                );
            }
            let poisson = solve_error(grid, &walls, RzField::Pressure, 0.0, 1.0);
            assert!(poisson < 1e-10, "pressure, {end:?}: L off by {poisson:.2e}");
        }
    }
}

#[test]
fn a_projection_leaves_no_divergence_on_uniform_and_stretched_radii() {
    for grid in [
        RzGrid::uniform([32, 48], 1.0, [0.0, 3.0]).unwrap(),
        stretched_grid([32, 48], [0.0, 3.0]),
    ] {
        for end in [AxialEnd::Periodic, AxialEnd::NoSlip] {
            let mut flow =
                AxisymmetricFlow::new(grid.clone(), walls(OuterWall::NoSlip, end), 1e-3).unwrap();
            flow.set_velocity(
                |r, z| r * (1.0 - r) * (3.0 * z).sin(),
                |r, z| (2.0 * r + z).cos(),
            );
            let before = flow.max_divergence();
            flow.remove_divergence();
            let after = flow.max_divergence();
            assert!(
                after < 1e-12 * before,
                "{end:?}: |D u| {before:.3e} → {after:.3e}, relative {:.1e}",
                after / before
            );
        }
    }
}

/// `f R²/(4ν) (1 − x²)`, `x = r/R`.
fn poiseuille(force: f64, viscosity: f64, radius: f64, r: f64) -> f64 {
    force * radius * radius / (4.0 * viscosity) * (1.0 - (r / radius).powi(2))
}

/// Largest error of the steady pipe flow on `grid` after 20 steps from
/// the exact profile, over the peak velocity.
fn poiseuille_error(grid: RzGrid) -> f64 {
    let (force, viscosity) = (2.0, 0.05);
    let walls = walls(OuterWall::NoSlip, AxialEnd::Periodic);
    let mut flow = AxisymmetricFlow::new(grid.clone(), walls, viscosity).unwrap();
    flow.body_force = force;
    flow.set_velocity(|_, _| 0.0, |r, _| poiseuille(force, viscosity, 1.0, r));
    for _ in 0..20 {
        flow.step(0.02).unwrap();
    }
    let mut error: f64 = 0.0;
    for k in 1..=grid.cells[1] {
        for i in 1..=grid.cells[0] {
            let exact = poiseuille(force, viscosity, 1.0, grid.centre(i));
            error = error.max((flow.axial[grid.index(i, k)] - exact).abs());
            error = error.max(flow.radial[grid.index(i, k)].abs());
        }
    }
    error / poiseuille(force, viscosity, 1.0, 0.0)
}

#[test]
fn the_pipe_poiseuille_profile_is_steady_to_round_off_on_uniform_radii() {
    // The centre operator and the wall's parabola are exact on a + b r²
    // when every centre lies midway between its neighbours.
    let error = poiseuille_error(RzGrid::uniform([16, 4], 1.0, [0.0, 1.0]).unwrap());
    assert!(error < 1e-12, "Poiseuille off by {error:.2e} of its peak");
}

#[test]
fn the_pipe_poiseuille_profile_converges_at_second_order_on_stretched_radii() {
    // On stretched radii a face no longer lies midway between the centres
    // on either side: the flux r ∂_r u there is first order locally, the
    // profile second order.
    let stretched: Vec<f64> = [16, 32, 64]
        .iter()
        .map(|&n| poiseuille_error(stretched_grid([n, 4], [0.0, 1.0])))
        .collect();
    let grown: Vec<f64> = [1, 2, 4]
        .iter()
        .map(|&m| {
            let faces = core_and_growth_faces(0.3, 6 * m, 1.0, 16 * m).unwrap();
            poiseuille_error(RzGrid::from_radial_faces(&faces, 4, [0.0, 1.0]).unwrap())
        })
        .collect();
    for (name, errors) in [("tanh", stretched), ("core and growth", grown)] {
        let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
        assert!(
            orders.iter().all(|&p| p >= 1.9) && errors[0] < 1e-2,
            "{name}: errors {}, orders {orders:.2?}",
            scientific(&errors)
        );
    }
}

/// `J_n(x) = (1/π) ∫_0^π cos(n τ − x sin τ) dτ`, by the trapezoidal rule,
/// which converges geometrically for this periodic integrand.
fn bessel(n: usize, x: f64) -> f64 {
    let points = 400;
    let step = PI / points as f64;
    let integrand = |tau: f64| (n as f64 * tau - x * tau.sin()).cos();
    let inner: f64 = (1..points).map(|j| integrand(j as f64 * step)).sum();
    (inner + 0.5 * (integrand(0.0) + integrand(PI))) * step / PI
}

/// The first `count` zeros of `J_0`, by Newton from McMahon's estimates.
fn bessel_zeros(count: usize) -> Vec<f64> {
    (1..=count)
        .map(|n| {
            let mut x = (n as f64 - 0.25) * PI;
            for _ in 0..20 {
                x += bessel(0, x) / bessel(1, x);
            }
            x
        })
        .collect()
}

/// Flow in a pipe started from rest by a uniform force `f`:
/// `u = f R²/(4ν) [1 − x² − Σ_n 8 J_0(λ_n x) / (λ_n³ J_1(λ_n)) e^{−λ_n² ν t/R²}]`.
fn pipe_start_up(zeros: &[f64], force: f64, viscosity: f64, r: f64, t: f64) -> f64 {
    let scale = force / (4.0 * viscosity);
    let transient: f64 = zeros
        .iter()
        .map(|&l| {
            8.0 * bessel(0, l * r) / (l.powi(3) * bessel(1, l)) * (-l * l * viscosity * t).exp()
        })
        .sum();
    scale * (1.0 - r * r - transient)
}

fn started_pipe(grid: RzGrid, dt: f64, end: f64) -> AxisymmetricFlow {
    let walls = walls(OuterWall::NoSlip, AxialEnd::Periodic);
    let mut flow = AxisymmetricFlow::new(grid, walls, 1.0).unwrap();
    flow.body_force = 1.0;
    let steps = (end / dt).round() as usize;
    for _ in 0..steps {
        flow.step(dt).unwrap();
    }
    flow
}

fn axial_error(flow: &AxisymmetricFlow, exact: impl Fn(f64) -> f64) -> f64 {
    let grid = &flow.grid;
    (1..=grid.cells[0])
        .map(|i| (flow.axial[grid.index(i, 1)] - exact(grid.centre(i))).abs())
        .fold(0.0, f64::max)
}

#[test]
fn the_pipe_start_up_converges_at_second_order_in_space_and_time() {
    // R = 1, ν = 1, f = 1, compared at t = 0.1 (the slowest mode has
    // decayed to e^{−0.58}); the series to 40 terms is exact to 1e-12 there.
    let zeros = bessel_zeros(40);
    let exact = |r: f64| pipe_start_up(&zeros, 1.0, 1.0, r, 0.1);
    let end = 0.1;
    for (name, make) in [
        (
            "uniform",
            Box::new(|n: usize| RzGrid::uniform([n, 2], 1.0, [0.0, 1.0]).unwrap())
                as Box<dyn Fn(usize) -> RzGrid>,
        ),
        (
            "stretched",
            Box::new(|n: usize| stretched_grid([n, 2], [0.0, 1.0])),
        ),
    ] {
        // Space: a step small enough that its error is a small part.
        let errors: Vec<f64> = [16, 32, 64]
            .iter()
            .map(|&n| axial_error(&started_pipe(make(n), 1e-4, end), exact))
            .collect();
        let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
        assert!(
            orders.iter().all(|&p| p >= 1.9),
            "{name} r: errors {}, orders {orders:.2?}",
            scientific(&errors)
        );
        // Time: on one grid against a run of a much smaller step.
        let reference = started_pipe(make(32), 2.5e-5, end);
        let errors: Vec<f64> = [4e-3, 2e-3, 1e-3]
            .iter()
            .map(|&dt| {
                let flow = started_pipe(make(32), dt, end);
                let grid = &flow.grid;
                (1..=32)
                    .map(|i| {
                        (flow.axial[grid.index(i, 1)] - reference.axial[grid.index(i, 1)]).abs()
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        let orders = [order(errors[0], errors[1]), order(errors[1], errors[2])];
        assert!(
            orders.iter().all(|&p| p >= 1.9),
            "{name} t: errors {}, orders {orders:.2?}",
            scientific(&errors)
        );
    }
}

/// A divergence-free field from the stream function
/// `ψ = r² (1 − r²)² sin(2π z)`: `u_r = −(1/r) ∂_z ψ`, `u_z = (1/r) ∂_r ψ`.
fn stream_velocity(r: f64, z: f64) -> [f64; 2] {
    let s = 1.0 - r * r;
    let k = 2.0 * PI;
    [
        -r * s * s * k * (k * z).cos(),
        (2.0 * s * s - 4.0 * r * r * s) * (k * z).sin(),
    ]
}

/// `N(u) = −∇·(u u)` of the stream field, by fourth-order differences of
/// the exact products (their error, ~1e-11, is far below the grids').
fn exact_convection(r: f64, z: f64) -> [f64; 2] {
    let d = 1e-3;
    let derivative = |f: &dyn Fn(f64) -> f64, x: f64| {
        (-f(x + 2.0 * d) + 8.0 * f(x + d) - 8.0 * f(x - d) + f(x - 2.0 * d)) / (12.0 * d)
    };
    let u = |r: f64, z: f64| stream_velocity(r, z);
    let radial = -derivative(&|s| s * u(s, z)[0].powi(2), r) / r
        - derivative(&|s| u(r, s)[0] * u(r, s)[1], z);
    let axial = -derivative(&|s| s * u(s, z)[0] * u(s, z)[1], r) / r
        - derivative(&|s| u(r, s)[1].powi(2), z);
    [radial, axial]
}

/// The conservative form of the radial flux of `u_r` divided by the first
/// face's radius leaves an O(h) error on that face alone: the errors are
/// second order in the volume-weighted norm `(Σ e² r dr dz / Σ r dr dz)^½`
/// (and `u_z` in the largest error too).
#[test]
fn convection_converges_at_second_order_on_a_manufactured_field() {
    let errors: Vec<[f64; 3]> = [16, 32, 64]
        .iter()
        .map(|&n| {
            let grid = RzGrid::uniform([n, n], 1.0, [0.0, 1.0]).unwrap();
            let walls = walls(OuterWall::NoSlip, AxialEnd::Periodic);
            let mut flow = AxisymmetricFlow::new(grid.clone(), walls, 1.0).unwrap();
            flow.set_velocity(
                |r, z| stream_velocity(r, z)[0],
                |r, z| stream_velocity(r, z)[1],
            );
            let (mut out_r, mut out_z) = (grid.zeros(), grid.zeros());
            convection(
                &grid,
                &flow.radial,
                &flow.axial,
                1..n + 1,
                &mut out_r,
                &mut out_z,
            );
            let (mut squares, mut volume) = ([0.0f64; 2], [0.0f64; 2]);
            let mut largest_axial: f64 = 0.0;
            for k in 1..=n {
                for i in 1..=n {
                    let at = grid.index(i, k);
                    if i < n {
                        let exact = exact_convection(grid.face(i), grid.z_centre(k))[0];
                        squares[0] += (out_r[at] - exact).powi(2) * grid.face(i);
                        volume[0] += grid.face(i);
                    }
                    let exact = exact_convection(grid.centre(i), grid.z_face(k))[1];
                    squares[1] += (out_z[at] - exact).powi(2) * grid.centre(i);
                    volume[1] += grid.centre(i);
                    largest_axial = largest_axial.max((out_z[at] - exact).abs());
                }
            }
            [
                (squares[0] / volume[0]).sqrt(),
                (squares[1] / volume[1]).sqrt(),
                largest_axial,
            ]
        })
        .collect();
    for (c, name) in ["u_r, weighted", "u_z, weighted", "u_z, largest"]
        .iter()
        .enumerate()
    {
        let orders = [
            order(errors[0][c], errors[1][c]),
            order(errors[1][c], errors[2][c]),
        ];
        assert!(
            orders.iter().all(|&p| p >= 1.9),
            "{name}: errors {}, orders {orders:.2?}",
            scientific(&errors.iter().map(|e| e[c]).collect::<Vec<_>>())
        );
    }
}

#[test]
fn the_divergence_of_a_gradient_is_the_pressure_laplacian() {
    let grid = stretched_grid([12, 10], [0.0, 2.0]);
    let walls = walls(OuterWall::NoSlip, AxialEnd::NoSlip);
    let mut phi = grid.zeros();
    for (n, value) in phi.iter_mut().enumerate() {
        *value = noise(n);
    }
    walls.fill_centre_ghosts(&grid, &mut phi);
    let (mut radial, mut axial) = (grid.zeros(), grid.zeros());
    subtract_gradient(
        &grid,
        &phi,
        -1.0,
        walls.z_unknowns(&grid, RzField::Axial),
        &mut radial,
        &mut axial,
    );
    let mut div = grid.zeros();
    divergence(&grid, &radial, &axial, &mut div);
    let pressure = RadialOperator::centres(&grid, OuterClosure::ZeroGradient);
    let laplacian = apply(
        &grid,
        &walls,
        RzField::Pressure,
        &pressure,
        &mut phi,
        0.0,
        1.0,
    );
    let mut error: f64 = 0.0;
    for k in 1..=10 {
        for i in 1..=12 {
            let at = grid.index(i, k);
            error = error.max((div[at] - laplacian[at]).abs());
        }
    }
    assert!(error < 1e-10, "D G φ and L φ differ by {error:.2e}");
}

#[test]
fn inconsistent_walls_and_grids_are_refused_naming_what_is_allowed() {
    let mixed = RzWalls::new(OuterWall::NoSlip, [AxialEnd::Periodic, AxialEnd::NoSlip]);
    assert!(matches!(mixed, Err(FluidError::Boundary(ref m)) if m.contains("periodic together")));
    let crowded = core_and_growth_faces(0.5, 10, 1.0, 40);
    assert!(matches!(crowded, Err(FluidError::Parameter(ref m)) if m.contains("fewer cells")));
    let off_axis = RzGrid::from_radial_faces(&[0.1, 0.5, 1.0], 4, [0.0, 1.0]);
    assert!(matches!(off_axis, Err(FluidError::Parameter(ref m)) if m.contains("axis")));
}
