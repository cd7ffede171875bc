//! Initial particle placement: lattices, random non-overlapping fills (the
//! start of a sedimentation), with uniformly spread radii from a seeded
//! generator so that a case is reproducible.

use crate::neighbours::CellGrid;
use crate::particles::NewParticle;
use grainflow_core::{Dimension, Vec3};
use rand::Rng;
use rand_pcg::Pcg64;

/// Radius drawn uniformly in [r (1 − spread), r (1 + spread)].
#[derive(Clone, Copy, Debug)]
pub struct RadiusDistribution {
    pub mean: f64,
    pub spread: f64,
}

impl RadiusDistribution {
    pub fn sample(&self, rng: &mut Pcg64) -> f64 {
        if self.spread == 0.0 {
            self.mean
        } else {
            self.mean * (1.0 + self.spread * (2.0 * rng.gen::<f64>() - 1.0))
        }
    }

    pub fn max(&self) -> f64 {
        self.mean * (1.0 + self.spread)
    }
}

/// Common material of generated particles.
#[derive(Clone, Copy, Debug)]
pub struct Material {
    pub density: f64,
    pub fixed: bool,
    pub velocity: Vec3,
}

fn particle(position: Vec3, radius: f64, material: &Material) -> NewParticle {
    NewParticle {
        position,
        velocity: material.velocity,
        angular_velocity: Vec3::zeros(),
        radius,
        density: material.density,
        fixed: material.fixed,
    }
}

/// Particles on a rectangular lattice of spacing `spacing` (per axis)
/// filling `[lower, upper]`, each displaced at random by up to `jitter`
/// times the free room of its site.
#[allow(clippy::too_many_arguments)]
pub fn lattice(
    dimension: Dimension,
    lower: Vec3,
    upper: Vec3,
    spacing: Vec3,
    radii: RadiusDistribution,
    jitter: f64,
    material: &Material,
    rng: &mut Pcg64,
) -> Vec<NewParticle> {
    let mut counts = [1usize; 3];
    for axis in 0..dimension.count() {
        counts[axis] = (((upper[axis] - lower[axis]) / spacing[axis]) + 1e-9)
            .floor()
            .max(0.0) as usize;
    }
    let mut out = Vec::with_capacity(counts.iter().product());
    for k in 0..counts[2] {
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                let radius = radii.sample(rng);
                let site = Vec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5);
                let mut x = lower + site.component_mul(&spacing);
                for axis in 0..dimension.count() {
                    let room = (0.5 * spacing[axis] - radius).max(0.0) * jitter;
                    x[axis] += room * (2.0 * rng.gen::<f64>() - 1.0);
                }
                if dimension == Dimension::Two {
                    x.z = 0.0;
                }
                out.push(particle(x, radius, material));
            }
        }
    }
    out
}

/// `count` particles placed at random in `[lower, upper]` without overlap
/// with each other or with `existing` (random sequential addition).
/// Fails when the region is too full to place them.
#[allow(clippy::too_many_arguments)]
pub fn random(
    dimension: Dimension,
    lower: Vec3,
    upper: Vec3,
    count: usize,
    radii: RadiusDistribution,
    material: &Material,
    existing: &[NewParticle],
    rng: &mut Pcg64,
) -> Result<Vec<NewParticle>, String> {
    let r_max = radii
        .max()
        .max(existing.iter().map(|p| p.radius).fold(0.0, f64::max));
    let mut grid_upper = upper;
    let mut grid_lower = lower;
    if dimension == Dimension::Two {
        grid_lower.z = 0.0;
        grid_upper.z = 0.0;
    }
    let grid = CellGrid::new(
        dimension,
        grid_lower,
        grid_upper,
        2.0 * r_max,
        4 * (count + existing.len()) + 4096,
    );
    let mut cells: Vec<Vec<usize>> = vec![Vec::new(); grid.len()];
    let mut placed: Vec<NewParticle> = Vec::with_capacity(count);
    let inside = |x: &Vec3| {
        (0..dimension.count()).all(|a| x[a] >= lower[a] - r_max && x[a] <= upper[a] + r_max)
    };
    let mut all: Vec<(Vec3, f64)> = Vec::new();
    for p in existing.iter().filter(|p| inside(&p.position)) {
        let c = grid.index(grid.coordinates(&p.position));
        cells[c].push(all.len());
        all.push((p.position, p.radius));
    }
    let attempts_per_particle = 2000;
    for n in 0..count {
        let radius = radii.sample(rng);
        let mut success = false;
        for _ in 0..attempts_per_particle {
            let mut x = Vec3::zeros();
            for axis in 0..dimension.count() {
                let lo = lower[axis] + radius;
                let hi = upper[axis] - radius;
                if hi < lo {
                    return Err(format!(
                        "the region is narrower than a particle along axis {axis}"
                    ));
                }
                x[axis] = lo + (hi - lo) * rng.gen::<f64>();
            }
            let c = grid.coordinates(&x);
            let mut free = true;
            'search: for cz in c[2].saturating_sub(1)..=(c[2] + 1).min(grid.counts[2] - 1) {
                for cy in c[1].saturating_sub(1)..=(c[1] + 1).min(grid.counts[1] - 1) {
                    for cx in c[0].saturating_sub(1)..=(c[0] + 1).min(grid.counts[0] - 1) {
                        for &other in &cells[grid.index([cx, cy, cz])] {
                            let (y, r) = all[other];
                            if (x - y).norm() < radius + r {
                                free = false;
                                break 'search;
                            }
                        }
                    }
                }
            }
            if free {
                cells[grid.index(c)].push(all.len());
                all.push((x, radius));
                placed.push(particle(x, radius, material));
                success = true;
                break;
            }
        }
        if !success {
            return Err(format!(
                "could place only {n} of {count} particles without overlap: enlarge the region or lower the count"
            ));
        }
    }
    Ok(placed)
}
