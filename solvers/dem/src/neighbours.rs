//! Verlet neighbour list on a cell grid, with the tangential history of each
//! contact.
//!
//! Partners are candidate contacts within r_i + r_j + skin. Each owned
//! particle lists all its partners (a full list, both sides of every pair),
//! in increasing index. A pair of owned particles i < j is evaluated once,
//! from i's entry (the upper entry), which holds the pair's history; j's
//! entry (the lower one) points back to it (`mirror`), for analyses and for
//! carrying histories across builds. A pair with a ghost is evaluated
//! from both sides, each side keeping its own history. The list is rebuilt
//! when some particle has moved by more than half the skin since the last
//! build, and the tangential displacement of every open contact is carried
//! over by the pair's ids. Between builds no pair can close unnoticed.

use crate::particles::Particles;
use grainflow_core::{Dimension, Vec3};
use rayon::prelude::*;

/// Particles per parallel build chunk: fixed, so the pair order does not
/// depend on the number of threads.
const BUILD_CHUNK: usize = 512;

/// A regular grid of cells at least one cutoff wide covering a box.
#[derive(Clone, Debug, Default)]
pub struct CellGrid {
    pub lower: Vec3,
    pub cell_size: Vec3,
    pub counts: [usize; 3],
}

impl CellGrid {
    /// Cells of side ≥ `cutoff` over `[lower, upper]`, coarsened if needed so
    /// that there are at most `max_cells`.
    pub fn new(
        dimension: Dimension,
        lower: Vec3,
        upper: Vec3,
        cutoff: f64,
        max_cells: usize,
    ) -> Self {
        let extent = upper - lower;
        let mut size = cutoff;
        loop {
            let mut counts = [1usize; 3];
            for axis in 0..dimension.count() {
                counts[axis] = ((extent[axis] / size).floor() as usize).max(1);
            }
            if counts.iter().product::<usize>() <= max_cells.max(1) {
                let mut cell_size = Vec3::repeat(1.0);
                for axis in 0..3 {
                    cell_size[axis] = extent[axis].max(f64::MIN_POSITIVE) / counts[axis] as f64;
                }
                return CellGrid {
                    lower,
                    cell_size,
                    counts,
                };
            }
            size *= 1.25;
        }
    }

    #[inline]
    pub fn coordinates(&self, x: &Vec3) -> [usize; 3] {
        let mut c = [0usize; 3];
        for axis in 0..3 {
            let k = ((x[axis] - self.lower[axis]) / self.cell_size[axis]).floor();
            c[axis] = (k.max(0.0) as usize).min(self.counts[axis] - 1);
        }
        c
    }

    #[inline]
    pub fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.counts[1] + c[1]) * self.counts[0] + c[0]
    }

    pub fn len(&self) -> usize {
        self.counts.iter().product()
    }

    /// The Z-order (Morton) rank of the cell holding `x`: the bits of its
    /// three cell coordinates interleaved. Cells close in space are mostly
    /// close in this order along every axis at once, unlike the row order
    /// of [`CellGrid::index`], where the next layer of cells is a whole
    /// layer away.
    #[inline]
    pub fn z_order(&self, x: &Vec3) -> u64 {
        fn spread(mut v: u64) -> u64 {
            // 21 bits to every third bit.
            v &= 0x1f_ffff;
            v = (v | v << 32) & 0x001f_0000_0000_ffff;
            v = (v | v << 16) & 0x001f_0000_ff00_00ff;
            v = (v | v << 8) & 0x100f_00f0_0f00_f00f;
            v = (v | v << 4) & 0x10c3_0c30_c30c_30c3;
            v = (v | v << 2) & 0x1249_2492_4924_9249;
            v
        }
        let [cx, cy, cz] = self.coordinates(x).map(|c| c as u64);
        spread(cx) | spread(cy) << 1 | spread(cz) << 2
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Particles binned by cell: `members[start[c]..start[c + 1]]` are in cell c.
#[derive(Clone, Debug, Default)]
pub struct CellBins {
    pub start: Vec<usize>,
    pub members: Vec<u32>,
    pub cell_of: Vec<usize>,
}

impl CellBins {
    /// Counting sort of particles `0..positions.len()` into the grid's cells.
    pub fn fill(&mut self, grid: &CellGrid, positions: &[Vec3]) {
        let cells = grid.len();
        self.cell_of.clear();
        positions
            .par_iter()
            .with_min_len(1024)
            .map(|x| grid.index(grid.coordinates(x)))
            .collect_into_vec(&mut self.cell_of);
        self.start.clear();
        self.start.resize(cells + 1, 0);
        for &c in &self.cell_of {
            self.start[c + 1] += 1;
        }
        for c in 0..cells {
            self.start[c + 1] += self.start[c];
        }
        let mut next = self.start.clone();
        self.members.clear();
        self.members.resize(positions.len(), 0);
        for (k, &c) in self.cell_of.iter().enumerate() {
            self.members[next[c]] = k as u32;
            next[c] += 1;
        }
    }
}

/// [`NeighbourList::state`] bit: the pair overlaps.
pub const TOUCHING: u8 = 1;
/// [`NeighbourList::state`] bit: the pair is within the lubrication range.
pub const LUBRICATED: u8 = 2;

#[derive(Clone, Debug, Default)]
pub struct NeighbourList {
    /// Extra distance within which pairs are listed beyond the reach of
    /// their interaction, so that the list holds until a particle has moved
    /// half of it.
    pub skin: f64,
    /// Gap between surfaces up to which a pair interacts without touching
    /// (the lubrication range in a fluid, zero in a dry scene): pairs are
    /// listed within `r_i + r_j + gap + skin`.
    pub gap: f64,
    /// Partners of owned particle i: `partner[offsets[i]..offsets[i + 1]]`,
    /// owned or ghost, in increasing index. Every pair is listed from both
    /// sides (a full list), so each particle sums its own forces.
    pub offsets: Vec<u32>,
    pub partner: Vec<u32>,
    /// First upper entry of owned particle i (partner index above i): its
    /// lower entries are `offsets[i]..upper_start[i]`.
    pub upper_start: Vec<u32>,
    /// For a lower entry, the index of its pair's upper entry (in the
    /// partner's list); `u32::MAX` for upper entries.
    pub mirror: Vec<u32>,
    /// Tangential displacement ξ of each upper entry, as seen from its owner
    /// (zero when not in contact; lower entries hold zero, their pair's
    /// history is −ξ of the mirror).
    pub history: Vec<Vec3>,
    /// State of each upper entry at the last force evaluation, a set of
    /// [`TOUCHING`] (it may hold a non-zero history) and [`LUBRICATED`] (a
    /// film force acts without contact): the force loop reads this byte
    /// rather than the 24-byte history for the many listed pairs that are
    /// apart, and its second pass collects the pairs whose state is not 0.
    pub state: Vec<u8>,
    /// Owned positions at the last build.
    pub reference_position: Vec<Vec3>,
    bins: CellBins,
    /// Number of builds so far.
    pub builds: u64,
}

impl NeighbourList {
    pub fn new(skin: f64) -> Self {
        NeighbourList {
            skin,
            ..Default::default()
        }
    }

    /// Number of listed (particle, partner) entries.
    pub fn len(&self) -> usize {
        self.partner.len()
    }

    pub fn is_empty(&self) -> bool {
        self.partner.is_empty()
    }

    /// Entries of owned particle i.
    #[inline]
    pub fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }

    /// Tangential history of entry e, seen from its owner.
    pub fn history_of(&self, e: usize) -> Vec3 {
        match self.mirror[e] {
            u32::MAX => self.history[e],
            upper => -self.history[upper as usize],
        }
    }

    /// The open contacts (partner id, ξ seen from i) of owned particle i.
    pub fn open_contacts(&self, i: usize, particles: &Particles, open: &mut Vec<(u64, Vec3)>) {
        open.clear();
        for e in self.range(i) {
            let history = self.history_of(e);
            if history != Vec3::zeros() {
                open.push((particles.id[self.partner[e] as usize], history));
            }
        }
    }

    /// Takes the current list out, to carry its open contacts into the next
    /// build (before particles are reordered or ghosts rebuilt).
    pub fn take_previous(&mut self, particles: &Particles) -> PreviousList {
        let n = self.offsets.len().saturating_sub(1);
        PreviousList {
            ids: particles.id.clone(),
            old_index: (0..n).collect(),
            offsets: std::mem::take(&mut self.offsets),
            partner: std::mem::take(&mut self.partner),
            mirror: std::mem::take(&mut self.mirror),
            history: std::mem::take(&mut self.history),
        }
    }

    /// Lists the partners of every owned particle among owned and ghost
    /// particles binned on `grid`, and restores the history of the contacts
    /// open in the `previous` list.
    pub fn build(&mut self, particles: &Particles, grid: &CellGrid, previous: &PreviousList) {
        self.bins.fill(grid, &particles.position);
        let n_owned = particles.n_owned;
        let margin = self.skin + self.gap;
        let bins = &self.bins;
        let two_d = grid.counts[2] == 1;
        let chunks: Vec<(Vec<u32>, Vec<u32>, Vec<Vec3>)> = (0..n_owned)
            .collect::<Vec<_>>()
            .par_chunks(BUILD_CHUNK)
            .map(|chunk| {
                let mut counts = Vec::with_capacity(chunk.len());
                let mut partners = Vec::with_capacity(chunk.len() * 12);
                let mut histories = Vec::with_capacity(chunk.len() * 12);
                let mut open: Vec<(u64, Vec3)> = Vec::new();
                for &i in chunk {
                    let start = partners.len();
                    let xi = particles.position[i];
                    let ri = particles.radius[i];
                    let fixed_i = particles.inverse_mass[i] == 0.0;
                    let c = grid.coordinates(&xi);
                    let z_range = if two_d {
                        0..=0
                    } else {
                        c[2].saturating_sub(1)..=(c[2] + 1).min(grid.counts[2] - 1)
                    };
                    for cz in z_range {
                        for cy in c[1].saturating_sub(1)..=(c[1] + 1).min(grid.counts[1] - 1) {
                            for cx in c[0].saturating_sub(1)..=(c[0] + 1).min(grid.counts[0] - 1) {
                                let cell = grid.index([cx, cy, cz]);
                                for &j in &bins.members[bins.start[cell]..bins.start[cell + 1]] {
                                    let j = j as usize;
                                    if j == i || (fixed_i && particles.inverse_mass[j] == 0.0) {
                                        continue;
                                    }
                                    let reach = ri + particles.radius[j] + margin;
                                    if (particles.position[j] - xi).norm_squared() < reach * reach {
                                        partners.push(j as u32);
                                    }
                                }
                            }
                        }
                    }
                    partners[start..].sort_unstable();
                    counts.push((partners.len() - start) as u32);
                    // Carry over the open contacts of this particle, matched
                    // by the partner's id.
                    previous.open_contacts_of(i, &mut open);
                    for &j in &partners[start..] {
                        if (j as usize) < i {
                            // A lower entry: the partner's entry holds it.
                            histories.push(Vec3::zeros());
                            continue;
                        }
                        let id = particles.id[j as usize];
                        let history = open.iter().find(|(k, _)| *k == id).map(|&(_, h)| h);
                        histories.push(history.unwrap_or_else(Vec3::zeros));
                    }
                }
                (counts, partners, histories)
            })
            .collect();

        self.offsets.clear();
        self.offsets.push(0);
        for (counts, _, _) in &chunks {
            for &c in counts {
                let last = *self.offsets.last().unwrap();
                self.offsets.push(last + c);
            }
        }
        // The chunks' entries and their contact states are copied into
        // place on rayon's threads; the copy is bound by memory, so a second
        // thread shortens it only a little (docs/performance.md).
        let entries = *self.offsets.last().unwrap() as usize;
        self.partner.resize(entries, 0);
        self.history.resize(entries, Vec3::zeros());
        self.state.resize(entries, 0);
        let mut partner_rest = &mut self.partner[..];
        let mut history_rest = &mut self.history[..];
        let mut state_rest = &mut self.state[..];
        let mut places = Vec::with_capacity(chunks.len());
        for (_, partners, _) in &chunks {
            let len = partners.len();
            let (partner, p_tail) = std::mem::take(&mut partner_rest).split_at_mut(len);
            let (history, h_tail) = std::mem::take(&mut history_rest).split_at_mut(len);
            let (state, s_tail) = std::mem::take(&mut state_rest).split_at_mut(len);
            places.push((partner, history, state));
            (partner_rest, history_rest, state_rest) = (p_tail, h_tail, s_tail);
        }
        places.into_par_iter().zip(chunks.par_iter()).for_each(
            |((partner, history, state), (_, partners, histories))| {
                partner.copy_from_slice(partners);
                history.copy_from_slice(histories);
                for (s, h) in state.iter_mut().zip(histories) {
                    *s = if *h != Vec3::zeros() { TOUCHING } else { 0 };
                }
            },
        );
        self.link_pairs(n_owned);
        self.reference_position.clear();
        self.reference_position
            .extend_from_slice(&particles.position[..n_owned]);
        self.builds += 1;
    }
}

impl NeighbourList {
    /// Finds the upper entries of every owned particle and the mirror of
    /// every lower entry (a binary search in the partner's sorted list).
    fn link_pairs(&mut self, n_owned: usize) {
        let (offsets, partner) = (&self.offsets, &self.partner);
        let entries_of = |i: usize| &partner[offsets[i] as usize..offsets[i + 1] as usize];
        self.upper_start = (0..n_owned)
            .into_par_iter()
            .map(|i| offsets[i] + entries_of(i).partition_point(|&j| (j as usize) < i) as u32)
            .collect();
        self.mirror = (0..n_owned)
            .into_par_iter()
            .flat_map_iter(|i| {
                entries_of(i).iter().map(move |&j| {
                    if (j as usize) < i {
                        let back = entries_of(j as usize)
                            .binary_search(&(i as u32))
                            .expect("the pair list is symmetric");
                        offsets[j as usize] + back as u32
                    } else {
                        u32::MAX
                    }
                })
            })
            .collect();
    }
}

/// The neighbour list of the previous build, kept to carry the tangential
/// history of open contacts into the next one.
#[derive(Clone, Debug, Default)]
pub struct PreviousList {
    /// Ids of the particles (owned and ghosts) at the previous build.
    ids: Vec<u64>,
    /// Previous index of each current owned particle.
    old_index: Vec<usize>,
    offsets: Vec<u32>,
    partner: Vec<u32>,
    mirror: Vec<u32>,
    history: Vec<Vec3>,
}

impl PreviousList {
    /// Follows a reordering of the owned particles (new k was old `order[k]`).
    pub fn reorder(&mut self, order: &[usize]) {
        // Particles added since the previous build have no entry there.
        let old_index = &self.old_index;
        self.old_index = order
            .par_iter()
            .with_min_len(1024)
            .map(|&k| old_index.get(k).copied().unwrap_or(usize::MAX))
            .collect();
    }

    /// Follows a migration: the owned particles `kept` (old indices, in
    /// their new order) stay, then come particles from other ranks with
    /// their open contacts (partner id, ξ seen from them), which become rows
    /// of their own.
    pub fn retain_and_adopt(&mut self, kept: &[usize], adopted: &[Vec<(u64, Vec3)>]) {
        let mut old_index: Vec<usize> = kept
            .iter()
            .map(|&k| self.old_index.get(k).copied().unwrap_or(usize::MAX))
            .collect();
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        for open in adopted {
            old_index.push(self.offsets.len() - 1);
            for &(id, history) in open {
                self.partner.push(self.ids.len() as u32);
                self.ids.push(id);
                self.mirror.push(u32::MAX);
                self.history.push(history);
            }
            self.offsets.push(self.partner.len() as u32);
        }
        self.old_index = old_index;
    }

    /// The open contacts (partner id, ξ) of the current owned particle i.
    pub fn open_contacts_of(&self, i: usize, open: &mut Vec<(u64, Vec3)>) {
        open.clear();
        let Some(&old) = self.old_index.get(i) else {
            return;
        };
        if old == usize::MAX || old + 1 >= self.offsets.len() {
            return;
        }
        for e in self.offsets[old] as usize..self.offsets[old + 1] as usize {
            let history = match self.mirror[e] {
                u32::MAX => self.history[e],
                upper => -self.history[upper as usize],
            };
            if history != Vec3::zeros() {
                open.push((self.ids[self.partner[e] as usize], history));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Z order interleaves the cell coordinates' bits, x lowest: the
    /// eight cells of a 2 × 2 × 2 block come first and in a row, then the
    /// next block along x, whatever the grid's row order.
    #[test]
    fn z_order_interleaves_the_cell_coordinates() {
        let grid = CellGrid {
            lower: Vec3::zeros(),
            cell_size: Vec3::new(1.0, 1.0, 1.0),
            counts: [300, 300, 300],
        };
        let at = |c: [usize; 3]| {
            grid.z_order(&(Vec3::new(c[0] as f64, c[1] as f64, c[2] as f64) + Vec3::repeat(0.5)))
        };
        let block: Vec<u64> = (0..8).map(|k| at([k & 1, (k >> 1) & 1, k >> 2])).collect();
        assert_eq!(block, (0..8).collect::<Vec<u64>>());
        assert_eq!(at([2, 0, 0]), 8);
        assert_eq!(at([0, 2, 0]), 16);
        assert_eq!(at([0, 0, 2]), 32);
        // Coordinates up to 2^21 − 1 keep their bits apart.
        assert_eq!(at([299, 0, 0]) & at([0, 299, 0]), 0);
        assert_eq!(
            at([299, 299, 299]),
            at([299, 0, 0]) | at([0, 299, 0]) | at([0, 0, 299])
        );
    }
}
