//! A particle whose forcing region straddles the edges of a triply
//! periodic domain acts through its periodic images (the DEM's ghosts
//! within the immersed boundaries' reach), whose shares of the loads go
//! back to it: seen by the grid, it is the same particle as one in the
//! middle of the domain.

use grainflow_core::{Communicator, Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, NormalCalibration, NormalStiffness};
use grainflow_fluid::{Boundaries, FlowSolver, Grid};
use grainflow_ibm::forcing::{ghost_reach, Exponents};
use grainflow_ibm::ImmersedBoundaries;

/// One sphere of radius 0.5 at `centre`, with its periodic images.
fn one_particle(domain: &Domain, grid: &Grid, centre: Vec3) -> DemSystem {
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(0.9, 1e-2, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.0,
        rolling_friction: 0.0,
    };
    let mut dem = DemSystem::new(domain.clone(), law, Vec::new(), 0.05);
    dem.ghost_reach = ghost_reach(grid, 0.5);
    dem.add_particles(&[NewParticle {
        position: centre,
        velocity: Vec3::new(0.3, -0.2, 0.5),
        angular_velocity: Vec3::new(1.0, 0.5, -2.0),
        radius: 0.5,
        density: 2.0,
        fixed: false,
    }]);
    dem
}

/// The grid volume, the loads of one forcing stage on a fluid at rest,
/// and the momentum the forcing gives the fluid, for a sphere at the
/// corner of the domain (its support cut by all three periodic edges) and
/// for the same sphere in the middle, shifted by whole cells: equal to
/// round-off.
#[test]
fn a_sphere_across_periodic_edges_acts_like_one_inside() {
    let extent = [4.0, 4.0, 4.0];
    let grid = Grid::new(Dimension::Three, [32, 32, 32], [0.0; 3], extent);
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::zeros(),
        upper: Vec3::from(extent),
        periodic: [true; 3],
        gravity: Vec3::zeros(),
    };
    let mut results = Vec::new();
    for centre in [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 2.0, 2.0)] {
        let mut flow = FlowSolver::new(
            grid.clone(),
            Boundaries::periodic(),
            0.01,
            Communicator::serial(),
        )
        .unwrap();
        let mut immersed = ImmersedBoundaries::new(&grid);
        let dem = one_particle(&domain, &grid, centre);
        let images = dem.particles.len() - 1;
        assert_eq!(images, if centre.x == 0.0 { 7 } else { 0 });
        let unknowns: Vec<_> = (0..3).map(|c| *flow.velocity_unknowns(c)).collect();
        let bodies = immersed.bodies(&dem.particles, &grid, &unknowns);
        let mut volume: Vec<f64> = immersed
            .grid_volumes(&grid, &bodies)
            .iter()
            .map(|v| v.sum() / 3.0)
            .collect();
        dem.sum_onto_owners(&mut volume, 1);
        let volume = volume[0];
        let loads = immersed
            .apply(
                &grid,
                &mut flow.velocity,
                &bodies,
                0.1,
                &Exponents::Uniform(1.0),
            )
            .summed_on_owners(&dem);
        let (force, torque) = (loads.force[0], loads.torque[0]);
        let momentum: Vec<f64> = (0..3)
            .map(|c| {
                let field = &flow.velocity[c];
                let mut sum = 0.0;
                grid.for_each(&unknowns[c], |index, _| sum += field[index]);
                sum * grid.cell_volume()
            })
            .collect();
        results.push((volume, force, torque, momentum));
    }
    let (corner, middle) = (&results[0], &results[1]);
    println!("volume {:.12} / {:.12}", corner.0, middle.0);
    println!(
        "force {:?} / {:?}",
        corner.1.as_slice(),
        middle.1.as_slice()
    );
    assert!((corner.0 - middle.0).abs() < 1e-12 * middle.0);
    assert!((corner.1 - middle.1).norm() < 1e-12 * middle.1.norm());
    assert!((corner.2 - middle.2).norm() < 1e-12 * middle.2.norm());
    for c in 0..3 {
        assert!((corner.3[c] - middle.3[c]).abs() < 1e-12 * middle.1.norm());
        // The fluid gains what the particle loses: ∫ f dV h = −F h.
        assert!((middle.3[c] + 0.1 * middle.1[c]).abs() < 1e-12 * middle.1.norm());
    }
    // The sphere of radius 0.5 seen on this grid (D/Δx = 8).
    let exact = std::f64::consts::PI / 6.0;
    assert!(
        (middle.0 / exact - 1.0).abs() < 0.07,
        "{}",
        middle.0 / exact
    );
}
