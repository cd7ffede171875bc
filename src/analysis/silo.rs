//! The silo (Izard et al. 2014, §3.3): the pressure coarse-grained in
//! horizontal slabs along gravity and the Janssen fits of its profile,
//! with the plateau free and with it tied to the weight (eq. 22).

use grainflow_core::Vec3;
use grainflow_dem::stress::particle_moments;
use grainflow_dem::DemSystem;
use grainflow_io::write_whole;
use serde_json::{json, Map, Value};
use std::io::Write;
use std::path::Path;

/// Coarse-grained pressure in horizontal slabs along gravity and the Janssen
/// fit p(z) = p∞ (1 − exp(−(h − z)/λ)), f_w K = S/(P λ) (Izard eq. 22).
pub(super) fn silo(
    system: &DemSystem,
    slab: f64,
    exclude_bottom: f64,
    out: &Path,
) -> std::io::Result<Map<String, Value>> {
    let p = &system.particles;
    let g = system.domain.gravity;
    let up = -g.normalize();
    let lower = system.domain.lower;
    let extent = system.domain.extent();
    // Cross-section S and perimeter P of the box normal to gravity.
    let vertical = (0..3)
        .max_by(|&a, &b| up[a].abs().total_cmp(&up[b].abs()))
        .unwrap();
    let horizontal: Vec<usize> = (0..3).filter(|&a| a != vertical).collect();
    let (wa, wb) = (extent[horizontal[0]], extent[horizontal[1]]);
    let section = wa * wb;
    let perimeter = 2.0 * (wa + wb);

    let moments = particle_moments(system);
    let base = lower[vertical];
    let mobile: Vec<usize> = (0..p.n_owned)
        .filter(|&k| p.inverse_mass[k] > 0.0)
        .collect();
    let highest = mobile
        .iter()
        .map(|&k| p.position[k][vertical] + p.radius[k])
        .fold(f64::MIN, f64::max);
    let slabs = ((highest - base) / slab).ceil().max(1.0) as usize;
    let mut pressure = vec![0.0; slabs];
    let mut vertical_stress = vec![0.0; slabs];
    let mut horizontal_stress = vec![0.0; slabs];
    let mut solid_volume = vec![0.0; slabs];
    for &k in &mobile {
        let s =
            (((p.position[k][vertical] - base) / slab).floor().max(0.0) as usize).min(slabs - 1);
        // Granular pressure: −trace(σ)/3 with σ = (1/V) Σ f ⊗ (x_c − x_p)
        // (compression positive).
        let m = &moments[k];
        pressure[s] += -m.trace() / 3.0;
        vertical_stress[s] += -m[(vertical, vertical)];
        horizontal_stress[s] +=
            -0.5 * (m[(horizontal[0], horizontal[0])] + m[(horizontal[1], horizontal[1])]);
        solid_volume[s] += 4.0 / 3.0 * std::f64::consts::PI * p.radius[k].powi(3);
    }
    let volume = section * slab;
    let z: Vec<f64> = (0..slabs).map(|s| base + (s as f64 + 0.5) * slab).collect();
    let pressure: Vec<f64> = pressure.iter().map(|x| x / volume).collect();
    let vertical_stress: Vec<f64> = vertical_stress.iter().map(|x| x / volume).collect();
    let horizontal_stress: Vec<f64> = horizontal_stress.iter().map(|x| x / volume).collect();
    let fraction: Vec<f64> = solid_volume.iter().map(|v| v / volume).collect();
    // Free surface h: the column's solid volume spread at the bulk (median)
    // solid fraction, so that a stray grain on top does not count.
    let mut sorted = fraction.clone();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let bulk_fraction = sorted[sorted.len() / 2];
    let top = base + solid_volume.iter().sum::<f64>() / (section * bulk_fraction);

    write_whole(&out.join("silo_profile.csv"), |file| {
        writeln!(
            file,
            "z,pressure,vertical_stress,horizontal_stress,solid_fraction"
        )?;
        for s in 0..slabs {
            writeln!(
                file,
                "{:e},{:e},{:e},{:e},{:e}",
                z[s], pressure[s], vertical_stress[s], horizontal_stress[s], fraction[s]
            )?;
        }
        Ok(())
    })?;
    // Fit over full slabs between the bottom exclusion and one slab below the top.
    let fit: Vec<usize> = (0..slabs)
        .filter(|&s| z[s] - base >= exclude_bottom && z[s] + slab <= top - slab)
        .collect();
    let depth: Vec<f64> = fit.iter().map(|&s| top - z[s]).collect();
    let measured: Vec<f64> = fit.iter().map(|&s| pressure[s]).collect();
    let (saturation, length) = janssen_fit(&depth, &measured);
    let mean_fraction = bulk_fraction;
    // Eq. 22 as the paper fits it: f_w K alone, the saturation tied to it
    // by the weight of the column, ρ_gm = C ρ_p (C the bulk solid fraction).
    let grain_density = mobile
        .first()
        .map(|&k| p.mass[k] / (4.0 / 3.0 * std::f64::consts::PI * p.radius[k].powi(3)))
        .unwrap_or(0.0);
    let weight_density = mean_fraction * grain_density * g.norm();
    let fwk_eq22 = janssen_fit_eq22(&depth, &measured, weight_density, section / perimeter);
    // Janssen's redirection K = σ_h/σ_v, averaged over the fitted slabs.
    let redirection = fit
        .iter()
        .map(|&s| horizontal_stress[s] / vertical_stress[s])
        .sum::<f64>()
        / fit.len().max(1) as f64;
    // Mobilised wall friction f_w = Σ|F_v| / Σ|F_h| over the contacts of
    // grains in the fitted slabs with the wall: glued grains and side planes.
    let in_fit = |x: &Vec3| {
        let height = x[vertical] - base;
        height >= exclude_bottom && height <= top - base - 2.0 * slab
    };
    let (mut shear, mut normal) = (0.0, 0.0);
    for &k in mobile.iter().filter(|&&k| in_fit(&p.position[k])) {
        let with_glued = system
            .particle_contacts_of(k)
            .into_iter()
            .filter(|c| p.is_fixed(c.partner))
            .map(|c| c.force);
        let with_side_walls = system
            .wall_contacts_of(k)
            .into_iter()
            .filter(|(w, _)| system.walls[*w].normal.dot(&up).abs() < 1e-9)
            .map(|(_, c)| c.force);
        for force in with_glued.chain(with_side_walls) {
            let vertical_part = force.dot(&up);
            shear += vertical_part.abs();
            normal += (force - vertical_part * up).norm();
        }
    }
    let wall_friction = shear / normal.max(f64::MIN_POSITIVE);
    let mut metrics = Map::new();
    metrics.insert("janssen_K".into(), json!(redirection));
    metrics.insert("wall_friction_mobilised".into(), json!(wall_friction));
    metrics.insert(
        "janssen_fwK_direct".into(),
        json!(wall_friction * redirection),
    );
    metrics.insert("janssen_fwK".into(), json!(section / (perimeter * length)));
    metrics.insert("janssen_fwK_eq22".into(), json!(fwk_eq22));
    metrics.insert("janssen_length".into(), json!(length));
    metrics.insert("saturation_pressure".into(), json!(saturation));
    metrics.insert("column_height".into(), json!(top - base));
    metrics.insert("solid_fraction".into(), json!(mean_fraction));
    Ok(metrics)
}

/// Least squares of p = p∞ (1 − exp(−d/λ)) over depth d: p∞ is linear for a
/// given λ; λ is found by golden-section search on the residual.
pub fn janssen_fit(depth: &[f64], pressure: &[f64]) -> (f64, f64) {
    let residual = |length: f64| {
        let shape: Vec<f64> = depth.iter().map(|d| 1.0 - (-d / length).exp()).collect();
        let saturation = shape.iter().zip(pressure).map(|(s, p)| s * p).sum::<f64>()
            / shape.iter().map(|s| s * s).sum::<f64>();
        let r = shape
            .iter()
            .zip(pressure)
            .map(|(s, p)| (saturation * s - p).powi(2))
            .sum::<f64>();
        (r, saturation)
    };
    let max_depth = depth.iter().cloned().fold(0.0, f64::max);
    let (mut a, mut b) = ((1e-4 * max_depth).ln(), (1e3 * max_depth).ln());
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..200 {
        let c = b - ratio * (b - a);
        let d = a + ratio * (b - a);
        if residual(c.exp()).0 < residual(d.exp()).0 {
            b = d;
        } else {
            a = c;
        }
    }
    let length = (0.5 * (a + b)).exp();
    (residual(length).1, length)
}

/// Least squares of eq. 22, p = ρ_gm g λ (1 − exp(−d/λ)) with
/// λ = (S/P)/(f_w K), over f_w K alone (`weight_density` = ρ_gm g,
/// `section_over_perimeter` = S/P): golden-section search on ln f_w K.
pub fn janssen_fit_eq22(
    depth: &[f64],
    pressure: &[f64],
    weight_density: f64,
    section_over_perimeter: f64,
) -> f64 {
    let residual = |fwk: f64| {
        let length = section_over_perimeter / fwk;
        depth
            .iter()
            .zip(pressure)
            .map(|(d, p)| (weight_density * length * (1.0 - (-d / length).exp()) - p).powi(2))
            .sum::<f64>()
    };
    let (mut a, mut b) = (1e-4f64.ln(), 1e2f64.ln());
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..200 {
        let c = b - ratio * (b - a);
        let d = a + ratio * (b - a);
        if residual(c.exp()) < residual(d.exp()) {
            b = d;
        } else {
            a = c;
        }
    }
    (0.5 * (a + b)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 22 for the silo's shaft (S/P = 0.025 m) at f_w K = 0.3, ρ_gm g =
    /// 0.49 · 1317 · 9.81, sampled every 5 cm over 3 m.
    fn janssen_profile(fwk: f64) -> (Vec<f64>, Vec<f64>, f64) {
        let weight_density = 0.49 * 1317.0 * 9.81;
        let length = 0.025 / fwk;
        let depth: Vec<f64> = (1..=60).map(|k| 0.05 * k as f64).collect();
        let pressure = depth
            .iter()
            .map(|d| weight_density * length * (1.0 - (-d / length).exp()))
            .collect();
        (depth, pressure, weight_density)
    }

    #[test]
    fn both_fits_recover_the_janssen_factor_of_an_exact_profile() {
        for fwk in [0.1, 0.3, 0.6] {
            let (depth, pressure, weight_density) = janssen_profile(fwk);
            let eq22 = janssen_fit_eq22(&depth, &pressure, weight_density, 0.025);
            assert!(
                (eq22 / fwk - 1.0).abs() < 1e-6,
                "eq. 22 fit {eq22} for {fwk}"
            );
            let (saturation, length) = janssen_fit(&depth, &pressure);
            assert!((0.025 / length / fwk - 1.0).abs() < 1e-6, "λ = {length}");
            assert!((saturation / (weight_density * 0.025 / fwk) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn the_one_parameter_fit_reads_the_plateau_the_two_parameter_fit_the_shape() {
        // A plateau 1.5 times Janssen's with the same λ: the free-saturation
        // fit keeps f_w K from the shape; eq. 22, where the plateau is
        // ρ_gm g λ, reads about f_w K / 1.5 from its level.
        let (depth, pressure, weight_density) = janssen_profile(0.3);
        let raised: Vec<f64> = pressure.iter().map(|p| 1.5 * p).collect();
        let (_, length) = janssen_fit(&depth, &raised);
        assert!((0.025 / length / 0.3 - 1.0).abs() < 1e-6);
        let eq22 = janssen_fit_eq22(&depth, &raised, weight_density, 0.025);
        assert!((eq22 - 0.2).abs() < 0.02, "eq. 22 fit {eq22}");
    }
}
