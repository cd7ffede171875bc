//! The coupled step of an (r, z) flow and grains on its axis: the stages
//! of [`crate::coupled`] (prediction, forcing, projection, inner momentum,
//! DEM sub-steps with the loads held), with the (r, z) forcing of
//! [`super::forcing`] and the same hydrodynamic loads, virtual mass and
//! lubrication. The DEM is the Cartesian one, its grains on the line
//! x = y = 0, the symmetry axis along its z: with every load along z they
//! stay on it.

use std::time::Instant;

use grainflow_core::Vec3;
use grainflow_dem::{DemSystem, StepDiagnostics};
use grainflow_fluid::axisymmetric::AxisymmetricFlow;
use grainflow_fluid::{stage_fraction, FluidError, STAGES};

use super::bodies::{check_grains_on_axis, EndLayers};
use super::forcing::AxisymmetricImmersed;
use crate::coupled::{
    carry_virtual_mass, dem_substeps, kept_inner_momentum, moved_back, restore_coupling,
    save_coupling, smallest_density_ratio, CoupledReport, Coupling, Timings,
};
use crate::exponents::passes_for;
use crate::forcing::Loads;
use crate::stage_loads::{
    hydrodynamic_loads, inner_momentum_rate, set_stage_loads, GrainLoad, StageMeasures,
    VirtualMassReturn,
};

/// An (r, z) fluid with grains on its axis.
pub struct AxisymmetricCoupledSystem {
    pub flow: AxisymmetricFlow,
    pub dem: DemSystem,
    pub immersed: AxisymmetricImmersed,
    /// Fluid density ρ (kg/m³).
    pub fluid_density: f64,
    pub coupling: Coupling,
    /// Largest DEM sub-step (s).
    pub dem_dt: f64,
    /// The virtual-mass coefficient `C_v` (1/2, a sphere's added mass,
    /// with the inner-fluid-momentum load; 0 with the rigid inner fluid).
    pub virtual_mass: f64,
    pub timings: Timings,
    /// Length of the last stage (s); none before the first.
    previous_stage_dt: Option<f64>,
}

impl AxisymmetricCoupledSystem {
    /// Couples `flow` and `dem`: the grains on the axis (x = y = 0) with
    /// their supports in the uniform radial core, gravity along z.
    pub fn new(
        flow: AxisymmetricFlow,
        dem: DemSystem,
        fluid_density: f64,
        coupling: Coupling,
        dem_dt: f64,
    ) -> Result<Self, FluidError> {
        check_grains_on_axis(&dem.particles, &flow.grid)?;
        let gravity = dem.domain.gravity;
        if gravity.x != 0.0 || gravity.y != 0.0 {
            return Err(FluidError::Unsupported(format!(
                "gravity ({}, {}, {}) m/s² has a part across the axis: an axisymmetric scene \
                 takes gravity along z only",
                gravity.x, gravity.y, gravity.z
            )));
        }
        let immersed = AxisymmetricImmersed::new(&flow.grid, EndLayers::NONE);
        let mut dem = dem;
        let virtual_mass = carry_virtual_mass(&mut dem, coupling, fluid_density);
        Ok(AxisymmetricCoupledSystem {
            flow,
            dem,
            immersed,
            fluid_density,
            coupling,
            dem_dt,
            virtual_mass,
            timings: Timings::default(),
            previous_stage_dt: None,
        })
    }

    /// Advances fluid and grains by `dt`; refuses the step (nothing
    /// changed) when the flow's CFL limit forbids it.
    pub fn step(&mut self, dt: f64) -> Result<CoupledReport, FluidError> {
        self.step_observed(dt, |_| {})
    }

    /// [`AxisymmetricCoupledSystem::step`], handing the grains to
    /// `after_stage` after each stage's DEM sub-steps.
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
        let grain_load = GrainLoad {
            coupling: self.coupling,
            fluid_density: self.fluid_density,
            virtual_mass: self.virtual_mass,
            virtual_mass_return: VirtualMassReturn::for_layer(&self.immersed.layer),
        };
        for stage in 0..STAGES {
            let stage_dt = stage_fraction(stage) * dt;
            let clock = Instant::now();
            let bodies = self.immersed.bodies(&self.dem.particles, &self.flow);
            let before = self.immersed.inner_momentum(&self.flow, &bodies);
            let (moved_from, moved_over) = self.inner_momentum_moved_from(stage_dt);
            let clock = lap(&mut self.timings.loads, clock);
            self.flow.predict(stage, dt);
            let clock = lap(&mut self.timings.flow, clock);
            // Passes of exponent at most one, each but the last projected
            // here (`Exponents::passes`); one under eq. 7.
            let exponents = self.immersed.exponents(&self.flow, &bodies, dt);
            let passes = passes_for(exponents.iter().copied().fold(0.0, f64::max));
            let exponents: Vec<f64> = exponents.iter().map(|e| e / passes as f64).collect();
            let mut forcing = Loads::zeros(self.dem.particles.len());
            let mut clock = clock;
            for pass in 0..passes {
                if pass > 0 {
                    clock = lap(&mut self.timings.forcing, clock);
                    max_divergence = max_divergence.max(self.flow.project(stage, dt));
                    clock = lap(&mut self.timings.flow, clock);
                }
                forcing.add(
                    &self
                        .immersed
                        .apply(&mut self.flow, &bodies, stage_dt, &exponents),
                );
            }
            let clock = lap(&mut self.timings.forcing, clock);
            max_divergence = max_divergence.max(self.flow.project(stage, dt));
            let clock = lap(&mut self.timings.flow, clock);
            let after = self.immersed.inner_momentum(&self.flow, &bodies);
            let body_force = Vec3::new(0.0, 0.0, self.flow.body_force);
            let grid_volumes =
                (body_force != Vec3::zeros()).then(|| self.immersed.grid_volumes(&bodies));
            let inner_rate =
                inner_momentum_rate(&before, &after, &moved_from, moved_over, stage_dt);
            let measured = StageMeasures {
                forcing: &forcing,
                inner_rate: &inner_rate,
                grid_volumes: grid_volumes.as_deref(),
            };
            let loads = hydrodynamic_loads(&self.dem, grain_load, body_force, &measured, stage_dt);
            set_stage_loads(&mut self.dem, &loads, &after);
            self.previous_stage_dt = Some(stage_dt);
            let clock = lap(&mut self.timings.loads, clock);
            let (report, count) = dem_substeps(&mut self.dem, stage_dt, self.dem_dt);
            largest_overlap = largest_overlap.max(report.max_overlap_ratio);
            dem_report = report;
            substeps += count;
            lap(&mut self.timings.dem, clock);
            after_stage(&self.dem);
        }
        dem_report.max_overlap_ratio = largest_overlap;
        Ok(CoupledReport {
            flow: self.flow.end_step(dt, max_divergence),
            dem: dem_report,
            dem_substeps: substeps,
        })
    }

    /// The inner momentum each grain's last move started from and the
    /// time it took: the previous stage's, kept with the grain; before the
    /// first stage, measured where the grain stood one stage earlier at
    /// its present velocity.
    fn inner_momentum_moved_from(&mut self, stage_dt: f64) -> (Loads, f64) {
        if let Some(previous) = self.previous_stage_dt {
            return (kept_inner_momentum(&self.dem), previous);
        }
        let bodies = self
            .immersed
            .bodies(&moved_back(&self.dem, stage_dt), &self.flow);
        (self.immersed.inner_momentum(&self.flow, &bodies), stage_dt)
    }
}

/// Adds the time since `clock` to `part`; returns the time now.
fn lap(part: &mut f64, clock: Instant) -> Instant {
    let now = Instant::now();
    *part += (now - clock).as_secs_f64();
    now
}

impl AxisymmetricCoupledSystem {
    /// Saves what the next coupled step reads: the flow, the grains (with
    /// what travels with them), the last stage's length and the timings.
    pub fn save_state(&self, state: &mut grainflow_core::State) {
        self.flow.save_state(state);
        self.dem.save_state(state);
        save_coupling(state, self.previous_stage_dt, &self.timings);
    }

    /// Takes back what [`AxisymmetricCoupledSystem::save_state`] saved, into
    /// a system built from the same case.
    pub fn restore_state(
        &mut self,
        state: &mut grainflow_core::State,
    ) -> Result<(), grainflow_core::StateError> {
        self.flow.restore_state(state)?;
        self.dem.restore_state(state)?;
        (self.previous_stage_dt, self.timings) = restore_coupling(state)?;
        Ok(())
    }

    /// The smallest `ρ_p/ρ` among the moving grains (infinite if none).
    pub fn smallest_density_ratio(&self) -> f64 {
        smallest_density_ratio(&self.dem, self.fluid_density)
    }
}
