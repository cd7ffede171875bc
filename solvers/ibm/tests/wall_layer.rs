//! The first layer of cells along a wall, which the grains leave to the
//! fluid: which faces it holds, and that a sphere resting on the wall
//! forces every face it reaches but those.

use grainflow_core::{Communicator, Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, NormalCalibration, NormalStiffness};
use grainflow_fluid::{Boundaries, BoundaryCondition, FlowSolver, Grid};
use grainflow_ibm::forcing::{ghost_reach, Exponents, WallLayer};
use grainflow_ibm::solid_fraction::{solid_fraction, transition_width};
use grainflow_ibm::ImmersedBoundaries;

const EXTENT: [f64; 3] = [4.0, 4.0, 4.0];
const CELLS: usize = 32;
const RADIUS: f64 = 0.5;

/// Periodic along x, free-slip walls along y, a no-slip floor and an
/// open top along z.
fn boundaries() -> Boundaries {
    Boundaries::periodic()
        .with(1, BoundaryCondition::FreeSlip, BoundaryCondition::FreeSlip)
        .with(2, BoundaryCondition::NoSlip, BoundaryCondition::Outflow)
}

#[test]
fn a_layer_lies_along_every_wall_and_no_open_or_periodic_face() {
    let grid = Grid::new(Dimension::Three, [CELLS; 3], [0.0; 3], EXTENT);
    let layers = WallLayer::along_walls(&grid, &boundaries(), [0.0; 3], EXTENT);
    let h = EXTENT[0] / CELLS as f64;
    let expected = [
        WallLayer {
            axis: 1,
            wall: 0.0,
            inward: 1.0,
            depth: h,
        },
        WallLayer {
            axis: 1,
            wall: 4.0,
            inward: -1.0,
            depth: h,
        },
        WallLayer {
            axis: 2,
            wall: 0.0,
            inward: 1.0,
            depth: h,
        },
    ];
    assert_eq!(layers, expected);
}

/// The grid volume (per component) of a sphere resting on the floor and
/// the velocity after one stage of forcing on a fluid at rest, with the
/// floor's layer free or not.
fn forced_once(fixed: bool, free: bool) -> (Vec3, Vec<Vec<f64>>) {
    forced_once_at(centre(), fixed, free)
}

/// [`forced_once`] for a sphere centred at `at`.
fn forced_once_at(at: Vec3, fixed: bool, free: bool) -> (Vec3, Vec<Vec<f64>>) {
    let grid = Grid::new(Dimension::Three, [CELLS; 3], [0.0; 3], EXTENT);
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::zeros(),
        upper: Vec3::from(EXTENT),
        periodic: [true, false, false],
        gravity: Vec3::zeros(),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(0.9, 1e-2, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.0,
        rolling_friction: 0.0,
    };
    let mut dem = DemSystem::new(domain, law, Vec::new(), 0.05);
    dem.ghost_reach = ghost_reach(&grid, RADIUS);
    dem.add_particles(&[NewParticle {
        position: at,
        velocity: Vec3::new(0.3, -0.2, 0.5),
        angular_velocity: Vec3::new(1.0, 0.5, -2.0),
        radius: RADIUS,
        density: 2.0,
        fixed,
    }]);
    let mut flow =
        FlowSolver::new(grid.clone(), boundaries(), 0.01, Communicator::serial()).unwrap();
    let mut immersed = ImmersedBoundaries::new(&grid);
    if free {
        immersed.free_wall_layers =
            WallLayer::along_walls(&grid, &flow.boundaries, [0.0; 3], EXTENT);
    }
    let unknowns: Vec<_> = (0..3).map(|c| *flow.velocity_unknowns(c)).collect();
    let bodies = immersed.bodies(&dem.particles, &grid, &unknowns);
    let volumes = immersed.grid_volumes(&grid, &bodies)[0];
    immersed.apply(
        &grid,
        &mut flow.velocity,
        &bodies,
        0.1,
        &Exponents::Uniform(1.0),
    );
    (volumes, flow.velocity)
}

/// The sphere's centre: resting on the floor.
fn centre() -> Vec3 {
    Vec3::new(2.0, 2.0, RADIUS)
}

/// A moving sphere resting on the floor. With the floor's layer free, the
/// faces of the first cells (u and v half a cell up, w a cell up) keep
/// the fluid's velocity and the grain's grid volume loses exactly their
/// solid fractions (summed here from eq. 8 on those faces); every other
/// face is forced as without it. A glued sphere forces the layer either
/// way.
#[test]
fn a_sphere_on_the_floor_leaves_the_first_cells_to_the_fluid() {
    let grid = Grid::new(Dimension::Three, [CELLS; 3], [0.0; 3], EXTENT);
    let h = EXTENT[0] / CELLS as f64;
    let (forced_volume, forced_velocity) = forced_once(false, false);
    let (free_volume, free_velocity) = forced_once(false, true);

    // The solid fraction on the layer's faces of each component.
    let width = transition_width(&grid.spacing);
    let cell_volume = h * h * h;
    for component in 0..3 {
        let height = if component == 2 { h } else { 0.5 * h };
        let mut in_layer = 0.0;
        for i in 0..CELLS {
            for j in 0..CELLS {
                let mut x = [(i as f64 + 0.5) * h, (j as f64 + 0.5) * h, height];
                if component < 2 {
                    x[component] = [i, j][component] as f64 * h;
                }
                let c = centre();
                let r = [x[0] - c.x, x[1] - c.y, x[2] - c.z];
                in_layer += solid_fraction(r, RADIUS, width) * cell_volume;
            }
        }
        assert!(in_layer > 0.05 * forced_volume[component], "{in_layer}");
        let lost = forced_volume[component] - free_volume[component];
        assert!(
            (lost - in_layer).abs() < 1e-12 * forced_volume[component],
            "component {component}: lost {lost}, in the layer {in_layer}"
        );
    }

    // The velocities: at rest in the layer, as when forced elsewhere.
    let flow = FlowSolver::new(grid.clone(), boundaries(), 0.01, Communicator::serial()).unwrap();
    let mut moved_in_layer = 0;
    for component in 0..3 {
        let location = grainflow_fluid::Location::Face(component);
        grid.for_each(flow.velocity_unknowns(component), |index, point| {
            let z = grid.coordinate(location, 2, point[2]);
            if z <= h * (1.0 + 1e-9) {
                assert_eq!(free_velocity[component][index], 0.0);
                moved_in_layer += (forced_velocity[component][index] != 0.0) as usize;
            } else {
                assert_eq!(
                    free_velocity[component][index], forced_velocity[component][index],
                    "component {component} at {point:?}"
                );
            }
        });
    }
    assert!(moved_in_layer > 100, "{moved_in_layer}");

    let glued = forced_once(true, false).0;
    assert_eq!(forced_once(true, true).0, glued);
    assert_eq!(glued, forced_volume);
}

/// A moving sphere touching either free-slip side wall (y = 0 and y = 4):
/// the faces of the first cells along that wall (u and w half a cell in,
/// v a cell in) keep the fluid's velocity, the grid volume loses exactly
/// the solid fraction there, and every other face is forced as without
/// the layer. The layer is cut across each axis of the stencil, not only
/// the vertical.
#[test]
fn a_sphere_against_a_side_wall_leaves_the_first_cells_to_the_fluid() {
    let grid = Grid::new(Dimension::Three, [CELLS; 3], [0.0; 3], EXTENT);
    let h = EXTENT[1] / CELLS as f64;
    let width = transition_width(&grid.spacing);
    let flow = FlowSolver::new(grid.clone(), boundaries(), 0.01, Communicator::serial()).unwrap();
    for (wall, inward) in [(0.0, 1.0), (EXTENT[1], -1.0)] {
        let at = Vec3::new(2.0, wall + inward * RADIUS, 2.0);
        let (forced_volume, forced_velocity) = forced_once_at(at, false, false);
        let (free_volume, free_velocity) = forced_once_at(at, false, true);
        let in_layer = |x: f64| {
            let distance = inward * (x - wall);
            distance > 0.0 && distance <= h * (1.0 + 1e-9)
        };
        let mut moved_in_layer = 0;
        for component in 0..3 {
            let location = grainflow_fluid::Location::Face(component);
            let mut layer_volume = 0.0;
            grid.for_each(flow.velocity_unknowns(component), |index, point| {
                let x = [0, 1, 2].map(|axis| grid.coordinate(location, axis, point[axis]));
                if in_layer(x[1]) {
                    let r = [x[0] - at.x, x[1] - at.y, x[2] - at.z];
                    layer_volume += solid_fraction(r, RADIUS, width) * h * h * h;
                    assert_eq!(free_velocity[component][index], 0.0);
                    moved_in_layer += (forced_velocity[component][index] != 0.0) as usize;
                } else {
                    assert_eq!(
                        free_velocity[component][index], forced_velocity[component][index],
                        "wall {wall}, component {component} at {point:?}"
                    );
                }
            });
            assert!(
                layer_volume > 0.05 * forced_volume[component],
                "{layer_volume}"
            );
            let lost = forced_volume[component] - free_volume[component];
            assert!(
                (lost - layer_volume).abs() < 1e-12 * forced_volume[component],
                "wall {wall}, component {component}: lost {lost}, in the layer {layer_volume}"
            );
        }
        assert!(moved_in_layer > 100, "wall {wall}: {moved_in_layer}");
    }
}
