//! Case-specific measurements, reported under `"metrics"` in `summary.json`
//! and as CSV tables beside it.

pub mod bed;
mod channel_grains;
mod column_collapse;
mod erodible_bed;
mod front_phases;
mod silo;
pub mod sphere_in_fluid;

use silo::silo;
pub use silo::{janssen_fit, janssen_fit_eq22};

use crate::case::AnalysisSection;
pub use column_collapse::ColumnCollapse;
pub use erodible_bed::{ErodibleBed, ErodibleBedSettings};
pub use front_phases::{front_phases, FrontPhases};
use grainflow_core::Vec3;
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
}
