//! How many threads a DEM run uses.
//!
//! A second thread pays for itself only when a step has enough grains to
//! cover what the threads cost each other: a hand-over between two CPUs at
//! every pass (two per step), the grains at the boundary of their runs, and,
//! on a host whose CPUs are not all free, the waits for a thread the host
//! has descheduled. Measured (docs/performance.md, "Threads on a shared
//! host"): on a 2-core host kept busy by other processes (load average
//! 6–8), two threads took 1.3–1.8 times as long as one for the 3D column
//! at every size from 800 to 20,000 grains (1.65 at 6,400, 1.35 at
//! 12,800), and the 2D collapse (400 grains) took 45–72 times as long
//! before the team's waits blocked; on a quiet host two threads run the
//! 20,000-grain column's dense window 1.7–1.9 times as fast. The
//! crossover lies between, where the host decides it: a run of fewer than
//! 20,000 grains keeps to one thread, and a larger one keeps the quiet
//! host's gain: one thread per [`GRAINS_PER_THREAD`] grains, at least one
//! and at most the cores the run may use. `--threads N` (the case's `parallel.threads`) forces N.

/// Grains per thread of a DEM run when the number of threads is not forced
/// (see the module's documentation for the crossover).
pub const GRAINS_PER_THREAD: usize = 10_000;

/// Threads for a scene of `grains` grains (per rank) on `cores` cores: one
/// per [`GRAINS_PER_THREAD`] grains, at least one, at most `cores`.
pub fn threads_for(grains: usize, cores: usize) -> usize {
    (grains / GRAINS_PER_THREAD).clamp(1, cores.max(1))
}

/// MPI ranks of this job on this host, from the launcher's environment
/// (Open MPI, MPICH, Slurm); 1 when not started by one.
pub fn ranks_on_this_host() -> usize {
    [
        "OMPI_COMM_WORLD_LOCAL_SIZE",
        "MPI_LOCALNRANKS",
        "SLURM_NTASKS_PER_NODE",
    ]
    .iter()
    .find_map(|name| std::env::var(name).ok()?.trim().parse::<usize>().ok())
    .unwrap_or(1)
    .max(1)
}

/// The ranks that share the `cores` this process may use: none but itself
/// when a launcher has bound it to fewer cores than the host has (its
/// cores are its own share already), otherwise the job's ranks on this
/// host ([`ranks_on_this_host`]).
pub fn ranks_sharing(cores: usize) -> usize {
    let host = std::fs::read_to_string("/sys/devices/system/cpu/online")
        .ok()
        .and_then(|text| online_cpus(&text))
        .unwrap_or(cores);
    if cores < host {
        1
    } else {
        ranks_on_this_host()
    }
}

/// CPUs in a list such as `0-3,8,10-11` (`/sys/devices/system/cpu/online`).
fn online_cpus(list: &str) -> Option<usize> {
    list.trim().split(',').try_fold(0, |count, range| {
        let mut ends = range.split('-').map(|e| e.trim().parse::<usize>().ok());
        let first = ends.next()??;
        let last = ends.next().unwrap_or(Some(first))?;
        Some(count + last.checked_sub(first)? + 1)
    })
}

/// The threads a run uses and why, for the log and `grainflow check`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ThreadChoice {
    pub threads: usize,
    pub why: String,
}

/// The threads of a run of `grains` grains (per rank, the grains still to
/// be poured included) on a host of `cores` cores shared by `ranks` ranks
/// of the job: `forced` if given, otherwise [`threads_for`] the grains on
/// this rank's share of the cores.
pub fn choose_threads(
    grains: usize,
    cores: usize,
    ranks: usize,
    forced: Option<usize>,
) -> ThreadChoice {
    if let Some(threads) = forced {
        return ThreadChoice {
            threads,
            why: format!("forced by --threads {threads}"),
        };
    }
    let ranks = ranks.max(1);
    let cores_per_rank = (cores / ranks).max(1);
    let threads = threads_for(grains, cores_per_rank);
    let cores_text = match (cores, ranks) {
        (1, 1) => "1 core".to_string(),
        (_, 1) => format!("{cores} cores"),
        _ => format!("{cores} cores shared by {ranks} ranks on this host"),
    };
    let why = if threads == cores_per_rank && threads > 1 {
        format!("{grains} grains: every core ({cores_text})")
    } else if threads == cores_per_rank {
        format!("{grains} grains on {cores_text}")
    } else {
        format!(
            "{grains} grains on {cores_text}: one thread per {GRAINS_PER_THREAD} grains, \
             below which one thread is faster; --threads N forces N"
        )
    };
    ThreadChoice { threads, why }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_scenes_run_on_one_thread_large_ones_on_every_core() {
        assert_eq!(threads_for(400, 2), 1);
        assert_eq!(threads_for(12_800, 2), 1);
        assert_eq!(threads_for(20_000, 2), 2);
        assert_eq!(threads_for(1_000_000, 16), 16);
        assert_eq!(threads_for(0, 0), 1);
    }

    #[test]
    fn online_cpus_are_counted_from_their_ranges() {
        assert_eq!(online_cpus("0-1\n"), Some(2));
        assert_eq!(online_cpus("0-3,8,10-11"), Some(7));
        assert_eq!(online_cpus("0"), Some(1));
        assert_eq!(online_cpus("x"), None);
    }

    #[test]
    fn ranks_on_one_host_share_its_cores() {
        assert_eq!(choose_threads(50_000, 2, 2, None).threads, 1);
        assert_eq!(choose_threads(50_000, 8, 2, None).threads, 4);
        assert_eq!(choose_threads(400, 2, 1, Some(2)).threads, 2);
        let choice = choose_threads(400, 2, 1, None);
        assert_eq!(choice.threads, 1);
        assert!(choice.why.contains("400 grains"), "{}", choice.why);
    }
}
