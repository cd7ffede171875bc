//! The DEM time step: velocity Verlet over particles, walls and contacts.
//!
//! One step of size Δt:
//! 1. half kick v += Δt/2 F/m, ω += Δt/2 T/I, then drift x += Δt v;
//! 2. rebuild the neighbour list (migrate, sort, ghosts) if a particle moved
//!    more than half the skin, else refresh the ghosts;
//! 3. contact forces (eq. 13–16) and, in a fluid, lubrication (eq. 19),
//!    its films implicit together through each grain's film rate
//!    (`system/film_rates.rs`): each particle evaluates the pairs it holds the upper side of, its
//!    walls, gravity and the external (hydrodynamic) load; then each
//!    particle collects the pairs evaluated by its partners, in a fixed
//!    order;
//! 4. half kick with the new forces, each chunk's as soon as its forces are
//!    complete (in the force loop's pass).
//!
//! This file holds the system, the step and the queries of its contacts;
//! step 2 is in `system/rebuild.rs`, steps 3–4 in `system/force_loop.rs`
//! (with `system/handover.rs`: what a chunk hands to later chunks, and
//! `system/film_rates.rs`), checkpoints in `system/saved_state.rs`.

use crate::contact_law::{ContactLaw, ContactPoint};
use crate::ghosts::Ghosts;
use crate::lubrication::Lubrication;
use crate::neighbours::{CellGrid, NeighbourList, PreviousList, LUBRICATED, TOUCHING};
use crate::particles::{permuted, NewParticle, Particles, PACKED_STATE};
use crate::thread_share::{LazyTeam, RunClaims, ThreadShare};
use crate::walls::PlaneWall;
use grainflow_core::{Communicator, Dimension, Domain, ProcessGrid, Subdomain, Vec3};
use rayon::prelude::*;
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

mod film_rates;
mod force_loop;
mod saved_state;
use handover::HandoverSources;
mod handover;
#[cfg(test)]
mod pair_evaluation_tests;
mod rebuild;
#[cfg(test)]
mod tests;

/// Smallest amount of work handed to one thread: below it the loops run on
/// the calling thread, so small scenes pay no synchronisation.
const PARTICLES_PER_TASK: usize = 256;

/// Particles per chunk of the force loop among `n`: the largest of 256,
/// 512 and 1024 that still leaves 16 chunks to share among threads. A pair
/// within one chunk hands its result to the upper particle in cache; one
/// across chunks goes through a hand-over list, so larger chunks save
/// memory traffic.
/// It depends on `n` alone, never on the number of threads.
fn force_chunk(n: usize) -> usize {
    [1024, 512]
        .into_iter()
        .find(|&chunk| n >= 16 * chunk)
        .unwrap_or(PARTICLES_PER_TASK)
}

/// A contact as seen from one of its particles.
#[derive(Clone, Copy, Debug)]
pub struct Contact {
    /// Index of the partner particle (`usize::MAX` for a wall).
    pub partner: usize,
    /// Unit normal from the partner to this particle.
    pub normal: Vec3,
    /// Force on this particle.
    pub force: Vec3,
    pub normal_force: f64,
}

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
    /// The film force between close grains: only in a scene with a fluid.
    /// Set it before adding particles (the pair list reaches its range).
    pub lubrication: Option<Lubrication>,
    /// Gap between surfaces at which contacts start (0 in a dry scene). In
    /// a fluid, the immersed boundaries spread each grain's surface over
    /// about a cell: touching at a gap of the order of a cell keeps the
    /// forced layers of two grains, or of a grain and a wall, from sealing
    /// the fluid between them (the projection would answer a grain leaving
    /// a wall with an inviscid suction the real film does not produce). The
    /// lubrication force of eq. 19 measures the gap left before contact,
    /// so that a bounce loses to the film what it would with contact at
    /// the true surface (the thin-film restitution). Set it before adding
    /// particles.
    pub contact_gap: f64,
    /// Gap below which pairs are listed for hard contact (its candidate
    /// threshold D, Martin et al. 2022 section 3.3); 0 with soft contact.
    pub listing_gap: f64,
    /// Least distance from a subdomain's faces within which particles have
    /// ghosts, beyond the interaction range: the reach of a grain's
    /// immersed boundary in a fluid, so that every grain that forces a
    /// rank's cells is there (0 in a dry scene). Set it before adding
    /// particles.
    pub ghost_reach: f64,
    /// The step the film forces of the current totals were made implicit
    /// for (0 before the first step: explicit).
    film_dt: f64,
    /// Per local particle (owned, then ghosts), the sum over its
    /// lubrication films of their damping over its mass at the last force
    /// evaluation (`film_rates.rs`); empty without lubrication.
    film_rate: Vec<f64>,
    pub walls: Vec<PlaneWall>,
    /// Tangential displacement of each owned particle against each wall:
    /// `wall_history[p * wall_stride() + w]`.
    pub wall_history: Vec<Vec3>,
    /// Bit w set while owned particle p touches wall w (so that the loop
    /// reads a wall history only for contacts that are or were open).
    wall_touching: Vec<u64>,
    /// Bit w set for owned particle p if wall w was within its radius plus
    /// the skin at the last neighbour build: no other wall can reach it
    /// before the next build (a particle moves less than half the skin).
    wall_candidates: Vec<u64>,
    /// Whether external loads were ever set (a scene with a fluid): the
    /// force loop of a dry scene does not read them.
    external_loads: bool,
    pub neighbours: NeighbourList,
    ghosts: Ghosts,
    /// Particle–particle contacts of each owned particle at the last force
    /// evaluation (its coordination number).
    pub contacts: Vec<u32>,
    /// Largest radius over all ranks at the last neighbour build.
    max_radius: f64,
    /// For the pair list of build `.0`: per chunk of the force loop, the
    /// chunks that own a lower partner of one of its particles, the only
    /// ones it receives hand-overs from.
    handover_sources: (u64, HandoverSources),
    /// The run of force-loop chunks each thread works on in every pass.
    share: ThreadShare,
    /// The threads that run those passes.
    team: LazyTeam,
    /// Threads forced for the passes of the force loop; when `None`, one
    /// per [`crate::threads::GRAINS_PER_THREAD`] owned grains, at most the
    /// current rayon pool's.
    pub threads: Option<usize>,
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
            lubrication: None,
            contact_gap: 0.0,
            listing_gap: 0.0,
            ghost_reach: 0.0,
            film_dt: 0.0,
            film_rate: Vec::new(),
            walls,
            wall_history: Vec::new(),
            wall_touching: Vec::new(),
            wall_candidates: Vec::new(),
            external_loads: false,
            neighbours: NeighbourList::new(skin),
            ghosts: Ghosts::default(),
            contacts: Vec::new(),
            max_radius: 0.0,
            handover_sources: (u64::MAX, HandoverSources::default()),
            share: ThreadShare::default(),
            team: LazyTeam::default(),
            threads: None,
            time: 0.0,
            steps: 0,
            last: StepDiagnostics::default(),
            next_id: 0,
        }
    }

    /// Shares the scene among the ranks of `communicator` in a process grid
    /// of `ranks` boxes of equal lengths (before any particle is added).
    pub fn decompose(&mut self, communicator: Communicator, ranks: [usize; 3]) {
        self.decompose_in(communicator, &ProcessGrid::even(ranks));
    }

    /// Shares the scene among the ranks of `communicator` in the boxes of
    /// `grid` (before any particle is added).
    pub fn decompose_in(&mut self, communicator: Communicator, grid: &ProcessGrid) {
        assert!(
            self.particles.is_empty(),
            "decompose before adding particles"
        );
        assert_eq!(grid.rank_count(), communicator.size(), "one box per rank");
        self.subdomain = grid.subdomain(&self.domain, communicator.rank());
        self.communicator = communicator;
    }

    pub fn dimension(&self) -> Dimension {
        self.domain.dimension
    }

    /// Adds particles (before the first step or between steps; collective:
    /// every rank passes the same list and keeps those it owns). Ids follow
    /// the order of the list over all ranks.
    pub fn add_particles(&mut self, new: &[NewParticle]) {
        self.add_particles_in_groups(new, &vec![0; new.len()]);
    }

    /// [`DemSystem::add_particles`], particle k in group `groups[k]`.
    pub fn add_particles_in_groups(&mut self, new: &[NewParticle], groups: &[u64]) {
        assert_eq!(new.len(), groups.len(), "one group per particle");
        self.particles.clear_ghosts();
        for (particle, &group) in new.iter().zip(groups) {
            let mut p = particle.clone();
            if self.dimension() == Dimension::Two {
                p.position.z = 0.0;
                p.velocity.z = 0.0;
                p.angular_velocity.x = 0.0;
                p.angular_velocity.y = 0.0;
            }
            let mut centre = p.position;
            self.domain.wrap(&mut centre);
            if self.subdomain.owns(&self.domain, &centre) {
                self.particles
                    .push(self.domain.dimension, self.next_id, group, &p);
            }
            self.next_id += 1;
        }
        self.wall_history
            .resize(self.particles.n_owned * self.wall_stride(), Vec3::zeros());
        self.wall_touching.resize(self.particles.n_owned, 0);
        self.rebuild();
        self.compute_forces(0.0);
    }

    /// Mean diameter of the grains that move, over every rank (`None`
    /// where none moves). Every rank must call it.
    pub fn mean_moving_diameter(&self) -> Option<f64> {
        let p = &self.particles;
        let (mut sum, mut count) = (0.0, 0usize);
        for k in (0..p.n_owned).filter(|&k| !p.is_fixed(k)) {
            sum += 2.0 * p.radius[k];
            count += 1;
        }
        let count = self.communicator.sum_count(count);
        (count > 0).then(|| self.communicator.sum(sum) / count as f64)
    }

    /// The id the next added particle gets (the same on every rank).
    pub fn next_id(&self) -> u64 {
        self.next_id
    }

    /// Entries per particle in `wall_history` (at least one, so that the
    /// per-particle chunks exist without walls).
    pub fn wall_stride(&self) -> usize {
        self.walls.len().max(1)
    }

    /// Interaction range of a ghost: the largest pair distance in the list.
    fn interaction_range(&self) -> f64 {
        self.range_for(self.max_radius)
    }

    /// The interaction range with grains of radius up to `max_radius`: the
    /// largest listed pair distance, 2 r + gap + skin.
    pub fn range_for(&self, max_radius: f64) -> f64 {
        2.0 * max_radius + self.listed_gap(max_radius) + self.neighbours.skin
    }

    /// The gap between surfaces up to which pairs interact: lubrication,
    /// contact gap and hard-contact listing, whichever reaches farthest.
    fn listed_gap(&self, max_radius: f64) -> f64 {
        self.lubrication
            .map_or(0.0, |law| law.reach(max_radius) + self.contact_gap)
            .max(self.contact_gap)
            .max(self.listing_gap)
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

    /// Advances the particles by one step of size `dt`.
    pub fn step(&mut self, dt: f64) -> StepDiagnostics {
        if self.lubrication.is_some() && self.film_dt != dt {
            // The first half kick must already see the film forces made
            // implicit for this step, not for another one (or explicit).
            self.evaluate_forces(0.0, dt);
        }
        let moved_beyond_skin = self.kick_and_drift(dt);
        self.time += dt;
        if self.communicator.any(moved_beyond_skin) {
            self.rebuild();
        } else {
            self.ghosts.refresh(&mut self.particles, &self.communicator);
        }
        let diagnostics = self.evaluate_forces_and_kick(dt, dt, Some(0.5 * dt));
        self.steps += 1;
        self.last = diagnostics;
        diagnostics
    }

    /// Hard contact's position update x ← x + Δt v with the end-of-step
    /// velocities (Martin et al. 2022, below eq. 9), then the list and the
    /// ghosts; returns whether a position or velocity is not finite.
    pub fn drift(&mut self, dt: f64) -> bool {
        let n = self.particles.n_owned;
        let limit_sq = (0.5 * self.neighbours.skin).powi(2);
        let reference = &self.neighbours.reference_position;
        let stale = reference.len() != n;
        let p = &mut self.particles;
        let (moved_beyond_skin, non_finite) = p.position[..n]
            .par_iter_mut()
            .zip(p.velocity[..n].par_iter())
            .zip(p.angular_velocity[..n].par_iter())
            .enumerate()
            .with_min_len(PARTICLES_PER_TASK)
            .map(|(k, ((x, v), w))| {
                *x += dt * v;
                let moved = stale || (*x - reference[k]).norm_squared() > limit_sq;
                let finite = x
                    .iter()
                    .chain(v.iter())
                    .chain(w.iter())
                    .all(|c| c.is_finite());
                (moved, !finite)
            })
            .reduce(|| (false, false), |a, b| (a.0 || b.0, a.1 || b.1));
        self.time += dt;
        self.steps += 1;
        if self.communicator.any(non_finite) {
            return true;
        }
        if self.communicator.any(moved_beyond_skin) {
            self.rebuild();
        } else {
            self.ghosts.refresh(&mut self.particles, &self.communicator);
        }
        false
    }

    /// Copies the current state of every particle onto its ghosts (the DEM
    /// step leaves the ghosts' velocities half a kick behind; a coupled
    /// stage forces the flow with every grain's latest motion).
    pub fn refresh_ghosts(&mut self) {
        self.ghosts.refresh(&mut self.particles, &self.communicator);
    }

    /// Adds the `width` numbers per local particle (owned, then ghosts)
    /// accumulated on ghosts to the particles they copy; the owned entries
    /// then hold the totals ([`Ghosts::reverse_sum`]).
    pub fn sum_onto_owners(&self, values: &mut [f64], width: usize) {
        assert_eq!(values.len(), self.particles.len() * width);
        self.ghosts.reverse_sum(values, width, &self.communicator);
    }

    /// Copies the `width` numbers of each owned particle onto its ghosts
    /// (`values` holds `width` numbers per local particle, owned then
    /// ghosts; collective): [`Ghosts::copy_to_ghosts`].
    pub fn copy_onto_ghosts(&self, values: &mut [f64], width: usize) {
        assert_eq!(values.len(), self.particles.len() * width);
        self.ghosts
            .copy_to_ghosts(values, width, &self.communicator);
    }

    /// The owned particle a ghost (index ≥ n_owned) copies, or `usize::MAX`
    /// for a copy of another rank's particle.
    pub fn ghost_source(&self, ghost: usize) -> usize {
        self.ghosts.source[ghost - self.particles.n_owned]
    }

    /// Records the contacts a hard-contact step closed: the particle count
    /// of each owned particle and its walls as bits (what `contacts` and
    /// `touches_a_wall` report).
    pub fn record_contacts(&mut self, particle_contacts: Vec<u32>, walls_touched: Vec<u64>) {
        self.contacts = particle_contacts;
        self.wall_touching = walls_touched;
    }

    /// Sets the external force and torque of every owned particle (held
    /// fixed over the following steps), updating the current totals so
    /// that the next half kick already uses them.
    pub fn set_external_loads(&mut self, force: &[Vec3], torque: &[Vec3]) {
        let n = self.particles.n_owned;
        assert!(
            force.len() == n && torque.len() == n,
            "one load per owned particle"
        );
        self.external_loads = true;
        let p = &mut self.particles;
        for k in 0..n {
            if p.inverse_mass[k] == 0.0 {
                continue;
            }
            p.force[k] += force[k] - p.external_force[k];
            p.torque[k] += torque[k] - p.external_torque[k];
            p.external_force[k] = force[k];
            p.external_torque[k] = torque[k];
        }
    }

    /// Half kick and drift; returns whether a particle moved more than half
    /// the skin since the last neighbour build.
    fn kick_and_drift(&mut self, dt: f64) -> bool {
        let n = self.particles.n_owned;
        let half_dt = 0.5 * dt;
        let limit_sq = (0.5 * self.neighbours.skin).powi(2);
        if self.neighbours.reference_position.len() != n {
            return true;
        }
        self.update_share(n);
        let share = &self.share;
        let team = self.team.of(share.threads());
        let reference = &self.neighbours.reference_position;
        let p = &mut self.particles;
        let parts: Vec<_> = share
            .split(&mut p.position[..n], n)
            .into_iter()
            .zip(share.split(&mut p.velocity[..n], n))
            .zip(share.split(&mut p.angular_velocity[..n], n))
            .map(|((x, v), w)| (x, v, w))
            .collect();
        let (f, t) = (&p.force, &p.torque);
        let (inv_m, inv_i) = (&p.inverse_mass, &p.inverse_inertia);
        // Plain loops over each thread's run: the compiler keeps them tight.
        team.run_parts(parts, |thread, (x, v, w)| {
            let run = share.particles_of(thread, n);
            let (f, t) = (&f[run.clone()], &t[run.clone()]);
            let (inv_m, inv_i) = (&inv_m[run.clone()], &inv_i[run.clone()]);
            let x0 = &reference[run];
            let mut moved = false;
            for k in 0..x.len() {
                v[k] += half_dt * inv_m[k] * f[k];
                w[k] += half_dt * inv_i[k] * t[k];
                x[k] += dt * v[k];
                moved |= (x[k] - x0[k]).norm_squared() > limit_sq;
            }
            moved
        })
        .into_iter()
        .any(|moved| moved)
    }

    /// Fits the threads' runs of chunks to `n` owned particles and the
    /// current neighbour build.
    fn update_share(&mut self, n: usize) {
        let threads = self
            .threads
            .unwrap_or_else(|| crate::threads::threads_for(n, rayon::current_num_threads()));
        self.share
            .update(n, force_chunk(n), threads, self.neighbours.builds);
    }

    /// The contacts of owned particle i with other particles, as evaluated
    /// by the last force computation (for analyses: stresses, coordination).
    pub fn particle_contacts_of(&self, i: usize) -> Vec<Contact> {
        let p = &self.particles;
        let mut out = Vec::new();
        for e in self.neighbours.range(i) {
            let j = self.neighbours.partner[e] as usize;
            let branch = p.position[i] - p.position[j];
            let reach = p.radius[i] + p.radius[j] + self.contact_gap;
            if branch.norm_squared() >= reach * reach {
                continue;
            }
            let distance = branch.norm();
            let normal = branch / distance;
            let relative_velocity = p.velocity[i]
                - p.velocity[j]
                - (p.radius[i] * p.angular_velocity[i] + p.radius[j] * p.angular_velocity[j])
                    .cross(&normal);
            let contact = self.law.force(
                reach - distance,
                normal,
                relative_velocity,
                p.inverse_mass[i] + p.inverse_mass[j],
                self.law.friction,
                self.neighbours.history_of(e),
                0.0,
            );
            out.push(Contact {
                partner: j,
                normal,
                force: contact.force,
                normal_force: contact.normal_force,
            });
        }
        out
    }

    /// The contacts of owned particle i with walls (normal = the wall's).
    pub fn wall_contacts_of(&self, i: usize) -> Vec<(usize, Contact)> {
        let p = &self.particles;
        let mut out = Vec::new();
        for (w, wall) in self.walls.iter().enumerate() {
            let overlap = p.radius[i] + self.contact_gap - wall.distance(&p.position[i]);
            if overlap <= 0.0 || !wall.is_present(self.time) || p.inverse_mass[i] == 0.0 {
                continue;
            }
            let normal = wall.normal_towards(&p.position[i]);
            let relative_velocity =
                p.velocity[i] - (p.radius[i] * p.angular_velocity[i]).cross(&normal);
            let contact = self.law.force(
                overlap,
                normal,
                relative_velocity,
                p.inverse_mass[i],
                wall.friction,
                self.wall_history[i * self.wall_stride() + w],
                0.0,
            );
            out.push((
                w,
                Contact {
                    partner: usize::MAX,
                    normal,
                    force: contact.force,
                    normal_force: contact.normal_force,
                },
            ));
        }
        out
    }

    /// Whether owned particle k touched a wall at the last force evaluation.
    pub fn touches_a_wall(&self, k: usize) -> bool {
        self.wall_touching.get(k).is_some_and(|&bits| bits != 0)
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
