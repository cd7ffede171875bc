//! Ghost copies of particles near the subdomain's edges.
//!
//! Ghosts come in stages, axis by axis (x, y, then z), each axis in two
//! directions: a rank sends the particles within the interaction range of
//! its lower face to its lower neighbour, then those within range of its
//! upper face to its upper neighbour, shifted by the period where the face
//! is a periodic end of the domain. The candidates of an axis include the
//! ghosts received along the axes before it, so that edge and corner copies
//! reach the diagonal neighbours in two or three hops. A periodic axis of a
//! single rank sends to itself: its ghosts are the periodic images. Every
//! box must be at least one interaction range wide, so that a ghost always
//! comes from the next box.
//!
//! The stages are recorded at each neighbour build; between builds the same
//! stages refresh the ghosts' motion in the same order.

use crate::particles::{Particles, PACKED_MOTION, PACKED_STATE};
use grainflow_core::{Communicator, Domain, Side, State, StateError, Subdomain, Vec3};

/// One direction of one axis of the exchange.
#[derive(Clone, Debug)]
struct Stage {
    destination: Option<usize>,
    source: Option<usize>,
    /// Displacement of the copies sent (a period across a periodic end).
    shift: Vec3,
    /// Local particles (owned or ghosts of earlier axes) sent.
    sent: Vec<usize>,
    /// Ghosts received: `first..first + count`.
    first: usize,
    count: usize,
}

#[derive(Clone, Debug, Default)]
pub struct Ghosts {
    stages: Vec<Stage>,
    /// The owned particle each ghost copies when it is an image of one of
    /// this rank's particles, `usize::MAX` when it copies another rank's.
    pub source: Vec<usize>,
}

impl Ghosts {
    /// The stages under `prefix`: per stage its peers (`u64::MAX` for
    /// none), shift, first ghost and count, and the particles it sends.
    pub fn save_state(&self, state: &mut State, prefix: &str) {
        let peer = |p: Option<usize>| p.map_or(u64::MAX, |r| r as u64);
        let mut header = Vec::new();
        let mut shifts = Vec::new();
        let mut sent = Vec::new();
        for stage in &self.stages {
            header.extend([
                peer(stage.destination),
                peer(stage.source),
                stage.first as u64,
                stage.count as u64,
                stage.sent.len() as u64,
            ]);
            shifts.push(stage.shift);
            sent.extend(stage.sent.iter().map(|&k| k as u64));
        }
        state.put_u64s(&format!("{prefix}.stages"), &header);
        state.put_vec3s(&format!("{prefix}.shifts"), &shifts);
        state.put_u64s(&format!("{prefix}.sent"), &sent);
        state.put_usizes(&format!("{prefix}.source"), &self.source);
    }

    /// Takes back the stages of [`Ghosts::save_state`] for `owned` owned
    /// particles among `len`.
    pub fn restore_state(
        &mut self,
        state: &mut State,
        prefix: &str,
        owned: usize,
        len: usize,
    ) -> Result<(), StateError> {
        let header = state.take_u64s(&format!("{prefix}.stages"))?;
        let shifts = state.take_vec3s(&format!("{prefix}.shifts"))?;
        let sent = state.take_u64s(&format!("{prefix}.sent"))?;
        let source = state.take_usizes(&format!("{prefix}.source"))?;
        let bad = || {
            StateError(format!(
                "the saved ghost stages under {prefix} are inconsistent"
            ))
        };
        if header.len() != 5 * shifts.len() || source.len() != len - owned {
            return Err(bad());
        }
        let peer = |p: u64| (p != u64::MAX).then_some(p as usize);
        let mut stages = Vec::with_capacity(shifts.len());
        let mut at = 0;
        for (h, &shift) in header.chunks_exact(5).zip(&shifts) {
            let (first, count, sending) = (h[2] as usize, h[3] as usize, h[4] as usize);
            let to = at + sending;
            if to > sent.len() || first + count > len {
                return Err(bad());
            }
            let stage_sent: Vec<usize> = sent[at..to].iter().map(|&k| k as usize).collect();
            if stage_sent.iter().any(|&k| k >= len) {
                return Err(bad());
            }
            stages.push(Stage {
                destination: peer(h[0]),
                source: peer(h[1]),
                shift,
                sent: stage_sent,
                first,
                count,
            });
            at = to;
        }
        if at != sent.len() {
            return Err(bad());
        }
        self.stages = stages;
        self.source = source;
        Ok(())
    }

    /// Drops old ghosts and receives the copies of every particle within
    /// `range` of this subdomain (collective: every rank calls it).
    pub fn build(
        &mut self,
        particles: &mut Particles,
        domain: &Domain,
        subdomain: &Subdomain,
        communicator: &Communicator,
        range: f64,
    ) {
        particles.clear_ghosts();
        self.stages.clear();
        self.source.clear();
        let extent = domain.extent();
        let rank = communicator.rank();
        let mut message = Vec::new();
        for axis in 0..domain.dimension.count() {
            if subdomain.ranks[axis] == 1 && !domain.periodic[axis] {
                continue;
            }
            let candidates = particles.len();
            for side in [Side::Lower, Side::Upper] {
                let destination = subdomain.neighbour(domain, axis, side);
                let source = subdomain.neighbour(domain, axis, opposite(side));
                let last = subdomain.ranks[axis] - 1;
                let mut shift = Vec3::zeros();
                let sent: Vec<usize> = match side {
                    Side::Lower => {
                        if subdomain.coords[axis] == 0 {
                            shift[axis] = extent[axis];
                        }
                        let face = subdomain.lower[axis] + range;
                        (0..candidates)
                            .filter(|&k| particles.position[k][axis] < face)
                            .collect()
                    }
                    Side::Upper => {
                        if subdomain.coords[axis] == last {
                            shift[axis] = -extent[axis];
                        }
                        let face = subdomain.upper[axis] - range;
                        (0..candidates)
                            .filter(|&k| particles.position[k][axis] >= face)
                            .collect()
                    }
                };
                let sent = if destination.is_some() {
                    sent
                } else {
                    Vec::new()
                };
                message.clear();
                for &k in &sent {
                    particles.pack_state(k, shift, &mut message);
                }
                let tag = self.stages.len() as u16;
                let received = communicator.shift(tag, &message, destination, source);
                let first = particles.len();
                for packed in received.chunks_exact(PACKED_STATE) {
                    particles.push_packed(packed, false);
                }
                let count = particles.len() - first;
                if destination == Some(rank) {
                    // Images of this rank's particles: their owned source.
                    let n_owned = particles.n_owned;
                    for &k in &sent {
                        let owned = if k < n_owned {
                            k
                        } else {
                            self.source[k - n_owned]
                        };
                        self.source.push(owned);
                    }
                } else {
                    self.source.extend(std::iter::repeat_n(usize::MAX, count));
                }
                self.stages.push(Stage {
                    destination,
                    source,
                    shift,
                    sent,
                    first,
                    count,
                });
            }
        }
    }

    /// Copies the current motion of each ghost's particle onto it, stage by
    /// stage as built (collective).
    pub fn refresh(&self, particles: &mut Particles, communicator: &Communicator) {
        let mut message = Vec::new();
        for (tag, stage) in self.stages.iter().enumerate() {
            message.clear();
            for &k in &stage.sent {
                particles.pack_motion(k, stage.shift, &mut message);
            }
            let received =
                communicator.shift(tag as u16, &message, stage.destination, stage.source);
            assert_eq!(
                received.len(),
                stage.count * PACKED_MOTION,
                "a neighbour refreshed a different set of ghosts than it built"
            );
            for (k, packed) in received.chunks_exact(PACKED_MOTION).enumerate() {
                particles.unpack_motion(stage.first + k, packed);
            }
        }
    }
}

impl Ghosts {
    /// Copies `width` numbers per owned particle onto its ghosts, stage by
    /// stage as built (a ghost of a ghost receives its copy in turn):
    /// `values` holds `width` numbers per local particle (owned, then
    /// ghosts); on return each ghost's entries equal its particle's
    /// (collective). For per-particle quantities that are not part of the
    /// particles' motion.
    pub fn copy_to_ghosts(&self, values: &mut [f64], width: usize, communicator: &Communicator) {
        let mut message = Vec::new();
        for (tag, stage) in self.stages.iter().enumerate() {
            message.clear();
            for &k in &stage.sent {
                message.extend_from_slice(&values[k * width..(k + 1) * width]);
            }
            let received = communicator.shift(
                COPY_TAG + tag as u16,
                &message,
                stage.destination,
                stage.source,
            );
            assert_eq!(
                received.len(),
                stage.count * width,
                "a neighbour copied onto a different set of ghosts than it built"
            );
            values[stage.first * width..(stage.first + stage.count) * width]
                .copy_from_slice(&received);
        }
    }
}

impl Ghosts {
    /// Adds what was accumulated on each ghost to the particle it copies,
    /// stage by stage in reverse (a ghost of a ghost passes its share on):
    /// `values` holds `width` numbers per local particle (owned, then
    /// ghosts); on return the owned entries hold their totals (collective).
    /// This is how a rank's partial sums for another rank's particle (the
    /// hydrodynamic load of a grain whose forcing region straddles ranks)
    /// reach its owner.
    pub fn reverse_sum(&self, values: &mut [f64], width: usize, communicator: &Communicator) {
        for (tag, stage) in self.stages.iter().enumerate().rev() {
            let received = &values[stage.first * width..(stage.first + stage.count) * width];
            // Back to the rank the ghosts came from; from the rank this one
            // sent its particles to.
            let returned = communicator.shift(
                REVERSE_TAG + tag as u16,
                received,
                stage.source,
                stage.destination,
            );
            assert_eq!(
                returned.len(),
                stage.sent.len() * width,
                "a neighbour returned sums for a different set of ghosts"
            );
            for (&k, sums) in stage.sent.iter().zip(returned.chunks_exact(width)) {
                for (value, sum) in values[k * width..(k + 1) * width].iter_mut().zip(sums) {
                    *value += sum;
                }
            }
        }
    }
}

/// First message tag of the reverse sums.
const REVERSE_TAG: u16 = 500;

/// First message tag of the copies onto ghosts.
const COPY_TAG: u16 = 700;

fn opposite(side: Side) -> Side {
    match side {
        Side::Lower => Side::Upper,
        Side::Upper => Side::Lower,
    }
}
