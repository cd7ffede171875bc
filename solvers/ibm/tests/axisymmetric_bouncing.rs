//! A sphere settling onto a wall on the axis of a cylinder, in (r, z)
//! (Izard et al. 2014, §4.1): the DEM's contact with the floor and the
//! lubrication film of eq. 19 inside the (r, z) coupled step.

use grainflow_core::{Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{
    ContactLaw, DemSystem, Lubrication, NormalCalibration, NormalStiffness, PlaneWall,
};
use grainflow_fluid::axisymmetric::{AxialEnd, AxisymmetricFlow, OuterWall, RzGrid, RzWalls};
use grainflow_ibm::axisymmetric::AxisymmetricCoupledSystem;
use grainflow_ibm::Coupling;

const DIAMETER: f64 = 6e-3;
const FLUID_DENSITY: f64 = 1000.0;
const PARTICLE_DENSITY: f64 = 8000.0;
const RESTITUTION: f64 = 0.97;

/// `cases/bouncing_sphere.toml` in (r, z): a sphere of 6 mm, ρp/ρ = 8,
/// released 10 D above a no-slip floor in a cylinder of radius 4 D (free
/// slip elsewhere), `per` cells per diameter, viscosity `viscosity`
/// (Pa s), lubrication with η/R = 2e-4 or none.
fn bouncing_on_axis(per: usize, viscosity: f64, lubricated: bool) -> AxisymmetricCoupledSystem {
    let radius = 4.0 * DIAMETER;
    let height = 13.0 * DIAMETER;
    let cells = [4 * per, 13 * per];
    let grid = RzGrid::uniform(cells, radius, [0.0, height]).unwrap();
    let walls = RzWalls::new(OuterWall::FreeSlip, [AxialEnd::NoSlip, AxialEnd::FreeSlip]).unwrap();
    let flow = AxisymmetricFlow::new(grid, walls, viscosity / FLUID_DENSITY).unwrap();
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::new(-radius, -radius, 0.0),
        upper: Vec3::new(radius, radius, height),
        periodic: [false; 3],
        gravity: Vec3::new(0.0, 0.0, -9.81),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(RESTITUTION, 1e-4, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.25,
        rolling_friction: 0.0,
    };
    let floor = PlaneWall {
        name: "floor".into(),
        point: Vec3::zeros(),
        normal: Vec3::new(0.0, 0.0, 1.0),
        friction: 0.25,
        remove_at: None,
        two_sided: false,
    };
    let mut dem = DemSystem::new(domain, law, vec![floor], 0.1 * DIAMETER);
    if lubricated {
        dem.lubrication = Some(Lubrication {
            viscosity,
            roughness: 2e-4,
            range: 0.5,
        });
    }
    dem.add_particles(&[NewParticle {
        position: Vec3::new(0.0, 0.0, 10.5 * DIAMETER),
        velocity: Vec3::zeros(),
        angular_velocity: Vec3::zeros(),
        radius: 0.5 * DIAMETER,
        density: PARTICLE_DENSITY,
        fixed: false,
    }]);
    AxisymmetricCoupledSystem::new(flow, dem, FLUID_DENSITY, Coupling::InnerFluidMomentum, 2e-5)
        .unwrap()
}

/// The speed the film of eq. 19 would still take from the grain on its
/// way out from where it is (zero without a film or beyond its range).
fn film_loss_to_come(dem: &DemSystem) -> f64 {
    let p = &dem.particles;
    dem.lubrication.map_or(0.0, |film| {
        let gap = p.position[0].z - p.radius[0] - dem.contact_gap;
        film.speed_lost_leaving_wall(gap, p.radius[0], p.inverse_mass[0])
    })
}

/// The Stokes number `(ρp + ρ/2) V_T D / (9 μ)` and `e/e_n = V_R/(V_T e_n)`
/// of a run to 0.3 s with steps of CFL ≤ 1: `V_T` the largest settling
/// speed before the first contact, `V_R` the largest rising speed after
/// it, read after every stage, less what the film still takes from it on
/// its way out (the rebound as the experiments see it once the grain has
/// crossed the film, as `cases/bouncing_sphere.toml` reads it).
fn bounce(per: usize, viscosity: f64, lubricated: bool) -> (f64, f64) {
    let mut system = bouncing_on_axis(per, viscosity, lubricated);
    let dx = DIAMETER / per as f64;
    let (mut approach, mut rebound): (f64, f64) = (0.0, 0.0);
    let mut touched = false;
    while system.flow.time < 0.3 {
        let grain = system.dem.particles.velocity[0].z.abs();
        let dt = (dx / grain)
            .min(system.flow.time_step_for_cfl(1.0))
            .min(6e-4);
        let mut rise: f64 = 0.0;
        let report = system
            .step_observed(dt, |dem| {
                rise = rise.max(dem.particles.velocity[0].z - film_loss_to_come(dem))
            })
            .unwrap();
        if !touched {
            approach = approach.max(-system.dem.particles.velocity[0].z);
        }
        touched |= report.dem.max_overlap_ratio > 0.0;
        if touched {
            rebound = rebound.max(rise);
        }
    }
    let stokes = (PARTICLE_DENSITY + 0.5 * FLUID_DENSITY) * approach * DIAMETER / (9.0 * viscosity);
    (stokes, rebound / approach / RESTITUTION)
}

/// Measured at D/Δx = 10 (1 to 2 s each on two cores), the paper's forcing
/// reaching the floor: St 5.2 lands with e/e_n below 0.05 (the
/// experiments' fit exp(−35/St) gives 0.002); St 163, read through the
/// film, within ±0.1 of the fit (the experiments' scatter; measured 0.897
/// against 0.807, +0.090; with the first cells at the floor left to the
/// fluid, 0.882); without the film at St ≈ 41 the sphere rebounds nearly
/// as in a dry contact (0.922, above 0.9). The sweep at D/Δx = 20 and 40
/// is in docs/validation.md, section 10.
#[test]
fn a_bounce_on_the_axis_follows_the_experiments_with_the_film_of_eq_19() {
    let (stokes, restitution) = bounce(10, 0.3, true);
    println!("St {stokes:.1}: e/e_n {restitution:.3}");
    assert!(
        stokes < 8.0 && restitution < 0.05,
        "St {stokes}: {restitution}"
    );
    let (stokes, restitution) = bounce(10, 0.02, true);
    let fit = (-35.0 / stokes).exp();
    println!("St {stokes:.1}: e/e_n {restitution:.3} against {fit:.3}");
    assert!(
        (restitution - fit).abs() < 0.1,
        "St {stokes}: {restitution} against {fit}"
    );
    let (stokes, restitution) = bounce(10, 0.0659, false);
    println!("St {stokes:.1} without the film: e/e_n {restitution:.3}");
    assert!(restitution > 0.9, "St {stokes}: {restitution}");
}
