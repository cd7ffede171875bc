//! The soft-sphere contact law (Izard et al. 2014, eq. 13–18).
//!
//! Normal: F_n = max(0, k_n δ − γ_n v_n) along the contact normal, with δ the
//! overlap and v_n the normal relative velocity (eq. 15; no attraction).
//! Tangential: a spring k_t ξ on the accumulated tangential displacement ξ of
//! the contact, capped by Coulomb |F_t| ≤ μ F_n (eq. 16); when capped, ξ is
//! reset to the capped force so that the contact slides.
//!
//! Calibration from the restitution e_n and contact time t_c with the
//! effective mass m* = m_i m_j / (m_i + m_j) of each pair:
//! - `Paper`: eq. 17–18, γ_n = −2 m* ln(e_n)/t_c, k_n = m* π²/t_c² + γ_n²/(4 m*).
//!   These are exact for a contact that ends when the overlap returns to
//!   zero. With the no-attraction clamp of eq. 15 a contact ends earlier,
//!   when the force returns to zero, and the restitution is larger than e_n
//!   (by 0.4 % at e_n = 0.87, 10 % at e_n = 0.5).
//! - `Exact` (default): the same damping rate β = −ln(e_n)/t_c, and the
//!   damped frequency ω solving ω t_c = π − 2 arctan(β/ω), which is the
//!   duration of a force-clamped contact. Then the restitution is exactly e_n
//!   and the contact lasts exactly t_c (up to time-integration error):
//!   γ_n = 2 m* β, k_n = m* (ω² + β²).

use grainflow_core::Vec3;

/// How (e_n, t_c) are turned into (k_n, γ_n).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalCalibration {
    Exact,
    Paper,
}

/// The normal spring and dashpot.
#[derive(Clone, Copy, Debug)]
pub enum NormalStiffness {
    /// k_n and γ_n proportional to the effective mass of each pair:
    /// k_n = m* `stiffness_per_mass`, γ_n = m* `damping_per_mass`.
    FromRestitution {
        restitution: f64,
        contact_time: f64,
        calibration: NormalCalibration,
        stiffness_per_mass: f64,
        damping_per_mass: f64,
    },
    /// The same k_n [N/m] and γ_n [N s/m] for every pair.
    Fixed { stiffness: f64, damping: f64 },
}

impl NormalStiffness {
    pub fn from_restitution(
        restitution: f64,
        contact_time: f64,
        calibration: NormalCalibration,
    ) -> Self {
        let beta = -restitution.ln() / contact_time;
        let omega = match calibration {
            NormalCalibration::Paper => std::f64::consts::PI / contact_time,
            NormalCalibration::Exact => clamped_contact_frequency(beta, contact_time),
        };
        NormalStiffness::FromRestitution {
            restitution,
            contact_time,
            calibration,
            stiffness_per_mass: omega * omega + beta * beta,
            damping_per_mass: 2.0 * beta,
        }
    }

    /// (k_n, γ_n) for a pair of effective mass `effective_mass`.
    #[inline(always)]
    pub fn coefficients(&self, effective_mass: f64) -> (f64, f64) {
        self.coefficients_from_inverse_mass(1.0 / effective_mass)
    }

    /// (k_n, γ_n) for a pair with 1/m_i + 1/m_j = `inverse_mass_sum` (the
    /// division is done only where the law needs m*).
    #[inline(always)]
    pub fn coefficients_from_inverse_mass(&self, inverse_mass_sum: f64) -> (f64, f64) {
        match *self {
            NormalStiffness::FromRestitution {
                stiffness_per_mass,
                damping_per_mass,
                ..
            } => (
                stiffness_per_mass / inverse_mass_sum,
                damping_per_mass / inverse_mass_sum,
            ),
            NormalStiffness::Fixed { stiffness, damping } => (stiffness, damping),
        }
    }
}

/// Smallest restitution the `Exact` calibration can reach: with
/// b = −ln(e_n) ≥ 2 no underdamped contact has both the restitution e_n
/// and the duration t_c (x + 2 arctan(b/x) > π for every x = ω t_c > 0).
pub const MIN_EXACT_RESTITUTION: f64 = 0.135_335_283_236_612_7; // e^{-2}

/// Damped angular frequency ω of the linear oscillator whose force-clamped
/// contact lasts `contact_time`: x = ω t_c solves x + 2 arctan(b/x) = π with
/// b = β t_c < 2. The left side falls below π past x = 0 and returns to it
/// at the root, which lies in [√(b(2 − b)), π] (bisection).
fn clamped_contact_frequency(beta: f64, contact_time: f64) -> f64 {
    let b = beta * contact_time;
    assert!(b < 2.0, "restitution below e^-2 has no exact calibration");
    let residual = |x: f64| x + 2.0 * (b / x).atan() - std::f64::consts::PI;
    let (mut low, mut high) = ((b * (2.0 - b)).sqrt(), std::f64::consts::PI);
    for _ in 0..200 {
        let mid = 0.5 * (low + high);
        if residual(mid) < 0.0 {
            low = mid;
        } else {
            high = mid;
        }
    }
    0.5 * (low + high) / contact_time
}

/// Restitution of a force-clamped linear spring–dashpot contact with damping
/// rate β and damped frequency ω: e = exp(−β (π − 2 arctan(β/ω)) / ω).
pub fn clamped_restitution(stiffness_per_mass: f64, damping_per_mass: f64) -> f64 {
    let beta = 0.5 * damping_per_mass;
    let omega = (stiffness_per_mass - beta * beta).sqrt();
    (-beta * (std::f64::consts::PI - 2.0 * (beta / omega).atan()) / omega).exp()
}

/// What the law needs to know of one contact, seen from particle i.
#[derive(Clone, Copy, Debug)]
pub struct ContactPoint {
    /// Overlap δ > 0.
    pub overlap: f64,
    /// Unit normal from the partner (or wall) to i.
    pub normal: Vec3,
    /// Velocity of i's contact point relative to the partner's.
    pub relative_velocity: Vec3,
    /// ω_i − ω_j (ω_i against a wall).
    pub relative_spin: Vec3,
    /// r_i and r_j (infinite for a wall).
    pub radius: f64,
    pub partner_radius: f64,
    /// 1/m_i + 1/m_j = 1/m* (1/m_i against a wall), and likewise 1/I.
    pub inverse_mass_sum: f64,
    pub inverse_inertia_sum: f64,
    /// Coulomb coefficient of this pair or wall.
    pub friction: f64,
}

/// The whole contact law of a scene.
#[derive(Clone, Copy, Debug)]
pub struct ContactLaw {
    pub normal: NormalStiffness,
    /// k_t / k_n (0.2 in the paper).
    pub tangential_ratio: f64,
    /// Coulomb coefficient between particles.
    pub friction: f64,
    /// Rolling resistance μ_r (0: none, as in the paper): a torque of
    /// magnitude μ_r R* F_n opposing the relative rolling, R* = r_i r_j/(r_i + r_j).
    pub rolling_friction: f64,
}

/// Force on particle i of a contact, and the updated tangential history.
#[derive(Clone, Copy, Debug)]
pub struct ContactForce {
    /// Force on i (the partner receives its opposite).
    pub force: Vec3,
    /// Tangential force on i (for torques: τ_i = −r_i n × F_t).
    pub tangential: Vec3,
    pub normal_force: f64,
    pub history: Vec3,
}

/// What one contact does to its two particles.
#[derive(Clone, Copy, Debug)]
pub struct PairLoad {
    /// Force on i (the partner receives its opposite).
    pub force: Vec3,
    /// Torque on i.
    pub torque: Vec3,
    /// Torque on the partner (meaningless against a wall).
    pub partner_torque: Vec3,
}

impl ContactLaw {
    /// The law a hard-contact scene carries: Coulomb friction between
    /// grains and no spring (its steps never evaluate the soft law).
    pub fn rigid(friction: f64) -> ContactLaw {
        ContactLaw {
            normal: NormalStiffness::Fixed {
                stiffness: 0.0,
                damping: 0.0,
            },
            tangential_ratio: 0.0,
            friction,
            rolling_friction: 0.0,
        }
    }

    /// Contact force on i from the overlap `overlap` > 0 along the unit
    /// normal `normal` (pointing from the partner to i), the relative velocity
    /// of i's contact point `relative_velocity`, the pair's 1/m_i + 1/m_j
    /// (1/m* ; 1/m_i against a wall),
    /// the previous tangential displacement and the time step.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)] // the scalars of one contact, kept flat for the hot loop
    pub fn force(
        &self,
        overlap: f64,
        normal: Vec3,
        relative_velocity: Vec3,
        inverse_mass_sum: f64,
        friction: f64,
        history: Vec3,
        dt: f64,
    ) -> ContactForce {
        let (k_n, gamma_n) = self.normal.coefficients_from_inverse_mass(inverse_mass_sum);
        let normal_speed = relative_velocity.dot(&normal);
        let normal_force = (k_n * overlap - gamma_n * normal_speed).max(0.0);
        let tangential_velocity = relative_velocity - normal_speed * normal;

        // Keep the history in the current tangent plane at its length (the
        // contact frame rotates with the pair), then accumulate the slip.
        let mut displacement = tangential_velocity * dt;
        let old_length_sq = history.norm_squared();
        if old_length_sq > 0.0 {
            // The reciprocal depends on the history alone, so it is under way
            // while the normal is still being formed.
            let inverse_old_length_sq = 1.0 / old_length_sq;
            let along = history.dot(&normal);
            let rotated = history - along * normal;
            // ε = (ξ·n)²/|ξ|²: how far the tangent plane turned since the
            // last step (v_t Δt / R squared, about 1e-8 in a dense flow).
            // The stretch back to the old length, (1 − ε)^(−1/2), is its
            // series where the terms left out (35ε⁴/128 and beyond) are
            // below round-off, which spares a division and a square root
            // on the contact's chain of dependent operations.
            let turned = along * along * inverse_old_length_sq;
            if turned < 1e-4 {
                let stretch = 1.0 + turned * (0.5 + turned * (0.375 + turned * 0.3125));
                displacement += rotated * stretch;
            } else {
                let new_length_sq = rotated.norm_squared();
                if new_length_sq > 0.0 {
                    displacement += rotated * (old_length_sq / new_length_sq).sqrt();
                }
            }
        }

        let k_t = self.tangential_ratio * k_n;
        let mut tangential = -k_t * displacement;
        let limit = friction * normal_force;
        let magnitude_sq = tangential.norm_squared();
        if magnitude_sq > limit * limit {
            // Eq. 16: sliding; the spring is shortened to the Coulomb force
            // (F_t = −k_t ξ, so ξ scales with F_t).
            let scale = limit / magnitude_sq.sqrt();
            tangential *= scale;
            displacement *= scale;
        }
        ContactForce {
            force: normal_force * normal + tangential,
            tangential,
            normal_force,
            history: displacement,
        }
    }

    /// Force on i and torques on i and on its partner of one contact
    /// (eq. 13–16, torques eq. 14 plus rolling resistance), advancing its
    /// tangential history when dt > 0. The partner receives −force.
    #[inline(always)]
    pub fn load(&self, contact: &ContactPoint, history: &mut Vec3, dt: f64) -> PairLoad {
        let result = self.force(
            contact.overlap,
            contact.normal,
            contact.relative_velocity,
            contact.inverse_mass_sum,
            contact.friction,
            *history,
            dt,
        );
        if dt > 0.0 {
            *history = result.history;
        }
        // Eq. 14: F_t acts on i at −r_i n and −F_t on the partner at +r_j n,
        // so both torques are −r n × F_t.
        let arm_torque = -contact.normal.cross(&result.tangential);
        let mut torque = contact.radius * arm_torque;
        let mut partner_torque = contact.partner_radius * arm_torque;
        if self.rolling_friction > 0.0 {
            // R* = r_i r_j/(r_i + r_j), r_i against a wall.
            let (ri, rj) = (contact.radius, contact.partner_radius);
            let effective_radius = if rj.is_finite() {
                ri * rj / (ri + rj)
            } else {
                ri
            };
            let rolling = self.rolling_torque(
                contact.normal,
                contact.relative_spin,
                result.normal_force,
                effective_radius,
                1.0 / contact.inverse_inertia_sum,
                dt,
            );
            torque += rolling;
            partner_torque -= rolling;
        }
        PairLoad {
            force: result.force,
            torque,
            partner_torque,
        }
    }

    /// Rolling-resistance torque on i (the partner receives its opposite):
    /// constant magnitude μ_r R* F_n against the rolling part of ω_i − ω_j,
    /// capped so that it cannot reverse the rolling within one step
    /// (|T| ≤ I* |ω_roll| / Δt, I* = I_i I_j/(I_i + I_j)): a grain at rest
    /// stays at rest instead of chattering.
    #[inline(always)]
    pub fn rolling_torque(
        &self,
        normal: Vec3,
        relative_spin: Vec3,
        normal_force: f64,
        effective_radius: f64,
        effective_inertia: f64,
        dt: f64,
    ) -> Vec3 {
        let rolling = relative_spin - relative_spin.dot(&normal) * normal;
        let speed = rolling.norm();
        if speed == 0.0 || dt == 0.0 {
            return Vec3::zeros();
        }
        let magnitude = (self.rolling_friction * effective_radius * normal_force)
            .min(effective_inertia * speed / dt);
        -magnitude / speed * rolling
    }

    /// Duration of a binary contact of effective mass m* (t_c, or derived
    /// from k_n, γ_n when they are given directly).
    pub fn contact_time(&self, effective_mass: f64) -> f64 {
        match self.normal {
            NormalStiffness::FromRestitution { contact_time, .. } => contact_time,
            NormalStiffness::Fixed { stiffness, damping } => {
                let beta = 0.5 * damping / effective_mass;
                let omega = (stiffness / effective_mass - beta * beta).max(0.0).sqrt();
                (std::f64::consts::PI - 2.0 * (beta / omega).atan()) / omega
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_calibration_gives_the_requested_restitution() {
        for e in [0.14, 0.2, 0.3, 0.5, 0.87, 0.97, 1.0] {
            let law = NormalStiffness::from_restitution(e, 1e-4, NormalCalibration::Exact);
            if let NormalStiffness::FromRestitution {
                stiffness_per_mass,
                damping_per_mass,
                ..
            } = law
            {
                let measured = clamped_restitution(stiffness_per_mass, damping_per_mass);
                assert!((measured - e).abs() < 1e-12, "e = {e}: {measured}");
            }
        }
    }

    #[test]
    fn paper_calibration_overshoots_the_restitution_by_the_clamp() {
        // e_n = 0.5: β/ω = ln 2/π = 0.22064, the clamped contact lasts
        // (π − 2 arctan 0.22064)/ω and e = exp(−0.22064 · 2.70714) = 0.55028.
        let law = NormalStiffness::from_restitution(0.5, 1e-4, NormalCalibration::Paper);
        if let NormalStiffness::FromRestitution {
            stiffness_per_mass,
            damping_per_mass,
            ..
        } = law
        {
            let measured = clamped_restitution(stiffness_per_mass, damping_per_mass);
            assert!((measured - 0.55028).abs() < 1e-5, "{measured}");
        }
    }

    /// The history carried into a turned tangent plane keeps its length:
    /// |ξ'| = |ξ| to round-off, whether the turn is small enough for the
    /// series or not (ε from 1e-12 to 0.5, on both sides of its 1e-4 limit),
    /// and ξ' is the projection of ξ scaled by (1 − ε)^(−1/2).
    #[test]
    fn the_rotated_history_keeps_its_length() {
        let law = ContactLaw {
            normal: NormalStiffness::Fixed {
                stiffness: 1e5,
                damping: 0.0,
            },
            tangential_ratio: 0.2,
            friction: 1e9,
            rolling_friction: 0.0,
        };
        let history = Vec3::new(3e-6, -1e-6, 0.0);
        for turned in [1e-12, 1e-8, 1e-6, 9.9e-5, 1.01e-4, 1e-3, 0.1, 0.5] {
            // A normal tilted out of the plane z = const so that
            // (ξ·n)²/|ξ|² = ε.
            let along = history.normalize();
            let sideways = Vec3::z();
            let normal = along * f64::sqrt(turned) + sideways * f64::sqrt(1.0 - turned);
            // No slip (zero velocity), no dt: ξ' is the carried history alone.
            let result = law.force(1e-6, normal, Vec3::zeros(), 1.0, 1e9, history, 1.0);
            let length_error = (result.history.norm() - history.norm()).abs() / history.norm();
            assert!(
                length_error < 1e-14,
                "ε = {turned:e}: |ξ'| off by {length_error:e}"
            );
            let projected = history - history.dot(&normal) * normal;
            let expected = projected / f64::sqrt(1.0 - turned);
            let error = (result.history - expected).norm() / history.norm();
            assert!(error < 1e-14, "ε = {turned:e}: ξ' off by {error:e}");
        }
    }
}
