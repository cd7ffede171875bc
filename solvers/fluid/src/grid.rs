//! The staggered (MAC) grid of a rank's subdomain.
//!
//! Pressure lives at cell centres; the velocity component along axis `a`
//! lives on the faces normal to `a` (Izard et al. 2014, eq. 1–2 are
//! discretised on this arrangement, which couples pressure and velocity
//! without odd–even modes). Spacing is uniform along every axis but the
//! last active one (z in 3D, y in 2D), which may be stretched: the direct
//! solvers diagonalise the other axes by transforms, which need a uniform
//! spacing, and eliminate along the last one, which does not (as in CaNS,
//! where the wall-normal axis is the stretched one). A stretched axis is
//! given by its face coordinates ([`Grid::stretched`], or
//! [`clustered_faces`] for the usual tanh clustering at walls).
//!
//! Every field is one flat `Vec<f64>` over the padded block: the `cells`
//! of the subdomain plus one ghost layer on each side of every active axis
//! (x fastest, then y, then z). In 2D the z axis has one cell and no ghost
//! layer. Padded index `i` along an active axis covers:
//!
//! - cell centres at `lower + (i - 1/2) h` for `i = 0..=n+1` (0 and n+1 are ghosts),
//! - faces at `lower + i h` for `i = 0..=n+1`: face `i` is the upper face of
//!   cell `i`, so faces 0 and `n` are the lower and upper ends of the subdomain.
//!
//! Along a stretched axis cell `i` has width `w_i` (the ghost cells mirror
//! the first and last cells, so a wall lies midway between a ghost centre
//! and the first centre), its centre lies midway between its faces, and
//! `g_i = (w_i + w_{i+1}) / 2` is the distance between centres `i` and
//! `i + 1`: the control length of face `i`. The operators use `w` for
//! differences of face values and `g` for differences of centre values, so
//! the divergence of a gradient is still the three-point Laplacian the
//! pressure solver inverts, and the projection stays exact.

use std::ops::Range;

use rayon::prelude::*;

use grainflow_core::Dimension;

use crate::error::FluidError;

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

/// The staggered grid of one subdomain.
#[derive(Clone, Debug)]
pub struct Grid {
    pub dimension: Dimension,
    /// Cells along x, y, z (z is 1 in 2D).
    pub cells: [usize; 3],
    /// Lower corner of the subdomain (m).
    pub lower: [f64; 3],
    /// Upper corner of the subdomain (m).
    pub upper: [f64; 3],
    /// Cell size along each axis (m); along a stretched axis the mean
    /// width (the extent over the cells): use [`Grid::width`] and
    /// [`Grid::gap`] there.
    pub spacing: [f64; 3],
    ghost: [usize; 3],
    padded: [usize; 3],
    strides: [usize; 3],
    line: LineSpacing,
}

/// The spacing of the last active axis, cell by cell (padded indices).
#[derive(Clone, Debug)]
struct LineSpacing {
    uniform: bool,
    /// Coordinate of face `i`, the upper face of padded cell `i`, `i = 0..=n+1`.
    faces: Vec<f64>,
    /// Width `w_i` of padded cell `i`.
    widths: Vec<f64>,
    /// Distance `g_i` from centre `i` to centre `i + 1` (`i = 0..=n`; the
    /// last entry repeats the ghost's width).
    gaps: Vec<f64>,
    /// Weights `[lower, upper]` of the three-point Laplacian of a field at
    /// cell centres along the axis, at padded cell `i`:
    /// `(1/w_i) [(f_{i+1} − f_i)/g_i − (f_i − f_{i−1})/g_{i−1}]`.
    centre_laplacian: Vec<[f64; 2]>,
    /// The same for a field on the faces normal to the axis, at face `i`:
    /// `(1/g_i) [(f_{i+1} − f_i)/w_{i+1} − (f_i − f_{i−1})/w_i]`.
    face_laplacian: Vec<[f64; 2]>,
}

impl LineSpacing {
    /// `cells` cells of width `h` from `lower`: every width and gap is
    /// exactly `h`, so the operators reduce to their uniform forms.
    fn uniform(cells: usize, lower: f64, h: f64) -> Self {
        let faces = (0..cells + 2).map(|i| lower + i as f64 * h).collect();
        Self::build(faces, vec![h; cells + 2], vec![h; cells + 2], true)
    }

    /// From the owned faces `f_0 < … < f_n`.
    fn from_faces(owned: &[f64]) -> Self {
        let n = owned.len() - 1;
        let mut widths = vec![0.0; n + 2];
        for i in 1..=n {
            widths[i] = owned[i] - owned[i - 1];
        }
        widths[0] = widths[1];
        widths[n + 1] = widths[n];
        let mut faces = owned.to_vec();
        faces.push(owned[n] + widths[n + 1]);
        let mut gaps: Vec<f64> = (0..=n).map(|i| 0.5 * (widths[i] + widths[i + 1])).collect();
        gaps.push(widths[n + 1]);
        Self::build(faces, widths, gaps, false)
    }

    fn build(faces: Vec<f64>, widths: Vec<f64>, gaps: Vec<f64>, uniform: bool) -> Self {
        let last = widths.len() - 1;
        let centre_laplacian = (0..=last)
            .map(|i| {
                let below = gaps[i.saturating_sub(1)];
                [1.0 / (widths[i] * below), 1.0 / (widths[i] * gaps[i])]
            })
            .collect();
        let face_laplacian = (0..=last)
            .map(|i| {
                let above = widths[(i + 1).min(last)];
                [1.0 / (gaps[i] * widths[i]), 1.0 / (gaps[i] * above)]
            })
            .collect();
        LineSpacing {
            uniform,
            faces,
            widths,
            gaps,
            centre_laplacian,
            face_laplacian,
        }
    }
}

/// Where a stretched axis clusters its cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clustering {
    /// Fine at both ends (a channel between two walls).
    BothEnds,
    /// Fine at the lower end (a bed or a single wall below).
    Lower,
    /// Fine at the upper end.
    Upper,
}

/// Face coordinates `f_0 = lower < … < f_n = upper` of `cells` cells
/// clustered by the hyperbolic-tangent map of the uniform coordinate
/// `ξ = i/n` with factor `β > 0` (larger is finer at the clustered ends;
/// `β → 0` is uniform):
///
/// - both ends: `f = lower + L/2 (1 + tanh(β (2ξ − 1)) / tanh β)`,
/// - lower end: `f = lower + L (1 + tanh(β (ξ − 1)) / tanh β)`,
/// - upper end: `f = lower + L tanh(β ξ) / tanh β`.
///
/// The map is smooth, so adjacent widths differ by `O(1/n)` relatively and
/// the central differences stay second order on it.
pub fn clustered_faces(
    clustering: Clustering,
    factor: f64,
    cells: usize,
    lower: f64,
    upper: f64,
) -> Vec<f64> {
    let length = upper - lower;
    let scale = factor.tanh();
    let mut faces: Vec<f64> = (0..=cells)
        .map(|i| {
            let xi = i as f64 / cells as f64;
            let unit = match clustering {
                Clustering::BothEnds => 0.5 * (1.0 + (factor * (2.0 * xi - 1.0)).tanh() / scale),
                Clustering::Lower => 1.0 + (factor * (xi - 1.0)).tanh() / scale,
                Clustering::Upper => (factor * xi).tanh() / scale,
            };
            lower + length * unit
        })
        .collect();
    faces[0] = lower;
    faces[cells] = upper;
    faces
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
        let line_axis = active - 1;
        let line = LineSpacing::uniform(cells[line_axis], lower[line_axis], spacing[line_axis]);
        Grid {
            dimension,
            cells,
            lower,
            upper,
            spacing,
            ghost,
            padded,
            strides,
            line,
        }
    }

    /// A grid uniform along all axes but the last active one (z in 3D, y
    /// in 2D), whose `cells + 1` face coordinates are `faces`, from the
    /// lower to the upper corner. Refuses faces that are not strictly
    /// increasing, do not match the corners, or are not `cells + 1`.
    pub fn stretched(
        dimension: Dimension,
        cells: [usize; 3],
        lower: [f64; 3],
        upper: [f64; 3],
        faces: &[f64],
    ) -> Result<Self, FluidError> {
        let mut grid = Grid::new(dimension, cells, lower, upper);
        let axis = grid.line_axis();
        let n = grid.cells[axis];
        let name = ["x", "y", "z"][axis];
        if faces.len() != n + 1 {
            return Err(FluidError::Parameter(format!(
                "the stretched {name} axis has {n} cells and needs {} face coordinates, got {}",
                n + 1,
                faces.len()
            )));
        }
        let extent = upper[axis] - lower[axis];
        let tolerance = 1e-12 * extent;
        if (faces[0] - lower[axis]).abs() > tolerance || (faces[n] - upper[axis]).abs() > tolerance
        {
            return Err(FluidError::Parameter(format!(
                "the stretched {name} axis must run from {} to {}, its faces run from {} to {}",
                lower[axis], upper[axis], faces[0], faces[n]
            )));
        }
        if let Some(i) = (1..=n)
            .find(|&i| faces[i].partial_cmp(&faces[i - 1]) != Some(std::cmp::Ordering::Greater))
        {
            return Err(FluidError::Parameter(format!(
                "the faces of the stretched {name} axis must increase strictly: face {i} at {} \
                 follows {}",
                faces[i],
                faces[i - 1]
            )));
        }
        let mut owned = faces.to_vec();
        owned[0] = lower[axis];
        owned[n] = upper[axis];
        grid.line = LineSpacing::from_faces(&owned);
        Ok(grid)
    }

    /// The part of this grid made of `cells` cells from cell `offset` along
    /// each axis, with the same spacing: a rank's share
    /// ([`crate::Partition::local_grid`]). The last axis stays whole.
    pub fn sub_grid(&self, offset: [usize; 3], cells: [usize; 3]) -> Grid {
        let mut sub = self.clone();
        for axis in 0..self.dim() {
            if axis == self.line_axis() {
                assert!(
                    offset[axis] == 0 && cells[axis] == self.cells[axis],
                    "the last axis is not split"
                );
                continue;
            }
            assert!(cells[axis] >= 2 && offset[axis] + cells[axis] <= self.cells[axis]);
            let h = self.spacing[axis];
            sub.cells[axis] = cells[axis];
            sub.lower[axis] = self.lower[axis] + offset[axis] as f64 * h;
            sub.upper[axis] = if offset[axis] + cells[axis] == self.cells[axis] {
                self.upper[axis]
            } else {
                self.lower[axis] + (offset[axis] + cells[axis]) as f64 * h
            };
        }
        sub.padded = [0, 1, 2].map(|a| sub.cells[a] + 2 * sub.ghost[a]);
        sub.strides = [1, sub.padded[0], sub.padded[0] * sub.padded[1]];
        sub
    }

    /// Number of active axes (2 or 3).
    pub fn dim(&self) -> usize {
        self.dimension.count()
    }

    /// The last active axis (z in 3D, y in 2D): the one solved by
    /// elimination, the only one that may be stretched.
    pub fn line_axis(&self) -> usize {
        self.dim() - 1
    }

    /// Whether the cells along `axis` all have the same width.
    pub fn is_uniform(&self, axis: usize) -> bool {
        axis != self.line_axis() || self.line.uniform
    }

    /// Width of padded cell `i` along `axis` (the ghosts mirror their
    /// neighbours).
    #[inline]
    pub fn width(&self, axis: usize, i: usize) -> f64 {
        if axis == self.line_axis() {
            self.line.widths[i]
        } else {
            self.spacing[axis]
        }
    }

    /// Distance along `axis` between the centres of padded cells `i` and
    /// `i + 1`: the control length of face `i`.
    #[inline]
    pub fn gap(&self, axis: usize, i: usize) -> f64 {
        if axis == self.line_axis() {
            self.line.gaps[i]
        } else {
            self.spacing[axis]
        }
    }

    /// Smallest cell width along `axis`.
    pub fn min_width(&self, axis: usize) -> f64 {
        if self.is_uniform(axis) {
            return self.spacing[axis];
        }
        self.line
            .widths
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// Largest ratio of the widths of two adjacent owned cells along
    /// `axis` (1 on a uniform axis): a measure of how abruptly the grid
    /// is stretched.
    pub fn max_growth(&self, axis: usize) -> f64 {
        if self.is_uniform(axis) {
            return 1.0;
        }
        let widths = &self.line.widths[self.interior(axis)];
        widths
            .windows(2)
            .map(|pair| (pair[1] / pair[0]).max(pair[0] / pair[1]))
            .fold(1.0, f64::max)
    }

    /// An upper bound of the largest |eigenvalue| of the three-point
    /// Laplacian along `axis`: `4/h²` on a uniform axis, the Gershgorin
    /// bound `max_i 2 (lower_i + upper_i)` of its weights on a stretched one.
    pub fn laplacian_bound(&self, axis: usize) -> f64 {
        if self.is_uniform(axis) {
            let h = self.spacing[axis];
            return 4.0 / (h * h);
        }
        let line = &self.line;
        self.interior(axis)
            .flat_map(|i| [line.centre_laplacian[i], line.face_laplacian[i]])
            .map(|[below, above]| 2.0 * (below + above))
            .fold(0.0, f64::max)
    }

    /// Weights `[wall, first, second]` of the quadratic wall ghost along the
    /// line axis at `side` (0 lower, 1 upper): the value at the ghost centre
    /// of the parabola through the wall value (on the wall face) and the
    /// first two centres from the wall. `[8/3, −2, 1/3]` on a uniform axis.
    pub fn wall_ghost_weights(&self, side: usize) -> [f64; 3] {
        let n = self.cells[self.line_axis()];
        let widths = &self.line.widths;
        let (first, second) = if side == 0 {
            (widths[1], widths[2])
        } else {
            (widths[n], widths[n - 1])
        };
        // Distances from the wall; the ghost mirrors the first cell.
        let ghost = -0.5 * first;
        let near = 0.5 * first;
        let far = first + 0.5 * second;
        [
            (ghost - near) * (ghost - far) / (near * far),
            ghost * (ghost - far) / (near * (near - far)),
            ghost * (ghost - near) / (far * (far - near)),
        ]
    }

    /// Coordinates of the owned faces along `axis`, lower to upper end.
    pub fn face_coordinates(&self, axis: usize) -> Vec<f64> {
        if self.ghost[axis] == 0 {
            return vec![self.lower[axis], self.upper[axis]];
        }
        (0..=self.cells[axis])
            .map(|i| self.coordinate(Location::Face(axis), axis, i + self.ghost[axis] - 1))
            .collect()
    }

    /// Weights `[lower, upper]` of the three-point Laplacian along the
    /// line axis at padded index `i` of a field at `location` (see the
    /// module documentation); `1/h²` twice on a uniform axis.
    #[inline]
    pub fn line_laplacian(&self, location: Location, i: usize) -> [f64; 2] {
        if location == Location::Face(self.line_axis()) {
            self.line.face_laplacian[i]
        } else {
            self.line.centre_laplacian[i]
        }
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

    /// Volume of a cell (area in 2D) of a uniform grid; on a stretched
    /// grid the mean volume.
    pub fn cell_volume(&self) -> f64 {
        self.spacing[..self.dim()].iter().product()
    }

    /// Product of the widths along the axes other than the line axis:
    /// the volume of a cell (area in 2D) per unit length along it.
    pub fn section_area(&self) -> f64 {
        self.spacing[..self.line_axis()].iter().product()
    }

    /// Coordinate along `axis` of padded index `i` of a field at `location`.
    pub fn coordinate(&self, location: Location, axis: usize, i: usize) -> f64 {
        let on_face = location == Location::Face(axis);
        if !self.is_uniform(axis) {
            let face = self.line.faces[i];
            return if on_face {
                face
            } else {
                face - 0.5 * self.line.widths[i]
            };
        }
        let offset = if on_face { 1.0 } else { 0.5 };
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
        self.par_update_planes(block, out, |_| &value);
    }

    /// [`Grid::par_update`] with a kernel made per plane: `kernel(plane)`,
    /// `plane` the padded index along the slowest active axis (the line
    /// axis, the one that may be stretched), returns the point update
    /// `value(index, out[index])` of that plane, so that the weights of a
    /// stretched axis are looked up once per plane, not per point.
    pub fn par_update_planes<K, V>(&self, block: &Block, out: &mut [f64], kernel: K)
    where
        K: Fn(usize) -> V + Sync,
        V: Fn(usize, f64) -> f64,
    {
        let slow = self.dim() - 1;
        let plane = self.strides[slow];
        let planes = block.start[slow]..block.end[slow];
        let mut inner = *block;
        inner.start[slow] = 0;
        inner.end[slow] = 1;
        if rayon::current_num_threads() == 1 {
            // No thread to share with: the plain loop, without the
            // bookkeeping of parallel iterators.
            for layer in planes {
                let value = kernel(layer);
                let first = layer * plane;
                let values = &mut out[first..first + plane];
                self.for_each(&inner, |local, _| {
                    values[local] = value(first + local, values[local]);
                });
            }
            return;
        }
        let plane_points: usize = (0..slow).map(|a| block.end[a] - block.start[a]).product();
        out[planes.start * plane..planes.end * plane]
            .par_chunks_mut(plane)
            .with_min_len(POINTS_PER_TASK.div_ceil(plane_points.max(1)))
            .enumerate()
            .for_each(|(offset, values)| {
                let layer = planes.start + offset;
                let value = kernel(layer);
                let first = layer * plane;
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
    /// `value(index, plane)` is given the padded index along the slowest
    /// active axis, as in [`Grid::par_update_planes`].
    pub fn par_max(&self, block: &Block, value: impl Fn(usize, usize) -> f64 + Sync) -> f64 {
        let slow = self.dim() - 1;
        let plane_points: usize = (0..slow).map(|a| block.end[a] - block.start[a]).product();
        let plane_max = |plane: usize| {
            let mut inner = *block;
            inner.start[slow] = plane;
            inner.end[slow] = plane + 1;
            let mut largest: f64 = 0.0;
            self.for_each(&inner, |index, _| {
                largest = largest.max(value(index, plane))
            });
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
