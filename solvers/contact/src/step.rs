//! One hard-contact time step over a [`DemSystem`]'s grains, walls and
//! pair list (Martin et al. 2022, eq. 5–9):
//! 1. U = u^k + Δt M⁻¹ f_ext for every grain (gravity, external loads);
//! 2. candidates: gaps below the threshold D, widened to what the fastest
//!    grains can close within the step (the list is rebuilt if it does not
//!    reach that far);
//! 3. u^{k+1} and the impulses: COCD or NSCD;
//! 4. the contact law's residual at the solution;
//! 5. c^{k+1} = c^k + Δt v^{k+1}; the largest overlap after the move.
//!
//! On several ranks each rank holds its own pairs: NSCD sweeps them, the
//! copies of its grains kept in step ([`crate::sharing`]); COCD solves one
//! program over all ranks' pairs together ([`crate::shared_program`]).
//! Every test and figure of the step is taken over all ranks.

use crate::candidates::{self, LeftOutLaw};
use crate::certificate;
use crate::cocd::{self, ConicSolver, Solution};
use crate::contacts::{self, Bodies, ContactSet, Partner, Scales};
use crate::nscd;
use crate::sharing::Sharing;
use grainflow_core::Vec3;
use grainflow_dem::{DemSystem, StepDiagnostics};
use std::collections::HashMap;
use std::time::Instant;

/// The scheme and its parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Convex optimization contact dynamics (inelastic).
    Cocd,
    /// Non-smooth contact dynamics with Newton's restitution e.
    Nscd { restitution: f64 },
}

/// What one step did and how well its contact law holds.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepReport {
    /// Candidate contacts in the program and those that carry a force.
    pub candidates: usize,
    /// Programs solved: more than one where a pair left out would have
    /// overlapped ([`candidates`]).
    pub programs: u32,
    pub closed: usize,
    /// Interior-point iterations (COCD) or Gauss–Seidel sweeps (NSCD).
    pub iterations: u32,
    /// Whether the solver stopped short of the tolerance (COCD at reduced
    /// accuracy, NSCD at its sweep limit).
    pub unconverged: bool,
    /// Largest complementarity residual of the contact law and largest
    /// violation of Coulomb's cone (see [`certificate`]).
    pub complementarity: f64,
    pub coulomb_violation: f64,
    /// Largest overlap after the move over the mean diameter.
    pub penetration: f64,
    /// Whether Clarabel took over from grainflow's interior point.
    pub fell_back: bool,
    /// Candidate threshold used (m).
    pub threshold: f64,
    pub seconds_solve: f64,
    pub non_finite: bool,
}

/// Hard contact between the grains of a dry scene.
#[derive(Clone, Debug)]
pub struct HardContact {
    pub method: Method,
    /// ε: the solver's relative tolerance (COCD) or the residual at which
    /// Gauss–Seidel stops (NSCD).
    pub tolerance: f64,
    /// Interior-point iterations (COCD) or sweeps (NSCD) allowed per step.
    pub max_iterations: u32,
    /// Candidate threshold D on the gap, in m (section 3.3).
    pub threshold: f64,
    /// COCD: the interior-point code (Clarabel takes over a step that
    /// grainflow's fails).
    pub conic_solver: ConicSolver,
    /// COCD's projected gradient on several ranks: the bytes a rank can
    /// give the interior point's separator (its dense Schur complement)
    /// where the interior point would take over a step; a step that would
    /// need more stops the run instead (None: no bound).
    pub separator_room: Option<f64>,
    /// Every listed pair enters the program, instead of those within reach
    /// and the left-out ones that would break their law
    /// ([`candidates`]): the reference the selection is measured against.
    pub whole_list: bool,
    /// Why grainflow's interior point failed the last step Clarabel took
    /// over.
    pub last_fallback: Option<String>,
    /// The warm start of NSCD and of COCD's projected gradient: the
    /// impulses of the last step's contacts, by the ids of their grains
    /// (u64::MAX − wall for a wall).
    previous_impulses: HashMap<(u64, u64), (f64, Vec3)>,
}

impl HardContact {
    /// Saves the warm start NSCD carries from one step to the next (the
    /// last step's impulses by contact), sorted by contact so that the same
    /// state always saves the same bytes.
    pub fn save_state(&self, state: &mut grainflow_core::State) {
        let mut keys: Vec<&(u64, u64)> = self.previous_impulses.keys().collect();
        keys.sort_unstable();
        let pairs: Vec<u64> = keys.iter().flat_map(|&&(a, b)| [a, b]).collect();
        let impulses: Vec<f64> = keys
            .iter()
            .flat_map(|key| {
                let (normal, tangential) = self.previous_impulses[*key];
                [normal, tangential.x, tangential.y, tangential.z]
            })
            .collect();
        state.put_u64s("hard_contact.pairs", &pairs);
        state.put_f64s("hard_contact.impulses", &impulses);
    }

    /// Takes back what [`HardContact::save_state`] saved.
    pub fn restore_state(
        &mut self,
        state: &mut grainflow_core::State,
    ) -> Result<(), grainflow_core::StateError> {
        let pairs = state.take_u64s("hard_contact.pairs")?;
        let impulses = state.take_f64s("hard_contact.impulses")?;
        if pairs.len() % 2 != 0 || impulses.len() != 2 * pairs.len() {
            return Err(grainflow_core::StateError(
                "the saved hard-contact impulses do not match their contacts".into(),
            ));
        }
        self.previous_impulses = pairs
            .chunks_exact(2)
            .zip(impulses.chunks_exact(4))
            .map(|(p, i)| ((p[0], p[1]), (i[0], Vec3::new(i[1], i[2], i[3]))))
            .collect();
        Ok(())
    }

    pub fn new(method: Method, tolerance: f64, max_iterations: u32, threshold: f64) -> Self {
        HardContact {
            method,
            tolerance,
            max_iterations,
            threshold,
            conic_solver: ConicSolver::InteriorPoint,
            separator_room: None,
            whole_list: false,
            last_fallback: None,
            previous_impulses: HashMap::new(),
        }
    }

    /// Lists pairs within the threshold from now on (call before the first
    /// step, or the first step rebuilds the list).
    pub fn prepare(&self, system: &mut DemSystem) {
        if system.listing_gap < self.threshold {
            system.listing_gap = self.threshold;
            system.rebuild();
        }
    }

    /// Advances the grains by one step of size `dt`. An error names why the
    /// step could not be solved (the grains are left at the start of the
    /// step).
    pub fn step(&mut self, system: &mut DemSystem, dt: f64) -> Result<StepReport, String> {
        // 1. Free velocities, of every local grain (a copy: its grain's).
        let n = system.particles.n_owned;
        let local = system.particles.len();
        let shared = system.communicator.size() > 1;
        let gravity = system.domain.gravity;
        let (free_velocity, free_spin) = {
            let p = &system.particles;
            let mut velocity = Vec::with_capacity(local);
            let mut spin = Vec::with_capacity(local);
            for k in 0..n {
                velocity.push(if p.is_fixed(k) {
                    Vec3::zeros()
                } else {
                    p.velocity[k] + dt * (gravity + p.inverse_mass[k] * p.external_force[k])
                });
                spin.push(p.angular_velocity[k] + dt * p.inverse_inertia[k] * p.external_torque[k]);
            }
            velocity.resize(local, Vec3::zeros());
            spin.resize(local, Vec3::zeros());
            if let Some(sharing) = Sharing::of(system) {
                sharing.motion_onto_ghosts(&mut velocity, &mut spin);
            }
            (velocity, spin)
        };

        // 2. Candidates: a pair approaches by at most 2 v_max Δt within the
        // step; 1.5 for the speed the contacts themselves may add. The list
        // reaches that far; the program starts from the pairs their own
        // motion can close and takes in the others that would overlap.
        let fastest = free_velocity[..n]
            .iter()
            .map(|v| v.norm())
            .fold(0.0, f64::max);
        // Reductions over the ranks return the rank's own value on one.
        let fastest = system.communicator.max(fastest);
        let threshold = self.threshold.max(3.0 * fastest * dt);
        if threshold > system.neighbours.gap {
            system.listing_gap = 2.0 * threshold;
            system.rebuild();
            return self.step(system, dt);
        }
        let holder = match self.method {
            Method::Cocd if shared => contacts::CrossingPairs::LowerRank,
            _ => contacts::CrossingPairs::LowerId,
        };
        let listed = contacts::listed_held(system, threshold, holder);
        let mut in_program =
            candidates::within_reach(&listed, (&free_velocity, &free_spin), self.threshold, dt);
        if self.whole_list {
            in_program.fill(true);
        }
        let left_out_law = match self.method {
            Method::Cocd => LeftOutLaw::Cone { dt },
            Method::Nscd { restitution } => LeftOutLaw::Signorini { dt, restitution },
        };

        // 3. Solve, until no pair left out would overlap.
        let started = Instant::now();
        let mut programs = 0;
        let (contacts, scales, solution, bounds, unconverged, end_motion) = loop {
            programs += 1;
            let program = listed.subset(&in_program);
            // On several ranks, the bodies whose grain other ranks' pairs
            // reach too: the copies, and the owned grains touched elsewhere.
            let (contacts, bodies, scales, shared_bodies) = match Sharing::of(system) {
                Some(sharing) => {
                    let elsewhere = sharing.touched_elsewhere(&program);
                    let (contacts, bodies) = contacts::with_bodies_marked(
                        system,
                        program,
                        &free_velocity,
                        &free_spin,
                        &elsewhere,
                    );
                    let mut sums = Scales::partial(&bodies);
                    let fastest = sharing.max(sums[3]);
                    sums[3] = 0.0;
                    sharing.sum_each(&mut sums);
                    sums[3] = fastest;
                    let shared_bodies = (0..bodies.len())
                        .map(|b| b >= bodies.owned || elsewhere[bodies.grain[b] as usize])
                        .collect();
                    let scales = Scales::of_sums(sums, dt, &gravity);
                    (contacts, bodies, scales, shared_bodies)
                }
                None => {
                    let (contacts, bodies) =
                        contacts::with_bodies(system, program, &free_velocity, &free_spin);
                    let scales = Scales::of(&bodies, dt, &gravity);
                    (contacts, bodies, scales, Vec::new())
                }
            };
            let (solution, bounds, unconverged) =
                self.solve(system, &contacts, &bodies, &scales, dt, &shared_bodies)?;
            let mut end_motion =
                candidates::end_motion(system, &bodies, &solution, &free_velocity, &free_spin);
            end_motion.0.resize(local, Vec3::zeros());
            end_motion.1.resize(local, Vec3::zeros());
            if let Some(sharing) = Sharing::of(system) {
                sharing.motion_onto_ghosts(&mut end_motion.0, &mut end_motion.1);
            }
            let p = &system.particles;
            let broken = candidates::broken(
                &listed,
                &in_program,
                left_out_law,
                (&end_motion.0, &end_motion.1),
                (&p.velocity, &p.angular_velocity),
            );
            let any_broken = match Sharing::of(system) {
                Some(sharing) => sharing.any(!broken.is_empty()),
                None => !broken.is_empty(),
            };
            if !any_broken {
                break (contacts, scales, solution, bounds, unconverged, end_motion);
            }
            if candidates::take_the_whole_list(programs, &in_program) {
                in_program.fill(true);
            } else {
                let near = candidates::within_reach(
                    &listed,
                    (&end_motion.0, &end_motion.1),
                    self.threshold,
                    dt,
                );
                for (a, near) in near.into_iter().enumerate() {
                    in_program[a] |= near;
                }
                for a in broken {
                    in_program[a] = true;
                }
            }
        };
        let seconds_solve = started.elapsed().as_secs_f64();
        if solution.fallback_reason.is_some() {
            self.last_fallback = solution.fallback_reason.clone();
        }

        // 4. The contact law at the solution.
        let mut residual = certificate::contact_law_residual(
            &contacts,
            &scales,
            &bounds,
            &solution.velocity,
            &solution.spin,
            &solution.normal_impulse,
            &solution.tangential_impulse,
            matches!(self.method, Method::Nscd { .. }),
        );
        residual.complementarity = system.communicator.max(residual.complementarity);
        residual.coulomb = system.communicator.max(residual.coulomb);

        // End-of-step velocities; the force and torque written out are the
        // step's mean ones, m (u^{k+1} − u^k)/Δt (contacts and gravity).
        let p = &mut system.particles;
        let (end_velocity, end_spin) = end_motion;
        for k in 0..n {
            if p.is_fixed(k) {
                continue;
            }
            let (v, w) = (end_velocity[k], end_spin[k]);
            p.force[k] = p.mass[k] * (v - p.velocity[k]) / dt;
            p.torque[k] = (w - p.angular_velocity[k]) / (p.inverse_inertia[k] * dt);
            p.velocity[k] = v;
            p.angular_velocity[k] = w;
        }

        // Contacts that carry a force (for coordination and rest tests).
        let largest_impulse = solution.normal_impulse.iter().cloned().fold(0.0, f64::max);
        let largest_impulse = system.communicator.max(largest_impulse);
        let carries = |a: usize| solution.normal_impulse[a] > 1e-9 * largest_impulse;
        let mut particle_contacts = vec![0.0; local];
        let mut walls_touched = vec![0u64; n];
        let (mut closed, mut wall_contacts) = (0, 0);
        for a in (0..contacts.len()).filter(|&a| carries(a)) {
            closed += 1;
            let i = contacts.grain[a] as usize;
            match contacts.partner[a] {
                Partner::Grain(j) => {
                    particle_contacts[i] += 1.0;
                    particle_contacts[j as usize] += 1.0;
                }
                Partner::Wall(w) => {
                    walls_touched[i] |= 1u64 << w.min(63);
                    wall_contacts += 1;
                }
            }
        }
        if shared {
            system.sum_onto_owners(&mut particle_contacts, 1);
        }
        let closed = system.communicator.sum_count(closed);
        let wall_contacts = system.communicator.sum_count(wall_contacts);
        let particle_contacts = particle_contacts[..n].iter().map(|&c| c as u32).collect();
        system.record_contacts(particle_contacts, walls_touched);

        // 5. Move.
        let non_finite = system.drift(dt);
        let penetration = if non_finite {
            f64::NAN
        } else {
            system
                .communicator
                .max(certificate::largest_overlap(system, scales.length))
        };
        system.last = StepDiagnostics {
            max_overlap_ratio: 2.0 * penetration,
            particle_contacts: closed - wall_contacts,
            wall_contacts,
            non_finite,
        };
        Ok(StepReport {
            candidates: system.communicator.sum_count(contacts.len()),
            programs,
            closed,
            iterations: solution.iterations,
            unconverged,
            complementarity: residual.complementarity,
            coulomb_violation: residual.coulomb,
            penetration,
            fell_back: solution.fallback_reason.is_some(),
            threshold,
            seconds_solve,
            non_finite,
        })
    }

    /// One program over `contacts`: the solution, the normal bound b_α of
    /// each contact and whether the solver stopped short of its tolerance.
    /// `shared_bodies`: on several ranks, the bodies another rank's pairs
    /// reach too (empty on one).
    fn solve(
        &mut self,
        system: &DemSystem,
        contacts: &ContactSet,
        bodies: &Bodies,
        scales: &Scales,
        dt: f64,
        shared_bodies: &[bool],
    ) -> Result<(Solution, Vec<f64>, bool), String> {
        match self.method {
            Method::Cocd => {
                let bounds: Vec<f64> = contacts.gap.iter().map(|d| -d / dt).collect();
                // Reductions over the ranks return the rank's own value on one.
                let solution = if system.communicator.sum_count(contacts.len()) == 0 {
                    Solution {
                        velocity: bodies.free_velocity.clone(),
                        spin: bodies.free_spin.clone(),
                        ..Solution::default()
                    }
                } else {
                    let shared = (system.communicator.size() > 1).then(|| cocd::RankShare {
                        separator: shared_bodies,
                        ids: &system.particles.id,
                        communicator: &system.communicator,
                        separator_room: self.separator_room,
                    });
                    // The projected gradient starts from the last step's
                    // impulses (a packing at rest changes little between
                    // steps); the interior points start from their own.
                    let warm = self.conic_solver == ConicSolver::ProjectedGradient;
                    let start = warm.then(|| self.last_impulses(system, contacts));
                    let solution = cocd::solve(
                        contacts,
                        bodies,
                        system.dimension(),
                        scales,
                        self.tolerance,
                        self.max_iterations,
                        self.conic_solver,
                        shared,
                        start.as_deref(),
                    )?;
                    if warm {
                        self.keep_impulses(system, contacts, &solution);
                    }
                    solution
                };
                let reduced = solution.reduced_accuracy;
                Ok((solution, bounds, reduced))
            }
            Method::Nscd { restitution } => {
                let bounds = nscd::normal_bounds(contacts, bodies, dt, restitution);
                let initial = self.last_impulses(system, contacts);
                let (solution, converged) = nscd::solve(
                    contacts,
                    bodies,
                    scales,
                    &bounds,
                    &initial,
                    self.tolerance,
                    self.max_iterations,
                    Sharing::of(system).as_ref(),
                );
                self.keep_impulses(system, contacts, &solution);
                Ok((solution, bounds, !converged))
            }
        }
    }

    /// The impulses (normal, tangential on grain i) the last step left on
    /// each of `contacts`; zero on a new contact.
    fn last_impulses(&self, system: &DemSystem, contacts: &ContactSet) -> Vec<(f64, Vec3)> {
        let ids = &system.particles.id;
        (0..contacts.len())
            .map(|a| {
                let (key, sign) = pair_key(ids, contacts.grain[a], contacts.partner[a]);
                self.previous_impulses
                    .get(&key)
                    .map_or((0.0, Vec3::zeros()), |&(p_n, p_t)| (p_n, sign * p_t))
            })
            .collect()
    }

    /// Keeps the impulses of the contacts of `solution` that carry one,
    /// for the next step's start.
    fn keep_impulses(&mut self, system: &DemSystem, contacts: &ContactSet, solution: &Solution) {
        let ids = &system.particles.id;
        self.previous_impulses = (0..contacts.len())
            .filter(|&a| solution.normal_impulse[a] > 0.0)
            .map(|a| {
                let (key, sign) = pair_key(ids, contacts.grain[a], contacts.partner[a]);
                let impulses = (
                    solution.normal_impulse[a],
                    sign * solution.tangential_impulse[a],
                );
                (key, impulses)
            })
            .collect();
    }
}

/// Identity of a contact that survives reordering: the ids of its grains,
/// lower first, or of its grain and wall; and the sign that turns an
/// impulse on grain i into one on the grain of lower id.
fn pair_key(ids: &[u64], grain: u32, partner: Partner) -> ((u64, u64), f64) {
    let i = ids[grain as usize];
    match partner {
        Partner::Grain(j) => {
            let j = ids[j as usize];
            ((i.min(j), i.max(j)), if i <= j { 1.0 } else { -1.0 })
        }
        Partner::Wall(w) => ((i, u64::MAX - w as u64), 1.0),
    }
}
