//! How fast the direct forcing relaxes a grain's transition layer.
//!
//! Eq. 7 moves a face of solid fraction `α` the fraction `α` of the way
//! to the rigid velocity at every Runge–Kutta stage, so over a time `t`
//! the layer is relaxed by `(1 − α)^{3t/Δt}`: at a rate that grows as the
//! step shrinks, while the flow renews the layer (advection, diffusion) at
//! a rate that does not. The shorter the step, the more of the layer moves
//! with the grain and the larger the grain looks (the falling sphere at
//! D/Δx = 10 in (r, z) settles 12.5 % slower at a tenth of the paper's
//! step, `docs/validation.md` §10).
//!
//! With a relaxation rate `r` of its own, a stage moves the face by
//!
//! ```text
//! β = 1 − (1 − α)^{r Δt}          (eq. 7 at r Δt = 1)
//! ```
//!
//! (the same `β` at each of the three stages, as eq. 7 is), which relaxes
//! the layer at `−3 r ln(1 − α)` whatever the step; where `α = 1`, `β = 1`
//! and the inside of the grain moves rigidly at every stage. Where
//! `r Δt > 1` a stage forces in `n = ⌈r Δt⌉` passes of `r Δt/n`, each
//! followed by the projection: they compose to the same `β`, and the
//! pressure between touching grains stays bounded, as under eq. 7
//! ([`crate::forcing::Exponents::passes`]).
//!
//! [`LayerForcing::Renewal`] takes `r` as the rate at which the flow
//! itself renews the layer, by advection across a cell and diffusion
//! across it:
//!
//! ```text
//! r = s/Δx + ν/(c Δx²),      c = 0.8,
//! ```
//!
//! with `s` the root mean square slip `|u − U_p|` of the fluid in the
//! grain's layer (faces weighted by `α (1 − α)`, after the prediction,
//! every component), a measure that does not depend on the frame. Each
//! term is calibrated where it alone acts: `c = 0.8` is the viscous number
//! at which a sphere spun in a Stokes flow carries the torque `8πμR³ω`
//! within 2.6 % over a factor 4 in Δt (`tests/spin_down.rs`), and in a
//! flow that slips past the layer at the grain's speed `U`, `s ≈ U` makes
//! `r Δt = 1` at the paper's step `Δt = Δx/U` (eq. 7 as the paper
//! calibrated it). A settling sphere at Re = 20 sits mostly in the first
//! regime (`s ≈ 0.13 U` at D/Δx = 20); a bouncing sphere at St above a few
//! hundred in the second.

/// The viscous number `ν Δt_f/Δx²` of the layer's relaxation by diffusion
/// (the spin-down calibration above).
pub const VISCOUS_NUMBER: f64 = 0.8;

/// Numbers per local particle in the layer's slip sums: `Σ w (u − U)_c²`
/// for the three components, then `Σ w` for each.
pub const SLIP_SUMS: usize = 6;

/// The relaxation of the transition layer by the direct forcing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LayerForcing {
    /// Eq. 7 at every stage (the paper's): the rate follows the step.
    EveryStage,
    /// As eq. 7 at a fixed step `Δt_f` (s), whatever the fluid step.
    Held { step: f64 },
    /// At the flow's own renewal rate of the layer (module docs).
    Renewal,
}

impl LayerForcing {
    /// The exponent `r Δt` of every grain in a step of `step_dt`, where it
    /// is the same for all; `None` for [`LayerForcing::Renewal`], whose
    /// exponent is each grain's own ([`renewal_exponent`]).
    pub fn uniform_exponent(&self, step_dt: f64) -> Option<f64> {
        match *self {
            LayerForcing::EveryStage => Some(1.0),
            LayerForcing::Held { step } => Some(step_dt / step),
            LayerForcing::Renewal => None,
        }
    }

    /// The step at which the layer is relaxed as eq. 7 does at a fluid
    /// step `step_dt`, where one is fixed: what the grains' CFL number is
    /// read against. `None` for [`LayerForcing::Renewal`], whose grain
    /// does not depend on it.
    pub fn layer_step(&self, step_dt: f64) -> Option<f64> {
        match *self {
            LayerForcing::EveryStage => Some(step_dt),
            LayerForcing::Held { step } => Some(step),
            LayerForcing::Renewal => None,
        }
    }
}

/// The root mean square slip `s` from one grain's [`SLIP_SUMS`] numbers:
/// the mean square slip of each component over its faces, summed.
pub fn slip_from_sums(sums: &[f64]) -> f64 {
    (0..3)
        .filter(|&c| sums[3 + c] > 0.0)
        .map(|c| sums[c] / sums[3 + c])
        .sum::<f64>()
        .sqrt()
}

/// `r Δt` of [`LayerForcing::Renewal`] for a grain whose layer slips at
/// `slip` (m/s), in a fluid of kinematic viscosity `viscosity` on cells of
/// size `spacing`, at a fluid step `step_dt`.
pub fn renewal_exponent(slip: f64, viscosity: f64, spacing: f64, step_dt: f64) -> f64 {
    step_dt * (slip / spacing + viscosity / (VISCOUS_NUMBER * spacing * spacing))
}

/// The weight of a face of solid fraction `alpha` in the layer's slip:
/// largest mid-layer, none inside or outside the grain.
#[inline]
pub(crate) fn slip_weight(alpha: f64) -> f64 {
    alpha * (1.0 - alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_layer_slipping_at_the_grains_speed_is_forced_as_eq_7_at_cfl_one() {
        // Without viscosity the exponent is the grain's CFL number.
        let (speed, spacing) = (0.4, 1e-3);
        let step = spacing / speed;
        assert!((renewal_exponent(speed, 0.0, spacing, step) - 1.0).abs() < 1e-15);
        // Without slip, the viscous number: ν Δt/Δx² = 0.8 gives one.
        let viscosity = 1e-6;
        let step = VISCOUS_NUMBER * spacing * spacing / viscosity;
        assert!((renewal_exponent(0.0, viscosity, spacing, step) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_slip_adds_the_components_mean_squares() {
        // x faces slip by 3 everywhere, z by 4, y faces absent (2D).
        let sums = [9.0 * 2.0, 0.0, 16.0 * 0.5, 2.0, 0.0, 0.5];
        assert!((slip_from_sums(&sums) - 5.0).abs() < 1e-15);
    }

    #[test]
    fn the_uniform_exponents_are_eq_7_and_the_held_step() {
        assert_eq!(LayerForcing::EveryStage.uniform_exponent(0.3), Some(1.0));
        let held = LayerForcing::Held { step: 0.2 };
        assert!((held.uniform_exponent(0.1).unwrap() - 0.5).abs() < 1e-15);
        assert_eq!(LayerForcing::Renewal.uniform_exponent(0.1), None);
        assert_eq!(LayerForcing::Renewal.layer_step(0.1), None);
    }
}
