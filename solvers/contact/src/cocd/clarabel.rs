//! Clarabel, the reference solver of the program (and the last to take
//! over a step grainflow's interior point fails).

use super::program::ConicProgram;
use super::ConicSolution;
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// Solves the program with Clarabel: (x, z, iterations, reduced accuracy).
pub(crate) fn solve_with_clarabel(
    program: &ConicProgram,
    tolerance: f64,
    max_iterations: u32,
) -> Result<ConicSolution, String> {
    let columns = program.mass.len();
    let p_matrix = CscMatrix::new(
        columns,
        columns,
        (0..=columns).collect(),
        (0..columns).collect(),
        program.mass.clone(),
    );
    let q = program.q();
    let mut cones = Vec::new();
    if program.linear_rows > 0 {
        cones.push(SupportedConeT::NonnegativeConeT(program.linear_rows));
    }
    cones.extend((0..program.cone_count).map(|_| SupportedConeT::SecondOrderConeT(3)));

    // The objective is of order one in these units; its absolute gap
    // tolerance follows its size, so that a nearly still scene is solved as
    // accurately as a fast one.
    let size: f64 = program.size();
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .max_iter(max_iterations)
        .tol_gap_abs(tolerance * size.max(f64::MIN_POSITIVE))
        .tol_gap_rel(tolerance)
        .tol_feas(tolerance)
        .build()
        .map_err(|e| format!("COCD solver settings: {e}"))?;
    let mut solver = DefaultSolver::new(
        &p_matrix,
        &q,
        &program.a_matrix,
        &program.b,
        &cones,
        settings,
    )
    .map_err(|e| format!("COCD problem rejected by the conic solver: {e:?}"))?;
    solver.solve();
    let solution = &solver.solution;
    let reduced_accuracy = match solution.status {
        SolverStatus::Solved => false,
        SolverStatus::AlmostSolved => true,
        status => {
            return Err(format!(
                "the conic solver (Clarabel) stopped with status {status:?} after {} iterations \
                 ({} rows, {} unknowns)",
                solution.iterations,
                program.b.len(),
                columns
            ))
        }
    };
    Ok((
        solution.x.clone(),
        solution.z.clone(),
        solution.iterations,
        reduced_accuracy,
    ))
}
