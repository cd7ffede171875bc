//! The algebra of the second-order cone K = {(u₀, ū) ∈ ℝ³: |ū| ≤ u₀} that
//! the interior point needs for a 3D Coulomb cone (Vandenberghe 2010, "The
//! CVXOPT linear and quadratic cone program solvers", §4–5).
//!
//! - The Jordan product u ∘ v = (uᵀv, u₀ v̄ + v₀ ū), with identity
//!   e = (1, 0, 0); u ∈ int K has the "eigenvalues" u₀ ± |ū|.
//! - The Nesterov–Todd scaling of a pair s, z ∈ int K: the matrix
//!   W = η W̄ with W̄ = [w̄₀ w̄₁ᵀ; w̄₁ I + w̄₁w̄₁ᵀ/(1 + w̄₀)] (symmetric,
//!   W̄² = 2w̄w̄ᵀ − J, J = diag(1, −1, −1), w̄ᵀJw̄ = 1) such that
//!   W⁻¹ s = W z = λ, the scaled point. From s̄ = s/√(sᵀJs) and
//!   z̄ = z/√(zᵀJz): γ = √((1 + s̄ᵀz̄)/2), w̄ = (s̄ + J z̄)/(2γ) and
//!   η = (sᵀJs / zᵀJz)^¼.
//! - W⁻¹ = η⁻¹ J W̄ J, so W⁻² = η⁻² (2 Jw̄ (Jw̄)ᵀ − J): the 3 × 3 block a
//!   cone adds to the normal matrix through its rows of A.

/// A point of ℝ³ in the cone's coordinates (u₀, ū).
pub type Cone3 = [f64; 3];

/// uᵀJu = u₀² − |ū|².
fn j_norm_squared(u: &Cone3) -> f64 {
    u[0] * u[0] - u[1] * u[1] - u[2] * u[2]
}

/// The smaller eigenvalue u₀ − |ū| (positive inside the cone).
pub fn lowest_eigenvalue(u: &Cone3) -> f64 {
    u[0] - (u[1] * u[1] + u[2] * u[2]).sqrt()
}

/// u ∘ v.
pub fn jordan_product(u: &Cone3, v: &Cone3) -> Cone3 {
    [
        u[0] * v[0] + u[1] * v[1] + u[2] * v[2],
        u[0] * v[1] + v[0] * u[1],
        u[0] * v[2] + v[0] * u[2],
    ]
}

/// d with λ ∘ d = r, for λ inside the cone.
pub fn jordan_divide(lambda: &Cone3, r: &Cone3) -> Cone3 {
    let det = j_norm_squared(lambda);
    let d0 = (lambda[0] * r[0] - lambda[1] * r[1] - lambda[2] * r[2]) / det;
    [
        d0,
        (r[1] - d0 * lambda[1]) / lambda[0],
        (r[2] - d0 * lambda[2]) / lambda[0],
    ]
}

/// The Nesterov–Todd scaling of a pair s, z inside the cone.
#[derive(Clone, Copy, Debug, Default)]
pub struct NtScaling {
    eta: f64,
    w: Cone3,
}

impl NtScaling {
    pub fn new(s: &Cone3, z: &Cone3) -> Self {
        let (s_norm, z_norm) = (j_norm_squared(s).sqrt(), j_norm_squared(z).sqrt());
        let s_bar = s.map(|v| v / s_norm);
        let z_bar = z.map(|v| v / z_norm);
        let dot = s_bar[0] * z_bar[0] + s_bar[1] * z_bar[1] + s_bar[2] * z_bar[2];
        let gamma = ((1.0 + dot) / 2.0).sqrt();
        let w = [
            (s_bar[0] + z_bar[0]) / (2.0 * gamma),
            (s_bar[1] - z_bar[1]) / (2.0 * gamma),
            (s_bar[2] - z_bar[2]) / (2.0 * gamma),
        ];
        NtScaling {
            eta: (s_norm / z_norm).sqrt(),
            w,
        }
    }

    /// W̄ v.
    fn bar_times(&self, v: &Cone3) -> Cone3 {
        let w = &self.w;
        let w1v1 = w[1] * v[1] + w[2] * v[2];
        let c = v[0] + w1v1 / (1.0 + w[0]);
        [w[0] * v[0] + w1v1, v[1] + c * w[1], v[2] + c * w[2]]
    }

    /// W v.
    pub fn times(&self, v: &Cone3) -> Cone3 {
        self.bar_times(v).map(|x| self.eta * x)
    }

    /// W⁻¹ v = η⁻¹ J W̄ J v.
    pub fn inverse_times(&self, v: &Cone3) -> Cone3 {
        let u = self.bar_times(&[v[0], -v[1], -v[2]]);
        [u[0] / self.eta, -u[1] / self.eta, -u[2] / self.eta]
    }

    /// W⁻², symmetric: η⁻² (2 Jw̄ (Jw̄)ᵀ − J), row by row.
    pub fn inverse_squared(&self) -> [[f64; 3]; 3] {
        let jw = [self.w[0], -self.w[1], -self.w[2]];
        let scale = 1.0 / (self.eta * self.eta);
        let mut m = [[0.0; 3]; 3];
        for (p, row) in m.iter_mut().enumerate() {
            for (q, value) in row.iter_mut().enumerate() {
                let j = if p == q {
                    if p == 0 {
                        1.0
                    } else {
                        -1.0
                    }
                } else {
                    0.0
                };
                *value = scale * (2.0 * jw[p] * jw[q] - j);
            }
        }
        m
    }
}

/// Largest α ≤ 1 keeping u + α du in the cone (u inside it).
pub fn step_to_boundary(u: &Cone3, du: &Cone3) -> f64 {
    // u + α du stays inside while φ(α) = (u₀ + α du₀)² − |ū + α dū|² > 0
    // and u₀ + α du₀ > 0: φ(α) = a α² + 2 b α + c with c > 0.
    let a = j_norm_squared(du);
    let b = u[0] * du[0] - u[1] * du[1] - u[2] * du[2];
    let c = j_norm_squared(u).max(0.0);
    let mut alpha: f64 = 1.0;
    if du[0] < 0.0 {
        alpha = alpha.min(-u[0] / du[0]);
    }
    // The smallest positive root of φ, computed without cancellation.
    let discriminant = b * b - a * c;
    if discriminant >= 0.0 {
        let root = discriminant.sqrt();
        let q = -(b + b.signum() * root);
        for candidate in [q / a, c / q] {
            if candidate.is_finite() && candidate > 0.0 {
                alpha = alpha.min(candidate);
            }
        }
    }
    alpha
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Cone3, b: &Cone3, tolerance: f64) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tolerance)
    }

    /// Points inside the cone, from near its axis to near its boundary.
    fn interior_points() -> Vec<(Cone3, Cone3)> {
        vec![
            ([1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
            ([2.0, 0.5, -1.0], [0.3, 0.1, 0.2]),
            ([1.0, 0.999, 0.0], [5.0, -1.0, 3.0]),
            ([1e-6, 3e-7, -2e-7], [40.0, 10.0, 30.0]),
        ]
    }

    #[test]
    fn the_scaling_maps_s_and_z_to_one_point() {
        for (s, z) in interior_points() {
            let w = NtScaling::new(&s, &z);
            let lambda = w.times(&z);
            let size = lambda[0].abs().max(1e-300);
            assert!(
                close(&w.inverse_times(&s), &lambda, 1e-12 * size),
                "{s:?} {z:?}"
            );
            // W⁻² s = z, from the explicit block.
            let m = w.inverse_squared();
            let back: Cone3 = [0, 1, 2].map(|p| (0..3).map(|q| m[p][q] * s[q]).sum());
            let z_size = z[0].abs();
            assert!(close(&back, &z, 1e-10 * z_size), "{back:?} against {z:?}");
            assert!(lowest_eigenvalue(&lambda) > 0.0);
        }
    }

    #[test]
    fn division_undoes_the_jordan_product() {
        let lambda = [2.0, 0.5, -1.0];
        let d = [0.3, -4.0, 2.5];
        let r = jordan_product(&lambda, &d);
        assert!(close(&jordan_divide(&lambda, &r), &d, 1e-14));
    }

    #[test]
    fn the_step_stops_at_the_boundary() {
        // From the axis towards (0, 1, 0): the boundary where 1 − α = α.
        let alpha = step_to_boundary(&[1.0, 0.0, 0.0], &[-1.0, 1.0, 0.0]);
        assert!((alpha - 0.5).abs() < 1e-15, "{alpha}");
        // Moving deeper inside: the full step.
        assert_eq!(step_to_boundary(&[1.0, 0.2, 0.0], &[1.0, 0.0, 0.0]), 1.0);
        // Through the apex: u + α du = (1 − α)(1, 0.5, 0) leaves at α = 1/…
        let alpha = step_to_boundary(&[1.0, 0.5, 0.0], &[-2.0, -1.0, 0.0]);
        assert!((alpha - 0.5).abs() < 1e-15, "{alpha}");
        // Each step lands on the boundary (or stays inside at α = 1).
        for (u, du) in [
            ([2.0, 0.5, -1.0], [-0.5, 3.0, 1.0]),
            ([1.0, 0.0, 0.9], [0.1, 0.0, 0.5]),
        ] {
            let alpha = step_to_boundary(&u, &du);
            let end = [0, 1, 2].map(|k| u[k] + alpha * du[k]);
            assert!(
                alpha == 1.0 || lowest_eigenvalue(&end).abs() < 1e-12,
                "{alpha} {end:?}"
            );
            assert!(lowest_eigenvalue(&end) > -1e-12);
        }
    }
}
