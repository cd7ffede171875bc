//! One-dimensional real-to-real transforms that diagonalise the three-point
//! second difference along one axis.
//!
//! The discrete operator `(f[j-1] - 2 f[j] + f[j+1]) / h²` on `n` unknowns
//! has, for each end condition below, a complete set of eigenvectors
//! (Fourier, cosine or sine modes) with eigenvalues `-(2 - 2 cos θ_k) / h²`.
//! Transforming a line, dividing by the eigenvalue and transforming back is
//! therefore an exact (round-off) inverse of the discrete operator.
//!
//! | kind            | unknowns                      | transform          | θ_k                    |
//! |-----------------|-------------------------------|--------------------|------------------------|
//! | `Periodic`      | `n` cells, `f[n] = f[0]`      | real DFT, halfcomplex | `2π k / n`          |
//! | `Neumann`       | `n` cells, ghost = first cell | DCT-II / DCT-III   | `π k / n`, k = 0..n    |
//! | `DirichletCell` | `n` cells, ghost = −first cell | DST-II / DST-III  | `π (k+1) / n`          |
//! | `DirichletFace` | `N` faces between two zero faces | DST-I           | `π (k+1) / (N+1)`      |
//! | `DirichletNeumann` | `n` cells, ghost = −first below, = last above | DST-IV | `π (k+½) / n`    |
//! | `NeumannDirichlet` | `n` cells, ghost = first below, = −last above | DCT-IV | `π (k+½) / n`    |
//!
//! The interface is narrow on purpose: plan once for a length, then apply
//! forward or backward to many lines of a flat array along one axis.
//! `backward` is the exact inverse of `forward` (the normalisation lives in
//! `backward`).

use std::f64::consts::PI;
use std::sync::Arc;

use rustdct::{DctPlanner, Dst1, TransformType2And3, TransformType4};
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use rayon::prelude::*;

/// Smallest number of values handed to one thread: the lines of a small
/// grid are transformed on the calling thread.
const LINE_VALUES_PER_TASK: usize = 16_384;

/// Which family of modes diagonalises the second difference on a line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransformKind {
    /// Periodic line: real discrete Fourier transform in halfcomplex order
    /// (`Re X_0, Re X_1, ..., Re X_{n/2}, Im X_{(n-1)/2}, ..., Im X_1`).
    Periodic,
    /// Cell-centred unknowns with a zero-gradient end (ghost equals the
    /// first unknown): cosine modes, DCT-II forward.
    Neumann,
    /// Cell-centred unknowns with a zero value on the face half a cell
    /// beyond (ghost equals minus the first unknown): sine modes, DST-II.
    DirichletCell,
    /// Face unknowns strictly between two boundary faces where the value is
    /// zero: sine modes, DST-I.
    DirichletFace,
    /// Cell-centred unknowns, zero on the lower face (odd ghost) and zero
    /// gradient at the upper end (even ghost): quarter-wave sine modes,
    /// DST-IV (a no-slip floor under a free-slip lid).
    DirichletNeumann,
    /// The mirror of [`TransformKind::DirichletNeumann`]: zero gradient
    /// below, zero on the upper face; DCT-IV.
    NeumannDirichlet,
}

#[derive(Clone)]
enum Plan {
    Fourier {
        forward: Arc<dyn Fft<f64>>,
        inverse: Arc<dyn Fft<f64>>,
        spectrum: Vec<Complex<f64>>,
        scratch: Vec<Complex<f64>>,
    },
    CosineSine {
        plan: Arc<dyn TransformType2And3<f64>>,
        scratch: Vec<f64>,
    },
    SineFace {
        plan: Arc<dyn Dst1<f64>>,
        scratch: Vec<f64>,
    },
    /// DST-IV or DCT-IV: each its own inverse up to the factor 2/n.
    QuarterWave {
        plan: Arc<dyn TransformType4<f64>>,
        scratch: Vec<f64>,
    },
}

impl TransformKind {
    /// The DST-IV or DCT-IV of `line` (its own inverse up to 2/n).
    fn quarter_wave(
        self,
        plan: &Arc<dyn TransformType4<f64>>,
        line: &mut [f64],
        scratch: &mut [f64],
    ) {
        if self == TransformKind::DirichletNeumann {
            plan.process_dst4_with_scratch(line, scratch);
        } else {
            plan.process_dct4_with_scratch(line, scratch);
        }
    }
}

/// A planned transform of lines of length `len`.
#[derive(Clone)]
pub struct AxisTransform {
    kind: TransformKind,
    len: usize,
    plan: Plan,
    line: Vec<f64>,
}

impl AxisTransform {
    /// Plans the transform of `kind` for lines of `len` values.
    pub fn new(kind: TransformKind, len: usize) -> Self {
        assert!(len >= 1, "a transformed line needs at least one value");
        let plan = match kind {
            TransformKind::Periodic => {
                let mut planner = FftPlanner::<f64>::new();
                let forward = planner.plan_fft_forward(len);
                let inverse = planner.plan_fft_inverse(len);
                let scratch_len = forward
                    .get_inplace_scratch_len()
                    .max(inverse.get_inplace_scratch_len());
                Plan::Fourier {
                    forward,
                    inverse,
                    spectrum: vec![Complex::new(0.0, 0.0); len],
                    scratch: vec![Complex::new(0.0, 0.0); scratch_len],
                }
            }
            TransformKind::Neumann | TransformKind::DirichletCell => {
                let mut planner = DctPlanner::<f64>::new();
                let plan: Arc<dyn TransformType2And3<f64>> = if kind == TransformKind::Neumann {
                    planner.plan_dct2(len)
                } else {
                    planner.plan_dst2(len)
                };
                let scratch = vec![0.0; plan.get_scratch_len()];
                Plan::CosineSine { plan, scratch }
            }
            TransformKind::DirichletFace => {
                let mut planner = DctPlanner::<f64>::new();
                let plan = planner.plan_dst1(len);
                let scratch = vec![0.0; plan.get_scratch_len()];
                Plan::SineFace { plan, scratch }
            }
            TransformKind::DirichletNeumann | TransformKind::NeumannDirichlet => {
                let mut planner = DctPlanner::<f64>::new();
                let plan = if kind == TransformKind::DirichletNeumann {
                    planner.plan_dst4(len)
                } else {
                    planner.plan_dct4(len)
                };
                let scratch = vec![0.0; plan.get_scratch_len()];
                Plan::QuarterWave { plan, scratch }
            }
        };
        AxisTransform {
            kind,
            len,
            plan,
            line: vec![0.0; len],
        }
    }

    pub fn kind(&self) -> TransformKind {
        self.kind
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The angle θ_k of each transformed entry: the second difference acts
    /// on entry `k` as multiplication by `-(2 - 2 cos θ_k) / h²`.
    pub fn angles(&self) -> Vec<f64> {
        let n = self.len as f64;
        (0..self.len)
            .map(|k| match self.kind {
                TransformKind::Periodic => {
                    let frequency = k.min(self.len - k) as f64;
                    2.0 * PI * frequency / n
                }
                TransformKind::Neumann => PI * k as f64 / n,
                TransformKind::DirichletCell => PI * (k + 1) as f64 / n,
                TransformKind::DirichletFace => PI * (k + 1) as f64 / (n + 1.0),
                TransformKind::DirichletNeumann | TransformKind::NeumannDirichlet => {
                    PI * (k as f64 + 0.5) / n
                }
            })
            .collect()
    }

    /// Physical values to modal amplitudes, in place.
    pub fn forward(&mut self, line: &mut [f64]) {
        debug_assert_eq!(line.len(), self.len);
        let n = self.len;
        match &mut self.plan {
            Plan::Fourier {
                forward,
                spectrum,
                scratch,
                ..
            } => {
                for (c, &x) in spectrum.iter_mut().zip(line.iter()) {
                    *c = Complex::new(x, 0.0);
                }
                forward.process_with_scratch(spectrum, scratch);
                for k in 0..=n / 2 {
                    line[k] = spectrum[k].re;
                }
                for k in 1..n.div_ceil(2) {
                    line[n - k] = spectrum[k].im;
                }
            }
            Plan::CosineSine { plan, scratch } => {
                if self.kind == TransformKind::Neumann {
                    plan.process_dct2_with_scratch(line, scratch);
                } else {
                    plan.process_dst2_with_scratch(line, scratch);
                }
            }
            Plan::SineFace { plan, scratch } => {
                // rustdct's DST-I reads parts of its scratch it does not
                // write for some lengths (29, 39, …): a reused scratch
                // corrupts the next line unless cleared.
                scratch.fill(0.0);
                plan.process_dst1_with_scratch(line, scratch)
            }
            Plan::QuarterWave { plan, scratch } => self.kind.quarter_wave(plan, line, scratch),
        }
    }

    /// Modal amplitudes back to physical values, in place; the exact
    /// inverse of [`AxisTransform::forward`].
    pub fn backward(&mut self, line: &mut [f64]) {
        debug_assert_eq!(line.len(), self.len);
        let n = self.len;
        match &mut self.plan {
            Plan::Fourier {
                inverse,
                spectrum,
                scratch,
                ..
            } => {
                // Rebuild the Hermitian spectrum of a real line.
                spectrum[0] = Complex::new(line[0], 0.0);
                for k in 1..=n / 2 {
                    let imaginary = if k < n - k { line[n - k] } else { 0.0 };
                    spectrum[k] = Complex::new(line[k], imaginary);
                    spectrum[n - k] = spectrum[k].conj();
                }
                inverse.process_with_scratch(spectrum, scratch);
                let scale = 1.0 / n as f64;
                for (x, c) in line.iter_mut().zip(spectrum.iter()) {
                    *x = c.re * scale;
                }
            }
            Plan::CosineSine { plan, scratch } => {
                if self.kind == TransformKind::Neumann {
                    plan.process_dct3_with_scratch(line, scratch);
                } else {
                    plan.process_dst3_with_scratch(line, scratch);
                }
                let scale = 2.0 / n as f64;
                line.iter_mut().for_each(|x| *x *= scale);
            }
            Plan::SineFace { plan, scratch } => {
                scratch.fill(0.0);
                plan.process_dst1_with_scratch(line, scratch);
                let scale = 2.0 / (n + 1) as f64;
                line.iter_mut().for_each(|x| *x *= scale);
            }
            Plan::QuarterWave { plan, scratch } => {
                self.kind.quarter_wave(plan, line, scratch);
                let scale = 2.0 / n as f64;
                line.iter_mut().for_each(|x| *x *= scale);
            }
        }
    }

    /// Transforms every line along `axis` of a flat array of `shape`
    /// (x fastest), forward or backward.
    pub fn apply_along(
        &mut self,
        data: &mut [f64],
        shape: [usize; 3],
        axis: usize,
        direction: Direction,
    ) {
        assert_eq!(shape[axis], self.len, "line length differs from the plan");
        debug_assert_eq!(data.len(), shape.iter().product::<usize>());
        let stride: usize = shape[..axis].iter().product();
        let len = self.len;
        // Blocks of `stride` interleaved lines, shared among threads, each
        // with its own work arrays (the plans are shared); every line is
        // transformed alone, whatever the number of threads.
        if rayon::current_num_threads() == 1 {
            for block in data.chunks_mut(stride * len) {
                self.apply_to_block(block, stride, direction);
            }
            return;
        }
        let lines_per_task = LINE_VALUES_PER_TASK.div_ceil(stride * len).max(1);
        let this = &*self;
        data.par_chunks_mut(stride * len)
            .with_min_len(lines_per_task)
            .for_each_init(
                || this.clone(),
                |transform, block| transform.apply_to_block(block, stride, direction),
            );
    }

    /// Transforms the `stride` interleaved lines of one block.
    fn apply_to_block(&mut self, block: &mut [f64], stride: usize, direction: Direction) {
        if stride == 1 {
            self.apply(block, direction);
            return;
        }
        let mut line = std::mem::take(&mut self.line);
        for offset in 0..stride {
            for (j, value) in line.iter_mut().enumerate() {
                *value = block[offset + j * stride];
            }
            self.apply(&mut line, direction);
            for (j, value) in line.iter().enumerate() {
                block[offset + j * stride] = *value;
            }
        }
        self.line = line;
    }

    fn apply(&mut self, line: &mut [f64], direction: Direction) {
        match direction {
            Direction::Forward => self.forward(line),
            Direction::Backward => self.backward(line),
        }
    }
}

/// Physical to modal (`Forward`) or modal to physical (`Backward`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    Forward,
    Backward,
}

#[cfg(test)]
mod tests {
    use super::*;

    const KINDS: [TransformKind; 6] = [
        TransformKind::Periodic,
        TransformKind::Neumann,
        TransformKind::DirichletCell,
        TransformKind::DirichletFace,
        TransformKind::DirichletNeumann,
        TransformKind::NeumannDirichlet,
    ];

    fn sample(len: usize) -> Vec<f64> {
        (0..len)
            .map(|j| ((j * 7 + 3) % 11) as f64 - 4.3 + 0.1 * j as f64)
            .collect()
    }

    /// Second difference with the end condition of `kind` (h = 1).
    fn second_difference(kind: TransformKind, f: &[f64]) -> Vec<f64> {
        let n = f.len();
        let neighbour = |j: isize| -> f64 {
            if (0..n as isize).contains(&j) {
                return f[j as usize];
            }
            let inside = if j < 0 { 0 } else { n - 1 };
            match kind {
                TransformKind::Periodic => f[j.rem_euclid(n as isize) as usize],
                TransformKind::Neumann => f[inside],
                TransformKind::DirichletCell => -f[inside],
                TransformKind::DirichletFace => 0.0,
                // Odd below and even above, or the reverse.
                TransformKind::DirichletNeumann if j < 0 => -f[inside],
                TransformKind::NeumannDirichlet if j >= 0 => -f[inside],
                TransformKind::DirichletNeumann | TransformKind::NeumannDirichlet => f[inside],
            }
        };
        (0..n as isize)
            .map(|j| neighbour(j - 1) - 2.0 * f[j as usize] + neighbour(j + 1))
            .collect()
    }

    /// Every length up to 70, each plan used for several lines in a row
    /// (a plan's work arrays are reused from line to line).
    #[test]
    fn backward_inverts_forward() {
        for kind in KINDS {
            for len in 1..=70 {
                let mut transform = AxisTransform::new(kind, len);
                for round in 0..3 {
                    let original: Vec<f64> = sample(len).iter().map(|x| x + round as f64).collect();
                    let mut line = original.clone();
                    transform.forward(&mut line);
                    transform.backward(&mut line);
                    for (a, b) in line.iter().zip(&original) {
                        assert!(
                            (a - b).abs() <= 1e-12,
                            "{kind:?} n={len} round {round}: {a} vs {b}"
                        );
                    }
                }
            }
        }
    }

    /// The transform of the second difference equals the eigenvalue times
    /// the transform, entry by entry, to round-off.
    #[test]
    fn modes_diagonalise_the_second_difference() {
        for kind in KINDS {
            for len in [2, 7, 8, 16] {
                let f = sample(len);
                let mut transformed = f.clone();
                let mut laplacian = second_difference(kind, &f);
                let mut transform = AxisTransform::new(kind, len);
                transform.forward(&mut transformed);
                transform.forward(&mut laplacian);
                let scale = transformed.iter().map(|x| x.abs()).fold(0.0, f64::max);
                for ((theta, mode), lap) in
                    transform.angles().iter().zip(&transformed).zip(&laplacian)
                {
                    let expected = -(2.0 - 2.0 * theta.cos()) * mode;
                    assert!(
                        (expected - lap).abs() <= 1e-12 * scale,
                        "{kind:?} n={len}: {expected} vs {lap}"
                    );
                }
            }
        }
    }

    #[test]
    fn transforms_every_line_along_an_axis() {
        let shape = [3, 4, 5];
        let total = 60;
        let data: Vec<f64> = (0..total).map(|i| ((i * 13) % 17) as f64).collect();
        for axis in 0..3 {
            let mut transform = AxisTransform::new(TransformKind::Neumann, shape[axis]);
            let mut along = data.clone();
            transform.apply_along(&mut along, shape, axis, Direction::Forward);
            // Compare one line with the direct line transform.
            let stride: usize = shape[..axis].iter().product();
            // First point of the line (i, j, k) = (0, 1, 2), (1, 0, 2), (1, 2, 0).
            let start = [27, 25, 7][axis];
            let mut line: Vec<f64> = (0..shape[axis]).map(|j| data[start + j * stride]).collect();
            transform.forward(&mut line);
            for (j, value) in line.iter().enumerate() {
                assert!((along[start + j * stride] - value).abs() < 1e-12);
            }
            transform.apply_along(&mut along, shape, axis, Direction::Backward);
            for (a, b) in along.iter().zip(&data) {
                assert!((a - b).abs() < 1e-12);
            }
        }
    }
}
