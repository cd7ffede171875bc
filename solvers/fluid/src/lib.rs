//! grainflow fluid: the incompressible Navier–Stokes equations (Izard et
//! al. 2014, eq. 1–2) on a staggered grid, advanced by a low-storage
//! three-stage Runge–Kutta scheme with Crank–Nicolson viscous terms and a
//! pressure projection at every stage, with direct (transform plus
//! tridiagonal) Poisson and Helmholtz solvers.
//!
//! Modules, one job each:
//! - [`grid`]: the staggered grid of a subdomain, flat fields with one ghost
//!   layer, uniform or stretched along its last axis;
//! - [`boundary`]: conditions on the domain faces and the ghost values they set;
//! - [`operators`]: divergence, gradient, Laplacian, convection;
//! - [`transform`]: the 1D transforms that diagonalise the second difference;
//! - [`partition`]: how the cells are shared among ranks;
//! - [`poisson`]: direct solvers for `(a I + b L) x = r` (on several ranks
//!   through pencils), their transforms
//!   by rustfft/rustdct or, with the cargo feature `fftw`, by FFTW (module
//!   `fftw`: one plan per axis over all its lines);
//! - [`navier_stokes`]: the time step;
//! - [`axisymmetric`]: the same scheme in (r, z) for scenes symmetric about
//!   an axis, at the cost of a 2D grid.
//!
//! A flow is a [`Grid`] (cells and corners of the subdomain), its
//! [`Boundaries`] (per face: periodic, no-slip, free-slip, moving wall) and
//! a kinematic viscosity, given to [`FlowSolver::new`]; the caller sets the
//! body force and the mean pressure gradient, an initial velocity
//! ([`FlowSolver::set_velocity`], then [`FlowSolver::remove_divergence`]),
//! and calls [`FlowSolver::step`], which returns a [`StepReport`] (kinetic
//! energy, CFL number, divergence) or refuses a step beyond [`CFL_LIMIT`].
//!
//! On several ranks ([`FlowSolver::distributed`]) each holds its share of
//! the cells ([`partition`]: x, and y in 3D, split; the last axis whole),
//! ghosts across shared faces come from the neighbours, and the direct
//! solvers run through pencil transposes (one all-to-all per change of
//! arrangement), or, for a 3D slab along x whose ranks share memory,
//! plane by plane across the ranks' arrays with no transposes.
//!
//! Limits of this version, each refused or stated where it applies: the
//! last axis is never split among ranks; uniform spacing except along the
//! last axis, which may be stretched ([`Grid::stretched`]); fluid may
//! cross the faces of an axis as a through-flow (the same normal velocity
//! on both) or leave through an outflow on the upper face of the last axis;
//! wall velocities
//! constant in time (the viscous solve works on increments with
//! homogeneous conditions); walls of different kinds on the two faces of
//! an axis only along the last axis (z in 3D, y in 2D); the pressure after
//! a step is first order in time, the velocity second order.

// Axis and side loops index several per-axis arrays at once; an index
// reads closer to the maths than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod axisymmetric;
pub mod boundary;
pub mod error;
#[cfg(feature = "fftw")]
pub mod fftw;
pub mod grid;
pub mod navier_stokes;
pub mod operators;
pub mod partition;
pub mod poisson;
mod saved_state;
pub mod transform;

pub use boundary::{Boundaries, BoundaryCondition};
pub use error::FluidError;
pub use grid::{clustered_faces, Block, Clustering, Grid, Location};
pub use navier_stokes::{
    stage_fraction, time_step_for_cfl_rates, FlowSolver, StepReport, ViscousScheme, CFL_LIMIT,
    EXPLICIT_VISCOUS_LIMIT, STAGES,
};
pub use partition::{flow_process_grid, Partition};
pub use poisson::{DirectSolver, TransformBackend};
