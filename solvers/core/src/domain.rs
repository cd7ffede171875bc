//! The physical box of a scene and the part of it a rank owns.

use crate::Vec3;

/// 2D (discs in the x–y plane) or 3D (spheres).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dimension {
    Two,
    Three,
}

impl Dimension {
    pub fn count(self) -> usize {
        match self {
            Dimension::Two => 2,
            Dimension::Three => 3,
        }
    }
}

/// The global box `[lower, upper]` with a periodicity flag per axis.
/// In 2D the z extent is ignored and z is never periodic.
#[derive(Clone, Debug)]
pub struct Domain {
    pub dimension: Dimension,
    pub lower: Vec3,
    pub upper: Vec3,
    pub periodic: [bool; 3],
    pub gravity: Vec3,
}

impl Domain {
    pub fn extent(&self) -> Vec3 {
        self.upper - self.lower
    }

    /// Wraps a position into the box along its periodic axes.
    pub fn wrap(&self, x: &mut Vec3) {
        let length = self.extent();
        for axis in 0..3 {
            if self.periodic[axis] {
                let offset = (x[axis] - self.lower[axis]).rem_euclid(length[axis]);
                x[axis] = self.lower[axis] + offset;
            }
        }
    }
}

/// The part of the domain a rank owns: particles whose centre lies in
/// `[lower, upper)` are owned here; copies of others within the interaction
/// range are ghosts.
#[derive(Clone, Debug)]
pub struct Subdomain {
    pub lower: Vec3,
    pub upper: Vec3,
}

impl Subdomain {
    /// The whole domain as one subdomain (one rank).
    pub fn whole(domain: &Domain) -> Self {
        Subdomain {
            lower: domain.lower,
            upper: domain.upper,
        }
    }
}
