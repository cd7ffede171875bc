//! Grains poured during a run (`[[particles.pour]]`): batches on a jittered
//! lattice, released one after the other just above the deposit, so that
//! grains land from a small height however high the deposit has grown
//! (a filling that follows the free surface, as a silo is filled).
//!
//! A batch is released at t = 0 and then every `interval` (and, if
//! `settled_speed` is set, once the previous batch has landed: the rms
//! speed of its grains is below it). It is the
//! lattice of the pour's box, lifted along −g so that its lowest surface
//! lies `gap` above the highest surface of the mobile grains; it is never
//! placed below the box itself. Every rank draws the same batch from the
//! pour's own random stream and keeps the grains it owns, so that ids and
//! states do not depend on the number of ranks.

use crate::case::{Case, PourSection};
use crate::scene::{domain, vector};
use grainflow_core::{Dimension, Vec3};
use grainflow_dem::generate::{self, Material, RadiusDistribution};
use grainflow_dem::DemSystem;
use rand_pcg::Pcg64;

/// The pours of a case and how far each has gone.
pub struct Pouring {
    pours: Vec<Pour>,
}

struct Pour {
    /// Its index in `particles.pour` (for messages).
    index: usize,
    /// The group of its grains: after those of the blocks.
    group: u64,
    lower: Vec3,
    upper: Vec3,
    spacing: f64,
    jitter: f64,
    material: Material,
    radii: RadiusDistribution,
    count: usize,
    interval: f64,
    gap: f64,
    settled_speed: Option<f64>,
    /// How far it has gone (what a checkpoint keeps).
    progress: PourProgress,
}

impl Pouring {
    pub fn new(case: &Case) -> Self {
        let p = case.particles_section();
        let radii = RadiusDistribution {
            mean: p.radius,
            spread: p.radius_spread,
        };
        let pours = p
            .pour
            .iter()
            .enumerate()
            .map(|(index, section)| {
                let group = (p.block.len() + index) as u64;
                Pour::new(index, group, section, p.density, p.seed, radii)
            })
            .collect();
        Pouring { pours }
    }

    /// Whether every pour has released all its grains.
    pub fn is_done(&self) -> bool {
        self.pours.iter().all(|p| p.progress.poured == p.count)
    }

    /// Grains still to be released.
    pub fn remaining(&self) -> usize {
        self.pours.iter().map(|p| p.count - p.progress.poured).sum()
    }

    /// Batches released so far, over all pours.
    pub fn batches_released(&self) -> usize {
        self.pours.iter().map(|p| p.progress.batches).sum()
    }

    /// The pours still going on: grains per batch (the mean), their
    /// shortest interval (s), and whether any waits for the previous batch
    /// to land. None once every pour is done.
    pub fn pace(&self, dimension: Dimension) -> Option<(usize, f64, bool)> {
        let going: Vec<&Pour> = self
            .pours
            .iter()
            .filter(|p| p.progress.poured < p.count)
            .collect();
        if going.is_empty() {
            return None;
        }
        let batch = going.iter().map(|p| p.batch_size(dimension)).sum::<usize>() / going.len();
        let interval = going
            .iter()
            .map(|p| p.interval)
            .fold(f64::INFINITY, f64::min);
        let waits = going.iter().any(|p| p.settled_speed.is_some());
        Some((batch.max(1), interval, waits))
    }

    /// One line per pour for the log: what it releases and how.
    pub fn describe(&self, dimension: Dimension) -> Vec<String> {
        self.pours
            .iter()
            .map(|p| {
                let wait = p
                    .settled_speed
                    .map(|v| format!(" and once the last batch's rms speed is below {v} m/s"))
                    .unwrap_or_default();
                format!(
                    "particles.pour[{}]: {} grains in batches of up to {}, every {} s{wait}, \
                     released {} m above the highest mobile grain",
                    p.index,
                    p.count,
                    p.batch_size(dimension),
                    p.interval,
                    p.gap
                )
            })
            .collect()
    }

    /// Releases every batch due at the system's time (collective: every
    /// rank calls it at the same step). Returns a log line per batch, or
    /// why the pour cannot go on.
    pub fn release_due(&mut self, system: &mut DemSystem) -> Result<Vec<String>, String> {
        let mut lines = Vec::new();
        for pour in &mut self.pours {
            if pour.progress.poured == pour.count
                || system.time < pour.progress.next_release - 1e-9 * pour.interval
            {
                continue;
            }
            if let Some(speed) = pour.settled_speed {
                if pour.last_batch_speed(system) > speed {
                    continue;
                }
            }
            lines.push(pour.release(system)?);
        }
        Ok(lines)
    }
}

impl Pour {
    fn new(
        index: usize,
        group: u64,
        section: &PourSection,
        density: f64,
        seed: u64,
        radii: RadiusDistribution,
    ) -> Self {
        Pour {
            index,
            group,
            lower: vector(&section.lower),
            upper: vector(&section.upper),
            spacing: section.spacing,
            jitter: section.jitter,
            material: Material {
                density,
                fixed: false,
                velocity: vector(&section.velocity),
            },
            radii,
            count: section.count,
            interval: section.interval,
            gap: section.gap,
            settled_speed: section.settled_speed,
            progress: PourProgress {
                poured: 0,
                last_batch: 0..0,
                batches: 0,
                next_release: 0.0,
                // A stream of its own: the blocks' grains and radii do not
                // change when a pour is added.
                rng: Pcg64::new(u128::from(seed), 1 + index as u128),
            },
        }
    }

    fn batch_size(&self, dimension: Dimension) -> usize {
        (0..dimension.count())
            .map(|a| ((self.upper[a] - self.lower[a]) / self.spacing + 1e-9).floor() as usize)
            .product::<usize>()
            .min(self.count)
    }

    /// Root-mean-square speed of the grains of the last batch (collective).
    fn last_batch_speed(&self, system: &DemSystem) -> f64 {
        let p = &system.particles;
        let (mut sum, mut count) = (0.0, 0usize);
        for k in (0..p.n_owned).filter(|&k| self.progress.last_batch.contains(&p.id[k])) {
            sum += p.velocity[k].norm_squared();
            count += 1;
        }
        let c = &system.communicator;
        (c.sum(sum) / c.sum_count(count).max(1) as f64).sqrt()
    }

    /// Draws the next batch, lifts it above the deposit and adds it.
    fn release(&mut self, system: &mut DemSystem) -> Result<String, String> {
        let dimension = system.dimension();
        let up = -system.domain.gravity.normalize();
        let mut batch = generate::lattice(
            dimension,
            self.lower,
            self.upper,
            Vec3::repeat(self.spacing),
            self.radii,
            self.jitter,
            &self.material,
            &mut self.progress.rng,
        );
        // The last batch keeps its lowest sites.
        batch.sort_by(|a, b| a.position.dot(&up).total_cmp(&b.position.dot(&up)));
        batch.truncate(self.count - self.progress.poured);

        let p = &system.particles;
        let highest = (0..p.n_owned)
            .filter(|&k| !p.is_fixed(k))
            .map(|k| p.position[k].dot(&up) + p.radius[k])
            .fold(f64::MIN, f64::max);
        let highest = system.communicator.max(highest);
        let bottom = batch
            .iter()
            .map(|g| g.position.dot(&up) - g.radius)
            .fold(f64::MAX, f64::min);
        let lift = (highest + self.gap - bottom).max(0.0);
        for grain in &mut batch {
            grain.position += lift * up;
        }
        let d = &system.domain;
        for grain in &batch {
            let outside = (0..dimension.count()).any(|a| {
                !d.periodic[a] && (grain.position[a] < d.lower[a] || grain.position[a] > d.upper[a])
            });
            if outside {
                return Err(format!(
                    "at t = {:.6e} s particles.pour[{}] has no room for its next batch: the \
                     deposit reaches {highest:.4} m along −g and the batch would leave the domain \
                     (a grain at {:?}); {} of {} grains poured; allowed: a domain that holds the \
                     whole deposit plus a batch (raise domain.upper) or a smaller count",
                    system.time,
                    self.index,
                    grain.position.as_slice(),
                    self.progress.poured,
                    self.count
                ));
            }
        }
        let first_id = system.next_id();
        system.add_particles_in_groups(&batch, &vec![self.group; batch.len()]);
        self.progress.last_batch = first_id..system.next_id();
        self.progress.poured += batch.len();
        self.progress.batches += 1;
        // A pour that waits for the deposit to settle counts its interval
        // from the actual release.
        self.progress.next_release = match self.settled_speed {
            Some(_) => system.time + self.interval,
            None => self.progress.next_release + self.interval,
        };
        Ok(format!(
            "t = {:.6e} s: particles.pour[{}] batch {}: {} grains, lowest surface at {:.4} m \
             along −g; {} of {} poured",
            system.time,
            self.index,
            self.progress.batches,
            batch.len(),
            bottom + lift,
            self.progress.poured,
            self.count
        ))
    }
}

/// How far one pour has gone: what a checkpoint keeps of it.
#[derive(serde::Serialize, serde::Deserialize)]
struct PourProgress {
    /// Grains released so far, and in how many batches.
    poured: usize,
    /// Ids of the grains of the last batch.
    last_batch: std::ops::Range<u64>,
    batches: usize,
    next_release: f64,
    /// The pour's own stream, the same on every rank.
    rng: Pcg64,
}

impl Pouring {
    /// Saves how far each pour has gone, its random stream included.
    pub fn save_state(&self, state: &mut grainflow_core::State) {
        let progress: Vec<&PourProgress> = self.pours.iter().map(|p| &p.progress).collect();
        state.put_value("pouring", &progress);
    }

    pub fn restore_state(
        &mut self,
        state: &mut grainflow_core::State,
    ) -> Result<(), grainflow_core::StateError> {
        let progress: Vec<PourProgress> = state.take_value("pouring")?;
        if progress.len() != self.pours.len() {
            return Err(grainflow_core::StateError(format!(
                "the checkpoint holds {} pours, the case {}",
                progress.len(),
                self.pours.len()
            )));
        }
        for (pour, p) in self.pours.iter_mut().zip(progress) {
            pour.progress = p;
        }
        Ok(())
    }
}

/// The scene's pours, with the batches due at t = 0 released into
/// `system` (before its time step is chosen, so that the lightest poured
/// grain counts). Returns the log lines of the releases.
pub fn start(case: &Case, system: &mut DemSystem) -> Result<(Pouring, Vec<String>), String> {
    let mut pouring = Pouring::new(case);
    let mut lines = pouring.describe(domain(case).dimension);
    lines.extend(pouring.release_due(system)?);
    Ok((pouring, lines))
}
