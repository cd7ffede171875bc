//! Frictional plane walls: a wall is a particle of infinite radius and mass
//! (Izard et al. 2014, below eq. 16).

use grainflow_core::Vec3;

#[derive(Clone, Debug)]
pub struct PlaneWall {
    pub name: String,
    /// A point of the plane.
    pub point: Vec3,
    /// Unit normal pointing into the region where particles are.
    pub normal: Vec3,
    /// Coulomb coefficient between a particle and this wall.
    pub friction: f64,
    /// Time at which the wall is taken away (the gate of a column collapse).
    pub remove_at: Option<f64>,
}

impl PlaneWall {
    pub fn is_present(&self, time: f64) -> bool {
        self.remove_at.is_none_or(|t| time < t)
    }

    /// Signed distance from the plane to a point (positive on the particle side).
    #[inline(always)]
    pub fn distance(&self, x: &Vec3) -> f64 {
        (x - self.point).dot(&self.normal)
    }
}
