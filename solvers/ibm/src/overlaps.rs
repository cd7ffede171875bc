//! One weighting where the transition layers of several grains overlap.
//!
//! Where grains press into each other (a soft contact's overlap, a grain
//! on glued ones), their solid fractions on the faces between them add up
//! to more than one; so they do, by up to 2e-4, where grains merely touch
//! along a direction oblique to the grid (the width of eq. 9–10 depends on
//! the direction, so the two tanh layers do not add up to one exactly). The
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

use crate::face_sums::bodies_by_plane;
use crate::forcing::{Bodies, ImmersedBoundaries};
use crate::solid_fraction::support;

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
                    let faces = &list[body].faces[component];
                    faces.visit_plane(dim, layer, totals, layer * plane, |totals, alpha| {
                        for (total, alpha) in totals.iter_mut().zip(alpha) {
                            *total += alpha;
                        }
                    })
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
                    let faces = &list[body].faces[component];
                    faces.visit_plane(dim, layer, totals, layer * plane, |totals, _| {
                        totals.fill(0.0)
                    })
                },
                &mut self.total_fraction[component],
            );
        }
    }
}

/// The bodies whose support overlaps another's: only where two fractions
/// are both non-zero can they add up to more than one. Sorted along x,
/// each body looks for one such neighbour on either side and stops at the
/// first (in a dense bed, one of the nearest), the bodies in parallel.
pub(crate) fn pressed_bodies(bodies: &Bodies, width: f64) -> Vec<bool> {
    let list = &bodies.list;
    let reach: Vec<f64> = list.iter().map(|b| support(b.radius, width)).collect();
    let low: Vec<f64> = list
        .iter()
        .zip(&reach)
        .map(|(b, r)| b.centre.x - r)
        .collect();
    let widest = reach.iter().copied().fold(0.0, f64::max);
    let mut order: Vec<usize> = (0..list.len()).collect();
    order.sort_by(|&a, &b| low[a].total_cmp(&low[b]));
    let found: Vec<bool> = (0..order.len())
        .into_par_iter()
        .map(|at| {
            let p = order[at];
            let centre = list[p].centre;
            let overlaps = |q: usize| {
                let reach = reach[p] + reach[q];
                (list[q].centre - centre).norm_squared() < reach * reach
            };
            // After p along x: up to where the supports no longer meet
            // along x; before it: up to where none can reach p's low end.
            let after = order[at + 1..]
                .iter()
                .take_while(|&&q| low[q] < centre.x + reach[p])
                .any(|&q| overlaps(q));
            after
                || order[..at]
                    .iter()
                    .rev()
                    .take_while(|&&q| low[q] + 2.0 * widest > low[p])
                    .any(|&q| overlaps(q))
        })
        .collect();
    let mut pressed = vec![false; list.len()];
    for (&p, &found) in order.iter().zip(&found) {
        pressed[p] = found;
    }
    pressed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::Body;
    use grainflow_core::Vec3;

    /// A random bed of 400 grains of mixed sizes, some far apart, some
    /// overlapping: the sweep marks exactly the grains whose supports meet
    /// another's, as comparing every pair does.
    #[test]
    fn the_pressed_bodies_are_those_whose_supports_meet_another() {
        let (width, mut seed) = (2e-4, 7u64);
        let mut random = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let list: Vec<Body> = (0..400)
            .map(|p| {
                let centre = Vec3::new(0.04 * random(), 0.02 * random(), 0.02 * random());
                Body::standing(p, centre, 1e-3 * (0.5 + random()))
            })
            .collect();
        let every_pair: Vec<bool> = list
            .iter()
            .map(|a| {
                list.iter().any(|b| {
                    let reach = support(a.radius, width) + support(b.radius, width);
                    a.particle != b.particle && (a.centre - b.centre).norm_squared() < reach * reach
                })
            })
            .collect();
        let pressed = pressed_bodies(&Bodies::of_list(list), width);
        let count = pressed.iter().filter(|&&p| p).count();
        assert!(
            count > 50 && count < 350,
            "{count} pressed: the bed must hold both kinds"
        );
        assert_eq!(pressed, every_pair);
    }
}
