//! Second-order central difference operators on the staggered grid.
//!
//! Each operator reads ghost values, so the caller fills ghosts first, and
//! writes only the points of the block it is given. With `D` the
//! divergence (faces to centres) and `G` the gradient (centres to faces),
//! `D G` is exactly the cell-centred three-point Laplacian: this is what
//! makes the projection leave a divergence at round-off. Every point is
//! computed alone ([`Grid::par_update_planes`]), planes shared among threads.
//!
//! Along the line axis (the last active one) the spacing may vary from
//! cell to cell: a difference of face values is divided by the cell width
//! `w`, a difference of centre values by the distance between centres `g`
//! (see [`crate::grid`]), and interpolations to a face or centre are plain
//! means of the two neighbours, as in CaNS; on a smoothly stretched grid
//! the neighbouring widths differ by `O(h²)` and every operator stays
//! second order. The other axes are uniform and use their constant spacing.

use crate::grid::{Block, Grid, Location};

/// `divergence = D velocity` at every owned cell:
/// `Σ_a (u_a[i] − u_a[i − e_a]) / w_a`.
pub fn divergence(grid: &Grid, velocity: &[Vec<f64>], divergence: &mut [f64]) {
    let line = grid.line_axis();
    let line_velocity = &velocity[line];
    let line_stride = grid.stride(line);
    grid.par_update_planes(&grid.cell_block(), divergence, |plane| {
        let width = grid.width(line, plane);
        move |index, _| {
            let mut sum = 0.0;
            for (axis, component) in velocity.iter().enumerate().take(line) {
                let stride = grid.stride(axis);
                sum += (component[index] - component[index - stride]) / grid.spacing[axis];
            }
            sum + (line_velocity[index] - line_velocity[index - line_stride]) / width
        }
    });
}

/// `velocity_c −= scale · (G scalar)_c` on the faces of `block`, the faces
/// normal to `component`: `(s[i + e_c] − s[i]) / g_c`.
pub fn subtract_gradient(
    grid: &Grid,
    scalar: &[f64],
    component: usize,
    block: &Block,
    scale: f64,
    velocity_component: &mut [f64],
) {
    let stride = grid.stride(component);
    grid.par_update_planes(block, velocity_component, |plane| {
        let factor = scale / grid.gap(component, plane);
        move |index, velocity| velocity - factor * (scalar[index + stride] - scalar[index])
    });
}

/// `out += scale · L field` on `block`, with `L` the three-point Laplacian
/// along every active axis of a field at `location`.
pub fn add_laplacian(
    grid: &Grid,
    field: &[f64],
    location: Location,
    block: &Block,
    scale: f64,
    out: &mut [f64],
) {
    let line = grid.line_axis();
    let mut weights = [0.0; 3];
    let mut strides = [0; 3];
    for axis in 0..line {
        weights[axis] = scale / (grid.spacing[axis] * grid.spacing[axis]);
        strides[axis] = grid.stride(axis);
    }
    let line_stride = grid.stride(line);
    grid.par_update_planes(block, out, |plane| {
        let [below, above] = grid.line_laplacian(location, plane).map(|w| scale * w);
        move |index, out| {
            let centre = field[index];
            let mut sum = 0.0;
            for axis in 0..line {
                let s = strides[axis];
                sum += weights[axis] * (field[index + s] - 2.0 * centre + field[index - s]);
            }
            sum += above * (field[index + line_stride] - centre)
                + below * (field[index - line_stride] - centre);
            out + sum
        }
    });
}

/// The convective tendency of velocity component `c`,
/// `tendency = −∇·(u u_c)` in divergence form on the faces of `block`.
///
/// Along the component's own axis the flux `u_c²` is formed at cell
/// centres from the mean of the two neighbouring faces; along another axis
/// `d` the flux `u_d u_c` is formed at the edge shared by the two faces,
/// each factor the mean of its two neighbours. Central differences of these
/// fluxes are second order and conserve momentum and, for a divergence-free
/// field on a uniform grid, kinetic energy.
pub fn convective_tendency(
    grid: &Grid,
    velocity: &[Vec<f64>],
    component: usize,
    block: &Block,
    tendency: &mut [f64],
) {
    let along = &velocity[component];
    let sc = grid.stride(component);
    // One pass per flux direction keeps the inner loop branch-free. The
    // flux along the component's axis is differenced between centres.
    grid.par_update_planes(block, tendency, |plane| {
        let factor = 0.25 / grid.gap(component, plane);
        move |index, _| {
            let upper = along[index] + along[index + sc];
            let lower = along[index - sc] + along[index];
            -factor * (upper * upper - lower * lower)
        }
    });
    // Across it, between the edges on either side of the face, which lie
    // on the face's own cell faces along that axis.
    for axis in (0..grid.dim()).filter(|&axis| axis != component) {
        let across = &velocity[axis];
        let sd = grid.stride(axis);
        grid.par_update_planes(block, tendency, |plane| {
            let factor = 0.25 / grid.width(axis, plane);
            move |index, tendency| {
                let upper =
                    (along[index] + along[index + sd]) * (across[index] + across[index + sc]);
                let lower = (along[index - sd] + along[index])
                    * (across[index - sd] + across[index - sd + sc]);
                tendency - factor * (upper - lower)
            }
        });
    }
}
