//! One grain as the grid sees it, and the sums over its faces that the
//! immersed boundaries read: the fluid's momentum inside it
//! (`∫ α u dV`, `∫ r × α u dV`), its shares of faces that other grains
//! cover, the slip of its layer, and the force and torque of a face field
//! on it (eq. 5–6). Each sum runs over the grain's rows of faces
//! ([`FaceRows`]) in a fixed order, so that its bits do not depend on the
//! number of threads.

use grainflow_core::Vec3;

use crate::faces::{FaceRows, Row};
use crate::layer_forcing::{slip_weight, SLIP_SUMS};

/// One particle (owned or a ghost) as the grid sees it.
#[derive(Clone, Debug)]
pub(crate) struct Body {
    /// Local index of the particle.
    pub(crate) particle: usize,
    pub(crate) centre: Vec3,
    pub(crate) velocity: Vec3,
    pub(crate) angular_velocity: Vec3,
    pub(crate) radius: f64,
    /// Its faces of each velocity component with their solid fractions,
    /// made once per stage: the forcing, the loads, the inner momentum
    /// and the grid volumes all read them (the exponential of eq. 8 is
    /// the costly part of each face).
    pub(crate) faces: Vec<FaceRows>,
    /// `Σ α` over its faces of each component, where the pass that made
    /// its shares summed them ([`FaceRows::share_and_weigh`]).
    pub(crate) fraction_sums: Option<Vec3>,
}

impl Body {
    /// A still body at `centre` of `radius`, without faces (for tests of
    /// what reads only where bodies stand).
    #[cfg(test)]
    pub(crate) fn standing(particle: usize, centre: Vec3, radius: f64) -> Body {
        Body {
            particle,
            centre,
            velocity: Vec3::zeros(),
            angular_velocity: Vec3::zeros(),
            radius,
            faces: Vec::new(),
            fraction_sums: None,
        }
    }

    /// The body without its faces.
    pub(crate) fn clone_without_faces(&self) -> Body {
        Body {
            particle: self.particle,
            centre: self.centre,
            velocity: self.velocity,
            angular_velocity: self.angular_velocity,
            radius: self.radius,
            faces: Vec::new(),
            fraction_sums: None,
        }
    }

    /// Rigid velocity `u_p + ω_p × r` at offset `r` from the centre.
    #[inline]
    fn velocity_at(&self, offset: &Vec3) -> Vec3 {
        self.velocity + self.angular_velocity.cross(offset)
    }

    /// The `component` of the rigid velocity along `row` of faces `step`
    /// apart: `base + i slope` at its face `i` (`ω × x̂ = (0, ω_z, −ω_y)`).
    #[inline]
    pub(crate) fn rigid_along(&self, row: &Row, component: usize, step: f64) -> (f64, f64) {
        let w = self.angular_velocity;
        let slope = [0.0, w.z, -w.y][component] * step;
        (self.velocity_at(&row.offset)[component], slope)
    }

    /// `∫ α u dV` and `∫ r × α u dV` over the body's faces of the face
    /// field `velocity`, cells of volume `volume`.
    pub(crate) fn inner_momentum(&self, velocity: &[Vec<f64>], volume: f64) -> (Vec3, Vec3) {
        let (momentum, angular) = self.moments(&[velocity], |component, _, row| {
            let velocity = &velocity[component][row.faces()];
            let (mut sum, mut along) = (0.0, 0.0);
            for (i, (alpha, v)) in row.alpha.iter().zip(velocity).enumerate() {
                let q = alpha * v;
                sum += q;
                along += i as f64 * q;
            }
            (sum, along)
        });
        (momentum * volume, angular * volume)
    }

    /// The sums of the layer's slip `Σ w (V − U)_c²` and `Σ w` on the
    /// faces of each component `c` in the face field `velocity`, `w` the
    /// face's [`slip_weight`] ([`crate::layer_forcing`]).
    pub(crate) fn layer_slip(&self, velocity: &[Vec<f64>]) -> [f64; SLIP_SUMS] {
        let mut sums = [0.0; SLIP_SUMS];
        for (component, faces) in self.faces.iter().enumerate() {
            for row in faces.rows() {
                let (base, slope) = self.rigid_along(&row, component, faces.step);
                let velocity = &velocity[component][row.faces()];
                for (i, (alpha, v)) in row.alpha.iter().zip(velocity).enumerate() {
                    let weight = slip_weight(*alpha);
                    let slip = v - (base + i as f64 * slope);
                    sums[component] += weight * slip * slip;
                    sums[3 + component] += weight;
                }
            }
        }
        sums
    }

    /// Replaces the body's fractions by its shares of the faces whose
    /// totals of all bodies' fractions, `totals`, exceed one, and returns
    /// its [`Body::inner_momentum`] in `velocity` with them, in one pass.
    pub(crate) fn share_and_weigh(
        &mut self,
        totals: &[Vec<f64>],
        velocity: &[Vec<f64>],
        volume: f64,
    ) -> (Vec3, Vec3) {
        let mut momentum = Vec3::zeros();
        let mut angular = Vec3::zeros();
        let mut fraction_sums = Vec3::zeros();
        for (component, faces) in self.faces.iter_mut().enumerate() {
            let (sum, moment, fractions) =
                faces.share_and_weigh(&totals[component], &velocity[component]);
            momentum[component] += sum;
            fraction_sums[component] = fractions;
            let mut axis = Vec3::zeros();
            axis[component] = 1.0;
            angular += moment.cross(&axis);
        }
        self.fraction_sums = Some(fraction_sums);
        (momentum * volume, angular * volume)
    }

    /// `(Σ q, Σ r × q)` over the body's faces of every component, `q` the
    /// vector along the component whose row sums `(Σ_i q_i, Σ_i i q_i)`
    /// are `row_sums(component, faces, row)`: the force and torque of a
    /// face field on the body. `reads` are the face fields (one vector a
    /// component) that `row_sums` reads, at most two: the pass asks for
    /// their rows ahead.
    pub(crate) fn moments(
        &self,
        reads: &[&[Vec<f64>]],
        mut row_sums: impl FnMut(usize, &FaceRows, &Row) -> (f64, f64),
    ) -> (Vec3, Vec3) {
        let mut force = Vec3::zeros();
        let mut torque = Vec3::zeros();
        for (component, faces) in self.faces.iter().enumerate() {
            let mut fields: [&[f64]; 2] = [&[], &[]];
            for (field, read) in fields.iter_mut().zip(reads) {
                *field = &read[component];
            }
            let (sum, moment) = faces.moments(&fields, |row| row_sums(component, faces, row));
            force[component] += sum;
            // Σ r × (q e_c) = (Σ q r) × e_c.
            let mut axis = Vec3::zeros();
            axis[component] = 1.0;
            torque += moment.cross(&axis);
        }
        (force, torque)
    }
}
