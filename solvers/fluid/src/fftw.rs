//! FFTW's real-to-real transforms for the direct solvers (cargo feature
//! `fftw`, linked against the system's libfftw3).
//!
//! The transforms are the same as [`crate::transform`]'s, with FFTW's
//! unnormalised kinds (FFTW manual, §4.8 "What FFTW really computes"):
//!
//! | kind            | forward       | backward      | round trip    |
//! |-----------------|---------------|---------------|---------------|
//! | `Periodic`      | R2HC          | HC2R          | `n`           |
//! | `Neumann`       | REDFT10 (DCT-II) | REDFT01 (DCT-III) | `2n`   |
//! | `DirichletCell` | RODFT10 (DST-II) | RODFT01 (DST-III) | `2n`   |
//! | `DirichletFace` | RODFT00 (DST-I)  | RODFT00          | `2(n+1)` |
//! | `DirichletNeumann` | RODFT11 (DST-IV) | RODFT11        | `2n`     |
//! | `NeumannDirichlet` | REDFT11 (DCT-IV) | REDFT11        | `2n`     |
//!
//! Entry `k` of each holds the same mode as the pure-Rust transform (R2HC
//! uses the same halfcomplex order), up to a constant factor, so the
//! eigenvalues `−(2 − 2 cos θ_k)/h²` of [`crate::transform::AxisTransform::angles`]
//! apply unchanged; the backward transform divides by the round trip.
//!
//! Unlike the pure-Rust path, which gathers each strided line into a
//! buffer, one FFTW "guru" plan covers every line along an axis of the
//! solver's modal array in place, strides included. FFTW's planner is not
//! thread-safe: plans are made and destroyed under one lock. The batch is
//! split along its outermost dimension into a fixed number of parts
//! ([`PARTS`] at most), each planned once and run on whichever thread of the
//! pool takes it. The parts do not follow the number of threads: FFTW may
//! choose another algorithm, with other rounding, for another batch size,
//! and a split per thread made the bits of a run depend on the threads.

use std::sync::Mutex;

use fftw_sys as ffi;
use rayon::prelude::*;

use crate::transform::{Direction, TransformKind};

/// How FFTW chooses its algorithms: by estimate. FFTW_MEASURE times the
/// candidates on the machine and keeps the fastest, so on a loaded node
/// two runs of a case (or a run and its restart) could take different
/// algorithms with different rounding: two runs of the immersed avalanche
/// on 2 ranks differed from the third row of their series, and a resumed
/// run from the one that never stopped. FFTW_ESTIMATE picks by a model of
/// the machine, the same plans every time, so runs and restarts agree bit
/// for bit.
const PLANNING: u32 = ffi::FFTW_ESTIMATE;

/// Serialises FFTW's planner (plan creation and destruction).
static PLANNER: Mutex<()> = Mutex::new(());

/// One FFTW plan over a contiguous part of the modal array.
struct ChunkPlan {
    plan: ffi::fftw_plan,
    /// The part of the array it was planned on: `start..start + len`.
    start: usize,
    len: usize,
}

// An FFTW plan is read-only once made; executing it on distinct arrays
// from several threads is thread-safe (FFTW manual, §5.4).
unsafe impl Send for ChunkPlan {}
unsafe impl Sync for ChunkPlan {}

impl Drop for ChunkPlan {
    fn drop(&mut self) {
        let _lock = PLANNER.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: the plan was made by fftw_plan_guru64_r2r and is
        // destroyed once.
        unsafe { ffi::fftw_destroy_plan(self.plan) };
    }
}

/// The parts a batch of lines is planned in when it is transformed on a
/// pool of threads: enough for the cores of a node, the same for any
/// number of threads.
pub const PARTS: usize = 16;

/// The forward and backward transforms of every line along one axis of a
/// flat array of a given shape (x fastest), planned in place on that array.
pub struct BatchTransform {
    forward: Vec<ChunkPlan>,
    backward: Vec<ChunkPlan>,
    /// `1 / round trip`, applied after the backward transform.
    scale: f64,
}

impl BatchTransform {
    /// Plans the transforms of `kind` along `axis` of `data`, whose shape
    /// is `shape`, in `parts` parts along the outermost dimension (at most
    /// one per outer index). Plans are chosen by FFTW's estimate, not by
    /// timing (see [`PLANNING`]); `data` is left as it is.
    pub fn new(
        kind: TransformKind,
        data: &mut [f64],
        shape: [usize; 3],
        axis: usize,
        parts: usize,
    ) -> Self {
        assert_eq!(data.len(), shape.iter().product::<usize>());
        let len = shape[axis];
        let (forward_kind, backward_kind, round_trip) = match kind {
            TransformKind::Periodic => (
                ffi::fftw_r2r_kind::FFTW_R2HC,
                ffi::fftw_r2r_kind::FFTW_HC2R,
                len,
            ),
            TransformKind::Neumann => (
                ffi::fftw_r2r_kind::FFTW_REDFT10,
                ffi::fftw_r2r_kind::FFTW_REDFT01,
                2 * len,
            ),
            TransformKind::DirichletCell => (
                ffi::fftw_r2r_kind::FFTW_RODFT10,
                ffi::fftw_r2r_kind::FFTW_RODFT01,
                2 * len,
            ),
            TransformKind::DirichletFace => (
                ffi::fftw_r2r_kind::FFTW_RODFT00,
                ffi::fftw_r2r_kind::FFTW_RODFT00,
                2 * (len + 1),
            ),
            TransformKind::DirichletNeumann => (
                ffi::fftw_r2r_kind::FFTW_RODFT11,
                ffi::fftw_r2r_kind::FFTW_RODFT11,
                2 * len,
            ),
            TransformKind::NeumannDirichlet => (
                ffi::fftw_r2r_kind::FFTW_REDFT11,
                ffi::fftw_r2r_kind::FFTW_REDFT11,
                2 * len,
            ),
        };
        let inner: usize = shape[..axis].iter().product();
        let outer: usize = shape[axis + 1..].iter().product();
        let block = inner * len;
        let chunks = parts.clamp(1, outer.max(1));
        let plans = |fftw_kind: ffi::fftw_r2r_kind, data: &mut [f64]| {
            (0..chunks)
                .filter_map(|chunk| {
                    let first = outer * chunk / chunks;
                    let last = outer * (chunk + 1) / chunks;
                    (last > first).then(|| {
                        let part = &mut data[first * block..last * block];
                        plan_lines(fftw_kind, part, len, inner, last - first, first * block)
                    })
                })
                .collect::<Vec<_>>()
        };
        BatchTransform {
            forward: plans(forward_kind, data),
            backward: plans(backward_kind, data),
            scale: 1.0 / round_trip as f64,
        }
    }

    /// Transforms every line of `data` (the array it was planned on).
    pub fn apply(&self, data: &mut [f64], direction: Direction) {
        let plans = match direction {
            Direction::Forward => &self.forward,
            Direction::Backward => &self.backward,
        };
        let scale = self.scale;
        let run = |plan: &ChunkPlan, part: &mut [f64]| {
            debug_assert_eq!(part.len(), plan.len);
            // SAFETY: `part` is the slice the plan was made on (same
            // length, strides and alignment), transformed in place.
            unsafe { ffi::fftw_execute_r2r(plan.plan, part.as_mut_ptr(), part.as_mut_ptr()) };
            if direction == Direction::Backward {
                part.iter_mut().for_each(|x| *x *= scale);
            }
        };
        if plans.len() == 1 {
            let plan = &plans[0];
            run(plan, &mut data[plan.start..plan.start + plan.len]);
            return;
        }
        let mut parts = Vec::with_capacity(plans.len());
        let mut rest = data;
        let mut offset = 0;
        for plan in plans {
            let (_, tail) = rest.split_at_mut(plan.start - offset);
            let (part, tail) = tail.split_at_mut(plan.len);
            parts.push((plan, part));
            rest = tail;
            offset = plan.start + plan.len;
        }
        parts
            .into_par_iter()
            .for_each(|(plan, part)| run(plan, part));
    }
}

/// One guru plan over `count` blocks of `inner` interleaved lines of `len`
/// values (line stride `inner`, block stride `inner · len`) in `part`.
fn plan_lines(
    kind: ffi::fftw_r2r_kind,
    part: &mut [f64],
    len: usize,
    inner: usize,
    count: usize,
    start: usize,
) -> ChunkPlan {
    let line = ffi::fftw_iodim64 {
        n: len as isize,
        is: inner as isize,
        os: inner as isize,
    };
    let batches = [
        ffi::fftw_iodim64 {
            n: inner as isize,
            is: 1,
            os: 1,
        },
        ffi::fftw_iodim64 {
            n: count as isize,
            is: (inner * len) as isize,
            os: (inner * len) as isize,
        },
    ];
    let _lock = PLANNER.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: the dimensions describe `part` exactly (count blocks of
    // inner × len values); in-place r2r plans are allowed.
    let plan = unsafe {
        ffi::fftw_plan_guru64_r2r(
            1,
            &line,
            2,
            batches.as_ptr(),
            part.as_mut_ptr(),
            part.as_mut_ptr(),
            &kind,
            PLANNING,
        )
    };
    assert!(
        !plan.is_null(),
        "FFTW could not plan a transform of {len} values"
    );
    ChunkPlan {
        plan,
        start,
        len: part.len(),
    }
}
