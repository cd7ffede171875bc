//! Errors a fluid case can make.

use std::fmt;

/// A fluid set-up the solvers cannot run.
#[derive(Debug, Clone, PartialEq)]
pub enum FluidError {
    /// Inconsistent or unsupported boundary conditions.
    Boundary(String),
    /// A time step beyond the stability limit of the explicit terms.
    Unstable { cfl: f64, limit: f64 },
    /// An explicit viscous step beyond its stability limit.
    ViscousUnstable { number: f64, limit: f64 },
    /// A set-up this version does not run.
    Unsupported(String),
    /// A physical parameter out of its range.
    Parameter(String),
}

impl fmt::Display for FluidError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FluidError::Boundary(message) => write!(f, "fluid boundary conditions: {message}"),
            FluidError::Unstable { cfl, limit } => write!(
                f,
                "fluid time step refused: CFL number {cfl:.3} exceeds the limit {limit:.3} \
                 (reduce dt)"
            ),
            FluidError::ViscousUnstable { number, limit } => write!(
                f,
                "fluid time step refused: viscous number ν Δt Σ 4/h² = {number:.3} exceeds the \
                 limit {limit:.3} of the explicit viscous step (reduce dt or use Crank–Nicolson)"
            ),
            FluidError::Unsupported(message) => write!(f, "fluid: {message}"),
            FluidError::Parameter(message) => write!(f, "fluid parameter: {message}"),
        }
    }
}

impl std::error::Error for FluidError {}
