//! The physical box of a scene and the part of it a rank owns.

use crate::Vec3;

/// 2D (discs in the x–y plane) or 3D (spheres).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dimension {
    Two,
    Three,
}

impl Dimension {
    pub fn count(self) -> usize {
        match self {
            Dimension::Two => 2,
            Dimension::Three => 3,
        }
    }
}

/// The global box `[lower, upper]` with a periodicity flag per axis.
/// In 2D the z extent is ignored and z is never periodic.
#[derive(Clone, Debug)]
pub struct Domain {
    pub dimension: Dimension,
    pub lower: Vec3,
    pub upper: Vec3,
    pub periodic: [bool; 3],
    pub gravity: Vec3,
}

impl Domain {
    pub fn extent(&self) -> Vec3 {
        self.upper - self.lower
    }

    /// The least of x·`up` over the box's corners: the height of its lowest
    /// corner along `up`, from which heights inside the box are never
    /// negative, whichever way gravity is tilted.
    pub fn lowest_along(&self, up: &Vec3) -> f64 {
        let (lo, hi) = (self.lower, self.upper);
        (0..8)
            .map(|c| {
                let corner = Vec3::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                );
                corner.dot(up)
            })
            .fold(f64::MAX, f64::min)
    }

    /// Wraps a position into the box along its periodic axes.
    pub fn wrap(&self, x: &mut Vec3) {
        let length = self.extent();
        for axis in 0..3 {
            if self.periodic[axis] {
                let offset = (x[axis] - self.lower[axis]).rem_euclid(length[axis]);
                x[axis] = self.lower[axis] + offset;
            }
        }
    }
}

/// Where the boxes of a process grid end inside the domain along each
/// axis: `ranks[axis] − 1` increasing positions, or none where the axis is
/// cut into equal lengths.
pub type BoxCuts = [Vec<f64>; 3];

/// The part of the domain a rank owns, in a Cartesian process grid of
/// `ranks[0] × ranks[1] × ranks[2]` boxes (of equal lengths along an axis
/// without cuts, else ending at the cuts): particles whose centre lies in
/// `[lower, upper)` are owned here (the ranks at the ends of an axis also
/// own what lies beyond the domain's faces); copies of others within the
/// interaction range are ghosts.
#[derive(Clone, Debug)]
pub struct Subdomain {
    pub lower: Vec3,
    pub upper: Vec3,
    /// Ranks along each axis.
    pub ranks: [usize; 3],
    /// This rank's position in the process grid.
    pub coords: [usize; 3],
    /// Where the boxes end along each axis (none: equal lengths).
    pub cuts: BoxCuts,
}

/// The lower or upper neighbour along an axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Lower,
    Upper,
}

impl Subdomain {
    /// The whole domain as one subdomain (one rank).
    pub fn whole(domain: &Domain) -> Self {
        Subdomain {
            lower: domain.lower,
            upper: domain.upper,
            ranks: [1, 1, 1],
            coords: [0, 0, 0],
            cuts: BoxCuts::default(),
        }
    }

    /// The box of `rank` in a process grid of `ranks` boxes of equal
    /// lengths (x fastest: rank = (c_z n_y + c_y) n_x + c_x).
    pub fn of_rank(domain: &Domain, ranks: [usize; 3], rank: usize) -> Self {
        Self::of_rank_cut(domain, ranks, &BoxCuts::default(), rank)
    }

    /// The box of `rank` in a process grid of `ranks` whose boxes end at
    /// `cuts` (equal lengths along an axis without cuts).
    pub fn of_rank_cut(domain: &Domain, ranks: [usize; 3], cuts: &BoxCuts, rank: usize) -> Self {
        let coords = grid_coords(ranks, rank);
        let extent = domain.extent();
        let mut lower = domain.lower;
        let mut upper = domain.upper;
        for axis in 0..3 {
            let (n, c) = (ranks[axis], coords[axis]);
            let at = &cuts[axis];
            if at.is_empty() {
                let width = extent[axis] / n as f64;
                lower[axis] = domain.lower[axis] + width * c as f64;
                if c + 1 < n {
                    upper[axis] = domain.lower[axis] + width * (c + 1) as f64;
                }
            } else {
                assert_eq!(at.len() + 1, n, "one cut between each two boxes");
                if c > 0 {
                    lower[axis] = at[c - 1];
                }
                if c + 1 < n {
                    upper[axis] = at[c];
                }
            }
        }
        Subdomain {
            lower,
            upper,
            ranks,
            coords,
            cuts: cuts.clone(),
        }
    }

    /// Number of ranks in the process grid.
    pub fn rank_count(&self) -> usize {
        self.ranks.iter().product()
    }

    /// Rank at process-grid coordinates `coords`.
    pub fn rank_at(&self, coords: [usize; 3]) -> usize {
        grid_rank(self.ranks, coords)
    }

    /// Process-grid coordinates of the rank owning position `x` (the same
    /// formula decides ownership everywhere, so every position has exactly
    /// one owner).
    pub fn owner_coords(&self, domain: &Domain, x: &Vec3) -> [usize; 3] {
        let extent = domain.extent();
        let mut coords = [0; 3];
        for axis in 0..3 {
            let n = self.ranks[axis];
            if n > 1 && self.cuts[axis].is_empty() {
                let c = ((x[axis] - domain.lower[axis]) / extent[axis] * n as f64).floor();
                coords[axis] = (c.max(0.0) as usize).min(n - 1);
            } else if n > 1 {
                // The boxes below x: a position on a cut is the upper box's.
                coords[axis] = self.cuts[axis].partition_point(|&cut| cut <= x[axis]);
            }
        }
        coords
    }

    /// Rank owning position `x`.
    pub fn owner(&self, domain: &Domain, x: &Vec3) -> usize {
        self.rank_at(self.owner_coords(domain, x))
    }

    /// Whether this rank owns position `x`.
    pub fn owns(&self, domain: &Domain, x: &Vec3) -> bool {
        self.owner_coords(domain, x) == self.coords
    }

    /// The neighbouring rank on `side` along `axis`, across a periodic face
    /// if need be (None at a wall of the domain).
    pub fn neighbour(&self, domain: &Domain, axis: usize, side: Side) -> Option<usize> {
        let upper = side == Side::Upper;
        grid_neighbour(self.ranks, self.coords, axis, upper, domain.periodic[axis])
    }
}

/// Coordinates of `rank` in a process grid of `ranks` (x fastest: rank =
/// (c_z n_y + c_y) n_x + c_x). Every decomposition (grains, cells) numbers
/// its ranks so.
pub fn grid_coords(ranks: [usize; 3], rank: usize) -> [usize; 3] {
    let coords = [
        rank % ranks[0],
        (rank / ranks[0]) % ranks[1],
        rank / (ranks[0] * ranks[1]),
    ];
    assert!(
        coords[2] < ranks[2],
        "rank {rank} outside the process grid {ranks:?}"
    );
    coords
}

/// The rank at `coords` in a process grid of `ranks` ([`grid_coords`]).
pub fn grid_rank(ranks: [usize; 3], coords: [usize; 3]) -> usize {
    (coords[2] * ranks[1] + coords[1]) * ranks[0] + coords[0]
}

/// The rank next to the one at `coords` along `axis`, on its upper side or
/// its lower one, across the end of a `periodic` axis (None at a wall).
pub fn grid_neighbour(
    ranks: [usize; 3],
    coords: [usize; 3],
    axis: usize,
    upper: bool,
    periodic: bool,
) -> Option<usize> {
    let (n, c) = (ranks[axis], coords[axis]);
    let next = match upper {
        false if c > 0 => c - 1,
        true if c + 1 < n => c + 1,
        false if periodic => n - 1,
        true if periodic => 0,
        _ => return None,
    };
    let mut coords = coords;
    coords[axis] = next;
    Some(grid_rank(ranks, coords))
}

/// Scenes and checks the tests of the decomposition share.
#[cfg(test)]
pub(crate) mod test_support {
    use super::*;

    /// A 4 × 0.12 × 1 m box, periodic along y if asked.
    pub(crate) fn column(periodic_y: bool) -> Domain {
        Domain {
            dimension: Dimension::Three,
            lower: Vec3::new(-2.0, 0.0, 0.0),
            upper: Vec3::new(2.0, 0.12, 1.0),
            periodic: [false, periodic_y, false],
            gravity: Vec3::zeros(),
        }
    }

    /// Each position at x = `xs` (y and z spread) has one owner among the
    /// 4 × 2 × 1 `boxes`, whose box holds it along x.
    pub(crate) fn assert_one_owner_each(domain: &Domain, boxes: &[Subdomain], xs: &[f64]) {
        for (k, x) in xs.iter().enumerate() {
            let position = Vec3::new(*x, 0.013 * k as f64, 0.5);
            let owners: Vec<usize> = (0..boxes.len())
                .filter(|&r| boxes[r].owns(domain, &position))
                .collect();
            assert_eq!(owners.len(), 1, "{position:?}");
            let b = &boxes[owners[0]];
            assert_eq!(b.owner(domain, &position), owners[0]);
            let inside_x = (b.coords[0] == 0 || position.x >= b.lower.x)
                && (b.coords[0] == 3 || position.x < b.upper.x);
            assert!(inside_x, "{position:?} in {b:?}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::{assert_one_owner_each, column};
    use super::*;

    /// Every position has one owner, whose box holds it; neighbours wrap
    /// across periodic ends only.
    #[test]
    fn each_position_has_one_owner_and_boxes_tile_the_domain() {
        let domain = column(true);
        let ranks = [4, 2, 1];
        let boxes: Vec<Subdomain> = (0..8)
            .map(|r| Subdomain::of_rank(&domain, ranks, r))
            .collect();
        let xs = [-2.0, -1.0, -0.3, 0.0, 0.999, 1.0, 1.9999, 2.0, 2.5];
        assert_one_owner_each(&domain, &boxes, &xs);
        let corner = &boxes[0];
        assert_eq!(corner.neighbour(&domain, 0, Side::Lower), None);
        assert_eq!(corner.neighbour(&domain, 0, Side::Upper), Some(1));
        assert_eq!(corner.neighbour(&domain, 1, Side::Lower), Some(4));
        assert_eq!(corner.neighbour(&domain, 1, Side::Upper), Some(4));
        assert_eq!(corner.neighbour(&domain, 2, Side::Upper), None);
    }
}
