//! What a checkpoint keeps of a DEM system: everything its next step reads,
//! so that a restored run continues bit for bit. The particles in their
//! order (owned, then ghosts), the pair list with its tangential histories,
//! the ghost stages, the wall histories and the counters; the scene's
//! settings (law, walls, gaps) come from the case, rebuilt on restore.
//!
//! A state saved on a rank restores on the same rank of a job of the same
//! size; on another number of ranks [`DemSystem::gathered`] and
//! [`DemSystem::adopt_grains`] carry the grains and their open contacts
//! instead (the pair list is rebuilt, so the sums of the next steps may
//! differ at round-off).

use super::rebuild::{PackedGrain, PackedGrains};
use super::DemSystem;
use crate::neighbours::PreviousList;
use crate::particles::Particles;
use crate::system::StepDiagnostics;
use grainflow_core::{State, StateError};

impl Particles {
    /// Every array of every particle, owned and ghosts, under `prefix`.
    pub fn save_state(&self, state: &mut State, prefix: &str) {
        let name = |field: &str| format!("{prefix}.{field}");
        state.put_usize(&name("n_owned"), self.n_owned);
        state.put_u64s(&name("id"), &self.id);
        state.put_u64s(&name("group"), &self.group);
        for (field, values) in [
            ("position", &self.position),
            ("velocity", &self.velocity),
            ("angular_velocity", &self.angular_velocity),
            ("force", &self.force),
            ("torque", &self.torque),
            ("external_force", &self.external_force),
            ("external_torque", &self.external_torque),
            ("dem_start_velocity", &self.dem_start_velocity),
            ("inner_fluid_momentum", &self.inner_fluid_momentum),
            (
                "inner_fluid_angular_momentum",
                &self.inner_fluid_angular_momentum,
            ),
        ] {
            state.put_vec3s(&name(field), values);
        }
        for (field, values) in [
            ("radius", &self.radius),
            ("mass", &self.mass),
            ("inverse_mass", &self.inverse_mass),
            ("inverse_inertia", &self.inverse_inertia),
        ] {
            state.put_f64s(&name(field), values);
        }
    }

    /// The particles saved by [`Particles::save_state`] under `prefix`.
    pub fn restore_state(state: &mut State, prefix: &str) -> Result<Particles, StateError> {
        let name = |field: &str| format!("{prefix}.{field}");
        let particles = Particles {
            n_owned: state.take_usize(&name("n_owned"))?,
            id: state.take_u64s(&name("id"))?,
            group: state.take_u64s(&name("group"))?,
            position: state.take_vec3s(&name("position"))?,
            velocity: state.take_vec3s(&name("velocity"))?,
            angular_velocity: state.take_vec3s(&name("angular_velocity"))?,
            radius: state.take_f64s(&name("radius"))?,
            mass: state.take_f64s(&name("mass"))?,
            inverse_mass: state.take_f64s(&name("inverse_mass"))?,
            inverse_inertia: state.take_f64s(&name("inverse_inertia"))?,
            force: state.take_vec3s(&name("force"))?,
            torque: state.take_vec3s(&name("torque"))?,
            external_force: state.take_vec3s(&name("external_force"))?,
            external_torque: state.take_vec3s(&name("external_torque"))?,
            dem_start_velocity: state.take_vec3s(&name("dem_start_velocity"))?,
            inner_fluid_momentum: state.take_vec3s(&name("inner_fluid_momentum"))?,
            inner_fluid_angular_momentum: state
                .take_vec3s(&name("inner_fluid_angular_momentum"))?,
        };
        let len = particles.id.len();
        let lengths = [
            particles.group.len(),
            particles.position.len(),
            particles.velocity.len(),
            particles.angular_velocity.len(),
            particles.radius.len(),
            particles.mass.len(),
            particles.inverse_mass.len(),
            particles.inverse_inertia.len(),
            particles.force.len(),
            particles.torque.len(),
            particles.external_force.len(),
            particles.external_torque.len(),
            particles.dem_start_velocity.len(),
            particles.inner_fluid_momentum.len(),
            particles.inner_fluid_angular_momentum.len(),
        ];
        if particles.n_owned > len || lengths.iter().any(|&l| l != len) {
            return Err(StateError(format!(
                "the particle arrays under {prefix} disagree in length"
            )));
        }
        Ok(particles)
    }
}

/// The step diagnostics as four numbers.
fn diagnostics_to_numbers(d: &StepDiagnostics) -> [f64; 4] {
    [
        d.max_overlap_ratio,
        d.particle_contacts as f64,
        d.wall_contacts as f64,
        f64::from(u8::from(d.non_finite)),
    ]
}

impl DemSystem {
    /// Saves everything the next step reads under `dem.` (collective only
    /// in that every rank saves its own share).
    pub fn save_state(&self, state: &mut State) {
        self.particles.save_state(state, "dem.particles");
        let list = &self.neighbours;
        state.put_f64s("dem.list.skin_gap", &[list.skin, list.gap]);
        state.put_u32s("dem.list.offsets", &list.offsets);
        state.put_u32s("dem.list.partner", &list.partner);
        state.put_u32s("dem.list.upper_start", &list.upper_start);
        state.put_u32s("dem.list.mirror", &list.mirror);
        state.put_vec3s("dem.list.history", &list.history);
        state.put_u8s("dem.list.state", &list.state);
        state.put_vec3s("dem.list.reference_position", &list.reference_position);
        state.put_u64("dem.list.builds", list.builds);
        self.ghosts.save_state(state, "dem.ghosts");
        state.put_vec3s("dem.wall_history", &self.wall_history);
        state.put_u64s("dem.wall_touching", &self.wall_touching);
        state.put_u64s("dem.wall_candidates", &self.wall_candidates);
        state.put_u32s("dem.contacts", &self.contacts);
        state.put_f64s(
            "dem.scalars",
            &[self.film_dt, self.max_radius, self.time, self.ghost_reach],
        );
        state.put_u64s(
            "dem.counters",
            &[self.steps, self.next_id, u64::from(self.external_loads)],
        );
        state.put_f64s("dem.last", &diagnostics_to_numbers(&self.last));
    }

    /// Takes back what [`DemSystem::save_state`] saved, into a system built
    /// from the same case on a rank of a job of the same size.
    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        let particles = Particles::restore_state(state, "dem.particles")?;
        let n = particles.n_owned;
        let stride = self.wall_stride();
        let skin_gap = state.take_f64s("dem.list.skin_gap")?;
        let [skin, gap] = skin_gap[..] else {
            return Err(StateError("dem.list.skin_gap holds two numbers".into()));
        };
        if skin != self.neighbours.skin {
            return Err(StateError(format!(
                "the pair list's skin was {skin:e} m, the case now gives {:e} m",
                self.neighbours.skin
            )));
        }
        let list = &mut self.neighbours;
        list.gap = gap;
        list.offsets = state.take_u32s("dem.list.offsets")?;
        list.partner = state.take_u32s("dem.list.partner")?;
        list.upper_start = state.take_u32s("dem.list.upper_start")?;
        list.mirror = state.take_u32s("dem.list.mirror")?;
        list.history = state.take_vec3s("dem.list.history")?;
        list.state = state.take_u8s("dem.list.state")?;
        list.reference_position = state.take_vec3s("dem.list.reference_position")?;
        list.builds = state.take_u64("dem.list.builds")?;
        let consistent = list.offsets.len() == n + 1
            && list.upper_start.len() == n
            && list.offsets.last().map(|&l| l as usize) == Some(list.partner.len())
            && list.mirror.len() == list.partner.len()
            && list.history.len() == list.partner.len()
            && list.state.len() == list.partner.len()
            && list.reference_position.len() == n
            && list.partner.iter().all(|&j| (j as usize) < particles.len());
        if !consistent {
            return Err(StateError(
                "the saved pair list does not fit the saved particles".into(),
            ));
        }
        self.ghosts
            .restore_state(state, "dem.ghosts", n, particles.len())?;
        self.wall_history = state.take_vec3s("dem.wall_history")?;
        self.wall_touching = state.take_u64s("dem.wall_touching")?;
        self.wall_candidates = state.take_u64s("dem.wall_candidates")?;
        self.contacts = state.take_u32s("dem.contacts")?;
        if self.wall_history.len() != n * stride
            || self.wall_touching.len() != n
            || self.wall_candidates.len() != n
        {
            return Err(StateError(
                "the saved wall histories do not fit the saved particles and the case's walls"
                    .into(),
            ));
        }
        let scalars = state.take_f64s("dem.scalars")?;
        let [film_dt, max_radius, time, ghost_reach] = scalars[..] else {
            return Err(StateError("dem.scalars holds four numbers".into()));
        };
        let counters = state.take_u64s("dem.counters")?;
        let [steps, next_id, external_loads] = counters[..] else {
            return Err(StateError("dem.counters holds three numbers".into()));
        };
        let last = state.take_f64s("dem.last")?;
        let [overlap, particle_contacts, wall_contacts, non_finite] = last[..] else {
            return Err(StateError("dem.last holds four numbers".into()));
        };
        self.particles = particles;
        self.film_dt = film_dt;
        self.max_radius = max_radius;
        self.time = time;
        self.ghost_reach = ghost_reach;
        self.steps = steps;
        self.next_id = next_id;
        self.external_loads = external_loads != 0;
        self.last = StepDiagnostics {
            max_overlap_ratio: overlap,
            particle_contacts: particle_contacts as usize,
            wall_contacts: wall_contacts as usize,
            non_finite: non_finite != 0.0,
        };
        // Derived from the pair list at its next use.
        self.handover_sources = (u64::MAX, Default::default());
        Ok(())
    }
}

impl DemSystem {
    /// Takes back the grains of the states `states` saved on the ranks of a
    /// job of another size (every old rank's state, read by every rank):
    /// each rank keeps the grains its subdomain owns, with their contact
    /// and wall histories, and rebuilds its pair list and ghosts
    /// (collective). The sums of the next steps run in another order, so
    /// the run continues within round-off of the one that wrote them.
    pub fn restore_redistributed(&mut self, states: &mut [State]) -> Result<(), StateError> {
        let stride = self.wall_stride();
        let mut message = Vec::new();
        let mut open = Vec::new();
        let mut scalars = None;
        for state in states.iter_mut() {
            let mut old = DemSystem::new(
                self.domain.clone(),
                self.law,
                self.walls.clone(),
                self.neighbours.skin,
            );
            old.lubrication = self.lubrication;
            old.restore_state(state)?;
            for k in 0..old.particles.n_owned {
                old.neighbours.open_contacts(k, &old.particles, &mut open);
                old.pack_grain(k, &open, &mut message);
            }
            scalars = Some((
                old.time,
                old.steps,
                old.next_id,
                old.film_dt,
                old.external_loads,
                old.last,
                old.ghost_reach,
            ));
        }
        let Some((time, steps, next_id, film_dt, external_loads, last, ghost_reach)) = scalars
        else {
            return Err(StateError("no saved state to take the grains from".into()));
        };
        let mut grains: Vec<PackedGrain> = PackedGrains::new(&message, stride)
            .filter(|g| {
                let centre = grainflow_core::Vec3::new(g.state[1], g.state[2], g.state[3]);
                self.subdomain.owns(&self.domain, &centre)
            })
            .collect();
        grains.sort_by_key(|g| g.state[0].to_bits());
        self.particles = Particles::default();
        self.wall_touching.clear();
        self.wall_history.clear();
        self.wall_candidates.clear();
        self.contacts.clear();
        self.time = time;
        self.steps = steps;
        self.next_id = next_id;
        self.film_dt = film_dt;
        self.external_loads = external_loads;
        self.ghost_reach = ghost_reach;
        let adopted: Vec<Vec<(u64, grainflow_core::Vec3)>> =
            grains.iter().map(|g| self.push_grain(g)).collect();
        let mut previous = PreviousList::default();
        previous.retain_and_adopt(&[], &adopted);
        self.handover_sources = (u64::MAX, Default::default());
        self.rebuild_from(previous);
        self.last = last;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact_law::{ContactLaw, NormalCalibration, NormalStiffness};
    use crate::particles::NewParticle;
    use crate::walls::PlaneWall;
    use grainflow_core::{Dimension, Domain, Vec3};
    use rand::{Rng, SeedableRng};

    /// 400 frictional spheres poured into a box periodic along x and y,
    /// onto a floor: contacts open and close, histories build up, the pair
    /// list is rebuilt on the way.
    fn pile() -> DemSystem {
        let domain = Domain {
            dimension: Dimension::Three,
            lower: Vec3::zeros(),
            upper: Vec3::new(0.04, 0.04, 0.2),
            periodic: [true, true, false],
            gravity: Vec3::new(0.0, 0.0, -9.81),
        };
        let law = ContactLaw {
            normal: NormalStiffness::from_restitution(0.5, 4e-4, NormalCalibration::Exact),
            tangential_ratio: 0.2,
            friction: 0.5,
            rolling_friction: 0.0,
        };
        let floor = PlaneWall {
            name: "floor".into(),
            point: Vec3::zeros(),
            normal: Vec3::new(0.0, 0.0, 1.0),
            friction: 0.5,
            remove_at: None,
            two_sided: false,
        };
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        // 8 x 8 grains per layer, 7 layers, jittered, falling onto the floor.
        let new: Vec<NewParticle> = (0..448)
            .map(|k| NewParticle {
                position: Vec3::new(
                    0.0025 + 0.005 * (k % 8) as f64 + 4e-4 * (rng.gen::<f64>() - 0.5),
                    0.0025 + 0.005 * (k / 8 % 8) as f64 + 4e-4 * (rng.gen::<f64>() - 0.5),
                    0.003 + 0.0045 * (k / 64) as f64,
                ),
                velocity: Vec3::new(0.1 * (rng.gen::<f64>() - 0.5), 0.0, -0.5),
                angular_velocity: Vec3::zeros(),
                radius: 0.0015 + 0.0005 * rng.gen::<f64>(),
                density: 2500.0,
                fixed: false,
            })
            .collect();
        let mut system = DemSystem::new(domain, law, vec![floor], 4e-4);
        system.add_particles(&new);
        system
    }

    fn bits(v: &[Vec3]) -> Vec<[u64; 3]> {
        v.iter()
            .map(|x| [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()])
            .collect()
    }

    #[test]
    fn a_restored_pile_continues_bit_for_bit() {
        let dt = 8e-6;
        let mut whole = pile();
        let mut first = pile();
        for _ in 0..4000 {
            whole.step(dt);
            first.step(dt);
        }
        let mut saved = State::new();
        first.save_state(&mut saved);
        let mut state = State::decode(&saved.encode()).unwrap();
        let mut resumed = pile();
        resumed.restore_state(&mut state).unwrap();
        assert_eq!(state.names().count(), 0, "every section is taken");
        for _ in 0..4000 {
            whole.step(dt);
            resumed.step(dt);
        }
        assert!(whole.neighbours.builds > 2 && whole.last.particle_contacts > 100);
        let (a, b) = (&whole.particles, &resumed.particles);
        assert_eq!(a.id, b.id);
        assert_eq!(bits(&a.position), bits(&b.position));
        assert_eq!(bits(&a.velocity), bits(&b.velocity));
        assert_eq!(bits(&a.angular_velocity), bits(&b.angular_velocity));
        assert_eq!(
            bits(&whole.neighbours.history),
            bits(&resumed.neighbours.history)
        );
        assert_eq!(bits(&whole.wall_history), bits(&resumed.wall_history));
        assert_eq!(whole.steps, resumed.steps);
        assert_eq!(whole.time.to_bits(), resumed.time.to_bits());
    }

    #[test]
    fn grains_taken_from_saved_states_continue_within_round_off() {
        let dt = 8e-6;
        let mut whole = pile();
        for _ in 0..4000 {
            whole.step(dt);
        }
        let mut saved = State::new();
        whole.save_state(&mut saved);
        let mut resumed = pile();
        resumed
            .restore_redistributed(std::slice::from_mut(&mut saved))
            .unwrap();
        assert_eq!(resumed.particles.n_owned, whole.particles.n_owned);
        assert!(resumed.neighbours.history.iter().any(|h| h.norm() > 0.0));
        for _ in 0..200 {
            whole.step(dt);
            resumed.step(dt);
        }
        let mut largest: f64 = 0.0;
        for k in 0..whole.particles.n_owned {
            let j = resumed.index_of(whole.particles.id[k]).unwrap();
            let d = whole.particles.position[k] - resumed.particles.position[j];
            largest = largest.max(d.norm() / whole.particles.radius[k]);
        }
        assert!(largest < 1e-10, "positions differ by {largest:e} radii");
        assert_eq!(whole.steps, resumed.steps);
    }

    #[test]
    fn a_state_of_another_scene_is_refused_with_a_reason() {
        let mut first = pile();
        first.step(1e-6);
        let mut saved = State::new();
        first.save_state(&mut saved);
        // A second wall: the wall histories no longer fit.
        let mut walls = first.walls.clone();
        walls.push(PlaneWall {
            name: "ceiling".into(),
            point: Vec3::new(0.0, 0.0, 0.2),
            normal: Vec3::new(0.0, 0.0, -1.0),
            friction: 0.5,
            remove_at: None,
            two_sided: false,
        });
        let mut other = DemSystem::new(
            first.domain.clone(),
            first.law,
            walls,
            first.neighbours.skin,
        );
        let error = other.restore_state(&mut saved).unwrap_err();
        assert!(error.0.contains("wall"), "{error}");
    }
}
