//! Per-particle state as flat arrays: owned particles in `[0, n_owned)`,
//! ghost copies after them.

use grainflow_core::{Dimension, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Numbers per particle in a [`Particles::pack_state`] message.
pub const PACKED_STATE: usize = 36;
/// Numbers per particle in a [`Particles::pack_motion`] message.
pub const PACKED_MOTION: usize = 15;

#[derive(Clone, Debug, Default)]
pub struct Particles {
    /// Owned particles are `[0, n_owned)`; ghosts are `[n_owned, len())`.
    pub n_owned: usize,
    /// Global identifier, stable over the run (ghosts carry their owner's).
    pub id: Vec<u64>,
    /// The group the particle was made in: the index of its block in the
    /// case's `particles.block` (or the group a `file` block read with it),
    /// so that the particle files tell a column's grains from a bed's.
    pub group: Vec<u64>,
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
    /// Velocity at the start of the DEM's interval in the last stage of a
    /// coupled step: the change since is the impulse the fluid answers one
    /// stage late (`grainflow_ibm::coupled`). Travels with the particle.
    pub dem_start_velocity: Vec<Vec3>,
    /// The fluid momentum and angular momentum inside the particle per unit
    /// density, `∫ α_p u dV` and `∫ α_p r × u dV`, measured at the end of
    /// the last stage of a coupled step: the next stage's load takes the
    /// change since, a derivative over the volume moving with the particle
    /// (`grainflow_ibm::coupled`). Travels with the particle.
    pub inner_fluid_momentum: Vec<Vec3>,
    pub inner_fluid_angular_momentum: Vec<Vec3>,
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
    pub fn push(&mut self, dimension: Dimension, id: u64, group: u64, new: &NewParticle) {
        assert_eq!(
            self.n_owned,
            self.len(),
            "owned particles are added before ghosts"
        );
        let (mass, inertia) = mass_and_inertia(dimension, new.radius, new.density);
        self.id.push(id);
        self.group.push(group);
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
        let start = self.velocity[self.velocity.len() - 1];
        self.dem_start_velocity.push(start);
        self.inner_fluid_momentum.push(Vec3::zeros());
        self.inner_fluid_angular_momentum.push(Vec3::zeros());
        self.n_owned += 1;
    }

    /// Drops all ghosts, keeping the owned particles.
    pub fn clear_ghosts(&mut self) {
        let n = self.n_owned;
        self.id.truncate(n);
        self.group.truncate(n);
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
        self.dem_start_velocity.truncate(n);
        self.inner_fluid_momentum.truncate(n);
        self.inner_fluid_angular_momentum.truncate(n);
    }

    /// Appends a ghost copy of particle `source` displaced by `shift`.
    pub fn push_ghost(&mut self, source: usize, shift: Vec3) {
        self.id.push(self.id[source]);
        self.group.push(self.group[source]);
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
        self.dem_start_velocity
            .push(self.dem_start_velocity[source]);
        self.inner_fluid_momentum
            .push(self.inner_fluid_momentum[source]);
        self.inner_fluid_angular_momentum
            .push(self.inner_fluid_angular_momentum[source]);
    }

    /// Reorders the owned particles by `order` (new index k holds old
    /// `order[k]`); ghosts must have been cleared.
    pub fn permute_owned(&mut self, order: &[usize]) {
        assert_eq!(self.len(), self.n_owned);
        fn apply<T: Clone + Send + Sync>(values: &mut Vec<T>, order: &[usize]) {
            *values = permuted(values, order);
        }
        apply(&mut self.id, order);
        apply(&mut self.group, order);
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
        apply(&mut self.dem_start_velocity, order);
        apply(&mut self.inner_fluid_momentum, order);
        apply(&mut self.inner_fluid_angular_momentum, order);
    }

    /// Keeps the owned particles `kept` (in that order), dropping the others;
    /// ghosts must have been cleared.
    pub fn retain_owned(&mut self, kept: &[usize]) {
        self.permute_owned(kept);
        self.n_owned = kept.len();
    }

    /// Appends the whole state of particle `k`, displaced by `shift`, to a
    /// message ([`PACKED_STATE`] numbers; the id and the group travel as
    /// their bits).
    pub fn pack_state(&self, k: usize, shift: Vec3, message: &mut Vec<f64>) {
        message.push(f64::from_bits(self.id[k]));
        message.extend((self.position[k] + shift).iter());
        message.extend(self.velocity[k].iter());
        message.extend(self.angular_velocity[k].iter());
        message.extend([
            self.radius[k],
            self.mass[k],
            self.inverse_mass[k],
            self.inverse_inertia[k],
        ]);
        for v in [
            &self.force[k],
            &self.torque[k],
            &self.external_force[k],
            &self.external_torque[k],
            &self.dem_start_velocity[k],
            &self.inner_fluid_momentum[k],
            &self.inner_fluid_angular_momentum[k],
        ] {
            message.extend(v.iter());
        }
        message.push(f64::from_bits(self.group[k]));
    }

    /// Appends a particle from a [`Particles::pack_state`] message: an owned
    /// one (no ghosts may exist yet) or a ghost.
    pub fn push_packed(&mut self, packed: &[f64], owned: bool) {
        assert!(
            !owned || self.n_owned == self.len(),
            "owned particles are added before ghosts"
        );
        let vector = |at: usize| Vec3::new(packed[at], packed[at + 1], packed[at + 2]);
        self.id.push(packed[0].to_bits());
        self.position.push(vector(1));
        self.velocity.push(vector(4));
        self.angular_velocity.push(vector(7));
        self.radius.push(packed[10]);
        self.mass.push(packed[11]);
        self.inverse_mass.push(packed[12]);
        self.inverse_inertia.push(packed[13]);
        self.force.push(vector(14));
        self.torque.push(vector(17));
        self.external_force.push(vector(20));
        self.external_torque.push(vector(23));
        self.dem_start_velocity.push(vector(26));
        self.inner_fluid_momentum.push(vector(29));
        self.inner_fluid_angular_momentum.push(vector(32));
        self.group.push(packed[35].to_bits());
        if owned {
            self.n_owned += 1;
        }
    }

    /// Appends what changes between neighbour builds (position displaced by
    /// `shift`, velocities, force and torque) of particle `k` to a message
    /// ([`PACKED_MOTION`] numbers).
    pub fn pack_motion(&self, k: usize, shift: Vec3, message: &mut Vec<f64>) {
        message.extend((self.position[k] + shift).iter());
        for v in [
            &self.velocity[k],
            &self.angular_velocity[k],
            &self.force[k],
            &self.torque[k],
        ] {
            message.extend(v.iter());
        }
    }

    /// Sets particle `k` from a [`Particles::pack_motion`] message.
    pub fn unpack_motion(&mut self, k: usize, packed: &[f64]) {
        let vector = |at: usize| Vec3::new(packed[at], packed[at + 1], packed[at + 2]);
        self.position[k] = vector(0);
        self.velocity[k] = vector(3);
        self.angular_velocity[k] = vector(6);
        self.force[k] = vector(9);
        self.torque[k] = vector(12);
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

/// `values` in the order `order` (new k was old `order[k]`), gathered on
/// rayon's threads: a permutation of the 20,000 grains of a column is a
/// visible part of a neighbour build on one thread.
pub(crate) fn permuted<T: Clone + Send + Sync>(values: &[T], order: &[usize]) -> Vec<T> {
    order
        .par_iter()
        .with_min_len(1024)
        .map(|&k| values[k].clone())
        .collect()
}
