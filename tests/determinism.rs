//! Results do not depend on the number of threads, and a periodic boundary
//! is invisible to the contacts that cross it.

mod common;

use grainflow::case::Case;
use grainflow::scene;
use grainflow_dem::DemSystem;

const FALLING_PACKING: &str = r#"
    [domain]
    dimension = 3
    lower = [0.0, 0.0, 0.0]
    upper = [0.088, 0.088, 0.3]
    periodic = [true, true, false]
    gravity = [0.0, 0.0, -9.81]
    [particles]
    density = 2500.0
    radius = 5.0e-3
    radius_spread = 0.1
    [[particles.block]]
    kind = "lattice"
    lower = [0.0, 0.0, 0.0]
    upper = [0.088, 0.088, 0.2]
    spacing = 0.011
    jitter = 0.8
    [contact]
    model = "soft"
    restitution = 0.5
    contact_time = 1.0e-4
    friction = 0.5
    rolling_friction = 0.05
    [[walls]]
    point = [0.0, 0.0, 0.0]
    normal = [0.0, 0.0, 1.0]
    [time]
    end = 0.1
"#;

/// `work` run on a pool of `threads` threads.
fn on_threads<T: Send>(threads: usize, work: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(work)
}

fn run_with_threads(threads: usize, steps: usize) -> DemSystem {
    on_threads(threads, || {
        let case = Case::from_text(FALLING_PACKING, "packing", &[]).unwrap();
        let mut system = scene::build(&case).unwrap();
        // Forced: left to choose, a scene this small runs on one thread.
        system.threads = Some(threads);
        for _ in 0..steps {
            system.step(5.0e-6);
        }
        system
    })
}

#[test]
fn one_two_and_three_threads_give_identical_states() {
    // 1152 spheres falling onto a floor and into each other (0.05 s): many
    // contacts open and close, the neighbour list is rebuilt many times.
    // Three threads give a run that both receives hand-overs from the run
    // before it and hands over to the run after it.
    let serial = run_with_threads(1, 10_000);
    assert!(
        serial.last.particle_contacts > 150,
        "the packing must be in contact: {} contacts",
        serial.last.particle_contacts
    );
    for threads in [2, 3] {
        let parallel = run_with_threads(threads, 10_000);
        assert_eq!(serial.particles.n_owned, parallel.particles.n_owned);
        let mut largest = 0.0f64;
        for k in 0..serial.particles.n_owned {
            let j = parallel.index_of(serial.particles.id[k]).unwrap();
            for (a, b) in [
                (serial.particles.position[k], parallel.particles.position[j]),
                (serial.particles.velocity[k], parallel.particles.velocity[j]),
                (
                    serial.particles.angular_velocity[k],
                    parallel.particles.angular_velocity[j],
                ),
            ] {
                largest = largest.max((a - b).amax());
            }
        }
        // The force loop gathers in a fixed order: bitwise identical.
        assert_eq!(
            largest, 0.0,
            "{threads} threads changed the state by {largest}"
        );
    }
}

/// A head-on collision of two spheres centred at `x` (the pair straddles the
/// periodic boundary at x = 0 when `x` is near 0) in a box periodic along x.
fn collide_at(x: f64) -> (f64, f64) {
    let text = format!(
        r#"
        [domain]
        dimension = 3
        lower = [0.0, -0.01, -0.01]
        upper = [0.05, 0.01, 0.01]
        periodic = [true, false, false]
        [particles]
        density = 1319.0
        radius = 1.5e-3
        [[particles.block]]
        kind = "explicit"
        positions = [[{a}, 0.0, 0.0], [{b}, 0.0, 0.0]]
        velocities = [[0.5, 0.1, 0.0], [-0.5, 0.0, 0.0]]
        [contact]
        model = "soft"
        restitution = 0.87
        contact_time = 1.0e-5
        friction = 0.25
        [time]
        end = 1.0e-4
    "#,
        a = (x - 1.6e-3).rem_euclid(0.05),
        b = (x + 1.6e-3).rem_euclid(0.05)
    );
    let case = Case::from_text(&text, "periodic", &[]).unwrap();
    let mut system = scene::build(&case).unwrap();
    // Contact at t = 2e-4 s, lasting 1e-5 s.
    for _ in 0..2000 {
        system.step(2.0e-7);
    }
    let p = &system.particles;
    let (a, b) = (system.index_of(0).unwrap(), system.index_of(1).unwrap());
    let relative = p.velocity[a] - p.velocity[b];
    (relative.x, relative.y)
}

#[test]
fn a_contact_across_a_periodic_boundary_behaves_as_in_the_interior() {
    let interior = collide_at(0.025);
    let straddling = collide_at(0.0);
    assert!(
        interior.0 < 0.0,
        "the pair must have collided and separated: {interior:?}"
    );
    // Equal up to round-off: positions near x = 0.05 carry 7e-18 m of
    // round-off, amplified at the first contact step by 1/overlap (~1e7).
    assert!(
        (interior.0 - straddling.0).abs() < 1e-8,
        "{interior:?} vs {straddling:?}"
    );
    assert!(
        (interior.1 - straddling.1).abs() < 1e-8,
        "{interior:?} vs {straddling:?}"
    );
}

/// The flow solver shares the planes of its operators and the lines of its
/// transforms among threads; each value is computed alone, so a channel
/// (periodic x and y, no-slip walls in z, a vortex on a stream) gives the
/// same bits on 1 and 2 threads (the grid is large enough to be split:
/// several planes and lines per task).
#[test]
fn a_flow_gives_the_same_bits_on_one_and_two_threads() {
    let case = common::load(
        "taylor_green_3d.toml",
        &[
            "fluid.cells=[64, 48, 40]",
            "domain.periodic=[true, true, false]",
            "fluid.boundary.z=[\"no_slip\", \"moving\"]",
            "fluid.boundary.z_upper_velocity=[0.5, 0.2, 0.0]",
            "fluid.initial={kind=\"uniform\", velocity=[0.3, 0.1, 0.0]}",
            "fluid.pressure_gradient=[-1.0, 0.0, 0.0]",
            "analysis.kind=\"channel\"",
        ],
    );
    let run = |threads: usize| {
        on_threads(threads, || {
            let mut solver = grainflow::scene::fluid::build(&case).unwrap();
            for _ in 0..5 {
                solver.step(0.01).unwrap();
            }
            (
                solver.velocity.clone(),
                solver.pressure.clone(),
                solver.kinetic_energy().to_bits(),
                solver.max_cfl(1.0).to_bits(),
            )
        })
    };
    let (one, two) = (run(1), run(2));
    assert!(one.0.iter().flatten().any(|&u| u != 0.0));
    assert!(one == two, "the flow differs between 1 and 2 threads");
}

/// Grains in a fluid: the forcing integrates each particle alone and adds
/// the results in a fixed order, the flow and the DEM are thread-blind, so
/// three spheres settling towards a floor (one of them touching it by the
/// end, lubrication on) give the same bits on 1 and 2 threads.
#[test]
fn grains_in_a_fluid_give_the_same_bits_on_one_and_two_threads() {
    let case = common::load(
        "bouncing_sphere.toml",
        &[
            "fluid.cells=[48, 48, 72]",
            "domain.upper=[0.036, 0.036, 0.054]",
            "particles.block[0].positions=[[0.012, 0.018, 0.0035], [0.026, 0.012, 0.02], [0.02, 0.026, 0.03]]",
            "particles.block[0].velocities=[[0.0, 0.0, -0.2], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]",
            "fluid.viscosity=0.05",
        ],
    );
    let run = |threads: usize| {
        on_threads(threads, || {
            let (mut system, _) = grainflow::simulation::coupled::build(&case).unwrap();
            let mut overlap: f64 = 0.0;
            for _ in 0..20 {
                let report = system.step(6e-4).unwrap();
                overlap = overlap.max(report.dem.max_overlap_ratio);
            }
            let p = &system.dem.particles;
            (
                system.flow.velocity.clone(),
                p.position[..3].to_vec(),
                p.velocity[..3].to_vec(),
                p.angular_velocity[..3].to_vec(),
                overlap,
            )
        })
    };
    let (one, two) = (run(1), run(2));
    assert!(one.4 > 0.0, "no contact happened");
    assert!(one.2.iter().all(|v| v.norm() > 0.0));
    assert!(
        one == two,
        "grains in a fluid differ between 1 and 2 threads"
    );
}

/// The falling packing of `FALLING_PACKING` in hard contact, `steps` steps
/// of 2 ms on `threads` threads.
fn hard_run_with_threads(model: &str, threads: usize, steps: usize) -> DemSystem {
    let text = FALLING_PACKING.replace(
        "model = \"soft\"\n    restitution = 0.5\n    contact_time = 1.0e-4\n    friction = 0.5\n    rolling_friction = 0.05",
        &format!("model = \"{model}\"\n    friction = 0.5"),
    );
    // Three layers of 64 spheres, so that the test stays short.
    let text = text
        .replace("end = 0.1", "end = 0.1\n    dt = 2.0e-3")
        .replace(
            "upper = [0.088, 0.088, 0.2]",
            "upper = [0.088, 0.088, 0.033]",
        );
    on_threads(threads, || {
        let case = Case::from_text(&text, "packing", &[]).unwrap();
        let mut system = scene::build(&case).unwrap();
        let mut contact = scene::hard_contact(&case).expect("hard contact");
        contact.prepare(&mut system);
        for _ in 0..steps {
            let report = contact.step(&mut system, 2.0e-3).unwrap();
            assert!(report.coulomb_violation < contact.tolerance);
            assert!(report.penetration < contact.tolerance);
        }
        system
    })
}

/// Hard contact (192 spheres across periodic edges, 40 steps of 2 ms: the
/// layers land and pile up) gives the same bits on 1 and 2 threads: the
/// solve is serial and the position update is per grain.
#[test]
fn hard_contact_gives_the_same_bits_on_one_and_two_threads() {
    for model in ["cocd", "nscd"] {
        let serial = hard_run_with_threads(model, 1, 40);
        let parallel = hard_run_with_threads(model, 2, 40);
        assert!(
            serial.last.particle_contacts > 150,
            "{model}: the packing must be in contact: {}",
            serial.last.particle_contacts
        );
        for k in 0..serial.particles.n_owned {
            let j = parallel.index_of(serial.particles.id[k]).unwrap();
            assert_eq!(serial.particles.position[k], parallel.particles.position[j]);
            assert_eq!(serial.particles.velocity[k], parallel.particles.velocity[j]);
            assert_eq!(
                serial.particles.angular_velocity[k],
                parallel.particles.angular_velocity[j]
            );
        }
    }
}
