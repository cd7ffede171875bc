//! What a run will cost on this machine, told by `check` before it runs:
//! a few steps of the scene itself are timed and extrapolated to the run's
//! steps. Timing the scene on the machine that will run it takes in what
//! a table of throughputs cannot: this host's CPUs and load, the threads,
//! the scene's own mix of cells, grains and contacts.
//!
//! The uncertainty has two parts: the standard error of the mean timed
//! step, and how
//! much a step's cost changes during a run, which a probe at t = 0 cannot
//! see: grains that settle into a dense pack or a collapse that spreads
//! change the contacts by several times, a flow's cost hardly moves.

use std::time::Instant;

/// Steps are timed for at least this long (s)...
const PROBE_AT_LEAST: f64 = 0.5;
/// ...and at least this many...
const PROBE_STEPS: u64 = 5;
/// ...but no longer than this (s), whatever the step's cost.
const PROBE_AT_MOST: f64 = 3.0;

/// How much the cost per step may change during a run: a factor each way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Evolution {
    /// A flow: its cost per step is the same all along (a factor 1.25 for
    /// the host).
    Steady,
    /// Grains, whose contacts come and go: a factor 2.
    Contacts,
}

impl Evolution {
    fn factor(self) -> f64 {
        match self {
            Evolution::Steady => 1.25,
            Evolution::Contacts => 2.0,
        }
    }
}

/// The estimated wall time of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// Most likely wall time (s) and its range.
    pub seconds: f64,
    pub low: f64,
    pub high: f64,
    /// The steps timed and what they took (s).
    pub probe_steps: u64,
    pub probe_seconds: f64,
}

impl Estimate {
    /// A line for `check`.
    pub fn line(&self, steps: f64, what: &str) -> String {
        format!(
            "estimated wall time on this machine: {} ({} to {}) for {steps:.0} {what}, from {} \
             steps timed here ({:.3e} s each)",
            clock(self.seconds),
            clock(self.low),
            clock(self.high),
            self.probe_steps,
            self.probe_seconds / self.probe_steps.max(1) as f64
        )
    }
}

/// Times `step` (one step of the scene; false when it failed) and
/// extrapolates to `steps` steps, after a set-up of `setup` seconds (the
/// scene's building, timed by the caller). The first step, which sets up
/// plans and lists, is left out when more were timed. None if no step
/// succeeded.
pub fn probe(
    setup: f64,
    steps: f64,
    evolution: Evolution,
    mut step: impl FnMut() -> bool,
) -> Option<Estimate> {
    let started = Instant::now();
    let mut times = Vec::new();
    loop {
        let clock = Instant::now();
        if !step() {
            break;
        }
        times.push(clock.elapsed().as_secs_f64());
        let elapsed = started.elapsed().as_secs_f64();
        let enough = times.len() as u64 >= PROBE_STEPS && elapsed >= PROBE_AT_LEAST;
        if enough || elapsed >= PROBE_AT_MOST || times.len() as f64 >= steps {
            break;
        }
    }
    estimate(&times, steps, evolution).map(|e| Estimate {
        seconds: setup + e.seconds,
        low: setup + e.low,
        high: setup + e.high,
        ..e
    })
}

/// The estimate from the step times `times` (s).
fn estimate(times: &[f64], steps: f64, evolution: Evolution) -> Option<Estimate> {
    let timed = if times.len() > 1 { &times[1..] } else { times };
    if timed.is_empty() {
        return None;
    }
    let n = timed.len() as f64;
    let mean = timed.iter().sum::<f64>() / n;
    // The relative standard error of the mean step.
    let spread = if timed.len() > 1 {
        let variance = timed.iter().map(|t| (t - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (variance / n).sqrt() / mean
    } else {
        0.0
    };
    let factor = evolution.factor() * (1.0 + spread);
    let seconds = mean * steps;
    Some(Estimate {
        seconds,
        low: seconds / factor,
        high: seconds * factor,
        probe_steps: times.len() as u64,
        probe_seconds: times.iter().sum(),
    })
}

/// How much a soft-contact step of packed grains costs over one of the
/// same grains apart, in 3D: on this code, the 18,156 grains of
/// `cases/channel_collapse_fill_3d.toml` at its start (a cloud over a glued
/// bed) took 39 ns a particle-step and the same column packed
/// (`cases/channel_collapse_3d.toml` at its release) 206 ns, one thread.
pub const PACKED_OVER_APART_3D: f64 = 5.2;
/// The same in 2D: the 1,604 discs of `cases/erodible_bed_fill_2d.toml`
/// with soft contacts at its start, 86.5 µs a step, and packed
/// (`cases/erodible_bed_2d.toml`), 190 µs.
pub const PACKED_OVER_APART_2D: f64 = 2.2;
/// The same for COCD in 2D, whose conic program grows with the contacts:
/// rains run at 7.9 and 8.2 times the cost of the steps `check` timed at
/// their start (`cases/column_fill_cocd_2d.toml`, 566 steps;
/// `cases/static_box_fill.toml`, 2,000 steps; `docs/performance.md`, each
/// case's wall time).
pub const PACKED_OVER_APART_COCD_2D: f64 = 8.0;

/// Grains that start apart under gravity and will pack (a rain, a cloud
/// released above a floor): the steps timed at the start cost less than
/// those of the packed grains, which are most of such a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Packing {
    /// Steps until the highest grain has fallen to the lowest one's level,
    /// `√(2 H / g)/Δt` (those are counted at the timed cost).
    pub apart_steps: f64,
    /// A packed step's cost over a step timed here.
    pub cost_ratio: f64,
}

impl Estimate {
    /// The estimate of a run of `steps` steps (after `setup` seconds)
    /// whose grains pack: all but `packing.apart_steps` of them cost
    /// `packing.cost_ratio` times the steps timed.
    pub fn packing(&self, setup: f64, steps: f64, packing: Packing) -> Estimate {
        let apart = packing.apart_steps.clamp(0.0, steps);
        let scale = (apart + packing.cost_ratio * (steps - apart)) / steps.max(1.0);
        let scaled = |seconds: f64| setup + (seconds - setup) * scale;
        Estimate {
            seconds: scaled(self.seconds),
            low: scaled(self.low),
            high: scaled(self.high),
            ..self.clone()
        }
    }
}

/// `seconds` as h:mm:ss.
pub(super) fn clock(seconds: f64) -> String {
    let s = seconds.round() as u64;
    format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_estimate_leaves_out_the_first_step_and_widens_with_the_spread() {
        // A first step of set-up, then 0.1 s steps give 1000 steps in 100 s.
        let steady = estimate(&[5.0, 0.1, 0.1, 0.1], 1000.0, Evolution::Steady).unwrap();
        assert!((steady.seconds - 100.0).abs() < 1e-9);
        assert!((steady.high - 125.0).abs() < 1e-9 && (steady.low - 80.0).abs() < 1e-9);
        // Steps that vary widen the range beyond the scene's own factor, by
        // the standard error of their mean.
        let varied = estimate(&[5.0, 0.05, 0.15], 1000.0, Evolution::Contacts).unwrap();
        assert!((varied.seconds - 100.0).abs() < 1e-9);
        let spread = (0.05f64.powi(2) * 2.0 / 2.0).sqrt() / 0.1;
        assert!((varied.high - 100.0 * 2.0 * (1.0 + spread)).abs() < 1e-9);
        assert!(estimate(&[], 10.0, Evolution::Steady).is_none());
    }

    #[test]
    fn grains_that_will_pack_count_their_packed_steps_at_the_packed_cost() {
        // 1000 steps of 0.1 s timed apart; 200 of them before the grains
        // land, the other 800 at five times the cost: 20 + 400 s.
        let apart = estimate(&[5.0, 0.1, 0.1, 0.1], 1000.0, Evolution::Contacts).unwrap();
        let packing = Packing {
            apart_steps: 200.0,
            cost_ratio: 5.0,
        };
        let packed = apart.packing(0.0, 1000.0, packing);
        assert!((packed.seconds - 420.0).abs() < 1e-9);
        assert!((packed.high - 840.0).abs() < 1e-9 && (packed.low - 210.0).abs() < 1e-9);
        // The set-up is not scaled; a run that ends before the grains land
        // keeps the timed cost.
        let with_setup = Estimate {
            seconds: apart.seconds + 3.0,
            low: apart.low + 3.0,
            high: apart.high + 3.0,
            ..apart.clone()
        };
        assert!((with_setup.packing(3.0, 1000.0, packing).seconds - 423.0).abs() < 1e-9);
        let short = Packing {
            apart_steps: 5000.0,
            ..packing
        };
        assert!((apart.packing(0.0, 1000.0, short).seconds - 100.0).abs() < 1e-9);
    }
}
