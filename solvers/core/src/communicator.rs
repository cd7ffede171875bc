//! The communicator: global reductions and the rank layout.
//!
//! The serial communicator is a single rank. The MPI communicator (a later
//! cargo feature) will provide the same calls; solvers only use these.

/// A group of ranks sharing one scene.
#[derive(Clone, Debug)]
pub struct Communicator {
    rank: usize,
    size: usize,
}

impl Communicator {
    /// One rank owning the whole domain.
    pub fn serial() -> Self {
        Communicator { rank: 0, size: 1 }
    }

    pub fn rank(&self) -> usize {
        self.rank
    }

    pub fn size(&self) -> usize {
        self.size
    }

    /// Whether this rank writes the shared outputs (log, series, summary).
    pub fn is_root(&self) -> bool {
        self.rank == 0
    }

    /// Sum of a value over all ranks.
    pub fn sum(&self, local: f64) -> f64 {
        local
    }

    /// Sum of a count over all ranks.
    pub fn sum_count(&self, local: usize) -> usize {
        local
    }

    /// Maximum of a value over all ranks.
    pub fn max(&self, local: f64) -> f64 {
        local
    }

    /// Whether any rank reports true.
    pub fn any(&self, local: bool) -> bool {
        local
    }
}
