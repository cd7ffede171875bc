//! grainflow hard contact (Martin et al. 2022, sections 2–3).
//!
//! Grains do not overlap; each time step finds the end-of-step generalized
//! velocity u^{k+1} (translation and rotation of every grain) and the
//! contact impulses at once, then moves the grains by c^{k+1} = c^k + Δt v^{k+1}.
//! Two schemes share the candidate contacts, the bodies and the checks:
//!
//! - **COCD** (convex optimization contact dynamics, eq. 5–10): u^{k+1}
//!   minimises ½ uᵀMu − uᵀMU, U = u^k + Δt M⁻¹ f_ext, under one convex
//!   constraint per candidate contact α,
//!   D_α + Δt ∇D_α·u ≥ μ Δt |P_α A_α u|  (eq. 9),
//!   a second-order cone (eq. 13). Inelastic, Coulomb's full cone; the
//!   contact forces are the cone's dual variables ([`cocd`]). Solved by
//!   grainflow's interior point on the normal equations
//!   ([`interior_point`]: half-planes in 2D, second-order cones in 3D),
//!   by Clarabel on request (the reference) or where it fails.
//! - **NSCD** (non-smooth contact dynamics, Moreau–Jean, section 3.5): the
//!   same Euler step with Signorini's condition on the predicted gap,
//!   D_α + Δt v_n ≥ 0 ⊥ f_n ≥ 0, and Coulomb's law with its sliding rule,
//!   not convexified; solved by Gauss–Seidel over the contacts, each local
//!   problem exactly ([`nscd`]).
//!
//! Every step reports the residual of the contact law in conic
//! complementarity form and the largest overlap after the move
//! ([`certificate`]).
//!
//! Candidates ([`contacts`]) are the pairs and grain–wall pairs whose gap
//! is below a threshold D (section 3.3), widened when grains are fast
//! enough to close a larger gap within the step. The program holds those
//! a pair's own motion can close; the others are checked at the solution
//! and join it if they would overlap ([`candidates`]).
//!
//! Layout: [`step`] advances the grains (either scheme); [`cocd`] builds
//! the conic program and picks its solver; [`conic`] holds the solvers
//! (interior point, projected gradient and their linear algebra); [`ranks`]
//! shares a step's program among MPI ranks.

pub mod candidates;
pub mod certificate;
pub mod cocd;
pub mod conic;
pub mod contacts;
pub mod nscd;
pub mod ranks;
pub mod step;

use conic::{csc, dissection, normal_factor};
pub use conic::{interior_point, projected_gradient, second_order_cone};
pub use ranks::{shared_program, sharing};

pub use cocd::ConicSolver;
pub use contacts::{Bodies, ContactSet, Partner, Scales};
pub use step::{HardContact, Method, StepReport};
