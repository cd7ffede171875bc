//! The radial parts of the (r, z) Laplacians as tridiagonal rows.
//!
//! - At centres (pressure, and `u_z`):
//!   `A f_i = (1 / (r̄_i w_i)) [r_i (f_{i+1} − f_i)/g_i − r_{i−1} (f_i − f_{i−1})/g_{i−1}]`,
//!   the discrete `(1/r) ∂_r (r ∂_r f)`. The flux through the axis carries
//!   `r_0 = 0` and drops out. At the outer wall the flux is zero (pressure,
//!   free slip) or, for a wall value `u_w`, `R ∂_r u` from the parabola
//!   through `u_w` at `R` and the last two centres, which keeps the row
//!   tridiagonal and makes the operator exact on `a + b r²` (the
//!   Poiseuille profile of a pipe is then steady to round-off).
//! - On radial faces (`u_r`): `B u_i = (d_{i+1} − d_i) / g_i` with
//!   `d_i = (r_i u_i − r_{i−1} u_{i−1}) / (r̄_i w_i)`, the discrete
//!   `∂_r ((1/r) ∂_r (r u_r)) = ∇²u_r − u_r/r²` (the radial part of the
//!   vector Laplacian without swirl), with `u_0 = u_n = 0`. It is the
//!   gradient of the divergence's radial part, so it commutes with the
//!   projection's gradient exactly.
//!
//! Row `j` of an operator acts on the unknown at padded index `first + j`.

use super::grid::RzGrid;

/// How a centre field is closed at the outer wall.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OuterClosure {
    /// Zero radial gradient (pressure, free slip).
    ZeroGradient,
    /// A prescribed value at `R` (no-slip, a sliding wall).
    WallValue,
}

/// A tridiagonal radial operator over a line of unknowns.
#[derive(Clone, Debug)]
pub struct RadialOperator {
    /// Padded index of the first unknown.
    pub first: usize,
    /// `[lower, diagonal, upper]` of each row.
    pub rows: Vec<[f64; 3]>,
    /// Coefficient of the wall value in the last row.
    pub wall: f64,
}

impl RadialOperator {
    /// The operator at centres, rows `i = 1..=n_r`.
    pub fn centres(grid: &RzGrid, outer: OuterClosure) -> Self {
        let n = grid.cells[0];
        let mut rows = Vec::with_capacity(n);
        let mut wall = 0.0;
        for i in 1..=n {
            let scale = 1.0 / grid.ring(i);
            let inner = grid.face(i - 1) / grid.gap(i - 1);
            let (mut lower, mut diagonal, mut upper) = (inner * scale, -inner * scale, 0.0);
            if i < n {
                let outer_flux = grid.face(i) / grid.gap(i);
                diagonal -= outer_flux * scale;
                upper = outer_flux * scale;
            } else if outer == OuterClosure::WallValue {
                // R ∂_r u at R from the parabola through (R, u_w),
                // (r̄_n, u_n), (r̄_{n−1}, u_{n−1}): with s = R − r,
                // d1 = R − r̄_n, d2 = R − r̄_{n−1},
                // ∂_r u = −d2/(d1 (d2 − d1)) u_n + d1/(d2 (d2 − d1)) u_{n−1}
                //         + (d1 + d2)/(d1 d2) u_w.
                let radius = grid.face(n);
                let d1 = radius - grid.centre(n);
                let d2 = radius - grid.centre(n - 1);
                let flux = radius * scale;
                diagonal -= flux * d2 / (d1 * (d2 - d1));
                lower += flux * d1 / (d2 * (d2 - d1));
                wall = flux * (d1 + d2) / (d1 * d2);
            }
            rows.push([lower, diagonal, upper]);
        }
        RadialOperator {
            first: 1,
            rows,
            wall,
        }
    }

    /// The operator on the interior radial faces, rows `i = 1..n_r`.
    pub fn faces(grid: &RzGrid) -> Self {
        let n = grid.cells[0];
        let rows = (1..n)
            .map(|i| {
                let gap = grid.gap(i);
                // d_{i+1} = (r_{i+1} u_{i+1} − r_i u_i)/ring_{i+1},
                // d_i = (r_i u_i − r_{i−1} u_{i−1})/ring_i.
                let above = 1.0 / (grid.ring(i + 1) * gap);
                let below = 1.0 / (grid.ring(i) * gap);
                [
                    grid.face(i - 1) * below,
                    -grid.face(i) * (above + below),
                    grid.face(i + 1) * above,
                ]
            })
            .collect();
        RadialOperator {
            first: 1,
            rows,
            wall: 0.0,
        }
    }

    pub fn len(&self) -> usize {
        self.rows.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// `out[k-line] += scale · (A f + wall · wall_value)` on every row,
    /// for the padded z rows `z_rows`.
    pub fn apply_add(
        &self,
        grid: &RzGrid,
        field: &[f64],
        wall_value: f64,
        scale: f64,
        z_rows: std::ops::Range<usize>,
        out: &mut [f64],
    ) {
        let last = self.rows.len() - 1;
        for k in z_rows {
            let base = grid.index(self.first, k);
            for (j, &[lower, diagonal, upper]) in self.rows.iter().enumerate() {
                let at = base + j;
                // The last row's upper neighbour is the wall (u_r = 0, or
                // a centre field's closure folded into the row).
                let below = lower * field[at - 1];
                let above = if j == last {
                    0.0
                } else {
                    upper * field[at + 1]
                };
                let mut value = below + diagonal * field[at] + above;
                if j == last {
                    value += self.wall * wall_value;
                }
                out[at] += scale * value;
            }
        }
    }
}
