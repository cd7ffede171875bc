//! Ghost copies of particles near the subdomain's edges.
//!
//! On one rank the only ghosts are periodic images: a particle within the
//! interaction range of a periodic face is copied, shifted by the period, to
//! the other side. Ghosts are rebuilt with the neighbour list and refreshed
//! from their sources every step in between.

use crate::particles::Particles;
use grainflow_core::{Domain, Vec3};

#[derive(Clone, Debug, Default)]
pub struct Ghosts {
    /// Owned index each ghost copies, in ghost order.
    pub source: Vec<usize>,
    /// Displacement of each ghost from its source (a multiple of the period).
    pub shift: Vec<Vec3>,
}

impl Ghosts {
    /// Drops old ghosts and creates the periodic images within `range` of a
    /// periodic face (corners and edges included).
    pub fn build(&mut self, particles: &mut Particles, domain: &Domain, range: f64) {
        particles.clear_ghosts();
        self.source.clear();
        self.shift.clear();
        let extent = domain.extent();
        for owned in 0..particles.n_owned {
            let x = particles.position[owned];
            // Per axis: the shifts that bring an image within range.
            let mut candidates: [[f64; 2]; 3] = [[0.0, f64::NAN]; 3];
            for axis in 0..3 {
                if !domain.periodic[axis] {
                    continue;
                }
                if x[axis] - domain.lower[axis] < range {
                    candidates[axis][1] = extent[axis];
                } else if domain.upper[axis] - x[axis] < range {
                    candidates[axis][1] = -extent[axis];
                }
            }
            for sx in candidates[0] {
                for sy in candidates[1] {
                    for sz in candidates[2] {
                        if sx.is_nan() || sy.is_nan() || sz.is_nan() {
                            continue;
                        }
                        if sx == 0.0 && sy == 0.0 && sz == 0.0 {
                            continue;
                        }
                        let shift = Vec3::new(sx, sy, sz);
                        self.source.push(owned);
                        self.shift.push(shift);
                        particles.push_ghost(owned, shift);
                    }
                }
            }
        }
    }

    /// Copies the current state of each source onto its ghost.
    pub fn refresh(&self, particles: &mut Particles) {
        let first_ghost = particles.n_owned;
        for (k, (&source, shift)) in self.source.iter().zip(&self.shift).enumerate() {
            let ghost = first_ghost + k;
            particles.position[ghost] = particles.position[source] + shift;
            particles.velocity[ghost] = particles.velocity[source];
            particles.angular_velocity[ghost] = particles.angular_velocity[source];
            particles.force[ghost] = particles.force[source];
            particles.torque[ghost] = particles.torque[source];
        }
    }
}
