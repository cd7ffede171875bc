//! `check` of grains in a flow.

use super::cost_estimate::{self, Evolution};
use super::{cfl_steps, coupled_simulation, memory_line, scales_line, Settling};
use crate::case::Case;
use crate::{scene, RunError};
use grainflow_ibm::LayerForcing;
use std::fmt::Write;

/// `check` of grains in a fluid: the models, the dimensionless numbers of
/// the lightest grain (density ratio, Archimedes, Schiller–Naumann terminal
/// Reynolds and Stokes numbers), resolution, the fluid step against the
/// CFL limit at that terminal velocity, the DEM sub-step, lubrication.
pub(super) fn report(case: &Case) -> Result<String, RunError> {
    let building = std::time::Instant::now();
    let (system, contact_time) = coupled_simulation::build(case).map_err(RunError::Case)?;
    let setup = building.elapsed().as_secs_f64();
    let warning = coupled_simulation::check_dem_substep(system.dem_dt, contact_time)?;
    let density_warning = coupled_simulation::check_density_ratio(
        system.smallest_density_ratio(),
        system.coupling,
        system.immersed.layer,
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
    match system.immersed.layer {
        LayerForcing::Held { step } => {
            let _ = writeln!(
                out,
                "  direct forcing: the transition layer relaxed as eq. 7 does at a step of \
                 {step:.4e} s, whatever the fluid step (coupling.forcing_step)"
            );
        }
        LayerForcing::EveryStage => {
            let _ = writeln!(out, "  direct forcing: eq. 7 at every stage");
        }
        LayerForcing::Renewal => {
            let _ = writeln!(
                out,
                "  direct forcing: the transition layer relaxed at the rate the flow renews it \
                 (coupling.layer_forcing = \"renewal\"): the grain the same at any step"
            );
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
    if system.immersed.layer == LayerForcing::Renewal {
        // The viscous part of r Δt alone (the slip adds to it).
        let viscous = grainflow_ibm::layer_forcing::renewal_exponent(
            0.0,
            system.flow.viscosity,
            grid.spacing[0],
            dt,
        );
        if viscous > 1.0 {
            let _ = writeln!(
                out,
                "  at dt = {dt:e} s the layer's viscous renewal alone gives r dt = {viscous:.2}: \
                 a stage forces in at least {} passes, each followed by a projection (a \
                 shorter step takes fewer)",
                viscous.ceil()
            );
        }
        let cell = grid.spacing[0];
        let number = system.flow.viscosity * dt / (cell * cell);
        if let Some(line) = stokes_leak_warning(number) {
            let _ = writeln!(out, "{line}");
        }
    }
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
            if let Some(layer_step) = system.immersed.layer.layer_step(dt) {
                let cfl = velocity * layer_step / h;
                if let Some(w) = coupled_simulation::forcing_step_warning(cfl) {
                    let _ = writeln!(out, "{w}");
                }
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

/// The renewal forcing's drag deficit in Stokes flow through an array of
/// spheres at D/Δx = 8 against the viscous number of a cell ν Δt/Δx²
/// (`solvers/ibm/tests/stokes_array.rs`, docs/validation.md §10): the
/// layer leaks between two forcings once the step exceeds about a viscous
/// time of a cell.
const RENEWAL_STOKES_DEFICIT: [(f64, f64); 5] = [
    (0.8, 0.033),
    (1.6, 0.044),
    (3.2, 0.071),
    (6.4, 0.120),
    (12.8, 0.203),
];

/// A warning where the renewal forcing's grain depends on the step: past
/// ν Δt/Δx² = 1.6 its Stokes drag falls by more than the 4.4 % it keeps
/// from 0.8 to 1.6. The deficit is read off [`RENEWAL_STOKES_DEFICIT`],
/// interpolated in the logarithm of the number (extrapolated past 12.8).
fn stokes_leak_warning(number: f64) -> Option<String> {
    let table = &RENEWAL_STOKES_DEFICIT;
    if number <= table[1].0 {
        return None;
    }
    let k = table
        .windows(2)
        .position(|w| number <= w[1].0)
        .unwrap_or(table.len() - 2);
    let ((n0, d0), (n1, d1)) = (table[k], table[k + 1]);
    let deficit = d0 + (d1 - d0) * (number / n0).ln() / (n1 / n0).ln();
    let shorter = table[1].0 / number;
    Some(format!(
        "warning: ν Δt/Δx² = {number:.3}: past a viscous time of a cell the fluid leaks through \
         the forced layer between two forcings, and in Stokes flow the grain's drag falls by \
         about {:.0} % (D/Δx = 8; 4.4 % at 1.6, 7.1 % at 3.2, 20 % at 12.8: \
         tests/stokes_array.rs); where the flow is slow and viscous, a step {shorter:.2} times \
         this one keeps it within 5 %",
        100.0 * deficit
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_leak_warning_reads_the_measured_deficits_and_is_silent_below_a_viscous_time() {
        assert!(stokes_leak_warning(0.8).is_none());
        assert!(stokes_leak_warning(1.6).is_none());
        let at = |n: f64| stokes_leak_warning(n).unwrap();
        assert!(at(3.2).contains("about 7 %"), "{}", at(3.2));
        assert!(at(12.8).contains("about 20 %"), "{}", at(12.8));
        // Between two measured numbers, between their deficits.
        assert!(at(2.26).contains("about 6 %"), "{}", at(2.26));
    }
}
