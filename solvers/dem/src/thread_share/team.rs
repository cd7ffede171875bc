//! The threads that run the passes of a DEM step (why they spin between
//! passes: the parent module).

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

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
