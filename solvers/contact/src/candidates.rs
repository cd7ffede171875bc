//! Which listed pairs enter a step's program.
//!
//! The neighbour list reaches every pair that any grain could close within
//! the step: the gap D, widened to 3 v_max Δt (two grains at the fastest
//! free speed, and half again for the speed contacts add). Most of those
//! pairs cannot close: in a flowing mass neighbours move together, and a
//! pair's gap changes by Δt n·(v_i − v_j), not by Δt v_max. Put into the
//! program, they make it larger and its factor denser for nothing: a
//! release of 12,400 discs at 0.5 m/s held 4.3–5.3 candidates per disc.
//!
//! So the program starts from the pairs whose constraint (below) the free
//! motion brings within D of breaking, with half again of the free
//! relative velocity for what contacts add, and every pair left out is
//! checked at the solution. With no
//! impulse, a left-out pair meets its contact law exactly when it meets its
//! constraint:
//!
//! - COCD, the convexified non-penetration of eq. 9:
//!   D_α + Δt (v_n − μ |v_t|) ≥ 0;
//! - NSCD, Signorini's bound on the predicted gap: v_n ≥ b_α.
//!
//! If every left-out pair meets it, the solution satisfies every
//! optimality condition of the program over all listed pairs, and is its
//! solution. Otherwise the pairs that fail join the program, with those
//! the end motion brings within D of failing, and it is solved again;
//! after [`ROUNDS`] programs (fewer where the list is not much larger
//! than the program) every listed pair enters, which is the whole
//! program. In the release above a second program was needed in about
//! one step in three, and a step cost a quarter of the whole program's.

use crate::cocd::Solution;
use crate::contacts::{Bodies, ContactSet, Partner, STATIC};
use grainflow_core::Vec3;
use grainflow_dem::DemSystem;

/// Programs solved in a step before every listed pair enters. The whole
/// list is the last resort, not the next round: where grains fall fast
/// the reach 3 v_max Δt lists far more pairs than can close (a rain of
/// 42,000 discs of 1 mm at 2–3 m/s: 2.05 million listed, 68,500 in the
/// program), and a step that needed a fourth round then solved a
/// program thirty times larger (542 s against about 10 s, interior
/// point). Each round adds only the pairs that broke and their
/// neighbours in reach (177, then 11, then 1 in that rain), so a few
/// more rounds settle it.
pub const ROUNDS: u32 = 8;

/// Programs after which the whole list enters where it is at most
/// [`WHOLE_LIST_FACTOR`] times the program: one more solve then costs
/// about what a round does and ends the step.
const EARLY_ROUNDS: u32 = 3;
const WHOLE_LIST_FACTOR: usize = 2;

/// Whether the next program, after `programs` with some pair broken,
/// takes every listed pair (`in_program` marks those in the last one):
/// after [`ROUNDS`], or after [`EARLY_ROUNDS`] where the list is not
/// much larger than the program.
pub fn take_the_whole_list(programs: u32, in_program: &[bool]) -> bool {
    let held = in_program.iter().filter(|&&in_it| in_it).count();
    programs >= ROUNDS || (programs >= EARLY_ROUNDS && in_program.len() <= WHOLE_LIST_FACTOR * held)
}

/// Whether each listed pair may come within D of breaking its constraint
/// on the grains' free motion (`free_velocity`, `free_spin` of every owned
/// grain; zero for a glued one): D_α + 1.5 Δt min(0, U_n − μ |U_t|) < D,
/// with U = A_α U the free relative velocity at the contact point.
pub fn within_reach(
    listed: &ContactSet,
    (free_velocity, free_spin): (&[Vec3], &[Vec3]),
    threshold: f64,
    dt: f64,
) -> Vec<bool> {
    (0..listed.len())
        .map(|a| {
            let n = listed.normal[a];
            let relative = relative_velocity(listed, a, free_velocity, free_spin);
            let u_n = relative.dot(&n);
            let u_t = (relative - u_n * n).norm();
            let closing = (u_n - listed.friction[a] * u_t).min(0.0);
            listed.gap[a] + 1.5 * dt * closing < threshold
        })
        .collect()
}

/// Velocity and spin of every owned grain at the end of the step: the
/// solution's for a body, the free motion for a grain without contact,
/// zero for a glued grain.
pub fn end_motion(
    system: &DemSystem,
    bodies: &Bodies,
    solution: &Solution,
    free_velocity: &[Vec3],
    free_spin: &[Vec3],
) -> (Vec<Vec3>, Vec<Vec3>) {
    let p = &system.particles;
    (0..p.n_owned)
        .map(|k| {
            if p.is_fixed(k) {
                (Vec3::zeros(), Vec3::zeros())
            } else if bodies.column[k] == STATIC {
                (free_velocity[k], free_spin[k])
            } else {
                let column = bodies.column[k] as usize;
                (solution.velocity[column], solution.spin[column])
            }
        })
        .unzip()
}

/// Relative velocity A_α u of listed pair `a` from the velocity and spin
/// of every owned grain (a wall does not move).
pub fn relative_velocity(listed: &ContactSet, a: usize, velocity: &[Vec3], spin: &[Vec3]) -> Vec3 {
    let i = listed.grain[a] as usize;
    let j = match listed.partner[a] {
        Partner::Grain(j) => Some((velocity[j as usize], spin[j as usize])),
        Partner::Wall(_) => None,
    };
    listed.relative_velocity_of(a, Some((velocity[i], spin[i])), j)
}

/// The law a left-out pair must meet with no impulse.
#[derive(Clone, Copy, Debug)]
pub enum LeftOutLaw {
    /// COCD: D_α + Δt (v_n − μ |v_t|) ≥ 0.
    Cone { dt: f64 },
    /// NSCD: v_n ≥ b_α, with b_α from the gap and the start velocity.
    Signorini { dt: f64, restitution: f64 },
}

/// The left-out pairs (`in_program[a]` false) that break `law` at the end
/// motion (`velocity`, `spin` of every owned grain); `start_velocity`,
/// `start_spin`: u^k of every owned grain, for NSCD's bound.
pub fn broken(
    listed: &ContactSet,
    in_program: &[bool],
    law: LeftOutLaw,
    (velocity, spin): (&[Vec3], &[Vec3]),
    (start_velocity, start_spin): (&[Vec3], &[Vec3]),
) -> Vec<usize> {
    (0..listed.len())
        .filter(|&a| !in_program[a])
        .filter(|&a| {
            let n = listed.normal[a];
            let relative = relative_velocity(listed, a, velocity, spin);
            let v_n = relative.dot(&n);
            match law {
                LeftOutLaw::Cone { dt } => {
                    let v_t = (relative - v_n * n).norm();
                    listed.gap[a] + dt * (v_n - listed.friction[a] * v_t) < 0.0
                }
                LeftOutLaw::Signorini { dt, restitution } => {
                    let start = relative_velocity(listed, a, start_velocity, start_spin);
                    let bound =
                        crate::nscd::normal_bound(listed.gap[a], start.dot(&n), dt, restitution);
                    v_n < bound
                }
            }
        })
        .collect()
}
