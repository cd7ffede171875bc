//! `check` of grains without a fluid: the contact model, the time step
//! against the contact time, the threads, what the run will cost (a pour
//! included) and its memory.

use super::cost_estimate::{self, Evolution};
use super::{memory_line, pour_cost};
use crate::case::Case;
use crate::simulation::dry::{check_time_step, time_step};
use crate::simulation::dry_stepper::DryStepper;
use crate::{scene, stability, RunError};
use grainflow_contact::{ConicSolver, Method};
use std::fmt::Write;

/// `check` of a dry scene.
pub(super) fn report(case: &Case) -> Result<String, RunError> {
    let building = std::time::Instant::now();
    let mut system = scene::build(case).map_err(RunError::Case)?;
    let setup = building.elapsed().as_secs_f64();
    // The first batch of a pour is there at t = 0: its grains count in the
    // time step.
    let (pouring, pour_lines) =
        crate::scene::pouring::start(case, &mut system).map_err(RunError::Case)?;
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
        let (limit, after) = match (hard.method, hard.conic_solver) {
            (Method::Cocd, grainflow_contact::ConicSolver::ProjectedGradient) => (
                "projected-gradient iterations",
                " (the interior point takes over a step they do not solve)",
            ),
            (Method::Cocd, _) => ("interior-point iterations", ""),
            _ => ("Gauss-Seidel sweeps", ""),
        };
        let _ = writeln!(
            out,
            "  friction = {}, tolerance = {:.1e}, at most {} {limit} per step{after}",
            system.law.friction, hard.tolerance, hard.max_iterations,
        );
        let _ = writeln!(
            out,
            "  candidate threshold D = {:.4e} m (widened to 3 v_max dt when grains are faster)",
            hard.threshold
        );
        for w in scene::hard_contact_warnings(hard, dt, &system) {
            let _ = writeln!(out, "{w}");
        }
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
    if pouring.remaining() > 0 {
        // The pour's grains are still to come: its first batches are run
        // as `grainflow run` would, and the rest summed batch by batch.
        if let Some((probe, plan)) = pour_cost::run_first_batches(case)? {
            if let Some(estimate) = pour_cost::estimate(&probe, &plan, setup) {
                let _ = writeln!(out, "{}", estimate.lines(&probe, &plan));
            }
        }
        let _ = writeln!(out, "{}", memory_line(case));
        return Ok(out);
    }
    let (mut stepper, dt, _) = DryStepper::new(case, &mut system)?;
    let steps = (case.time.end / dt).ceil();
    // A COCD step of a large packing takes minutes to hours: predicted,
    // not timed.
    if let Some(h) = hard.as_ref().filter(|h| h.method == Method::Cocd) {
        if let Some(line) =
            super::cocd_cost::untimed_line(dim, n, steps, h.conic_solver, h.tolerance)
        {
            let _ = writeln!(out, "{line}");
            let _ = writeln!(out, "{}", memory_line(case));
            return Ok(out);
        }
    }
    let limit = case.time.overlap_limit;
    // Timed on the threads the run would use.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.threads)
        .build()
        .map_err(|e| RunError::Case(format!("cannot start threads: {e}")))?;
    // Grains apart at the first step that will pack: the packed steps
    // cost several times more (read at the first step: a long probe on a
    // fast machine may already see them land).
    let mut packing = None;
    let mut first = true;
    let method = hard.as_ref().map(|h| h.method);
    let estimate = pool.install(|| {
        cost_estimate::probe(setup, steps, Evolution::Contacts, || {
            let stepped = stepper.step(&mut system, dt, limit).is_none();
            if std::mem::take(&mut first) && stepped {
                packing = packing_of(&system, dt, method);
            }
            stepped
        })
    });
    if let Some(estimate) = estimate {
        let what = if case.time.rest_speed.is_some() {
            "steps to time.end (at most: the run stops at rest)"
        } else {
            "steps to time.end"
        };
        let estimate = match packing {
            Some((packing, _, _)) => estimate.packing(setup, steps, packing),
            None => estimate,
        };
        let _ = writeln!(out, "{}", estimate.line(steps, what));
        if let Some(line) = hard
            .as_ref()
            .and_then(|h| slower_than_the_interior_point(h, dim, n - glued, &estimate))
        {
            let _ = writeln!(out, "{line}");
        }
        if let Some((packing, contacts, landed)) = packing {
            let _ = writeln!(
                out,
                "  the grains start apart ({contacts:.2} contacts a grain) and will pack: \
                     the steps after t = {landed:.3} s, when the highest has fallen to the \
                     lowest, counted at {} times the steps timed here (a packed step's cost \
                     over one of grains apart, measured on this code for this contact model \
                     in {dim}D)",
                packing.cost_ratio
            );
        }
    }
    let _ = writeln!(out, "{}", memory_line(case));
    Ok(out)
}

/// The fewest moving spheres at which the interior point's fit
/// (`cocd_cost::step_seconds`, fitted from 17,986 spheres) is read
/// against a timed step: below, its fixed costs weigh and the fit reads
/// low (1,600 spheres at rest: about 6 s a step measured at ε = 1e-8,
/// 0.74 s by the fit at 1e-5).
const INTERIOR_POINT_FIT_FROM: usize = 10_000;

/// Where the projected gradient's steps timed here cost more than the
/// interior point's fit says a step of as many spheres at rest takes: a
/// jammed packing, where the first-order method crawls (a release of
/// 15,000 spheres from rest at a step of √(d/g): 1,127 s over its first
/// four steps against the interior point's 222 s, docs/validation.md §11).
fn slower_than_the_interior_point(
    hard: &grainflow_contact::HardContact,
    dimension: usize,
    moving: usize,
    estimate: &cost_estimate::Estimate,
) -> Option<String> {
    if hard.conic_solver != ConicSolver::ProjectedGradient
        || dimension != 3
        || moving < INTERIOR_POINT_FIT_FROM
    {
        return None;
    }
    let timed = estimate.probe_seconds / estimate.probe_steps.max(1) as f64;
    let interior = super::cocd_cost::step_seconds(3, moving as f64, hard.tolerance);
    (timed > interior).then(|| {
        format!(
            "  the projected gradient took {} a step here, more than the interior point's fit \
             for {moving} spheres at rest ({}): a jammed packing; contact.conic_solver = \
             \"interior_point\" is likely faster",
            super::cost_estimate::clock(timed),
            super::cost_estimate::clock(interior)
        )
    })
}

/// Below this many moving grains a step's fixed costs weigh as much as its
/// contacts (200 grains of `cases/avalanche_bed.toml` ran at 2.0 times the
/// cost of their start, not 5.2), and a few grains do not pack at all.
const PACKING_GRAINS: usize = 300;

/// Whether the moving grains of `system` (soft, or hard under `method`),
/// at least [`PACKING_GRAINS`] of
/// them, are apart (fewer than a quarter of a contact each, where a
/// packing holds 1.5 to 3) under gravity, and if so
/// how their run's cost grows ([`cost_estimate::Packing`]), with their
/// contacts per grain and the time at which the highest has fallen to the
/// lowest one's level.
fn packing_of(
    system: &grainflow_dem::DemSystem,
    dt: f64,
    method: Option<Method>,
) -> Option<(cost_estimate::Packing, f64, f64)> {
    let p = &system.particles;
    let moving: Vec<usize> = (0..p.n_owned).filter(|&k| !p.is_fixed(k)).collect();
    let g = system.domain.gravity;
    let gravity = g.norm();
    if moving.len() < PACKING_GRAINS || gravity == 0.0 {
        return None;
    }
    let contacts = system.last.particle_contacts as f64 / moving.len() as f64;
    if contacts >= 0.25 {
        return None;
    }
    let down = g / gravity;
    let depth = |k: &usize| p.position[*k].dot(&down);
    let lowest = moving.iter().map(depth).fold(f64::NEG_INFINITY, f64::max);
    let highest = moving.iter().map(depth).fold(f64::INFINITY, f64::min);
    let landed = (2.0 * (lowest - highest) / gravity).sqrt();
    // Measured for the soft DEM and for COCD in 2D; NSCD and COCD in 3D
    // keep the probe's cost.
    let cost_ratio = match (method, system.domain.dimension.count()) {
        (None, 2) => cost_estimate::PACKED_OVER_APART_2D,
        (None, _) => cost_estimate::PACKED_OVER_APART_3D,
        (Some(Method::Cocd), 2) => cost_estimate::PACKED_OVER_APART_COCD_2D,
        _ => return None,
    };
    let packing = cost_estimate::Packing {
        apart_steps: landed / dt,
        cost_ratio,
    };
    Some((packing, contacts, landed))
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow_contact::HardContact;

    fn timed(seconds_a_step: f64) -> cost_estimate::Estimate {
        cost_estimate::Estimate {
            seconds: 0.0,
            low: 0.0,
            high: 0.0,
            probe_steps: 2,
            probe_seconds: 2.0 * seconds_a_step,
        }
    }

    /// 13,300 moving spheres at ε = 1e-5: the interior point's fit is
    /// 49 s a step; a projected-gradient step timed at 119 s (the narrow
    /// channel's release at 14.3 ms) is pointed to it, one at 1 s is not,
    /// nor the interior point itself, nor a packing below the fit's range.
    #[test]
    fn check_points_a_jammed_projected_gradient_to_the_interior_point() {
        let mut hard = HardContact::new(Method::Cocd, 1e-5, 20_000, 1e-4);
        hard.conic_solver = ConicSolver::ProjectedGradient;
        let line = slower_than_the_interior_point(&hard, 3, 13_300, &timed(119.0)).unwrap();
        assert!(line.contains("took 0:01:59 a step here"), "{line}");
        assert!(line.contains("at rest (0:00:49)"), "{line}");
        assert!(slower_than_the_interior_point(&hard, 3, 13_300, &timed(1.0)).is_none());
        assert!(slower_than_the_interior_point(&hard, 3, 1_600, &timed(119.0)).is_none());
        hard.conic_solver = ConicSolver::InteriorPoint;
        assert!(slower_than_the_interior_point(&hard, 3, 13_300, &timed(119.0)).is_none());
    }
}
