//! Time-step limits of the explicit DEM integration, measured by the sweep
//! in `tests/stability.rs` (velocity Verlet, linear spring–dashpot):
//!
//! - accuracy: beyond Δt/t_c = [`ACCURATE_DT_OVER_TC`] a binary collision's
//!   restitution departs from e_n by more than 1 %;
//! - stability: beyond Δt/t_c = [`STABLE_DT_OVER_TC`] a dense packing under
//!   gravity (several contacts per grain) blows up. A single binary contact
//!   survives larger steps; packings are what a scene holds.
//!
//! `check` and `run` warn past the first and refuse past the second.

use grainflow_dem::ContactLaw;

pub const ACCURATE_DT_OVER_TC: f64 = 0.05;
pub const STABLE_DT_OVER_TC: f64 = 0.3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeStepVerdict {
    Accurate,
    /// Stable but the restitution is off by more than 1 %.
    Inaccurate,
    /// Past the stability limit: the run is refused.
    Unstable,
}

/// Smallest binary contact time of the scene: the contact of the lightest
/// pair, m* = m_min/2 (or m_min against a wall, whichever is shorter).
pub fn shortest_contact_time(law: &ContactLaw, lightest_mass: f64) -> f64 {
    law.contact_time(0.5 * lightest_mass)
        .min(law.contact_time(lightest_mass))
}

pub fn verdict(dt_over_tc: f64) -> TimeStepVerdict {
    if dt_over_tc > STABLE_DT_OVER_TC {
        TimeStepVerdict::Unstable
    } else if dt_over_tc > ACCURATE_DT_OVER_TC {
        TimeStepVerdict::Inaccurate
    } else {
        TimeStepVerdict::Accurate
    }
}
