//! The DEM time step: velocity Verlet over particles, walls and contacts.
//!
//! One step of size Δt:
//! 1. half kick v += Δt/2 F/m, ω += Δt/2 T/I, then drift x += Δt v;
//! 2. rebuild the neighbour list (migrate, sort, ghosts) if a particle moved
//!    more than half the skin, else refresh the ghosts;
//! 3. contact forces: each pair in parallel (eq. 13–16), then each particle
//!    gathers its pairs in a fixed order, its wall contacts and gravity;
//! 4. half kick with the new forces.

use crate::contact_law::ContactLaw;
use crate::ghosts::Ghosts;
use crate::neighbours::{CellBins, CellGrid, NeighbourList};
use crate::particles::{NewParticle, Particles};
use crate::walls::PlaneWall;
use grainflow_core::{Communicator, Dimension, Domain, Subdomain, Vec3};
use rayon::prelude::*;

/// Smallest amount of work handed to one thread: below it the loops run on
/// the calling thread, so small scenes pay no synchronisation.
const PARTICLES_PER_TASK: usize = 256;
const PAIRS_PER_TASK: usize = 1024;

/// Per-step measures used to detect a run going wrong.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepDiagnostics {
    /// Largest overlap divided by the smaller radius of its pair (or the
    /// particle radius for a wall).
    pub max_overlap_ratio: f64,
    /// Particle–particle contacts (overlap > 0).
    pub particle_contacts: usize,
    /// Particle–wall contacts.
    pub wall_contacts: usize,
    /// Whether a position or velocity is not finite.
    pub non_finite: bool,
}

#[derive(Clone)]
pub struct DemSystem {
    pub domain: Domain,
    pub subdomain: Subdomain,
    pub communicator: Communicator,
    pub particles: Particles,
    pub law: ContactLaw,
    pub walls: Vec<PlaneWall>,
    /// Tangential displacement of each owned particle against each wall:
    /// `wall_history[p * wall_stride() + w]`.
    pub wall_history: Vec<Vec3>,
    pub neighbours: NeighbourList,
    ghosts: Ghosts,
    /// Force on `first`, and the torques on `first` and on `second`, of each
    /// pair from the last force evaluation.
    pub pair_force: Vec<Vec3>,
    pub pair_torque_first: Vec<Vec3>,
    pub pair_torque_second: Vec<Vec3>,
    pub time: f64,
    pub steps: u64,
    pub last: StepDiagnostics,
    next_id: u64,
}

impl DemSystem {
    pub fn new(domain: Domain, law: ContactLaw, walls: Vec<PlaneWall>, skin: f64) -> Self {
        DemSystem {
            subdomain: Subdomain::whole(&domain),
            communicator: Communicator::serial(),
            domain,
            particles: Particles::default(),
            law,
            walls,
            wall_history: Vec::new(),
            neighbours: NeighbourList::new(skin),
            ghosts: Ghosts::default(),
            pair_force: Vec::new(),
            pair_torque_first: Vec::new(),
            pair_torque_second: Vec::new(),
            time: 0.0,
            steps: 0,
            last: StepDiagnostics::default(),
            next_id: 0,
        }
    }

    pub fn dimension(&self) -> Dimension {
        self.domain.dimension
    }

    /// Adds owned particles (before the first step or between steps).
    pub fn add_particles(&mut self, new: &[NewParticle]) {
        self.particles.clear_ghosts();
        for particle in new {
            let mut p = particle.clone();
            if self.dimension() == Dimension::Two {
                p.position.z = 0.0;
                p.velocity.z = 0.0;
                p.angular_velocity.x = 0.0;
                p.angular_velocity.y = 0.0;
            }
            self.particles.push(self.domain.dimension, self.next_id, &p);
            self.next_id += 1;
        }
        self.wall_history
            .resize(self.particles.n_owned * self.wall_stride(), Vec3::zeros());
        self.rebuild();
        self.compute_forces(0.0);
    }

    /// Entries per particle in `wall_history` (at least one, so that the
    /// per-particle chunks exist without walls).
    pub fn wall_stride(&self) -> usize {
        self.walls.len().max(1)
    }

    /// Interaction range of a ghost: the largest pair distance in the list.
    fn interaction_range(&self) -> f64 {
        2.0 * self.particles.max_radius() + self.neighbours.skin
    }

    fn cell_grid(&self) -> CellGrid {
        let range = self.interaction_range();
        let pad = Vec3::repeat(range);
        let n = self.particles.len().max(1);
        CellGrid::new(
            self.dimension(),
            self.subdomain.lower - pad,
            self.subdomain.upper + pad,
            range,
            (8 * n).max(4096),
        )
    }

    /// Migration, locality sort, ghosts and pair list.
    pub fn rebuild(&mut self) {
        let open = self.neighbours.open_contacts(&self.particles);
        self.particles.clear_ghosts();
        for x in &mut self.particles.position {
            self.domain.wrap(x);
        }
        let grid = self.cell_grid();

        // Sort owned particles by cell so that neighbours sit close in memory.
        let mut bins = CellBins::default();
        bins.fill(&grid, &self.particles.position);
        let order: Vec<usize> = bins.members.iter().map(|&k| k as usize).collect();
        if order.iter().enumerate().any(|(k, &o)| k != o) {
            self.particles.permute_owned(&order);
            let stride = self.wall_stride();
            let old = std::mem::take(&mut self.wall_history);
            self.wall_history = order
                .iter()
                .flat_map(|&o| old[o * stride..(o + 1) * stride].iter().copied())
                .collect();
        }

        let range = self.interaction_range();
        self.ghosts.build(&mut self.particles, &self.domain, range);
        self.neighbours.build(&self.particles, &grid, &open);
    }

    /// Advances the particles by one step of size `dt`.
    pub fn step(&mut self, dt: f64) -> StepDiagnostics {
        let moved_beyond_skin = self.kick_and_drift(dt);
        self.time += dt;
        if moved_beyond_skin {
            self.rebuild();
        } else {
            self.ghosts.refresh(&mut self.particles);
        }
        let mut diagnostics = self.compute_forces(dt);
        diagnostics.non_finite = self.kick(0.5 * dt);
        self.steps += 1;
        self.last = diagnostics;
        diagnostics
    }

    /// Half kick and drift; returns whether a particle moved more than half
    /// the skin since the last neighbour build.
    fn kick_and_drift(&mut self, dt: f64) -> bool {
        let n = self.particles.n_owned;
        let half_dt = 0.5 * dt;
        let limit_sq = (0.5 * self.neighbours.skin).powi(2);
        let reference = &self.neighbours.reference_position;
        if reference.len() != n {
            return true;
        }
        let p = &mut self.particles;
        p.position[..n]
            .par_iter_mut()
            .zip(p.velocity[..n].par_iter_mut())
            .zip(p.angular_velocity[..n].par_iter_mut())
            .zip(p.force[..n].par_iter())
            .zip(p.torque[..n].par_iter())
            .zip(p.inverse_mass[..n].par_iter())
            .zip(p.inverse_inertia[..n].par_iter())
            .zip(reference.par_iter())
            .with_min_len(PARTICLES_PER_TASK)
            .map(|(((((((x, v), w), f), t), &inv_m), &inv_i), x0)| {
                *v += half_dt * inv_m * f;
                *w += half_dt * inv_i * t;
                *x += dt * *v;
                (*x - x0).norm_squared() > limit_sq
            })
            .reduce(|| false, |a, b| a || b)
    }

    /// Half kick; returns whether a position or velocity is not finite.
    fn kick(&mut self, half_dt: f64) -> bool {
        let n = self.particles.n_owned;
        let p = &mut self.particles;
        p.velocity[..n]
            .par_iter_mut()
            .zip(p.angular_velocity[..n].par_iter_mut())
            .zip(p.force[..n].par_iter())
            .zip(p.torque[..n].par_iter())
            .zip(p.inverse_mass[..n].par_iter())
            .zip(p.inverse_inertia[..n].par_iter())
            .zip(p.position[..n].par_iter())
            .with_min_len(PARTICLES_PER_TASK)
            .map(|((((((v, w), f), t), &inv_m), &inv_i), x)| {
                *v += half_dt * inv_m * f;
                *w += half_dt * inv_i * t;
                !(x.iter().chain(v.iter()).all(|c| c.is_finite()))
            })
            .reduce(|| false, |a, b| a || b)
    }

    /// Contact forces and gravity on every owned particle; `dt` advances the
    /// tangential histories (0 evaluates without advancing them).
    pub fn compute_forces(&mut self, dt: f64) -> StepDiagnostics {
        let p = &self.particles;
        let law = self.law;
        let friction = law.friction;
        let pairs = self.neighbours.len();
        self.pair_force.resize(pairs, Vec3::zeros());
        self.pair_torque_first.resize(pairs, Vec3::zeros());
        self.pair_torque_second.resize(pairs, Vec3::zeros());
        let rolling = law.rolling_friction > 0.0;

        // Eq. 13–16 for every listed pair.
        let (max_pair_overlap, particle_contacts) = self
            .neighbours
            .first
            .par_iter()
            .zip(self.neighbours.second.par_iter())
            .zip(self.neighbours.history.par_iter_mut())
            .zip(self.pair_force.par_iter_mut())
            .zip(self.pair_torque_first.par_iter_mut())
            .zip(self.pair_torque_second.par_iter_mut())
            .with_min_len(PAIRS_PER_TASK)
            .map(|(((((&i, &j), history), force), torque_i), torque_j)| {
                let (i, j) = (i as usize, j as usize);
                let branch = p.position[i] - p.position[j];
                let (ri, rj) = (p.radius[i], p.radius[j]);
                let distance_sq = branch.norm_squared();
                let reach = ri + rj;
                if distance_sq >= reach * reach {
                    *history = Vec3::zeros();
                    *force = Vec3::zeros();
                    *torque_i = Vec3::zeros();
                    *torque_j = Vec3::zeros();
                    return (0.0, 0usize);
                }
                let distance = distance_sq.sqrt();
                let normal = branch / distance;
                let overlap = reach - distance;
                let relative_velocity = p.velocity[i]
                    - p.velocity[j]
                    - (ri * p.angular_velocity[i] + rj * p.angular_velocity[j]).cross(&normal);
                let effective_mass = 1.0 / (p.inverse_mass[i] + p.inverse_mass[j]);
                let contact = law.force(
                    overlap,
                    normal,
                    relative_velocity,
                    effective_mass,
                    friction,
                    *history,
                    dt,
                );
                if dt > 0.0 {
                    *history = contact.history;
                }
                *force = contact.force;
                // Eq. 14: F_t acts at −r_i n on i and (as −F_t) at +r_j n on j.
                let tangential_torque = -normal.cross(&contact.tangential);
                *torque_i = ri * tangential_torque;
                *torque_j = rj * tangential_torque;
                if rolling {
                    let inverse_inertia = p.inverse_inertia[i] + p.inverse_inertia[j];
                    let resistance = law.rolling_torque(
                        normal,
                        p.angular_velocity[i] - p.angular_velocity[j],
                        contact.normal_force,
                        ri * rj / (ri + rj),
                        1.0 / inverse_inertia,
                        dt,
                    );
                    *torque_i += resistance;
                    *torque_j -= resistance;
                }
                (overlap / ri.min(rj), 1usize)
            })
            .reduce(|| (0.0, 0), |a, b| (a.0.max(b.0), a.1 + b.1));

        // Gather per owned particle, in pair order, then walls and gravity.
        let n_owned = p.n_owned;
        let walls = &self.walls;
        let wall_stride = self.wall_stride();
        let time = self.time;
        let gravity = self.domain.gravity;
        let offsets = &self.neighbours.offsets;
        let pair_of = &self.neighbours.pair_of;
        let pair_force = &self.pair_force;
        let pair_torque_first = &self.pair_torque_first;
        let pair_torque_second = &self.pair_torque_second;
        let mut force = std::mem::take(&mut self.particles.force);
        let mut torque = std::mem::take(&mut self.particles.torque);
        let p = &self.particles;
        let wall_history: &mut [Vec3] = &mut self.wall_history;
        let (max_wall_overlap, wall_contacts) = force[..n_owned]
            .par_iter_mut()
            .zip(torque[..n_owned].par_iter_mut())
            .zip(wall_history.par_chunks_mut(wall_stride))
            .enumerate()
            .with_min_len(PARTICLES_PER_TASK)
            .map(|(k, ((f, t), histories))| {
                let mut total_force = Vec3::zeros();
                let mut total_torque = Vec3::zeros();
                let radius = p.radius[k];
                for &entry in &pair_of[offsets[k] as usize..offsets[k + 1] as usize] {
                    let pair = (entry >> 1) as usize;
                    if entry & 1 == 0 {
                        total_force += pair_force[pair];
                        total_torque += pair_torque_first[pair];
                    } else {
                        total_force -= pair_force[pair];
                        total_torque += pair_torque_second[pair];
                    }
                }
                let mut max_overlap: f64 = 0.0;
                let mut contacts = 0usize;
                if p.inverse_mass[k] > 0.0 {
                    for (w, wall) in walls.iter().enumerate() {
                        let history = &mut histories[w];
                        if !wall.is_present(time) {
                            *history = Vec3::zeros();
                            continue;
                        }
                        let overlap = radius - wall.distance(&p.position[k]);
                        if overlap <= 0.0 {
                            *history = Vec3::zeros();
                            continue;
                        }
                        let normal = wall.normal;
                        let relative_velocity =
                            p.velocity[k] - (radius * p.angular_velocity[k]).cross(&normal);
                        let contact = law.force(
                            overlap,
                            normal,
                            relative_velocity,
                            p.mass[k],
                            wall.friction,
                            *history,
                            dt,
                        );
                        if dt > 0.0 {
                            *history = contact.history;
                        }
                        total_force += contact.force;
                        total_torque -= radius * normal.cross(&contact.tangential);
                        if rolling {
                            total_torque += law.rolling_torque(
                                normal,
                                p.angular_velocity[k],
                                contact.normal_force,
                                radius,
                                1.0 / p.inverse_inertia[k],
                                dt,
                            );
                        }
                        max_overlap = max_overlap.max(overlap / radius);
                        contacts += 1;
                    }
                    total_force += p.mass[k] * gravity;
                }
                *f = total_force;
                *t = total_torque;
                (max_overlap, contacts)
            })
            .reduce(|| (0.0, 0), |a, b| (a.0.max(b.0), a.1 + b.1));
        self.particles.force = force;
        self.particles.torque = torque;

        StepDiagnostics {
            max_overlap_ratio: self
                .communicator
                .max(max_pair_overlap.max(max_wall_overlap)),
            particle_contacts: self.communicator.sum_count(particle_contacts),
            wall_contacts: self.communicator.sum_count(wall_contacts),
            non_finite: false,
        }
    }

    /// Largest particle speed (owned, over all ranks).
    pub fn max_speed(&self) -> f64 {
        let n = self.particles.n_owned;
        let local = self.particles.velocity[..n]
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max);
        self.communicator.max(local)
    }

    /// Index of the owned particle with id `id`.
    pub fn index_of(&self, id: u64) -> Option<usize> {
        self.particles.id[..self.particles.n_owned]
            .iter()
            .position(|&k| k == id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact_law::{NormalCalibration, NormalStiffness};
    use crate::particles::NewParticle;
    use rand::{Rng, SeedableRng};
    use std::collections::BTreeSet;

    /// Random spheres in a box periodic along x and y: the pair list holds
    /// exactly the pairs within r_i + r_j + skin under the minimum image.
    #[test]
    fn the_pair_list_matches_a_brute_force_search_with_periodic_images() {
        let domain = Domain {
            dimension: Dimension::Three,
            lower: Vec3::zeros(),
            upper: Vec3::new(0.1, 0.08, 0.12),
            periodic: [true, true, false],
            gravity: Vec3::zeros(),
        };
        let law = ContactLaw {
            normal: NormalStiffness::from_restitution(0.5, 1e-4, NormalCalibration::Exact),
            tangential_ratio: 0.2,
            friction: 0.5,
            rolling_friction: 0.0,
        };
        let skin = 1e-3;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(42);
        let new: Vec<NewParticle> = (0..1500)
            .map(|_| NewParticle {
                position: Vec3::new(
                    rng.gen::<f64>() * 0.1,
                    rng.gen::<f64>() * 0.08,
                    rng.gen::<f64>() * 0.12,
                ),
                velocity: Vec3::zeros(),
                angular_velocity: Vec3::zeros(),
                radius: 0.003 + 0.002 * rng.gen::<f64>(),
                density: 2500.0,
                fixed: false,
            })
            .collect();
        let mut system = DemSystem::new(domain.clone(), law, Vec::new(), skin);
        system.add_particles(&new);

        let p = &system.particles;
        let listed: BTreeSet<(u64, u64)> = system
            .neighbours
            .first
            .iter()
            .zip(&system.neighbours.second)
            .map(|(&i, &j)| {
                let (a, b) = (p.id[i as usize], p.id[j as usize]);
                (a.min(b), a.max(b))
            })
            .collect();
        let mut expected = BTreeSet::new();
        let extent = domain.extent();
        for a in 0..new.len() {
            for b in a + 1..new.len() {
                let mut d = new[a].position - new[b].position;
                for axis in 0..2 {
                    d[axis] -= extent[axis] * (d[axis] / extent[axis]).round();
                }
                if d.norm() < new[a].radius + new[b].radius + skin {
                    expected.insert((a as u64, b as u64));
                }
            }
        }
        assert!(expected.len() > 1000);
        assert_eq!(listed, expected);
        // Owned-owned pairs appear once; a pair across the boundary appears
        // once from each side (one ghost each).
        assert!(system.neighbours.len() >= expected.len());
    }
}
