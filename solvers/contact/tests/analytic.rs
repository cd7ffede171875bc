//! Hard contact against closed-form motions: rolling and sliding on an
//! incline, a grain held by two glued grains, inelastic and elastic
//! head-on impacts, and an impact across a periodic edge.

use grainflow_contact::contacts::gather;
use grainflow_contact::{cocd, nscd, ConicSolver, HardContact, Method, Scales};
use grainflow_core::{Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, PlaneWall};

const G: f64 = 9.81;
const RADIUS: f64 = 5e-3;
const DENSITY: f64 = 2500.0;
const TOLERANCE: f64 = 1e-9;

fn domain(dimension: Dimension, gravity: Vec3, periodic_x: bool) -> Domain {
    Domain {
        dimension,
        lower: Vec3::new(-0.2, -0.2, -0.2),
        upper: Vec3::new(0.2, 0.2, 0.2),
        periodic: [periodic_x, false, false],
        gravity,
    }
}

fn grain(position: Vec3, velocity: Vec3, fixed: bool) -> NewParticle {
    NewParticle {
        position,
        velocity,
        angular_velocity: Vec3::zeros(),
        radius: RADIUS,
        density: DENSITY,
        fixed,
    }
}

fn methods() -> [Method; 2] {
    [Method::Cocd, Method::Nscd { restitution: 0.0 }]
}

fn hard(method: Method) -> HardContact {
    HardContact::new(method, TOLERANCE, 10_000, 0.1 * RADIUS)
}

/// Gauss–Seidel solves each local problem exactly: its residual is the
/// tolerance it stops at. An interior point ends with s_α z_α of the order
/// of its last barrier parameter; where a contact is about to open or close
/// (s and z both near zero, a hopping grain touching down) the natural map
/// is then of the order of its square root.
fn complementarity_bound(method: Method) -> f64 {
    match method {
        Method::Cocd => 10.0 * TOLERANCE.sqrt(),
        Method::Nscd { .. } => TOLERANCE,
    }
}

/// A grain on a plane inclined by θ, released from rest: its downhill
/// speed after `steps` steps of `dt`, and its spin.
fn on_incline(
    dimension: Dimension,
    method: Method,
    theta: f64,
    friction: f64,
    steps: usize,
    dt: f64,
) -> (f64, f64, f64) {
    let normal = Vec3::new(-theta.sin(), 0.0, 0.0)
        + match dimension {
            Dimension::Two => Vec3::new(0.0, theta.cos(), 0.0),
            Dimension::Three => Vec3::new(0.0, 0.0, theta.cos()),
        };
    let gravity = match dimension {
        Dimension::Two => Vec3::new(0.0, -G, 0.0),
        Dimension::Three => Vec3::new(0.0, 0.0, -G),
    };
    let plane = PlaneWall {
        name: "incline".into(),
        point: Vec3::zeros(),
        normal,
        friction,
        remove_at: None,
        two_sided: false,
    };
    let mut system = DemSystem::new(
        domain(dimension, gravity, false),
        ContactLaw::rigid(friction),
        vec![plane],
        0.2 * RADIUS,
    );
    system.add_particles(&[grain(RADIUS * normal, Vec3::zeros(), false)]);
    let mut contact = hard(method);
    contact.prepare(&mut system);
    let mut separation: f64 = 0.0;
    for _ in 0..steps {
        let report = contact.step(&mut system, dt).unwrap();
        assert!(
            !report.fell_back,
            "grainflow's interior point failed a step"
        );
        assert!(report.coulomb_violation < TOLERANCE && report.penetration < TOLERANCE);
        assert!(report.complementarity < complementarity_bound(method));
        let gap = system.walls[0].distance(&system.particles.position[0]) - RADIUS;
        separation = separation.max(gap);
    }
    let p = &system.particles;
    let downhill = Vec3::new(-theta.cos(), 0.0, 0.0)
        + match dimension {
            Dimension::Two => Vec3::new(0.0, -theta.sin(), 0.0),
            Dimension::Three => Vec3::new(0.0, 0.0, -theta.sin()),
        };
    let spin = p.angular_velocity[0].norm();
    (p.velocity[0].dot(&downhill), spin, separation)
}

/// Rolling without slip (μ above tan θ (1 + m r²/J)⁻¹... ): the grain
/// accelerates at g sin θ / (1 + J/(m r²)), 2/3 g sin θ for a disc and
/// 5/7 g sin θ for a sphere, and spins at v/r; both schemes give it to the
/// solver tolerance (the step is exact for a constant acceleration).
#[test]
fn rolling_down_an_incline_accelerates_at_the_rolling_rate() {
    let theta: f64 = 20f64.to_radians();
    let (steps, dt) = (100, 1e-3);
    for (dimension, ratio) in [(Dimension::Two, 2.0 / 3.0), (Dimension::Three, 5.0 / 7.0)] {
        for method in methods() {
            let (speed, spin, separation) = on_incline(dimension, method, theta, 0.5, steps, dt);
            let expected = ratio * G * theta.sin() * steps as f64 * dt;
            assert!(
                (speed / expected - 1.0).abs() < 1e-6,
                "{dimension:?} {method:?}: speed {speed} against {expected}"
            );
            assert!(
                (spin * RADIUS / speed - 1.0).abs() < 1e-6,
                "{method:?}: no slip"
            );
            assert!(
                separation < 10.0 * TOLERANCE * 2.0 * RADIUS,
                "stays on the plane"
            );
        }
    }
}

/// Sliding (μ below tan θ/3 for a disc): NSCD gives Coulomb's
/// g (sin θ − μ cos θ) and the spin-up 2 μ g cos θ / r exactly. COCD's
/// convexified constraint makes a sliding grain leave the plane at
/// μ |v_t| (eq. 9): it hops, and both the hop and the speed error vanish
/// at first order in Δt.
#[test]
fn sliding_down_an_incline_follows_coulomb_and_cocd_hops() {
    let theta: f64 = 30f64.to_radians();
    let mu = 0.1;
    let (steps, dt) = (100, 1e-3);
    let time = steps as f64 * dt;
    let expected = G * (theta.sin() - mu * theta.cos()) * time;
    let expected_spin = 2.0 * mu * G * theta.cos() / RADIUS * time;
    let (speed, spin, separation) = on_incline(
        Dimension::Two,
        Method::Nscd { restitution: 0.0 },
        theta,
        mu,
        steps,
        dt,
    );
    assert!(
        (speed / expected - 1.0).abs() < 1e-6,
        "NSCD speed {speed} against {expected}"
    );
    assert!(
        (spin / expected_spin - 1.0).abs() < 1e-6,
        "NSCD spin {spin} against {expected_spin}"
    );
    assert!(separation < 10.0 * TOLERANCE * 2.0 * RADIUS);

    // COCD: the hop separates the grain by at most μ Δt |v_t| and shifts
    // its speed from Coulomb's at first order in Δt (measured: −5.8e-5,
    // −2.9e-5, −1.45e-5 at Δt = 1e-3, 5e-4, 2.5e-4 s).
    let mut deviations = Vec::new();
    let mut separations = Vec::new();
    for (steps, dt) in [(100, 1e-3), (200, 5e-4), (400, 2.5e-4)] {
        let (speed, _, separation) = on_incline(Dimension::Two, Method::Cocd, theta, mu, steps, dt);
        assert!(separation > 0.0 && separation <= mu * dt * speed);
        deviations.push(speed / expected - 1.0);
        separations.push(separation);
    }
    for k in 1..3 {
        let order = (deviations[k - 1] / deviations[k]).log2();
        assert!((order - 1.0).abs() < 0.05, "speed error order {order}");
        let order = (separations[k - 1] / separations[k]).log2();
        assert!((order - 1.0).abs() < 0.05, "separation order {order}");
    }
}

/// A disc resting on two glued discs: no motion, and each support carries
/// m g / (2 cos φ), φ the angle of the contact normal from the vertical
/// (frictionless, so that the forces are determined: with friction a pair
/// of opposite tangential forces can be added without moving anything).
#[test]
fn grain_on_two_glued_grains_is_held_by_the_statics_forces() {
    let spacing = 1.2 * RADIUS; // half the distance between the supports
    let height = ((2.0 * RADIUS).powi(2) - spacing * spacing).sqrt();
    let cos_phi = height / (2.0 * RADIUS);
    let mut system = DemSystem::new(
        domain(Dimension::Two, Vec3::new(0.0, -G, 0.0), false),
        ContactLaw::rigid(0.0),
        vec![],
        0.2 * RADIUS,
    );
    system.add_particles(&[
        grain(Vec3::new(-spacing, 0.0, 0.0), Vec3::zeros(), true),
        grain(Vec3::new(spacing, 0.0, 0.0), Vec3::zeros(), true),
        grain(Vec3::new(0.0, height, 0.0), Vec3::zeros(), false),
    ]);
    let dt = 1e-3;
    let mut contact = hard(Method::Cocd);
    contact.prepare(&mut system);
    let top = system.index_of(2).unwrap();
    let weight = system.particles.mass[top] * G;
    let free: Vec<Vec3> = (0..3)
        .map(|k| {
            if system.particles.is_fixed(k) {
                Vec3::zeros()
            } else {
                Vec3::new(0.0, -G * dt, 0.0)
            }
        })
        .collect();
    let spins = vec![Vec3::zeros(); 3];
    let (contacts, bodies) = gather(&system, 0.1 * RADIUS, &free, &spins);
    assert_eq!(contacts.len(), 2);
    let scales = Scales::of(&bodies, dt, &Vec3::new(0.0, -G, 0.0));
    let conic = cocd::solve(
        &contacts,
        &bodies,
        Dimension::Two,
        &scales,
        TOLERANCE,
        100,
        ConicSolver::Clarabel,
        None,
        None,
    )
    .unwrap();
    let bounds: Vec<f64> = contacts.gap.iter().map(|d| -d / dt).collect();
    let zeros = vec![(0.0, Vec3::zeros()); 2];
    let (gauss_seidel, converged) = nscd::solve(
        &contacts, &bodies, &scales, &bounds, &zeros, TOLERANCE, 10_000, None,
    );
    assert!(converged);
    for solution in [&conic, &gauss_seidel] {
        for a in 0..2 {
            let force = solution.normal_impulse[a] / dt;
            assert!((force / (weight / (2.0 * cos_phi)) - 1.0).abs() < 1e-6);
            assert!(solution.tangential_impulse[a].norm() < 1e-6 * force);
        }
        // An interior point stops at s ~ ε: the grain may leave at ε L/Δt.
        assert!(solution.velocity[0].norm() < 10.0 * TOLERANCE * 2.0 * RADIUS / dt);
    }
    for _ in 0..50 {
        contact.step(&mut system, dt).unwrap();
    }
    let moved = system.particles.position[top] - Vec3::new(0.0, height, 0.0);
    assert!(moved.norm() < 1e-9 * RADIUS, "moved by {}", moved.norm());
}

/// Two equal spheres meet head on at ±v: COCD is inelastic (both stop);
/// NSCD with Newton's e sends them back at ∓e v. Momentum is conserved.
/// The same pair across a periodic edge gives the same velocities.
#[test]
fn head_on_impacts_are_inelastic_or_newtonian_and_periodic_edges_change_nothing() {
    let speed = 0.2;
    let dt = 1e-4;
    for (method, restitution) in [
        (Method::Cocd, 0.0),
        (Method::Nscd { restitution: 0.5 }, 0.5),
    ] {
        let mut finals = Vec::new();
        for (centre, periodic) in [(0.0, false), (0.2, true)] {
            let mut system = DemSystem::new(
                domain(Dimension::Three, Vec3::zeros(), periodic),
                ContactLaw::rigid(0.3),
                vec![],
                0.2 * RADIUS,
            );
            let left = centre - 1.3 * RADIUS;
            let right = centre + 1.3 * RADIUS;
            let wrap = |x: f64| if x > 0.2 { x - 0.4 } else { x };
            system.add_particles(&[
                grain(
                    Vec3::new(wrap(left), 0.0, 0.0),
                    Vec3::new(speed, 0.0, 0.0),
                    false,
                ),
                grain(
                    Vec3::new(wrap(right), 0.0, 0.0),
                    Vec3::new(-speed, 0.0, 0.0),
                    false,
                ),
            ]);
            let mut contact = hard(method);
            contact.prepare(&mut system);
            for _ in 0..100 {
                contact.step(&mut system, dt).unwrap();
            }
            let first = system.index_of(0).unwrap();
            let second = system.index_of(1).unwrap();
            let v0 = system.particles.velocity[first].x;
            let v1 = system.particles.velocity[second].x;
            assert!((v0 + v1).abs() < 1e-12, "momentum");
            assert!(
                (v0 + restitution * speed).abs() < 1e-7 * speed,
                "{method:?}: {v0} against {}",
                -restitution * speed
            );
            finals.push(v0);
        }
        assert!((finals[0] - finals[1]).abs() < 1e-9 * speed);
    }
}

/// A two-sided plate (the gate between a column and an erodible layer):
/// a grain flying at it from either side stops at its own face, inelastic
/// with COCD, at e_n = 0.5 with NSCD, and neither crosses it.
#[test]
fn grains_stop_or_bounce_on_their_own_face_of_a_two_sided_plate() {
    let speed = 0.2;
    for (method, restitution) in [
        (Method::Cocd, 0.0),
        (Method::Nscd { restitution: 0.5 }, 0.5),
    ] {
        let plate = PlaneWall {
            name: "gate".into(),
            point: Vec3::zeros(),
            normal: Vec3::x(),
            friction: 0.3,
            remove_at: None,
            two_sided: true,
        };
        let mut system = DemSystem::new(
            domain(Dimension::Three, Vec3::zeros(), false),
            ContactLaw::rigid(0.3),
            vec![plate],
            0.2 * RADIUS,
        );
        // Apart along y, so that they do not meet across the plate.
        system.add_particles(&[
            grain(
                Vec3::new(1.3 * RADIUS, 0.0, 0.0),
                Vec3::new(-speed, 0.0, 0.0),
                false,
            ),
            grain(
                Vec3::new(-1.3 * RADIUS, 3.0 * RADIUS, 0.0),
                Vec3::new(speed, 0.0, 0.0),
                false,
            ),
        ]);
        let mut contact = hard(method);
        contact.prepare(&mut system);
        for _ in 0..100 {
            let report = contact.step(&mut system, 1e-4).unwrap();
            assert!(report.penetration < TOLERANCE, "{method:?}");
        }
        for (id, side) in [(0, 1.0), (1, -1.0)] {
            let k = system.index_of(id).unwrap();
            let (x, v) = (
                system.particles.position[k].x,
                system.particles.velocity[k].x,
            );
            assert!(
                side * x >= RADIUS * (1.0 - TOLERANCE),
                "{method:?}: grain {id} at {x}"
            );
            assert!(
                (side * v - restitution * speed).abs() < 1e-9,
                "{method:?}: grain {id} leaves at {v}"
            );
        }
    }
}
