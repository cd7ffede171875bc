//! Hard contact on several ranks: what a step shares among them.
//!
//! Each rank holds the pairs of its own grains, a pair across ranks on the
//! rank of its lower id ([`crate::contacts::listed`]); a grain then takes
//! impulses from the pairs of its own rank and from those of the ranks that
//! hold its copies. Gauss–Seidel (NSCD) sweeps each rank's pairs with the
//! latest motion it has; after each sweep what every rank's pairs did to
//! the copies of a grain is added to the grain ([`Sharing::settle_copies`])
//! and its motion goes back to every copy. Within a rank this is
//! Gauss–Seidel, across ranks Jacobi. Left at that, n ranks that each stop
//! the same grain would stop it n times over and the sweeps swing ever
//! wider; so the grain's mass is split among the n local sets of pairs that
//! act on it (its [`Sharing::multiplicity`]), as in the domain-decomposition
//! forms of NSCD: each set sweeps a copy of mass m/n, and after the sweep
//! the grain moves with the mean of its copies, which is its own mass's
//! response to all the impulses, Σ P/m. A fixed point of the sweeps is
//! therefore the solution of one rank, reached to the tolerance in more
//! sweeps where grains carry load across a boundary.

use crate::contacts::{Bodies, ContactSet, Partner};
use grainflow_core::Vec3;
use grainflow_dem::DemSystem;

/// The ranks of a system whose grains are shared among several.
pub struct Sharing<'a> {
    system: &'a DemSystem,
}

impl<'a> Sharing<'a> {
    /// The sharing of `system`, or None on one rank.
    pub fn of(system: &'a DemSystem) -> Option<Self> {
        (system.communicator.size() > 1).then_some(Sharing { system })
    }

    pub fn max(&self, local: f64) -> f64 {
        self.system.communicator.max(local)
    }

    pub fn any(&self, local: bool) -> bool {
        self.system.communicator.any(local)
    }

    pub fn sum_each(&self, values: &mut [f64]) {
        self.system.communicator.sum_each(values);
    }

    /// Copies the owned entries of `velocity` and `spin` (one per local
    /// grain, owned then ghosts) onto the ghosts' entries.
    pub fn motion_onto_ghosts(&self, velocity: &mut [Vec3], spin: &mut [Vec3]) {
        let mut values = vec![0.0; 6 * velocity.len()];
        for (k, (&v, &w)) in velocity.iter().zip(spin.iter()).enumerate() {
            put_motion(&mut values, k, v, w);
        }
        self.system.copy_onto_ghosts(&mut values, 6);
        for (k, (v, w)) in velocity.iter_mut().zip(spin.iter_mut()).enumerate() {
            (*v, *w) = motion_at(&values, k);
        }
    }

    /// Owned grains whose copies the pairs of another rank touch (each
    /// must be a body here, to take what those pairs do to it).
    pub fn touched_elsewhere(&self, contacts: &ContactSet) -> Vec<bool> {
        let here = touched_here(contacts, self.system.particles.len());
        let acting = self.acting_sets(contacts);
        (0..self.system.particles.n_owned)
            .map(|k| acting[k] > here[k])
            .collect()
    }

    /// The number of local sets of pairs (this rank's, other ranks', one
    /// per copy) that act on each body, n ≥ 1 (collective).
    pub fn multiplicity(&self, contacts: &ContactSet, bodies: &Bodies) -> Vec<f64> {
        let acting = self.acting_sets(contacts);
        (0..bodies.len())
            .map(|c| acting[bodies.grain[c] as usize].max(1.0))
            .collect()
    }

    /// For each local grain, how many local sets of pairs touch it, over
    /// every rank, its copies included (collective).
    fn acting_sets(&self, contacts: &ContactSet) -> Vec<f64> {
        let mut acting = touched_here(contacts, self.system.particles.len());
        self.system.sum_onto_owners(&mut acting, 1);
        self.system.copy_onto_ghosts(&mut acting, 1);
        acting
    }

    /// The bodies as a rank sweeps them: each a copy of mass m/n
    /// ([`Sharing::multiplicity`]).
    pub fn split_masses(bodies: &Bodies, multiplicity: &[f64]) -> Bodies {
        let mut split = bodies.clone();
        for (c, &n) in multiplicity.iter().enumerate() {
            split.inverse_mass[c] *= n;
            split.inverse_inertia[c] *= n;
        }
        split
    }

    /// After a sweep: each owned body moves with the mean of its n copies,
    /// its motion at the sweep's start (`before`) plus the mean of the
    /// changes each set of pairs made, here and on other ranks; then every
    /// copy takes its grain's motion (collective).
    pub fn settle_copies(
        &self,
        bodies: &Bodies,
        velocity: &mut [Vec3],
        spin: &mut [Vec3],
        before: &[(Vec3, Vec3)],
        multiplicity: &[f64],
    ) {
        let n = self.system.particles.len();
        let mut values = vec![0.0; 6 * n];
        for c in bodies.owned..bodies.len() {
            let k = bodies.grain[c] as usize;
            let (v, w) = before[c];
            put_motion(&mut values, k, velocity[c] - v, spin[c] - w);
        }
        self.system.sum_onto_owners(&mut values, 6);
        for c in 0..bodies.owned {
            let (elsewhere, elsewhere_spin) = motion_at(&values, bodies.grain[c] as usize);
            let n = multiplicity[c];
            if n == 1.0 {
                // One set of pairs acts on it, here or on another rank.
                velocity[c] += elsewhere;
                spin[c] += elsewhere_spin;
            } else {
                let (v, w) = before[c];
                velocity[c] = v + ((velocity[c] - v) + elsewhere) / n;
                spin[c] = w + ((spin[c] - w) + elsewhere_spin) / n;
            }
        }
        values.fill(0.0);
        for c in 0..bodies.owned {
            put_motion(&mut values, bodies.grain[c] as usize, velocity[c], spin[c]);
        }
        self.system.copy_onto_ghosts(&mut values, 6);
        for c in bodies.owned..bodies.len() {
            (velocity[c], spin[c]) = motion_at(&values, bodies.grain[c] as usize);
        }
    }

    /// Every body's motion at the start of a sweep.
    pub fn motion_before(velocity: &[Vec3], spin: &[Vec3]) -> Vec<(Vec3, Vec3)> {
        velocity.iter().zip(spin).map(|(&v, &w)| (v, w)).collect()
    }
}

/// Writes the velocity and spin of local grain `k` into its six numbers of
/// `values` (the layout the ghost exchanges carry).
fn put_motion(values: &mut [f64], k: usize, velocity: Vec3, spin: Vec3) {
    values[6 * k..6 * k + 3].copy_from_slice(velocity.as_slice());
    values[6 * k + 3..6 * k + 6].copy_from_slice(spin.as_slice());
}

/// The velocity and spin of local grain `k` in `values`.
fn motion_at(values: &[f64], k: usize) -> (Vec3, Vec3) {
    (
        Vec3::from_column_slice(&values[6 * k..6 * k + 3]),
        Vec3::from_column_slice(&values[6 * k + 3..6 * k + 6]),
    )
}

/// 1 for each of `local` grains a pair of `contacts` touches, else 0.
fn touched_here(contacts: &ContactSet, local: usize) -> Vec<f64> {
    let mut touched = vec![0.0; local];
    for a in 0..contacts.len() {
        touched[contacts.grain[a] as usize] = 1.0;
        if let Partner::Grain(j) = contacts.partner[a] {
            touched[j as usize] = 1.0;
        }
    }
    touched
}
