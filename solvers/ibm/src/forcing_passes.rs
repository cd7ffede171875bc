//! A stage's forcing in passes (`exponents.rs`): where a grain's exponent
//! `e` exceeds one, the stage forces in `n = ⌈e⌉` passes of `e/n`, each
//! followed by the projection.
//!
//! The passes of a stage force the same bodies with the same fractions
//! `β` towards the same rigid velocities `U`: only the fluid's velocity
//! before each pass, `V*_k`, changes from one to the next. So the sums
//! `Σ β` and `Σ β U` are made once and kept through the passes, each pass
//! adds its `V*_k` into `S = Σ_k V*_k` as it forces, and the loads of all
//! the passes,
//!
//! ```text
//! F_p = −Σ_k Σ_faces w_p (U_p − V*_k) dV/h = −Σ_faces w_p (n U_p − S) dV/h,
//! w_p = β_p / max(1, Σ_q β_q),
//! ```
//!
//! are read in one pass over each body's faces, before the last pass
//! forces (with `S` completed by that pass's `V*`). A stage in one pass is
//! eq. 7's form ([`ImmersedBoundaries::apply`]), its loads `w_p (U_p − V*)`
//! bit for bit.

use grainflow_core::Vec3;
use grainflow_fluid::Grid;
use rayon::prelude::*;

use crate::exponents::{forced_fraction, Exponents};
use crate::face_sums::touched_block;
use crate::forcing::{Bodies, ImmersedBoundaries, Loads};

impl ImmersedBoundaries {
    /// Makes the stage's sums `Σ β_p` and `Σ β_p U_p` of `bodies` forced
    /// at `exponents`, unless the bodies were made with them (eq. 7:
    /// [`Bodies::forcing_sums_made`]). The passes follow:
    /// [`ImmersedBoundaries::force_pass`] for all but the last, then
    /// [`ImmersedBoundaries::last_pass`].
    pub fn begin_forcing(&mut self, grid: &Grid, bodies: &Bodies, exponents: &Exponents) {
        if !bodies.forcing_sums_made() {
            self.add_forcing_sums(grid, bodies, exponents);
        }
        self.set_forcing_sums_pending(true);
    }

    /// One pass of the stage's forcing that is not its last: `velocity`
    /// forced with the sums [`ImmersedBoundaries::begin_forcing`] made,
    /// which it keeps, and its velocity before the forcing added into `S`.
    pub fn force_pass(&mut self, grid: &Grid, velocity: &mut [Vec<f64>], bodies: &Bodies) {
        if self.velocity_before_passes.is_empty() {
            self.velocity_before_passes = (0..grid.dim()).map(|_| grid.zeros()).collect();
        }
        for component in 0..grid.dim() {
            if let Some(block) = touched_block(bodies, component) {
                force_block_adding_prediction(
                    grid,
                    &block,
                    &mut velocity[component],
                    &mut self.velocity_before_passes[component],
                    &self.total_fraction[component],
                    &self.solid_velocity[component],
                );
            }
        }
    }

    /// The last of the stage's `passes` passes of forcing of length
    /// `stage_dt`: returns the loads of all of them on each local particle
    /// from this rank's faces, per unit fluid density (eq. 5–7 without the
    /// density factors), then forces `velocity` and clears the sums.
    pub fn last_pass(
        &mut self,
        grid: &Grid,
        velocity: &mut [Vec<f64>],
        bodies: &Bodies,
        stage_dt: f64,
        exponents: &Exponents,
        passes: usize,
    ) -> Loads {
        let loads = self.loads_of_passes(grid, velocity, bodies, stage_dt, exponents, passes);
        self.force_touched::<false>(grid, velocity, bodies);
        if passes > 1 {
            for component in 0..grid.dim() {
                if let Some(block) = touched_block(bodies, component) {
                    crate::deferred_loads::clear_block(
                        grid,
                        &block,
                        &mut self.velocity_before_passes[component],
                    );
                }
            }
        }
        self.set_forcing_sums_pending(false);
        loads
    }

    /// The loads `−Σ_faces w_p (n U_p − S − V) dV/h` of the stage's passes
    /// before the last forces `velocity` (`S` = 0 in one pass): the
    /// particle receives −f, the opposite of what it gives. With the sums
    /// made before the shares, `α_p` is the share `w_p` already.
    fn loads_of_passes(
        &self,
        grid: &Grid,
        velocity: &[Vec<f64>],
        bodies: &Bodies,
        stage_dt: f64,
        exponents: &Exponents,
        passes: usize,
    ) -> Loads {
        let total = &self.total_fraction;
        let before = &self.velocity_before_passes;
        let made_before_shares = bodies.forcing_sums_made();
        let n = passes as f64;
        let scale = -grid.cell_volume() / stage_dt;
        let per_body: Vec<(Vec3, Vec3)> = bodies
            .list
            .par_iter()
            .map(|body| {
                let exponent = exponents.of(body.particle);
                let reads: &[&[Vec<f64>]] = match (made_before_shares, passes) {
                    (true, 1) => &[velocity],
                    (false, 1) => &[velocity, total],
                    _ => &[velocity, before],
                };
                let (force, torque) = body.moments(reads, |component, faces, row| {
                    let rigid = body.rigid_along(row, component, faces.step);
                    let faces = row.faces();
                    let fields = RowFields {
                        alpha: row.alpha,
                        velocity: &velocity[component][faces.clone()],
                        total: &total[component][faces.clone()],
                        before: match passes {
                            1 => &[],
                            _ => &before[component][faces],
                        },
                    };
                    match (made_before_shares, passes) {
                        (true, 1) => row_load::<true, false>(&fields, rigid, exponent, n),
                        (false, 1) => row_load::<false, false>(&fields, rigid, exponent, n),
                        (true, _) => row_load::<true, true>(&fields, rigid, exponent, n),
                        (false, _) => row_load::<false, true>(&fields, rigid, exponent, n),
                    }
                });
                (force * scale, torque * scale)
            })
            .collect();
        self.gather(bodies, &per_body)
    }
}

/// The fields of one row of a body's faces that its load reads.
struct RowFields<'a> {
    alpha: &'a [f64],
    velocity: &'a [f64],
    total: &'a [f64],
    /// `S`, over the passes before the last (empty in one pass).
    before: &'a [f64],
}

/// `(Σ_i q_i, Σ_i i q_i)` of the load `q = w (n U − S − V)` along a row
/// whose rigid velocity is `base + i slope` (`rigid`), `w` the share `α`
/// where the sums were made before the shares (`SHARES`), else
/// `β/max(1, Σ β)`; in one pass (not `SEVERAL`) `w (U − V)`, eq. 7's form.
#[inline(always)]
fn row_load<const SHARES: bool, const SEVERAL: bool>(
    row: &RowFields,
    (base, slope): (f64, f64),
    exponent: f64,
    n: f64,
) -> (f64, f64) {
    let length = row.alpha.len();
    let (velocity, total) = (&row.velocity[..length], &row.total[..length]);
    let before = if SEVERAL {
        &row.before[..length]
    } else {
        &[][..]
    };
    let (mut sum, mut along) = (0.0, 0.0);
    for (i, (alpha, v)) in row.alpha.iter().zip(velocity).enumerate() {
        let weight = match SHARES {
            true => *alpha,
            false => forced_fraction(*alpha, exponent) / total[i].max(1.0),
        };
        let rigid = base + i as f64 * slope;
        let q = match SEVERAL {
            true => weight * (n * rigid - (before[i] + v)),
            false => weight * (rigid - v),
        };
        sum += q;
        along += i as f64 * q;
    }
    (sum, along)
}

/// `V += (Σ β_p U_p − Σ β_p V) / max(1, Σ β_p)` on the faces of `block`
/// of one component, each face's `V` before the forcing added into
/// `before`, the sums `total` and `target` kept: one pass of a stage
/// forced in several, the planes of the slowest axis shared among
/// threads (each face computed alone).
fn force_block_adding_prediction(
    grid: &Grid,
    block: &grainflow_fluid::Block,
    velocity: &mut [f64],
    before: &mut [f64],
    total: &[f64],
    target: &[f64],
) {
    let slow = grid.dim() - 1;
    let plane = grid.stride(slow);
    let mut inner = *block;
    inner.start[slow] = 0;
    inner.end[slow] = 1;
    let first = block.start[slow];
    let rows = |layer: usize, velocity: &mut [f64], before: &mut [f64]| {
        let at = (first + layer) * plane;
        for k in inner.start[2]..inner.end[2] {
            for j in inner.start[1]..inner.end[1] {
                let faces = grid.index(inner.start[0], j, k)..grid.index(inner.end[0], j, k);
                let sums = total[at + faces.start..at + faces.end]
                    .iter()
                    .zip(&target[at + faces.start..at + faces.end]);
                let faces = velocity[faces.clone()].iter_mut().zip(&mut before[faces]);
                for ((v, before), (total, target)) in faces.zip(sums) {
                    let predicted = *v;
                    *before += predicted;
                    *v += (target - total * predicted) / total.max(1.0);
                }
            }
        }
    };
    let planes = block.start[slow] * plane..block.end[slow] * plane;
    velocity[planes.clone()]
        .par_chunks_mut(plane)
        .zip(before[planes].par_chunks_mut(plane))
        .enumerate()
        .for_each(|(layer, (velocity, before))| rows(layer, velocity, before));
}
