//! The run: builds the scene of a case ([`model::Model`]: grains, a fluid,
//! or both), then one time loop ([`time_loop`]) advances it, calls the
//! writers on their [`schedule::Schedule`], writes checkpoints and stops
//! with a diagnosis when the integration goes wrong, or with a checkpoint
//! when told to ([`stop`]). A run resumes from a checkpoint of its own
//! output folder ([`crate::checkpoint`]).

pub mod axisymmetric;
pub mod coupled;
pub mod dry;
pub mod dry_stepper;
pub mod fluid;
pub mod model;
pub mod schedule;
pub mod stop;
pub mod time_loop;

use crate::case::Case;
use crate::checkpoint::extent::states_to_read;
use crate::checkpoint::{self, case_changes};
use crate::output::writers::{Writers, WritersRecord};
use crate::output::RunDirectory;
use crate::RunError;
use grainflow_core::Communicator;
use model::Model;
use schedule::Schedule;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};

/// Result of a finished run, as written to `summary.json`.
#[derive(Debug)]
pub struct Summary {
    pub json: Value,
    pub metrics: Map<String, Value>,
    /// Set when the run stopped early on a signal or its wall-clock limit:
    /// what it says, the checkpoint to resume from named.
    pub stopped: Option<String>,
}

/// Which checkpoint a run resumes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Restart {
    /// The newest checkpoint in the output folder (refused if none).
    Latest,
    /// The newest if there is one, else a fresh start (a batch script that
    /// resubmits itself).
    Auto,
    /// This checkpoint folder.
    From(PathBuf),
}

impl std::str::FromStr for Restart {
    type Err = String;
    fn from_str(text: &str) -> Result<Self, String> {
        Ok(match text {
            "latest" => Restart::Latest,
            "auto" => Restart::Auto,
            path => Restart::From(PathBuf::from(path)),
        })
    }
}

/// How a run is started.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// A progress bar or log lines on the terminal.
    pub show_progress: bool,
    /// Stop with a checkpoint on SIGTERM and SIGINT (the command line).
    pub listen_to_signals: bool,
    pub restart: Option<Restart>,
}

/// Runs a validated case into `out`. Nothing is written if the scene cannot
/// be built or its time step is refused.
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
    let options = RunOptions {
        show_progress,
        ..RunOptions::default()
    };
    run_with(case, out, communicator, &options)
}

/// A run, fresh or resumed, on the ranks of `communicator`.
///
/// The loop runs on a worker of a thread pool, so that parallel loops too
/// small to split run inline instead of waking the pool every step.
pub fn run_with(
    case: &Case,
    out: &Path,
    communicator: Communicator,
    options: &RunOptions,
) -> Result<Summary, RunError> {
    crate::footprint::Footprint::of(case)
        .check_fits(communicator.size(), crate::footprint::machine_memory())?;
    if communicator.size() > 1 && crate::sharing::separator_factorised(case) {
        check_separator_on_root(case, &communicator)?;
    }
    if rayon::current_thread_index().is_some() {
        return run_here(case, out, communicator, options);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(rayon::current_num_threads())
        .build()
        .map_err(|e| RunError::Case(format!("cannot start threads: {e}")))?;
    pool.install(|| run_here(case, out, communicator, options))
}

/// [`crate::sharing::check_separator_fits`] on the root alone, which builds
/// the whole scene for it: on a node of many ranks, one copy of the scene
/// instead of one per rank. Every rank learns the verdict (collective); the
/// root holds the message, which it alone prints.
fn check_separator_on_root(case: &Case, communicator: &Communicator) -> Result<(), RunError> {
    let verdict = if communicator.is_root() {
        crate::sharing::check_separator_fits(case, communicator.size()).map(|_| ())
    } else {
        Ok(())
    };
    if communicator.any(verdict.is_err()) {
        return Err(verdict.err().unwrap_or_else(|| {
            RunError::Case("the root rank refused the scene's separator".into())
        }));
    }
    Ok(())
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
             ranks: scenes of grains (any contact model), of a fluid alone and of grains in \
             a fluid"
        )))
    };
    if case.domain.geometry == crate::case::Geometry::Axisymmetric {
        return refuse("an axisymmetric scene (domain.geometry = \"axisymmetric\")");
    }
    Ok(())
}

/// The checkpoint a run resumes from, if any, with its manifest; refuses
/// (nothing written) a missing one, one of another case or rank count.
fn checkpoint_to_resume(
    case: &Case,
    out: &Path,
    restart: &Option<Restart>,
) -> Result<Option<(PathBuf, checkpoint::Manifest)>, RunError> {
    let path = match restart {
        None => return Ok(None),
        Some(Restart::From(path)) => path.clone(),
        Some(Restart::Latest) => checkpoint::latest(out).ok_or_else(|| {
            RunError::Case(format!(
                "--restart latest: no finished checkpoint in {}; allowed: --restart auto \
                 (start afresh when there is none) or a checkpoint folder",
                out.join(checkpoint::FOLDER).display()
            ))
        })?,
        Some(Restart::Auto) => match checkpoint::latest(out) {
            Some(path) => path,
            None => return Ok(None),
        },
    };
    let manifest = checkpoint::read_manifest(&path).map_err(|e| RunError::Case(e.0))?;
    case_changes::check(&manifest.case, &case.to_toml()).map_err(RunError::Case)?;
    Ok(Some((path, manifest)))
}

fn run_here(
    case: &Case,
    out: &Path,
    communicator: Communicator,
    options: &RunOptions,
) -> Result<Summary, RunError> {
    check_ranks(case, communicator.size())?;
    // The root writes the shared files; all ranks stop if it cannot.
    let writable = if communicator.is_root() {
        crate::output::check_writable(out)
    } else {
        Ok(())
    };
    if communicator.any(writable.is_err()) {
        return Err(writable.err().unwrap_or_else(|| {
            RunError::Case(format!(
                "--out {}: the root rank cannot write there",
                out.display()
            ))
        }));
    }
    let resume = checkpoint_to_resume(case, out, &options.restart)?;
    let mut model = Model::build(case, communicator.clone())?;
    let mut resumed = None;
    if let Some((path, manifest)) = &resume {
        let fail = |e: String| format!("resuming from {}: {e}", path.display());
        let clock = std::time::Instant::now();
        let mut read = || -> Result<(WritersRecord, Schedule), String> {
            if manifest.kind != model.kind() {
                return Err(format!(
                    "it holds a {} scene, the case a {} scene",
                    manifest.kind,
                    model.kind()
                ));
            }
            let mut states = if manifest.ranks == communicator.size() {
                vec![checkpoint::read_state(path, communicator.rank()).map_err(|e| e.0)?]
            } else {
                // Another number of ranks: each rank reads the states that
                // hold its share (and the old root's), and keeps its share.
                let needed = model.needed_extent();
                states_to_read(manifest.ranks, &manifest.extents, &needed)
                    .into_iter()
                    .map(|rank| checkpoint::read_state(path, rank).map_err(|e| e.0))
                    .collect::<Result<Vec<_>, _>>()?
            };
            if manifest.ranks == communicator.size() {
                model.restore_state(&mut states[0]).map_err(|e| e.0)?;
            } else {
                model.restore_redistributed(&mut states).map_err(|e| e.0)?;
            }
            // The writers' records and the schedule: the (old) root's.
            let writers = states[0].take_value("writers").map_err(|e| e.0)?;
            let schedule = states[0].take_value("schedule").map_err(|e| e.0)?;
            Ok((writers, schedule))
        };
        let read = read();
        // A rank that cannot read its state stops every rank, before any
        // writes.
        if communicator.any(read.is_err()) {
            return Err(RunError::Case(fail(read.err().unwrap_or_else(|| {
                "another rank could not read its state".to_string()
            }))));
        }
        let (writers, schedule) = read.expect("checked on every rank");
        // The root appends to the run's files: all stop, nothing written,
        // where it cannot.
        let resumable = if communicator.is_root() {
            writers.check_resumable_in(out, path)
        } else {
            Ok(())
        };
        if communicator.any(resumable.is_err()) {
            return Err(RunError::Case(resumable.err().unwrap_or_else(|| {
                "the root rank cannot resume the run's outputs".to_string()
            })));
        }
        let seconds = clock.elapsed().as_secs_f64();
        resumed = Some((path.clone(), manifest.clone(), writers, schedule, seconds));
    }
    // The threads: fewer than the pool's for a dry scene too small to gain
    // from them (the neighbour builds and the contact solver's run on the
    // pool too, so it shrinks with them).
    let threads = match &model {
        Model::Dry(dry) => dry.threads.threads,
        _ => rayon::current_num_threads(),
    };
    let mut run = move || -> Result<Summary, RunError> {
        let (run_directory, writers_record) = match &resumed {
            None => (
                RunDirectory::create_on(out, case, &communicator).map_err(RunError::Io)?,
                None,
            ),
            Some((_, _, record, _, _)) => (
                RunDirectory::resume(out, &communicator, record.log).map_err(RunError::Io)?,
                Some(record),
            ),
        };
        let mut writers =
            Writers::create(run_directory, case, &model, &communicator, writers_record)
                .map_err(RunError::Io)?;
        let schedule = match &resumed {
            None => Schedule::of(case),
            Some((path, manifest, record, schedule, seconds)) => {
                writers.run.log(&format!(
                    "resumed from {} at t = {:.6e} s (step {}), written by grainflow {}; \
                     read and restored in {seconds:.3} s",
                    path.display(),
                    manifest.time,
                    manifest.steps,
                    manifest.grainflow_version
                ));
                Schedule::resumed(case, schedule.clone(), record.wall_seconds)
            }
        };
        time_loop::simulate(
            case,
            out,
            &communicator,
            &mut model,
            &mut writers,
            schedule,
            options,
            resumed.is_some(),
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

/// Peak resident memory of this process (Linux), if known.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
