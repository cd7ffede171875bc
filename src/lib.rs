//! grainflow: resolved grains in fluids.
//!
//! This crate assembles scenes from case files and runs them; the physics
//! lives in the solver crates (`grainflow-dem`, `grainflow-fluid`, ...). A
//! run goes case file → [`case::Case`] (typed, validated) →
//! [`simulation::model::Model`] (grains from [`scene::build`], a fluid from
//! [`scene::fluid::build`], or both) → [`simulation::run`]: one time loop
//! ([`simulation::time_loop`]) that calls the writers of [`output`] and the
//! analyses on a schedule, and writes [`checkpoint`]s to resume from.

pub mod analysis;
pub mod case;
pub mod check;
pub mod checkpoint;
pub mod footprint;
#[cfg(feature = "hdf5")]
pub mod hdf5_output;
pub mod output;
pub mod progress;
pub mod report;
pub mod scene;
pub mod sharing;
pub mod simulation;
pub mod stability;

/// Why a run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The case cannot run as given (nothing was written).
    #[error("{0}")]
    Case(String),
    /// The integration went wrong; outputs hold the last good state.
    #[error("{0}")]
    Unstable(String),
    #[error("output: {0}")]
    Io(std::io::Error),
}
