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

use rayon::prelude::*;

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
    /// Unknowns, r fastest, then transformed.
    work: Vec<f64>,
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
    pub fn solve(&mut self, grid: &RzGrid, field: &mut [f64], a: f64, b: f64) {
        let n = self.radial.len();
        let lines = self.z_rows.len();
        let first = self.radial.first;
        for (line, k) in self.z_rows.clone().enumerate() {
            let start = grid.index(first, k);
            self.work[line * n..(line + 1) * n].copy_from_slice(&field[start..start + n]);
        }
        let shape = [n, lines, 1];
        self.transform
            .apply_along(&mut self.work, shape, 1, Direction::Forward);
        let rows = &self.radial.rows;
        let eigenvalues = &self.z_eigenvalues;
        let singular = self.singular && a == 0.0;
        let rings = &self.rings;
        self.work
            .par_chunks_mut(n)
            .with_min_len(16)
            .enumerate()
            .for_each_init(
                || vec![0.0; n],
                |modified, (mode, line)| {
                    let shift = a + b * eigenvalues[mode];
                    let null_mode = singular && eigenvalues[mode] == 0.0;
                    thomas(rows, b, shift, line, modified, null_mode);
                    if null_mode {
                        let volume: f64 = rings.iter().sum();
                        let mean = line.iter().zip(rings).map(|(x, w)| x * w).sum::<f64>() / volume;
                        line.iter_mut().for_each(|x| *x -= mean);
                    }
                },
            );
        self.transform
            .apply_along(&mut self.work, shape, 1, Direction::Backward);
        for (line, k) in self.z_rows.clone().enumerate() {
            let start = grid.index(first, k);
            field[start..start + n].copy_from_slice(&self.work[line * n..(line + 1) * n]);
        }
    }
}

/// Solves `(shift I + b A) x = f` in place for the tridiagonal `A` of
/// `rows`; with `drop_last`, the last equation is replaced by `x_n = 0`
/// (a singular operator with a compatible right-hand side).
fn thomas(
    rows: &[[f64; 3]],
    b: f64,
    shift: f64,
    x: &mut [f64],
    modified: &mut [f64],
    drop_last: bool,
) {
    let n = x.len();
    let solved = if drop_last { n - 1 } else { n };
    let mut previous_upper = 0.0;
    for j in 0..solved {
        let [lower, diagonal, upper] = rows[j];
        let (lower, diagonal, upper) = (b * lower, shift + b * diagonal, b * upper);
        let pivot = if j == 0 {
            diagonal
        } else {
            diagonal - lower * previous_upper
        };
        let right = if j == 0 {
            x[0]
        } else {
            x[j] - lower * x[j - 1]
        };
        previous_upper = if j + 1 < solved { upper / pivot } else { 0.0 };
        modified[j] = previous_upper;
        x[j] = right / pivot;
    }
    if drop_last {
        x[n - 1] = 0.0;
    }
    for j in (0..solved.saturating_sub(1)).rev() {
        x[j] -= modified[j] * x[j + 1];
    }
}
