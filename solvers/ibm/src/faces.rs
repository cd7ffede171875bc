//! The faces of one velocity component within a body's support, row by
//! row along x, with the body's solid fraction on each (eq. 8–10).
//!
//! A stage makes them once, while the particles stand still, and every
//! pass of the immersed boundaries reads them: the inner momentum before
//! and after the stage, the forcing's sums over the bodies, its loads and
//! the grid volumes. Each row holds the faces where the support sphere
//! crosses it, stored one after the other, so a pass reads the fractions
//! and the grid's faces in the same order, row by row, and takes the
//! offset `r` of a face from the centre as the row's first offset plus
//! `i Δx` along x: no coordinate is recomputed and no fraction (the
//! exponential of eq. 8, the costly part) is made twice.

use std::ops::Range;

use grainflow_core::Vec3;
use grainflow_fluid::{Block, Grid, Location};

use crate::forcing::WallLayer;
use crate::solid_fraction::{face_fractions, support};

/// A run of consecutive faces along x.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Row {
    /// Flat index of the row's first face.
    pub first: usize,
    /// Offset of the first face from the body's centre; face `i` of the
    /// row lies at `offset + i Δx x̂`.
    pub offset: Vec3,
    /// Where the row's fractions start in [`FaceRows::alpha`].
    start: usize,
    /// Faces in the row.
    pub len: usize,
}

/// A body's faces of one component within its support, with their solid
/// fractions.
#[derive(Clone, Debug)]
pub(crate) struct FaceRows {
    /// The box of faces (within the component's unknowns) that holds the
    /// support.
    pub stencil: Block,
    /// Where the rows of each plane of the stencil along the slowest axis
    /// start in `rows`, and their end.
    plane_rows: Vec<usize>,
    /// The lines of the stencil along x that cross the support, the planes
    /// of the slowest axis in order.
    rows: Vec<Row>,
    /// The fractions of all rows, one after the other.
    alpha: Vec<f64>,
    /// `Δx`, the distance between the faces of a row.
    pub step: f64,
    /// `Σ α` over the faces.
    pub sum: f64,
}

impl FaceRows {
    /// The faces of `component` in `block` within the support of a body at
    /// `centre` of `radius` (eq. 8 with `Δ = width`), their fractions zero
    /// on the faces of `free_layers`.
    pub fn new(
        width: f64,
        grid: &Grid,
        block: &Block,
        component: usize,
        centre: Vec3,
        radius: f64,
        free_layers: &[WallLayer],
    ) -> FaceRows {
        let dim = grid.dim();
        let reach = support(radius, width);
        let location = Location::Face(component);
        let mut stencil = *block;
        for axis in 0..dim {
            let index = FaceIndex::new(grid, component, axis);
            let range = index.range(centre[axis], reach, block.start[axis]..block.end[axis]);
            stencil.start[axis] = range.start;
            stencil.end[axis] = range.end;
        }
        let along_x = FaceIndex::new(grid, component, 0);
        // Only the layers the support reaches: none, for a grain away from
        // the walls.
        let layers: Vec<&WallLayer> = free_layers
            .iter()
            .filter(|layer| layer.within(centre[layer.axis], reach))
            .collect();
        let extent = [0, 1, 2].map(|a| stencil.end[a] - stencil.start[a]);
        let slow = dim - 1;
        let mut rows = Vec::with_capacity(extent[1] * extent[2]);
        let mut plane_rows = Vec::with_capacity(extent[slow] + 1);
        plane_rows.push(0);
        // Each face's offset: x, and y² + z² and |y| + |z| of its row, for
        // the fractions made all at once below.
        let capacity = extent.iter().product();
        let (mut x, mut across, mut across_l1) = (
            Vec::with_capacity(capacity),
            Vec::with_capacity(capacity),
            Vec::with_capacity(capacity),
        );
        // The offsets along y and z of the stencil's lines (zero along an
        // inactive z).
        let line_offsets = |axis: usize| -> Vec<f64> {
            (stencil.start[axis]..stencil.end[axis])
                .map(|i| match axis < dim {
                    true => grid.coordinate(location, axis, i) - centre[axis],
                    false => 0.0,
                })
                .collect()
        };
        let (across_y, across_z) = (line_offsets(1), line_offsets(2));
        for (k, &z) in (stencil.start[2]..).zip(&across_z) {
            for (j, &y) in (stencil.start[1]..).zip(&across_y) {
                let mut offset = Vec3::new(0.0, y, z);
                // The faces of the row within the support; beyond it the
                // fraction is zero (eq. 8 cut at `TAIL`), so none is lost.
                let across_squared = offset.y * offset.y + offset.z * offset.z;
                let faces = if across_squared > reach * reach {
                    stencil.start[0]..stencil.start[0]
                } else {
                    let half = (reach * reach - across_squared).sqrt();
                    along_x.range(centre.x, half, stencil.start[0]..stencil.end[0])
                };
                if faces.is_empty() {
                    if slow == 1 {
                        plane_rows.push(rows.len());
                    }
                    continue;
                }
                offset.x = grid.coordinate(location, 0, faces.start) - centre.x;
                let start = x.len();
                let len = faces.len();
                x.extend((0..len).map(|i| offset.x + i as f64 * grid.spacing[0]));
                across.resize(start + len, across_squared);
                across_l1.resize(start + len, offset.y.abs() + offset.z.abs());
                rows.push(Row {
                    first: grid.index(faces.start, j, k),
                    offset,
                    start,
                    len,
                });
                if slow == 1 {
                    plane_rows.push(rows.len());
                }
            }
            if slow == 2 {
                plane_rows.push(rows.len());
            }
        }
        let mut alpha = vec![0.0; x.len()];
        face_fractions(&x, &across, &across_l1, radius, width, &mut alpha);
        for layer in &layers {
            for row in &rows {
                let faces = &mut alpha[row.start..row.start + row.len];
                layer.clear_row(grid, component, row.first, faces);
            }
        }
        let sum = alpha.iter().sum();
        FaceRows {
            stencil,
            plane_rows,
            rows,
            alpha,
            step: grid.spacing[0],
            sum,
        }
    }

    /// Whether the body has no face of this component here.
    pub fn is_empty(&self) -> bool {
        (0..3).any(|a| self.stencil.end[a] <= self.stencil.start[a])
    }

    /// The rows of the planes `planes` (padded indices along the slowest
    /// active axis of a `dim`-dimensional grid).
    pub fn rows_in(&self, dim: usize, planes: Range<usize>) -> &[Row] {
        let slow = dim - 1;
        let (low, high) = (self.stencil.start[slow], self.stencil.end[slow]);
        let first = planes.start.clamp(low, high) - low;
        let last = planes.end.clamp(low, high) - low;
        &self.rows[self.plane_rows[first]..self.plane_rows[last]]
    }

    /// The fractions of `row`.
    #[inline]
    pub fn alpha(&self, row: &Row) -> &[f64] {
        &self.alpha[row.start..row.start + row.len]
    }

    /// Hands `visit` each row of plane `layer` (padded index along the
    /// slowest active axis of a `dim`-dimensional grid): the row's slice of
    /// `field`, a face field of that plane from flat index `first`, and
    /// the row's fractions.
    pub fn visit_plane(
        &self,
        dim: usize,
        layer: usize,
        field: &mut [f64],
        first: usize,
        mut visit: impl FnMut(&mut [f64], &[f64]),
    ) {
        for row in self.rows_in(dim, layer..layer + 1) {
            let at = row.first - first;
            visit(&mut field[at..at + row.len], self.alpha(row));
        }
    }

    /// Divides each fraction by the total of all bodies' on its face,
    /// `totals[face]`, where that exceeds one: the body's share of a face
    /// that several supports cover.
    pub fn share(&mut self, totals: &[f64]) {
        let mut changed = false;
        for row in &self.rows {
            let faces = &totals[row.first..row.first + row.len];
            let alpha = &mut self.alpha[row.start..row.start + row.len];
            for (alpha, &total) in alpha.iter_mut().zip(faces) {
                if total > 1.0 {
                    *alpha /= total;
                    changed = true;
                }
            }
        }
        if changed {
            self.sum = self.alpha.iter().sum();
        }
    }

    /// `(Σ q, Σ q r)` over the faces, `q` a scalar on each face given row
    /// by row: `row_sums(row, α)` returns `(Σ_i q_i, Σ_i i q_i)` over the
    /// row's faces `i`, whose offsets are `row.offset + i Δx x̂`.
    pub fn moments(&self, mut row_sums: impl FnMut(&Row, &[f64]) -> (f64, f64)) -> (f64, Vec3) {
        let mut sum = 0.0;
        let mut moment = Vec3::zeros();
        for row in &self.rows {
            let (plain, along) = row_sums(row, self.alpha(row));
            sum += plain;
            moment += row.offset * plain;
            moment.x += self.step * along;
        }
        (sum, moment)
    }
}

/// The padded index along one axis of the faces of one component at a
/// coordinate: `(x − lower)/h + ghost − offset`, `offset` 1 along the
/// component and ½ across it.
struct FaceIndex {
    lower: f64,
    inverse_spacing: f64,
    shift: f64,
}

impl FaceIndex {
    fn new(grid: &Grid, component: usize, axis: usize) -> Self {
        let offset = if axis == component { 1.0 } else { 0.5 };
        FaceIndex {
            lower: grid.lower[axis],
            inverse_spacing: 1.0 / grid.spacing[axis],
            shift: grid.ghost(axis) as f64 - offset,
        }
    }

    /// The faces within `reach` of the coordinate `centre`, clipped to
    /// `within`. (A face at the support's edge by round-off has a zero
    /// fraction, so the rounding here loses none.)
    fn range(&self, centre: f64, reach: f64, within: Range<usize>) -> Range<usize> {
        let index_of = |x: f64| (x - self.lower) * self.inverse_spacing + self.shift;
        let first = index_of(centre - reach).ceil().max(0.0) as usize;
        let last = index_of(centre + reach).floor();
        let start = first.max(within.start);
        let end = if last < 0.0 {
            start
        } else {
            (last as usize + 1).min(within.end)
        };
        start..end.max(start)
    }
}
