//! The exponent `e` of each grain's forcing in a stage: eq. 7 moves a
//! face of solid fraction `α` by `α` of the way to the grain's rigid
//! velocity; a held or renewed forcing (`layer_forcing.rs`) by
//! `1 − (1 − α)^e`, in as many passes of forcing and projection as it
//! takes to keep each pass's exponent at most one.

use grainflow_core::Communicator;
use rayon::prelude::*;

use crate::fast_math::{exp, ln_one_minus};
use crate::forcing::Bodies;

/// The exponent `e` of each grain's forcing `1 − (1 − α)^e` in a stage.
#[derive(Clone, Debug, PartialEq)]
pub enum Exponents {
    /// The same for every grain (eq. 7: 1).
    Uniform(f64),
    /// One per local particle, owned then ghosts.
    PerParticle(Vec<f64>),
}

impl Exponents {
    /// The number of passes of forcing and projection a stage of `bodies`
    /// takes so that no grain is forced with an exponent above one in a
    /// pass: the largest exponent on every rank, rounded up (collective).
    ///
    /// Each pass moves a face at most its fraction of the way to the rigid
    /// velocity, as eq. 7 does, and the projection follows it; passes of
    /// `e/n` compose to the same relaxation of a grain's layer,
    /// `1 − (1 − α)^e`. Forced at once with an exponent `e > 1`:
    ///
    /// - a face deep in the lens between two grains keeps only `(1 − α)^e`
    ///   of the prediction and its pressure gradient; where the two move
    ///   differently their rigid velocities do not add up to a flow
    ///   without divergence, and the pressure the projection needs there
    ///   grows as `(1 − α)^{−e}`, in the lens where their fractions add up
    ///   to one or more without bound (`tests/overlapping_grains.rs`; the
    ///   immersed avalanche's bed went unstable under the renewal forcing);
    /// - a grain alone in a steady viscous flow creeps and then blows up:
    ///   a fixed sphere in Stokes flow at `r Δt = 4` (`tests/stokes_array.rs`)
    ///   held its drag for 2,000 steps, then its superficial velocity drifted
    ///   and the lateral velocity grew sixteenfold per 500 steps until the
    ///   CFL number passed √3 at step 4,000; in four passes it is steady
    ///   to ten digits over 5,500 steps.
    pub fn passes(&self, bodies: &Bodies, communicator: &Communicator) -> usize {
        let largest = bodies
            .list
            .iter()
            .map(|body| self.of(body.particle))
            .fold(0.0, f64::max);
        passes_for(communicator.max(largest))
    }

    /// Each exponent divided by `passes`.
    pub fn per_pass(self, passes: usize) -> Exponents {
        let n = passes as f64;
        match self {
            _ if passes == 1 => self,
            Exponents::Uniform(exponent) => Exponents::Uniform(exponent / n),
            Exponents::PerParticle(each) => {
                Exponents::PerParticle(each.into_iter().map(|e| e / n).collect())
            }
        }
    }

    /// The exponent of local particle `particle`.
    #[inline]
    pub(crate) fn of(&self, particle: usize) -> f64 {
        match self {
            Exponents::Uniform(exponent) => *exponent,
            Exponents::PerParticle(each) => each[particle],
        }
    }
}

/// The passes a stage whose largest forcing exponent is `largest` takes
/// ([`Exponents::passes`]): `⌈largest⌉`, at least one.
pub(crate) fn passes_for(largest: f64) -> usize {
    (largest.ceil() as usize).max(1)
}

/// The fraction `1 − (1 − α)^exponent` of the way to the rigid velocity
/// that a stage moves a face of solid fraction `α` (eq. 7 at exponent 1).
#[inline(always)]
pub(crate) fn forced_fraction(alpha: f64, exponent: f64) -> f64 {
    if exponent == 1.0 {
        alpha.min(1.0)
    } else {
        raise(alpha, exponent)
    }
}

/// `1 − (1 − α)^exponent`, and 1 inside the grain (`α = 1`) at any
/// exponent: without branches or calls, so that a loop over a body's
/// faces runs on vector instructions. `1 − e^z` for `z = e ln(1 − α)`,
/// within two units in the last place of 1: a face's forcing to round-off
/// of the velocities it mixes.
#[inline(always)]
pub(crate) fn raise(alpha: f64, exponent: f64) -> f64 {
    let raised = 1.0 - exp(exponent * ln_one_minus(alpha));
    if alpha >= 1.0 {
        1.0
    } else {
        raised
    }
}

impl Bodies {
    /// The bodies with each fraction `α` replaced by `β = 1 − (1 −
    /// α)^e`, `e` the body's exponent in `exponents`: forced with eq. 7's
    /// weights (exponent one), they are forced as `exponents` forces the
    /// bodies themselves, with the exponential made once for every pass of
    /// a stage rather than twice in each.
    pub fn raised(&self, exponents: &Exponents) -> Bodies {
        let list = self
            .list
            .par_iter()
            .map(|body| {
                let exponent = exponents.of(body.particle);
                let mut raised = body.clone_without_faces();
                raised.faces = if exponent == 1.0 {
                    body.faces.clone()
                } else {
                    let raise = move |alpha| raise(alpha, exponent);
                    body.faces.iter().map(|faces| faces.mapped(raise)).collect()
                };
                raised
            })
            .collect();
        Bodies {
            count: self.count,
            list,
            forcing_sums_made: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fraction without calls is libm's `−expm1(e ln1p(−α))` to two
    /// units in the last place of 1, over a layer's fractions and the exponents
    /// a pass takes (a renewal's slip-weak 0.01 to a pass's 1), and exact
    /// inside the grain and under eq. 7.
    #[test]
    fn the_forced_fraction_is_libms_to_round_off() {
        let mut worst: f64 = 0.0;
        for exponent in [0.01, 0.05, 0.3, 0.5, 0.81, 0.999] {
            for n in 0..=20_000 {
                let alpha = n as f64 / 20_000.0;
                let libm = -(exponent * (-alpha).ln_1p()).exp_m1();
                worst = worst.max((forced_fraction(alpha, exponent) - libm).abs());
            }
            assert_eq!(forced_fraction(1.0, exponent), 1.0);
            assert_eq!(forced_fraction(0.0, exponent), 0.0);
        }
        assert!(worst <= 2.0 * f64::EPSILON, "{worst:e}");
        assert_eq!(forced_fraction(0.3, 1.0), 0.3);
    }
}
