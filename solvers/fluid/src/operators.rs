//! Second-order central difference operators on the staggered grid.
//!
//! Each operator reads ghost values, so the caller fills ghosts first, and
//! writes only the points of the block it is given. With `D` the
//! divergence (faces to centres) and `G` the gradient (centres to faces),
//! `D G` is exactly the cell-centred three-point Laplacian: this is what
//! makes the projection leave a divergence at round-off. Every point is
//! computed alone ([`Grid::par_update`]), planes shared among threads.

use crate::grid::{Block, Grid};

/// `divergence = D velocity` at every owned cell:
/// `Σ_a (u_a[i] − u_a[i − e_a]) / h_a`.
pub fn divergence(grid: &Grid, velocity: &[Vec<f64>], divergence: &mut [f64]) {
    let dim = grid.dim();
    grid.par_update(&grid.cell_block(), divergence, |index, _| {
        let mut sum = 0.0;
        for (axis, component) in velocity.iter().enumerate().take(dim) {
            let stride = grid.stride(axis);
            sum += (component[index] - component[index - stride]) / grid.spacing[axis];
        }
        sum
    });
}

/// `velocity_c −= scale · (G scalar)_c` on the faces of `block`, the faces
/// normal to `component`.
pub fn subtract_gradient(
    grid: &Grid,
    scalar: &[f64],
    component: usize,
    block: &Block,
    scale: f64,
    velocity_component: &mut [f64],
) {
    let stride = grid.stride(component);
    let factor = scale / grid.spacing[component];
    grid.par_update(block, velocity_component, |index, velocity| {
        velocity - factor * (scalar[index + stride] - scalar[index])
    });
}

/// `out += scale · L field` on `block`, with `L` the three-point Laplacian
/// along every active axis.
pub fn add_laplacian(grid: &Grid, field: &[f64], block: &Block, scale: f64, out: &mut [f64]) {
    let dim = grid.dim();
    let mut weights = [0.0; 3];
    let mut strides = [0; 3];
    for axis in 0..dim {
        weights[axis] = scale / (grid.spacing[axis] * grid.spacing[axis]);
        strides[axis] = grid.stride(axis);
    }
    grid.par_update(block, out, |index, out| {
        let centre = field[index];
        let mut sum = 0.0;
        for axis in 0..dim {
            let s = strides[axis];
            sum += weights[axis] * (field[index + s] - 2.0 * centre + field[index - s]);
        }
        out + sum
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
/// field, kinetic energy.
pub fn convective_tendency(
    grid: &Grid,
    velocity: &[Vec<f64>],
    component: usize,
    block: &Block,
    tendency: &mut [f64],
) {
    let along = &velocity[component];
    let sc = grid.stride(component);
    // One pass per flux direction keeps the inner loop branch-free.
    let h = grid.spacing[component];
    grid.par_update(block, tendency, |index, _| {
        let upper = along[index] + along[index + sc];
        let lower = along[index - sc] + along[index];
        -0.25 * (upper * upper - lower * lower) / h
    });
    for axis in (0..grid.dim()).filter(|&axis| axis != component) {
        let across = &velocity[axis];
        let sd = grid.stride(axis);
        let factor = 0.25 / grid.spacing[axis];
        grid.par_update(block, tendency, |index, tendency| {
            let upper = (along[index] + along[index + sd]) * (across[index] + across[index + sc]);
            let lower =
                (along[index - sd] + along[index]) * (across[index - sd] + across[index - sd + sc]);
            tendency - factor * (upper - lower)
        });
    }
}
