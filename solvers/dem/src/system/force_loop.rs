//! The force loop: contact, wall and film forces over fixed chunks of
//! particles in two passes, each chunk kicked once its forces are complete
//! (see the module documentation of `system.rs`, step 3–4).

use super::handover::*;
use super::*;

impl DemSystem {
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
    pub(super) fn evaluate_forces(&mut self, history_dt: f64, film_dt: f64) -> StepDiagnostics {
        self.evaluate_forces_and_kick(history_dt, film_dt, None)
    }

    /// [`DemSystem::evaluate_forces`], then the closing half kick of
    /// `closing_kick` (Δt/2) if given, each chunk's as soon as its forces
    /// are complete (no pass of its own).
    pub(super) fn evaluate_forces_and_kick(
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
