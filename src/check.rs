//! `grainflow check`: validates a case without running it and prints the
//! derived numbers and the models the scene will run.

use crate::case::Case;
use crate::cfl_steps::{self, Confinement, SpeedScales};
use crate::cost_estimate::{self, Evolution};
use crate::footprint::{human_bytes, machine_memory, Footprint};
use crate::simulation::coupled as coupled_simulation;
use crate::simulation::dry::{check_time_step, time_step};
use crate::simulation::dry_stepper::DryStepper;
use crate::{fluid_scene, scene, sharing, stability, RunError};
use grainflow_contact::{ConicSolver, Method};
use grainflow_fluid::{ViscousScheme, CFL_LIMIT, EXPLICIT_VISCOUS_LIMIT};
use grainflow_ibm::settling::{archimedes_number, schiller_naumann_reynolds};
use std::fmt::Write;

/// [`report`], and with `ranks` above one how the scene would be shared
/// among that many MPI ranks ([`sharing::report`]).
pub fn report_on(case: &Case, ranks: usize) -> Result<String, RunError> {
    crate::simulation::check_ranks(case, ranks)?;
    // Before anything is built: a scene too large for the machine is
    // refused by its keys, not by a failed allocation.
    Footprint::of(case).check_fits(ranks, machine_memory())?;
    let mut text = report(case)?;
    if ranks > 1 {
        let grid = sharing::flow_grid(case);
        let sharing = match (case.has_grains(), case.fluid.is_some()) {
            (true, true) => {
                let (system, _) = coupled_simulation::build(case).map_err(RunError::Case)?;
                sharing::report(case, Some(&system.dem), grid.as_ref(), ranks)
            }
            (true, false) => {
                let system = scene::build(case).map_err(RunError::Case)?;
                sharing::report(case, Some(&system), None, ranks)
            }
            _ => sharing::report(case, None, grid.as_ref(), ranks),
        };
        text += &sharing.map_err(RunError::Case)?;
    }
    Ok(text)
}

pub fn report(case: &Case) -> Result<String, RunError> {
    if case.domain.geometry == crate::case::Geometry::Axisymmetric {
        return crate::check_axisymmetric::report(case, &memory_line(case));
    }
    if !case.has_grains() {
        return fluid_report(case);
    }
    if case.fluid.is_some() {
        return coupled_report(case);
    }
    let building = std::time::Instant::now();
    let mut system = scene::build(case).map_err(RunError::Case)?;
    let setup = building.elapsed().as_secs_f64();
    // The first batch of a pour is there at t = 0: its grains count in the
    // time step.
    let (pouring, pour_lines) = crate::pouring::start(case, &mut system).map_err(RunError::Case)?;
    let hard = scene::hard_contact(case);
    let p = &system.particles;
    let n = p.n_owned;
    let glued = (0..n).filter(|&k| p.is_fixed(k)).count();
    let mut out = String::new();
    let dim = system.domain.dimension.count();
    let _ = writeln!(out, "models:");
    let model = match hard.as_ref().map(|h| h.method) {
        None => "soft-sphere DEM (linear spring-dashpot, tangential history, Coulomb)".to_string(),
        Some(Method::Cocd) => {
            let solver = hard
                .as_ref()
                .map_or(ConicSolver::Clarabel, |h| h.conic_solver)
                .name();
            format!("hard contact: COCD, one conic program per step ({solver}), inelastic, Coulomb's cone")
        }
        Some(Method::Nscd { restitution }) => format!(
            "hard contact: NSCD, Gauss-Seidel over the contacts, Newton restitution {restitution}, Coulomb"
        ),
    };
    let _ = writeln!(out, "  {dim}D {model}");
    let _ = writeln!(
        out,
        "  dry scene: no [fluid] table, so no fluid grid is allocated and no lubrication"
    );
    let _ = writeln!(out, "  walls: {}", system.walls.len());
    for w in &system.walls {
        let removal = w
            .remove_at
            .map(|t| format!(", removed at t = {t} s"))
            .unwrap_or_default();
        let _ = writeln!(
            out,
            "    {} normal {:?} friction {}{}{}",
            w.name,
            w.normal.as_slice(),
            w.friction,
            if w.two_sided { ", two-sided" } else { "" },
            removal
        );
    }
    let periodic: Vec<&str> = ["x", "y", "z"]
        .iter()
        .zip(system.domain.periodic)
        .filter(|(_, p)| *p)
        .map(|(a, _)| *a)
        .collect();
    let _ = writeln!(
        out,
        "  periodic axes: {}",
        if periodic.is_empty() {
            "none".into()
        } else {
            periodic.join(", ")
        }
    );
    let _ = writeln!(out, "particles: {n} ({glued} glued) at t = 0");
    if !pour_lines.is_empty() {
        let _ = writeln!(
            out,
            "  {} more to be poured during the run",
            pouring.remaining()
        );
        for line in &pour_lines {
            let _ = writeln!(out, "  {line}");
        }
    }
    let masses: Vec<f64> = (0..n).map(|k| p.mass[k]).collect();
    let (m_min, m_max) = (
        masses.iter().cloned().fold(f64::MAX, f64::min),
        masses.iter().cloned().fold(0.0, f64::max),
    );
    let _ = writeln!(
        out,
        "  mass: {m_min:.4e} .. {m_max:.4e} kg{}",
        if dim == 2 { " per metre" } else { "" }
    );
    if let Some(hard) = &hard {
        let dt = case.time.dt.expect("validated: hard contact has time.dt");
        let _ = writeln!(out, "contact:");
        let _ = writeln!(
            out,
            "  friction = {}, tolerance = {:.1e}, at most {} {} per step",
            system.law.friction,
            hard.tolerance,
            hard.max_iterations,
            if hard.method == Method::Cocd {
                "interior-point iterations"
            } else {
                "Gauss-Seidel sweeps"
            }
        );
        let _ = writeln!(
            out,
            "  candidate threshold D = {:.4e} m (widened to 3 v_max dt when grains are faster)",
            hard.threshold
        );
        let _ = writeln!(out, "time:");
        let steps = (case.time.end / dt).ceil();
        let _ = writeln!(
            out,
            "  dt = {dt:.4e} s (no contact time: grains do not overlap); end = {} s: {steps:.0} steps",
            case.time.end
        );
    } else {
        let (dt, contact_time) = time_step(case, &system);
        let warning = check_time_step(dt, contact_time)?;
        let (k_lo, g_lo) = system.law.normal.coefficients(0.5 * m_min);
        let _ = writeln!(out, "contact:");
        let _ = writeln!(
            out,
            "  k_n = {k_lo:.4e} N/m, gamma_n = {g_lo:.4e} N s/m (lightest pair)"
        );
        let _ = writeln!(
            out,
            "  k_t/k_n = {}, friction = {}",
            system.law.tangential_ratio, system.law.friction
        );
        let _ = writeln!(out, "  shortest contact time t_c = {contact_time:.4e} s");
        let _ = writeln!(out, "time:");
        let _ = writeln!(out, "  dt = {dt:.4e} s = {:.4} t_c", dt / contact_time);
        let _ = writeln!(
            out,
            "  limits: accurate (restitution within 1 %) dt <= {:.4e} s; stable dt <= {:.4e} s",
            stability::ACCURATE_DT_OVER_TC * contact_time,
            stability::STABLE_DT_OVER_TC * contact_time
        );
        let steps = (case.time.end / dt).ceil();
        let _ = writeln!(
            out,
            "  end = {} s: {steps:.0} steps, {:.3e} particle-steps",
            case.time.end,
            steps * n as f64
        );
        if let Some(w) = warning {
            let _ = writeln!(out, "{w}");
        }
    }
    if let Some(w) = scene::glued_overlap_warning(case).map_err(RunError::Case)? {
        let _ = writeln!(out, "{w}");
    }
    // As `grainflow run` chooses them, on one rank.
    let threads = grainflow_dem::threads::choose_threads(
        n + pouring.remaining(),
        rayon::current_num_threads(),
        1,
        case.parallel.as_ref().and_then(|p| p.threads),
    );
    let _ = writeln!(out, "threads: {} ({})", threads.threads, threads.why);
    let (mut stepper, dt, _) = DryStepper::new(case, &mut system)?;
    let steps = (case.time.end / dt).ceil();
    let limit = case.time.overlap_limit;
    // Timed on the threads the run would use.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.threads)
        .build()
        .map_err(|e| RunError::Case(format!("cannot start threads: {e}")))?;
    let estimate = pool.install(|| {
        cost_estimate::probe(setup, steps, Evolution::Contacts, || {
            stepper.step(&mut system, dt, limit).is_none()
        })
    });
    if let Some(estimate) = estimate {
        let what = if case.time.rest_speed.is_some() {
            "steps to time.end (at most: the run stops at rest)"
        } else {
            "steps to time.end"
        };
        let _ = writeln!(out, "{}", estimate.line(steps, what));
        if pouring.remaining() > 0 {
            let _ = writeln!(
                out,
                "  (an underestimate: the steps were timed with the {} moving grains there at \
                 t = 0, and the pour brings {} more; a step costs more as they come in: in the \
                 full silo it cost ten times the probe's once 6,370 grains were in)",
                n - glued,
                pouring.remaining()
            );
        }
    }
    let _ = writeln!(out, "{}", memory_line(case));
    Ok(out)
}

/// Largest ratio of neighbouring widths along a stretched axis that
/// `check` passes without a warning.
const MAX_SMOOTH_GROWTH: f64 = 1.25;

/// `check` warns when Crank–Nicolson leaves the finest grid modes with
/// more than this factor per step.
const SLOW_DAMPING: f64 = 0.9;

/// What a step multiplies a Laplacian mode by with Crank–Nicolson at each
/// stage, `Π_k (1 − α_k z/2) / (1 + α_k z/2)`, `z` its viscous number: it
/// tends to −1 as `z` grows (the scheme is A- but not L-stable).
fn crank_nicolson_damping(viscous_number: f64) -> f64 {
    (0..grainflow_fluid::STAGES)
        .map(|stage| {
            let half = 0.5 * grainflow_fluid::stage_fraction(stage) * viscous_number;
            (1.0 - half) / (1.0 + half)
        })
        .product()
}

/// `check` of a fluid-only scene: grid, Reynolds number of the initial
/// flow, the convective and viscous time-step limits, memory.
fn fluid_report(case: &Case) -> Result<String, RunError> {
    let building = std::time::Instant::now();
    let solver = fluid_scene::build(case).map_err(RunError::Case)?;
    let setup = building.elapsed().as_secs_f64();
    let f = case.fluid_section();
    let grid = &solver.grid;
    let dim = grid.dim();
    let cells: usize = grid.cells.iter().product();
    let h = (0..dim)
        .map(|axis| grid.min_width(axis))
        .fold(f64::INFINITY, f64::min);
    let nu = solver.viscosity;
    let mut out = String::new();
    let _ = writeln!(out, "models:");
    let _ = writeln!(
        out,
        "  {dim}D incompressible Navier–Stokes, staggered grid, RK3 + Crank–Nicolson, \
         FFT/tridiagonal direct pressure solve ({} transforms)",
        match fluid_scene::transform_backend(case) {
            grainflow_fluid::TransformBackend::Fftw => "FFTW",
            grainflow_fluid::TransformBackend::Rust => "rustfft/rustdct",
        }
    );
    let _ = writeln!(
        out,
        "  fluid-only scene: no [particles], so no DEM and no lubrication"
    );
    for (name, [lower, upper]) in ["x", "y", "z"]
        .iter()
        .zip(solver.boundaries.faces)
        .take(dim)
    {
        let _ = writeln!(out, "  {name} faces: {lower:?}, {upper:?}");
    }
    let _ = writeln!(
        out,
        "fluid: {:?} cells ({cells}), spacing {:?} m",
        &grid.cells[..dim],
        &grid.spacing[..dim]
    );
    let line = grid.line_axis();
    if !grid.is_uniform(line) {
        let widest = grid
            .interior(line)
            .map(|i| grid.width(line, i))
            .fold(0.0, f64::max);
        let growth = grid.max_growth(line);
        let _ = writeln!(
            out,
            "  {} stretched: widths {:.4e} to {widest:.4e} m, largest ratio of neighbours {growth:.3}{}",
            ["x", "y", "z"][line],
            grid.min_width(line),
            if growth > MAX_SMOOTH_GROWTH {
                " -- warning: above 1.25 the second-order truncation error grows with the \
                 change of width; add cells or lower the factor"
            } else {
                ""
            }
        );
    }
    let _ = writeln!(
        out,
        "  density {} kg/m3, viscosity {} Pa s (nu = {nu:.4e} m2/s)",
        f.density, f.viscosity
    );
    let speed = solver.max_cfl(1.0) * h / dim as f64;
    let length = (0..dim)
        .map(|a| case.domain.upper[a] - case.domain.lower[a])
        .fold(0.0, f64::max);
    if speed > 0.0 {
        let _ = writeln!(
            out,
            "  initial flow: largest speed about {speed:.4e} m/s, Re = U L / nu = {:.4e}",
            speed * length / nu
        );
    }
    let _ = writeln!(out, "time:");
    // The first step sees the walls, inflows and unbalanced forces beside
    // the initial flow: from rest, a lid sets the pace.
    let convective = solver.time_step_for_cfl(CFL_LIMIT);
    let viscous = EXPLICIT_VISCOUS_LIMIT / solver.viscous_number(1.0);
    let _ = writeln!(
        out,
        "  convective limit (CFL sqrt(3), RK3): dt <= {convective:.4e} s in the first step \
         (initial flow, moving walls and inflows, unbalanced body force)"
    );
    let _ = writeln!(
        out,
        "  viscous limit of an explicit step (nu dt sum 4/h^2 <= {EXPLICIT_VISCOUS_LIMIT:.3}): \
         dt <= {viscous:.4e} s{}",
        if solver.viscous_scheme == ViscousScheme::Explicit {
            " -- applies: fluid.viscous = \"explicit\""
        } else {
            " (lifted here by Crank–Nicolson)"
        }
    );
    match (case.time.dt, case.time.cfl) {
        (Some(dt), _) => {
            let _ = writeln!(
                out,
                "  dt = {dt:.4e} s: CFL of the first step at most {:.3}{}",
                solver.cfl_bound(dt),
                if solver.cfl_bound(dt) > CFL_LIMIT {
                    " -- beyond the RK3 limit: the run will refuse it"
                } else {
                    ""
                }
            );
            let stiffness = solver.viscous_number(dt);
            let damping = crank_nicolson_damping(stiffness);
            if solver.viscous_scheme == ViscousScheme::CrankNicolson && damping.abs() > SLOW_DAMPING
            {
                let _ = writeln!(
                    out,
                    "  viscous number nu dt sum 4/h^2 = {stiffness:.3e}: Crank–Nicolson multiplies \
                     the finest grid modes by {damping:.3} per step -- warning: a sudden start or \
                     wall leaves grid-scale oscillations that decay slowly; start with a smaller dt"
                );
            }
            let steps = (case.time.end / dt).ceil();
            let _ = writeln!(
                out,
                "  end = {} s: {steps:.0} steps, {:.3e} cell-steps",
                case.time.end,
                steps * cells as f64
            );
        }
        (None, Some(cfl)) => {
            let _ = writeln!(
                out,
                "  dt adapted to CFL {cfl}: first step {:.4e} s",
                solver.time_step_for_cfl(cfl).min(case.time.end)
            );
        }
        (None, None) => {}
    }
    // With time.cfl the steps are counted at the first step's size.
    let dt = case
        .time
        .dt
        .unwrap_or_else(|| solver.time_step_for_cfl(case.time.cfl.unwrap_or(1.0)))
        .min(case.time.end);
    let steps = (case.time.end / dt).ceil();
    let mut solver = solver;
    let estimate =
        cost_estimate::probe(setup, steps, Evolution::Steady, || solver.step(dt).is_ok());
    if let Some(estimate) = estimate {
        let what = if case.time.dt.is_some() {
            "steps"
        } else {
            "steps of the first step's size"
        };
        let _ = writeln!(out, "{}", estimate.line(steps, what));
    }
    let _ = writeln!(out, "{}", memory_line(case));
    Ok(out)
}

/// A sphere settling under gravity, for the numbers `check` prints.
pub(crate) struct Settling {
    pub rho: f64,
    pub rho_p: f64,
    pub mu: f64,
    pub diameter: f64,
    pub g: f64,
}

impl Settling {
    /// Writes Ar, the Schiller–Naumann terminal Re, U and St, and the step
    /// `dt` against the CFL limit on cells of `h` at that velocity; returns U.
    pub(crate) fn write(&self, out: &mut String, dt: f64, h: f64) -> f64 {
        let Settling {
            rho,
            rho_p,
            mu,
            diameter,
            g,
        } = *self;
        let archimedes = archimedes_number(rho, rho_p, mu, diameter, g);
        let reynolds = schiller_naumann_reynolds(archimedes);
        let velocity = reynolds * mu / (rho * diameter);
        let stokes = (rho_p + 0.5 * rho) * velocity * diameter / (9.0 * mu);
        let _ = writeln!(
            out,
            "  Ar = {archimedes:.4e}; Schiller–Naumann terminal Re = {reynolds:.4}, \
             U = {velocity:.4e} m/s, St = {stokes:.4}"
        );
        let _ = writeln!(
            out,
            "  dt = {dt:.4e} s = {:.4} (D/g)^1/2: CFL at the terminal velocity {:.3} (RK3 \
             limit {CFL_LIMIT:.3})",
            dt / (diameter / g).sqrt(),
            velocity * dt / h
        );
        velocity
    }
}

/// `check` of grains in a fluid: the models, the dimensionless numbers of
/// the lightest grain (density ratio, Archimedes, Schiller–Naumann terminal
/// Reynolds and Stokes numbers), resolution, the fluid step against the
/// CFL limit at that terminal velocity, the DEM sub-step, lubrication.
fn coupled_report(case: &Case) -> Result<String, RunError> {
    let building = std::time::Instant::now();
    let (system, contact_time) = coupled_simulation::build(case).map_err(RunError::Case)?;
    let setup = building.elapsed().as_secs_f64();
    let warning = coupled_simulation::check_dem_substep(system.dem_dt, contact_time)?;
    let density_warning = coupled_simulation::check_density_ratio(
        system.smallest_density_ratio(),
        system.coupling,
        system.flow.grid.dim(),
    )?;
    let f = case.fluid_section();
    let grid = &system.flow.grid;
    let dim = grid.dim();
    let cells: usize = grid.cells.iter().product();
    let p = &system.dem.particles;
    let n = p.n_owned;
    let mut out = String::new();
    let _ = writeln!(out, "models:");
    let _ = writeln!(
        out,
        "  {dim}D incompressible Navier–Stokes, staggered grid, RK3 + Crank–Nicolson, direct \
         pressure solve"
    );
    let _ = writeln!(
        out,
        "  immersed boundaries: tanh solid fraction (eq. 8–10), direct forcing at every stage \
         (eq. 7), loads {:?}",
        system.coupling
    );
    let _ = writeln!(
        out,
        "  {dim}D soft-sphere DEM sub-cycled within each stage, hydrodynamic loads held fixed"
    );
    match &system.dem.lubrication {
        Some(l) => {
            let _ = writeln!(
                out,
                "  lubrication (eq. 19): eta/R = {:e}, acting up to gaps of {} R, implicit per pair",
                l.roughness, l.range
            );
        }
        None => {
            let _ = writeln!(out, "  no lubrication ([lubrication] absent)");
        }
    }
    match system.immersed.forcing_step {
        Some(step) => {
            let _ = writeln!(
                out,
                "  direct forcing: the transition layer relaxed as eq. 7 does at a step of \
                 {step:.4e} s, whatever the fluid step (coupling.forcing_step)"
            );
        }
        None => {
            let _ = writeln!(out, "  direct forcing: eq. 7 at every stage");
        }
    }
    let h = grid.spacing[..dim]
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let _ = writeln!(
        out,
        "fluid: {:?} cells ({cells}), spacing {:?} m; density {} kg/m3, viscosity {} Pa s",
        &grid.cells[..dim],
        &grid.spacing[..dim],
        f.density,
        f.viscosity
    );
    let _ = writeln!(out, "particles: {n}");
    let moving: Vec<usize> = (0..n).filter(|&k| !p.is_fixed(k)).collect();
    let dt = case.time.dt.expect("validated");
    if let Some(&k) = moving
        .iter()
        .min_by(|&&a, &&b| p.mass[a].total_cmp(&p.mass[b]))
    {
        let rho = f.density;
        let diameter = 2.0 * p.radius[k];
        let rho_p = p.mass[k] / grainflow_ibm::particle_volume(system.dem.dimension(), p.radius[k]);
        let g = system.dem.domain.gravity.norm();
        let mu = f.viscosity;
        let _ = writeln!(
            out,
            "  lightest grain: D = {diameter:.4e} m, D/dx = {:.1}, density ratio rho_p/rho = {:.4}",
            diameter / h,
            rho_p / rho
        );
        if dim == 3 && g > 0.0 && rho_p != rho {
            let settling = Settling {
                rho,
                rho_p,
                mu,
                diameter,
                g,
            };
            let velocity = settling.write(&mut out, dt, h);
            let layer_step = system.immersed.forcing_step.unwrap_or(dt);
            if let Some(w) = coupled_simulation::forcing_step_warning(velocity * layer_step / h) {
                let _ = writeln!(out, "{w}");
            }
        }
    }
    let _ = writeln!(out, "time:");
    let _ = writeln!(
        out,
        "  DEM sub-step <= {:.4e} s = {:.4} t_c (t_c = {contact_time:.4e} s): {:.0} sub-steps per fluid step",
        system.dem_dt,
        system.dem_dt / contact_time,
        (dt / system.dem_dt).ceil()
    );
    let steps = (case.time.end / dt).ceil();
    let _ = writeln!(
        out,
        "  end = {} s: {steps:.0} fluid steps, {:.3e} cell-steps",
        case.time.end,
        steps * cells as f64
    );
    let overlap_warning = scene::glued_overlap_warning(case).map_err(RunError::Case)?;
    for w in warning
        .iter()
        .chain(&density_warning)
        .chain(&overlap_warning)
    {
        let _ = writeln!(out, "{w}");
    }
    let dt = case
        .time
        .dt
        .expect("validated: grains in a fluid have time.dt");
    let (steps, what) = match case.time.cfl {
        Some(cfl) => {
            let scales = cfl_steps::speed_scales(&system);
            let steps = scales.steps(case.time.end, dt, cfl, h);
            let _ = writeln!(out, "{}", scales_line(&scales, cfl, steps));
            (steps, format!("steps adapted to CFL {cfl}"))
        }
        None => ((case.time.end / dt).ceil(), "steps".to_string()),
    };
    let mut system = system;
    let estimate = cost_estimate::probe(setup, steps, Evolution::Contacts, || {
        system.step(dt).is_ok()
    });
    if let Some(estimate) = estimate {
        let _ = writeln!(out, "{}", estimate.line(steps, &what));
    }
    let _ = writeln!(out, "{}", memory_line(case));
    Ok(out)
}

/// `check`'s line on the speed scales behind the steps of a run adapted to
/// `time.cfl`.
pub(crate) fn scales_line(scales: &SpeedScales, cfl: f64, steps: f64) -> String {
    let driven = match scales.driven {
        Some(d) => {
            let over = match d.confinement {
                Confinement::Channel { width } => format!("in a channel {width:.4e} m wide"),
                Confinement::Film { depth } => format!("in a film {depth:.4e} m deep"),
                Confinement::Free => "with no wall to hold it".to_string(),
            };
            format!(
                ", the flow driven at {:.4e} m/s² {over} (its laminar start-up: fastest {:.4e} \
                 m/s after the first second)",
                d.acceleration,
                d.fastest_speed(1.0)
            )
        }
        None => String::new(),
    };
    format!(
        "  time.cfl = {cfl}: about {steps:.0} steps, counted at the speeds the scene is set to \
         reach (grains settling at {:.4e} m/s{driven}; the flow's and the grains' speeds summed \
         at {} times the larger, as measured on the ten Cate run)",
        scales.settling.terminal,
        cfl_steps::SPEED_SUM_OVER_SCALE
    )
}

/// The scene's memory estimate beside this machine's memory.
fn memory_line(case: &Case) -> String {
    let machine = machine_memory()
        .map(|m| format!(" (this machine: {})", human_bytes(m)))
        .unwrap_or_default();
    let footprint = Footprint::of(case);
    let keep = case.checkpoint.as_ref().map_or(2, |c| c.keep);
    format!(
        "memory estimate: {}{machine}\ncheckpoint: about {} each on disk, the last {keep} kept \
         (written on SIGTERM, SIGINT, time.wall_limit{})",
        human_bytes(footprint.bytes),
        human_bytes(footprint.checkpoint_bytes(case.walls.len())),
        if case.checkpoint.is_some() {
            ", the [checkpoint] schedule and at the end"
        } else {
            ""
        }
    )
}
