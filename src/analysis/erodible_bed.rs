//! A granular column released onto an inclined channel covered by an
//! erodible layer of the same grains (Martin et al. 2022, section 5): the
//! front and its three phases, the erodible bed's energy, the mass
//! profiles, the velocity profiles at probes and the static/flowing
//! interface.
//!
//! The scene is set in the channel's frame: x down the slope from the
//! back wall (the domain's lower x), the bed normal along the axis of the
//! largest component of gravity, which is tilted by the slope. The column
//! stands between the back wall and the gate (the wall with `remove_at`);
//! at the release, the mobile grains behind the gate are the column's and
//! those beyond it the erodible bed's, and they keep that origin. The
//! glued grains are the rigid bed.
//!
//! The front is where the flow has raised the surface above where it stood
//! at the release: h(x), the solid volume of the mobile grains per unit
//! length in bins [`BIN_DIAMETERS`] mean diameters wide, is compared with
//! h(x) at the release, and the front is the position beyond which the
//! raised volume of the flowing bins (their grains' mean u_x at
//! `flowing_speed` or more), ∫ max(h − h_release, 0) dx from the end of
//! the channel, amounts to [`FRONT_GRAINS`] mean grains (in 3D, per mean
//! diameter of span; interpolated within its bin); r_f(t) is the farthest
//! such position so far. Static grains of the bed ahead do not raise it,
//! even where the bed dilated (a layer of 10 diameters released at 22°
//! swelled by more than five grains' volume a metre ahead of the flow,
//! which made the front jump
//! there when static bins counted); a few grains rolling ahead of the flow
//! do not make the front; and it moves continuously as the flow carries
//! mass forwards. (The leading edge of the largest linked set of moving
//! grains, tried first, jumped by R0 at a time with 410 discs of 8 mm: the
//! head of a thin flow stops and starts in clusters.) Without an erodible
//! layer it is the leading edge of the spreading mass, less a few grains.

use super::channel_grains::{raised_front, static_flowing, velocity_layers, Bins, Grains};
use super::front_phases::{front_phases, FrontPhases};
use super::reached;
use crate::scene::deposit;
use grainflow_core::{Dimension, Vec3};
use grainflow_dem::DemSystem;
use grainflow_io::write_whole;
use serde_json::{json, Map, Value};
use std::io::Write;
use std::path::Path;

/// The width of the bins of h(x) and of the front, in mean diameters.
pub const BIN_DIAMETERS: f64 = 2.0;
/// The raised volume beyond the front, in mean grain volumes.
pub const FRONT_GRAINS: f64 = 5.0;
/// The width of a probe's window along x, in mean diameters.
pub const PROBE_DIAMETERS: f64 = 5.0;

/// What `analysis.kind = "erodible_bed"` sets (`docs/case-reference.md`).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ErodibleBedSettings {
    pub profile_times: Vec<f64>,
    pub probes: Vec<f64>,
    pub sample_interval: f64,
    pub profile_interval: f64,
    pub flowing_speed: f64,
    pub smoothing: f64,
}

/// What the grains were at the release.
#[derive(serde::Serialize, serde::Deserialize)]
struct Release {
    /// Ids of the grains of the erodible bed, sorted.
    bed_ids: Vec<u64>,
    /// Mean diameter of the mobile grains (m).
    diameter: f64,
    /// Top of the rigid bed of glued grains above the floor (m), the
    /// mean over all of them.
    rigid_top: f64,
    /// (x, top above the floor) of each glued grain, by x: the rigid bed's
    /// top where it is not flat (a glued layer beyond the gate).
    #[serde(default)]
    rigid_bed: Vec<[f64; 2]>,
    /// Mean thickness of the erodible layer above the rigid bed (m).
    layer_thickness: f64,
    /// Mean height of the column's top above the rigid bed (m).
    column_height: f64,
    /// h(x) at the release, per bin.
    initial_heights: Vec<f64>,
    column_grains: usize,
}

impl Release {
    /// The mean top of the glued grains whose centres lie in
    /// [`from`, `to`] along the channel (the whole bed's where none does).
    fn rigid_top_between(&self, from: f64, to: f64) -> f64 {
        mean_top_between(&self.rigid_bed, from, to).unwrap_or(self.rigid_top)
    }
}

/// The mean top of the grains of `bed` ((x, top), by x) whose centres lie
/// in [`from`, `to`], if any does.
fn mean_top_between(bed: &[[f64; 2]], from: f64, to: f64) -> Option<f64> {
    let within = &bed[bed.partition_point(|g| g[0] < from)..];
    let within = &within[..within.partition_point(|g| g[0] <= to)];
    (!within.is_empty()).then(|| within.iter().map(|g| g[1]).sum::<f64>() / within.len() as f64)
}

/// One sample of the front and of the bed's energy.
#[derive(serde::Serialize, serde::Deserialize)]
struct Sample {
    /// Time after the release (s).
    time: f64,
    /// Front position from the back wall (m).
    front: f64,
    bed_kinetic: f64,
    bed_potential: f64,
    /// The largest down-slope velocity of a mobile grain (m/s); zero in
    /// the samples of a checkpoint written before it was kept.
    #[serde(default)]
    fastest: f64,
}

/// The measurements of an erodible-bed run.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct ErodibleBed {
    settings: ErodibleBedSettings,
    release_time: f64,
    /// Back wall and gate along x (m).
    back: f64,
    gate: f64,
    release: Option<Release>,
    next_sample: f64,
    next_profile: f64,
    /// Profile times after the release still to come, the next one last.
    mass_profile_times: Vec<f64>,
    samples: Vec<Sample>,
    /// (time after release, x, h, h at release).
    mass_profiles: Vec<[f64; 4]>,
    /// (time after release, probe x, height above the rigid bed, mean u_x,
    /// grains in the layer).
    velocity_profiles: Vec<[f64; 5]>,
    /// (time after release, x, static/flowing interface, surface), both
    /// heights above the rigid bed.
    interface: Vec<[f64; 4]>,
}

impl ErodibleBed {
    pub(super) fn new(system: &DemSystem, settings: &ErodibleBedSettings) -> Self {
        let gate = system
            .walls
            .iter()
            .find(|w| w.remove_at.is_some())
            .expect("validation asks for a gate");
        let release_time = gate.remove_at.unwrap_or(0.0);
        let mut mass_profile_times = settings.profile_times.clone();
        mass_profile_times.sort_by(|a, b| b.total_cmp(a));
        ErodibleBed {
            settings: settings.clone(),
            release_time,
            back: system.domain.lower.x,
            gate: gate.point.x,
            release: None,
            next_sample: 0.0,
            next_profile: 0.0,
            mass_profile_times,
            samples: Vec::new(),
            mass_profiles: Vec::new(),
            velocity_profiles: Vec::new(),
            interface: Vec::new(),
        }
    }

    pub(super) fn wants_grains(&self, time: f64) -> bool {
        let after = time - self.release_time;
        after >= 0.0
            && (self.release.is_none()
                || after >= self.next_sample
                || after >= self.next_profile
                || self
                    .mass_profile_times
                    .last()
                    .is_some_and(|&t| reached(after, t)))
    }

    pub(super) fn after_step(&mut self, system: &DemSystem) {
        if !self.wants_grains(system.time) {
            return;
        }
        let after = system.time - self.release_time;
        if self.release.is_none() {
            self.release = Some(self.at_release(system));
        }
        let grains = Grains::of(system);
        let release = self.release.as_ref().expect("set above");
        let bins = Bins::new(system, release.diameter);
        let heights = bins.heights(&grains);
        if after >= self.next_sample {
            let flowing = bins.flowing(&grains, self.settings.flowing_speed);
            let volume = grains.front_volume(release.diameter);
            let reached = self
                .samples
                .last()
                .map_or(self.gate, |s| self.back + s.front);
            let front = raised_front(&bins, &heights, &release.initial_heights, &flowing, volume)
                .map_or(reached, |x| x.max(reached));
            let (bed_kinetic, bed_potential) = bed_energies(system, &release.bed_ids);
            self.samples.push(Sample {
                time: after,
                front: front - self.back,
                bed_kinetic,
                bed_potential,
                fastest: grains.fastest_down_slope(),
            });
            self.next_sample = after + self.settings.sample_interval;
        }
        while let Some(&t) = self.mass_profile_times.last() {
            if !reached(after, t) {
                break;
            }
            self.mass_profile_times.pop();
            for (b, h) in heights.iter().enumerate() {
                let x = bins.centre(b);
                self.mass_profiles
                    .push([t, x, *h, release.initial_heights[b]]);
            }
        }
        if after >= self.next_profile {
            let speed = self.settings.flowing_speed;
            let half = 0.5 * PROBE_DIAMETERS * release.diameter;
            let rigid_top_at = |x: f64| release.rigid_top_between(x - half, x + half);
            for &probe in &self.settings.probes {
                let layers = velocity_layers(&grains, probe, release.diameter, rigid_top_at(probe));
                for (z, u, n) in layers {
                    self.velocity_profiles.push([after, probe, z, u, n as f64]);
                }
            }
            let width = PROBE_DIAMETERS * release.diameter;
            let count = ((system.domain.extent().x / width).floor() as usize).max(1);
            for b in 0..count {
                let x = self.back + (b as f64 + 0.5) * width;
                let layers = velocity_layers(&grains, x, release.diameter, rigid_top_at(x));
                if let Some((interface, surface)) = static_flowing(&layers, release.diameter, speed)
                {
                    self.interface.push([after, x, interface, surface]);
                }
            }
            self.next_profile = after + self.settings.profile_interval;
        }
    }

    fn at_release(&self, system: &DemSystem) -> Release {
        let grains = Grains::of(system);
        let p = &system.particles;
        let mobile: Vec<usize> = (0..grains.centre.len())
            .filter(|&k| !grains.fixed[k])
            .collect();
        let diameter = 2.0 * mobile.iter().map(|&k| grains.radius[k]).sum::<f64>()
            / mobile.len().max(1) as f64;
        let mut rigid_bed: Vec<[f64; 2]> = (0..grains.centre.len())
            .filter(|&k| grains.fixed[k])
            .map(|k| [grains.centre[k].x, grains.height(k) + grains.radius[k]])
            .collect();
        rigid_bed.sort_by(|a, b| a[0].total_cmp(&b[0]));
        let rigid_top =
            mean_top_between(&rigid_bed, f64::NEG_INFINITY, f64::INFINITY).unwrap_or(0.0);
        let mut bed_ids: Vec<u64> = mobile
            .iter()
            .filter(|&&k| grains.centre[k].x > self.gate)
            .map(|&k| p.id[k])
            .collect();
        bed_ids.sort_unstable();
        // The mean of the highest grain surfaces in cells two diameters
        // wide (and spanwise in 3D), as for a column collapse's H0.
        let centres: Vec<Vec3> = mobile.iter().map(|&k| grains.centre[k]).collect();
        let radii: Vec<f64> = mobile.iter().map(|&k| grains.radius[k]).collect();
        let spanwise = (system.domain.dimension == Dimension::Three).then(|| {
            let axis = 3 - grains.normal;
            (
                axis,
                system.domain.lower[axis],
                system.domain.extent()[axis],
            )
        });
        let mean_top = |from: f64, to: f64| {
            deposit::mean_top(
                &centres,
                &radii,
                [from, to],
                BIN_DIAMETERS * diameter,
                grains.normal,
                grains.floor,
                spanwise,
            )
        };
        let far = mobile
            .iter()
            .map(|&k| grains.centre[k].x)
            .fold(self.gate, f64::max);
        // Each over the rigid bed beneath it: the column's over the glued
        // grains behind the gate, the layer's over those beyond.
        let rigid_top_between =
            |from: f64, to: f64| mean_top_between(&rigid_bed, from, to).unwrap_or(rigid_top);
        let layer_thickness = if bed_ids.is_empty() {
            0.0
        } else {
            (mean_top(self.gate, far) - rigid_top_between(self.gate, far)).max(0.0)
        };
        let column_height =
            mean_top(self.back, self.gate) - rigid_top_between(self.back, self.gate);
        let mut release = Release {
            column_grains: mobile.len() - bed_ids.len(),
            bed_ids,
            diameter,
            rigid_top,
            rigid_bed,
            layer_thickness,
            column_height,
            initial_heights: Vec::new(),
        };
        release.initial_heights = Bins::new(system, diameter).heights(&grains);
        release
    }

    pub(super) fn finish(&self, out: &Path) -> std::io::Result<Map<String, Value>> {
        let mut metrics = Map::new();
        let Some(release) = &self.release else {
            return Ok(metrics);
        };
        let length = self.gate - self.back;
        let times: Vec<f64> = self.samples.iter().map(|s| s.time).collect();
        let fronts: Vec<f64> = self.samples.iter().map(|s| s.front).collect();
        let phases = front_phases(
            &times,
            &fronts,
            self.settings.smoothing,
            self.settings.flowing_speed,
        );
        write_whole(&out.join("front.csv"), |file| {
            writeln!(
                file,
                "time_after_release,front,front_over_length,front_speed,\
                 bed_kinetic,bed_potential,bed_kinetic_to_potential,fastest_grain"
            )?;
            for (k, s) in self.samples.iter().enumerate() {
                writeln!(
                    file,
                    "{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}",
                    s.time,
                    s.front,
                    s.front / length,
                    phases.speed[k],
                    s.bed_kinetic,
                    s.bed_potential,
                    s.bed_kinetic / s.bed_potential.max(f64::MIN_POSITIVE),
                    s.fastest
                )?;
            }
            Ok(())
        })?;
        write_rows(
            &out.join("profiles.csv"),
            "time_after_release,x,height,height_at_release",
            &self.mass_profiles,
        )?;
        write_rows(
            &out.join("velocity_profiles.csv"),
            "time_after_release,probe,height,velocity_x,grains",
            &self.velocity_profiles,
        )?;
        write_rows(
            &out.join("static_flowing.csv"),
            "time_after_release,x,interface,surface",
            &self.interface,
        )?;
        let front = fronts.last().copied().unwrap_or(length);
        let max_ratio = self
            .samples
            .iter()
            .map(|s| s.bed_kinetic / s.bed_potential.max(f64::MIN_POSITIVE))
            .fold(0.0, f64::max);
        metrics.insert("initial_length".into(), json!(length));
        metrics.insert("initial_height".into(), json!(release.column_height));
        metrics.insert("aspect_ratio".into(), json!(release.column_height / length));
        metrics.insert("erodible_thickness".into(), json!(release.layer_thickness));
        metrics.insert("mean_diameter".into(), json!(release.diameter));
        metrics.insert("column_grains".into(), json!(release.column_grains));
        metrics.insert("bed_grains".into(), json!(release.bed_ids.len()));
        metrics.insert("final_front".into(), json!(front));
        metrics.insert("runout".into(), json!((front - length) / length));
        metrics.insert("bed_max_kinetic_to_potential".into(), json!(max_ratio));
        let (jumps, first_jump) = front_jumps(&self.samples, length);
        metrics.insert("front_jumps".into(), json!(jumps));
        metrics.insert("front_first_jump_time".into(), json!(first_jump));
        phases.insert_metrics(&mut metrics);
        Ok(metrics)
    }
}

/// How many times the front advanced between two samples farther than
/// any grain could carry it (twice the fastest mobile grain's down-slope
/// travel over the interval, plus half the column's length `length`), and
/// when it first did. A front that jumps is not the released mass's: the
/// bed ahead of it has started to flow on its own (a loose layer beyond
/// its angle of repose), and the front, its speed and its phases then
/// describe the bed. The allowance lets the front's own steps pass: the
/// raised volume of its criterion gathers a few bins at a time, and a
/// wave of the bed set moving just ahead of the head joins it at once
/// (up to 3 bins in a sample on the 2D scene of the tests). Samples
/// without the fastest grain's velocity (from an older checkpoint) are
/// not judged.
fn front_jumps(samples: &[Sample], length: f64) -> (usize, Option<f64>) {
    let mut jumps = 0;
    let mut first = None;
    for pair in samples.windows(2) {
        let (before, after) = (&pair[0], &pair[1]);
        let fastest = before.fastest.max(after.fastest);
        if fastest == 0.0 {
            continue;
        }
        let reach = 2.0 * fastest * (after.time - before.time) + 0.5 * length;
        if after.front - before.front > reach {
            jumps += 1;
            first.get_or_insert(after.time);
        }
    }
    (jumps, first)
}

fn write_rows<const N: usize>(path: &Path, header: &str, rows: &[[f64; N]]) -> std::io::Result<()> {
    write_whole(path, |file| {
        writeln!(file, "{header}")?;
        for row in rows {
            let line: Vec<String> = row.iter().map(|v| format!("{v:.6e}")).collect();
            writeln!(file, "{}", line.join(","))?;
        }
        Ok(())
    })
}

impl FrontPhases {
    fn insert_metrics(&self, metrics: &mut Map<String, Value>) {
        metrics.insert("front_max_speed".into(), json!(self.max_speed));
        metrics.insert("front_max_speed_time".into(), json!(self.max_speed_time));
        metrics.insert(
            "deceleration_end_time".into(),
            json!(self.deceleration_end_time),
        );
        metrics.insert("slow_phase".into(), json!(self.slow_phase));
        metrics.insert("slow_phase_speed".into(), json!(self.slow_phase_speed));
        metrics.insert("front_stop_time".into(), json!(self.stop_time));
    }
}

/// E_k and E_p of the grains of the erodible bed: translation and
/// rotation, and m |g| h with h the height along −g above the domain's
/// corner lowest along −g (so that E_p ≥ 0 on a tilted channel).
fn bed_energies(system: &DemSystem, bed_ids: &[u64]) -> (f64, f64) {
    let p = &system.particles;
    let g = system.domain.gravity;
    let magnitude = g.norm();
    let up = -g / magnitude.max(f64::MIN_POSITIVE);
    let reference = system.domain.lowest_along(&up);
    let (mut kinetic, mut potential) = (0.0, 0.0);
    for k in 0..p.n_owned {
        if p.is_fixed(k) || bed_ids.binary_search(&p.id[k]).is_err() {
            continue;
        }
        kinetic += 0.5 * p.mass[k] * p.velocity[k].norm_squared()
            + 0.5 * p.angular_velocity[k].norm_squared() / p.inverse_inertia[k];
        potential += p.mass[k] * magnitude * (p.position[k].dot(&up) - reference);
    }
    (kinetic, potential)
}

#[cfg(test)]
mod tests {
    use super::{front_jumps, Sample};

    fn sample(time: f64, front: f64, fastest: f64) -> Sample {
        Sample {
            time,
            front,
            bed_kinetic: 0.0,
            bed_potential: 1.0,
            fastest,
        }
    }

    #[test]
    fn a_front_ahead_of_every_grain_is_counted_as_a_jump() {
        // A column 10 cm long.
        let length = 0.1;
        // Carried by grains at 1 m/s: 1 cm in 10 ms, then a step of the
        // raised volume's criterion just below half the column.
        let carried = [
            sample(0.0, 0.10, 1.0),
            sample(0.01, 0.11, 1.0),
            sample(0.02, 0.12 + 0.049, 1.0),
        ];
        assert_eq!(front_jumps(&carried, length), (0, None));
        // 0.77 m in 10 ms while no grain moves faster than 1 m/s: the
        // loose layer ahead flowing on its own.
        let jumped = [sample(0.0, 0.10, 1.0), sample(0.01, 0.87, 1.0)];
        assert_eq!(front_jumps(&jumped, length), (1, Some(0.01)));
        // Samples of an older checkpoint, without the grains' speed.
        let unknown = [sample(0.0, 0.10, 0.0), sample(0.01, 0.87, 0.0)];
        assert_eq!(front_jumps(&unknown, length), (0, None));
    }
}
