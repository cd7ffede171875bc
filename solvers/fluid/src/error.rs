//! Errors a fluid case can make.

use std::fmt;

/// A fluid set-up the solvers cannot run.
#[derive(Debug, Clone, PartialEq)]
pub enum FluidError {
    /// Inconsistent or unsupported boundary conditions.
    Boundary(String),
}

impl fmt::Display for FluidError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FluidError::Boundary(message) => write!(f, "fluid boundary conditions: {message}"),
        }
    }
}

impl std::error::Error for FluidError {}
