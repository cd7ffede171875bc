//! Rebuilding the neighbour list: migration between ranks, the locality
//! sort, ghosts and the pair list, carrying open contacts over.

use super::*;

impl DemSystem {
    /// Migration, locality sort, ghosts and pair list (collective).
    pub fn rebuild(&mut self) {
        // The old list, with the ids of all particles (owned and ghosts) it
        // refers to, carries the open contacts over to the new one.
        let previous = self.neighbours.take_previous(&self.particles);
        self.rebuild_from(previous);
    }

    /// [`DemSystem::rebuild`] carrying the open contacts of `previous`.
    pub(super) fn rebuild_from(&mut self, mut previous: PreviousList) {
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
    pub(super) fn pack_grain(&self, k: usize, open: &[(u64, Vec3)], message: &mut Vec<f64>) {
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
    pub(super) fn push_grain(&mut self, grain: &PackedGrain) -> Vec<(u64, Vec3)> {
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
}

/// One grain read from a [`DemSystem::pack_grain`] message.
pub(super) struct PackedGrain<'a> {
    pub(super) state: &'a [f64],
    pub(super) wall_touching: u64,
    pub(super) wall_history: Vec<Vec3>,
    pub(super) open: Vec<(u64, Vec3)>,
}

/// The grains of a message, in order.
pub(super) struct PackedGrains<'a> {
    pub(super) message: &'a [f64],
    pub(super) at: usize,
    pub(super) wall_stride: usize,
}

impl<'a> PackedGrains<'a> {
    pub(super) fn new(message: &'a [f64], wall_stride: usize) -> Self {
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
