//! Grains in a fluid: coupled steps (the flow's three Runge–Kutta stages,
//! each forcing the flow towards the grains' rigid motion and advancing the
//! DEM over the stage with the hydrodynamic load held fixed), the checks
//! that refuse a scene before it runs, and the warnings after.

use super::dry::shortest_contact_time;
use super::fluid::cfl_overrun;
use crate::analysis::sphere_in_fluid::SphereInFluid;
use crate::case::{AnalysisSection, Case, WallLayerName};
use crate::stability::TimeStepVerdict;
use crate::{scene, scene::fluid as fluid_scene, sharing, stability, RunError};
use grainflow_core::{Communicator, State, StateError};
use grainflow_fluid::time_step_for_cfl_rates;
use grainflow_ibm::forcing::WallLayer;
use grainflow_ibm::{
    rigid_inner_fluid_limits, CoupledReport, CoupledSystem, Coupling, LayerForcing,
    RigidInnerFluidLimits, Timings,
};
use serde_json::{json, Map, Value};

/// The coupled scene of a validated case with grains and a fluid, and its
/// DEM sub-step's ratio to the shortest contact time.
pub fn build(case: &Case) -> Result<(CoupledSystem, f64), String> {
    build_on(case, Communicator::serial())
}

/// [`build`] shared among the ranks of `communicator`: the grains in the
/// flow's process grid, each rank holding the grains of its cells and the
/// ghosts of those whose immersed boundary reaches them.
pub fn build_on(case: &Case, communicator: Communicator) -> Result<(CoupledSystem, f64), String> {
    let mut flow = fluid_scene::build_on(case, communicator.clone())?;
    // Gravity acts on the grains, buoyancy (−ρ V g) through their loads.
    // On the fluid, along an axis closed by walls, it is balanced by the
    // hydrostatic pressure, which the kinematic pressure leaves out; along
    // a periodic axis no pressure can balance it (the pressure is
    // periodic), so there it drives the fluid, as down the inclined bed of
    // Izard et al. (2014, section 4.2). The grains' loads
    // −ρ∫f + ρ d/dt∫α u − ρ V g hold either way: the forcing inside a grain
    // hands it the body force on its inner fluid.
    let periodic = fluid_scene::boundaries(case)
        .faces
        .map(|[lower, _]| lower == grainflow_fluid::BoundaryCondition::Periodic);
    let gravity = flow.body_force;
    flow.body_force = [0, 1, 2].map(|axis| if periodic[axis] { gravity[axis] } else { 0.0 });
    let ranks = flow.partition().ranks;
    let grid = &flow.grid;
    let reach = |max_radius| grainflow_ibm::forcing::ghost_reach(grid, max_radius);
    let dem = scene::build_with(case, communicator, Some(ranks), reach)?;
    let contact_time = shortest_contact_time(&dem);
    let ratio = case.time.dt_over_contact_time.unwrap_or(0.02);
    let coupling_section = case.coupling.clone().unwrap_or_default();
    let density = case.fluid_section().density;
    let coupling = coupling_section.coupling();
    let mut system = CoupledSystem::new(flow, dem, density, coupling, ratio * contact_time);
    system.immersed.layer = coupling_section.layer_forcing();
    if coupling_section.wall_layer == WallLayerName::Free {
        system.immersed.free_wall_layers = WallLayer::along_walls(
            &system.flow.grid,
            &system.flow.boundaries,
            system.dem.domain.lower.into(),
            system.dem.domain.upper.into(),
        );
    }
    Ok((system, contact_time))
}

/// The next fluid step: `time.dt`, or with `time.cfl` the step at which the
/// flow (cell by cell, with its walls and unbalanced body force,
/// [`grainflow_fluid::FlowSolver::cfl_bound`]) or the fastest grain (its
/// speed over the smallest cell size) reaches that CFL number, at most
/// `time.dt`. The larger of the two rates, not their sum: the fluid inside
/// a grain is forced to the grain's velocity, so a grain's speed is a speed
/// of the flow, and the sum would count it twice (halving the step of a
/// settling grain, below the grain CFL number near 1 at which the forcing
/// of eq. 7 was calibrated).
fn step_size(system: &CoupledSystem, case: &Case) -> f64 {
    let largest = case
        .time
        .dt
        .expect("validated: grains in a fluid have time.dt");
    let Some(cfl) = case.time.cfl else {
        return largest;
    };
    let grid = &system.flow.grid;
    let h = grid.spacing[..grid.dim()]
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let (flow_rate, acceleration_rate) = system.flow.cfl_rates();
    let speed_rate = flow_rate.max(system.dem.max_speed() / h);
    largest.min(time_step_for_cfl_rates(cfl, speed_rate, acceleration_rate))
}

/// Refuses a DEM sub-step past the stability limit of the contacts
/// (before anything is written); returns a warning past the accuracy limit.
/// In a fluid the sub-step is set by `time.dt_over_contact_time` alone
/// (`time.dt` is the fluid's step).
pub fn check_dem_substep(dem_dt: f64, contact_time: f64) -> Result<Option<String>, RunError> {
    let ratio = dem_dt / contact_time;
    match stability::verdict(ratio) {
        TimeStepVerdict::Unstable => Err(RunError::Case(format!(
            "time.dt_over_contact_time = {ratio:.3}: the DEM sub-step {:.3e} s is past the \
             stability limit {} t_c of the explicit contact integration (t_c = {contact_time:.3e} \
             s); allowed: time.dt_over_contact_time ≤ {} (default 0.02)",
            dem_dt,
            stability::STABLE_DT_OVER_TC,
            stability::STABLE_DT_OVER_TC
        ))),
        TimeStepVerdict::Inaccurate => Ok(Some(format!(
            "warning: the DEM sub-step is {ratio:.3} t_c, past {}: restitution errors above 1 % \
             (time.dt_over_contact_time ≤ {})",
            stability::ACCURATE_DT_OVER_TC,
            stability::ACCURATE_DT_OVER_TC
        ))),
        TimeStepVerdict::Accurate => Ok(None),
    }
}

/// The diagnosis of a step adapted to `time.cfl` that collapsed below
/// [`COLLAPSED_STEP`] of `time.dt` before the end: a flow running away,
/// which the adapted step would otherwise follow towards zero, the run
/// standing still.
pub fn collapsed_step(step_dt: f64, case: &Case, time: f64, end: f64) -> Option<String> {
    let largest = case.time.dt?;
    let collapsed = case.time.cfl.is_some() && step_dt < COLLAPSED_STEP * largest;
    (collapsed && end - time > step_dt).then(|| {
        format!(
            "the step adapted to time.cfl collapsed to {step_dt:.3e} s, below {COLLAPSED_STEP} of \
             time.dt = {largest:.3e} s: the flow is running away (a cell Reynolds number too high \
             for the grid, or grains moving faster than the scene was set for); refine the grid \
             or raise the viscosity"
        )
    })
}

/// What made a coupled step unstable, if anything: a flow or a grain not
/// finite, a CFL number past what the step allows (with the step to cut),
/// or an overlap past `time.overlap_limit`.
pub fn unstable_step(report: &CoupledReport, step_dt: f64, case: &Case) -> Option<String> {
    if !report.flow.kinetic_energy.is_finite() || report.dem.non_finite {
        return Some("the flow or a grain is not finite".into());
    }
    if let Some(why) = cfl_overrun(report.flow.max_cfl, step_dt, case) {
        return Some(why);
    }
    (report.dem.max_overlap_ratio > case.time.overlap_limit).then(|| {
        format!(
            "overlap of {:.3} radii beyond time.overlap_limit = {}; reduce \
             time.dt_over_contact_time",
            report.dem.max_overlap_ratio, case.time.overlap_limit
        )
    })
}

/// The fraction of `time.dt` below which an adapted step has collapsed.
pub const COLLAPSED_STEP: f64 = 1e-3;

/// Below this CFL number at a grain's settling velocity the forced layer
/// around it, pulled towards its velocity at every stage, thickens the
/// grain noticeably: at D/Δx = 8 the falling sphere settles 4 % slow at
/// CFL 1 and 12 % slow at 0.5 (docs/validation.md, §7).
const FORCING_CFL_WARNING: f64 = 0.6;

/// The warning for a forcing step short against the time a grain takes to
/// cross a cell (`cfl` = U Δt / Δx, with `coupling.forcing_step` for Δt
/// where it is set: at the settling velocity in `check`, the run's mean
/// over the steps in which grains move in `run`).
pub fn forcing_step_warning(cfl: f64) -> Option<String> {
    (cfl < FORCING_CFL_WARNING).then(|| {
        format!(
            "warning: the grains' CFL number (speed Δt/Δx) is {cfl:.2}: the direct forcing \
             drags the transition layer along at every stage, so the shorter the step the \
             larger the grain looks (about 8 % slower settling from CFL 1 to 0.5 at D/Δx = 8); \
             the forcing is calibrated near CFL 1 (a larger time.dt, time.cfl ≈ 1, \
             coupling.forcing_step = Δx/U, or coupling.layer_forcing = \"renewal\", whose \
             grain does not depend on the step)"
        )
    })
}

/// The lowest density ratio at which the load from the inner fluid
/// momentum has been seen to hold, `[2D, 3D]`: a 3D sphere at D/Δx = 8
/// and Ar = 100 from 10 down to 0.5 over two time units (the map of
/// `solvers/ibm/tests/falling_sphere.rs`); a 2D disc rising from rest
/// (D/Δx = 4 and 8, Δt 2e-4 to 2e-3 s, ρ = 1000 kg/m³, μ = 0.19 Pa s)
/// held at 1.05 and blew up at 0.95 and below. Below these `check` and
/// `run` warn.
pub const INNER_FLUID_MOMENTUM_TESTED_DOWN_TO: [f64; 2] = [1.05, 0.5];

/// Refuses the paper's rigid-inner-fluid load where it fails under the
/// scene's forcing of the transition layer `layer` (density ratio below
/// its [`rigid_inner_fluid_limits`]); returns a warning close to it, and
/// for the load from the inner fluid momentum below the ratios it was
/// tested at ([`INNER_FLUID_MOMENTUM_TESTED_DOWN_TO`]). `ratio` is the
/// smallest `ρ_p/ρ` of the scene's moving grains, `dim` its dimension.
pub fn check_density_ratio(
    ratio: f64,
    coupling: Coupling,
    layer: LayerForcing,
    dim: usize,
) -> Result<Option<String>, RunError> {
    if coupling == Coupling::InnerFluidMomentum {
        let tested = INNER_FLUID_MOMENTUM_TESTED_DOWN_TO[dim - 2];
        return Ok((ratio < tested).then(|| {
            format!(
                "warning: density ratio rho_p/rho = {ratio:.4} is below {tested}, the lowest at \
                 which coupling.formulation = \"inner_fluid_momentum\" was seen to hold in \
                 {dim}D (light grains driven by an explicit load can blow up: a rising 2D disc \
                 did at 0.95); the run stops with a diagnosis if the flow's CFL number runs away"
            )
        }));
    }
    let RigidInnerFluidLimits {
        fails_below,
        warns_below,
    } = rigid_inner_fluid_limits(layer);
    let forcing = match layer {
        LayerForcing::Renewal => "with coupling.layer_forcing = \"renewal\"",
        _ => "with the layer forced as eq. 7",
    };
    if ratio < fails_below {
        return Err(RunError::Case(format!(
            "coupling.formulation = \"rigid_inner_fluid\" fails at density ratio rho_p/rho = \
             {ratio:.4}: {forcing} it blows up below {fails_below}; allowed: \
             \"inner_fluid_momentum\" (tested down to {} in 3D, {} in 2D), or grains denser \
             than {fails_below} times the fluid",
            INNER_FLUID_MOMENTUM_TESTED_DOWN_TO[1], INNER_FLUID_MOMENTUM_TESTED_DOWN_TO[0]
        )));
    }
    Ok((ratio < warns_below).then(|| {
        format!(
            "warning: density ratio {ratio:.4} is below {warns_below}, where \
             \"rigid_inner_fluid\" {forcing} lets a grain's spin overshoot and oscillate after \
             a collision (it fails below {fails_below}); \"inner_fluid_momentum\" holds further \
             down"
        )
    }))
}

/// The log's last line of a coupled run: its steps and where the time went.
pub fn done_line(steps: u64, dem_substeps: usize, wall_seconds: f64, t: &Timings) -> String {
    format!(
        "{steps} steps ({dem_substeps} DEM sub-steps) in {wall_seconds:.2} s: flow {:.2} s, \
         forcing {:.2} s, loads {:.2} s, DEM {:.2} s",
        t.flow, t.forcing, t.loads, t.dem
    )
}

/// The case's name of a layer forcing, for `summary.json`.
fn layer_forcing_name(layer: &LayerForcing) -> &'static str {
    match layer {
        LayerForcing::EveryStage => "every_stage",
        LayerForcing::Held { .. } => "held",
        LayerForcing::Renewal => "renewal",
    }
}

/// The step the layer is held at, if it is.
fn held_step(layer: &LayerForcing) -> Option<f64> {
    match *layer {
        LayerForcing::Held { step } => Some(step),
        _ => None,
    }
}

/// What every coupled run reports of its sub-steps and its time.
pub struct CoupledCounts<'a> {
    pub steps: u64,
    pub dem_substeps: usize,
    pub dem_dt: f64,
    pub contact_time: f64,
    pub layer: LayerForcing,
    pub timings: &'a Timings,
}

/// The entries of a coupled run's `summary.json`: the scene's own
/// `scene`, then those every coupled run has (the steps and sub-steps, the
/// time settings and where the time went).
pub fn coupled_summary<'a>(
    scene: impl IntoIterator<Item = (&'a str, Value)>,
    case: &Case,
    c: &CoupledCounts,
    wall_seconds: f64,
) -> Map<String, Value> {
    let t = c.timings;
    let mut summary: Map<String, Value> = scene.into_iter().map(|(k, v)| (k.into(), v)).collect();
    for (key, value) in [
        ("dem_substeps", json!(c.dem_substeps)),
        ("dt", json!(case.time.dt)),
        ("cfl", json!(case.time.cfl)),
        ("layer_forcing", json!(layer_forcing_name(&c.layer))),
        ("forcing_step", json!(held_step(&c.layer))),
        ("dem_dt", json!(c.dem_dt)),
        ("contact_time", json!(c.contact_time)),
        (
            "seconds_per_step",
            json!(wall_seconds / c.steps.max(1) as f64),
        ),
        ("seconds_flow", json!(t.flow)),
        ("seconds_forcing", json!(t.forcing)),
        ("seconds_loads", json!(t.loads)),
        ("seconds_dem", json!(t.dem)),
    ] {
        summary.insert(key.into(), value);
    }
    summary
}

/// Grains in a fluid: coupled steps, fixed or adapted to a CFL number (the
/// flow's and the grains'), the last one landing on the end time.
pub struct CoupledModel {
    pub system: CoupledSystem,
    analysis: SphereInFluid,
    contact_time: f64,
    dt: f64,
    steps: u64,
    dem_substeps: usize,
    max_divergence: f64,
    last_report: Option<CoupledReport>,
    /// The grains' CFL number (fastest grain, smallest cell) summed over
    /// the distance it travels, and that distance: their ratio is the mean
    /// at which the forcing ran (calibrated near 1), a grain at rest on a
    /// wall not weighing in.
    grain_cfl_sum: f64,
    distance: f64,
    particles: usize,
    cells: usize,
    pub description: Vec<String>,
    pub warnings: Vec<String>,
}

impl CoupledModel {
    /// The coupled scene of a case. Refuses, before anything is written, a
    /// DEM sub-step past the stability limit and a load that fails at the
    /// scene's density ratio.
    pub fn build(case: &Case, communicator: Communicator) -> Result<Self, RunError> {
        let (system, contact_time) =
            build_on(case, communicator.clone()).map_err(RunError::Case)?;
        let mut warnings = Vec::new();
        warnings.extend(check_dem_substep(system.dem_dt, contact_time)?);
        warnings.extend(check_density_ratio(
            system.smallest_density_ratio(),
            system.coupling,
            system.immersed.layer,
            system.flow.grid.dim(),
        )?);
        let dt = case
            .time
            .dt
            .expect("validated: a coupled scene has time.dt");
        let grid = &system.flow.grid;
        let global_cells = system.flow.partition().global_cells;
        let cells: usize = global_cells.iter().product();
        let particles = communicator.sum_count(system.dem.particles.n_owned);
        let mut description = vec![
            format!(
                "grainflow {}: {particles} grains in a fluid, {}D staggered grid {:?} ({cells} cells), \
                 immersed boundaries ({:?}), soft-sphere DEM sub-cycled in each stage{}",
                env!("CARGO_PKG_VERSION"),
                grid.dim(),
                &global_cells[..grid.dim()],
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
        let ranks = communicator.size();
        if ranks > 1 {
            let r = system.flow.partition().ranks;
            description.push(format!(
                "{ranks} MPI ranks in a process grid of {} x {} x {} (cells and grains)",
                r[0], r[1], r[2]
            ));
            warnings.extend(sharing::load_warning(
                ranks,
                None,
                Some(cells as f64 / ranks as f64),
            ));
        }
        let analysis = SphereInFluid::new(case, &system.dem, system.fluid_density);
        Ok(CoupledModel {
            system,
            analysis,
            contact_time,
            dt,
            steps: 0,
            dem_substeps: 0,
            max_divergence: 0.0,
            last_report: None,
            grain_cfl_sum: 0.0,
            distance: 0.0,
            particles,
            cells,
            description,
            warnings,
        })
    }

    /// The slab height of the inclined bed's analysis, if the case has it.
    pub fn bed_slab(&self, case: &Case) -> Option<Option<f64>> {
        match &case.analysis {
            Some(AnalysisSection::InclinedBed { slab }) => Some(*slab),
            _ => None,
        }
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

    /// One coupled step, the last one landing on `end`; the diagnosis of a
    /// failure.
    pub fn advance(&mut self, case: &Case, end: f64) -> Result<(), String> {
        let step_dt = step_size(&self.system, case).min(end - self.system.flow.time);
        self.dt = step_dt;
        let steps = self.steps;
        let time = self.system.flow.time;
        if let Some(why) = collapsed_step(step_dt, case, time, end) {
            return Err(format!(
                "unstable at t = {time:.6e} s (step {steps}): {why}"
            ));
        }
        let analysis = &mut self.analysis;
        let time = self.system.flow.time;
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
        let speed = self.system.dem.max_speed();
        if speed > 0.0 {
            let grid = &self.system.flow.grid;
            let h = grid.spacing[..grid.dim()]
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min);
            // Read at the step the layer is relaxed at (the step itself
            // under renewal, where it does not matter).
            let layer_step = self.system.immersed.layer.layer_step(step_dt);
            self.grain_cfl_sum += speed * step_dt * (speed * layer_step.unwrap_or(step_dt) / h);
            self.distance += speed * step_dt;
        }
        let (time, dem) = (self.system.flow.time, &self.system.dem);
        self.analysis
            .after_step(time, dem, step_dt, &self.last_report);
        Ok(())
    }

    /// A row of `flow_series.csv`: the fluid's kinetic energy (J, per unit
    /// depth in 2D), its CFL number at the last step and divergence.
    pub fn flow_row(&self, dt: f64) -> [f64; 6] {
        let flow = &self.system.flow;
        let density = self.system.fluid_density;
        [
            flow.time,
            dt,
            self.steps as f64,
            density * flow.kinetic_energy(),
            flow.max_cfl(dt),
            self.max_divergence,
        ]
    }

    /// The mean grain CFL number over the run (0 if no grain moved).
    fn grain_cfl(&self) -> f64 {
        if self.distance > 0.0 {
            self.grain_cfl_sum / self.distance
        } else {
            0.0
        }
    }

    /// The warning for a forcing step short against the grains' crossing
    /// time, at the end of a run in which grains moved.
    pub fn closing_warning(&self) -> Option<String> {
        let layer_held = self.system.immersed.layer != LayerForcing::Renewal;
        (layer_held && self.distance > 0.0)
            .then(|| forcing_step_warning(self.grain_cfl()))
            .flatten()
    }

    /// The metrics of the sphere's analysis (the bed's come from its
    /// writer).
    pub fn metrics(&self) -> Map<String, Value> {
        self.analysis.metrics()
    }

    /// The scene's own entries of `summary.json`.
    pub fn summary(&self, case: &Case, wall_seconds: f64) -> Map<String, Value> {
        let scene = [
            ("particles", json!(self.particles)),
            ("cells", json!(self.cells)),
            ("dimension", json!(self.system.flow.grid.dim())),
            ("mean_grain_cfl", json!(self.grain_cfl())),
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
            &(
                self.dt,
                self.steps,
                self.dem_substeps,
                self.max_divergence,
                self.grain_cfl_sum,
                self.distance,
            ),
        );
    }

    /// Takes back the states of every rank of a job of another size.
    pub fn restore_redistributed(&mut self, states: &mut [State]) -> Result<(), StateError> {
        self.system.restore_redistributed(states)?;
        self.restore_run(&mut states[0])
    }

    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        self.system.restore_state(state)?;
        self.restore_run(state)
    }

    /// The analysis and counters of a state (the same on every rank).
    fn restore_run(&mut self, state: &mut State) -> Result<(), StateError> {
        self.analysis = state.take_value("coupled.analysis")?;
        (
            self.dt,
            self.steps,
            self.dem_substeps,
            self.max_divergence,
            self.grain_cfl_sum,
            self.distance,
        ) = state.take_value("coupled.loop")?;
        Ok(())
    }
}
