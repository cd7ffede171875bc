//! grainflow soft-sphere DEM (Izard et al. 2014, section 2.2).
//!
//! Spheres (3D) or discs (2D) collide through a linear spring–dashpot normal
//! force and a tangential spring with a Coulomb cap (eq. 13–18). Particles
//! live on a subdomain: the owned ones first, then ghost copies (periodic
//! images here, other ranks' particles later) within the interaction range.
//! Contacts are found through a Verlet list built on a cell grid (O(N)); the
//! force loop runs in parallel over pairs and gathers per particle in a fixed
//! order, so results do not depend on the number of threads.
//!
//! The pieces, in the order a step uses them:
//! - [`Particles`]: flat per-particle arrays (SoA), owned then ghosts.
//! - [`ContactLaw`]: the normal and tangential laws and their calibration.
//! - [`PlaneWall`]: frictional planes, removable at a given time.
//! - [`Lubrication`]: the film force of close grains, in a fluid only.
//! - [`NeighbourList`]: cell binning and the Verlet pair list with the
//!   tangential displacement history of each contact.
//! - [`DemSystem`]: the time step (velocity Verlet) tying them together.

pub mod contact_law;
pub mod generate;
pub mod ghosts;
pub mod lubrication;
pub mod neighbours;
pub mod particles;
pub mod stress;
pub mod system;
mod thread_share;
pub mod threads;
pub mod walls;

pub use contact_law::{ContactLaw, NormalCalibration, NormalStiffness};
pub use lubrication::Lubrication;
pub use neighbours::NeighbourList;
pub use particles::Particles;
pub use system::{Contact, DemSystem, StepDiagnostics};
pub use walls::PlaneWall;
