//! A sphere released from rest in a closed box of fluid (Izard et al. 2014,
//! section 3.1, reduced): the start of its fall against the added-mass
//! estimate of eq. 20.

use grainflow_core::{Communicator, Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, NormalCalibration, NormalStiffness};
use grainflow_fluid::{Boundaries, BoundaryCondition, FlowSolver, Grid};
use grainflow_ibm::{CoupledSystem, Coupling};

/// ρ_p/ρ = 4, Ar = ρ(ρ_p − ρ) g D³/μ² = 800, D = g = ρ = 1.
fn falling_sphere(
    cells_per_diameter: usize,
    extent: [f64; 3],
    coupling: Coupling,
) -> CoupledSystem {
    let (diameter, density_ratio, archimedes): (f64, f64, f64) = (1.0, 4.0, 800.0);
    let viscosity = ((density_ratio - 1.0) * diameter.powi(3) / archimedes).sqrt();
    let cells = extent.map(|e| (e * cells_per_diameter as f64).round() as usize);
    let grid = Grid::new(Dimension::Three, cells, [0.0; 3], extent);
    let slip = BoundaryCondition::FreeSlip;
    let walls = Boundaries::periodic()
        .with(0, slip, slip)
        .with(1, slip, slip)
        .with(2, slip, slip);
    let flow = FlowSolver::new(grid, walls, viscosity, Communicator::serial()).unwrap();
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::zeros(),
        upper: Vec3::from(extent),
        periodic: [false; 3],
        gravity: Vec3::new(0.0, 0.0, -1.0),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(0.9, 1e-3, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.25,
        rolling_friction: 0.0,
    };
    let mut dem = DemSystem::new(domain, law, Vec::new(), 0.1);
    dem.add_particles(&[NewParticle {
        position: Vec3::new(0.5 * extent[0], 0.5 * extent[1], extent[2] - 2.5 * diameter),
        velocity: Vec3::zeros(),
        angular_velocity: Vec3::zeros(),
        radius: 0.5 * diameter,
        density: density_ratio,
        fixed: false,
    }]);
    CoupledSystem::new(flow, dem, 1.0, coupling, 1e-3)
}

#[test]
#[ignore]
fn probe_terminal() {
    let cells: usize = std::env::var("CELLS")
        .map(|c| c.parse().unwrap())
        .unwrap_or(8);
    let width: f64 = std::env::var("WIDTH")
        .map(|c| c.parse().unwrap())
        .unwrap_or(6.0);
    let height: f64 = std::env::var("HEIGHT")
        .map(|c| c.parse().unwrap())
        .unwrap_or(20.0);
    let cfl: f64 = std::env::var("CFL")
        .map(|c| c.parse().unwrap())
        .unwrap_or(0.5);
    let mut system = falling_sphere(cells, [width, width, height], Coupling::InnerFluidMomentum);
    let dt = cfl / (1.25 * cells as f64);
    let start = std::time::Instant::now();
    let mut t_print = 0.0;
    while system.dem.particles.position[0].z > 3.0 {
        system.step(dt).unwrap();
        if system.flow.time >= t_print {
            let v = -system.dem.particles.velocity[0].z;
            let nu = (3.0f64 / 800.0).sqrt();
            println!(
                "t {:.2} z {:.3} v {:.5} Re {:.3} wall {:.1}",
                system.flow.time,
                system.dem.particles.position[0].z,
                v,
                v / nu,
                start.elapsed().as_secs_f64()
            );
            t_print += 1.0;
        }
    }
}
