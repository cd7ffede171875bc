//! Cost of the line transforms of the direct solvers on the grids of the
//! flow benchmarks: every line along x, then along y, of a 64³ and a 128³
//! array, forward and backward, for the periodic (real FFT) and Neumann
//! (DCT-II/III) kinds. Prints the median over repeats of ns per value per
//! transform (forward + backward counted as two), on the threads of the
//! pool (`RAYON_NUM_THREADS`). `scripts/bench/transforms.py` runs FFTW on
//! the same lines beside it.
//!
//! usage: cargo bench -p grainflow-fluid --bench transforms

use grainflow_fluid::transform::{AxisTransform, Direction, TransformKind};
use std::time::Instant;

fn main() {
    for n in [64, 128] {
        let shape = [n, n, n];
        let values = n * n * n;
        for kind in [TransformKind::Periodic, TransformKind::Neumann] {
            for axis in [0, 1] {
                let mut transform = AxisTransform::new(kind, n);
                let mut data: Vec<f64> = (0..values).map(|k| ((k * 7919) % 1013) as f64).collect();
                let repeats = if n == 64 { 21 } else { 7 };
                let mut samples = Vec::with_capacity(repeats);
                for _ in 0..repeats {
                    let started = Instant::now();
                    transform.apply_along(&mut data, shape, axis, Direction::Forward);
                    transform.apply_along(&mut data, shape, axis, Direction::Backward);
                    samples.push(started.elapsed().as_secs_f64() * 1e9 / (2 * values) as f64);
                }
                samples.sort_by(f64::total_cmp);
                println!(
                    "grainflow n={n} kind={kind:?} axis={axis} ns_per_value={:.3}",
                    samples[repeats / 2]
                );
            }
        }
    }
}
