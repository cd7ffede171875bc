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
    /// A thin plate that grains touch from either side (a gate with a
    /// column behind it and an erodible layer in front): each grain is
    /// pushed away from the plane towards its own side. Otherwise the
    /// grains live on the side `normal` points into.
    pub two_sided: bool,
}

impl PlaneWall {
    pub fn is_present(&self, time: f64) -> bool {
        self.remove_at.is_none_or(|t| time < t)
    }

    /// Signed distance from the plane to a point (positive on the particle
    /// side; for a two-sided wall, the distance on either side).
    #[inline(always)]
    pub fn distance(&self, x: &Vec3) -> f64 {
        let signed = (x - self.point).dot(&self.normal);
        if self.two_sided {
            signed.abs()
        } else {
            signed
        }
    }

    /// The wall's normal towards the grain at `x`: `normal`, or for a
    /// two-sided wall its opposite on the other side.
    #[inline(always)]
    pub fn normal_towards(&self, x: &Vec3) -> Vec3 {
        if self.two_sided && (x - self.point).dot(&self.normal) < 0.0 {
            -self.normal
        } else {
            self.normal
        }
    }
}
