//! The direct solver of `(a I + b L) x = f` for one field of an (r, z)
//! flow, `L` being its Laplacian: transforms along z (uniform, see
//! [`crate::transform`]) turn `L` into `A_r + λ_m` for each axial mode `m`,
//! `λ_m = −(2 − 2 cos θ_m)/h²`, and each mode's radial line is a
//! tridiagonal system, eliminated by the Thomas algorithm. The result is
//! the exact inverse of the discrete operator, to round-off.
//!
//! The pressure's Laplacian (`a = 0`, zero gradient at every wall) is
//! singular on the constant: its mode `λ = 0` drops the last radial
//! equation (which the compatible right-hand side satisfies once the others
//! are) and the solution is shifted to zero volume mean.
//!
//! The elimination sweeps the radial rows once for all the modes together,
//! its inner loop over the modes (vector instructions); the transforms run
//! on the threads.

use crate::transform::{AxisTransform, Direction};

use super::grid::RzGrid;
use super::radial::RadialOperator;

/// A direct solver for one field's `(a I + b L)`.
pub struct RzDirectSolver {
    radial: RadialOperator,
    /// Padded z indices of the unknowns.
    z_rows: std::ops::Range<usize>,
    transform: AxisTransform,
    /// `λ_m` of each axial mode.
    z_eigenvalues: Vec<f64>,
    /// Whether `L` annihilates constants (pressure: zero gradient all round).
    singular: bool,
    /// Volume weight `r̄_i w_i` of each radial unknown, for the mean of a
    /// singular solve.
    rings: Vec<f64>,
    /// Unknowns, the z rows (then the modes) fastest.
    work: Vec<f64>,
    /// The elimination's `upper / pivot` of every row and mode.
    upper: Vec<f64>,
}

impl RzDirectSolver {
    /// The solver for the field whose radial operator is `radial`, whose
    /// unknowns along z are the padded rows `z_rows`, diagonalised along z
    /// by `transform`; `singular` for the all-Neumann pressure Laplacian.
    pub fn new(
        grid: &RzGrid,
        radial: RadialOperator,
        z_rows: std::ops::Range<usize>,
        transform: AxisTransform,
        singular: bool,
    ) -> Self {
        let h = grid.dz;
        let z_eigenvalues = transform
            .angles()
            .iter()
            .map(|theta| -(2.0 - 2.0 * theta.cos()) / (h * h))
            .collect();
        let rings = (0..radial.len())
            .map(|j| grid.ring(radial.first + j))
            .collect();
        let work = vec![0.0; radial.len() * z_rows.len()];
        RzDirectSolver {
            radial,
            z_rows,
            transform,
            z_eigenvalues,
            singular,
            rings,
            upper: work.clone(),
            work,
        }
    }

    /// The radial operator of this field.
    pub fn radial(&self) -> &RadialOperator {
        &self.radial
    }

    /// Padded z indices of the unknowns.
    pub fn z_rows(&self) -> std::ops::Range<usize> {
        self.z_rows.clone()
    }

    /// Replaces the unknowns of the padded `field` by the solution of
    /// `(a I + b L) x = field`, homogeneous conditions at the walls.
    ///
    /// The work array holds the modes fastest (each radial row of all the
    /// modes contiguous): the transforms run along contiguous lines, and
    /// the elimination sweeps the rows once for every mode together, its
    /// inner loop over the modes free of the recurrence along r (vector
    /// instructions), each mode's arithmetic the same whatever the others.
    pub fn solve(&mut self, grid: &RzGrid, field: &mut [f64], a: f64, b: f64) {
        let n = self.radial.len();
        let modes = self.z_rows.len();
        let first = self.radial.first;
        let z_first = self.z_rows.start;
        for j in 0..n {
            let row = &mut self.work[j * modes..(j + 1) * modes];
            for (m, value) in row.iter_mut().enumerate() {
                *value = field[grid.index(first + j, z_first + m)];
            }
        }
        let shape = [modes, n, 1];
        self.transform
            .apply_along(&mut self.work, shape, 0, Direction::Forward);
        let shifts: Vec<f64> = self.z_eigenvalues.iter().map(|l| a + b * l).collect();
        let null_mode = (self.singular && a == 0.0)
            .then(|| self.z_eigenvalues.iter().position(|&l| l == 0.0))
            .flatten();
        thomas_across_modes(
            &self.radial.rows,
            b,
            &shifts,
            null_mode,
            &mut self.work,
            &mut self.upper,
        );
        if let Some(m) = null_mode {
            // Zero volume mean over the radial line of the constant mode.
            let volume: f64 = self.rings.iter().sum();
            let mean = (0..n)
                .map(|j| self.work[j * modes + m] * self.rings[j])
                .sum::<f64>()
                / volume;
            (0..n).for_each(|j| self.work[j * modes + m] -= mean);
        }
        self.transform
            .apply_along(&mut self.work, shape, 0, Direction::Backward);
        for j in 0..n {
            let row = &self.work[j * modes..(j + 1) * modes];
            for (m, value) in row.iter().enumerate() {
                field[grid.index(first + j, z_first + m)] = *value;
            }
        }
    }
}

/// Solves `(shift_m I + b A) x_m = f_m` in place for every mode `m` at
/// once, `A` the tridiagonal of `rows` and `x` holding row `j` of every
/// mode at `j M .. (j + 1) M` (`M` modes). The singular mode `null_mode`
/// (shift 0 with `A` annihilating constants: the pressure's constant)
/// drops its last equation for `x_n = 0`, which its compatible right-hand
/// side satisfies.
fn thomas_across_modes(
    rows: &[[f64; 3]],
    b: f64,
    shifts: &[f64],
    null_mode: Option<usize>,
    x: &mut [f64],
    upper_over_pivot: &mut [f64],
) {
    let modes = shifts.len();
    let n = rows.len();
    for j in 0..n {
        let [lower, diagonal, upper] = rows[j].map(|c| b * c);
        let (done, rest) = x.split_at_mut(j * modes);
        let row = &mut rest[..modes];
        let (before, this) = upper_over_pivot.split_at_mut(j * modes);
        let this = &mut this[..modes];
        if j == 0 {
            for m in 0..modes {
                let inverse = 1.0 / (shifts[m] + diagonal);
                this[m] = upper * inverse;
                row[m] *= inverse;
            }
        } else {
            let previous = &done[(j - 1) * modes..];
            let previous_upper = &before[(j - 1) * modes..];
            for m in 0..modes {
                let inverse = 1.0 / (shifts[m] + diagonal - lower * previous_upper[m]);
                this[m] = upper * inverse;
                row[m] = (row[m] - lower * previous[m]) * inverse;
            }
        }
    }
    // The singular mode's last pivot is zero to round-off: its last row
    // is the dropped equation's, x_n = 0.
    if let Some(m) = null_mode {
        x[(n - 1) * modes + m] = 0.0;
    }
    for j in (0..n - 1).rev() {
        let (head, tail) = x.split_at_mut((j + 1) * modes);
        let row = &mut head[j * modes..];
        let next = &tail[..modes];
        let factors = &upper_over_pivot[j * modes..(j + 1) * modes];
        for m in 0..modes {
            row[m] -= factors[m] * next[m];
        }
    }
}
