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

use crate::contact_law::{ContactLaw, ContactPoint};
use crate::ghosts::Ghosts;
use crate::lubrication::Lubrication;
use crate::neighbours::{CellGrid, NeighbourList, PreviousList, LUBRICATED, TOUCHING};
use crate::particles::{permuted, NewParticle, Particles, PACKED_STATE};
use crate::thread_share::{LazyTeam, RunClaims, ThreadShare};
use crate::walls::PlaneWall;
use grainflow_core::{Communicator, Dimension, Domain, Subdomain, Vec3};
use rayon::prelude::*;
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

mod film_rates;
mod saved_state;

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
    /// of `ranks` boxes (before any particle is added).
    pub fn decompose(&mut self, communicator: Communicator, ranks: [usize; 3]) {
        assert!(
            self.particles.is_empty(),
            "decompose before adding particles"
        );
        assert_eq!(
            ranks.iter().product::<usize>(),
            communicator.size(),
            "one box per rank"
        );
        self.subdomain = Subdomain::of_rank(&self.domain, ranks, communicator.rank());
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

    /// Migration, locality sort, ghosts and pair list (collective).
    pub fn rebuild(&mut self) {
        // The old list, with the ids of all particles (owned and ghosts) it
        // refers to, carries the open contacts over to the new one.
        let previous = self.neighbours.take_previous(&self.particles);
        self.rebuild_from(previous);
    }

    /// [`DemSystem::rebuild`] carrying the open contacts of `previous`.
    fn rebuild_from(&mut self, mut previous: PreviousList) {
        self.max_radius = self.communicator.max(self.particles.max_radius());
        self.neighbours.gap = self.listed_gap(self.max_radius);
        self.particles.clear_ghosts();
        for x in &mut self.particles.position {
            self.domain.wrap(x);
        }
        self.migrate(&mut previous);
        let grid = self.cell_grid();

        // Sort owned particles by cell, cells in Z order, so that
        // neighbours sit close in memory and most pairs fall in one chunk of
        // the force loop (stable: a particle's rank within its cell is kept).
        // Keyed by (cell, old index): an unstable sort of the keys is the
        // stable sort of the cells, the same on any number of threads.
        let mut keyed: Vec<(u64, usize)> = self.particles.position[..self.particles.n_owned]
            .par_iter()
            .with_min_len(PARTICLES_PER_TASK)
            .enumerate()
            .map(|(k, x)| (grid.z_order(x), k))
            .collect();
        keyed.par_sort_unstable();
        let order: Vec<usize> = keyed.into_iter().map(|(_, k)| k).collect();
        if order.iter().enumerate().any(|(k, &o)| k != o) {
            previous.reorder(&order);
            self.particles.permute_owned(&order);
            let stride = self.wall_stride();
            self.wall_touching = permuted(&self.wall_touching, &order);
            let mut history = vec![Vec3::zeros(); self.wall_history.len()];
            if stride > 0 {
                let old = &self.wall_history;
                history
                    .par_chunks_mut(stride)
                    .zip(order.par_iter())
                    .with_min_len(PARTICLES_PER_TASK)
                    .for_each(|(row, &o)| row.copy_from_slice(&old[o * stride..(o + 1) * stride]));
            }
            self.wall_history = history;
        }

        let range = self.interaction_range().max(self.ghost_reach);
        self.ghosts.build(
            &mut self.particles,
            &self.domain,
            &self.subdomain,
            &self.communicator,
            range,
        );
        self.neighbours.build(&self.particles, &grid, &previous);
        self.list_wall_candidates();
    }

    /// Hands each owned particle whose centre has left this subdomain to the
    /// rank that owns it now, with its wall histories and the tangential
    /// history of its open contacts, and takes in those that arrive here
    /// (collective).
    fn migrate(&mut self, previous: &mut PreviousList) {
        let n = self.particles.n_owned;
        let stride = self.wall_stride();
        let rank = self.communicator.rank();
        let mut outgoing = vec![Vec::new(); self.communicator.size()];
        let mut kept = Vec::with_capacity(n);
        let mut open = Vec::new();
        for k in 0..n {
            let owner = self
                .subdomain
                .owner(&self.domain, &self.particles.position[k]);
            if owner == rank {
                kept.push(k);
                continue;
            }
            previous.open_contacts_of(k, &mut open);
            self.pack_grain(k, &open, &mut outgoing[owner]);
        }
        let arrived = self.communicator.exchange(outgoing);
        if kept.len() == n && arrived.iter().all(|m| m.is_empty()) {
            return;
        }
        self.particles.retain_owned(&kept);
        self.wall_touching.resize(n, 0);
        self.wall_touching = kept.iter().map(|&k| self.wall_touching[k]).collect();
        let old = std::mem::take(&mut self.wall_history);
        self.wall_history = kept
            .iter()
            .flat_map(|&k| old[k * stride..(k + 1) * stride].iter().copied())
            .collect();
        let mut adopted = Vec::new();
        for message in &arrived {
            for grain in PackedGrains::new(message, stride) {
                adopted.push(self.push_grain(&grain));
            }
        }
        previous.retain_and_adopt(&kept, &adopted);
    }

    /// Appends owned grain k to a message with everything that travels with
    /// it: its state, its wall contacts and histories, and the open
    /// contacts `open` (partner id, ξ seen from k). Read by [`PackedGrains`].
    fn pack_grain(&self, k: usize, open: &[(u64, Vec3)], message: &mut Vec<f64>) {
        let stride = self.wall_stride();
        self.particles.pack_state(k, Vec3::zeros(), message);
        message.push(f64::from_bits(
            self.wall_touching.get(k).copied().unwrap_or(0),
        ));
        for history in &self.wall_history[k * stride..(k + 1) * stride] {
            message.extend(history.iter());
        }
        message.push(open.len() as f64);
        for (id, history) in open {
            message.push(f64::from_bits(*id));
            message.extend(history.iter());
        }
    }

    /// Adds a grain of a [`DemSystem::pack_grain`] message as owned (no
    /// ghosts may exist); returns its open contacts.
    fn push_grain(&mut self, grain: &PackedGrain) -> Vec<(u64, Vec3)> {
        self.particles.push_packed(grain.state, true);
        self.wall_touching.push(grain.wall_touching);
        self.wall_history.extend_from_slice(&grain.wall_history);
        grain.open.clone()
    }

    /// The whole scene gathered on the root rank as a one-rank system, for
    /// analyses that measure every grain (collective; None on the other
    /// ranks). The grains come in the order of their ids with their wall
    /// and contact histories; the pair list is rebuilt and the forces
    /// evaluated again without advancing the histories.
    pub fn gathered(&self) -> Option<DemSystem> {
        let stride = self.wall_stride();
        let mut message = Vec::new();
        let mut open = Vec::new();
        for k in 0..self.particles.n_owned {
            self.neighbours.open_contacts(k, &self.particles, &mut open);
            self.pack_grain(k, &open, &mut message);
        }
        let pieces = self.communicator.gather(&message)?;
        let mut grains: Vec<PackedGrain> = pieces
            .iter()
            .flat_map(|m| PackedGrains::new(m, stride))
            .collect();
        grains.sort_by_key(|g| g.state[0].to_bits());
        let mut whole = DemSystem::new(
            self.domain.clone(),
            self.law,
            self.walls.clone(),
            self.neighbours.skin,
        );
        whole.lubrication = self.lubrication;
        whole.contact_gap = self.contact_gap;
        whole.listing_gap = self.listing_gap;
        whole.time = self.time;
        whole.steps = self.steps;
        whole.last = self.last;
        whole.next_id = self.next_id;
        whole.external_loads = self.external_loads;
        let adopted: Vec<Vec<(u64, Vec3)>> = grains.iter().map(|g| whole.push_grain(g)).collect();
        let mut previous = PreviousList::default();
        previous.retain_and_adopt(&[], &adopted);
        whole.rebuild_from(previous);
        whole.evaluate_forces(0.0, self.film_dt);
        whole.last = self.last;
        Some(whole)
    }

    /// Marks, for each owned particle, the walls it may touch before the
    /// next neighbour build.
    fn list_wall_candidates(&mut self) {
        let n = self.particles.n_owned;
        let margin = self.neighbours.skin + self.neighbours.gap;
        let walls = &self.walls;
        let p = &self.particles;
        self.wall_candidates.resize(n, 0);
        self.wall_candidates
            .par_iter_mut()
            .enumerate()
            .with_min_len(PARTICLES_PER_TASK)
            .for_each(|(i, candidates)| {
                *candidates = walls
                    .iter()
                    .enumerate()
                    .filter(|(_, wall)| wall.distance(&p.position[i]) < p.radius[i] + margin)
                    .fold(0, |bits, (w, _)| bits | 1u64 << w);
            });
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

    /// The owned particle a ghost (index ≥ n_owned) copies.
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

    /// Contact forces and gravity on every owned particle; `dt` advances the
    /// tangential histories (0 evaluates without advancing them).
    ///
    /// Two passes over fixed chunks of particles ([`force_chunk`]), each
    /// thread over its run of chunks in increasing order
    /// ([`ThreadShare`]), then over what is left of the other runs from
    /// their ends ([`RunClaims`]), in a fixed order of sums whatever the
    /// threads:
    /// 1. each particle evaluates its upper entries (each pair of owned
    ///    particles once, pairs with ghosts from both sides), its walls and
    ///    gravity; a pair whose upper particle is in the same chunk hands it
    ///    −F and its torque at once (the chunk's sums stay in cache); one
    ///    whose upper particle is owned by a later chunk is handed over in
    ///    a list the chunk publishes when done;
    /// 2. a chunk adds what earlier chunks handed to its particles, in
    ///    increasing chunk and particle order, as soon as those chunks
    ///    ([`HandoverSources`]) have all published their lists: at once
    ///    when they are in the thread's own run, while the chunk is still
    ///    in cache; otherwise between the run's later chunks, once the
    ///    thread that owns them has got that far, or at the end of the run.
    ///    The sums are the same either way, so the result does not depend
    ///    on the number of threads, and Newton's third law holds bitwise.
    pub fn compute_forces(&mut self, dt: f64) -> StepDiagnostics {
        self.evaluate_forces(dt, dt)
    }

    /// [`DemSystem::compute_forces`] advancing the tangential histories by
    /// `history_dt` and making the film forces implicit over `film_dt`.
    fn evaluate_forces(&mut self, history_dt: f64, film_dt: f64) -> StepDiagnostics {
        self.evaluate_forces_and_kick(history_dt, film_dt, None)
    }

    /// [`DemSystem::evaluate_forces`], then the closing half kick of
    /// `closing_kick` (Δt/2) if given, each chunk's as soon as its forces
    /// are complete (no pass of its own).
    fn evaluate_forces_and_kick(
        &mut self,
        history_dt: f64,
        film_dt: f64,
        closing_kick: Option<f64>,
    ) -> StepDiagnostics {
        self.film_dt = film_dt;
        self.update_film_rates();
        let n = self.particles.n_owned;
        assert_eq!(self.wall_candidates.len(), n, "wall candidates not built");
        self.contacts.resize(n, 0);
        let mut force = std::mem::take(&mut self.particles.force);
        let mut torque = std::mem::take(&mut self.particles.torque);
        let mut velocity = std::mem::take(&mut self.particles.velocity);
        let mut angular_velocity = std::mem::take(&mut self.particles.angular_velocity);

        let velocities = PassVelocities::new(&mut velocity, &mut angular_velocity);
        let totals = self.evaluate_upper_pairs_and_walls(
            &mut force[..n],
            &mut torque[..n],
            &velocities,
            history_dt,
            film_dt,
            closing_kick,
        );

        self.particles.force = force;
        self.particles.torque = torque;
        self.particles.velocity = velocity;
        self.particles.angular_velocity = angular_velocity;
        StepDiagnostics {
            max_overlap_ratio: self.communicator.max(totals.max_overlap_ratio),
            // Each contact is counted by both of its particles.
            particle_contacts: self.communicator.sum_count(totals.listed_contacts) / 2,
            wall_contacts: self.communicator.sum_count(totals.wall_contacts),
            non_finite: self.communicator.any(totals.non_finite),
        }
    }

    /// Recomputes [`DemSystem::handover_sources`] after a neighbour build.
    fn refresh_handover_sources(&mut self, n: usize, chunk_len: usize) {
        let list = &self.neighbours;
        let chunks = n.div_ceil(chunk_len);
        if self.handover_sources.0 == list.builds && self.handover_sources.1.chunks() == chunks {
            return;
        }
        let per_chunk: Vec<Vec<u32>> = (0..chunks)
            .into_par_iter()
            .map(|chunk| {
                let first = chunk * chunk_len;
                let mut sources: Vec<u32> = (first..(first + chunk_len).min(n))
                    .flat_map(|i| {
                        &list.partner[list.offsets[i] as usize..list.upper_start[i] as usize]
                    })
                    // Lower partners are owned grains (ghosts come after them).
                    .map(|&j| j / chunk_len as u32)
                    .filter(|&source| (source as usize) < chunk)
                    .collect();
                sources.sort_unstable();
                sources.dedup();
                sources
            })
            .collect();
        let mut sources = HandoverSources::default();
        for chunk_sources in per_chunk {
            sources.chunks.extend_from_slice(&chunk_sources);
            sources.offsets.push(sources.chunks.len());
        }
        self.handover_sources = (list.builds, sources);
    }

    /// The two passes of `compute_forces`, and the closing half kick of
    /// `closing_kick` (Δt/2) of each chunk once it is complete.
    fn evaluate_upper_pairs_and_walls(
        &mut self,
        forces: &mut [Vec3],
        torques: &mut [Vec3],
        velocities: &PassVelocities,
        dt: f64,
        film_dt: f64,
        closing_kick: Option<f64>,
    ) -> PassTotals {
        let n = forces.len();
        let chunk_len = force_chunk(n);
        self.refresh_handover_sources(n, chunk_len);
        self.update_share(n);
        let law = self.law;
        let lubrication = self.lubrication;
        let contact_gap = self.contact_gap;
        let walls = &self.walls;
        let wall_stride = self.wall_stride();
        let time = self.time;
        let gravity = self.domain.gravity;
        let external_loads = self.external_loads;
        let chunks = n.div_ceil(chunk_len);
        let sources_of = &self.handover_sources.1;
        let film_rate = &self.film_rate;
        let list = &mut self.neighbours;
        let (offsets, upper_start, partner) = (&list.offsets, &list.upper_start, &list.partner);
        let entry_chunks =
            EntryChunk::split(offsets, n, &mut list.history, &mut list.state, chunk_len);
        let handovers: Vec<OnceLock<Vec<Handover>>> =
            (0..chunks).map(|_| OnceLock::new()).collect();
        let p = &self.particles;
        // One chunk's pass 1, and its pass 2 when its sources are done.
        let evaluate = |chunk: usize, arrays: &mut ChunkArrays| -> (f64, usize) {
            let ChunkArrays {
                forces,
                torques,
                wall_histories,
                counts,
                entry,
                touching,
                candidates,
            } = arrays;
            let first = chunk * chunk_len;
            let end = first + forces.len();
            let entry_base = offsets[first] as usize;
            let mut max_overlap: f64 = 0.0;
            let mut wall_contacts = 0usize;
            // What the chunk's pairs hand to their upper partner: summed
            // here, in cache, when it lies in the chunk too; listed in
            // `outgoing` when a later chunk owns it (a ghost's owner
            // evaluates the pair itself).
            let mut handed = HandedOver::new(first..end, n);
            for local in 0..forces.len() {
                let i = first + local;
                // Velocities are read where a pair or wall acts: most
                // grains of a loose scene touch nothing, and their
                // velocities then stay out of the cache.
                let (xi, ri) = (p.position[i], p.radius[i]);
                let mut total_force = Vec3::zeros();
                let mut total_torque = Vec3::zeros();
                let mut count = 0u32;
                let upper = upper_start[i] as usize..offsets[i + 1] as usize;
                for (e, &j) in (upper.start - entry_base..).zip(&partner[upper]) {
                    let j = j as usize;
                    let branch = xi - p.position[j];
                    let rj = p.radius[j];
                    let reach = ri + rj + contact_gap;
                    let distance_sq = branch.norm_squared();
                    if distance_sq >= reach * reach {
                        // Most listed partners are apart: touch the
                        // history only when a contact has just ended.
                        if entry.state[e] != 0 {
                            entry.state[e] = 0;
                            entry.history[e] = Vec3::zeros();
                        }
                        if let Some(film) = &lubrication {
                            let distance = distance_sq.sqrt();
                            let normal = branch * (1.0 / distance);
                            let force = film.force(
                                distance - reach,
                                normal,
                                velocities.linear(i) - velocities.linear(j),
                                ri,
                                rj,
                                film_rate[i] + film_rate[j],
                                film_dt,
                            );
                            if force != Vec3::zeros() {
                                total_force += force;
                                entry.state[e] = LUBRICATED;
                                handed.give(Handover {
                                    target: j as u32,
                                    touching: false,
                                    force,
                                    partner_torque: Vec3::zeros(),
                                });
                            }
                        }
                        continue;
                    }
                    entry.state[e] = TOUCHING;
                    // Eq. 13–16, normal from j to i.
                    let distance = distance_sq.sqrt();
                    let normal = branch * (1.0 / distance);
                    let overlap = reach - distance;
                    let (vi, wi) = (velocities.linear(i), velocities.angular(i));
                    let wj = velocities.angular(j);
                    let inverse_mass_sum = p.inverse_mass[i] + p.inverse_mass[j];
                    let contact = ContactPoint {
                        overlap,
                        normal,
                        relative_velocity: vi
                            - velocities.linear(j)
                            - (ri * wi + rj * wj).cross(&normal),
                        relative_spin: wi - wj,
                        radius: ri,
                        partner_radius: rj,
                        inverse_mass_sum,
                        inverse_inertia_sum: p.inverse_inertia[i] + p.inverse_inertia[j],
                        friction: law.friction,
                    };
                    let mut load = law.load(&contact, &mut entry.history[e], dt);
                    if let Some(film) = &lubrication {
                        // Eq. 19 across the gap left before contact.
                        load.force += film.force(
                            -overlap,
                            normal,
                            vi - velocities.linear(j),
                            ri,
                            rj,
                            film_rate[i] + film_rate[j],
                            film_dt,
                        );
                    }
                    total_force += load.force;
                    total_torque += load.torque;
                    handed.give(Handover {
                        target: j as u32,
                        touching: true,
                        force: load.force,
                        partner_torque: load.partner_torque,
                    });
                    max_overlap = max_overlap.max(overlap / ri.min(rj));
                    count += 1;
                }
                if p.inverse_mass[i] > 0.0 {
                    let wall_history =
                        &mut wall_histories[local * wall_stride..(local + 1) * wall_stride];
                    let mut touches = touching[local];
                    // In increasing w, as a loop over all walls would.
                    let mut near = candidates[local] | touches;
                    while near != 0 {
                        let w = near.trailing_zeros() as usize;
                        near &= near - 1;
                        let wall = &walls[w];
                        let (vi, wi) = (velocities.linear(i), velocities.angular(i));
                        let bit = 1u64 << w;
                        let distance = wall.distance(&xi);
                        let normal = wall.normal_towards(&xi);
                        let present = wall.is_present(time);
                        if let (Some(film), true) = (&lubrication, present) {
                            // Eq. 19 against a wall, across the gap left
                            // before contact.
                            total_force += film.force(
                                distance - ri - contact_gap,
                                normal,
                                vi,
                                ri,
                                f64::INFINITY,
                                film_rate[i],
                                film_dt,
                            );
                        }
                        let overlap = ri + contact_gap - distance;
                        if overlap <= 0.0 || !present {
                            if touches & bit != 0 {
                                wall_history[w] = Vec3::zeros();
                                touches &= !bit;
                            }
                            continue;
                        }
                        touches |= bit;
                        let contact = ContactPoint {
                            overlap,
                            normal,
                            relative_velocity: vi - (ri * wi).cross(&normal),
                            relative_spin: wi,
                            radius: ri,
                            partner_radius: f64::INFINITY,
                            inverse_mass_sum: p.inverse_mass[i],
                            inverse_inertia_sum: p.inverse_inertia[i],
                            friction: wall.friction,
                        };
                        let load = law.load(&contact, &mut wall_history[w], dt);
                        total_force += load.force;
                        total_torque += load.torque;
                        max_overlap = max_overlap.max(overlap / ri);
                        wall_contacts += 1;
                    }
                    touching[local] = touches;
                    total_force += p.mass[i] * gravity;
                    if external_loads {
                        total_force += p.external_force[i];
                        total_torque += p.external_torque[i];
                    }
                }
                forces[local] = handed.force[local] + total_force;
                torques[local] = handed.torque[local] + total_torque;
                counts[local] = handed.count[local] + count;
            }
            // By target chunk, each target's pairs kept in order.
            let mut outgoing = handed.outgoing;
            outgoing.sort_by_key(|h| h.target as usize / chunk_len);
            handovers[chunk]
                .set(outgoing)
                .unwrap_or_else(|_| unreachable!("each chunk publishes once"));
            (max_overlap, wall_contacts)
        };
        let share = &self.share;
        let arrays = forces
            .chunks_mut(chunk_len)
            .zip(torques.chunks_mut(chunk_len))
            .zip(self.wall_history.chunks_mut(chunk_len * wall_stride))
            .zip(self.contacts.chunks_mut(chunk_len))
            .zip(entry_chunks)
            .zip(self.wall_touching.chunks_mut(chunk_len))
            .zip(self.wall_candidates.chunks(chunk_len))
            .map(
                |(
                    (((((forces, torques), wall_histories), counts), entry), touching),
                    candidates,
                )| {
                    ChunkArrays {
                        forces,
                        torques,
                        wall_histories,
                        counts,
                        entry,
                        touching,
                        candidates,
                    }
                },
            );
        let slots: Vec<Mutex<Option<ChunkArrays>>> =
            arrays.map(|chunk| Mutex::new(Some(chunk))).collect();
        let threads = share.threads();
        let claims: Vec<RunClaims> = (0..threads)
            .map(|t| RunClaims::new(share.chunks_of(t)))
            .collect();
        let team = self.team.of(threads);
        // The closing half kick of a complete chunk: every pair that reads
        // its grains' velocities has been evaluated by then (its own pairs
        // in this chunk, those with lower partners in the chunks it
        // received from, which published after evaluating them).
        let kick = |chunk: usize, forces: &[Vec3], torques: &[Vec3]| -> bool {
            let Some(half_dt) = closing_kick else {
                return false;
            };
            let first = chunk * chunk_len;
            // SAFETY: as above, no pair of this pass reads these grains
            // any more, and only this thread holds the chunk.
            unsafe { velocities.kick(first, forces, torques, half_dt, p) }
        };
        let thread_results = team.run_parts((0..threads).collect(), |thread, _| {
            let mut max_overlap: f64 = 0.0;
            let mut wall_contacts = 0;
            let mut listed = 0;
            let mut non_finite = false;
            // (chunk, seconds of its evaluation, intake and kick).
            let mut seconds: Vec<(usize, f64)> = Vec::new();
            let mut waiting: Vec<(usize, ChunkArrays)> = Vec::new();
            // An evaluated chunk takes in its hand-overs and is kicked as
            // soon as its sources have published: at once when this thread
            // evaluated them, while the chunk is still in cache; between
            // this thread's later chunks when another thread holds them.
            // Its intake and kick count in its chunk's time (the wait does
            // not): left out, they would load the later runs beyond the
            // balance.
            let take_in = |chunk: usize, arrays: ChunkArrays, seconds: &mut Vec<(usize, f64)>| {
                let start = Instant::now();
                let count = receive_handovers(
                    chunk,
                    chunk_len,
                    sources_of.of(chunk),
                    &handovers,
                    arrays.forces,
                    arrays.torques,
                    arrays.counts,
                );
                let kicked_non_finite = kick(chunk, arrays.forces, arrays.torques);
                seconds.push((chunk, start.elapsed().as_secs_f64()));
                (count, kicked_non_finite)
            };
            // The thread's own run from its front, then what is left of the
            // other runs from their backs (the next run's first): a thread
            // that a busy host has slowed down in this step hands its last
            // chunks to one that is done, and a run keeps its grains in its
            // thread's cache in every step where the threads keep pace.
            let victims = (1..threads).map(|k| (thread + k) % threads);
            let claimed =
                std::iter::from_fn(|| claims[thread].front()).chain(victims.flat_map(|victim| {
                    let claims = &claims[victim];
                    std::iter::from_fn(move || claims.back())
                }));
            for chunk in claimed {
                let mut arrays = slots[chunk]
                    .lock()
                    .expect("chunk")
                    .take()
                    .expect("each chunk is claimed once");
                let start = Instant::now();
                let (overlap, walls) = evaluate(chunk, &mut arrays);
                // The chunk has published its hand-overs: wake a thread
                // blocked for them.
                team.notify();
                max_overlap = max_overlap.max(overlap);
                wall_contacts += walls;
                seconds.push((chunk, start.elapsed().as_secs_f64()));
                waiting.push((chunk, arrays));
                let mut k = 0;
                while k < waiting.len() {
                    if all_published(sources_of.of(waiting[k].0), &handovers) {
                        let (ready, arrays) = waiting.remove(k);
                        let (count, bad) = take_in(ready, arrays, &mut seconds);
                        listed += count;
                        non_finite |= bad;
                    } else {
                        k += 1;
                    }
                }
            }
            // Every chunk is claimed: what still waits receives from chunks
            // that other threads are finishing.
            for (chunk, arrays) in waiting {
                team.wait(|| all_published(sources_of.of(chunk), &handovers));
                let (count, bad) = take_in(chunk, arrays, &mut seconds);
                listed += count;
                non_finite |= bad;
            }
            (max_overlap, wall_contacts, listed, non_finite, seconds)
        });
        let mut totals = PassTotals::default();
        for (overlap, walls, count, non_finite, seconds) in thread_results {
            totals.max_overlap_ratio = totals.max_overlap_ratio.max(overlap);
            totals.wall_contacts += walls;
            totals.listed_contacts += count;
            totals.non_finite |= non_finite;
            for (chunk, s) in seconds {
                self.share.record(chunk, s);
            }
        }
        totals
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

/// One grain read from a [`DemSystem::pack_grain`] message.
struct PackedGrain<'a> {
    state: &'a [f64],
    wall_touching: u64,
    wall_history: Vec<Vec3>,
    open: Vec<(u64, Vec3)>,
}

/// The grains of a message, in order.
struct PackedGrains<'a> {
    message: &'a [f64],
    at: usize,
    wall_stride: usize,
}

impl<'a> PackedGrains<'a> {
    fn new(message: &'a [f64], wall_stride: usize) -> Self {
        PackedGrains {
            message,
            at: 0,
            wall_stride,
        }
    }
}

impl<'a> Iterator for PackedGrains<'a> {
    type Item = PackedGrain<'a>;

    fn next(&mut self) -> Option<PackedGrain<'a>> {
        let m = self.message;
        let mut at = self.at;
        if at >= m.len() {
            return None;
        }
        let state = &m[at..at + PACKED_STATE];
        at += PACKED_STATE;
        let wall_touching = m[at].to_bits();
        at += 1;
        let wall_history = m[at..at + 3 * self.wall_stride]
            .chunks_exact(3)
            .map(|h| Vec3::new(h[0], h[1], h[2]))
            .collect();
        at += 3 * self.wall_stride;
        let contacts = m[at] as usize;
        at += 1;
        let open = m[at..at + 4 * contacts]
            .chunks_exact(4)
            .map(|c| (c[0].to_bits(), Vec3::new(c[1], c[2], c[3])))
            .collect();
        at += 4 * contacts;
        self.at = at;
        Some(PackedGrain {
            state,
            wall_touching,
            wall_history,
            open,
        })
    }
}

/// What a pair hands to its upper particle when a later chunk of the force
/// loop owns it.
#[derive(Clone, Copy, Debug)]
struct Handover {
    target: u32,
    touching: bool,
    /// Force on the lower particle (the target receives −force).
    force: Vec3,
    partner_torque: Vec3,
}

/// What the pairs of one chunk of the force loop hand to their upper
/// particles.
struct HandedOver {
    /// The chunk's particles, and the owned ones (`0..owned`).
    chunk: std::ops::Range<usize>,
    owned: usize,
    /// Sums for upper particles in the chunk (−F, the partner torque,
    /// contacts), indexed from the chunk's first particle.
    force: Vec<Vec3>,
    torque: Vec<Vec3>,
    count: Vec<u32>,
    /// Pairs whose upper particle a later chunk owns, in the order made.
    outgoing: Vec<Handover>,
}

impl HandedOver {
    fn new(chunk: std::ops::Range<usize>, owned: usize) -> Self {
        let len = chunk.len();
        HandedOver {
            chunk,
            owned,
            force: vec![Vec3::zeros(); len],
            torque: vec![Vec3::zeros(); len],
            count: vec![0; len],
            outgoing: Vec::new(),
        }
    }

    /// Sums a pair for its upper particle in the chunk, lists it for one a
    /// later chunk owns; drops it for a ghost (its owner evaluates the pair
    /// itself).
    #[inline]
    fn give(&mut self, handover: Handover) {
        let j = handover.target as usize;
        if j < self.chunk.end {
            let local = j - self.chunk.start;
            self.force[local] -= handover.force;
            self.torque[local] += handover.partner_torque;
            self.count[local] += u32::from(handover.touching);
        } else if j < self.owned {
            self.outgoing.push(handover);
        }
    }
}

/// Whether every chunk of `sources` has published its hand-over list.
fn all_published(sources: &[u32], handovers: &[OnceLock<Vec<Handover>>]) -> bool {
    sources
        .iter()
        .all(|&source| handovers[source as usize].get().is_some())
}

/// Per chunk of the force loop, the earlier chunks that hand over to it, in
/// increasing order (compressed rows).
#[derive(Clone, Debug)]
struct HandoverSources {
    offsets: Vec<usize>,
    chunks: Vec<u32>,
}

impl Default for HandoverSources {
    fn default() -> Self {
        HandoverSources {
            offsets: vec![0],
            chunks: Vec::new(),
        }
    }
}

impl HandoverSources {
    /// Number of chunks described.
    fn chunks(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The chunks that hand over to `chunk`.
    fn of(&self, chunk: usize) -> &[u32] {
        &self.chunks[self.offsets[chunk]..self.offsets[chunk + 1]]
    }
}

/// Adds to the particles of `chunk` what the chunks `sources` handed them,
/// in increasing chunk order and, within a chunk, in the order it made
/// them (increasing lower particle), once every source has published its
/// list; returns the chunk's (particle, contact) entries.
fn receive_handovers(
    chunk: usize,
    chunk_len: usize,
    sources: &[u32],
    handovers: &[OnceLock<Vec<Handover>>],
    forces: &mut [Vec3],
    torques: &mut [Vec3],
    counts: &mut [u32],
) -> usize {
    let first = chunk * chunk_len;
    for &source in sources {
        let list = handovers[source as usize]
            .get()
            .expect("every source has published its list");
        let start = list.partition_point(|h| (h.target as usize) < first);
        let stop = list.partition_point(|h| (h.target as usize) < first + forces.len());
        for h in &list[start..stop] {
            let local = h.target as usize - first;
            forces[local] -= h.force;
            torques[local] += h.partner_torque;
            counts[local] += u32::from(h.touching);
        }
    }
    // The chunk's counts are final now: summed here rather than in a pass
    // of their own.
    counts.iter().map(|&c| c as usize).sum()
}

/// What the passes of the force loop add up over the threads.
#[derive(Default)]
struct PassTotals {
    max_overlap_ratio: f64,
    wall_contacts: usize,
    /// (particle, contact) entries: each contact twice.
    listed_contacts: usize,
    /// A closing kick left a position or velocity not finite.
    non_finite: bool,
}

/// The velocities of all local grains during a force pass, which reads
/// them for any grain and kicks each chunk's grains once its forces are
/// complete (on the thread that completed it).
struct PassVelocities<'a> {
    linear: *mut Vec3,
    angular: *mut Vec3,
    len: usize,
    _arrays: std::marker::PhantomData<&'a mut [Vec3]>,
}

// SAFETY: grains are written only through `kick`, whose caller guarantees
// that no other thread reads them at the same time.
unsafe impl Sync for PassVelocities<'_> {}

impl<'a> PassVelocities<'a> {
    fn new(linear: &'a mut [Vec3], angular: &'a mut [Vec3]) -> Self {
        assert_eq!(
            linear.len(),
            angular.len(),
            "one angular velocity per grain"
        );
        PassVelocities {
            linear: linear.as_mut_ptr(),
            angular: angular.as_mut_ptr(),
            len: linear.len(),
            _arrays: std::marker::PhantomData,
        }
    }

    #[inline]
    fn linear(&self, i: usize) -> Vec3 {
        assert!(i < self.len);
        // SAFETY: in bounds; no grain is read while it is being kicked.
        unsafe { *self.linear.add(i) }
    }

    #[inline]
    fn angular(&self, i: usize) -> Vec3 {
        assert!(i < self.len);
        // SAFETY: as for `linear`.
        unsafe { *self.angular.add(i) }
    }

    /// Half kick of Δt/2 = `half_dt` of the grains from `first` on, one
    /// per force; returns whether a position or velocity is not finite.
    ///
    /// # Safety
    /// No other thread may read or write these grains' velocities during
    /// the call.
    unsafe fn kick(
        &self,
        first: usize,
        forces: &[Vec3],
        torques: &[Vec3],
        half_dt: f64,
        p: &Particles,
    ) -> bool {
        let end = first + forces.len();
        assert!(end <= self.len);
        // SAFETY: in bounds, and no other thread touches these grains
        // (the caller's promise).
        let (v, w) = unsafe {
            (
                std::slice::from_raw_parts_mut(self.linear.add(first), forces.len()),
                std::slice::from_raw_parts_mut(self.angular.add(first), forces.len()),
            )
        };
        let (inv_m, inv_i) = (&p.inverse_mass[first..end], &p.inverse_inertia[first..end]);
        let x = &p.position[first..end];
        let mut finite = true;
        for k in 0..v.len() {
            v[k] += half_dt * inv_m[k] * forces[k];
            w[k] += half_dt * inv_i[k] * torques[k];
            // A sum is finite only if every term is (short of overflowing,
            // which no sound state comes near).
            finite &= (x[k].sum() + v[k].sum()).is_finite();
        }
        !finite
    }
}

/// The arrays one chunk of the force loop writes.
struct ChunkArrays<'a> {
    forces: &'a mut [Vec3],
    torques: &'a mut [Vec3],
    wall_histories: &'a mut [Vec3],
    counts: &'a mut [u32],
    entry: EntryChunk<'a>,
    touching: &'a mut [u64],
    candidates: &'a [u64],
}

/// The per-entry arrays of one chunk of particles (pass 1 of the force
/// loop writes them for its own particles' entries only).
struct EntryChunk<'a> {
    history: &'a mut [Vec3],
    state: &'a mut [u8],
}

impl<'a> EntryChunk<'a> {
    /// Splits the per-entry arrays at the entries of every `chunk_len`
    /// particles.
    fn split(
        offsets: &[u32],
        n: usize,
        mut history: &'a mut [Vec3],
        mut state: &'a mut [u8],
        chunk_len: usize,
    ) -> Vec<EntryChunk<'a>> {
        let mut chunks = Vec::with_capacity(n / chunk_len + 1);
        for start in (0..n).step_by(chunk_len) {
            let end = (start + chunk_len).min(n);
            let len = (offsets[end] - offsets[start]) as usize;
            let (history_head, history_tail) = std::mem::take(&mut history).split_at_mut(len);
            let (state_head, state_tail) = std::mem::take(&mut state).split_at_mut(len);
            chunks.push(EntryChunk {
                history: history_head,
                state: state_head,
            });
            (history, state) = (history_tail, state_tail);
        }
        chunks
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
        let mut listed = BTreeSet::new();
        let mut entries = Vec::new();
        for i in 0..p.n_owned {
            for e in system.neighbours.range(i) {
                let j = system.neighbours.partner[e] as usize;
                entries.push((p.id[i], p.id[j]));
                listed.insert((p.id[i].min(p.id[j]), p.id[i].max(p.id[j])));
            }
        }
        // A full list: each pair from both sides, exactly once each.
        let unique: BTreeSet<(u64, u64)> = entries.iter().copied().collect();
        assert_eq!(unique.len(), entries.len());
        assert_eq!(entries.len(), 2 * listed.len());
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
    }
}

#[cfg(test)]
mod pair_evaluation_tests {
    use super::*;
    use crate::contact_law::{NormalCalibration, NormalStiffness};
    use rand::{Rng, SeedableRng};

    /// Grains poured into a box periodic along x (ghost pairs) with a floor,
    /// run long enough for rebuilds, reordering and sliding contacts. Each
    /// pair is evaluated once (pass 1) and handed to its partner (pass 2);
    /// the result must equal an independent evaluation of every contact
    /// from its owner's side with the carried history, and Newton's third
    /// law must hold exactly for pairs of owned grains.
    #[test]
    fn pairs_evaluated_once_match_an_evaluation_from_each_side() {
        let domain = Domain {
            dimension: Dimension::Three,
            lower: Vec3::zeros(),
            upper: Vec3::new(0.04, 0.04, 0.2),
            periodic: [true, false, false],
            gravity: Vec3::new(0.0, 0.0, -9.81),
        };
        let law = ContactLaw {
            normal: NormalStiffness::from_restitution(0.5, 1e-4, NormalCalibration::Exact),
            tangential_ratio: 0.2,
            friction: 0.5,
            rolling_friction: 0.05,
        };
        let walls = vec![
            PlaneWall {
                name: "floor".into(),
                point: Vec3::zeros(),
                normal: Vec3::z(),
                friction: 0.5,
                remove_at: None,
                two_sided: false,
            },
            PlaneWall {
                name: "front".into(),
                point: Vec3::zeros(),
                normal: Vec3::y(),
                friction: 0.5,
                remove_at: None,
                two_sided: false,
            },
            PlaneWall {
                name: "back".into(),
                point: Vec3::new(0.0, 0.04, 0.0),
                normal: -Vec3::y(),
                friction: 0.5,
                remove_at: None,
                two_sided: false,
            },
        ];
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let new: Vec<NewParticle> = (0..400)
            .map(|k| NewParticle {
                position: Vec3::new(
                    0.004 + 0.008 * (k % 5) as f64,
                    0.004 + 0.008 * ((k / 5) % 5) as f64,
                    0.004 + 0.008 * (k / 25) as f64,
                ),
                velocity: Vec3::new(rng.gen::<f64>() - 0.5, rng.gen::<f64>() - 0.5, 0.0) * 0.2,
                angular_velocity: Vec3::zeros(),
                radius: 0.0025 + 0.001 * rng.gen::<f64>(),
                density: 2500.0,
                fixed: false,
            })
            .collect();
        let mut system = DemSystem::new(domain, law, walls, 5e-4);
        system.add_particles(&new);
        let dt = 5e-6;
        for _ in 0..40_000 {
            system.step(dt);
        }
        assert!(
            system.neighbours.builds > 10,
            "{}",
            system.neighbours.builds
        );
        let diagnostics = system.compute_forces(0.0);
        assert!(diagnostics.particle_contacts > 300, "{diagnostics:?}");

        let p = &system.particles;
        let n = p.n_owned;
        let scale = (0..n).map(|i| p.force[i].norm()).fold(0.0, f64::max);
        let mut ghost_pairs = 0;
        for i in 0..n {
            let mut expected = p.mass[i] * system.domain.gravity;
            for (_, contact) in system.wall_contacts_of(i) {
                expected += contact.force;
            }
            for contact in system.particle_contacts_of(i) {
                expected += contact.force;
                ghost_pairs += usize::from(contact.partner >= n);
            }
            let error = (p.force[i] - expected).norm() / scale;
            assert!(
                error < 1e-12,
                "particle {i}: relative force error {error:e}"
            );
        }
        assert!(
            ghost_pairs > 0,
            "the scene must test pairs across the periodic edge"
        );
        // Third law: the owned grains' contact forces cancel exactly.
        let total: Vec3 = (0..n)
            .flat_map(|i| system.particle_contacts_of(i))
            .filter(|c| c.partner < n)
            .map(|c| c.force)
            .sum();
        assert!(total.norm() / scale < 1e-12, "{total:?}");

        // Shifting the scene along its periodic direction reorders the
        // grains at the next build (many pairs swap their upper and lower
        // sides): every open contact keeps its history, seen from each side.
        let histories = |system: &DemSystem| {
            let p = &system.particles;
            let mut seen = std::collections::BTreeMap::new();
            for i in 0..p.n_owned {
                for e in system.neighbours.range(i) {
                    let j = system.neighbours.partner[e] as usize;
                    let history = system.neighbours.history_of(e);
                    if history != Vec3::zeros() {
                        seen.insert((p.id[i], p.id[j]), (history, j >= p.n_owned));
                    }
                }
            }
            seen
        };
        let before = histories(&system);
        let order_before = system.particles.id.clone();
        for x in &mut system.particles.position {
            x.x += 0.4 * 0.04;
        }
        system.rebuild();
        assert_ne!(
            order_before, system.particles.id,
            "the shift must reorder the grains"
        );
        let after = histories(&system);
        assert!(before.len() > 300, "{}", before.len());
        assert_eq!(
            before.keys().collect::<Vec<_>>(),
            after.keys().collect::<Vec<_>>()
        );
        // Exact for pairs of owned grains; a pair across the periodic edge
        // is evaluated from both sides, whose branch vectors differ by the
        // round-off of adding the period (amplified in ξ by the projection
        // on the tangent plane).
        let mut exact = 0;
        for (pair, &(history, ghost_before)) in &before {
            let (moved, ghost_after) = after[pair];
            if !ghost_before && !ghost_after {
                assert_eq!(moved, history, "{pair:?}");
                exact += 1;
            } else {
                let error = (moved - history).norm() / history.norm();
                assert!(error < 1e-6, "{pair:?}: {history:?} became {moved:?}");
            }
        }
        assert!(exact > 200, "{exact}");
    }
}
