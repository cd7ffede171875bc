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
//!
//! On several ranks the unknowns move between arrangements in which the
//! transformed lines are whole (`poisson/pencils.rs`); the tridiagonal
//! systems of the modes are in `poisson/line_solves.rs`.

use crate::boundary::{local_ends, unknowns, EndKind, FieldEnds};
use crate::error::FluidError;
use crate::grid::{Block, Grid, Location};
use crate::partition::Partition;
use crate::transform::{AxisTransform, Direction, TransformKind};
use grainflow_core::{grid_coords, Communicator, SharedArray};

mod line_solves;
mod pencils;

use line_solves::{LineRows, ModeLines};
use pencils::{flat_index, layouts, Arrangement, Layout, Pencils, SlabPlanes};

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
