//! The loads of the immersed boundaries on the particles, per local
//! particle, and their sum onto the owned ones.

use grainflow_core::Vec3;
use grainflow_dem::DemSystem;

/// Force and torque per local particle (owned, then ghosts), per unit
/// fluid density.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Loads {
    pub force: Vec<Vec3>,
    pub torque: Vec<Vec3>,
}

impl Loads {
    pub(crate) fn zeros(count: usize) -> Self {
        Loads {
            force: vec![Vec3::zeros(); count],
            torque: vec![Vec3::zeros(); count],
        }
    }

    /// Adds `other`, particle by particle.
    pub(crate) fn add(&mut self, other: &Loads) {
        for (sum, value) in self.force.iter_mut().zip(&other.force) {
            *sum += value;
        }
        for (sum, value) in self.torque.iter_mut().zip(&other.torque) {
            *sum += value;
        }
    }

    /// The loads on `dem`'s owned particles from loads on every local one:
    /// each ghost's share goes to its owner (on this rank for a periodic
    /// image, on another for another rank's grain; collective).
    pub fn summed_on_owners(&self, dem: &DemSystem) -> Loads {
        let pairs: Vec<Vec3> = self
            .force
            .iter()
            .zip(&self.torque)
            .flat_map(|(&f, &t)| [f, t])
            .collect();
        let summed = vectors_on_owners(dem, &pairs, 2);
        let (force, torque) = summed.chunks_exact(2).map(|v| (v[0], v[1])).unzip();
        Loads { force, torque }
    }
}

/// `width` vectors per local particle (owned, then ghosts), summed onto the
/// owned particles: each ghost's share goes to its owner (collective).
pub fn vectors_on_owners(dem: &DemSystem, local: &[Vec3], width: usize) -> Vec<Vec3> {
    let mut values: Vec<f64> = local.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    dem.sum_onto_owners(&mut values, 3 * width);
    values[..3 * width * dem.particles.n_owned]
        .chunks_exact(3)
        .map(|v| Vec3::new(v[0], v[1], v[2]))
        .collect()
}
