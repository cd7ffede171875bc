//! `check` of an axisymmetric scene: the models, the (r, z) grid, the
//! dimensionless numbers of the lightest grain, the steps, and the wall
//! time estimated by timing a few steps of the scene itself.

use super::cost_estimate::{self, Evolution};
use super::Settling;
use crate::case::Case;
use crate::check::cfl_steps::SpeedScales;
use crate::simulation::coupled as coupled_simulation;
use crate::{scene::axisymmetric as axisymmetric_scene, RunError};
use grainflow_core::{Communicator, Dimension};
use grainflow_ibm::settling::added_mass_coefficient;
use std::fmt::Write;

pub fn report(case: &Case, memory_line: &str) -> Result<String, RunError> {
    let building = std::time::Instant::now();
    let (mut system, contact_time) =
        axisymmetric_scene::build(case, Communicator::serial()).map_err(RunError::Case)?;
    let setup = building.elapsed().as_secs_f64();
    let warning = coupled_simulation::check_dem_substep(system.dem_dt, contact_time)?;
    let density_warning = coupled_simulation::check_density_ratio(
        system.smallest_density_ratio(),
        system.coupling,
        system.immersed.layer,
        3,
    )?;
    let f = case.fluid_section();
    let grid = &system.flow.grid;
    let [nr, nz] = grid.cells;
    let mut out = String::new();
    let _ = writeln!(out, "models:");
    let _ = writeln!(
        out,
        "  axisymmetric incompressible Navier–Stokes in (r, z) without swirl, staggered grid, \
         RK3 + Crank–Nicolson, direct solves (transforms along z, elimination along r)"
    );
    let _ = writeln!(
        out,
        "  immersed boundaries on the axis: tanh solid fraction in the meridian plane (eq. \
         8–10), direct forcing at every stage (eq. 7), loads {:?}",
        system.coupling
    );
    let _ = writeln!(
        out,
        "  3D soft-sphere DEM, the grains on the axis, sub-cycled within each stage{}",
        if system.dem.lubrication.is_some() {
            "; lubrication (eq. 19)"
        } else {
            ""
        }
    );
    let core = grid.width(1);
    let widest = (1..=nr).map(|i| grid.width(i)).fold(0.0, f64::max);
    let _ = writeln!(
        out,
        "fluid: (r, z) grid {nr} x {nz} ({} cells) over radius {:.4e} m and z {:?} m; radial \
         cells {core:.4e} to {widest:.4e} m, dz {:.4e} m; density {} kg/m3, viscosity {} Pa s",
        nr * nz,
        grid.radius,
        grid.z_range,
        grid.dz,
        f.density,
        f.viscosity
    );
    let p = &system.dem.particles;
    let _ = writeln!(out, "particles: {} on the axis", p.n_owned);
    let dt = case.time.dt.expect("validated");
    let h = core.min(grid.dz);
    let moving = (0..p.n_owned).filter(|&k| !p.is_fixed(k));
    let mut settling_from_rest = crate::check::cfl_steps::Settling::default();
    if let Some(k) = moving.min_by(|&a, &b| p.mass[a].total_cmp(&p.mass[b])) {
        let (rho, mu) = (f.density, f.viscosity);
        let diameter = 2.0 * p.radius[k];
        let rho_p = p.mass[k]
            / grainflow_ibm::particle_volume(grainflow_core::Dimension::Three, p.radius[k]);
        let g = system.dem.domain.gravity.norm();
        let _ = writeln!(
            out,
            "  lightest grain: D = {diameter:.4e} m, D/dr = {:.1}, D/dz = {:.1}, density ratio \
             rho_p/rho = {:.4}",
            diameter / core,
            diameter / grid.dz,
            rho_p / rho
        );
        if g > 0.0 && rho_p != rho {
            let settling = Settling {
                rho,
                rho_p,
                mu,
                diameter,
                g,
            };
            settling.write(&mut out, dt, h);
            let added_mass = added_mass_coefficient(Dimension::Three);
            settling_from_rest = crate::check::cfl_steps::Settling::from_rest(
                rho, rho_p, mu, diameter, g, added_mass,
            );
        }
    }
    let _ = writeln!(out, "time:");
    let _ = writeln!(
        out,
        "  DEM sub-step <= {:.4e} s = {:.4} t_c (t_c = {contact_time:.4e} s)",
        system.dem_dt,
        system.dem_dt / contact_time
    );
    let (steps, what) = match case.time.cfl {
        Some(cfl) => {
            let scales = SpeedScales {
                settling: settling_from_rest,
                driven: None,
            };
            let steps = scales.steps(case.time.end, dt, cfl, h);
            let _ = writeln!(out, "{}", super::scales_line(&scales, cfl, steps));
            (steps, format!("steps adapted to CFL {cfl}"))
        }
        None => ((case.time.end / dt).ceil(), "steps".to_string()),
    };
    let _ = writeln!(
        out,
        "  end = {} s: {steps:.0} fluid steps, {:.3e} cell-steps",
        case.time.end,
        steps * (nr * nz) as f64
    );
    for w in warning.iter().chain(&density_warning) {
        let _ = writeln!(out, "{w}");
    }
    let estimate = cost_estimate::probe(setup, steps, Evolution::Contacts, || {
        system.step(dt).is_ok()
    });
    if let Some(estimate) = estimate {
        let _ = writeln!(out, "{}", estimate.line(steps, &what));
    }
    let _ = writeln!(out, "{memory_line}");
    Ok(out)
}
