//! What a run that pours its grains will cost. Its steps grow dearer as
//! the grains come in (in the full silo a step costs twenty times more at
//! the end of the pour than at its start), so timing the first steps, as
//! [`super::cost_estimate`] does, misses most of the run. Instead the scene
//! is run through its first batches. That gives two things:
//!
//! - how long a batch takes to land (simulated time between releases, from
//!   the second batch on: the first is placed at the pour's box and need
//!   not fall), unless the pour releases on a fixed interval;
//! - how a step's cost grows with the grains in motion, `c(N) = a + b N`,
//!   fitted by least squares to the timed steps; `a` holds what does not
//!   move (glued liners, walls, the run's fixed costs).
//!
//! The rest of the pour is then summed batch by batch, `τ/Δt` steps of
//! `c(N_k)` for the k-th batch to come, and the settling after it.

use crate::case::Case;
use crate::simulation::dry::DryModel;
use crate::RunError;
use grainflow_core::Communicator;
use std::time::Instant;

/// The probe runs the scene until this many batches are out (the second
/// and third have then landed on the deposit)...
const PROBE_BATCHES: usize = 4;
/// ...or for this long (s), whichever comes first.
const PROBE_AT_MOST: f64 = 20.0;

/// The first batches of a pour, run and timed.
#[derive(Clone, Debug, Default)]
pub struct PourProbe {
    /// Each timed step: the grains in motion during it and its wall time (s).
    pub steps: Vec<(f64, f64)>,
    /// Simulated times at which batches were released (s), t = 0 included.
    pub releases: Vec<f64>,
    /// Simulated time at the end of the probe (s).
    pub time: f64,
    /// Wall time of the probe (s).
    pub wall: f64,
    /// Grains in motion at the end of the probe.
    pub moving: usize,
    /// Why the probe stopped before its batches were out, if a step failed.
    pub failed: Option<String>,
}

/// What is left of the pour when the probe ends, and how the run ends.
#[derive(Clone, Copy, Debug)]
pub struct PourPlan {
    /// Grains still to be poured.
    pub remaining: usize,
    /// Grains per batch.
    pub batch: usize,
    /// The pour's own interval between batches (s): the time a batch takes
    /// when it does not wait for the previous one to land.
    pub interval: f64,
    /// Whether each batch waits for the previous one to land.
    pub waits_for_landing: bool,
    /// The step (s) and `time.end` (s).
    pub dt: f64,
    pub end: f64,
    /// Whether the run stops once the grains are at rest (`time.rest_speed`).
    pub stops_at_rest: bool,
}

/// Runs `case`'s scene, as `grainflow run` would on one rank, through its
/// first batches; with what is left of the pour then. None when the case
/// pours nothing after t = 0.
pub fn run_first_batches(case: &Case) -> Result<Option<(PourProbe, PourPlan)>, RunError> {
    let mut model = DryModel::build(case, Communicator::serial())?;
    if model.pouring().is_done() {
        return Ok(None);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(model.threads.threads)
        .build()
        .map_err(|e| RunError::Case(format!("cannot start threads: {e}")))?;
    let dimension = model.system.dimension();
    // The pace of the pour as it starts, kept for a pour that ends within
    // the probe.
    let Some(pace) = model.pouring().pace(dimension) else {
        return Ok(None);
    };
    let moving = |model: &DryModel| {
        let p = &model.system.particles;
        (0..p.n_owned).filter(|&k| !p.is_fixed(k)).count()
    };
    let mut probe = PourProbe {
        releases: vec![0.0; model.pouring().batches_released()],
        ..PourProbe::default()
    };
    let started = Instant::now();
    pool.install(|| {
        let mut grains = moving(&model);
        while probe.releases.len() < PROBE_BATCHES
            && started.elapsed().as_secs_f64() < PROBE_AT_MOST
            && !model.reached(case.time.end)
            && !model.pouring().is_done()
        {
            let before = model.pouring().batches_released();
            let clock = Instant::now();
            // A failed step ends the probe; the run would stop there too.
            if let Err(why) = model.advance() {
                probe.failed = Some(why);
                break;
            }
            probe
                .steps
                .push((grains as f64, clock.elapsed().as_secs_f64()));
            let after = model.pouring().batches_released();
            if after > before {
                probe
                    .releases
                    .extend(std::iter::repeat_n(model.system.time, after - before));
                grains = moving(&model);
            }
        }
    });
    probe.wall = started.elapsed().as_secs_f64();
    probe.time = model.system.time;
    probe.moving = moving(&model);
    let (batch, interval, waits_for_landing) = model.pouring().pace(dimension).unwrap_or(pace);
    let plan = PourPlan {
        remaining: model.pouring().remaining(),
        batch,
        interval,
        waits_for_landing,
        dt: model.dt(),
        end: case.time.end,
        stops_at_rest: case.time.rest_speed.is_some(),
    };
    Ok(Some((probe, plan)))
}

/// A step's wall time against the grains in motion, `a + b N` (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepCost {
    pub fixed: f64,
    pub per_grain: f64,
    /// Whether `b` was fitted; otherwise the steps all moved the same grains
    /// and the cost is taken proportional to them (`a = 0`), which bounds
    /// it from above as grains come in.
    pub fitted: bool,
}

impl StepCost {
    pub fn at(&self, moving: f64) -> f64 {
        self.fixed + self.per_grain * moving
    }

    /// Least squares over the timed steps, the first left out (it sets up
    /// lists and plans). None without a step.
    pub fn fit(steps: &[(f64, f64)]) -> Option<Self> {
        let timed = if steps.len() > 1 { &steps[1..] } else { steps };
        if timed.is_empty() {
            return None;
        }
        let n = timed.len() as f64;
        let mean_n = timed.iter().map(|s| s.0).sum::<f64>() / n;
        let mean_t = timed.iter().map(|s| s.1).sum::<f64>() / n;
        let sxx: f64 = timed.iter().map(|s| (s.0 - mean_n).powi(2)).sum();
        let sxt: f64 = timed.iter().map(|s| (s.0 - mean_n) * (s.1 - mean_t)).sum();
        // Distinct counts of grains: at least two batches' worth apart.
        if sxx <= 1e-12 * n * mean_n.max(1.0).powi(2) {
            return Some(StepCost {
                fixed: 0.0,
                per_grain: mean_t / mean_n.max(1.0),
                fitted: false,
            });
        }
        // A cost that falls as grains come in is the host's noise: the
        // fitted slope is held at zero, the mean cost kept.
        let per_grain = (sxt / sxx).max(0.0);
        Some(StepCost {
            fixed: (mean_t - per_grain * mean_n).max(0.0),
            per_grain,
            fitted: true,
        })
    }
}

/// How long a batch takes (simulated s), and whether it was measured
/// (false: a lower bound, the probe ended before a batch had landed on
/// the deposit).
pub fn batch_time(probe: &PourProbe, plan: &PourPlan) -> (f64, bool) {
    if !plan.waits_for_landing {
        return (plan.interval, true);
    }
    let landings: Vec<f64> = probe
        .releases
        .windows(2)
        .skip(1)
        .map(|w| w[1] - w[0])
        .collect();
    if landings.is_empty() {
        // Since the second release, or since the start: at least that long.
        let since = probe
            .releases
            .get(1)
            .map_or(probe.time, |&t| probe.time - t);
        return (since.max(plan.interval), false);
    }
    let mean = landings.iter().sum::<f64>() / landings.len() as f64;
    (mean.max(plan.interval), true)
}

/// The estimated wall time of the whole run.
#[derive(Clone, Debug)]
pub struct PourEstimate {
    pub seconds: f64,
    pub low: f64,
    pub high: f64,
    /// Steps in all, and the batches still to come after the probe.
    pub steps: f64,
    pub batches: usize,
    /// Simulated time per batch and whether it was measured.
    pub batch_time: f64,
    pub measured: bool,
    pub cost: StepCost,
    /// Simulated time at which the pour ends.
    pub pour_ends: f64,
}

/// How far each way the cost may stray from `a + b N`: contacts that come
/// and go as a deposit builds (the factor [`super::cost_estimate`] gives
/// grains).
const SPREAD: f64 = 2.0;

/// Sums the run after the probe: the batches to come, each `τ/Δt` steps of
/// `c(N)` with N its grains in motion, then (stopping at rest) one batch
/// time of settling with every grain in, or the steps to `time.end`.
/// `setup` is the scene's building (s).
pub fn estimate(probe: &PourProbe, plan: &PourPlan, setup: f64) -> Option<PourEstimate> {
    let cost = StepCost::fit(&probe.steps)?;
    let (tau, measured) = batch_time(probe, plan);
    let batches = plan.remaining.div_ceil(plan.batch.max(1));
    let mut time = probe.time;
    let mut moving = probe.moving as f64;
    let mut seconds = setup + probe.wall;
    let mut steps = probe.steps.len() as f64;
    let mut left = plan.remaining;
    while left > 0 && time < plan.end {
        let grains = left.min(plan.batch);
        left -= grains;
        moving += grains as f64;
        let span = tau.min(plan.end - time);
        let n = span / plan.dt;
        seconds += n * cost.at(moving);
        steps += n;
        time += span;
    }
    let pour_ends = time;
    let after = if plan.stops_at_rest {
        tau.min(plan.end - time).max(0.0)
    } else {
        (plan.end - time).max(0.0)
    };
    seconds += after / plan.dt * cost.at(moving);
    steps += after / plan.dt;
    Some(PourEstimate {
        seconds,
        low: setup + probe.wall + (seconds - setup - probe.wall) / SPREAD,
        high: setup + probe.wall + (seconds - setup - probe.wall) * SPREAD,
        steps,
        batches,
        batch_time: tau,
        measured,
        cost,
        pour_ends,
    })
}

impl PourEstimate {
    /// `check`'s lines.
    pub fn lines(&self, probe: &PourProbe, plan: &PourPlan) -> String {
        let clock = super::cost_estimate::clock;
        let landing = match (plan.waits_for_landing, self.measured) {
            (false, _) => format!(
                "one batch every {:.4} s (the pour's interval)",
                self.batch_time
            ),
            (true, true) => format!(
                "one batch landing every {:.4} s, measured on the first {} batches",
                self.batch_time,
                probe.releases.len()
            ),
            (true, false) => format!(
                "one batch landing every {:.4} s at least (the probe ended before a batch had \
                 landed on the deposit: an underestimate)",
                self.batch_time
            ),
        };
        let cost = if self.cost.fitted {
            format!(
                "a step costing {:.3e} s + {:.3e} s per grain in motion",
                self.cost.fixed, self.cost.per_grain
            )
        } else {
            format!(
                "a step costing {:.3e} s per grain in motion (all timed steps moved the same \
                 grains: an upper bound)",
                self.cost.per_grain
            )
        };
        let end = if plan.stops_at_rest {
            "and one batch's time to settle (the run stops at rest)"
        } else {
            "and the steps to time.end"
        };
        let failed = probe
            .failed
            .as_ref()
            .map(|why| format!("; the probe stopped at a failed step ({why})"))
            .unwrap_or_default();
        format!(
            "estimated wall time on this machine: {} ({} to {}) for about {:.0} steps: the first \
             {} batches run here ({} steps, t = {:.4} s, in {:.1} s), then {} more batches to \
             t = {:.4} s {end}; {landing}; {cost}, fitted to the {} steps timed{failed}",
            clock(self.seconds),
            clock(self.low),
            clock(self.high),
            self.steps,
            probe.releases.len(),
            probe.steps.len(),
            probe.time,
            probe.wall,
            self.batches,
            self.pour_ends,
            probe.steps.len(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A probe of a pour whose batches of 100 grains land every 0.1 s,
    /// timed at 1 ms + 1 µs per grain in motion, at Δt = 1e-3 s.
    fn probe() -> PourProbe {
        let mut probe = PourProbe::default();
        let dt = 1e-3;
        let mut moving = 0usize;
        for step in 0..400 {
            let t = step as f64 * dt;
            // Releases at 0, 0.05 (the first batch lands at once), 0.15, 0.25, 0.35.
            if [0, 50, 150, 250, 350].contains(&step) {
                probe.releases.push(t);
                moving += 100;
            }
            probe
                .steps
                .push((moving as f64, 1e-3 + 1e-6 * moving as f64));
        }
        probe.time = 0.4;
        probe.wall = probe.steps.iter().map(|s| s.1).sum();
        probe.moving = moving;
        probe
    }

    fn plan() -> PourPlan {
        PourPlan {
            remaining: 1000,
            batch: 100,
            interval: 0.03,
            waits_for_landing: true,
            dt: 1e-3,
            end: 100.0,
            stops_at_rest: true,
        }
    }

    #[test]
    fn the_fit_recovers_a_step_cost_linear_in_the_grains_in_motion() {
        let cost = StepCost::fit(&probe().steps).unwrap();
        assert!(cost.fitted);
        assert!((cost.fixed - 1e-3).abs() < 1e-12, "{cost:?}");
        assert!((cost.per_grain - 1e-6).abs() < 1e-15, "{cost:?}");
    }

    #[test]
    fn a_batch_lands_in_the_mean_time_between_releases_after_the_first() {
        let (tau, measured) = batch_time(&probe(), &plan());
        assert!(measured);
        assert!((tau - 0.1).abs() < 1e-12, "{tau}");
        // On a fixed interval the pour's own interval is the batch time.
        let fixed = PourPlan {
            waits_for_landing: false,
            ..plan()
        };
        assert_eq!(batch_time(&probe(), &fixed), (0.03, true));
        // Before a second landing: at least the time since the second release.
        let mut short = probe();
        short.releases.truncate(2);
        let (tau, measured) = batch_time(&short, &plan());
        assert!(!measured && (tau - 0.35).abs() < 1e-12, "{tau}");
    }

    #[test]
    fn the_rest_of_the_pour_is_summed_batch_by_batch() {
        let probe = probe();
        let e = estimate(&probe, &plan(), 2.0).unwrap();
        // Ten batches of 100 steps each, the k-th with 500 + 100 k grains,
        // then 100 steps of settling with all 1,500.
        let batches: f64 = (1..=10)
            .map(|k| 100.0 * (1e-3 + 1e-6 * (500.0 + 100.0 * k as f64)))
            .sum();
        let settling = 100.0 * (1e-3 + 1e-6 * 1500.0);
        let expected = 2.0 + probe.wall + batches + settling;
        assert!(
            (e.seconds - expected).abs() < 1e-9 * expected,
            "{} {expected}",
            e.seconds
        );
        assert!((e.steps - 1500.0).abs() < 1e-9);
        assert!((e.pour_ends - 1.4).abs() < 1e-9);
        assert!((e.high - 2.0 - probe.wall - 2.0 * (batches + settling)).abs() < 1e-9);
        // A time.end inside the pour stops the sum there.
        let short = PourPlan {
            end: 0.65,
            ..plan()
        };
        let e = estimate(&probe, &short, 0.0).unwrap();
        let expected =
            probe.wall + 100.0 * (1e-3 + 6e-4) + 100.0 * (1e-3 + 7e-4) + 50.0 * (1e-3 + 8e-4);
        assert!(
            (e.seconds - expected).abs() < 1e-9,
            "{} {expected}",
            e.seconds
        );
    }

    #[test]
    fn steps_that_all_move_the_same_grains_give_a_proportional_cost() {
        let steps = vec![(200.0, 5e-3), (200.0, 2e-3), (200.0, 2e-3)];
        let cost = StepCost::fit(&steps).unwrap();
        assert!(!cost.fitted);
        assert!((cost.at(400.0) - 4e-3).abs() < 1e-15, "{cost:?}");
    }
}
