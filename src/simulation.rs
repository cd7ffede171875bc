//! The run: builds the scene, advances it, writes the outputs on schedule
//! and stops with a diagnosis when the integration goes wrong.

use crate::analysis::Analysis;
use crate::case::Case;
use crate::dry_stepping::DryStepper;
use crate::output::Outputs;
use crate::progress::Progress;
use crate::stability::{self, TimeStepVerdict};
use crate::{coupled_simulation, fluid_simulation, pouring, scene, sharing, RunError};
use grainflow_core::Communicator;
use grainflow_dem::threads::{self, choose_threads, ThreadChoice};
use grainflow_dem::DemSystem;
use serde_json::{json, Map, Value};
use std::path::Path;
use std::time::Instant;

/// Result of a finished run, as written to `summary.json`.
#[derive(Debug)]
pub struct Summary {
    pub json: Value,
    pub metrics: Map<String, Value>,
}

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

/// Runs a validated case into `out`. Nothing is written if the scene cannot
/// be built or its time step is refused.
///
/// The loop runs on a worker of a thread pool, so that parallel loops too
/// small to split run inline instead of waking the pool every step.
pub fn run(case: &Case, out: &Path, show_progress: bool) -> Result<Summary, RunError> {
    run_on(case, out, show_progress, Communicator::serial())
}

/// [`run`] on the ranks of `communicator` (every rank calls it).
pub fn run_on(
    case: &Case,
    out: &Path,
    show_progress: bool,
    communicator: Communicator,
) -> Result<Summary, RunError> {
    crate::footprint::Footprint::of(case)
        .check_fits(communicator.size(), crate::footprint::machine_memory())?;
    if rayon::current_thread_index().is_some() {
        return run_here(case, out, show_progress, communicator);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(rayon::current_num_threads())
        .build()
        .map_err(|e| RunError::Case(format!("cannot start threads: {e}")))?;
    pool.install(|| run_here(case, out, show_progress, communicator))
}

/// Refuses, before anything is written, what does not run on several ranks
/// yet.
pub(crate) fn check_ranks(case: &Case, ranks: usize) -> Result<(), RunError> {
    if ranks == 1 {
        return Ok(());
    }
    let refuse = |what: &str| {
        Err(RunError::Case(format!(
            "{what} runs on one rank in this version; started on {ranks} ranks: run it \
             without mpirun (its threads use every core of a node); allowed on several \
             ranks: scenes with contact.model = \"soft\" and scenes of a fluid alone"
        )))
    };
    if case.has_grains() && scene::hard_contact(case).is_some() {
        return refuse("hard contact (contact.model = \"cocd\" or \"nscd\")");
    }
    Ok(())
}

fn run_here(
    case: &Case,
    out: &Path,
    show_progress: bool,
    communicator: Communicator,
) -> Result<Summary, RunError> {
    check_ranks(case, communicator.size())?;
    if !case.has_grains() {
        return fluid_simulation::run(case, out, show_progress, communicator);
    }
    if case.fluid.is_some() {
        return coupled_simulation::run(case, out, show_progress, communicator);
    }
    let started = Instant::now();
    let mut system = scene::build_on(case, communicator.clone()).map_err(RunError::Case)?;
    let (pouring, pour_log) = pouring::start(case, &mut system).map_err(RunError::Case)?;
    // The threads: fewer than the pool's for a scene too small to gain from
    // them (the neighbour builds and the contact solver's run on the pool
    // too, so it shrinks with them).
    let choice = dry_threads(case, &system, &pouring);
    let threads = choice.threads;
    let run = move || {
        run_dry(
            case,
            out,
            show_progress,
            communicator,
            (started, system, pouring, pour_log, choice),
        )
    };
    if threads < rayon::current_num_threads() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| RunError::Case(format!("cannot start threads: {e}")))?;
        return pool.install(run);
    }
    run()
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

/// What [`run_here`] has built for [`run_dry`]: the clock, the scene, its
/// pouring, the pouring's log lines and the threads.
type Built = (
    Instant,
    DemSystem,
    pouring::Pouring,
    Vec<String>,
    ThreadChoice,
);

fn run_dry(
    case: &Case,
    out: &Path,
    show_progress: bool,
    communicator: Communicator,
    (started, mut system, mut pouring, pour_log, choice): Built,
) -> Result<Summary, RunError> {
    let root = communicator.is_root();
    let (mut stepper, dt, warning) = DryStepper::new(case, &mut system)?;

    let mut outputs = Outputs::create_on(out, case, communicator.clone()).map_err(RunError::Io)?;
    let p = &system.particles;
    let mut particles = communicator.sum_count(p.n_owned);
    let glued = communicator.sum_count((0..p.n_owned).filter(|&k| p.is_fixed(k)).count());
    let to_pour = match pouring.remaining() {
        0 => String::new(),
        n => format!(", {n} more to be poured"),
    };
    outputs.run.log(&format!(
        "grainflow {}: {particles} particles ({glued} glued{to_pour}), {}D, dry scene (no fluid grid)",
        env!("CARGO_PKG_VERSION"),
        system.domain.dimension.count()
    ));
    for line in &pour_log {
        outputs.run.log(line);
    }
    outputs
        .run
        .log(&format!("threads: {} ({})", choice.threads, choice.why));
    if communicator.size() > 1 {
        let s = &system.subdomain;
        outputs.run.log(&format!(
            "{} MPI ranks in a process grid of {} x {} x {}",
            communicator.size(),
            s.ranks[0],
            s.ranks[1],
            s.ranks[2]
        ));
        let ranks = communicator.size();
        if let Some(w) = sharing::load_warning(ranks, Some(particles as f64 / ranks as f64), None) {
            outputs.run.log(&w);
            if root {
                eprintln!("{w}");
            }
        }
    }
    outputs.run.log(&stepper.describe(dt));
    if let Some(w) = &warning {
        outputs.run.log(w);
        if root {
            eprintln!("{w}");
        }
    }

    let end = case.time.end;
    let interval = case.output.interval.unwrap_or(end / 100.0);
    let tracked_interval = case.output.tracked_interval.unwrap_or(interval);
    let last_removal = system
        .walls
        .iter()
        .filter_map(|w| w.remove_at)
        .fold(0.0, f64::max);
    let rest_after = case.time.rest_after.unwrap_or(last_removal);
    // On several ranks the analyses run on the root over the gathered
    // grains, gathered only at the steps they record.
    let distributed = communicator.size() > 1;
    let analysed = case.analysis.is_some();
    let mut analysis = if !distributed {
        Analysis::new(case.analysis.as_ref(), &system)
    } else if analysed {
        match system.gathered() {
            Some(whole) => Analysis::new(case.analysis.as_ref(), &whole),
            None => Analysis::None,
        }
    } else {
        Analysis::None
    };
    let mut moving = false;

    let mut progress = Progress::new(root && show_progress, end);
    let mut next_output = 0.0;
    let mut next_tracked = 0.0;
    let mut stop_reason = "end time reached".to_string();
    let mut failure: Option<String> = None;
    let mut particle_steps = 0.0;
    let mut wall_state: Vec<bool> = system.walls.iter().map(|w| w.is_present(0.0)).collect();

    outputs.write_frame(&system, dt).map_err(RunError::Io)?;
    outputs
        .write_tracked(&system, &case.particles_section().tracked)
        .map_err(RunError::Io)?;
    next_output += interval;
    next_tracked += tracked_interval;

    while system.time < end - 0.5 * dt {
        failure = stepper.step(&mut system, dt, case.time.overlap_limit);
        if failure.is_none() {
            if !distributed {
                analysis.after_step(&system);
            } else if analysed && communicator.any(analysis.wants_grains(system.time)) {
                if let Some(whole) = system.gathered() {
                    analysis.after_step(&whole);
                }
            }
        }
        if failure.is_none() && !pouring.is_done() {
            match pouring.release_due(&mut system) {
                Ok(lines) => {
                    for line in &lines {
                        outputs.run.log(line);
                    }
                    if !lines.is_empty() {
                        particles = communicator.sum_count(system.particles.n_owned);
                    }
                }
                Err(why) => failure = Some(why),
            }
        }
        particle_steps += particles as f64;
        if failure.is_some() {
            break;
        }
        for (k, wall) in system.walls.iter().enumerate() {
            let present = wall.is_present(system.time);
            if present != wall_state[k] {
                wall_state[k] = present;
                outputs.run.log(&format!(
                    "t = {:.6e} s: wall {} removed",
                    system.time, wall.name
                ));
            }
        }

        if system.time >= next_tracked - 0.5 * dt {
            outputs
                .write_tracked(&system, &case.particles_section().tracked)
                .map_err(RunError::Io)?;
            next_tracked += tracked_interval;
        }
        // At rest: after rest_after and the last batch of a pour, once the
        // grains have moved faster than the rest speed and then slowed
        // below it.
        let at_rest = match case.time.rest_speed {
            Some(v) if system.time >= rest_after && pouring.is_done() => {
                let speed = rms_speed(&system);
                moving |= speed > v;
                moving && speed < v
            }
            _ => false,
        };
        if system.time >= next_output - 0.5 * dt || at_rest {
            outputs.write_frame(&system, dt).map_err(RunError::Io)?;
            next_output += interval;
        }
        if at_rest {
            stop_reason = format!(
                "at rest: rms particle speed below {} m/s",
                case.time.rest_speed.unwrap()
            );
            break;
        }
        if let Some(line) = progress.update(system.time, system.steps) {
            outputs.run.log(&line);
            eprintln!("{line}");
        }
    }
    progress.finish();

    let wall_seconds = started.elapsed().as_secs_f64();
    let mut metrics = Map::new();
    if failure.is_none() {
        metrics = if !distributed {
            analysis.finish(&system, out).map_err(RunError::Io)?
        } else if let Some(whole) = analysed.then(|| system.gathered()).flatten() {
            analysis.finish(&whole, out).map_err(RunError::Io)?
        } else {
            Map::new()
        };
        outputs
            .write_final_particles(&system)
            .map_err(RunError::Io)?;
    }
    metrics.extend(stepper.metrics());
    let json = json!({
        "analysis": case.analysis,
        "status": if failure.is_some() { "unstable" } else { "ok" },
        "stop_reason": failure.clone().unwrap_or(stop_reason.clone()),
        "particles": particles,
        "ranks": communicator.size(),
        "dimension": system.domain.dimension.count(),
        "steps": system.steps,
        "dt": dt,
        "contact_model": case.contact_section().model,
        "contact_time": stepper.contact_time(),
        "simulated_time": system.time,
        "wall_seconds": wall_seconds,
        "particle_steps_per_second": particle_steps / wall_seconds,
        "neighbour_builds": system.neighbours.builds,
        "threads": rayon::current_num_threads(),
        "peak_memory_bytes": communicator.max(peak_memory_bytes().unwrap_or(0) as f64) as u64,
        "metrics": metrics,
    });
    outputs.run.finish(
        &json,
        failure,
        &format!(
            "done: {stop_reason}; {} steps in {wall_seconds:.2} s ({:.3e} particle-steps/s)",
            system.steps,
            particle_steps / wall_seconds
        ),
    )?;
    Ok(Summary { json, metrics })
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

/// Peak resident memory of this process (Linux), if known.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
