//! The same physics in two frames of reference: a grain that spins in a
//! fluid moving with it feels no lift, whether the two drift across the
//! grid or not (Galilean invariance of the hydrodynamic load).
//!
//! A load that differentiates the inner fluid momentum over a volume held
//! fixed during each stage, `∫ α ∂u/∂t`, misses the flux through the
//! grain's moving surface, about `ρ V_p ω × u_p`: in a frame where grain
//! and fluid drift at U it pushed the spinning grain sideways at 3.3e-3 m/s
//! after 0.1 s (U = 0.05 m/s, ω = 10 rad/s). The derivative over the moving
//! volume leaves what the grid itself does not keep invariant.

mod common;

use common::PeriodicSphere;
use grainflow_fluid::Location;
use grainflow_ibm::{
    rigid_inner_fluid_limits, CoupledSystem, Coupling, LayerForcing, RIGID_INNER_FLUID_FAILS_BELOW,
    RIGID_INNER_FLUID_WARNS_BELOW,
};

const DIAMETER: f64 = 0.01;

/// A sphere of D = 1 cm and ρ_p/ρ = 2 at D/Δx = 8 in a triply periodic
/// box of 4 D of water, spinning at `spin` rad/s about z; grain and fluid
/// drift together at `drift` m/s along x. No gravity.
fn spinning_sphere(drift: f64, spin: f64, coupling: Coupling) -> CoupledSystem {
    let cells = std::env::var("GALILEAN_CELLS").map_or(32, |v| v.parse().unwrap());
    spinning_sphere_on(cells, drift, spin, coupling)
}

/// [`spinning_sphere`] on `cells` cells along each side of the box.
fn spinning_sphere_on(cells: usize, drift: f64, spin: f64, coupling: Coupling) -> CoupledSystem {
    PeriodicSphere {
        diameter: DIAMETER,
        cells,
        viscosity: 1e-6,
        density: 2000.0,
        drift,
        spin,
    }
    .build(coupling)
}

/// The grain's velocity across the drift after 20 steps of 5 ms.
fn lateral_velocity(drift: f64, spin: f64, coupling: Coupling) -> f64 {
    lateral_velocity_of(spinning_sphere(drift, spin, coupling), 5e-3)
}

/// The grain's velocity across the drift after 0.1 s in steps of `dt`.
fn lateral_velocity_of(mut system: CoupledSystem, dt: f64) -> f64 {
    for _ in 0..(0.1 / dt).round() as usize {
        system.step(dt).unwrap();
    }
    system.dem.particles.velocity[0].y
}

/// Measured (v_y after 0.1 s, D/Δx = 8): the fixed-volume derivative gave
/// −3.9e-3 m/s drifting; the moving-volume one gives +2.27e-4 (5.8 %), the
/// paper's rigid inner fluid (no inner momentum at all) +1.9e-4.
#[test]
fn a_spinning_grain_drifting_with_its_fluid_feels_no_frame_dependent_lift() {
    /// The lateral velocity the fixed-volume derivative gave (m/s).
    const FIXED_VOLUME_LIFT: f64 = 3.9e-3;
    for coupling in [Coupling::InnerFluidMomentum, Coupling::RigidInnerFluid] {
        let at_rest = lateral_velocity(0.0, 10.0, coupling);
        let drifting = lateral_velocity(0.05, 10.0, coupling);
        let reversed = lateral_velocity(0.05, -10.0, coupling);
        println!(
            "{coupling:?}: v_y = {at_rest:+.3e} at rest, {drifting:+.3e} drifting, \
             {reversed:+.3e} drifting with the spin reversed"
        );
        // At rest the spin alone is symmetric: no sideways push.
        assert!(at_rest.abs() < 1e-15, "{at_rest}");
        // Whatever is left flips with the spin, to round-off.
        assert!((drifting + reversed).abs() < 1e-12, "{drifting} {reversed}");
        // A tenth of the fixed-volume lift at the most.
        assert!(
            drifting.abs() < 0.1 * FIXED_VOLUME_LIFT,
            "{coupling:?}: {drifting}"
        );
    }
}

/// What the default load leaves of the frame-dependent lift falls with the
/// grid, below 5 % of the fixed-volume derivative's D/Δx = 8 figure at
/// D/Δx = 16. Measured: +2.27e-4 m/s at D/Δx = 8, +8.9e-5 at 16; the
/// paper's rigid inner fluid gives +1.9e-4 and +2.6e-4, which does not
/// fall. Against the fixed-volume derivative on the same grid (−3.91e-3
/// and −8.54e-3 m/s, measured with the transport term switched off), the
/// default leaves 5.8 % and 1.0 %; of the steady drift over the last
/// 0.05 s (the start-up kick apart, test below), 6.4 % and 1.8 %
/// (1.90e-3 against 2.94e-2 m/s², 1.36e-3 against 7.67e-2): the residual
/// falls slowly, the error it corrects grows towards its continuous value.
/// Seconds.
#[test]
fn the_frame_dependent_lift_left_by_the_default_load_shrinks_with_the_grid() {
    const FIXED_VOLUME_LIFT: f64 = 3.9e-3;
    let drifting = |cells| {
        let system = spinning_sphere_on(cells, 0.05, 10.0, Coupling::InnerFluidMomentum);
        lateral_velocity_of(system, 5e-3)
    };
    let (coarse, fine) = (drifting(32), drifting(64));
    println!("v_y drifting: {coarse:+.3e} at D/Δx = 8, {fine:+.3e} at 16");
    assert!(fine.abs() < 0.05 * FIXED_VOLUME_LIFT, "{fine}");
    assert!(fine.abs() < 0.5 * coarse.abs(), "{coarse} {fine}");
}

/// The drifting grain's lateral velocity after its first step and every
/// 5 ms up to 0.1 s, in steps of `dt`, its transition layer relaxed as
/// eq. 7 does at a held step `held` (`LayerForcing::Held`), whatever `dt`.
fn lateral_history_held(held: f64, dt: f64) -> (f64, Vec<f64>) {
    let mut system = spinning_sphere_on(32, 0.05, 10.0, Coupling::InnerFluidMomentum);
    system.immersed.layer = LayerForcing::Held { step: held };
    let per_sample = (5e-3 / dt).round() as usize;
    let mut first = None;
    let mut samples = Vec::new();
    for step in 1..=20 * per_sample {
        system.step(dt).unwrap();
        let lateral = system.dem.particles.velocity[0].y;
        first.get_or_insert(lateral);
        if step % per_sample == 0 {
            samples.push(lateral);
        }
    }
    (first.unwrap(), samples)
}

/// The steady lateral acceleration over the last 0.05 s of a history of
/// [`lateral_history_held`] (m/s²).
fn steady_drift(samples: &[f64]) -> f64 {
    (samples[19] - samples[9]) / 0.05
}

/// What is left of the frame-dependent lift at D/Δx = 8 has two parts,
/// measured with the layer relaxed at a held rate (that of eq. 7 at 5 ms)
/// while the step is cut. A start-up kick against the drift: the grain is
/// spun impulsively, and the transport through its moving surface enters
/// the load one stage late (the rate of the previous stage), so while the
/// fluid of the layer spins up the first stages see part of the
/// fixed-volume error. It is a lag in time, linear in the drift and first
/// order in the step (v_y after the first step −1.94e-4, −7.58e-5,
/// −2.69e-5 m/s at Δt = 5, 2.5, 1.25 ms; eq. 7 at 5 ms, whose virtual mass
/// is handed back in the next stage, −1.38e-4). Then a steady drift along
/// the lift, which converges as the step is cut (2.04e-3, 1.90e-3,
/// 1.85e-3 m/s² over the last 0.05 s: the differences fall by 0.37) and is
/// smaller where the layer is held tighter (1.57e-3 held at 2.5 ms): a
/// property of the grid and of the forcing. Our reading: the grid's
/// central differences carry the short waves of the spinning layer slower
/// than the drift, the forcing pulls the layer back onto the grain, and
/// the lag between the two acts as a Magnus lift. The velocity at 0.1 s
/// (the tests above) is the sum of the two, of opposite signs. Seconds.
#[test]
fn the_lift_left_at_d_over_dx_8_is_a_start_up_lag_and_a_steady_drift_set_by_the_layer() {
    let runs = [5e-3, 2.5e-3, 1.25e-3].map(|dt| lateral_history_held(5e-3, dt));
    let kicks = runs.each_ref().map(|(first, _)| *first);
    let drifts = runs.each_ref().map(|(_, samples)| steady_drift(samples));
    let (_, tighter) = lateral_history_held(2.5e-3, 2.5e-3);
    let tighter = steady_drift(&tighter);
    let listed = |values: &[f64]| {
        let values: Vec<String> = values.iter().map(|v| format!("{v:+.3e}")).collect();
        values.join(", ")
    };
    println!(
        "layer held at 5 ms, Δt = 5, 2.5, 1.25 ms: first step {} m/s, steady drift {} m/s²; \
         held at 2.5 ms: {tighter:+.3e} m/s²",
        listed(&kicks),
        listed(&drifts)
    );
    // The kick is against the drift's lift and at least halves with the
    // step (measured 0.39 and 0.36 of the last).
    assert!(kicks.iter().all(|&k| k < 0.0), "{kicks:?}");
    assert!(
        kicks[1] > 0.55 * kicks[0] && kicks[2] > 0.55 * kicks[1],
        "{kicks:?}"
    );
    // The steady drift converges as the step is cut: its change at least
    // halves from one halving to the next (measured 0.37), and the two
    // shortest steps agree within 5 % (measured 2.8 %)...
    assert!(drifts.iter().all(|&d| d > 0.0), "{drifts:?}");
    assert!(
        (drifts[2] - drifts[1]).abs() < 0.5 * (drifts[1] - drifts[0]).abs(),
        "{drifts:?}"
    );
    assert!((drifts[2] / drifts[1] - 1.0).abs() < 0.05, "{drifts:?}");
    // ... and is at least 10 % smaller with the layer held twice as fast
    // (measured 17 %).
    assert!(tighter < 0.9 * drifts[1], "{tighter} {}", drifts[1]);
}

/// Where the spin's vorticity outside the grain stands along the drift,
/// relative to the grain's centre, in cells: the centroid of ω_z over the
/// fluid beyond 1.5 cells from the surface within a cube of ±D around the
/// grain (ω_z on the cells' z-edges from the faces' velocities).
fn outer_vorticity_offset(system: &CoupledSystem) -> f64 {
    let grid = &system.flow.grid;
    let (u, v) = (&system.flow.velocity[0], &system.flow.velocity[1]);
    let centre = system.dem.particles.position[0];
    let dx = grid.width(0, grid.interior(0).start);
    let shell = 0.5 * DIAMETER + 1.5 * dx;
    let (mut total, mut moment) = (0.0, 0.0);
    for k in grid.interior(2) {
        for j in grid.interior(1).start..grid.interior(1).end - 1 {
            for i in grid.interior(0).start..grid.interior(0).end - 1 {
                let r = [
                    grid.coordinate(Location::Face(0), 0, i) - centre.x,
                    grid.coordinate(Location::Face(1), 1, j) - centre.y,
                    grid.coordinate(Location::Centre, 2, k) - centre.z,
                ];
                let distance = r.iter().map(|x| x * x).sum::<f64>().sqrt();
                if r.iter().any(|x| x.abs() > DIAMETER) || distance < shell {
                    continue;
                }
                let vorticity = (v[grid.index(i + 1, j, k)] - v[grid.index(i, j, k)]) / dx
                    - (u[grid.index(i, j + 1, k)] - u[grid.index(i, j, k)]) / dx;
                total += vorticity;
                moment += vorticity * r[0];
            }
        }
    }
    moment / total / dx
}

/// Where the steady drift comes from: the flow, not the load. Spun at
/// ω_z = 10 rad/s, the grain sheds vorticity of the opposite sign into
/// the fluid around it; at rest that vorticity is centred on the grain
/// (to 1e-15 cells), drifting at 0.05 m/s it stands upstream of it,
/// 0.59–1.11 cells over the second half of the first 0.1 s (0.81 on
/// average) and 1.45 cells by 0.2 s. The equations carry it at the drift
/// exactly and the step is converged (test above): the grid's central
/// differences carry the grid-scale shell slower. Vorticity that falls behind
/// moves the fluid's impulse ½ ∫ x × ω dV along −y for ω_z > 0, and the
/// grain takes the opposite push: the +y lift measured above, the same
/// under the paper's rigid inner fluid, which has no inner momentum at
/// all. The grain also falls behind its fluid along the drift, by
/// 7.2e-5 m/s at 0.1 s (2.3e-6 without the spin). Seconds.
#[test]
fn the_steady_drift_is_the_spins_vorticity_carried_slower_than_the_drift() {
    let history = |drift: f64, spin: f64| {
        let mut system = spinning_sphere_on(32, drift, spin, Coupling::InnerFluidMomentum);
        let mut offsets = Vec::new();
        for _ in 0..20 {
            system.step(5e-3).unwrap();
            if spin != 0.0 {
                offsets.push(outer_vorticity_offset(&system));
            }
        }
        let lag = system.dem.particles.velocity[0].x - drift;
        (offsets, lag)
    };
    let (at_rest, _) = history(0.0, 10.0);
    let (drifting, lag) = history(0.05, 10.0);
    let (_, lag_without_spin) = history(0.05, 0.0);
    let late = &drifting[10..];
    let mean = late.iter().sum::<f64>() / late.len() as f64;
    println!(
        "outer vorticity's offset: at rest {:+.1e} cells at most, drifting {mean:+.3} cells over \
         the last 0.05 s ({:+.3} … {:+.3}); lag along the drift {lag:+.2e} m/s, \
         {lag_without_spin:+.2e} without the spin",
        at_rest.iter().fold(0.0f64, |m, x| m.max(x.abs())),
        late.iter().cloned().fold(f64::MAX, f64::min),
        late.iter().cloned().fold(f64::MIN, f64::max)
    );
    assert!(at_rest.iter().all(|x| x.abs() < 1e-9), "{at_rest:?}");
    // Upstream by more than half a cell at every sample of the second
    // half (measured 0.59 to 1.11 cells).
    assert!(late.iter().all(|&x| x < -0.5), "{late:?}");
    // The spinning grain falls behind its fluid ten times more than the
    // one that does not spin (measured 31 times).
    assert!(
        lag < 0.0 && lag.abs() > 10.0 * lag_without_spin.abs(),
        "{lag} {lag_without_spin}"
    );
}

/// A sphere spun up impulsively in fluid at rest, at density ratio
/// `ratio`: its spin after each of `steps` steps of `dt`.
fn spin_down(ratio: f64, coupling: Coupling, dt: f64, steps: usize) -> Vec<f64> {
    spin_down_with(ratio, coupling, LayerForcing::EveryStage, dt, steps)
}

/// [`spin_down`] with the transition layer relaxed by `layer`.
fn spin_down_with(
    ratio: f64,
    coupling: Coupling,
    layer: LayerForcing,
    dt: f64,
    steps: usize,
) -> Vec<f64> {
    let mut system = spinning_sphere(0.0, 10.0, coupling);
    system.immersed.layer = layer;
    let p = &mut system.dem.particles;
    let (mass, inverse_inertia) = (p.mass[0], p.inverse_inertia[0]);
    // Scale the grain's density from 2000 to `ratio` × 1000 kg/m³.
    let scale = ratio * 1000.0 / 2000.0;
    p.mass[0] = mass * scale;
    p.inverse_mass[0] /= scale;
    p.inverse_inertia[0] = inverse_inertia / scale;
    let mut spins = Vec::new();
    for _ in 0..steps {
        if system.step(dt).is_err() {
            break;
        }
        spins.push(system.dem.particles.angular_velocity[0].z);
    }
    spins
}

/// A sphere spun impulsively to 10 rad/s in water at rest (D/Δx = 8,
/// Δt = 5 ms) spins down monotonically with the load from the inner fluid
/// momentum at any density ratio tried (0.5 to 5). With the paper's rigid
/// inner fluid (eq. 5–6) measured over 40 steps: the spin blows up at
/// ρ_p/ρ = 1.7 and below (−174 rad/s after 20 steps at 1.7), reverses in
/// the first step at 2.0 (to −1.97 rad/s), overshoots and oscillates up
/// to 2.6, and decays monotonically from 2.8: in rotation it fails higher
/// than in translation (where 1.8 holds), which sets
/// `RIGID_INNER_FLUID_FAILS_BELOW` and `RIGID_INNER_FLUID_WARNS_BELOW`.
#[test]
fn an_impulsive_spin_decays_without_reversing_where_the_load_holds() {
    let monotone = |spins: &[f64]| {
        spins.len() == 20 && spins.windows(2).all(|w| w[1] <= w[0]) && spins[19] > 0.0
    };
    for ratio in [0.5, 2.0, 5.0] {
        let spins = spin_down(ratio, Coupling::InnerFluidMomentum, 5e-3, 20);
        assert!(
            monotone(&spins) && spins[0] < 10.0,
            "inner momentum at {ratio}: {spins:?}"
        );
    }
    let rigid = |ratio| spin_down(ratio, Coupling::RigidInnerFluid, 5e-3, 20);
    assert!(monotone(&rigid(RIGID_INNER_FLUID_WARNS_BELOW)));
    assert!(rigid(2.0)[0] < 0.0, "the spin reverses at 2.0");
    // Just below where runs refuse it, it blows up.
    let failing = rigid(RIGID_INNER_FLUID_FAILS_BELOW - 0.1);
    assert!(failing.last().is_none_or(|w| w.abs() > 10.0), "{failing:?}");
}

/// The paper's rigid inner fluid spun impulsively (as above) with the layer
/// relaxed at its renewal rate, where runs warn and refuse it
/// ([`rigid_inner_fluid_limits`]). Measured over 20 steps: the spin decays
/// monotonically from 3.2 down to 1.6 (10 → 5.08 rad/s in the first step
/// at 2.0, where under eq. 7 it reverses), overshoots at 1.5 to 1.3 (at
/// 1.3: 1.14 rad/s after the first step, 1.27 after the last) and blows
/// up at 1.2.
#[test]
fn under_the_renewal_forcing_a_rigid_inner_fluid_spin_decays_further_down() {
    let limits = rigid_inner_fluid_limits(LayerForcing::Renewal);
    let spin = |ratio| {
        let spins = spin_down_with(
            ratio,
            Coupling::RigidInnerFluid,
            LayerForcing::Renewal,
            5e-3,
            20,
        );
        println!("rigid inner fluid, renewal, ratio {ratio}: {spins:?}");
        spins
    };
    let monotone = |spins: &[f64]| {
        spins.len() == 20 && spins.windows(2).all(|w| w[1] <= w[0]) && spins[19] > 0.0
    };
    assert!(monotone(&spin(limits.warns_below)));
    assert!(monotone(&spin(2.0)), "no reversal at 2.0");
    let overshooting = spin(limits.fails_below);
    assert!(
        overshooting.len() == 20 && overshooting.iter().all(|w| w.abs() < 10.0),
        "{overshooting:?}"
    );
    assert!(!monotone(&overshooting), "{overshooting:?}");
    let failing = spin(limits.fails_below - 0.1);
    assert!(failing.last().is_none_or(|w| w.abs() > 10.0), "{failing:?}");
}
