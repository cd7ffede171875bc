//! How a scene is shared among MPI ranks: the process grid a case gets on
//! a number of ranks and each rank's load, for `grainflow check --ranks N`
//! before a cluster job, and the warning a run logs when its ranks hold
//! too little to keep the exchanges' latency small (docs/performance.md:
//! below about 10,000 grains or 100,000 cells per rank the messages, not
//! the work, set the pace).

mod separator;

pub use separator::Separator;

use crate::case::Case;
use crate::{scene, scene::fluid as fluid_scene};
use grainflow_core::{fits, ProcessGrid, Vec3};
use grainflow_dem::DemSystem;
use grainflow_fluid::{Grid, Partition};
use std::fmt::Write;

/// The separator a COCD scene's program has at the start on `ranks` ranks
/// ([`Separator`]), with the process grid that shares it; None for other
/// scenes. Builds the scene on this process alone.
pub fn cocd_separator(
    case: &Case,
    ranks: usize,
) -> Result<Option<(Separator, ProcessGrid)>, String> {
    let Some(hard) = (case.has_grains() && scene::solved_by_cocd(case))
        .then(|| scene::hard_contact(case))
        .flatten()
    else {
        return Ok(None);
    };
    let mut system = scene::build(case)?;
    hard.prepare(&mut system);
    let centres = &system.particles.position[..system.particles.n_owned];
    let range = system.range_for(system.particles.max_radius());
    let radii = &system.particles.radius[..system.particles.n_owned];
    let grid = scene::process_grid_of(case, &system.domain, ranks, range, centres, radii)?;
    Ok(Some((Separator::of(&system, hard.threshold, &grid), grid)))
}

/// Refuses a COCD scene on `ranks` ranks (more than one) whose share of the
/// scene and the separator's Σ that every rank holds whole
/// ([`Separator::held_per_rank_bytes`]) need more memory than this
/// machine's, naming the separator; returns the separator and its process
/// grid (None for other scenes).
pub fn check_separator_fits(
    case: &Case,
    ranks: usize,
) -> Result<Option<(Separator, ProcessGrid)>, crate::RunError> {
    let separator = cocd_separator(case, ranks).map_err(crate::RunError::Case)?;
    if let Some((separator, _)) = separator.as_ref().filter(|_| separator_factorised(case)) {
        crate::footprint::Footprint::of(case).check_fits_holding(
            ranks,
            crate::footprint::machine_memory(),
            Some((
                separator.held_per_rank_bytes(),
                "contact.model = \"cocd\": the dense Schur complement of its separator",
            )),
        )?;
    }
    Ok(separator)
}

/// Whether a COCD scene's solver factorises the separator's Schur
/// complement at every iteration (the interior point): not the projected
/// gradient, which sums the ranks' parts of Aᵀz on the separator instead.
/// Its Σ is needed only where the interior point takes over a step, and
/// where it would not fit that step stops the run instead
/// (`HardContact::separator_room`): `check` says so, `run` does not refuse.
pub fn separator_factorised(case: &Case) -> bool {
    case.contact.as_ref().map(|c| c.conic_solver())
        != Some(grainflow_contact::ConicSolver::ProjectedGradient)
}

/// Fewer grains per rank than this and a run warns.
pub const GRAINS_PER_RANK_WARNING: usize = 10_000;
/// Fewer cells per rank than this and a run warns.
pub const CELLS_PER_RANK_WARNING: usize = 100_000;

/// The grains per rank by which [`load_warning`] judges a dry scene: none
/// under COCD, whose work per grain (a sparse Cholesky factor at every
/// iteration) dwarfs the exchanges. One step of the 1,600 spheres of
/// `cases/static_box_3d.toml` took 1.96 and 2.01 s on one rank and 1.01
/// and 1.08 s on two (800 grains a rank: efficiency 0.95); the packings
/// of 8,748 and 17,986 spheres 0.94–0.98 and 0.92 (docs/cluster.md).
pub fn grains_judged(case: &Case, grains_per_rank: f64) -> Option<f64> {
    (!scene::solved_by_cocd(case)).then_some(grains_per_rank)
}

/// The warning for ranks holding `grains` grains and `cells` fluid cells
/// each on average (None where the scene has none).
pub fn load_warning(ranks: usize, grains: Option<f64>, cells: Option<f64>) -> Option<String> {
    let mut thin = Vec::new();
    if let Some(g) = grains.filter(|&g| g < GRAINS_PER_RANK_WARNING as f64) {
        thin.push(format!(
            "{g:.0} grains per rank (below {GRAINS_PER_RANK_WARNING})"
        ));
    }
    if let Some(c) = cells.filter(|&c| c < CELLS_PER_RANK_WARNING as f64) {
        thin.push(format!(
            "{c:.0} cells per rank (below {CELLS_PER_RANK_WARNING})"
        ));
    }
    (!thin.is_empty()).then(|| {
        format!(
            "warning: {} on {ranks} ranks: the exchanges' latency, not the work, sets the pace \
             there (docs/performance.md); fewer ranks with more threads each use the cores better",
            thin.join(" and ")
        )
    })
}

/// What `grainflow check --ranks N` prints: the process grid the case gets
/// on `ranks` ranks and each rank's load. `system` is the scene's DEM on
/// one rank (None for a fluid alone), `grid` the whole flow grid (None
/// for a dry scene). What does not run on several ranks is refused before
/// ([`crate::simulation::check_ranks`]).
pub fn report(
    case: &Case,
    system: Option<&DemSystem>,
    grid: Option<&Grid>,
    ranks: usize,
) -> Result<String, String> {
    let mut out = String::new();
    let _ = writeln!(out, "on {ranks} MPI ranks:");
    let boxes = match grid {
        Some(grid) => ProcessGrid::even(fluid_scene::process_grid_of(case, grid, ranks)?),
        None => {
            let system = system.expect("a scene with grains or a fluid");
            let centres: Vec<Vec3> = positions(system);
            let range = system.range_for(system.particles.max_radius());
            let radii = &system.particles.radius[..system.particles.n_owned];
            scene::process_grid_of(case, &system.domain, ranks, range, &centres, radii)?
        }
    };
    let process_grid = boxes.ranks;
    if process_grid.iter().product::<usize>() != ranks {
        return Err(format!(
            "parallel.process_grid = {process_grid:?} does not hold {ranks} ranks"
        ));
    }
    let _ = writeln!(
        out,
        "  process grid {} x {} x {}",
        process_grid[0], process_grid[1], process_grid[2]
    );
    let cuts = boxes.describe_cuts();
    if !cuts.is_empty() {
        let _ = writeln!(
            out,
            "  boxes cut among the grains for equal interiors along the split axes: {cuts} m"
        );
    }
    let mut mean_cells = None;
    if let Some(grid) = grid {
        let partition = Partition::new(grid, process_grid, 0).map_err(|e| format!("fluid: {e}"))?;
        let cells: Vec<usize> = (0..ranks)
            .map(|r| partition.share_of(r).1.iter().product())
            .collect();
        let mean = cells.iter().sum::<usize>() as f64 / ranks as f64;
        let _ = writeln!(
            out,
            "  fluid cells per rank: {} to {} (the last axis whole on every rank)",
            cells.iter().min().unwrap(),
            cells.iter().max().unwrap()
        );
        mean_cells = Some(mean);
    }
    let mut mean_grains = None;
    if let Some(system) = system {
        let centres = positions(system);
        if grid.is_some() {
            // Grains in a fluid: the flow's grid, whose boxes must hold a
            // grain's reach (interaction range and immersed boundary).
            let reach = system
                .range_for(system.particles.max_radius())
                .max(system.ghost_reach);
            if !fits(&system.domain, process_grid, reach) {
                return Err(format!(
                    "the process grid {process_grid:?} of the flow makes boxes narrower than \
                     the grains' reach {reach:.3e} m; allowed: fewer ranks along the short axes"
                ));
            }
        }
        let counts = boxes.grains_per_box(&system.domain, &centres);
        let mean = centres.len() as f64 / ranks as f64;
        let _ = writeln!(
            out,
            "  grains per rank at the start: {} to {} (mean {mean:.0})",
            counts.iter().min().unwrap(),
            counts.iter().max().unwrap()
        );
        // In a fluid the cells carry the work (a grain's forcing is done
        // cell by cell): only a dry scene is judged by its grains.
        if grid.is_none() {
            mean_grains = grains_judged(case, mean);
        }
    }
    if let Some(warning) = load_warning(ranks, mean_grains, mean_cells) {
        let _ = writeln!(out, "  {warning}");
    }
    Ok(out)
}

fn positions(system: &DemSystem) -> Vec<Vec3> {
    let p = &system.particles;
    p.position[..p.n_owned].to_vec()
}

/// The flow grid of a case with a fluid (None for a dry scene).
pub fn flow_grid(case: &Case) -> Option<Grid> {
    case.fluid.is_some().then(|| fluid_scene::grid(case))
}
