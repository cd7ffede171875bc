//! The lubrication force between approaching grains in a viscous fluid
//! (Izard et al. 2014, eq. 19, after Brenner):
//!
//! ```text
//! F_i = −6π μ ((u_i − u_j)·n) / (δ + η) · (R_i R_j / (R_i + R_j))² n,
//! ```
//!
//! with `n` the unit normal from j to i, `δ` the gap between the surfaces
//! and `η` a roughness length that keeps the force finite at contact. A
//! wall is a grain of infinite radius, so its factor is `R_i²`. The force
//! acts for `0 ≤ δ ≤ range`, as in the paper; while grains overlap the
//! contact law alone acts. (Held at its `δ = 0` value through a contact,
//! the film's damping `6π μ R*² / η` would act for the whole contact time,
//! which a soft DEM stretches far beyond a real one: at `t_c = 1e-4` s it
//! took a quarter of the rebound of a sphere at St = 300 and all of it at
//! St = 38; docs/validation.md, §7.) It exists only in a scene with a
//! fluid: the immersed boundaries do not resolve the film once the gap is
//! below a cell.
//!
//! The force is a damper of coefficient `c = 6π μ R*² / (δ + η)` on the
//! normal relative velocity. As `δ → 0` with a small roughness, `c Δt / m`
//! grows past any explicit limit, so the films are integrated implicitly.
//! Alone, a film takes `v_n` over a step `Δt` to `v_n / (1 + c Δt / m*)`:
//! the force `−c v_n / (1 + c Δt / m*)` applied for `Δt`. A grain held by
//! several films (between two walls, in a packing) must see them implicit
//! together: each made implicit on its own pair, two films facing each
//! other flip the grain's velocity without decay once `c Δt / m ≳ 1`, and
//! three or more make it grow. So each film is divided by the sum of the
//! film rates of both its grains,
//!
//! ```text
//! F = −c v_n / (1 + Δt (r_i + r_j)),     r_i = Σ_{films of i} c_k / m_i,
//! ```
//!
//! (a wall has `r = 0`). With one film this is the pair's implicit step;
//! for a grain between two walls it is the exact implicit step of the two,
//! `v / (1 + Δt r_i)`. In any network the films on grain i change its
//! velocity within a step by at most `a_i = Δt r_i / (1 + Δt r_i) < 1`
//! times the relative velocities they act on, so by Gershgorin's theorem
//! the eigenvalues of the step's damping lie in `[0, 2 max a_i) ⊂ [0, 2)`:
//! no mode of the network grows, whatever the gaps and the step (this is
//! the Jacobi scaling of the implicit system `(M + Δt C) v⁺ = M v`). It
//! tends to the explicit force when `Δt r ≪ 1`.

use grainflow_core::Vec3;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lubrication {
    /// Dynamic viscosity of the fluid μ (Pa s).
    pub viscosity: f64,
    /// Roughness length over the smaller radius of the pair, η / R
    /// (10⁻⁶ to 10⁻³ for real grains).
    pub roughness: f64,
    /// Largest gap at which the force acts, over the smaller radius of the
    /// pair (the paper's R/2 is 0.5).
    pub range: f64,
}

impl Lubrication {
    /// The damping coefficient `c = 6π μ R*² / (δ + η)` of the film
    /// between a grain of radius `radius` and a partner of radius
    /// `partner_radius` (infinite for a wall) at surface gap `gap`; zero
    /// beyond the range and while the surfaces overlap.
    #[inline]
    pub fn damping(&self, gap: f64, radius: f64, partner_radius: f64) -> f64 {
        let smaller = radius.min(partner_radius);
        if gap > self.range * smaller || gap < 0.0 {
            return 0.0;
        }
        let reduced_radius = if partner_radius.is_finite() {
            radius * partner_radius / (radius + partner_radius)
        } else {
            radius
        };
        6.0 * PI * self.viscosity * reduced_radius * reduced_radius
            / (gap + self.roughness * smaller)
    }

    /// Force on i from a partner of radius `partner_radius` (infinite for a
    /// wall) at surface gap `gap` (negative while they overlap), along the
    /// unit normal `normal` from the partner to i, with relative velocity
    /// `relative_velocity = u_i − u_j`; `film_rates = r_i + r_j`, the sum of
    /// the two grains' film rates (module doc; the pair's own
    /// `c (1/m_i + 1/m_j)` when it is their only film), and DEM step `dt`
    /// (0 gives the explicit force). Zero beyond the range and while the
    /// surfaces overlap.
    #[inline]
    #[allow(clippy::too_many_arguments)] // the scalars of one pair, kept flat for the hot loop
    pub fn force(
        &self,
        gap: f64,
        normal: Vec3,
        relative_velocity: Vec3,
        radius: f64,
        partner_radius: f64,
        film_rates: f64,
        dt: f64,
    ) -> Vec3 {
        let damping = self.damping(gap, radius, partner_radius);
        if damping == 0.0 {
            return Vec3::zeros();
        }
        let implicit = damping / (1.0 + dt * film_rates);
        -implicit * relative_velocity.dot(&normal) * normal
    }

    /// Largest gap at which a pair whose smaller radius is `radius` interacts.
    pub fn reach(&self, radius: f64) -> f64 {
        self.range * radius
    }

    /// Speed the film alone takes from a grain of radius `radius` and
    /// inverse inertia `inverse_mass` leaving a wall from surface gap `gap`
    /// (negative while touching) out to the film's range. Over the film
    /// alone `m dv = −6π μ R² dδ / (δ + η)`, so the loss is
    /// `(6π μ R²/m) ln((δ_f + η)/(δ + η))` whatever the time the crossing
    /// takes; zero at or beyond the range.
    pub fn speed_lost_leaving_wall(&self, gap: f64, radius: f64, inverse_mass: f64) -> f64 {
        let (range, roughness) = (self.range * radius, self.roughness * radius);
        if gap >= range {
            return 0.0;
        }
        let per_mass = 6.0 * PI * self.viscosity * radius * radius * inverse_mass;
        per_mass * ((range + roughness) / (gap.max(0.0) + roughness)).ln()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn law() -> Lubrication {
        Lubrication {
            viscosity: 1e-3,
            roughness: 1e-3,
            range: 0.5,
        }
    }

    #[test]
    fn explicit_force_is_eq_19() {
        let (r1, r2, gap, approach) = (1e-3, 2e-3, 1e-4, -0.02);
        let n = Vec3::new(0.0, 0.0, 1.0);
        let f = law().force(gap, n, approach * n, r1, r2, 1.0, 0.0);
        let reduced: f64 = r1 * r2 / (r1 + r2);
        let expected = -6.0 * PI * 1e-3 * approach / (gap + 1e-3 * r1) * reduced.powi(2);
        assert_relative_eq!(f.z, expected, max_relative = 1e-14);
        assert!(f.z > 0.0, "an approaching pair is pushed apart");
        assert_eq!(f.x, 0.0);
        // Separating pairs are held together by the same law.
        let g = law().force(gap, n, -approach * n, r1, r2, 1.0, 0.0);
        assert_relative_eq!(g.z, -expected, max_relative = 1e-14);
    }

    #[test]
    fn the_speed_lost_leaving_a_wall_is_the_film_integrated_over_the_gap() {
        let (radius, inverse_mass) = (1e-3, 250.0);
        let film = law();
        let per_mass = 6.0 * PI * 1e-3 * radius * radius * inverse_mass;
        let eta = 1e-3 * radius;
        let whole = film.speed_lost_leaving_wall(0.0, radius, inverse_mass);
        assert_relative_eq!(
            whole,
            per_mass * (1.0 + 0.5 / 1e-3f64).ln(),
            max_relative = 1e-14
        );
        // Touching counts as contact; from a gap, what is left of the range.
        assert_eq!(
            film.speed_lost_leaving_wall(-1e-6, radius, inverse_mass),
            whole
        );
        let gap = 1e-5;
        let crossed = whole - film.speed_lost_leaving_wall(gap, radius, inverse_mass);
        assert_relative_eq!(
            crossed,
            per_mass * ((gap + eta) / eta).ln(),
            max_relative = 1e-12
        );
        assert_eq!(
            film.speed_lost_leaving_wall(0.5e-3, radius, inverse_mass),
            0.0
        );
    }

    #[test]
    fn the_film_acts_between_contact_and_the_range_only() {
        let n = Vec3::new(1.0, 0.0, 0.0);
        let v = -0.1 * n;
        assert_eq!(
            law().force(0.51e-3, n, v, 1e-3, f64::INFINITY, 1.0, 0.0),
            Vec3::zeros()
        );
        assert!(law().force(0.49e-3, n, v, 1e-3, f64::INFINITY, 1.0, 0.0).x > 0.0);
        let at_contact = law().force(0.0, n, v, 1e-3, f64::INFINITY, 1.0, 0.0);
        // Overlapping surfaces: the contact law alone.
        let overlapping = law().force(-1e-9, n, v, 1e-3, f64::INFINITY, 1.0, 0.0);
        assert_eq!(overlapping, Vec3::zeros());
        // Against a wall the factor is R².
        let expected = 6.0 * PI * 1e-3 * 0.1 * 1e-6 / 1e-6;
        assert_relative_eq!(at_contact.x, expected, max_relative = 1e-14);
    }

    /// Implicit integration: one step of the damper alone takes v to
    /// v / (1 + c Δt / m), so the approach never reverses in a step.
    #[test]
    fn a_stiff_damper_never_reverses_the_approach() {
        let mass = 1e-6;
        let n = Vec3::new(0.0, 1.0, 0.0);
        let v = -0.3;
        let damping = 6.0 * PI * 1e-3 * 1e-6 / 1e-6;
        assert_relative_eq!(
            law().damping(0.0, 1e-3, f64::INFINITY),
            damping,
            max_relative = 1e-14
        );
        for dt in [1e-9, 1e-6, 1e-3, 1.0] {
            let f = law().force(0.0, n, v * n, 1e-3, f64::INFINITY, damping / mass, dt);
            let after = v + dt * f.y / mass;
            assert_relative_eq!(after, v / (1.0 + damping * dt / mass), max_relative = 1e-12);
            assert!(after <= 0.0 && after > v);
        }
    }
}
