//! Requests to stop a run early, with a checkpoint to resume from: SIGTERM
//! and SIGINT (what a batch scheduler sends before a job's limit, or a
//! user's Ctrl-C) and the case's `time.wall_limit`. The current step
//! finishes first. A second SIGINT or SIGTERM, while the first is being
//! honoured, ends the process at once.
//!
//! The decision is collective: ranks that did not receive the signal, or
//! whose clocks differ, stop at the same step as the others.

use grainflow_core::Communicator;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Exit status of a run stopped by a signal or its wall-clock limit after
/// writing a checkpoint (sysexits' EX_TEMPFAIL: resume it).
pub const EXIT_STOPPED: u8 = 75;

/// Why a run stops before its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopRequest {
    Signal,
    WallLimit,
}

/// Watches for the signals and the wall-clock limit of one run.
pub struct StopWatch {
    signalled: Arc<AtomicBool>,
    registered: Vec<signal_hook::SigId>,
    wall_limit: Option<f64>,
}

impl StopWatch {
    /// Starts watching; `listen` registers the signal handlers (a run
    /// started from the command line; tests that run in-process leave the
    /// signals alone).
    pub fn new(listen: bool, wall_limit: Option<f64>) -> Self {
        let signalled = Arc::new(AtomicBool::new(false));
        let mut registered = Vec::new();
        if listen {
            for signal in [signal_hook::consts::SIGTERM, signal_hook::consts::SIGINT] {
                // A second signal while the first is honoured ends the
                // process (exit status 1), then the first sets the flag.
                if let Ok(id) = signal_hook::flag::register_conditional_shutdown(
                    signal,
                    1,
                    Arc::clone(&signalled),
                ) {
                    registered.push(id);
                }
                if let Ok(id) = signal_hook::flag::register(signal, Arc::clone(&signalled)) {
                    registered.push(id);
                }
            }
        }
        StopWatch {
            signalled,
            registered,
            wall_limit,
        }
    }

    /// Whether to stop after this step (collective): a signal reached a
    /// rank, or the root's clock says that another step of the longest seen
    /// and a checkpoint as long as the longest written would pass the wall
    /// limit.
    pub fn requested(
        &self,
        communicator: &Communicator,
        wall_seconds: f64,
        longest_step: f64,
        longest_checkpoint: f64,
    ) -> Option<StopRequest> {
        let signalled = self.signalled.load(Ordering::Relaxed);
        let out_of_time = communicator.is_root()
            && self.wall_limit.is_some_and(|limit| {
                // Margin for the first checkpoint, whose time is not known.
                let checkpoint = longest_checkpoint.max(10.0 * longest_step).max(1.0);
                wall_seconds + 2.0 * longest_step + checkpoint >= limit
            });
        if communicator.size() == 1 {
            return match (signalled, out_of_time) {
                (true, _) => Some(StopRequest::Signal),
                (false, true) => Some(StopRequest::WallLimit),
                _ => None,
            };
        }
        if communicator.any(signalled) {
            Some(StopRequest::Signal)
        } else if communicator.any(out_of_time) {
            Some(StopRequest::WallLimit)
        } else {
            None
        }
    }

    /// The flag a signal sets (tests raise it themselves).
    pub fn flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.signalled)
    }
}

impl Drop for StopWatch {
    fn drop(&mut self) {
        for id in self.registered.drain(..) {
            signal_hook::low_level::unregister(id);
        }
    }
}

/// A clock that remembers the longest of the intervals it measured.
#[derive(Default)]
pub struct Longest {
    pub seconds: f64,
}

impl Longest {
    pub fn add(&mut self, since: Instant) {
        self.seconds = self.seconds.max(since.elapsed().as_secs_f64());
    }
}
