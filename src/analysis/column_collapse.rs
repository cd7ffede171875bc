//! The collapse of a granular column released by removing its gates:
//! its initial aspect ratio, its runout at rest and its height profiles.

use super::reached;
use crate::scene::deposit;
use grainflow_core::Vec3;
use grainflow_dem::DemSystem;
use grainflow_io::write_whole;
use serde_json::{json, Map, Value};
use std::io::Write;
use std::path::Path;

/// Symmetric collapse of a column between the gate walls (Izard et al.
/// 2014, section 3.4): H0 and R0 at release, R∞ at rest.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct ColumnCollapse {
    release_time: f64,
    centre: f64,
    half_width: f64,
    /// The sides the column spreads to from `centre`: both for a column
    /// between two gates, +x for one against a back wall.
    sides: Vec<f64>,
    initial_height: Option<f64>,
    /// Times after the release at which to record the height profile, and
    /// the profiles recorded: (time after release, x, mass profile, top).
    profile_times: Vec<f64>,
    profiles: Vec<(f64, f64, f64, f64)>,
}

impl ColumnCollapse {
    pub(super) fn new(system: &DemSystem, profile_times: &[f64]) -> Self {
        let gates: Vec<_> = system
            .walls
            .iter()
            .filter(|w| w.remove_at.is_some())
            .collect();
        let release_time = gates.iter().filter_map(|w| w.remove_at).fold(0.0, f64::max);
        let xs: Vec<f64> = gates.iter().map(|w| w.point.x).collect();
        let (lo, hi) = (
            xs.iter().cloned().fold(f64::MAX, f64::min),
            xs.iter().cloned().fold(f64::MIN, f64::max),
        );
        let (centre, half_width, sides) = if gates.len() >= 2 {
            (0.5 * (lo + hi), 0.5 * (hi - lo), vec![-1.0, 1.0])
        } else {
            // One gate: the column stands against a fixed back wall at the
            // domain's lower x.
            (system.domain.lower.x, hi - system.domain.lower.x, vec![1.0])
        };
        let mut profile_times = profile_times.to_vec();
        profile_times.sort_by(|a, b| b.total_cmp(a)); // next one last
        ColumnCollapse {
            release_time,
            centre,
            half_width,
            sides,
            initial_height: None,
            profile_times,
            profiles: Vec::new(),
        }
    }

    /// Mass profile h(x): in bins two mean diameters wide along x, the
    /// volume of the mobile grains whose centre lies in the bin over the
    /// bin's width (and, in 3D, the spanwise length): the height the grains
    /// would have packed without voids. Unlike the top of the highest grain,
    /// it does not jump when a single grain flies up. Also the top of the
    /// highest grain above the floor, per bin.
    pub(super) fn profile(system: &DemSystem) -> Vec<(f64, f64, f64)> {
        let p = &system.particles;
        let vertical = Self::vertical(system);
        let floor = system.domain.lower[vertical];
        let mobile: Vec<usize> = (0..p.n_owned).filter(|&k| !p.is_fixed(k)).collect();
        let diameter =
            2.0 * mobile.iter().map(|&k| p.radius[k]).sum::<f64>() / mobile.len().max(1) as f64;
        let width = 2.0 * diameter;
        let (span, volume): (f64, fn(f64) -> f64) = match system.domain.dimension {
            grainflow_core::Dimension::Two => (1.0, |r| std::f64::consts::PI * r * r),
            grainflow_core::Dimension::Three => {
                let spanwise = (0..3).find(|&a| a != 0 && a != vertical).unwrap();
                (system.domain.extent()[spanwise], |r| {
                    4.0 / 3.0 * std::f64::consts::PI * r * r * r
                })
            }
        };
        let lower = system.domain.lower.x;
        let bins = ((system.domain.extent().x / width).ceil() as usize).max(1);
        let mut solid = vec![0.0f64; bins];
        let mut top = vec![0.0f64; bins];
        for &k in &mobile {
            let bin = (((p.position[k].x - lower) / width) as usize).min(bins - 1);
            solid[bin] += volume(p.radius[k]) / (width * span);
            top[bin] = top[bin].max(p.position[k][vertical] + p.radius[k] - floor);
        }
        (0..bins)
            .map(|b| (lower + (b as f64 + 0.5) * width, solid[b], top[b]))
            .collect()
    }

    pub(super) fn vertical(system: &DemSystem) -> usize {
        let g = system.domain.gravity;
        (0..3)
            .max_by(|&a, &b| g[a].abs().total_cmp(&g[b].abs()))
            .unwrap()
    }

    fn height(system: &DemSystem) -> f64 {
        let p = &system.particles;
        let v = Self::vertical(system);
        let floor = system.domain.lower[v];
        (0..p.n_owned)
            .filter(|&k| p.inverse_mass[k] > 0.0)
            .map(|k| p.position[k][v] + p.radius[k] - floor)
            .fold(0.0, f64::max)
    }

    pub(super) fn wants_grains(&self, time: f64) -> bool {
        let released = time >= self.release_time;
        let profile_due = self
            .profile_times
            .last()
            .is_some_and(|&t| reached(time, self.release_time + t));
        (released && self.initial_height.is_none()) || profile_due
    }

    pub(super) fn after_step(&mut self, system: &DemSystem) {
        if self.initial_height.is_none() && system.time >= self.release_time {
            self.initial_height = Some(self.column_top(system));
        }
        while let Some(&t) = self.profile_times.last() {
            if !reached(system.time, self.release_time + t) {
                break;
            }
            self.profile_times.pop();
            for (x, h, top) in Self::profile(system) {
                self.profiles.push((t, x, h, top));
            }
        }
    }

    /// The mobile grains' centres and radii, and their mean diameter.
    pub(super) fn mobile_grains(system: &DemSystem) -> (Vec<Vec3>, Vec<f64>, f64) {
        let p = &system.particles;
        let mobile = (0..p.n_owned).filter(|&k| p.inverse_mass[k] > 0.0);
        let centres: Vec<Vec3> = mobile.clone().map(|k| p.position[k]).collect();
        let radii: Vec<f64> = mobile.map(|k| p.radius[k]).collect();
        let diameter = 2.0 * radii.iter().sum::<f64>() / radii.len().max(1) as f64;
        (centres, radii, diameter)
    }

    /// H0: the mean top of the column between its gates
    /// ([`deposit::mean_top`] over cells two mean diameters wide), not the
    /// highest grain, which sits above it by a grain or so.
    pub(super) fn column_top(&self, system: &DemSystem) -> f64 {
        let (centres, radii, diameter) = Self::mobile_grains(system);
        let vertical = Self::vertical(system);
        let from = if self.sides.contains(&-1.0) {
            self.centre - self.half_width
        } else {
            self.centre
        };
        let spanwise = (system.domain.dimension == grainflow_core::Dimension::Three).then(|| {
            let axis = (0..3).find(|&a| a != 0 && a != vertical).unwrap();
            (
                axis,
                system.domain.lower[axis],
                system.domain.extent()[axis],
            )
        });
        deposit::mean_top(
            &centres,
            &radii,
            [from, self.centre + self.half_width],
            2.0 * diameter,
            vertical,
            system.domain.lower[vertical],
            spanwise,
        )
    }

    /// Front of the deposit on each side of the column's centre: the
    /// farthest grain surface of the main mass, the grains linked to one
    /// another by contacts (gaps below [`deposit::CONTACT_GAP`] of a mean
    /// diameter, [`deposit::main_mass`]); grains that came to rest alone
    /// ahead of it do not count. Returns the mean over the sides.
    fn front(&self, system: &DemSystem) -> f64 {
        let (centres, radii, diameter) = Self::mobile_grains(system);
        let link = deposit::CONTACT_GAP * diameter;
        let mass = deposit::main_mass(&system.domain, &centres, &radii, link);
        let fronts: Vec<f64> = self
            .sides
            .iter()
            .map(|&side| deposit::front(&centres, &radii, &mass, self.centre, side))
            .collect();
        fronts.iter().sum::<f64>() / fronts.len() as f64
    }

    pub(super) fn finish(
        &self,
        system: &DemSystem,
        out: &Path,
    ) -> std::io::Result<Map<String, Value>> {
        if !self.profiles.is_empty() {
            write_whole(&out.join("profiles.csv"), |file| {
                writeln!(file, "time_after_release,x,height,top")?;
                for (t, x, h, top) in &self.profiles {
                    writeln!(file, "{t:.6e},{x:.6e},{h:.6e},{top:.6e}")?;
                }
                Ok(())
            })?;
        }
        let mut metrics = Map::new();
        let h0 = self.initial_height.unwrap_or(f64::NAN);
        let r0 = self.half_width;
        let front = self.front(system);
        metrics.insert("initial_height".into(), json!(h0));
        metrics.insert("initial_half_width".into(), json!(r0));
        metrics.insert("aspect_ratio".into(), json!(h0 / r0));
        metrics.insert("final_front".into(), json!(front));
        metrics.insert("final_height".into(), json!(Self::height(system)));
        metrics.insert("runout".into(), json!((front - r0) / r0));
        Ok(metrics)
    }
}
