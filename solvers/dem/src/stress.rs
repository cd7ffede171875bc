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
    (0..p.n_owned)
        .map(|i| {
            let mut moment = Matrix3::zeros();
            if p.is_fixed(i) {
                return moment;
            }
            // Every contact acts at −r_i n from the centre.
            for c in system.particle_contacts_of(i) {
                moment += c.force * (-p.radius[i] * c.normal).transpose();
            }
            for (_, c) in system.wall_contacts_of(i) {
                moment += c.force * (-p.radius[i] * c.normal).transpose();
            }
            moment
        })
        .collect()
}
