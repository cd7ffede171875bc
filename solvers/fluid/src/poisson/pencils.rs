//! The unknowns of a direct solve on several ranks: where each rank's
//! share lies in each arrangement (physical boxes, x and y pencils) and
//! how values move between arrangements.

use super::*;

/// Where each rank's share of a field's unknowns lies in one arrangement:
/// the box `[lower, upper)` of global unknown indices of every rank, its
/// values stored x fastest.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    pub(super) boxes: Vec<[[usize; 2]; 3]>,
}

impl Layout {
    /// The extent of `rank`'s box along each axis.
    pub(super) fn shape(&self, rank: usize) -> [usize; 3] {
        self.boxes[rank].map(|[lower, upper]| upper - lower)
    }

    pub(super) fn len(&self, rank: usize) -> usize {
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
pub(super) struct Pencils {
    pub(super) communicator: Communicator,
    /// Where the tridiagonal line solve runs.
    pub(super) solve_in: Arrangement,
    pub(super) physical: Layout,
    pub(super) x_pencils: Layout,
    pub(super) y_pencils: Option<Layout>,
    pub(super) x_data: SharedArray,
    pub(super) y_data: SharedArray,
    /// A slab along x on ranks that share memory: the lines solved where
    /// they lie, no pencils (`x_data` then stays empty).
    pub(super) planes: Option<SlabPlanes>,
    /// Send and receive buffers of the all-to-all, kept between solves
    /// (allocating megabytes at every transpose costs more than moving them).
    pub(super) buffers: std::cell::RefCell<(Vec<f64>, Vec<f64>)>,
}

impl Pencils {
    /// Moves the values of `source` (arranged as `from`) into `target`
    /// (arranged as `to`): each rank sends every other the part of its box
    /// that lies in the other's new box.
    pub(super) fn redistribute(
        &self,
        from: &Layout,
        source: &SharedArray,
        to: &Layout,
        target: &mut [f64],
    ) {
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
pub(super) struct SlabPlanes {
    /// This rank's planes, `[first, end)` in global unknown indices along y.
    pub(super) planes: [usize; 2],
    /// The shape of one plane: the whole x, one y, the whole z.
    pub(super) shape: [usize; 3],
    pub(super) plane: Vec<f64>,
    pub(super) lines: ModeLines,
}

/// One arrangement of a solve's unknowns among the ranks ([`Pencils`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Arrangement {
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
pub(super) fn flat_index(whole: &[[usize; 2]; 3], point: [usize; 3]) -> usize {
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
pub(super) fn layouts(
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
