//! The process grid of grains: how many boxes along each axis, and where
//! they end.
//!
//! A scene on `size` ranks is cut into `n_x × n_y × n_z = size` boxes. The
//! choice follows three rules ([`process_grid`]): every box at least one
//! interaction range wide along a split axis (a ghost then comes from the
//! next box only); among the grids allowed, those whose busiest box holds
//! the fewest grains at the start; among these, the least area of cuts
//! (the ghosts, hence the messages, scale with it).
//!
//! Boxes of equal lengths share the grains well only where they fill the
//! domain. A column at rest in the lower half of its domain, cut across
//! its height into equal halves, leaves the upper rank idle, so the equal
//! grid cuts it along its height instead, through every layer of grains:
//! a longer cut, more ghosts and, for hard contact, a separator twice as
//! large (the 2D packing of 50,000 discs: 831 unknowns against 408).
//! [`balanced_process_grid`] places the cuts among the grains along each
//! split axis instead, so that every box has the same interior to
//! factorise (its grains less the layer along its lower cut, which the
//! ranks factorise together), and then the least area of cuts decides
//! alone. The flow's grid, whose boxes must be those of its cells, keeps
//! equal lengths.

use crate::domain::{BoxCuts, Domain, Subdomain};
use crate::Vec3;

/// A process grid: `ranks` boxes along each axis, ending at `cuts` (equal
/// lengths along an axis without cuts).
#[derive(Clone, Debug, PartialEq)]
pub struct ProcessGrid {
    pub ranks: [usize; 3],
    pub cuts: BoxCuts,
}

impl ProcessGrid {
    /// `ranks` boxes of equal lengths along each axis.
    pub fn even(ranks: [usize; 3]) -> Self {
        ProcessGrid {
            ranks,
            cuts: BoxCuts::default(),
        }
    }

    /// Number of ranks.
    pub fn rank_count(&self) -> usize {
        self.ranks.iter().product()
    }

    /// The box of `rank`.
    pub fn subdomain(&self, domain: &Domain, rank: usize) -> Subdomain {
        Subdomain::of_rank_cut(domain, self.ranks, &self.cuts, rank)
    }

    /// How many of `positions` each box owns, by rank.
    pub fn grains_per_box(&self, domain: &Domain, positions: &[Vec3]) -> Vec<usize> {
        let grid = self.subdomain(domain, 0);
        let mut counts = vec![0usize; self.rank_count()];
        for x in positions {
            let mut x = *x;
            domain.wrap(&mut x);
            counts[grid.owner(domain, &x)] += 1;
        }
        counts
    }

    /// Whether every box is at least `min_width` wide along every split
    /// axis.
    pub fn fits(&self, domain: &Domain, min_width: f64) -> bool {
        (0..3).all(|axis| {
            let n = self.ranks[axis];
            if n == 1 {
                return true;
            }
            let at = &self.cuts[axis];
            if at.is_empty() {
                return domain.extent()[axis] / n as f64 >= min_width;
            }
            boxes_at_least(domain.lower[axis], at, domain.upper[axis], min_width)
        })
    }

    /// Where each axis's boxes end, for a log line ([`describe_cuts`]).
    pub fn describe_cuts(&self) -> String {
        describe_cuts(&self.cuts)
    }
}

/// Where each axis's boxes end, `x = …; y = …` (empty for equal lengths).
pub fn describe_cuts(cuts: &BoxCuts) -> String {
    let names = ["x", "y", "z"];
    (0..3)
        .filter(|&axis| !cuts[axis].is_empty())
        .map(|axis| {
            let at: Vec<String> = cuts[axis].iter().map(|c| format!("{c:.4e}")).collect();
            format!("{} = {}", names[axis], at.join(", "))
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Whether the boxes from `lower` to `upper`, ending at `cuts`, are each
/// at least `min_width` long.
fn boxes_at_least(lower: f64, cuts: &[f64], upper: f64, min_width: f64) -> bool {
    let ends: Vec<f64> = std::iter::once(lower)
        .chain(cuts.iter().copied())
        .chain(std::iter::once(upper))
        .collect();
    ends.windows(2).all(|w| w[1] - w[0] >= min_width)
}

/// The process grid for `size` ranks in boxes of equal lengths: among the
/// factorisations n_x n_y n_z = size (n_z = 1 in 2D) whose boxes are at
/// least `min_width` wide along every split axis, those whose busiest box
/// holds the fewest of the grains at `positions` (within 2 %: the work is
/// shared), and among them the one with the least area of cuts between
/// boxes. Ties go to the first in (n_x, n_y, n_z) order.
pub fn process_grid(
    domain: &Domain,
    size: usize,
    min_width: f64,
    positions: &[Vec3],
) -> Result<[usize; 3], String> {
    choose(
        domain,
        size,
        min_width,
        positions,
        domain.extent(),
        ProcessGrid::even,
    )
    .map(|grid| grid.ranks)
}

/// The grains a process grid shares under hard contact: their centres and
/// radii, and the gap below which two grains pair (the contact candidates'
/// threshold), which decides the grains along a cut that join the ranks'
/// separator.
#[derive(Clone, Copy, Debug)]
pub struct PairedGrains<'a> {
    pub centres: &'a [Vec3],
    pub radii: &'a [f64],
    pub pairing_gap: f64,
}

impl PairedGrains<'_> {
    /// The farthest two centres can be and still pair.
    fn reach(&self) -> f64 {
        let largest = self.radii.iter().copied().fold(0.0, f64::max);
        2.0 * largest + self.pairing_gap.max(0.0)
    }

    /// How many grains at or above `cut` along `axis` (the higher box's
    /// side) pair with a grain below it: |x_i − x_j| − r_i − r_j below the
    /// pairing gap. `reach` is [`PairedGrains::reach`], taken once by the
    /// caller; `order` lists the grains by their coordinate along `axis`,
    /// `along` those coordinates in that order. The grains below
    /// within reach of the cut are binned on the other two axes, so that
    /// each grain above looks at its 3 × 3 bins only.
    fn joining_above(
        &self,
        axis: usize,
        cut: f64,
        reach: f64,
        order: &[usize],
        along: &[f64],
    ) -> usize {
        if reach <= 0.0 {
            return 0;
        }
        let at = |x: f64| along.partition_point(|&a| a < x);
        let (low, split, high) = (at(cut - reach), at(cut), at(cut + reach));
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let bin = |k: usize| {
            let x = self.centres[k];
            ((x[u] / reach).floor() as i64, (x[v] / reach).floor() as i64)
        };
        let mut below: std::collections::HashMap<(i64, i64), Vec<usize>> =
            std::collections::HashMap::new();
        for &k in &order[low..split] {
            below.entry(bin(k)).or_default().push(k);
        }
        order[split..high]
            .iter()
            .filter(|&&i| {
                let (bu, bv) = bin(i);
                (-1..=1).any(|du| {
                    (-1..=1).any(|dv| {
                        below.get(&(bu + du, bv + dv)).is_some_and(|cell| {
                            cell.iter().any(|&j| {
                                let gap = (self.centres[i] - self.centres[j]).norm()
                                    - self.radii[i]
                                    - self.radii[j];
                                gap < self.pairing_gap
                            })
                        })
                    })
                })
            })
            .count()
    }
}

/// The process grid for `size` ranks with its cuts among the grains along
/// each split axis that is not periodic, chosen by the rules of
/// [`process_grid`] with the cuts at the grains' quantiles (each single cut
/// then shares the grains evenly, and the least area of cuts decides
/// between grids that do so alike), then moved so that along each axis the
/// boxes' interiors match ([`balanced_cuts`]); the area of a cut is taken
/// over the box that holds the grains (each side at least `min_width`),
/// which is where a cut meets them.
pub fn balanced_process_grid(
    domain: &Domain,
    size: usize,
    min_width: f64,
    grains: &PairedGrains,
) -> Result<ProcessGrid, String> {
    let positions = grains.centres;
    let mut extent = domain.extent();
    if !positions.is_empty() {
        for axis in 0..3 {
            let (low, high) = positions.iter().fold((f64::MAX, f64::MIN), |(l, h), x| {
                (l.min(x[axis]), h.max(x[axis]))
            });
            extent[axis] = (high - low).max(min_width);
        }
    }
    let chosen = choose(domain, size, min_width, positions, extent, |ranks| {
        ProcessGrid {
            ranks,
            cuts: cuts_among(domain, ranks, min_width, grains, false),
        }
    })?;
    Ok(ProcessGrid {
        ranks: chosen.ranks,
        cuts: balanced_cuts(domain, chosen.ranks, min_width, grains),
    })
}

/// The cuts of a process grid of `ranks` boxes along each split axis that
/// is not periodic, placed among the grains so that every box's interior
/// holds as many grains ([`cuts_sharing_interiors`]); equal lengths along
/// an axis where that would leave a box narrower than `min_width`, with
/// fewer grains than boxes, or periodic.
pub fn balanced_cuts(
    domain: &Domain,
    ranks: [usize; 3],
    min_width: f64,
    grains: &PairedGrains,
) -> BoxCuts {
    cuts_among(domain, ranks, min_width, grains, true)
}

/// [`balanced_cuts`], the grains that pair across each cut from above
/// left out of the interiors where `separators` (else the grains'
/// quantiles).
fn cuts_among(
    domain: &Domain,
    ranks: [usize; 3],
    min_width: f64,
    grains: &PairedGrains,
    separators: bool,
) -> BoxCuts {
    let positions = grains.centres;
    let reach = grains.reach();
    let mut cuts = BoxCuts::default();
    for axis in 0..3 {
        let n = ranks[axis];
        if n == 1 || domain.periodic[axis] || positions.len() < n {
            continue;
        }
        let coordinate =
            |k: usize| positions[k][axis].clamp(domain.lower[axis], domain.upper[axis]);
        let mut order: Vec<usize> = (0..positions.len()).collect();
        order.sort_by(|&a, &b| coordinate(a).total_cmp(&coordinate(b)));
        let along: Vec<f64> = order.iter().map(|&k| coordinate(k)).collect();
        let at = cuts_sharing_interiors(&along, n, |cut| match separators {
            true => grains.joining_above(axis, cut, reach, &order, &along),
            false => 0,
        });
        if boxes_at_least(domain.lower[axis], &at, domain.upper[axis], min_width) {
            cuts[axis] = at;
        }
    }
    cuts
}

/// The n − 1 cuts among the sorted coordinates `along` that leave each of
/// n boxes the same interior: a box's grains less those above its lower
/// cut that join the separator, `joining_above(cut)` of them. Under hard
/// contact the ranks factorise their interiors apart and the grains along
/// each cut together, the higher box's grains that pair across it being
/// that separator (`grainflow_contact::shared_program`), so each box then
/// has as much to factorise; cut at the plain quantiles, the lowest box of
/// a 3D packing on two ranks held 4,374 grains to factorise against the
/// other's 4,009, and took 1.2 times as long. Each cut lies midway between
/// the two grains on either side of its count: box k holds the interior I
/// and the separator above cut k − 1, with I = (N − Σ separators)/n, the
/// separators counted at the last cuts (a fixed point reached in a few
/// rounds; plain quantiles where none joins). Counted exactly, not as a
/// layer one interaction range wide: on that packing such a layer held 556
/// grains where 361 joined the separator, and the interiors came out 5 %
/// apart (docs/cluster.md).
fn cuts_sharing_interiors(
    along: &[f64],
    n: usize,
    joining_above: impl Fn(f64) -> usize,
) -> Vec<f64> {
    let count = along.len();
    let midway = |split: usize| {
        let split = split.clamp(1, count - 1);
        0.5 * (along[split - 1] + along[split])
    };
    let mut at: Vec<f64> = (1..n).map(|k| midway(count * k / n)).collect();
    for _ in 0..8 {
        let joined: usize = at.iter().map(|&c| joining_above(c)).sum();
        let interior = count.saturating_sub(joined) as f64 / n as f64;
        let (mut reached, mut next) = (0.0, Vec::with_capacity(n - 1));
        for _ in 1..n {
            reached += interior;
            let cut = midway(reached.round() as usize);
            reached += joining_above(cut) as f64;
            next.push(cut);
        }
        if next == at {
            break;
        }
        at = next;
    }
    at
}

/// The grid among the factorisations of `size` (each given its cuts by
/// `grid_of`) by the rules of [`process_grid`], the area of a cut taken
/// over the sides `extent`.
fn choose(
    domain: &Domain,
    size: usize,
    min_width: f64,
    positions: &[Vec3],
    extent: Vec3,
    grid_of: impl Fn([usize; 3]) -> ProcessGrid,
) -> Result<ProcessGrid, String> {
    let dims = domain.dimension.count();
    let mut feasible: Vec<(usize, f64, ProcessGrid)> = Vec::new();
    for nx in (1..=size).filter(|&n| size.is_multiple_of(n)) {
        for ny in (1..=size / nx).filter(|&n| (size / nx).is_multiple_of(n)) {
            let nz = size / nx / ny;
            let ranks = [nx, ny, nz];
            if dims == 2 && nz > 1 {
                continue;
            }
            let grid = grid_of(ranks);
            if !grid.fits(domain, min_width) {
                continue;
            }
            let mut area = 0.0;
            for (axis, &n) in ranks.iter().enumerate().take(dims) {
                let cuts = match (n, domain.periodic[axis]) {
                    (1, _) => 0,
                    (n, true) => n,
                    (n, false) => n - 1,
                };
                let face: f64 = (0..dims)
                    .filter(|&b| b != axis)
                    .map(|b| extent[b])
                    .product();
                area += cuts as f64 * face;
            }
            let busiest = grid
                .grains_per_box(domain, positions)
                .into_iter()
                .max()
                .unwrap_or(0);
            feasible.push((busiest, area, grid));
        }
    }
    let least_load = feasible.iter().map(|f| f.0).min().unwrap_or(0);
    let balanced = |load: usize| load as f64 <= 1.02 * least_load as f64;
    let mut best: Option<(f64, ProcessGrid)> = None;
    for (load, area, grid) in feasible {
        if balanced(load) && best.as_ref().is_none_or(|(a, _)| area < *a) {
            best = Some((area, grid));
        }
    }
    best.map(|(_, grid)| grid).ok_or_else(|| {
        format!(
            "{size} ranks cannot split the domain into boxes at least one interaction range \
             ({min_width:.3e} m) wide along every split axis; allowed: fewer ranks"
        )
    })
}

/// How many of `positions` each box of a process grid of equal lengths
/// owns, by rank.
pub fn grains_per_box(domain: &Domain, ranks: [usize; 3], positions: &[Vec3]) -> Vec<usize> {
    ProcessGrid::even(ranks).grains_per_box(domain, positions)
}

/// Whether boxes of equal lengths are at least `min_width` wide along
/// every split axis (a ghost then comes from the next box only).
pub fn fits(domain: &Domain, ranks: [usize; 3], min_width: f64) -> bool {
    ProcessGrid::even(ranks).fits(domain, min_width)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::test_support::{assert_one_owner_each, column};
    use crate::Dimension;

    /// The least area of cuts: a long flat box is cut across its length;
    /// a periodic axis counts one more cut than a walled one.
    #[test]
    fn the_process_grid_cuts_the_least_area() {
        let domain = column(true);
        assert_eq!(process_grid(&domain, 1, 0.01, &[]).unwrap(), [1, 1, 1]);
        // Cuts across x: 0.12 m² each; across z: 0.48 m²; across y: 4 m².
        assert_eq!(process_grid(&domain, 2, 0.01, &[]).unwrap(), [2, 1, 1]);
        assert_eq!(process_grid(&domain, 4, 0.01, &[]).unwrap(), [4, 1, 1]);
        assert_eq!(process_grid(&domain, 6, 0.01, &[]).unwrap(), [6, 1, 1]);
        // Boxes narrower than the range are not allowed: with a range of
        // 0.7 m, x takes at most 5 ranks, z and y one.
        assert_eq!(process_grid(&domain, 4, 0.7, &[]).unwrap(), [4, 1, 1]);
        let refused = process_grid(&domain, 6, 0.7, &[]).unwrap_err();
        assert!(refused.contains("6 ranks"), "{refused}");
        // A tall box is cut across its height.
        let tall = Domain {
            upper: Vec3::new(-1.9, 0.12, 1.0),
            ..domain.clone()
        };
        assert_eq!(process_grid(&tall, 2, 0.01, &[]).unwrap(), [1, 1, 2]);
        // Grains in the lower third of the tall box: a cut across the
        // height would leave a rank idle, so x is cut instead.
        let low: Vec<Vec3> = (0..100)
            .map(|k| Vec3::new(-2.0 + 0.001 * k as f64, 0.06, 0.003 * k as f64))
            .collect();
        assert_eq!(process_grid(&tall, 2, 0.01, &low).unwrap(), [2, 1, 1]);
        assert!(!fits(&domain, [1, 2, 1], 0.07));
        assert!(fits(&domain, [1, 2, 1], 0.06));
    }

    /// A tall box whose grains fill its lower third: boxes of equal
    /// lengths must be cut along the height (a cut across it would leave a
    /// rank idle); with the cuts among the grains the cut across
    /// the height, the shorter one, shares them evenly and is chosen.
    #[test]
    fn cuts_among_the_grains_share_a_low_column_across_its_height_interior_for_interior() {
        let tall = Domain {
            upper: Vec3::new(-1.9, 0.12, 1.0),
            ..column(false)
        };
        let low: Vec<Vec3> = (0..100)
            .map(|k| Vec3::new(-2.0 + 0.001 * k as f64, 0.06, 0.003 * k as f64))
            .collect();
        // Neighbours 3.16 mm apart, radii 1.5 mm: each grain pairs with the
        // next (gap 0.16 mm below 0.2 mm), not the one after.
        let radii = vec![1.5e-3; low.len()];
        let paired = PairedGrains {
            centres: &low,
            radii: &radii,
            pairing_gap: 2e-4,
        };
        assert_eq!(process_grid(&tall, 2, 0.01, &low).unwrap(), [2, 1, 1]);
        let grid = balanced_process_grid(&tall, 2, 0.01, &paired).unwrap();
        assert_eq!(grid.ranks, [1, 1, 2]);
        // One grain above the cut pairs across it: the interiors
        // (100 − 1)/2 = 49.5, rounded to 50 below; the cut midway between
        // the 50th and 51st grains' heights.
        assert_eq!(grid.cuts[2].len(), 1);
        assert!((grid.cuts[2][0] - 0.1485).abs() < 1e-12, "{:?}", grid.cuts);
        assert_eq!(grid.grains_per_box(&tall, &low), vec![50, 50]);
        // Four ranks, across the height: each box's interior 24 or 25
        // grains, the three higher boxes holding one more that pairs below.
        let four = balanced_process_grid(&tall, 4, 0.01, &paired).unwrap();
        assert_eq!(four.ranks, [1, 1, 4]);
        let held = four.grains_per_box(&tall, &low);
        let interiors: Vec<usize> = held
            .iter()
            .enumerate()
            .map(|(k, &h)| if k == 0 { h } else { h - 1 })
            .collect();
        assert!(
            interiors.iter().all(|&i| (24..=25).contains(&i)),
            "{held:?}"
        );
        // Without a separator the cuts are the quantiles: 25 grains each.
        let mut heights: Vec<f64> = low.iter().map(|x| x.z).collect();
        heights.sort_by(f64::total_cmp);
        let quantiles = cuts_sharing_interiors(&heights, 4, |_| 0);
        assert_eq!(quantiles.len(), 3);
        for (k, cut) in quantiles.iter().enumerate() {
            let expected = 0.5 * (heights[25 * (k + 1) - 1] + heights[25 * (k + 1)]);
            assert!((cut - expected).abs() < 1e-15, "{quantiles:?}");
        }
        // A quantile cut that would leave a box narrower than the range
        // falls back to equal lengths on that axis.
        let narrow = balanced_cuts(&tall, [1, 1, 2], 0.9, &paired);
        assert!(narrow[2].is_empty(), "{narrow:?}");
        // Periodic axes keep equal lengths.
        let periodic = Domain {
            periodic: [false, false, true],
            ..tall.clone()
        };
        assert!(balanced_cuts(&periodic, [1, 1, 2], 0.01, &paired)[2].is_empty());
    }

    /// A jittered 3D packing of 2,000 grains of unequal radii cut in two:
    /// the grains above the cut that pair with one below (counted here
    /// pair by pair) join the separator, and the two interiors come out
    /// within two grains of each other.
    #[test]
    fn a_packing_cut_in_two_leaves_equal_interiors_once_the_separator_is_out() {
        let domain = Domain {
            dimension: Dimension::Three,
            lower: Vec3::zeros(),
            upper: Vec3::new(0.01, 0.01, 0.04),
            periodic: [false; 3],
            gravity: Vec3::zeros(),
        };
        // 10 × 10 × 20 sites 1 mm apart, jittered by up to ±0.15 mm; radii
        // 0.40–0.48 mm (a linear congruential sequence: no dependency).
        let mut seed = 12_345u64;
        let mut uniform = move || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut centres, mut radii) = (Vec::new(), Vec::new());
        for k in 0..2000 {
            let site = [k % 10, (k / 10) % 10, k / 100];
            centres.push(Vec3::from_fn(|a, _| {
                1e-3 * (site[a] as f64 + 0.5) + 3e-4 * (uniform() - 0.5)
            }));
            radii.push(4e-4 + 8e-5 * uniform());
        }
        let gap = 1e-4;
        let paired = PairedGrains {
            centres: &centres,
            radii: &radii,
            pairing_gap: gap,
        };
        let grid = balanced_process_grid(&domain, 2, 2e-3, &paired).unwrap();
        assert_eq!(grid.ranks, [1, 1, 2], "{grid:?}");
        let cut = grid.cuts[2][0];
        let n = centres.len();
        let joined = (0..n)
            .filter(|&i| centres[i].z >= cut)
            .filter(|&i| {
                (0..n).any(|j| {
                    centres[j].z < cut
                        && (centres[i] - centres[j]).norm() - radii[i] - radii[j] < gap
                })
            })
            .count();
        let below = (0..n).filter(|&i| centres[i].z < cut).count();
        let above = n - below - joined;
        // Enough to matter: cut at the quantile, the interiors would be
        // `joined` apart (47 here).
        assert!(joined > 20, "{joined} grains pair across the cut");
        assert!(below.abs_diff(above) <= 2, "interiors {below} and {above}");
    }

    /// A flat packing at the bottom of a tall box is cut along its height,
    /// where a cut meets fewer grains, though the box's cross-section is
    /// the smaller face.
    #[test]
    fn the_cut_is_measured_where_it_meets_the_grains() {
        let tall = Domain {
            dimension: Dimension::Three,
            lower: Vec3::zeros(),
            upper: Vec3::new(1.0, 1.0, 4.0),
            periodic: [false; 3],
            gravity: Vec3::zeros(),
        };
        // 10 × 10 × 4 grains in the lowest 0.4 of the box.
        let flat: Vec<Vec3> = (0..400)
            .map(|k| {
                let (i, j, l) = (k % 10, (k / 10) % 10, k / 100);
                Vec3::new(
                    0.05 + 0.1 * i as f64,
                    0.05 + 0.1 * j as f64,
                    0.05 + 0.1 * l as f64,
                )
            })
            .collect();
        // Grains 0.1 apart of radius 0.04 do not pair at a gap of 0.01:
        // the cut is the quantile. Across x or y (0.27 of area each, the
        // first wins) rather than across z (0.81), the box's smallest face.
        let radii = vec![0.04; flat.len()];
        let paired = PairedGrains {
            centres: &flat,
            radii: &radii,
            pairing_gap: 0.01,
        };
        let grid = balanced_process_grid(&tall, 2, 0.01, &paired).unwrap();
        assert_eq!(grid.ranks, [1, 2, 1]);
        assert!((grid.cuts[1][0] - 0.5).abs() < 1e-12, "{:?}", grid.cuts);
        assert_eq!(grid.grains_per_box(&tall, &flat), vec![200, 200]);
    }

    /// Boxes ending at cuts tile the domain: every position has one owner,
    /// whose box holds it, a position on a cut belonging to the box above.
    #[test]
    fn boxes_ending_at_cuts_own_each_position_once() {
        let domain = column(true);
        let grid = ProcessGrid {
            ranks: [4, 2, 1],
            cuts: [vec![-1.5, -1.4, 0.7], Vec::new(), Vec::new()],
        };
        let boxes: Vec<Subdomain> = (0..8).map(|r| grid.subdomain(&domain, r)).collect();
        assert_eq!(boxes[1].lower.x, -1.5);
        assert_eq!(boxes[1].upper.x, -1.4);
        assert_eq!(boxes[3].upper.x, 2.0);
        let xs = [-2.5, -2.0, -1.5, -1.45, -1.4, 0.0, 0.7, 1.9, 2.5];
        assert_one_owner_each(&domain, &boxes, &xs);
        assert!(grid.fits(&domain, 0.05));
        assert!(!grid.fits(&domain, 0.2));
        assert_eq!(grid.describe_cuts(), "x = -1.5000e0, -1.4000e0, 7.0000e-1");
    }
}
