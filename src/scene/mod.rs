//! Scene assembly: turns a validated [`Case`] into what a run steps: the
//! grains ([`build`], a [`DemSystem`]), the flow ([`fluid`]), the flow in
//! (r, z) ([`axisymmetric`]); with the grains poured during a run
//! ([`pouring`]), the deposits written once and read back ([`deposit`]),
//! and the checks of grains placed in contact ([`initial_overlaps`],
//! [`grain_pairs`]).

pub mod axisymmetric;
pub mod deposit;
pub mod fluid;
pub mod grain_pairs;
mod hard_limits;
pub mod initial_overlaps;
pub mod pouring;

use crate::case::{BlockSection, Case, ContactModel};
use grainflow_contact::{ConicSolver, HardContact, Method};
use grainflow_core::{
    balanced_cuts, balanced_process_grid, fits, process_grid, Communicator, Dimension, Domain,
    PairedGrains, ProcessGrid, Vec3,
};
use grainflow_dem::generate::{self, Material, RadiusDistribution};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::Lubrication;
use grainflow_dem::{ContactLaw, DemSystem, NormalCalibration, NormalStiffness, PlaneWall};
pub use hard_limits::{hard_contact_warnings, LONGEST_HARD_STEP, LOOSEST_COCD_TOLERANCE};
use rand::SeedableRng;
use rand_pcg::Pcg64;
use std::ops::Range;

/// A 2- or 3-component list as a vector (z = 0 in 2D; empty = zero).
pub fn vector(values: &[f64]) -> Vec3 {
    let mut v = Vec3::zeros();
    for (axis, value) in values.iter().enumerate().take(3) {
        v[axis] = *value;
    }
    v
}

pub fn domain(case: &Case) -> Domain {
    let d = &case.domain;
    let dimension = if d.dimension == 2 {
        Dimension::Two
    } else {
        Dimension::Three
    };
    let mut periodic = [false; 3];
    for (axis, &flag) in d.periodic.iter().enumerate() {
        periodic[axis] = flag;
    }
    let mut lower = vector(&d.lower);
    let mut upper = vector(&d.upper);
    if dimension == Dimension::Two {
        lower.z = 0.0;
        upper.z = 0.0;
    }
    Domain {
        dimension,
        lower,
        upper,
        periodic,
        gravity: vector(&d.gravity),
    }
}

pub fn contact_law(case: &Case) -> ContactLaw {
    let c = case.contact_section();
    if c.is_hard() {
        return ContactLaw::rigid(c.friction);
    }
    let normal = match (c.restitution, c.contact_time, c.stiffness, c.damping) {
        (Some(e), Some(tc), _, _) => {
            let calibration = if c.calibration() == "paper" {
                NormalCalibration::Paper
            } else {
                NormalCalibration::Exact
            };
            NormalStiffness::from_restitution(e, tc, calibration)
        }
        (_, _, Some(k), Some(g)) => NormalStiffness::Fixed {
            stiffness: k,
            damping: g,
        },
        _ => unreachable!("validated"),
    };
    ContactLaw {
        normal,
        tangential_ratio: c.tangential_ratio(),
        friction: c.friction,
        rolling_friction: c.rolling_friction,
    }
}

pub fn walls(case: &Case) -> Vec<PlaneWall> {
    let contact = case.contact_section();
    let default_friction = contact.wall_friction.unwrap_or(contact.friction);
    case.walls
        .iter()
        .enumerate()
        .map(|(k, w)| PlaneWall {
            name: w.name.clone().unwrap_or_else(|| format!("wall{k}")),
            point: vector(&w.point),
            normal: vector(&w.normal).normalize(),
            friction: w.friction.unwrap_or(default_friction),
            remove_at: w.remove_at,
            two_sided: w.two_sided,
        })
        .collect()
}

/// The particles of every generator block, in order, refused where a
/// moving grain starts inside another ([`initial_overlaps`]).
/// The particles of a case's blocks, and the group of each.
pub fn particles(case: &Case) -> Result<(Vec<NewParticle>, Vec<u64>), String> {
    let (placed, blocks, groups) = particles_by_block(case)?;
    initial_overlaps::check(&domain(case), &placed, &blocks)?;
    Ok((placed, groups))
}

/// The warning for glued grains placed overlapping each other, if any (a
/// moving grain placed inside another is an error, [`particles`]).
pub fn glued_overlap_warning(case: &Case) -> Result<Option<String>, String> {
    let (placed, blocks, _) = particles_by_block(case)?;
    initial_overlaps::check(&domain(case), &placed, &blocks)
}

/// The particles of every generator block, in order, the range each
/// block made and each particle's group: its block's index, or the
/// `group` column of a `file` block.
#[allow(clippy::type_complexity)]
fn particles_by_block(
    case: &Case,
) -> Result<(Vec<NewParticle>, Vec<Range<usize>>, Vec<u64>), String> {
    let p = case.particles_section();
    let dimension = domain(case).dimension;
    let mut rng = Pcg64::seed_from_u64(p.seed);
    let radii = RadiusDistribution {
        mean: p.radius,
        spread: p.radius_spread,
    };
    // A generator block's grains: the particles' density, its own
    // `fixed` and initial velocity.
    let material = |fixed: bool, velocity: &[f64]| Material {
        density: p.density,
        fixed,
        velocity: vector(velocity),
    };
    let mut all: Vec<NewParticle> = Vec::new();
    let mut blocks = Vec::with_capacity(p.block.len());
    let mut groups = Vec::new();
    for (k, block) in p.block.iter().enumerate() {
        let mut file_groups = None;
        let made = match block {
            BlockSection::Lattice {
                lower,
                upper,
                spacing,
                layer_spacing,
                jitter,
                fixed,
                velocity,
            } => {
                let material = material(*fixed, velocity);
                let last = dimension.count() - 1;
                let mut step = Vec3::repeat(*spacing);
                step[last] = layer_spacing.unwrap_or(*spacing);
                generate::lattice(
                    dimension,
                    vector(lower),
                    vector(upper),
                    step,
                    radii,
                    *jitter,
                    &material,
                    &mut rng,
                )
            }
            BlockSection::Random {
                lower,
                upper,
                count,
                fixed,
                velocity,
            } => {
                let material = material(*fixed, velocity);
                generate::random(
                    dimension,
                    vector(lower),
                    vector(upper),
                    *count,
                    radii,
                    &material,
                    &all,
                    &mut rng,
                )
                .map_err(|e| format!("particles.block[{k}] (random): {e}"))?
            }
            BlockSection::Explicit {
                positions,
                velocities,
                angular_velocities,
                radii: given,
                fixed,
            } => positions
                .iter()
                .enumerate()
                .map(|(n, x)| NewParticle {
                    position: vector(x),
                    velocity: velocities
                        .get(n)
                        .map(|v| vector(v))
                        .unwrap_or_else(Vec3::zeros),
                    angular_velocity: angular_velocities
                        .get(n)
                        .map(|w| vector(w))
                        .unwrap_or_else(Vec3::zeros),
                    radius: given.get(n).copied().unwrap_or(p.radius),
                    density: p.density,
                    fixed: *fixed,
                })
                .collect(),
            BlockSection::File {
                path,
                fixed,
                fixed_groups,
            } => {
                let in_file = |e: String| format!("particles.block[{k}] (file {path}): {e}");
                let (mut read, groups) =
                    read_particles(path, dimension, p.density, *fixed).map_err(in_file)?;
                glue_groups(&mut read, groups.as_deref(), fixed_groups).map_err(in_file)?;
                file_groups = groups;
                read
            }
            BlockSection::CollisionPairs {
                count,
                impact_speed,
                psi_max,
                gap,
            } => collision_pairs(
                dimension,
                *count,
                *impact_speed,
                *psi_max,
                *gap,
                p.radius,
                p.density,
            ),
        };
        if made.is_empty() {
            return Err(format!(
                "particles.block[{k}] creates no particle: enlarge its region"
            ));
        }
        blocks.push(all.len()..all.len() + made.len());
        match file_groups.take() {
            Some(read) => groups.extend(read),
            None => groups.extend(std::iter::repeat_n(k as u64, made.len())),
        }
        all.extend(made);
    }
    Ok((all, blocks, groups))
}

/// Glues the grains of a `file` block whose group (`groups`, the file's
/// column) is listed in `glued` (`fixed_groups`).
fn glue_groups(
    particles: &mut [NewParticle],
    groups: Option<&[u64]>,
    glued: &[u64],
) -> Result<(), String> {
    if glued.is_empty() {
        return Ok(());
    }
    let groups = groups.ok_or_else(|| {
        format!(
            "fixed_groups = {glued:?} needs a `group` column in the file (the columns of final_particles.csv); allowed: fixed_groups = [] or a file with groups"
        )
    })?;
    if let Some(missing) = glued.iter().find(|g| !groups.contains(g)) {
        let mut present = groups.to_vec();
        present.sort_unstable();
        present.dedup();
        return Err(format!(
            "fixed_groups lists group {missing}, which no grain of the file has; allowed: the file's groups {present:?}"
        ));
    }
    for (particle, group) in particles.iter_mut().zip(groups) {
        particle.fixed |= glued.contains(group);
    }
    Ok(())
}

/// Reads `x,y[,z],radius[,vx,vy[,vz]][,group]` rows after a header line
/// (the columns of `final_particles.csv`); the groups where the file has
/// them.
fn read_particles(
    path: &str,
    dimension: Dimension,
    density: f64,
    fixed: bool,
) -> Result<(Vec<NewParticle>, Option<Vec<u64>>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    let dim = dimension.count();
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or("empty file")?
        .split(',')
        .map(str::trim)
        .collect();
    let names: &[&str] = if dim == 3 {
        &["x", "y", "z", "radius"]
    } else {
        &["x", "y", "radius"]
    };
    if header.len() < names.len() || header[..names.len()] != *names {
        return Err(format!("the header must start with {}", names.join(",")));
    }
    let group_column = header.iter().position(|h| *h == "group");
    let numbers = header.len() - group_column.is_some() as usize;
    let with_velocity = numbers >= names.len() + dim;
    let mut out = Vec::new();
    let mut groups = Vec::new();
    for (n, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let values: Result<Vec<f64>, _> =
            line.split(',').map(|v| v.trim().parse::<f64>()).collect();
        let values = values.map_err(|e| format!("line {}: {e}", n + 2))?;
        if values.len() < names.len() {
            return Err(format!("line {}: expected {} values", n + 2, names.len()));
        }
        let position = vector(&values[..dim]);
        let radius = values[dim];
        if radius.is_nan() || radius <= 0.0 {
            return Err(format!("line {}: radius must be positive", n + 2));
        }
        let velocity = if with_velocity {
            vector(&values[dim + 1..2 * dim + 1])
        } else {
            Vec3::zeros()
        };
        if let Some(column) = group_column {
            let group = values.get(column).copied().unwrap_or(f64::NAN);
            if !(group >= 0.0 && group.fract() == 0.0) {
                return Err(format!(
                    "line {}: group must be a whole number ≥ 0, found {group}",
                    n + 2
                ));
            }
            groups.push(group as u64);
        }
        out.push(NewParticle {
            position,
            velocity,
            angular_velocity: Vec3::zeros(),
            radius,
            density,
            fixed,
        });
    }
    Ok((out, group_column.map(|_| groups)))
}

/// Pair k: particle 2k moving with (v_n, Ψ1 v_n) towards particle 2k + 1 at
/// rest, placed so that the centres line up along x at first touch (a
/// head-on normal with tangential slip Ψ1 v_n); pairs 10 r (+ the drift)
/// apart along y (3D: z) so that they never meet.
fn collision_pairs(
    dimension: Dimension,
    count: usize,
    impact_speed: f64,
    psi_max: f64,
    gap: f64,
    radius: f64,
    density: f64,
) -> Vec<NewParticle> {
    let mut out = Vec::with_capacity(2 * count);
    for k in 0..count {
        let psi = if count > 1 {
            psi_max * k as f64 / (count - 1) as f64
        } else {
            0.0
        };
        let mut centre = Vec3::zeros();
        let separation_axis = if dimension == Dimension::Two { 1 } else { 2 };
        centre[separation_axis] = (10.0 * radius + psi_max * gap) * k as f64;
        let half = radius + 0.5 * gap;
        let approach_drift = psi * gap;
        out.push(NewParticle {
            position: centre - Vec3::x() * half - Vec3::y() * approach_drift,
            velocity: Vec3::new(impact_speed, psi * impact_speed, 0.0),
            angular_velocity: Vec3::zeros(),
            radius,
            density,
            fixed: false,
        });
        out.push(NewParticle {
            position: centre + Vec3::x() * half,
            velocity: Vec3::zeros(),
            angular_velocity: Vec3::zeros(),
            radius,
            density,
            fixed: false,
        });
    }
    out
}

/// Default Verlet skin: a tenth of the mean diameter.
pub fn skin(case: &Case) -> f64 {
    case.contact_section()
        .skin
        .unwrap_or(0.2 * case.particles_section().radius)
}

/// The film force of eq. 19, for grains in a fluid with a `[lubrication]` table.
pub fn lubrication(case: &Case) -> Option<Lubrication> {
    let fluid = case.fluid.as_ref()?;
    let section = case.lubrication.as_ref()?;
    Some(Lubrication {
        viscosity: fluid.viscosity,
        roughness: section.roughness,
        range: section.range,
    })
}

/// Gap at which grains in a fluid start touching: `coupling.contact_gap`
/// cells of the fluid grid (0 in a dry scene).
pub fn contact_gap(case: &Case) -> f64 {
    let Some(fluid) = case.fluid.as_ref() else {
        return 0.0;
    };
    let cells = case.coupling.clone().unwrap_or_default().contact_gap;
    let dim = case.dimension();
    let smallest = (0..dim)
        .map(|a| (case.domain.upper[a] - case.domain.lower[a]) / fluid.cells[a] as f64)
        .fold(f64::INFINITY, f64::min);
    cells * smallest
}

/// Whether the scene's contacts are COCD's conic programs, whose step
/// factorises a sparse Cholesky factor at every interior-point iteration
/// (its ranks are balanced by grains and judged apart from the other
/// models').
pub fn solved_by_cocd(case: &Case) -> bool {
    case.contact_section().model == ContactModel::Cocd
}

/// Hard contact (Martin et al. 2022), for `contact.model` = cocd or nscd.
pub fn hard_contact(case: &Case) -> Option<HardContact> {
    let c = case.contact_section();
    let method = match c.model {
        ContactModel::Cocd => Method::Cocd,
        ContactModel::Nscd => Method::Nscd {
            restitution: c.restitution.unwrap_or(0.0),
        },
        ContactModel::Soft => return None,
    };
    let conic_solver = c.conic_solver();
    let (tolerance, iterations) = match (method, conic_solver) {
        (Method::Cocd, ConicSolver::ProjectedGradient) => (1e-8, 20_000),
        (Method::Cocd, _) => (1e-8, 200),
        (Method::Nscd { .. }, _) => (1e-6, 5000),
    };
    let mut hard = HardContact::new(
        method,
        c.tolerance.unwrap_or(tolerance),
        c.max_iterations.unwrap_or(iterations),
        c.threshold.unwrap_or(0.2 * case.particles_section().radius),
    );
    hard.conic_solver = conic_solver;
    hard.whole_list = c.candidates.as_deref() == Some("listed");
    Some(hard)
}

/// The scene's DEM system on one rank, with its particles placed.
pub fn build(case: &Case) -> Result<DemSystem, String> {
    build_on(case, Communicator::serial())
}

/// The scene's DEM system shared among the ranks of `communicator`: each
/// rank holds the particles of its box of the process grid.
pub fn build_on(case: &Case, communicator: Communicator) -> Result<DemSystem, String> {
    build_with(case, communicator, None, |_| 0.0)
}

/// [`build_on`] in the process grid `ranks` if given (that of the flow, for
/// grains in a fluid), with ghosts within `ghost_reach(r_max)` of each
/// subdomain at least (the reach of the grains' immersed boundaries).
pub fn build_with(
    case: &Case,
    communicator: Communicator,
    ranks: Option<[usize; 3]>,
    ghost_reach: impl Fn(f64) -> f64,
) -> Result<DemSystem, String> {
    let domain = domain(case);
    let (placed, groups) = particles(case)?;
    check_inside(&domain, &placed)?;
    let mut system = DemSystem::new(domain, contact_law(case), walls(case), skin(case));
    system.threads = case.parallel.as_ref().and_then(|p| p.threads);
    // Before the particles: the pair list reaches the lubrication range
    // and the contact gap.
    system.lubrication = lubrication(case);
    system.contact_gap = contact_gap(case);
    if let Some(hard) = hard_contact(case) {
        system.listing_gap = hard.threshold;
    }
    let max_radius = placed.iter().map(|p| p.radius).fold(0.0, f64::max);
    system.ghost_reach = ghost_reach(max_radius);
    let range = system.range_for(max_radius).max(system.ghost_reach);
    let grid = match ranks {
        Some(ranks) if fits(&system.domain, ranks, range) => ProcessGrid::even(ranks),
        Some(ranks) => {
            return Err(format!(
                "the process grid {ranks:?} of the flow makes boxes narrower than the grains' \
                 reach {range:.3e} m (interaction range and immersed boundary); allowed: fewer \
                 ranks along the short axes (parallel.process_grid)"
            ))
        }
        None => {
            let centres: Vec<Vec3> = placed.iter().map(|p| p.position).collect();
            let radii: Vec<f64> = placed.iter().map(|p| p.radius).collect();
            process_grid_of(
                case,
                &system.domain,
                communicator.size(),
                range,
                &centres,
                &radii,
            )?
        }
    };
    system.decompose_in(communicator, &grid);
    system.add_particles_in_groups(&placed, &groups);
    Ok(system)
}

/// The process grid of a dry case on `size` ranks: `parallel.process_grid`
/// if given (and more than one rank runs), else the one that shares the
/// grains at `positions` (of radii `radii`) best with the least area of
/// cuts. Every box must
/// be at least one interaction range wide along a split axis.
///
/// Under COCD the boxes end among the grains along each split axis that is
/// not periodic, every box with the same interior
/// ([`balanced_process_grid`]): the ranks factorise the grains along the
/// cuts together, and a shorter cut that shares the grains evenly makes
/// that separator smaller (a 2D packing of 50,000 discs at rest in the
/// lower half of its domain: 408 unknowns across its height against 831
/// along it; docs/cluster.md). Other scenes keep boxes
/// of equal lengths reaching the domain's faces, which hold a spreading
/// flow longer (a collapse's two halves stay with their ranks).
pub fn process_grid_of(
    case: &Case,
    domain: &Domain,
    size: usize,
    range: f64,
    positions: &[Vec3],
    radii: &[f64],
) -> Result<ProcessGrid, String> {
    let balanced = solved_by_cocd(case);
    let paired = PairedGrains {
        centres: positions,
        radii,
        pairing_gap: hard_contact(case).map_or(0.0, |hard| hard.threshold),
    };
    let Some(ranks) = case
        .parallel
        .as_ref()
        .and_then(|p| p.ranks())
        .filter(|_| size > 1)
    else {
        return if balanced {
            balanced_process_grid(domain, size, range, &paired)
        } else {
            process_grid(domain, size, range, positions).map(ProcessGrid::even)
        };
    };
    let given = case.parallel.as_ref().and_then(|p| p.process_grid.as_ref());
    if ranks.iter().product::<usize>() != size {
        return Err(format!(
            "parallel.process_grid = {:?} holds {} ranks, but the run has {size}; allowed: \
             counts whose product is the number of ranks",
            given.expect("set"),
            ranks.iter().product::<usize>()
        ));
    }
    let grid = ProcessGrid {
        ranks,
        cuts: if balanced {
            balanced_cuts(domain, ranks, range, &paired)
        } else {
            Default::default()
        },
    };
    if !grid.fits(domain, range) {
        return Err(format!(
            "parallel.process_grid = {:?} makes boxes narrower than the interaction range \
             {range:.3e} m along a split axis; allowed: fewer ranks along the short axes",
            given.expect("set")
        ));
    }
    Ok(grid)
}

fn check_inside(domain: &Domain, placed: &[NewParticle]) -> Result<(), String> {
    let dim = domain.dimension.count();
    for (k, p) in placed.iter().enumerate() {
        for axis in 0..dim {
            if p.position[axis] < domain.lower[axis] || p.position[axis] > domain.upper[axis] {
                return Err(format!(
                    "particle {k} at {:?} lies outside the domain [{:?}, {:?}]: enlarge domain.lower/upper",
                    p.position.as_slice(),
                    &domain.lower.as_slice()[..dim],
                    &domain.upper.as_slice()[..dim]
                ));
            }
        }
    }
    // A periodic axis must hold at least two interaction ranges, so that a
    // pair has a single image.
    let r_max = placed.iter().map(|p| p.radius).fold(0.0, f64::max);
    let extent = domain.extent();
    for axis in 0..dim {
        if domain.periodic[axis] && extent[axis] < 2.0 * (2.0 * r_max) * 1.2 {
            return Err(format!(
                "domain.periodic: axis {axis} is {:.3e} m long, less than 2.4 largest diameters; enlarge it",
                extent[axis]
            ));
        }
    }
    Ok(())
}
