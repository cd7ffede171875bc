//! Axisymmetric flows without swirl in (r, z): a sphere settling or
//! bouncing on the axis of a cylinder (Izard et al. 2014, §3.1 and §4.1
//! ran both benchmarks so) at the cost of a 2D grid.
//!
//! The equations are eq. 1–2 in cylindrical coordinates with `u_θ = 0`
//! and nothing depending on θ:
//!
//! ```text
//! ∂u_r/∂t + (1/r) ∂_r (r u_r²) + ∂_z (u_r u_z) = −∂_r p + ν (∇²u_r − u_r/r²),
//! ∂u_z/∂t + (1/r) ∂_r (r u_r u_z) + ∂_z (u_z²) = −∂_z p + ν ∇²u_z + f_z,
//! (1/r) ∂_r (r u_r) + ∂_z u_z = 0,
//! ```
//!
//! discretised on the staggered grid of [`RzGrid`] and advanced by the
//! same RK3 + Crank–Nicolson projection as the Cartesian flow.
//!
//! Modules, one job each:
//! - [`grid`]: the annular cells, radial faces spaced at will (uniform, the
//!   paper's uniform core and arithmetic growth, a tanh clustering), axial
//!   step uniform;
//! - [`walls`]: the outer wall, the two ends along z, and their ghosts;
//! - [`radial`]: the radial parts of the Laplacians as tridiagonal rows;
//! - [`operators`]: divergence, gradient, convection;
//! - [`solver`]: direct `(a I + b L)` solves, transforms along z and
//!   elimination along r;
//! - [`flow`]: the time step.
//!
//! Limits of this version: one rank; no swirl; the body force along z
//! (the axis) only.

pub mod flow;
pub mod grid;
pub mod operators;
pub mod radial;
pub mod solver;
pub mod walls;

pub use flow::AxisymmetricFlow;
pub use grid::{core_and_growth_faces, RzGrid};
pub use walls::{AxialEnd, OuterWall, RzField, RzWalls};
