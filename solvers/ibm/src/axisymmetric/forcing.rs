//! The direct forcing of eq. 7 on an (r, z) flow by grains on its axis,
//! and the loads it gives them (eq. 5–6), as [`crate::forcing`] does on a
//! Cartesian grid: within a stage of length `h`, every face of the
//! grains' supports receives
//!
//! ```text
//! f = Σ_p w_p (U_p − V) / h,      w_p = β_p / max(1, Σ_q β_q),
//! ```
//!
//! `β = 1 − (1 − α)^e` (`α` itself under eq. 7; [`crate::layer_forcing`]), with
//! the rigid velocity `U_p = (0, w_p)` of a grain that moves along the
//! axis without spinning (a spin about the axis would be swirl). The
//! grain receives `F_p = −Σ_faces w_p (U_p − V) dV / h` along z, `dV` the
//! ring volume `2π r̄ Δr Δz` of each `u_z` face; the radial components
//! cancel over a revolution, and so does every torque.

use grainflow_core::Vec3;
use grainflow_dem::Particles;
use grainflow_fluid::axisymmetric::{AxisymmetricFlow, RzGrid};

use super::bodies::{ring_width, AxialBodies, AxialBody, EndLayers};
use crate::exponents::forced_fraction;
use crate::forcing::Loads;
use crate::layer_forcing::{
    renewal_exponent, slip_from_sums, slip_weight, LayerForcing, SLIP_SUMS,
};
use crate::solid_fraction::solid_fraction;

/// The grains' action on an (r, z) flow.
pub struct AxisymmetricImmersed {
    /// `Δ` of eq. 8.
    pub width: f64,
    /// How fast the forcing relaxes the transition layer; eq. 7 at every
    /// stage unless set.
    pub layer: LayerForcing,
    /// The layers along the wall ends that moving grains leave to the
    /// fluid; none: the paper's forcing, which reaches the walls.
    pub free_end_layers: EndLayers,
    /// `Σ_p β_p` and `Σ_p β_p U_p` on the faces of each component (zero
    /// between stages), and the scratch of the overlaps' shares.
    total: [Vec<f64>; 2],
    target: [Vec<f64>; 2],
    shares: [Vec<f64>; 2],
}

impl AxisymmetricImmersed {
    /// The paper's forcing on `grid`, with `free_end_layers` left to the
    /// fluid.
    pub fn new(grid: &RzGrid, free_end_layers: EndLayers) -> Self {
        let zeros = || [grid.zeros(), grid.zeros()];
        AxisymmetricImmersed {
            width: ring_width(grid),
            layer: LayerForcing::EveryStage,
            free_end_layers,
            total: zeros(),
            target: zeros(),
            shares: zeros(),
        }
    }

    /// The grains of `particles` with their faces on `flow`'s grid.
    pub fn bodies(&mut self, particles: &Particles, flow: &AxisymmetricFlow) -> AxialBodies {
        AxialBodies::new(
            particles,
            &flow.grid,
            &flow.walls,
            &self.free_end_layers,
            &mut self.shares,
        )
    }

    /// The fluid's momentum inside each grain, `∫ α_p u dV` along z (per
    /// unit density).
    pub fn inner_momentum(&self, flow: &AxisymmetricFlow, bodies: &AxialBodies) -> Loads {
        let mut loads = Loads::zeros(bodies.count);
        for body in &bodies.list {
            let faces = &body.faces[1];
            let momentum: f64 = (0..faces.index.len())
                .map(|f| faces.alpha[f] * flow.axial[faces.index[f]] * faces.volume[f])
                .sum();
            loads.force[body.particle].z += momentum;
        }
        loads
    }

    /// `Σ_faces α_p dV` of each grain on the `u_z` faces: the volume the
    /// grid sees, along z (the body force acts along z only).
    pub fn grid_volumes(&self, bodies: &AxialBodies) -> Vec<Vec3> {
        let mut volumes = vec![Vec3::zeros(); bodies.count];
        for body in &bodies.list {
            let faces = &body.faces[1];
            volumes[body.particle].z = faces
                .alpha
                .iter()
                .zip(&faces.volume)
                .map(|(a, v)| a * v)
                .sum();
        }
        volumes
    }

    /// Each grain's exponent `e` of the forcing in a step `step_dt`, from
    /// the predicted velocity of `flow` under the renewal
    /// ([`crate::layer_forcing`]).
    pub fn exponents(
        &self,
        flow: &AxisymmetricFlow,
        bodies: &AxialBodies,
        step_dt: f64,
    ) -> Vec<f64> {
        bodies
            .list
            .iter()
            .map(|body| {
                self.layer.uniform_exponent(step_dt).unwrap_or_else(|| {
                    let slip = slip_from_sums(&layer_slip(flow, body));
                    renewal_exponent(slip, flow.viscosity, flow.grid.dz, step_dt)
                })
            })
            .collect()
    }

    /// Applies the forcing of a stage of length `stage_dt` with the
    /// grains' `exponents` (in list order) to the predicted velocity of
    /// `flow`, and returns each grain's load per unit density. A stage
    /// whose largest exponent exceeds one forces in as many passes
    /// ([`crate::forcing::Exponents::passes`] says why), each followed by a
    /// projection.
    pub fn apply(
        &mut self,
        flow: &mut AxisymmetricFlow,
        bodies: &AxialBodies,
        stage_dt: f64,
        exponents: &[f64],
    ) -> Loads {
        // 1. Σ β_p and Σ β_p U_p on the faces, in list order.
        for (body, &exponent) in bodies.list.iter().zip(exponents) {
            for c in 0..2 {
                let rigid = if c == 0 { 0.0 } else { body.velocity };
                let faces = &body.faces[c];
                for (&at, &alpha) in faces.index.iter().zip(&faces.alpha) {
                    let beta = forced_fraction(alpha, exponent);
                    self.total[c][at] += beta;
                    self.target[c][at] += beta * rigid;
                }
            }
        }
        // 2. The loads, from the velocity before the forcing.
        let mut loads = Loads::zeros(bodies.count);
        let scale = -1.0 / stage_dt;
        for (body, &exponent) in bodies.list.iter().zip(exponents) {
            let faces = &body.faces[1];
            let total = &self.total[1];
            let force: f64 = (0..faces.index.len())
                .map(|f| {
                    let at = faces.index[f];
                    let weight = forced_fraction(faces.alpha[f], exponent) / total[at].max(1.0);
                    weight * (body.velocity - flow.axial[at]) * faces.volume[f]
                })
                .sum();
            loads.force[body.particle].z += scale * force;
        }
        // 3. V += Σ w_p (U_p − V), and the scratch cleared.
        for body in &bodies.list {
            for c in 0..2 {
                let velocity = if c == 0 {
                    &mut flow.radial
                } else {
                    &mut flow.axial
                };
                let (total, target) = (&mut self.total[c], &mut self.target[c]);
                for &at in &body.faces[c].index {
                    let sum = total[at];
                    if sum > 0.0 {
                        velocity[at] += (target[at] - sum * velocity[at]) / sum.max(1.0);
                        total[at] = 0.0;
                        target[at] = 0.0;
                    }
                }
            }
        }
        flow.fill_velocity_ghosts();
        loads
    }

    /// `Σ_p α_p` capped at 1 at every cell centre, r fastest: the solid
    /// fraction field for output.
    pub fn cell_solid_fraction(&self, grid: &RzGrid, particles: &Particles) -> Vec<f64> {
        let [nr, nz] = grid.cells;
        let mut field = vec![0.0; nr * nz];
        for k in 0..particles.n_owned {
            let (z, radius) = (particles.position[k].z, particles.radius[k]);
            for kz in 1..=nz {
                for i in 1..=nr {
                    let offset = [grid.centre(i), grid.z_centre(kz) - z, 0.0];
                    field[(i - 1) + nr * (kz - 1)] += solid_fraction(offset, radius, self.width);
                }
            }
        }
        field.iter_mut().for_each(|alpha| *alpha = alpha.min(1.0));
        field
    }
}

/// The sums of the layer's slip of `body` in the predicted velocity of
/// `flow` ([`crate::layer_forcing`]): the faces weighted by their ring
/// volumes too, `u_r` against no radial motion, `u_z` against the grain's.
fn layer_slip(flow: &AxisymmetricFlow, body: &AxialBody) -> [f64; SLIP_SUMS] {
    let mut sums = [0.0; SLIP_SUMS];
    for (c, component) in [0, 2].into_iter().enumerate() {
        let (velocity, rigid) = if c == 0 {
            (&flow.radial, 0.0)
        } else {
            (&flow.axial, body.velocity)
        };
        let faces = &body.faces[c];
        for f in 0..faces.index.len() {
            let weight = slip_weight(faces.alpha[f]) * faces.volume[f];
            let slip = velocity[faces.index[f]] - rigid;
            sums[component] += weight * slip * slip;
            sums[3 + component] += weight;
        }
    }
    sums
}
