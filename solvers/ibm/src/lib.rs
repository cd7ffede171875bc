//! grainflow immersed boundaries: resolved spheres in the incompressible
//! flow (Izard et al. 2014, section 2.1) and the coupled fluid–DEM step
//! (section 4).
//!
//! - [`solid_fraction`]: the smooth solid volume fraction `α` of eq. 8–10;
//! - [`forcing`]: the direct forcing `f = α (U − V)/Δt` of eq. 7 on the
//!   staggered faces and the loads it gives the particles (eq. 5–6);
//! - [`layer_forcing`]: how fast the forcing relaxes a grain's transition
//!   layer (eq. 7 at every stage, or at the flow's own renewal rate);
//! - [`coupled`]: the coupled step — forcing at every Runge–Kutta stage,
//!   the DEM sub-cycled within each stage with the hydrodynamic loads held
//!   fixed, contacts and lubrication from the DEM;
//! - [`axisymmetric`]: the same for grains on the axis of an (r, z) flow;
//! - [`settling`]: what a settling sphere should do (Schiller–Naumann
//!   terminal velocity, the early-time fit of its velocity from rest).

// Component loops index several per-component arrays at once; an index
// reads closer to the maths than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod axisymmetric;
mod body;
pub mod coupled;
mod deferred_loads;
mod exponents;
mod face_sums;
mod faces;
mod fast_math;
pub mod forcing;
mod forcing_passes;
pub mod layer_forcing;
mod loads;
mod overlaps;
pub mod settling;
pub mod solid_fraction;
mod stage_loads;
mod wall_layer;

pub use coupled::{
    particle_volume, rigid_inner_fluid_limits, CoupledReport, CoupledSystem, Coupling,
    RigidInnerFluidLimits, Timings, RIGID_INNER_FLUID_FAILS_BELOW, RIGID_INNER_FLUID_WARNS_BELOW,
};
pub use forcing::{Bodies, ImmersedBoundaries, Loads};
pub use layer_forcing::LayerForcing;
