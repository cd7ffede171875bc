//! Contacts that start at a gap (grains in a fluid touch a cell early, so
//! that their forced layers do not seal the fluid between them): the
//! spring acts from the shifted surfaces, with the same restitution.

use grainflow_core::{Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, NormalCalibration, NormalStiffness, PlaneWall};

const RADIUS: f64 = 1e-3;
const GAP: f64 = 2e-4;

fn dropped(contact_gap: f64) -> DemSystem {
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::new(-0.01, -0.01, 0.0),
        upper: Vec3::new(0.01, 0.01, 0.02),
        periodic: [false; 3],
        gravity: Vec3::new(0.0, 0.0, -9.81),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(0.8, 1e-4, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.0,
        rolling_friction: 0.0,
    };
    let floor = PlaneWall {
        name: "floor".into(),
        point: Vec3::zeros(),
        normal: Vec3::z(),
        friction: 0.0,
        remove_at: None,
        two_sided: false,
    };
    let mut system = DemSystem::new(domain, law, vec![floor], 0.2 * RADIUS);
    system.contact_gap = contact_gap;
    system.add_particles(&[NewParticle {
        position: Vec3::new(0.0, 0.0, 3.0 * RADIUS),
        velocity: Vec3::new(0.0, 0.0, -0.5),
        angular_velocity: Vec3::zeros(),
        radius: RADIUS,
        density: 2500.0,
        fixed: false,
    }]);
    system
}

/// The first rebound keeps e_n of the impact speed with or without the
/// gap (to 0.5 %), and the sphere turns around a gap higher.
#[test]
fn shifted_contact_keeps_the_restitution_and_turns_a_gap_higher() {
    let mut turning = [0.0; 2];
    let mut restitution = [0.0; 2];
    for (k, gap) in [0.0, GAP].into_iter().enumerate() {
        let mut system = dropped(gap);
        let dt = 2e-6;
        let mut impact: f64 = 0.0;
        let mut lowest = f64::MAX;
        let mut previous = system.particles.velocity[0].z;
        for _ in 0..20_000 {
            system.step(dt);
            let v = system.particles.velocity[0].z;
            lowest = lowest.min(system.particles.position[0].z);
            impact = impact.min(v);
            if previous > 0.0 && v < previous {
                // Top of the first rebound's velocity: contact has ended.
                restitution[k] = previous / -impact;
                break;
            }
            previous = v;
        }
        turning[k] = lowest;
    }
    println!("restitution {restitution:?}, lowest centre {turning:?}");
    for e in restitution {
        assert!((e - 0.8).abs() < 0.004, "{e}");
    }
    assert!(
        ((turning[1] - turning[0]) - GAP).abs() < 0.01 * GAP,
        "{turning:?}"
    );
}
