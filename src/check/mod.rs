//! `grainflow check`: validates a case without running it and prints the
//! derived numbers, the models the scene will run and what the run will
//! cost. One report per kind of scene: grains alone ([`dry`]), a flow alone
//! ([`fluid`]), grains in a flow ([`coupled`]) and the axisymmetric scenes
//! ([`axisymmetric`]); each times a few steps of the scene itself
//! ([`cost_estimate`], and for grains poured during the run
//! [`pour_cost`]) and counts the steps of a run adapted to `time.cfl`
//! ([`cfl_steps`]).

mod axisymmetric;
pub mod cfl_steps;
mod cocd_cost;
pub mod cost_estimate;
mod coupled;
mod dry;
mod fluid;
pub mod pour_cost;

use crate::case::Case;
use crate::footprint::{human_bytes, machine_memory, Footprint};
use crate::simulation::coupled as coupled_simulation;
use crate::{scene, sharing, RunError};
use cfl_steps::{Confinement, SpeedScales};
use grainflow_fluid::CFL_LIMIT;
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
        text += &cocd_separator(case, ranks)?;
    }
    Ok(text)
}

/// For a COCD scene on several ranks, the separator its program has at
/// the start ([`sharing::Separator`]): the unknowns the ranks factorise
/// together at every iteration, and the memory each rank then needs.
/// Refuses one whose Σ does not fit beside each rank's share. Empty for
/// other scenes.
fn cocd_separator(case: &Case, ranks: usize) -> Result<String, RunError> {
    let Some((separator, grid)) = sharing::check_separator_fits(case, ranks)? else {
        return Ok(String::new());
    };
    let footprint = Footprint::of(case);
    let (per_rank, held, exchange) = if sharing::separator_factorised(case) {
        (
            footprint.per_rank_bytes(ranks, separator.held_per_rank_bytes()),
            "its share of the scene, Σ and its factor's dense end",
            String::new(),
        )
    } else {
        let per_rank = footprint.per_rank_bytes(ranks, 0.0);
        let fits = crate::footprint::machine_memory()
            .is_none_or(|memory| per_rank + separator.held_per_rank_bytes() <= memory);
        let fallback = if fits {
            "the interior point takes over a step it does not solve"
        } else {
            "the interior point cannot take over a step here (Σ does not fit beside a rank's \
             share): a step the projected gradient does not solve within \
             contact.max_iterations stops the run"
        };
        (
            per_rank,
            "its share of the scene; Σ beside it only where the interior point takes over a step",
            format!(
                "; the projected gradient factorises nothing: each iteration the ranks add up \
                 their parts of Aᵀz on the separator's {} unknowns ({} exchanged); {fallback}",
                separator.separator,
                human_bytes(8.0 * separator.separator as f64),
            ),
        )
    };
    Ok(format!(
        "  COCD on {ranks} ranks (process grid {} x {} x {}): {}{exchange}; memory per rank \
         about {} ({held})\n",
        grid.ranks[0],
        grid.ranks[1],
        grid.ranks[2],
        separator.describe(),
        human_bytes(per_rank),
    ))
}

/// The report of `check` on one rank.
pub fn report(case: &Case) -> Result<String, RunError> {
    if case.domain.geometry == crate::case::Geometry::Axisymmetric {
        return axisymmetric::report(case, &memory_line(case));
    }
    if !case.has_grains() {
        return fluid::report(case);
    }
    if case.fluid.is_some() {
        return coupled::report(case);
    }
    dry::report(case)
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
         reach (grains settling at {:.4e} m/s{driven}; the flow's CFL rate taken as {} \
         times the larger speed over the cell, as measured on the ten Cate run)",
        scales.settling.terminal,
        cfl_steps::FLOW_RATE_OVER_GRAIN_RATE
    )
}

/// The scene's memory estimate beside this machine's memory.
fn memory_line(case: &Case) -> String {
    let machine = machine_memory()
        .map(|m| format!(" (this machine: {})", human_bytes(m)))
        .unwrap_or_default();
    let footprint = Footprint::of(case);
    let keep = case.checkpoint.as_ref().map_or(2, |c| c.keep);
    let contact = if footprint.contact_bytes > 0.0 {
        format!(
            ", of which the COCD step's factor and work {} (a packing at rest; a loose flow \
             holds less)",
            human_bytes(footprint.contact_bytes)
        )
    } else {
        String::new()
    };
    format!(
        "memory estimate: {}{contact}{machine}\ncheckpoint: about {} each on disk, the last \
         {keep} kept (written on SIGTERM, SIGINT, time.wall_limit{})",
        human_bytes(footprint.bytes),
        human_bytes(footprint.checkpoint_bytes(case.walls.len())),
        if case.checkpoint.is_some() {
            ", the [checkpoint] schedule and at the end"
        } else {
            ""
        }
    )
}
