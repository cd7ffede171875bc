//! A sphere driven towards a wall through a viscous film, with the
//! lubrication force alone (eq. 19 against a wall: `−6π μ R² v / (h + η)`):
//! `m dv/dt = −6π μ R² v / (h + η)` with `v = dh/dt` integrates to
//!
//! ```text
//! v(h) = v₀ + (6π μ R² / m) ln((h₀ + η) / (h + η))      (v < 0 approaching),
//! ```
//!
//! so a sphere launched at speed `|v₀|` from the edge of the range stops
//! at the gap `h* = (h₀ + η) exp(−m |v₀| / (6π μ R²)) − η`.
//!
//! A sphere fast enough to reach the wall loses `c L` on the way in and
//! again on the way out (`c = 6π μ R² / m`, `L = ln((h₀ + η) / η)`), and
//! the contact returns `e_n` of what is left: the rebound over the dry one,
//!
//! ```text
//! e / e_n = 1 − (1 + 1/e_n) L / St,   St = m |v₀| / (6π μ R²),
//! ```
//!
//! the thin-film restitution of the film law alone (no rebound below
//! `St_c = (1 + 1/e_n) L`).

use grainflow_core::{Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{
    ContactLaw, DemSystem, Lubrication, NormalCalibration, NormalStiffness, PlaneWall,
};
use std::f64::consts::PI;

const RADIUS: f64 = 1e-3;
const DENSITY: f64 = 2500.0;
const VISCOSITY: f64 = 1.0;
const ROUGHNESS: f64 = 1e-3;
const CONTACT_TIME: f64 = 1e-5;

/// The sphere at the edge of the lubrication range (gap R/2), moving
/// towards the floor at `speed`; no gravity, no fluid other than the film.
fn approach(speed: f64, viscosity: f64, roughness: f64) -> DemSystem {
    approach_with_contact_gap(speed, viscosity, roughness, 0.0)
}

/// [`approach`] with contacts starting at a gap `contact_gap` from the wall
/// (the sphere released at the edge of the film's range from there).
fn approach_with_contact_gap(
    speed: f64,
    viscosity: f64,
    roughness: f64,
    contact_gap: f64,
) -> DemSystem {
    let floor = PlaneWall {
        name: "floor".into(),
        point: Vec3::zeros(),
        normal: Vec3::z(),
        friction: 0.0,
        remove_at: None,
        two_sided: false,
    };
    let mut system = film_scene(vec![floor], viscosity, roughness);
    system.contact_gap = contact_gap;
    system.add_particles(&[NewParticle {
        position: Vec3::new(0.0, 0.0, 1.5 * RADIUS + contact_gap - 1e-12),
        velocity: Vec3::new(0.0, 0.0, -speed),
        angular_velocity: Vec3::zeros(),
        radius: RADIUS,
        density: DENSITY,
        fixed: false,
    }]);
    system
}

/// `6π μ R² / m`.
fn damping_per_mass(viscosity: f64) -> f64 {
    let mass = DENSITY * 4.0 / 3.0 * PI * RADIUS.powi(3);
    6.0 * PI * viscosity * RADIUS * RADIUS / mass
}

/// Along the approach the velocity follows the logarithmic law to 1 % of
/// the launch speed, and the sphere stops within 5 % of the predicted gap.
#[test]
fn approach_velocity_follows_the_film_law() {
    let eta = ROUGHNESS * RADIUS;
    let h0 = 0.5 * RADIUS;
    let c = damping_per_mass(VISCOSITY);
    let speed = 0.9 * c * ((h0 + eta) / eta).ln(); // stops short of contact
    let dt = 1e-9;
    let mut system = approach(speed, VISCOSITY, ROUGHNESS);
    let mut worst: f64 = 0.0;
    for _ in 0..400_000 {
        system.step(dt);
        let h = system.particles.position[0].z - RADIUS;
        let v = system.particles.velocity[0].z;
        if v >= 0.0 {
            break;
        }
        let expected = -speed + c * ((h0 + eta) / (h + eta)).ln();
        worst = worst.max((v - expected).abs() / speed);
    }
    let h = system.particles.position[0].z - RADIUS;
    let stop = (h0 + eta) * (-speed / c).exp() - eta;
    println!("worst velocity error {worst:.2e} of v0; stopped at gap {h:.4e}, expected {stop:.4e}");
    assert!(worst < 0.01, "{worst}");
    assert!(
        (h - stop).abs() < 0.05 * stop,
        "stopped at {h:e}, expected {stop:e}"
    );
}

/// A viscous film with a fine roughness, at the DEM step of the contacts
/// (`t_c/50`): the film's damping rate at contact times that step,
/// `6π μ R² Δt / (m η)`, is 36, eighteen times the explicit limit of 2.
/// Integrated implicitly, the sphere slows down without ever being pushed
/// back and stops short of the wall. The first-order implicit step lets it
/// travel a little further than the film law (a quarter of the stopping
/// gap here, which is 1.4 % of the initial one), so the stop is checked
/// against the distance travelled: within 1 % of it.
#[test]
fn stiff_film_stops_the_sphere_without_rebound() {
    let (viscosity, roughness) = (10.0, 1e-4);
    let eta = roughness * RADIUS;
    let h0 = 0.5 * RADIUS;
    let c = damping_per_mass(viscosity);
    let dt = CONTACT_TIME / 50.0;
    let stiffness = c * dt / eta;
    assert!((stiffness - 36.0).abs() < 0.5, "{stiffness}");
    let speed = 0.5 * c * ((h0 + eta) / eta).ln();
    let mut system = approach(speed, viscosity, roughness);
    let mut lowest = f64::MAX;
    for _ in 0..20_000 {
        system.step(dt);
        lowest = lowest.min(system.particles.position[0].z - RADIUS);
        let v = system.particles.velocity[0].z;
        assert!(v <= 0.0, "pushed back out: {v}");
    }
    let stop = (h0 + eta) * (-speed / c).exp() - eta;
    let last = system.particles.velocity[0].z;
    println!("stopped at gap {lowest:.4e} (film law {stop:.4e}), final speed {last:.3e}");
    assert!(lowest > 0.0, "reached the wall: {lowest:e}");
    assert!(
        (lowest - stop).abs() < 0.01 * (h0 - stop),
        "{lowest:e} against {stop:e}"
    );
    assert!(last.abs() < 1e-6 * speed, "{last}");
}

/// The DEM step against the film's time scale `m η / (6π μ R²)` at
/// contact: the implicit film stays stable at every ratio (no reversal, no
/// contact); what grows with the ratio is the overshoot of the stopping
/// gap, first order in the step (1e-5, 1e-4, 1e-3, 9e-3 of the distance
/// travelled at 0.1, 1, 10, 100). Here a ratio of 1000 would need a step of
/// 0.56 t_c, beyond the contacts' own limit (0.3 t_c, refused by `run`):
/// the contact, not the film, is what breaks first.
#[test]
fn film_step_sweep() {
    let (viscosity, roughness) = (10.0, 1e-4);
    let eta = roughness * RADIUS;
    let h0 = 0.5 * RADIUS;
    let c = damping_per_mass(viscosity);
    let speed = 0.5 * c * ((h0 + eta) / eta).ln();
    let stop = (h0 + eta) * (-speed / c).exp() - eta;
    let mut previous_error = 0.0;
    println!("c dt / eta | stopping gap | film law | error / travel");
    for ratio in [0.1, 1.0, 10.0, 100.0] {
        let dt = ratio * eta / c;
        assert!(dt < 0.3 * CONTACT_TIME);
        let mut system = approach(speed, viscosity, roughness);
        let mut lowest = f64::MAX;
        let steps = ((20.0 * h0 / speed) / dt).ceil().max(2000.0) as usize;
        for _ in 0..steps.min(2_000_000) {
            system.step(dt);
            lowest = lowest.min(system.particles.position[0].z - RADIUS);
            assert!(
                system.particles.velocity[0].z <= 0.0,
                "ratio {ratio}: reversed"
            );
        }
        let error = (stop - lowest) / (h0 - stop);
        println!("{ratio:10} | {lowest:.4e} | {stop:.4e} | {error:+.3e}");
        assert!(lowest > 0.0, "ratio {ratio}: reached the wall");
        // First order: about 1e-4 of the travel per unit of the ratio.
        assert!(
            error.abs() < 1.1e-4 * ratio.max(1.0),
            "ratio {ratio}: {error}"
        );
        assert!(error >= previous_error - 1e-6, "ratio {ratio}: error fell");
        previous_error = error;
    }
}

/// A sphere launched at the edge of the range fast enough to reach the
/// wall: the rebound it leaves the range with, over `e_n` times the launch
/// speed, is the thin-film restitution `1 − (1 + 1/e_n) L / St` (module
/// doc) within 0.005, at three Stokes numbers spanning the rise of
/// `e / e_n` from 0.2 to 0.8. This is the film's whole answer to a bounce;
/// in a fluid the resolved flow adds its own losses (docs/validation.md,
/// bouncing sphere). With contacts starting at a gap (`contact_gap`, a
/// fifth of the radius here) the film is measured from where they start,
/// and the same law holds.
#[test]
fn a_bounce_through_the_film_has_the_thin_film_restitution() {
    // A thin liquid: the bounce comes at 0.3-1.2 m/s, the film's time
    // scale at contact, m η / (6π μ R²), is 280 DEM steps.
    let (restitution, viscosity) = (0.9, 0.01);
    let eta = ROUGHNESS * RADIUS;
    let h0 = 0.5 * RADIUS;
    let c = damping_per_mass(viscosity);
    let film = ((h0 + eta) / eta).ln();
    let critical = (1.0 + 1.0 / restitution) * film;
    let dt = CONTACT_TIME / 50.0;
    println!("contact gap / R | St / St_c | e/e_n | thin film");
    for (contact_gap, over_critical) in [0.0, 0.2 * RADIUS]
        .into_iter()
        .flat_map(|g| [1.25, 2.0, 5.0].map(|s| (g, s)))
    {
        let stokes = over_critical * critical;
        let speed = stokes * c;
        let mut system = approach_with_contact_gap(speed, viscosity, ROUGHNESS, contact_gap);
        let mut rebound = None;
        for _ in 0..2_000_000 {
            system.step(dt);
            let gap = system.particles.position[0].z - RADIUS - contact_gap;
            if gap > h0 {
                rebound = Some(system.particles.velocity[0].z);
                break;
            }
        }
        let rebound = rebound.expect("left the film's range");
        let ratio = rebound / (restitution * speed);
        let theory = 1.0 - critical / stokes;
        println!(
            "{:15} | {over_critical:9} | {ratio:.4} | {theory:.4}",
            contact_gap / RADIUS
        );
        assert!(
            (ratio - theory).abs() < 0.005,
            "contact gap {contact_gap}, St/St_c {over_critical}: {ratio} against {theory}"
        );
    }
}

/// An empty scene with `walls`, a film of `viscosity` (Pa s) and
/// `roughness` (η/R), no gravity.
fn film_scene(walls: Vec<PlaneWall>, viscosity: f64, roughness: f64) -> DemSystem {
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::new(-0.01, -0.01, 0.0),
        upper: Vec3::new(0.01, 0.01, 0.01),
        periodic: [false; 3],
        gravity: Vec3::zeros(),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(0.9, CONTACT_TIME, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.0,
        rolling_friction: 0.0,
    };
    let mut system = DemSystem::new(domain, law, walls, 0.2 * RADIUS);
    system.lubrication = Some(Lubrication {
        viscosity,
        roughness,
        range: 0.5,
    });
    system
}

/// [`film_scene`] with the stiff film of
/// [`stiff_film_stops_the_sphere_without_rebound`].
fn stiff_film_scene(walls: Vec<PlaneWall>) -> DemSystem {
    film_scene(walls, 10.0, 1e-4)
}

/// A grain of the tests below at `position`, moving at `velocity`.
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

/// One grain between a floor and a ceiling, both at surface gap `gap`,
/// moving along z at `speed`.
fn grain_between_walls(gap: f64, speed: f64) -> DemSystem {
    let wall = |name: &str, z: f64, normal: Vec3| PlaneWall {
        name: name.into(),
        point: Vec3::new(0.0, 0.0, z),
        normal,
        friction: 0.0,
        remove_at: None,
        two_sided: false,
    };
    let height = 2.0 * (RADIUS + gap);
    let mut system = stiff_film_scene(vec![
        wall("floor", 0.0, Vec3::z()),
        wall("ceiling", height, -Vec3::z()),
    ]);
    system.add_particles(&[grain(
        Vec3::new(0.0, 0.0, RADIUS + gap),
        Vec3::new(0.0, 0.0, speed),
        false,
    )]);
    system
}

/// A grain between two walls at gaps of the roughness length, where the
/// two films' damping rate `c Δt / m` is 0.1 to 1000 times a step. Each
/// film made implicit on its own pair flipped the velocity at every step
/// without decay once that rate passed 1; made implicit together, the
/// velocity keeps its sign and falls at every step by the exact implicit
/// factor of the two films, `1 / (1 + Δt (c₁ + c₂) / m)`, within 1 %
/// (the gaps change a little as the grain moves).
#[test]
fn a_grain_between_two_walls_slows_at_every_step_whatever_the_film_rate() {
    let eta = 1e-4 * RADIUS;
    let gap = eta;
    let c = damping_per_mass(10.0) / (gap + eta); // each film, over m
    println!("c dt / m | step factor | implicit pair of films");
    for rate in [0.1, 1.0, 10.0, 100.0, 1000.0] {
        let dt = rate / c;
        // Slow enough to move a tenth of the gap in all.
        let speed = 0.1 * gap / dt;
        let mut system = grain_between_walls(gap, -speed);
        let mut previous = -speed;
        for step in 0..50 {
            system.step(dt);
            let v = system.particles.velocity[0].z;
            assert!(
                v <= 0.0 && v.abs() <= previous.abs(),
                "rate {rate}, step {step}: {previous:e} -> {v:e}"
            );
            if step > 0 && previous.abs() > 1e-250 {
                let z = system.particles.position[0].z;
                let below = damping_per_mass(10.0) / (z - RADIUS + eta);
                let above = damping_per_mass(10.0) / (2.0 * gap + RADIUS - z + eta);
                let exact = 1.0 / (1.0 + dt * (below + above));
                let factor = v / previous;
                if step == 1 {
                    println!("{rate:8} | {factor:.5e} | {exact:.5e}");
                }
                assert!(
                    (factor - exact).abs() < 0.01 * exact,
                    "rate {rate}, step {step}: factor {factor} against {exact}"
                );
            }
            previous = v;
        }
    }
}

/// A grain caged by eight fixed grains at the corners of a cube around
/// it, every gap at the roughness length: eight films, whose normals add
/// up to `Σ n nᵀ = 8/3 I`. Each film made implicit on its own pair
/// multiplied the grain's velocity by `1 − 8/3 = −5/3` per step once the
/// films' rate `c Δt / m` was large; made implicit together the velocity
/// keeps its sign and shrinks at every step, at rates from 0.1 to 1000 per
/// step, and at the largest rate by the factor of the Jacobi scaling,
/// `1 − (8/3) x / (1 + 8x)` (about 2/3), within 1 %.
#[test]
fn a_grain_caged_by_eight_films_slows_at_every_step_whatever_the_film_rate() {
    let eta = 1e-4 * RADIUS;
    let gap = eta;
    let c = damping_per_mass(10.0) / (gap + eta);
    let centre = Vec3::new(0.0, 0.0, 0.005);
    let reach = (2.0 * RADIUS + gap) / 3f64.sqrt();
    for rate in [0.1, 1.0, 10.0, 100.0, 1000.0] {
        let dt = rate / c;
        let speed = 0.05 * gap / dt;
        let mut system = stiff_film_scene(Vec::new());
        let mut grains = vec![grain(centre, Vec3::new(0.0, 0.0, speed), false)];
        for corner in 0..8 {
            let sign = |bit: usize| if corner >> bit & 1 == 0 { -1.0 } else { 1.0 };
            let offset = reach * Vec3::new(sign(0), sign(1), sign(2));
            grains.push(grain(centre + offset, Vec3::zeros(), true));
        }
        system.add_particles(&grains);
        let caged = |s: &DemSystem| s.index_of(0).expect("the caged grain");
        let mut previous = speed;
        let mut factor = 0.0;
        for step in 0..20 {
            system.step(dt);
            let v = system.particles.velocity[caged(&system)].z;
            assert!(
                v >= 0.0 && v <= previous,
                "rate {rate}, step {step}: {previous:e} -> {v:e}"
            );
            factor = v / previous;
            previous = v;
        }
        println!(
            "c dt / m = {rate}: step factor {factor:.4}, speed after 20 steps {:.3e} of the start",
            previous / speed
        );
        if rate == 1000.0 {
            let x = rate;
            let jacobi = 1.0 - 8.0 / 3.0 * x / (1.0 + 8.0 * x);
            assert!(
                (factor - jacobi).abs() < 0.01 * jacobi,
                "{factor} against {jacobi}"
            );
        }
    }
}
