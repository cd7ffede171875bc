//! What a COCD step costs before one is taken: a step of a large packing
//! takes minutes to hours (its Cholesky factor's work grows about as N²
//! in 3D), so `check` does not time one where the fit below says it
//! would take longer than [`PROBE_LONGEST_STEP`], and says so.
//!
//! Fitted on packings at rest (every grain in contact, the most a step
//! holds), one thread of this project's 2-core machine, ε = 1e-8, the
//! other core idle, with faer 0.24's kernels (`docs/performance.md`,
//! "The dense kernels"): 3D 27.0 and 105.1 s at 8,748 and 17,986
//! spheres, 2D 6.76 and 17.25 s at 50,000 and 100,000 discs. `c N^b`
//! through the two points.

use super::cost_estimate::clock;
use grainflow_contact::ConicSolver;

/// The longest step `check` times (s).
pub const PROBE_LONGEST_STEP: f64 = 60.0;

const SECONDS_3D: [(f64, f64); 2] = [(8_748.0, 27.0), (17_986.0, 105.1)];
const SECONDS_2D: [(f64, f64); 2] = [(50_000.0, 6.76), (100_000.0, 17.25)];

/// Clarabel on the same 3D program of 8,748 spheres took 59 times the
/// interior point's time (2,256 s against 38.1 s, `docs/performance.md`,
/// before faer 0.24's kernels made the interior point faster still).
const CLARABEL_OVER_INTERIOR_POINT: f64 = 59.0;

/// Seconds of one COCD step of `grains` at rest in `dimension` with
/// grainflow's interior point, one thread of the reference machine.
pub fn step_seconds(dimension: usize, grains: f64) -> f64 {
    let [(n0, t0), (n1, t1)] = if dimension == 3 {
        SECONDS_3D
    } else {
        SECONDS_2D
    };
    let exponent = (t1 / t0).ln() / (n1 / n0).ln();
    t0 * (grains / n0).powf(exponent)
}

/// The `check` line for a COCD scene too large to time a step of, or
/// `None` where a step is short enough to time here.
pub fn untimed_line(
    dimension: usize,
    grains: usize,
    steps: f64,
    solver: ConicSolver,
) -> Option<String> {
    let factor = match solver {
        ConicSolver::InteriorPoint => 1.0,
        ConicSolver::Clarabel => CLARABEL_OVER_INTERIOR_POINT,
    };
    let step = factor * step_seconds(dimension, grains as f64);
    (step > PROBE_LONGEST_STEP).then(|| {
        format!(
            "estimated wall time: not timed here: a COCD step of {grains} grains at rest takes \
             about {} with {} on one thread of a 2-core machine (fitted on packings of up to {} \
             grains, docs/performance.md), {steps:.0} steps about {}; a loose flow is cheaper, \
             more threads or ranks share it",
            clock(step),
            solver.name(),
            if dimension == 3 { "17,986" } else { "100,000" },
            clock(step * steps)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_is_timed_below_a_minute_and_predicted_above() {
        // Through the measured points.
        assert!((step_seconds(3, 8_748.0) / 27.0 - 1.0).abs() < 1e-12);
        assert!((step_seconds(2, 50_000.0) / 6.76 - 1.0).abs() < 1e-12);
        // The 2D erodible-bed scenes (up to some 10⁴ discs) are timed.
        let ours = ConicSolver::InteriorPoint;
        assert!(untimed_line(2, 20_000, 1000.0, ours).is_none());
        assert!(untimed_line(3, 10_000, 10.0, ours).is_none());
        // The paper's 122,932 spheres: about 1.1 hours a step.
        let line = untimed_line(3, 122_932, 10.0, ours).unwrap();
        assert!(line.contains("about 1:0"), "{line}");
        // Clarabel is not timed on 10,000 spheres.
        assert!(untimed_line(3, 10_000, 10.0, ConicSolver::Clarabel).is_some());
    }
}
