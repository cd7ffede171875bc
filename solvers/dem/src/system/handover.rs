//! What the pairs of one chunk of the force loop hand to their upper
//! particles in later chunks, and the order in which chunks collect it.

use super::*;

/// What a pair hands to its upper particle when a later chunk of the force
/// loop owns it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Handover {
    pub(super) target: u32,
    pub(super) touching: bool,
    /// Force on the lower particle (the target receives −force).
    pub(super) force: Vec3,
    pub(super) partner_torque: Vec3,
}

/// What the pairs of one chunk of the force loop hand to their upper
/// particles.
pub(super) struct HandedOver {
    /// The chunk's particles, and the owned ones (`0..owned`).
    pub(super) chunk: std::ops::Range<usize>,
    pub(super) owned: usize,
    /// Sums for upper particles in the chunk (−F, the partner torque,
    /// contacts), indexed from the chunk's first particle.
    pub(super) force: Vec<Vec3>,
    pub(super) torque: Vec<Vec3>,
    pub(super) count: Vec<u32>,
    /// Pairs whose upper particle a later chunk owns, in the order made.
    pub(super) outgoing: Vec<Handover>,
}

impl HandedOver {
    pub(super) fn new(chunk: std::ops::Range<usize>, owned: usize) -> Self {
        let len = chunk.len();
        HandedOver {
            chunk,
            owned,
            force: vec![Vec3::zeros(); len],
            torque: vec![Vec3::zeros(); len],
            count: vec![0; len],
            outgoing: Vec::new(),
        }
    }

    /// Sums a pair for its upper particle in the chunk, lists it for one a
    /// later chunk owns; drops it for a ghost (its owner evaluates the pair
    /// itself).
    #[inline]
    pub(super) fn give(&mut self, handover: Handover) {
        let j = handover.target as usize;
        if j < self.chunk.end {
            let local = j - self.chunk.start;
            self.force[local] -= handover.force;
            self.torque[local] += handover.partner_torque;
            self.count[local] += u32::from(handover.touching);
        } else if j < self.owned {
            self.outgoing.push(handover);
        }
    }
}

/// Whether every chunk of `sources` has published its hand-over list.
pub(super) fn all_published(sources: &[u32], handovers: &[OnceLock<Vec<Handover>>]) -> bool {
    sources
        .iter()
        .all(|&source| handovers[source as usize].get().is_some())
}

/// Per chunk of the force loop, the earlier chunks that hand over to it, in
/// increasing order (compressed rows).
#[derive(Clone, Debug)]
pub(super) struct HandoverSources {
    pub(super) offsets: Vec<usize>,
    pub(super) chunks: Vec<u32>,
}

impl Default for HandoverSources {
    fn default() -> Self {
        HandoverSources {
            offsets: vec![0],
            chunks: Vec::new(),
        }
    }
}

impl HandoverSources {
    /// Number of chunks described.
    pub(super) fn chunks(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The chunks that hand over to `chunk`.
    pub(super) fn of(&self, chunk: usize) -> &[u32] {
        &self.chunks[self.offsets[chunk]..self.offsets[chunk + 1]]
    }
}

/// Adds to the particles of `chunk` what the chunks `sources` handed them,
/// in increasing chunk order and, within a chunk, in the order it made
/// them (increasing lower particle), once every source has published its
/// list; returns the chunk's (particle, contact) entries.
pub(super) fn receive_handovers(
    chunk: usize,
    chunk_len: usize,
    sources: &[u32],
    handovers: &[OnceLock<Vec<Handover>>],
    forces: &mut [Vec3],
    torques: &mut [Vec3],
    counts: &mut [u32],
) -> usize {
    let first = chunk * chunk_len;
    for &source in sources {
        let list = handovers[source as usize]
            .get()
            .expect("every source has published its list");
        let start = list.partition_point(|h| (h.target as usize) < first);
        let stop = list.partition_point(|h| (h.target as usize) < first + forces.len());
        for h in &list[start..stop] {
            let local = h.target as usize - first;
            forces[local] -= h.force;
            torques[local] += h.partner_torque;
            counts[local] += u32::from(h.touching);
        }
    }
    // The chunk's counts are final now: summed here rather than in a pass
    // of their own.
    counts.iter().map(|&c| c as usize).sum()
}
