//! The time loop of grains in a fluid: coupled steps (the flow's three
//! Runge–Kutta stages, each forcing the flow towards the grains' rigid
//! motion and advancing the DEM over the stage with the hydrodynamic load
//! held fixed), with the output contract of every case: `series.csv`,
//! `tracked.csv`, `particles/*.vtp` and `fields/*.vti` (velocity, pressure,
//! vorticity and solid fraction) with their `.pvd` indices, `summary.json`.

use crate::bed_analysis::InclinedBed;
use crate::case::{AnalysisSection, Case};
use crate::coupled_analysis::SphereInFluid;
use crate::fluid_simulation::{cfl_overrun, FieldFiles};
use crate::output::Outputs;
use crate::progress::Progress;
use crate::simulation::{peak_memory_bytes, shortest_contact_time, Summary};
use crate::stability::TimeStepVerdict;
use crate::{fluid_scene, scene, sharing, stability, RunError};
use grainflow_core::Communicator;
use grainflow_fluid::time_step_for_cfl_rates;
use grainflow_ibm::forcing::WallLayer;
use grainflow_ibm::{
    CoupledSystem, Coupling, RIGID_INNER_FLUID_FAILS_BELOW, RIGID_INNER_FLUID_WARNS_BELOW,
};
use grainflow_io::CsvSeries;
use serde_json::{json, Map};
use std::path::Path;
use std::time::Instant;

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
    let coupling = match case.coupling.as_ref().map(|c| c.formulation.as_str()) {
        Some("rigid_inner_fluid") => Coupling::RigidInnerFluid,
        _ => Coupling::InnerFluidMomentum,
    };
    let density = case.fluid_section().density;
    let mut system = CoupledSystem::new(flow, dem, density, coupling, ratio * contact_time);
    let coupling_section = case.coupling.clone().unwrap_or_default();
    system.immersed.forcing_step = coupling_section.forcing_step;
    if coupling_section.wall_layer == "free" {
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
/// flow (with its walls and unbalanced body force,
/// [`grainflow_fluid::FlowSolver::cfl_bound`]) and the grains (each grain's
/// speed over the smallest cell size) reach that CFL number, at most
/// `time.dt`.
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
    let speed_rate = flow_rate + system.dem.max_speed() / h;
    largest.min(time_step_for_cfl_rates(cfl, speed_rate, acceleration_rate))
}

/// Refuses a DEM sub-step past the stability limit of the contacts
/// (before anything is written); returns a warning past the accuracy limit.
/// In a fluid the sub-step is set by `time.dt_over_contact_time` alone
/// (`time.dt` is the fluid's step).
pub fn check_dem_substep(
    system: &CoupledSystem,
    contact_time: f64,
) -> Result<Option<String>, RunError> {
    let ratio = system.dem_dt / contact_time;
    match stability::verdict(ratio) {
        TimeStepVerdict::Unstable => Err(RunError::Case(format!(
            "time.dt_over_contact_time = {ratio:.3}: the DEM sub-step {:.3e} s is past the \
             stability limit {} t_c of the explicit contact integration (t_c = {contact_time:.3e} \
             s); allowed: time.dt_over_contact_time ≤ {} (default 0.02)",
            system.dem_dt,
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
             the forcing is calibrated near CFL 1 (a larger time.dt, time.cfl ≈ 1, or \
             coupling.forcing_step = Δx/U)"
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

/// Refuses the paper's rigid-inner-fluid load where it fails (density
/// ratio below [`RIGID_INNER_FLUID_FAILS_BELOW`]); returns a warning
/// close to it, and for the load from the inner fluid momentum below the
/// ratios it was tested at ([`INNER_FLUID_MOMENTUM_TESTED_DOWN_TO`]).
pub fn check_density_ratio(system: &CoupledSystem) -> Result<Option<String>, RunError> {
    let ratio = system.smallest_density_ratio();
    if system.coupling == Coupling::InnerFluidMomentum {
        let dim = system.flow.grid.dim();
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
    if ratio < RIGID_INNER_FLUID_FAILS_BELOW {
        return Err(RunError::Case(format!(
            "coupling.formulation = \"rigid_inner_fluid\" fails at density ratio rho_p/rho = \
             {ratio:.4}: it blows up below {RIGID_INNER_FLUID_FAILS_BELOW}; allowed: \
             \"inner_fluid_momentum\" (tested down to {} in 3D, {} in 2D), or grains denser \
             than {RIGID_INNER_FLUID_FAILS_BELOW} times the fluid",
            INNER_FLUID_MOMENTUM_TESTED_DOWN_TO[1], INNER_FLUID_MOMENTUM_TESTED_DOWN_TO[0]
        )));
    }
    Ok((ratio < RIGID_INNER_FLUID_WARNS_BELOW).then(|| {
        format!(
            "warning: density ratio {ratio:.4} is below {RIGID_INNER_FLUID_WARNS_BELOW}, where \
             \"rigid_inner_fluid\" lets a grain's spin overshoot and oscillate after a \
             collision (it fails below {RIGID_INNER_FLUID_FAILS_BELOW}); \"inner_fluid_momentum\" \
             holds further down"
        )
    }))
}

/// Runs a validated case of grains in a fluid into `out`. Nothing is
/// written if the scene cannot be built or a time step is refused.
///
/// On several ranks (`communicator`) the flow and the grains are shared in
/// one process grid; the root writes the shared files.
pub fn run(
    case: &Case,
    out: &Path,
    show_progress: bool,
    communicator: Communicator,
) -> Result<Summary, RunError> {
    let started = Instant::now();
    let root = communicator.is_root();
    let (mut system, contact_time) =
        build_on(case, communicator.clone()).map_err(RunError::Case)?;
    let warning = check_dem_substep(&system, contact_time)?;
    let density_warning = check_density_ratio(&system)?;
    let dt = case
        .time
        .dt
        .expect("validated: a coupled scene has time.dt");
    let end = case.time.end;

    let mut outputs =
        CoupledOutputs::create(out, case, communicator.clone()).map_err(RunError::Io)?;
    let grid = &system.flow.grid;
    let global_cells = system.flow.partition().global_cells;
    let cells: usize = global_cells.iter().product();
    let particles = communicator.sum_count(system.dem.particles.n_owned);
    outputs.particles.run.log(&format!(
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
    ));
    outputs.particles.run.log(&format!(
        "dt = {dt:.4e} s (fluid), DEM sub-step ≤ {:.4e} s = {:.4} t_c",
        system.dem_dt,
        system.dem_dt / contact_time
    ));
    let mut load_warning = None;
    if communicator.size() > 1 {
        let r = system.flow.partition().ranks;
        let ranks = communicator.size();
        outputs.particles.run.log(&format!(
            "{ranks} MPI ranks in a process grid of {} x {} x {} (cells and grains)",
            r[0], r[1], r[2]
        ));
        load_warning = sharing::load_warning(ranks, None, Some(cells as f64 / ranks as f64));
    }
    for w in warning.iter().chain(&density_warning).chain(&load_warning) {
        outputs.particles.run.log(w);
        if root {
            eprintln!("{w}");
        }
    }

    let mut analysis = SphereInFluid::new(case, &system);
    let mut bed = match &case.analysis {
        Some(AnalysisSection::InclinedBed { slab }) => {
            Some(InclinedBed::create(out, case, &system, *slab).map_err(RunError::Io)?)
        }
        _ => None,
    };
    let interval = case.output.interval.unwrap_or(end / 100.0);
    let tracked_interval = case.output.tracked_interval.unwrap_or(interval);
    let tracked = &case.particles_section().tracked;
    let mut next_output = interval;
    let mut next_tracked = tracked_interval;
    let mut steps = 0u64;
    let mut dem_substeps = 0usize;
    outputs
        .write(&mut system, dt, steps, 0.0)
        .map_err(RunError::Io)?;
    if let Some(bed) = &mut bed {
        bed.sample(&system).map_err(RunError::Io)?;
    }
    outputs
        .particles
        .write_tracked(&system.dem, tracked)
        .map_err(RunError::Io)?;
    let mut progress = Progress::new(root && show_progress, end);
    let mut failure = None;
    let mut max_divergence = 0.0;
    let mut last_report = None;
    // The grains' CFL number (fastest grain, smallest cell) averaged over
    // the distance it travels, so that a grain at rest on a wall does not
    // weigh in: the forcing is calibrated near 1.
    let h = {
        let grid = &system.flow.grid;
        grid.spacing[..grid.dim()]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    };
    let (mut grain_cfl_sum, mut distance) = (0.0, 0.0);
    while system.flow.time < end * (1.0 - 1e-12) {
        let step_dt = step_size(&system, case).min(end - system.flow.time);
        match system.step_observed(step_dt, |dem| analysis.after_stage(dem)) {
            Ok(report) => {
                last_report = Some(report);
                dem_substeps += report.dem_substeps;
                max_divergence = report.flow.max_divergence;
                if !report.flow.kinetic_energy.is_finite() || report.dem.non_finite {
                    failure = Some(format!(
                        "unstable at t = {:.6e} s (step {steps}): the flow or a grain is not finite",
                        system.flow.time
                    ));
                } else if let Some(why) = cfl_overrun(report.flow.max_cfl, step_dt, case) {
                    failure = Some(format!(
                        "unstable at t = {:.6e} s (step {steps}): {why}",
                        system.flow.time
                    ));
                } else if report.dem.max_overlap_ratio > case.time.overlap_limit {
                    failure = Some(format!(
                        "unstable at t = {:.6e} s (step {steps}): overlap of {:.3} radii beyond \
                         time.overlap_limit = {}; reduce time.dt_over_contact_time",
                        system.flow.time, report.dem.max_overlap_ratio, case.time.overlap_limit
                    ));
                }
            }
            Err(e) => {
                failure = Some(format!(
                    "unstable at t = {:.6e} s (step {steps}): {e}; reduce time.dt",
                    system.flow.time
                ));
            }
        }
        if failure.is_some() {
            break;
        }
        steps += 1;
        let speed = system.dem.max_speed();
        if speed > 0.0 {
            let layer_step = system.immersed.forcing_step.unwrap_or(step_dt);
            grain_cfl_sum += speed * step_dt * (speed * layer_step / h);
            distance += speed * step_dt;
        }
        analysis.after_step(&system, step_dt, &last_report);
        let at_end = system.flow.time >= end * (1.0 - 1e-12);
        if system.flow.time >= next_output - 0.5 * step_dt || at_end {
            outputs
                .write(&mut system, step_dt, steps, max_divergence)
                .map_err(RunError::Io)?;
            if let Some(bed) = &mut bed {
                bed.sample(&system).map_err(RunError::Io)?;
            }
            next_output += interval;
        }
        if system.flow.time >= next_tracked - 0.5 * step_dt || at_end {
            outputs
                .particles
                .write_tracked(&system.dem, tracked)
                .map_err(RunError::Io)?;
            next_tracked += tracked_interval;
        }
        if let Some(line) = progress.update(system.flow.time, steps) {
            outputs.particles.run.log(&line);
            eprintln!("{line}");
        }
    }
    progress.finish();

    let wall_seconds = started.elapsed().as_secs_f64();
    let metrics = match (&failure, &bed) {
        (None, Some(bed)) => bed.metrics(),
        (None, None) => analysis.metrics(),
        _ => Map::new(),
    };
    let t = system.timings;
    let grain_cfl = if distance > 0.0 {
        grain_cfl_sum / distance
    } else {
        0.0
    };
    if distance > 0.0 {
        if let Some(w) = forcing_step_warning(grain_cfl) {
            outputs.particles.run.log(&w);
            if root {
                eprintln!("{w}");
            }
        }
    }
    let summary = json!({
        "analysis": case.analysis,
        "status": if failure.is_some() { "unstable" } else { "ok" },
        "stop_reason": failure.clone().unwrap_or_else(|| "end time reached".to_string()),
        "particles": particles,
        "cells": cells,
        "ranks": communicator.size(),
        "dimension": system.flow.grid.dim(),
        "steps": steps,
        "dem_substeps": dem_substeps,
        "dt": dt,
        "cfl": case.time.cfl,
        "mean_grain_cfl": grain_cfl,
        "forcing_step": system.immersed.forcing_step,
        "dem_dt": system.dem_dt,
        "simulated_time": system.flow.time,
        "wall_seconds": wall_seconds,
        "seconds_per_step": wall_seconds / steps.max(1) as f64,
        "seconds_flow": t.flow,
        "seconds_forcing": t.forcing,
        "seconds_loads": t.loads,
        "seconds_dem": t.dem,
        "threads": rayon::current_num_threads(),
        "peak_memory_bytes": communicator.max(peak_memory_bytes().unwrap_or(0) as f64) as u64,
        "metrics": metrics,
    });
    let run = &mut outputs.particles.run;
    run.finish(
        &summary,
        failure,
        &format!(
            "done: {steps} steps ({dem_substeps} DEM sub-steps) in {wall_seconds:.2} s: flow \
             {:.2} s, forcing {:.2} s, loads {:.2} s, DEM {:.2} s",
            t.flow, t.forcing, t.loads, t.dem
        ),
    )?;
    Ok(Summary {
        json: summary,
        metrics,
    })
}

/// The outputs of grains in a fluid: the particle outputs of every scene
/// of grains, the flow's series columns and its field files (with the
/// solid fraction).
struct CoupledOutputs {
    particles: Outputs,
    /// `flow_series.csv` (the root's).
    flow_series: Option<CsvSeries>,
    fields: Option<FieldFiles>,
}

impl CoupledOutputs {
    fn create(dir: &Path, case: &Case, communicator: Communicator) -> std::io::Result<Self> {
        let root = communicator.is_root();
        let particles = Outputs::create_on(dir, case, communicator)?;
        let fields = FieldFiles::create(dir, case, root)?;
        let flow_series = CsvSeries::create_on(
            root,
            &dir.join("flow_series.csv"),
            &[
                "t",
                "dt",
                "step",
                "fluid_kinetic_energy",
                "max_cfl",
                "max_divergence",
                "wall_seconds",
            ],
        )?;
        Ok(CoupledOutputs {
            particles,
            flow_series,
            fields,
        })
    }

    /// Rows of `series.csv` (grains) and `flow_series.csv` (fluid, energy
    /// in J, per unit depth in 2D) and, if enabled, particle and field files.
    fn write(
        &mut self,
        system: &mut CoupledSystem,
        dt: f64,
        steps: u64,
        max_divergence: f64,
    ) -> std::io::Result<()> {
        self.particles.write_frame(&system.dem, dt)?;
        let density = system.fluid_density;
        let (energy, cfl) = (system.flow.kinetic_energy(), system.flow.max_cfl(dt));
        if let Some(series) = &mut self.flow_series {
            series.row(&[
                system.flow.time,
                dt,
                steps as f64,
                density * energy,
                cfl,
                max_divergence,
                self.particles.run.started.elapsed().as_secs_f64(),
            ])?;
        }
        if let Some(fields) = &mut self.fields {
            let solid = system
                .immersed
                .cell_solid_fraction(&system.flow.grid, &system.dem.particles);
            fields.write(&mut system.flow, density, &[("solid_fraction", &solid)])?;
        }
        Ok(())
    }
}
