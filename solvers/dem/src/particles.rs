//! Per-particle state as flat arrays: owned particles in `[0, n_owned)`,
//! ghost copies after them.

use grainflow_core::{Dimension, Vec3};
use std::f64::consts::PI;

#[derive(Clone, Debug, Default)]
pub struct Particles {
    /// Owned particles are `[0, n_owned)`; ghosts are `[n_owned, len())`.
    pub n_owned: usize,
    /// Global identifier, stable over the run (ghosts carry their owner's).
    pub id: Vec<u64>,
    pub position: Vec<Vec3>,
    pub velocity: Vec<Vec3>,
    pub angular_velocity: Vec<Vec3>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    /// 1/m, zero for a glued particle (infinite mass in every contact).
    pub inverse_mass: Vec<f64>,
    /// 1/I, zero for a glued particle.
    pub inverse_inertia: Vec<f64>,
    /// Total force and torque of the last evaluation (ghosts: their source's).
    pub force: Vec<Vec3>,
    pub torque: Vec<Vec3>,
    /// Force and torque from outside the DEM, held fixed over its steps:
    /// the hydrodynamic loads of the immersed boundaries in a fluid (zero
    /// in a dry scene).
    pub external_force: Vec<Vec3>,
    pub external_torque: Vec<Vec3>,
}

/// Mass and moment of inertia of a sphere (3D) or of a disc per unit
/// thickness (2D).
pub fn mass_and_inertia(dimension: Dimension, radius: f64, density: f64) -> (f64, f64) {
    match dimension {
        Dimension::Three => {
            let mass = density * 4.0 / 3.0 * PI * radius.powi(3);
            (mass, 0.4 * mass * radius * radius)
        }
        Dimension::Two => {
            let mass = density * PI * radius * radius;
            (mass, 0.5 * mass * radius * radius)
        }
    }
}

/// A particle to be added: its initial state and material.
#[derive(Clone, Debug)]
pub struct NewParticle {
    pub position: Vec3,
    pub velocity: Vec3,
    pub angular_velocity: Vec3,
    pub radius: f64,
    pub density: f64,
    pub fixed: bool,
}

impl Particles {
    pub fn len(&self) -> usize {
        self.id.len()
    }

    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }

    pub fn is_fixed(&self, index: usize) -> bool {
        self.inverse_mass[index] == 0.0
    }

    /// Appends an owned particle (no ghosts may exist yet).
    pub fn push(&mut self, dimension: Dimension, id: u64, new: &NewParticle) {
        assert_eq!(
            self.n_owned,
            self.len(),
            "owned particles are added before ghosts"
        );
        let (mass, inertia) = mass_and_inertia(dimension, new.radius, new.density);
        self.id.push(id);
        self.position.push(new.position);
        self.velocity.push(if new.fixed {
            Vec3::zeros()
        } else {
            new.velocity
        });
        self.angular_velocity.push(if new.fixed {
            Vec3::zeros()
        } else {
            new.angular_velocity
        });
        self.radius.push(new.radius);
        self.mass.push(mass);
        self.inverse_mass
            .push(if new.fixed { 0.0 } else { 1.0 / mass });
        self.inverse_inertia
            .push(if new.fixed { 0.0 } else { 1.0 / inertia });
        self.force.push(Vec3::zeros());
        self.torque.push(Vec3::zeros());
        self.external_force.push(Vec3::zeros());
        self.external_torque.push(Vec3::zeros());
        self.n_owned += 1;
    }

    /// Drops all ghosts, keeping the owned particles.
    pub fn clear_ghosts(&mut self) {
        let n = self.n_owned;
        self.id.truncate(n);
        self.position.truncate(n);
        self.velocity.truncate(n);
        self.angular_velocity.truncate(n);
        self.radius.truncate(n);
        self.mass.truncate(n);
        self.inverse_mass.truncate(n);
        self.inverse_inertia.truncate(n);
        self.force.truncate(n);
        self.torque.truncate(n);
        self.external_force.truncate(n);
        self.external_torque.truncate(n);
    }

    /// Appends a ghost copy of particle `source` displaced by `shift`.
    pub fn push_ghost(&mut self, source: usize, shift: Vec3) {
        self.id.push(self.id[source]);
        self.position.push(self.position[source] + shift);
        self.velocity.push(self.velocity[source]);
        self.angular_velocity.push(self.angular_velocity[source]);
        self.radius.push(self.radius[source]);
        self.mass.push(self.mass[source]);
        self.inverse_mass.push(self.inverse_mass[source]);
        self.inverse_inertia.push(self.inverse_inertia[source]);
        self.force.push(self.force[source]);
        self.torque.push(self.torque[source]);
        self.external_force.push(self.external_force[source]);
        self.external_torque.push(self.external_torque[source]);
    }

    /// Reorders the owned particles by `order` (new index k holds old
    /// `order[k]`); ghosts must have been cleared.
    pub fn permute_owned(&mut self, order: &[usize]) {
        assert_eq!(self.len(), self.n_owned);
        fn apply<T: Clone>(values: &mut Vec<T>, order: &[usize]) {
            let reordered: Vec<T> = order.iter().map(|&k| values[k].clone()).collect();
            *values = reordered;
        }
        apply(&mut self.id, order);
        apply(&mut self.position, order);
        apply(&mut self.velocity, order);
        apply(&mut self.angular_velocity, order);
        apply(&mut self.radius, order);
        apply(&mut self.mass, order);
        apply(&mut self.inverse_mass, order);
        apply(&mut self.inverse_inertia, order);
        apply(&mut self.force, order);
        apply(&mut self.torque, order);
        apply(&mut self.external_force, order);
        apply(&mut self.external_torque, order);
    }

    /// Largest radius among owned particles (0 when empty).
    pub fn max_radius(&self) -> f64 {
        self.radius[..self.n_owned]
            .iter()
            .cloned()
            .fold(0.0, f64::max)
    }

    /// Translational and rotational kinetic energy of the owned particles.
    pub fn kinetic_energy(&self) -> (f64, f64) {
        let mut translational = 0.0;
        let mut rotational = 0.0;
        for k in 0..self.n_owned {
            if self.inverse_mass[k] == 0.0 {
                continue;
            }
            translational += 0.5 * self.mass[k] * self.velocity[k].norm_squared();
            rotational += 0.5 * self.angular_velocity[k].norm_squared() / self.inverse_inertia[k];
        }
        (translational, rotational)
    }
}
