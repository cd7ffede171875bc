//! grainflow fluid: the incompressible Navier–Stokes equations (Izard et
//! al. 2014, eq. 1–2) on a staggered grid, advanced by a low-storage
//! three-stage Runge–Kutta scheme with Crank–Nicolson viscous terms and a
//! pressure projection at every stage, with direct (transform plus
//! tridiagonal) Poisson and Helmholtz solvers.
//!
//! Modules, one job each:
//! - [`grid`]: the staggered grid of a subdomain, flat fields with one ghost layer;
//! - [`boundary`]: conditions on the domain faces and the ghost values they set;
//! - [`operators`]: divergence, gradient, Laplacian, convection;
//! - [`transform`]: the 1D transforms that diagonalise the second difference;
//! - [`poisson`]: direct solvers for `(a I + b L) x = r`;
//! - [`navier_stokes`]: the time step.

// Axis and side loops index several per-axis arrays at once; an index
// reads closer to the maths than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod boundary;
pub mod error;
pub mod grid;
pub mod navier_stokes;
pub mod operators;
pub mod poisson;
pub mod transform;

pub use boundary::{Boundaries, BoundaryCondition};
pub use error::FluidError;
pub use grid::{Block, Grid, Location};
pub use navier_stokes::{FlowSolver, StepReport, CFL_LIMIT};
pub use poisson::DirectSolver;
