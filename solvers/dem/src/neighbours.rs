//! Verlet pair list on a cell grid, with the tangential history of each
//! contact.
//!
//! Pairs are candidate contacts within r_i + r_j + skin. A pair (i, j) always
//! has i owned; j is owned with a larger id, or a ghost. The list is rebuilt
//! when some particle has moved by more than half the skin since the last
//! build, and the tangential displacement of every open contact is carried
//! over by the pair's ids. Between builds no pair can close unnoticed.

use crate::particles::Particles;
use grainflow_core::{Dimension, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;

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
        self.cell_of
            .extend(positions.iter().map(|x| grid.index(grid.coordinates(x))));
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

#[derive(Clone, Debug, Default)]
pub struct NeighbourList {
    /// Extra distance beyond contact within which pairs are listed.
    pub skin: f64,
    /// Pair (first[k], second[k]); first is owned.
    pub first: Vec<u32>,
    pub second: Vec<u32>,
    /// Tangential displacement ξ of each pair (zero when not in contact).
    pub history: Vec<Vec3>,
    /// Per owned particle p, the pairs it belongs to, in pair order:
    /// `pair_of[offsets[p]..offsets[p + 1]]`, each `2 k` (as first) or
    /// `2 k + 1` (as second).
    pub offsets: Vec<u32>,
    pub pair_of: Vec<u32>,
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

    pub fn len(&self) -> usize {
        self.first.len()
    }

    pub fn is_empty(&self) -> bool {
        self.first.is_empty()
    }

    /// The tangential displacement of every open contact, keyed by the ids of
    /// its pair. Taken before particles are reordered or ghosts rebuilt.
    pub fn open_contacts(&self, particles: &Particles) -> HashMap<(u64, u64), Vec3> {
        self.first
            .iter()
            .zip(&self.second)
            .zip(&self.history)
            .filter(|(_, h)| h.norm_squared() > 0.0)
            .map(|((&i, &j), h)| ((particles.id[i as usize], particles.id[j as usize]), *h))
            .collect()
    }

    /// Lists all candidate pairs of owned and ghost particles binned on
    /// `grid`, and restores the history of the contacts in `open`.
    pub fn build(
        &mut self,
        particles: &Particles,
        grid: &CellGrid,
        open: &HashMap<(u64, u64), Vec3>,
    ) {
        self.bins.fill(grid, &particles.position);
        let n_owned = particles.n_owned;
        let skin = self.skin;
        let bins = &self.bins;
        let two_d = grid.counts[2] == 1;
        let chunks: Vec<Vec<(u32, u32)>> = (0..n_owned)
            .collect::<Vec<_>>()
            .par_chunks(BUILD_CHUNK)
            .map(|chunk| {
                let mut pairs = Vec::with_capacity(chunk.len() * 8);
                for &i in chunk {
                    let xi = particles.position[i];
                    let ri = particles.radius[i];
                    let id_i = particles.id[i];
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
                                    let ghost = j >= n_owned;
                                    if !ghost && particles.id[j] <= id_i {
                                        continue;
                                    }
                                    if fixed_i && particles.inverse_mass[j] == 0.0 {
                                        continue;
                                    }
                                    let reach = ri + particles.radius[j] + skin;
                                    if (particles.position[j] - xi).norm_squared() < reach * reach {
                                        pairs.push((i as u32, j as u32));
                                    }
                                }
                            }
                        }
                    }
                }
                // Within one particle, order partners by index: the pair order
                // is then fixed by the particle order alone.
                pairs.sort_unstable();
                pairs
            })
            .collect();

        self.first.clear();
        self.second.clear();
        for chunk in &chunks {
            for &(i, j) in chunk {
                self.first.push(i);
                self.second.push(j);
            }
        }
        self.history = self
            .first
            .iter()
            .zip(&self.second)
            .map(|(&i, &j)| {
                let key = (particles.id[i as usize], particles.id[j as usize]);
                open.get(&key).copied().unwrap_or_else(Vec3::zeros)
            })
            .collect();

        // Gather table: each owned particle's pairs in pair order.
        self.offsets.clear();
        self.offsets.resize(n_owned + 1, 0);
        for (&i, &j) in self.first.iter().zip(&self.second) {
            self.offsets[i as usize + 1] += 1;
            if (j as usize) < n_owned {
                self.offsets[j as usize + 1] += 1;
            }
        }
        for p in 0..n_owned {
            self.offsets[p + 1] += self.offsets[p];
        }
        let mut next: Vec<u32> = self.offsets[..n_owned].to_vec();
        self.pair_of.clear();
        self.pair_of.resize(self.offsets[n_owned] as usize, 0);
        for (k, (&i, &j)) in self.first.iter().zip(&self.second).enumerate() {
            self.pair_of[next[i as usize] as usize] = 2 * k as u32;
            next[i as usize] += 1;
            if (j as usize) < n_owned {
                self.pair_of[next[j as usize] as usize] = 2 * k as u32 + 1;
                next[j as usize] += 1;
            }
        }

        self.reference_position.clear();
        self.reference_position
            .extend_from_slice(&particles.position[..n_owned]);
        self.builds += 1;
    }
}
