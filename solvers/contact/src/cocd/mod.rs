//! COCD: one conic program per step (Martin et al. 2022, eq. 10 and 13),
//! solved by grainflow's interior point on the normal equations
//! ([`crate::interior_point`]) or, on request and where it fails, by
//! Clarabel's (the reference).
//!
//! In the units of [`Scales`] (ũ = v/V for translations, ω L/V for
//! rotations; masses over m̄, inertias over m̄ L²; κ = VΔt/L) the program
//! reads
//!
//!   min ½ ũᵀM̃ũ − ũᵀM̃Ũ   subject to   s_α = (D_α/L + κ n·A_α ũ, κ μ T_α A_α ũ) ∈ K_α,
//!
//! with T_α the tangent basis and K_α the second-order cone {(y, x): |x| ≤ y}
//! of eq. 13 (the epigraph variable of eq. 13 is not needed: Clarabel takes
//! the quadratic objective directly). In 2D the cone {|x| ≤ y} is the two
//! half-planes y + x ≥ 0, y − x ≥ 0; a frictionless contact keeps only
//! y ≥ 0. Clarabel's form is min ½xᵀPx + qᵀx, Ax + s = b, s ∈ K, here with
//! P = M̃, q = −M̃Ũ, A = −H̃, b = (D_α/d̄, 0).
//!
//! Its optimality conditions M̃(ũ − Ũ) = H̃ᵀz are eq. 5 with the impulses
//! Δt f_α = (z_n n + μ T_αᵀ z_t) m̄ V κ: the dual z_α = (f_n, f_t/μ) lies in
//! the (self-dual) cone, which is Coulomb's |f_t| ≤ μ f_n, and z_α·s_α = 0
//! is eq. 6–8 (section 2.3).

//!
//! `program` assembles the program and reads its solution back,
//! `clarabel` hands it to the reference solver; this module chooses the
//! solver, and the one that takes over where it fails.

mod clarabel;
mod program;

pub use program::{build, ConicProgram};

use crate::contacts::{Bodies, ContactSet, Scales};
use crate::shared_program::{Ranks, SharedProgram};
use clarabel::solve_with_clarabel;
use grainflow_core::{Communicator, Dimension, Vec3};
use program::{dofs, multipliers, recover};

/// End-of-step velocities of the bodies and the impulses of the contacts.
#[derive(Clone, Debug, Default)]
pub struct Solution {
    pub velocity: Vec<Vec3>,
    pub spin: Vec<Vec3>,
    /// Normal impulse Δt f_n and tangential impulse Δt f_t of each contact.
    pub normal_impulse: Vec<f64>,
    pub tangential_impulse: Vec<Vec3>,
    pub iterations: u32,
    /// Whether the solver stopped at reduced accuracy.
    pub reduced_accuracy: bool,
    /// Why grainflow's interior point failed, where Clarabel took the step
    /// over.
    pub fallback_reason: Option<String>,
}
/// Which interior-point code solves the conic program.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConicSolver {
    /// grainflow's own, on the normal equations M̃ + H̃ᵀΘH̃ (linear and
    /// second-order cones); see [`crate::interior_point`].
    InteriorPoint,
    /// Clarabel (any cone), the reference.
    Clarabel,
    /// An accelerated projected gradient on the dual (no factor; one rank);
    /// grainflow's interior point takes over a step it does not solve
    /// within its iterations. See [`crate::projected_gradient`].
    ProjectedGradient,
}

impl ConicSolver {
    /// Its name in the log and in `check`.
    pub fn name(self) -> &'static str {
        match self {
            ConicSolver::InteriorPoint => "grainflow's interior point",
            ConicSolver::Clarabel => "Clarabel",
            ConicSolver::ProjectedGradient => "grainflow's projected gradient",
        }
    }
}
/// A rank's part of a program shared among ranks ([`crate::shared_program`]):
/// `separator[b]` for the bodies whose grain another rank's pairs also
/// reach, `ids` the local grains' ids; `separator_room`: the bytes a rank
/// can give the interior point's dense Schur complement where it takes
/// over a step of the projected gradient (None: no bound).
pub struct RankShare<'a> {
    pub separator: &'a [bool],
    pub ids: &'a [u64],
    pub communicator: &'a Communicator,
    pub separator_room: Option<f64>,
}

/// Solves the step's conic program with `solver` (Clarabel taking over a
/// step grainflow's interior point fails, the interior point one its
/// projected gradient fails). `tolerance`: the relative gap and feasibility
/// tolerances (ε of section 3.2). `shared`: on several ranks, this rank's
/// part of the program (collective): grainflow's interior point and
/// projected gradient solve it shared, Clarabel the whole program gathered
/// on every rank. `start`: the
/// impulses (normal, tangential) each contact starts from, the last step's
/// where it was there, as [`Solution`] holds them; the projected gradient
/// alone reads them (the interior points start from their own point).
#[allow(clippy::too_many_arguments)]
pub fn solve(
    contacts: &ContactSet,
    bodies: &Bodies,
    dimension: Dimension,
    scales: &Scales,
    tolerance: f64,
    max_iterations: u32,
    solver: ConicSolver,
    shared: Option<RankShare<'_>>,
    start: Option<&[(f64, Vec3)]>,
) -> Result<Solution, String> {
    let program = build(contacts, bodies, dimension, scales);
    let start = start.map(|impulses| multipliers(contacts, &program, impulses));
    let ((x, z, iterations, reduced_accuracy), fallback_reason) = match shared {
        None => {
            let ranks = Ranks::alone(program.mass.len());
            solve_with_fallbacks(
                solver,
                &program,
                (tolerance, max_iterations),
                start.as_deref(),
                ranks,
                None,
                |iterations| solve_with_clarabel(&program, tolerance, iterations),
            )?
        }
        Some(RankShare {
            separator,
            ids,
            communicator,
            separator_room,
        }) => {
            let d = dofs(dimension);
            let shared = SharedProgram::new(&program, bodies, d, separator, ids, communicator)?;
            let ranks = Ranks {
                communicator: Some(communicator),
                interior: shared.interior,
            };
            // Where the separator's dense blocks would not fit, the
            // projected gradient's failure stops the run instead of the
            // interior point running out of memory (ns is the same on
            // every rank, and so is the verdict).
            let unknowns = shared.program.mass.len() - shared.interior;
            let blocks = crate::shared_program::separator_block_bytes(unknowns);
            let room = separator_room.unwrap_or(f64::INFINITY);
            let refused = (solver == ConicSolver::ProjectedGradient
                && communicator.any(blocks > room))
            .then(|| {
                format!(
                    "the interior point is not tried on these ranks: its Schur complement over \
                     the separator's {unknowns} unknowns needs about {} on every rank, {} left \
                     beside a rank's share (raise contact.max_iterations, loosen \
                     contact.tolerance, or run on fewer ranks)",
                    grainflow_core::human_bytes(blocks),
                    grainflow_core::human_bytes(room.max(0.0)),
                )
            });
            // The solvers' decisions are taken over all ranks: one fails on
            // every rank alike, and every rank takes the next one's.
            let ((x, z, iterations, reduced), why) = solve_with_fallbacks(
                solver,
                &shared.program,
                (tolerance, max_iterations),
                start.as_deref(),
                ranks,
                refused,
                |iterations| {
                    let (whole, layout) = shared.gathered(communicator);
                    let (x, z, iterations, reduced) =
                        solve_with_clarabel(&whole, tolerance, iterations)?;
                    let (x, z) = layout.rank_part(&x, &z);
                    Ok((x, z, iterations, reduced))
                },
            )?;
            ((shared.local_unknowns(&x, d), z, iterations, reduced), why)
        }
    };
    let mut solution = recover(contacts, &program, &x, &z, iterations, reduced_accuracy);
    solution.fallback_reason = fallback_reason;
    Ok(solution)
}

/// The interior point's iterations where it takes over a step the
/// projected gradient did not solve (the case's `max_iterations` is the
/// projected gradient's then).
const INTERIOR_POINT_ITERATIONS: u32 = 200;

/// (x, z, iterations, reduced accuracy) of a conic solve.
type ConicSolution = (Vec<f64>, Vec<f64>, u32, bool);

/// The solution of `solver` on `program` (shared among `ranks`), with why
/// the solvers before the one that solved it failed: grainflow's projected
/// gradient hands a step it does not solve to the interior point
/// ([`INTERIOR_POINT_ITERATIONS`]), the interior point one it fails to
/// `clarabel` (and the run stops if Clarabel fails too); Clarabel alone on
/// request. `asked`: ε and the iterations; `start`: the projected
/// gradient's multipliers; `refused`: why the interior point may not take
/// over from the projected gradient (the step then fails with both
/// reasons); `clarabel` takes its iterations (the case's, the interior
/// point's after the projected gradient).
fn solve_with_fallbacks(
    solver: ConicSolver,
    program: &ConicProgram,
    (tolerance, max_iterations): (f64, u32),
    start: Option<&[f64]>,
    ranks: Ranks<'_>,
    refused: Option<String>,
    clarabel: impl FnOnce(u32) -> Result<ConicSolution, String>,
) -> Result<(ConicSolution, Option<String>), String> {
    let (interior_point_iterations, earlier) = match solver {
        ConicSolver::Clarabel => return Ok((clarabel(max_iterations)?, None)),
        ConicSolver::InteriorPoint => (max_iterations, None),
        ConicSolver::ProjectedGradient => {
            match crate::projected_gradient::solve(program, tolerance, max_iterations, start, ranks)
            {
                Ok(solution) => return Ok((solution, None)),
                Err(why) => match refused {
                    Some(refused) => return Err(format!("{why}; {refused}")),
                    None => (INTERIOR_POINT_ITERATIONS, Some(why)),
                },
            }
        }
    };
    let joined = |why: String| match &earlier {
        Some(earlier) => format!("{earlier}; then {why}"),
        None => why,
    };
    match crate::interior_point::solve(program, tolerance, interior_point_iterations, ranks) {
        Ok(solution) => Ok((solution, earlier)),
        Err(why) => {
            let why = joined(why);
            let solution = clarabel(interior_point_iterations)
                .map_err(|again| format!("{why}; then {again}"))?;
            Ok((solution, Some(why)))
        }
    }
}
