//! The time loop of a fluid-only scene: steps of the flow solver (three
//! RK3 stages with Crank–Nicolson viscosity and a projection each), fixed
//! or adapted to a CFL number, with the output contract of every case
//! (`case.toml`, `log.txt`, `series.csv`, `tracked.csv`, `fields/*.vti` with
//! `fields.pvd`, `summary.json`).

use crate::case::{AnalysisSection, Case};
use crate::fluid_scene::{self, ChannelProfile, ExactFlow};
use crate::output::RunDirectory;
use crate::progress::Progress;
use crate::simulation::{peak_memory_bytes, Summary};
use crate::{sharing, RunError};
use grainflow_core::Communicator;
use grainflow_fluid::{FlowSolver, Location, StepReport, ViscousScheme, CFL_LIMIT};
use grainflow_io::{
    write_field_pieces_index, CellLayout, CsvSeries, FieldFrame, FieldPiece, PvdIndex,
};
use serde_json::{json, Map, Value};
use std::path::Path;
use std::time::Instant;

/// Runs a validated fluid-only case into `out`. Nothing is written if the
/// flow cannot be built or its fixed time step is beyond the CFL limit.
///
/// On several ranks (`communicator`) each holds its share of the cells;
/// the root writes the shared files and every rank its piece of the fields.
pub fn run(
    case: &Case,
    out: &Path,
    show_progress: bool,
    communicator: Communicator,
) -> Result<Summary, RunError> {
    let started = Instant::now();
    let root = communicator.is_root();
    let mut solver = fluid_scene::build_on(case, communicator.clone()).map_err(RunError::Case)?;
    let density = case.fluid_section().density;
    let end = case.time.end;
    // An adapted step also keeps an explicit viscous term stable.
    let viscous_cap = viscous_limit(&solver).map_or(f64::INFINITY, |limit| {
        0.9 * limit / solver.viscous_number(1.0)
    });
    let step_size = |solver: &FlowSolver| -> f64 {
        match (case.time.dt, case.time.cfl) {
            (Some(dt), _) => dt,
            (None, Some(cfl)) => solver.time_step_for_cfl(cfl).min(viscous_cap).min(end),
            (None, None) => unreachable!("validated: time.dt or time.cfl"),
        }
    };
    let first_dt = step_size(&solver);
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

    if let Some(limit) = viscous_limit(&solver) {
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

    let mut outputs = FluidOutputs::create(out, case, &communicator).map_err(RunError::Io)?;
    let grid = &solver.grid;
    let partition = solver.partition();
    let global_cells = partition.global_cells;
    let cells: usize = global_cells.iter().product();
    outputs.run.log(&format!(
        "grainflow {}: fluid-only scene, {}D staggered grid {:?} ({cells} cells), ν = {:.4e} m²/s, \
         RK3 + Crank–Nicolson, direct pressure solve; no particles",
        env!("CARGO_PKG_VERSION"),
        grid.dim(),
        &global_cells[..grid.dim()],
        solver.viscosity
    ));
    if communicator.size() > 1 {
        let r = partition.ranks;
        let ranks = communicator.size();
        outputs.run.log(&format!(
            "{ranks} MPI ranks, cells shared in a process grid of {} x {} x {} (pencil \
             transposes in the direct solves)",
            r[0], r[1], r[2]
        ));
        if let Some(w) = sharing::load_warning(ranks, None, Some(cells as f64 / ranks as f64)) {
            outputs.run.log(&w);
            if root {
                eprintln!("{w}");
            }
        }
    }
    match case.time.cfl {
        Some(cfl) => outputs.run.log(&format!("dt adapted to CFL {cfl}")),
        None => outputs.run.log(&format!(
            "dt = {first_dt:.4e} s (CFL of the first step at most {first_cfl:.3}, limit \
             {CFL_LIMIT:.3})"
        )),
    }

    let interval = case.output.interval.unwrap_or(end / 100.0);
    let mut next_output = interval;
    let mut steps = 0u64;
    let mut report = StepReport {
        kinetic_energy: solver.kinetic_energy(),
        max_cfl: solver.max_cfl(first_dt),
        max_divergence: solver.max_divergence(),
    };
    outputs
        .write_frame(&mut solver, first_dt, steps, &report, density)
        .map_err(RunError::Io)?;
    let mut progress = Progress::new(root && show_progress, end);
    let mut failure = None;
    let mut dt = first_dt;
    while solver.time < end * (1.0 - 1e-12) {
        // The last step lands on the end time, where analyses compare.
        dt = step_size(&solver).min(end - solver.time);
        let outcome = solver
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
            Ok(r) => report = r,
            Err(why) => {
                failure = Some(format!(
                    "unstable at t = {:.6e} s (step {steps}): {why}",
                    solver.time
                ));
                break;
            }
        }
        steps += 1;
        let at_end = solver.time >= end * (1.0 - 1e-12);
        if solver.time >= next_output - 0.5 * dt || at_end {
            outputs
                .write_frame(&mut solver, dt, steps, &report, density)
                .map_err(RunError::Io)?;
            next_output += interval;
        }
        if let Some(line) = progress.update(solver.time, steps) {
            outputs.run.log(&line);
            eprintln!("{line}");
        }
    }
    progress.finish();

    let wall_seconds = started.elapsed().as_secs_f64();
    let metrics = if failure.is_none() {
        fluid_metrics(case, &solver, &report)
    } else {
        Map::new()
    };
    let cell_steps = cells as f64 * steps as f64;
    let summary = json!({
        "analysis": case.analysis,
        "status": if failure.is_some() { "unstable" } else { "ok" },
        "stop_reason": failure.clone().unwrap_or_else(|| "end time reached".to_string()),
        "cells": cells,
        "ranks": communicator.size(),
        "dimension": solver.grid.dim(),
        "steps": steps,
        "dt": dt,
        "simulated_time": solver.time,
        "wall_seconds": wall_seconds,
        "cell_steps_per_second": cell_steps / wall_seconds,
        "threads": rayon::current_num_threads(),
        "peak_memory_bytes": communicator.max(peak_memory_bytes().unwrap_or(0) as f64) as u64,
        "metrics": metrics,
    });
    outputs.run.finish(
        &summary,
        failure,
        &format!(
            "done: {steps} steps in {wall_seconds:.2} s ({:.3e} cell-steps/s)",
            cell_steps / wall_seconds
        ),
    )?;
    Ok(Summary {
        json: summary,
        metrics,
    })
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

/// Cell-centred velocity (mean of a cell's two faces along each axis),
/// pressure [Pa] and vorticity (the curl on the cell's edges, averaged to
/// its centre) of the current flow, for ParaView.
pub(crate) fn cell_fields(
    solver: &mut FlowSolver,
    density: f64,
) -> (Vec<[f64; 3]>, Vec<f64>, Vec<[f64; 3]>) {
    solver.fill_velocity_ghosts();
    let grid = &solver.grid;
    let dim = grid.dim();
    let velocity = &solver.velocity;
    let cells = grid.cell_block();
    let mut cell_velocity = Vec::new();
    let mut pressure = Vec::new();
    let mut vorticity = Vec::new();
    let line = grid.line_axis();
    grid.for_each(&cells, |index, point| {
        let mut u = [0.0; 3];
        for a in 0..dim {
            u[a] = 0.5 * (velocity[a][index - grid.stride(a)] + velocity[a][index]);
        }
        cell_velocity.push(u);
        pressure.push(density * solver.pressure[index]);
        // ω_c = ∂u_b/∂x_a − ∂u_a/∂x_b on the four edges of the cell along c;
        // each difference spans the distance between the centres on either
        // side of its edge (edge `e` along the line axis lies on face `e`).
        let curl = |a: usize, b: usize| {
            let (sa, sb) = (grid.stride(a), grid.stride(b));
            let mut sum = 0.0;
            for shift_a in [1, 0] {
                for shift_b in [1, 0] {
                    let edge = index - shift_a * sa - shift_b * sb;
                    let mut edge_line = point[line];
                    if a == line {
                        edge_line -= shift_a;
                    }
                    if b == line {
                        edge_line -= shift_b;
                    }
                    sum += (velocity[b][edge + sa] - velocity[b][edge]) / grid.gap(a, edge_line)
                        - (velocity[a][edge + sb] - velocity[a][edge]) / grid.gap(b, edge_line);
                }
            }
            0.25 * sum
        };
        vorticity.push(if dim == 3 {
            [curl(1, 2), curl(2, 0), curl(0, 1)]
        } else {
            [0.0, 0.0, curl(0, 1)]
        });
    });
    (cell_velocity, pressure, vorticity)
}

/// The field files of a scene with a fluid: `fields/fields_NNNNNN.vti`
/// (cell-centred velocity, pressure in Pa, vorticity, and any extra
/// scalars) indexed by `fields.pvd`.
pub(crate) struct FieldFiles {
    dir: std::path::PathBuf,
    /// `fields.pvd` (the root's).
    index: Option<PvdIndex>,
    /// Lower corner of the domain: the origin of every piece's extent.
    origin: [f64; 3],
    frames: usize,
}

impl FieldFiles {
    /// The field files in `dir`, if `output.fields` asks for them.
    pub(crate) fn create(dir: &Path, case: &Case, root: bool) -> std::io::Result<Option<Self>> {
        if !case.output.fields {
            return Ok(None);
        }
        std::fs::create_dir_all(dir.join("fields"))?;
        let mut origin = [0.0; 3];
        origin[..case.domain.lower.len()].copy_from_slice(&case.domain.lower);
        Ok(Some(FieldFiles {
            dir: dir.to_path_buf(),
            index: root.then(|| PvdIndex::new(dir.join("fields.pvd"))),
            origin,
            frames: 0,
        }))
    }

    /// A field file of the current flow with `extra` cell scalars.
    pub(crate) fn write(
        &mut self,
        solver: &mut FlowSolver,
        density: f64,
        extra: &[(&str, &[f64])],
    ) -> std::io::Result<()> {
        let (velocity, pressure, vorticity) = cell_fields(solver, density);
        let grid = &solver.grid;
        let partition = solver.partition();
        let (ranks, rank) = (partition.size(), solver.communicator().rank());
        let faces = [0, 1, 2].map(|axis| grid.face_coordinates(axis));
        let layout = if grid.is_uniform(grid.line_axis()) {
            CellLayout::Uniform {
                origin: self.origin,
                spacing: grid.spacing,
            }
        } else {
            CellLayout::Rectilinear {
                faces: [&faces[0], &faces[1], &faces[2]],
            }
        };
        let extension = layout.extension();
        let piece = |r: usize| format!("fields_{:06}_{r:04}.{extension}", self.frames);
        let name = if ranks == 1 {
            format!("fields/fields_{:06}.{extension}", self.frames)
        } else {
            format!("fields/{}", piece(rank))
        };
        let mut scalars: Vec<(&str, &[f64])> = vec![("pressure", &pressure)];
        scalars.extend_from_slice(extra);
        FieldFrame {
            cells: grid.cells,
            offset: partition.offset(),
            layout,
            scalars: &scalars,
            vectors: &[("velocity", &velocity), ("vorticity", &vorticity)],
        }
        .write(&self.dir.join(&name))
        .map_err(|e| std::io::Error::new(e.kind(), format!("{name}: {e}")))?;
        // Every rank's piece is whole before the root's index lists it.
        if ranks > 1 {
            solver.communicator().barrier();
        }
        if let Some(index) = &mut self.index {
            if ranks == 1 {
                index.add(solver.time, &name)?;
            } else {
                let pieces: Vec<FieldPiece> = (0..ranks)
                    .map(|r| {
                        let (offset, cells) = partition.share_of(r);
                        FieldPiece {
                            source: piece(r),
                            offset,
                            cells,
                        }
                    })
                    .collect();
                let names: Vec<&str> = scalars.iter().map(|(n, _)| *n).collect();
                let index_name = format!("fields/fields_{:06}.p{extension}", self.frames);
                write_field_pieces_index(
                    &self.dir.join(&index_name),
                    partition.global_cells,
                    &layout,
                    &names,
                    &["velocity", "vorticity"],
                    &pieces,
                )?;
                index.add(solver.time, &index_name)?;
            }
        }
        self.frames += 1;
        Ok(())
    }
}

/// A fluid scene's outputs: the files of every run, its series and its
/// field files.
struct FluidOutputs {
    run: RunDirectory,
    /// `series.csv` (the root's).
    series: Option<CsvSeries>,
    fields: Option<FieldFiles>,
}

impl FluidOutputs {
    /// `tracked.csv` stays empty: a fluid-only scene tracks no particle.
    fn create(dir: &Path, case: &Case, communicator: &Communicator) -> std::io::Result<Self> {
        let root = communicator.is_root();
        let run = RunDirectory::create_on(dir, case, communicator)?;
        let fields = FieldFiles::create(dir, case, root)?;
        let series = CsvSeries::create_on(
            root,
            &dir.join("series.csv"),
            &[
                "t",
                "dt",
                "step",
                "kinetic_energy",
                "max_cfl",
                "max_divergence",
                "wall_seconds",
            ],
        )?;
        Ok(FluidOutputs {
            run,
            series,
            fields,
        })
    }

    /// A row of `series.csv` (kinetic energy per unit density) and, if
    /// enabled, a field file.
    fn write_frame(
        &mut self,
        solver: &mut FlowSolver,
        dt: f64,
        steps: u64,
        report: &StepReport,
        density: f64,
    ) -> std::io::Result<()> {
        if let Some(series) = &mut self.series {
            series.row(&[
                solver.time,
                dt,
                steps as f64,
                report.kinetic_energy,
                report.max_cfl,
                report.max_divergence,
                self.run.started.elapsed().as_secs_f64(),
            ])?;
        }
        if let Some(fields) = &mut self.fields {
            fields.write(solver, density, &[])?;
        }
        Ok(())
    }
}
