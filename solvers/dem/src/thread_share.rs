//! Which grains each thread works on, and the threads that do it.
//!
//! A DEM step passes over the grains twice, microseconds apart: the half
//! kick with the drift, then the force loop, which gives each chunk its
//! closing half kick once the chunk's forces are complete. Two things kept
//! two threads from doubling its speed, and this module answers both:
//!
//! - **Waking a sleeping thread for every pass.** A pool whose idle threads
//!   sleep at once (rayon's) pays for a wake-up in each pass: in a virtual
//!   machine, two 20,000-grain half kicks took 75 and 62 µs per step on two
//!   threads against 69 and 54 µs on one. A [`Team`](team::Team)'s
//!   helpers ([`team`]) spin between passes and park only after
//!   [`SPIN_BEFORE_PARKING`](team::SPIN_BEFORE_PARKING) without work.
//! - **Grains changing threads between passes and steps.** Each thread
//!   keeps the same run of the force loop's chunks in both passes and from
//!   step to step ([`ThreadShare`]), so that its grains stay in its core's
//!   caches. The runs are balanced on the chunks' measured cost (a
//!   column's dense base costs ten times its loose top) and move only at a
//!   neighbour build, when the grains are reordered anyway.
//!
//! A balance made once per build cannot follow a host that slows one of
//! its CPUs for a step or two, which a shared machine does all the time.
//! So a thread that has finished its own run claims what is left of the
//! others' from their ends ([`RunClaims`]): the chunks change threads only
//! in the steps where the threads fall out of step.
//!
//! What two threads still share every step are the grains at the boundary
//! between their runs; where two cores do not share a last-level cache
//! that has cost between a twentieth and a sixth of the step
//! (docs/performance.md).
//!
//! Which thread runs a chunk never changes what the chunk computes, nor the
//! order of any sum, so the results do not depend on the threads.

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

mod team;

pub(crate) use team::LazyTeam;

/// The runs of grains of the threads of a step.
#[derive(Clone, Debug, Default)]
pub(crate) struct ThreadShare {
    chunk_len: usize,
    chunks: usize,
    /// Thread t runs chunks `bounds[t]..bounds[t + 1]` of the force loop.
    bounds: Vec<usize>,
    /// Seconds of force evaluation of each chunk since the runs were set.
    chunk_seconds: Vec<f64>,
    /// The neighbour build at which the runs were set.
    build: u64,
}

impl ThreadShare {
    /// Makes the runs fit `n` particles in chunks of `chunk_len` on up to
    /// `threads` threads; at a new neighbour `build`, balances them on the
    /// times recorded since the last one.
    pub(crate) fn update(&mut self, n: usize, chunk_len: usize, threads: usize, build: u64) {
        let chunks = n.div_ceil(chunk_len);
        let parts = threads.min(chunks).max(1);
        let same_shape =
            self.chunk_len == chunk_len && self.chunks == chunks && self.bounds.len() == parts + 1;
        if same_shape && build == self.build {
            return;
        }
        let measured = same_shape && self.chunk_seconds.iter().any(|&s| s > 0.0);
        self.bounds = if measured {
            balanced_bounds(&self.chunk_seconds, parts)
        } else {
            (0..=parts).map(|t| t * chunks / parts).collect()
        };
        self.chunk_len = chunk_len;
        self.chunks = chunks;
        self.chunk_seconds = vec![0.0; chunks];
        self.build = build;
    }

    /// Number of threads given a run (at least one).
    pub(crate) fn threads(&self) -> usize {
        self.bounds.len().saturating_sub(1).max(1)
    }

    /// The chunks of the force loop thread `t` runs.
    pub(crate) fn chunks_of(&self, t: usize) -> Range<usize> {
        self.bounds[t]..self.bounds[t + 1]
    }

    /// The particles (of `n`) in thread `t`'s run.
    pub(crate) fn particles_of(&self, t: usize, n: usize) -> Range<usize> {
        let run = self.chunks_of(t);
        (run.start * self.chunk_len).min(n)..(run.end * self.chunk_len).min(n)
    }

    /// Splits a per-particle array (of `n`) into the threads' runs.
    pub(crate) fn split<'a, T>(&self, mut items: &'a mut [T], n: usize) -> Vec<&'a mut [T]> {
        assert_eq!(items.len(), n, "one item per particle");
        (0..self.threads())
            .map(|t| {
                let (run, rest) =
                    std::mem::take(&mut items).split_at_mut(self.particles_of(t, n).len());
                items = rest;
                run
            })
            .collect()
    }

    /// Adds the time a chunk's force evaluation took.
    pub(crate) fn record(&mut self, chunk: usize, seconds: f64) {
        self.chunk_seconds[chunk] += seconds;
    }
}

/// The chunks of one run not yet claimed in a pass: its thread claims them
/// from the front, a thread done with its own run from the back.
#[repr(align(64))]
pub(crate) struct RunClaims(AtomicU64);

impl RunClaims {
    pub(crate) fn new(run: Range<usize>) -> Self {
        RunClaims(AtomicU64::new(Self::pack(run.start, run.end)))
    }

    fn pack(front: usize, back: usize) -> u64 {
        let (front, back) = (u32::try_from(front), u32::try_from(back));
        (u64::from(front.expect("chunk index")) << 32) | u64::from(back.expect("chunk index"))
    }

    /// Claims the first unclaimed chunk, if any.
    pub(crate) fn front(&self) -> Option<usize> {
        self.claim(|front, back| (front + 1, back, front))
    }

    /// Claims the last unclaimed chunk, if any.
    pub(crate) fn back(&self) -> Option<usize> {
        self.claim(|front, back| (front, back - 1, back - 1))
    }

    fn claim(&self, take: impl Fn(usize, usize) -> (usize, usize, usize)) -> Option<usize> {
        let mut state = self.0.load(Ordering::Acquire);
        loop {
            let (front, back) = ((state >> 32) as usize, (state & 0xffff_ffff) as usize);
            if front >= back {
                return None;
            }
            let (front, back, chunk) = take(front, back);
            match self.0.compare_exchange_weak(
                state,
                Self::pack(front, back),
                Ordering::AcqRel,
                Ordering::Acquire,
            ) {
                Ok(_) => return Some(chunk),
                Err(current) => state = current,
            }
        }
    }
}

/// Bounds of `parts` contiguous runs of `costs` whose sums are as close to
/// equal as whole items allow: run t ends at the item boundary nearest to
/// t/parts of the total, and no run is empty while there are items left.
pub(crate) fn balanced_bounds(costs: &[f64], parts: usize) -> Vec<usize> {
    let items = costs.len();
    let total: f64 = costs.iter().sum();
    let mut bounds = vec![0; parts + 1];
    bounds[parts] = items;
    let mut prefix = 0.0;
    let mut k = 0;
    for t in 1..parts {
        let target = total * t as f64 / parts as f64;
        // Leave at least one item for each run after this one.
        let last = items - (parts - t);
        while k < last && prefix + costs[k] <= target {
            prefix += costs[k];
            k += 1;
        }
        // The next item goes in too if that brings the sum nearer.
        if k < last && target - prefix > prefix + costs[k] - target {
            k += 1;
        }
        k = k.max(bounds[t - 1] + 1).min(last);
        bounds[t] = k;
        prefix = costs[..k].iter().sum();
    }
    bounds
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balanced_bounds_split_equal_costs_evenly() {
        assert_eq!(balanced_bounds(&[1.0; 20], 2), vec![0, 10, 20]);
        assert_eq!(balanced_bounds(&[1.0; 9], 3), vec![0, 3, 6, 9]);
        assert_eq!(balanced_bounds(&[1.0; 5], 1), vec![0, 5]);
    }

    #[test]
    fn balanced_bounds_follow_the_costs() {
        // A dense base (cost 3) under a loose top (cost 1): half the total
        // (20 of 40) falls in the 7th base chunk, nearer its end (21) than
        // its start (18).
        let costs: Vec<f64> = (0..20).map(|k| if k < 10 { 3.0 } else { 1.0 }).collect();
        assert_eq!(balanced_bounds(&costs, 2), vec![0, 7, 20]);
        // The nearer boundary: 1 + 1 + 10 = 12 of 24 — the run ends after
        // the expensive item rather than before it.
        assert_eq!(
            balanced_bounds(&[1.0, 1.0, 10.0, 1.0, 11.0], 2),
            vec![0, 3, 5]
        );
    }

    #[test]
    fn balanced_bounds_leave_no_run_empty() {
        let b = balanced_bounds(&[100.0, 1.0, 1.0], 3);
        assert_eq!(b, vec![0, 1, 2, 3]);
        let b = balanced_bounds(&[0.0, 0.0, 0.0, 50.0], 2);
        assert!(b[1] >= 1 && b[1] <= 3, "{b:?}");
    }

    #[test]
    fn the_share_rebalances_only_at_a_new_build() {
        let mut share = ThreadShare::default();
        share.update(20 * 1024, 1024, 2, 1);
        assert_eq!(share.chunks_of(0), 0..10);
        for k in 0..20 {
            share.record(k, if k < 10 { 3.0 } else { 1.0 });
        }
        share.update(20 * 1024, 1024, 2, 1);
        assert_eq!(share.chunks_of(0), 0..10, "same build: unchanged");
        share.update(20 * 1024, 1024, 2, 2);
        assert_eq!(share.chunks_of(0), 0..7);
        assert_eq!(share.chunks_of(1), 7..20);
        assert_eq!(
            share.particles_of(1, 20 * 1024 - 5),
            7 * 1024..20 * 1024 - 5
        );
        // Fewer chunks than threads: one thread per chunk.
        share.update(300, 256, 4, 3);
        assert_eq!(share.threads(), 2);
    }

    #[test]
    fn a_run_is_claimed_from_both_ends_until_they_meet() {
        let claims = RunClaims::new(3..7);
        assert_eq!(claims.front(), Some(3));
        assert_eq!(claims.back(), Some(6));
        assert_eq!(claims.back(), Some(5));
        assert_eq!(claims.front(), Some(4));
        assert_eq!(claims.front(), None);
        assert_eq!(claims.back(), None);
        assert_eq!(RunClaims::new(2..2).front(), None);
    }

    #[test]
    fn threads_claiming_from_both_ends_take_each_chunk_once() {
        let claims = RunClaims::new(0..100_000);
        let (front, back) = std::thread::scope(|scope| {
            let front = scope.spawn(|| std::iter::from_fn(|| claims.front()).collect::<Vec<_>>());
            let back = scope.spawn(|| std::iter::from_fn(|| claims.back()).collect::<Vec<_>>());
            (front.join().unwrap(), back.join().unwrap())
        });
        // The front takes an increasing prefix, the back a decreasing
        // suffix, and together they hold every chunk exactly once.
        assert!(front.windows(2).all(|w| w[1] == w[0] + 1));
        assert!(back.windows(2).all(|w| w[1] + 1 == w[0]));
        let mut all: Vec<usize> = front.iter().chain(&back).copied().collect();
        all.sort_unstable();
        assert_eq!(all, (0..100_000).collect::<Vec<_>>());
    }
}
