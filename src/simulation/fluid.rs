//! A fluid alone: steps of the flow solver (three RK3 stages with
//! Crank–Nicolson viscosity and a projection each), fixed or adapted to a
//! CFL number, and the metrics of the analytic flows.

use crate::case::{AnalysisSection, Case};
use crate::scene::fluid::{self as fluid_scene, ChannelProfile, ExactFlow};
use crate::{sharing, RunError};
use grainflow_core::{Communicator, State, StateError};
use grainflow_fluid::{FlowSolver, Location, StepReport, ViscousScheme, CFL_LIMIT};
use serde_json::{json, Map, Value};

/// A fluid alone: steps of the flow solver, fixed or adapted to a CFL
/// number; the last step lands on the end time.
pub struct FluidModel {
    pub solver: FlowSolver,
    density: f64,
    /// The fixed step, or the CFL number the step adapts to.
    fixed_dt: Option<f64>,
    cfl: Option<f64>,
    /// An adapted step also keeps an explicit viscous term stable.
    viscous_cap: f64,
    /// The last step and its report (the initial flow's before the first).
    dt: f64,
    pub report: StepReport,
    steps: u64,
    cells: usize,
    pub description: Vec<String>,
    pub warnings: Vec<String>,
}

impl FluidModel {
    /// The flow of a fluid-only case. Refuses, before anything is written,
    /// a first step beyond the CFL limit or the explicit viscous limit.
    pub fn build(case: &Case, communicator: Communicator) -> Result<Self, RunError> {
        let solver = fluid_scene::build_on(case, communicator.clone()).map_err(RunError::Case)?;
        let end = case.time.end;
        let viscous_cap = viscous_limit(&solver).map_or(f64::INFINITY, |limit| {
            0.9 * limit / solver.viscous_number(1.0)
        });
        let mut model = FluidModel {
            density: case.fluid_section().density,
            fixed_dt: case.time.dt,
            cfl: case.time.cfl,
            viscous_cap,
            dt: 0.0,
            report: StepReport {
                kinetic_energy: 0.0,
                max_cfl: 0.0,
                max_divergence: 0.0,
            },
            steps: 0,
            cells: 0,
            description: Vec::new(),
            warnings: Vec::new(),
            solver,
        };
        let first_dt = model.step_size(end);
        let solver = &model.solver;
        // The walls, inflows and unbalanced forces count beside the initial
        // flow: a lid over a fluid at rest moves it within the first stage.
        let first_cfl = solver.cfl_bound(first_dt);
        if first_cfl > CFL_LIMIT {
            return Err(RunError::Case(format!(
                "time.dt = {first_dt:e} s gives a convective CFL number of up to {first_cfl:.3} in the \
                 first step (initial flow, moving walls and inflows, unbalanced body force), beyond \
                 the RK3 limit √3 = {CFL_LIMIT:.3}: use time.dt ≤ {:.3e} s or time.cfl",
                solver.time_step_for_cfl(CFL_LIMIT)
            )));
        }
        if let Some(limit) = viscous_limit(solver) {
            let number = solver.viscous_number(first_dt);
            if number > limit {
                return Err(RunError::Case(format!(
                    "time.dt = {first_dt:e} s gives a viscous number ν Δt Σ 4/h² = {number:.3}, beyond \
                     the limit {limit:.3} of fluid.viscous = \"explicit\": use time.dt ≤ {:.3e} s or \
                     fluid.viscous = \"crank_nicolson\"",
                    first_dt * limit / number
                )));
            }
        }
        let grid = &solver.grid;
        let partition = solver.partition();
        let global_cells = partition.global_cells;
        let cells: usize = global_cells.iter().product();
        let mut description = vec![format!(
            "grainflow {}: fluid-only scene, {}D staggered grid {:?} ({cells} cells), ν = {:.4e} m²/s, \
             RK3 + Crank–Nicolson, direct pressure solve; no particles",
            env!("CARGO_PKG_VERSION"),
            grid.dim(),
            &global_cells[..grid.dim()],
            solver.viscosity
        )];
        let mut warnings = Vec::new();
        let ranks = communicator.size();
        if ranks > 1 {
            let r = partition.ranks;
            description.push(format!(
                "{ranks} MPI ranks, cells shared in a process grid of {} x {} x {} (pencil \
                 transposes in the direct solves)",
                r[0], r[1], r[2]
            ));
            warnings.extend(sharing::load_warning(
                ranks,
                None,
                Some(cells as f64 / ranks as f64),
            ));
        }
        description.push(match case.time.cfl {
            Some(cfl) => format!("dt adapted to CFL {cfl}"),
            None => format!(
                "dt = {first_dt:.4e} s (CFL of the first step at most {first_cfl:.3}, limit \
                 {CFL_LIMIT:.3})"
            ),
        });
        let (kinetic_energy, max_cfl) = (solver.kinetic_energy(), solver.max_cfl(first_dt));
        model.report = StepReport {
            kinetic_energy,
            max_cfl,
            max_divergence: model.solver.max_divergence(),
        };
        model.dt = first_dt;
        model.cells = cells;
        model.description = description;
        model.warnings = warnings;
        Ok(model)
    }

    /// The next step: `time.dt`, or the step at `time.cfl` (within the
    /// viscous cap), at most what is left to `end`.
    fn step_size(&self, end: f64) -> f64 {
        match (self.fixed_dt, self.cfl) {
            (Some(dt), _) => dt,
            (None, Some(cfl)) => self
                .solver
                .time_step_for_cfl(cfl)
                .min(self.viscous_cap)
                .min(end),
            (None, None) => unreachable!("validated: time.dt or time.cfl"),
        }
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }

    pub fn steps(&self) -> u64 {
        self.steps
    }

    pub fn reached(&self, end: f64) -> bool {
        self.solver.time >= end * (1.0 - 1e-12)
    }

    /// One step, the last one landing on `end` (where analyses compare);
    /// the diagnosis of a failure.
    pub fn advance(&mut self, case: &Case, end: f64) -> Result<(), String> {
        let dt = self.step_size(end).min(end - self.solver.time);
        self.dt = dt;
        let outcome = self
            .solver
            .step(dt)
            .map_err(|e| format!("{e}; reduce time.dt or set time.cfl"))
            .and_then(|r| {
                if !r.kinetic_energy.is_finite() {
                    Err("the kinetic energy is not finite".to_string())
                } else if let Some(why) = cfl_overrun(r.max_cfl, dt, case) {
                    Err(why)
                } else {
                    Ok(r)
                }
            });
        match outcome {
            Ok(report) => {
                self.report = report;
                self.steps += 1;
                Ok(())
            }
            Err(why) => Err(format!(
                "unstable at t = {:.6e} s (step {}): {why}",
                self.solver.time, self.steps
            )),
        }
    }

    /// A row of `series.csv`: kinetic energy per unit density, CFL number
    /// and divergence of the last step.
    pub fn series_row(&self) -> [f64; 6] {
        [
            self.solver.time,
            self.dt,
            self.steps as f64,
            self.report.kinetic_energy,
            self.report.max_cfl,
            self.report.max_divergence,
        ]
    }

    /// The fluid's density [kg/m³] (the solver works per unit density).
    pub fn density(&self) -> f64 {
        self.density
    }

    pub fn metrics(&self, case: &Case) -> Map<String, Value> {
        fluid_metrics(case, &self.solver, &self.report)
    }

    /// The scene's own entries of `summary.json`.
    pub fn summary(&self, wall_seconds: f64) -> Map<String, Value> {
        let mut summary = Map::new();
        let cell_steps = self.cells as f64 * self.steps as f64;
        for (key, value) in [
            ("cells", json!(self.cells)),
            ("dimension", json!(self.solver.grid.dim())),
            ("dt", json!(self.dt)),
            ("cell_steps_per_second", json!(cell_steps / wall_seconds)),
        ] {
            summary.insert(key.into(), value);
        }
        summary
    }

    pub fn done_line(&self, wall_seconds: f64) -> String {
        let cell_steps = self.cells as f64 * self.steps as f64;
        format!(
            "{} steps in {wall_seconds:.2} s ({:.3e} cell-steps/s)",
            self.steps,
            cell_steps / wall_seconds
        )
    }

    pub fn save_state(&self, state: &mut State) {
        self.solver.save_state(state);
        let r = &self.report;
        state.put_f64s(
            "fluid.loop",
            &[self.dt, r.kinetic_energy, r.max_cfl, r.max_divergence],
        );
        state.put_u64("fluid.steps", self.steps);
    }

    /// Takes back the blocks of every rank of a job of another size.
    pub fn restore_redistributed(&mut self, states: &mut [State]) -> Result<(), StateError> {
        self.solver.restore_redistributed(states)?;
        self.restore_counters(&mut states[0])
    }

    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        self.solver.restore_state(state)?;
        self.restore_counters(state)
    }

    fn restore_counters(&mut self, state: &mut State) -> Result<(), StateError> {
        let numbers = state.take_f64s_of_len("fluid.loop", 4)?;
        self.dt = numbers[0];
        self.report = StepReport {
            kinetic_energy: numbers[1],
            max_cfl: numbers[2],
            max_divergence: numbers[3],
        };
        self.steps = state.take_u64("fluid.steps")?;
        Ok(())
    }
}

/// Why a step of `dt` that ended at CFL number `end_cfl` is not kept, if it
/// went past the RK3 limit: its stages ran beyond what RK3 carries, so its
/// result is neither written nor reported as a finished run. With
/// `time.cfl` this means a velocity the adapted step did not foresee.
pub fn cfl_overrun(end_cfl: f64, dt: f64, case: &Case) -> Option<String> {
    (end_cfl > CFL_LIMIT || end_cfl.is_nan()).then(|| {
        format!(
            "the step of {dt:.4e} s ended at CFL number {end_cfl:.3}, beyond the RK3 limit √3 = \
             {CFL_LIMIT:.3}; {}",
            if case.time.cfl.is_some() {
                "lower time.cfl"
            } else {
                "reduce time.dt or set time.cfl"
            }
        )
    })
}

/// The stability limit on the viscous number, if the viscous term is explicit.
fn viscous_limit(solver: &FlowSolver) -> Option<f64> {
    (solver.viscous_scheme == ViscousScheme::Explicit).then_some(solver.viscous_limit)
}

/// `max_divergence` (max |D u| Δx / U after the projections of the last
/// step) for every fluid scene, `l2_error` against the exact decaying flow,
/// `profile_error` against the steady channel profile.
fn fluid_metrics(case: &Case, solver: &FlowSolver, report: &StepReport) -> Map<String, Value> {
    let mut metrics = Map::new();
    let grid = &solver.grid;
    let h = (0..grid.dim())
        .map(|axis| grid.min_width(axis))
        .fold(f64::INFINITY, f64::min);
    let c = solver.communicator();
    let mut speed = f64::MIN_POSITIVE;
    for_each_velocity(solver, |_, value, _| speed = speed.max(value.abs()));
    let speed = c.max(speed);
    metrics.insert(
        "max_divergence".into(),
        json!(report.max_divergence * h / speed),
    );
    match &case.analysis {
        Some(AnalysisSection::ExactDecay) => {
            let exact = ExactFlow::of(case).expect("validated");
            let (mut error_sq, mut norm_sq) = (0.0, 0.0);
            for_each_velocity(solver, |component, value, x| {
                let reference = exact.velocity(component, x, solver.time);
                error_sq += (value - reference).powi(2);
                norm_sq += reference * reference;
            });
            let (error_sq, norm_sq) = (c.sum(error_sq), c.sum(norm_sq));
            metrics.insert("l2_error".into(), json!((error_sq / norm_sq).sqrt()));
        }
        Some(AnalysisSection::Channel) => {
            let profile = ChannelProfile::of(case).expect("validated");
            let (mut error, mut scale): (f64, f64) = (0.0, 0.0);
            for_each_velocity(solver, |component, value, x| {
                let reference = profile.velocity(component, x[profile.wall_axis], solver.time);
                error = error.max((value - reference).abs());
                scale = scale.max(reference.abs());
            });
            let (error, scale) = (c.max(error), c.max(scale));
            metrics.insert("profile_error".into(), json!(error / scale));
            // The pressure gradient that held a bulk velocity, against the
            // one the steady profile needs: ρ ν u''.
            let f = case.fluid_section();
            for axis in 0..grid.dim() {
                if f.bulk_velocity.along(axis).is_some() {
                    let name = ["x", "y", "z"][axis];
                    let held = f.density * solver.flow_rate_gradient[axis];
                    let steady = f.viscosity * profile.curvature[axis];
                    metrics.insert(format!("pressure_gradient_{name}"), json!(held));
                    metrics.insert(format!("steady_pressure_gradient_{name}"), json!(steady));
                }
            }
        }
        _ => {}
    }
    metrics.insert("kinetic_energy".into(), json!(report.kinetic_energy));
    metrics
}

/// Calls `visit(component, value, position)` for every velocity unknown.
fn for_each_velocity(solver: &FlowSolver, mut visit: impl FnMut(usize, f64, [f64; 3])) {
    let grid = &solver.grid;
    for component in 0..grid.dim() {
        let field = &solver.velocity[component];
        grid.for_each(solver.velocity_unknowns(component), |index, [i, j, k]| {
            visit(
                component,
                field[index],
                grid.position(Location::Face(component), i, j, k),
            );
        });
    }
}
