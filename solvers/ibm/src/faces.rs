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
//!
//! A row is stored in 8 bytes (its length and where it starts in the
//! body's box of faces), a seventh of its fractions at D/Δx = 4: the
//! passes are bound by memory traffic, and a row that also held its flat
//! index, offset and place among the fractions (48 bytes) weighed as much
//! as its fractions. The offsets are those of the box's lines, kept once.

use std::ops::Range;

use grainflow_core::Vec3;
use grainflow_fluid::{Block, Grid, Location};

use crate::forcing::WallLayer;
use crate::solid_fraction::{face_fractions, support};

/// A run of consecutive faces along x, as stored: its length and its first
/// face `(i, j, k)` counted from the corner of the body's box of faces.
#[derive(Clone, Copy, Debug)]
struct StoredRow {
    len: u16,
    i: u16,
    j: u16,
    k: u16,
}

/// A run of consecutive faces along x, as a pass reads it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Row<'a> {
    /// Flat index of the row's first face.
    pub first: usize,
    /// Offset of the first face from the body's centre; face `i` of the
    /// row lies at `offset + i Δx x̂`.
    pub offset: Vec3,
    /// The body's fractions on the row's faces.
    pub alpha: &'a [f64],
}

impl Row<'_> {
    /// Faces in the row.
    #[inline]
    pub fn len(&self) -> usize {
        self.alpha.len()
    }

    /// The row's faces as flat indices.
    #[inline]
    pub fn faces(&self) -> Range<usize> {
        self.first..self.first + self.alpha.len()
    }
}

/// A body's faces of one component within its support, with their solid
/// fractions.
#[derive(Clone, Debug)]
pub(crate) struct FaceRows {
    /// The box of faces (within the component's unknowns) that holds the
    /// support.
    pub stencil: Block,
    /// Flat index of the box's first face, and the grid's strides along y
    /// and z.
    origin: usize,
    strides: [usize; 2],
    /// The offsets from the centre of the box's lines along x, then y, then
    /// z (one zero along an inactive z).
    lines: Vec<f64>,
    /// Where the lines along y and along z start in `lines`.
    lines_y: usize,
    lines_z: usize,
    /// For each plane of the box along the slowest axis, and its end: the
    /// first of its rows in `rows` and of their fractions in `alpha`.
    plane_starts: Vec<(usize, usize)>,
    /// The lines of the box along x that cross the support, the planes of
    /// the slowest axis in order.
    rows: Vec<StoredRow>,
    /// The fractions of all rows, one after the other.
    alpha: Vec<f64>,
    /// `Δx`, the distance between the faces of a row.
    pub step: f64,
}

/// The offsets of a body's faces from its centre, face by face, from
/// which [`FaceRows::new`] makes all their fractions in one vector loop:
/// kept by each thread from body to body, so that a body allocates only
/// what it keeps.
#[derive(Default)]
pub(crate) struct FaceScratch {
    /// `|r|²` and `|x| + |y| + |z|` of each face's offset `r`.
    squared: Vec<f64>,
    l1: Vec<f64>,
    /// `i Δx` for the faces `i` of a row, from its first.
    along: Vec<f64>,
    /// The first and last face index of each row of a plane, unclipped.
    bounds: Vec<(f64, f64)>,
}

impl FaceRows {
    /// The faces of `component` in `block` within the support of a body at
    /// `centre` of `radius` (eq. 8 with `Δ = width`), their fractions zero
    /// on the faces of `free_layers`; `scratch` holds the faces' offsets
    /// while their fractions are made.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        width: f64,
        grid: &Grid,
        block: &Block,
        component: usize,
        centre: Vec3,
        radius: f64,
        free_layers: &[WallLayer],
        scratch: &mut FaceScratch,
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
        // The offsets of the box's lines along each axis (zero along an
        // inactive z).
        let mut lines = Vec::with_capacity(extent.iter().sum());
        for axis in 0..3 {
            lines.extend(
                (stencil.start[axis]..stencil.end[axis]).map(|i| match axis < dim {
                    true => grid.coordinate(location, axis, i) - centre[axis],
                    false => 0.0,
                }),
            );
        }
        let (lines_y, lines_z) = (extent[0], extent[0] + extent[1]);
        let mut rows = Vec::with_capacity(extent[1] * extent[2]);
        let mut plane_starts = Vec::with_capacity(extent[slow] + 1);
        plane_starts.push((0, 0));
        // Each face's offset: x, and y² + z² and |y| + |z| of its row, for
        // the fractions made all at once below.
        let FaceScratch {
            squared,
            l1,
            along,
            bounds,
        } = scratch;
        // Sized once for the whole box (kept from body to body, so this
        // rarely allocates) and written up to `made`: growing them row by
        // row counts or clears each face, which keeps these loops on
        // scalars or calls.
        let boxed = extent.iter().product();
        if squared.len() < boxed {
            squared.resize(boxed, 0.0);
            l1.resize(boxed, 0.0);
        }
        let mut made = 0;
        let short = |n: usize| u16::try_from(n).expect("a support spans fewer than 65,536 faces");
        let (reach_squared, step) = (reach * reach, grid.spacing[0]);
        along.clear();
        along.extend((0..extent[0]).map(|i| i as f64 * step));
        let x_range = stencil.start[0]..stencil.end[0];
        let lines_along_y = &lines[lines_y..lines_z];
        for k in 0..extent[2] {
            let z = lines[lines_z + k];
            // The faces of each row of the plane within the support, all
            // rows at once (vector instructions); beyond the support the
            // fraction is zero (eq. 8 cut at `TAIL`), so none is lost.
            bounds.clear();
            bounds.extend(lines_along_y.iter().map(|&y| {
                let across_squared = y * y + z * z;
                let half = (reach_squared - across_squared).max(0.0).sqrt();
                along_x.bounds(centre.x, half)
            }));
            for j in 0..extent[1] {
                let y = lines_along_y[j];
                let across_squared = y * y + z * z;
                if across_squared <= reach_squared {
                    let faces = along_x.clip(bounds[j], x_range.clone());
                    if !faces.is_empty() {
                        let i = faces.start - stencil.start[0];
                        let len = faces.len();
                        let first_x = lines[i];
                        let along = &along[..len];
                        let across_l1 = y.abs() + z.abs();
                        let row = made..made + len;
                        made += len;
                        let offsets = squared[row.clone()].iter_mut().zip(&mut l1[row]);
                        for ((squared, l1), &d) in offsets.zip(along) {
                            let x = first_x + d;
                            *squared = x * x + across_squared;
                            *l1 = x.abs() + across_l1;
                        }
                        rows.push(StoredRow {
                            len: short(len),
                            i: short(i),
                            j: short(j),
                            k: short(k),
                        });
                    }
                }
                if slow == 1 {
                    plane_starts.push((rows.len(), made));
                }
            }
            if slow == 2 {
                plane_starts.push((rows.len(), made));
            }
        }
        let alpha = face_fractions(&squared[..made], &l1[..made], radius, width);
        let mut faces = FaceRows {
            origin: grid.index(stencil.start[0], stencil.start[1], stencil.start[2]),
            strides: [grid.stride(1), grid.stride(2)],
            stencil,
            lines,
            lines_y,
            lines_z,
            plane_starts,
            rows,
            alpha,
            step,
        };
        if !layers.is_empty() {
            let mut start = 0;
            for r in 0..faces.rows.len() {
                let (first, len) = (faces.first(&faces.rows[r]), faces.rows[r].len as usize);
                let alpha = &mut faces.alpha[start..start + len];
                for layer in &layers {
                    layer.clear_row(grid, component, first, alpha);
                }
                start += len;
            }
        }
        faces
    }

    /// `Σ α` over the faces. (Made when asked: only the grid volumes of a
    /// scene with a body force read it, and it is a sum in series over
    /// every face.)
    pub fn sum(&self) -> f64 {
        self.alpha.iter().sum()
    }

    /// Whether the body has no face of this component here.
    pub fn is_empty(&self) -> bool {
        (0..3).any(|a| self.stencil.end[a] <= self.stencil.start[a])
    }

    /// Flat index of the first face of `row`.
    #[inline]
    fn first(&self, row: &StoredRow) -> usize {
        let [along_y, along_z] = self.strides;
        self.origin + row.i as usize + along_y * row.j as usize + along_z * row.k as usize
    }

    /// Offset of the first face of `row` from the body's centre.
    #[inline]
    fn offset(&self, row: &StoredRow) -> Vec3 {
        Vec3::new(
            self.lines[row.i as usize],
            self.lines[self.lines_y + row.j as usize],
            self.lines[self.lines_z + row.k as usize],
        )
    }

    /// The rows `rows` of `self.rows`, whose fractions start at `start`.
    fn rows_from(
        &self,
        rows: Range<usize>,
        mut start: usize,
    ) -> impl Iterator<Item = Row<'_>> + Clone {
        self.rows[rows].iter().map(move |row| {
            let len = row.len as usize;
            let view = Row {
                first: self.first(row),
                offset: self.offset(row),
                alpha: &self.alpha[start..start + len],
            };
            start += len;
            view
        })
    }

    /// All rows.
    pub fn rows(&self) -> impl Iterator<Item = Row<'_>> + Clone {
        self.rows_from(0..self.rows.len(), 0)
    }

    /// The faces of each row from the `ahead`-th on, as flat indices: a
    /// pass that reads row `r` asks the cache for row `r + ahead` with
    /// [`prefetch`].
    pub fn faces_ahead(&self, ahead: usize) -> impl Iterator<Item = Range<usize>> + '_ {
        self.rows.iter().skip(ahead).map(|row| {
            let first = self.first(row);
            first..first + row.len as usize
        })
    }

    /// The same faces with each fraction `α` replaced by `f(α)`.
    pub fn mapped(&self, f: impl Fn(f64) -> f64) -> FaceRows {
        let alpha: Vec<f64> = self.alpha.iter().map(|&a| f(a)).collect();
        FaceRows {
            stencil: self.stencil,
            origin: self.origin,
            strides: self.strides,
            lines: self.lines.clone(),
            lines_y: self.lines_y,
            lines_z: self.lines_z,
            plane_starts: self.plane_starts.clone(),
            rows: self.rows.clone(),
            alpha,
            step: self.step,
        }
    }

    /// The rows of the planes `planes` (padded indices along the slowest
    /// active axis of a `dim`-dimensional grid).
    pub fn rows_in(
        &self,
        dim: usize,
        planes: Range<usize>,
    ) -> impl Iterator<Item = Row<'_>> + Clone {
        let slow = dim - 1;
        let (low, high) = (self.stencil.start[slow], self.stencil.end[slow]);
        let first = planes.start.clamp(low, high) - low;
        let last = planes.end.clamp(low, high) - low;
        let (rows, start) = self.plane_starts[first];
        self.rows_from(rows..self.plane_starts[last].0, start)
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
            visit(&mut field[at..at + row.len()], row.alpha);
        }
    }

    /// Divides each fraction by the total of all bodies' on its face,
    /// `totals[face]`, where that exceeds one: the body's share of a face
    /// that several supports cover.
    pub fn share(&mut self, totals: &[f64]) {
        let mut start = 0;
        for row in &self.rows {
            let (first, len) = (self.first(row), row.len as usize);
            let faces = &totals[first..first + len];
            let alpha = &mut self.alpha[start..start + len];
            for (alpha, &total) in alpha.iter_mut().zip(faces) {
                if total > 1.0 {
                    *alpha /= total;
                }
            }
            start += len;
        }
    }

    /// [`FaceRows::share`] and [`FaceRows::moments`] of `q = α v` in one
    /// pass over the rows, `v` the face field `field`: each fraction
    /// becomes its share and is read at once for the fluid's momentum in
    /// the body (the same sums, in the same order, as the two passes), and
    /// for [`FaceRows::sum`] of the shares (the same bits), which the grid
    /// volumes of a scene with a body force read.
    pub fn share_and_weigh(&mut self, totals: &[f64], field: &[f64]) -> (f64, Vec3, f64) {
        let (mut sum, mut moment) = (0.0, Vec3::zeros());
        let mut fractions = 0.0;
        let mut start = 0;
        for r in 0..self.rows.len() {
            // `faces_ahead` would borrow the fractions this pass rewrites.
            if let Some(later) = self.rows.get(r + PREFETCH_ROWS) {
                let first = self.first(later);
                let later = first..first + later.len as usize;
                prefetch(&[totals, field], &later);
            }
            let stored = self.rows[r];
            let (first, len) = (self.first(&stored), stored.len as usize);
            let faces = first..first + len;
            let (totals, values) = (&totals[faces.clone()], &field[faces]);
            let alpha = &mut self.alpha[start..start + len];
            let (mut plain, mut along) = (0.0, 0.0);
            let rows = alpha.iter_mut().zip(totals.iter().zip(values));
            for (i, (alpha, (&total, &value))) in rows.enumerate() {
                if total > 1.0 {
                    *alpha /= total;
                }
                fractions += *alpha;
                let q = *alpha * value;
                plain += q;
                along += i as f64 * q;
            }
            sum += plain;
            moment += self.offset(&stored) * plain;
            moment.x += self.step * along;
            start += len;
        }
        (sum, moment, fractions)
    }

    /// `(Σ q, Σ q r)` over the faces, `q` a scalar on each face given row
    /// by row: `row_sums(row)` returns `(Σ_i q_i, Σ_i i q_i)` over the
    /// row's faces `i`, whose offsets are `row.offset + i Δx x̂`. `reads`
    /// are the face fields `row_sums` reads, asked for ahead ([`prefetch`]).
    pub fn moments(
        &self,
        reads: &[&[f64]],
        mut row_sums: impl FnMut(&Row) -> (f64, f64),
    ) -> (f64, Vec3) {
        let mut sum = 0.0;
        let mut moment = Vec3::zeros();
        let mut ahead = self.faces_ahead(PREFETCH_ROWS);
        for row in self.rows() {
            if let Some(later) = ahead.next() {
                prefetch(reads, &later);
            }
            let (plain, along) = row_sums(&row);
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
        self.clip(self.bounds(centre, reach), within)
    }

    /// The first and last index within `reach` of `centre`, as floats
    /// (the first at least zero).
    #[inline(always)]
    fn bounds(&self, centre: f64, reach: f64) -> (f64, f64) {
        let index_of = |x: f64| (x - self.lower) * self.inverse_spacing + self.shift;
        (
            index_of(centre - reach).ceil().max(0.0),
            index_of(centre + reach).floor(),
        )
    }

    /// The indices from [`FaceIndex::bounds`] clipped to `within`.
    #[inline(always)]
    fn clip(&self, (first, last): (f64, f64), within: Range<usize>) -> Range<usize> {
        let first = first as usize;
        let start = first.max(within.start);
        let end = if last < 0.0 {
            start
        } else {
            (last as usize + 1).min(within.end)
        };
        start..end.max(start)
    }
}

/// How many rows ahead a pass asks for the rows it will read. Measured on
/// many grains (D/Δx = 4, rows of about seven faces), one thread, the
/// immersed boundaries against the flow in the same runs: 2 and 4 rows
/// ahead 0.98–1.03, 8 rows 0.89–1.01, 16 rows 0.90–0.97 (medians 0.997
/// for 4, 0.944 for 8); on the avalanche 4, 8 and 16 alike.
pub(crate) const PREFETCH_ROWS: usize = 8;

/// Asks the cache for the lines of each of `fields` that hold `faces`,
/// ahead of a pass that will read them. A pass over a body's rows jumps
/// from row to row by a stride of the grid, which the hardware does not
/// foresee, and waits on each row's first line (a no-op off x86-64).
#[inline(always)]
pub(crate) fn prefetch(fields: &[&[f64]], faces: &Range<usize>) {
    #[cfg(target_arch = "x86_64")]
    for field in fields {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        if faces.end <= field.len() && faces.start < faces.end {
            // SAFETY: prefetching reads nothing and faults on nothing;
            // the addresses are inside `field` anyway.
            unsafe {
                let base = field.as_ptr();
                _mm_prefetch::<_MM_HINT_T0>(base.add(faces.start) as *const i8);
                _mm_prefetch::<_MM_HINT_T0>(base.add(faces.end - 1) as *const i8);
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (fields, faces);
    }
}
