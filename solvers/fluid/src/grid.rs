//! The staggered (MAC) grid of a rank's subdomain.
//!
//! Pressure lives at cell centres; the velocity component along axis `a`
//! lives on the faces normal to `a` (Izard et al. 2014, eq. 1–2 are
//! discretised on this arrangement, which couples pressure and velocity
//! without odd–even modes). Spacing is uniform along every axis.
//!
//! Every field is one flat `Vec<f64>` over the padded block: the `cells`
//! of the subdomain plus one ghost layer on each side of every active axis
//! (x fastest, then y, then z). In 2D the z axis has one cell and no ghost
//! layer. Padded index `i` along an active axis covers:
//!
//! - cell centres at `lower + (i - 1/2) h` for `i = 0..=n+1` (0 and n+1 are ghosts),
//! - faces at `lower + i h` for `i = 0..=n+1`: face `i` is the upper face of
//!   cell `i`, so faces 0 and `n` are the lower and upper ends of the subdomain.

use std::ops::Range;

use rayon::prelude::*;

use grainflow_core::Dimension;

/// Where the values of a field sit in a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// Cell centre (pressure, divergence).
    Centre,
    /// Centre of the upper face normal to the axis (velocity component along it).
    Face(usize),
}

/// A box of padded indices, `start[a]..end[a]` along each axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    pub start: [usize; 3],
    pub end: [usize; 3],
}

/// The uniform staggered grid of one subdomain.
#[derive(Clone, Debug)]
pub struct Grid {
    pub dimension: Dimension,
    /// Cells along x, y, z (z is 1 in 2D).
    pub cells: [usize; 3],
    /// Lower corner of the subdomain (m).
    pub lower: [f64; 3],
    /// Upper corner of the subdomain (m).
    pub upper: [f64; 3],
    /// Cell size along each axis (m).
    pub spacing: [f64; 3],
    ghost: [usize; 3],
    padded: [usize; 3],
    strides: [usize; 3],
}

impl Grid {
    /// A grid of `cells` between `lower` and `upper`. In 2D the z entries
    /// are ignored: one cell of unit depth.
    pub fn new(dimension: Dimension, cells: [usize; 3], lower: [f64; 3], upper: [f64; 3]) -> Self {
        let active = dimension.count();
        let mut cells = cells;
        let mut lower = lower;
        let mut upper = upper;
        let mut ghost = [0; 3];
        for axis in 0..3 {
            if axis < active {
                assert!(cells[axis] >= 2, "at least two cells along axis {axis}");
                assert!(upper[axis] > lower[axis], "empty extent along axis {axis}");
                ghost[axis] = 1;
            } else {
                cells[axis] = 1;
                lower[axis] = 0.0;
                upper[axis] = 1.0;
            }
        }
        let spacing = [0, 1, 2].map(|a| (upper[a] - lower[a]) / cells[a] as f64);
        let padded = [0, 1, 2].map(|a| cells[a] + 2 * ghost[a]);
        let strides = [1, padded[0], padded[0] * padded[1]];
        Grid {
            dimension,
            cells,
            lower,
            upper,
            spacing,
            ghost,
            padded,
            strides,
        }
    }

    /// Number of active axes (2 or 3).
    pub fn dim(&self) -> usize {
        self.dimension.count()
    }

    /// Ghost layers along `axis` (1 if active, 0 for z in 2D).
    pub fn ghost(&self, axis: usize) -> usize {
        self.ghost[axis]
    }

    /// Points along each axis including ghosts.
    pub fn padded(&self) -> [usize; 3] {
        self.padded
    }

    /// Distance in the flat array between neighbours along `axis`.
    pub fn stride(&self, axis: usize) -> usize {
        self.strides[axis]
    }

    /// Length of a flat field.
    pub fn len(&self) -> usize {
        self.padded.iter().product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Flat index of padded indices `(i, j, k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.strides[1] * j + self.strides[2] * k
    }

    /// A zero field.
    pub fn zeros(&self) -> Vec<f64> {
        vec![0.0; self.len()]
    }

    /// Padded indices of the cells owned by this subdomain along `axis`.
    pub fn interior(&self, axis: usize) -> Range<usize> {
        self.ghost[axis]..self.ghost[axis] + self.cells[axis]
    }

    /// All owned cells.
    pub fn cell_block(&self) -> Block {
        Block {
            start: [0, 1, 2].map(|a| self.interior(a).start),
            end: [0, 1, 2].map(|a| self.interior(a).end),
        }
    }

    /// Volume of a cell (area in 2D).
    pub fn cell_volume(&self) -> f64 {
        self.spacing[..self.dim()].iter().product()
    }

    /// Coordinate along `axis` of padded index `i` of a field at `location`.
    pub fn coordinate(&self, location: Location, axis: usize, i: usize) -> f64 {
        let offset = if location == Location::Face(axis) {
            1.0
        } else {
            0.5
        };
        self.lower[axis] + (i as f64 - self.ghost[axis] as f64 + offset) * self.spacing[axis]
    }

    /// Position of padded point `(i, j, k)` of a field at `location`.
    pub fn position(&self, location: Location, i: usize, j: usize, k: usize) -> [f64; 3] {
        [
            self.coordinate(location, 0, i),
            self.coordinate(location, 1, j),
            self.coordinate(location, 2, k),
        ]
    }

    /// Calls `visit(index, [i, j, k])` for every padded point of `block`,
    /// x fastest.
    #[inline]
    pub fn for_each(&self, block: &Block, mut visit: impl FnMut(usize, [usize; 3])) {
        for k in block.start[2]..block.end[2] {
            for j in block.start[1]..block.end[1] {
                let row = self.index(0, j, k);
                for i in block.start[0]..block.end[0] {
                    visit(row + i, [i, j, k]);
                }
            }
        }
    }

    /// Sets `out[index] = value(index, out[index])` for every padded point
    /// of `block`, the planes of the slowest active axis (z in 3D, y in 2D)
    /// shared among threads. Each point is computed alone, so the result
    /// does not depend on the number of threads.
    pub fn par_update(
        &self,
        block: &Block,
        out: &mut [f64],
        value: impl Fn(usize, f64) -> f64 + Sync,
    ) {
        if rayon::current_num_threads() == 1 {
            // No thread to share with: the plain loop, without the
            // bookkeeping of parallel iterators.
            self.for_each(block, |index, _| out[index] = value(index, out[index]));
            return;
        }
        let slow = self.dim() - 1;
        let plane = self.strides[slow];
        let plane_points: usize = (0..slow).map(|a| block.end[a] - block.start[a]).product();
        let planes = block.start[slow]..block.end[slow];
        out[planes.start * plane..planes.end * plane]
            .par_chunks_mut(plane)
            .with_min_len(POINTS_PER_TASK.div_ceil(plane_points.max(1)))
            .enumerate()
            .for_each(|(offset, values)| {
                let first = (planes.start + offset) * plane;
                let mut inner = *block;
                inner.start[slow] = 0;
                inner.end[slow] = 1;
                self.for_each(&inner, |local, _| {
                    values[local] = value(first + local, values[local]);
                });
            });
    }
}

impl Grid {
    /// `Σ term(index, point)` over `block`: one partial sum per plane of the
    /// slowest active axis, the planes shared among threads, then the
    /// partial sums added in plane order, so the result does not depend on
    /// the number of threads.
    pub fn par_sum(&self, block: &Block, term: impl Fn(usize, [usize; 3]) -> f64 + Sync) -> f64 {
        let slow = self.dim() - 1;
        let plane_points: usize = (0..slow).map(|a| block.end[a] - block.start[a]).product();
        let plane_sum = |plane: usize| {
            let mut inner = *block;
            inner.start[slow] = plane;
            inner.end[slow] = plane + 1;
            let mut sum = 0.0;
            self.for_each(&inner, |index, point| sum += term(index, point));
            sum
        };
        let planes = block.start[slow]..block.end[slow];
        let partial: Vec<f64> = if rayon::current_num_threads() == 1 {
            planes.map(plane_sum).collect()
        } else {
            planes
                .into_par_iter()
                .with_min_len(POINTS_PER_TASK.div_ceil(plane_points.max(1)))
                .map(plane_sum)
                .collect()
        };
        partial.iter().sum()
    }

    /// `max value(index)` over `block` (0 for an empty block), the planes
    /// shared among threads (a maximum does not depend on the order).
    pub fn par_max(&self, block: &Block, value: impl Fn(usize) -> f64 + Sync) -> f64 {
        let slow = self.dim() - 1;
        let plane_points: usize = (0..slow).map(|a| block.end[a] - block.start[a]).product();
        let plane_max = |plane: usize| {
            let mut inner = *block;
            inner.start[slow] = plane;
            inner.end[slow] = plane + 1;
            let mut largest: f64 = 0.0;
            self.for_each(&inner, |index, _| largest = largest.max(value(index)));
            largest
        };
        let planes = block.start[slow]..block.end[slow];
        if rayon::current_num_threads() == 1 {
            return planes.map(plane_max).fold(0.0, f64::max);
        }
        planes
            .into_par_iter()
            .with_min_len(POINTS_PER_TASK.div_ceil(plane_points.max(1)))
            .map(plane_max)
            .reduce(|| 0.0, f64::max)
    }
}

/// Smallest number of grid points handed to one thread: below it the
/// planes of a small grid run on the calling thread.
const POINTS_PER_TASK: usize = 16_384;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_and_centres_sit_where_documented() {
        let grid = Grid::new(
            Dimension::Three,
            [4, 5, 6],
            [0.0, -1.0, 2.0],
            [2.0, 1.5, 5.0],
        );
        assert_eq!(grid.padded(), [6, 7, 8]);
        assert_eq!(grid.len(), 6 * 7 * 8);
        assert_eq!(grid.index(1, 2, 3), 1 + 6 * 2 + 42 * 3);
        assert!((grid.spacing[1] - 0.5).abs() < 1e-15);
        // First owned cell centre is half a cell inside, face 0 is the lower end.
        assert!((grid.coordinate(Location::Centre, 1, 1) - (-0.75)).abs() < 1e-15);
        assert!((grid.coordinate(Location::Face(1), 1, 0) - (-1.0)).abs() < 1e-15);
        assert!((grid.coordinate(Location::Face(1), 1, 5) - 1.5).abs() < 1e-15);
        // A face along another axis sits at the cell centre of that axis.
        assert!((grid.coordinate(Location::Face(0), 1, 1) - (-0.75)).abs() < 1e-15);
        let mut count = 0;
        grid.for_each(&grid.cell_block(), |_, _| count += 1);
        assert_eq!(count, 4 * 5 * 6);
    }

    #[test]
    fn two_dimensional_grid_has_no_z_ghosts() {
        let grid = Grid::new(Dimension::Two, [8, 4, 99], [0.0; 3], [1.0, 0.5, 7.0]);
        assert_eq!(grid.cells, [8, 4, 1]);
        assert_eq!(grid.padded(), [10, 6, 1]);
        assert_eq!(grid.interior(2), 0..1);
        assert!((grid.cell_volume() - 0.125 * 0.125).abs() < 1e-15);
    }
}
