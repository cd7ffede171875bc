//! The memory a scene needs, estimated from its case alone: no grain is
//! placed and no field allocated, so that `check` and `run` can refuse a
//! scene larger than the machine with the keys that make it large, instead
//! of dying in an allocation.

use crate::case::{BlockSection, Case, ContactModel};
use crate::RunError;

/// Bytes of the DEM state per particle: seven vectors (with the external
/// force and torque) and five scalars, the reference position, the
/// coordination, the wall marks and the cell bins (~290 B), 24 B of
/// tangential history per wall, and per listed partner 81 B: index and
/// mirror (8 B), history (24 B), a state byte, and the
/// pair's force and partner torque handed between the two passes of the
/// force loop (48 B). A dense 3D packing lists about 13 partners.
pub fn bytes_per_particle(dimension: usize, walls: usize) -> usize {
    let partners = if dimension == 3 { 13 } else { 6 };
    290 + 24 * walls.max(1) + partners * 81
}

/// Bytes of the flow state per cell: velocity, its two RK3 tendencies and
/// its increment (4 vectors), pressure, correction and divergence, plus the
/// transform work arrays of the direct solves (about two fields).
pub fn bytes_per_cell(dimension: usize) -> usize {
    8 * (4 * dimension + 3 + 2)
}

/// Bytes per cell that immersed grains add: the solid fraction's weights
/// and the forcing's field, a vector per cell.
pub fn immersed_bytes_per_cell(dimension: usize) -> usize {
    16 * dimension
}

/// Peak bytes of a COCD step beyond the scene's own, `c N^b` for `N`
/// grains, fitted on packings at rest (every grain in contact: the most a
/// step holds), one thread, ε = 1e-8 (ε = 1e-5 holds the same within
/// 2 %): the normal matrix `K = P + AᵀΘA`, its Cholesky factor, the conic
/// program and the interior point's vectors (`docs/performance.md`, "What
/// a COCD step holds"). Measured peak resident memory less the scene's:
///
/// - 3D spheres: 98, 236, 602, 1,455 MB at 2,057, 4,312, 8,748, 17,986,
///   and 16.29 GB at 112,896 (16.46 GB peak less the scene's 0.18 GB,
///   ε = 1e-5, 2026-12-05); fitted through the two largest (0.94 times
///   the measure at 8,748, 1.00 at a packing of 37,004 measured apart).
///   The factor fills faster than `N`: nested dissection's top separator
///   is a slice of the packing. The fit through 8,748 and 17,986 alone
///   (`N^1.23`) fell 15 % short at 112,896.
/// - 2D discs: 91, 175, 398, 707 MB at 12,500, 25,000, 50,000, 100,000;
///   least squares in logarithms (1.00, 1.04, 0.92, 1.04 times): about
///   linear, the matrix split in two above 1,000 discs.
const COCD_BYTES_2D: (f64, f64) = (7015.3, 1.0042);
const COCD_BYTES_3D: (f64, f64) = (3683.9, 1.3152);

/// Peak bytes a 3D sphere adds to a COCD step solved by the projected
/// gradient (no factor: the program in columns, the operator's blocks, a
/// few vectors): 892–898 MiB peak for the first hard step of 111,132
/// spheres on one and two threads (2026-12-07) less the scene's 0.18 GB,
/// 6.8 kB a sphere (8.7 kB before the program lost its triplets). In 2D
/// the interior point's nearly linear figure stands for it.
const PROJECTED_GRADIENT_BYTES_3D: f64 = 6_800.0;

/// What a COCD step holds with the projected gradient for `grains` in
/// `dimension`.
pub fn projected_gradient_step_bytes(dimension: usize, grains: f64) -> f64 {
    if dimension == 3 {
        PROJECTED_GRADIENT_BYTES_3D * grains.max(0.0)
    } else {
        cocd_step_bytes(dimension, grains)
    }
}

/// [`COCD_BYTES_2D`], [`COCD_BYTES_3D`] for `grains` in `dimension`.
pub fn cocd_step_bytes(dimension: usize, grains: f64) -> f64 {
    let (c, b) = if dimension == 3 {
        COCD_BYTES_3D
    } else {
        COCD_BYTES_2D
    };
    if grains > 0.0 {
        c * grains.powf(b)
    } else {
        0.0
    }
}

/// What a scene holds at its largest, counted from the case.
#[derive(Clone, Debug, PartialEq)]
pub struct Footprint {
    /// Grains of every block and pour, `(key, count)`, in the case's order.
    pub grains: Vec<(String, f64)>,
    /// Cells of the fluid grid (zero in a dry scene).
    pub cells: f64,
    /// Bytes of the hard-contact solve at its largest (COCD; zero for the
    /// soft DEM and NSCD, whose Gauss–Seidel holds no factor).
    pub contact_bytes: f64,
    /// Estimated bytes of the whole scene, every rank together.
    pub bytes: f64,
}

/// What a rank holds before any scene: the program, its libraries and the
/// MPI library's buffers. Two ranks of the 1,600-sphere static box, whose
/// share of the scene is about a megabyte, peaked at 76.6 and 77.2 MB each
/// (2026-12-06).
pub const PROCESS_BYTES: f64 = 75e6;

/// Bytes of a checkpoint per grain (its arrays and its pair list with the
/// tangential histories) besides its wall histories (a vector per wall,
/// at least one), and per fluid cell (velocity and pressure with their
/// ghost layers), as measured on a dense packing of 10⁶ grains on a floor
/// (388 MB) and a 256³ flow (550 MB): docs/performance.md.
pub const CHECKPOINT_BYTES_PER_GRAIN: f64 = 366.0;
pub const CHECKPOINT_BYTES_PER_GRAIN_AND_WALL: f64 = 24.0;
pub const CHECKPOINT_BYTES_PER_CELL: f64 = 33.0;

impl Footprint {
    /// The size of one checkpoint of the scene, every rank together.
    pub fn checkpoint_bytes(&self, walls: usize) -> f64 {
        let grains: f64 = self.grains.iter().map(|(_, n)| n).sum();
        let per_grain =
            CHECKPOINT_BYTES_PER_GRAIN + CHECKPOINT_BYTES_PER_GRAIN_AND_WALL * walls.max(1) as f64;
        grains * per_grain + self.cells * CHECKPOINT_BYTES_PER_CELL
    }

    /// Counts the grains and cells of `case` without creating them.
    pub fn of(case: &Case) -> Footprint {
        let dim = case.domain.dimension as usize;
        let grains: Vec<(String, f64)> =
            case.particles
                .iter()
                .flat_map(|p| {
                    let blocks = p.block.iter().enumerate().map(move |(k, block)| {
                        let key = match block {
                            BlockSection::Lattice { .. } => "spacing",
                            BlockSection::Random { .. } | BlockSection::CollisionPairs { .. } => {
                                "count"
                            }
                            BlockSection::Explicit { .. } => "positions",
                            BlockSection::File { .. } => "path",
                        };
                        (
                            format!("particles.block[{k}].{key}"),
                            block_grains(block, dim),
                        )
                    });
                    let pours =
                        p.pour.iter().enumerate().map(|(k, pour)| {
                            (format!("particles.pour[{k}].count"), pour.count as f64)
                        });
                    blocks.chain(pours)
                })
                .collect();
        // An axisymmetric scene's fluid is its (r, z) grid: half the box's
        // cells along x radially, none along y.
        let axisymmetric = case.domain.geometry == crate::case::Geometry::Axisymmetric;
        let cells = case.fluid.as_ref().map_or(0.0, |f| {
            if axisymmetric {
                (f.cells[0] / 2) as f64 * f.cells[2] as f64
            } else {
                f.cells[..dim].iter().map(|&n| n as f64).product()
            }
        });
        let grid_dim = if axisymmetric { 2 } else { dim };
        let per_cell = bytes_per_cell(grid_dim)
            + if case.particles.is_some() {
                immersed_bytes_per_cell(grid_dim)
            } else {
                0
            };
        let total_grains: f64 = grains.iter().map(|(_, n)| n).sum();
        let cocd = case
            .contact
            .as_ref()
            .filter(|c| c.model == ContactModel::Cocd);
        let contact_bytes = match cocd {
            Some(c) if c.conic_solver() == grainflow_contact::ConicSolver::ProjectedGradient => {
                projected_gradient_step_bytes(dim, total_grains)
            }
            Some(_) => cocd_step_bytes(dim, total_grains),
            None => 0.0,
        };
        let bytes = total_grains * bytes_per_particle(dim, case.walls.len()) as f64
            + cells * per_cell as f64
            + contact_bytes;
        Footprint {
            grains,
            cells,
            contact_bytes,
            bytes,
        }
    }

    /// Bytes each of `ranks` ranks needs: its share of the scene, what a
    /// process holds before any ([`PROCESS_BYTES`]), and `held` bytes
    /// every rank holds whole (a COCD separator's Σ). One COCD step of
    /// 112,896 spheres with the projected gradient on 2 ranks (2026-12-06):
    /// 619 MiB estimated, 658–676 MiB measured (−6 to −9 %).
    pub fn per_rank_bytes(&self, ranks: usize, held: f64) -> f64 {
        self.bytes / ranks as f64 + PROCESS_BYTES + held
    }

    /// Refuses a scene whose share on each of `ranks` ranks needs more
    /// memory than `available` bytes (this machine's, [`machine_memory`]),
    /// naming the keys that make it large.
    pub fn check_fits(&self, ranks: usize, available: Option<f64>) -> Result<(), RunError> {
        self.check_fits_holding(ranks, available, None)
    }

    /// [`Footprint::check_fits`] with `held = (bytes, what)` more on every
    /// rank, not shared among them (what a COCD program's separator makes
    /// each rank hold: [`crate::sharing::Separator::held_per_rank_bytes`]),
    /// `what` naming it in the refusal.
    pub fn check_fits_holding(
        &self,
        ranks: usize,
        available: Option<f64>,
        held: Option<(f64, &str)>,
    ) -> Result<(), RunError> {
        let Some(available) = available else {
            return Ok(());
        };
        let held_bytes = held.map_or(0.0, |(bytes, _)| bytes);
        let share = self.per_rank_bytes(ranks, held_bytes);
        if share <= available {
            return Ok(());
        }
        let mut causes = Vec::new();
        if let Some((bytes, what)) = held {
            causes.push(format!(
                "{what}: about {} on every rank",
                human_bytes(bytes)
            ));
        }
        if self.cells > 0.0 {
            causes.push(format!("fluid.cells = {:.3e} cells", self.cells));
        }
        if self.contact_bytes > 0.5 * self.bytes {
            causes.push(format!(
                "contact.model = \"cocd\": about {} for its conic step at rest",
                human_bytes(self.contact_bytes)
            ));
        }
        let mut largest = self.grains.clone();
        largest.sort_by(|a, b| b.1.total_cmp(&a.1));
        for (key, count) in largest.iter().filter(|(_, n)| *n > 0.0).take(2) {
            causes.push(format!("{key}: {count:.3e} grains"));
        }
        // More ranks shrink the shares but not what each rank holds whole
        // (a separator grows with the ranks): where the share alone would
        // fit, fewer ranks are the way.
        let advice = if held_bytes > 0.0 && self.bytes / ranks as f64 <= available {
            "reduce them, or run on fewer ranks with more threads each"
        } else {
            "reduce them, or share the scene among more ranks (mpirun)"
        };
        Err(RunError::Case(format!(
            "the scene needs about {} per rank on {ranks} rank{} ({}), more than this \
             machine's {}: {advice}",
            human_bytes(share),
            if ranks == 1 { "" } else { "s" },
            causes.join(", "),
            human_bytes(available)
        )))
    }
}

/// How many grains `block` creates, from its parameters alone.
fn block_grains(block: &BlockSection, dim: usize) -> f64 {
    match block {
        BlockSection::Lattice {
            lower,
            upper,
            spacing,
            layer_spacing,
            ..
        } => (0..dim)
            .map(|a| {
                let step = if a == dim - 1 {
                    layer_spacing.unwrap_or(*spacing)
                } else {
                    *spacing
                };
                ((upper[a] - lower[a]) / step + 1e-9).floor().max(0.0)
            })
            .product(),
        BlockSection::Random { count, .. } => *count as f64,
        BlockSection::Explicit { positions, .. } => positions.len() as f64,
        // One grain per line after the header; an unreadable file is
        // reported when the scene is built.
        BlockSection::File { path, .. } => {
            std::fs::read_to_string(path).map_or(0.0, |text| text.lines().skip(1).count() as f64)
        }
        BlockSection::CollisionPairs { count, .. } => 2.0 * *count as f64,
    }
}

/// The physical memory of this machine (Linux: `MemTotal` of
/// `/proc/meminfo`), if known.
pub fn machine_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

pub use grainflow_core::human_bytes;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_larger_than_the_machine_is_refused_naming_its_keys() {
        let footprint = Footprint {
            grains: vec![("particles.block[0].count".into(), 1e12)],
            cells: 1e12,
            contact_bytes: 0.0,
            bytes: 1e12 * 1000.0,
        };
        let error = footprint.check_fits(1, Some(24e9)).unwrap_err().to_string();
        assert!(error.contains("fluid.cells"), "{error}");
        assert!(error.contains("particles.block[0].count"), "{error}");
        // Shared among enough ranks, each share fits.
        assert!(footprint.check_fits(100_000, Some(24e9)).is_ok());
        // Where the machine's memory is unknown nothing is refused.
        assert!(footprint.check_fits(1, None).is_ok());
    }

    /// What every rank holds whole (a COCD separator's Σ) is added to each
    /// rank's share, not divided among the ranks: a scene of 8 GB whose
    /// quarter fits a 3 GB machine no longer fits on 4 ranks beside 2 GB
    /// held on each, and the refusal names what is held and advises fewer
    /// ranks (more would grow the separator).
    #[test]
    fn a_separator_held_on_every_rank_is_counted_beside_each_share() {
        let footprint = Footprint {
            grains: vec![("particles.block[0].count".into(), 1e7)],
            cells: 0.0,
            contact_bytes: 7e9,
            bytes: 8e9,
        };
        let what = "contact.model = \"cocd\": the dense Schur complement of its separator";
        assert!(footprint.check_fits(4, Some(3e9)).is_ok());
        assert!(footprint
            .check_fits_holding(4, Some(3e9), Some((0.9e9, what)))
            .is_ok());
        let error = footprint
            .check_fits_holding(4, Some(3e9), Some((2e9, what)))
            .unwrap_err()
            .to_string();
        assert!(error.contains("3.8 GiB"), "{error}");
        assert!(error.contains("Schur complement"), "{error}");
        assert!(error.contains("fewer ranks"), "{error}");
    }

    /// A 3D packing of 250,000 spheres at rest fits a 24 GB machine with
    /// the soft DEM (about 0.4 GB) but not with COCD, whose factor alone
    /// needs about 46 GB there: `check` and `run` refuse it naming the
    /// contact model, before anything is built.
    #[test]
    fn a_cocd_factor_larger_than_the_machine_is_refused_naming_the_contact_model() {
        let scene = |model: &str| {
            let text = format!(
                "[domain]\ndimension = 3\nlower = [0.0, 0.0, 0.0]\nupper = [0.1, 0.1, 0.1]\n\
                 gravity = [0.0, 0.0, -9.81]\n\
                 [particles]\ndensity = 2500.0\nradius = 5.0e-4\n\
                 [[particles.block]]\nkind = \"random\"\ncount = 250000\n\
                 lower = [0.0, 0.0, 0.0]\nupper = [0.1, 0.1, 0.1]\n\
                 [contact]\nmodel = \"{model}\"\nfriction = 0.3\n{}\n\
                 [time]\nend = 1.0e-3\ndt = 1.0e-3\n",
                if model == "soft" {
                    "restitution = 0.5\ncontact_time = 1.0e-4"
                } else {
                    ""
                }
            );
            Footprint::of(&Case::from_text(&text, "test", &[]).unwrap())
        };
        let (soft, cocd) = (scene("soft"), scene("cocd"));
        assert_eq!(soft.contact_bytes, 0.0);
        assert!(soft.check_fits(1, Some(24e9)).is_ok());
        let error = cocd.check_fits(1, Some(24e9)).unwrap_err().to_string();
        assert!(error.contains("contact.model = \"cocd\""), "{error}");
        // The projected gradient holds no factor: 6.8 kB a sphere, 1.7 GB
        // for the 250,000 spheres whose factor would take about 46 GB.
        let gradient = scene("cocd\"\nconic_solver = \"projected_gradient");
        assert!((gradient.contact_bytes / 1.7e9 - 1.0).abs() < 1e-12);
        assert!(gradient.check_fits(1, Some(24e9)).is_ok());
    }
}
