//! What a COCD step costs before one is taken: a step of a large packing
//! takes minutes to hours (its Cholesky factor's work grows about as N²
//! in 3D), so `check` does not time one where the fit below says it
//! would take longer than [`PROBE_LONGEST_STEP`], and says so.
//!
//! Fitted on packings at rest (every grain in contact, the most a step
//! holds), one thread of this project's 2-core machine, the other core
//! idle, with faer 0.24's kernels (`docs/performance.md`, "Hard
//! contact"), `c N^b` through the two largest packings measured: 3D at
//! ε = 1e-5, 89.3 and 3,370 s at 17,986 and 112,896 spheres (N^1.98;
//! ε = 1e-8 took 105.1 s against 89.3 at 17,986, 18 iterations against
//! 15, and scales the 3D figure below 1e-6); 2D at ε = 1e-8, 6.76 and
//! 17.25 s at 50,000 and 100,000 discs.

use super::cost_estimate::clock;
use grainflow_contact::ConicSolver;

/// The longest step `check` times (s).
pub const PROBE_LONGEST_STEP: f64 = 60.0;

const SECONDS_3D: [(f64, f64); 2] = [(17_986.0, 89.3), (112_896.0, 3_370.0)];
/// A 3D step at ε below 1e-6 against one at 1e-5 (17,986 spheres).
const TIGHT_OVER_LOOSE_3D: f64 = 105.1 / 89.3;
const SECONDS_2D: [(f64, f64); 2] = [(50_000.0, 6.76), (100_000.0, 17.25)];

/// The projected gradient's first step on the same kind of packing (the
/// soft DEM's deposit, radii shrunk by 1.5 %), one thread, ε = 1e-5, with
/// each 3D contact's rows held as one block (2026-12-07,
/// `docs/performance.md`, *Hard contact*): 0.413, 0.424 s at 8,748 spheres
/// and 12.11, 13.88 s at 111,132; at ε = 1e-8 0.609, 0.711 s at 8,748. A
/// jammed packing takes many more iterations (the 3D static box's first
/// step: 13,040 at 1e-5, against 110 here), so this is what a step costs
/// at the least.
const PROJECTED_GRADIENT_3D: [(f64, f64); 2] = [(8_748.0, 0.4185), (111_132.0, 13.0)];
const PROJECTED_GRADIENT_TIGHT_OVER_LOOSE: f64 = 0.660 / 0.4185;

/// Clarabel on the same 3D program of 8,748 spheres took 59 times the
/// interior point's time (2,256 s against 38.1 s, `docs/performance.md`,
/// before faer 0.24's kernels made the interior point faster still).
const CLARABEL_OVER_INTERIOR_POINT: f64 = 59.0;

/// Seconds of one COCD step of `grains` at rest in `dimension` with
/// grainflow's interior point at the tolerance `tolerance`, one thread of
/// the reference machine.
pub fn step_seconds(dimension: usize, grains: f64, tolerance: f64) -> f64 {
    let ([(n0, t0), (n1, t1)], scale) = if dimension == 3 {
        let tight = tolerance < 1e-6;
        (SECONDS_3D, if tight { TIGHT_OVER_LOOSE_3D } else { 1.0 })
    } else {
        (SECONDS_2D, 1.0)
    };
    let exponent = (t1 / t0).ln() / (n1 / n0).ln();
    scale * t0 * (grains / n0).powf(exponent)
}

/// Seconds of the first COCD step of `spheres` 3D spheres with grainflow's
/// projected gradient at `tolerance`, one thread, on a packing like the
/// benchmark's (at the least: a jammed packing takes more).
pub fn projected_gradient_seconds(spheres: f64, tolerance: f64) -> f64 {
    let [(n0, t0), (n1, t1)] = PROJECTED_GRADIENT_3D;
    let exponent = (t1 / t0).ln() / (n1 / n0).ln();
    let scale = if tolerance < 1e-6 {
        PROJECTED_GRADIENT_TIGHT_OVER_LOOSE
    } else {
        1.0
    };
    scale * t0 * (spheres / n0).powf(exponent)
}

/// The `check` line for a COCD scene too large to time a step of, or
/// `None` where a step is short enough to time here.
pub fn untimed_line(
    dimension: usize,
    grains: usize,
    steps: f64,
    solver: ConicSolver,
    tolerance: f64,
) -> Option<String> {
    let step = match solver {
        ConicSolver::InteriorPoint => step_seconds(dimension, grains as f64, tolerance),
        ConicSolver::Clarabel => {
            CLARABEL_OVER_INTERIOR_POINT * step_seconds(dimension, grains as f64, tolerance)
        }
        ConicSolver::ProjectedGradient if dimension == 3 => {
            projected_gradient_seconds(grains as f64, tolerance)
        }
        // No 2D fit: its step is timed on the scene itself.
        ConicSolver::ProjectedGradient => return None,
    };
    // Where the interior point's factor sets a long step, what the
    // projected gradient's would cost.
    let other = match solver {
        ConicSolver::InteriorPoint if dimension == 3 => format!(
            "; contact.conic_solver = \"projected_gradient\" (one rank, no factor) takes about \
             {} a step on such a packing, more on a jammed one",
            clock(projected_gradient_seconds(grains as f64, tolerance))
        ),
        _ => String::new(),
    };
    (step > PROBE_LONGEST_STEP).then(|| {
        format!(
            "estimated wall time: not timed here: a COCD step of {grains} grains at rest takes \
             about {} with {} on one thread of a 2-core machine (fitted on packings of up to {} \
             grains, docs/performance.md), {steps:.0} steps about {}; a loose flow is cheaper, \
             more threads or ranks share it{other}",
            clock(step),
            solver.name(),
            if dimension == 3 { "112,896" } else { "100,000" },
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
        assert!((step_seconds(3, 112_896.0, 1e-5) / 3_370.0 - 1.0).abs() < 1e-12);
        assert!((step_seconds(3, 17_986.0, 1e-8) / 105.1 - 1.0).abs() < 1e-12);
        assert!((step_seconds(2, 50_000.0, 1e-8) / 6.76 - 1.0).abs() < 1e-12);
        // Below the fit: 8,748 spheres took 21.5 and 20.6 s at ε = 1e-5,
        // 27.2 and 26.8 s at 1e-8; the fit says within 10 %.
        assert!((step_seconds(3, 8_748.0, 1e-5) / 21.07 - 1.0).abs() < 0.1);
        assert!((step_seconds(3, 8_748.0, 1e-8) / 27.0 - 1.0).abs() < 0.1);
        // The 2D erodible-bed scenes (up to some 10⁴ discs) are timed.
        let ours = ConicSolver::InteriorPoint;
        assert!(untimed_line(2, 20_000, 1000.0, ours, 1e-8).is_none());
        assert!(untimed_line(3, 10_000, 10.0, ours, 1e-8).is_none());
        // The paper's 122,932 spheres: about 1.2 hours a step at 1e-8.
        let line = untimed_line(3, 122_932, 10.0, ours, 1e-8).unwrap();
        assert!(line.contains("about 1:1"), "{line}");
        assert!(line.contains("\"projected_gradient\""), "{line}");
        // The projected gradient through its measured points, and timed up
        // to a few 10⁵ spheres.
        assert!((projected_gradient_seconds(111_132.0, 1e-5) / 13.0 - 1.0).abs() < 1e-12);
        assert!((projected_gradient_seconds(8_748.0, 1e-8) / 0.660 - 1.0).abs() < 1e-12);
        let gradient = ConicSolver::ProjectedGradient;
        assert!(untimed_line(3, 122_932, 10.0, gradient, 1e-5).is_none());
        assert!(untimed_line(3, 1_000_000, 10.0, gradient, 1e-5).is_some());
        // Clarabel is not timed on 10,000 spheres.
        assert!(untimed_line(3, 10_000, 10.0, ConicSolver::Clarabel, 1e-8).is_some());
    }
}
