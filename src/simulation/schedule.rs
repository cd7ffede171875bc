//! When the time loop writes: outputs (series rows, particle and field
//! files) every `output.interval` of simulated time, `tracked.csv` every
//! `output.tracked_interval`, and checkpoints every `checkpoint.interval`,
//! `checkpoint.steps` or `checkpoint.wall_interval`, whichever comes first.
//! A checkpoint records the schedule, so that a resumed run writes at the
//! times the uninterrupted run does.

use crate::case::Case;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Schedule {
    #[serde(skip)]
    output_interval: f64,
    #[serde(skip)]
    tracked_interval: f64,
    #[serde(skip)]
    checkpoint_interval: Option<f64>,
    #[serde(skip)]
    checkpoint_steps: Option<u64>,
    #[serde(skip)]
    checkpoint_wall_interval: Option<f64>,
    next_output: f64,
    next_tracked: f64,
    next_checkpoint: f64,
    next_checkpoint_step: u64,
    next_checkpoint_wall: f64,
    /// The step of the last checkpoint written, if any.
    #[serde(default)]
    last_checkpoint_step: Option<u64>,
}

impl Schedule {
    /// The schedule of a case from time 0 (default output interval: a
    /// hundredth of the run).
    pub fn of(case: &Case) -> Self {
        let end = case.time.end;
        let output_interval = case.output.interval.unwrap_or(end / 100.0);
        let checkpoint = case.checkpoint.clone().unwrap_or_default();
        Schedule {
            output_interval,
            tracked_interval: case.output.tracked_interval.unwrap_or(output_interval),
            checkpoint_interval: checkpoint.interval,
            checkpoint_steps: checkpoint.steps,
            checkpoint_wall_interval: checkpoint.wall_interval,
            next_output: 0.0,
            next_tracked: 0.0,
            next_checkpoint: checkpoint.interval.unwrap_or(f64::INFINITY),
            next_checkpoint_step: checkpoint.steps.unwrap_or(u64::MAX),
            next_checkpoint_wall: checkpoint.wall_interval.unwrap_or(f64::INFINITY),
            last_checkpoint_step: None,
        }
    }

    /// The case's intervals with the next times of a checkpoint's record
    /// (a resumed run; the wall clock restarts with the new piece).
    pub fn resumed(case: &Case, record: Schedule, wall_seconds: f64) -> Self {
        let fresh = Self::of(case);
        Schedule {
            next_checkpoint_wall: wall_seconds
                + fresh.checkpoint_wall_interval.unwrap_or(f64::INFINITY),
            next_checkpoint: if fresh.checkpoint_interval.is_some() {
                record.next_checkpoint
            } else {
                f64::INFINITY
            },
            next_checkpoint_step: if fresh.checkpoint_steps.is_some() {
                record.next_checkpoint_step
            } else {
                u64::MAX
            },
            next_output: record.next_output,
            next_tracked: record.next_tracked,
            last_checkpoint_step: record.last_checkpoint_step,
            ..fresh
        }
    }

    /// Whether an output is due at `time` after a step of `dt` (within half
    /// a step); if so the next one is set.
    pub fn output_due(&mut self, time: f64, dt: f64, forced: bool) -> bool {
        let due = forced || time >= self.next_output - 0.5 * dt;
        if due {
            self.next_output += self.output_interval;
        }
        due
    }

    pub fn tracked_due(&mut self, time: f64, dt: f64, forced: bool) -> bool {
        let due = forced || time >= self.next_tracked - 0.5 * dt;
        if due {
            self.next_tracked += self.tracked_interval;
        }
        due
    }

    /// Whether a scheduled checkpoint is due after step `steps` at `time`
    /// (the root's `wall_seconds` decides the wall-clock schedule: the
    /// caller makes it collective); if so the next ones are set past now.
    pub fn checkpoint_due(&mut self, time: f64, dt: f64, steps: u64, wall_seconds: f64) -> bool {
        let due = time >= self.next_checkpoint - 0.5 * dt
            || steps >= self.next_checkpoint_step
            || wall_seconds >= self.next_checkpoint_wall;
        if due {
            self.checkpoint_written(time, steps, wall_seconds);
        }
        due
    }

    /// Sets the next scheduled checkpoints after one written now.
    pub fn checkpoint_written(&mut self, time: f64, steps: u64, wall_seconds: f64) {
        self.last_checkpoint_step = Some(steps);
        if let Some(interval) = self.checkpoint_interval {
            while self.next_checkpoint <= time + 1e-12 * interval.max(time.abs()) {
                self.next_checkpoint += interval;
            }
        }
        if let Some(every) = self.checkpoint_steps {
            self.next_checkpoint_step = (steps / every + 1) * every;
        }
        if let Some(interval) = self.checkpoint_wall_interval {
            self.next_checkpoint_wall = wall_seconds + interval;
        }
    }

    pub fn last_checkpoint_step(&self) -> Option<u64> {
        self.last_checkpoint_step
    }

    /// Whether any checkpoint is scheduled on the wall clock (whose
    /// decision is the root's, made collective by the caller).
    pub fn has_wall_checkpoints(&self) -> bool {
        self.checkpoint_wall_interval.is_some()
    }
}
