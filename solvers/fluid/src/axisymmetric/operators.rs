//! Divergence, gradient and convection on the staggered (r, z) grid,
//! axisymmetric without swirl. With `h` the axial step:
//!
//! - divergence at centre `(i, k)`:
//!   `D u = (r_i u_r[i] − r_{i−1} u_r[i−1]) / (r̄_i w_i) + (u_z[k] − u_z[k−1]) / h`;
//! - gradient: `(p_{i+1} − p_i)/g_i` on radial faces, `(p_{k+1} − p_k)/h`
//!   on axial faces; `D G` is then the radial centre operator plus the
//!   axial second difference, the Laplacian the pressure solver inverts, so
//!   the projection leaves `D u = 0` to round-off;
//! - convection in conservative form, `N(u) = −∇·(u u)`:
//!   `N_r = −(1/r) ∂_r (r u_r²) − ∂_z (u_r u_z)` on the radial faces (no
//!   `u_θ²/r` term without swirl), each face's control ring reaching from
//!   centre `i` to centre `i + 1`;
//!   `N_z = −(1/r) ∂_r (r u_r u_z) − ∂_z (u_z²)` on the axial faces.
//!   The products `u_r u_z` live on the corners `(r_i, z_k)`, `u_z` brought
//!   to `r_i` by linear interpolation between the centres on either side;
//!   the fluxes through the axis and the outer wall carry `r = 0` or
//!   `u_r = 0` and vanish.

use super::grid::RzGrid;

/// `out = D u` at every centre `(i, k)`, `i = 1..=n_r`, `k = 1..=n_z`.
pub fn divergence(grid: &RzGrid, radial: &[f64], axial: &[f64], out: &mut [f64]) {
    let [nr, nz] = grid.cells;
    let h = grid.dz;
    for k in 1..=nz {
        for i in 1..=nr {
            let at = grid.index(i, k);
            let radial_part =
                (grid.face(i) * radial[at] - grid.face(i - 1) * radial[at - 1]) / grid.ring(i);
            let axial_part = (axial[at] - axial[grid.index(i, k - 1)]) / h;
            out[at] = radial_part + axial_part;
        }
    }
}

/// `u_r −= scale · G_r φ` on the interior radial faces and
/// `u_z −= scale · G_z φ` on the axial faces in `axial_rows`; `phi` has its
/// ghosts set.
pub fn subtract_gradient(
    grid: &RzGrid,
    phi: &[f64],
    scale: f64,
    axial_rows: std::ops::Range<usize>,
    radial: &mut [f64],
    axial: &mut [f64],
) {
    let [nr, nz] = grid.cells;
    let h = grid.dz;
    let up = grid.index(0, 1);
    for k in 1..=nz {
        for i in 1..nr {
            let at = grid.index(i, k);
            radial[at] -= scale * (phi[at + 1] - phi[at]) / grid.gap(i);
        }
    }
    for k in axial_rows {
        for i in 1..=nr {
            let at = grid.index(i, k);
            axial[at] -= scale * (phi[at + up] - phi[at]) / h;
        }
    }
}

/// `u_z` brought to the radial face `i` (between centres `i` and `i + 1`).
#[inline]
fn axial_at_face(grid: &RzGrid, axial: &[f64], i: usize, at: usize) -> f64 {
    let gap = grid.gap(i);
    let toward_outer = (grid.face(i) - grid.centre(i)) / gap;
    (1.0 - toward_outer) * axial[at] + toward_outer * axial[at + 1]
}

/// `N(u)` on the unknowns: radial faces `1..n_r` for every z centre, and
/// axial faces in `axial_rows` for every radial centre. Ghosts of both
/// components must be set.
pub fn convection(
    grid: &RzGrid,
    radial: &[f64],
    axial: &[f64],
    axial_rows: std::ops::Range<usize>,
    out_radial: &mut [f64],
    out_axial: &mut [f64],
) {
    let [nr, nz] = grid.cells;
    let h = grid.dz;
    let up = grid.index(0, 1);
    // u_r u_z on the corner (r_i, z_k), the upper face k of z centre k.
    let corner = |i: usize, k: usize| {
        let at = grid.index(i, k);
        let radial_mean = 0.5 * (radial[at] + radial[at + up]);
        radial_mean * axial_at_face(grid, axial, i, at)
    };
    for k in 1..=nz {
        for i in 1..nr {
            let at = grid.index(i, k);
            // u_r at the centres on either side of face i.
            let inner = 0.5 * (radial[at - 1] + radial[at]);
            let outer = 0.5 * (radial[at] + radial[at + 1]);
            // (1/r) ∂_r (r u_r²) in conservative form over the face's
            // control ring: it keeps the momentum and the step stable at
            // high cell Reynolds numbers (the form ∂_r (u_r²) + u_r²/r,
            // exact near the axis, let a bounce at cell Re ≈ 400 blow up).
            // Divided by r_1 = O(h), its first face carries an O(h) local
            // error (1/12 relative for u_r ∝ r), second order in the
            // volume-weighted norm.
            let ring = 0.5 * (grid.centre(i) + grid.centre(i + 1)) * grid.gap(i);
            let radial_flux =
                (grid.centre(i + 1) * outer * outer - grid.centre(i) * inner * inner) / ring;
            let axial_flux = (corner(i, k) - corner(i, k - 1)) / h;
            out_radial[at] = -(radial_flux + axial_flux);
        }
    }
    for k in axial_rows {
        for i in 1..=nr {
            let at = grid.index(i, k);
            let radial_flux =
                (grid.face(i) * corner(i, k) - grid.face(i - 1) * corner(i - 1, k)) / grid.ring(i);
            // u_z at the z centres k + 1 and k.
            let above = 0.5 * (axial[at] + axial[at + up]);
            let below = 0.5 * (axial[at - up] + axial[at]);
            let axial_flux = (above * above - below * below) / h;
            out_axial[at] = -(radial_flux + axial_flux);
        }
    }
}

/// `out += scale · ∂_z² f` (the three-point second difference) on the
/// padded rows `rows` and radial indices `radii`; ghosts set.
pub fn add_axial_second_difference(
    grid: &RzGrid,
    field: &[f64],
    scale: f64,
    radii: std::ops::Range<usize>,
    rows: std::ops::Range<usize>,
    out: &mut [f64],
) {
    let up = grid.index(0, 1);
    let factor = scale / (grid.dz * grid.dz);
    for k in rows {
        for i in radii.clone() {
            let at = grid.index(i, k);
            out[at] += factor * (field[at + up] - 2.0 * field[at] + field[at - up]);
        }
    }
}
