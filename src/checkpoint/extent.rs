//! Which ranks' states a resume on another number of ranks reads.
//!
//! A checkpoint's manifest records, for each rank that wrote it, what its
//! state holds: the box of its owned grains' centres and the block of flow
//! values (padded cell indices, ghost layers included). A rank of the new
//! job reads only the states whose holdings meet what it needs (its
//! subdomain for grains, its padded block for the flow), and always the
//! old root's, which carries the run's records. So a resume reads about
//! the share of the scene a rank will hold, not the whole scene on every
//! rank.

use grainflow_core::Communicator;
use grainflow_dem::DemSystem;
use grainflow_fluid::FlowSolver;
use serde::{Deserialize, Serialize};

/// What a rank's state holds, or what a rank needs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Extent {
    /// Lower and upper corners of the grains' centres (a rank without
    /// grains has none).
    pub grains: Option<[[f64; 3]; 2]>,
    /// First and last-plus-one padded cell index along each axis, in the
    /// whole grid's numbering less the ghost width (a ghost below the
    /// domain is at −1).
    pub cells: Option<[[i64; 3]; 2]>,
}

/// Numbers per extent when gathered: a flag and six values for each part.
const FLAT: usize = 14;

impl Extent {
    /// What this rank's state holds: its owned grains, its flow block.
    pub fn held(grains: Option<&DemSystem>, flow: Option<&FlowSolver>) -> Self {
        let grains = grains.and_then(|dem| {
            let p = &dem.particles;
            let centres = &p.position[..p.n_owned];
            (!centres.is_empty()).then(|| {
                let mut lower = [f64::INFINITY; 3];
                let mut upper = [f64::NEG_INFINITY; 3];
                for x in centres {
                    for a in 0..3 {
                        lower[a] = lower[a].min(x[a]);
                        upper[a] = upper[a].max(x[a]);
                    }
                }
                [lower, upper]
            })
        });
        Extent {
            grains,
            cells: flow.map(padded_block),
        }
    }

    /// What this rank needs to take its share: the grains its subdomain
    /// owns (to infinity beyond the domain's faces, where the edge ranks
    /// own what lies outside) and its flow block.
    pub fn needed(grains: Option<&DemSystem>, flow: Option<&FlowSolver>) -> Self {
        let grains = grains.map(|dem| {
            let s = &dem.subdomain;
            let mut lower = [s.lower.x, s.lower.y, s.lower.z];
            let mut upper = [s.upper.x, s.upper.y, s.upper.z];
            for a in 0..3 {
                if s.coords[a] == 0 {
                    lower[a] = f64::NEG_INFINITY;
                }
                if s.coords[a] + 1 == s.ranks[a] {
                    upper[a] = f64::INFINITY;
                }
            }
            [lower, upper]
        });
        Extent {
            grains,
            cells: flow.map(padded_block),
        }
    }

    /// Whether a state holding `self` has something for a rank that needs
    /// `needed` (closed boxes: a grain on a face may belong to either).
    pub fn meets(&self, needed: &Extent) -> bool {
        let grains = match (&self.grains, &needed.grains) {
            (Some([lo, hi]), Some([need_lo, need_hi])) => {
                (0..3).all(|a| lo[a] <= need_hi[a] && need_lo[a] <= hi[a])
            }
            _ => false,
        };
        let cells = match (&self.cells, &needed.cells) {
            (Some([lo, hi]), Some([need_lo, need_hi])) => {
                (0..3).all(|a| lo[a] < need_hi[a] && need_lo[a] < hi[a])
            }
            _ => false,
        };
        grains || cells
    }

    /// Every rank's extent on the root (collective; `None` elsewhere).
    pub fn gather(&self, communicator: &Communicator) -> Option<Vec<Extent>> {
        let mut flat = Vec::with_capacity(FLAT);
        match &self.grains {
            Some([lower, upper]) => {
                flat.push(1.0);
                flat.extend(lower.iter().chain(upper));
            }
            None => flat.extend([0.0; 7]),
        }
        match &self.cells {
            // Cell indices are exact in a double.
            Some([lower, upper]) => {
                flat.push(1.0);
                flat.extend(lower.iter().chain(upper).map(|&i| i as f64));
            }
            None => flat.extend([0.0; 7]),
        }
        let all = communicator.gather(&flat)?;
        Some(
            all.iter()
                .map(|v| Extent {
                    grains: (v[0] == 1.0).then(|| [[v[1], v[2], v[3]], [v[4], v[5], v[6]]]),
                    cells: (v[7] == 1.0).then(|| {
                        let i = |k: usize| v[k] as i64;
                        [[i(8), i(9), i(10)], [i(11), i(12), i(13)]]
                    }),
                })
                .collect(),
        )
    }
}

/// The states a rank that needs `needed` reads from a checkpoint written
/// on `ranks` ranks whose manifest lists `held` (empty in a checkpoint
/// that predates the list: then all of them). The old root's comes first.
pub fn states_to_read(ranks: usize, held: &[Extent], needed: &Extent) -> Vec<usize> {
    if held.len() != ranks {
        return (0..ranks).collect();
    }
    (0..ranks)
        .filter(|&rank| rank == 0 || held[rank].meets(needed))
        .collect()
}

/// A flow solver's block, ghost layers included, in the whole grid's
/// cell numbering.
fn padded_block(flow: &FlowSolver) -> [[i64; 3]; 2] {
    let offset = flow.partition().offset();
    let mut block = [[0; 3]; 2];
    for a in 0..3 {
        let ghost = flow.grid.ghost(a) as i64;
        block[0][a] = offset[a] as i64 - ghost;
        block[1][a] = (offset[a] + flow.grid.cells[a]) as i64 + ghost;
    }
    block
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grains(lower: [f64; 3], upper: [f64; 3]) -> Extent {
        Extent {
            grains: Some([lower, upper]),
            cells: None,
        }
    }

    #[test]
    fn a_rank_reads_the_root_and_the_states_whose_grains_or_cells_meet_its_share() {
        let held = [
            grains([0.0, 0.0, 0.0], [0.4, 1.0, 1.0]),
            grains([0.5, 0.0, 0.0], [0.9, 1.0, 1.0]),
            Extent {
                grains: None,
                cells: Some([[-1, -1, -1], [10, 17, 17]]),
            },
        ];
        let upper_half = Extent {
            grains: Some([
                [0.5, f64::NEG_INFINITY, f64::NEG_INFINITY],
                [f64::INFINITY; 3],
            ]),
            cells: Some([[9, -1, -1], [17, 17, 17]]),
        };
        // The root always; rank 1's grains; rank 2's block reaches the
        // upper half's ghost layer (index 9): it is read for it.
        assert_eq!(states_to_read(3, &held, &upper_half), [0, 1, 2]);
        let lower_half = Extent {
            grains: Some([[f64::NEG_INFINITY; 3], [0.45, f64::INFINITY, f64::INFINITY]]),
            cells: Some([[-1, -1, -1], [8, 17, 17]]),
        };
        let far = Extent {
            grains: Some([[2.0, 0.0, 0.0], [3.0, 1.0, 1.0]]),
            cells: Some([[20, -1, -1], [30, 17, 17]]),
        };
        assert_eq!(states_to_read(3, &held, &lower_half), [0, 2]);
        assert_eq!(states_to_read(3, &held, &far), [0]);
        // A manifest without the list: every state.
        assert_eq!(states_to_read(3, &[], &far), [0, 1, 2]);
    }

    #[test]
    fn extents_travel_through_a_gather_unchanged() {
        let extent = Extent {
            grains: Some([[0.1, -2.0, 3.5], [0.2, 1e-9, 4.0]]),
            cells: Some([[-1, 0, 7], [33, 65, 129]]),
        };
        let all = extent.gather(&Communicator::serial()).expect("the root");
        assert_eq!(all, [extent]);
        let empty = Extent::default();
        assert_eq!(empty.gather(&Communicator::serial()).unwrap(), [empty]);
    }
}
