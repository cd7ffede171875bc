//! NSCD: the Moreau–Jean step solved by Gauss–Seidel over the contacts
//! (Martin et al. 2022, section 3.5; Jean 1999).
//!
//! The step is eq. 5 with, per contact, Signorini's condition on the
//! predicted gap and Coulomb's law with its sliding rule (not convexified):
//!   v_n ≥ b_α ⊥ P_n ≥ 0,
//!   |P_t| ≤ μ P_n, and P_t = −μ P_n v_t/|v_t| where v_t ≠ 0,
//! with b_α = −D_α/Δt (the gap closes at most to zero within the step).
//! With a restitution e, a contact that closes within the step on its
//! start velocity (D_α + Δt v_n⁻ ≤ 0) rebounds: b_α = −D_α/Δt − e v_n⁻
//! (Newton's law).
//!
//! Gauss–Seidel visits each contact with the others' impulses held fixed.
//! For spheres and discs the local Delassus operator is w_n n nᵀ +
//! w_t (I − n nᵀ) ([`ContactSet::inverse_effective_masses`]), so the local
//! problem is solved exactly: P_n = max(0, (b − v_n^free)/w_n), then the
//! sticking P_t = −v_t^free/w_t projected onto the disc |P_t| ≤ μ P_n. Sweeps
//! repeat until the complementarity residual of the contact law
//! ([`crate::certificate`]) is below the tolerance over √2. On several
//! ranks each sweeps its own pairs and the copies of the grains are brought
//! in step after each sweep ([`crate::sharing`]).

use crate::certificate;
use crate::cocd::Solution;
use crate::contacts::{Bodies, ContactSet, Scales};
use crate::sharing::Sharing;
use grainflow_core::Vec3;

/// The normal bound b_α of each contact (see the module documentation).
pub fn normal_bounds(
    contacts: &ContactSet,
    bodies: &Bodies,
    dt: f64,
    restitution: f64,
) -> Vec<f64> {
    (0..contacts.len())
        .map(|a| {
            let start = contacts.relative_velocity(a, &bodies.start_velocity, &bodies.start_spin);
            normal_bound(
                contacts.gap[a],
                start.dot(&contacts.normal[a]),
                dt,
                restitution,
            )
        })
        .collect()
}

/// b_α of a contact of gap `gap` approaching at `approach` = v_n⁻ at the
/// start of the step.
pub fn normal_bound(gap: f64, approach: f64, dt: f64, restitution: f64) -> f64 {
    let gap_bound = -gap / dt;
    if gap + dt * approach <= 0.0 {
        gap_bound.max(-restitution * approach)
    } else {
        gap_bound
    }
}

/// Solves the step by Gauss–Seidel from the impulses `initial` (a warm
/// start; zeros for none). Returns the solution and whether the residual
/// went below `tolerance` within `max_sweeps` (on every rank of
/// `sharing`).
#[allow(clippy::too_many_arguments)]
pub fn solve(
    contacts: &ContactSet,
    bodies: &Bodies,
    scales: &Scales,
    bounds: &[f64],
    initial: &[(f64, Vec3)],
    tolerance: f64,
    max_sweeps: u32,
    sharing: Option<&Sharing>,
) -> (Solution, bool) {
    let mut velocity = bodies.free_velocity.clone();
    let mut spin = bodies.free_spin.clone();
    // On several ranks each set of pairs sweeps its share of a grain's mass
    // where several sets act on it ([`crate::sharing`]).
    let multiplicity = sharing.map(|sharing| sharing.multiplicity(contacts, bodies));
    let split;
    let bodies = match &multiplicity {
        Some(n) => {
            split = Sharing::split_masses(bodies, n);
            &split
        }
        None => bodies,
    };
    let mut before = sharing.map(|_| Sharing::motion_before(&velocity, &spin));
    let mut normal_impulse = vec![0.0; contacts.len()];
    let mut tangential_impulse = vec![Vec3::zeros(); contacts.len()];
    for (a, &(p_n, p_t)) in initial.iter().enumerate() {
        normal_impulse[a] = p_n;
        tangential_impulse[a] = p_t;
        contacts.apply_impulse(
            a,
            p_n * contacts.normal[a] + p_t,
            bodies,
            &mut velocity,
            &mut spin,
        );
    }
    if let (Some(sharing), Some(before), Some(n)) = (sharing, &before, &multiplicity) {
        sharing.settle_copies(bodies, &mut velocity, &mut spin, before, n);
    }
    let effective: Vec<(f64, f64)> = (0..contacts.len())
        .map(|a| contacts.inverse_effective_masses(a, bodies))
        .collect();

    let mut sweeps = 0;
    let mut converged = match sharing {
        Some(sharing) => !sharing.any(!contacts.is_empty()),
        None => contacts.is_empty(),
    };
    while !converged && sweeps < max_sweeps {
        if let Some(before) = before.as_mut() {
            *before = Sharing::motion_before(&velocity, &spin);
        }
        for a in 0..contacts.len() {
            let n = contacts.normal[a];
            let (w_n, w_t) = effective[a];
            let relative = contacts.relative_velocity(a, &velocity, &spin);
            let v_n = relative.dot(&n);
            let v_t = relative - v_n * n;
            let old_n = normal_impulse[a];
            let old_t = tangential_impulse[a];
            let p_n = (old_n + (bounds[a] - v_n) / w_n).max(0.0);
            let sticking = old_t - v_t / w_t;
            let limit = contacts.friction[a] * p_n;
            let norm = sticking.norm();
            let p_t = if norm <= limit {
                sticking
            } else {
                (limit / norm) * sticking
            };
            normal_impulse[a] = p_n;
            tangential_impulse[a] = p_t;
            let change = (p_n - old_n) * n + (p_t - old_t);
            contacts.apply_impulse(a, change, bodies, &mut velocity, &mut spin);
        }
        sweeps += 1;
        if let (Some(sharing), Some(before), Some(n)) = (sharing, &before, &multiplicity) {
            sharing.settle_copies(bodies, &mut velocity, &mut spin, before, n);
        }
        let residual = certificate::contact_law_residual(
            contacts,
            scales,
            bounds,
            &velocity,
            &spin,
            &normal_impulse,
            &tangential_impulse,
            true,
        );
        // A residual r bounds a contact's overlap after the move by √2 r
        // (at a slowly sliding contact the cone projection absorbs part of
        // it): stopping at ε/√2 keeps the overlap below ε mean diameters.
        let largest = sharing.map_or(residual.complementarity, |sharing| {
            sharing.max(residual.complementarity)
        });
        converged = largest <= tolerance * std::f64::consts::FRAC_1_SQRT_2;
    }
    (
        Solution {
            velocity,
            spin,
            normal_impulse,
            tangential_impulse,
            iterations: sweeps,
            reduced_accuracy: !converged,
            fallback_reason: None,
        },
        converged,
    )
}
