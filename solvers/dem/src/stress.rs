//! Coarse-grained granular stress from contact forces (Love–Weber).
//!
//! For a volume V holding mobile particles p, the contact stress is
//! σ = (1/V) Σ_p Σ_c f_c ⊗ (x_c − x_p), summed over the contacts c of each
//! particle, with f_c the force on p and x_c the contact point. For a pair of
//! mobile particles this is f ⊗ (x_i − x_j); contacts with walls and glued
//! particles contribute only the mobile side.

use crate::system::DemSystem;
use nalgebra::Matrix3;

/// Contact moment tensor Σ_c f_c ⊗ (x_c − x_p) of every owned particle
/// (zero for glued particles), from the last force evaluation.
pub fn particle_moments(system: &DemSystem) -> Vec<Matrix3<f64>> {
    let p = &system.particles;
    let n = p.n_owned;
    let mut moments = vec![Matrix3::zeros(); n];
    for (k, (&i, &j)) in system
        .neighbours
        .first
        .iter()
        .zip(&system.neighbours.second)
        .enumerate()
    {
        let (i, j) = (i as usize, j as usize);
        let force = system.pair_force[k];
        if force.norm_squared() == 0.0 {
            continue;
        }
        let normal = (p.position[i] - p.position[j]).normalize();
        // Force on i acts at −r_i n from i; on j, −force acts at +r_j n.
        if p.inverse_mass[i] > 0.0 {
            moments[i] += force * (-p.radius[i] * normal).transpose();
        }
        if j < n && p.inverse_mass[j] > 0.0 {
            moments[j] += (-force) * (p.radius[j] * normal).transpose();
        }
    }
    for (k, moment) in moments.iter_mut().enumerate() {
        if p.inverse_mass[k] == 0.0 {
            continue;
        }
        for wall in system.walls.iter().filter(|w| w.is_present(system.time)) {
            let gap = wall.distance(&p.position[k]) - p.radius[k];
            if gap >= 0.0 {
                continue;
            }
            // The wall force is recovered from the stored history through the
            // same law, without advancing it.
            let w = system
                .walls
                .iter()
                .position(|x| std::ptr::eq(x, wall))
                .unwrap();
            let history = system.wall_history[k * system.wall_stride() + w];
            let relative_velocity =
                p.velocity[k] - (p.radius[k] * p.angular_velocity[k]).cross(&wall.normal);
            let contact = system.law.force(
                -gap,
                wall.normal,
                relative_velocity,
                p.mass[k],
                wall.friction,
                history,
                0.0,
            );
            *moment += contact.force * (-p.radius[k] * wall.normal).transpose();
        }
    }
    moments
}
