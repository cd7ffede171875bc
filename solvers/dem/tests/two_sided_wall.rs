//! A two-sided wall, a thin plate that grains touch from either side (the
//! gate between a column and an erodible layer): each grain bounces off
//! the face on its own side with the law's restitution and never crosses.

use grainflow_core::{Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, NormalCalibration, NormalStiffness, PlaneWall};

const RADIUS: f64 = 1e-3;
const RESTITUTION: f64 = 0.8;

/// Two grains, one on each side of a plate at x = 0, flying at it at
/// 0.5 m/s, 6 radii apart along the plate; no gravity.
fn plate_between_two_grains(two_sided: bool) -> DemSystem {
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::new(-0.01, -0.01, -0.01),
        upper: Vec3::new(0.01, 0.01, 0.01),
        periodic: [false; 3],
        gravity: Vec3::zeros(),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(RESTITUTION, 1e-4, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.0,
        rolling_friction: 0.0,
    };
    let plate = PlaneWall {
        name: "gate".into(),
        point: Vec3::zeros(),
        normal: Vec3::x(),
        friction: 0.0,
        remove_at: None,
        two_sided,
    };
    let mut system = DemSystem::new(domain, law, vec![plate], 0.2 * RADIUS);
    // Apart along y, so that they do not meet across the plate.
    let grain = |x: f64, v: f64| NewParticle {
        position: Vec3::new(x, x, 0.0),
        velocity: Vec3::new(v, 0.0, 0.0),
        angular_velocity: Vec3::zeros(),
        radius: RADIUS,
        density: 2500.0,
        fixed: false,
    };
    system.add_particles(&[grain(3.0 * RADIUS, -0.5), grain(-3.0 * RADIUS, 0.5)]);
    system
}

/// Where the grain created `k`-th is now (the DEM sorts its grains).
fn index(system: &DemSystem, k: usize) -> usize {
    let id = k as u64;
    system.particles.id.iter().position(|&i| i == id).unwrap()
}

#[test]
fn grains_on_either_side_of_a_two_sided_wall_bounce_off_their_own_face() {
    let mut system = plate_between_two_grains(true);
    let mut closest = [f64::MAX; 2];
    for _ in 0..5_000 {
        system.step(2e-6);
        for k in 0..2 {
            let x = system.particles.position[index(&system, k)].x;
            closest[k] = closest[k].min(x.abs());
            // Never across the plate.
            assert!(x * [1.0, -1.0][k] > 0.0, "grain {k} crossed to x = {x}");
        }
    }
    let v = [0, 1].map(|k| system.particles.velocity[index(&system, k)].x);
    // Out again on its own side at e_n of the impact speed.
    assert!((v[0] / 0.5 - RESTITUTION).abs() < 0.004, "{v:?}");
    assert!((v[1] / -0.5 - RESTITUTION).abs() < 0.004, "{v:?}");
    assert!(
        closest.iter().all(|&c| c < RADIUS && c > 0.9 * RADIUS),
        "{closest:?}"
    );
}

#[test]
fn a_one_sided_wall_pushes_a_grain_behind_it_through_to_its_front() {
    // The grain behind a one-sided wall overlaps it by more than its size:
    // the wall throws it forwards (why a gate with grains on both sides
    // must be two-sided).
    let mut system = plate_between_two_grains(false);
    system.step(2e-6);
    let behind = system.particles.velocity[index(&system, 1)].x;
    assert!(behind > 1.0, "{behind}");
}
