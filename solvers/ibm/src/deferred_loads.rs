//! The loads of eq. 7's forcing and the inner momentum after the
//! projection, in one pass over each body's faces.
//!
//! A stage reads a body's faces for the loads of its forcing,
//! `F_p = −Σ w_p (U_p − V*) dV/h` with `V*` the predicted velocity before
//! the forcing, and again after the projection for the fluid's momentum
//! inside it, `I⁺ = Σ α_p u dV`. Both are sums over the same rows of the
//! same fractions (with eq. 7 at every stage, the loads' weights `w_p` are
//! the bodies' shares `α_p`), so the forcing keeps `V*` in its scratch sum
//! `Σ β` once it has read it (`force_block` with `KEEP_PREDICTION`), and
//! one pass after the projection makes both, row by row. Each sum is made
//! in the order the two passes made it, so the bits are the same.
//!
//! Only eq. 7 in one pass takes this route: under a held or renewed
//! forcing the weights read `Σ β` itself, and with several passes each
//! pass has its own `V*`.

use grainflow_core::Vec3;
use grainflow_fluid::{Block, Grid};
use rayon::prelude::*;

use crate::body::Body;
use crate::face_sums::touched_block;
use crate::faces::{prefetch, PREFETCH_ROWS};
use crate::forcing::{Bodies, ImmersedBoundaries, Loads};

impl ImmersedBoundaries {
    /// Eq. 7 on the predicted `velocity`, as [`ImmersedBoundaries::apply`]
    /// moves it, with the predicted velocity kept on the forced faces for
    /// [`ImmersedBoundaries::loads_and_inner_momentum`], which must follow
    /// (after the projection). Needs the forcing's sums made with the
    /// bodies ([`ImmersedBoundaries::bodies_with_inner_momentum`] under
    /// eq. 7 at every stage: [`Bodies::forcing_sums_made`]).
    pub fn force_keeping_prediction(
        &mut self,
        grid: &Grid,
        velocity: &mut [Vec<f64>],
        bodies: &Bodies,
    ) {
        assert!(
            bodies.forcing_sums_made(),
            "the loads are deferred only for eq. 7 with its sums made"
        );
        self.force_touched::<true>(grid, velocity, bodies);
        self.set_forcing_sums_pending(true);
    }

    /// The loads of the forcing of a stage of length `stage_dt` (as
    /// [`ImmersedBoundaries::apply`] returns them) and the inner momentum
    /// in the projected `velocity` (as
    /// [`ImmersedBoundaries::inner_momentum`]), from the prediction that
    /// [`ImmersedBoundaries::force_keeping_prediction`] kept; the kept
    /// prediction is then cleared.
    pub fn loads_and_inner_momentum(
        &mut self,
        grid: &Grid,
        velocity: &[Vec<f64>],
        bodies: &Bodies,
        stage_dt: f64,
    ) -> (Loads, Loads) {
        let volume = grid.cell_volume();
        let scale = -volume / stage_dt;
        let predicted = &self.total_fraction;
        let per_body: Vec<[(Vec3, Vec3); 2]> = bodies
            .list
            .par_iter()
            .map(|body| {
                let [(force, torque), (momentum, angular)] =
                    body.load_and_inner_momentum(predicted, velocity);
                [
                    (force * scale, torque * scale),
                    (momentum * volume, angular * volume),
                ]
            })
            .collect();
        for component in 0..grid.dim() {
            if let Some(block) = touched_block(bodies, component) {
                clear_block(grid, &block, &mut self.total_fraction[component]);
            }
        }
        self.set_forcing_sums_pending(false);
        let loads: Vec<_> = per_body.iter().map(|pair| pair[0]).collect();
        let momentum: Vec<_> = per_body.iter().map(|pair| pair[1]).collect();
        (self.gather(bodies, &loads), self.gather(bodies, &momentum))
    }
}

impl Body {
    /// The row sums of the load `α (U − V*)` in the predicted field
    /// `predicted` and of the momentum `α u` in `velocity`, in one pass:
    /// `[(Σ q, Σ r × q)]` of each, as [`Body::moments`] makes them.
    fn load_and_inner_momentum(
        &self,
        predicted: &[Vec<f64>],
        velocity: &[Vec<f64>],
    ) -> [(Vec3, Vec3); 2] {
        let mut sums = [(Vec3::zeros(), Vec3::zeros()); 2];
        for (component, faces) in self.faces.iter().enumerate() {
            let mut plain = [0.0; 2];
            let mut moment = [Vec3::zeros(); 2];
            let mut ahead = faces.faces_ahead(PREFETCH_ROWS);
            for row in faces.rows() {
                if let Some(later) = ahead.next() {
                    prefetch(&[&predicted[component], &velocity[component]], &later);
                }
                let (base, slope) = self.rigid_along(&row, component, faces.step);
                let before = &predicted[component][row.faces()];
                let after = &velocity[component][row.faces()];
                let (mut load, mut load_along) = (0.0, 0.0);
                let (mut inner, mut inner_along) = (0.0, 0.0);
                let faces_of_row = row.alpha.iter().zip(before.iter().zip(after));
                for (i, (alpha, (before, after))) in faces_of_row.enumerate() {
                    let q = alpha * (base + i as f64 * slope - before);
                    load += q;
                    load_along += i as f64 * q;
                    let q = alpha * after;
                    inner += q;
                    inner_along += i as f64 * q;
                }
                for (k, (sum, along)) in [(load, load_along), (inner, inner_along)]
                    .into_iter()
                    .enumerate()
                {
                    plain[k] += sum;
                    moment[k] += row.offset * sum;
                    moment[k].x += faces.step * along;
                }
            }
            // Σ r × (q e_c) = (Σ q r) × e_c.
            let mut axis = Vec3::zeros();
            axis[component] = 1.0;
            for k in 0..2 {
                sums[k].0[component] += plain[k];
                sums[k].1 += moment[k].cross(&axis);
            }
        }
        sums
    }
}

/// Zero on the faces of `block` of the face field `field`, the planes of
/// the slowest axis shared among threads.
pub(crate) fn clear_block(grid: &Grid, block: &Block, field: &mut [f64]) {
    let slow = grid.dim() - 1;
    let plane = grid.stride(slow);
    let mut inner = *block;
    inner.start[slow] = 0;
    inner.end[slow] = 1;
    let planes = block.start[slow] * plane..block.end[slow] * plane;
    field[planes].par_chunks_mut(plane).for_each(|layer| {
        for k in inner.start[2]..inner.end[2] {
            for j in inner.start[1]..inner.end[1] {
                layer[grid.index(inner.start[0], j, k)..grid.index(inner.end[0], j, k)].fill(0.0);
            }
        }
    });
}
