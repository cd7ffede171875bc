//! The conic solvers of COCD's program (module docs of [`crate::cocd`]):
//! grainflow's interior point on the normal equations
//! ([`interior_point`], its factor in `normal_factor`: supernodal, split
//! by nested dissection over threads and ranks), the accelerated projected
//! gradient on the dual ([`projected_gradient`], no factor), and the
//! second-order cone's algebra both use ([`second_order_cone`]).

pub(crate) mod cone_blocks;
pub(crate) mod csc;
pub(crate) mod dissection;
pub mod interior_point;
pub(crate) mod normal_factor;
pub mod projected_gradient;
pub mod second_order_cone;
