//! What a running case shows a person: on a terminal a bar redrawn by the
//! clock (elapsed time ticking even when a step takes minutes), elsewhere
//! (batch jobs, `mpirun`) a log line every few percent of the simulated
//! time or every minute, whichever comes first. Both give the step, the
//! simulated time, the rate and an ETA from the recent rate. Only the root
//! rank shows anything.
//!
//! A job stopped and resumed (Ctrl-Z and `fg`, a scheduler's suspend) has
//! wall time pass while the process does nothing: the rate and the ETA
//! leave that time out. Between two reads of the clock, the process's CPU
//! time grows by at least the wall time while one thread runs; wall time
//! beyond the CPU time's growth, when over a second, is counted as a pause.
//! A slow step, even of minutes, keeps its time: its thread runs. A wait
//! that uses no CPU (a long write to a slow disk, another rank's work that
//! an MPI library waits for without polling) counts as a pause too, and
//! makes the ETA that much short.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// How often the bar redraws by itself between steps.
const TICK: Duration = Duration::from_millis(500);
/// The bar's text is refreshed at most this often (s): formatting it at
/// every step of a fast DEM would cost more than the step.
const TEXT_EVERY: f64 = 0.25;
/// Without a terminal: a line at least every this many seconds...
const LINE_EVERY: f64 = 60.0;
/// ...and at every this fraction of the simulated time.
const LINE_FRACTION: f64 = 0.05;
/// The ETA and rates come from the progress over this many seconds.
const RATE_WINDOW: f64 = 30.0;
/// The clock is read about this often (s); between reads, steps are counted.
const CLOCK_EVERY: f64 = 0.01;
/// Wall time without CPU time shorter than this (s) is not a pause (a
/// write to disk, the system's scheduling).
const SHORTEST_PAUSE: f64 = 1.0;

enum Display {
    Bar(ProgressBar),
    Lines,
    Quiet,
}

/// The progress of one run, from t = 0 to `end`.
pub struct Progress {
    display: Display,
    end: f64,
    started: Instant,
    /// (active s, simulated time, step) at recent clock reads, oldest
    /// first; active time is the elapsed time less the pauses.
    recent: VecDeque<(f64, f64, u64)>,
    /// The last clock read: (elapsed s, the process's CPU s if known).
    last_read: (f64, Option<f64>),
    /// Wall seconds the process stood stopped so far.
    paused: f64,
    last_text: f64,
    last_line: f64,
    /// The next line is due at this many [`LINE_FRACTION`]s of the run.
    next_line: u32,
    /// Steps until the clock is read again, and how many to skip each time.
    countdown: u64,
    stride: u64,
}

impl Progress {
    /// A bar on stderr if `shown` and stderr is a terminal, log lines if
    /// `shown` and it is not, nothing otherwise.
    pub fn new(shown: bool, end: f64) -> Self {
        let display = match (shown, std::io::IsTerminal::is_terminal(&std::io::stderr())) {
            (false, _) => Display::Quiet,
            (true, true) => Display::Bar(ProgressBar::new(1000)),
            (true, false) => Display::Lines,
        };
        Self::with_display(display, end)
    }

    /// A bar drawn on `target` (a terminal, or a recording one in tests).
    pub fn on(target: ProgressDrawTarget, end: f64) -> Self {
        Self::with_display(
            Display::Bar(ProgressBar::with_draw_target(Some(1000), target)),
            end,
        )
    }

    /// Log lines only: the form a batch job gets.
    pub fn lines(end: f64) -> Self {
        Self::with_display(Display::Lines, end)
    }

    fn with_display(display: Display, end: f64) -> Self {
        if let Display::Bar(bar) = &display {
            bar.set_style(
                ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {percent:>3}% {msg}")
                    .expect("template")
                    .progress_chars("=> "),
            );
            bar.set_message(format!("t = 0 / {end:.3e} s"));
            // The elapsed time ticks even while a long step runs.
            bar.enable_steady_tick(TICK);
        }
        Progress {
            display,
            end,
            started: Instant::now(),
            recent: VecDeque::from([(0.0, 0.0, 0)]),
            last_read: (0.0, process_cpu_seconds()),
            paused: 0.0,
            last_text: 0.0,
            last_line: 0.0,
            next_line: 1,
            countdown: 1,
            stride: 1,
        }
    }

    /// Whether a bar is drawn (the runners then keep other lines off the
    /// terminal).
    pub fn is_visible(&self) -> bool {
        matches!(self.display, Display::Bar(_))
    }

    /// After a step: the run is at simulated `time` after `step` steps.
    /// Returns a line for the log when one is due (without a terminal).
    pub fn update(&mut self, time: f64, step: u64) -> Option<String> {
        if matches!(self.display, Display::Quiet) {
            return None;
        }
        self.countdown -= 1;
        if self.countdown > 0 && time < self.end {
            return None;
        }
        let elapsed = self.started.elapsed().as_secs_f64();
        self.update_at(elapsed, process_cpu_seconds(), time, step)
    }

    /// [`Progress::update`] at `elapsed` seconds since the start, the
    /// process having used `cpu` seconds of CPU time (if known).
    pub fn update_at(
        &mut self,
        elapsed: f64,
        cpu: Option<f64>,
        time: f64,
        step: u64,
    ) -> Option<String> {
        let (last_elapsed, last_cpu) = self.last_read;
        if let (Some(cpu), Some(last_cpu)) = (cpu, last_cpu) {
            let idle = (elapsed - last_elapsed) - (cpu - last_cpu);
            if idle > SHORTEST_PAUSE {
                self.paused += idle;
            }
        }
        self.last_read = (elapsed, cpu);
        let active = elapsed - self.paused;
        let &(first_active, _, first_step) = self.recent.front().expect("a sample");
        let step_seconds = (active - first_active) / (step - first_step).max(1) as f64;
        self.stride = ((CLOCK_EVERY / step_seconds.max(1e-9)) as u64).clamp(1, 10_000);
        self.countdown = self.stride;
        self.recent.push_back((active, time, step));
        while self.recent.len() > 2 && active - self.recent[1].0 > RATE_WINDOW {
            self.recent.pop_front();
        }
        let fraction = (time / self.end).clamp(0.0, 1.0);
        match &self.display {
            Display::Quiet => None,
            Display::Bar(bar) => {
                if elapsed - self.last_text >= TEXT_EVERY || fraction >= 1.0 {
                    self.last_text = elapsed;
                    bar.set_position((1000.0 * fraction) as u64);
                    bar.set_message(self.status(time, step));
                }
                None
            }
            // A run of under a second needs no news of its progress.
            Display::Lines if elapsed < 1.0 => None,
            Display::Lines => {
                let reached = |k: u32| fraction >= k as f64 * LINE_FRACTION - 1e-12;
                if !reached(self.next_line) && elapsed - self.last_line < LINE_EVERY {
                    return None;
                }
                self.last_line = elapsed;
                while reached(self.next_line) {
                    self.next_line += 1;
                }
                Some(format!(
                    "{:>3.0} % after {}: {}",
                    (100.0 * fraction).floor(),
                    clock(elapsed),
                    self.status(time, step)
                ))
            }
        }
    }

    /// Step, simulated time, rates over the recent window and the ETA.
    fn status(&self, time: f64, step: u64) -> String {
        let &(t0, time0, step0) = self.recent.front().expect("a sample");
        let &(t1, _, _) = self.recent.back().expect("a sample");
        let wall = t1 - t0;
        let (steps_per_second, simulated_per_second) = if wall > 0.0 {
            ((step - step0) as f64 / wall, (time - time0) / wall)
        } else {
            (0.0, 0.0)
        };
        let eta = if simulated_per_second > 0.0 {
            clock((self.end - time).max(0.0) / simulated_per_second)
        } else {
            "--".to_string()
        };
        format!(
            "step {step}, t = {time:.4e} / {:.3e} s, {}, {:.3e} simulated s per hour, ETA {eta}",
            self.end,
            if steps_per_second >= 10.0 {
                format!("{steps_per_second:.0} steps/s")
            } else {
                format!("{:.2} s/step", 1.0 / steps_per_second.max(1e-12))
            },
            3600.0 * simulated_per_second
        )
    }

    /// Clears the bar (the summary follows).
    pub fn finish(&self) {
        if let Display::Bar(bar) = &self.display {
            bar.finish_and_clear();
        }
    }
}

/// The CPU time the process has used so far, all its threads together
/// (none where the system does not say).
fn process_cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut now = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `now` is a valid timespec for the call to fill.
        let status = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut now) };
        (status == 0).then_some(now.tv_sec as f64 + 1e-9 * now.tv_nsec as f64)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// `seconds` as h:mm:ss.
fn clock(seconds: f64) -> String {
    let s = seconds.round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

#[cfg(test)]
mod tests {
    use super::*;
    use indicatif::TermLike;
    use std::sync::{Arc, Mutex};

    /// A terminal that records what is written to it.
    #[derive(Debug, Default, Clone)]
    struct Recorder(Arc<Mutex<Vec<String>>>);

    impl TermLike for Recorder {
        fn width(&self) -> u16 {
            200
        }
        fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
            Ok(())
        }
        fn write_line(&self, s: &str) -> std::io::Result<()> {
            self.0.lock().unwrap().push(s.to_string());
            Ok(())
        }
        fn write_str(&self, s: &str) -> std::io::Result<()> {
            self.0.lock().unwrap().push(s.to_string());
            Ok(())
        }
        fn clear_line(&self) -> std::io::Result<()> {
            Ok(())
        }
        fn flush(&self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn the_bar_ticks_while_a_step_takes_seconds() {
        let terminal = Recorder::default();
        let target = ProgressDrawTarget::term_like(Box::new(terminal.clone()));
        let mut progress = Progress::on(target, 10.0);
        progress.update(1.0, 1);
        // The next step ends 2.6 s later: the bar must not stand still.
        std::thread::sleep(Duration::from_millis(2600));
        progress.update(2.0, 2);
        progress.finish();
        let drawn = terminal.0.lock().unwrap().clone();
        let elapsed: std::collections::BTreeSet<&str> = drawn
            .iter()
            .filter_map(|line| line.get(..8).filter(|e| e.starts_with("00:00:0")))
            .collect();
        assert!(
            ["00:00:01", "00:00:02"].iter().all(|e| elapsed.contains(e)),
            "elapsed times drawn: {elapsed:?}"
        );
    }

    #[test]
    fn without_a_terminal_a_line_comes_every_few_percent_or_every_minute() {
        let mut progress = Progress::lines(100.0);
        // Fast at first: 2 simulated s per wall second, a line per 5 %.
        let mut lines = Vec::new();
        for step in 1..=10u64 {
            let elapsed = step as f64;
            lines.extend(progress.update_at(elapsed, Some(elapsed), 2.0 * elapsed, step));
        }
        assert_eq!(lines.len(), 4, "{lines:?}");
        assert!(lines[0].starts_with("  6 % after 0:00:03"), "{}", lines[0]);
        assert!(lines[3].contains("ETA 0:00:40"), "{}", lines[3]);
        // Then a step of five minutes that moves 1 %: a line at once, the
        // minute having passed, with the rate of the last 30 s.
        let line = progress
            .update_at(310.0, Some(310.0), 21.0, 11)
            .expect("a line after a minute");
        assert!(line.contains("step 11, t = 2.1000e1"), "{line}");
        assert!(line.contains("300.00 s/step"), "{line}");
    }

    /// A job stopped for an hour and resumed: its CPU time stood still, so
    /// the hour is left out of the rate and the ETA, which stay those of
    /// the steps around it (0.1 s a step, 1 simulated s per 10 s).
    #[test]
    fn a_pause_is_left_out_of_the_rate_and_the_eta() {
        let mut progress = Progress::lines(1000.0);
        let clock = |progress: &mut Progress, wall: f64, cpu: f64, step: u64| {
            progress.update_at(wall, Some(cpu), 0.01 * step as f64, step)
        };
        for step in 1..=600u64 {
            let t = 0.1 * step as f64;
            clock(&mut progress, t, 2.0 * t, step);
        }
        // Stopped for an hour after step 600, then one more step: the
        // minute since the last line has passed, so a line comes.
        let line = clock(&mut progress, 3660.1, 120.2, 601).expect("a line after the pause");
        assert!(line.contains("after 1:01:00"), "{line}");
        assert!(line.contains("0.10 s/step"), "{line}");
        // 993.99 simulated s to go at 0.1 per wall s: 9,940 s (the step
        // after the pause adds its 0.1 s of CPU time to the window's).
        let eta = line.split("ETA ").nth(1).expect("an ETA");
        let parts: Vec<f64> = eta.split(':').map(|p| p.parse().unwrap()).collect();
        let seconds = 3600.0 * parts[0] + 60.0 * parts[1] + parts[2];
        assert!((seconds / 9940.0 - 1.0).abs() < 0.01, "{line}");
        // Without the CPU time the hour counts.
        let mut blind = Progress::lines(1000.0);
        for step in 1..=600u64 {
            blind.update_at(0.1 * step as f64, None, 0.01 * step as f64, step);
        }
        let line = blind.update_at(3660.1, None, 6.01, 601).expect("a line");
        assert!(line.contains("s/step"), "{line}");
    }
}
