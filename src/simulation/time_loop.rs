//! The one time loop of every scene:
//!
//! 1. advance the model one step (a failure stops the run with its
//!    diagnosis; the outputs keep the last good state);
//! 2. write what the schedule says is due (tracked grains, series rows and
//!    files), and at the end time or at rest;
//! 3. write a checkpoint when one is scheduled, or when a signal or the
//!    wall-clock limit asks the run to stop, and then stop;
//! 4. report progress.
//!
//! At the end it writes the summary.

use super::model::Model;
use super::schedule::Schedule;
use super::stop::{Longest, StopRequest, StopWatch};
use super::{peak_memory_bytes, RunOptions, Summary};
use crate::case::Case;
use crate::checkpoint::{self, Manifest};
use crate::output::writers::Writers;
use crate::progress::Progress;
use crate::RunError;
use grainflow_core::{Communicator, State};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Advances `model` to the case's end time (or rest, failure or a request
/// to stop), calling `writers` on `schedule`; `resumed`: the model and the
/// writers come from a checkpoint, whose outputs at its time are written.
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    case: &Case,
    out: &Path,
    communicator: &Communicator,
    model: &mut Model,
    writers: &mut Writers,
    mut schedule: Schedule,
    options: &RunOptions,
    resumed: bool,
) -> Result<Summary, RunError> {
    let root = communicator.is_root();
    let (description, warnings) = model.description();
    if !resumed {
        for line in description {
            writers.run.log(line);
        }
    }
    for warning in warnings {
        writers.run.warn(warning);
    }
    let end = case.time.end;
    if !resumed {
        let (time, dt) = (model.time(), model.dt());
        if schedule.output_due(time, dt, true) {
            writers.write_frame(model, dt).map_err(RunError::Io)?;
        }
        if schedule.tracked_due(time, dt, true) {
            writers.write_tracked(model).map_err(RunError::Io)?;
        }
    }
    let stop_watch = StopWatch::new(options.listen_to_signals, case.time.wall_limit);
    let keep = case.checkpoint.as_ref().map_or(2, |c| c.keep);
    let mut progress = Progress::new(root && options.show_progress, end);
    let mut stop_reason = "end time reached".to_string();
    let mut failure = None;
    let mut stopped = None;
    let mut last_checkpoint: Option<PathBuf> = None;
    let (mut longest_step, mut longest_checkpoint) = (Longest::default(), Longest::default());
    while !model.reached(end) {
        let step_clock = Instant::now();
        match model.advance(case, end) {
            Ok(lines) => lines.iter().for_each(|line| writers.run.log(line)),
            Err(why) => {
                failure = Some(why);
                break;
            }
        }
        longest_step.add(step_clock);
        let (time, dt, steps) = (model.time(), model.dt(), model.steps());
        let at_end = model.reached(end);
        let rest = model.stop_before_end();
        if schedule.tracked_due(time, dt, at_end) {
            writers.write_tracked(model).map_err(RunError::Io)?;
        }
        if schedule.output_due(time, dt, at_end || rest.is_some()) {
            writers.write_frame(model, dt).map_err(RunError::Io)?;
        }
        if let Some(reason) = rest {
            stop_reason = reason;
            break;
        }
        if let Some(line) = progress.update(time, steps) {
            writers.run.log(&line);
            eprintln!("{line}");
        }
        if at_end {
            break;
        }
        let wall_seconds = writers.wall_seconds();
        let request = stop_watch.requested(
            communicator,
            wall_seconds,
            longest_step.seconds,
            longest_checkpoint.seconds,
        );
        let scheduled =
            scheduled_checkpoint(&mut schedule, communicator, time, dt, steps, wall_seconds);
        if request.is_some() || scheduled {
            let reason = match request {
                Some(StopRequest::Signal) => "signal",
                Some(StopRequest::WallLimit) => "wall_limit",
                None => "schedule",
            };
            if request.is_some() {
                schedule.checkpoint_written(time, steps, wall_seconds);
            }
            let clock = Instant::now();
            let path = write_checkpoint(
                case,
                out,
                communicator,
                model,
                writers,
                &schedule,
                reason,
                keep,
            )
            .map_err(RunError::Io)?;
            longest_checkpoint.add(clock);
            last_checkpoint = Some(path.clone());
            if let Some(request) = request {
                let why = match request {
                    StopRequest::Signal => "stopped by a signal".to_string(),
                    StopRequest::WallLimit => format!(
                        "stopped before time.wall_limit = {} s",
                        case.time.wall_limit.unwrap_or_default()
                    ),
                };
                stop_reason = format!("{why} at t = {time:.6e} s; resume from {}", path.display());
                stopped = Some(stop_reason.clone());
                break;
            }
        }
    }
    progress.finish();
    // A run with checkpoints ends with one, from which it can be taken
    // further (a later time.end).
    let ended = failure.is_none() && stopped.is_none();
    if ended && case.checkpoint.is_some() && schedule.last_checkpoint_step() != Some(model.steps())
    {
        schedule.checkpoint_written(model.time(), model.steps(), writers.wall_seconds());
        let clock = Instant::now();
        let path = write_checkpoint(
            case,
            out,
            communicator,
            model,
            writers,
            &schedule,
            "end",
            keep,
        )
        .map_err(RunError::Io)?;
        longest_checkpoint.add(clock);
        last_checkpoint = Some(path);
    }
    finish(
        case,
        out,
        communicator,
        model,
        writers,
        failure,
        stopped,
        stop_reason,
        last_checkpoint,
    )
}

/// Whether a scheduled checkpoint is due (collective when the wall clock,
/// which is the root's, schedules them).
fn scheduled_checkpoint(
    schedule: &mut Schedule,
    communicator: &Communicator,
    time: f64,
    dt: f64,
    steps: u64,
    wall_seconds: f64,
) -> bool {
    let local = schedule.checkpoint_due(time, dt, steps, wall_seconds);
    if communicator.size() == 1 || !schedule.has_wall_checkpoints() {
        return local;
    }
    let due = communicator.any(local);
    if due && !local {
        schedule.checkpoint_written(time, steps, wall_seconds);
    }
    due
}

/// Writes a checkpoint of the run now (collective); returns its folder.
#[allow(clippy::too_many_arguments)]
fn write_checkpoint(
    case: &Case,
    out: &Path,
    communicator: &Communicator,
    model: &Model,
    writers: &mut Writers,
    schedule: &Schedule,
    reason: &str,
    keep: usize,
) -> std::io::Result<PathBuf> {
    let clock = Instant::now();
    let mut state = State::new();
    model.save_state(&mut state);
    state.put_value("writers", &writers.record());
    state.put_value("schedule", schedule);
    let extents = model.held_extent().gather(communicator).unwrap_or_default();
    let manifest = Manifest {
        grainflow_version: env!("CARGO_PKG_VERSION").to_string(),
        state_format: grainflow_core::state::FORMAT_VERSION,
        kind: model.kind().to_string(),
        ranks: communicator.size(),
        time: model.time(),
        steps: model.steps(),
        reason: reason.to_string(),
        case: case.to_toml(),
        extents,
    };
    let path = checkpoint::write(out, communicator, &manifest, &state, keep)?;
    let seconds = clock.elapsed().as_secs_f64();
    writers.checkpoint_seconds += seconds;
    writers.run.log(&format!(
        "t = {:.6e} s (step {}): checkpoint {} ({reason}, {seconds:.3} s)",
        manifest.time,
        manifest.steps,
        path.display()
    ));
    Ok(path)
}

/// The metrics and the summary of the run, written to `summary.json`, and
/// the log's last line.
#[allow(clippy::too_many_arguments)]
fn finish(
    case: &Case,
    out: &Path,
    communicator: &Communicator,
    model: &mut Model,
    writers: &mut Writers,
    failure: Option<String>,
    stopped: Option<String>,
    stop_reason: String,
    last_checkpoint: Option<PathBuf>,
) -> Result<Summary, RunError> {
    let incomplete = failure.is_some() || stopped.is_some();
    let metrics = match (&writers.bed, incomplete) {
        (Some(bed), false) => bed.metrics(),
        _ => model.metrics(case, out, incomplete).map_err(RunError::Io)?,
    };
    if let Model::Coupled(coupled) = &*model {
        if let Some(w) = coupled.closing_warning() {
            writers.run.warn(&w);
        }
    }
    let wall_seconds = writers.wall_seconds();
    let status = match (&failure, &stopped) {
        (Some(_), _) => "unstable",
        (None, Some(_)) => "stopped",
        (None, None) => "ok",
    };
    let mut summary = model.summary(case, wall_seconds);
    for (key, value) in [
        ("analysis", json!(case.analysis)),
        ("status", json!(status)),
        (
            "stop_reason",
            json!(failure.clone().unwrap_or(stop_reason.clone())),
        ),
        ("ranks", json!(communicator.size())),
        ("steps", json!(model.steps())),
        ("simulated_time", json!(model.time())),
        ("wall_seconds", json!(wall_seconds)),
        ("output_seconds", json!(writers.output_seconds)),
        ("checkpoint_seconds", json!(writers.checkpoint_seconds)),
        (
            "last_checkpoint",
            json!(last_checkpoint.map(|p| p.display().to_string())),
        ),
        ("threads", json!(rayon::current_num_threads())),
        (
            "peak_memory_bytes",
            json!(communicator.max(peak_memory_bytes().unwrap_or(0) as f64) as u64),
        ),
    ] {
        summary.insert(key.into(), value);
    }
    summary.insert("metrics".into(), json!(metrics));
    let json = serde_json::Value::Object(summary);
    writers.run.finish(
        &json,
        failure,
        &format!("done: {stop_reason}; {}", model.done_line(wall_seconds)),
    )?;
    Ok(Summary {
        json,
        metrics,
        stopped,
    })
}
