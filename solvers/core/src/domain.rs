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

/// The part of the domain a rank owns, in a Cartesian process grid of
/// `ranks[0] × ranks[1] × ranks[2]` equal boxes: particles whose centre
/// lies in `[lower, upper)` are owned here (the ranks at the ends of an
/// axis also own what lies beyond the domain's faces); copies of others
/// within the interaction range are ghosts.
#[derive(Clone, Debug)]
pub struct Subdomain {
    pub lower: Vec3,
    pub upper: Vec3,
    /// Ranks along each axis.
    pub ranks: [usize; 3],
    /// This rank's position in the process grid.
    pub coords: [usize; 3],
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
        }
    }

    /// The box of `rank` in a process grid of `ranks` (x fastest:
    /// rank = (c_z n_y + c_y) n_x + c_x).
    pub fn of_rank(domain: &Domain, ranks: [usize; 3], rank: usize) -> Self {
        let coords = grid_coords(ranks, rank);
        let extent = domain.extent();
        let mut lower = domain.lower;
        let mut upper = domain.upper;
        for axis in 0..3 {
            let width = extent[axis] / ranks[axis] as f64;
            lower[axis] = domain.lower[axis] + width * coords[axis] as f64;
            if coords[axis] + 1 < ranks[axis] {
                upper[axis] = domain.lower[axis] + width * (coords[axis] + 1) as f64;
            }
        }
        Subdomain {
            lower,
            upper,
            ranks,
            coords,
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
            if n > 1 {
                let c = ((x[axis] - domain.lower[axis]) / extent[axis] * n as f64).floor();
                coords[axis] = (c.max(0.0) as usize).min(n - 1);
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

/// The process grid for `size` ranks: among the factorisations
/// n_x n_y n_z = size (n_z = 1 in 2D) whose boxes are at least `min_width`
/// wide along every split axis, those whose busiest box holds the fewest of
/// the grains at `positions` (within 2 %: the work is shared), and among
/// them the one with the least area of cuts between boxes (the ghost
/// volume, hence the communication, scales with it). Ties go to the first
/// in (n_x, n_y, n_z) order.
pub fn process_grid(
    domain: &Domain,
    size: usize,
    min_width: f64,
    positions: &[Vec3],
) -> Result<[usize; 3], String> {
    let dims = domain.dimension.count();
    let extent = domain.extent();
    let mut feasible: Vec<(usize, f64, [usize; 3])> = Vec::new();
    for nx in (1..=size).filter(|&n| size.is_multiple_of(n)) {
        for ny in (1..=size / nx).filter(|&n| (size / nx).is_multiple_of(n)) {
            let nz = size / nx / ny;
            let ranks = [nx, ny, nz];
            if dims == 2 && nz > 1 {
                continue;
            }
            if !fits(domain, ranks, min_width) {
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
            feasible.push((busiest_box(domain, ranks, positions), area, ranks));
        }
    }
    let least_load = feasible.iter().map(|f| f.0).min().unwrap_or(0);
    let balanced = |load: usize| load as f64 <= 1.02 * least_load as f64;
    let mut best: Option<(f64, [usize; 3])> = None;
    for &(load, area, ranks) in &feasible {
        if balanced(load) && best.is_none_or(|(a, _)| area < a) {
            best = Some((area, ranks));
        }
    }
    best.map(|(_, ranks)| ranks).ok_or_else(|| {
        format!(
            "{size} ranks cannot split the domain into boxes at least one interaction range \
             ({min_width:.3e} m) wide along every split axis; allowed: fewer ranks"
        )
    })
}

/// The number of `positions` in the fullest box of a process grid.
fn busiest_box(domain: &Domain, ranks: [usize; 3], positions: &[Vec3]) -> usize {
    grains_per_box(domain, ranks, positions)
        .into_iter()
        .max()
        .unwrap_or(0)
}

/// How many of `positions` each box of a process grid owns, by rank.
pub fn grains_per_box(domain: &Domain, ranks: [usize; 3], positions: &[Vec3]) -> Vec<usize> {
    let grid = Subdomain::of_rank(domain, ranks, 0);
    let mut counts = vec![0usize; grid.rank_count()];
    for x in positions {
        let mut x = *x;
        domain.wrap(&mut x);
        counts[grid.owner(domain, &x)] += 1;
    }
    counts
}

/// Whether boxes of a process grid are at least `min_width` wide along
/// every split axis (a ghost then comes from the next box only).
pub fn fits(domain: &Domain, ranks: [usize; 3], min_width: f64) -> bool {
    let extent = domain.extent();
    (0..3).all(|axis| ranks[axis] == 1 || extent[axis] / ranks[axis] as f64 >= min_width)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column(periodic_y: bool) -> Domain {
        Domain {
            dimension: Dimension::Three,
            lower: Vec3::new(-2.0, 0.0, 0.0),
            upper: Vec3::new(2.0, 0.12, 1.0),
            periodic: [false, periodic_y, false],
            gravity: Vec3::zeros(),
        }
    }

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

    /// Every position has one owner, whose box holds it; neighbours wrap
    /// across periodic ends only.
    #[test]
    fn each_position_has_one_owner_and_boxes_tile_the_domain() {
        let domain = column(true);
        let ranks = [4, 2, 1];
        let boxes: Vec<Subdomain> = (0..8)
            .map(|r| Subdomain::of_rank(&domain, ranks, r))
            .collect();
        for (k, x) in [-2.0, -1.0, -0.3, 0.0, 0.999, 1.0, 1.9999, 2.0, 2.5]
            .iter()
            .enumerate()
        {
            let position = Vec3::new(*x, 0.013 * k as f64, 0.5);
            let owners: Vec<usize> = (0..8)
                .filter(|&r| boxes[r].owns(&domain, &position))
                .collect();
            assert_eq!(owners.len(), 1, "{position:?}");
            let b = &boxes[owners[0]];
            assert_eq!(b.owner(&domain, &position), owners[0]);
            let inside_x = (b.coords[0] == 0 || position.x >= b.lower.x)
                && (b.coords[0] == 3 || position.x < b.upper.x);
            assert!(inside_x, "{position:?} in {b:?}");
        }
        let corner = &boxes[0];
        assert_eq!(corner.neighbour(&domain, 0, Side::Lower), None);
        assert_eq!(corner.neighbour(&domain, 0, Side::Upper), Some(1));
        assert_eq!(corner.neighbour(&domain, 1, Side::Lower), Some(4));
        assert_eq!(corner.neighbour(&domain, 1, Side::Upper), Some(4));
        assert_eq!(corner.neighbour(&domain, 2, Side::Upper), None);
    }
}
