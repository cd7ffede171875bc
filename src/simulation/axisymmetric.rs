//! Grains on the axis of an axisymmetric fluid (`domain.geometry =
//! "axisymmetric"`): coupled steps of the (r, z) flow and the DEM, fixed or
//! adapted to a CFL number, the last one landing on the end time; the
//! sphere's analysis, the series and the (r, z) fields.

use super::coupled::{
    check_dem_substep, check_density_ratio, collapsed_step, coupled_summary, done_line,
    unstable_step, CoupledCounts,
};
use crate::analysis::sphere_in_fluid::SphereInFluid;
use crate::case::Case;
use crate::{scene::axisymmetric as axisymmetric_scene, RunError};
use grainflow_core::{Communicator, State, StateError};
use grainflow_fluid::time_step_for_cfl_rates;
use grainflow_ibm::axisymmetric::AxisymmetricCoupledSystem;
use grainflow_ibm::CoupledReport;
use serde_json::{json, Map, Value};

pub struct AxisymmetricModel {
    pub system: AxisymmetricCoupledSystem,
    analysis: SphereInFluid,
    contact_time: f64,
    dt: f64,
    steps: u64,
    dem_substeps: usize,
    max_divergence: f64,
    last_report: Option<CoupledReport>,
    pub description: Vec<String>,
    pub warnings: Vec<String>,
}

impl AxisymmetricModel {
    /// The scene of a validated axisymmetric case; refuses, before anything
    /// is written, what cannot run (more than one rank, a grain off the
    /// axis, a DEM sub-step past the contacts' limit, a load that fails).
    pub fn build(case: &Case, communicator: Communicator) -> Result<Self, RunError> {
        let (system, contact_time) =
            axisymmetric_scene::build(case, communicator).map_err(RunError::Case)?;
        let mut warnings = Vec::new();
        warnings.extend(check_dem_substep(system.dem_dt, contact_time)?);
        warnings.extend(check_density_ratio(
            system.smallest_density_ratio(),
            system.coupling,
            system.immersed.layer,
            3,
        )?);
        let dt = case
            .time
            .dt
            .expect("validated: a coupled scene has time.dt");
        let grid = &system.flow.grid;
        let [nr, nz] = grid.cells;
        let description = vec![
            format!(
                "grainflow {}: {} grains on the axis of an axisymmetric fluid, (r, z) grid {nr} x \
                 {nz} ({} cells, radius {:.4e} m, radial cells {:.4e} to {:.4e} m, dz {:.4e} m), \
                 immersed boundaries ({:?}), soft-sphere DEM sub-cycled in each stage{}",
                env!("CARGO_PKG_VERSION"),
                system.dem.particles.n_owned,
                nr * nz,
                grid.radius,
                grid.smallest_width(),
                (1..=nr).map(|i| grid.width(i)).fold(0.0, f64::max),
                grid.dz,
                system.coupling,
                if system.dem.lubrication.is_some() {
                    ", lubrication"
                } else {
                    ""
                }
            ),
            format!(
                "dt = {dt:.4e} s (fluid), DEM sub-step ≤ {:.4e} s = {:.4} t_c",
                system.dem_dt,
                system.dem_dt / contact_time
            ),
        ];
        let analysis = SphereInFluid::new(case, &system.dem, system.fluid_density);
        Ok(AxisymmetricModel {
            system,
            analysis,
            contact_time,
            dt,
            steps: 0,
            dem_substeps: 0,
            max_divergence: 0.0,
            last_report: None,
            description,
            warnings,
        })
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }

    pub fn steps(&self) -> u64 {
        self.steps
    }

    pub fn reached(&self, end: f64) -> bool {
        self.system.flow.time >= end * (1.0 - 1e-12)
    }

    /// `time.dt`, or with `time.cfl` the step at which the flow (cell by
    /// cell, with a sliding wall and the body force of a periodic pipe) or
    /// the grain (speed over the smallest cell) reaches that CFL number, at
    /// most `time.dt`: the larger rate, as in 3D (`coupled::step_size`).
    fn step_size(&self, case: &Case) -> f64 {
        let largest = case
            .time
            .dt
            .expect("validated: grains in a fluid have time.dt");
        let Some(cfl) = case.time.cfl else {
            return largest;
        };
        let flow = &self.system.flow;
        let h = flow.grid.smallest_width().min(flow.grid.dz);
        let speed_rate = flow.max_cfl(1.0).max(self.system.dem.max_speed() / h);
        let acceleration_rate = flow.body_force.abs() / flow.grid.dz;
        largest.min(time_step_for_cfl_rates(cfl, speed_rate, acceleration_rate))
    }

    /// One coupled step, the last one landing on `end`; the diagnosis of a
    /// failure.
    pub fn advance(&mut self, case: &Case, end: f64) -> Result<(), String> {
        let step_dt = self.step_size(case).min(end - self.system.flow.time);
        self.dt = step_dt;
        let steps = self.steps;
        let time = self.system.flow.time;
        if let Some(why) = collapsed_step(step_dt, case, time, end) {
            return Err(format!(
                "unstable at t = {time:.6e} s (step {steps}): {why}"
            ));
        }
        let analysis = &mut self.analysis;
        let report = self
            .system
            .step_observed(step_dt, |dem| analysis.after_stage(dem))
            .map_err(|e| {
                format!("unstable at t = {time:.6e} s (step {steps}): {e}; reduce time.dt")
            })?;
        self.last_report = Some(report);
        self.dem_substeps += report.dem_substeps;
        self.max_divergence = report.flow.max_divergence;
        let time = self.system.flow.time;
        if let Some(why) = unstable_step(&report, step_dt, case) {
            return Err(format!(
                "unstable at t = {time:.6e} s (step {steps}): {why}"
            ));
        }
        self.steps += 1;
        self.analysis
            .after_step(time, &self.system.dem, step_dt, &self.last_report);
        Ok(())
    }

    /// A row of `flow_series.csv`: the fluid's kinetic energy (J), its CFL
    /// number at the last step and divergence.
    pub fn flow_row(&self, dt: f64) -> [f64; 6] {
        let flow = &self.system.flow;
        [
            flow.time,
            dt,
            self.steps as f64,
            self.system.fluid_density * flow.kinetic_energy(),
            flow.max_cfl(dt),
            self.max_divergence,
        ]
    }

    pub fn metrics(&self) -> Map<String, Value> {
        self.analysis.metrics()
    }

    /// The scene's own entries of `summary.json`.
    pub fn summary(&self, case: &Case, wall_seconds: f64) -> Map<String, Value> {
        let grid = &self.system.flow.grid;
        let scene = [
            ("particles", json!(self.system.dem.particles.n_owned)),
            ("cells", json!(grid.cells[0] * grid.cells[1])),
            ("geometry", json!("axisymmetric")),
            ("dimension", json!(3)),
        ];
        let counts = CoupledCounts {
            steps: self.steps,
            dem_substeps: self.dem_substeps,
            dem_dt: self.system.dem_dt,
            contact_time: self.contact_time,
            layer: self.system.immersed.layer,
            timings: &self.system.timings,
        };
        coupled_summary(scene, case, &counts, wall_seconds)
    }

    pub fn done_line(&self, wall_seconds: f64) -> String {
        done_line(
            self.steps,
            self.dem_substeps,
            wall_seconds,
            &self.system.timings,
        )
    }

    pub fn save_state(&self, state: &mut State) {
        self.system.save_state(state);
        state.put_value("coupled.analysis", &self.analysis);
        state.put_value(
            "coupled.loop",
            &(self.dt, self.steps, self.dem_substeps, self.max_divergence),
        );
    }

    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        self.system.restore_state(state)?;
        self.analysis = state.take_value("coupled.analysis")?;
        (self.dt, self.steps, self.dem_substeps, self.max_divergence) =
            state.take_value("coupled.loop")?;
        Ok(())
    }
}
