//! Hard contact in 3D against closed-form motions, to 1e-10: a sphere
//! rolling and sliding down a plane inclined along an oblique direction,
//! a sphere thrown along a floor that rolls on at 5/7 of its speed, one
//! with backspin that stops dead, and resting stacks whose contact forces
//! statics fixes.
//!
//! Each scheme is exact for these motions, not merely consistent: the
//! step is exact for a constant acceleration, and an impulse at the
//! contact point below the centre keeps the angular momentum about that
//! point, m r n × v + J ω. What is left is the solvers' tolerance.

use grainflow_contact::contacts::{gather, Partner};
use grainflow_contact::{cocd, nscd, ConicSolver, HardContact, Method, Scales};
use grainflow_core::{Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, PlaneWall};

const G: f64 = 9.81;
const RADIUS: f64 = 5e-3;
const DENSITY: f64 = 2500.0;
/// The solvers' tolerance ε: the normal equations of grainflow's interior
/// point reach 1e-10 on these programs; Gauss–Seidel stops at it.
const TOLERANCE: f64 = 1e-10;
/// Gauss–Seidel stops on its velocity residual; the forces it leaves in a
/// chain of contacts are further off by the chain's conditioning
/// (measured: 8.5e-8 in the column of four at ε = 1e-10, 1.1e-10 on
/// three supports at 1e-13, 2.3e-12 at most at 1e-15), so statics runs it
/// tighter.
const GAUSS_SEIDEL_STATICS: f64 = 1e-15;
/// What the closed forms are held to (relative).
const CLOSED_FORM: f64 = 1e-10;

/// The four ways a step can be solved: COCD on grainflow's interior
/// point, on its projected gradient and on Clarabel, and NSCD (inelastic).
fn schemes() -> [HardContact; 4] {
    let with = |method, solver| {
        // The projected gradient stops at its tolerance, where the interior
        // point's last Newton step lands far inside it; started from the
        // last step's impulses, it left 1.1e-9 of the thrown sphere's
        // rolling speed at ε (60 steps): held to the closed forms at ε/100.
        let tolerance = match solver {
            ConicSolver::ProjectedGradient => 0.01 * TOLERANCE,
            _ => TOLERANCE,
        };
        let mut contact = HardContact::new(method, tolerance, 10_000, 0.1 * RADIUS);
        contact.conic_solver = solver;
        contact
    };
    [
        with(Method::Cocd, ConicSolver::InteriorPoint),
        with(Method::Cocd, ConicSolver::ProjectedGradient),
        with(Method::Cocd, ConicSolver::Clarabel),
        with(
            Method::Nscd { restitution: 0.0 },
            ConicSolver::InteriorPoint,
        ),
    ]
}

fn name(contact: &HardContact) -> String {
    format!("{:?} on {}", contact.method, contact.conic_solver.name())
}

fn grain(position: Vec3, velocity: Vec3, angular_velocity: Vec3, fixed: bool) -> NewParticle {
    NewParticle {
        position,
        velocity,
        angular_velocity,
        radius: RADIUS,
        density: DENSITY,
        fixed,
    }
}

/// A 3D box of 40 cm around the origin under gravity −g ẑ, with one plane
/// through the origin of unit normal `normal` and friction `friction`.
fn on_plane(normal: Vec3, friction: f64, grains: &[NewParticle]) -> DemSystem {
    let plane = PlaneWall {
        name: "plane".into(),
        point: Vec3::zeros(),
        normal,
        friction,
        remove_at: None,
        two_sided: false,
    };
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::new(-0.2, -0.2, -0.2),
        upper: Vec3::new(0.2, 0.2, 0.2),
        periodic: [false; 3],
        gravity: Vec3::new(0.0, 0.0, -G),
    };
    let mut system = DemSystem::new(
        domain,
        ContactLaw::rigid(friction),
        vec![plane],
        0.2 * RADIUS,
    );
    system.add_particles(grains);
    system
}

/// Runs `steps` steps of `dt`, holding every step's certificates below ε
/// (and grainflow's interior point to its own steps); returns the largest
/// gap that opened between the grain and the plane.
fn run(contact: &mut HardContact, system: &mut DemSystem, steps: usize, dt: f64) -> f64 {
    contact.prepare(system);
    let mut separation: f64 = 0.0;
    for _ in 0..steps {
        let report = contact.step(system, dt).unwrap();
        assert!(!report.fell_back, "{}: fell back", name(contact));
        assert!(
            report.coulomb_violation < TOLERANCE && report.penetration < TOLERANCE,
            "{}: {report:?}",
            name(contact)
        );
        let gap = system.walls[0].distance(&system.particles.position[0]) - RADIUS;
        separation = separation.max(gap);
    }
    separation
}

/// Asserts that the grain of `system` moves at `velocity` and spins at
/// `spin` to [`CLOSED_FORM`], printing the errors.
fn holds_motion(contact: &HardContact, system: &DemSystem, velocity: Vec3, spin: Vec3, gap: f64) {
    let p = &system.particles;
    let v = relative(p.velocity[0], velocity);
    let w = relative(p.angular_velocity[0], spin);
    println!(
        "{}: velocity {v:.1e}, spin {w:.1e}, gap {gap:.1e} m",
        name(contact)
    );
    assert!(
        v < CLOSED_FORM && w < CLOSED_FORM,
        "{}: {v} {w}",
        name(contact)
    );
}

fn relative(value: Vec3, expected: Vec3) -> f64 {
    (value - expected).norm() / expected.norm()
}

/// A plane inclined by θ whose steepest descent points along azimuth ψ
/// in the horizontal plane: its unit normal and its unit downhill vector.
fn incline(theta: f64, psi: f64) -> (Vec3, Vec3) {
    let across = Vec3::new(psi.cos(), psi.sin(), 0.0);
    let normal = -across * theta.sin() + Vec3::z() * theta.cos();
    let downhill = -across * theta.cos() - Vec3::z() * theta.sin();
    (normal, downhill)
}

/// Rolling without slip (μ = 0.5 > 2/7 tan θ): the sphere accelerates at
/// 5/7 g sin θ straight down the slope, whatever the slope's azimuth, and
/// spins at ω = n × v / r. Every scheme holds it to 1e-10 (measured after
/// 0.1 s, velocity and spin: 4e-15 with NSCD, 4e-12 and 1.1e-11 on
/// grainflow's interior point, 9e-12 and 2.2e-11 on Clarabel).
#[test]
fn a_sphere_rolls_down_an_oblique_incline_at_five_sevenths_of_g_sin_theta() {
    let (theta, psi) = (20f64.to_radians(), 35f64.to_radians());
    let (normal, downhill) = incline(theta, psi);
    let (steps, dt) = (100, 1e-3);
    let velocity = downhill * (5.0 / 7.0 * G * theta.sin() * steps as f64 * dt);
    let spin = normal.cross(&velocity) / RADIUS;
    for mut contact in schemes() {
        let start = grain(RADIUS * normal, Vec3::zeros(), Vec3::zeros(), false);
        let mut system = on_plane(normal, 0.5, &[start]);
        let separation = run(&mut contact, &mut system, steps, dt);
        holds_motion(&contact, &system, velocity, spin, separation);
        // An interior point ends a step with gaps of the order of ε
        // diameters: the sphere may leave at ε d/Δt.
        assert!(
            separation < 10.0 * TOLERANCE * 2.0 * RADIUS,
            "{}: stays on",
            name(&contact)
        );
    }
}

/// Sliding (μ = 0.1 < 2/7 tan 40°): NSCD gives Coulomb's acceleration
/// g (sin θ − μ cos θ) down the slope and the spin-up 5 μ g cos θ / (2 r)
/// about n × downhill to 1e-10. COCD's convexified cone lifts a sliding
/// sphere off the plane by at most μ |v_t| Δt in a step (eq. 9), and its
/// speed then lags Coulomb's at first order in Δt.
#[test]
fn a_sphere_slides_down_a_steep_oblique_incline_by_coulombs_law() {
    let (theta, psi) = (40f64.to_radians(), -60f64.to_radians());
    let (normal, downhill) = incline(theta, psi);
    let mu = 0.1;
    let deviation = |contact: &mut HardContact, steps: usize, dt: f64| {
        let time = steps as f64 * dt;
        let velocity = downhill * (G * (theta.sin() - mu * theta.cos()) * time);
        let spin = normal.cross(&downhill) * (2.5 * mu * G * theta.cos() / RADIUS * time);
        let start = grain(RADIUS * normal, Vec3::zeros(), Vec3::zeros(), false);
        let mut system = on_plane(normal, mu, &[start]);
        let separation = run(contact, &mut system, steps, dt);
        let p = &system.particles;
        (
            relative(p.velocity[0], velocity),
            relative(p.angular_velocity[0], spin),
            separation,
            p.velocity[0].norm(),
        )
    };
    let [_, _, _, mut nscd] = schemes();
    let (v, w, separation, _) = deviation(&mut nscd, 100, 1e-3);
    println!("NSCD: velocity {v:.1e}, spin {w:.1e}, gap {separation:.1e} m");
    assert!(v < CLOSED_FORM && w < CLOSED_FORM && separation < CLOSED_FORM * RADIUS);

    let [mut cocd, _, _, _] = schemes();
    let mut errors = Vec::new();
    for (steps, dt) in [(100, 1e-3), (200, 5e-4)] {
        let (v, _, separation, speed) = deviation(&mut cocd, steps, dt);
        println!("COCD at Δt = {dt}: velocity {v:.2e}, gap {separation:.2e} m");
        assert!(separation > 0.0 && separation <= mu * dt * speed);
        errors.push(v);
    }
    let order = (errors[0] / errors[1]).log2();
    assert!((order - 1.0).abs() < 0.05, "COCD's lag is of order {order}");
}

/// A sphere thrown along a level floor (μ = 0.2) at v₀ without spin slides,
/// slows at μ g and spins up until its contact point stops, at
/// t = 2 v₀/(7 μ g); it then rolls on at 5/7 v₀, in the direction it was
/// thrown. Any scheme whose impulses act at the contact point keeps
/// m r v + J ω, so the 5/7 is exact (measured: 2e-15). COCD's sphere hops
/// while it slides (it rose 1.6e-4 m, 3 % of its radius) and lands
/// rolling.
#[test]
fn a_sphere_thrown_along_a_floor_rolls_on_at_five_sevenths_of_its_speed() {
    let thrown = Vec3::new(0.24, -0.18, 0.0);
    let rolling = thrown * (5.0 / 7.0);
    let spin = Vec3::z().cross(&rolling) / RADIUS;
    // Rolling from 0.0156 s; 60 steps of 1 ms.
    for mut contact in schemes() {
        let start = grain(RADIUS * Vec3::z(), thrown, Vec3::zeros(), false);
        let mut system = on_plane(Vec3::z(), 0.2, &[start]);
        let separation = run(&mut contact, &mut system, 60, 1e-3);
        holds_motion(&contact, &system, rolling, spin, separation);
    }
}

/// A sphere thrown at v₀ with the backspin ω₀ = 5 v₀/(2 r) about −n × v₀
/// carries no angular momentum about its contact point: friction stops its
/// slide and its spin together at t = v₀/(μ g), and it stays. NSCD's steps
/// take μ g Δt off the speed each: it stops after ⌈v₀/(μ g Δt)⌉ steps,
/// having covered Δt Σ_k max(v₀ − k μ g Δt, 0) (v₀²/(2 μ g) as Δt → 0).
#[test]
fn a_sphere_with_backspin_stops_dead_where_its_slide_ends() {
    let (v0, mu, dt) = (0.2, 0.25, 1e-3);
    let direction = Vec3::new(0.6, 0.8, 0.0);
    let backspin = -Vec3::z().cross(&direction) * (2.5 * v0 / RADIUS);
    let start = Vec3::new(0.0, 0.0, RADIUS);
    let mut covered = 0.0;
    for k in 1..=200 {
        covered += dt * (v0 - k as f64 * mu * G * dt).max(0.0);
    }
    for mut contact in schemes() {
        let thrown = grain(start, direction * v0, backspin, false);
        let mut system = on_plane(Vec3::z(), mu, &[thrown]);
        run(&mut contact, &mut system, 200, dt);
        let p = &system.particles;
        let (v, w) = (
            p.velocity[0].norm() / v0,
            p.angular_velocity[0].norm() * RADIUS / v0,
        );
        let moved = p.position[0] - start;
        println!(
            "{}: speed {v:.1e} v0, spin {w:.1e} v0/r, stopped {:.4e} m from the start",
            name(&contact),
            moved.norm()
        );
        assert!(
            v < CLOSED_FORM && w < CLOSED_FORM,
            "{}: {v} {w}",
            name(&contact)
        );
        if matches!(contact.method, Method::Nscd { .. }) {
            assert!(relative(moved, direction * covered) < CLOSED_FORM);
        }
        // Every scheme stops within a step's travel of the continuous v₀²/(2 μ g).
        assert!((moved.norm() - v0 * v0 / (2.0 * mu * G)).abs() < v0 * dt);
    }
}

/// Stacks at rest on a frictionless floor (the forces are then fixed by
/// statics): a column of four spheres, whose k-th contact from the top
/// carries k m g, and a sphere on three glued spheres at the corners of an
/// equilateral triangle, each support carrying m g/(3 cos φ). The
/// programs' impulses over Δt give these forces to 1e-10 in all three
/// solvers (measured: 2.9e-11 on grainflow's interior point, 1.3e-11 on
/// Clarabel, 2.3e-12 with Gauss–Seidel), and 50 steps move nothing by more than ε diameters (the
/// overlap the certificates allow).
#[test]
fn resting_stacks_carry_the_weights_statics_gives() {
    let dt = 1e-3;
    let column: Vec<NewParticle> = (0..4)
        .map(|k| {
            grain(
                Vec3::new(0.0, 0.0, RADIUS * (1.0 + 2.0 * k as f64)),
                Vec3::zeros(),
                Vec3::zeros(),
                false,
            )
        })
        .collect();
    // Supports 1.2 r from the axis, their centres r above the floor.
    let spread = 1.2 * RADIUS;
    let rise = ((2.0 * RADIUS).powi(2) - spread * spread).sqrt();
    let cos_phi = rise / (2.0 * RADIUS);
    let mut tetrahedron: Vec<NewParticle> = (0..3)
        .map(|k| {
            let angle = 2.0 * std::f64::consts::PI * k as f64 / 3.0;
            let at = Vec3::new(spread * angle.cos(), spread * angle.sin(), RADIUS);
            grain(at, Vec3::zeros(), Vec3::zeros(), true)
        })
        .collect();
    tetrahedron.push(grain(
        Vec3::new(0.0, 0.0, RADIUS + rise),
        Vec3::zeros(),
        Vec3::zeros(),
        false,
    ));

    for (stack, label) in [(column, "column"), (tetrahedron, "on three")] {
        let system = on_plane(Vec3::z(), 0.0, &stack);
        let p = &system.particles;
        let n = p.n_owned;
        let free: Vec<Vec3> = (0..n)
            .map(|k| {
                if p.is_fixed(k) {
                    Vec3::zeros()
                } else {
                    Vec3::new(0.0, 0.0, -G * dt)
                }
            })
            .collect();
        let (contacts, bodies) = gather(&system, 0.1 * RADIUS, &free, &vec![Vec3::zeros(); n]);
        let scales = Scales::of(&bodies, dt, &Vec3::new(0.0, 0.0, -G));
        let weight = p.mass[0] * G;
        // What statics gives each contact: in the column, the weight of
        // the grains from its upper one up.
        let expected: Vec<f64> = (0..contacts.len())
            .map(|a| {
                let mut upper = p.position[contacts.grain[a] as usize].z;
                if let Partner::Grain(j) = contacts.partner[a] {
                    upper = upper.max(p.position[j as usize].z);
                }
                let carried = (0..n).filter(|&k| p.position[k].z > upper - RADIUS).count();
                match label {
                    "column" => carried as f64 * weight,
                    _ => weight / (3.0 * cos_phi),
                }
            })
            .collect();
        let solutions = [
            (
                "COCD on grainflow's interior point",
                ConicSolver::InteriorPoint,
            ),
            (
                "COCD on grainflow's projected gradient",
                ConicSolver::ProjectedGradient,
            ),
            ("COCD on Clarabel", ConicSolver::Clarabel),
        ]
        .map(|(what, solver)| {
            let iterations = match solver {
                ConicSolver::ProjectedGradient => 100_000,
                _ => 100,
            };
            let solution = cocd::solve(
                &contacts,
                &bodies,
                Dimension::Three,
                &scales,
                TOLERANCE,
                iterations,
                solver,
                None,
                None,
            )
            .unwrap();
            assert!(
                solution.fallback_reason.is_none(),
                "{what}: {:?}",
                solution.fallback_reason
            );
            (what, solution)
        });
        let bounds: Vec<f64> = contacts.gap.iter().map(|d| -d / dt).collect();
        let zeros = vec![(0.0, Vec3::zeros()); contacts.len()];
        let (gauss_seidel, converged) = nscd::solve(
            &contacts,
            &bodies,
            &scales,
            &bounds,
            &zeros,
            GAUSS_SEIDEL_STATICS,
            100_000,
            None,
        );
        assert!(converged);
        for (what, solution) in solutions
            .iter()
            .map(|(w, s)| (*w, s))
            .chain([("NSCD", &gauss_seidel)])
        {
            let worst = (0..contacts.len())
                .map(|a| (solution.normal_impulse[a] / dt / expected[a] - 1.0).abs())
                .fold(0.0, f64::max);
            println!("{label}, {what}: forces within {worst:.1e}");
            assert!(worst < CLOSED_FORM, "{label}, {what}: {worst}");
        }
        assert_eq!(contacts.len(), if label == "column" { 4 } else { 3 });
        for mut contact in schemes() {
            let mut system = on_plane(Vec3::z(), 0.0, &stack);
            run(&mut contact, &mut system, 50, dt);
            for k in 0..n {
                let now = system.index_of(k as u64).unwrap();
                let moved = system.particles.position[now] - p.position[k];
                assert!(
                    moved.norm() < TOLERANCE * 2.0 * RADIUS,
                    "{label}, {}: {k} moved {}",
                    name(&contact),
                    moved.norm()
                );
            }
        }
    }
}
