//! Reference results for one sphere settling from rest in a fluid, used by
//! the analyses that compare a run with them.

use grainflow_core::Dimension;

/// The added-mass coefficient `C_a` of a grain accelerating in a fluid at
/// rest (added mass `C_a ρ V_p`, potential flow): 1/2 for a sphere, 1 for a
/// disc (a circular cylinder per unit length). A grain released from rest
/// starts at `a₀ = (ρ_p − ρ) g / (ρ_p + C_a ρ)` (Izard et al. 2014, eq. 20
/// for the sphere).
pub fn added_mass_coefficient(dimension: Dimension) -> f64 {
    match dimension {
        Dimension::Three => 0.5,
        Dimension::Two => 1.0,
    }
}

/// Least-squares `a₀` of `v = a₀ t + c t^{3/2}` through `(t, v)` samples:
/// the early-time motion from rest under a constant force, added mass
/// and the leading history (Basset) term.
pub fn early_acceleration(samples: &[(f64, f64)]) -> f64 {
    let (mut s11, mut s12, mut s22, mut r1, mut r2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(t, v) in samples {
        let (f1, f2) = (t, t.powf(1.5));
        s11 += f1 * f1;
        s12 += f1 * f2;
        s22 += f2 * f2;
        r1 += f1 * v;
        r2 += f2 * v;
    }
    (r1 * s22 - r2 * s12) / (s11 * s22 - s12 * s12)
}

/// The Archimedes number `Ar = ρ |ρ_p − ρ| g D³ / μ²` of a grain of density
/// `rho_p` and diameter `diameter` in a fluid of density `rho` and dynamic
/// viscosity `mu` under gravity `g`.
pub fn archimedes_number(rho: f64, rho_p: f64, mu: f64, diameter: f64, g: f64) -> f64 {
    rho * (rho_p - rho).abs() * g * diameter.powi(3) / (mu * mu)
}

/// The terminal Reynolds number of a sphere of Archimedes number `Ar`
/// with the Schiller–Naumann drag `C_D = 24/Re (1 + 0.15 Re^0.687)`: the
/// balance of eq. 21, `C_D Re² = 4 Ar / 3`, solved by bisection.
pub fn schiller_naumann_reynolds(archimedes: f64) -> f64 {
    terminal_reynolds(
        |re| 24.0 * re * (1.0 + 0.15 * re.powf(0.687)),
        archimedes,
        [0.0, 1e6],
    )
}

/// The terminal Reynolds number of a sphere of Archimedes number `Ar` on
/// the standard drag curve of Clift, Grace & Weber (1978),
/// `C_D = 24/Re (1 + 0.1315 Re^{0.82 − 0.05 log₁₀ Re})` for 0.01 < Re ≤ 20.
pub fn clift_grace_weber_reynolds(archimedes: f64) -> f64 {
    terminal_reynolds(
        |re| 24.0 * re * (1.0 + 0.1315 * re.powf(0.82 - 0.05 * re.log10())),
        archimedes,
        [0.01, 20.0],
    )
}

/// The Reynolds number in `bracket` at which `C_D Re²` (`drag_re2`, of a
/// drag law) balances the buoyant weight, `C_D Re² = 4 Ar / 3` (eq. 21),
/// by bisection.
fn terminal_reynolds(drag_re2: impl Fn(f64) -> f64, archimedes: f64, bracket: [f64; 2]) -> f64 {
    let balance = |re: f64| drag_re2(re) - 4.0 * archimedes / 3.0;
    let [mut low, mut high] = bracket;
    for _ in 0..200 {
        let mid = 0.5 * (low + high);
        if balance(mid) > 0.0 {
            high = mid;
        } else {
            low = mid;
        }
    }
    0.5 * (low + high)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schiller_naumann_balance() {
        // Ar = 800: Re ≈ 20.3 (the paper's "Re = 20 approximately").
        let re = schiller_naumann_reynolds(800.0);
        let drag = 24.0 / re * (1.0 + 0.15 * re.powf(0.687));
        assert!((drag * re * re - 4.0 * 800.0 / 3.0).abs() < 1e-9);
        assert!((re - 20.318).abs() < 1e-3, "{re}");
    }
}
