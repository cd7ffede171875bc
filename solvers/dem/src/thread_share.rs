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
//!   threads against 69 and 54 µs on one. A [`Team`]'s helpers spin between
//!   passes and park only after [`SPIN_BEFORE_PARKING`] without work.
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
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

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

/// The threads that run the passes of a DEM step: the calling thread and
/// helpers that spin for up to [`SPIN_BEFORE_PARKING`] after a pass, and
/// only then park until the next one.
///
/// No thread ever waits for a thread that may not be running. A pass is
/// split into parts, and any thread of the team runs any part not yet
/// taken (its own first): a helper the host has not scheduled yet when the
/// caller is done with its own part finds its part already run, so the
/// caller never waits for a helper to wake up. The caller waits only for
/// helpers that are inside the pass, running a part they took, and a
/// thread that waits for another's result inside a pass ([`Team::wait`])
/// spins for at most [`SPIN_BEFORE_BLOCKING`] and then blocks until the
/// other thread signals, so that a host with fewer free CPUs than threads
/// runs the thread it waits for instead of the waiting one.
pub(crate) struct Team {
    shared: Arc<TeamShared>,
    helpers: Vec<JoinHandle<()>>,
}

/// How long a helper spins for the next pass before it parks.
const SPIN_BEFORE_PARKING: Duration = Duration::from_micros(300);

/// How long a thread spins for another's result inside a pass before it
/// blocks. On a host that runs both threads a hand-over comes within this
/// (a 20,000-grain column's dense passes wait tens of microseconds for the
/// other run's chunks); one that has not come by then waits for a thread
/// the host has descheduled, which a spinning waiter would only delay
/// further. Measured on the 20,000-grain column's settling window, two
/// threads against one: at 20 µs the gain fell to 1.36–1.63 (the waiter
/// blocked and paid a wake-up on most waits), at 200 µs it is 1.90–2.23 on
/// a quiet host, and with a busy process on one core two threads take 1.22
/// times as long as one, no collapse (docs/performance.md).
const SPIN_BEFORE_BLOCKING: Duration = Duration::from_micros(200);

/// Spins between two looks at the clock.
const SPINS_PER_CLOCK: u32 = 64;

/// The most spins of one wait, whatever the clock says: a waiter that the
/// host deschedules while it spins does not spin again for as long.
const MOST_SPINS: u64 = 1 << 16;

/// The current pass, borrowed from the caller for its duration.
#[derive(Clone, Copy)]
struct PassWork(*const (dyn Fn(usize) + Sync + 'static));

// SAFETY: the pointer is dereferenced only by threads inside the pass, and
// `Team::run` closes the pass and waits for them to leave before it
// returns, so the closure (which is `Sync`) outlives every use.
unsafe impl Send for PassWork {}

/// How the waits of a team ended, for tests and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct WaitCounts {
    /// Waits (for a result or for helpers to leave a pass) that ended while
    /// spinning.
    pub(crate) spun: u64,
    /// Waits that blocked until signalled.
    pub(crate) blocked: u64,
    /// Spins over all waits.
    pub(crate) spins: u64,
    /// Helpers' parks between passes.
    pub(crate) parked: u64,
    /// Parts run by a thread other than their own.
    pub(crate) taken_over: u64,
}

#[derive(Default)]
struct WaitCounters {
    spun: AtomicU64,
    blocked: AtomicU64,
    spins: AtomicU64,
    parked: AtomicU64,
    taken_over: AtomicU64,
}

/// Bits of [`TeamShared::pass`]: the pass's generation (high 32), whether
/// it is closed to helpers (bit 31) and how many helpers are inside.
const CLOSED: u64 = 1 << 31;
const INSIDE: u64 = CLOSED - 1;

struct TeamShared {
    /// Counts the passes started; a helper looks at a pass when it changes.
    generation: AtomicU64,
    /// The current pass: its generation, whether it is closed, and the
    /// helpers inside it (see [`CLOSED`]).
    pass: AtomicU64,
    /// Parts of the current pass, and which have been taken.
    parts: AtomicUsize,
    taken: Vec<AtomicBool>,
    work: Mutex<Option<PassWork>>,
    /// Helpers parked on `wake`, and whether the team is being dropped.
    parking: Mutex<(usize, bool)>,
    wake: Condvar,
    /// Threads blocked in [`Team::wait`] or waiting for helpers to leave,
    /// and the condition variable they block on.
    blocked: AtomicUsize,
    signal_lock: Mutex<()>,
    signal: Condvar,
    /// A helper's pass panicked.
    panicked: AtomicBool,
    counters: WaitCounters,
    /// Tests: helpers do not enter passes while set, as if the host did not
    /// run them.
    #[cfg(test)]
    stalled: AtomicBool,
}

impl TeamShared {
    /// Wakes the threads blocked on `signal`, if any; called after
    /// publishing what they may wait for.
    fn notify(&self) {
        std::sync::atomic::fence(Ordering::SeqCst);
        if self.blocked.load(Ordering::SeqCst) > 0 {
            let _guard = self.signal_lock.lock().expect("signal");
            self.signal.notify_all();
        }
    }

    /// Waits until `ready` holds: spins for up to [`SPIN_BEFORE_BLOCKING`],
    /// then blocks until a [`TeamShared::notify`] finds it holds.
    fn wait(&self, ready: impl Fn() -> bool) {
        if ready() {
            return;
        }
        let started = Instant::now();
        let mut spins = 0u64;
        loop {
            std::hint::spin_loop();
            spins += 1;
            if ready() {
                self.counters.spins.fetch_add(spins, Ordering::Relaxed);
                self.counters.spun.fetch_add(1, Ordering::Relaxed);
                return;
            }
            if spins >= MOST_SPINS
                || (spins.is_multiple_of(u64::from(SPINS_PER_CLOCK))
                    && started.elapsed() > SPIN_BEFORE_BLOCKING)
            {
                break;
            }
        }
        self.counters.spins.fetch_add(spins, Ordering::Relaxed);
        self.counters.blocked.fetch_add(1, Ordering::Relaxed);
        let mut guard = self.signal_lock.lock().expect("signal");
        self.blocked.fetch_add(1, Ordering::SeqCst);
        std::sync::atomic::fence(Ordering::SeqCst);
        while !ready() {
            guard = self.signal.wait(guard).expect("signal");
        }
        self.blocked.fetch_sub(1, Ordering::SeqCst);
    }

    /// Runs the parts of the current pass not yet taken, `first` first.
    fn run_parts(&self, work: &(dyn Fn(usize) + Sync), first: usize) {
        let parts = self.parts.load(Ordering::Acquire);
        for k in 0..parts {
            let part = (first + k) % parts;
            if !self.taken[part].swap(true, Ordering::AcqRel) {
                if part != first {
                    self.counters.taken_over.fetch_add(1, Ordering::Relaxed);
                }
                work(part);
            }
        }
    }
}

impl Team {
    /// A team of `threads` threads in all (the caller and `threads − 1`
    /// helpers).
    pub(crate) fn new(threads: usize) -> Team {
        let threads = threads.max(1);
        let shared = Arc::new(TeamShared {
            generation: AtomicU64::new(0),
            pass: AtomicU64::new(CLOSED),
            parts: AtomicUsize::new(0),
            taken: (0..threads).map(|_| AtomicBool::new(true)).collect(),
            work: Mutex::new(None),
            parking: Mutex::new((0, false)),
            wake: Condvar::new(),
            blocked: AtomicUsize::new(0),
            signal_lock: Mutex::new(()),
            signal: Condvar::new(),
            panicked: AtomicBool::new(false),
            counters: WaitCounters::default(),
            #[cfg(test)]
            stalled: AtomicBool::new(false),
        });
        let helpers = (1..threads)
            .map(|t| {
                let shared = Arc::clone(&shared);
                std::thread::Builder::new()
                    .name(format!("grainflow-dem-{t}"))
                    .spawn(move || helper_loop(&shared, t))
                    .expect("cannot start a DEM helper thread")
            })
            .collect();
        Team { shared, helpers }
    }

    /// Threads in the team, the caller's included.
    pub(crate) fn threads(&self) -> usize {
        self.helpers.len() + 1
    }

    /// Waits until `ready` holds, for a result that another thread of the
    /// same pass publishes and then signals with [`Team::notify`]: spins
    /// briefly, then blocks.
    pub(crate) fn wait(&self, ready: impl Fn() -> bool) {
        self.shared.wait(ready);
    }

    /// Wakes the threads of a pass blocked in [`Team::wait`], after
    /// publishing what they may be waiting for.
    pub(crate) fn notify(&self) {
        self.shared.notify();
    }

    /// How the team's waits have ended so far.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(crate) fn wait_counts(&self) -> WaitCounts {
        let c = &self.shared.counters;
        WaitCounts {
            spun: c.spun.load(Ordering::Relaxed),
            blocked: c.blocked.load(Ordering::Relaxed),
            spins: c.spins.load(Ordering::Relaxed),
            parked: c.parked.load(Ordering::Relaxed),
            taken_over: c.taken_over.load(Ordering::Relaxed),
        }
    }

    /// Runs `work(t, parts[t])` for every part t and returns the results in
    /// part order. Part t runs on thread t if that thread comes for it
    /// before another thread of the team is free to take it; there must be
    /// no more parts than threads.
    pub(crate) fn run_parts<P, R, W>(&self, parts: Vec<P>, work: W) -> Vec<R>
    where
        P: Send,
        R: Send,
        W: Fn(usize, P) -> R + Sync,
    {
        let count = parts.len();
        assert!(count <= self.threads(), "a part per thread at most");
        if count == 1 {
            let part = parts.into_iter().next().expect("one part");
            return vec![work(0, part)];
        }
        let slots: Vec<Mutex<Option<P>>> = parts.into_iter().map(|p| Mutex::new(Some(p))).collect();
        let results: Vec<Mutex<Option<R>>> = (0..count).map(|_| Mutex::new(None)).collect();
        self.run(count, &|t| {
            let part = slots[t]
                .lock()
                .expect("part")
                .take()
                .expect("each part runs once");
            let result = work(t, part);
            *results[t].lock().expect("result") = Some(result);
        });
        results
            .into_iter()
            .map(|r| r.into_inner().expect("result").expect("every part ran"))
            .collect()
    }

    /// Runs `work(t)` for every part t < `parts` on the threads of the team
    /// and returns when all have finished.
    fn run(&self, parts: usize, work: &(dyn Fn(usize) + Sync)) {
        let shared = &*self.shared;
        // SAFETY: only the lifetime is erased; a helper uses the pointer
        // only while inside the pass, and this function closes the pass and
        // waits for the helpers inside to leave before it returns (also
        // when the caller's part panics).
        let erased: *const (dyn Fn(usize) + Sync + 'static) =
            unsafe { std::mem::transmute(work as *const (dyn Fn(usize) + Sync)) };
        *shared.work.lock().expect("pass") = Some(PassWork(erased));
        for (k, taken) in shared.taken.iter().enumerate() {
            taken.store(k >= parts, Ordering::Relaxed);
        }
        shared.parts.store(parts, Ordering::Release);
        let generation = shared.generation.load(Ordering::Relaxed).wrapping_add(1);
        // Open the pass, then announce it.
        shared
            .pass
            .store((generation & 0xffff_ffff) << 32, Ordering::Release);
        shared.generation.store(generation, Ordering::Release);
        {
            let parking = shared.parking.lock().expect("parking");
            if parking.0 > 0 {
                shared.wake.notify_all();
            }
        }
        struct CloseThePass<'a>(&'a TeamShared);
        impl Drop for CloseThePass<'_> {
            fn drop(&mut self) {
                let shared = self.0;
                // No helper enters once the pass is closed; wait for those
                // inside, which are running parts they took.
                shared.pass.fetch_or(CLOSED, Ordering::AcqRel);
                shared.wait(|| shared.pass.load(Ordering::Acquire) & INSIDE == 0);
                *shared.work.lock().expect("pass") = None;
            }
        }
        let closing = CloseThePass(shared);
        shared.run_parts(work, 0);
        drop(closing);
        if shared.panicked.swap(false, Ordering::AcqRel) {
            panic!("a DEM helper thread panicked");
        }
    }
}

/// Enters the pass of `generation` if it is still open: counts the helper
/// in, so that the caller waits for it to leave.
fn enter(shared: &TeamShared, generation: u64) -> bool {
    let tag = (generation & 0xffff_ffff) << 32;
    let mut state = shared.pass.load(Ordering::Acquire);
    loop {
        if state & !(CLOSED | INSIDE) != tag || state & CLOSED != 0 {
            return false;
        }
        match shared.pass.compare_exchange_weak(
            state,
            state + 1,
            Ordering::AcqRel,
            Ordering::Acquire,
        ) {
            Ok(_) => return true,
            Err(current) => state = current,
        }
    }
}

fn helper_loop(shared: &TeamShared, thread: usize) {
    let mut seen = 0u64;
    loop {
        // Spin for the next pass, then park.
        let started = Instant::now();
        let mut spins = 0u32;
        while shared.generation.load(Ordering::Acquire) == seen {
            std::hint::spin_loop();
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(256) && started.elapsed() > SPIN_BEFORE_PARKING {
                let mut parking = shared.parking.lock().expect("parking");
                parking.0 += 1;
                shared.counters.parked.fetch_add(1, Ordering::Relaxed);
                while shared.generation.load(Ordering::Acquire) == seen && !parking.1 {
                    parking = shared.wake.wait(parking).expect("parking");
                }
                parking.0 -= 1;
                if parking.1 {
                    return;
                }
            }
        }
        seen = shared.generation.load(Ordering::Acquire);
        if shared.parking.lock().expect("parking").1 {
            return;
        }
        #[cfg(test)]
        while shared.stalled.load(Ordering::Acquire) {
            std::thread::sleep(Duration::from_micros(100));
        }
        if !enter(shared, seen) {
            // The pass was over (or closing) before this helper came.
            continue;
        }
        let pass = *shared.work.lock().expect("pass");
        if let Some(PassWork(work)) = pass {
            // SAFETY: `Team::run` keeps the closure alive until this helper
            // has left the pass below.
            let work = unsafe { &*work };
            let ran = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                shared.run_parts(work, thread);
            }));
            if ran.is_err() {
                shared.panicked.store(true, Ordering::Release);
            }
        }
        shared.pass.fetch_sub(1, Ordering::AcqRel);
        shared.notify();
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        self.shared.parking.lock().expect("parking").1 = true;
        self.shared.generation.fetch_add(1, Ordering::AcqRel);
        {
            let _parking = self.shared.parking.lock().expect("parking");
            self.shared.wake.notify_all();
        }
        #[cfg(test)]
        self.shared.stalled.store(false, Ordering::Release);
        for helper in self.helpers.drain(..) {
            let _ = helper.join();
        }
    }
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Team({} threads)", self.threads())
    }
}

/// A DEM system's team, started when first needed; a clone of the system
/// starts its own.
#[derive(Debug, Default)]
pub(crate) struct LazyTeam(Option<Team>);

impl Clone for LazyTeam {
    fn clone(&self) -> Self {
        LazyTeam(None)
    }
}

impl LazyTeam {
    /// The team, of `threads` threads.
    pub(crate) fn of(&mut self, threads: usize) -> &Team {
        if self.0.as_ref().map(Team::threads) != Some(threads) {
            self.0 = Some(Team::new(threads));
        }
        self.0.as_ref().expect("just started")
    }
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

    #[test]
    fn a_team_returns_results_in_part_order_pass_after_pass() {
        let team = Team::new(3);
        for pass in 0..1000 {
            let results = team.run_parts(vec![10, 20, 30], |t, p| (t, p + pass));
            assert_eq!(
                results,
                vec![(0, 10 + pass), (1, 20 + pass), (2, 30 + pass)]
            );
        }
        // Fewer parts than threads, and a pass after the helpers parked.
        std::thread::sleep(Duration::from_millis(5));
        assert_eq!(team.run_parts(vec![5, 6], |t, p| t * 100 + p), vec![5, 106]);
    }

    #[test]
    fn a_helper_that_panics_fails_the_pass() {
        let team = Team::new(2);
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            team.run_parts(vec![0, 1], |t, _| assert!(t == 0, "helper fails"))
        }));
        assert!(outcome.is_err());
        // The team still works afterwards.
        assert_eq!(team.run_parts(vec![1, 2], |_, p| p * 2), vec![2, 4]);
    }
    /// Runs `body` on a thread of its own and fails if it has not finished
    /// within a minute: a team that waits for a thread that never comes
    /// would hang the test instead of failing it.
    fn finishes<T: Send + 'static>(body: impl FnOnce() -> T + Send + 'static) -> T {
        let (done, finished) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = done.send(body());
        });
        finished
            .recv_timeout(Duration::from_secs(60))
            .expect("the team never finished: it waits for threads that do not run")
    }

    #[test]
    fn a_pass_does_not_wait_for_helpers_the_host_does_not_run() {
        // Helpers that never get a CPU: the caller runs their parts, and
        // every pass ends without them.
        let counts = finishes(|| {
            let team = Team::new(4);
            team.shared.stalled.store(true, Ordering::Release);
            let caller = std::thread::current().id();
            for pass in 0..200 {
                let results = team.run_parts(vec![1, 2, 3, 4], |t, p| {
                    (t, p * pass, std::thread::current().id() == caller)
                });
                let expected: Vec<_> = (0..4).map(|t| (t, (t + 1) * pass, true)).collect();
                assert_eq!(results, expected);
            }
            let counts = team.wait_counts();
            team.shared.stalled.store(false, Ordering::Release);
            // Once the host runs them again, the helpers take part again.
            std::thread::sleep(Duration::from_millis(20));
            let helper_ran = (0..1000).any(|_| {
                team.run_parts(vec![(), ()], |_, ()| {
                    std::thread::sleep(Duration::from_micros(50));
                    std::thread::current().id() != caller
                })
                .into_iter()
                .any(|ran| ran)
            });
            assert!(helper_ran, "the helpers never came back");
            counts
        });
        assert_eq!(counts.taken_over, 200 * 3, "{counts:?}");
        assert_eq!(counts.blocked, 0, "nothing to wait for: {counts:?}");
    }

    #[test]
    fn waits_among_more_threads_than_cpus_block_rather_than_spin() {
        // Eight threads, more than this host's CPUs, each part waiting for
        // the one before it to publish, the first slower than any spin:
        // the waiters spin a bounded number of times, then block and leave
        // their CPU to the threads they wait for.
        let passes = 100;
        let counts = finishes(move || {
            let team = Team::new(8);
            for _ in 0..passes {
                let published: Vec<AtomicBool> = (0..8).map(|_| AtomicBool::new(false)).collect();
                let order = team.run_parts((0..8).collect(), |t, _: usize| {
                    if t == 0 {
                        std::thread::sleep(Duration::from_micros(200));
                    } else {
                        team.wait(|| published[t - 1].load(Ordering::Acquire));
                    }
                    published[t].store(true, Ordering::Release);
                    team.notify();
                    t
                });
                assert_eq!(order, (0..8).collect::<Vec<_>>());
            }
            // Idle helpers park between passes rather than spin.
            std::thread::sleep(Duration::from_millis(20));
            team.wait_counts()
        });
        let waits = counts.spun + counts.blocked;
        assert!(counts.blocked >= 1, "no wait blocked: {counts:?}");
        assert!(
            counts.spins <= waits * MOST_SPINS,
            "spins beyond the bound: {counts:?}"
        );
        assert!(counts.parked >= 7, "idle helpers did not park: {counts:?}");
    }
}
