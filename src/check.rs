//! `grainflow check`: validates a case without running it and prints the
//! derived numbers and the models the scene will run.

use crate::case::Case;
use crate::simulation::{check_time_step, time_step};
use crate::{scene, stability, RunError};
use std::fmt::Write;

/// Bytes of the DEM state per particle: five vectors and five scalars, the
/// reference position, the coordination, the wall marks and the cell bins
/// (~240 B), 24 B of tangential history per wall, and per listed partner
/// 81 B: index and mirror (8 B), history (24 B), an open flag, and the
/// pair's force and partner torque handed between the two passes of the
/// force loop (48 B). A dense 3D packing lists about 13 partners.
fn bytes_per_particle(dimension: usize, walls: usize) -> usize {
    let partners = if dimension == 3 { 13 } else { 6 };
    240 + 24 * walls.max(1) + partners * 81
}

pub fn report(case: &Case) -> Result<String, RunError> {
    let system = scene::build(case).map_err(RunError::Case)?;
    let (dt, contact_time) = time_step(case, &system);
    let warning = check_time_step(dt, contact_time)?;
    let p = &system.particles;
    let n = p.n_owned;
    let glued = (0..n).filter(|&k| p.is_fixed(k)).count();
    let mut out = String::new();
    let dim = system.domain.dimension.count();
    let _ = writeln!(out, "models:");
    let _ = writeln!(
        out,
        "  {dim}D soft-sphere DEM (linear spring-dashpot, tangential history, Coulomb)"
    );
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
            "    {} normal {:?} friction {}{}",
            w.name,
            w.normal.as_slice(),
            w.friction,
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
    let _ = writeln!(out, "particles: {n} ({glued} glued)");
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
    let _ = writeln!(
        out,
        "memory estimate: {:.1} MiB",
        (n * bytes_per_particle(dim, system.walls.len())) as f64 / (1 << 20) as f64
    );
    Ok(out)
}
