//! `check` of a flow without grains: the grid, the Reynolds number of the
//! initial flow, the convective and viscous limits of the step, the cost.

use super::cost_estimate::{self, Evolution};
use super::memory_line;
use crate::case::Case;
use crate::{scene::fluid as fluid_scene, RunError};
use grainflow_fluid::{ViscousScheme, CFL_LIMIT, EXPLICIT_VISCOUS_LIMIT};
use std::fmt::Write;

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
pub(super) fn report(case: &Case) -> Result<String, RunError> {
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
