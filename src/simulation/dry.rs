//! A dry scene: grains alone, no fluid grid. Each step advances the grains
//! (soft DEM or hard contact, [`DryStepper`]), feeds the analyses, releases
//! the pours that are due and notes the walls taken away.

use super::dry_stepper::DryStepper;
use crate::analysis::Analysis;
use crate::case::Case;
use crate::stability::{self, TimeStepVerdict};
use crate::{scene, scene::pouring, sharing, RunError};
use grainflow_core::{Communicator, State, StateError};
use grainflow_dem::threads::{self, choose_threads, ThreadChoice};
use grainflow_dem::DemSystem;
use serde_json::{json, Map, Value};
use std::path::Path;

/// The shortest binary contact time of the scene: that of the lightest
/// moving pair (the lightest particle of all if none moves).
pub fn shortest_contact_time(system: &DemSystem) -> f64 {
    let p = &system.particles;
    // Over every rank, so that all take the same step.
    let c = &system.communicator;
    let global_min = |local: f64| -c.max(-local);
    let mobile = (0..p.n_owned)
        .filter(|&k| !p.is_fixed(k))
        .map(|k| p.mass[k])
        .fold(f64::MAX, f64::min);
    let mut lightest = global_min(mobile);
    if lightest == f64::MAX {
        lightest = global_min(p.mass[..p.n_owned].iter().cloned().fold(f64::MAX, f64::min));
    }
    stability::shortest_contact_time(&system.law, lightest)
}

/// The time step of a case and the scene's shortest contact time.
pub fn time_step(case: &Case, system: &DemSystem) -> (f64, f64) {
    let contact_time = shortest_contact_time(system);
    let dt = match (case.time.dt, case.time.dt_over_contact_time) {
        (Some(dt), _) => dt,
        (None, Some(f)) => f * contact_time,
        (None, None) => 0.02 * contact_time,
    };
    (dt, contact_time)
}

/// Refuses a time step past the stability limit (before anything is
/// written); returns a warning past the accuracy limit.
pub fn check_time_step(dt: f64, contact_time: f64) -> Result<Option<String>, RunError> {
    let ratio = dt / contact_time;
    match stability::verdict(ratio) {
        TimeStepVerdict::Unstable => Err(RunError::Case(format!(
            "time step dt = {dt:.3e} s is {ratio:.3} t_c (t_c = {contact_time:.3e} s): past the stability limit \
             dt/t_c ≤ {} of the explicit contact integration; allowed: time.dt ≤ {:.3e} s, \
             time.dt_over_contact_time ≤ {} (default 0.02)",
            stability::STABLE_DT_OVER_TC,
            stability::STABLE_DT_OVER_TC * contact_time,
            stability::STABLE_DT_OVER_TC
        ))),
        TimeStepVerdict::Inaccurate => Ok(Some(format!(
            "warning: dt = {ratio:.3} t_c exceeds {}: restitution errors above 1 % (use dt ≤ {:.3e} s)",
            stability::ACCURATE_DT_OVER_TC,
            stability::ACCURATE_DT_OVER_TC * contact_time
        ))),
        TimeStepVerdict::Accurate => Ok(None),
    }
}

pub struct DryModel {
    pub system: DemSystem,
    stepper: DryStepper,
    dt: f64,
    pouring: pouring::Pouring,
    analysis: Analysis,
    /// On several ranks the analyses run on the root over the gathered
    /// grains, gathered only at the steps they record.
    distributed: bool,
    analysed: bool,
    /// Whether the grains have moved faster than the rest speed yet.
    moving: bool,
    rest_after: f64,
    rest_speed: Option<f64>,
    overlap_limit: f64,
    /// Whether each wall is still there.
    wall_present: Vec<bool>,
    /// Grains over all ranks, and grain-steps so far.
    particles: usize,
    particle_steps: f64,
    pub threads: ThreadChoice,
    /// The lines for the log at the start.
    pub description: Vec<String>,
    pub warnings: Vec<String>,
}

impl DryModel {
    /// The scene of a case without a fluid. Refuses (before anything is
    /// written) a soft time step past the stability limit.
    pub fn build(case: &Case, communicator: Communicator) -> Result<Self, RunError> {
        let mut system = scene::build_on(case, communicator.clone()).map_err(RunError::Case)?;
        let (pouring, pour_log) = pouring::start(case, &mut system).map_err(RunError::Case)?;
        let threads = dry_threads(case, &system, &pouring);
        let (stepper, dt, stepper_warnings) = DryStepper::new(case, &mut system)?;
        let p = &system.particles;
        let particles = communicator.sum_count(p.n_owned);
        let glued = communicator.sum_count((0..p.n_owned).filter(|&k| p.is_fixed(k)).count());
        let to_pour = match pouring.remaining() {
            0 => String::new(),
            n => format!(", {n} more to be poured"),
        };
        let mut description = vec![format!(
            "grainflow {}: {particles} particles ({glued} glued{to_pour}), {}D, dry scene (no fluid grid)",
            env!("CARGO_PKG_VERSION"),
            system.domain.dimension.count()
        )];
        description.extend(pour_log);
        description.push(format!("threads: {} ({})", threads.threads, threads.why));
        let mut warnings = Vec::new();
        let ranks = communicator.size();
        if ranks > 1 {
            let s = &system.subdomain;
            let cuts = grainflow_core::describe_cuts(&s.cuts);
            description.push(format!(
                "{ranks} MPI ranks in a process grid of {} x {} x {}{}",
                s.ranks[0],
                s.ranks[1],
                s.ranks[2],
                if cuts.is_empty() {
                    String::new()
                } else {
                    format!(", boxes cut among the grains for equal interiors: {cuts}")
                }
            ));
            warnings.extend(sharing::load_warning(
                ranks,
                sharing::grains_judged(case, particles as f64 / ranks as f64),
                None,
            ));
        }
        description.push(stepper.describe(dt));
        warnings.extend(stepper_warnings);

        let last_removal = system
            .walls
            .iter()
            .filter_map(|w| w.remove_at)
            .fold(0.0, f64::max);
        let distributed = ranks > 1;
        let analysed = case.analysis.is_some();
        let analysis = if !distributed {
            Analysis::new(case.analysis.as_ref(), &system)
        } else if analysed {
            match system.gathered() {
                Some(whole) => Analysis::new(case.analysis.as_ref(), &whole),
                None => Analysis::None,
            }
        } else {
            Analysis::None
        };
        let wall_present = system.walls.iter().map(|w| w.is_present(0.0)).collect();
        Ok(DryModel {
            system,
            stepper,
            dt,
            pouring,
            analysis,
            distributed,
            analysed,
            moving: false,
            rest_after: case.time.rest_after.unwrap_or(last_removal),
            rest_speed: case.time.rest_speed,
            overlap_limit: case.time.overlap_limit,
            wall_present,
            particles,
            particle_steps: 0.0,
            threads,
            description,
            warnings,
        })
    }

    /// The pours and how far they have gone.
    pub fn pouring(&self) -> &pouring::Pouring {
        &self.pouring
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }

    pub fn reached(&self, end: f64) -> bool {
        self.system.time >= end - 0.5 * self.dt
    }

    /// One step; log lines (pours released, walls removed), or the
    /// diagnosis of a failure.
    pub fn advance(&mut self) -> Result<Vec<String>, String> {
        let mut lines = Vec::new();
        let failure = self
            .stepper
            .step(&mut self.system, self.dt, self.overlap_limit);
        if failure.is_none() {
            if !self.distributed {
                self.analysis.after_step(&self.system);
            } else if self.analysed
                && self
                    .system
                    .communicator
                    .any(self.analysis.wants_grains(self.system.time))
            {
                if let Some(whole) = self.system.gathered() {
                    self.analysis.after_step(&whole);
                }
            }
        }
        let failure = match failure {
            None if !self.pouring.is_done() => match self.pouring.release_due(&mut self.system) {
                Ok(released) => {
                    if !released.is_empty() {
                        self.particles = self
                            .system
                            .communicator
                            .sum_count(self.system.particles.n_owned);
                    }
                    lines.extend(released);
                    None
                }
                Err(why) => Some(why),
            },
            other => other,
        };
        self.particle_steps += self.particles as f64;
        if let Some(why) = failure {
            return Err(why);
        }
        for (k, wall) in self.system.walls.iter().enumerate() {
            let present = wall.is_present(self.system.time);
            if present != self.wall_present[k] {
                self.wall_present[k] = present;
                lines.push(format!(
                    "t = {:.6e} s: wall {} removed",
                    self.system.time, wall.name
                ));
            }
        }
        Ok(lines)
    }

    /// Whether the grains are at rest: after `time.rest_after` and the last
    /// batch of a pour, once they have moved faster than `time.rest_speed`
    /// and then slowed below it.
    pub fn at_rest(&mut self) -> Option<String> {
        let v = self.rest_speed?;
        if self.system.time < self.rest_after || !self.pouring.is_done() {
            return None;
        }
        let speed = rms_speed(&self.system);
        self.moving |= speed > v;
        (self.moving && speed < v).then(|| format!("at rest: rms particle speed below {v} m/s"))
    }

    /// The metrics of the analyses (their files written) and of hard
    /// contact, and `final_particles.csv` (collective).
    pub fn finish(&self, out: &Path, failed: bool) -> std::io::Result<Map<String, Value>> {
        let mut metrics = Map::new();
        if !failed {
            metrics = if !self.distributed {
                self.analysis.finish(&self.system, out)?
            } else if let Some(whole) = self.analysed.then(|| self.system.gathered()).flatten() {
                self.analysis.finish(&whole, out)?
            } else {
                Map::new()
            };
            crate::output::grains::write_final_particles(out, &self.system)?;
        }
        metrics.extend(self.stepper.metrics());
        Ok(metrics)
    }

    /// The scene's own entries of `summary.json`.
    pub fn summary(&self, case: &Case, wall_seconds: f64) -> Map<String, Value> {
        let mut summary = Map::new();
        for (key, value) in [
            ("particles", json!(self.particles)),
            ("dimension", json!(self.system.domain.dimension.count())),
            ("dt", json!(self.dt)),
            ("contact_model", json!(case.contact_section().model)),
            ("contact_time", json!(self.stepper.contact_time())),
            (
                "particle_steps_per_second",
                json!(self.particle_steps / wall_seconds),
            ),
            ("neighbour_builds", json!(self.system.neighbours.builds)),
        ] {
            summary.insert(key.into(), value);
        }
        summary
    }

    /// The last line of the log.
    pub fn done_line(&self, wall_seconds: f64) -> String {
        format!(
            "{} steps in {wall_seconds:.2} s ({:.3e} particle-steps/s)",
            self.system.steps,
            self.particle_steps / wall_seconds
        )
    }

    pub fn save_state(&self, state: &mut State) {
        self.system.save_state(state);
        self.stepper.save_state(state);
        self.pouring.save_state(state);
        state.put_value("dry.analysis", &self.analysis);
        state.put_value(
            "dry.loop",
            &(
                self.moving,
                &self.wall_present,
                self.particles,
                self.particle_steps,
            ),
        );
    }

    /// Takes back the states of every rank of a job of another size (the
    /// grains by where they are; the rest from the first, the old root's).
    pub fn restore_redistributed(&mut self, states: &mut [State]) -> Result<(), StateError> {
        self.system.restore_redistributed(states)?;
        let root = self.system.communicator.is_root();
        self.restore_run(&mut states[0])?;
        // On several ranks the analyses live on the root.
        if self.distributed && !root {
            self.analysis = Analysis::None;
        }
        Ok(())
    }

    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        self.system.restore_state(state)?;
        self.restore_run(state)
    }

    /// The contact solver, pours, analyses and counters of a state.
    fn restore_run(&mut self, state: &mut State) -> Result<(), StateError> {
        self.stepper.restore_state(state)?;
        self.pouring.restore_state(state)?;
        self.analysis = state.take_value("dry.analysis")?;
        let (moving, wall_present, particles, particle_steps): (bool, Vec<bool>, usize, f64) =
            state.take_value("dry.loop")?;
        if wall_present.len() != self.wall_present.len() {
            return Err(StateError("the saved walls do not match the case's".into()));
        }
        self.moving = moving;
        self.wall_present = wall_present;
        self.particles = particles;
        self.particle_steps = particle_steps;
        Ok(())
    }
}

/// The threads of a dry run of `system`, the grains still to be poured
/// included.
fn dry_threads(case: &Case, system: &DemSystem, pouring: &pouring::Pouring) -> ThreadChoice {
    let ranks = system.communicator.size();
    let grains = system.particles.n_owned + pouring.remaining() / ranks;
    let cores = rayon::current_num_threads();
    choose_threads(
        grains,
        cores,
        threads::ranks_sharing(cores).min(ranks),
        case.parallel.as_ref().and_then(|p| p.threads),
    )
}

/// Root-mean-square speed √(2 E_k / M) of the mobile grains, leaving out
/// grains that touch a wall but no other grain: a grain rolling away alone
/// on the floor (a disc rolls forever without rolling resistance) does not
/// keep a deposit from being at rest, while a grain still falling or flying
/// (touching nothing) does.
pub fn rms_speed(system: &DemSystem) -> f64 {
    let p = &system.particles;
    let (mut energy, mut mass) = (0.0, 0.0);
    for k in (0..p.n_owned).filter(|&k| !p.is_fixed(k)) {
        let lone_on_a_wall = system.contacts.get(k) == Some(&0) && system.touches_a_wall(k);
        if !lone_on_a_wall {
            energy += p.mass[k] * p.velocity[k].norm_squared();
            mass += p.mass[k];
        }
    }
    let c = &system.communicator;
    (c.sum(energy) / c.sum(mass).max(f64::MIN_POSITIVE)).sqrt()
}
