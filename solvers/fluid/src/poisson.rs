//! Direct solvers for the discrete Poisson and Helmholtz equations,
//! `(a I + b L) x = r`, with `L` the three-point Laplacian of the staggered
//! grid and its end conditions.
//!
//! All active axes but the last are diagonalised by real transforms
//! ([`crate::transform`]): in modal space `L` along those axes becomes the
//! eigenvalue `λ_k = −(2 − 2 cos θ_k) / h²`. Along the last axis (z in 3D,
//! y in 2D) what remains is one tridiagonal system per mode,
//! `b (x_{j−1} − 2 x_j + x_{j+1}) / h² + (a + b Σ λ) x_j = r_j`, solved by
//! the Thomas algorithm (Sherman–Morrison for a periodic line). The
//! discrete equation is thus solved to round-off, with no iteration. Walls
//! of different kinds on the two faces of an axis (no slip below, free
//! slip above) are allowed along the last axis only, where no transform is
//! needed.
//!
//! The end conditions enter the first and last rows of a line through the
//! ghost they set ([`crate::boundary`]), written with `c = b / h²` for the
//! homogeneous conditions the solver works on:
//!
//! | end                      | ghost              | first row: diagonal shift, upper entry |
//! |--------------------------|--------------------|-----------------------------------------|
//! | `Neumann`                | `u_1`              | `+c`, `c`                               |
//! | `DirichletCell`          | `−u_1`             | `−c`, `c`                               |
//! | `DirichletCellQuadratic` | `−2 u_1 + u_2 / 3` | `−2c`, `(4/3) c`                        |
//! | `DirichletFace`          | none (wall face)   | `0`, `c`                                |
//!
//! and the mirror at the last row (its lower entry). The quadratic ghost,
//! the no-slip closure of tangential velocity along this axis, is exact for
//! parabolas: with it the first row reads
//! `(a + b Σ λ − 4c) x_1 + (4/3) c x_2 = r_1`. It makes the line operator
//! non-symmetric but keeps it diagonally dominant for the Helmholtz
//! equation (`c < 0`) and similar, by a diagonal scaling, to a symmetric
//! negative definite one: real negative eigenvalues, so Crank–Nicolson
//! stays unconditionally stable. The transformed axes keep the linear
//! ghost `−u_1`, the one the sine transform diagonalises.
//!
//! The pressure equation `L φ = r` with periodic or zero-gradient ends
//! everywhere is singular: constants are its null space. For the one mode
//! where this happens, the mean of the right-hand side is removed (it is
//! round-off for the divergence of a velocity with no net flux), one value
//! is pinned, and the solution is shifted to zero mean.

use crate::boundary::{local_ends, unknowns, EndKind, FieldEnds};
use crate::error::FluidError;
use crate::grid::{Block, Grid, Location};
use crate::partition::Partition;
use crate::transform::{AxisTransform, Direction, TransformKind};
use grainflow_core::{grid_coords, Communicator, SharedArray};

/// Which library transforms the lines of the direct solvers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransformBackend {
    /// rustfft and rustdct: pure Rust, always built.
    Rust,
    /// FFTW (cargo feature `fftw`): one plan per axis over all its lines.
    Fftw,
}

impl TransformBackend {
    /// FFTW when built with it, else the pure-Rust transforms.
    pub fn preferred() -> Self {
        if cfg!(feature = "fftw") {
            TransformBackend::Fftw
        } else {
            TransformBackend::Rust
        }
    }

    /// Whether this build can use it.
    pub fn is_available(self) -> bool {
        self == TransformBackend::Rust || cfg!(feature = "fftw")
    }
}

/// The planned transforms of the axes a solver diagonalises.
enum LineTransforms {
    Rust(Vec<AxisTransform>),
    #[cfg(feature = "fftw")]
    Fftw(Vec<crate::fftw::BatchTransform>),
}

impl LineTransforms {
    /// Transforms every line along `axis` of `data` (of `shape`; for FFTW
    /// the array the axis was planned on).
    fn apply(&mut self, axis: usize, data: &mut [f64], shape: [usize; 3], direction: Direction) {
        match self {
            LineTransforms::Rust(t) => t[axis].apply_along(data, shape, axis, direction),
            #[cfg(feature = "fftw")]
            LineTransforms::Fftw(t) => {
                let _ = shape;
                t[axis].apply(data, direction)
            }
        }
    }
}

/// A planned direct solver for one field's unknowns and end conditions.
pub struct DirectSolver {
    /// The ends of the last active axis, solved by tridiagonal elimination.
    line_ends: [EndKind; 2],
    /// The line operator per row, in units of the Laplacian's coefficient.
    rows: LineRows,
    /// Padded indices of the unknowns in the field.
    block: Block,
    /// Unknowns along each axis (1 along an inactive axis).
    shape: [usize; 3],
    transforms: LineTransforms,
    /// `Σ λ_k` over the transformed axes, for every mode.
    modal: Vec<f64>,
    modes: SharedArray,
    lines: ModeLines,
    /// On several ranks, the pencils the transforms work on; None when one
    /// rank holds every unknown (the transforms then act on `modes`).
    pencils: Option<Pencils>,
}

/// Where each rank's share of a field's unknowns lies in one arrangement:
/// the box `[lower, upper)` of global unknown indices of every rank, its
/// values stored x fastest.
#[derive(Clone, Debug)]
struct Layout {
    boxes: Vec<[[usize; 2]; 3]>,
}

impl Layout {
    /// The extent of `rank`'s box along each axis.
    fn shape(&self, rank: usize) -> [usize; 3] {
        self.boxes[rank].map(|[lower, upper]| upper - lower)
    }

    fn len(&self, rank: usize) -> usize {
        self.shape(rank).iter().product()
    }
}

/// The unknowns of a solve on several ranks, rearranged so that each
/// transform and the line solve see whole lines (as in CaNS and
/// 2DECOMP&FFT): `physical`, split like the cells with the line axis whole;
/// `x_pencils`, x whole; in 3D `y_pencils`, y whole. With ranks along both
/// x and y a solve goes physical → x → y → physical, the line solve, and
/// back; each change of arrangement is one all-to-all. With ranks along
/// one axis only (a slab), the other transformed axis is whole in the
/// ranks' own boxes and the pencils share it instead of the line axis, so
/// the lines are solved in the pencils: one all-to-all each way.
struct Pencils {
    communicator: Communicator,
    /// Where the tridiagonal line solve runs.
    solve_in: Arrangement,
    physical: Layout,
    x_pencils: Layout,
    y_pencils: Option<Layout>,
    x_data: SharedArray,
    y_data: SharedArray,
    /// A slab along x on ranks that share memory: the lines solved where
    /// they lie, no pencils (`x_data` then stays empty).
    planes: Option<SlabPlanes>,
    /// Send and receive buffers of the all-to-all, kept between solves
    /// (allocating megabytes at every transpose costs more than moving them).
    buffers: std::cell::RefCell<(Vec<f64>, Vec<f64>)>,
}

impl Pencils {
    /// Moves the values of `source` (arranged as `from`) into `target`
    /// (arranged as `to`): each rank sends every other the part of its box
    /// that lies in the other's new box.
    fn redistribute(&self, from: &Layout, source: &SharedArray, to: &Layout, target: &mut [f64]) {
        if from.boxes == to.boxes {
            // The same arrangement (no split along the axes that differ).
            target.copy_from_slice(source);
            return;
        }
        let me = self.communicator.rank();
        let ranks = from.boxes.len();
        if source.is_shared() {
            // Ranks of one node: once every source is complete, each rank
            // copies its new box straight out of the others' arrays. The
            // barrier also ends every read of the last transpose, whose
            // source no rank writes before this one (a solve only writes
            // the target of the last transpose until the next one).
            self.communicator.synchronize_shared(&[source]);
            for other in 0..ranks {
                if let Some(part) = intersection(&from.boxes[other], &to.boxes[me]) {
                    copy_part(
                        &from.boxes[other],
                        source.of_rank(other),
                        &to.boxes[me],
                        target,
                        &part,
                    );
                }
            }
            return;
        }
        let parts_to: Vec<Option<[[usize; 2]; 3]>> = (0..ranks)
            .map(|other| intersection(&from.boxes[me], &to.boxes[other]))
            .collect();
        let parts_from: Vec<Option<[[usize; 2]; 3]>> = (0..ranks)
            .map(|other| intersection(&from.boxes[other], &to.boxes[me]))
            .collect();
        // This rank's own part is copied directly, not sent to itself.
        if let Some(own) = &parts_to[me] {
            copy_part(&from.boxes[me], source, &to.boxes[me], target, own);
        }
        let size = |(other, part): (usize, &Option<[[usize; 2]; 3]>)| match part {
            Some(p) if other != me => p.iter().map(|[lower, upper]| upper - lower).product(),
            _ => 0,
        };
        let send_counts: Vec<usize> = parts_to.iter().enumerate().map(size).collect();
        // Every rank knows every box: the counts need no exchange.
        let receive_counts: Vec<usize> = parts_from.iter().enumerate().map(size).collect();
        let mut buffers = self.buffers.borrow_mut();
        let (send, receive) = &mut *buffers;
        send.clear();
        for (other, part) in parts_to.iter().enumerate() {
            if let (Some(part), true) = (part, other != me) {
                visit_rows(&from.boxes[me], part, |row| {
                    send.extend_from_slice(&source[row]);
                });
            }
        }
        receive.resize(receive_counts.iter().sum(), 0.0);
        self.communicator
            .all_to_all_flat(send, &send_counts, receive, &receive_counts);
        let mut at = 0;
        for (other, part) in parts_from.iter().enumerate() {
            if let (Some(part), true) = (part, other != me) {
                visit_rows(&to.boxes[me], part, |row| {
                    let length = row.len();
                    target[row].copy_from_slice(&receive[at..at + length]);
                    at += length;
                });
            }
        }
    }
}

/// The solve of a slab split along x only (3D), on ranks that share
/// memory, with no pencils: each rank takes the y-planes of its share of
/// the x pencils and, plane by plane, copies the plane's x rows from every
/// rank's array into `plane` (x fastest, then the line axis z), transforms
/// them along x, solves the z lines of the plane's modes, transforms back
/// and writes the rows back where they came from. Each value is read and
/// written once per solve, and the transform and line solve work on a
/// plane in cache; through pencils every value is copied into another
/// array and back, and the transform and the line solve each sweep that
/// array through memory.
struct SlabPlanes {
    /// This rank's planes, `[first, end)` in global unknown indices along y.
    planes: [usize; 2],
    /// The shape of one plane: the whole x, one y, the whole z.
    shape: [usize; 3],
    plane: Vec<f64>,
    lines: ModeLines,
}

/// One arrangement of a solve's unknowns among the ranks ([`Pencils`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Arrangement {
    Physical,
    XPencils,
    YPencils,
}

/// The common part of two boxes, if any.
fn intersection(a: &[[usize; 2]; 3], b: &[[usize; 2]; 3]) -> Option<[[usize; 2]; 3]> {
    let part = [0, 1, 2].map(|axis| [a[axis][0].max(b[axis][0]), a[axis][1].min(b[axis][1])]);
    part.iter()
        .all(|[lower, upper]| lower < upper)
        .then_some(part)
}

/// Copies `part` of `source` (an array over the box `from`) into `target`
/// (an array over the box `to`), row by row.
fn copy_part(
    from: &[[usize; 2]; 3],
    source: &[f64],
    to: &[[usize; 2]; 3],
    target: &mut [f64],
    part: &[[usize; 2]; 3],
) {
    let length = part[0][1] - part[0][0];
    for k in part[2][0]..part[2][1] {
        for j in part[1][0]..part[1][1] {
            let from_row = flat_index(from, [part[0][0], j, k]);
            let to_row = flat_index(to, [part[0][0], j, k]);
            target[to_row..to_row + length].copy_from_slice(&source[from_row..from_row + length]);
        }
    }
}

/// The index of the global point `point` in an array over the box `whole`
/// (x fastest).
fn flat_index(whole: &[[usize; 2]; 3], point: [usize; 3]) -> usize {
    let shape = whole.map(|[lower, upper]| upper - lower);
    ((point[2] - whole[2][0]) * shape[1] + (point[1] - whole[1][0])) * shape[0] + point[0]
        - whole[0][0]
}

/// Calls `visit(range)` with the flat indices, in an array over `whole`,
/// of every row (along x, contiguous) of `part`, in order.
fn visit_rows(
    whole: &[[usize; 2]; 3],
    part: &[[usize; 2]; 3],
    mut visit: impl FnMut(std::ops::Range<usize>),
) {
    for k in part[2][0]..part[2][1] {
        for j in part[1][0]..part[1][1] {
            let first = flat_index(whole, [part[0][0], j, k]);
            visit(first..first + part[0][1] - part[0][0]);
        }
    }
}

/// The three-point operator along a line, row by row: row `j` reads
/// `lower_j x_{j−1} + shift_j x_j + upper_j x_{j+1}`, the end closures
/// folded into the first and last rows (`lower_0` and `upper_{n−1}` unused
/// unless the line is periodic). `width_j` is the width of the row's
/// control volume, the weight under which the operator is symmetric.
#[derive(Clone, Debug, Default)]
struct LineRows {
    lower: Vec<f64>,
    shift: Vec<f64>,
    upper: Vec<f64>,
    width: Vec<f64>,
}

impl LineRows {
    /// The line operator of a field at `location` along the line axis of
    /// `grid`, rows `first..first + length` (padded), closed by `ends`.
    fn new(
        grid: &Grid,
        location: Location,
        first: usize,
        length: usize,
        ends: [EndKind; 2],
    ) -> Self {
        let axis = grid.line_axis();
        let mut rows = LineRows::default();
        for j in 0..length {
            let [below, above] = grid.line_laplacian(location, first + j);
            rows.lower.push(below);
            rows.upper.push(above);
            rows.shift.push(-(below + above));
            rows.width.push(if location == Location::Face(axis) {
                grid.gap(axis, first + j)
            } else {
                grid.width(axis, first + j)
            });
        }
        // What the ghost beyond each end puts on its row: `ghost = a x_near
        // + b x_far` (homogeneous), so the row's diagonal gains `a` times
        // the coupling to the ghost and its inner neighbour `b` times it.
        for side in 0..2 {
            let [near, far] = match ends[side] {
                EndKind::Neumann => [1.0, 0.0],
                EndKind::DirichletCell => [-1.0, 0.0],
                EndKind::DirichletCellQuadratic => {
                    let [_, near, far] = grid.wall_ghost_weights(side);
                    [near, far]
                }
                EndKind::DirichletFace | EndKind::Periodic => [0.0, 0.0],
                EndKind::Halo => unreachable!("the line axis is never split among ranks"),
            };
            // The end row couples outwards to the ghost, inwards to the
            // row next to it (which the quadratic ghost also reads).
            let (row, outward, inward) = if side == 0 {
                (0, &rows.lower, &mut rows.upper)
            } else {
                (length - 1, &rows.upper, &mut rows.lower)
            };
            let coupling = outward[row];
            debug_assert!(far == 0.0 || length >= 2);
            rows.shift[row] += near * coupling;
            inward[row] += far * coupling;
        }
        rows
    }

    /// The same rows times `factor`.
    fn scaled(&self, factor: f64, out: &mut LineRows) {
        let scale = |from: &[f64], to: &mut Vec<f64>| {
            to.clear();
            to.extend(from.iter().map(|value| factor * value));
        };
        scale(&self.lower, &mut out.lower);
        scale(&self.shift, &mut out.shift);
        scale(&self.upper, &mut out.upper);
    }
}

impl DirectSolver {
    /// Plans a solver for a field with these end conditions (only their
    /// kinds matter: the solver works on homogeneous conditions; prescribed
    /// values enter through the right-hand side or an increment form). A
    /// field with prescribed face values along the line axis lives on the
    /// faces normal to it, any other at cell centres along it.
    pub fn new(grid: &Grid, ends: &FieldEnds) -> Result<Self, FluidError> {
        Self::with_backend(grid, ends, TransformBackend::preferred())
    }

    /// [`DirectSolver::new`] with the transforms of `backend`; refuses one
    /// this build does not have.
    pub fn with_backend(
        grid: &Grid,
        ends: &FieldEnds,
        backend: TransformBackend,
    ) -> Result<Self, FluidError> {
        let partition = Partition::serial(grid);
        Self::distributed(
            grid,
            ends,
            grid,
            &partition,
            Communicator::serial(),
            backend,
        )
    }

    /// The solver of one rank of several: `global` is the whole grid and
    /// `ends` its end conditions, `local` this rank's share of the cells
    /// ([`Partition::local_grid`]); every rank of `communicator` builds its
    /// own and solves together (every solve is collective).
    pub fn distributed(
        global: &Grid,
        ends: &FieldEnds,
        local: &Grid,
        partition: &Partition,
        communicator: Communicator,
        backend: TransformBackend,
    ) -> Result<Self, FluidError> {
        let grid = local;
        if !backend.is_available() {
            return Err(FluidError::Unsupported(format!(
                "the {backend:?} transforms are not in this build (rebuild with \
                 `--features fftw`, which needs the system's libfftw3)"
            )));
        }
        let dim = grid.dim();
        let line_axis = dim - 1;
        let global_block = unknowns(global, ends);
        let global_shape = [0, 1, 2].map(|a| global_block.end[a] - global_block.start[a]);
        let block = unknowns(grid, &local_ends(ends, partition));
        let shape = [0, 1, 2].map(|a| block.end[a] - block.start[a]);
        let (layouts, solve_in) = layouts(partition, global_shape, line_axis);
        let me = communicator.rank();
        assert_eq!(
            layouts[0].shape(me),
            shape,
            "this rank's unknowns are its box of the physical layout"
        );
        // The modes this rank solves lines for: its box of the arrangement
        // the line solve runs in.
        let solve_box = match solve_in {
            Arrangement::Physical => layouts[0].boxes[me],
            Arrangement::XPencils => layouts[1].boxes[me],
            Arrangement::YPencils => layouts[2].boxes[me],
        };
        let offset = solve_box.map(|[lower, _]| lower);
        let solve_shape = solve_box.map(|[lower, upper]| upper - lower);
        debug_assert_eq!(solve_shape[line_axis], shape[line_axis]);
        let mut transforms = Vec::new();
        let mut eigenvalues: Vec<Vec<f64>> = Vec::new();
        for (axis, end) in ends.iter().enumerate().take(line_axis) {
            let kind = match (end[0].kind, end[1].kind) {
                (EndKind::DirichletCellQuadratic, _) | (_, EndKind::DirichletCellQuadratic) => {
                    return Err(FluidError::Boundary(format!(
                        "axis {axis} is solved by a transform, which diagonalises only the \
                         linear wall closure; the quadratic one is for the last axis ({line_axis})"
                    )))
                }
                (EndKind::Periodic, EndKind::Periodic) => TransformKind::Periodic,
                (EndKind::Neumann, EndKind::Neumann) => TransformKind::Neumann,
                (EndKind::DirichletCell, EndKind::DirichletCell) => TransformKind::DirichletCell,
                (EndKind::DirichletFace, EndKind::DirichletFace) => TransformKind::DirichletFace,
                (lower, upper) => {
                    return Err(FluidError::Boundary(format!(
                        "axis {axis} is solved by a transform and needs the same kind of end on \
                         both faces, got {lower:?} and {upper:?}"
                    )))
                }
            };
            let transform = AxisTransform::new(kind, global_shape[axis]);
            let h2 = grid.spacing[axis] * grid.spacing[axis];
            eigenvalues.push(
                transform.angles()[offset[axis]..offset[axis] + solve_shape[axis]]
                    .iter()
                    .map(|theta| -(2.0 - 2.0 * theta.cos()) / h2)
                    .collect::<Vec<f64>>(),
            );
            transforms.push(transform);
        }
        let line_ends = [ends[line_axis][0].kind, ends[line_axis][1].kind];
        let periodic_line = line_ends.map(|k| k == EndKind::Periodic);
        if periodic_line[0] != periodic_line[1] {
            return Err(FluidError::Boundary(format!(
                "axis {line_axis}: periodic on one end only"
            )));
        }
        if periodic_line[0] && !grid.is_uniform(line_axis) {
            return Err(FluidError::Boundary(format!(
                "axis {line_axis}: a periodic line must be uniform, this one is stretched"
            )));
        }
        let quadratic_line = line_ends.contains(&EndKind::DirichletCellQuadratic);
        if quadratic_line && shape[line_axis] < 2 {
            return Err(FluidError::Boundary(format!(
                "axis {line_axis}: the quadratic wall closure reads the second unknown from the \
                 wall and needs at least 2 unknowns along the line, got {}",
                shape[line_axis]
            )));
        }
        if periodic_line[0] && shape[line_axis] < 3 {
            return Err(FluidError::Boundary(format!(
                "axis {line_axis}: a periodic line needs at least 3 cells"
            )));
        }
        let location = if line_ends[0] == EndKind::DirichletFace {
            Location::Face(line_axis)
        } else {
            Location::Centre
        };
        let rows = LineRows::new(
            grid,
            location,
            block.start[line_axis],
            shape[line_axis],
            line_ends,
        );
        // Modes are ordered like the compact array: first axis fastest.
        let mode_count: usize = solve_shape[..line_axis].iter().product();
        let modal = (0..mode_count)
            .map(|mode| {
                let mut remainder = mode;
                let mut sum = 0.0;
                for (axis, eigenvalues) in eigenvalues.iter().enumerate() {
                    sum += eigenvalues[remainder % solve_shape[axis]];
                    remainder /= solve_shape[axis];
                }
                sum
            })
            .collect();
        let total = shape.iter().product();
        // A slab along x whose ranks share memory solves in planes.
        let in_planes = partition.size() > 1
            && line_axis == 2
            && solve_in == Arrangement::XPencils
            && communicator.shares_memory();
        // On ranks of one node the arrays the transposes read live in shared
        // memory (every rank allocates them in the same order).
        let array = |len: usize| communicator.shared_array(len);
        #[cfg_attr(not(feature = "fftw"), allow(unused_mut))]
        let mut modes = array(total);
        #[cfg_attr(not(feature = "fftw"), allow(unused_mut))]
        let mut pencils = (partition.size() > 1).then(|| {
            let [physical, x_pencils, y_pencils] = layouts;
            Pencils {
                planes: in_planes.then(|| {
                    let shape = [global_shape[0], 1, global_shape[2]];
                    SlabPlanes {
                        planes: x_pencils.boxes[me][1],
                        shape,
                        plane: vec![0.0; shape.iter().product()],
                        lines: ModeLines::new(shape[0], shape[2], periodic_line[0]),
                    }
                }),
                // No array for pencils that are the ranks' own boxes, nor
                // for those a slab solved in planes skips.
                x_data: if x_pencils.boxes != physical.boxes && !in_planes {
                    array(x_pencils.len(me))
                } else {
                    SharedArray::default()
                },
                y_data: if line_axis == 2 && y_pencils.boxes != physical.boxes {
                    array(y_pencils.len(me))
                } else {
                    SharedArray::default()
                },
                y_pencils: (line_axis == 2).then_some(y_pencils),
                solve_in,
                physical,
                x_pencils,
                communicator: communicator.clone(),
                buffers: Default::default(),
            }
        });
        let transforms = match backend {
            TransformBackend::Rust => LineTransforms::Rust(transforms),
            #[cfg(feature = "fftw")]
            TransformBackend::Fftw => LineTransforms::Fftw(
                transforms
                    .iter()
                    .enumerate()
                    .map(|(axis, transform)| {
                        // Each axis is planned on the array it transforms:
                        // the ranks' own boxes where its lines are whole
                        // there, else its pencils.
                        let mut parts = crate::fftw::PARTS;
                        let (data, shape): (&mut [f64], _) = match (&mut pencils, axis) {
                            (None, _) => (&mut modes, shape),
                            // A slab solved in planes: x on one plane, in
                            // one part (the planes come one after another).
                            (
                                Some(Pencils {
                                    planes: Some(p), ..
                                }),
                                0,
                            ) => {
                                parts = 1;
                                (&mut p.plane, p.shape)
                            }
                            (Some(p), 0) if p.x_pencils.boxes != p.physical.boxes => {
                                (&mut p.x_data, p.x_pencils.shape(me))
                            }
                            (Some(p), 1)
                                if p.y_pencils.as_ref().expect("3D").boxes != p.physical.boxes =>
                            {
                                let y_shape = p.y_pencils.as_ref().expect("3D").shape(me);
                                (&mut p.y_data, y_shape)
                            }
                            (Some(_), _) => (&mut modes, shape),
                        };
                        crate::fftw::BatchTransform::new(transform.kind(), data, shape, axis, parts)
                    })
                    .collect(),
            ),
            #[cfg(not(feature = "fftw"))]
            TransformBackend::Fftw => unreachable!("refused above"),
        };
        Ok(DirectSolver {
            line_ends,
            rows,
            block,
            shape,
            transforms,
            modal,
            modes,
            // Planes bring their own work arrays, one plane's worth.
            lines: ModeLines::new(
                if in_planes { 0 } else { mode_count },
                shape[line_axis],
                periodic_line[0],
            ),
            pencils,
        })
    }
    /// The padded indices of the unknowns this solver owns in a field.
    pub fn unknowns(&self) -> &Block {
        &self.block
    }

    /// Solves the Poisson equation `L x = r`. On entry `field` holds `r`
    /// on the unknowns; on exit `x`. Ghosts are not touched. When the
    /// system is singular (no Dirichlet end anywhere) the solution has
    /// zero mean.
    pub fn solve_poisson(&mut self, grid: &Grid, field: &mut [f64]) {
        self.solve(grid, field, 0.0, 1.0);
    }

    /// Solves the Helmholtz equation `(I − c L) x = r` in place, `c ≥ 0`
    /// (the implicit half of a Crank–Nicolson viscous step, `c = ν Δt / 2`).
    pub fn solve_helmholtz(&mut self, grid: &Grid, field: &mut [f64], c: f64) {
        self.solve(grid, field, 1.0, -c);
    }

    /// Solves `(identity I + laplacian L) x = r` in place.
    pub fn solve(&mut self, grid: &Grid, field: &mut [f64], identity: f64, laplacian: f64) {
        self.gather(grid, field);
        if matches!(
            &self.pencils,
            Some(Pencils {
                planes: Some(_),
                ..
            })
        ) {
            self.solve_in_planes(identity, laplacian);
        } else {
            self.transform(Direction::Forward);
            self.solve_lines(identity, laplacian);
            self.transform(Direction::Backward);
        }
        self.scatter(grid, field);
    }

    /// Every transformed axis of the modal array, first to last forward,
    /// last to first backward.
    fn transform(&mut self, direction: Direction) {
        if self.pencils.is_some() {
            return self.transform_pencils(direction);
        }
        let modes = &mut self.modes;
        match &mut self.transforms {
            LineTransforms::Rust(transforms) => {
                let mut axes: Vec<_> = transforms.iter_mut().enumerate().collect();
                if direction == Direction::Backward {
                    axes.reverse();
                }
                for (axis, transform) in axes {
                    transform.apply_along(modes, self.shape, axis, direction);
                }
            }
            #[cfg(feature = "fftw")]
            LineTransforms::Fftw(transforms) => {
                let mut axes: Vec<_> = transforms.iter().collect();
                if direction == Direction::Backward {
                    axes.reverse();
                }
                for transform in axes {
                    transform.apply(modes, direction);
                }
            }
        }
    }

    /// [`DirectSolver::transform`] on several ranks: each axis on the pencils
    /// that hold its lines whole.
    fn transform_pencils(&mut self, direction: Direction) {
        let pencils = self.pencils.as_mut().expect("several ranks");
        let me = pencils.communicator.rank();
        let x_shape = pencils.x_pencils.shape(me);
        let mut x_data = std::mem::take(&mut pencils.x_data);
        let mut y_data = std::mem::take(&mut pencils.y_data);
        let pencils = self.pencils.as_ref().expect("several ranks");
        let (physical, x_pencils) = (&pencils.physical, &pencils.x_pencils);
        let transforms = &mut self.transforms;
        let mut apply = |axis: usize, data: &mut [f64], shape: [usize; 3]| {
            transforms.apply(axis, data, shape, direction)
        };
        // A slab: `own` transformed in the ranks' boxes, `along` in the
        // pencils `layout` (holding `data`), the lines solved there or back
        // in the ranks' boxes.
        let own_shape = physical.shape(me);
        let mut slab_transform = |[own, along]: [usize; 2],
                                  layout: &Layout,
                                  data: &mut SharedArray,
                                  solve_here: bool,
                                  modes: &mut SharedArray| {
            let shape = layout.shape(me);
            if direction == Direction::Forward {
                apply(own, modes, own_shape);
                pencils.redistribute(physical, modes, layout, data);
                apply(along, data, shape);
                if !solve_here {
                    pencils.redistribute(layout, data, physical, modes);
                }
            } else {
                if !solve_here {
                    pencils.redistribute(physical, modes, layout, data);
                }
                apply(along, data, shape);
                pencils.redistribute(layout, data, physical, modes);
                apply(own, modes, own_shape);
            }
        };
        match (&pencils.y_pencils, direction) {
            (None, _) => {
                pencils.redistribute(physical, &self.modes, x_pencils, &mut x_data);
                apply(0, &mut x_data, x_shape);
                pencils.redistribute(x_pencils, &x_data, physical, &mut self.modes);
            }
            // A process grid split along one axis only: the other axis'
            // lines are whole in the ranks' own boxes, transformed there;
            // the lines are solved in the pencils when they hold them whole
            // (forward ends there, backward starts there).
            (Some(y_pencils), _) if y_pencils.boxes == physical.boxes => {
                let solve_here = pencils.solve_in == Arrangement::XPencils;
                slab_transform([1, 0], x_pencils, &mut x_data, solve_here, &mut self.modes);
            }
            (Some(y_pencils), _) if x_pencils.boxes == physical.boxes => {
                let solve_here = pencils.solve_in == Arrangement::YPencils;
                slab_transform([0, 1], y_pencils, &mut y_data, solve_here, &mut self.modes);
            }
            (Some(y_pencils), Direction::Forward) => {
                pencils.redistribute(physical, &self.modes, x_pencils, &mut x_data);
                apply(0, &mut x_data, x_shape);
                pencils.redistribute(x_pencils, &x_data, y_pencils, &mut y_data);
                apply(1, &mut y_data, y_pencils.shape(me));
                pencils.redistribute(y_pencils, &y_data, physical, &mut self.modes);
            }
            (Some(y_pencils), Direction::Backward) => {
                pencils.redistribute(physical, &self.modes, y_pencils, &mut y_data);
                apply(1, &mut y_data, y_pencils.shape(me));
                pencils.redistribute(y_pencils, &y_data, x_pencils, &mut x_data);
                apply(0, &mut x_data, x_shape);
                pencils.redistribute(x_pencils, &x_data, physical, &mut self.modes);
            }
        }
        let pencils = self.pencils.as_mut().expect("several ranks");
        pencils.x_data = x_data;
        pencils.y_data = y_data;
    }

    fn gather(&mut self, grid: &Grid, field: &[f64]) {
        let mut compact = 0;
        let modes = &mut self.modes;
        grid.for_each(&self.block, |index, _| {
            modes[compact] = field[index];
            compact += 1;
        });
    }

    fn scatter(&self, grid: &Grid, field: &mut [f64]) {
        let mut compact = 0;
        grid.for_each(&self.block, |index, _| {
            field[index] = self.modes[compact];
            compact += 1;
        });
    }

    /// One tridiagonal solve along the line axis per transformed mode, all
    /// modes swept together: at each row the modes are contiguous, so the
    /// elimination runs over flat arrays.
    fn solve_lines(&mut self, identity: f64, laplacian: f64) {
        let modes = match &mut self.pencils {
            Some(p) if p.solve_in == Arrangement::XPencils => &mut p.x_data,
            Some(p) if p.solve_in == Arrangement::YPencils => &mut p.y_data,
            _ => &mut self.modes,
        };
        self.lines.solve(
            modes,
            &self.modal,
            &self.rows,
            self.line_ends,
            identity,
            laplacian,
        );
    }

    /// The transforms and line solves of [`DirectSolver::solve`] on a slab
    /// split along x whose ranks share memory ([`SlabPlanes`]): y
    /// transformed in the ranks' own boxes, then, once every rank has done
    /// so, x and the lines plane by plane across all the ranks' arrays,
    /// and y back once every rank has written its planes.
    fn solve_in_planes(&mut self, identity: f64, laplacian: f64) {
        let pencils = self.pencils.as_mut().expect("several ranks");
        let planes = pencils.planes.as_mut().expect("a slab solved in planes");
        let communicator = &pencils.communicator;
        let boxes = &pencils.physical.boxes;
        let own_shape = pencils.physical.shape(communicator.rank());
        let transforms = &mut self.transforms;
        transforms.apply(1, &mut self.modes, own_shape, Direction::Forward);
        communicator.synchronize_shared(&[&self.modes]);
        let segments = self.modes.segments_mut();
        debug_assert_eq!(segments.len(), boxes.len());
        let [length_x, _, length_z] = planes.shape;
        // Visits the x rows of plane `y` in every rank's array: the rank's
        // first value of the row, the row's offset in the plane, its length.
        let rows_of = |y: usize, visit: &mut dyn FnMut(*mut f64, usize, usize)| {
            for (whole, &(start, len)) in boxes.iter().zip(&segments) {
                let width = whole[0][1] - whole[0][0];
                for z in 0..length_z {
                    let from = flat_index(whole, [whole[0][0], y, whole[2][0] + z]);
                    assert!(from + width <= len, "a row inside the rank's array");
                    // SAFETY: within the segment (checked above).
                    visit(
                        unsafe { start.add(from) },
                        whole[0][0] + z * length_x,
                        width,
                    );
                }
            }
        };
        for y in planes.planes[0]..planes.planes[1] {
            let plane = &mut planes.plane;
            // SAFETY (both copies): the rows of plane `y` belong to this
            // rank's planes, which no other rank reads or writes between
            // the two synchronisations, and `plane` is this rank's own.
            rows_of(y, &mut |row, at, width| unsafe {
                std::ptr::copy_nonoverlapping(row, plane[at..at + width].as_mut_ptr(), width)
            });
            transforms.apply(0, plane, planes.shape, Direction::Forward);
            let first = (y - planes.planes[0]) * length_x;
            planes.lines.solve(
                plane,
                &self.modal[first..first + length_x],
                &self.rows,
                self.line_ends,
                identity,
                laplacian,
            );
            transforms.apply(0, plane, planes.shape, Direction::Backward);
            rows_of(y, &mut |row, at, width| unsafe {
                std::ptr::copy_nonoverlapping(plane[at..at + width].as_ptr(), row, width)
            });
        }
        communicator.synchronize_shared(&[&self.modes]);
        transforms.apply(1, &mut self.modes, own_shape, Direction::Backward);
    }
}

/// The physical, x-pencil and y-pencil layouts of a field's unknowns
/// (`shape` of them in all) among the ranks of `partition`, and the one
/// the line solve runs in. Physical: the ranks' boxes of cells (a rank at
/// the upper end of an axis whose last face is prescribed has one unknown
/// fewer), the line axis whole. With ranks along x and y (and in 2D): x
/// pencils, x whole, y as physical (3D), the line axis shared among the
/// ranks along x; y pencils (3D), x as physical, y whole, z shared among
/// the ranks along y; lines solved in the physical layout. With ranks
/// along x only (3D): x pencils x whole, y shared, z whole, where the
/// lines are solved; y pencils are the physical boxes. Along y only, the
/// mirror image.
fn layouts(
    partition: &Partition,
    shape: [usize; 3],
    line_axis: usize,
) -> ([Layout; 3], Arrangement) {
    let [along_x, along_y] = [partition.ranks[0], partition.ranks[1]];
    let solve_in = if line_axis == 2 && along_y == 1 && along_x > 1 && shape[1] >= along_x {
        Arrangement::XPencils
    } else if line_axis == 2 && along_x == 1 && along_y > 1 && shape[0] >= along_y {
        Arrangement::YPencils
    } else {
        Arrangement::Physical
    };
    let even = |length: usize, parts: usize, part: usize| {
        [part * length / parts, (part + 1) * length / parts]
    };
    let whole = |axis: usize| [0, shape[axis]];
    let mut physical = Vec::new();
    let mut x_pencils = Vec::new();
    let mut y_pencils = Vec::new();
    for rank in 0..partition.size() {
        let coords = grid_coords(partition.ranks, rank);
        let cells = |axis: usize| {
            let c = coords[axis];
            [
                partition.cell_start(axis, c).min(shape[axis]),
                partition.cell_start(axis, c + 1).min(shape[axis]),
            ]
        };
        let box_of = |axis: usize| {
            if axis < line_axis {
                cells(axis)
            } else {
                whole(axis)
            }
        };
        physical.push([box_of(0), box_of(1), box_of(2)]);
        let line_share = |parts: usize, part: usize| even(shape[line_axis], parts, part);
        if line_axis == 1 {
            x_pencils.push([
                whole(0),
                line_share(partition.ranks[0], coords[0]),
                whole(2),
            ]);
            y_pencils.push([whole(0), whole(1), whole(2)]);
        } else {
            match solve_in {
                Arrangement::XPencils => {
                    x_pencils.push([whole(0), even(shape[1], along_x, coords[0]), whole(2)]);
                    y_pencils.push(physical[rank]);
                }
                Arrangement::YPencils => {
                    x_pencils.push(physical[rank]);
                    y_pencils.push([even(shape[0], along_y, coords[1]), whole(1), whole(2)]);
                }
                Arrangement::Physical => {
                    x_pencils.push([whole(0), cells(1), line_share(along_x, coords[0])]);
                    y_pencils.push([cells(0), whole(1), line_share(along_y, coords[1])]);
                }
            }
        }
    }
    let layouts = [
        Layout { boxes: physical },
        Layout { boxes: x_pencils },
        Layout { boxes: y_pencils },
    ];
    (layouts, solve_in)
}

/// Work arrays of the tridiagonal systems of all modes: the line operator
/// `rows` scaled by the Laplacian's coefficient, and per mode the diagonal
/// part `base` that the transformed axes and the identity add to every row
/// (the first and last rows of a periodic line add a Sherman–Morrison
/// term). Row `j` of mode `m` is at `m + j · modes` in a flat array.
struct ModeLines {
    rows: LineRows,
    base: Vec<f64>,
    first: Vec<f64>,
    last: Vec<f64>,
    /// The elimination's modified upper diagonal, one per row and mode.
    modified: Vec<f64>,
    /// Sherman–Morrison correction of a periodic line, one per row and mode.
    correction: Vec<f64>,
    /// `γ = −b₀` of the Sherman–Morrison update, per mode.
    gamma: Vec<f64>,
    singular_line: Vec<f64>,
}

impl ModeLines {
    fn new(modes: usize, length: usize, periodic: bool) -> Self {
        ModeLines {
            rows: LineRows::default(),
            base: vec![0.0; modes],
            first: vec![0.0; modes],
            last: vec![0.0; modes],
            modified: vec![0.0; modes * length],
            correction: if periodic {
                vec![0.0; modes * length]
            } else {
                Vec::new()
            },
            gamma: if periodic {
                vec![0.0; modes]
            } else {
                Vec::new()
            },
            singular_line: Vec::with_capacity(length),
        }
    }

    /// Solves the lines of every mode of `values` (row `j` of mode `m` at
    /// `m + j · modes`, `modes = modal.len()`):
    /// `(identity + laplacian Σλ_m) x + laplacian L_line x = r`, with
    /// `Σλ_m` in `modal` and `line` the line operator `L_line`, closed by
    /// `ends`. The one singular mode of a pure Neumann or periodic Poisson
    /// problem (`Σλ = 0`) is solved apart ([`ModeLines::solve_singular`]).
    fn solve(
        &mut self,
        values: &mut [f64],
        modal: &[f64],
        line: &LineRows,
        ends: [EndKind; 2],
        identity: f64,
        laplacian: f64,
    ) {
        let length = line.shift.len();
        let stride = modal.len();
        debug_assert_eq!(values.len(), stride * length);
        line.scaled(laplacian, &mut self.rows);
        let periodic = ends[0] == EndKind::Periodic;
        let singular = identity == 0.0
            && modal[0] == 0.0
            && ends
                .iter()
                .all(|&kind| matches!(kind, EndKind::Periodic | EndKind::Neumann));
        for (base, &modal) in self.base.iter_mut().zip(modal) {
            *base = identity + laplacian * modal;
        }
        if singular {
            // Set the singular mode aside; it is swept as the identity.
            self.singular_line.clear();
            self.singular_line
                .extend((0..length).map(|j| values[j * stride]));
        }
        if periodic {
            self.solve_cyclic(values, length, singular);
        } else {
            self.sweep(values, length, singular);
        }
        if singular {
            let solution = self.solve_singular(length, &line.width);
            for (j, value) in solution.iter().enumerate() {
                values[j * stride] = *value;
            }
        }
    }

    /// The per-mode diagonal parts of the first and last rows, `base`
    /// until a periodic line changes them. Mode 0 of a singular system is
    /// swept as the identity ([`thomas`]); its first row gets a unit
    /// diagonal so that a periodic line's `γ` stays finite.
    fn end_bases(&mut self, singular: bool) {
        self.first.copy_from_slice(&self.base);
        self.last.copy_from_slice(&self.base);
        if singular {
            self.first[0] = 1.0 - self.rows.shift[0];
        }
    }

    /// Thomas algorithm on every mode: `rhs` is overwritten with the
    /// solutions.
    fn sweep(&mut self, rhs: &mut [f64], length: usize, singular: bool) {
        self.end_bases(singular);
        let bases = [&self.first[..], &self.base[..], &self.last[..]];
        thomas(rhs, &mut self.modified, length, &self.rows, bases, singular);
    }

    /// Periodic lines (uniform, so every row has the same coupling `c`):
    /// the corner entries `c` are a rank-one update `u vᵀ` of a
    /// tridiagonal matrix, `u = (γ, 0, …, 0, c)`, `v = (1, 0, …, 0, c/γ)`
    /// with `γ = −b₀` (Sherman–Morrison); two sweeps, then
    /// `x = y − z (v·y) / (1 + v·z)`.
    fn solve_cyclic(&mut self, rhs: &mut [f64], length: usize, singular: bool) {
        self.end_bases(singular);
        let modes = self.first.len();
        let last_row = (length - 1) * modes;
        let coupling = self.rows.upper[0];
        self.correction.fill(0.0);
        for m in 0..modes {
            let gamma = -(self.first[m] + self.rows.shift[0]);
            self.gamma[m] = gamma;
            self.correction[m] = gamma;
            self.correction[last_row + m] = coupling;
            self.first[m] -= gamma;
            self.last[m] -= coupling * coupling / gamma;
        }
        let bases = [&self.first[..], &self.base[..], &self.last[..]];
        thomas(rhs, &mut self.modified, length, &self.rows, bases, singular);
        thomas(
            &mut self.correction,
            &mut self.modified,
            length,
            &self.rows,
            bases,
            singular,
        );
        // v·y / (1 + v·z) per mode, kept in `gamma`'s place once used.
        for m in 0..modes {
            let ratio = coupling / self.gamma[m];
            let numerator = rhs[m] + ratio * rhs[last_row + m];
            let denominator = 1.0 + self.correction[m] + ratio * self.correction[last_row + m];
            self.gamma[m] = numerator / denominator;
        }
        let factor = &self.gamma;
        for (row, correction) in rhs
            .chunks_exact_mut(modes)
            .zip(self.correction.chunks_exact(modes))
        {
            for m in 0..modes {
                row[m] -= factor[m] * correction[m];
            }
        }
    }

    /// The singular mode of a pure Neumann or periodic Laplacian: remove
    /// the mean of the right-hand side, weighted by the rows' widths (the
    /// compatibility condition: the operator conserves `Σ w_j x_j`), pin
    /// the first value to zero and drop its row (implied by the others),
    /// then shift the solution to zero mean. For a periodic line the
    /// wrap-around couplings to the pinned value vanish too.
    fn solve_singular(&mut self, length: usize, widths: &[f64]) -> &[f64] {
        let line = &mut self.singular_line;
        let total: f64 = widths.iter().sum();
        let weighted_mean =
            |line: &[f64]| line.iter().zip(widths).map(|(x, w)| x * w).sum::<f64>() / total;
        let mean = weighted_mean(line);
        line.iter_mut().for_each(|r| *r -= mean);
        line[0] = 0.0;
        // Rows 1..n of the line operator, without their coupling to x_0.
        let rows = &self.rows;
        let mut reduced = LineRows {
            lower: rows.lower[1..].to_vec(),
            shift: rows.shift[1..].to_vec(),
            upper: rows.upper[1..].to_vec(),
            width: Vec::new(),
        };
        reduced.lower[0] = 0.0;
        let zero = [0.0];
        let mut modified = vec![0.0; length - 1];
        thomas(
            &mut line[1..],
            &mut modified,
            length - 1,
            &reduced,
            [&zero[..], &zero[..], &zero[..]],
            false,
        );
        let mean = weighted_mean(line);
        line.iter_mut().for_each(|x| *x -= mean);
        line
    }
}

/// Thomas algorithm for `modes = bases[0].len()` independent tridiagonal
/// systems of `length` rows, row `j` of mode `m` reading
/// `lower_j x_{j−1} + (base_m + shift_j) x_j + upper_j x_{j+1}` with
/// `base` taken from `bases = [first row, interior rows, last row]`;
/// right-hand sides in `rhs` (row-major over modes), overwritten with the
/// solutions. With `identity_first_mode`, mode 0 solves the identity
/// instead (its diagonal is 1, its off-diagonals 0): the place holder of a
/// singular mode solved apart.
fn thomas(
    rhs: &mut [f64],
    modified: &mut [f64],
    length: usize,
    rows: &LineRows,
    bases: [&[f64]; 3],
    identity_first_mode: bool,
) {
    let [first, interior, last] = bases;
    let modes = first.len();
    for m in 0..modes {
        let pivot = first[m] + rows.shift[0];
        modified[m] = rows.upper[0] / pivot;
        rhs[m] /= pivot;
    }
    if identity_first_mode {
        modified[0] = 0.0;
        rhs[0] = 0.0;
    }
    for j in 1..length {
        let base = if j == length - 1 { last } else { interior };
        let (lower, shift, upper) = (rows.lower[j], rows.shift[j], rows.upper[j]);
        let (done, rest) = rhs.split_at_mut(j * modes);
        let previous = &done[(j - 1) * modes..];
        let current = &mut rest[..modes];
        let (done_modified, rest_modified) = modified.split_at_mut(j * modes);
        let previous_modified = &done_modified[(j - 1) * modes..];
        let current_modified = &mut rest_modified[..modes];
        for m in 0..modes {
            let pivot = base[m] + shift - lower * previous_modified[m];
            current_modified[m] = upper / pivot;
            current[m] = (current[m] - lower * previous[m]) / pivot;
        }
        if identity_first_mode {
            current_modified[0] = 0.0;
            current[0] = 0.0;
        }
    }
    for j in (0..length - 1).rev() {
        let (head, tail) = rhs.split_at_mut((j + 1) * modes);
        let current = &mut head[j * modes..];
        let next = &tail[..modes];
        let current_modified = &modified[j * modes..(j + 1) * modes];
        for m in 0..modes {
            current[m] -= current_modified[m] * next[m];
        }
    }
}
