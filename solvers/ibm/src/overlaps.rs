//! One weighting where the transition layers of several grains overlap.
//!
//! Where grains press into each other (a soft contact's overlap, a grain
//! on glued ones), their solid fractions on the faces between them add up
//! to more than one (merely touching, the two layers add up to one at
//! most: `tests/overlapping_grains.rs`). The
//! forcing of eq. 7 weights each grain's share of the face by
//! `α_p / max(1, Σ_q α_q)`; the inner momentum `∫ α_p u dV` and the grid
//! volume `∫ α_p dV` counted the same fluid in both grains. So once a
//! stage's fractions are made, each is replaced by its share,
//!
//! ```text
//! α_p ← α_p / max(1, Σ_q α_q),
//! ```
//!
//! which the forcing, the loads, the inner momentum and the grid volumes
//! then all read. With eq. 7 at every stage the forcing is unchanged (its
//! weights were these shares already); a face covered by one grain keeps
//! its fraction bit for bit.

use grainflow_fluid::Grid;
use rayon::prelude::*;

use crate::forcing::{bodies_by_plane, Bodies, ImmersedBoundaries};

impl ImmersedBoundaries {
    /// Replaces the fractions of the `pressed` bodies ([`pressed_bodies`])
    /// by their shares where their supports overlap (module doc).
    pub(crate) fn share_overlaps(&mut self, grid: &Grid, bodies: &mut Bodies, pressed: &[bool]) {
        if !pressed.iter().any(|&p| p) {
            return;
        }
        let dim = grid.dim();
        let slow = dim - 1;
        let plane = grid.stride(slow);
        for component in 0..dim {
            let mut reaching = bodies_by_plane(bodies, component, slow, grid.padded()[slow]);
            for bodies in &mut reaching {
                bodies.retain(|&body| pressed[body]);
            }
            // Only a face of two bodies or more can exceed one.
            if reaching.iter().all(|bodies| bodies.len() < 2) {
                continue;
            }
            // Σ_q α_q on the faces of the pressed bodies, plane by plane,
            // each face summing its bodies in list order whatever the
            // number of threads; then each body's share; then the sums
            // cleared.
            let each_plane = |action: &(dyn Fn(usize, usize, &mut [f64]) + Sync),
                              totals: &mut [f64]| {
                totals
                    .par_chunks_mut(plane)
                    .enumerate()
                    .filter(|(layer, _)| reaching[*layer].len() >= 2)
                    .for_each(|(layer, totals)| {
                        for &body in &reaching[layer] {
                            action(body, layer, totals);
                        }
                    });
            };
            let list = &bodies.list;
            each_plane(
                &|body, layer, totals| {
                    list[body].faces[component].add_plane_to(dim, layer, totals, layer * plane)
                },
                &mut self.total_fraction[component],
            );
            let totals: &[f64] = &self.total_fraction[component];
            bodies
                .list
                .par_iter_mut()
                .zip(pressed)
                .filter(|(_, &pressed)| pressed)
                .for_each(|(body, _)| body.faces[component].share(totals));
            let list = &bodies.list;
            each_plane(
                &|body, layer, totals| {
                    list[body].faces[component].clear_plane_of(dim, layer, totals, layer * plane)
                },
                &mut self.total_fraction[component],
            );
        }
    }
}

/// The bodies that press into another: only where two spheres overlap can
/// their fractions add up to more than one (`s_p + s_q ≥ 0` for the
/// signed distances to two surfaces that do not overlap, and eq. 8 is
/// `½ (1 − tanh)` of them). Sorted along x and swept, each pair compared
/// once.
pub(crate) fn pressed_bodies(bodies: &Bodies) -> Vec<bool> {
    let list = &bodies.list;
    let mut pressed = vec![false; list.len()];
    let mut order: Vec<usize> = (0..list.len()).collect();
    order.sort_by(|&a, &b| {
        let low = |k: usize| list[k].centre.x - list[k].radius;
        low(a).total_cmp(&low(b))
    });
    for (at, &p) in order.iter().enumerate() {
        let (centre, radius) = (list[p].centre, list[p].radius);
        for &q in &order[at + 1..] {
            if list[q].centre.x - list[q].radius >= centre.x + radius {
                break;
            }
            let reach = radius + list[q].radius;
            if (list[q].centre - centre).norm_squared() < reach * reach {
                pressed[p] = true;
                pressed[q] = true;
            }
        }
    }
    pressed
}
