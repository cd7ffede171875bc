//! Grains that overlap as placed, before the first step.
//!
//! A moving grain that starts inside another is thrown out of it by the
//! whole elastic energy of the overlap in one contact time: with the
//! overlap of a badly placed explicit grain, the run would stop at its
//! first step on `time.overlap_limit`, or worse go on with a grain shot
//! across the scene. So such a scene is refused by its blocks. A deposit
//! at rest read from a file overlaps far less than the refusal's limit
//! (0.04 % of a radius in `cases/data/avalanche_bed.csv`). Glued grains
//! exert no force on each other, so overlaps between two of them are
//! only worth a warning (a rough bed built of interpenetrating grains).

use crate::scene::grain_pairs::near_pairs;
use grainflow_core::Domain;
use grainflow_dem::particles::NewParticle;
use std::ops::Range;

/// Largest overlap, as a fraction of the smaller radius, of two grains one
/// of which moves: beyond it the scene is refused.
pub const MOBILE_OVERLAP_LIMIT: f64 = 0.05;

/// Overlap of two glued grains, as a fraction of the smaller radius,
/// beyond which `check` warns: a lattice of touching grains is meant.
pub const GLUED_OVERLAP_WARNING: f64 = 0.01;

/// The deepest overlap of a pair of placed grains.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Overlap {
    pair: [usize; 2],
    /// Overlap over the smaller radius.
    depth: f64,
}

/// Refuses grains placed overlapping by more than
/// [`MOBILE_OVERLAP_LIMIT`] where one of the two moves, naming the blocks
/// (`blocks[k]` is the range of `placed` that `particles.block[k]` made);
/// returns a warning for glued grains that overlap each other.
pub fn check(
    domain: &Domain,
    placed: &[NewParticle],
    blocks: &[Range<usize>],
) -> Result<Option<String>, String> {
    let (mut mobile, mut glued): (Option<Overlap>, Option<Overlap>) = (None, None);
    for overlap in overlaps(domain, placed) {
        let deepest = if placed[overlap.pair[0]].fixed && placed[overlap.pair[1]].fixed {
            &mut glued
        } else {
            &mut mobile
        };
        if deepest.is_none_or(|d| overlap.depth > d.depth) {
            *deepest = Some(overlap);
        }
    }
    let name = |k: usize| {
        let block = blocks.iter().position(|b| b.contains(&k)).unwrap_or(0);
        format!(
            "particles.block[{block}] grain {} at {:?}",
            k - blocks.get(block).map_or(0, |b| b.start),
            &placed[k].position.as_slice()[..domain.dimension.count()]
        )
    };
    if let Some(o) = mobile.filter(|o| o.depth > MOBILE_OVERLAP_LIMIT) {
        return Err(format!(
            "{} and {} overlap by {:.1} % of the smaller radius: a moving grain placed inside \
             another is thrown out at the first step; allowed: overlaps of at most {} % where \
             a grain moves (place the grains apart, or glue both with fixed = true)",
            name(o.pair[0]),
            name(o.pair[1]),
            100.0 * o.depth,
            100.0 * MOBILE_OVERLAP_LIMIT
        ));
    }
    Ok(glued.filter(|o| o.depth > GLUED_OVERLAP_WARNING).map(|o| {
        format!(
            "warning: glued grains overlap, the deepest {} and {} by {:.1} % of the smaller \
             radius (glued grains exert no force on each other; a grain that lands there meets \
             their union)",
            name(o.pair[0]),
            name(o.pair[1]),
            100.0 * o.depth
        )
    }))
}

/// Every overlapping pair of `placed` ([`near_pairs`] within no gap).
fn overlaps(domain: &Domain, placed: &[NewParticle]) -> Vec<Overlap> {
    let centres: Vec<_> = placed.iter().map(|p| p.position).collect();
    let radii: Vec<f64> = placed.iter().map(|p| p.radius).collect();
    near_pairs(domain, &centres, &radii, 0.0)
        .into_iter()
        .map(|near| Overlap {
            pair: near.pair,
            depth: -near.gap / radii[near.pair[0]].min(radii[near.pair[1]]),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One block holding every grain.
    fn one_block() -> Vec<Range<usize>> {
        vec![Range {
            start: 0,
            end: usize::MAX,
        }]
    }
    use grainflow_core::{Dimension, Vec3};

    fn grain(x: f64, y: f64, fixed: bool) -> NewParticle {
        NewParticle {
            position: Vec3::new(x, y, 0.0),
            velocity: Vec3::zeros(),
            angular_velocity: Vec3::zeros(),
            radius: 1.0,
            density: 1.0,
            fixed,
        }
    }

    fn square(periodic: bool) -> Domain {
        Domain {
            dimension: Dimension::Two,
            lower: Vec3::zeros(),
            upper: Vec3::new(10.0, 10.0, 0.0),
            periodic: [periodic, false, false],
            gravity: Vec3::zeros(),
        }
    }

    #[test]
    fn a_moving_grain_placed_inside_another_is_refused_by_its_blocks() {
        let placed = [grain(2.0, 5.0, true), grain(3.9, 5.0, false)];
        let error = check(&square(false), &placed, &[0..1, 1..2]).unwrap_err();
        assert!(error.contains("particles.block[0] grain 0"), "{error}");
        assert!(error.contains("particles.block[1] grain 0"), "{error}");
        assert!(error.contains("10.0 %"), "{error}");
        // Within the limit (a deposit at rest) it passes without a word.
        let placed = [grain(2.0, 5.0, false), grain(3.96, 5.0, false)];
        assert_eq!(check(&square(false), &placed, &one_block()), Ok(None));
    }

    #[test]
    fn overlaps_across_a_periodic_boundary_count() {
        let placed = [grain(0.5, 5.0, false), grain(9.0, 5.0, false)];
        assert!(check(&square(true), &placed, &one_block()).is_err());
        assert_eq!(check(&square(false), &placed, &one_block()), Ok(None));
    }

    #[test]
    fn glued_grains_that_overlap_are_a_warning() {
        let placed = [
            grain(2.0, 5.0, true),
            grain(3.0, 5.0, true),
            grain(6.0, 5.0, false),
        ];
        let warning = check(&square(false), &placed, &one_block())
            .unwrap()
            .unwrap();
        assert!(warning.contains("100.0 %"), "{warning}");
    }
}
