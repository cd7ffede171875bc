//! A sphere released from rest in a closed box of fluid (Izard et al. 2014,
//! section 3.1, reduced): the start of its fall against the added-mass
//! estimate of eq. 20.

use grainflow_core::{Communicator, Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, NormalCalibration, NormalStiffness};
use grainflow_fluid::{Boundaries, BoundaryCondition, FlowSolver, Grid};
use grainflow_ibm::settling::early_acceleration;
use grainflow_ibm::{rigid_inner_fluid_limits, CoupledSystem, Coupling, LayerForcing};

/// A sphere of diameter 1 and density `density_ratio` (fluid density 1,
/// g = 1 downwards) at rest 2.5 D below the top of a free-slip box, the
/// viscosity set by the Archimedes number `Ar = |ρ_p − ρ| g D³ / (ρ ν²)`.
fn settling_sphere(
    cells_per_diameter: usize,
    extent: [f64; 3],
    density_ratio: f64,
    archimedes: f64,
    coupling: Coupling,
) -> CoupledSystem {
    settling_sphere_drifting(
        cells_per_diameter,
        extent,
        density_ratio,
        archimedes,
        coupling,
        None,
    )
}

/// [`settling_sphere`]; with `drift = Some(U)` the box is periodic along
/// x and fluid and sphere start moving together at U along x.
fn settling_sphere_drifting(
    cells_per_diameter: usize,
    extent: [f64; 3],
    density_ratio: f64,
    archimedes: f64,
    coupling: Coupling,
    drift: Option<f64>,
) -> CoupledSystem {
    let diameter: f64 = 1.0;
    let viscosity = ((density_ratio - 1.0).abs() * diameter.powi(3) / archimedes).sqrt();
    let cells = extent.map(|e| (e * cells_per_diameter as f64).round() as usize);
    let grid = Grid::new(Dimension::Three, cells, [0.0; 3], extent);
    let slip = BoundaryCondition::FreeSlip;
    let mut walls = Boundaries::periodic()
        .with(1, slip, slip)
        .with(2, slip, slip);
    if drift.is_none() {
        walls = walls.with(0, slip, slip);
    }
    let mut flow = FlowSolver::new(grid, walls, viscosity, Communicator::serial()).unwrap();
    let drift_velocity = drift.unwrap_or(0.0);
    flow.set_velocity(|component, _| if component == 0 { drift_velocity } else { 0.0 });
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::zeros(),
        upper: Vec3::from(extent),
        periodic: [drift.is_some(), false, false],
        gravity: Vec3::new(0.0, 0.0, -1.0),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(0.9, 1e-2, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.25,
        rolling_friction: 0.0,
    };
    let mut dem = DemSystem::new(domain, law, Vec::new(), 0.1);
    let height = if density_ratio > 1.0 {
        extent[2] - 2.5 * diameter
    } else {
        2.5 * diameter
    };
    dem.add_particles(&[NewParticle {
        position: Vec3::new(0.5 * extent[0], 0.5 * extent[1], height),
        velocity: Vec3::new(drift_velocity, 0.0, 0.0),
        angular_velocity: Vec3::zeros(),
        radius: 0.5 * diameter,
        density: density_ratio,
        fixed: false,
    }]);
    CoupledSystem::new(flow, dem, 1.0, coupling, 1e-3)
}

/// Section 3.1: a sphere released from rest first accelerates at
/// `(ρ_p − ρ) g / (ρ_p + ρ/2)` (eq. 20), buoyant weight against the sphere
/// plus half its volume of fluid; the history (Basset) force then slows it
/// as `√t`. The early velocity is `v = a₀ t − b t^{3/2}`: fitted over
/// t ≤ 0.2 (D/g)^½, `a₀` is within 3 % of eq. 20 at D/Δx = 16 with
/// Δt = 0.02 (D/g)^½. A box of 5 D leaves 0.5 % of added mass to
/// confinement.
///
/// The limit this also shows: the direct forcing of eq. 7 pulls the
/// transition layer towards the sphere at every stage, so a shorter step
/// makes the sphere look larger, with more added mass: at Δt = 0.005
/// (D/g)^½ the same fit is 5 % low (measured −5.0 %; −2.3 % at 0.01).
/// With the forcing step held at 0.02 (`forcing_step`: the layer relaxed
/// at the same rate whatever the step) the run at 0.005 gives the run at
/// 0.02 again, within 1 % of eq. 20.
#[test]
fn initial_acceleration_matches_added_mass_and_depends_on_the_step() {
    let expected = 3.0 / 4.5;
    let error_at = |dt: f64, forcing_step: Option<f64>| {
        let mut system = settling_sphere(
            16,
            [5.0, 5.0, 5.0],
            4.0,
            800.0,
            Coupling::InnerFluidMomentum,
        );
        system.immersed.layer =
            forcing_step.map_or(LayerForcing::EveryStage, |step| LayerForcing::Held { step });
        let mut samples = Vec::new();
        for _ in 0..(0.2 / dt).round() as usize {
            system.step(dt).unwrap();
            samples.push((system.flow.time, -system.dem.particles.velocity[0].z));
        }
        early_acceleration(&samples) / expected - 1.0
    };
    let coarse = error_at(0.02, None);
    let fine = error_at(0.005, None);
    let fine_held = error_at(0.005, Some(0.02));
    println!(
        "initial acceleration error: {coarse:+.4} at dt 0.02, {fine:+.4} at dt 0.005, \
         {fine_held:+.4} at dt 0.005 with the forcing step at 0.02"
    );
    assert!(coarse.abs() < 0.03, "{coarse}");
    assert!(
        fine < -0.03,
        "the step dependence is gone ({fine}): update docs/validation.md §7"
    );
    assert!(
        (fine_held - coarse).abs() < 0.01,
        "{fine_held} against {coarse}"
    );
}

/// Marches a settling (or rising) sphere for `steps` steps of `dt`;
/// returns its final vertical velocity, or None when the run failed (a
/// step refused for its CFL number, or a velocity not finite).
fn settle(density_ratio: f64, coupling: Coupling, dt: f64, steps: usize) -> Option<f64> {
    settle_with(density_ratio, coupling, LayerForcing::EveryStage, dt, steps)
}

/// [`settle`] with the transition layer relaxed by `layer`.
fn settle_with(
    density_ratio: f64,
    coupling: Coupling,
    layer: LayerForcing,
    dt: f64,
    steps: usize,
) -> Option<f64> {
    let mut system = settling_sphere(8, [3.0, 3.0, 6.0], density_ratio, 100.0, coupling);
    system.immersed.layer = layer;
    for _ in 0..steps {
        system.step(dt).ok()?;
        let v = system.dem.particles.velocity[0];
        if !v.norm().is_finite() {
            return None;
        }
    }
    Some(system.dem.particles.velocity[0].z)
}

/// The density-ratio map of the two couplings (D/Δx = 8, Ar = 100,
/// Δt (g/D)^½ = 0.05, two time units). The paper's rigid inner fluid
/// (eq. 5–6) fails below ρ_p/ρ ≈ 1.7 (the run blows up within two time
/// units; at 1.7 it depends on Δt) and holds at 1.8 and above, which is
/// what `check` warns and refuses on. Keeping the measured rate of change
/// of the inner fluid momentum holds from 10 down to 0.5, through
/// neutral buoyancy: each sphere moves the right way, slower than its
/// Stokes velocity `|ρ_p − ρ| g D² / (18 μ)` (an upper bound from rest,
/// since drag at finite Re, added mass and walls only slow it).
#[test]
fn density_ratio_map() {
    let (dt, steps) = (0.05, 40);
    for ratio in [10.0, 4.0, 1.5, 1.2, 1.05, 0.95, 0.7, 0.5] {
        let velocity = settle(ratio, Coupling::InnerFluidMomentum, dt, steps)
            .unwrap_or_else(|| panic!("inner fluid momentum failed at density ratio {ratio}"));
        let nu = ((ratio - 1.0f64).abs() / 100.0).sqrt();
        let stokes = (ratio - 1.0) / (18.0 * nu);
        println!(
            "inner fluid momentum, ratio {ratio}: w = {velocity:+.4}, Stokes {:+.4}",
            -stokes
        );
        assert!(
            velocity * stokes < 0.0,
            "ratio {ratio}: w = {velocity} moves the wrong way"
        );
        assert!(
            velocity.abs() < stokes.abs(),
            "ratio {ratio}: |w| = {velocity} above Stokes"
        );
    }
    for ratio in [1.8, 2.0, 4.0] {
        let velocity = settle(ratio, Coupling::RigidInnerFluid, dt, steps);
        println!("rigid inner fluid, ratio {ratio}: {velocity:?}");
        assert!(
            velocity.is_some_and(|w| w < 0.0),
            "rigid inner fluid failed at {ratio}"
        );
    }
    for ratio in [1.6, 1.3, 1.05, 0.9, 0.5] {
        let velocity = settle(ratio, Coupling::RigidInnerFluid, dt, steps);
        println!("rigid inner fluid, ratio {ratio}: {velocity:?}");
        assert!(
            velocity.is_none(),
            "rigid inner fluid expected to fail at {ratio}, got {velocity:?}"
        );
    }
}

/// The paper's rigid inner fluid in translation with the layer relaxed at
/// its renewal rate (`coupling.layer_forcing = "renewal"`), where runs
/// refuse it ([`rigid_inner_fluid_limits`]). Measured (the map of
/// [`density_ratio_map`], two time units): it holds from 2.0 down to 1.25
/// (w = −0.1117 at 1.3, −0.1009 at 1.25) and blows up at 1.2 and 1.1; under
/// eq. 7 it blows up at 1.6.
#[test]
fn rigid_inner_fluid_holds_further_down_under_the_renewal_forcing() {
    let (dt, steps) = (0.05, 40);
    let limits = rigid_inner_fluid_limits(LayerForcing::Renewal);
    let settle = |ratio| {
        settle_with(
            ratio,
            Coupling::RigidInnerFluid,
            LayerForcing::Renewal,
            dt,
            steps,
        )
    };
    for ratio in [1.6, limits.fails_below] {
        let velocity = settle(ratio);
        println!("rigid inner fluid, renewal, ratio {ratio}: {velocity:?}");
        assert!(velocity.is_some_and(|w| w < 0.0), "failed at {ratio}");
    }
    let below = settle(limits.fails_below - 0.1);
    assert!(
        below.is_none(),
        "expected to fail below the limit, got {below:?}"
    );
}

/// The sphere of [`settle`] (D/Δx = 8, ρ_p/ρ = 4, Ar = 100) in a box
/// periodic along x, in a frame where fluid and sphere start drifting
/// together at `drift` along x: its velocity relative to the drift after
/// `steps` steps of `dt`.
fn settle_in_frame(drift: f64, dt: f64, steps: usize) -> Vec3 {
    let mut system = settling_sphere_drifting(
        8,
        [3.0, 3.0, 6.0],
        4.0,
        100.0,
        Coupling::InnerFluidMomentum,
        Some(drift),
    );
    for _ in 0..steps {
        system.step(dt).unwrap();
    }
    system.dem.particles.velocity[0] - Vec3::new(drift, 0.0, 0.0)
}

/// Galilean invariance of the coupled step: a sphere settling in a fluid
/// that drifts with it along a periodic axis, at up to twice its settling
/// speed, settles as it does at rest. Measured after four time units
/// (D/Δx = 8, Δt = 0.05 (D/g)^½): w = −0.46624 at rest, −0.46595 and
/// −0.46524 drifting at 0.5 and 1 (0.06 % and 0.21 %), a lag along the
/// drift of 1.8e-4 and 3.7e-4. What is left is the grid's (the sphere
/// crosses cells at the drift speed): 0.5 % and 0.1 % of w allowed.
#[test]
fn a_sphere_settles_alike_in_a_frame_drifting_along_a_periodic_axis() {
    let (dt, steps) = (0.05, 80);
    let at_rest = settle_in_frame(0.0, dt, steps);
    assert!(
        at_rest.x.abs() < 1e-12 && at_rest.y.abs() < 1e-12,
        "{at_rest}"
    );
    for drift in [0.5, 1.0] {
        let moving = settle_in_frame(drift, dt, steps);
        println!(
            "drift {drift}: velocity relative to the drift {:+.5} {:+.5} {:+.5}, at rest {:+.5}",
            moving.x, moving.y, moving.z, at_rest.z
        );
        let settling = at_rest.z.abs();
        assert!(
            (moving.z - at_rest.z).abs() < 5e-3 * settling,
            "drift {drift}: w = {} against {}",
            moving.z,
            at_rest.z
        );
        assert!(
            moving.x.abs() < 1e-3 * settling && moving.y.abs() < 1e-3 * settling,
            "drift {drift}: lateral {moving}"
        );
    }
}
