//! grainflow core: the vector type, the physical domain and its decomposition
//! into subdomains, and the communicator every solver talks through.
//!
//! Nothing in grainflow assumes a single rank: particles and fields live on a
//! [`Subdomain`] with ghost copies, and every global quantity (a sum, a
//! maximum) goes through the [`Communicator`]. The serial build uses
//! [`Communicator::serial`], a one-rank communicator.

pub mod communicator;
pub mod domain;
pub mod process_grid;
pub mod shared;
pub mod state;
pub mod units;

pub use communicator::Communicator;
pub use domain::{
    grid_coords, grid_neighbour, grid_rank, BoxCuts, Dimension, Domain, Side, Subdomain,
};
pub use process_grid::{
    balanced_cuts, balanced_process_grid, describe_cuts, fits, grains_per_box, process_grid,
    PairedGrains, ProcessGrid,
};
pub use shared::SharedArray;
pub use state::{State, StateError};
pub use units::human_bytes;

/// Three-component vector of `f64`. 2D scenes live in the (x, y) plane with
/// z = 0, rotations about z only.
pub type Vec3 = nalgebra::Vector3<f64>;
