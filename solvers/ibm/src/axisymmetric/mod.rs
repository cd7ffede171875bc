//! Grains on the axis of an axisymmetric (r, z) flow: a sphere settling or
//! bouncing on the axis of a cylinder, as Izard et al. (2014, §3.1 and
//! §4.1) ran their benchmarks, on a 2D grid.
//!
//! - [`bodies`]: the faces within each grain's support, their solid
//!   fractions (eq. 8–10 in the meridian plane) and ring volumes; the
//!   checks that refuse a grain off the axis or whose support reaches a
//!   stretched radial cell;
//! - [`forcing`]: the direct forcing of eq. 7 and the loads of eq. 5–6
//!   along the axis;
//! - [`coupled`]: the coupled step, the Cartesian one's stages and loads.

pub mod bodies;
pub mod coupled;
pub mod forcing;

pub use bodies::{check_grains_on_axis, AxialBodies, EndLayers};
pub use coupled::AxisymmetricCoupledSystem;
pub use forcing::AxisymmetricImmersed;
