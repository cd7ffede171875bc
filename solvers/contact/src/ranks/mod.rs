//! Hard contact on several MPI ranks: a step's program shared among the
//! ranks, each owning its grains' unknowns, the unknowns coupled across
//! rank boundaries forming a separator ([`shared_program`]), and the
//! exchange of contacts and impulses between neighbouring ranks
//! ([`sharing`]).

pub mod shared_program;
pub mod sharing;
