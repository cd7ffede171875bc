//! The separator a hard-contact program would have on several ranks.
//!
//! COCD's interior point factorises the normal matrix K = M̃ + AᵀΘA at every
//! iteration (Martin et al. 2022, eq. 7–9; `grainflow_contact::normal_factor`).
//! Shared among ranks by the grains' subdomains, K splits into one block per
//! rank and the unknowns of grains in contact across a rank boundary. Those
//! form a vertex separator S: taking, for every pair of grains of two
//! ranks, the grain of the higher rank cuts every coupling between the
//! ranks' interiors. Each rank then factorises its interior and the ranks
//! assemble together the Schur complement
//!
//!   Σ = K_SS − Σ_r K_Sr K_rr⁻¹ K_rS,
//!
//! dense and of the separator's size: ns² numbers that every rank holds
//! and ns³/3 multiply–adds to factorise at every interior-point iteration,
//! which the ranks share by column blocks. That size, not the ranks'
//! interiors, sets what several ranks can gain.

use grainflow_contact::shared_program::SEPARATOR_BLOCK_OVER_SQUARE;
use grainflow_contact::{contacts, Partner};
use grainflow_core::ProcessGrid;
use grainflow_dem::DemSystem;

/// The program's unknowns as shared among ranks.
#[derive(Clone, Debug, PartialEq)]
pub struct Separator {
    /// Unknowns of the whole program: the free grains' velocities and spins.
    pub unknowns: usize,
    /// Unknowns of the separator S.
    pub separator: usize,
    /// Unknowns of each rank's interior.
    pub interiors: Vec<usize>,
    /// The most separator unknowns the pairs of one rank reach: that
    /// rank's factor ends in a dense block over them.
    pub touched: usize,
    /// Candidate pairs of two free grains, and those across ranks.
    pub pairs: usize,
    pub crossing_pairs: usize,
}

impl Separator {
    /// The separator of the program over the candidate pairs of `system`
    /// (one rank, every grain owned) within the gap `threshold`, its grains
    /// shared by a process grid of `ranks` as a run shares them.
    pub fn of(system: &DemSystem, threshold: f64, boxes: &ProcessGrid) -> Self {
        let p = &system.particles;
        let n = p.n_owned;
        let per_grain = match system.dimension().count() {
            2 => 3,
            _ => 6,
        };
        let grid = boxes.subdomain(&system.domain, 0);
        let owner: Vec<usize> = (0..n)
            .map(|k| {
                let mut x = p.position[k];
                system.domain.wrap(&mut x);
                grid.owner(&system.domain, &x)
            })
            .collect();
        let mut in_separator = vec![false; n];
        let mut crossing_pairs = 0;
        let listed = contacts::listed(system, threshold);
        // The pairs of two free grains, each with the rank that holds it:
        // the lower of the two owners.
        let free_pairs: Vec<(usize, usize, usize)> = listed
            .partner
            .iter()
            .enumerate()
            .filter_map(|(a, partner)| {
                let Partner::Grain(j) = *partner else {
                    return None;
                };
                let (i, j) = (listed.grain[a] as usize, j as usize);
                // A fixed grain has no unknowns: its pairs couple nothing.
                (!p.is_fixed(i) && !p.is_fixed(j)).then(|| (i, j, owner[i].min(owner[j])))
            })
            .collect();
        let pairs = free_pairs.len();
        for &(i, j, _) in &free_pairs {
            if owner[i] != owner[j] {
                // The lower rank holds the pair; the other grain's columns
                // then stand on both ranks.
                crossing_pairs += 1;
                let higher = if owner[i] > owner[j] { i } else { j };
                in_separator[higher] = true;
            }
        }
        // The separator grains each rank's pairs reach.
        let mut reached: Vec<(usize, usize)> = free_pairs
            .iter()
            .flat_map(|&(i, j, rank)| [(rank, i), (rank, j)])
            .filter(|&(_, k)| in_separator[k])
            .collect();
        reached.sort_unstable();
        reached.dedup();
        let mut touched_grains = vec![0usize; grid.rank_count()];
        for &(rank, _) in &reached {
            touched_grains[rank] += 1;
        }
        let touched = per_grain * touched_grains.iter().copied().max().unwrap_or(0);
        let mut interiors = vec![0; grid.rank_count()];
        let (mut unknowns, mut separator) = (0, 0);
        for k in (0..n).filter(|&k| !p.is_fixed(k)) {
            unknowns += per_grain;
            if in_separator[k] {
                separator += per_grain;
            } else {
                interiors[owner[k]] += per_grain;
            }
        }
        Separator {
            unknowns,
            separator,
            interiors,
            touched,
            pairs,
            crossing_pairs,
        }
    }

    /// Bytes of the dense Schur complement Σ.
    pub fn schur_bytes(&self) -> f64 {
        8.0 * (self.separator as f64).powi(2)
    }

    /// Bytes a rank holds for the separator beyond its share of the scene
    /// (`grainflow_contact::normal_factor`, the shared factor): Σ itself,
    /// ns² numbers on every rank, and the end of the rank's own factor, a
    /// dense block over the separator unknowns its pairs reach (ns_t of
    /// them on the rank that reaches most), which the sparse factor's last
    /// supernode holds together with the interior columns merged into it:
    /// [`SEPARATOR_BLOCK_OVER_SQUARE`] ns_t² numbers.
    pub fn held_per_rank_bytes(&self) -> f64 {
        self.schur_bytes() + SEPARATOR_BLOCK_OVER_SQUARE * 8.0 * (self.touched as f64).powi(2)
    }

    /// Multiply–adds of one dense Cholesky factorisation of Σ.
    pub fn schur_flops(&self) -> f64 {
        (self.separator as f64).powi(3) / 3.0
    }

    /// A rank's share of [`Separator::schur_flops`]: the ranks factorise Σ
    /// together, each its column blocks (dealt round them).
    pub fn schur_flops_per_rank(&self) -> f64 {
        self.schur_flops() / self.interiors.len().max(1) as f64
    }

    /// The lines `check --ranks N` prints.
    pub fn describe(&self) -> String {
        let share = 100.0 * self.separator as f64 / self.unknowns.max(1) as f64;
        format!(
            "the contact program's separator: {} of {} unknowns ({share:.1} %), the grains of \
             {} of {} candidate pairs that cross a rank boundary; its dense Schur complement \
             {} (with the dense end of a rank's own factor, about {} held on a rank) and {:.1e} \
             multiply-adds per interior-point iteration to factorise it, {:.1e} on each rank; \
             ranks' interiors {} to {} unknowns; one rank's pairs reach at most {} of the separator's",
            self.separator,
            self.unknowns,
            self.crossing_pairs,
            self.pairs,
            crate::footprint::human_bytes(self.schur_bytes()),
            crate::footprint::human_bytes(self.held_per_rank_bytes()),
            self.schur_flops(),
            self.schur_flops_per_rank(),
            self.interiors.iter().min().copied().unwrap_or(0),
            self.interiors.iter().max().copied().unwrap_or(0),
            self.touched,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow_core::{Dimension, Domain, Vec3};
    use grainflow_dem::particles::NewParticle;
    use grainflow_dem::{ContactLaw, NormalCalibration, NormalStiffness};

    /// A layer of 4 × 4 touching spheres of 1 mm (the fixed ones at `fixed`)
    /// in a box 4 mm square, on one rank.
    fn layer(fixed: &[(usize, usize)]) -> DemSystem {
        let d = 1e-3;
        let domain = Domain {
            dimension: Dimension::Three,
            lower: Vec3::zeros(),
            upper: Vec3::new(4.0 * d, 4.0 * d, d),
            periodic: [false; 3],
            gravity: Vec3::zeros(),
        };
        let law = ContactLaw {
            normal: NormalStiffness::from_restitution(0.5, 1e-4, NormalCalibration::Exact),
            tangential_ratio: 0.2,
            friction: 0.3,
            rolling_friction: 0.0,
        };
        let mut system = DemSystem::new(domain, law, Vec::new(), 0.1 * d);
        let grains: Vec<NewParticle> = (0..16)
            .map(|k| {
                let (ix, iy) = (k % 4, k / 4);
                NewParticle {
                    position: Vec3::new((ix as f64 + 0.5) * d, (iy as f64 + 0.5) * d, 0.5 * d),
                    velocity: Vec3::zeros(),
                    angular_velocity: Vec3::zeros(),
                    radius: 0.5 * d,
                    density: 2500.0,
                    fixed: fixed.contains(&(ix, iy)),
                }
            })
            .collect();
        system.add_particles(&grains);
        system
    }

    /// Split across x, the 24 pairs of touching neighbours cross the
    /// boundary in the 4 rows: the separator is the column of the upper
    /// rank's side, 4 spheres of 6 unknowns.
    #[test]
    fn the_separator_of_a_layer_split_in_two_is_the_column_on_the_upper_side() {
        let separator = Separator::of(&layer(&[]), 1e-4, &ProcessGrid::even([2, 1, 1]));
        assert_eq!(
            separator,
            Separator {
                unknowns: 96,
                separator: 24,
                interiors: vec![48, 24],
                // Both ranks' pairs reach the whole column.
                touched: 24,
                pairs: 24,
                crossing_pairs: 4,
            }
        );
        // Unsplit, nothing crosses.
        let whole = Separator::of(&layer(&[]), 1e-4, &ProcessGrid::even([1, 1, 1]));
        assert_eq!((whole.separator, whole.interiors), (0, vec![96]));
    }

    /// On a 2 × 2 grid the separator is the upper ranks' grains along both
    /// cuts, 7 spheres; each rank's pairs reach 4 of them at most (the
    /// lowest rank's crossing pairs reach the 2 + 2 beyond its two cuts;
    /// the highest rank's own pairs 3), so a rank's factor ends in a dense
    /// block over 24 of the 42 separator unknowns, and the held bytes are
    /// Σ's and 1.5 times that block's square.
    #[test]
    fn on_a_two_by_two_grid_a_rank_reaches_part_of_the_separator() {
        let separator = Separator::of(&layer(&[]), 1e-4, &ProcessGrid::even([2, 2, 1]));
        assert_eq!(separator.separator, 42);
        assert_eq!(separator.crossing_pairs, 8);
        assert_eq!(separator.touched, 24);
        assert_eq!(
            separator.held_per_rank_bytes(),
            8.0 * (42.0f64 * 42.0 + 1.5 * 24.0 * 24.0)
        );
    }

    /// A fixed grain has no unknowns, and its pairs couple nothing.
    #[test]
    fn a_fixed_grain_on_the_boundary_leaves_the_separator() {
        let separator = Separator::of(&layer(&[(2, 0)]), 1e-4, &ProcessGrid::even([2, 1, 1]));
        assert_eq!(separator.unknowns, 90);
        assert_eq!(separator.separator, 18);
        assert_eq!(separator.crossing_pairs, 3);
        assert_eq!(separator.pairs, 21);
        assert_eq!(separator.schur_bytes(), 8.0 * 18.0 * 18.0);
        // Two ranks share Σ's factor.
        assert_eq!(separator.schur_flops_per_rank(), 18.0f64.powi(3) / 6.0);
    }
}
