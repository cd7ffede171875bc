//! The checks every hard-contact step reports.
//!
//! **Contact law.** Per contact, in the units of [`Scales`], the gap
//! variable s = (Δt (v_n − b_α)/L, μ Δt v_t/L) and the force variable
//! z = (P_n, P_t/μ)/(m̄ V κ). With b_α = −D_α/Δt, s ∈ K is the convexified
//! non-penetration of eq. 9, z ∈ K is Coulomb's cone, and z·s = 0 with both
//! in K is eq. 6–8: COCD's law in conic complementarity form. NSCD's law
//! (Signorini with Coulomb's sliding rule) is the same with De Saxcé's
//! modified gap s_n + μ Δt |v_t|/d̄. The residual of a contact is the natural
//! map |s − Π_K(s − z)|, zero exactly when its law holds, with Π_K the
//! projection on the second-order cone {(y, x): |x| ≤ y} (on y ≥ 0 for a
//! frictionless contact). The step reports the largest. An interior-point
//! solution keeps s and z inside their cones, with s_α z_α of the order of
//! its last barrier parameter: this residual is then set by how far the
//! solver went, not by its tolerance on the objective.
//!
//! **Coulomb's cone.** The largest of −P_n and |P_t| − μ P_n over the
//! contacts, over the largest normal impulse.
//!
//! **Non-penetration.** The largest overlap between grains, or between a
//! grain and a wall, after the move, over the mean diameter.

use crate::contacts::{ContactSet, Scales};
use grainflow_core::Vec3;
use grainflow_dem::DemSystem;

/// How well a step's velocities and impulses satisfy the contact law.
#[derive(Clone, Copy, Debug, Default)]
pub struct LawResidual {
    /// Largest natural-map residual of the complementarity conditions.
    pub complementarity: f64,
    /// Largest violation of Coulomb's cone, relative.
    pub coulomb: f64,
}

/// The residuals of the contact law over the contacts. `de_saxce`: NSCD's
/// law (Signorini + Coulomb's sliding rule) instead of COCD's convexified
/// one.
#[allow(clippy::too_many_arguments)]
pub fn contact_law_residual(
    contacts: &ContactSet,
    scales: &Scales,
    bounds: &[f64],
    velocity: &[Vec3],
    spin: &[Vec3],
    normal_impulse: &[f64],
    tangential_impulse: &[Vec3],
    de_saxce: bool,
) -> LawResidual {
    let to_gap = scales.time / scales.length;
    let unit = scales.impulse();
    let mut largest: f64 = 0.0;
    let mut cone_violation: f64 = 0.0;
    for a in 0..contacts.len() {
        cone_violation = cone_violation
            .max(-normal_impulse[a])
            .max(tangential_impulse[a].norm() - contacts.friction[a] * normal_impulse[a]);
        let n = contacts.normal[a];
        let mu = contacts.friction[a];
        let relative = contacts.relative_velocity(a, velocity, spin);
        let v_n = relative.dot(&n);
        let v_t = relative - v_n * n;
        let mut s_n = to_gap * (v_n - bounds[a]);
        let z_n = normal_impulse[a] / unit;
        let residual = if mu == 0.0 {
            s_n.min(z_n).abs()
        } else {
            if de_saxce {
                s_n += mu * to_gap * v_t.norm();
            }
            let s_t = mu * to_gap * v_t;
            let z_t = tangential_impulse[a] / (mu * unit);
            let (y, x) = (s_n - z_n, s_t - z_t);
            let x_norm = x.norm();
            let (py, px) = if x_norm <= y {
                (y, x)
            } else if x_norm <= -y {
                (0.0, Vec3::zeros())
            } else {
                let half = 0.5 * (y + x_norm);
                (half, (half / x_norm) * x)
            };
            ((s_n - py).powi(2) + (s_t - px).norm_squared()).sqrt()
        };
        largest = largest.max(residual);
    }
    let reference = normal_impulse.iter().cloned().fold(0.0, f64::max);
    LawResidual {
        complementarity: largest,
        coulomb: if reference > 0.0 {
            cone_violation / reference
        } else {
            cone_violation / unit
        },
    }
}

/// Largest overlap of the current configuration, grain–grain or
/// grain–wall, between grains of which one at least moves, divided by
/// `length` (0 when nothing overlaps).
pub fn largest_overlap(system: &DemSystem, length: f64) -> f64 {
    let p = &system.particles;
    let list = &system.neighbours;
    let mut largest: f64 = 0.0;
    for i in 0..p.n_owned {
        for e in list.range(i) {
            let j = list.partner[e] as usize;
            if j < i {
                continue; // the pair was measured from j's side
            }
            if p.is_fixed(i) && p.is_fixed(j) {
                continue; // glued grains never meet in a program
            }
            let gap = (p.position[i] - p.position[j]).norm() - p.radius[i] - p.radius[j];
            largest = largest.max(-gap);
        }
        if p.is_fixed(i) {
            continue;
        }
        for wall in system.walls.iter().filter(|w| w.is_present(system.time)) {
            largest = largest.max(p.radius[i] - wall.distance(&p.position[i]));
        }
    }
    largest / length
}
