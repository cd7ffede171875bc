//! The tridiagonal systems along the line axis: the three-point operator
//! of a line with its end closures, the systems of all modes together, and
//! the Thomas algorithm (Sherman–Morrison for a periodic line).

use super::*;

/// The three-point operator along a line, row by row: row `j` reads
/// `lower_j x_{j−1} + shift_j x_j + upper_j x_{j+1}`, the end closures
/// folded into the first and last rows (`lower_0` and `upper_{n−1}` unused
/// unless the line is periodic). `width_j` is the width of the row's
/// control volume, the weight under which the operator is symmetric.
#[derive(Clone, Debug, Default)]
pub(super) struct LineRows {
    pub(super) lower: Vec<f64>,
    pub(super) shift: Vec<f64>,
    pub(super) upper: Vec<f64>,
    pub(super) width: Vec<f64>,
}

impl LineRows {
    /// The line operator of a field at `location` along the line axis of
    /// `grid`, rows `first..first + length` (padded), closed by `ends`.
    pub(super) fn new(
        grid: &Grid,
        location: Location,
        first: usize,
        length: usize,
        ends: [EndKind; 2],
    ) -> Self {
        let axis = grid.line_axis();
        let mut rows = LineRows::default();
        for j in 0..length {
            let [below, above] = grid.line_laplacian(location, first + j);
            rows.lower.push(below);
            rows.upper.push(above);
            rows.shift.push(-(below + above));
            rows.width.push(if location == Location::Face(axis) {
                grid.gap(axis, first + j)
            } else {
                grid.width(axis, first + j)
            });
        }
        // What the ghost beyond each end puts on its row: `ghost = a x_near
        // + b x_far` (homogeneous), so the row's diagonal gains `a` times
        // the coupling to the ghost and its inner neighbour `b` times it.
        for side in 0..2 {
            let [near, far] = match ends[side] {
                EndKind::Neumann => [1.0, 0.0],
                EndKind::DirichletCell => [-1.0, 0.0],
                EndKind::DirichletCellQuadratic => {
                    let [_, near, far] = grid.wall_ghost_weights(side);
                    [near, far]
                }
                EndKind::DirichletFace | EndKind::Periodic => [0.0, 0.0],
                EndKind::Halo => unreachable!("the line axis is never split among ranks"),
            };
            // The end row couples outwards to the ghost, inwards to the
            // row next to it (which the quadratic ghost also reads).
            let (row, outward, inward) = if side == 0 {
                (0, &rows.lower, &mut rows.upper)
            } else {
                (length - 1, &rows.upper, &mut rows.lower)
            };
            let coupling = outward[row];
            debug_assert!(far == 0.0 || length >= 2);
            rows.shift[row] += near * coupling;
            inward[row] += far * coupling;
        }
        rows
    }

    /// The same rows times `factor`.
    fn scaled(&self, factor: f64, out: &mut LineRows) {
        let scale = |from: &[f64], to: &mut Vec<f64>| {
            to.clear();
            to.extend(from.iter().map(|value| factor * value));
        };
        scale(&self.lower, &mut out.lower);
        scale(&self.shift, &mut out.shift);
        scale(&self.upper, &mut out.upper);
    }
}

/// Work arrays of the tridiagonal systems of all modes: the line operator
/// `rows` scaled by the Laplacian's coefficient, and per mode the diagonal
/// part `base` that the transformed axes and the identity add to every row
/// (the first and last rows of a periodic line add a Sherman–Morrison
/// term). Row `j` of mode `m` is at `m + j · modes` in a flat array.
pub(super) struct ModeLines {
    pub(super) rows: LineRows,
    pub(super) base: Vec<f64>,
    pub(super) first: Vec<f64>,
    pub(super) last: Vec<f64>,
    /// The elimination's modified upper diagonal, one per row and mode.
    pub(super) modified: Vec<f64>,
    /// Sherman–Morrison correction of a periodic line, one per row and mode.
    pub(super) correction: Vec<f64>,
    /// `γ = −b₀` of the Sherman–Morrison update, per mode.
    pub(super) gamma: Vec<f64>,
    pub(super) singular_line: Vec<f64>,
}

impl ModeLines {
    pub(super) fn new(modes: usize, length: usize, periodic: bool) -> Self {
        ModeLines {
            rows: LineRows::default(),
            base: vec![0.0; modes],
            first: vec![0.0; modes],
            last: vec![0.0; modes],
            modified: vec![0.0; modes * length],
            correction: if periodic {
                vec![0.0; modes * length]
            } else {
                Vec::new()
            },
            gamma: if periodic {
                vec![0.0; modes]
            } else {
                Vec::new()
            },
            singular_line: Vec::with_capacity(length),
        }
    }

    /// Solves the lines of every mode of `values` (row `j` of mode `m` at
    /// `m + j · modes`, `modes = modal.len()`):
    /// `(identity + laplacian Σλ_m) x + laplacian L_line x = r`, with
    /// `Σλ_m` in `modal` and `line` the line operator `L_line`, closed by
    /// `ends`. The one singular mode of a pure Neumann or periodic Poisson
    /// problem (`Σλ = 0`) is solved apart ([`ModeLines::solve_singular`]).
    pub(super) fn solve(
        &mut self,
        values: &mut [f64],
        modal: &[f64],
        line: &LineRows,
        ends: [EndKind; 2],
        identity: f64,
        laplacian: f64,
    ) {
        let length = line.shift.len();
        let stride = modal.len();
        debug_assert_eq!(values.len(), stride * length);
        line.scaled(laplacian, &mut self.rows);
        let periodic = ends[0] == EndKind::Periodic;
        let singular = identity == 0.0
            && modal[0] == 0.0
            && ends
                .iter()
                .all(|&kind| matches!(kind, EndKind::Periodic | EndKind::Neumann));
        for (base, &modal) in self.base.iter_mut().zip(modal) {
            *base = identity + laplacian * modal;
        }
        if singular {
            // Set the singular mode aside; it is swept as the identity.
            self.singular_line.clear();
            self.singular_line
                .extend((0..length).map(|j| values[j * stride]));
        }
        if periodic {
            self.solve_cyclic(values, length, singular);
        } else {
            self.sweep(values, length, singular);
        }
        if singular {
            let solution = self.solve_singular(length, &line.width);
            for (j, value) in solution.iter().enumerate() {
                values[j * stride] = *value;
            }
        }
    }

    /// The per-mode diagonal parts of the first and last rows, `base`
    /// until a periodic line changes them. Mode 0 of a singular system is
    /// swept as the identity ([`thomas`]); its first row gets a unit
    /// diagonal so that a periodic line's `γ` stays finite.
    fn end_bases(&mut self, singular: bool) {
        self.first.copy_from_slice(&self.base);
        self.last.copy_from_slice(&self.base);
        if singular {
            self.first[0] = 1.0 - self.rows.shift[0];
        }
    }

    /// Thomas algorithm on every mode: `rhs` is overwritten with the
    /// solutions.
    fn sweep(&mut self, rhs: &mut [f64], length: usize, singular: bool) {
        self.end_bases(singular);
        let bases = [&self.first[..], &self.base[..], &self.last[..]];
        thomas(rhs, &mut self.modified, length, &self.rows, bases, singular);
    }

    /// Periodic lines (uniform, so every row has the same coupling `c`):
    /// the corner entries `c` are a rank-one update `u vᵀ` of a
    /// tridiagonal matrix, `u = (γ, 0, …, 0, c)`, `v = (1, 0, …, 0, c/γ)`
    /// with `γ = −b₀` (Sherman–Morrison); two sweeps, then
    /// `x = y − z (v·y) / (1 + v·z)`.
    fn solve_cyclic(&mut self, rhs: &mut [f64], length: usize, singular: bool) {
        self.end_bases(singular);
        let modes = self.first.len();
        let last_row = (length - 1) * modes;
        let coupling = self.rows.upper[0];
        self.correction.fill(0.0);
        for m in 0..modes {
            let gamma = -(self.first[m] + self.rows.shift[0]);
            self.gamma[m] = gamma;
            self.correction[m] = gamma;
            self.correction[last_row + m] = coupling;
            self.first[m] -= gamma;
            self.last[m] -= coupling * coupling / gamma;
        }
        let bases = [&self.first[..], &self.base[..], &self.last[..]];
        thomas(rhs, &mut self.modified, length, &self.rows, bases, singular);
        thomas(
            &mut self.correction,
            &mut self.modified,
            length,
            &self.rows,
            bases,
            singular,
        );
        // v·y / (1 + v·z) per mode, kept in `gamma`'s place once used.
        for m in 0..modes {
            let ratio = coupling / self.gamma[m];
            let numerator = rhs[m] + ratio * rhs[last_row + m];
            let denominator = 1.0 + self.correction[m] + ratio * self.correction[last_row + m];
            self.gamma[m] = numerator / denominator;
        }
        let factor = &self.gamma;
        for (row, correction) in rhs
            .chunks_exact_mut(modes)
            .zip(self.correction.chunks_exact(modes))
        {
            for m in 0..modes {
                row[m] -= factor[m] * correction[m];
            }
        }
    }

    /// The singular mode of a pure Neumann or periodic Laplacian: remove
    /// the mean of the right-hand side, weighted by the rows' widths (the
    /// compatibility condition: the operator conserves `Σ w_j x_j`), pin
    /// the first value to zero and drop its row (implied by the others),
    /// then shift the solution to zero mean. For a periodic line the
    /// wrap-around couplings to the pinned value vanish too.
    fn solve_singular(&mut self, length: usize, widths: &[f64]) -> &[f64] {
        let line = &mut self.singular_line;
        let total: f64 = widths.iter().sum();
        let weighted_mean =
            |line: &[f64]| line.iter().zip(widths).map(|(x, w)| x * w).sum::<f64>() / total;
        let mean = weighted_mean(line);
        line.iter_mut().for_each(|r| *r -= mean);
        line[0] = 0.0;
        // Rows 1..n of the line operator, without their coupling to x_0.
        let rows = &self.rows;
        let mut reduced = LineRows {
            lower: rows.lower[1..].to_vec(),
            shift: rows.shift[1..].to_vec(),
            upper: rows.upper[1..].to_vec(),
            width: Vec::new(),
        };
        reduced.lower[0] = 0.0;
        let zero = [0.0];
        let mut modified = vec![0.0; length - 1];
        thomas(
            &mut line[1..],
            &mut modified,
            length - 1,
            &reduced,
            [&zero[..], &zero[..], &zero[..]],
            false,
        );
        let mean = weighted_mean(line);
        line.iter_mut().for_each(|x| *x -= mean);
        line
    }
}

/// Thomas algorithm for `modes = bases[0].len()` independent tridiagonal
/// systems of `length` rows, row `j` of mode `m` reading
/// `lower_j x_{j−1} + (base_m + shift_j) x_j + upper_j x_{j+1}` with
/// `base` taken from `bases = [first row, interior rows, last row]`;
/// right-hand sides in `rhs` (row-major over modes), overwritten with the
/// solutions. With `identity_first_mode`, mode 0 solves the identity
/// instead (its diagonal is 1, its off-diagonals 0): the place holder of a
/// singular mode solved apart.
fn thomas(
    rhs: &mut [f64],
    modified: &mut [f64],
    length: usize,
    rows: &LineRows,
    bases: [&[f64]; 3],
    identity_first_mode: bool,
) {
    let [first, interior, last] = bases;
    let modes = first.len();
    for m in 0..modes {
        let pivot = first[m] + rows.shift[0];
        modified[m] = rows.upper[0] / pivot;
        rhs[m] /= pivot;
    }
    if identity_first_mode {
        modified[0] = 0.0;
        rhs[0] = 0.0;
    }
    for j in 1..length {
        let base = if j == length - 1 { last } else { interior };
        let (lower, shift, upper) = (rows.lower[j], rows.shift[j], rows.upper[j]);
        let (done, rest) = rhs.split_at_mut(j * modes);
        let previous = &done[(j - 1) * modes..];
        let current = &mut rest[..modes];
        let (done_modified, rest_modified) = modified.split_at_mut(j * modes);
        let previous_modified = &done_modified[(j - 1) * modes..];
        let current_modified = &mut rest_modified[..modes];
        for m in 0..modes {
            let pivot = base[m] + shift - lower * previous_modified[m];
            current_modified[m] = upper / pivot;
            current[m] = (current[m] - lower * previous[m]) / pivot;
        }
        if identity_first_mode {
            current_modified[0] = 0.0;
            current[0] = 0.0;
        }
    }
    for j in (0..length - 1).rev() {
        let (head, tail) = rhs.split_at_mut((j + 1) * modes);
        let current = &mut head[j * modes..];
        let next = &tail[..modes];
        let current_modified = &modified[j * modes..(j + 1) * modes];
        for m in 0..modes {
            current[m] -= current_modified[m] * next[m];
        }
    }
}
