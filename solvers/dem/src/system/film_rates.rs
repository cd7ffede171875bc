//! The film rates that make the lubrication films on a grain implicit
//! together (`crate::lubrication`, module doc): before each force
//! evaluation in a fluid, every owned grain sums `c_k / m` over the films
//! it holds with grains and walls, and its ghosts receive the sum, so that
//! both sides of a film divide it by the same `1 + Δt (r_i + r_j)`.
//!
//! The rates depend on the positions alone, which the step has just moved;
//! each grain sums its own films in the order of its pair list (then its
//! walls in increasing index), so the sums do not depend on the number of
//! threads.

use super::{DemSystem, PARTICLES_PER_TASK};
use rayon::prelude::*;

impl DemSystem {
    /// Fills `film_rate` for every local particle (owned, then ghosts;
    /// collective). Nothing to do in a scene without lubrication.
    pub(super) fn update_film_rates(&mut self) {
        let Some(film) = self.lubrication else {
            return;
        };
        let n = self.particles.n_owned;
        let mut rates = std::mem::take(&mut self.film_rate);
        rates.resize(self.particles.len(), 0.0);
        let p = &self.particles;
        let list = &self.neighbours;
        let (walls, time, contact_gap) = (&self.walls, self.time, self.contact_gap);
        let candidates = &self.wall_candidates;
        let touching = &self.wall_touching;
        rates[..n]
            .par_iter_mut()
            .enumerate()
            .with_min_len(PARTICLES_PER_TASK)
            .for_each(|(i, rate)| {
                if p.inverse_mass[i] == 0.0 {
                    *rate = 0.0;
                    return;
                }
                let (xi, ri) = (p.position[i], p.radius[i]);
                let mut damping = 0.0;
                let partners = list.offsets[i] as usize..list.offsets[i + 1] as usize;
                for &j in &list.partner[partners] {
                    let j = j as usize;
                    let rj = p.radius[j];
                    let gap = (xi - p.position[j]).norm() - ri - rj - contact_gap;
                    damping += film.damping(gap, ri, rj);
                }
                let mut near = candidates[i] | touching.get(i).copied().unwrap_or(0);
                while near != 0 {
                    let w = near.trailing_zeros() as usize;
                    near &= near - 1;
                    let wall = &walls[w];
                    if wall.is_present(time) {
                        let gap = wall.distance(&xi) - ri - contact_gap;
                        damping += film.damping(gap, ri, f64::INFINITY);
                    }
                }
                *rate = damping * p.inverse_mass[i];
            });
        self.ghosts
            .copy_to_ghosts(&mut rates, 1, &self.communicator);
        self.film_rate = rates;
    }
}
