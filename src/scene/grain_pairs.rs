//! Pairs of grains closer than a given surface gap, found through bins:
//! what the scene checks and the analyses need before or beside the DEM's
//! own neighbour lists (placed grains that are not yet a system, grains
//! gathered from every rank).

use grainflow_core::{Domain, Vec3};
use std::collections::HashMap;

/// A pair of grains and the gap between their surfaces (negative where
/// they overlap).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearPair {
    pub pair: [usize; 2],
    pub gap: f64,
}

/// Every pair `i < j` of the grains (`centres`, `radii`) whose surfaces
/// are less than `within` apart (0: the overlapping pairs), through bins of
/// the largest diameter plus `within`; along a periodic axis of `domain`
/// the nearest image counts.
pub fn near_pairs(domain: &Domain, centres: &[Vec3], radii: &[f64], within: f64) -> Vec<NearPair> {
    let dim = domain.dimension.count();
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    let bin = 2.0 * r_max + within.max(0.0);
    if centres.len() < 2 || bin <= 0.0 {
        return Vec::new();
    }
    let extent = domain.extent();
    let bins = [0, 1, 2].map(|a| {
        if a < dim {
            ((extent[a] / bin).floor() as i64).max(1)
        } else {
            1
        }
    });
    let bin_of = |x: &Vec3| {
        [0, 1, 2].map(|a| {
            if a < dim {
                (((x[a] - domain.lower[a]) / bin).floor() as i64).clamp(0, bins[a] - 1)
            } else {
                0
            }
        })
    };
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (k, x) in centres.iter().enumerate() {
        grid.entry(bin_of(x)).or_default().push(k);
    }
    let reach = |a: usize| if a < dim { -1..=1 } else { 0..=0 };
    let mut found = Vec::new();
    for (k, x) in centres.iter().enumerate() {
        let home = bin_of(x);
        let mut seen = Vec::new();
        for dz in reach(2) {
            for dy in reach(1) {
                for dx in reach(0) {
                    let mut cell = [home[0] + dx, home[1] + dy, home[2] + dz];
                    let mut outside = false;
                    for a in 0..dim {
                        if domain.periodic[a] {
                            cell[a] = cell[a].rem_euclid(bins[a]);
                        } else {
                            outside |= cell[a] < 0 || cell[a] >= bins[a];
                        }
                    }
                    // A short periodic axis wraps onto the same bin twice.
                    if outside || seen.contains(&cell) {
                        continue;
                    }
                    seen.push(cell);
                    for &other in grid.get(&cell).into_iter().flatten() {
                        if other <= k {
                            continue;
                        }
                        let mut offset = centres[other] - x;
                        for a in 0..dim {
                            if domain.periodic[a] {
                                offset[a] -= extent[a] * (offset[a] / extent[a]).round();
                            }
                        }
                        let gap = offset.norm() - radii[k] - radii[other];
                        if gap < within {
                            found.push(NearPair {
                                pair: [k, other],
                                gap,
                            });
                        }
                    }
                }
            }
        }
    }
    found
}
