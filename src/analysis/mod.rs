//! Case-specific measurements, reported under `"metrics"` in `summary.json`
//! and as CSV tables beside it.

pub mod bed;
mod channel_grains;
mod column_collapse;
mod erodible_bed;
mod front_phases;
pub mod sphere_in_fluid;

use crate::case::AnalysisSection;
pub use column_collapse::ColumnCollapse;
pub use erodible_bed::{ErodibleBed, ErodibleBedSettings};
pub use front_phases::{front_phases, FrontPhases};
use grainflow_core::Vec3;
use grainflow_dem::stress::particle_moments;
use grainflow_dem::DemSystem;
use grainflow_io::{write_whole, write_whole_bytes};
use serde_json::{json, Map, Value};
use std::io::Write;
use std::path::Path;

/// How far short of a time (s) the run's clock may fall and still have
/// reached it: a time summed from 10⁵ steps of 10 µs reads 0.99999999…
/// at what is 1 s, and a profile at the end time was lost.
const CLOCK_ROUND_OFF: f64 = 1e-9;

/// Whether the run's `clock` has reached `time`, to its round-off.
pub(crate) fn reached(clock: f64, time: f64) -> bool {
    clock + CLOCK_ROUND_OFF >= time
}

#[derive(serde::Serialize, serde::Deserialize)]
pub enum Analysis {
    None,
    BinaryCollision(BinaryCollision),
    Bouncing(Bouncing),
    Silo { slab: f64, exclude_bottom: f64 },
    ColumnCollapse(ColumnCollapse),
    ErodibleBed(Box<ErodibleBed>),
    StaticBox(StaticBox),
}

impl Analysis {
    pub fn new(section: Option<&AnalysisSection>, system: &DemSystem) -> Self {
        match section {
            None => Analysis::None,
            Some(AnalysisSection::BinaryCollision) => {
                Analysis::BinaryCollision(BinaryCollision::start(system))
            }
            Some(AnalysisSection::Bouncing) => Analysis::Bouncing(Bouncing::default()),
            Some(AnalysisSection::Silo {
                slab,
                exclude_bottom,
            }) => Analysis::Silo {
                slab: *slab,
                exclude_bottom: *exclude_bottom,
            },
            Some(AnalysisSection::ColumnCollapse { profile_times }) => {
                Analysis::ColumnCollapse(ColumnCollapse::new(system, profile_times))
            }
            Some(AnalysisSection::ErodibleBed {
                profile_times,
                probes,
                sample_interval,
                profile_interval,
                flowing_speed,
                smoothing,
            }) => Analysis::ErodibleBed(Box::new(ErodibleBed::new(
                system,
                &ErodibleBedSettings {
                    profile_times: profile_times.clone(),
                    probes: probes.clone(),
                    sample_interval: *sample_interval,
                    profile_interval: *profile_interval,
                    flowing_speed: *flowing_speed,
                    smoothing: *smoothing,
                },
            ))),
            Some(AnalysisSection::StaticBox { settle }) => {
                Analysis::StaticBox(StaticBox::new(*settle))
            }
            Some(
                AnalysisSection::ExactDecay
                | AnalysisSection::Channel
                | AnalysisSection::FallingSphere
                | AnalysisSection::BouncingSphere
                | AnalysisSection::InclinedBed { .. },
            ) => {
                unreachable!("validation keeps fluid analyses out of dry scenes")
            }
        }
    }

    /// Whether [`Analysis::after_step`] records anything at `time` (on
    /// several ranks the grains are gathered only then).
    pub fn wants_grains(&self, time: f64) -> bool {
        match self {
            Analysis::None | Analysis::Silo { .. } => false,
            Analysis::BinaryCollision(_) | Analysis::Bouncing(_) => true,
            Analysis::ColumnCollapse(c) => c.wants_grains(time),
            Analysis::ErodibleBed(e) => e.wants_grains(time),
            Analysis::StaticBox(b) => time >= b.settle,
        }
    }

    /// Called after every step.
    pub fn after_step(&mut self, system: &DemSystem) {
        match self {
            Analysis::BinaryCollision(b) => b.after_step(system),
            Analysis::Bouncing(b) => b.after_step(system),
            Analysis::ColumnCollapse(c) => c.after_step(system),
            Analysis::ErodibleBed(e) => e.after_step(system),
            Analysis::StaticBox(b) => b.after_step(system),
            _ => {}
        }
    }

    /// Final metrics; tables are written into `out`.
    pub fn finish(&self, system: &DemSystem, out: &Path) -> std::io::Result<Map<String, Value>> {
        match self {
            Analysis::None => Ok(Map::new()),
            Analysis::BinaryCollision(b) => b.finish(system, out),
            Analysis::Bouncing(b) => Ok(b.finish()),
            Analysis::Silo {
                slab,
                exclude_bottom,
            } => silo(system, *slab, *exclude_bottom, out),
            Analysis::ColumnCollapse(c) => c.finish(system, out),
            Analysis::ErodibleBed(e) => e.finish(out),
            Analysis::StaticBox(b) => b.finish(out),
        }
    }
}

/// Grains at rest in a box (Martin et al. 2022, Fig. 3): after `settle`,
/// the ratio of their kinetic energy (translation and rotation) to their
/// potential energy above the bottom of the domain, Σ m |g| h with h the
/// height along −g above the domain's lowest corner (`domain.lower` under
/// gravity along an axis; another corner under a tilted one, where heights
/// from `domain.lower` would not all be positive). A static assembly must stay at
/// rest: the ratio stays at round-off while the contact solver holds it.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct StaticBox {
    settle: f64,
    /// (t, E_k/E_p) after `settle`, every step.
    history: Vec<(f64, f64)>,
}

impl StaticBox {
    fn new(settle: f64) -> Self {
        StaticBox {
            settle,
            history: Vec::new(),
        }
    }

    /// E_k / E_p of the grains now.
    pub fn kinetic_to_potential(system: &DemSystem) -> f64 {
        let p = &system.particles;
        let g = system.domain.gravity;
        let up = -g / g.norm().max(f64::MIN_POSITIVE);
        let reference = system.domain.lowest_along(&up);
        let (translational, rotational) = p.kinetic_energy();
        let potential: f64 = (0..p.n_owned)
            .filter(|&k| !p.is_fixed(k))
            .map(|k| p.mass[k] * g.norm() * (p.position[k].dot(&up) - reference))
            .sum();
        let c = &system.communicator;
        c.sum(translational + rotational) / c.sum(potential).max(f64::MIN_POSITIVE)
    }

    fn after_step(&mut self, system: &DemSystem) {
        if system.time >= self.settle {
            self.history
                .push((system.time, Self::kinetic_to_potential(system)));
        }
    }

    fn finish(&self, out: &Path) -> std::io::Result<Map<String, Value>> {
        write_whole(&out.join("kinetic_to_potential.csv"), |file| {
            writeln!(file, "time,kinetic_to_potential")?;
            for (t, ratio) in &self.history {
                writeln!(file, "{t:.6e},{ratio:.6e}")?;
            }
            Ok(())
        })?;
        let largest = self.history.iter().map(|h| h.1).fold(0.0, f64::max);
        let mut metrics = Map::new();
        metrics.insert("max_kinetic_to_potential".into(), json!(largest));
        metrics.insert(
            "final_kinetic_to_potential".into(),
            json!(self.history.last().map_or(0.0, |h| h.1)),
        );
        metrics.insert("settle".into(), json!(self.settle));
        Ok(metrics)
    }
}

fn by_id(system: &DemSystem) -> Vec<usize> {
    let p = &system.particles;
    let mut index = vec![usize::MAX; p.n_owned];
    for k in 0..p.n_owned {
        index[p.id[k] as usize] = k;
    }
    index
}

/// Binary collisions (Izard et al. 2014, section 3.2; Foerster et al. 1994):
/// Ψ = tangential velocity of the contact points over the normal relative
/// velocity before impact, before (Ψ1) and after (Ψ2), each in the contact
/// frame of its instant (first touch, separation). On the sliding branch
/// Ψ2 = Ψ1 − (7/2) μ (1 + e_n).
#[derive(serde::Serialize, serde::Deserialize)]
pub struct BinaryCollision {
    /// Per pair: Ψ1 and the normal relative speed before impact.
    before: Vec<(f64, f64)>,
    /// Per pair: whether it is touching now, and (Ψ2, e) at separation.
    touching: Vec<bool>,
    after: Vec<Option<(f64, f64)>>,
}

impl BinaryCollision {
    fn start(system: &DemSystem) -> Self {
        let index = by_id(system);
        let p = &system.particles;
        let pairs = p.n_owned / 2;
        let before = (0..pairs)
            .map(|k| {
                let (a, b) = (index[2 * k], index[2 * k + 1]);
                let relative = p.velocity[a] - p.velocity[b];
                (relative.y / relative.x, relative.x)
            })
            .collect();
        BinaryCollision {
            before,
            touching: vec![false; pairs],
            after: vec![None; pairs],
        }
    }

    fn after_step(&mut self, system: &DemSystem) {
        let index = by_id(system);
        let p = &system.particles;
        for k in 0..self.before.len() {
            if self.after[k].is_some() {
                continue;
            }
            let (a, b) = (index[2 * k], index[2 * k + 1]);
            let branch = p.position[a] - p.position[b];
            let touching = branch.norm() < p.radius[a] + p.radius[b];
            if self.touching[k] && !touching {
                // Separation: resolve the contact-point velocity in the
                // current contact frame; the tangent keeps the sign of the
                // impact's tangential direction (+y).
                let normal = branch.normalize();
                let contact_velocity = p.velocity[a]
                    - p.velocity[b]
                    - (p.radius[a] * p.angular_velocity[a] + p.radius[b] * p.angular_velocity[b])
                        .cross(&normal);
                let normal_speed = contact_velocity.dot(&normal);
                let tangential = contact_velocity - normal_speed * normal;
                let tangent = (Vec3::y() - Vec3::y().dot(&normal) * normal).normalize();
                let (_, vn) = self.before[k];
                self.after[k] = Some((tangential.dot(&tangent) / vn, normal_speed / vn));
            }
            self.touching[k] = touching;
        }
    }

    fn finish(&self, system: &DemSystem, out: &Path) -> std::io::Result<Map<String, Value>> {
        let friction = system.law.friction;
        let path = out.join("collisions.csv");
        let mut table = String::from("psi1,psi2,restitution,sliding,psi2_sliding_theory\n");
        let mut metrics = Map::new();
        let rows: Vec<(f64, f64, f64)> = self
            .before
            .iter()
            .zip(&self.after)
            .filter_map(|(&(psi1, _), after)| after.map(|(psi2, e)| (psi1, psi2, e)))
            .collect();
        metrics.insert("collisions".into(), json!(rows.len()));
        let Some(&(_, _, head_on)) = rows.first() else {
            write_whole_bytes(&path, table)?;
            return Ok(metrics);
        };
        // A pair slides throughout when the Coulomb impulse cannot stop the
        // slip: Ψ1 > (7/2) μ (1 + e_n), e_n measured on the head-on pair.
        let offset_theory = 3.5 * friction * (1.0 + head_on);
        let mut offsets = Vec::new();
        for &(psi1, psi2, e) in &rows {
            let sliding = psi1 > offset_theory;
            if sliding {
                offsets.push(psi1 - psi2);
            }
            table.push_str(&format!(
                "{psi1:e},{psi2:e},{e:e},{},{:e}\n",
                sliding as u8,
                psi1 - offset_theory
            ));
        }
        write_whole_bytes(&path, table)?;
        metrics.insert("restitution".into(), json!(head_on));
        if !offsets.is_empty() {
            metrics.insert(
                "psi_sliding_offset".into(),
                json!(offsets.iter().sum::<f64>() / offsets.len() as f64),
            );
            metrics.insert("psi_sliding_offset_theory".into(), json!(offset_theory));
            metrics.insert("sliding_pairs".into(), json!(offsets.len()));
        }
        Ok(metrics)
    }
}

/// Impacts of particle 0 on the walls. The mechanical energy
/// E = ½ m v² + ½ I ω² + m g·(height of the lowest point above the wall) is
/// constant in free flight (velocity Verlet is exact for a parabola), so the
/// energy kept by an impact is E after / E before, and e = √ of it.
#[derive(Default, serde::Serialize, serde::Deserialize)]
pub struct Bouncing {
    in_contact: bool,
    energy_before: f64,
    free_energy: f64,
    wall: usize,
    impacts: Vec<(f64, f64, f64)>,
}

impl Bouncing {
    fn energy(system: &DemSystem, k: usize, wall: usize) -> f64 {
        let p = &system.particles;
        let w = &system.walls[wall];
        let height = w.distance(&p.position[k]) - p.radius[k];
        let g_normal = -system.domain.gravity.dot(&w.normal);
        0.5 * p.mass[k] * p.velocity[k].norm_squared()
            + 0.5 * p.angular_velocity[k].norm_squared() / p.inverse_inertia[k]
            + p.mass[k] * g_normal * height
    }

    fn after_step(&mut self, system: &DemSystem) {
        let Some(k) = system.index_of(0) else { return };
        let p = &system.particles;
        let touching = system
            .walls
            .iter()
            .position(|w| w.is_present(system.time) && w.distance(&p.position[k]) < p.radius[k]);
        match (self.in_contact, touching) {
            (false, Some(wall)) => {
                self.in_contact = true;
                self.wall = wall;
                self.energy_before = self.free_energy;
            }
            (true, None) => {
                self.in_contact = false;
                let energy_after = Self::energy(system, k, self.wall);
                self.impacts
                    .push((system.time, self.energy_before, energy_after));
                self.free_energy = energy_after;
            }
            (false, None) => {
                // Free flight: remember the energy against the nearest wall.
                if let Some(wall) = (0..system.walls.len())
                    .filter(|&w| system.walls[w].is_present(system.time))
                    .min_by(|&a, &b| {
                        let da = system.walls[a].distance(&p.position[k]);
                        let db = system.walls[b].distance(&p.position[k]);
                        da.total_cmp(&db)
                    })
                {
                    self.free_energy = Self::energy(system, k, wall);
                }
            }
            _ => {}
        }
    }

    fn finish(&self) -> Map<String, Value> {
        let mut metrics = Map::new();
        let ratio: Vec<f64> = self
            .impacts
            .iter()
            .map(|&(_, before, after)| after / before)
            .collect();
        metrics.insert("impacts".into(), json!(self.impacts.len()));
        metrics.insert(
            "impact_times".into(),
            json!(self.impacts.iter().map(|i| i.0).collect::<Vec<_>>()),
        );
        metrics.insert("energy_ratio_per_impact".into(), json!(ratio));
        metrics.insert(
            "restitution_per_impact".into(),
            json!(ratio.iter().map(|r| r.sqrt()).collect::<Vec<_>>()),
        );
        if let Some(first) = ratio.first() {
            metrics.insert("restitution".into(), json!(first.sqrt()));
        }
        metrics
    }
}

/// Coarse-grained pressure in horizontal slabs along gravity and the Janssen
/// fit p(z) = p∞ (1 − exp(−(h − z)/λ)), f_w K = S/(P λ) (Izard eq. 22).
fn silo(
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
    use grainflow_core::{Dimension, Domain};
    use grainflow_dem::particles::NewParticle;
    use grainflow_dem::{ContactLaw, NormalCalibration, NormalStiffness};

    /// One sphere of 1 kg at rest at `at` in the unit box, under `gravity`,
    /// moving at 1 m/s.
    fn one_grain(at: Vec3, gravity: Vec3) -> DemSystem {
        let domain = Domain {
            dimension: Dimension::Three,
            lower: Vec3::zeros(),
            upper: Vec3::new(1.0, 1.0, 1.0),
            periodic: [false; 3],
            gravity,
        };
        let law = ContactLaw {
            normal: NormalStiffness::from_restitution(0.5, 1e-4, NormalCalibration::Exact),
            tangential_ratio: 0.2,
            friction: 0.3,
            rolling_friction: 0.0,
        };
        let mut system = DemSystem::new(domain, law, Vec::new(), 0.01);
        let radius: f64 = 0.05;
        system.add_particles(&[NewParticle {
            position: at,
            velocity: Vec3::new(1.0, 0.0, 0.0),
            angular_velocity: Vec3::zeros(),
            radius,
            density: 1.0 / (4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)),
            fixed: false,
        }]);
        system
    }

    /// E_k/E_p = ½ m v² / (m |g| h), h the height above the box's lowest
    /// corner along −g: from the floor under gravity along −z, from the
    /// corner (1, 0, 0) under gravity tilted 45° towards +x (heights from
    /// `domain.lower` would be negative there; the ratio read 1e306).
    #[test]
    fn the_potential_energy_is_measured_from_the_lowest_corner_under_tilted_gravity() {
        let at = Vec3::new(0.2, 0.5, 0.3);
        let axial = one_grain(at, Vec3::new(0.0, 0.0, -9.81));
        let expected = 0.5 / (9.81 * 0.3);
        let ratio = StaticBox::kinetic_to_potential(&axial);
        assert!(
            (ratio / expected - 1.0).abs() < 1e-12,
            "{ratio} against {expected}"
        );
        let g = 9.81 / 2f64.sqrt();
        let tilted = one_grain(at, Vec3::new(g, 0.0, -g));
        // Up is (−1, 0, 1)/√2; the lowest corner (1, 0, 0).
        let height = ((1.0 - 0.2) + 0.3) / 2f64.sqrt();
        let expected = 0.5 / (9.81 * height);
        let ratio = StaticBox::kinetic_to_potential(&tilted);
        assert!(
            (ratio / expected - 1.0).abs() < 1e-12,
            "{ratio} against {expected}"
        );
    }

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
