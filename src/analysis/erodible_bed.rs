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
//! the channel, amounts to [`FRONT_GRAINS`] mean grains (interpolated
//! within its bin); r_f(t) is the farthest such position so far. Static
//! grains of the bed ahead do not raise it, even where the bed dilated
//! (a layer of 10 diameters released at 22° swelled by more than five
//! grains' volume a metre ahead of the flow, which made the front jump
//! there when static bins counted); a few grains rolling ahead of the flow
//! do not make the front; and it moves continuously as the flow carries
//! mass forwards. (The leading edge of the largest linked set of moving
//! grains, tried first, jumped by R0 at a time with 410 discs of 8 mm: the
//! head of a thin flow stops and starts in clusters.) Without an erodible
//! layer it is the leading edge of the spreading mass, less a few grains.

use super::front_phases::{front_phases, FrontPhases};
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
    /// Top of the rigid bed of glued grains above the floor (m).
    rigid_top: f64,
    /// Mean thickness of the erodible layer above the rigid bed (m).
    layer_thickness: f64,
    /// Mean height of the column's top above the rigid bed (m).
    column_height: f64,
    /// h(x) at the release, per bin.
    initial_heights: Vec<f64>,
    column_grains: usize,
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
                || self.mass_profile_times.last().is_some_and(|&t| after >= t))
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
        if after >= self.next_sample {
            let heights = bins.heights(&grains);
            let flowing = bins.flowing(&grains, self.settings.flowing_speed);
            let grain = grains.mean_volume_per_span();
            let reached = self
                .samples
                .last()
                .map_or(self.gate, |s| self.back + s.front);
            let front = raised_front(
                &bins,
                &heights,
                &release.initial_heights,
                &flowing,
                FRONT_GRAINS * grain,
            )
            .map_or(reached, |x| x.max(reached));
            let (bed_kinetic, bed_potential) = bed_energies(system, &release.bed_ids);
            self.samples.push(Sample {
                time: after,
                front: front - self.back,
                bed_kinetic,
                bed_potential,
            });
            self.next_sample = after + self.settings.sample_interval;
        }
        while let Some(&t) = self.mass_profile_times.last() {
            if after < t {
                break;
            }
            self.mass_profile_times.pop();
            let heights = bins.heights(&grains);
            for (b, h) in heights.iter().enumerate() {
                let x = bins.centre(b);
                self.mass_profiles
                    .push([t, x, *h, release.initial_heights[b]]);
            }
        }
        if after >= self.next_profile {
            let speed = self.settings.flowing_speed;
            for &probe in &self.settings.probes {
                let layers = velocity_layers(&grains, probe, release);
                for (z, u, n) in layers {
                    self.velocity_profiles.push([after, probe, z, u, n as f64]);
                }
            }
            let width = PROBE_DIAMETERS * release.diameter;
            let count = ((system.domain.extent().x / width).floor() as usize).max(1);
            for b in 0..count {
                let x = self.back + (b as f64 + 0.5) * width;
                let layers = velocity_layers(&grains, x, release);
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
        let fixed: Vec<usize> = (0..grains.centre.len())
            .filter(|&k| grains.fixed[k])
            .collect();
        let rigid_top = if fixed.is_empty() {
            0.0
        } else {
            fixed
                .iter()
                .map(|&k| grains.height(k) + grains.radius[k])
                .sum::<f64>()
                / fixed.len() as f64
        };
        let mut bed_ids: Vec<u64> = mobile
            .iter()
            .filter(|&&k| grains.centre[k].x > self.gate)
            .map(|&k| p.id[k])
            .collect();
        bed_ids.sort_unstable();
        let mean_top = |from: f64, to: f64| {
            let tops = column_tops(&grains, &mobile, from, to, BIN_DIAMETERS * diameter);
            tops.iter().sum::<f64>() / tops.len().max(1) as f64
        };
        let far = mobile
            .iter()
            .map(|&k| grains.centre[k].x)
            .fold(self.gate, f64::max);
        let layer_thickness = if bed_ids.is_empty() {
            0.0
        } else {
            (mean_top(self.gate, far) - rigid_top).max(0.0)
        };
        let column_height = mean_top(self.back, self.gate) - rigid_top;
        let mut release = Release {
            column_grains: mobile.len() - bed_ids.len(),
            bed_ids,
            diameter,
            rigid_top,
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
                 bed_kinetic,bed_potential,bed_kinetic_to_potential"
            )?;
            for (k, s) in self.samples.iter().enumerate() {
                writeln!(
                    file,
                    "{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}",
                    s.time,
                    s.front,
                    s.front / length,
                    phases.speed[k],
                    s.bed_kinetic,
                    s.bed_potential,
                    s.bed_kinetic / s.bed_potential.max(f64::MIN_POSITIVE)
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
        phases.insert_metrics(&mut metrics);
        Ok(metrics)
    }
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

/// The grains in the channel's frame: centres, heights along the bed
/// normal above the floor, radii, velocities along x.
struct Grains {
    centre: Vec<Vec3>,
    radius: Vec<f64>,
    fixed: Vec<bool>,
    velocity_x: Vec<f64>,
    mass: Vec<f64>,
    normal: usize,
    floor: f64,
    /// Volume of a grain of radius r per unit span (2D) or the grain's
    /// volume (3D), and the span.
    dimension: Dimension,
    span: f64,
}

impl Grains {
    fn of(system: &DemSystem) -> Self {
        let p = &system.particles;
        let n = p.n_owned;
        let g = system.domain.gravity;
        let normal = if system.domain.dimension == Dimension::Two {
            1
        } else {
            (1..3)
                .max_by(|&a, &b| g[a].abs().total_cmp(&g[b].abs()))
                .unwrap()
        };
        let span = match system.domain.dimension {
            Dimension::Two => 1.0,
            Dimension::Three => system.domain.extent()[3 - normal],
        };
        Grains {
            centre: p.position[..n].to_vec(),
            radius: p.radius[..n].to_vec(),
            fixed: (0..n).map(|k| p.is_fixed(k)).collect(),
            velocity_x: (0..n).map(|k| p.velocity[k].x).collect(),
            mass: p.mass[..n].to_vec(),
            normal,
            floor: system.domain.lower[normal],
            dimension: system.domain.dimension,
            span,
        }
    }

    /// Height of grain k's centre above the floor.
    fn height(&self, k: usize) -> f64 {
        self.centre[k][self.normal] - self.floor
    }

    /// Mean solid volume of the mobile grains per unit span.
    fn mean_volume_per_span(&self) -> f64 {
        let mobile: Vec<usize> = (0..self.centre.len()).filter(|&k| !self.fixed[k]).collect();
        mobile.iter().map(|&k| self.volume_per_span(k)).sum::<f64>() / mobile.len().max(1) as f64
    }

    /// Solid volume of grain k per unit span.
    fn volume_per_span(&self, k: usize) -> f64 {
        let r = self.radius[k];
        match self.dimension {
            Dimension::Two => std::f64::consts::PI * r * r,
            Dimension::Three => 4.0 / 3.0 * std::f64::consts::PI * r * r * r / self.span,
        }
    }
}

/// Bins along x from the back wall.
struct Bins {
    lower: f64,
    width: f64,
    count: usize,
}

impl Bins {
    fn new(system: &DemSystem, diameter: f64) -> Self {
        let width = BIN_DIAMETERS * diameter;
        Bins {
            lower: system.domain.lower.x,
            width,
            count: ((system.domain.extent().x / width).ceil() as usize).max(1),
        }
    }

    fn of(&self, x: f64) -> usize {
        (((x - self.lower) / self.width).max(0.0) as usize).min(self.count - 1)
    }

    fn centre(&self, bin: usize) -> f64 {
        self.lower + (bin as f64 + 0.5) * self.width
    }

    /// h(x): the solid volume of the mobile grains centred in each bin over
    /// its width.
    fn heights(&self, grains: &Grains) -> Vec<f64> {
        let mut h = vec![0.0; self.count];
        for k in 0..grains.centre.len() {
            if !grains.fixed[k] {
                h[self.of(grains.centre[k].x)] += grains.volume_per_span(k) / self.width;
            }
        }
        h
    }

    /// Whether the mobile grains centred in each bin move down the slope
    /// at `speed` or faster on average (mass-weighted).
    fn flowing(&self, grains: &Grains, speed: f64) -> Vec<bool> {
        let mut momentum = vec![0.0; self.count];
        let mut mass = vec![0.0; self.count];
        for k in 0..grains.centre.len() {
            if !grains.fixed[k] {
                let b = self.of(grains.centre[k].x);
                momentum[b] += grains.mass[k] * grains.velocity_x[k];
                mass[b] += grains.mass[k];
            }
        }
        (0..self.count)
            .map(|b| mass[b] > 0.0 && momentum[b] >= speed * mass[b])
            .collect()
    }
}

/// The position beyond which the volume (per unit span) of the mobile
/// grains above their h at the release in the `flowing` bins,
/// `∫ max(h − initial, 0) dx` from the end of the channel, reaches
/// `volume`; `None` where it nowhere does.
fn raised_front(
    bins: &Bins,
    heights: &[f64],
    initial: &[f64],
    flowing: &[bool],
    volume: f64,
) -> Option<f64> {
    let mut beyond = 0.0;
    for b in (0..bins.count).rev().filter(|&b| flowing[b]) {
        let raised = (heights[b] - initial[b]).max(0.0) * bins.width;
        if beyond + raised >= volume {
            // Uniform within the bin: the share still needed from its end.
            let needed = (volume - beyond) / raised;
            return Some(bins.lower + (b as f64 + 1.0 - needed) * bins.width);
        }
        beyond += raised;
    }
    None
}

/// The highest grain surface above the rigid bed's floor in each bin of
/// `width` between `from` and `to`, over the bins that hold a grain.
fn column_tops(grains: &Grains, mobile: &[usize], from: f64, to: f64, width: f64) -> Vec<f64> {
    let count = (((to - from) / width).round() as usize).max(1);
    let mut top = vec![f64::NAN; count];
    for &k in mobile {
        let x = grains.centre[k].x;
        if x < from || x > to {
            continue;
        }
        let b = (((x - from) / (to - from) * count as f64) as usize).min(count - 1);
        let h = grains.height(k) + grains.radius[k];
        if top[b].is_nan() || h > top[b] {
            top[b] = h;
        }
    }
    top.into_iter().filter(|h| !h.is_nan()).collect()
}

/// Mass-weighted mean u_x of the mobile grains within a window of
/// [`PROBE_DIAMETERS`] mean diameters around `x`, in layers one mean
/// diameter thick from the rigid bed's top: (height of the layer's centre
/// above the rigid bed, u_x, grains), the layers that hold grains.
fn velocity_layers(grains: &Grains, x: f64, release: &Release) -> Vec<(f64, f64, usize)> {
    let d = release.diameter;
    let half = 0.5 * PROBE_DIAMETERS * d;
    let mut layers: Vec<(f64, f64, usize)> = Vec::new();
    for k in 0..grains.centre.len() {
        if grains.fixed[k] || (grains.centre[k].x - x).abs() > half {
            continue;
        }
        let z = grains.height(k) - release.rigid_top;
        let layer = (z / d).max(0.0) as usize;
        if layers.len() <= layer {
            layers.resize(layer + 1, (0.0, 0.0, 0));
        }
        let l = &mut layers[layer];
        l.0 += grains.mass[k];
        l.1 += grains.mass[k] * grains.velocity_x[k];
        l.2 += 1;
    }
    layers
        .into_iter()
        .enumerate()
        .filter(|(_, l)| l.2 > 0)
        .map(|(i, l)| ((i as f64 + 0.5) * d, l.1 / l.0, l.2))
        .collect()
}

/// The static/flowing interface of a column of layers (from
/// [`velocity_layers`]): the bottom of the lowest layer moving down the
/// slope at `flowing_speed` or faster (the paper's criterion u_x < 1
/// cm/s for static grains), or the surface where none does; and the
/// surface, the top of the highest layer. `None` for an empty column.
fn static_flowing(
    layers: &[(f64, f64, usize)],
    diameter: f64,
    flowing_speed: f64,
) -> Option<(f64, f64)> {
    let surface = layers.last()?.0 + 0.5 * diameter;
    let interface = layers
        .iter()
        .find(|l| l.1 >= flowing_speed)
        .map_or(surface, |l| l.0 - 0.5 * diameter);
    Some((interface, surface))
}

/// E_k and E_p of the grains of the erodible bed: translation and
/// rotation, and m |g| h with h the height along −g above the domain's
/// corner lowest along −g (so that E_p ≥ 0 on a tilted channel).
fn bed_energies(system: &DemSystem, bed_ids: &[u64]) -> (f64, f64) {
    let p = &system.particles;
    let g = system.domain.gravity;
    let magnitude = g.norm();
    let up = -g / magnitude.max(f64::MIN_POSITIVE);
    let (lo, hi) = (system.domain.lower, system.domain.upper);
    let reference = (0..8)
        .map(|c| {
            let corner = Vec3::new(
                if c & 1 == 0 { lo.x } else { hi.x },
                if c & 2 == 0 { lo.y } else { hi.y },
                if c & 4 == 0 { lo.z } else { hi.z },
            );
            corner.dot(&up)
        })
        .fold(f64::MAX, f64::min);
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
    use super::*;

    fn release(diameter: f64) -> Release {
        Release {
            bed_ids: Vec::new(),
            diameter,
            rigid_top: 0.0,
            layer_thickness: 0.0,
            column_height: 0.0,
            initial_heights: Vec::new(),
            column_grains: 0,
        }
    }

    fn grains(centres: &[[f64; 2]], velocities: &[f64]) -> Grains {
        let n = centres.len();
        Grains {
            centre: centres.iter().map(|c| Vec3::new(c[0], c[1], 0.0)).collect(),
            radius: vec![0.5; n],
            fixed: vec![false; n],
            velocity_x: velocities.to_vec(),
            mass: vec![1.0; n],
            normal: 1,
            floor: 0.0,
            dimension: Dimension::Two,
            span: 1.0,
        }
    }

    #[test]
    fn h_is_the_solid_volume_of_each_bin_over_its_width() {
        // Unit discs two high over x in [0, 6), one alone at x = 9.5.
        let mut centres = Vec::new();
        for i in 0..6 {
            centres.push([0.5 + i as f64, 0.5]);
            centres.push([0.5 + i as f64, 1.5]);
        }
        centres.push([9.5, 0.5]);
        let g = grains(&centres, &vec![0.0; centres.len()]);
        let bins = Bins {
            lower: 0.0,
            width: 2.0,
            count: 6,
        };
        let heights = bins.heights(&g);
        // Four discs of area π/4 in each bin two wide: h = π/2.
        assert!((heights[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((heights[4] - std::f64::consts::FRAC_PI_8).abs() < 1e-12);
        assert_eq!(heights[3], 0.0);
    }

    #[test]
    fn the_front_leaves_a_few_grains_of_raised_volume_ahead_of_it() {
        // Bins of 2: h raised by 1 over [0, 6), by 0.25 in [8, 10), and
        // the bin [6, 8) raised at the release already.
        let bins = Bins {
            lower: 0.0,
            width: 2.0,
            count: 5,
        };
        let heights = [1.0, 1.0, 1.0, 1.0, 0.25];
        let initial = [0.0, 0.0, 0.0, 1.0, 0.0];
        let all = [true; 5];
        // 0.5 beyond x = 8, none in [6, 8), then 2 in [4, 6): the other
        // 1.5 lie in [4.5, 6).
        let front = raised_front(&bins, &heights, &initial, &all, 2.0);
        assert!((front.unwrap() - 4.5).abs() < 1e-12, "{front:?}");
        // Less than the whole raised volume (6.5) in all: no front.
        assert_eq!(raised_front(&bins, &heights, &initial, &all, 7.0), None);
        // Mass removed (eroded) raises nothing.
        assert_eq!(raised_front(&bins, &initial, &heights, &all, 1.1), None);
        // The bin [8, 10) raised but static (a dilated bed): the 2 lie in
        // [4, 6) alone.
        let static_ahead = [true, true, true, true, false];
        let front = raised_front(&bins, &heights, &initial, &static_ahead, 2.0);
        assert!((front.unwrap() - 4.0).abs() < 1e-12, "{front:?}");
    }

    #[test]
    fn a_bin_flows_where_its_grains_move_down_the_slope_on_average() {
        // Unit discs: three at rest and one at 1 m/s in [0, 2), four at
        // 0.005 m/s in [2, 4), none in [4, 6).
        let g = grains(
            &[
                [0.5, 0.5],
                [1.5, 0.5],
                [0.5, 1.5],
                [1.5, 1.5],
                [2.5, 0.5],
                [3.5, 0.5],
                [2.5, 1.5],
                [3.5, 1.5],
            ],
            &[0.0, 0.0, 0.0, 1.0, 0.005, 0.005, 0.005, 0.005],
        );
        let bins = Bins {
            lower: 0.0,
            width: 2.0,
            count: 3,
        };
        assert_eq!(bins.flowing(&g, 0.01), [true, false, false]);
    }

    #[test]
    fn the_interface_is_the_bottom_of_the_lowest_flowing_layer() {
        // Unit discs stacked four high at x = 0: the two lower at rest,
        // the two upper at 0.5 and 1 m/s.
        let g = grains(
            &[[0.0, 0.5], [0.0, 1.5], [0.0, 2.5], [0.0, 3.5]],
            &[0.0, 0.005, 0.5, 1.0],
        );
        let layers = velocity_layers(&g, 0.0, &release(1.0));
        assert_eq!(layers.len(), 4);
        assert_eq!(layers[2], (2.5, 0.5, 1));
        let (interface, surface) = static_flowing(&layers, 1.0, 0.01).unwrap();
        assert_eq!((interface, surface), (2.0, 4.0));
        // All at rest: the interface is the surface.
        let rest = grains(&[[0.0, 0.5], [0.0, 1.5]], &[0.0, 0.0]);
        let layers = velocity_layers(&rest, 0.0, &release(1.0));
        assert_eq!(static_flowing(&layers, 1.0, 0.01), Some((2.0, 2.0)));
    }
}
