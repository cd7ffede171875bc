//! grainflow's interior point on 3D programs (second-order Coulomb cones)
//! against Clarabel on the same program.

use grainflow_contact::contacts::gather;
use grainflow_contact::{cocd, Bodies, ConicSolver, ContactSet, Scales};
use grainflow_core::{Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, PlaneWall};

const RADIUS: f64 = 5e-3;
/// ε of both solvers. The normal equations reach 1e-10 here in 12–14
/// iterations; at 1e-12 their matrix lost positive definiteness near the
/// end (iteration 22) and Clarabel would take the step over.
const TOLERANCE: f64 = 1e-10;

/// A small deterministic generator (no crate needed for a test).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Spheres on a jittered lattice over a frictional floor, nearly
/// touching, with random velocities and spins: most pairs are candidates,
/// some approach, some slide, some separate.
fn heap(friction: f64, seed: u64) -> DemSystem {
    let mut system = DemSystem::new(
        Domain {
            dimension: Dimension::Three,
            lower: Vec3::new(-0.1, -0.1, -0.01),
            upper: Vec3::new(0.1, 0.1, 0.2),
            periodic: [false; 3],
            gravity: Vec3::new(0.0, 0.0, -9.81),
        },
        ContactLaw::rigid(friction),
        vec![PlaneWall {
            name: "floor".into(),
            point: Vec3::zeros(),
            normal: Vec3::z(),
            friction,
            remove_at: None,
            two_sided: false,
        }],
        0.4 * RADIUS,
    );
    let mut random = Lcg(seed);
    let mut grains = Vec::new();
    for k in 0..4 {
        for j in 0..5 {
            for i in 0..5 {
                let jitter = |r: &mut Lcg| 0.05 * RADIUS * (r.next() - 0.5);
                let position = Vec3::new(
                    2.04 * RADIUS * i as f64 + jitter(&mut random),
                    2.04 * RADIUS * j as f64 + jitter(&mut random),
                    RADIUS * 1.02 + 2.04 * RADIUS * k as f64 + jitter(&mut random).abs(),
                );
                let velocity = Vec3::new(
                    random.next() - 0.5,
                    random.next() - 0.5,
                    random.next() - 0.5,
                ) * 0.2;
                let spin = Vec3::new(
                    random.next() - 0.5,
                    random.next() - 0.5,
                    random.next() - 0.5,
                ) * (20.0 / RADIUS)
                    * 0.01;
                grains.push(NewParticle {
                    position,
                    velocity,
                    angular_velocity: spin,
                    radius: RADIUS * (0.95 + 0.1 * random.next()),
                    density: 2500.0,
                    fixed: false,
                });
            }
        }
    }
    system.add_particles(&grains);
    system
}

/// One step's program of the heap: its candidates, bodies and scales.
fn step_of(system: &DemSystem) -> (ContactSet, Bodies, Scales) {
    let dt = 1e-3;
    let p = &system.particles;
    let n = p.n_owned;
    let free: Vec<Vec3> = (0..n)
        .map(|k| p.velocity[k] + dt * system.domain.gravity)
        .collect();
    let spin: Vec<Vec3> = (0..n).map(|k| p.angular_velocity[k]).collect();
    let (contacts, bodies) = gather(system, 0.4 * RADIUS, &free, &spin);
    let scales = Scales::of(&bodies, dt, &system.domain.gravity);
    (contacts, bodies, scales)
}

/// The program solved by `solver` at `tolerance` within `iterations`.
fn solved(
    (contacts, bodies, scales): &(ContactSet, Bodies, Scales),
    solver: ConicSolver,
    tolerance: f64,
    iterations: u32,
) -> cocd::Solution {
    cocd::solve(
        contacts,
        bodies,
        Dimension::Three,
        scales,
        tolerance,
        iterations,
        solver,
        None,
        None,
    )
    .unwrap()
}

/// The largest difference of two solutions' velocities and spins (times
/// the radius) over the bodies.
fn largest_difference(bodies: &Bodies, a: &cocd::Solution, b: &cocd::Solution) -> f64 {
    (0..bodies.len())
        .map(|k| {
            let dv = (a.velocity[k] - b.velocity[k]).norm();
            let dw = (a.spin[k] - b.spin[k]).norm() * RADIUS;
            dv.max(dw)
        })
        .fold(0.0, f64::max)
}

/// The objective ½|u − U|²_M at a solution, and |U|²_M.
fn objective(bodies: &Bodies, solution: &cocd::Solution) -> (f64, f64) {
    (0..bodies.len()).fold((0.0, 0.0), |(f, size), b| {
        let m = bodies.mass[b];
        let inertia = 1.0 / bodies.inverse_inertia[b];
        let dv = solution.velocity[b] - bodies.free_velocity[b];
        let dw = solution.spin[b] - bodies.free_spin[b];
        (
            f + 0.5 * (m * dv.norm_squared() + inertia * dw.norm_squared()),
            size + m * bodies.free_velocity[b].norm_squared()
                + inertia * bodies.free_spin[b].norm_squared(),
        )
    })
}

/// One step's program of 100 spheres (260 cones, contacts with the floor
/// among them) solved by both codes at μ = 0.3, 0.9 and 0: the objectives
/// agree to the tolerance (measured 2e-11 to 4e-11 of |U|²_M), and the
/// velocities to √ε, the distance from the optimum that an ε-optimal point
/// of this strongly convex objective is held to where contacts sit on the
/// edge of their cones (measured 6.5e-7 and 8.6e-7 V with friction, 5e-9
/// V without).
#[test]
fn the_interior_point_solves_3d_cones_as_clarabel_does() {
    for (friction, seed) in [(0.3, 1), (0.9, 2), (0.0, 3)] {
        let step = step_of(&heap(friction, seed));
        let (contacts, bodies, scales) = &step;
        assert!(contacts.len() > 200, "{} candidates", contacts.len());
        let ours = solved(&step, ConicSolver::InteriorPoint, TOLERANCE, 200);
        let reference = solved(&step, ConicSolver::Clarabel, TOLERANCE, 200);
        assert!(
            ours.fallback_reason.is_none(),
            "μ = {friction}: Clarabel took over: {:?}",
            ours.fallback_reason
        );
        let speed = scales.velocity;
        let largest = largest_difference(bodies, &ours, &reference);
        let ((f_ours, size), (f_reference, _)) =
            (objective(bodies, &ours), objective(bodies, &reference));
        eprintln!(
            "μ = {friction}: {} candidates, {} iterations against Clarabel's {}; velocities {:.1e} V apart, objectives {:.1e} of |U|²_M apart",
            contacts.len(),
            ours.iterations,
            reference.iterations,
            largest / speed,
            (f_ours - f_reference).abs() / size
        );
        assert!(
            (f_ours - f_reference).abs() < 10.0 * TOLERANCE * size,
            "μ = {friction}: objectives {f_ours:e} against {f_reference:e}"
        );
        assert!(
            largest < TOLERANCE.sqrt() * speed,
            "μ = {friction}: velocities differ by {:e} of V ({} iterations against {})",
            largest / speed,
            ours.iterations,
            reference.iterations
        );
    }
}

/// The same programs solved through their dual by the projected gradient
/// (`ConicSolver::ProjectedGradient`) against the interior point at
/// ε = 1e-9: objectives within 10 ε |U|²_M and velocities within √ε V, as
/// for the interior point against Clarabel (measured 4.0e-10 to 8.8e-10
/// and 8.3e-7 to 3.8e-6 V, in 100 to 660 iterations against 9 to 12);
/// every impulse inside Coulomb's cone to round-off, and no step handed to
/// the interior point.
#[test]
fn the_projected_gradient_solves_3d_cones_as_the_interior_point_does() {
    const EPSILON: f64 = 1e-9;
    for (friction, seed) in [(0.3, 1), (0.9, 2), (0.0, 3)] {
        let step = step_of(&heap(friction, seed));
        let (contacts, bodies, scales) = &step;
        let gradient = solved(&step, ConicSolver::ProjectedGradient, EPSILON, 20_000);
        let reference = solved(&step, ConicSolver::InteriorPoint, EPSILON, 200);
        assert!(
            gradient.fallback_reason.is_none(),
            "μ = {friction}: the interior point took over: {:?}",
            gradient.fallback_reason
        );
        let speed = scales.velocity;
        let largest = largest_difference(bodies, &gradient, &reference);
        let outside = (0..contacts.len())
            .map(|a| gradient.tangential_impulse[a].norm() - friction * gradient.normal_impulse[a])
            .fold(f64::NEG_INFINITY, f64::max);
        let ((f_gradient, size), (f_reference, _)) =
            (objective(bodies, &gradient), objective(bodies, &reference));
        eprintln!(
            "μ = {friction}: {} candidates, {} iterations against the interior point's {}; velocities {:.1e} V apart, objectives {:.1e} of |U|²_M apart, Coulomb {outside:.1e}",
            contacts.len(),
            gradient.iterations,
            reference.iterations,
            largest / speed,
            (f_gradient - f_reference).abs() / size
        );
        assert!(
            (f_gradient - f_reference).abs() < 10.0 * EPSILON * size,
            "μ = {friction}: objectives {f_gradient:e} against {f_reference:e}"
        );
        assert!(
            largest < EPSILON.sqrt() * speed,
            "μ = {friction}: velocities differ by {:e} of V",
            largest / speed
        );
        assert!(
            outside <= 1e-12 * scales.impulse(),
            "μ = {friction}: Coulomb violated by {outside:e}"
        );
    }
}

/// The projected gradient's fallbacks on a program shared among ranks (one
/// process here, a tenth of the bodies marked as the separator): a step it
/// does not solve goes to the interior point, which solves it shared;
/// where the separator's dense blocks (2.5 × 8 ns² bytes) would not fit
/// the room a rank has, the step fails instead, naming both reasons.
#[test]
fn a_shared_step_the_interior_point_cannot_take_over_fails_naming_why() {
    let system = heap(0.3, 1);
    let (contacts, bodies, scales) = step_of(&system);
    let separator: Vec<bool> = (0..bodies.len()).map(|b| b % 10 == 0).collect();
    let unknowns = 6 * separator.iter().filter(|&&s| s).count();
    let blocks = 2.5 * 8.0 * (unknowns * unknowns) as f64;
    let communicator = grainflow_core::Communicator::serial();
    let shared_step = |room: f64| {
        cocd::solve(
            &contacts,
            &bodies,
            Dimension::Three,
            &scales,
            1e-8,
            // Too few iterations for the projected gradient to solve it.
            3,
            ConicSolver::ProjectedGradient,
            Some(cocd::RankShare {
                separator: &separator,
                ids: &system.particles.id,
                communicator: &communicator,
                separator_room: Some(room),
            }),
            None,
        )
    };
    let taken_over = shared_step(2.0 * blocks).expect("the interior point solves it");
    let reason = taken_over
        .fallback_reason
        .clone()
        .expect("the interior point took over");
    assert!(reason.contains("within 3 iterations"), "{reason}");
    let reference = solved(
        &(contacts.clone(), bodies.clone(), scales),
        ConicSolver::InteriorPoint,
        1e-8,
        200,
    );
    let largest = largest_difference(&bodies, &taken_over, &reference);
    assert!(largest < 1e-6 * scales.velocity, "{largest:e}");
    let error = shared_step(0.5 * blocks).expect_err("no room for the interior point");
    assert!(
        error.contains("within 3 iterations") && error.contains("the interior point is not tried"),
        "{error}"
    );
}
