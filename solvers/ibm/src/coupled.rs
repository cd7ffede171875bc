//! The coupled step of a fluid and immersed grains (Izard et al. 2014,
//! sections 2.1 and 4).
//!
//! Each of the three Runge–Kutta stages of the flow, of length
//! `h = α_k Δt`, runs in order:
//!
//! 1. the flow's prediction (convection, viscous term);
//! 2. the direct forcing towards the particles' rigid velocities, which
//!    gives each particle its hydrodynamic load (eq. 5–7);
//! 3. the projection; where a grain's forcing exponent exceeds one (a
//!    layer relaxed faster than eq. 7 does at this step,
//!    [`crate::layer_forcing`]), 2 and 3 run in as many passes as it takes
//!    to keep every pass's exponent at most one
//!    ([`crate::forcing::Exponents::passes`]);
//! 4. the fluid momentum inside each particle, `I = ∫ α_p u dV`, on the
//!    faces of the particle where it stands;
//! 5. the DEM over `h` in sub-steps no longer than `dem_dt`, with the
//!    hydrodynamic load held fixed, contacts and lubrication (section 4).
//!
//! Advancing the particles within each stage (rather than once per step)
//! lets the next stage force the flow with their updated velocities, as
//! the Runge–Kutta integration of eq. 3–4 does.
//!
//! The hydrodynamic load comes in one of two forms ([`Coupling`]). The
//! paper's (eq. 3, 5–6) assumes the fluid inside a particle moves with it:
//! `m_p du_p/dt = m_p g − ρ ρ_p/(ρ_p − ρ) ∫ f dϑ`, which diverges as
//! `ρ_p → ρ` and fails before. The other keeps the rate of change of the
//! fluid momentum inside the particle as measured on the grid,
//!
//! ```text
//! m_p du_p/dt = −ρ ∫ f dϑ + ρ d/dt ∫_{V_p(t)} u dV + (m_p − ρ V_p) g + F_c,
//! ```
//!
//! (likewise for the torque), which holds further down in density ratio:
//! it is the same balance without the rigid-motion assumption, so the two
//! agree when the inner fluid does move rigidly. The derivative is over
//! the volume that moves with the particle (Kempe & Fröhlich 2012; Breugem
//! 2012), in two parts: the change of `I` over the stage on the faces where
//! the particle stands, `(I⁺ − I⁻)/h`, and the change that moving the
//! particle made, at the rate measured over the previous stage, `(I⁻ −
//! I⁺_prev)/h_prev`, where `I⁺_prev` is the previous stage's `I⁺` on the
//! faces where the particle stood then (kept per particle). A derivative
//! over a volume held fixed, `∫ α ∂u/∂t` alone, misses that flux through
//! the moving surface, about `ρ V_p ω × u_p` for a spinning grain: a lift
//! that depends on the frame of reference. Before the first stage the
//! particle is taken to have moved over one stage at its velocity, so that
//! the transport starts with the motion.
//!
//! The fluid answers a change of a particle's velocity one stage later
//! (the next forcing sees it). A contact lasts far less than a stage, so a
//! grain would bounce off a wall alone and only then have to drag the
//! fluid it carries along: an inelastic collision between the grain and
//! its added mass, which would eat most of the rebound. With the load
//! above, each particle therefore carries a virtual mass `C_v ρ V_p`
//! (after Schwarz, Kempe & Fröhlich 2015): its inertia in the DEM is
//! `m_p + C_v ρ V_p`, and the load hands back the impulse the fluid's
//! lagged answer takes away. Under eq. 7 the layer answers within about a
//! stage, and each stage adds back `C_v ρ V_p Δu / h`, the velocity change
//! `Δu` of the previous stage spread over this one; a layer relaxed more
//! slowly (held, or at its renewal rate) answers over several stages, and
//! the load adds back `C_v ρ d/dt ∫_{V_p(t)} u`, as the fluid in the
//! grain's volume answers ([`crate::stage_loads::VirtualMassReturn`]).
//! Over a run the two cancel; in a contact the grain and its added mass
//! bounce together.

use grainflow_core::Vec3;
use grainflow_core::{State, StateError};
use grainflow_dem::{DemSystem, StepDiagnostics};
use grainflow_fluid::{stage_fraction, Block, FlowSolver, FluidError, StepReport, STAGES};
use std::f64::consts::PI;
use std::time::Instant;

use crate::forcing::{vectors_on_owners, Bodies, Exponents, ImmersedBoundaries, Loads};
use crate::layer_forcing::{renewal_exponent, slip_from_sums, LayerForcing, SLIP_SUMS};
use crate::stage_loads::{
    hydrodynamic_loads, inner_momentum_rate, set_stage_loads, GrainLoad, StageMeasures,
    VirtualMassReturn,
};

/// Density ratio `ρ_p/ρ` below which the rigid-inner-fluid load (eq. 5–6)
/// blows up: in translation within a few time units at 1.6 and below, at
/// 1.7 depending on Δt (test `density_ratio_map`); in rotation, a grain
/// spun impulsively, at 1.7 (test
/// `an_impulsive_spin_decays_without_reversing_where_the_load_holds`).
/// Runs refuse it.
pub const RIGID_INNER_FLUID_FAILS_BELOW: f64 = 1.8;

/// Below this density ratio the rigid-inner-fluid load holds but a spun
/// grain's spin overshoots and oscillates (it reverses in one step at 2.0,
/// decays monotonically from 2.8): runs warn.
pub const RIGID_INNER_FLUID_WARNS_BELOW: f64 = 2.8;

/// Where the paper's rigid-inner-fluid load holds, under a forcing of the
/// transition layer: below `fails_below` runs refuse it, below
/// `warns_below` they warn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidInnerFluidLimits {
    pub fails_below: f64,
    pub warns_below: f64,
}

/// [`RigidInnerFluidLimits`] under `layer`. Eq. 7 at every stage, and a
/// held layer (eq. 7 at its own step): [`RIGID_INNER_FLUID_FAILS_BELOW`]
/// and [`RIGID_INNER_FLUID_WARNS_BELOW`]. The layer relaxed at its renewal
/// rate takes less of the grain's motion into its fluid at a stage, and
/// the load holds further down (tests
/// `rigid_inner_fluid_holds_further_down_under_the_renewal_forcing` and
/// `under_the_renewal_forcing_a_rigid_inner_fluid_spin_decays_further_down`,
/// D/Δx = 8): in translation from 1.25 (it blows up at 1.2), in rotation
/// monotonically from 1.6, overshooting at 1.3–1.5, blowing up at 1.2.
pub fn rigid_inner_fluid_limits(layer: LayerForcing) -> RigidInnerFluidLimits {
    match layer {
        LayerForcing::Renewal => RigidInnerFluidLimits {
            fails_below: 1.3,
            warns_below: 1.6,
        },
        LayerForcing::EveryStage | LayerForcing::Held { .. } => RigidInnerFluidLimits {
            fails_below: RIGID_INNER_FLUID_FAILS_BELOW,
            warns_below: RIGID_INNER_FLUID_WARNS_BELOW,
        },
    }
}

/// How the hydrodynamic load on a particle is formed from the forcing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coupling {
    /// `−ρ ∫ f + ρ d/dt ∫ α u` plus buoyancy: stable for any density ratio.
    InnerFluidMomentum,
    /// The paper's eq. 5–6, `−ρ ρ_p/(ρ_p − ρ) ∫ f`: the fluid inside a
    /// particle assumed rigid; unstable as `ρ_p/ρ` nears 1.
    RigidInnerFluid,
}

/// Wall seconds spent in each part of the coupled steps so far.
#[derive(Clone, Copy, Debug, Default)]
pub struct Timings {
    /// Prediction and projection of the flow.
    pub flow: f64,
    /// Direct forcing and the loads it gives.
    pub forcing: f64,
    /// Inner momentum before and after each stage and the loads' assembly.
    pub loads: f64,
    /// DEM sub-steps.
    pub dem: f64,
}

/// What a coupled step reports.
#[derive(Clone, Copy, Debug)]
pub struct CoupledReport {
    pub flow: StepReport,
    /// The DEM diagnostics of the step's last sub-step, with the largest
    /// overlap of all of them (positive if any contact happened).
    pub dem: StepDiagnostics,
    /// DEM sub-steps taken in the step.
    pub dem_substeps: usize,
}

/// A fluid with immersed grains: the flow, the DEM and the forcing that
/// ties them.
pub struct CoupledSystem {
    pub flow: FlowSolver,
    pub dem: DemSystem,
    pub immersed: ImmersedBoundaries,
    /// Fluid density ρ (kg/m³): the flow solver works per unit density.
    pub fluid_density: f64,
    pub coupling: Coupling,
    /// Largest DEM sub-step (s).
    pub dem_dt: f64,
    /// The virtual-mass coefficient `C_v` (the added-mass coefficient of
    /// the grain, 1/2 for a sphere and 1 for a disc, with the
    /// inner-fluid-momentum load; 0 with the rigid inner fluid).
    pub virtual_mass: f64,
    pub timings: Timings,
    /// Length of the last stage (s), over which the particles moved from
    /// where their `inner_fluid_momentum` was measured; none before the
    /// first stage.
    previous_stage_dt: Option<f64>,
}

impl CoupledSystem {
    /// Couples `flow` and `dem` (same domain; the DEM's gravity acts on
    /// the grains, the flow's body force on the fluid). On several ranks
    /// the DEM must share the domain like the flow (the same process
    /// grid); its ghosts are rebuilt to reach [`crate::forcing::ghost_reach`].
    /// Collective.
    pub fn new(
        flow: FlowSolver,
        dem: DemSystem,
        fluid_density: f64,
        coupling: Coupling,
        dem_dt: f64,
    ) -> Self {
        let immersed = ImmersedBoundaries::new(&flow.grid);
        let mut dem = dem;
        let virtual_mass = carry_virtual_mass(&mut dem, coupling, fluid_density);
        // Every grain that forces this rank's cells must be here, and the
        // ghosts carry the inertia with the virtual mass.
        let max_radius = dem.communicator.max(dem.particles.max_radius());
        dem.ghost_reach = dem
            .ghost_reach
            .max(crate::forcing::ghost_reach(&flow.grid, max_radius));
        dem.rebuild();
        CoupledSystem {
            flow,
            dem,
            immersed,
            fluid_density,
            coupling,
            dem_dt,
            virtual_mass,
            timings: Timings::default(),
            previous_stage_dt: None,
        }
    }

    /// Advances fluid and grains by `dt`; refuses the step (nothing
    /// changed) when the flow's stability limits forbid it.
    pub fn step(&mut self, dt: f64) -> Result<CoupledReport, FluidError> {
        self.step_observed(dt, |_| {})
    }

    /// [`CoupledSystem::step`], handing the grains to `after_stage` after
    /// each stage's DEM sub-steps: an analysis that needs the grains'
    /// motion finer than a step (a rebound's peak, which the fluid's answer
    /// in the next stages takes down again). Every rank calls it the same
    /// number of times, so it may make collective calls.
    pub fn step_observed(
        &mut self,
        dt: f64,
        mut after_stage: impl FnMut(&DemSystem),
    ) -> Result<CoupledReport, FluidError> {
        self.flow.begin_step(dt)?;
        let mut max_divergence: f64 = 0.0;
        let mut substeps = 0;
        let mut dem_report = StepDiagnostics::default();
        let mut largest_overlap: f64 = 0.0;
        let unknowns: Vec<_> = (0..self.flow.grid.dim())
            .map(|c| *self.flow.velocity_unknowns(c))
            .collect();
        for stage in 0..STAGES {
            let stage_dt = stage_fraction(stage) * dt;
            let clock = Instant::now();
            // The particles stand still until the DEM runs; their ghosts
            // take their latest motion.
            self.dem.refresh_ghosts();
            // Where the last move started (before the stage's bodies,
            // whose forcing sums wait for `apply`).
            let (moved_from, moved_over) = self.inner_momentum_moved_from(&unknowns, stage_dt);
            let (bodies, before) = self.immersed.bodies_with_inner_momentum(
                &self.dem.particles,
                &self.flow.grid,
                &unknowns,
                &self.flow.velocity,
            );
            let before = before.summed_on_owners(&self.dem);
            let clock = self.lap(clock, Part::Loads);
            self.flow.predict(stage, dt);
            let clock = self.lap(clock, Part::Flow);
            let exponents = self.layer_exponents(&bodies, dt);
            let passes = exponents.passes(&bodies, &self.dem.communicator);
            let exponents = exponents.per_pass(passes);
            // Every pass forces with the same fractions 1 − (1 − α)^e:
            // made once, then forced as eq. 7 forces its fractions.
            let raised = (exponents != Exponents::Uniform(1.0)).then(|| bodies.raised(&exponents));
            let (forced, exponents) = match &raised {
                Some(raised) => (raised, Exponents::Uniform(1.0)),
                None => (&bodies, exponents),
            };
            // Eq. 7 in one pass reads the faces for its loads after the
            // projection, with the inner momentum (`deferred_loads.rs`).
            let deferred = passes == 1 && forced.forcing_sums_made();
            let mut clock = clock;
            let mut forcing = if deferred {
                let (grid, velocity) = (&self.flow.grid, &mut self.flow.velocity);
                self.immersed
                    .force_keeping_prediction(grid, velocity, forced);
                Loads::zeros(self.dem.particles.len())
            } else {
                // Each pass but the last is projected here, the last below
                // (`forcing_passes.rs`).
                self.immersed
                    .begin_forcing(&self.flow.grid, forced, &exponents);
                for _ in 1..passes {
                    let (grid, velocity) = (&self.flow.grid, &mut self.flow.velocity);
                    self.immersed.force_pass(grid, velocity, forced);
                    clock = self.lap(clock, Part::Forcing);
                    max_divergence = max_divergence.max(self.flow.project(stage, dt));
                    clock = self.lap(clock, Part::Flow);
                }
                let (grid, velocity) = (&self.flow.grid, &mut self.flow.velocity);
                self.immersed
                    .last_pass(grid, velocity, forced, stage_dt, &exponents, passes)
            };
            let clock = self.lap(clock, Part::Forcing);
            max_divergence = max_divergence.max(self.flow.project(stage, dt));
            let clock = self.lap(clock, Part::Flow);
            let after = if deferred {
                let (loads, after) = self.immersed.loads_and_inner_momentum(
                    &self.flow.grid,
                    &self.flow.velocity,
                    &bodies,
                    stage_dt,
                );
                forcing.add(&loads);
                after
            } else {
                self.immersed
                    .inner_momentum(&self.flow.grid, &self.flow.velocity, &bodies)
            };
            let forcing = forcing.summed_on_owners(&self.dem);
            let after = after.summed_on_owners(&self.dem);
            // Along a periodic axis the fluid carries gravity as a body
            // force b, and the forcing hands each grain the body force on
            // the fluid its grid volume holds.
            let body_force = Vec3::from(self.flow.body_force);
            let grid_volumes = (body_force != Vec3::zeros()).then(|| {
                let local = self.immersed.grid_volumes(&self.flow.grid, &bodies);
                vectors_on_owners(&self.dem, &local, 1)
            });
            let inner_rate =
                inner_momentum_rate(&before, &after, &moved_from, moved_over, stage_dt);
            let loads = hydrodynamic_loads(
                &self.dem,
                self.grain_load(),
                body_force,
                &StageMeasures {
                    forcing: &forcing,
                    inner_rate: &inner_rate,
                    grid_volumes: grid_volumes.as_deref(),
                },
                stage_dt,
            );
            set_stage_loads(&mut self.dem, &loads, &after);
            self.previous_stage_dt = Some(stage_dt);
            let clock = self.lap(clock, Part::Loads);
            let (report, count) = dem_substeps(&mut self.dem, stage_dt, self.dem_dt);
            largest_overlap = largest_overlap.max(report.max_overlap_ratio);
            dem_report = report;
            substeps += count;
            self.lap(clock, Part::Dem);
            after_stage(&self.dem);
        }
        dem_report.max_overlap_ratio = largest_overlap;
        Ok(CoupledReport {
            flow: self.flow.end_step(dt, max_divergence),
            dem: dem_report,
            dem_substeps: substeps,
        })
    }

    /// The grains' exponents of the stage's forcing in a step of `dt`:
    /// under [`crate::LayerForcing::Renewal`] each local particle's `r Δt`, from
    /// its layer's slip in the predicted flow summed over the ranks and
    /// copied onto its ghosts, so that every copy of a grain forces with
    /// one rate (collective); under the others, one for all.
    fn layer_exponents(&self, bodies: &Bodies, dt: f64) -> Exponents {
        if let Some(exponent) = self.immersed.layer.uniform_exponent(dt) {
            return Exponents::Uniform(exponent);
        }
        let mut sums = self.immersed.layer_slips(&self.flow.velocity, bodies);
        self.dem.sum_onto_owners(&mut sums, SLIP_SUMS);
        self.dem.copy_onto_ghosts(&mut sums, SLIP_SUMS);
        let spacing = self.immersed.width / std::f64::consts::SQRT_2;
        let exponents = sums
            .chunks_exact(SLIP_SUMS)
            .map(|own| renewal_exponent(slip_from_sums(own), self.flow.viscosity, spacing, dt))
            .collect();
        Exponents::PerParticle(exponents)
    }

    /// Adds the time since `clock` to `part`; returns the time now.
    fn lap(&mut self, clock: Instant, part: Part) -> Instant {
        let now = Instant::now();
        let seconds = (now - clock).as_secs_f64();
        let t = &mut self.timings;
        match part {
            Part::Flow => t.flow += seconds,
            Part::Forcing => t.forcing += seconds,
            Part::Loads => t.loads += seconds,
            Part::Dem => t.dem += seconds,
        }
        now
    }

    /// The inner momentum each owned particle's last move started from,
    /// and the time that move took: the previous stage's `I⁺`, kept per
    /// particle, and its length; before the first stage, `I` on the faces
    /// the particle would have stood on one stage of `stage_dt` earlier at
    /// its present velocity. Collective.
    fn inner_momentum_moved_from(&mut self, unknowns: &[Block], stage_dt: f64) -> (Loads, f64) {
        if let Some(previous) = self.previous_stage_dt {
            return (kept_inner_momentum(&self.dem), previous);
        }
        let earlier = moved_back(&self.dem, stage_dt);
        let bodies = self.immersed.bodies(&earlier, &self.flow.grid, unknowns);
        let measured = self
            .immersed
            .inner_momentum(&self.flow.grid, &self.flow.velocity, &bodies)
            .summed_on_owners(&self.dem);
        (measured, stage_dt)
    }

    /// How the grains take their loads: what [`hydrodynamic_loads`] reads.
    fn grain_load(&self) -> GrainLoad {
        GrainLoad {
            coupling: self.coupling,
            fluid_density: self.fluid_density,
            virtual_mass: self.virtual_mass,
            virtual_mass_return: VirtualMassReturn::for_layer(&self.immersed.layer),
        }
    }

    /// The smallest `ρ_p/ρ` among the moving particles of every rank
    /// (infinite if none).
    pub fn smallest_density_ratio(&self) -> f64 {
        smallest_density_ratio(&self.dem, self.fluid_density)
    }
}

/// The virtual-mass coefficient `C_v` of `coupling` (a grain's added-mass
/// coefficient with the inner-fluid-momentum load, 0 with the rigid inner
/// fluid), added to the inertia of every moving owned grain of `dem`.
pub(crate) fn carry_virtual_mass(
    dem: &mut DemSystem,
    coupling: Coupling,
    fluid_density: f64,
) -> f64 {
    let dimension = dem.dimension();
    let virtual_mass = match coupling {
        Coupling::InnerFluidMomentum => crate::settling::added_mass_coefficient(dimension),
        Coupling::RigidInnerFluid => 0.0,
    };
    let p = &mut dem.particles;
    for k in 0..p.n_owned {
        if p.inverse_mass[k] > 0.0 {
            let carried = virtual_mass * fluid_density * particle_volume(dimension, p.radius[k]);
            p.inverse_mass[k] = 1.0 / (p.mass[k] + carried);
        }
    }
    virtual_mass
}

/// The smallest `ρ_p/ρ` among the moving grains of `dem` on every rank
/// (infinite if none; collective).
pub(crate) fn smallest_density_ratio(dem: &DemSystem, fluid_density: f64) -> f64 {
    let p = &dem.particles;
    let dimension = dem.dimension();
    let local = (0..p.n_owned)
        .filter(|&k| p.inverse_mass[k] > 0.0)
        .map(|k| p.mass[k] / particle_volume(dimension, p.radius[k]) / fluid_density)
        .fold(f64::INFINITY, f64::min);
    -dem.communicator.max(-local)
}

/// The inner momentum each owned grain keeps from the previous stage.
pub(crate) fn kept_inner_momentum(dem: &DemSystem) -> Loads {
    let p = &dem.particles;
    let n = p.n_owned;
    Loads {
        force: p.inner_fluid_momentum[..n].to_vec(),
        torque: p.inner_fluid_angular_momentum[..n].to_vec(),
    }
}

/// The grains of `dem` where they stood `stage_dt` earlier at their
/// present velocities (before the first stage, where the transport of
/// their inner momentum starts).
pub(crate) fn moved_back(dem: &DemSystem, stage_dt: f64) -> grainflow_dem::Particles {
    let mut earlier = dem.particles.clone();
    for k in 0..earlier.len() {
        earlier.position[k] -= earlier.velocity[k] * stage_dt;
    }
    earlier
}

/// Saves the coupling's own state: the last stage's length and the time
/// spent in each part.
pub(crate) fn save_coupling(state: &mut State, previous_stage_dt: Option<f64>, t: &Timings) {
    state.put_f64s("coupled.previous_stage_dt", previous_stage_dt.as_slice());
    state.put_f64s("coupled.timings", &[t.flow, t.forcing, t.loads, t.dem]);
}

/// Takes back what [`save_coupling`] saved.
pub(crate) fn restore_coupling(state: &mut State) -> Result<(Option<f64>, Timings), StateError> {
    let previous = state.take_f64s("coupled.previous_stage_dt")?;
    if previous.len() > 1 {
        return Err(StateError(
            "coupled.previous_stage_dt holds at most one number".into(),
        ));
    }
    let t = state.take_f64s_of_len("coupled.timings", 4)?;
    let timings = Timings {
        flow: t[0],
        forcing: t[1],
        loads: t[2],
        dem: t[3],
    };
    Ok((previous.first().copied(), timings))
}

/// The DEM over a stage of `stage_dt` in equal sub-steps no longer than
/// `dem_dt`: the last sub-step's diagnostics with the largest overlap of
/// all of them, and the number of sub-steps.
pub(crate) fn dem_substeps(
    dem: &mut DemSystem,
    stage_dt: f64,
    dem_dt: f64,
) -> (StepDiagnostics, usize) {
    let count = (stage_dt / dem_dt).ceil().max(1.0) as usize;
    let mut report = StepDiagnostics::default();
    let mut largest: f64 = 0.0;
    for _ in 0..count {
        report = dem.step(stage_dt / count as f64);
        largest = largest.max(report.max_overlap_ratio);
    }
    report.max_overlap_ratio = largest;
    (report, count)
}

#[derive(Clone, Copy)]
enum Part {
    Flow,
    Forcing,
    Loads,
    Dem,
}

/// Volume of a sphere, or area of a disc (2D, per unit depth).
pub fn particle_volume(dimension: grainflow_core::Dimension, radius: f64) -> f64 {
    match dimension {
        grainflow_core::Dimension::Three => 4.0 / 3.0 * PI * radius.powi(3),
        grainflow_core::Dimension::Two => PI * radius * radius,
    }
}

impl CoupledSystem {
    /// Saves what the next coupled step reads: the flow, the grains (with
    /// the inner fluid momentum and the velocity at the start of the last
    /// DEM interval that travel with them), the length of the last stage,
    /// and the time spent so far in each part.
    pub fn save_state(&self, state: &mut State) {
        self.flow.save_state(state);
        self.dem.save_state(state);
        save_coupling(state, self.previous_stage_dt, &self.timings);
    }

    /// Takes back the states saved on every rank of a job of another size
    /// (read by every rank; collective): the flow block by block, the
    /// grains by where they are, the rest from the first state.
    pub fn restore_redistributed(&mut self, states: &mut [State]) -> Result<(), StateError> {
        self.flow.restore_redistributed(states)?;
        self.dem.restore_redistributed(states)?;
        self.restore_coupling(&mut states[0])
    }

    /// Takes back what [`CoupledSystem::save_state`] saved, into a system
    /// built from the same case on a rank of a job of the same size.
    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        self.flow.restore_state(state)?;
        self.dem.restore_state(state)?;
        self.restore_coupling(state)
    }

    fn restore_coupling(&mut self, state: &mut State) -> Result<(), StateError> {
        (self.previous_stage_dt, self.timings) = restore_coupling(state)?;
        Ok(())
    }
}
