//! The shape of a granular mass on a floor: the grains that form one
//! deposit, its front and the mean height of its top.
//!
//! Discrete simulations of column collapses measure the runout at the
//! farthest grain still in contact with the main deposit, leaving out the
//! grains ejected ahead of it that came to rest alone (Staron & Hinch
//! 2005; Utili, Zhao & Houlsby 2015): what an experiment's camera would
//! call the front. Here a grain belongs to the deposit when a chain of
//! contacts links it to the largest connected mass, two grains being in
//! contact when the gap between their surfaces is below [`CONTACT_GAP`] of
//! a mean diameter: grains resting on one another overlap, and two that
//! came to rest side by side on the floor touch within that. A single
//! file of touching grains still counts; a grain that stopped alone, even
//! a fraction of a grain ahead, does not. (Linking grains through any gap
//! smaller than a grain instead let sparse grains ahead of a 3D front
//! percolate: the 3D runouts read 40–60 % longer at a ≈ 0.6–1.)

use crate::scene::grain_pairs::near_pairs;
use grainflow_core::{Domain, Vec3};

/// Two grains are in contact when their surfaces are less than this
/// fraction of a mean diameter apart.
pub const CONTACT_GAP: f64 = 0.05;

/// The grains of the largest mass connected through gaps smaller than
/// `link_gap` (indices into `centres`, in increasing order).
pub fn main_mass(domain: &Domain, centres: &[Vec3], radii: &[f64], link_gap: f64) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..centres.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    for near in near_pairs(domain, centres, radii, link_gap) {
        let (a, b) = (
            root(&mut parent, near.pair[0]),
            root(&mut parent, near.pair[1]),
        );
        if a != b {
            parent[a.max(b)] = a.min(b);
        }
    }
    let roots: Vec<usize> = (0..centres.len()).map(|k| root(&mut parent, k)).collect();
    let mut sizes = vec![0usize; centres.len()];
    for &r in &roots {
        sizes[r] += 1;
    }
    // The largest mass; the first in the grains' order among equals.
    let Some(largest) = (0..sizes.len()).max_by_key(|&r| (sizes[r], std::cmp::Reverse(r))) else {
        return Vec::new();
    };
    (0..centres.len())
        .filter(|&k| roots[k] == largest)
        .collect()
}

/// The front of `grains` on `side` (+1 or −1 along x) of `centre`: the
/// largest distance along x from `centre` reached by a grain's surface.
pub fn front(centres: &[Vec3], radii: &[f64], grains: &[usize], centre: f64, side: f64) -> f64 {
    grains
        .iter()
        .map(|&k| side * (centres[k].x - centre) + radii[k])
        .fold(0.0, f64::max)
}

/// The mean height above `floor` of the top of the grains whose centre
/// lies in `[from, to]` along x: the highest grain surface along
/// `vertical` in each cell of a grid `width` wide along x (and along
/// `spanwise` in 3D, over its whole extent `[0, length]` from its lower
/// end `start`), averaged over the cells that hold a grain. The top of a
/// column without the one grain that sits highest on it.
pub fn mean_top(
    centres: &[Vec3],
    radii: &[f64],
    [from, to]: [f64; 2],
    width: f64,
    vertical: usize,
    floor: f64,
    spanwise: Option<(usize, f64, f64)>,
) -> f64 {
    let cells = |length: f64| ((length / width).round() as usize).max(1);
    let along = cells(to - from);
    let across = spanwise.map_or(1, |(_, _, length)| cells(length));
    let mut top = vec![f64::NAN; along * across];
    for (x, r) in centres.iter().zip(radii) {
        if x.x < from || x.x > to {
            continue;
        }
        let i = (((x.x - from) / (to - from) * along as f64) as usize).min(along - 1);
        let j = spanwise.map_or(0, |(axis, start, length)| {
            (((x[axis] - start) / length * across as f64) as usize).min(across - 1)
        });
        let height = x[vertical] + r - floor;
        let cell = &mut top[i * across + j];
        if cell.is_nan() || height > *cell {
            *cell = height;
        }
    }
    let filled: Vec<f64> = top.into_iter().filter(|h| !h.is_nan()).collect();
    filled.iter().sum::<f64>() / filled.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow_core::Dimension;

    fn floor_2d() -> Domain {
        Domain {
            dimension: Dimension::Two,
            lower: Vec3::new(-10.0, 0.0, 0.0),
            upper: Vec3::new(10.0, 10.0, 0.0),
            periodic: [false; 3],
            gravity: Vec3::new(0.0, -9.81, 0.0),
        }
    }

    /// Unit discs in a row on the floor from x = 0.5, touching, then two
    /// more: one a fraction of a grain past the last, one a grain and a
    /// half past it.
    fn row_with_strays(gap_near: f64, gap_far: f64) -> (Vec<Vec3>, Vec<f64>) {
        let mut centres: Vec<Vec3> = (0..6)
            .map(|i| Vec3::new(0.5 + i as f64, 0.5, 0.0))
            .collect();
        let last = centres[5].x;
        centres.push(Vec3::new(last + 1.0 + gap_near, 0.5, 0.0));
        centres.push(Vec3::new(last + 2.0 + gap_near + gap_far, 0.5, 0.0));
        let radii = vec![0.5; centres.len()];
        (centres, radii)
    }

    #[test]
    fn the_front_is_the_farthest_grain_linked_to_the_main_mass() {
        // A gap of 0.3 grain links the seventh grain; 1.5 grains cut the eighth.
        let (centres, radii) = row_with_strays(0.3, 1.5);
        let mass = main_mass(&floor_2d(), &centres, &radii, 1.0);
        assert_eq!(mass, (0..7).collect::<Vec<_>>());
        let reached = front(&centres, &radii, &mass, 0.0, 1.0);
        assert!((reached - 7.3).abs() < 1e-12, "{reached}");
        // Touching grains only (a contact-connected mass) stop at the sixth.
        let touching = main_mass(&floor_2d(), &centres, &radii, 1e-9);
        assert_eq!(front(&centres, &radii, &touching, 0.0, 1.0), 6.0);
    }

    #[test]
    fn the_top_of_a_column_is_its_mean_surface_not_its_highest_grain() {
        // Ten columns of five unit discs, one disc perched on top.
        let mut centres: Vec<Vec3> = (0..10)
            .flat_map(|i| (0..5).map(move |j| Vec3::new(0.5 + i as f64, 0.5 + j as f64, 0.0)))
            .collect();
        centres.push(Vec3::new(4.5, 5.5, 0.0));
        let radii = vec![0.5; centres.len()];
        let top = mean_top(&centres, &radii, [0.0, 10.0], 1.0, 1, 0.0, None);
        assert!((top - 5.1).abs() < 1e-12, "{top}");
    }
}
